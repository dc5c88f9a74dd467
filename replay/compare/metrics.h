/* metrics.h — error metrics of a rendered image against a reference (the bench's accuracy
 * axis). Both images are w×h, `channels` floats per pixel interleaved (RGB in
 * practice), row-major. Every metric is computed per channel over all pixels and then
 * averaged over the channels, except max_abs, the largest |t − r| anywhere (an average of
 * per-channel maxima would name no pixel).
 *
 *   rmse        sqrt(mean (t − r)²)
 *   rel_mse     mean (t − r)² / (r² + ε), ε = REP_METRIC_EPSILON (relative MSE as in the
 *               denoising literature; ε keeps black reference pixels from dominating)
 *   mae         mean |t − r|
 *   max_abs     max |t − r| over all pixels and channels
 *   block_rmse  both images averaged over 8×8 blocks first (blocks at the right and bottom
 *               edges average the pixels they have), then RMSE over the blocks: noise and edge
 *               aliasing within a block cancel, bias does not
 *
 * A NaN or infinity in either image is an error (ENG_ERR_INVALID naming the image, pixel and
 * channel), never skipped: a metric that ignores the pixels a method breaks would flatter it. */
#ifndef ISPM_REP_METRICS_H
#define ISPM_REP_METRICS_H

#include "eng_core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define REP_METRIC_EPSILON 1e-2
#define REP_METRIC_BLOCK 8

typedef struct rep_metrics_err {
    double rmse, rel_mse, mae, max_abs, block_rmse;
} rep_metrics_err;

/* Computes the metrics of test against ref. what names the pair in messages (e.g.
 * "frame 3 indirect.radiance"). w, h >= 1, channels 1..ENG_MAX_CHANNELS. */
eng_result rep_metric_compute(const float *test, const float *ref, int w, int h, int channels, const char *what,
                              rep_metrics_err *out, eng_error *err);

/* Bias measures of an indirect image: images RGB (3 floats a pixel), per pixel
 * the mean of R, G, B ("intensity").
 *
 *   mean_ratio     Σ t / Σ r over all pixels (1 = the right amount of light)
 *   block_p90      8×8 blocks: |mean t − mean r| / mean r per block, its 90th percentile over
 *                  the blocks whose mean r is at least REP_BLOCK_MIN_FRACTION of the image's
 *                  mean (black blocks have no relative error)
 *   flat_block_p90 the same over the blocks away from geometric edges: those with no pixel of
 *                  the edge mask (mask ≠ 1; = block_p90 without a mask)
 *   edge_*, flat_* the same ratio, and the relative RMSE √(mean (t − r)²) / mean r, over the
 *                  pixels of the edge mask (mask ≠ 0) and over the other surface pixels
 *                  (mask = 0); edge_fraction: the edge pixels over the surface pixels
 * mask: w×h, 1 edge, 0 away from edges, −1 not counted (background); NULL = no edge split
 * (edge_* = 0, flat_* over all pixels). */
#define REP_BLOCK_MIN_FRACTION 0.01
typedef struct rep_metrics_bias {
    double mean_ratio, block_p90;
    double edge_ratio, edge_rel_rmse, flat_ratio, flat_rel_rmse, edge_fraction;
    double flat_block_p90;
} rep_metrics_bias;

void rep_metric_bias(const float *test, const float *ref, int w, int h, const signed char *mask,
                     rep_metrics_bias *out);

/* The edge mask of rep_metric_bias from an eye G-buffer (position XYZ, normal XYZ, top row
 * first, w×h) and the camera (view_proj, column-major, eye): a surface pixel is an edge pixel
 * when a visible surface point of another plane lies within `radius` metres of it (searched
 * among the pixels within the radius projected at its distance), another plane meaning a
 * normal more than ~8° apart (cos < 0.99) or a point farther than radius/4 off its tangent
 * plane; a background pixel in that window (a silhouette) also counts. Background pixels
 * (normal 0) are −1. */
void rep_edge_mask(const float *position, const float *normal, int w, int h, const float view_proj[16],
                   const float eye[3], double radius, signed char *mask);

#ifdef __cplusplus
}
#endif

#endif
