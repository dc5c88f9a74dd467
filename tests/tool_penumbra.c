/* tool_penumbra.c — the soft-shadow measurements (bench/penumbra.sh,
 * tests/e2e_softshadow.sh): compares frame 0 of an engine run (direct.radiance,
 * gbuffer.position) with frame 0 of a reference run of the same sequence (reference.direct).
 *
 *   width  the 10%–90% width (m, along world x) of the shadow edge on the floor: per image
 *          column, the mean of (R+G+B)/3 over rows ROW±ROWS of floor pixels (|y| < 1 mm) with
 *          x in [X0, X1]; the 10% and 90% levels between the profile's minimum and maximum;
 *          the width is the distance between the last column below 10% before the first
 *          column above 90%, each crossing interpolated linearly. Same columns for both runs.
 *   p90    floor direct light: means of 8×8 blocks made only of floor pixels, relative error
 *          |ispm − ref| / max(ref, 5% of the mean floor block), its 90th percentile.
 *
 *   pen    the largest direct.penumbra of the run (texels), −1 when it has none.
 *
 * usage: ispm_test_penumbra RUN REF X0 X1 [MAX_WIDTH_ERR MAX_P90]
 * prints "width_ispm_mm width_ref_mm width_err p90 pen"; with the limits, exit 1 when
 * |width_ispm/width_ref − 1| > MAX_WIDTH_ERR or p90 > MAX_P90.
 *
 * usage: ispm_test_penumbra --lines RUN REF [LINE...]   (any scene; also needs gbuffer.normal)
 *   floor_p90  the floor blocks' p90 as above, but over the blocks lit in the reference (block
 *              mean at least 10% of the brightest floor block) and relative to the reference's
 *              block alone;
 *   LINE       x=COL:AXIS or y=ROW:AXIS (AXIS +x, -x, +y, -y, +z or -z): on that image column or
 *              row, the longest run of pixels whose gbuffer.normal is within 0.1 of AXIS (x=40:+y,
 *              the floor), the 10–90% width (pixels) of its one shadow edge for the run and the
 *              reference (edge_width) and their ratio; exit 1 when either has none.
 * PENUMBRA_DUMP=1 (--lines) writes every block's and every line pixel's values to stderr. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rep_run.h"
#include "rep_util.h"

#define ROWS 16

typedef struct image {
    int w, h;
    float *rgb; /* mean of R, G, B per pixel */
    float *pos; /* xyz per pixel, or NULL */
} image;

static int channel(const rep_part *p, const char *name)
{
    for (int c = 0; c < p->channel_count; c++)
        if (strcmp(p->channels[c], name) == 0)
            return c;
    return -1;
}

/* Frame 0's buffer `name` of the run at dir as w×h×nch floats in out, channels in the order
 * of names; quiet: a missing buffer returns 1 without a message. */
static int read_buffer(const char *dir, const char *name, const char *const *names, int nch, int quiet, int *w,
                       int *h, float **out)
{
    rep_run *run = NULL;
    eng_error err;
    rep_part *parts = NULL;
    if (rep_run_open(dir, &run, &err) != ENG_OK || rep_run_read_frame(run, 0, &parts, &err) != ENG_OK) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    int j = rep_frame_find(&run->frames[0], name);
    int ch[3] = {-1, -1, -1}, ok = j >= 0;
    for (int c = 0; c < nch && ok; c++)
        ok = (ch[c] = channel(&parts[j], names[c])) >= 0;
    if (!ok) {
        if (!quiet)
            fprintf(stderr, "%s: frame 0 has no %s with channels %s...\n", dir, name, names[0]);
        rep_parts_free(parts, run->frames[0].buffer_count);
        rep_run_close(run);
        return 1;
    }
    const rep_part *p = &parts[j];
    *w = p->width;
    *h = p->height;
    size_t n = (size_t)p->width * (size_t)p->height;
    *out = rep_xmalloc(n * (size_t)nch * sizeof(float));
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < nch; c++)
            (*out)[i * (size_t)nch + (size_t)c] = p->data[i * (size_t)p->channel_count + (size_t)ch[c]];
    rep_parts_free(parts, run->frames[0].buffer_count);
    rep_run_close(run);
    return 0;
}

static const char *const RGB[] = {"R", "G", "B"};
static const char *const XYZ[] = {"X", "Y", "Z"};
static const char *const Y[] = {"Y"};

static float lum(const float *rgb, size_t i)
{
    return (rgb[i * 3] + rgb[i * 3 + 1] + rgb[i * 3 + 2]) / 3.0f;
}

