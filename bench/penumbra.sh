#!/usr/bin/env bash
# bench/penumbra.sh — soft shadows against the reference (docs/shadows.md), for each way the soft
# shadows find their occluders (setting pcss_blocker: map, rays), side by side:
#
#   soft-r005/015/030  scenes/stress/soft-r*.json: a box under a spherical light of radius
#                      0.05/0.15/0.3 m; the 10–90% penumbra width (mm) across the box's shadow
#                      edge along the image rows 80..112 and the floor's 8×8-block p90 relative
#                      error (tests/tool_penumbra.c), goals ±20% and 10%
#   spot-r015          the same box under a spot light of radius 0.15 m (soft-spot-r015.gltf)
#   cornell-r015       the Cornell box at 256×256 with its light given a radius of 0.15 m
#                      (scenes/stress/cornell-r015.gltf): floor block p90 over the blocks lit in
#                      the reference and the 10–90% widths (pixels) down the floor column x = 40
#                      and along the left wall's row y = 148 (ispm_test_penumbra --lines), goals
#                      10% and ±20%
#
# The references (`ispm reference`, direct light, first surface only) are rendered once and kept
# in REFCACHE: SPP_SOFT samples per pixel for the box scenes, SPP_CORNELL for the Cornell box.
# Then the cost per frame: 4 still frames of soft-r030 and of the Cornell box with each method and
# with the punctual light, in ROUNDS alternating rounds; per round the median of frames 1–3 of the
# softshadow pass (the blocker search) and of the direct pass, then the median over rounds.
# usage: bench/penumbra.sh [OUTDIR]
#   (ISPM, PENUMBRA: the binaries, default build/...; REFCACHE default /tmp/ispm-penumbra-ref;
#    SPP_SOFT 64, SPP_CORNELL 256, ROUNDS 3)
set -euo pipefail
cd "$(dirname "$0")/.."
ISPM=${ISPM:-build/cli/ispm}
TOOL=${PENUMBRA:-build/tests/ispm_test_penumbra}
OUT=${1:-/tmp/ispm-penumbra}
REFCACHE=${REFCACHE:-/tmp/ispm-penumbra-ref}
SPP_SOFT=${SPP_SOFT:-64}
SPP_CORNELL=${SPP_CORNELL:-256}
ROUNDS=${ROUNDS:-3}
METHODS="map rays"
mkdir -p "$OUT" "$REFCACHE"

# mkseq NAME BASE SCENE FRAMES BLOCKER: a sequence in $OUT from BASE with its scene, frame count and
# pcss_blocker ("-": the default, and the capture the measures need).
mkseq() {
  python3 - "$@" <<'PY'
import json, os, sys
name, base, scene, frames, blocker, out = sys.argv[1:7]
s = json.load(open(base))
s["name"] = name
s["scene"] = os.path.abspath(scene)
s["frames"] = int(frames)
s["still"] = True
s.setdefault("settings", {})["indirect"] = "none"
if blocker != "-":
    s["settings"]["pcss_blocker"] = blocker
s["capture"] = ["gbuffer.*", "direct.radiance", "direct.penumbra"]
json.dump(s, open(out, "w"))
PY
}

# reference NAME SEQ SPP: the cached reference run of SEQ.
reference() {
  local dir="$REFCACHE/$1-spp$3"
  if [ ! -f "$dir/manifest.json" ]; then
    "$ISPM" reference "$2" -o "$dir" --frames 0 --spp "$3" --max-depth 1 --photons 1024 --force --quiet >/dev/null
  fi
  echo "$dir"
}

