#!/usr/bin/env bash
# The final gather's measures (docs/final-gather.md), ratios taken side by side in one run:
#   1. references: `ispm reference` of frame 0, pixel centres, of cornell-box-fg (256x256, SPP,
#      default 1024) and, with ATRIUM=1, atrium-640x480 (ATRIUM_SPP, default 128), each made
#      once into CACHE and linked as runs/<name>-reference for the bench configs;
#   2. the record of 4 still frames of cornell-box-fg (32,768 photons) with "preset":
#      "interactive", "indirect": "kd-gather" and the 16-ray final gather, in ROUNDS alternating
#      rounds: per round the sum of the frames' pass times from each manifest, and the ratios
#      to the k-d gather's (ratio of medians, and the rounds' range);
#   3. reprojected flicker of indirect.radiance (ispm replay, docs/stability.md) on the stress
#      paths near-plane and corner: k-d gather, final gather (64 rays, pixel seeds), interactive;
#   4. one-frame accuracy: `ispm bench bench/final-gather.json` (mean ratio, 8x8-block p90 away
#      from geometric edges and over all blocks, frame time); with FULL=1 also the 16-frame
#      config and, with ATRIUM=1, the atrium's.
# Usage: bench/final-gather.sh [OUTDIR] (default out/final-gather); ISPM=path/to/ispm.
set -euo pipefail
cd "$(dirname "$0")/.."
ISPM=${ISPM:-build/cli/ispm}
OUT=${1:-out/final-gather}
CACHE=${CACHE:-/tmp/ispm-final-gather}
ROUNDS=${ROUNDS:-3}
SPP=${SPP:-1024}
ATRIUM_SPP=${ATRIUM_SPP:-128}
mkdir -p "$OUT" "$CACHE" runs

reference() { # sequence, name, spp
  local ref="$CACHE/$2-reference-c$3"
  if [ ! -f "$ref/manifest.json" ]; then
    "$ISPM" reference "$1" -o "$ref" --spp "$3" --frames 0 --pixel-center --force --quiet
  fi
  ln -sfn "$ref" "runs/$2-reference"
}
reference scenes/cornell-box/cornell-box-fg.json cornell-box-fg "$SPP"
if [ "${ATRIUM:-0}" = 1 ]; then
  reference scenes/atrium/atrium-640x480.json atrium-640x480 "$ATRIUM_SPP"
fi

# A copy of a sequence with settings added (absolute scene path), 4 frames unless it says.
variant() { # in out json-settings [frames]
  python3 - "$1" "$2" "$3" "${4:-0}" <<'PY'
import json, os, sys
src, dst, extra, frames = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), int(sys.argv[4])
s = json.load(open(src))
s["scene"] = os.path.abspath(os.path.join(os.path.dirname(src), s["scene"]))
s["settings"].update(extra)
if frames:
    s["frames"] = frames
