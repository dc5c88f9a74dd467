#!/usr/bin/env bash
# Fault injection in the style of SQLite's: every call that writes (open to create, write,
# fsync, rename, link, mkdir, ...; tests/tool_fault.c, preloaded) of record (a new run and
# --force onto one), bless (a new golden
# and --accept onto one), merge (a new run and --force onto one) and export (.png, .exr onto an
# existing file) is made to fail in turn, and the state after each is checked: the command
# either succeeded with a valid result (the failed call was one it may survive) or failed and
# left the previous state as it was — no run or golden that looks complete, the old golden, run
# or image byte for byte. Each command's calls are first counted; then every STEP-th is failed,
# STEP chosen so that each command is tried about FAULT_TRIALS times (10: about two minutes on
# two cores; FAULT_TRIALS=0 fails every call). Prints per command the calls, the faults injected
# and how many ended in failure (state intact) or success (result valid).
# usage: e2e_faults.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$(realpath "$1"); SRC=$(realpath "$2"); WORK=$3
SHIM=$(dirname "$ISPM")/../tests/libispm_fault.so
fail() { echo "FAIL: $*"; exit 1; }
[ -f "$SHIM" ] || { echo "SKIP: $SHIM not built"; exit 77; }
TRIALS=${FAULT_TRIALS:-10}
rm -rf "$WORK"; mkdir -p "$WORK"
W=$WORK
printf '{"scene": "%s", "frames": 2, "fps": 8, "resolution": [32, 24], "camera": {"node": "Camera"},
 "settings": {"shadow_map_size": 16, "photon_count": 256}}\n' "$SRC/scenes/cornell-box/cornell-box.gltf" > "$W/tiny.json"
sed 's/"photon_count": 256/"photon_count": 512/' "$W/tiny.json" > "$W/other.json"

"$ISPM" record "$W/tiny.json" -o "$W/run" --quiet > /dev/null || fail "record the fixture run"
"$ISPM" record "$W/other.json" -o "$W/run2" --quiet > /dev/null || fail "record the second run"
"$ISPM" bless "$W/run" "$W/gold" > /dev/null || fail "bless the fixture golden"
"$ISPM" record "$W/tiny.json" -o "$W/shardA" --frames 0-0 --quiet > /dev/null || fail "record shard A"
"$ISPM" record "$W/tiny.json" -o "$W/shardB" --frames 1-1 --quiet > /dev/null || fail "record shard B"
"$ISPM" export "$W/run" --frame 0 --buffer final.display -o "$W/want.png" > /dev/null || fail "export png"
"$ISPM" export "$W/run" --frame 0 --buffer final.display -o "$W/want.exr" > /dev/null || fail "export exr"

tree_sum() { (cd "$1" && find . -type f -print0 | sort -z | xargs -0 sha256sum) | sha256sum; }
replays() { "$ISPM" replay "$1" --golden "$2" --report "$W/rep" > /dev/null 2>&1; }
TOTAL_FAULTS=0; TOTAL_CHECKS=0

# trial NAME SETUP CHECK_OK CHECK_FAILED CMD...: counts CMD's calls once, then fails every STEP-th.
# SETUP restores the state before each try; CHECK_OK judges a success, CHECK_FAILED a failure.
trial() {
  name=$1; setup=$2; ok=$3; failed=$4; shift 4
  $setup
  ISPM_FAULT_LOG="$W/log" LD_PRELOAD="$SHIM" "$@" > /dev/null 2>&1 || fail "$name: fails without a fault"
  $ok || fail "$name: no valid result without a fault"
  calls=$(cut -d' ' -f1 "$W/log")
  [ "$calls" -gt 0 ] || fail "$name: no call counted"
  first=1 # TAIL=N: only the last N calls (what comes after a part already tried elsewhere)
  [ "${TAIL:-0}" -gt 0 ] && [ "$calls" -gt "$TAIL" ] && first=$((calls - TAIL + 1))
  span=$((calls - first + 1))
  step=1
  [ "$TRIALS" -gt 0 ] && step=$(( (span + TRIALS - 1) / TRIALS ))
  n_fault=0; n_failed=0; n_ok=0
  for k in $(seq "$first" "$step" "$calls") $([ $(( (span - 1) % step )) -ne 0 ] && echo "$calls"); do
    $setup
    ISPM_FAULT_AT=$k ISPM_FAULT_LOG="$W/log" LD_PRELOAD="$SHIM" "$@" > "$W/out.txt" 2> "$W/err.txt"; rc=$?
    [ "$(cut -d' ' -f2 "$W/log")" = 1 ] || fail "$name: call $k of $calls was not reached"
    n_fault=$((n_fault + 1))
    if [ $rc -eq 0 ]; then
      $ok || { cat "$W/err.txt"; fail "$name: call $k failed, exit 0, but the result is not valid"; }
      n_ok=$((n_ok + 1))
    else
      [ $rc -lt 128 ] || { cat "$W/err.txt"; fail "$name: call $k failed: killed by a signal ($rc)"; }
      $failed || { cat "$W/err.txt"; fail "$name: call $k failed (exit $rc) and the previous state is lost"; }
      n_failed=$((n_failed + 1))
    fi
  done
  TOTAL_FAULTS=$((TOTAL_FAULTS + n_fault)); TOTAL_CHECKS=$((TOTAL_CHECKS + n_fault))
  printf '%-28s %4d calls, %3d faults (every %d from %d): %3d failed with the old state intact, %3d succeeded validly\n' \
    "$name" "$calls" "$n_fault" "$step" "$first" "$n_failed" "$n_ok"
}