static int floor_px(const float *pos, size_t i)
{
    return fabsf(pos[i * 3 + 1]) < 1e-3f;
}

/* The 10–90% width (m) of the profile v over the columns with world x xs (n of them, x rising). */
static double width_10_90(const double *v, const double *xs, int n)
{
    double lo = v[0], hi = v[0];
    for (int i = 1; i < n; i++) {
        lo = v[i] < lo ? v[i] : lo;
        hi = v[i] > hi ? v[i] : hi;
    }
    double l10 = lo + 0.1 * (hi - lo), l90 = lo + 0.9 * (hi - lo);
    int i90 = 0;
    while (i90 < n && v[i90] < l90)
        i90++;
    int i10 = i90;
    while (i10 > 0 && v[i10 - 1] >= l10)
        i10--;
    if (i10 == 0 || i90 >= n)
        return NAN;
    /* Crossings between i10-1 and i10, between i90-1 and i90. */
    double x10 = xs[i10 - 1] + (xs[i10] - xs[i10 - 1]) * (l10 - v[i10 - 1]) / (v[i10] - v[i10 - 1]);
    double x90 = i90 > 0 ? xs[i90 - 1] + (xs[i90] - xs[i90 - 1]) * (l90 - v[i90 - 1]) / (v[i90] - v[i90 - 1])
                         : xs[0];
    return x90 - x10;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* ---------------------------------------------------------------- --lines */

/* The 10–90% width (pixels) of the one shadow edge on profile v (n pixels along a line): the
 * levels between the profile's minimum and maximum; from the darkest pixel, the nearest 10% and
 * 90% crossings on the side where the profile rises to its maximum, each interpolated linearly. */
static double edge_width(const double *v, int n)
{
    int imin = 0, imax = 0;
    for (int i = 1; i < n; i++) {
        imin = v[i] < v[imin] ? i : imin;
        imax = v[i] > v[imax] ? i : imax;
    }
    double lo = v[imin], hi = v[imax];
    if (!(hi > lo))
        return NAN;
    double l10 = lo + 0.1 * (hi - lo), l90 = lo + 0.9 * (hi - lo);
    int dir = imax > imin ? 1 : -1;
    double x10 = NAN, x90 = NAN;
    for (int i = imin; i != imax; i += dir) {
        double a = v[i], b = v[i + dir];
        /* The last rise through 10% before the first through 90%. */
        if (isnan(x90) && a < l10 && b >= l10)
            x10 = i + dir * (l10 - a) / (b - a);
        if (isnan(x90) && a < l90 && b >= l90) {
            x90 = i + dir * (l90 - a) / (b - a);
            break;
        }
    }
    if (isnan(x10) && !isnan(x90))
        x10 = imin;
    return fabs(x90 - x10);
}

/* The 8x8 blocks made only of floor pixels, in row order: their mean luminance in the engine's
 * image (be) and the reference (br), each holding (w / 8) * (h / 8) values; returns how many. */
static int floor_blocks(const float *eng, const float *ref, const float *pos, int w, int h, double *be, double *br)
{
    int bw = w / 8, bh = h / 8, nb = 0;
    for (int by = 0; by < bh; by++)
        for (int bx = 0; bx < bw; bx++) {
            double se = 0, sr = 0;
            int ok = 1;
            for (int y = by * 8; y < by * 8 + 8 && ok; y++)
                for (int x = bx * 8; x < bx * 8 + 8; x++) {
                    size_t i = (size_t)y * (size_t)w + (size_t)x;
                    if (!floor_px(pos, i)) {
                        ok = 0;
                        break;
                    }
                    se += lum(eng, i);
                    sr += lum(ref, i);
                }
            if (!ok)
                continue;
            be[nb] = se / 64;
            br[nb] = sr / 64;
            if (getenv("PENUMBRA_DUMP"))
                fprintf(stderr, "block %d at %d,%d\n", nb, bx * 8, by * 8);
            nb++;
        }
    return nb;
}

/* --lines (see the header): the floor p90 over lit blocks, then each LINE's widths. */
static int lines_main(const char *prog, int argc, char **argv, const float *eng, const float *ref, const float *pos, const float *nrm,
                      int w, int h)
{
    /* Floor blocks lit in the reference: block mean at least 10% of the brightest floor block. */
    double *be = rep_xcalloc((size_t)(w / 8) * (size_t)(h / 8), sizeof(double));
    double *br = rep_xcalloc((size_t)(w / 8) * (size_t)(h / 8), sizeof(double));
    double max_ref = 0.0;
    int nb = floor_blocks(eng, ref, pos, w, h, be, br);
    for (int i = 0; i < nb; i++)
        max_ref = br[i] > max_ref ? br[i] : max_ref;
    int lit = 0;
    for (int i = 0; i < nb; i++)
        if (br[i] >= 0.1 * max_ref) {
            if (getenv("PENUMBRA_DUMP"))
                fprintf(stderr, "block %d %.4f %.4f %+.3f\n", i, be[i], br[i], be[i] / br[i] - 1.0);
            be[lit++] = fabs(be[i] - br[i]) / br[i];
        }
    if (lit == 0) {
        fprintf(stderr, "%s: no lit 8x8 block of floor pixels\n", prog);
        return 1;
    }
    qsort(be, (size_t)lit, sizeof(double), cmp_double);
    printf("floor_p90 %.4f (%d lit blocks of %d)\n", be[(size_t)ceil(0.9 * lit) - 1], lit, nb);
    free(be);
    free(br);
    int rc = 0;
    for (int a = 0; a < argc; a++) {
        char kind, sign, axis;
        int at;
        if (sscanf(argv[a], "%c=%d:%c%c", &kind, &at, &sign, &axis) != 4 || (kind != 'x' && kind != 'y') ||
            (sign != '+' && sign != '-') || axis < 'x' || axis > 'z' || at < 0 || at >= (kind == 'x' ? w : h)) {
            fprintf(stderr, "%s: bad line %s (want x=COL:+y or y=ROW:-z)\n", prog, argv[a]);
            return 2;
        }
        float want[3] = {0, 0, 0};
        want[axis - 'x'] = sign == '+' ? 1.0f : -1.0f;
        int len = kind == 'x' ? h : w;
        double *ve = rep_xcalloc((size_t)len, sizeof(double)), *vr = rep_xcalloc((size_t)len, sizeof(double));
        int best = 0, best_at = 0, run = 0;
        for (int k = 0; k <= len; k++) {
            int on = 0;
            if (k < len) {
                size_t i = kind == 'x' ? (size_t)k * (size_t)w + (size_t)at : (size_t)at * (size_t)w + (size_t)k;
                float d = 0;
                for (int c = 0; c < 3; c++)
                    d += (nrm[i * 3 + c] - want[c]) * (nrm[i * 3 + c] - want[c]);
                on = d < 0.01f;
            }
            run = on ? run + 1 : 0;
            if (run > best) {
                best = run;
                best_at = k - run + 1;
            }
        }
        for (int k = 0; k < best; k++) {
            int kk = best_at + k;
            size_t i = kind == 'x' ? (size_t)kk * (size_t)w + (size_t)at : (size_t)at * (size_t)w + (size_t)kk;
            ve[k] = lum(eng, i);
            vr[k] = lum(ref, i);
            if (getenv("PENUMBRA_DUMP"))
                fprintf(stderr, "%s %d %.4f %.4f\n", argv[a], kk, ve[k], vr[k]);
        }
        double we = best >= 4 ? edge_width(ve, best) : NAN, wr = best >= 4 ? edge_width(vr, best) : NAN;
        printf("%s %.2f %.2f %.3f (pixels %d-%d)\n", argv[a], we, wr, we / wr, best_at, best_at + best - 1);
        if (isnan(we) || isnan(wr))
            rc = 1;
        free(ve);
        free(vr);
    }
    return rc;
}

int main(int argc, char **argv)
{
    if (argc >= 4 && strcmp(argv[1], "--lines") == 0) {
        int w, h, rw, rh, pw, ph, nw, nh;
        float *eng = NULL, *ref = NULL, *pos = NULL, *nrm = NULL;
        if (read_buffer(argv[2], "direct.radiance", RGB, 3, 0, &w, &h, &eng) ||
            read_buffer(argv[2], "gbuffer.position", XYZ, 3, 0, &pw, &ph, &pos) ||
            read_buffer(argv[2], "gbuffer.normal", XYZ, 3, 0, &nw, &nh, &nrm) ||
            read_buffer(argv[3], "reference.direct", RGB, 3, 0, &rw, &rh, &ref))
            return 1;
        if (rw != w || rh != h || pw != w || ph != h || nw != w || nh != h) {
            fprintf(stderr, "%s, %s: image sizes differ\n", argv[2], argv[3]);
            return 1;
        }
        int rc = lines_main(argv[0], argc - 4, argv + 4, eng, ref, pos, nrm, w, h);
        free(eng);
        free(ref);
        free(pos);
        free(nrm);
        return rc;
    }
    if (argc != 5 && argc != 7) {
        fprintf(stderr, "usage: %s RUN REF X0 X1 [MAX_WIDTH_ERR MAX_P90] | --lines RUN REF [LINE...]\n", argv[0]);
        return 2;
    }
    double x0 = atof(argv[3]), x1 = atof(argv[4]);
    int w, h, rw, rh, pw, ph;
    float *eng = NULL, *ref = NULL, *pos = NULL;
    if (read_buffer(argv[1], "direct.radiance", RGB, 3, 0, &w, &h, &eng) ||
        read_buffer(argv[1], "gbuffer.position", XYZ, 3, 0, &pw, &ph, &pos) ||
        read_buffer(argv[2], "reference.direct", RGB, 3, 0, &rw, &rh, &ref))
        return 1;
    /* The widest penumbra the engine reports (direct.penumbra), −1 without the buffer. */
    double pen_max = -1.0;
    float *pen = NULL;
    int qw, qh;
    if (read_buffer(argv[1], "direct.penumbra", Y, 1, 1, &qw, &qh, &pen) == 0) {
        pen_max = 0.0;
        for (size_t i = 0; i < (size_t)qw * (size_t)qh; i++)
            pen_max = pen[i] > pen_max ? pen[i] : pen_max;
        free(pen);
    }
    if (rw != w || rh != h || pw != w || ph != h) {
        fprintf(stderr, "%s, %s: image sizes differ\n", argv[1], argv[2]);
        return 1;
    }
    /* Penumbra profile. */
    double *ve = rep_xcalloc((size_t)w, sizeof(double)), *vr = rep_xcalloc((size_t)w, sizeof(double));
    double *xs = rep_xcalloc((size_t)w, sizeof(double));
    int n = 0;
    for (int x = 0; x < w; x++) {
        double se = 0, sr = 0, sx = 0;
        int cnt = 0;
        for (int y = h / 2 - ROWS; y <= h / 2 + ROWS; y++) {
            size_t i = (size_t)y * (size_t)w + (size_t)x;
            if (!floor_px(pos, i) || pos[i * 3] < x0 || pos[i * 3] > x1) {
                cnt = -1;
                break;
            }
            se += lum(eng, i);
            sr += lum(ref, i);
            sx += pos[i * 3];
            cnt++;
        }
        if (cnt <= 0)
            continue;
        ve[n] = se / cnt;
        vr[n] = sr / cnt;
        xs[n] = sx / cnt;
        n++;
    }
    if (n < 4) {
        fprintf(stderr, "%s: fewer than 4 floor columns with x in [%g, %g]\n", argv[1], x0, x1);
        return 1;
    }
    double we = width_10_90(ve, xs, n), wr = width_10_90(vr, xs, n);
    /* Floor blocks. */
    double *be = rep_xcalloc((size_t)(w / 8) * (size_t)(h / 8), sizeof(double));
    double *br = rep_xcalloc((size_t)(w / 8) * (size_t)(h / 8), sizeof(double));
    double mean_ref = 0;
    int nb = floor_blocks(eng, ref, pos, w, h, be, br);
    for (int i = 0; i < nb; i++)
        mean_ref += br[i];
    if (nb == 0) {
        fprintf(stderr, "%s: no 8x8 block of floor pixels\n", argv[1]);
        return 1;
    }
    mean_ref /= nb;
    for (int i = 0; i < nb; i++)
        be[i] = fabs(be[i] - br[i]) / fmax(br[i], 0.05 * mean_ref);
    qsort(be, (size_t)nb, sizeof(double), cmp_double);
    double p90 = be[(size_t)ceil(0.9 * nb) - 1];
    double err = we / wr - 1.0;
    printf("%.1f %.1f %+.3f %.4f %.1f\n", we * 1000.0, wr * 1000.0, err, p90, pen_max);
    int rc = 0;
    if (argc == 7) {
        double max_err = atof(argv[5]), max_p90 = atof(argv[6]);
        if (!(fabs(err) <= max_err)) {
            fprintf(stderr, "penumbra width %.1f mm vs reference %.1f mm: off by %.0f%% (limit %.0f%%)\n",
                    we * 1000.0, wr * 1000.0, 100.0 * err, 100.0 * max_err);
            rc = 1;
        }
        if (!(p90 <= max_p90)) {
            fprintf(stderr, "floor direct light 8x8-block p90 relative error %.3f (limit %.3f)\n", p90, max_p90);
            rc = 1;
        }
    }
    free(ve);
    free(vr);
    free(xs);
    free(be);
    free(br);
    free(eng);
    free(ref);
    free(pos);
    return rc;
}
