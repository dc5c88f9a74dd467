/* metrics.c — error metrics of an image against a reference (metrics.h): RMSE, relative MSE,
 * mean and maximum absolute error, and an 8×8 block-averaged RMSE. Sums are in double, in
 * row-major order, so the values are reproducible. Owns nothing. */
#include "metrics.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static eng_result check_finite(const float *img, int w, int h, int channels, const char *what, const char *which,
                               eng_error *err)
{
    size_t n = (size_t)w * (size_t)h * (size_t)channels;
    for (size_t i = 0; i < n; i++)
        if (!isfinite(img[i])) {
            size_t px = i / (size_t)channels;
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s has %s at pixel (%zu, %zu) channel %zu", what, which,
                            isnan(img[i]) ? "NaN" : "Inf", px % (size_t)w, px / (size_t)w, i % (size_t)channels);
        }
    return ENG_OK;
}

eng_result rep_metric_compute(const float *test, const float *ref, int w, int h, int channels, const char *what,
                              rep_metrics_err *out, eng_error *err)
{
    memset(out, 0, sizeof *out);
    if (w < 1 || h < 1 || channels < 1 || channels > ENG_MAX_CHANNELS)
        return eng_fail(err, ENG_ERR_INVALID, "%s: bad image shape %dx%d×%d", what, w, h, channels);
    eng_result r = check_finite(test, w, h, channels, what, "the image", err);
    if (r == ENG_OK)
        r = check_finite(ref, w, h, channels, what, "the reference", err);
    if (r != ENG_OK)
        return r;
    const size_t npix = (size_t)w * (size_t)h;
    double se[ENG_MAX_CHANNELS] = {0}, rel[ENG_MAX_CHANNELS] = {0}, ae[ENG_MAX_CHANNELS] = {0};
    double max_abs = 0.0;
    for (size_t i = 0; i < npix; i++)
        for (int c = 0; c < channels; c++) {
            double t = test[i * (size_t)channels + (size_t)c], f = ref[i * (size_t)channels + (size_t)c];
            double d = t - f;
            se[c] += d * d;
            rel[c] += d * d / (f * f + REP_METRIC_EPSILON);
            ae[c] += fabs(d);
            if (fabs(d) > max_abs)
                max_abs = fabs(d);
        }
    /* Blocks: sum the differences of each block (the mean of the differences is the
     * difference of the means), then the RMSE over the blocks. */
    const int B = REP_METRIC_BLOCK;
    const int bw = (w + B - 1) / B, bh = (h + B - 1) / B;
    double bse[ENG_MAX_CHANNELS] = {0};
    for (int by = 0; by < bh; by++)
        for (int bx = 0; bx < bw; bx++) {
            double sum[ENG_MAX_CHANNELS] = {0};
            int n = 0;
            for (int y = by * B; y < by * B + B && y < h; y++)
                for (int x = bx * B; x < bx * B + B && x < w; x++, n++)
                    for (int c = 0; c < channels; c++) {
                        size_t k = ((size_t)y * (size_t)w + (size_t)x) * (size_t)channels + (size_t)c;
                        sum[c] += (double)test[k] - (double)ref[k];
                    }
            for (int c = 0; c < channels; c++) {
                double m = sum[c] / n;
                bse[c] += m * m;
            }
        }
    for (int c = 0; c < channels; c++) {
        out->rmse += sqrt(se[c] / (double)npix);
        out->rel_mse += rel[c] / (double)npix;
        out->mae += ae[c] / (double)npix;
        out->block_rmse += sqrt(bse[c] / ((double)bw * bh));
    }
    out->rmse /= channels;
    out->rel_mse /= channels;
    out->mae /= channels;
    out->block_rmse /= channels;
    out->max_abs = max_abs;
    return ENG_OK;
}
