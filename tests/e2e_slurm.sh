#!/usr/bin/env bash
# Frame shards on a real Slurm cluster (issue 20): a private one-node cluster started here
# (scripts/slurm/local-cluster.sh: own munged, slurmctld, slurmd, stopped by PID on exit)
# records the CI sequence (golden/cornell-box-ci's sequence.path) as 3 shards in a job array
# (scripts/slurm/shard.sbatch), merges them in a job that depends on the array
# (merge.sbatch, afterok) and replays the merged run against the golden in a third job
# (replay.sbatch): every buffer bit-exact. Then a shard killed mid-way (scancel of one array
# task while it records): the merge job is cancelled (kill_invalid_depend), the shard has no
# manifest, no merged run that looks complete exists, and ispm merge run by hand refuses it.
# Exit 77 when no cluster can be started here (not root, no slurm-wlm/munge), unless
# ISPM_REQUIRE_DEPS=1 (CI), where that is a failure.
# usage: e2e_slurm.sh ISPM SOURCE_DIR WORK_DIR
set -u
ISPM=$1; SRC=$2; WORK=$3
fail() { echo "FAIL: $*"; [ -d "$WORK/cluster/log" ] && tail -n 5 "$WORK"/cluster/log/*.log 2>/dev/null; exit 1; }
rm -rf "$WORK"; mkdir -p "$WORK"
WORK=$(cd "$WORK" && pwd); ISPM=$(cd "$(dirname "$ISPM")" && pwd)/$(basename "$ISPM")
CLUSTER=$SRC/scripts/slurm/local-cluster.sh
t0=$(date +%s)

out=$(bash "$CLUSTER" start "$WORK/cluster" 2> "$WORK/cluster.err"); rc=$?
if [ $rc -eq 77 ]; then
  [ "${ISPM_REQUIRE_DEPS:-0}" = 1 ] && fail "$(cat "$WORK/cluster.err")"
  echo "SKIP: $(cat "$WORK/cluster.err")"; exit 77
fi
trap 'bash "$CLUSTER" stop "$WORK/cluster"' EXIT
[ $rc -eq 0 ] || fail "the cluster did not start: $(cat "$WORK/cluster.err")"
eval "$out"
PATH=$PATH:/usr/sbin
echo "e2e_slurm: cluster up in $(( $(date +%s) - t0 )) s ($SLURM_CONF)"

GOLDEN=$SRC/golden/cornell-box-ci
SEQ=$(sed -n 's/.*"path":[[:space:]]*"\([^"]*\.json\)".*/\1/p' "$GOLDEN/manifest.json" | head -n 1)
[ -f "$SRC/$SEQ" ] || fail "golden/cornell-box-ci names sequence '$SEQ', not found"
export ISPM

state() { scontrol show job "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | head -n 1; }
# wait_done ID...: every job (and array task) ended; 90 s at most.
wait_done() {
  for _ in $(seq 450); do
    [ -z "$(squeue -h -j "$(IFS=,; echo "$*")" 2>/dev/null)" ] && return 0
    sleep 0.2
  done
  squeue; fail "jobs $* still queued after 90 s"
}

# 1. Three shards, merge, replay: bit-exact against the golden.
ids=$(cd "$SRC" && bash scripts/slurm/submit.sh "$SEQ" "$WORK/ok" 3 "$GOLDEN" -- --chdir="$SRC") || fail "submit.sh"
eval "$ids"
echo "e2e_slurm: submitted $ids"
wait_done "$shards" "$merge" "$replay"
for k in 0 1 2; do [ -f "$WORK/ok/shard-$k/manifest.json" ] || { cat "$WORK/ok/shard-$k.log"; fail "shard $k incomplete"; }; done
[ "$(state "$merge")" = COMPLETED ] || { cat "$WORK/ok/merge.log"; fail "merge job $(state "$merge")"; }
[ "$(state "$replay")" = COMPLETED ] || { cat "$WORK/ok/replay.log"; fail "replay job $(state "$replay")"; }
grep -qE "0 failed, 0 warned, 0 within tolerance, ([0-9]+) bit-exact \(\1 buffers, 8 frames\)" "$WORK/ok/replay.log" ||
  { cat "$WORK/ok/replay.log"; fail "merged run not bit-exact against $GOLDEN"; }
grep -q '"shards"' "$WORK/ok/run/manifest.json" || fail "merged manifest records no shards"
echo "e2e_slurm: 3 shards merged, replay: $(grep -o '[0-9]* bit-exact ([0-9]* buffers, 8 frames)' "$WORK/ok/replay.log")"

# 2. A shard killed mid-way: task 1 cancelled once its recording has begun.
ids=$(cd "$SRC" && bash scripts/slurm/submit.sh "$SEQ" "$WORK/kill" 3 "$GOLDEN" -- --chdir="$SRC") || fail "submit.sh"
eval "$ids"
for _ in $(seq 300); do [ -f "$WORK/kill/shard-1/run.json" ] && break; sleep 0.1; done
[ -f "$WORK/kill/shard-1/run.json" ] || fail "shard 1 never began recording"
scancel "${shards}_1" || fail "scancel ${shards}_1"
# The merge is cancelled as soon as its dependency can never be met; the other shards are then
# cancelled too, to end the test early.
for _ in $(seq 300); do [ "$(state "$merge")" = CANCELLED ] && break; sleep 0.1; done
scancel "$shards"
wait_done "$shards" "$merge" "$replay"
[ "$(state "$merge")" = CANCELLED ] || fail "merge job is $(state "$merge") after a cancelled shard (expected CANCELLED)"
[ "$(state "$replay")" = CANCELLED ] || fail "replay job is $(state "$replay") (expected CANCELLED)"
[ ! -f "$WORK/kill/shard-1/manifest.json" ] || fail "the killed shard has a manifest"
[ ! -f "$WORK/kill/run/manifest.json" ] || fail "a merged run that looks complete exists"
"$ISPM" merge "$WORK/kill/shard-0" "$WORK/kill/shard-1" "$WORK/kill/shard-2" -o "$WORK/kill/run" > "$WORK/merge.out" 2>&1; rc=$?
[ $rc -eq 2 ] || { cat "$WORK/merge.out"; fail "ispm merge with a killed shard exited $rc (expected 2)"; }
grep -q "shard-1: no manifest.json" "$WORK/merge.out" || { cat "$WORK/merge.out"; fail "merge did not name the incomplete shard"; }
[ ! -f "$WORK/kill/run/manifest.json" ] || fail "ispm merge left a complete-looking run"
"$ISPM" replay "$WORK/kill/run" > /dev/null 2>&1; rc=$?
[ $rc -eq 4 ] || fail "replay of the refused merge exited $rc (expected 4: no run)"
echo "e2e_slurm: killed shard: merge $(state "$merge"), no merged run ($(head -n 1 "$WORK/merge.out"))"
echo "e2e_slurm: PASS in $(( $(date +%s) - t0 )) s"
