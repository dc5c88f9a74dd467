/* rep_internal.h — what the replay module's files share and its tests reach into; not part of
 * the public API (rep.h).
 *
 * The pieces, one file each:
 *   util.c       allocation (out of memory ends the process), paths, files, atomic writes
 *   run.c        run reader: manifest.json parsed and validated, frame files decoded through
 *                the OIIO shim and verified against the manifest's digests
 *   tolerance.c  tolerances.json: parsing, validation, first-match lookup
 *   compare.c    one buffer against its golden: metrics and verdict
 *   report.c     report.json, report.txt and the summary; calls the two writers below
 *   report_html.c report.html and its thumbnails (PNG files in img/)
 *   junit.c      report.junit.xml, and the XML/HTML text escaping both use
 *   thumb.c      float buffers (and their differences) mapped to 8-bit thumbnails
 *   replay.c     rep_replay: walks frames and buffers, builds the report
 *   bless.c      rep_bless: a verified run becomes a golden, atomically, after a review
 *   provenance.c the run's manifest against the golden's: what made them, per-pass timing
 */
#ifndef ISPM_REP_INTERNAL_H
#define ISPM_REP_INTERNAL_H

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include "eng.h"
#include "flip.h"
#include "oiio_shim.h"
#include "rep.h"

/* A buffer larger than this many floats (1 GiB) is taken for a lying manifest or header. */
#define REP_MAX_FLOATS ((size_t)1 << 28)
/* Largest manifest or tolerances file read. */
#define REP_MAX_JSON_BYTES ((size_t)64 << 20)

/* ---------------------------------------------------------------- util.c */

