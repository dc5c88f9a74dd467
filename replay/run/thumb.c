/* thumb.c — the report's thumbnails: one float buffer (or the difference of two) mapped to a
 * small 8-bit RGB image that a browser can show.
 *
 * How floats become bytes, per buffer kind (chosen by the buffer's name):
 *   *.display   already exposed and sRGB-encoded by the engine: clamp to [0,1], times 255;
 *   *.radiance  linear radiance: clamp to [0,1], sRGB transfer curve (no exposure, so a golden
 *               and a run of the same scene look alike and a flip shows only the change);
 *   other       data (positions, normals, depth, shadow distances, material, motion): one
 *               linear ramp per buffer, from the smallest to the largest finite value of the
 *               shown channels over golden *and* run together, so both thumbnails share one
 *               mapping and flipping between them compares like with like.
 * Channels shown: R,G,B when the buffer has them, else its first three (two: red and green,
 * one: grey). A pixel with a NaN or Inf in a shown channel is painted magenta (255,0,255).
 * The difference image is a heatmap of max over common channels of |run − golden|: black where
 * equal, then linear from dark red (the smallest non-zero difference is never black) through
 * yellow to white at the buffer's largest difference; a value whose class (finite, NaN, +Inf,
 * −Inf) differs is magenta; a cyan square ring (drawn only over black) marks the largest
 * difference, so that one changed pixel is found at a glance. Thumbnails are box-downsampled so the longest side is at most
 * REP_THUMB_MAX_SIDE; the heatmap takes the maximum over each box, so a single changed pixel
 * survives the reduction. Everything here is pure computation; files are report_html.c's.
 * It sits in the run room, below compare and report, because it is not the report's alone:
 * ꟻLIP takes a buffer's colour kind from rep_thumb_kind_of, and `ispm inspect` and the bench
 * map buffers to images with it too.
 */
#include "rep_run.h"
#include "rep_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

rep_thumb_kind rep_thumb_kind_of(const char *buffer)
{
    const char *dot = strrchr(buffer, '.');
    const char *leaf = dot ? dot + 1 : buffer;
    if (strcmp(leaf, "display") == 0)
        return REP_THUMB_DISPLAY;
    if (strcmp(leaf, "radiance") == 0)
        return REP_THUMB_RADIANCE;
    return REP_THUMB_DATA;
}

static int channel_index(const eng_buffer *b, const char *name)
{
    for (int c = 0; c < b->channel_count; c++)
        if (strcmp(b->channels[c], name) == 0)
            return c;
    return -1;
}

static void pick_channels(const eng_buffer *b, rep_thumb_map *m)
{
    static const char *const rgb[3] = {"R", "G", "B"};
    if (channel_index(b, "R") >= 0 && channel_index(b, "G") >= 0 && channel_index(b, "B") >= 0) {
        m->n = 3;
        for (int i = 0; i < 3; i++)
            snprintf(m->ch[i], sizeof m->ch[i], "%s", rgb[i]);
        return;
    }
    m->n = b->channel_count < 3 ? b->channel_count : 3;
    for (int i = 0; i < m->n; i++)
        snprintf(m->ch[i], sizeof m->ch[i], "%s", b->channels[i]);
}

static void widen(const eng_buffer *b, const rep_thumb_map *m, double *lo, double *hi)
{
    if (!b)
        return;
    int idx[3];
    for (int i = 0; i < m->n; i++)
        idx[i] = channel_index(b, m->ch[i]);
    size_t pixels = (size_t)b->width * (size_t)b->height;
    for (size_t p = 0; p < pixels; p++)
        for (int i = 0; i < m->n; i++) {
            if (idx[i] < 0)
                continue;
            float v = b->data[p * (size_t)b->channel_count + (size_t)idx[i]];
            if (!isfinite(v))
                continue;
            if (v < *lo)
                *lo = v;
            if (v > *hi)
                *hi = v;
        }
}

