/* rep.h — the replay module's public API: replay, bless, progress. Above the three rooms (run/,
 * compare/, report/); a program that reads runs itself uses run/rep_run.h.
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

#include "eng_core.h"
#include "rep_compare.h" /* rep_exit, rep_tol_flags */

#ifdef __cplusplus
extern "C" {
#endif

/* Progress of a long command (progress.c): "<label>: frame 3/8  elapsed 2.1 s  left 3.5 s", one
 * refreshed line on a terminal, one line per step otherwise. */
typedef struct rep_progress {
    FILE *f;            /* NULL: silent */
    const char *label;  /* "ispm record" */
    const char *unit;   /* "frame" */
    int total;
    double start;
    int tty, open;
} rep_progress;
void rep_progress_begin(rep_progress *p, FILE *f, const char *label, const char *unit, int total);
/* done of total steps finished; detail (may be NULL) is appended to the line. */
void rep_progress_step(rep_progress *p, int done, const char *detail);
/* Ends a refreshed line. */
void rep_progress_end(rep_progress *p);

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
    rep_tol_flags flags;      /* command-line thresholds over the file's default entry */
    int provenance_fail;      /* a different scene, sequence or settings fails (default: warns) */
    double timing_fail;       /* > 0: a pass whose share of the frame time is over this many times the
                                 golden's fails; 0: timing is reported only */
    int frames_set, frame_first, frame_last; /* frames_set: only frames frame_first..frame_last */
    const char *buffers;      /* NULL, or an fnmatch pattern: only the buffers it matches are compared */
    rep_progress *progress;   /* NULL, or stepped once per frame compared (total set by replay) */
    int no_flip;              /* skip ꟻLIP (flip.h) of the colour buffers (for timing it; reports show none) */
    const char *expectations; /* NULL: <golden_dir>/expectations.json if there is one (report/expect_report.c) */
    const char *today;        /* NULL: today's UTC date; "YYYY-MM-DD": the date expectations are judged on */
    int no_files;             /* write no report files (fills the model only: ispm tolerances suggest) */
} rep_options;

/* Returns the idiff-style exit code; on REP_UNREADABLE err names the file and problem. The
 * human summary goes to `summary` (may be NULL). */
rep_exit rep_replay(const rep_options *o, FILE *summary, eng_error *err);

/* Copies a complete run to golden_dir atomically (golden_dir.tmp then rename; an existing
 * golden's tolerances.json is kept, otherwise a default one is written). Same as
 * rep_bless_reviewed with accept set and no summary. */
eng_result rep_bless(const char *run_dir, const char *golden_dir, eng_error *err);

typedef struct rep_bless_options {
    const char *run_dir;
    const char *golden_dir;
    int accept;             /* replace a golden that differs from the run */
    const char *review_dir; /* the HTML review (report.html, img/); NULL: <run_dir>/bless */
} rep_bless_options;

typedef enum rep_bless_outcome {
    REP_BLESS_NEW = 0,      /* there was no golden: the run became it */
    REP_BLESS_SAME,         /* bit-exact, same inputs: the golden is left as it is */
    REP_BLESS_REPLACED,     /* it differed and accept was given: replaced, BLESS.md says what moved */
    REP_BLESS_REFUSED       /* it differs and accept was not given: nothing in the golden changed */
} rep_bless_outcome;

/* Reviewed bless: compares the run with the golden it would replace (as replay does, the
 * review's report.html with thumbnails in review_dir) and prints what would change to summary;
 * then blesses per rep_bless_outcome. A blessed golden holds BLESS.md, the written review. */
eng_result rep_bless_reviewed(const rep_bless_options *o, FILE *summary, rep_bless_outcome *outcome, eng_error *err);

/* ispm golden migrate: a golden of frame files (format 1) becomes one of objects (format 2)
 * in the shared store found by rep_store_find, or a new "../objects" beside it. Every buffer is
 * read, verified and stored; the new golden is read back and must be the old one buffer by
 * buffer (name, digest, size, channel names, float bits) before it replaces it. A golden of
 * format 2 is left as it is. One line on out says what was done. */
eng_result rep_golden_migrate(const char *golden_dir, FILE *out, eng_error *err);

/* ispm golden unpack: any golden (or run) written again as a golden of frame files (format 1) in
 * the new folder dst, with its tolerances.json, for tools that read frame files (oiiotool,
 * idiff, older builds of ispm under scripts/bisect.sh); read back and checked buffer by buffer. */
eng_result rep_golden_unpack(const char *golden, const char *dst, FILE *out, eng_error *err);

typedef struct rep_gc_stats {
    int goldens;                /* goldens read under the root */
    size_t kept, removed;       /* objects */
    uint64_t bytes_kept, bytes_removed;
} rep_gc_stats;

/* ispm golden gc: removes the objects of root/objects that no golden under root (four levels
 * deep, renderer sets included) lists. Any golden that cannot be read stops it before anything
 * is removed (ENG_ERR_*: it might list any object). dry_run: counts only. */
eng_result rep_golden_gc(const char *root, int dry_run, rep_gc_stats *st, eng_error *err);

#ifdef __cplusplus
}
#endif

#endif