/* Allocation that cannot fail: out of memory prints one line and aborts, as in ispm_core. */
void *rep_xmalloc(size_t n);
void *rep_xcalloc(size_t n, size_t size);
void *rep_xrealloc(void *p, size_t n);
char *rep_xstrdup(const char *s);
char *rep_xprintf(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
/* Sorts v ascending: the array qsort with a < / > comparison leaves (a radix sort where every
 * value is finite and non-negative, as ꟻLIP maps and flicker measures are; qsort otherwise). */
void rep_sort_floats(float *v, size_t n);
/* The median of v[0..n) (the mean of the middle two when n is even), sorting v in place; NAN
 * when n is 0. */
double rep_median(double *v, int n);
/* dir + "/" + name, without doubling a trailing slash. Caller frees. */
char *rep_path_join(const char *dir, const char *name);

/* A growing NUL-terminated string. Zero-initialise; free s when done. */
typedef struct rep_sb {
    char *s;
    size_t len, cap;
} rep_sb;
void rep_sb_printf(rep_sb *sb, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

int rep_is_file(const char *path); /* regular file (following links) */
int rep_is_dir(const char *path);
/* mkdir -p. */
eng_result rep_mkdirs(const char *path, eng_error *err);
/* Writes path.tmp.<pid>, flushes it to disk, renames it over path: readers see the old file or the
 * new one, never a part. */
eng_result rep_write_atomic(const char *path, const char *data, size_t len, eng_error *err);
/* Copies a regular file's bytes to dst (created or truncated) and flushes them to disk. */
eng_result rep_copy_file(const char *src, const char *dst, eng_error *err);
/* rm -rf without following symbolic links; a missing path is not an error. */
eng_result rep_remove_tree(const char *path, eng_error *err);

/* ---------------------------------------------------------------- run.c */

typedef struct rep_buffer_info {
    char *name;
    int width, height;
    int channel_count;
    char *channels[ENG_MAX_CHANNELS]; /* as the manifest lists them */
    char digest[40];                  /* 32 lowercase hex */
    uint64_t nan, inf;
    int has_nonfinite_counts;         /* the manifest gave "nan" and "inf" */
} rep_buffer_info;

typedef struct rep_frame_info {
    int index;
    double time;
    char *file; /* as in the manifest, relative to the run folder */
    char *path; /* run folder + file */
    int buffer_count;
    rep_buffer_info *buffers;
    int has_camera;        /* the manifest gave "camera" (runs recorded before it did not) */
    float view_proj[16];   /* eye camera world → clip, column-major (GL) */
    float eye[3];
} rep_frame_info;

/* A run's manifest, validated: one owner, freed whole by rep_run_close. */
typedef struct rep_run {
    char *dir;
    char *manifest_path;
    int width, height; /* "resolution" */
    char *sequence_name; /* may be NULL */
    char *gl_renderer;   /* the manifest's gl.renderer (GL_RENDERER); NULL if absent */
    int frame_count;
    rep_frame_info *frames;
    int complete;        /* manifest.json read; 0: a run still being recorded (rep_run_open_live) */
    int planned_frames;  /* live: run.json's frame_count (0 if absent); complete: frame_count */
} rep_run;

/* Opens a run: parses and validates manifest.json (format, version, "complete": true, frame
 * count equal to the frames listed, indices in order, safe relative file names, buffer sizes
 * within REP_MAX_FLOATS, unique names, well-formed digests) and checks that every frame file
 * exists. Any failure means the run cannot be read: *out is NULL, err names the file and the
 * problem (ENG_ERR_IO missing, ENG_ERR_PARSE not JSON, ENG_ERR_INVALID otherwise). */
eng_result rep_run_open(const char *dir, rep_run **out, eng_error *err);
void rep_run_close(rep_run *run);

/* Opens a run that may still be recording (live view, issue 19 item 3). With manifest.json it
 * is rep_run_open. Without it, a folder holding run.json (written by capture before any frame)
 * is a run in progress: its frames are those whose frames/NNNNNN.exr and frames/NNNNNN.json
 * (the frame's manifest record, written after the EXR) both exist, from frame 0 up to the first
 * one missing either: the rule by which capture's --resume counts a frame as captured. Zero
 * frames is a valid state. Without either file: rep_run_open's error. */
eng_result rep_run_open_live(const char *dir, rep_run **out, eng_error *err);
/* Appends the frames of a live run that have landed since (same rule); once manifest.json is
 * there, the manifest's frames replace the records and run->complete is set. *added gets the
 * number of new frames. Already listed frames keep their rep_frame_info (pointers stay valid;
 * the frames array itself may move). A complete run is left as it is. */
eng_result rep_run_refresh(rep_run *run, int *added, eng_error *err);

/* Index of the buffer called name in frame f, or -1. */
int rep_frame_find(const rep_frame_info *f, const char *name);

/* Decodes frame `frame` of the run and verifies it against the manifest: the file holds
 * exactly the listed parts, each of the listed size and channel set, each decoding to the
 * listed digest (and non-finite counts). On success (*parts)[j] is the buffer
 * run->frames[frame].buffers[j]; free with rep_parts_free(*parts, buffer_count). Failure
 * (missing, truncated, tampered, disagreeing file) names the file and part. */
eng_result rep_run_read_frame(const rep_run *run, int frame, rep_part **parts, eng_error *err);

/* ---------------------------------------------------------------- tolerance.c */

/* One buffer's tolerances. Thresholds are compared with ">": a difference equal to the
 * threshold passes. Disabled thresholds (hardwarn, rmse_* unless set) are +INFINITY. */
/* Stability limits of one buffer (the "stability" object of a tolerance rule): the run's
 * sequence-level statistics (stability_internal.h) must not exceed them. INFINITY = unchecked;
 * golden_margin < 0 = unchecked, else every statistic must also stay within the golden run's own
 * value × (1 + golden_margin). */
typedef struct rep_tol_stab {
    int set;
    double static_mean, static_p99, reprojected_mean, reprojected_p99, temporal_std_mean, temporal_std_p99;
    double golden_margin;
} rep_tol_stab;

typedef struct rep_tol {
    int exact; /* any bit difference fails */
    rep_tol_stab stab;
    double warn, warnrelative, warnpercent, hardwarn;
    double fail, failrelative, failpercent, hardfail;
    double rmse_warn, rmse_fail;
    /* ꟻLIP (flip.h) of colour buffers: fail when the mean or the 99th percentile is over
     * (INFINITY: unchecked); the HDR exposure range [start, stop] and the observer's ppd (0: 67). */
    double flip_mean_fail, flip_p99_fail;
    double flip_exposure[2], flip_ppd;
} rep_tol;

typedef struct rep_tol_rule {
    char *match; /* fnmatch pattern against the buffer name */
    rep_tol tol; /* fully resolved: unspecified keys already taken from "default" */
    unsigned keys_set; /* REP_FLAG_* bits of the threshold keys the rule itself gives */
} rep_tol_rule;

typedef struct rep_tolerances {
    char *path; /* NULL when built-in defaults */
    rep_tol def;
    int rule_count;
    rep_tol_rule *rules;
    /* The set used when the run comes from another renderer than the golden (renderer.c): the
     * file's "cross_renderer" section (same keys: "default", "buffers"; path "FILE#cross_renderer"),
     * else the built-in cross-renderer defaults (path NULL). Never NULL in a loaded set. */
    struct rep_tolerances *cross;
} rep_tolerances;

/* The built-in cross-renderer defaults (a run from another GL renderer than its golden's): no
 * bit-exact rule, fail 0.02 absolute and 5 % relative on at most 1 % of the pixels, RMSE 0.02. */
void rep_tol_cross_builtin(rep_tol *t);

/* The built-in defaults: warn 0, fail 1e-4, failrelative 1e-4, failpercent 0, hardfail 1e-2,
 * everything else 0 or disabled. */
void rep_tol_builtin(rep_tol *t);

/* Parses tolerances JSON; path is only used in messages. Unknown keys, wrong types, negative
 * or non-finite numbers and rules without "match" are ENG_ERR_INVALID naming the key. */
eng_result rep_tol_parse(const char *path, const char *json, size_t len, rep_tolerances **out,
                         eng_error *err);
/* Loads a tolerances file. If missing_ok and the file does not exist, *out holds the built-in
 * defaults (path NULL). */
eng_result rep_tol_load(const char *path, int missing_ok, rep_tolerances **out, eng_error *err);
void rep_tol_free(rep_tolerances *t);

/* Tolerances for a buffer: the first rule whose pattern matches wins, else "default". Returns
 * the pattern that matched, or "default". */
const char *rep_tol_lookup(const rep_tolerances *t, const char *buffer, rep_tol *out);

/* Command-line thresholds (rep.h) over the default entry and the rules that inherit from it. */
void rep_tol_apply_flags(rep_tolerances *t, const rep_tol_flags *f);
/* The flags as typed: "-fail 0.1 -failpercent 2"; NULL when none. Caller frees. */
char *rep_tol_flags_text(const rep_tol_flags *f);

/* The tolerances.json that bless writes for a new golden (the built-in defaults, spelled out). */
char *rep_tol_default_json(void);

/* ---------------------------------------------------------------- compare.c */

typedef enum rep_verdict {
    REP_V_CHECKED = 0, /* no golden: integrity verified, every value finite */
    REP_V_BITEXACT,
    REP_V_WITHIN,      /* differs, within tolerance */
    REP_V_WARN,
    REP_V_FAIL,
    REP_V_SIZE,
    REP_V_COUNT
} rep_verdict;

const char *rep_verdict_name(rep_verdict v); /* "bit-exact", "within tolerance", ... */

/* Why a buffer failed or warned (bits). */
enum {
    REP_WHY_PERCENT = 1,   /* more failing (warning) pixels than failpercent (warnpercent) */
    REP_WHY_HARD = 2,      /* some |Δ| over hardfail (hardwarn) */
    REP_WHY_RMSE = 4,      /* RMSE over rmse_fail (rmse_warn) */
    REP_WHY_NONFINITE = 8, /* a non-finite value changed class, or appeared in a run without golden */
    REP_WHY_EXACT = 16,    /* exact mode and some bit differs */
    REP_WHY_FLIP = 32      /* ꟻLIP mean or 99th percentile over flip_mean_fail / flip_p99_fail */
};

#define REP_CHANNEL_NAME_MAX 64

typedef struct rep_metrics {
    uint64_t pixels, values;
    uint64_t values_differing;       /* bitwise */
    double max_abs;                  /* over values finite in both */
    int max_x, max_y;                /* -1 if no finite difference */
    char max_channel[REP_CHANNEL_NAME_MAX];
    double mean_abs, rmse, psnr;     /* psnr: peak = max |golden|, or 1; +INF when rmse is 0 */
    uint64_t fail_pixels, warn_pixels;
    double fail_percent, warn_percent;
    int first_fail_x, first_fail_y;  /* -1 if none */
    uint64_t run_nan, run_inf, golden_nan, golden_inf;
    uint64_t nonfinite_mismatch;     /* values whose class (finite/NaN/+Inf/-Inf) differs */
    int nf_x, nf_y;                  /* first such value, row-major; -1 if none */
    char nf_channel[REP_CHANNEL_NAME_MAX];
    float nf_run, nf_golden;         /* the values there */
    unsigned fail_why, warn_why;
} rep_metrics;

/* Compares a run buffer with its golden under tol. Channels are matched by name; a different
 * size or channel set gives REP_V_SIZE (metrics zero). Per value d = |a-b|, rel = d/max(|a|,|b|)
 * (0 when both are 0). A pixel fails (warns) if some channel has d > fail AND rel >
 * failrelative (warn/warnrelative). The buffer fails if failing pixels exceed failpercent % of
 * all pixels, or some d > hardfail, or RMSE > rmse_fail, or (exact) any bit differs, or any
 * value's class NaN/+Inf/-Inf/finite differs between run and golden; it warns likewise. Values
 * non-finite in both with the same class count as d = 0. */
rep_verdict rep_compare(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol,
                        rep_metrics *m);

/* ꟻLIP of a colour buffer (flip.h; rep_flip_kind_of its name, channels R, G, B) against its
 * golden, under tol's exposure range and ppd: kind and statistics into *kind and *s (a
 * bit-exact buffer gets zeros without computing). Over flip_mean_fail or flip_p99_fail adds
 * REP_WHY_FLIP to m->fail_why and returns REP_V_FAIL; otherwise returns v. A buffer that is no
 * colour image, or whose sizes differ, gets REP_FLIP_NONE and v back. skip: measure nothing. */
/* The ꟻLIP map (w×h floats, caller frees) of a run buffer against its golden as kind k under
 * tol (the map behind rep_compare_flip's statistics; report.html's heat map); *exposures (may be
 * NULL) gets how many exposures were evaluated. NULL when either lacks R, G, B or sizes differ. */
float *rep_flip_buffers(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol, rep_flip_kind k,
                        int *exposures);
rep_verdict rep_compare_flip(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol, rep_verdict v,
                             int skip, rep_metrics *m, rep_flip_kind *kind, rep_flip_stats *s);
/* rep_compare_flip that hands the map over in *map (NULL when none was computed; caller frees). */
rep_verdict rep_compare_flip_map(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol, rep_verdict v,
                                 int skip, rep_metrics *m, rep_flip_kind *kind, rep_flip_stats *s, float **map);

/* ---------------------------------------------------------------- provenance.c */

enum { REP_PROV_INFO = 0, REP_PROV_WARN = 1, REP_PROV_FAIL = 2 };

typedef struct rep_prov_item {
    char *key;            /* dotted manifest path: "settings.photon_count", "gl.renderer" */
    char *run, *golden;   /* the values as compact JSON; NULL: absent on that side */
    int level;            /* REP_PROV_* */
} rep_prov_item;

typedef struct rep_timing_pass {
    char *name;
    double run_share, golden_share; /* median over frames of the pass's share of its frame; NAN: absent */
    double ratio;                   /* run_share / golden_share; NAN when either is absent */
    double run_ms, golden_ms;       /* median milliseconds */
    int failed;                     /* ratio over timing_fail */
} rep_timing_pass;

typedef struct rep_prov {
    size_t count;
    rep_prov_item *items; /* in manifest order */
    int warn, fail;       /* items at those levels */
    int timing_count;
    rep_timing_pass *timing;
    double run_frame_ms, golden_frame_ms; /* median frame time (sum of passes) */
    double timing_fail;   /* the limit applied, 0: none */
    int timing_failed;
} rep_prov;

/* Compares the manifests of run_dir and golden_dir (provenance and timing, module comment). */
eng_result rep_prov_compare(const char *run_dir, const char *golden_dir, int provenance_fail, double timing_fail,
                            rep_prov **out, eng_error *err);
void rep_prov_free(rep_prov *p);
const char *rep_prov_level_name(int level);
/* One difference, "warn settings.exposure: golden 0, run 1\n". */
void rep_prov_line(rep_sb *sb, const rep_prov_item *it);
/* The provenance block of report.txt (a line saying "same" when nothing differs). */
void rep_prov_text(rep_sb *sb, const rep_prov *p);
/* The timing block of report.txt: one line per pass. */
void rep_timing_text(rep_sb *sb, const rep_prov *p);
/* report.json's "provenance" and "timing" objects (cJSON *). */
void *rep_prov_json(const rep_prov *p);
void *rep_timing_json(const rep_prov *p);
/* One line on what made the run in dir (sequence, scene, tool, GL, Embree). Caller frees. */
char *rep_manifest_origin(const char *dir);

/* ---------------------------------------------------------------- photonset.c */

/* photons.map compared as a set of photons keyed by path (photonset.c). Counts are photons. */
typedef struct rep_photon_diff {
    uint64_t run, golden;            /* photons in each map */
    uint64_t added, removed;         /* photons only in the run / only in the golden */
    uint64_t changed, within;        /* matched photons differing over / within tolerance */
    uint64_t paths_added, paths_removed;
    int unaligned;                   /* more path edits than the alignment follows: compared whole */
} rep_photon_diff;

/* Whether b is a photon map (named photons.map, with the 14 photon channels). */
int rep_is_photon_map(const eng_buffer *b);
/* The set comparison; m gets what applies (pixels = photons of the larger map, fail_pixels =
 * photons added, removed or changed, max_abs over matched photons). Maps of different sizes
 * are compared too: a size difference is photons added or removed. */
rep_verdict rep_photon_compare(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol, rep_metrics *m,
                               rep_photon_diff *pd);

/* ---------------------------------------------------------------- report.c */

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
} rep_entry;

/* ---------------------------------------------------------------- keep.c */

/* What replay's walk keeps for report.html (keep.c): decoded parts and ꟻLIP maps by frame,
 * side and buffer name, in frame order, at most REP_KEEP_MAX_FLOATS floats in all (128 MiB)
 * and REP_KEEP_MAX_ITEMS items. */
#define REP_KEEP_MAX_FLOATS ((size_t)1 << 25)
#define REP_KEEP_MAX_ITEMS 4096
enum { REP_KEEP_RUN = 0, REP_KEEP_GOLDEN = 1 };

typedef struct rep_kept {
    int frame, side;
    char *name;
    rep_part part; /* data NULL: not kept */
    float *flip;   /* run side only: the ꟻLIP map against the golden, or NULL */
} rep_kept;

typedef struct rep_keep {
    rep_kept *items;
    size_t count, cap;
    size_t floats; /* held, parts and maps */
} rep_keep;

/* Moves *p (zeroed after) into k unless it is already there or k is full (then *p stays). */
void rep_keep_part(rep_keep *k, int frame, int side, rep_part *p);
/* Takes map (floats values) as the run's ꟻLIP map of a buffer: 1 if taken, 0 (caller frees). */
int rep_keep_flip(rep_keep *k, int frame, const char *name, float *map, size_t floats);
/* What k holds, or NULL (k may be NULL). */
const rep_part *rep_keep_find_part(const rep_keep *k, int frame, int side, const char *name);
const float *rep_keep_find_flip(const rep_keep *k, int frame, const char *name);
void rep_keep_free(rep_keep *k); /* accepts NULL */

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
    struct rep_stab_report *stab; /* temporal stability (stability_internal.h); NULL: not measured */
    rep_prov *prov;          /* manifests compared (provenance, timing); NULL without golden */
    char *flags_text;        /* owned: the command-line thresholds, "-fail 0.1 -failpercent 2", or NULL */
    char *scope_text;        /* owned: "frames 2-3, buffers final.*" when replay looked at a part only */
    /* GL renderers (renderer.c): renderer_differs when both manifests name one and they
     * differ; then the buffers were compared under the cross-renderer tolerances. */
    char *run_renderer, *golden_renderer; /* owned; NULL if not recorded */
    int renderer_differs;
    rep_keep *keep;          /* owned: parts and ꟻLIP maps kept for report.html, or NULL */
} rep_report;

