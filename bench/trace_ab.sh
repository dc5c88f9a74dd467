#!/bin/sh
# trace_ab.sh — two ispm builds' photon trace side by side (issue 22 item 4): `ispm tracebench`
# of each, alternating A, B, A, B, ... RUNS times, on the same sequence; prints every run's
# "% of raw" (the trace's rays/s over raw rtcIntersect1's on the same rays, measured in the
# same process) and the medians, and B's trace rate over A's. On a loaded machine single
# timings swing by ±50 %: read the medians of the alternated runs.
#
# usage: bench/trace_ab.sh OLD_ISPM NEW_ISPM [SEQUENCE] [-- tracebench options]
#        (RUNS=N, default 5; SEQUENCE default scenes/cornell-box/cornell-box-perf.json)
set -eu
[ $# -ge 2 ] || { echo "usage: bench/trace_ab.sh OLD_ISPM NEW_ISPM [SEQUENCE] [-- tracebench options]" >&2; exit 2; }
A=$1 B=$2
shift 2
SEQ=scenes/cornell-box/cornell-box-perf.json
if [ $# -gt 0 ] && [ "$1" != "--" ]; then SEQ=$1; shift; fi
[ $# -gt 0 ] && [ "$1" = "--" ] && shift
RUNS=${RUNS:-5}
for bin in "$A" "$B"; do
    "$bin" tracebench --help >/dev/null 2>&1 || { echo "trace_ab: $bin: no 'ispm tracebench'" >&2; exit 2; }
done
TMP=$(mktemp -d /tmp/ispm-trace-ab.XXXXXX)
trap 'rm -rf "$TMP"' EXIT
median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
# One tracebench run of binary $1 (options after it): prints "trace_Mrays raw_Mrays percent".
one() {
    bin=$1
    shift
    "$bin" tracebench "$SEQ" "$@" >"$TMP/out" 2>&1 || { cat "$TMP/out" >&2; exit 1; }
    grep -q 'bit-identical to the ray-by-ray trace: yes' "$TMP/out" || { echo "trace_ab: $bin: photon map differs" >&2; exit 1; }
    awk '/photon trace /{t=$3} /raw rtcIntersect1/{r=$3} /ratio/{p=$2} END{print t, r, p}' "$TMP/out"
}
shift_args="$*"
i=1
while [ "$i" -le "$RUNS" ]; do
    # shellcheck disable=SC2086
    a=$(one "$A" $shift_args) && echo "$a" >>"$TMP/a"
    # shellcheck disable=SC2086
    b=$(one "$B" $shift_args) && echo "$b" >>"$TMP/b"
    echo "run $i: A trace $(echo "$a" | cut -d' ' -f1) Mrays/s, raw $(echo "$a" | cut -d' ' -f2), $(echo "$a" | cut -d' ' -f3) % of raw  |  B trace $(echo "$b" | cut -d' ' -f1) Mrays/s, raw $(echo "$b" | cut -d' ' -f2), $(echo "$b" | cut -d' ' -f3) % of raw"
    i=$((i + 1))
done
pa=$(cut -d' ' -f3 "$TMP/a" | median) pb=$(cut -d' ' -f3 "$TMP/b" | median)
ta=$(cut -d' ' -f1 "$TMP/a" | median) tb=$(cut -d' ' -f1 "$TMP/b" | median)
ra=$(cut -d' ' -f2 "$TMP/a" | median) rb=$(cut -d' ' -f2 "$TMP/b" | median)
echo "medians over $RUNS alternated runs of $SEQ:"
echo "  A $A: trace $ta Mrays/s, raw $ra Mrays/s, $pa % of raw"
echo "  B $B: trace $tb Mrays/s, raw $rb Mrays/s, $pb % of raw   (goal >= 70 %: $(awk -v p="$pb" 'BEGIN{print (p >= 70) ? "met" : "SHORT"}'))"
echo "  B's trace rate / A's: $(awk -v a="$ta" -v b="$tb" 'BEGIN{printf "%.2fx", (a > 0) ? b / a : 0}')   B's raw rate / A's: $(awk -v a="$ra" -v b="$rb" 'BEGIN{printf "%.2fx", (a > 0) ? b / a : 0}')"