void rep_thumb_map_make(const char *buffer, const eng_buffer *run, const eng_buffer *golden, rep_thumb_map *m)
{
    memset(m, 0, sizeof *m);
    m->kind = rep_thumb_kind_of(buffer);
    pick_channels(run ? run : golden, m);
    m->lo = 0;
    m->hi = 1;
    if (m->kind != REP_THUMB_DATA)
        return;
    double lo = INFINITY, hi = -INFINITY;
    widen(run, m, &lo, &hi);
    widen(golden, m, &lo, &hi);
    if (lo <= hi) {
        m->lo = lo;
        m->hi = hi;
    }
}

/* w × h scaled down so the longest side is at most side (0: not scaled). */
static void fit(int w, int h, int side, int *tw, int *th)
{
    int longest = w > h ? w : h;
    if (side <= 0 || longest <= side) {
        *tw = w;
        *th = h;
        return;
    }
    *tw = (int)((long long)w * side / longest);
    *th = (int)((long long)h * side / longest);
    if (*tw < 1)
        *tw = 1;
    if (*th < 1)
        *th = 1;
}

/* Source pixel range [*a, *b) of thumbnail pixel i of n over a source of size s. */
static void box(int i, int n, int s, int *a, int *b)
{
    *a = (int)((long long)i * s / n);
    *b = (int)((long long)(i + 1) * s / n);
    if (*b <= *a)
        *b = *a + 1;
}

void rep_thumb_size(int w, int h, int *tw, int *th)
{
    fit(w, h, REP_THUMB_MAX_SIDE, tw, th);
}

/* lround(v * 255) for v in (0, 1), without the libm call (~75 of ~7,000 perf samples of a
 * differing replay of the CI run): x lies in (0, 255), its integer part k is the truncation,
 * x - k is exact, and ties go up, away from zero, as lround's do. */
static unsigned char to_byte(double v)
{
    if (!(v > 0))
        return 0;
    if (v >= 1)
        return 255;
    double x = v * 255.0;
    int k = (int)x;
    return (unsigned char)(x - (double)k >= 0.5 ? k + 1 : k);
}

static double srgb(double v)
{
    if (!(v > 0))
        return 0;
    if (v >= 1)
        return 1;
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}

unsigned char *rep_thumb_render(const eng_buffer *b, const rep_thumb_map *m, int *tw, int *th)
{
    return rep_image_render(b, m, REP_THUMB_MAX_SIDE, tw, th);
}

unsigned char *rep_image_render(const eng_buffer *b, const rep_thumb_map *m, int max_side, int *tw, int *th)
{
    fit(b->width, b->height, max_side, tw, th);
    unsigned char *out = rep_xcalloc((size_t)*tw * (size_t)*th, 3);
    int idx[3] = {-1, -1, -1};
    for (int i = 0; i < m->n; i++)
        idx[i] = channel_index(b, m->ch[i]);
    double span = m->hi > m->lo ? m->hi - m->lo : 0;
    size_t nc = (size_t)b->channel_count;
    for (int ty = 0; ty < *th; ty++) {
        int y0, y1;
        box(ty, *th, b->height, &y0, &y1);
        for (int tx = 0; tx < *tw; tx++) {
            int x0, x1;
            box(tx, *tw, b->width, &x0, &x1);
            double sum[3] = {0, 0, 0};
            int bad = 0;
            for (int y = y0; y < y1; y++)
                for (int x = x0; x < x1; x++) {
                    const float *px = &b->data[((size_t)y * (size_t)b->width + (size_t)x) * nc];
                    for (int i = 0; i < m->n; i++) {
                        if (idx[i] < 0)
                            continue;
                        if (!isfinite(px[idx[i]]))
                            bad = 1;
                        else
                            sum[i] += px[idx[i]];
                    }
                }
            unsigned char *o = &out[((size_t)ty * (size_t)*tw + (size_t)tx) * 3];
            if (bad) {
                o[0] = 255, o[1] = 0, o[2] = 255;
                continue;
            }
            double count = (double)(y1 - y0) * (double)(x1 - x0);
            double v[3] = {0, 0, 0};
            for (int i = 0; i < m->n; i++) {
                double a = sum[i] / count;
                if (idx[i] < 0)
                    v[i] = 0;
                else if (m->kind == REP_THUMB_RADIANCE)
                    v[i] = srgb(a);
                else if (m->kind == REP_THUMB_DISPLAY)
                    v[i] = a;
                else
                    v[i] = span > 0 ? (a - m->lo) / span : 0.5;
            }
            if (m->n == 1)
                v[1] = v[2] = v[0];
            for (int i = 0; i < 3; i++)
                o[i] = to_byte(v[i]);
        }
    }
    return out;
}

