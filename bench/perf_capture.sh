#!/bin/sh
# bench/perf_capture.sh — issue 22 row 1 (bench/perf.sh) for two binaries side by side: `record`
# of scenes/cornell-box/cornell-box-ci.json (8 frames, 160²) capturing all 43 buffers and
# capturing final.display only, for OLD and NEW alternating (old all, new all, old display,
# new display, ...), RUNS times each (default 3); prints the medians, each binary's ratio all /
# display-only (goal <= 1.2x), whether NEW's display-only side is slower than OLD's, the
# process CPU time (user + sys, less distorted by other load than wall time) of each side, and
# whether the two all-buffer runs hold the same buffers with the same digests.
#
# usage: bench/perf_capture.sh OLD_ISPM NEW_ISPM [OUTDIR]    (from the repository root)
# CHRT="chrt -f 5" (as root) runs every command at real-time priority, as in perf_threads.sh.
set -eu

CI=scenes/cornell-box/cornell-box-ci.json
bad() { echo "perf_capture.sh: $*" >&2; exit 2; }
[ $# -ge 2 ] && [ $# -le 3 ] || bad "usage: bench/perf_capture.sh OLD_ISPM NEW_ISPM [OUTDIR]"
[ -f "$CI" ] || bad "run from the repository root ($CI not found)"
[ -x "$1" ] && [ -x "$2" ] || bad "$1 or $2 is not an executable"
OLD=$1 NEW=$2 OUT=${3:-$(mktemp -d /tmp/ispm-perf-capture.XXXXXX)} RUNS=${RUNS:-3} CHRT=${CHRT:-}
mkdir -p "$OUT"

. "$(dirname "$0")/timing.sh" # now, median, ratio
seconds() { # NAME COMMAND...: prints its wall time; appends its CPU seconds (user + sys) to $OUT/cpu.NAME
    name=$1
    shift
    s=$(now)
    # A shell that runs the command, then reads its own children's CPU ticks (cutime + cstime).
    LOG=$OUT/log $CHRT sh -c '"$@" >>"$LOG" 2>&1 || exit 1; awk -v t="$(getconf CLK_TCK)" "{ printf \" %.2f\", (\$16 + \$17) / t }" /proc/$$/stat' \
        sh "$@" 2>>"$OUT/log" >>"$OUT/cpu.$name" || { echo "perf_capture.sh: failed: $* (see $OUT/log)" >&2; exit 1; }
    e=$(now)
    awk -v s="$s" -v e="$e" 'BEGIN { printf "%.3f\n", e - s }'
}

echo "bench/perf_capture.sh: $RUNS runs each, alternating; $(nproc) CPUs, load $(cut -d' ' -f1-3 /proc/loadavg)${CHRT:+, under $CHRT}"
echo "  old: $OLD"
echo "  new: $NEW"
oa="" na="" od="" nd=""
rm -f "$OUT"/cpu.*
i=0
while [ "$i" -lt "$RUNS" ]; do
    oa="$oa $(seconds oa "$OLD" record $CI -o "$OUT/oa" --force --quiet)"
    na="$na $(seconds na "$NEW" record $CI -o "$OUT/na" --force --quiet)"
    od="$od $(seconds od "$OLD" record $CI -o "$OUT/od" --force --quiet --capture final.display)"
    nd="$nd $(seconds nd "$NEW" record $CI -o "$OUT/nd" --force --quiet --capture final.display)"
    i=$((i + 1))
done
for v in oa na od nd; do
    eval "m_$v=\$(echo \"\$$v\" | median)"
    eval "c$v=\$(cat \"\$OUT/cpu.$v\")"
    eval "m_c$v=\$(echo \"\$c$v\" | median)"
done
printf '  %-28s %6.2f s, CPU %5.2f s (runs:%s; CPU:%s)\n' \
    "old all buffers" "$m_oa" "$m_coa" "$oa" "$coa" "new all buffers" "$m_na" "$m_cna" "$na" "$cna" \
    "old final.display only" "$m_od" "$m_cod" "$od" "$cod" "new final.display only" "$m_nd" "$m_cnd" "$nd" "$cnd"
echo "  all / display-only: old $(ratio "$m_oa" "$m_od")x, new $(ratio "$m_na" "$m_nd")x   (goal <= 1.2x; CPU: old $(ratio "$m_coa" "$m_cod")x, new $(ratio "$m_cna" "$m_cnd")x)"
echo "  new / old: all buffers $(ratio "$m_na" "$m_oa")x, final.display only $(ratio "$m_nd" "$m_od")x (must not be slower)"
# Same buffers, same digests (the frame records also hold timings, which differ run to run).
digests() { grep -h -E '"(name|digest)"' "$1"/frames/*.json; }
if [ -n "$(digests "$OUT/oa")" ] && [ "$(digests "$OUT/oa")" = "$(digests "$OUT/na")" ]; then same=identical; else same=DIFFERENT; fi
echo "  all-buffer runs: buffer names and digests $same ($(ls "$OUT/oa/frames/"*.exr | wc -l) frames), $(du -sk "$OUT/oa/frames" | cut -f1) KiB old, $(du -sk "$OUT/na/frames" | cut -f1) KiB new"
