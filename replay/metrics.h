/* metrics.h — error metrics of a rendered image against a reference (the bench's accuracy
 * axis; issue 5). Both images are w×h, `channels` floats per pixel interleaved (RGB in
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

#include "eng.h"

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

#ifdef __cplusplus
}
#endif

#endif