/* ---------------------------------------------------------------- renderer.c */

/* Records both runs' GL renderers in r and returns the tolerance set to compare with: tols,
 * or tols->cross when the run comes from another renderer than the golden (a GPU's EGL run
 * against an llvmpipe golden). Manifests without gl.renderer (older runs) count as the same. */
const rep_tolerances *rep_renderer_tolerances(rep_report *r, const rep_run *run, const rep_run *gold,
                                              const rep_tolerances *tols);
/* One line on the renderers for the reports ("different renderer: run …, golden …; …"), or
 * NULL when they are the same. Caller frees. */
char *rep_renderer_note(const rep_report *r);

/* Appends a zeroed entry for (frame, buffer) and returns it. */
rep_entry *rep_report_add(rep_report *r, int frame, const char *buffer);
void rep_report_free(rep_report *r);
/* The exit code the entries imply (UNREADABLE is set by the caller). */
rep_exit rep_report_exit(const rep_report *r);

/* The human summary: header, one line per buffer that is not bit-exact (or, without golden,
 * not clean), worst first, and the verdict line. quiet: only failures and the verdict line.
 * Caller frees. */
char *rep_report_text(const rep_report *r, int quiet);
/* report.json as a string. Caller frees. */
char *rep_report_json(const rep_report *r);
/* Writes report.json, report.txt, report.junit.xml and report.html (with img/) into dir
 * (created if needed), each file atomically. */
