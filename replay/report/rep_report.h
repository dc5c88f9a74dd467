/* rep_report.h — the report room's face: the report model and the writers that render it.
 *
 * The model (report_model.c) is one replay's result: its entries (one per buffer of a frame),
 * their worst-first order, which of them the reports dwell on, each entry's line and the run's
 * verdict word, XML escaping, and the renderers that made the two runs (renderer.c). Every
 * writer depends on the model and on the rooms below, never on another writer:
 *   report_text.c  report.txt, the summary, report.json (stability section: stab_text.c)
 *   junit.c        report.junit.xml
 *   report_html.c  report.html and its images in img/ (stability section: stab_html.c)
 * report_write.c writes all four files from the same entries. Charts are plot.h's.
 */
#ifndef ISPM_REP_REPORT_H
#define ISPM_REP_REPORT_H

#include <stddef.h>

#include "eng_core.h"
#include "rep_compare.h"
#include "rep_run.h"
#include "rep_util.h"

struct rep_stab_report; /* rep_stab.h */

/* ---------------------------------------------------------------- report_model.c */
typedef enum rep_problem {
    REP_PROB_NONE = 0,
    REP_PROB_MISSING,       /* buffer in golden, not in run */
    REP_PROB_EXTRA,         /* buffer in run, not in golden */
    REP_PROB_FRAME_MISSING, /* the whole frame is missing from the run */
    REP_PROB_FRAME_EXTRA    /* the run has a frame the golden lacks */
} rep_problem;

/* One buffer of one frame. */
typedef struct rep_entry {
    int frame;
    char *buffer;
    rep_verdict verdict;
    rep_problem problem;
    int compared;         /* metrics (and tol) are meaningful */
    rep_metrics m;
    rep_tol tol;
    char *tol_match;      /* pattern that chose tol, or "default" */
    int photon_set;       /* compared as a photon set: pd holds the counts */
    rep_photon_diff pd;
    char *run_shape;      /* "WxH C1,C2,.." for size mismatches */
    char *golden_shape;
    rep_flip_kind flip_kind; /* ꟻLIP measured (LDR/HDR), or REP_FLIP_NONE */
    rep_flip_stats flip;     /* zero without computing when the buffer is bit-exact */
    /* An expected failure (expectations.json): the entry failed and a rule in force names it;
     * it does not fail the run. expect_rule indexes r->expect->rules. */
    int expected, expect_rule;
} rep_entry;

/* What the expectations made of a replay (report/expect_report.c). */
typedef struct rep_expect_note {
    int rule;        /* index in the file's rules */
    char *buffer;    /* unexpected pass: the buffer that no longer fails; expired: NULL */
} rep_expect_note;

typedef struct rep_expect_outcome {
    rep_expectations *set;   /* owned: the rules (rep_compare.h) */
    char today[11];          /* the date rules were judged on, YYYY-MM-DD */
    int expected;            /* entries that failed as expected */
    int unexpected_count, expired_count;
    rep_expect_note *unexpected, *expired;
} rep_expect_outcome;
/* A frame whose manifest record carries a display warning (all black, clipped). */
typedef struct rep_display_warning {
    int golden; /* 0: the run's frame, 1: the golden's */
    int frame;
    char *text;
} rep_display_warning;

