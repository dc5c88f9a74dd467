/* test_flip.c — Check suite of ꟻLIP / HDR-ꟻLIP (replay/compare/flip.c): identical images give 0,
 * uniform images against values computed by hand from the papers' formulas, and the metric's
 * documented behaviour on constructed images (a one-pixel change, a shift, a contrast change). */
#include "flip.h"
#include "rep_compare.h"
#include "rep_util.h"

#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* c_max of [F] §4.2 by hand: Hunt-adjusted Lab of linear green (0,1,0) is (87.7362, −75.6099,
 * 72.9812), of blue (0,0,1) (32.2982, 25.5781, −34.8364); HyAB = 55.4380 + 147.8636 = 203.30165;
 * 203.30165^0.7 = 41.276098. */
#define CMAX 41.276098411857355

static double srgb_lin(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

/* L* of a grey of linear luminance Y (a grey's a*, b* are 0, and Hunt leaves L alone). */
static double grey_L(double Y)
{
    return 116.0 * cbrt(Y) - 16.0;
}

/* [F] Eq. 6 with the papers' p_c = 0.4, p_t = 0.95, q_c = 0.7. */
static double remap_by_hand(double hyab)
{
    double e = pow(hyab, 0.7), p = 0.4 * CMAX;
    return e < p ? 0.95 * e / p : 0.95 + (e - p) / (CMAX - p) * 0.05;
}

static float *image(int w, int h)
{
    return calloc((size_t)w * (size_t)h * 3, sizeof(float));
}

static void fill(float *img, int w, int h, float r, float g, float b)
{
    for (int p = 0; p < w * h; p++) {
        img[3 * p] = r;
        img[3 * p + 1] = g;
        img[3 * p + 2] = b;
    }
}

static double mean_of(const float *t, const float *r, int w, int h, const rep_flip_desc *d)
{
    rep_flip_stats s;
    rep_flip_compute(t, r, w, h, 3, d, &s);
    return s.mean;
}

START_TEST(identical_images_give_zero)
{
    int w = 23, h = 17;
    float *a = image(w, h), *b = image(w, h), *map = malloc((size_t)w * h * sizeof(float));
    unsigned s = 12345;
    for (int i = 0; i < w * h * 3; i++) {
        s = s * 1103515245u + 12345u;
        a[i] = (float)((s >> 8) & 0xffff) / 65535.0f * 3.0f; /* radiance up to 3; LDR clamps */
    }
    memcpy(b, a, (size_t)w * h * 3 * sizeof(float));
    rep_flip_desc ldr = {REP_FLIP_LDR, 0, 0, 0}, hdr = {REP_FLIP_HDR, 0, 0, 0};
    rep_flip_map(a, b, w, h, 3, &ldr, map);
    for (int p = 0; p < w * h; p++)
        ck_assert_float_eq(map[p], 0.0f);
    rep_flip_map(a, b, w, h, 3, &hdr, map);
    for (int p = 0; p < w * h; p++)
        ck_assert_float_eq(map[p], 0.0f);
    rep_flip_stats st;
    rep_flip_compute(a, b, w, h, 3, &hdr, &st);
    ck_assert(st.mean == 0 && st.p99 == 0 && st.max == 0);
    ck_assert_int_eq(st.exposures, 8); /* default range −4..4: ⌈8⌉ exposures */
    free(a);
    free(b);
    free(map);
}
END_TEST

/* Uniform images: the normalised CSF filters keep each value, the zero-sum feature kernels give
 * 0, so ꟻLIP is the re-mapped HyAB of the two colours ([F] Eq. 9 with ΔE_f = 0). */
START_TEST(uniform_images_match_hand_computation)
{
    const int sizes[2][2] = {{1, 1}, {5, 3}};
    for (int k = 0; k < 2; k++) {
        int w = sizes[k][0], h = sizes[k][1];
        float *a = image(w, h), *b = image(w, h), *map = malloc((size_t)w * h * sizeof(float));
        rep_flip_desc ldr = {REP_FLIP_LDR, 0, 0, 0};
        /* black against white: HyAB = |0 − 100| = 100 > p_c·c_max after ^0.7 (25.12 > 16.51) */
        fill(a, w, h, 0, 0, 0);
        fill(b, w, h, 1, 1, 1);
        rep_flip_map(a, b, w, h, 3, &ldr, map);
        double bw = remap_by_hand(100.0);
        ck_assert_double_eq_tol(bw, 0.96737976, 1e-7);
        for (int p = 0; p < w * h; p++)
            ck_assert_double_eq_tol(map[p], bw, 1e-5);
        /* sRGB grey 0.5 against 0.6: ΔL only; 0.2850 */
        fill(a, w, h, 0.5f, 0.5f, 0.5f);
        fill(b, w, h, 0.6f, 0.6f, 0.6f);
        rep_flip_map(a, b, w, h, 3, &ldr, map);
        double dl = fabs(grey_L(srgb_lin(0.5)) - grey_L(srgb_lin(0.6)));
        double grey = remap_by_hand(dl);
        ck_assert_double_eq_tol(grey, 0.28501300, 1e-7);
        for (int p = 0; p < w * h; p++)
            ck_assert_double_eq_tol(map[p], grey, 1e-5);
        /* red against green: Hunt-Lab (53.2369, 42.6393, 35.7755) vs (87.7362, −75.6099, 72.9812) */
        fill(a, w, h, 1, 0, 0);
        fill(b, w, h, 0, 1, 0);
        rep_flip_map(a, b, w, h, 3, &ldr, map);
        double rg = remap_by_hand(fabs(53.23687853 - 87.73621066) + hypot(42.63926567 + 75.60993020, 35.77545926 - 72.98123138));
        ck_assert_double_eq_tol(rg, 0.98666228, 1e-7);
        for (int p = 0; p < w * h; p++)
            ck_assert_double_eq_tol(map[p], rg, 1e-5);
        const double red[3] = {1, 0, 0}, green[3] = {0, 1, 0};
        ck_assert_double_eq_tol(rep_flip_uniform_ldr(red, green), rg, 1e-6);
        free(a);
        free(b);
        free(map);
    }
}
END_TEST

/* HDR: a 1×1 grey of radiance 0.2 against 0.3 over the pinned range [0, 1]: two exposures (c = 0,
 * 1), each tone-mapped with the ACES fit of [H] Eq. 2, the larger re-mapped ΔL wins. */
START_TEST(hdr_uniform_matches_hand_computation)
{
    float a[3] = {0.2f, 0.2f, 0.2f}, b[3] = {0.3f, 0.3f, 0.3f}, map[1];
    rep_flip_desc hdr = {REP_FLIP_HDR, 0, 0.0, 1.0};
    rep_flip_map(a, b, 1, 1, 3, &hdr, map);
    double best = 0;
    for (int c = 0; c <= 1; c++) {
        double t[2];
        for (int i = 0; i < 2; i++) {
            double x = ldexp(i ? (double)0.3f : (double)0.2f, c);
            t[i] = (0.36 * 2.51 * x * x + 0.6 * 0.03 * x) / (0.36 * 2.43 * x * x + 0.6 * 0.59 * x + 0.14);
        }
        double v = remap_by_hand(fabs(grey_L(t[0]) - grey_L(t[1])));
        best = v > best ? v : best;
    }
    ck_assert_double_eq_tol(map[0], best, 1e-5);
    printf("flip: HDR 1x1 grey 0.2 vs 0.3, exposures [0,1]: %.6f (by hand %.6f)\n", map[0], best);
    rep_flip_stats st;
    rep_flip_compute(a, b, 1, 1, 3, &hdr, &st);
    ck_assert_int_eq(st.exposures, 2);
}
END_TEST

/* One pixel of a grey 31×31 image changed: the error is largest at that pixel, and exactly 0
 * where neither the CSF filters (radius 10 at 67 ppd) nor the feature kernels (radius 9) reach
 * it; swapping the images changes nothing (the metric is symmetric). */
START_TEST(one_pixel_change)
{
    int w = 31, h = 31, cx = 15, cy = 15;
    float *a = image(w, h), *b = image(w, h);
    float *m1 = malloc((size_t)w * h * sizeof(float)), *m2 = malloc((size_t)w * h * sizeof(float));
    fill(a, w, h, 0.5f, 0.5f, 0.5f);
    fill(b, w, h, 0.5f, 0.5f, 0.5f);
    for (int c = 0; c < 3; c++)
        b[3 * (cy * w + cx) + c] = 0.8f;
    rep_flip_desc ldr = {REP_FLIP_LDR, 0, 0, 0};
    rep_flip_map(b, a, w, h, 3, &ldr, m1);
    rep_flip_map(a, b, w, h, 3, &ldr, m2);
    ck_assert_mem_eq(m1, m2, (size_t)w * h * sizeof(float));
    float centre = m1[cy * w + cx];
    ck_assert(centre > 0.05f);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float v = m1[y * w + x];
            ck_assert(v <= centre);
            if (abs(x - cx) > 10 || abs(y - cy) > 10)
                ck_assert_float_eq(v, 0.0f);
        }
    ck_assert(m1[cy * w + cx + 3] > 0); /* within reach */
    /* the whole image changed is more visible than one pixel */
    double uniform = remap_by_hand(fabs(grey_L(srgb_lin(0.5)) - grey_L(srgb_lin(0.8))));
    rep_flip_stats st;
    rep_flip_stats_of(m1, (size_t)w * h, &st);
    printf("flip: one pixel 0.5->0.8 in 31x31: centre %.6f, mean %.6f (uniform change %.6f)\n", centre, st.mean,
           uniform);
    ck_assert(st.mean < uniform);
    free(a);
    free(b);
    free(m1);
    free(m2);
}
END_TEST

