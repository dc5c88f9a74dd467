#!/bin/sh
# bench/perf_threads.sh — issue 22 item 3 (row 3 of bench/perf.sh) for two binaries side by side:
# `record` of scenes/cornell-box/cornell-box-perf.json (3 frames, 65,536 photons, 160²,
# final.display captured) with --threads 1 and --threads 2, and `record` of one 32² frame (the
# process start-up), for OLD and NEW alternating (old t1, new t1, old t2, new t2, ...), RUNS times
# each (default 3); prints the medians and the ratios, each taken within this one run.
#
# usage: bench/perf_threads.sh OLD_ISPM NEW_ISPM [OUTDIR]    (from the repository root)
# CHRT="chrt -f 5" (as root) runs every command at real-time priority, so that other load on a
# shared machine does not interleave (the ratios then read as on an idle machine).
set -eu

OLD=$1 NEW=$2
RUNS=${RUNS:-3}
OUT=${3:-$(mktemp -d /tmp/ispm-perf-threads.XXXXXX)}
CHRT=${CHRT:-}
PERF=scenes/cornell-box/cornell-box-perf.json
for b in "$OLD" "$NEW"; do [ -x "$b" ] || { echo "perf_threads.sh: $b is not an executable" >&2; exit 2; }; done
[ -f "$PERF" ] || { echo "perf_threads.sh: run from the repository root ($PERF not found)" >&2; exit 2; }
mkdir -p "$OUT"

# One 32² frame of the Cornell box: what a record costs besides its frames.
TINY=$OUT/tiny.json
sed -e 's/"frames": *[0-9]*/"frames": 1/' -e 's/"resolution": *\[[0-9, ]*\]/"resolution": [32, 32]/' \
    -e "s|\"scene\": *\"|\"scene\": \"$(pwd)/scenes/cornell-box/|" scenes/cornell-box/cornell-box-ci.json >"$TINY"

. "$(dirname "$0")/timing.sh" # now, median, ratio
seconds() { # COMMAND...: its wall time; a failure stops the benchmark
    s=$(now)
    $CHRT "$@" >>"$OUT/log" 2>&1 || { echo "perf_threads.sh: failed: $* (see $OUT/log)" >&2; exit 1; }
    e=$(now)
    awk -v s="$s" -v e="$e" 'BEGIN { printf "%.3f\n", e - s }'
}

echo "bench/perf_threads.sh: $RUNS runs each, alternating; $(nproc) CPUs, load $(cut -d' ' -f1-3 /proc/loadavg)${CHRT:+, under $CHRT}"
echo "  old: $OLD"
echo "  new: $NEW"
o1="" n1="" o2="" n2="" ot="" nt=""
i=0
while [ "$i" -lt "$RUNS" ]; do
    ot="$ot $(seconds "$OLD" record "$TINY" -o "$OUT/ot" --force --quiet)"
    nt="$nt $(seconds "$NEW" record "$TINY" -o "$OUT/nt" --force --quiet)"
    o1="$o1 $(seconds "$OLD" record $PERF -o "$OUT/o1" --force --quiet --threads 1 --capture final.display)"
    n1="$n1 $(seconds "$NEW" record $PERF -o "$OUT/n1" --force --quiet --threads 1 --capture final.display)"
    o2="$o2 $(seconds "$OLD" record $PERF -o "$OUT/o2" --force --quiet --threads 2 --capture final.display)"
    n2="$n2 $(seconds "$NEW" record $PERF -o "$OUT/n2" --force --quiet --threads 2 --capture final.display)"
    i=$((i + 1))
done
for v in ot nt o1 n1 o2 n2; do eval "m_$v=\$(echo \"\$$v\" | median)"; done
printf '  %-34s %6.2f s (runs:%s)\n' "old record, one 32² frame" "$m_ot" "$ot" "new record, one 32² frame" "$m_nt" "$nt" \
    "old --threads 1" "$m_o1" "$o1" "new --threads 1" "$m_n1" "$n1" "old --threads 2" "$m_o2" "$o2" \
    "new --threads 2" "$m_n2" "$n2"
echo "  start-up (one 32² frame): new takes $(ratio "$m_nt" "$m_ot")x old's time"
echo "  --threads 1: new takes $(ratio "$m_n1" "$m_o1")x old's time (must not be slower)"
echo "  2 threads faster than 1: old $(ratio "$m_o1" "$m_o2")x, new $(ratio "$m_n1" "$m_n2")x   (goal >= 1.8x)"
for t in 1 2; do
    # Bytes differ where the two binaries' default capture_compression does (zip before
    # session 8, rle in sessions 8-16, none since): then the pixels are compared through the frame's buffer digests.
    digests() { tr -d ' \t\n' < "$1" | grep -o '"digest":"[0-9a-f]*"'; }
    if cmp -s "$OUT/o$t/frames/000002.exr" "$OUT/n$t/frames/000002.exr"; then same="EXR files identical"
    elif [ -n "$(digests "$OUT/o$t/frames/000002.json")" ] &&
         [ "$(digests "$OUT/o$t/frames/000002.json")" = "$(digests "$OUT/n$t/frames/000002.json")" ]; then
        same="pixels identical (every buffer digest; the EXR bytes differ: compression)"
    else same="DIFFERENT"; fi
    echo "  frame 2, --threads $t: old and new $same"
done
