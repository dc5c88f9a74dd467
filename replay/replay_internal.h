/* replay_internal.h — what replay.c offers bless.c and the tests beyond rep.h: the replay walk
 * with its report model handed back, for a caller that reads the entries itself.
 */
#ifndef ISPM_REPLAY_INTERNAL_H
#define ISPM_REPLAY_INTERNAL_H

#include "eng_core.h"
#include "rep.h"
#include "rep_report.h"

/* rep_replay without the summary: fills r (free with rep_report_free) and writes the report
 * files; returns r->exit. */
rep_exit rep_replay_report(const rep_options *o, rep_report *r, eng_error *err);

#endif
