/* compare.c — one buffer of a run against the same buffer of its golden: metrics and verdict.
 *
 * The rules are idiff's (a pixel fails when some channel's absolute difference exceeds
 * `fail` and its relative difference exceeds `failrelative`; the buffer fails when more than
 * `failpercent` % of pixels fail or any difference exceeds `hardfail`), plus RMSE limits, an
 * exact (bit-identical) mode, and one deliberate departure: idiff 2.4 lets NaN and Inf slip
 * through its comparisons, so here any value whose class (finite, NaN, +Inf, -Inf) differs
 * between run and golden fails the buffer whatever the tolerances, and the first such value
 * is named. Arithmetic is in double over float inputs, in a fixed pixel order, so the metrics
 * themselves are reproducible.
 *
 * Local gates (Unreal's screenshot comparison moved to them): failpercent is global, so a light
 * leak in one corner stays under it. Every buffer that differs is also cut into block_size ×
 * block_size blocks aligned to pixel (0, 0), the right and bottom edge blocks partial and taken
 * as they are; a block's measure is its mean |Δ| over its pixels and channels (values finite in
 * both; a non-finite change fails on its own), and relative, that mean over the golden block's
 * mean |value| floored at REP_BLOCK_REL_FLOOR. The worst block by each measure is kept, whether
 * or not a gate is set, so every report can say where the error is densest. The only memory
 * allocated is one row of block sums, freed before return.
 */
#include "flip.h"
#include "rep_compare.h"
#include "rep_run.h"
#include "rep_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { CLS_FINITE = 0, CLS_NAN, CLS_PINF, CLS_NINF };

static int classify(float v)
{
    if (isnan(v))
        return CLS_NAN;
    if (isinf(v))
        return v > 0 ? CLS_PINF : CLS_NINF;
    return CLS_FINITE;
}

static void copy_name(char dst[REP_CHANNEL_NAME_MAX], const char *src)
{
    snprintf(dst, REP_CHANNEL_NAME_MAX, "%s", src);
}

const char *rep_verdict_name(rep_verdict v)
{
    switch (v) {
    case REP_V_CHECKED: return "checked";
    case REP_V_BITEXACT: return "bit-exact";
    case REP_V_WITHIN: return "within tolerance";
    case REP_V_WARN: return "warn";
    case REP_V_FAIL: return "fail";
    case REP_V_SIZE: return "size mismatch";
    case REP_V_COUNT: break;
    }
    return "unknown";
}