eng_result rep_report_write(const rep_report *r, const char *dir, eng_error *err);

/* Every entry, worst first (the order of report.txt). *n gets the count; caller frees. */
const rep_entry **rep_report_sorted(const rep_report *r, size_t *n);
/* Not bit-exact (with a golden) or not clean (without): the entries the reports dwell on. */
int rep_entry_listed(const rep_entry *e);
/* report.txt's line for one entry, newline included. */
void rep_report_line(rep_sb *sb, const rep_report *r, const rep_entry *e);
/* The run's verdict in one word: "OK", "WARN", "FAIL", "SIZE MISMATCH", "UNREADABLE". */
const char *rep_exit_word(rep_exit x);

/* ---------------------------------------------------------------- replay.c */

/* rep_replay without the summary: fills r (free with rep_report_free) and writes the report
 * files; returns r->exit. */
rep_exit rep_replay_report(const rep_options *o, rep_report *r, eng_error *err);

/* ---------------------------------------------------------------- junit.c */

/* Appends s escaped for XML/HTML text and attribute values: & < > " ' become entities;
 * characters XML 1.0 forbids (controls other than tab/newline/return) and bytes that are not
 * valid UTF-8 become U+FFFD, so any buffer or path name yields a well-formed document. */
void rep_sb_xml(rep_sb *sb, const char *s);

