#!/usr/bin/env bash
# Issue 21's GPU timing: builds ispm, then records each sequence at 1920x1080 through EGL on
# EGL device N (--gl-device; on a machine with an NVIDIA GPU its EGL device, usually 0) and
# prints the GPU's name (GL_RENDERER), the median per-pass milliseconds and the frames per
# second of full ISPM (every pass of the frame, the CPU photon trace included; the read-back
# for capture is timed apart and not counted). Only final.display is captured, so the
# recording writes little. Never part of the test suite.
#
# usage: bench/gpu.sh [--device N] [--frames F] [--warmup W] [--resolution WxH] [--threads T]
#                     [--out DIR] [SEQUENCE.json ...]
#   sequences default to the Cornell box (scenes/cornell-box/cornell-box.json) and every
#   room-scale scene's sequence present (scenes/*/room*.json); the frame count F (default 64)
#   replaces the sequence's, the first W frames (default 8: shader compilation, first uploads)
#   are left out of the medians. BUILD_DIR (default build-gpu) is where it builds;
#   ISPM=path/to/ispm skips the build. Exit: 0 done, 1 a build or recording failed, 2 bad use.
set -euo pipefail
cd "$(dirname "$0")/.."
DEVICE=0 FRAMES=64 WARMUP=8 RES=1920x1080 THREADS=$(nproc) OUT=out/gpu
SEQS=()
usage() { sed -n '9,15p' "$0" | sed 's/^# \{0,1\}//'; exit "$1"; }
while [ $# -gt 0 ]; do
  case $1 in
    --device) DEVICE=${2:?}; shift 2 ;;
    --frames) FRAMES=${2:?}; shift 2 ;;
    --warmup) WARMUP=${2:?}; shift 2 ;;
    --resolution) RES=${2:?}; shift 2 ;;
    --threads) THREADS=${2:?}; shift 2 ;;
    --out) OUT=${2:?}; shift 2 ;;
    -h|--help) usage 0 ;;
    -*) echo "bench/gpu.sh: unknown option $1" >&2; usage 2 >&2 ;;
    *) SEQS+=("$1"); shift ;;
  esac
done
[[ $RES =~ ^[0-9]+x[0-9]+$ && $FRAMES =~ ^[0-9]+$ && $WARMUP =~ ^[0-9]+$ && $FRAMES -gt $WARMUP ]] \
  || { echo "bench/gpu.sh: need --resolution WxH and --frames F > --warmup W" >&2; exit 2; }
[ "$THREADS" -le 64 ] || THREADS=64
if [ ${#SEQS[@]} -eq 0 ]; then
  SEQS=(scenes/cornell-box/cornell-box.json)
  for s in scenes/*/room*.json; do [ -f "$s" ] && SEQS+=("$s"); done
fi

if [ -z "${ISPM:-}" ]; then
  BUILD_DIR=${BUILD_DIR:-build-gpu}
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null \
    || { echo "bench/gpu.sh: configure failed (scripts/setup.sh installs the packages)" >&2; exit 1; }
  cmake --build "$BUILD_DIR" -j"$(nproc)" --target ispm >/dev/null || { echo "bench/gpu.sh: build failed" >&2; exit 1; }
  ISPM=$BUILD_DIR/cli/ispm
fi
mkdir -p "$OUT"
echo "bench/gpu.sh: $(date -u '+%Y-%m-%d %H:%M UTC'), EGL device $DEVICE, ${RES}, $FRAMES frames (first $WARMUP left out), $THREADS CPU threads"
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version --format=csv,noheader | sed 's/^/nvidia-smi: /' || true

for seq in "${SEQS[@]}"; do
  name=$(basename "$seq" .json)
  tmp="$OUT/$name-${RES}.json"
  # The sequence at the asked size and length, its scene path made absolute; capture only the image.
  python3 - "$seq" "$tmp" "$RES" "$FRAMES" <<'PY'
import json, os, sys
src, dst, res, frames = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
q = json.load(open(src))
q["scene"] = os.path.abspath(os.path.join(os.path.dirname(src), q["scene"]))
q["resolution"] = [int(v) for v in res.split("x")]
q["frames"] = frames
q["capture"] = ["final.display"]
q["name"] = q.get("name", "seq") + "-gpu"
json.dump(q, open(dst, "w"), indent=1)
PY
  run="$OUT/$name-${RES}-run"
  "$ISPM" record "$tmp" -o "$run" --force --quiet --threads "$THREADS" --gl egl --gl-device "$DEVICE" \
    || { echo "bench/gpu.sh: recording $seq failed" >&2; exit 1; }
  python3 - "$run/manifest.json" "$WARMUP" "$seq" <<'PY'
import json, statistics, sys
m = json.load(open(sys.argv[1])); warm = int(sys.argv[2])
frames = m["frames"][warm:]
names = [p["name"] for p in frames[0]["passes"] if p["name"] != "readback"]
gl = m["gl"]
print("%s: %dx%d, %d frames timed" % (sys.argv[3], m["resolution"][0], m["resolution"][1], len(frames)))
print("  GPU (GL_RENDERER): %s; %s; EGL %s" % (gl["renderer"], gl["version"], gl.get("device")))
for n in names:
    print("  %-14s %9.3f ms" % (n, statistics.median(p["ms"] for f in frames for p in f["passes"] if p["name"] == n)))
tot = [sum(p["ms"] for p in f["passes"] if p["name"] != "readback") for f in frames]
med = statistics.median(tot)
print("  %-14s %9.3f ms (min %.3f, max %.3f)" % ("frame", med, min(tot), max(tot)))
print("  %-14s %9.1f Hz (goal: >= 60 Hz)" % ("frames/s", 1000.0 / med))
PY
done