rep_verdict rep_compare(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol, rep_metrics *m)
{
    memset(m, 0, sizeof *m);
    m->max_x = m->max_y = m->first_fail_x = m->first_fail_y = m->nf_x = m->nf_y = -1;
    if (run->width != golden->width || run->height != golden->height ||
        run->channel_count != golden->channel_count || run->channel_count < 1 ||
        run->channel_count > ENG_MAX_CHANNELS)
        return REP_V_SIZE;
    int nch = run->channel_count;
    int map[ENG_MAX_CHANNELS]; /* run channel c is golden channel map[c] */
    for (int c = 0; c < nch; c++) {
        map[c] = -1;
        for (int k = 0; k < nch; k++)
            if (strcmp(run->channels[c], golden->channels[k]) == 0)
                map[c] = k;
        if (map[c] < 0)
            return REP_V_SIZE;
    }

    size_t npix = (size_t)run->width * (size_t)run->height;
    double sum = 0, sum2 = 0, peak = 0;
    int hard_fail = 0, hard_warn = 0;
    /* With no negative threshold, a finite value equal bit for bit to the golden's (most of a
     * replay: d = 0, rel = 0) moves nothing but the peak: it skips the arithmetic below, which
     * would add +0 to the sums and pass no test, so the metrics are the same bits. */
    const int same_fast = tol->fail >= 0 && tol->failrelative >= 0 && tol->warn >= 0 && tol->warnrelative >= 0 &&
                          tol->hardfail >= 0 && tol->hardwarn >= 0;
    for (size_t p = 0; p < npix; p++) {
        int pfail = 0, pwarn = 0;
        const float *ra = run->data + p * (size_t)nch;
        const float *gb = golden->data + p * (size_t)nch;
        for (int c = 0; c < nch; c++) {
            float a = ra[c], b = gb[map[c]];
            uint32_t ua, ub;
            memcpy(&ua, &a, 4);
            memcpy(&ub, &b, 4);
            if (ua != ub)
                m->values_differing++;
            int ca = classify(a), cb = classify(b);
            m->run_nan += ca == CLS_NAN;
            m->run_inf += ca == CLS_PINF || ca == CLS_NINF;
            m->golden_nan += cb == CLS_NAN;
            m->golden_inf += cb == CLS_PINF || cb == CLS_NINF;
            if (same_fast && ua == ub && ca == CLS_FINITE) {
                if (fabs((double)b) > peak)
                    peak = fabs((double)b);
                continue;
            }
            if (ca != CLS_FINITE || cb != CLS_FINITE) {
                if (ca != cb && m->nonfinite_mismatch++ == 0) {
                    m->nf_x = (int)(p % (size_t)run->width);
                    m->nf_y = (int)(p / (size_t)run->width);
                    copy_name(m->nf_channel, run->channels[c]);
                    m->nf_run = a;
                    m->nf_golden = b;
                }
                continue;
            }
            double d = fabs((double)a - (double)b);
            double mag = fmax(fabs((double)a), fabs((double)b));
            double rel = mag > 0 ? d / mag : 0;
            if (fabs((double)b) > peak)
                peak = fabs((double)b);
            sum += d;
            sum2 += d * d;
            if (d > m->max_abs) {
                m->max_abs = d;
                m->max_x = (int)(p % (size_t)run->width);
                m->max_y = (int)(p / (size_t)run->width);
                copy_name(m->max_channel, run->channels[c]);
            }
            if (d > tol->fail && rel > tol->failrelative)
                pfail = 1;
            if (d > tol->warn && rel > tol->warnrelative)
                pwarn = 1;
            if (d > tol->hardfail)
                hard_fail = 1;
            if (d > tol->hardwarn)
                hard_warn = 1;
        }
        if (pfail && m->fail_pixels++ == 0) {
            m->first_fail_x = (int)(p % (size_t)run->width);
            m->first_fail_y = (int)(p / (size_t)run->width);
        }
        m->warn_pixels += pwarn;
    }
    m->pixels = npix;
    m->values = npix * (size_t)nch;
    m->mean_abs = sum / (double)m->values;
    m->rmse = sqrt(sum2 / (double)m->values);
    m->psnr = m->rmse > 0 ? 20.0 * log10((peak > 0 ? peak : 1.0) / m->rmse) : INFINITY;
    m->fail_percent = 100.0 * (double)m->fail_pixels / (double)npix;
    m->warn_percent = 100.0 * (double)m->warn_pixels / (double)npix;

    m->width = run->width;
    m->height = run->height;
    m->block_size = tol->block_size > 0 ? tol->block_size : REP_BLOCK_SIZE;
    m->block_abs = m->block_rel = (rep_block){0, -1, -1, 0, 0};
    if (m->values_differing == 0)
        return REP_V_BITEXACT;
    rep_compare_blocks(run, golden, map, m->block_size, m);
    if (m->block_abs.value > tol->block_fail || m->block_rel.value > tol->block_failrelative)
        m->fail_why |= REP_WHY_BLOCK;
    if (tol->exact)
        m->fail_why |= REP_WHY_EXACT;
    if (m->nonfinite_mismatch)
        m->fail_why |= REP_WHY_NONFINITE;
    if (m->fail_percent > tol->failpercent)
        m->fail_why |= REP_WHY_PERCENT;
    if (hard_fail)
        m->fail_why |= REP_WHY_HARD;
    if (m->rmse > tol->rmse_fail)
        m->fail_why |= REP_WHY_RMSE;
    if (m->fail_why)
        return REP_V_FAIL;
    if (m->warn_percent > tol->warnpercent)
        m->warn_why |= REP_WHY_PERCENT;
    if (hard_warn)
        m->warn_why |= REP_WHY_HARD;
    if (m->rmse > tol->rmse_warn)
        m->warn_why |= REP_WHY_RMSE;
    if (m->block_abs.value > tol->block_warn || m->block_rel.value > tol->block_warnrelative)
        m->warn_why |= REP_WHY_BLOCK;
    return m->warn_why ? REP_V_WARN : REP_V_WITHIN;
}

/* Sums |a - b| of the values finite in both over one block row (rows y0..y1) into sum[bx]. */
static void block_row_sums(const eng_buffer *run, const eng_buffer *golden, const int *map, int bs, int y0, int y1,
                           double *sum)
{
    int nch = run->channel_count;
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < run->width; x++) {
            size_t p = (size_t)y * (size_t)run->width + (size_t)x;
            const float *ra = run->data + p * (size_t)nch, *gb = golden->data + p * (size_t)nch;
            double s = 0;
            for (int c = 0; c < nch; c++) {
                float a = ra[c], b = gb[map[c]];
                if (a != b && isfinite(a) && isfinite(b))
                    s += fabs((double)a - (double)b);
            }
            sum[x / bs] += s;
        }
}

/* Mean |value| of the golden's finite values over the block at (x0, y0), w × h. */
static double golden_block_mean(const eng_buffer *golden, int x0, int y0, int w, int h)
{
    int nch = golden->channel_count;
    double s = 0;
    for (int y = y0; y < y0 + h; y++) {
        const float *g = golden->data + ((size_t)y * (size_t)golden->width + (size_t)x0) * (size_t)nch;
        for (int k = 0; k < w * nch; k++)
            if (isfinite(g[k]))
                s += fabs((double)g[k]);
    }
    return s / ((double)w * (double)h * (double)nch);
}

