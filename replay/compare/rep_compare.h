/* rep_compare.h — the compare room's face: how a run's buffers and manifests are held against
 * a golden's.
 *
 *   tolerance.c  tolerances.json: parsing, validation, first-match lookup, command-line flags
 *   compare.c    one buffer against its golden: metrics and verdict (ꟻLIP through flip.h)
 *   photonset.c  photons.map compared as a set of photon paths
 *   provenance.c the run's manifest against the golden's: what made them, per-pass timing
 * Temporal stability is rep_stab.h's; the bench's image metrics metrics.h's; pixel lineage
 * lineage.h's. The verdicts here are per buffer; rep_exit is what they add up to for a run.
 */
#ifndef ISPM_REP_COMPARE_H
#define ISPM_REP_COMPARE_H

#include <stddef.h>
#include <stdint.h>

#include "eng_core.h"
#include "flip.h"
#include "rep_run.h"
#include "rep_util.h"

/* idiff-style exit codes; when several apply, the largest wins. */
/* REP_UNWRITABLE: the comparison ran, but its report could not be written (a read-only or full
 * disk): not to be taken for an unreadable input. */
typedef enum rep_exit {
    REP_OK = 0, REP_WARN = 1, REP_FAIL = 2, REP_SIZE = 3, REP_UNREADABLE = 4, REP_UNWRITABLE = 5
} rep_exit;

/* idiff-style thresholds given on the command line (ispm replay -fail 0.1 ...): each key whose
 * bit is set replaces the tolerance file's "default" entry, and so every rule that took that
 * key from the default; a key a rule sets itself stays the rule's. */
enum {
    REP_FLAG_WARN = 1, REP_FLAG_WARNRELATIVE = 2, REP_FLAG_WARNPERCENT = 4, REP_FLAG_HARDWARN = 8,
    REP_FLAG_FAIL = 16, REP_FLAG_FAILRELATIVE = 32, REP_FLAG_FAILPERCENT = 64, REP_FLAG_HARDFAIL = 128
};
typedef struct rep_tol_flags {
    unsigned set; /* REP_FLAG_* bits */
    double warn, warnrelative, warnpercent, hardwarn, fail, failrelative, failpercent, hardfail;
} rep_tol_flags;

/* Parses one idiff-style option name ("fail", "-failpercent", "--hardwarn") and its value into
 * f. Returns 0 when name is not one of the eight, -1 when the value is not a finite number >= 0,
 * 1 when taken. */
int rep_tol_flag_parse(rep_tol_flags *f, const char *name, const char *value);

/* ---------------------------------------------------------------- tolerance.c */

/* One buffer's tolerances. Thresholds are compared with ">": a difference equal to the
 * threshold passes. Disabled thresholds (hardwarn, rmse_* unless set) are +INFINITY. */
/* Stability limits of one buffer (the "stability" object of a tolerance rule): the run's
 * sequence-level statistics (rep_stab.h) must not exceed them. INFINITY = unchecked;
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
    /* Local gates: the mean |run − golden| over the pixels and channels of each block_size ×
     * block_size block (aligned to pixel (0, 0); the right and bottom edge blocks partial, averaged
     * over their own pixels) must not be over block_fail (block_warn); relative: that mean divided
     * by max(the golden block's mean |value|, REP_BLOCK_REL_FLOOR) over block_failrelative
     * (block_warnrelative). INFINITY: unchecked. */
    double block_fail, block_failrelative, block_warn, block_warnrelative;
    int block_size;
} rep_tol;

/* The default block side and the floor of the relative block measure's denominator (a black
 * block would otherwise make any difference in it infinitely large). */
#define REP_BLOCK_SIZE 8
#define REP_BLOCK_REL_FLOOR 1e-3

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
/* Loads a tolerances file (an input: regular file, JSON depth and trailing text checked).
 * missing_ok: the golden's own file, which may not be a symbolic link, and when nothing at all
 * is at path *out holds the built-in defaults (path NULL); a dangling link, FIFO or device is an
 * error, never the defaults. */
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

