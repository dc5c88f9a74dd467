/* rep_trend.h — the trend over replayed runs (trend.c): how the metrics that creep (ꟻLIP mean,
 * flicker, a pass's share of the frame, the frame time) moved from run to run, as trend.json and
 * trend.html with charts (plot.h).
 */
#ifndef ISPM_REP_TREND_H
#define ISPM_REP_TREND_H

#include <stdio.h>

#include "eng_core.h"

/* Writes out_dir/trend.json and out_dir/trend.html (charts in out_dir/img/) over the runs, in the
 * order given. Each run must have been replayed (RUN/replay/report.json, or report_dirs[i] when
 * report_dirs is not NULL) and hold its manifest: a run without either is ENG_ERR_IO, a report
 * that is not replay's ENG_ERR_INVALID, both naming the file. Per run: the verdict, the frame
 * time and each pass's time and share (medians over frames, from the manifest), and per buffer
 * max |Δ| (max over frames), RMSE (over all frames), ꟻLIP mean (mean over frames) and p99 (max),
 * and flicker (reprojected and static mean, from the replay's stability measurement). Every
 * series records where it moved most (the largest step between consecutive runs), which the
 * charts ring. One line to summary (may be NULL). */
eng_result rep_trend_write(const char *const *runs, const char *const *report_dirs, int run_count, const char *out_dir,
                           FILE *summary, eng_error *err);

/* The run's tool.git (the commit its binary was built from, "-dirty" removed), or NULL when the
 * manifest cannot be read or names none. Caller frees. */
char *rep_trend_run_git(const char *run_dir);

#endif
