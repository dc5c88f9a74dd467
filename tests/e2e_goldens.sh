#!/usr/bin/env bash
# Goldens whose buffers are stored once (docs/goldens.md), through the command line: a golden of
# frame files migrated to objects replays bit-exact against its own frames; bless into a folder
# with a store writes only new objects; a run from another renderer goes into its renderer's
# set, which replay then picks and names; info and export read a golden of objects; gc removes
# only unlisted objects; format-1 and format-2 goldens live side by side; every bad store is one
# line naming the file and exit 4.
# usage: e2e_goldens.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"

# expect CODE NAMED CMD...: CMD exits CODE with exactly one line on stderr containing NAMED.
expect() {
  code=$1; named=$2; shift 2
  "$@" > /dev/null 2> "$WORK/err.txt"; rc=$?
  [ $rc -eq "$code" ] || { cat "$WORK/err.txt"; fail "$*: exit $rc, want $code"; }
  [ "$(wc -l < "$WORK/err.txt")" -eq 1 ] || { cat "$WORK/err.txt"; fail "$*: want one line on stderr"; }
  grep -qF -- "$named" "$WORK/err.txt" || { cat "$WORK/err.txt"; fail "$*: the error does not name $named"; }
}
# bitexact RUN GOLDEN LABEL: replay exits 0 with every buffer bit-exact.
bitexact() {
  "$ISPM" replay "$1" --golden "$2" --report "$WORK/rep-$3" > "$WORK/$3.out" 2>&1; rc=$?
  [ $rc -eq 0 ] || { cat "$WORK/$3.out"; fail "$3: replay exited $rc"; }
  grep -q "0 failed, 0 warned, 0 within tolerance" "$WORK/$3.out" || { cat "$WORK/$3.out"; fail "$3: not bit-exact"; }
}
json() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }

# A golden of frame files, whatever the repository stores: stress-corner unpacked.
"$ISPM" golden unpack "$SRC/golden/stress-corner" "$WORK/old" > "$WORK/unpack.out" || fail "unpack exited $?"
[ "$(json "$WORK/old/manifest.json" 'd["format_version"]')" = 1 ] || fail "unpack did not write format 1"
ls "$WORK/old/frames/"*.exr > /dev/null || fail "unpack wrote no frame files"

# ---- migrate: frame files to objects, checked; old and new goldens side by side
mkdir -p "$WORK/g"
cp -r "$WORK/old" "$WORK/g/a"; cp -r "$WORK/old" "$WORK/g/plain"
"$ISPM" golden migrate "$WORK/g/a" > "$WORK/migrate.out" || { cat "$WORK/migrate.out"; fail "migrate exited $?"; }
grep -q "bit-exact as objects" "$WORK/migrate.out" || fail "migrate did not report its check"
[ "$(json "$WORK/g/a/manifest.json" 'd["format_version"]')" = 2 ] || fail "migrate did not write format 2"
[ ! -e "$WORK/g/a/frames" ] || fail "migrate left frame files"
[ -d "$WORK/g/objects" ] || fail "no shared store beside the golden"
bitexact "$WORK/old" "$WORK/g/a" migrated
bitexact "$WORK/old" "$WORK/g/plain" format1
"$ISPM" golden migrate "$WORK/g/a" | grep -q "nothing to do" || fail "second migrate not a no-op"

# ---- tools read a golden of objects as a run
"$ISPM" info "$WORK/g/a" > "$WORK/info.out" || fail "info exited $?"
grep -q "buffers (frame 0)" "$WORK/info.out" || fail "info printed no buffers"
"$ISPM" export "$WORK/g/a" --frame 1 -o "$WORK/f1.exr" > /dev/null || fail "export of a whole frame exited $?"
"$ISPM" export "$WORK/g/a" --frame 1 --buffer final.display -o "$WORK/f1.png" > /dev/null || fail "export of a buffer exited $?"
if command -v oiiotool > /dev/null; then
  n=$(json "$WORK/old/manifest.json" 'len(d["frames"][1]["buffers"])')
  oiiotool --info "$WORK/f1.exr" | grep -q "($n subimages)" || fail "export: not $n parts"
fi
expect 2 "whole frame" "$ISPM" export "$WORK/g/a" --frame 1 -o "$WORK/f1.png"

# ---- bless into a folder with a store: only new objects
"$ISPM" bless "$WORK/old" "$WORK/g/b" > "$WORK/bless.out" || { cat "$WORK/bless.out"; fail "bless exited $?"; }
grep -q "stored as objects: 0 new" "$WORK/bless.out" || { cat "$WORK/bless.out"; fail "bless wrote objects the store had"; }
[ "$(json "$WORK/g/b/manifest.json" 'd["objects"]')" = "../objects" ] || fail "bless did not use the shared store"
bitexact "$WORK/old" "$WORK/g/b" blessed

