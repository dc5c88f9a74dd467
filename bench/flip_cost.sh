#!/usr/bin/env bash
# What ꟻLIP costs a replay (issue 19 item 2): `ispm replay RUN --golden GOLDEN` with and without
# --no-flip, alternating, REPEATS times each; prints the median wall and CPU (user) seconds of each
# and their ratios. Replays of a run bit-exact to its golden compute no ꟻLIP at all (identical
# buffers get 0 without a filter pass), so measure both such a run and one that differs.
# usage: bench/flip_cost.sh ISPM RUN GOLDEN [REPEATS=3]
set -u
ISPM=$1; RUN=$2; GOLDEN=$3; N=${4:-3}
OUT=$(mktemp -d); trap 'rm -rf "$OUT"' EXIT
with=(); without=(); uwith=(); uwithout=()
one() { # ARGS...: prints "wall user"
  /usr/bin/time -f '%e %U' -o "$OUT/t" "$ISPM" replay "$RUN" --golden "$GOLDEN" --report "$OUT/rep" --quiet "$@" > /dev/null
  tail -n 1 "$OUT/t" # (a non-zero exit adds a line before it)
}
for _ in $(seq "$N"); do
  read -r w u <<< "$(one)"; with+=("$w"); uwith+=("$u")
  read -r w u <<< "$(one --no-flip)"; without+=("$w"); uwithout+=("$u")
done
median() { printf '%s\n' "$@" | sort -g | awk '{ a[NR] = $1 } END { print a[int((NR + 1) / 2)] }'; }
mw=$(median "${with[@]}"); mo=$(median "${without[@]}"); uw=$(median "${uwith[@]}"); uo=$(median "${uwithout[@]}")
awk -v mw="$mw" -v mo="$mo" -v uw="$uw" -v uo="$uo" -v n="$N" 'BEGIN {
  printf "replay with FLIP: %.2f s wall, %.2f s user; without: %.2f s wall, %.2f s user (median of %d)\n", mw, uw, mo, uo, n
  printf "ratio with/without: wall x%.2f, user x%.2f\n", mw / mo, uw / uo }'