/* report.junit.xml: one <testsuite> named "ispm.<suite>", one <testcase> per entry, named
 * after the buffer, classname "ispm.<suite>.frameNNNNNN". Failed and size-mismatched
 * entries (over tolerance, non-finite, missing or extra) get a <failure> whose type is
 * fail|size|nonfinite|missing|extra; warnings and within-tolerance differences are told in
 * <system-out>; nothing is <skipped/>. An unreadable input adds one testcase with <error>.
 * Caller frees. */
char *rep_report_junit(const rep_report *r, const char *suite);

/* ---------------------------------------------------------------- thumb.c */

#define REP_THUMB_MAX_SIDE 256

typedef enum rep_thumb_kind {
    REP_THUMB_DATA = 0, /* min/max ramp shared by golden and run */
    REP_THUMB_RADIANCE, /* linear: clamp, sRGB curve */
    REP_THUMB_DISPLAY   /* already display-encoded: clamp */
} rep_thumb_kind;

/* How a buffer's floats become bytes; one map serves a golden and a run alike. */
typedef struct rep_thumb_map {
    rep_thumb_kind kind;
    int n;                                   /* channels shown, 0..3 */
    char ch[3][REP_CHANNEL_NAME_MAX];        /* their names */
    double lo, hi;                           /* DATA: finite range over both buffers */
} rep_thumb_map;