/* Black → red → yellow → white for t in [0,1]. */
static void hot(double t, unsigned char *o)
{
    double r = t * 3, g = t * 3 - 1, b = t * 3 - 2;
    o[0] = to_byte(r);
    o[1] = to_byte(g);
    o[2] = to_byte(b);
}

static int fclass(float v)
{
    return isnan(v) ? 1 : isinf(v) ? (v > 0 ? 2 : 3) : 0;
}

unsigned char *rep_thumb_diff(const eng_buffer *run, const eng_buffer *golden, double *scale, int *tw, int *th)
{
    *scale = 0;
    if (run->width != golden->width || run->height != golden->height)
        return NULL;
    int ia[ENG_MAX_CHANNELS], ib[ENG_MAX_CHANNELS], n = 0;
    for (int c = 0; c < run->channel_count; c++) {
        int k = channel_index(golden, run->channels[c]);
        if (k >= 0) {
            ia[n] = c;
            ib[n++] = k;
        }
    }
    if (n == 0)
        return NULL;
    size_t pixels = (size_t)run->width * (size_t)run->height;
    /* Per-pixel difference first (-1: a class mismatch), then the largest finite one. */
    double *d = rep_xmalloc(pixels * sizeof *d);
    size_t argmax = pixels;
    for (size_t p = 0; p < pixels; p++) {
        double m = 0;
        for (int i = 0; i < n; i++) {
            float a = run->data[p * (size_t)run->channel_count + (size_t)ia[i]];
            float b = golden->data[p * (size_t)golden->channel_count + (size_t)ib[i]];
            if (fclass(a) != fclass(b)) {
                m = -1;
                break;
            }
            double e = fclass(a) ? 0 : fabs((double)a - (double)b);
            if (e > m)
                m = e;
        }
        d[p] = m;
        if (m > *scale) {
            *scale = m;
            argmax = p;
        }
    }
    rep_thumb_size(run->width, run->height, tw, th);
    unsigned char *out = rep_xcalloc((size_t)*tw * (size_t)*th, 3);
    for (int ty = 0; ty < *th; ty++) {
        int y0, y1;
        box(ty, *th, run->height, &y0, &y1);
        for (int tx = 0; tx < *tw; tx++) {
            int x0, x1;
            box(tx, *tw, run->width, &x0, &x1);
            double m = 0;
            int bad = 0;
            for (int y = y0; y < y1; y++)
                for (int x = x0; x < x1; x++) {
                    double e = d[(size_t)y * (size_t)run->width + (size_t)x];
                    if (e < 0)
                        bad = 1;
                    else if (e > m)
                        m = e;
                }
            unsigned char *o = &out[((size_t)ty * (size_t)*tw + (size_t)tx) * 3];
            if (bad)
                o[0] = 255, o[1] = 0, o[2] = 255;
            else if (m > 0)
                hot(0.25 + 0.75 * (m / *scale), o);
        }
    }
    /* A ring around the largest difference: one changed pixel is easy to miss in a heatmap. */
    if (argmax < pixels) {
        int cx = (int)((long long)(argmax % (size_t)run->width) * *tw / run->width);
        int cy = (int)((long long)(argmax / (size_t)run->width) * *th / run->height);
        for (int y = cy - 7; y <= cy + 7; y++)
            for (int x = cx - 7; x <= cx + 7; x++) {
                int r = abs(x - cx) > abs(y - cy) ? abs(x - cx) : abs(y - cy);
                if (r < 6 || x < 0 || y < 0 || x >= *tw || y >= *th)
                    continue;
                unsigned char *o = &out[((size_t)y * (size_t)*tw + (size_t)x) * 3];
                if (!o[0] && !o[1] && !o[2])
                    o[0] = 0, o[1] = 200, o[2] = 255;
            }
    }
    free(d);
    return out;
}
