/* rep.h — the replay module's one public header.
 *
 * Replay reads a recorded run (RUN/manifest.json + one multi-part EXR per frame, as capture
 * writes it) and, given a golden run, compares every buffer of every frame under per-buffer
 * tolerances in the manner of idiff (-warn/-fail/-failpercent/-hardfail/-failrelative), except
 * that a non-finite value that changes class (NaN, +Inf, -Inf) always fails. It verifies both
 * runs' files against their manifests' digests, names the first frame and buffer whose
 * recorded digest differs, and writes report.json and report.txt. Bless turns a complete run
 * into a golden. Replay reads files only: it links ispm_core, never the renderer.
 */
#ifndef ISPM_REP_H
#define ISPM_REP_H

#include <stdio.h>

#include "eng.h"

#ifdef __cplusplus
extern "C" {
#endif

/* idiff-style exit codes; when several apply, the largest wins. */
typedef enum rep_exit { REP_OK = 0, REP_WARN = 1, REP_FAIL = 2, REP_SIZE = 3, REP_UNREADABLE = 4 } rep_exit;

typedef struct rep_options {
    const char *run_dir;
    const char *golden_dir;   /* NULL: only check the run's integrity and non-finite values */
    const char *tolerances;   /* NULL: <golden_dir>/tolerances.json (missing file = defaults) */
    const char *report_dir;   /* NULL: <run_dir>/replay ; gets report.json, report.txt,
                                 report.junit.xml, report.html and img/ */
    int quiet;                /* summary: only the verdict line and failures */
    const char *reference_dir;/* NULL, or a run whose frames hold reference.full / reference.indirect /
                                 reference.direct: the temporal error of the matching passes is
                                 measured against them (one frame, or as many as the run) */
} rep_options;

/* Returns the idiff-style exit code; on REP_UNREADABLE err names the file and problem. The
 * human summary goes to `summary` (may be NULL). */
rep_exit rep_replay(const rep_options *o, FILE *summary, eng_error *err);

/* Copies a complete run to golden_dir atomically (golden_dir.tmp then rename; an existing
 * golden's tolerances.json is kept, otherwise a default one is written). */
eng_result rep_bless(const char *run_dir, const char *golden_dir, eng_error *err);

#ifdef __cplusplus
}
#endif

#endif
