#!/usr/bin/env bash
# Crash safety: a recording killed (SIGKILL) at a random moment never leaves a run that replay
# accepts (exit 4), and `record --resume` completes it into a run bit-identical to an
# uninterrupted one: same manifest up to the command line and pass timings, every buffer
# bit-exact in a replay against the uninterrupted run. Also: --resume refuses a run of another
# sequence or settings, a complete run and frames without run.json (exit 2); a folder killed
# before run.json was written holds nothing, and --resume records it from the start.
# Delays are random; CRASH_SEED=N repeats a sequence of them, CRASH_KILLS=N sets how many.
# usage: e2e_crash.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
RANDOM=${CRASH_SEED:-$$}
KILLS=${CRASH_KILLS:-3}
echo "e2e_crash: CRASH_SEED=$RANDOM"

# A short sequence: 4 frames of the Cornell box at 64x64.
SEQ=$WORK/crash.json
cat > "$SEQ" <<JSON
{"name": "crash", "scene": "$SRC/scenes/cornell-box/cornell-box.gltf", "frames": 4, "fps": 8,
 "resolution": [64, 64], "camera": {"node": "Camera"}, "settings": {"shadow_map_size": 64}}
JSON
now_ms() { echo $(( $(date +%s%N) / 1000000 )); }

t0=$(now_ms)
"$ISPM" record "$SEQ" -o "$WORK/ref" --quiet > /dev/null || fail "uninterrupted record"
T=$(( $(now_ms) - t0 ))
echo "e2e_crash: uninterrupted record takes ${T} ms"

# What must match between two recordings of the same sequence: everything in the manifest but
# the command line and per-pass milliseconds (timings).
stable() { grep -vE '"(ms|command)":' "$1/manifest.json"; }

# check_resumed RUN: RUN, completed by --resume, equals the uninterrupted run.
check_resumed() {
  diff <(stable "$WORK/ref") <(stable "$1") > "$WORK/manifest.diff" || { head -20 "$WORK/manifest.diff"; fail "$1: manifest differs from the uninterrupted run's"; }
  "$ISPM" replay "$1" --golden "$WORK/ref" --report "$WORK/replay" > "$WORK/replay.out"; rc=$?
  [ $rc -eq 0 ] || { cat "$WORK/replay.out"; fail "$1: replay against the uninterrupted run exited $rc"; }
  grep -q "0 failed, 0 warned, 0 within tolerance" "$WORK/replay.out" || { cat "$WORK/replay.out"; fail "$1: not every buffer bit-exact"; }
}

# start_and_kill RUN DELAY_MS ARGS...: starts a recording, SIGKILLs it after DELAY_MS; prints
# "killed" or "finished".
start_and_kill() {
  run=$1; delay=$2; shift 2
  "$ISPM" record "$SEQ" -o "$run" --quiet "$@" > /dev/null 2>&1 &
  pid=$!
  sleep "$(printf '%d.%03d' $((delay / 1000)) $((delay % 1000)))"
  if kill -KILL "$pid" 2> /dev/null; then wait "$pid" 2> /dev/null; echo killed
  else wait "$pid"; [ $? -eq 0 ] || fail "record exited non-zero before the kill"; echo finished; fi
}