void rep_compare_blocks(const eng_buffer *run, const eng_buffer *golden, const int *map, int bs, rep_metrics *m)
{
    m->width = run->width;
    m->height = run->height;
    m->block_size = bs;
    m->block_abs = m->block_rel = (rep_block){0, -1, -1, 0, 0};
    int nbx = (run->width + bs - 1) / bs;
    double *sum = rep_xcalloc((size_t)nbx + 1, sizeof *sum);
    for (int y0 = 0; y0 < run->height; y0 += bs) {
        int y1 = y0 + bs < run->height ? y0 + bs : run->height;
        memset(sum, 0, (size_t)nbx * sizeof *sum);
        block_row_sums(run, golden, map, bs, y0, y1, sum);
        for (int bx = 0; bx < nbx; bx++) {
            if (!(sum[bx] > 0))
                continue;
            int x0 = bx * bs, w = x0 + bs < run->width ? bs : run->width - x0, h = y1 - y0;
            double mean = sum[bx] / ((double)w * (double)h * (double)run->channel_count);
            if (mean > m->block_abs.value)
                m->block_abs = (rep_block){mean, x0, y0, w, h};
            double mag = golden_block_mean(golden, x0, y0, w, h);
            double rel = mean / (mag > REP_BLOCK_REL_FLOOR ? mag : REP_BLOCK_REL_FLOOR);
            if (rel > m->block_rel.value)
                m->block_rel = (rep_block){rel, x0, y0, w, h};
        }
    }
    free(sum);
}

static int rgb_index(const eng_buffer *b, int idx[3])
{
    static const char *const names[3] = {"R", "G", "B"};
    for (int i = 0; i < 3; i++) {
        idx[i] = -1;
        for (int c = 0; c < b->channel_count; c++)
            if (strcmp(b->channels[c], names[i]) == 0)
                idx[i] = c;
        if (idx[i] < 0)
            return 0;
    }
    return 1;
}

static float *packed_rgb(const eng_buffer *b, const int idx[3])
{
    size_t n = (size_t)b->width * (size_t)b->height;
    float *o = rep_xmalloc(n * 3 * sizeof *o);
    for (size_t p = 0; p < n; p++)
        for (int c = 0; c < 3; c++)
            o[3 * p + (size_t)c] = b->data[p * (size_t)b->channel_count + (size_t)idx[c]];
    return o;
}

float *rep_flip_buffers(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol, rep_flip_kind k,
                        int *exposures)
{
    int ia[3], ib[3];
    if (k == REP_FLIP_NONE || run->width != golden->width || run->height != golden->height || !rgb_index(run, ia) ||
        !rgb_index(golden, ib))
        return NULL;
    float *a = packed_rgb(run, ia), *b = packed_rgb(golden, ib);
    float *map = rep_xmalloc((size_t)run->width * (size_t)run->height * sizeof *map);
    rep_flip_desc d = {k, tol->flip_ppd, tol->flip_exposure[0], tol->flip_exposure[1]};
    rep_flip_map(a, b, run->width, run->height, 3, &d, map);
    if (exposures)
        *exposures = rep_flip_exposures(&d);
    free(a);
    free(b);
    return map;
}

rep_verdict rep_compare_flip_map(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol, rep_verdict v,
                                 int skip, rep_metrics *m, rep_flip_kind *kind, rep_flip_stats *s, float **keep)
{
    memset(s, 0, sizeof *s);
    *kind = REP_FLIP_NONE;
    if (keep)
        *keep = NULL;
    int ia[3], ib[3];
    rep_flip_kind k = rep_flip_kind_of(run->name ? run->name : "");
    if (skip || k == REP_FLIP_NONE || v == REP_V_SIZE || !rgb_index(run, ia) || !rgb_index(golden, ib))
        return v;
    *kind = k;
    if (v == REP_V_BITEXACT)
        return v; /* identical: ꟻLIP is 0 by construction, not worth a filter pass */
    int exposures = 0;
    float *map = rep_flip_buffers(run, golden, tol, k, &exposures);
    rep_flip_stats_of(map, (size_t)run->width * (size_t)run->height, s);
    s->exposures = exposures;
    if (keep)
        *keep = map;
    else
        free(map);
    if (s->mean > tol->flip_mean_fail || s->p99 > tol->flip_p99_fail) {
        m->fail_why |= REP_WHY_FLIP;
        return REP_V_FAIL;
    }
    return v;
}

rep_verdict rep_compare_flip(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol, rep_verdict v,
                             int skip, rep_metrics *m, rep_flip_kind *kind, rep_flip_stats *s)
{
    return rep_compare_flip_map(run, golden, tol, v, skip, m, kind, s, NULL);
}
