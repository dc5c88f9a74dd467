#!/usr/bin/env bash
# Hostile inputs at the command line (issue 8): every reader refuses a malformed file with
# exactly one line on stderr naming the file, and the documented exit code — record 2, replay
# 4 — never a crash. Record side: zero-sized and absurd resolutions, an empty and a truncated
# .glb. Replay side: a truncated or non-JSON manifest, zero-sized and absurd buffer sizes,
# a channel list that disagrees with the file, an empty and a truncated frame EXR, a golden
# without manifest, a malformed and a missing tolerance file.
# usage: e2e_inputs.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
SCENE=$SRC/scenes/cornell-box/cornell-box.gltf

# expect CODE NAMED CMD...: CMD exits CODE with exactly one line on stderr containing NAMED.
expect() {
  code=$1; named=$2; shift 2
  "$@" > /dev/null 2> "$WORK/err.txt"; rc=$?
  [ $rc -eq "$code" ] || { cat "$WORK/err.txt"; fail "$*: exit $rc, want $code"; }
  [ "$(wc -l < "$WORK/err.txt")" -eq 1 ] || { cat "$WORK/err.txt"; fail "$*: want one line on stderr"; }
  grep -qF -- "$named" "$WORK/err.txt" || { cat "$WORK/err.txt"; fail "$*: the error does not name $named"; }
}
seq_with() { # seq_with FILE RESOLUTION SCENE
  printf '{"scene": "%s", "frames": 1, "fps": 8, "resolution": %s, "camera": {"node": "Camera"},
 "settings": {"shadow_map_size": 16}}\n' "$3" "$2" > "$1"
}

# ---- record
seq_with "$WORK/zero.json" "[0, 32]" "$SCENE";       expect 2 zero.json "$ISPM" record "$WORK/zero.json" -o "$WORK/r" --quiet
seq_with "$WORK/absurd.json" "[100000, 100000]" "$SCENE"; expect 2 absurd.json "$ISPM" record "$WORK/absurd.json" -o "$WORK/r" --quiet
: > "$WORK/empty.glb"
seq_with "$WORK/emptyglb.json" "[8, 8]" "$WORK/empty.glb"; expect 2 empty.glb "$ISPM" record "$WORK/emptyglb.json" -o "$WORK/r" --quiet
head -c 40 "$SRC/tests/data/gltf/valid-triangle.glb" > "$WORK/cut.glb"
seq_with "$WORK/cutglb.json" "[8, 8]" "$WORK/cut.glb"; expect 2 cut.glb "$ISPM" record "$WORK/cutglb.json" -o "$WORK/r" --quiet
[ ! -e "$WORK/r/manifest.json" ] || fail "a manifest was written for bad input"
# A GL library that cannot be loaded (libOSMesa is opened at the first context,
# $ISPM_OSMESA_LIB names it): one line naming it, and no run that looks complete.
seq_with "$WORK/nogl.json" "[8, 8]" "$SCENE"
expect 1 libOSMesa-missing.so env ISPM_OSMESA_LIB=/nonexistent/libOSMesa-missing.so "$ISPM" record "$WORK/nogl.json" -o "$WORK/nogl" --quiet
[ ! -e "$WORK/nogl/manifest.json" ] || fail "a manifest was written without a GL context"

# ---- replay: a small good run to spoil in different ways
seq_with "$WORK/tiny.json" "[32, 24]" "$SCENE"
"$ISPM" record "$WORK/tiny.json" -o "$WORK/good" --quiet > /dev/null || fail "record the fixture run"
"$ISPM" replay "$WORK/good" --golden "$WORK/good" --report "$WORK/rep" > /dev/null || fail "replay of the fixture run"
spoil() { rm -rf "$WORK/$1"; cp -r "$WORK/good" "$WORK/$1"; }
M=manifest.json
# first_line_sub RUN SED: applies the sed substitution to the first line it matches only.
first_sub() { sed -i "0,/$2/s//$3/" "$WORK/$1/$M"; }

spoil cut;      head -c 300 "$WORK/good/$M" > "$WORK/cut/$M"
expect 4 "cut/$M" "$ISPM" replay "$WORK/cut" --report "$WORK/rep"
spoil notjson;  printf 'not json at all' > "$WORK/notjson/$M"
expect 4 "notjson/$M" "$ISPM" replay "$WORK/notjson" --report "$WORK/rep"
spoil zero;     first_sub zero '"width":[[:space:]]*32' '"width":\t0'
expect 4 "zero/$M" "$ISPM" replay "$WORK/zero" --report "$WORK/rep"
spoil huge;     first_sub huge '"height":[[:space:]]*24' '"height":\t2000000000'
expect 4 "huge/$M" "$ISPM" replay "$WORK/huge" --report "$WORK/rep"
spoil chans;    first_sub chans '\["R", "G", "B"\]' '["R", "G", "A"]'
expect 4 "chans/frames/000000.exr" "$ISPM" replay "$WORK/chans" --report "$WORK/rep"
spoil emptyexr; : > "$WORK/emptyexr/frames/000000.exr"
expect 4 "emptyexr/frames/000000.exr" "$ISPM" replay "$WORK/emptyexr" --report "$WORK/rep"
spoil cutexr;   truncate -s 2000 "$WORK/cutexr/frames/000000.exr"
expect 4 "cutexr/frames/000000.exr" "$ISPM" replay "$WORK/cutexr" --report "$WORK/rep"
spoil nogolden; rm "$WORK/nogolden/$M"
expect 4 "nogolden/$M" "$ISPM" replay "$WORK/good" --golden "$WORK/nogolden" --report "$WORK/rep"
printf '{"default": {"fail": "lots"}}' > "$WORK/badtol.json"
expect 4 badtol.json "$ISPM" replay "$WORK/good" --golden "$WORK/good" --tolerances "$WORK/badtol.json" --report "$WORK/rep"
expect 4 missingtol.json "$ISPM" replay "$WORK/good" --golden "$WORK/good" --tolerances "$WORK/missingtol.json" --report "$WORK/rep"
echo "e2e_inputs: ok"