# record into a fresh folder: a complete run that replays bit-exact, or no manifest.
rec_setup() { rm -rf "$W/r" "$W/r.lock"; }
rec_ok() { replays "$W/r" "$W/gold"; }
rec_failed() { [ ! -e "$W/r/manifest.json" ]; }
trial "record" rec_setup rec_ok rec_failed "$ISPM" record "$W/tiny.json" -o "$W/r" --quiet

# record --force onto a complete run (run2): the new run, or run2 as it was.
rforce_setup() {
  rm -rf "$W/r" "$W/r.recording" "$W/r.replaced" "$W/r.lock"; cp -r "$W/run2" "$W/r"
  [ -n "${R_SUM:-}" ] || R_SUM=$(tree_sum "$W/r")
}
rforce_failed() { [ "$(tree_sum "$W/r")" = "$R_SUM" ] && [ ! -e "$W/r.recording" ]; }
trial "record --force" rforce_setup rec_ok rforce_failed "$ISPM" record "$W/tiny.json" -o "$W/r" --force --quiet

# bless a new golden: a golden the run replays against, or none.
bnew_setup() { rm -rf "$W/g" "$W/g.tmp" "$W/g.old" "$W/g.lock"; }
bnew_ok() { replays "$W/run" "$W/g"; }
bnew_failed() { [ ! -e "$W/g/manifest.json" ]; }
trial "bless (new golden)" bnew_setup bnew_ok bnew_failed "$ISPM" bless "$W/run" "$W/g"

# bless --accept onto a golden with tuned tolerances: the new golden with them, or the old one.
bacc_setup() {
  rm -rf "$W/g" "$W/g.tmp" "$W/g.old" "$W/g.lock"; cp -r "$W/gold" "$W/g"
  echo '{"default": {"warn": 0.25}, "buffers": []}' > "$W/g/tolerances.json"
  [ -n "${G_SUM:-}" ] || G_SUM=$(tree_sum "$W/g")
}
bacc_ok() { grep -q 0.25 "$W/g/tolerances.json" && "$ISPM" replay "$W/run2" --golden "$W/g" -fail 0 -warn 0 --report "$W/rep" > /dev/null 2>&1; }
bacc_failed() { [ "$(tree_sum "$W/g")" = "$G_SUM" ]; }
# Most of bless --accept's calls are its review's (a replay writing the HTML report into the
# run's bless/ folder, which bless goes on without): the last 260, the golden's own, are tried.
TAIL=260 trial "bless --accept" bacc_setup bacc_ok bacc_failed "$ISPM" bless "$W/run2" "$W/g" --accept

# merge into a fresh folder: a run that replays bit-exact, or no manifest.
mnew_setup() { rm -rf "$W/m" "$W/m.merging" "$W/m.replaced" "$W/m.lock"; }
mnew_ok() { replays "$W/m" "$W/gold"; }
mnew_failed() { [ ! -e "$W/m/manifest.json" ]; }
trial "merge (new run)" mnew_setup mnew_ok mnew_failed "$ISPM" merge "$W/shardA" "$W/shardB" -o "$W/m"

# merge --force onto a complete run (run2's frames): the merged run, or run2 as it was.
mforce_setup() {
  rm -rf "$W/m" "$W/m.merging" "$W/m.replaced" "$W/m.lock"; cp -r "$W/run2" "$W/m"
  [ -n "${M_SUM:-}" ] || M_SUM=$(tree_sum "$W/m")
}
mforce_failed() { [ "$(tree_sum "$W/m")" = "$M_SUM" ]; }
trial "merge --force" mforce_setup mnew_ok mforce_failed "$ISPM" merge "$W/shardA" "$W/shardB" -o "$W/m" --force

# export onto an existing image (another buffer's): the new image, or the old one; no temporary
# left. Two EXR exports differ in their capDate attribute only.
same_image() {
  [ "$(stat -c %s "$1")" = "$(stat -c %s "$2")" ] || return 1
  at=$(grep -boa capDate "$1" | head -n 1 | cut -d: -f1)
  cmp -l "$1" "$2" | awk -v lo="${at:--100}" '$1 - 1 < lo || $1 - 1 > lo + 60 { bad = 1 } END { exit bad }'
}
for ext in png exr; do
  eval "exp_setup_$ext() { \"$ISPM\" export \"$W/run\" --frame 0 --buffer direct.radiance -o \"$W/x.$ext\" > /dev/null 2>&1 || true; cp \"$W/x.$ext\" \"$W/x.$ext.old\"; }"
  eval "exp_ok_$ext() { same_image \"$W/x.$ext\" \"$W/want.$ext\" && ! ls \"$W\" | grep -q 'x.$ext.tmp'; }"
  eval "exp_failed_$ext() { cmp -s \"$W/x.$ext\" \"$W/x.$ext.old\" && ! ls \"$W\" | grep -q 'x.$ext.tmp'; }"
  trial "export .$ext" exp_setup_$ext exp_ok_$ext exp_failed_$ext \
    "$ISPM" export "$W/run" --frame 0 --buffer final.display -o "$W/x.$ext"
done

echo "e2e_faults: $TOTAL_FAULTS faults injected, $TOTAL_CHECKS states checked"