/* ---------------------------------------------------------------- expect.c */

/* One rule of expectations.json: buffers matching `match` are expected to fail, for `reason`,
 * until the date `until` (inclusive; "" = no end), on renderers matching `renderer` (NULL: any). */
typedef struct rep_expect_rule {
    char *match, *reason, *renderer;
    char until[11];
} rep_expect_rule;

typedef struct rep_expectations {
    char *path;
    int count;
    rep_expect_rule *rules;
} rep_expectations;

/* Parses expectations JSON (a list of rules, or {"rules": [...]}); path is only used in
 * messages. Unknown keys, a missing or empty match or reason, "expect" other than "fail", an
 * invalid date are ENG_ERR_INVALID naming the file, the rule and the key. */
eng_result rep_expect_parse(const char *path, const char *json, size_t len, rep_expectations **out, eng_error *err);
eng_result rep_expect_load(const char *path, rep_expectations **out, eng_error *err);
void rep_expect_free(rep_expectations *x);
/* Whether s is a real calendar date spelled YYYY-MM-DD. */
int rep_date_valid(const char *s);
/* Today's UTC date, YYYY-MM-DD. */
void rep_date_today(char out[11]);
/* Whether rule k is past its date on today (both YYYY-MM-DD). */
int rep_expect_expired(const rep_expect_rule *rule, const char *today);
/* Whether rule k applies to a run made by renderer (the manifest's gl.renderer, NULL if not
 * recorded: then only rules without "renderer" apply). */
int rep_expect_applies(const rep_expect_rule *rule, const char *renderer);
/* The first rule in force (applies, not expired) whose match matches buffer: its index, or -1. */
int rep_expect_find(const rep_expectations *x, const char *buffer, const char *renderer, const char *today);

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
    REP_WHY_FLIP = 32,     /* ꟻLIP mean or 99th percentile over flip_mean_fail / flip_p99_fail */
    REP_WHY_BLOCK = 64     /* some block's mean |Δ| over block_fail / block_failrelative (warn twins) */
};

/* The worst block of a buffer by one measure: its mean |Δ| (or relative mean), its top-left
 * pixel and size (partial at the right and bottom edges). x = -1: no block differs. */
typedef struct rep_block {
    double value;
    int x, y, w, h;
} rep_block;

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
    /* Blocks of block_size (tolerance): the worst by mean |Δ| and by relative mean; the image's
     * size, for placing them. Measured whenever values differ. */
    int width, height, block_size;
    rep_block block_abs, block_rel;
} rep_metrics;

/* Compares a run buffer with its golden under tol. Channels are matched by name; a different
 * size or channel set gives REP_V_SIZE (metrics zero). Per value d = |a-b|, rel = d/max(|a|,|b|)
 * (0 when both are 0). A pixel fails (warns) if some channel has d > fail AND rel >
 * failrelative (warn/warnrelative). The buffer fails if failing pixels exceed failpercent % of
 * all pixels, or some d > hardfail, or RMSE > rmse_fail, or (exact) any bit differs, or any
 * value's class NaN/+Inf/-Inf/finite differs between run and golden, or some block's mean |d|
 * (rep_tol's block gates) is over block_fail or its relative mean over block_failrelative; it
 * warns likewise. Values non-finite in both with the same class count as d = 0. */
rep_verdict rep_compare(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol,
                        rep_metrics *m);
/* The block measures of rep_compare (tol's block gates), over the values finite in both; map:
 * run channel c is golden channel map[c]. Fills m's width, height, block_size, block_abs and
 * block_rel; the golden's magnitude is summed only in blocks that differ. */
void rep_compare_blocks(const eng_buffer *run, const eng_buffer *golden, const int *map, int block_size,
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

#endif