killed=0
for k in $(seq 1 "$KILLS"); do
  run=$WORK/run$k
  delay=$(( (RANDOM * 32768 + RANDOM) % (T + 1) ))
  what=$(start_and_kill "$run" "$delay")
  if [ "$what" = killed ]; then
    killed=$((killed + 1))
    if [ -f "$run/manifest.json" ]; then
      # Killed after the manifest's rename: the run is complete and must be whole.
      check_resumed "$run"
      echo "  kill $k after ${delay} ms: run already complete"
      continue
    fi
    "$ISPM" replay "$run" > /dev/null 2>&1; rc=$?
    [ $rc -eq 4 ] || fail "kill $k after ${delay} ms: replay of the interrupted run exited $rc, want 4"
    n=$(ls "$run/frames" 2> /dev/null | grep -c '\.exr$')
    # Every other kill also interrupts the resumed recording once.
    if [ $((k % 2)) -eq 0 ]; then
      what2=$(start_and_kill "$run" $(( RANDOM % (T / 2 + 1) )) --resume)
      if [ "$what2" = killed ] && [ ! -f "$run/manifest.json" ]; then
        "$ISPM" replay "$run" > /dev/null 2>&1; [ $? -eq 4 ] || fail "kill $k: replay accepted a run killed while resuming"
      fi
    fi
    if [ ! -f "$run/manifest.json" ]; then
      "$ISPM" record "$SEQ" -o "$run" --resume --quiet > /dev/null 2> "$WORK/resume.err"; rc=$?
      [ $rc -eq 0 ] || { cat "$WORK/resume.err"; fail "kill $k: --resume exited $rc"; }
    fi
    check_resumed "$run"
    echo "  kill $k after ${delay} ms: $n frame files left; resumed run bit-identical"
  else
    check_resumed "$run"
    echo "  kill $k after ${delay} ms: the recording had finished"
  fi
done
# The uninterrupted time is measured once; a machine that was busier then than later lets every
# delay outlast the recording. Then kill earlier, halving the range, until one recording is hit.
tries=0; run=$WORK/run-retry
while [ "$killed" -eq 0 ] && [ "$tries" -lt 6 ]; do
  tries=$((tries + 1)); T=$((T / 2))
  rm -rf "$run"
  delay=$(( RANDOM % (T + 1) ))
  if [ "$(start_and_kill "$run" "$delay")" = killed ]; then
    killed=1
    if [ -f "$run/manifest.json" ]; then
      check_resumed "$run"
    else
      "$ISPM" replay "$run" > /dev/null 2>&1; rc=$?
      [ $rc -eq 4 ] || fail "kill after ${delay} ms: replay of the interrupted run exited $rc, want 4"
      "$ISPM" record "$SEQ" -o "$run" --resume --quiet > /dev/null 2> "$WORK/resume.err" ||
        { cat "$WORK/resume.err"; fail "kill after ${delay} ms: --resume failed"; }
      check_resumed "$run"
    fi
    echo "  kill after ${delay} ms (range halved $tries times): resumed run bit-identical"
  fi
done
[ "$killed" -gt 0 ] || fail "no recording was killed (all finished within the delays)"

# Refusals, each one line and exit 2.
expect_refusal() {
  what=$1; shift
  "$ISPM" record "$@" --quiet > /dev/null 2> "$WORK/refuse.err"; rc=$?
  [ $rc -eq 2 ] || { cat "$WORK/refuse.err"; fail "$what: exit $rc, want 2"; }
  [ "$(wc -l < "$WORK/refuse.err")" -eq 1 ] || { cat "$WORK/refuse.err"; fail "$what: want one error line"; }
}
expect_refusal "--resume of a complete run" "$SEQ" -o "$WORK/ref" --resume
mkdir -p "$WORK/oldrun/frames"; cp "$WORK/ref/frames/000000.exr" "$WORK/oldrun/frames/"
expect_refusal "--resume of frames without run.json" "$SEQ" -o "$WORK/oldrun" --resume
expect_refusal "--resume with --force" "$SEQ" -o "$WORK/ref" --resume --force
cp -r "$WORK/ref" "$WORK/other"; rm "$WORK/other/manifest.json"
sed 's/"shadow_map_size": 64/"shadow_map_size": 32/' "$SEQ" > "$WORK/other.json"
expect_refusal "--resume with another sequence" "$WORK/other.json" -o "$WORK/other" --resume
grep -q "run.json" "$WORK/refuse.err" || fail "the refusal does not name run.json"
expect_refusal "--resume with other settings" "$SEQ" -o "$WORK/other" --resume --threads 3
# A frame with its EXR but not its record (killed between the renames) is rendered again.
rm "$WORK/other/frames/000002.json"
"$ISPM" record "$SEQ" -o "$WORK/other" --resume --quiet > /dev/null || fail "resume after a lost frame record"
check_resumed "$WORK/other"
echo "e2e_crash: ok ($killed of $KILLS recordings killed, none accepted by replay, all resumed bit-identical)"
