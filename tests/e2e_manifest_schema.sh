#!/usr/bin/env bash
# The run format's JSON Schema (docs/schema/manifest.schema.json) describes every run ispm
# writes: runs of each kind recorded here (a recording, one with --lineage, two shards and their
# merge, a reference, a replay's stability run), every committed golden, and every run the other
# end-to-end tests left in their work folders validate (manifest.json, run.json and the frame
# records); manifests broken in the ways a writer could break them are refused.
# usage: e2e_manifest_schema.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
VALIDATE="python3 $SRC/scripts/validate_runs.py"
fail() { echo "FAIL: $*"; exit 1; }
skip() { echo "SKIP: $*"; [ "${ISPM_REQUIRE_DEPS:-0}" = 1 ] && exit 1; exit 77; }
rm -rf "$WORK"; mkdir -p "$WORK"
python3 -c 'import jsonschema' 2> /dev/null || skip "python3-jsonschema is not installed"
SEQ=$SRC/scenes/cornell-box/cornell-box-ci.json

# Runs of every kind.
"$ISPM" record "$SEQ" -o "$WORK/runs/record" --quiet > /dev/null || fail "record exited $?"
"$ISPM" record "$SEQ" -o "$WORK/runs/lineage" --lineage --frames 0-1 --quiet > /dev/null || fail "record --lineage exited $?"
"$ISPM" record "$SEQ" -o "$WORK/runs/s0" --shard 0/2 --quiet > /dev/null || fail "record --shard 0/2 exited $?"
"$ISPM" record "$SEQ" -o "$WORK/runs/s1" --shard 1/2 --quiet > /dev/null || fail "record --shard 1/2 exited $?"
"$ISPM" merge "$WORK/runs/s0" "$WORK/runs/s1" -o "$WORK/runs/merged" > /dev/null || fail "merge exited $?"
"$ISPM" reference "$SEQ" -o "$WORK/runs/reference" --spp 1 --frames 0 --quiet > /dev/null || fail "reference exited $?"
"$ISPM" replay "$WORK/runs/record" --golden "$SRC/golden/cornell-box-ci" --report "$WORK/runs/replay" --quiet > /dev/null ||
  fail "replay exited $?"
[ -f "$WORK/runs/replay/stability/manifest.json" ] || fail "replay wrote no stability run"
$VALIDATE --find "$WORK/runs" > "$WORK/recorded.txt" || { cat "$WORK/recorded.txt"; fail "a run recorded here does not validate"; }
cat "$WORK/recorded.txt"
grep -q '^7 manifests, 6 run.json' "$WORK/recorded.txt" || fail "expected 7 manifests and 6 run.json: $(tail -1 "$WORK/recorded.txt")"

# Every committed golden.
$VALIDATE --find "$SRC/golden" > "$WORK/goldens.txt" || { cat "$WORK/goldens.txt"; fail "a golden does not validate"; }
cat "$WORK/goldens.txt"
n=$(ls "$SRC"/golden/*/manifest.json | wc -l) # objects/ is the shared store, not a golden
grep -q "^$n manifests" "$WORK/goldens.txt" || fail "expected $n golden manifests"

# What the other end-to-end tests recorded (those that ran before this one; CTest orders them
# first). The runs of e2e_inputs, e2e_hostile and e2e_goldens are hostile or tampered by design;
# fuzz corpora are not runs.
others=()
for d in "$(dirname "$WORK")"/*.work; do
  case "$(basename "$d")" in
    e2e_manifest_schema.work|e2e_inputs.work|e2e_hostile.work|e2e_goldens.work|fuzz_smoke.work) ;;
    *) [ -d "$d" ] && others+=("$d") ;;
  esac
done
if [ ${#others[@]} -gt 0 ]; then
  $VALIDATE --find "${others[@]}" > "$WORK/others.txt"
  rc=$?
  [ $rc -eq 0 ] || [ $rc -eq 2 ] || { cat "$WORK/others.txt"; fail "a run another test recorded does not validate"; }
  echo "other tests' runs: $(tail -1 "$WORK/others.txt")"
fi

# Broken manifests are refused, each for its own reason.
M=$WORK/runs/record/manifest.json
broken() {  # broken NAME PYTHON-EXPRESSION-ON-m
  mkdir -p "$WORK/broken/$1"
  python3 -c "import json,sys; m=json.load(open(sys.argv[1])); $2; json.dump(m, open(sys.argv[2],'w'))" \
    "$M" "$WORK/broken/$1/manifest.json" || fail "could not write the broken manifest $1"
  $VALIDATE "$WORK/broken/$1/manifest.json" > "$WORK/broken/$1.txt"
  [ $? -eq 1 ] || { cat "$WORK/broken/$1.txt"; fail "a manifest with $1 validates"; }
}
broken "no complete flag" "del m['complete']"
broken "another format version" "m['format_version'] = 3"
broken "format 2 without an object store" "m['format_version'] = 2"
broken "a short digest" "m['frames'][0]['buffers'][0]['digest'] = 'abc'"
broken "a buffer without channels" "m['frames'][0]['buffers'][1]['channels'] = []"
broken "a frame file elsewhere" "m['frames'][1]['file'] = '../000001.exr'"
broken "no settings in a recording" "del m['settings']"
broken "a negative NaN count" "m['frames'][2]['buffers'][3]['nan'] = -1"
mkdir -p "$WORK/broken/frame/frames"
echo '{"index": 0, "time": 0, "file": "frames/000000.exr"}' > "$WORK/broken/frame/frames/000000.json"
$VALIDATE "$WORK/broken/frame" > /dev/null; [ $? -eq 1 ] || fail "a frame record without buffers validates"
echo "ok"
