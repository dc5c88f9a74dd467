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

static int cmp_dbl(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void rep_metric_bias(const float *test, const float *ref, int w, int h, const signed char *mask,
                     rep_metrics_bias *out)
{
    memset(out, 0, sizeof *out);
    const size_t npix = (size_t)w * (size_t)h;
    double st = 0.0, sr = 0.0;
    double es[2] = {0}, rs[2] = {0}, ts[2] = {0}; /* [0] flat, [1] edge: Σ (t−r)², Σ r, Σ t */
    size_t cnt[2] = {0};
    for (size_t i = 0; i < npix; i++) {
        double t = ((double)test[3 * i] + test[3 * i + 1] + test[3 * i + 2]) / 3.0;
        double r = ((double)ref[3 * i] + ref[3 * i + 1] + ref[3 * i + 2]) / 3.0;
        st += t;
        sr += r;
        int m = mask ? mask[i] : 0;
        if (m < 0)
            continue;
        int k = m ? 1 : 0;
        es[k] += (t - r) * (t - r);
        rs[k] += r;
        ts[k] += t;
        cnt[k]++;
    }
    out->mean_ratio = sr > 0.0 ? st / sr : 0.0;
    for (int k = 0; k < 2; k++) {
        double ratio = rs[k] > 0.0 ? ts[k] / rs[k] : 0.0;
        double rel = cnt[k] && rs[k] > 0.0 ? sqrt(es[k] / (double)cnt[k]) / (rs[k] / (double)cnt[k]) : 0.0;
        if (k) {
            out->edge_ratio = ratio;
            out->edge_rel_rmse = rel;
        } else {
            out->flat_ratio = ratio;
            out->flat_rel_rmse = rel;
        }
    }
    out->edge_fraction = cnt[0] + cnt[1] ? (double)cnt[1] / (double)(cnt[0] + cnt[1]) : 0.0;

    const int B = REP_METRIC_BLOCK;
    const int bw = (w + B - 1) / B, bh = (h + B - 1) / B;
    double *bt = calloc((size_t)bw * bh, sizeof *bt), *br = calloc((size_t)bw * bh, sizeof *br);
    double *rel = calloc((size_t)bw * bh, sizeof *rel), *frel = calloc((size_t)bw * bh, sizeof *frel);
    unsigned char *edged = calloc((size_t)bw * bh, 1);
    if (!bt || !br || !rel || !frel || !edged) {
        free(bt);
        free(br);
        free(rel);
        free(frel);
        free(edged);
        return;
    }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * (size_t)w + (size_t)x, b = (size_t)(y / B) * bw + (size_t)(x / B);
            bt[b] += ((double)test[3 * i] + test[3 * i + 1] + test[3 * i + 2]) / 3.0;
            br[b] += ((double)ref[3 * i] + ref[3 * i + 1] + ref[3 * i + 2]) / 3.0;
            if (mask && mask[i] == 1)
                edged[b] = 1;
        }
    /* Block sums of equal pixel counts compare like block means; the threshold uses means. */
    double mean_r = sr / (double)npix;
    int nb = 0, nf = 0;
    for (int by = 0; by < bh; by++)
        for (int bx = 0; bx < bw; bx++) {
            size_t b = (size_t)by * bw + (size_t)bx;
            int pw = (bx * B + B <= w ? B : w - bx * B), ph = (by * B + B <= h ? B : h - by * B);
            double r = br[b] / (pw * ph), t = bt[b] / (pw * ph);
            if (r > 0.0 && r >= REP_BLOCK_MIN_FRACTION * mean_r) {
                rel[nb++] = fabs(t - r) / r;
                if (!edged[b])
                    frel[nf++] = fabs(t - r) / r;
            }
        }
    /* Nearest rank: the smallest value with at least 90 % of the blocks at or below it. */
    if (nb) {
        qsort(rel, (size_t)nb, sizeof *rel, cmp_dbl);
        int k = (int)ceil(0.9 * nb) - 1;
        out->block_p90 = rel[k < 0 ? 0 : k];
    }
    if (nf) {
        qsort(frel, (size_t)nf, sizeof *frel, cmp_dbl);
        int k = (int)ceil(0.9 * nf) - 1;
        out->flat_block_p90 = frel[k < 0 ? 0 : k];
    }
    free(bt);
    free(br);
    free(rel);
    free(frel);
    free(edged);
}

void rep_edge_mask(const float *position, const float *normal, int w, int h, const float view_proj[16],
                   const float eye[3], double radius, signed char *mask)
{
    /* Pixels per metre at distance 1: the larger of the two axes' scales (P00, P11 of the
     * projection appear in view_proj's first two rows scaled by the view rotation; their
     * column norms give them back). */
    double sx = sqrt((double)view_proj[0] * view_proj[0] + (double)view_proj[4] * view_proj[4] +
                     (double)view_proj[8] * view_proj[8]) * 0.5 * w;
    double sy = sqrt((double)view_proj[1] * view_proj[1] + (double)view_proj[5] * view_proj[5] +
                     (double)view_proj[9] * view_proj[9]) * 0.5 * h;
    double scale = sx > sy ? sx : sy;
    const double r2 = radius * radius, plane = 0.25 * radius;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * (size_t)w + (size_t)x;
            const float *P = position + 3 * i, *N = normal + 3 * i;
            if (N[0] == 0.0f && N[1] == 0.0f && N[2] == 0.0f) {
                mask[i] = -1;
                continue;
            }
            double dx = (double)P[0] - eye[0], dy = (double)P[1] - eye[1], dz = (double)P[2] - eye[2];
            double dist = sqrt(dx * dx + dy * dy + dz * dz);
            int R = (int)ceil(radius * scale / (dist > 1e-6 ? dist : 1e-6));
            if (R > 64)
                R = 64;
            int edge = 0;
            for (int v = y - R; v <= y + R && !edge; v++)
                for (int u = x - R; u <= x + R && !edge; u++) {
                    if ((u - x) * (u - x) + (v - y) * (v - y) > R * R)
                        continue;
                    if (u < 0 || v < 0 || u >= w || v >= h)
                        continue; /* the image's border is no edge of the scene */
                    size_t j = (size_t)v * (size_t)w + (size_t)u;
                    const float *Q = position + 3 * j, *M = normal + 3 * j;
                    if (M[0] == 0.0f && M[1] == 0.0f && M[2] == 0.0f) {
                        edge = 1; /* silhouette against the background */
                        continue;
                    }
                    double ex = (double)Q[0] - P[0], ey = (double)Q[1] - P[1], ez = (double)Q[2] - P[2];
                    double d2 = ex * ex + ey * ey + ez * ez;
                    double off = fabs(ex * N[0] + ey * N[1] + ez * N[2]);
                    double c = (double)N[0] * M[0] + (double)N[1] * M[1] + (double)N[2] * M[2];
                    if (d2 <= r2 && (c < 0.99 || off > plane))
                        edge = 1;
                }
            mask[i] = (signed char)edge;
        }
}
