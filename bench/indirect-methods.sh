#!/usr/bin/env bash
# Issue 12's measurement: every indirect method (photon volumes, quads, tile gather, k-d gather)
# over photon_count {8192, 32768, 131072, 524288} x kernel_radius {0.05, 0.1, 0.2} on the Cornell
# box at 160x160 and at 640x480, each size in one `ispm bench` run, so the "speedup vs
# kd-gather" lines it prints are ratios measured side by side. The GL compute tile gather
# (tile-gather-gl) is in the 160x160 run only: at 640x480, 524288 photons, r 0.2 one frame took
# 334 s on llvmpipe (docs/indirect.md), and its 160x160 series alone takes several minutes; so is
# the final gather (another estimator: 64 rays a pixel, README "Final gathering"). Makes the 256-spp references
# (frame 0) when they are missing. Usage: bench/indirect-methods.sh [OUTDIR] (default
# out/indirect-methods); ISPM=path/to/ispm to use another binary.
set -euo pipefail
cd "$(dirname "$0")/.."
ISPM=${ISPM:-build/cli/ispm}
OUT=${1:-out/indirect-methods}
for seq in cornell-box-ci cornell-box-640x480; do
  if [ ! -f "runs/$seq-reference/manifest.json" ]; then
    "$ISPM" reference "scenes/cornell-box/$seq.json" -o "runs/$seq-reference" --spp 256 --frames 0-0 --force --quiet
  fi
done
mkdir -p "$OUT"
"$ISPM" bench bench/indirect-methods.json -o "$OUT/160x160" | tee "$OUT/160x160.txt"
"$ISPM" bench bench/indirect-methods-640x480.json -o "$OUT/640x480" | tee "$OUT/640x480.txt"