/* The convolution sums each output's taps in order (0.0 + k0·p0, then + ki·pi) with repeated
 * edges, whatever the width (blocks of outputs and their tails, vector widths): bit for bit the
 * scalar loop below, in both directions; a reassociated sum (pairing the symmetric taps, say)
 * fails. */
START_TEST(convolution_is_the_ordered_tap_sum)
{
    const int ws[] = {1, 5, 16, 17, 37, 160}, r = 4;
    double taps[2 * 4 + 1];
    unsigned st = 12345;
    for (int i = 0; i <= 2 * r; i++) {
        st = st * 1103515245u + 12345u;
        taps[i] = (double)(st >> 8) / 16777216.0 - 0.3;
    }
    for (size_t t = 0; t < sizeof ws / sizeof ws[0]; t++) {
        int w = ws[t], h = 7;
        size_t n = (size_t)w * (size_t)h;
        double *in = malloc(n * sizeof *in), *out = malloc(n * sizeof *out), *ref = malloc(n * sizeof *ref);
        for (size_t p = 0; p < n; p++) {
            st = st * 1103515245u + 12345u;
            in[p] = (double)(st >> 8) / 65536.0 - 100.0;
        }
        for (int dir = 0; dir < 2; dir++) {
            for (int y = 0; y < h; y++)
                for (int x = 0; x < w; x++) {
                    double s = 0.0;
                    for (int i = 0; i <= 2 * r; i++) {
                        int xx = dir == 0 ? x + i - r : x, yy = dir == 1 ? y + i - r : y;
                        xx = xx < 0 ? 0 : xx >= w ? w - 1 : xx;
                        yy = yy < 0 ? 0 : yy >= h ? h - 1 : yy;
                        double v = taps[i] * in[(size_t)yy * (size_t)w + (size_t)xx];
                        s = i == 0 ? 0.0 + v : s + v;
                    }
                    ref[(size_t)y * (size_t)w + (size_t)x] = s;
                }
            rep_flip_convolve(in, out, w, h, taps, r, dir);
            ck_assert_msg(memcmp(out, ref, n * sizeof *out) == 0, "width %d, direction %d", w, dir);
        }
        free(in);
        free(out);
        free(ref);
    }
}
END_TEST

