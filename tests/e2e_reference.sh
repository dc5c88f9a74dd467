#!/usr/bin/env bash
# `ispm reference`: a reference run is a normal run (replay accepts it), records the renderer's
# settings in its manifest, maps --frames A-B to run frames 0..B-A at the sequence's times,
# and bad arguments give one line on stderr and exit 2. (Bit-identity across thread counts is
# tests/test_reference.c's; every process start here costs about a second.)
# usage: e2e_reference.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
GLASS=$SRC/scenes/cornell-box/cornell-glass-ci.json
BOX=$SRC/scenes/cornell-box/cornell-box-ci.json
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"

"$ISPM" reference --help > "$WORK/help.txt" || fail "reference --help exited $?"
grep -q "usage: ispm reference" "$WORK/help.txt" || fail "reference --help prints no usage"
"$ISPM" --help | grep -q "reference SEQUENCE" || fail "ispm --help does not list reference"

# A run that replay accepts, with the renderer's settings in the manifest.
"$ISPM" reference "$GLASS" -o "$WORK/run" --spp 2 --photons 2048 --quiet > "$WORK/out.txt" || fail "reference exited $?"
grep -q "run: $WORK/run" "$WORK/out.txt" || fail "no run line on stdout"
[ -f "$WORK/run/manifest.json" ] || fail "no manifest"
"$ISPM" replay "$WORK/run" --quiet > /dev/null || fail "replay refused the reference run (exit $?)"
python3 - "$WORK/run/manifest.json" <<'PY' || fail "manifest content"
import json, sys
m = json.load(open(sys.argv[1]))
r = m["renderer"]
assert r["name"] == "reference", r
s = r["settings"]
assert s["spp"] == 2 and s["photons_per_pass"] == 2048 and s["seed"] == 0 and s["caustics"] is True, s
assert s["max_depth"] == 64 and s["radius"] > 0 and s["first_frame"] == 0, s
assert s["pixel"] == "box", s
names = [b["name"] for b in m["frames"][0]["buffers"]]
assert names == ["reference.direct", "reference.indirect", "reference.full"], names
PY

# Frames 2-3 of an 8-frame sequence: two run frames at t = 2/8 and 3/8.
"$ISPM" reference "$BOX" -o "$WORK/frames" --spp 1 --frames 2-3 --quiet > /dev/null || fail "--frames 2-3 exited $?"
"$ISPM" replay "$WORK/frames" --quiet > /dev/null || fail "replay refused the --frames run"
python3 - "$WORK/frames/manifest.json" <<'PY' || fail "--frames manifest"
import json, sys
m = json.load(open(sys.argv[1]))
assert m["frame_count"] == 2 and len(m["frames"]) == 2, m["frame_count"]
assert [f["time"] for f in m["frames"]] == [0.25, 0.375], [f["time"] for f in m["frames"]]
assert m["renderer"]["settings"]["first_frame"] == 2 and m["renderer"]["settings"]["last_frame"] == 3
PY

# --pixel-center: recorded in the manifest; the bench reads it back as the reference's kind.
"$ISPM" reference "$BOX" -o "$WORK/centre" --spp 1 --frames 0 --pixel-center --quiet > /dev/null || fail "--pixel-center exited $?"
python3 - "$WORK/centre/manifest.json" <<'PY' || fail "--pixel-center manifest"
import json, sys
s = json.load(open(sys.argv[1]))["renderer"]["settings"]
assert s["pixel"] == "centre", s
PY

# An existing run is kept without --force, replaced with it.
"$ISPM" reference "$GLASS" -o "$WORK/run" --spp 1 --quiet > /dev/null 2>&1; [ $? -eq 1 ] || fail "overwrote a run without --force"
"$ISPM" reference "$GLASS" -o "$WORK/run" --spp 1 --force --quiet > /dev/null || fail "--force"

# Bad arguments: exit 2, one line naming the problem, no manifest.
expect_error() { # NAMED ARGS...
  named=$1; shift
  "$ISPM" reference "$@" 2> "$WORK/err.txt" > /dev/null; rc=$?
  [ $rc -eq 2 ] || fail "reference $*: exit $rc, want 2"
  [ "$(wc -l < "$WORK/err.txt")" -eq 1 ] || { cat "$WORK/err.txt"; fail "reference $*: want one error line"; }
  grep -qF -- "$named" "$WORK/err.txt" || { cat "$WORK/err.txt"; fail "reference $*: error does not name $named"; }
  [ ! -f "$WORK/bad/manifest.json" ] || fail "reference $*: a manifest was written"
}
expect_error "--spp" "$GLASS" -o "$WORK/bad" --spp 0
expect_error "--seed" "$GLASS" -o "$WORK/bad" --seed -1
expect_error "--frames" "$BOX" -o "$WORK/bad" --frames 5-2
expect_error "--frames" "$BOX" -o "$WORK/bad" --frames 3-8
expect_error "missing.json" "$WORK/missing.json" -o "$WORK/bad"
"$ISPM" reference "$GLASS" > /dev/null 2>&1; [ $? -eq 2 ] || fail "reference without -o must exit 2"
"$ISPM" reference "$GLASS" -o "$WORK/bad" --frobnicate > /dev/null 2>&1; [ $? -eq 2 ] || fail "unknown option must exit 2"
echo "e2e_reference: ok"