/* Writes an 8-bit image (w*h*nch bytes, interleaved, top row first; nch 1 or 3) as a PNG at
 * path, whatever its extension, with libpng (png_write.c): the chunks and filtered rows
 * OpenImageIO's PNG writer (rep_oiio_write_png) makes from the same pixels, deflated at zlib
 * level 1. Overwrites path. */
eng_result rep_png_write(const char *path, int w, int h, int nch, const unsigned char *pixels, eng_error *err);

/* The kind from the buffer's name: "*.display", "*.radiance", anything else is data. */
rep_thumb_kind rep_thumb_kind_of(const char *buffer);
/* The mapping for a buffer from its run and golden versions; either (not both) may be NULL. */
void rep_thumb_map_make(const char *buffer, const eng_buffer *run, const eng_buffer *golden, rep_thumb_map *m);
/* Thumbnail size: the buffer's, scaled down so the longest side is at most REP_THUMB_MAX_SIDE. */
void rep_thumb_size(int w, int h, int *tw, int *th);
/* b as *tw × *th RGB bytes under m; NaN/Inf pixels magenta. Caller frees. */
unsigned char *rep_thumb_render(const eng_buffer *b, const rep_thumb_map *m, int *tw, int *th);
/* The same at any size: the longest side at most max_side (0: full size; ispm export). */
unsigned char *rep_image_render(const eng_buffer *b, const rep_thumb_map *m, int max_side, int *tw, int *th);
/* Heatmap of |run − golden| as *tw × *th RGB bytes; *scale gets the largest finite difference
 * (white). NULL when the two differ in size or share no channel. Caller frees. */
unsigned char *rep_thumb_diff(const eng_buffer *run, const eng_buffer *golden, double *scale, int *tw, int *th);

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

#endif