/* An HDR map's exposures run as OpenMP tasks when rep_flip_map is called inside a parallel
 * region (as replay does): the map is the same bits as the serial call's. */
START_TEST(hdr_map_same_inside_a_parallel_region)
{
    int w = 37, h = 29;
    size_t n = (size_t)w * (size_t)h;
    float *a = image(w, h), *b = image(w, h);
    unsigned st = 777;
    for (size_t i = 0; i < 3 * n; i++) {
        st = st * 1103515245u + 12345u;
        a[i] = (float)(st >> 8) / 2097152.0f; /* 0..8 */
        st = st * 1103515245u + 12345u;
        b[i] = a[i] * (0.75f + (float)(st >> 8) / 33554432.0f);
    }
    float *m1 = malloc(n * sizeof(float)), *m2 = malloc(n * sizeof(float));
    rep_flip_desc hdr = {REP_FLIP_HDR, 0, 0, 0};
    ck_assert_int_gt(rep_flip_exposures(&hdr), 2);
    rep_flip_map(a, b, w, h, 3, &hdr, m1);
#pragma omp parallel num_threads(3)
#pragma omp single
    rep_flip_map(a, b, w, h, 3, &hdr, m2);
    ck_assert_mem_eq(m1, m2, n * sizeof(float));
    rep_flip_stats s;
    rep_flip_stats_of(m1, n, &s);
    ck_assert(s.mean > 0.01);
    free(a);
    free(b);
    free(m1);
    free(m2);
}
END_TEST

