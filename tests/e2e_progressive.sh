#!/usr/bin/env bash
# Progressive accumulation end to end (issue 13): record the still 64² CI sequence with
# "progressive": true and stratified random numbers (002 §4.2); replay it against its golden (bit-exact);
# the same recording with 1 thread is bit-identical (thread independence); a recording resumed
# after its last frames were lost re-renders the history silently and ends bit-identical; the
# sample count grows by one a frame where nothing moves, and stays 1 where everything moves
# (the animated camera restarts the accumulation every frame).
# usage: e2e_progressive.sh ISPM SOURCE_DIR WORK_DIR   (run by CTest)
set -u
ISPM=$1; SRC=$2; WORK=$3
SEQ=$SRC/scenes/cornell-box/cornell-box-progressive-ci.json
GOLDEN=$SRC/golden/cornell-box-progressive-ci
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
# stat RUN FRAME BUFFER WHAT: WHAT (Avg or Max) of the first channel of a buffer.
stat() {
  oiiotool "$1/frames/$(printf %06d "$2").exr" --subimage "$3" --printstats 2>/dev/null |
    awk -v w="$4" '$1 == "Stats" && $2 == w":" {print $3; exit}'
}
bitexact() { # bitexact RUN GOLDEN LABEL
  "$ISPM" replay "$1" --golden "$2" --report "$WORK/replay-$3" > "$WORK/$3.out"; rc=$?
  [ $rc -eq 0 ] || { cat "$WORK/$3.out"; fail "$3: replay exited $rc"; }
  grep -q "0 failed, 0 warned, 0 within tolerance" "$WORK/$3.out" || { cat "$WORK/$3.out"; fail "$3: not bit-exact"; }
}

"$ISPM" record "$SEQ" -o "$WORK/run" --quiet > /dev/null || fail "record exited $?"
if [ -d "$GOLDEN" ]; then
  bitexact "$WORK/run" "$GOLDEN" golden
fi
for b in progressive.radiance progressive.count progressive.radius; do
  grep -q "\"$b\"" "$WORK/run/manifest.json" || fail "no $b in the manifest"
done

# Counts: frame f has f + 1 samples on every surface pixel; the radius follows PPM.
[ "$(stat "$WORK/run" 0 progressive.count Max)" = "1.000000" ] || fail "frame 0: count max is not 1"
[ "$(stat "$WORK/run" 15 progressive.count Max)" = "16.000000" ] || fail "frame 15: count max is not 16"
r15=$(stat "$WORK/run" 15 progressive.radius Max)
awk -v r="$r15" 'BEGIN { r2 = 1; for (i = 1; i < 16; i++) r2 *= (i + 2/3) / (i + 1);
  d = r - sqrt(r2); exit !(d < 1e-5 && d > -1e-5) }' || fail "frame 15: radius $r15 is not PPM's"

# Thread independence.
"$ISPM" record "$SEQ" -o "$WORK/run1" --threads 1 --quiet > /dev/null || fail "record --threads 1 exited $?"
bitexact "$WORK/run1" "$WORK/run" threads

# Resume after losing frames 10..15: the accumulation is rebuilt silently.
cp -r "$WORK/run" "$WORK/resumed"
rm -f "$WORK/resumed/manifest.json" "$WORK"/resumed/frames/0000{10,11,12,13,14,15}.{exr,json}
"$ISPM" record "$SEQ" -o "$WORK/resumed" --resume --quiet > /dev/null || fail "record --resume exited $?"
bitexact "$WORK/resumed" "$WORK/run" resume

# Everything moves (the animated camera): every frame restarts.
sed -e 's/"still": true/"still": false/' -e 's/"frames": 16/"frames": 3/' "$SEQ" > "$WORK/moving.json"
sed -i "s#\"cornell-box.gltf\"#\"$SRC/scenes/cornell-box/cornell-box.gltf\"#" "$WORK/moving.json"
"$ISPM" record "$WORK/moving.json" -o "$WORK/moving" --quiet > /dev/null || fail "moving: record exited $?"
for f in 0 1 2; do
  [ "$(stat "$WORK/moving" $f progressive.count Max)" = "1.000000" ] || fail "moving frame $f: count is not 1"
  [ "$(stat "$WORK/moving" $f progressive.radius Max)" = "1.000000" ] || fail "moving frame $f: radius is not 1"
done
echo "e2e_progressive: OK"
