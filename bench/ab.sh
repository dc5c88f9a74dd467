#!/usr/bin/env bash
# Two builds side by side on one bench config: `ispm bench CONFIG` with binary A, then B, then A,
# ... (ROUNDS pairs, alternating so that a busy spell of the machine falls on both), and per
# method the ratio B/A of the medians of each grid point's frame time and of the method's own
# pass time, plus whether every point's errors against the reference are identical (the same
# images). For a change that must not move speed: ratios near 1.00 within the run-to-run noise.
# usage: bench/ab.sh ISPM_A ISPM_B [CONFIG] [OUTDIR]   (ROUNDS=1 by default)
#   CONFIG default bench/indirect-methods.json (its reference: bench/indirect-methods.sh makes it)
set -euo pipefail
cd "$(dirname "$0")/.."
A=$1; B=$2
CONFIG=${3:-bench/indirect-methods.json}
OUT=${4:-out/ab}
ROUNDS=${ROUNDS:-1}
mkdir -p "$OUT"
for r in $(seq 1 "$ROUNDS"); do
  for side in a b; do
    bin=$A; [ $side = b ] && bin=$B
    "$bin" bench "$CONFIG" -o "$OUT/$side$r" --quiet > "$OUT/$side$r.txt"
  done
done
python3 - "$OUT" "$ROUNDS" <<'PY'
import json, statistics, sys
from collections import defaultdict
out, rounds = sys.argv[1], int(sys.argv[2])
runs = {s: [json.load(open("%s/%s%d/bench.json" % (out, s, r))) for r in range(1, rounds + 1)] for s in "ab"}
def per_point(side):
    pts = defaultdict(lambda: {"frame": [], "pass": [], "rmse": set()})
    for b in runs[side]:
        for p in b["points"]:
            d = pts[p["label"]]
            d["method"] = p["method"]
            d["frame"].append(p["frame_ms"])
            d["pass"].append(max(p["pass_ms"].get(k, 0) for k in ("splat", "gather", "quads", "final_gather")))
            d["rmse"].add(p["indirect"]["rmse"])
    return pts
A, B = per_point("a"), per_point("b")
by_method = defaultdict(lambda: {"frame": [], "pass": [], "same": True})
for label, a in A.items():
    b = B[label]
    m = by_method[a["method"]]
    m["frame"].append(statistics.median(b["frame"]) / statistics.median(a["frame"]))
    m["pass"].append(statistics.median(b["pass"]) / statistics.median(a["pass"]) if statistics.median(a["pass"]) > 0 else 1.0)
    m["same"] &= a["rmse"] == b["rmse"]
print("%-16s %6s %14s %14s %s" % ("method", "points", "frame B/A", "pass B/A", "errors"))
allf = []
for name, m in by_method.items():
    gf = statistics.geometric_mean(m["frame"]); gp = statistics.geometric_mean(m["pass"])
    allf += m["frame"]
    print("%-16s %6d %8.3f (%.2f-%.2f) %8.3f      %s" % (name, len(m["frame"]), gf, min(m["frame"]), max(m["frame"]), gp,
          "identical" if m["same"] else "DIFFER"))
print("all points: frame time B/A %.3f (geometric mean of %d)" % (statistics.geometric_mean(allf), len(allf)))
PY