static void edge_image(float *img, int w, int h, int at)
{
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++)
                img[3 * (y * w + x) + c] = x < at ? 0.2f : 0.8f;
}

/* A vertical edge moved by 1, 2, 4 pixels: error only in the columns the filters reach from
 * the two edge positions, and more of it the farther the edge moved. */
START_TEST(shift_grows_with_distance)
{
    int w = 48, h = 8;
    float *ref = image(w, h), *t = image(w, h), *map = malloc((size_t)w * h * sizeof(float));
    rep_flip_desc ldr = {REP_FLIP_LDR, 0, 0, 0};
    edge_image(ref, w, h, 20);
    double last = 0;
    const int shifts[3] = {1, 2, 4};
    for (int i = 0; i < 3; i++) {
        edge_image(t, w, h, 20 + shifts[i]);
        rep_flip_map(t, ref, w, h, 3, &ldr, map);
        rep_flip_stats st;
        rep_flip_stats_of(map, (size_t)w * h, &st);
        printf("flip: edge shifted by %d px: mean %.6f p99 %.6f max %.6f\n", shifts[i], st.mean, st.p99, st.max);
        ck_assert(st.mean > last);
        last = st.mean;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                if (x < 20 - 11 || x > 20 + shifts[i] + 10)
                    ck_assert_float_eq(map[y * w + x], 0.0f);
        ck_assert(st.max <= 1.0);
    }
    free(ref);
    free(t);
    free(map);
}
END_TEST

static void grating(float *img, int w, int h, double amplitude)
{
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++)
                img[3 * (y * w + x) + c] = (float)(0.5 + ((x / 4) % 2 ? amplitude : -amplitude));
}

/* A square-wave grating (period 8 px) around grey 0.5 with its contrast reduced by a factor k:
 * the error grows as k leaves 1, and is 0 at k = 1. Also for HDR-ꟻLIP on the same values taken
 * as radiance. */
START_TEST(contrast_change_is_monotone)
{
    int w = 32, h = 16;
    float *ref = image(w, h), *t = image(w, h);
    const double ks[5] = {1.0, 0.9, 0.75, 0.5, 0.25};
    rep_flip_desc descs[2] = {{REP_FLIP_LDR, 0, 0, 0}, {REP_FLIP_HDR, 0, -2.0, 2.0}};
    grating(ref, w, h, 0.3);
    for (int d = 0; d < 2; d++) {
        double last = -1;
        for (int i = 0; i < 5; i++) {
            grating(t, w, h, 0.3 * ks[i]);
            double m = mean_of(t, ref, w, h, &descs[d]);
            printf("flip: %s grating contrast x%.2f: mean %.6f\n", d ? "HDR" : "LDR", ks[i], m);
            if (i == 0)
                ck_assert(m == 0);
            else
                ck_assert(m > last);
            last = m;
        }
    }
    free(ref);
    free(t);
}
END_TEST

/* Percentiles by nearest rank over 1..100 (/100). */
START_TEST(stats_by_nearest_rank)
{
    float v[100];
    for (int i = 0; i < 100; i++)
        v[99 - i] = (float)(i + 1) / 100.0f; /* descending: the order must not matter */
    rep_flip_stats st;
    rep_flip_stats_of(v, 100, &st);
    ck_assert_double_eq_tol(st.mean, 0.505, 1e-6);
    ck_assert_double_eq_tol(st.p50, 0.50, 1e-6);
    ck_assert_double_eq_tol(st.p95, 0.95, 1e-6);
    ck_assert_double_eq_tol(st.p99, 0.99, 1e-6);
    ck_assert_double_eq_tol(st.max, 1.0, 1e-6);
}
END_TEST

