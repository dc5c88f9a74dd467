# bench/timing.sh — the timing helpers bench/perf.sh, perf_threads.sh and perf_capture.sh share
# (sourced, not run): wall-clock now, the median of a space-separated list on stdin, a ratio.
now() { date +%s.%N; }
median() { tr ' ' '\n' | grep . | sort -n | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }
ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", a / b }'; }
