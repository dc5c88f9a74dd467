#!/usr/bin/env bash
# Buffers stored once within a run (docs/runs.md, "Buffers stored once within a run"), through
# the command line: a recording with a static light stores its shadow map and the light's other
# buffers once, so its frame files hold fewer parts than frames x buffers; it replays bit-exact
# against itself and against the same run recorded with capture_whole_frames; ispm export gives a
# whole frame that oiiotool reads with every part; two shards merged and a resumed recording give
# the uninterrupted run's digests and references; bless into frame files (format 1) and into an
# object store (format 2) both replay bit-exact; a bad reference is one line naming the manifest
# and exit 4.
# usage: e2e_run_dedupe.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
skip() { echo "SKIP: $*"; [ "${ISPM_REQUIRE_DEPS:-0}" = 1 ] && exit 1; exit 77; }
command -v oiiotool > /dev/null || skip "oiiotool is not installed"
rm -rf "$WORK"; mkdir -p "$WORK"
SEQ=$SRC/scenes/cornell-box/cornell-box-ci.json
W=$WORK/whole.json
python3 - "$SEQ" "$W" <<'PY'
import json, os, sys
s = json.load(open(sys.argv[1]))
s["scene"] = os.path.join(os.path.dirname(os.path.abspath(sys.argv[1])), s["scene"])
s["settings"]["capture_whole_frames"] = True
json.dump(s, open(sys.argv[2], "w"))
PY

"$ISPM" record "$SEQ" -o "$WORK/run" --quiet > /dev/null || fail "record exited $?"
"$ISPM" record "$W" -o "$WORK/whole" --quiet > /dev/null || fail "record (whole frames) exited $?"

# parts RUN: the parts its frame files hold, and frames x buffers, as "held total".
parts() {
  python3 - "$1" <<'PY'
import json, subprocess, sys
run = sys.argv[1]
m = json.load(open(run + "/manifest.json"))
held = 0
for f in m["frames"]:
    out = subprocess.run(["oiiotool", "--info", run + "/" + f["file"]], capture_output=True, text=True).stdout
    n = int(out.split("(")[1].split(" subimages")[0]) if "subimages" in out else 1
    own = sum(1 for b in f["buffers"] if "stored_in" not in b)
    if n != own:
        sys.exit("%s: %d parts, the manifest lists %d in it" % (f["file"], n, own))
    held += n
print(held, sum(len(f["buffers"]) for f in m["frames"]))
PY
}
read -r held total <<< "$(parts "$WORK/run")" || fail "the frame files disagree with the manifest"
[ "$held" -lt "$total" ] || fail "the run's frame files hold $held parts of $total: nothing stored once"
read -r wheld wtotal <<< "$(parts "$WORK/whole")" || fail "the whole-frame files disagree with the manifest"
[ "$wheld" -eq "$wtotal" ] && [ "$wtotal" -eq "$total" ] || fail "whole frames: $wheld parts of $wtotal (want $total of $total)"
echo "frame files hold $held parts of $total ($wheld with capture_whole_frames)"

# digests RUN: every frame's buffers as "name digest stored_in", one line per buffer.
digests() {
  python3 - "$1" "${2:-refs}" <<'PY'
import json, sys
m = json.load(open(sys.argv[1] + "/manifest.json"))
for f in m["frames"]:
    for b in f["buffers"]:
        print(f["index"], b["name"], b["digest"], b.get("stored_in", "-") if sys.argv[2] == "refs" else "")
PY
}
digests "$WORK/run" plain > "$WORK/run.txt"; digests "$WORK/whole" plain > "$WORK/whole.txt"
cmp -s "$WORK/run.txt" "$WORK/whole.txt" || fail "stored once or whole, the digests differ"

"$ISPM" replay "$WORK/run" --golden "$WORK/run" --report "$WORK/rep-self" --quiet > "$WORK/self.txt" ||
  fail "replay against itself exited $?"
grep -q "0 failed.* bit-exact ($total buffers" "$WORK/self.txt" || { cat "$WORK/self.txt"; fail "replay against itself is not all bit-exact"; }
# (Another sequence file: a provenance warning, exit 1; the buffers are what is compared.)
"$ISPM" replay "$WORK/whole" --golden "$WORK/run" --report "$WORK/rep-whole" --quiet > "$WORK/whole-rep.txt"
rc=$?; [ $rc -le 1 ] || fail "replay of the whole-frame run exited $rc"
grep -q "buffers: 0 failed.* bit-exact ($total buffers" "$WORK/whole-rep.txt" || fail "whole frames against stored once: not all bit-exact"

# A whole frame for oiiotool: every buffer, though frame 3's file holds only those that changed.
"$ISPM" export "$WORK/run" --frame 3 -o "$WORK/f3.exr" > /dev/null || fail "export --frame 3 exited $?"
want=$(python3 -c "import json; print(len(json.load(open('$WORK/run/manifest.json'))['frames'][3]['buffers']))")
oiiotool --info "$WORK/f3.exr" | grep -q "($want subimages)" || { oiiotool --info "$WORK/f3.exr"; fail "export: not $want parts"; }
oiiotool --info "$WORK/run/frames/000003.exr" | grep -q "($want subimages)" && fail "frame 3's file holds every buffer"