# ---- a golden set per renderer
cp -r "$WORK/old" "$WORK/gpu"
python3 - "$WORK/gpu/manifest.json" <<'PY'
import json, sys
m = json.load(open(sys.argv[1])); m["gl"]["renderer"] = "NVIDIA H100 80GB HBM3/PCIe/SSE2"; m["gl"]["vendor"] = "NVIDIA Corporation"
json.dump(m, open(sys.argv[1], "w"), indent=2)
PY
SLUG=nvidia-corporation-nvidia-h100-80gb-hbm3-pcie-sse2
"$ISPM" replay "$WORK/gpu" --golden "$WORK/g/a" --report "$WORK/rep-cross" > "$WORK/cross.out" 2>&1
grep -q "different renderer" "$WORK/cross.out" || { cat "$WORK/cross.out"; fail "no set yet: not the cross-renderer tolerances"; }
[ "$(json "$WORK/rep-cross/report.json" 'd["renderer"]["set"]')" = canonical ] || fail "report.json: not the canonical set"
"$ISPM" bless "$WORK/gpu" "$WORK/g/a" > "$WORK/bless-gpu.out" || { cat "$WORK/bless-gpu.out"; fail "bless of the GPU run exited $?"; }
grep -q "renderer set $SLUG" "$WORK/bless-gpu.out" || { cat "$WORK/bless-gpu.out"; fail "bless did not name the set"; }
[ -f "$WORK/g/a/renderers/$SLUG/manifest.json" ] || fail "no renderer set written"
[ "$(json "$WORK/g/a/renderers/$SLUG/manifest.json" 'd["objects"]')" = "../../../objects" ] || fail "the set does not share the store"
bitexact "$WORK/gpu" "$WORK/g/a" gpu-set
grep -q "renderer set $SLUG" "$WORK/gpu-set.out" || { cat "$WORK/gpu-set.out"; fail "replay did not name the set"; }
[ "$(json "$WORK/rep-gpu-set/report.json" 'd["renderer"]["set"]')" = "$SLUG" ] || fail "report.json: not the set"
bitexact "$WORK/old" "$WORK/g/a" canonical-again   # llvmpipe runs still meet the canonical set
"$ISPM" bless "$WORK/old" "$WORK/g/a" > /dev/null || fail "rebless of the canonical set exited $?"
[ -f "$WORK/g/a/renderers/$SLUG/manifest.json" ] || fail "reblessing the canonical set dropped the renderer set"

# ---- gc: only unlisted objects go
"$ISPM" golden gc "$WORK/g" > "$WORK/gc.out" || { cat "$WORK/gc.out"; fail "gc exited $?"; }
grep -q ", 0 unlisted removed" "$WORK/gc.out" || { cat "$WORK/gc.out"; fail "gc removed listed objects"; }
obj=$(ls "$WORK/g/objects/"*/*.exr | head -n 1)
stray=$WORK/g/objects/00/00000000000000000000000000000000.exr
mkdir -p "$(dirname "$stray")"; cp "$obj" "$stray"
"$ISPM" golden gc "$WORK/g" --dry-run | grep -q ", 1 unlisted, would be removed" || fail "gc --dry-run did not count the stray object"
[ -f "$stray" ] || fail "gc --dry-run removed a file"
"$ISPM" golden gc "$WORK/g" | grep -q ", 1 unlisted removed" || fail "gc did not remove the stray object"
[ ! -e "$stray" ] || fail "the stray object is still there"
bitexact "$WORK/old" "$WORK/g/a" after-gc
bitexact "$WORK/old" "$WORK/g/b" after-gc-b

# ---- bad stores: one line naming the file, exit 4, never a pass
bad() { rm -rf "$WORK/bad"; mkdir -p "$WORK/bad"; cp -r "$WORK/g/a" "$WORK/bad/a"; rm -rf "$WORK/bad/a/renderers"; cp -r "$WORK/g/objects" "$WORK/bad/objects"; }
first_obj() { json "$WORK/bad/a/manifest.json" 'd["frames"][0]["buffers"][0]["digest"]'; }
bad; d=$(first_obj); o=$WORK/bad/objects/${d:0:2}/$d.exr
other=$(ls "$WORK/bad/objects/"*/*.exr | grep -v "$d" | head -n 1)
cp "$other" "$o"
expect 4 "$d" "$ISPM" replay "$WORK/old" --golden "$WORK/bad/a" --report "$WORK/rep-bad"
bad; d=$(first_obj); rm "$WORK/bad/objects/${d:0:2}/$d.exr"
expect 4 "$d.exr" "$ISPM" replay "$WORK/old" --golden "$WORK/bad/a" --report "$WORK/rep-bad"
bad; d=$(first_obj); o=$WORK/bad/objects/${d:0:2}/$d.exr; mv "$o" "$WORK/bad/elsewhere.exr"; ln -s "$WORK/bad/elsewhere.exr" "$o"
expect 4 "$d.exr" "$ISPM" replay "$WORK/old" --golden "$WORK/bad/a" --report "$WORK/rep-bad"
# edit EXPR: a Python statement on the bad golden's manifest m
edit() {
  python3 - "$WORK/bad/a/manifest.json" "$1" <<'PY'
import json, sys
m = json.load(open(sys.argv[1])); exec(sys.argv[2]); json.dump(m, open(sys.argv[1], "w"), indent=1)
PY
}
bad; edit 'm["frames"][1]["buffers"][2]["digest"] = m["frames"][1]["buffers"][2]["digest"][:30] + "zz"'
expect 4 "hex" "$ISPM" replay "$WORK/old" --golden "$WORK/bad/a" --report "$WORK/rep-bad"
bad; edit 'm["objects"] = "../../objects"'
expect 4 "object store missing" "$ISPM" replay "$WORK/old" --golden "$WORK/bad/a" --report "$WORK/rep-bad"
bad; edit 'm["objects"] = "/tmp"'
expect 4 "escapes the golden" "$ISPM" replay "$WORK/old" --golden "$WORK/bad/a" --report "$WORK/rep-bad"
bad; mv "$WORK/bad/objects" "$WORK/bad/real-objects"; ln -s "$WORK/bad/real-objects" "$WORK/bad/objects"
expect 4 "symbolic link" "$ISPM" replay "$WORK/old" --golden "$WORK/bad/a" --report "$WORK/rep-bad"
bad; d=$(first_obj); rm "$WORK/bad/objects/${d:0:2}/$d.exr"
expect 4 "$d.exr" "$ISPM" golden gc "$WORK/bad"
echo "e2e_goldens: ok"