typedef struct rep_report {
    const char *run_dir;
    const char *golden_dir;  /* NULL: integrity-only */
    char *tol_path;          /* owned; NULL: built-in tolerances */
    int frames;              /* frames looked at (union of run and golden) */
    int buffers_per_frame;   /* from the run's frame 0 (or the golden's) */
    size_t count, cap;
    rep_entry *entries;      /* frame order, buffers in manifest order */
    /* First difference by manifest digests alone (redis DEBUG DIGEST): frame -1 if none. */
    int digest_frame;
    char *digest_buffer;
    const char *digest_why;
    rep_exit exit;
    eng_error error;         /* the unreadable input, when exit is UNREADABLE */
    struct rep_stab_report *stab; /* temporal stability (rep_stab.h); NULL: not measured */
    rep_prov *prov;          /* manifests compared (provenance, timing); NULL without golden */
    char *flags_text;        /* owned: the command-line thresholds, "-fail 0.1 -failpercent 2", or NULL */
    char *scope_text;        /* owned: "frames 2-3, buffers final.*" when replay looked at a part only */
    /* GL renderers (renderer.c): renderer_differs when both manifests name one and they
     * differ; then the buffers were compared under the cross-renderer tolerances. */
    char *run_renderer, *golden_renderer; /* owned; NULL if not recorded */
    int renderer_differs;
    /* The golden's set for the run's renderer (golden/renderers/<slug>) when it has one: the
     * slug, and the set's folder, which golden_dir then names (both owned); NULL: the canonical set. */
    char *renderer_set, *renderer_set_dir;
    rep_keep *keep;          /* owned: parts and ꟻLIP maps kept for report.html, or NULL */
    rep_expect_outcome *expect; /* owned: expectations in force, or NULL (no file) */
    int display_warning_count;
    rep_display_warning *display_warnings; /* owned: run's, then golden's, frame order */
    /* Rules of the tolerance file in use that name no buffer of the golden (stale or mistyped:
     * they judge nothing), one line each naming the file and the pattern; they do not change
     * the verdict. */
    int tol_warning_count;
    char **tol_warnings; /* owned */
} rep_report;

/* Adds to r one tolerance warning per rule of t whose pattern matches no buffer name of any
 * frame of gold (the cross-renderer section is judged only when t is it). */
struct rep_tolerances;
void rep_report_tol_warnings(rep_report *r, const struct rep_tolerances *t, const rep_run *gold);

/* Collects the display warnings of both runs' frame records into r (gold may be NULL). */
void rep_report_display_warnings(rep_report *r, const rep_run *run, const rep_run *gold);

/* Appends a zeroed entry for (frame, buffer) and returns it. */
rep_entry *rep_report_add(rep_report *r, int frame, const char *buffer);
/* Frees what r owns (entries, strings, the stability report, kept parts), not r itself. */
void rep_report_free(rep_report *r);
/* The exit code the entries imply (UNREADABLE is set by the caller). */
rep_exit rep_report_exit(const rep_report *r);
/* Every entry, worst first (the order of report.txt). *n gets the count; caller frees. */
const rep_entry **rep_report_sorted(const rep_report *r, size_t *n);
/* Failed or size-mismatched, and not an expected failure: what fails the run. */
int rep_entry_failed(const rep_entry *e);
/* The worst block (compare.c's mean |Δ|) over every compared entry, or NULL when none differs. */
const rep_entry *rep_report_worst_block(const rep_report *r);
/* "worst 8×8 block: frame 3 final.display (48,56) 8×8 mean |Δ| 0.0322 (relative 0.41)", no
 * newline; nothing when none. */
void rep_block_text(rep_sb *sb, const rep_entry *e);
/* Not bit-exact (with a golden) or not clean (without): the entries the reports dwell on. */
int rep_entry_listed(const rep_entry *e);
/* report.txt's line for one entry, newline included. */
void rep_report_line(rep_sb *sb, const rep_report *r, const rep_entry *e);
/* The run's verdict in one word: "OK", "WARN", "FAIL", "SIZE MISMATCH", "UNREADABLE". */
const char *rep_exit_word(rep_exit x);

/* Appends s escaped for XML/HTML text and attribute values: & < > " ' become entities;
 * characters XML 1.0 forbids (controls other than tab/newline/return) and bytes that are not
 * valid UTF-8 become U+FFFD, so any buffer or path name yields a well-formed document. */
void rep_sb_xml(rep_sb *sb, const char *s);

/* ---------------------------------------------------------------- renderer.c */
/* Records both runs' GL renderers in r and returns the tolerance set to compare with: tols,
 * or tols->cross when the run comes from another renderer than the golden (a GPU's EGL run
 * against an llvmpipe golden). Manifests without gl.renderer (older runs) count as the same. */
const rep_tolerances *rep_renderer_tolerances(rep_report *r, const rep_run *run, const rep_run *gold,
                                              const rep_tolerances *tols);
/* The set of golden_dir for the run's renderer: golden_dir/renderers/<rep_renderer_slug> when
 * the run and the canonical golden (gold) name different renderers and that set holds a
 * manifest; else NULL. *slug gets the slug then (caller frees both). */