/* rep_sort_floats leaves the array qsort leaves, bit for bit: by radix where every value is
 * finite and non-negative (duplicates, zeros, subnormals, the largest floats), by qsort where one
 * is negative, -0 or infinite. */
static int cmp_f(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

START_TEST(sort_is_qsorts_order)
{
    uint32_t seed = 7u;
    const float odd[] = {0.0f, -0.0f, -1.5f, INFINITY, 1e-45f, 3.4e38f};
    for (int trial = 0; trial < 40; trial++) {
        size_t n = (size_t)(1 + trial * 97);
        float *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
        ck_assert_ptr_nonnull(a);
        ck_assert_ptr_nonnull(b);
        for (size_t i = 0; i < n; i++) {
            seed = seed * 1664525u + 1013904223u;
            float v = (float)(seed >> 8) / (float)(1u << 24); /* [0, 1), many repeats below */
            a[i] = trial % 3 == 0 ? floorf(v * 8.0f) / 8.0f : v * (float)(1 + trial);
        }
        if (trial % 2) { /* one value from the odd ones at a varying place */
            seed = seed * 1664525u + 1013904223u;
            a[seed % n] = odd[(seed >> 8) % 6];
        }
        memcpy(b, a, n * sizeof *a);
        rep_sort_floats(a, n);
        qsort(b, n, sizeof *b, cmp_f);
        for (size_t i = 0; i < n; i++) /* bits: +0 and -0 compare equal */
            ck_assert_msg(memcmp(&a[i], &b[i], sizeof a[i]) == 0, "trial %d, n %zu: element %zu differs", trial,
                          n, i);
        free(a);
        free(b);
    }
}
END_TEST

START_TEST(kinds_and_heat_map)
{
    ck_assert_int_eq(rep_flip_kind_of("final.display"), REP_FLIP_LDR);
    ck_assert_int_eq(rep_flip_kind_of("composite.radiance"), REP_FLIP_HDR);
    ck_assert_int_eq(rep_flip_kind_of("gbuffer.normal"), REP_FLIP_NONE);
    unsigned char lo[3], hi[3], mid[3];
    rep_flip_heat_rgb(0, lo);
    rep_flip_heat_rgb(1, hi);
    rep_flip_heat_rgb(0.5, mid);
    ck_assert(lo[0] + lo[1] + lo[2] < 10);              /* black at 0 */
    ck_assert(hi[0] > 240 && hi[1] > 240);             /* pale yellow at 1 */
    ck_assert(mid[0] > mid[1] && mid[2] > mid[1]);     /* magenta-ish midway */
    /* one hot pixel survives a 4× reduction */
    float map[16 * 16] = {0};
    map[5 * 16 + 9] = 1.0f;
    int tw, th;
    unsigned char *px = rep_flip_heat(map, 16, 16, 4, &tw, &th);
    ck_assert_int_eq(tw, 4);
    ck_assert_int_eq(th, 4);
    ck_assert_int_eq(px[(1 * 4 + 2) * 3], hi[0]);
    ck_assert_int_eq(px[0], lo[0]);
    free(px);
}
END_TEST

static Suite *flip_suite(void)
{
    Suite *s = suite_create("flip");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, identical_images_give_zero);
    tcase_add_test(tc, uniform_images_match_hand_computation);
    tcase_add_test(tc, hdr_uniform_matches_hand_computation);
    tcase_add_test(tc, one_pixel_change);
    tcase_add_test(tc, convolution_is_the_ordered_tap_sum);
    tcase_add_test(tc, hdr_map_same_inside_a_parallel_region);
    tcase_add_test(tc, shift_grows_with_distance);
    tcase_add_test(tc, contrast_change_is_monotone);
    tcase_add_test(tc, stats_by_nearest_rank);
    tcase_add_test(tc, sort_is_qsorts_order);
    tcase_add_test(tc, kinds_and_heat_map);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(flip_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
