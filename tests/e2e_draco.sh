#!/usr/bin/env bash
# KHR_draco_mesh_compression at the command line (issue 17, item 4): a Draco-compressed box
# (.gltf + .bin and .glb, written by ispm_test_draco_box through the Draco encoder) records
# with exit 0 and a lit, non-black final.display, the same as the uncompressed box; corrupt
# Draco data, an attribute id the data lacks, an accessor count that disagrees and a Draco
# bufferView that does not exist are each one line on stderr naming the file and the mesh,
# exit 2.
# usage: e2e_draco.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; WORK=$3
TOOL=$(dirname "$ISPM")/../tests/ispm_test_draco_box
fail() { echo "FAIL: $*"; exit 1; }
command -v oiiotool > /dev/null || { echo "SKIP: no oiiotool"; exit 77; }
rm -rf "$WORK"; mkdir -p "$WORK"
"$TOOL" "$WORK" || fail "ispm_test_draco_box"
seqf() { # seqf FILE SCENE
  printf '{"scene": "%s", "frames": 1, "fps": 1, "resolution": [32, 24],
 "camera": {"keys": [{"time": 0, "position": [1.6, 1.3, 2.0], "target": [0, 0, 0]}]},
 "settings": {"shadow_map_size": 64, "photon_count": 1024, "threads": 2},
 "lights": [{"type": "point", "position": [1.5, 2.5, 1.5], "intensity": 20}],
 "capture": ["direct.radiance", "final.display"]}\n' "$2" > "$1"
}
avg() { # avg RUN: the mean of final.display's first channel
  oiiotool "$1/frames/000000.exr" --subimage final.display --printstats 2>/dev/null |
    awk '$1 == "Stats" && $2 == "Avg:" {print $3; exit}'
}
for f in plain-box.gltf draco-box.gltf draco-box.glb; do
  seqf "$WORK/$f.json" "$f"
  "$ISPM" record "$WORK/$f.json" -o "$WORK/run-$f" --quiet > /dev/null 2> "$WORK/$f.err" ||
    { cat "$WORK/$f.err"; fail "$f: record failed"; }
  [ ! -s "$WORK/$f.err" ] || { cat "$WORK/$f.err"; fail "$f: stderr not empty"; }
  a=$(avg "$WORK/run-$f")
  awk -v a="$a" 'BEGIN {exit !(a > 0.05)}' || fail "$f: final.display mean $a, want a lit box (> 0.05)"
  echo "$f: final.display mean $a"
done
# Same triangles, same light: the frame matches the uncompressed box's to within rounding.
a0=$(avg "$WORK/run-plain-box.gltf"); a1=$(avg "$WORK/run-draco-box.gltf")
awk -v a="$a0" -v b="$a1" 'BEGIN {d = a - b; exit !(d < 1e-3 && d > -1e-3)}' ||
  fail "Draco box mean $a1, uncompressed box $a0"

expect() { # expect FILE WORDS
  seqf "$WORK/bad.json" "$1"
  "$ISPM" record "$WORK/bad.json" -o "$WORK/bad" --quiet > /dev/null 2> "$WORK/bad.err"; rc=$?
  [ $rc -eq 2 ] || { cat "$WORK/bad.err"; fail "$1: exit $rc, want 2"; }
  [ "$(wc -l < "$WORK/bad.err")" -eq 1 ] || { cat "$WORK/bad.err"; fail "$1: want one line on stderr"; }
  grep -q "$1: mesh 0 (\"box\") primitive 0: KHR_draco_mesh_compression: .*$2" "$WORK/bad.err" ||
    { cat "$WORK/bad.err"; fail "$1: the line does not name the file, the mesh and \"$2\""; }
}
expect draco-corrupt.gltf "does not decode"
expect draco-badid.gltf "attribute NORMAL: id [0-9]* does not exist"
expect draco-count.gltf "accessor 1 (POSITION) has count 23, the Draco data 24 points"
expect draco-noview.gltf "bufferView 5 does not exist"
echo "e2e_draco: ok"