json.dump(s, open(dst, "w"), indent=1)
PY
}
W="$OUT/work"
mkdir -p "$W"
variant scenes/cornell-box/cornell-box-fg.json "$W/kd.json" '{"indirect": "kd-gather"}' 4
variant scenes/cornell-box/cornell-box-fg.json "$W/interactive.json" '{"preset": "interactive"}' 4
variant scenes/cornell-box/cornell-box-fg.json "$W/fg16.json" '{"indirect": "final-gather", "final_gather_rays": 16}' 4
frames_ms() { python3 -c "
import json, sys
m = json.load(open(sys.argv[1] + '/manifest.json'))
print('%.1f' % sum(p['ms'] for f in m['frames'] for p in f['passes']))" "$1"; }

echo "== record of 4 still frames, cornell-box-fg 256x256, 32768 photons ($ROUNDS alternating rounds, ms)"
: > "$W/times.txt"
for r in $(seq 1 "$ROUNDS"); do
  for v in kd interactive fg16; do
    "$ISPM" record "$W/$v.json" -o "$W/run-$v" --force --quiet > /dev/null
    echo "$r $v $(frames_ms "$W/run-$v")" >> "$W/times.txt"
  done
done
python3 - "$W/times.txt" <<'PY' | tee "$OUT/times.txt"
import statistics, sys
t = {}
for line in open(sys.argv[1]):
    r, v, ms = line.split()
    t.setdefault(v, []).append(float(ms))
kd = t["kd"]
for v in ["kd", "interactive", "fg16"]:
    per = [a / b for a, b in zip(t[v], kd)]
    print("%-12s median %8.1f ms  rounds %s  vs kd-gather %.3fx (rounds %.3f-%.3f)" % (
        v, statistics.median(t[v]), " ".join("%.0f" % x for x in t[v]),
        statistics.median(t[v]) / statistics.median(kd), min(per), max(per)))
PY

echo "== reprojected flicker of indirect.radiance (mean / p99), stress paths"
: > "$W/flicker.txt"
for path in near-plane corner; do
  variant "scenes/stress/$path.json" "$W/$path-kd.json" '{"indirect": "kd-gather"}'
  variant "scenes/stress/$path.json" "$W/$path-fg64.json" '{"indirect": "final-gather", "final_gather_rays": 64}'
  variant "scenes/stress/$path.json" "$W/$path-interactive.json" '{"preset": "interactive"}'
  for v in kd fg64 interactive; do
    python3 - "$W/$path-$v.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
s["frames"] = 6 if "frames" not in s else s["frames"]
s["capture"] = ["gbuffer.*", "direct.radiance", "indirect.radiance", "composite.radiance"]
json.dump(s, open(sys.argv[1], "w"), indent=1)
PY
    "$ISPM" record "$W/$path-$v.json" -o "$W/run-$path-$v" --force --quiet > /dev/null
    "$ISPM" replay "$W/run-$path-$v" --report "$W/replay-$path-$v" --no-flip --quiet > /dev/null || true
    python3 - "$W/replay-$path-$v/report.json" "$path" "$v" <<'PY' >> "$W/flicker.txt"
import json, sys
st = json.load(open(sys.argv[1]))["stability"]
b = st["buffers"]["indirect.radiance"] if isinstance(st.get("buffers"), dict) else None
if b is None:
    b = next(x for x in st["buffers"] if x.get("name") == "indirect.radiance")
r, s = b["reprojected"], b["static"]
print(sys.argv[2], sys.argv[3], r["mean"], r["p99"], s["mean"], s["p99"])
PY
  done
done
python3 - "$W/flicker.txt" <<'PY' | tee "$OUT/flicker.txt"
import sys
rows = [l.split() for l in open(sys.argv[1])]
kd = {r[0]: float(r[2]) for r in rows if r[1] == "kd"}
for p, v, rm, rp, sm, sp in rows:
    print("%-10s %-12s reprojected %.4f / %.3f  static %.4f / %.3f  vs kd-gather %.2fx" % (
        p, v, float(rm), float(rp), float(sm), float(sp), float(rm) / kd[p] if kd[p] > 0 else float("nan")))
PY

echo "== one frame against the reference (bench/final-gather.json)"
"$ISPM" bench bench/final-gather.json -o "$OUT/one-frame" --quiet > "$OUT/one-frame.txt" 2>&1 || { cat "$OUT/one-frame.txt"; exit 1; }
summary() { python3 - "$1/bench.json" <<'PY'
import json, sys
b = json.load(open(sys.argv[1]))
pts = b["points"]
kd = next((p for p in pts if p["method"].startswith("kd-gather")), None)
for p in pts:
    bi = p["indirect_bias"] if "indirect_bias" in p else p["bias"]
    print("%-20s mean %+6.1f %%  block p90 away from edges %.3f  all blocks %.3f  frame %8.1f ms%s" % (
        p["method"], 100 * (bi["mean_ratio"] - 1), bi["flat_block_p90"], bi["block_p90"], p["frame_ms"],
        "  (%.2fx kd-gather)" % (p["frame_ms"] / kd["frame_ms"]) if kd else ""))
    for f in p.get("series", []):
        sb = f["indirect_bias"]
        print("    frame %3d (%2d rendered, %9.1f ms): mean %+6.1f %%  block p90 away from edges %.3f  all blocks %.3f" % (
            f["frame"], f["frames_rendered"], f["elapsed_ms"], 100 * (sb["mean_ratio"] - 1), sb["flat_block_p90"],
            sb["block_p90"]))
PY
}
summary "$OUT/one-frame" | tee "$OUT/one-frame-summary.txt"
if [ "${FULL:-0}" = 1 ]; then
  echo "== 16 still frames (bench/final-gather-16.json)"
  "$ISPM" bench bench/final-gather-16.json -o "$OUT/sixteen" --quiet > "$OUT/sixteen.txt" 2>&1
  summary "$OUT/sixteen" | tee "$OUT/sixteen-summary.txt"
  if [ "${ATRIUM:-0}" = 1 ]; then
    echo "== atrium 640x480 (bench/final-gather-atrium.json)"
    "$ISPM" bench bench/final-gather-atrium.json -o "$OUT/atrium" --quiet > "$OUT/atrium.txt" 2>&1
    summary "$OUT/atrium" | tee "$OUT/atrium-summary.txt"
  fi
fi
