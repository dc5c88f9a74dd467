/* rep_regress.h — tolerances from evidence (suggest.c): the replay module's tool for the daily
 * regression suite beside rep.h's replay and bless. The trend over replayed runs is the report
 * room's (report/rep_trend.h).
 */
#ifndef ISPM_REP_REGRESS_H
#define ISPM_REP_REGRESS_H

#include <stdio.h>

#include "eng_core.h"

typedef struct rep_suggest_options {
    const char *const *runs;  /* runs that should pass (other seeds, another renderer, an accepted change) */
    int run_count;
    const char *golden_dir;
    const char *tolerances;   /* the file whose pixel thresholds (fail, warn, their relatives) are kept;
                                 NULL: <golden_dir>/tolerances.json (missing: the built-in defaults) */
    double margin;            /* >= 1: every suggested limit is the largest measured value times this */
    const char *out_path;     /* the tolerance file written (atomically) */
} rep_suggest_options;

/* Replays every run against the golden (nothing written beside the runs) and writes the tightest
 * tolerance file under which every run passes, times the margin: per buffer hardfail,
 * failpercent, warnpercent, rmse_fail, block_fail, block_failrelative, flip_mean_fail and
 * flip_p99_fail, each limit's "note" naming the run and frame that set it; a buffer bit-exact in
 * every run gets "exact": true; runs from another GL renderer than the golden's set the
 * "cross_renderer" section instead. A run that no tolerance can make pass (a missing, extra or
 * resized buffer, a non-finite change) is ENG_ERR_UNSUPPORTED naming it; an unreadable run or golden
 * is replay's error. One line per section goes to summary (may be NULL). */
eng_result rep_tol_suggest(const rep_suggest_options *o, FILE *summary, eng_error *err);

/* A suggested limit: v × margin rounded up to three significant digits, and never below
 * v × margin once printed with %.3g (0 for v <= 0). */
double rep_suggest_round(double v, double margin);

#endif