echo "== box scenes: width across the shadow edge (mm, rows 80..112), floor 8x8-block p90 (goals: ±20%, 10%)"
printf '%-12s %-6s %9s %9s %9s %10s\n' scene method ispm_mm ref_mm width_err floor_p90
for sc in soft-r005:soft-r005.gltf soft-r015:soft-r015.gltf soft-r030:soft-r030.gltf spot-r015:soft-spot-r015.gltf; do
  name=${sc%%:*}; gltf=scenes/stress/${sc#*:}
  mkseq "$name" scenes/stress/soft-r015.json "$gltf" 1 - "$OUT/$name.json"
  ref=$(reference "$name" "$OUT/$name.json" "$SPP_SOFT")
  for m in $METHODS; do
    mkseq "$name" scenes/stress/soft-r015.json "$gltf" 1 "$m" "$OUT/$name-$m.json"
    "$ISPM" record "$OUT/$name-$m.json" -o "$OUT/$name-$m" --force --quiet >/dev/null
    read -r we wr err p90 _ < <("$TOOL" "$OUT/$name-$m" "$ref" 0.42 0.93)
    printf '%-12s %-6s %9s %9s %9s %10s\n' "$name" "$m" "$we" "$wr" "$err" "$p90"
  done
done

echo "== cornell-r015 256x256: floor block p90 (lit blocks), 10-90% widths in pixels ispm / reference (goals: 10%, ±20%)"
mkseq cornell-r015 scenes/cornell-box/cornell-box.json scenes/stress/cornell-r015.gltf 1 - "$OUT/cornell-r015.json"
ref=$(reference cornell-r015 "$OUT/cornell-r015.json" "$SPP_CORNELL")
printf '%-6s %9s %22s %22s\n' method floor_p90 "x=40 (floor)" "y=148 (left wall)"
for m in $METHODS; do
  mkseq cornell-r015 scenes/cornell-box/cornell-box.json scenes/stress/cornell-r015.gltf 1 "$m" "$OUT/cornell-$m.json"
  "$ISPM" record "$OUT/cornell-$m.json" -o "$OUT/cornell-$m" --force --quiet >/dev/null
  "$TOOL" --lines "$OUT/cornell-$m" "$ref" x=40:+y y=148:+x > "$OUT/cornell-$m.lines" || true
  awk -v m="$m" '/^floor_p90/ {p = $2} /^x=40/ {c = sprintf("%s/%s (%s)", $2, $3, $4)}
    /^y=148/ {r = sprintf("%s/%s (%s)", $2, $3, $4)} END {printf "%-6s %9s %22s %22s\n", m, p, c, r}' "$OUT/cornell-$m.lines"
done

echo "== cost per frame (ms; median over $ROUNDS alternating rounds of the median of frames 1-3)"
for sc in soft-r030:scenes/stress/soft-r030.json:scenes/stress/soft-r030.gltf:scenes/stress/soft-r000.gltf \
          cornell-r015:scenes/cornell-box/cornell-box.json:scenes/stress/cornell-r015.gltf:scenes/cornell-box/cornell-box.gltf; do
  IFS=: read -r name base gltf punctual <<< "$sc"
  mkseq "$name-cost-punctual" "$base" "$punctual" 4 - "$OUT/cost-$name-punctual.json"
  for m in $METHODS; do mkseq "$name-cost-$m" "$base" "$gltf" 4 "$m" "$OUT/cost-$name-$m.json"; done
  for round in $(seq 1 "$ROUNDS"); do
    for m in punctual $METHODS; do
      "$ISPM" record "$OUT/cost-$name-$m.json" -o "$OUT/cost-$name-$m-$round" --force --quiet >/dev/null
    done
  done
  python3 - "$OUT" "$name" "$ROUNDS" $METHODS <<'PY'
import json, statistics, sys
out, name, rounds, methods = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4:]
def ms(run, p):
    m = json.load(open(run + "/manifest.json"))
    return statistics.median(sum(x["ms"] for x in f["passes"] if x["name"] == p) for f in m["frames"][1:])
def med(m, p):
    return statistics.median(ms("%s/cost-%s-%s-%d" % (out, name, m, r), p) for r in range(1, rounds + 1))
hard = med("punctual", "direct")
for m in methods:
    soft, direct = med(m, "softshadow"), med(m, "direct")
    print("%-13s %-6s softshadow %7.1f  direct %7.1f (punctual %6.1f)  soft shadows add %7.1f" %
          (name, m, soft, direct, hard, soft + direct - hard))
PY
done
