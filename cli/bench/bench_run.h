/* bench_run.h — the points of an `ispm bench` config and their rendering: one point per grid
 * value combination of each method, each a sequence with that point's settings, rendered
 * in-process with its per-pass times (medians over frames × repeats) and its errors against a
 * reference run. */
#ifndef ISPM_BENCH_RUN_H
#define ISPM_BENCH_RUN_H

#include "bench_config.h"
#include "eng.h"
#include "metrics.h"

typedef struct bench_point {
    int method;                 /* index into config methods */
    const char *method_name;
    seq_sequence *seq;          /* the sequence with this point's settings */
    char label[160];            /* "<method> v1/v2/…" (grid values) */
    /* results */
    int sample_count;
    double *pass_samples;       /* sample_count × ENG_MAX_PASSES, by bench_passes slot */
    double *frame_samples;
    double pass_ms[ENG_MAX_PASSES], frame_ms;
    rep_metrics_err indirect, full;
    rep_metrics_bias bias;      /* indirect.radiance: mean ratio, block p90, edges */
    /* Per report frame (config report_frames): the metrics of that frame alone, and the
     * frame time summed from the first bench frame through it (first repeat). */
    rep_metrics_err series_err[BENCH_MAX_SERIES];
    rep_metrics_bias series_bias[BENCH_MAX_SERIES];
    double series_ms[BENCH_MAX_SERIES];
    float *first_indirect;      /* indirect.radiance of the first bench frame */
    int pareto;                 /* on the Pareto front (set when the results are written) */
} bench_point;

/* Pass names seen over all points, in first-seen order: the slots of bench_point.pass_ms. */
typedef struct bench_passes {
    int count;
    char name[ENG_MAX_PASSES][SCN_NAME_MAX];
} bench_passes;

typedef struct bench_reference {
    float *indirect, *full; /* frame_count × w × h × 3 */
    /* How its pixels sample the scene: "centre" (ispm reference --pixel-center: the points the
     * engine's G-buffers shade), "box" (jittered over the pixel: at silhouettes a mix of the
     * surfaces a pixel covers), "unknown" (not made by ispm reference). */
    const char *pixel;
} bench_reference;

/* Every point of c (methods in order, the grid's last key fastest) with its sequence: the
 * sequence file with the point's grid values, the method's settings, the config's threads and
 * capture limited to what the bench reads, each validated by the engine as a sequence file is.
 * Also checks that the sequence has the config's frames. On failure (ENG_ERR_INVALID or the
 * sequence file's error, naming the file) nothing is left allocated, *pts is NULL and *n 0. */
eng_result bench_points_make(const bench_config *c, bench_point **pts, int *n, eng_error *err);

/* Frees the points and what running them allocated; accepts NULL. */
void bench_points_free(bench_point *pts, int n);

/* Reads reference.indirect and reference.full of the reference run's frames for c's frames
 * (or its reference_frame) into *ref; the run must be w×h. Errors name the run or the config. */
eng_result bench_reference_load(const bench_config *c, int w, int h, bench_reference *ref, eng_error *err);

/* Frees what bench_reference_load allocated; accepts a zeroed one. */
void bench_reference_free(bench_reference *ref);

/* Renders the n points in order, each in its own engine: warm-up, then frames × repeats; the
 * metrics come from the first repeat. Fills each point's results and *passes. Without quiet, a
 * progress line per point on stderr, then its bias measures. Stops at the first failure. */
eng_result bench_run_points(const bench_config *c, const scn_scene *scene, bench_point *pts, int n,
                            const bench_reference *ref, int quiet, bench_passes *passes, eng_error *err);

#endif