char *rep_renderer_set_dir(const char *golden_dir, const rep_run *run, const rep_run *gold, char **slug);
/* One line on the renderers for the reports ("different renderer: run …, golden …; …"), or
 * NULL when they are the same. Caller frees. */
char *rep_renderer_note(const rep_report *r);

/* ---------------------------------------------------------------- expect_report.c */
/* Loads the expectations for a replay into r->expect: path, or where path is NULL
 * golden_dir/expectations.json if it exists. Every rule's match must match some buffer of the
 * run or the golden (a rule that names nothing is a stale rule: ENG_ERR_INVALID naming the
 * file). today: "YYYY-MM-DD", or NULL for today's UTC date. No file: r->expect stays NULL. */
eng_result rep_report_expect_load(rep_report *r, const char *path, const char *golden_dir, const rep_run *run,
                                  const rep_run *gold, const char *today, eng_error *err);
/* Marks the failing entries that a rule in force (not expired, renderer matching the run's)
 * names as expected, and lists the unexpected passes (a buffer a rule in force names that fails
 * in no frame) and expired rules. */
void rep_report_expect_apply(rep_report *r);
void rep_expect_outcome_free(rep_expect_outcome *x);
/* report.txt's expectations block (expired rules, unexpected passes, expected failures with
 * their reasons), nothing when there is no file; report.json's "expectations" object (cJSON *). */
void rep_expect_text(rep_sb *sb, const rep_report *r);
void *rep_expect_json(const rep_report *r);
/* The rule's reason for an expected entry, or NULL. */
const char *rep_entry_expect_reason(const rep_report *r, const rep_entry *e);

/* ---------------------------------------------------------------- report_text.c */

/* The human summary: header, one line per buffer that is not bit-exact (or, without golden,
 * not clean), worst first, and the verdict line. quiet: only failures and the verdict line.
 * Caller frees. */
char *rep_report_text(const rep_report *r, int quiet);
/* report.json as a string. Caller frees. */
char *rep_report_json(const rep_report *r);

/* ---------------------------------------------------------------- junit.c */
/* report.junit.xml: one <testsuite> named "ispm.<suite>", one <testcase> per entry, named
 * after the buffer, classname "ispm.<suite>.frameNNNNNN". Failed and size-mismatched
 * entries (over tolerance, non-finite, missing or extra) get a <failure> whose type is
 * fail|size|nonfinite|missing|extra; warnings and within-tolerance differences are told in
 * <system-out>; expected failures are <skipped> with their reason; unexpected passes and
 * expired expectations are test cases of their own (classname ispm.<suite>.expectations). An unreadable input adds one testcase with <error>.
 * Caller frees. */
char *rep_report_junit(const rep_report *r, const char *suite);


/* ---------------------------------------------------------------- report_html.c */

/* At most this many thumbnails in one report (worst entries first). */
#define REP_THUMB_MAX_IMAGES 200

/* Writes dir/report.html and its thumbnails in dir/img/ (replaced whole). run and golden are
 * the opened runs the report is about, or NULL where one could not be opened: thumbnails are
 * then missing from the page, which says so. Thumbnails are made for the listed entries,
 * worst first, and for the final image of the first and last frame; a frame file that cannot
 * be decoded or a thumbnail that cannot be written only leaves its images out. Failure to
 * write report.html itself (or to create img/) is the error. */
eng_result rep_report_html_write(const rep_report *r, const rep_run *run, const rep_run *golden, const char *dir,
                                 eng_error *err);


/* ---------------------------------------------------------------- stab_text.c, stab_html.c */

/* report.txt's stability section; report.json's "stability" object (cJSON *); the HTML
 * section's two charts, written into dir/img (rel: their page-relative names, NULL for a chart not
 * made; caller frees), and the HTML section that shows them. */
void rep_stab_text(rep_sb *sb, const rep_report *r);
void *rep_stab_json(const rep_report *r);
void rep_stab_charts(const rep_report *r, const char *dir, char *rel[2]);
void rep_stab_html(rep_sb *sb, const rep_report *r, char *const charts[2]);

/* ---------------------------------------------------------------- report_write.c */

/* Writes report.json, report.txt, report.junit.xml and report.html (with img/) into dir
 * (created if needed), each file atomically. */
eng_result rep_report_write(const rep_report *r, const char *dir, eng_error *err);

#endif
