#!/usr/bin/env bash
# bench/penumbra.sh — soft shadows against the reference (issue 15; README "Soft shadows").
# For each light radius of scenes/stress/soft-r*.json (0.05, 0.15, 0.3 m): records the engine's
# frame, renders the reference's direct light (64 spp, first surface only), and prints side by
# side the 10–90% penumbra width of direct.radiance across the box's shadow edge and the floor's
# 8×8-block p90 relative error (tests/tool_penumbra.c). Then the soft-shadow pass's cost per
# frame: 4 still frames of the 0.3 m scene and of its punctual twin (soft-r000.gltf), the median
# of frames 1–3 of the softshadow pass (blocker search) and of the direct pass.
# usage: bench/penumbra.sh [OUTDIR]   (ISPM, PENUMBRA: the binaries; default build/...)
set -euo pipefail
cd "$(dirname "$0")/.."
ISPM=${ISPM:-build/cli/ispm}
TOOL=${PENUMBRA:-build/tests/ispm_test_penumbra}
OUT=${1:-/tmp/ispm-penumbra}
mkdir -p "$OUT"
printf '%-8s %12s %12s %9s %10s\n' radius ispm_mm reference_mm width_err floor_p90
for r in 005 015 030; do
  "$ISPM" record scenes/stress/soft-r$r.json -o "$OUT/r$r" --force --quiet >/dev/null
  "$ISPM" reference scenes/stress/soft-r$r.json -o "$OUT/ref$r" --frames 0 --spp 64 --max-depth 1 --photons 1024 \
    --force --quiet >/dev/null
  read -r we wr err p90 _ < <("$TOOL" "$OUT/r$r" "$OUT/ref$r" 0.42 0.93)
  printf '%-8s %12s %12s %9s %10s\n' "0.${r:1}" "$we" "$wr" "$err" "$p90"
done
# Cost: the same view over 4 still frames, with the 0.3 m light and with the punctual one.
for r in 000 030; do
  python3 - "$r" "$OUT/cost$r.json" <<'PY'
import json, os, sys
r, out = sys.argv[1], sys.argv[2]
s = json.load(open("scenes/stress/soft-r030.json"))
s["name"] = "penumbra-cost-r" + r
s["scene"] = os.path.abspath("scenes/stress/soft-r%s.gltf" % r)
s["frames"], s["still"] = 4, True
s["capture"] = ["direct.radiance"]
json.dump(s, open(out, "w"))
PY
  "$ISPM" record "$OUT/cost$r.json" -o "$OUT/cost$r" --force --quiet >/dev/null
done
python3 - "$OUT" <<'PY'
import json, statistics, sys
def ms(run, name):
    m = json.load(open(run + "/manifest.json"))
    v = [sum(p["ms"] for p in f["passes"] if p["name"] == name) for f in m["frames"][1:]]
    return statistics.median(v)
o = sys.argv[1]
hard_direct, soft_direct = ms(o + "/cost000", "direct"), ms(o + "/cost030", "direct")
blocker = ms(o + "/cost030", "softshadow")
print("soft-shadow cost per frame (median of frames 1-3, ms): softshadow pass %.1f, direct %.1f vs %.1f punctual "
      "(+%.1f); added %.1f" % (blocker, soft_direct, hard_direct, soft_direct - hard_direct,
                               blocker + soft_direct - hard_direct))
PY