# Two shards merged, and a recording resumed after frame 3: the uninterrupted run's digests and
# references (a shard's reference to its overlap frame becomes the owner's).
digests "$WORK/run" > "$WORK/run-refs.txt"
"$ISPM" record "$SEQ" -o "$WORK/s0" --shard 0/2 --quiet > /dev/null || fail "record --shard 0/2 exited $?"
"$ISPM" record "$SEQ" -o "$WORK/s1" --shard 1/2 --quiet > /dev/null || fail "record --shard 1/2 exited $?"
grep -q stored_in "$WORK/s1/manifest.json" || fail "the second shard stores nothing once"
"$ISPM" merge "$WORK/s0" "$WORK/s1" -o "$WORK/merged" > /dev/null || fail "merge exited $?"
digests "$WORK/merged" > "$WORK/merged.txt"
cmp -s "$WORK/run-refs.txt" "$WORK/merged.txt" || { diff "$WORK/run-refs.txt" "$WORK/merged.txt" | head; fail "merged run differs"; }
"$ISPM" replay "$WORK/merged" --golden "$WORK/run" --report "$WORK/rep-merged" --quiet > "$WORK/merged-rep.txt" ||
  fail "replay of the merged run exited $?"
cp -r "$WORK/run" "$WORK/resumed"
rm -rf "$WORK/resumed/manifest.json" "$WORK/resumed/replay" "$WORK"/resumed/frames/00000[4-7].*
"$ISPM" record "$SEQ" -o "$WORK/resumed" --resume --quiet > /dev/null || fail "record --resume exited $?"
digests "$WORK/resumed" > "$WORK/resumed.txt"
cmp -s "$WORK/run-refs.txt" "$WORK/resumed.txt" || fail "resumed run differs"
"$ISPM" replay "$WORK/resumed" --golden "$WORK/run" --report "$WORK/rep-resumed" --quiet > /dev/null ||
  fail "replay of the resumed run exited $?"

# Bless into frame files and into an object store: both replay bit-exact.
"$ISPM" bless "$WORK/run" "$WORK/g1" --accept > /dev/null 2>&1 || fail "bless (format 1) exited $?"
"$ISPM" replay "$WORK/run" --golden "$WORK/g1" --report "$WORK/rep-g1" --quiet > "$WORK/g1.txt" || fail "replay against the format-1 golden exited $?"
grep -q "bit-exact ($total buffers" "$WORK/g1.txt" || fail "format-1 golden: not all bit-exact"
mkdir -p "$WORK/store/objects"
"$ISPM" bless "$WORK/run" "$WORK/store/g2" --accept > /dev/null 2>&1 || fail "bless (format 2) exited $?"
grep -q '"format_version":[[:space:]]*2' "$WORK/store/g2/manifest.json" || fail "bless did not store objects"
! grep -q stored_in "$WORK/store/g2/manifest.json" || fail "a golden of objects keeps the run's stored_in references"
"$ISPM" replay "$WORK/run" --golden "$WORK/store/g2" --report "$WORK/rep-g2" --quiet > "$WORK/g2.txt" || fail "replay against the format-2 golden exited $?"
grep -q "bit-exact ($total buffers" "$WORK/g2.txt" || fail "format-2 golden: not all bit-exact"

# Bad references: one line naming the manifest, exit 4.
bad() {
  what=$1; named=$2
  rm -rf "$WORK/bad"; cp -r "$WORK/run" "$WORK/bad"; rm -rf "$WORK/bad/replay"
  python3 - "$WORK/bad/manifest.json" "$what" <<'PY'
import json, sys
p, what = sys.argv[1], sys.argv[2]
m = json.load(open(p))
f = m["frames"][2]
b = [x for x in f["buffers"] if "stored_in" in x][0]
if what == "forward": b["stored_in"] = "frames/000005.exr"
if what == "self": b["stored_in"] = "frames/000002.exr"
if what == "missing": b["stored_in"] = "frames/000042.exr"
if what == "chain": b["stored_in"] = "frames/000001.exr"
if what == "digest": b["digest"] = "0" * 32
if what == "notstring": b["stored_in"] = 3
json.dump(m, open(p, "w"))
PY
  "$ISPM" replay "$WORK/bad" --report "$WORK/rep-bad" --quiet > /dev/null 2> "$WORK/err.txt"; rc=$?
  [ $rc -eq 4 ] || { cat "$WORK/err.txt"; fail "$what: exit $rc, want 4"; }
  [ "$(wc -l < "$WORK/err.txt")" -eq 1 ] || { cat "$WORK/err.txt"; fail "$what: want one line on stderr"; }
  grep -qF "manifest.json" "$WORK/err.txt" && grep -qF -- "$named" "$WORK/err.txt" ||
    { cat "$WORK/err.txt"; fail "$what: the error does not name the manifest and $named"; }
}
bad forward "forward in time"
bad self "to its own frame"
bad missing "to no frame of the run"
bad chain "chain of references"
bad digest "differs"
bad notstring "stored_in"
# A part the reference needs, gone from the earlier file: the file and the part named, exit 4.
rm -rf "$WORK/bad"; cp -r "$WORK/run" "$WORK/bad"; rm -rf "$WORK/bad/replay"
oiiotool "$WORK/bad/frames/000002.exr" -o "$WORK/bad/frames/000000.exr" 2> /dev/null || fail "oiiotool could not write"
"$ISPM" replay "$WORK/bad" --report "$WORK/rep-bad" --quiet > /dev/null 2> "$WORK/err.txt"; rc=$?
[ $rc -eq 4 ] || { cat "$WORK/err.txt"; fail "a replaced earlier file: exit $rc, want 4"; }
grep -qF "000000.exr" "$WORK/err.txt" || { cat "$WORK/err.txt"; fail "the error does not name frames/000000.exr"; }
echo "PASS"
