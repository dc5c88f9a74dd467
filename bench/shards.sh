#!/usr/bin/env bash
# Frame shards against one machine (issue 20), two measurements:
#   bench/shards.sh equal OUTDIR SEQUENCE... [-- SHARD_COUNTS]
#     per sequence: one recording on this machine, then for each shard count (default 2 3 4)
#     the shards (record --shard K/N) merged; every buffer digest of every frame of the merged
#     run against the one-machine run's. Each shard starts with the smallest warm-up (1 frame,
#     written as the overlap); when merge refuses it ("needs --warmup W") the shard is recorded
#     again with that warm-up: the table gives the warm-up each shard needed.
#   bench/shards.sh time OUTDIR SEQUENCE [SHARDS=4] [REPEATS=2]
#     wall time of SHARDS shards on a private one-node Slurm cluster (scripts/slurm/, submit to
#     merged run) against one `ispm record` on the same machine, alternating, REPEATS times;
#     prints each pair and the median ratio. Needs root (slurmd).
# ISPM names the binary (default build/cli/ispm). Run from the repository root.
set -u
ISPM=${ISPM:-build/cli/ispm}
mode=${1:?usage: shards.sh equal|time OUTDIR ...}; OUT=${2:?usage: shards.sh equal|time OUTDIR ...}; shift 2
mkdir -p "$OUT"

# digests RUN: one line per buffer, "frame name digest", from the manifest.
digests() {
  awk '/"index":/ { gsub(/[^0-9]/, "", $2); f = $2 }
       /"name":/ { n = $2 }
       /"digest":/ && n != "" && f != "" { print f, n, $2; n = "" }' "$1/manifest.json"
}

if [ "$mode" = equal ]; then
  counts="2 3 4"; seqs=()
  while [ $# -gt 0 ]; do [ "$1" = -- ] && { shift; counts="$*"; break; }; seqs+=("$1"); shift; done
  printf "%-28s %6s %8s %10s %-14s %s\n" sequence shards frames buffers equal "warm-up needed per shard (frames)"
  for seq in "${seqs[@]}"; do
    name=$(basename "$seq" .json); D=$OUT/$name
    "$ISPM" record "$seq" -o "$D/one" --force --quiet > /dev/null || { echo "$name: record failed"; continue; }
    for n in $counts; do
      S=$D/n$n; rm -rf "$S"; mkdir -p "$S"; warm=()
      for ((k = 0; k < n; k++)); do
        warm[k]=1
        "$ISPM" record "$seq" -o "$S/shard-$k" --shard "$k/$n" --warmup 1 --overlap 1 --quiet > /dev/null || echo "shard $k failed"
      done
      shards=(); for ((k = 0; k < n; k++)); do shards+=("$S/shard-$k"); done
      for ((try = 0; try <= n; try++)); do
        msg=$("$ISPM" merge "${shards[@]}" -o "$S/run" --force 2>&1 > /dev/null) && break
        k=$(echo "$msg" | sed -n 's|.*/shard-\([0-9]*\): frame .*|\1|p')
        w=$(echo "$msg" | sed -n 's/.*needs --warmup \([0-9]*\).*/\1/p')
        [ -n "$k" ] && [ -n "$w" ] || { echo "$name n=$n: merge refused: $msg"; break; }
        warm[k]=$w
        "$ISPM" record "$seq" -o "$S/shard-$k" --shard "$k/$n" --warmup "$w" --overlap 1 --force --quiet > /dev/null
      done
      warm[0]=0 # the first shard begins at frame 0: nothing to warm up
      if [ -f "$S/run/manifest.json" ]; then
        total=$(digests "$D/one" | wc -l)
        same=$(diff <(digests "$D/one") <(digests "$S/run") > /dev/null && echo "all" || echo "DIFFER")
        frames=$(grep -c '"file":' "$S/run/manifest.json")
        printf "%-28s %6d %8d %10d %-14s %s\n" "$name" "$n" "$frames" "$total" "$same" "${warm[*]}"
      else
        printf "%-28s %6d %8s %10s %-14s %s\n" "$name" "$n" - - refused "${warm[*]}"
      fi
    done
  done
  exit 0
fi

if [ "$mode" = time ]; then
  seq=${1:?usage: shards.sh time OUTDIR SEQUENCE [SHARDS] [REPEATS]}; n=${2:-4}; reps=${3:-2}
  ISPM=$(cd "$(dirname "$ISPM")" && pwd)/$(basename "$ISPM"); export ISPM
  C=$OUT/cluster; rm -rf "$C"
  env_line=$(bash scripts/slurm/local-cluster.sh start "$C") || exit $?
  trap 'bash scripts/slurm/local-cluster.sh stop "$C"' EXIT
  eval "$env_line"; PATH=$PATH:/usr/sbin
  now() { date +%s.%N; }
  ratios=()
  for ((r = 0; r < reps; r++)); do
    t0=$(now); "$ISPM" record "$seq" -o "$OUT/one" --force --quiet > /dev/null; t1=$(now)
    rm -rf "$OUT/slurm"
    ids=$(bash scripts/slurm/submit.sh "$seq" "$OUT/slurm" "$n" -- --chdir="$PWD"); eval "$ids"
    while [ -n "$(squeue -h -j "$shards,$merge" 2>/dev/null)" ]; do sleep 0.2; done
    t2=$(now)
    [ -f "$OUT/slurm/run/manifest.json" ] || { cat "$OUT/slurm/merge.log"; echo "merge failed"; exit 1; }
    one=$(awk -v a="$t0" -v b="$t1" 'BEGIN { print b - a }'); sl=$(awk -v a="$t1" -v b="$t2" 'BEGIN { print b - a }')
    ratio=$(awk -v a="$one" -v b="$sl" 'BEGIN { printf "%.3f", b / a }')
    ratios+=("$ratio")
    printf "repeat %d: one machine %.1f s, %d shards on Slurm (submit to merged run) %.1f s, ratio %s\n" "$r" "$one" "$n" "$sl" "$ratio"
  done
  printf "median ratio slurm/one: %s\n" "$(printf '%s\n' "${ratios[@]}" | sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')"
  exit 0
fi
echo "usage: shards.sh equal|time OUTDIR ..." >&2; exit 2
