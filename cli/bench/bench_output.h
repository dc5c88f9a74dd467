/* bench_output.h — what `ispm bench` writes once every point has run: the tables, the charts,
 * the scatter/gather comparison and the speed-ups against the k-d gather. */
#ifndef ISPM_BENCH_OUTPUT_H
#define ISPM_BENCH_OUTPUT_H

#include "bench_config.h"
#include "bench_run.h"

/* Marks the Pareto front on pts and writes into outdir (which exists): compare_scatter_vs_gather
 * .png/.exr (when the points hold an ISPM / k-d gather pair at otherwise equal settings),
 * error_vs_time.png/.svg, pass_times.png, the convergence charts (with report_frames), then
 * bench.csv and, last, bench.json, each atomically. Without quiet, the scatter/gather
 * difference on stderr; then one "speedup vs kd-gather:" line per point paired with a k-d
 * gather point on stdout. Stops at the first failure; bench.json exists only if all went well. */
eng_result bench_write_results(const bench_config *c, const char *outdir, const char *command_line,
                               bench_point *pts, int n, const bench_passes *passes, const bench_reference *ref,
                               int quiet, eng_error *err);

#endif
