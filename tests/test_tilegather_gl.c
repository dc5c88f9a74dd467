/* test_tilegather_gl.c — Check suite of the tile gather evaluated in a GL compute shader
 * (engine/indirect/ind_tilegather_gl.c, shaders/tile_gather.comp.glsl; 002_… §6.3). It walks the same
 * tile lists as the CPU tile gather (ind_tilelists.c) in the same order with the same kernel and
 * BSDF, so it must equal the CPU tile gather — itself bit-identical to the k-d gather — up to
 * llvmpipe's rounding: every value within 1e-5 relative where not tiny, the photon counts
 * equal except for a few pixels at a kernel's edge; the same list lengths (gather.tile_count)
 * exactly; on the Cornell box, on metal (the GGX term), in the filters' irradiance mode (three
 * buffers) and with the camera inside kernels; and the same bits for 1 and 2 threads. */
#include "eng.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tile_test_util.h"

/* Every buffer of the CPU run b (but the photon map) is in the GL run a with the same size;
 * "*.count" buffers (and A of gather.indirect / gather.irradiance: the count) may differ at
 * no more than max_count_px pixels, by one photon each; every other value is within 1e-5
 * relative of the CPU's where that is above 1e-6 of the buffer's peak (below: within 1e-11 of
 * the peak). */
static void assert_close(const keeper *a, const keeper *b, const char *what, int max_count_px)
{
    ck_assert_int_ge(b->count, 1);
    for (int i = 0; i < b->count; i++) {
        const kept *y = &b->bufs[i], *x = find(a, y->name);
        if (!strcmp(y->name, "photons.map"))
            continue;
        ck_assert_msg(x != NULL, "%s: %s missing", what, y->name);
        ck_assert_msg(x->w == y->w && x->h == y->h && x->n == y->n, "%s: %s size", what, y->name);
        const size_t px = (size_t)x->w * x->h, n = (size_t)x->n;
        const int whole_count = strstr(y->name, ".count") != NULL || !strcmp(y->name, "gather.tile_count");
        const int alpha_count = !strcmp(y->name, "gather.indirect") || !strcmp(y->name, "gather.irradiance");
        double peak = 0.0;
        for (size_t j = 0; j < px * n; j++)
            peak = fmax(peak, fabs(y->data[j]));
        size_t count_px = 0, bad = 0, first = 0;
        double worst = 0.0;
        for (size_t p = 0; p < px; p++) {
            int count_differs = 0;
            for (size_t c = 0; c < n; c++) {
                const size_t j = p * n + c;
                const double u = x->data[j], v = y->data[j];
                if (whole_count || (alpha_count && c == 3)) {
                    if (u != v) {
                        ck_assert_msg(fabs(u - v) <= 1.0, "%s: %s[%zu]: count %g vs %g", what, y->name, j, u, v);
                        count_differs = 1;
                    }
                    continue;
                }
                const double m = fmax(fabs(u), fabs(v)), d = fabs(u - v);
                if (m > 1e-6 * peak) {
                    worst = fmax(worst, d / m);
                    if (d > 1e-5 * m && !bad++)
                        first = j;
                } else if (d > 1e-11 * peak && !bad++)
                    first = j;
            }
            count_px += (size_t)count_differs;
        }
        ck_assert_msg(bad == 0, "%s: %s: %zu values differ, first at %zu: %.9g vs %.9g (CPU)", what, y->name, bad,
                      first, x->data[first], y->data[first]);
        ck_assert_msg(count_px <= (size_t)max_count_px, "%s: %s: counts differ at %zu pixels", what, y->name,
                      count_px);
        if (!strcmp(y->name, "gather.tile_count"))
            ck_assert_int_eq(count_px, 0);
        fprintf(stderr, "  %s %s: max rel %.3g, count differs at %zu px, peak %.4g\n", what, y->name, worst, count_px,
                peak);
    }
}

/* The sum of a buffer's values (> 0 proves the image is not black). */
static double total(const kept *k)
{
    double s = 0.0;
    for (size_t j = 0; j < (size_t)k->w * k->h * k->n; j++)
        s += k->data[j];
    return s;
}

/* The GL tile gather against the CPU tile gather with the same extra settings; also checks
 * that the buffers of the mode were announced and `main` is not black. */
static void compare(const char *rel, const char *extra, int frame, const char *main_buffer, int buffers)
{
    static keeper kg, kc;
    keeper_clear(&kg); /* a failed check leaves the last test's buffers (the suites run unforked) */
    keeper_clear(&kc);
    char st[512];
    snprintf(st, sizeof st, "\"indirect\": \"tile-gather-gl\"%s%s", *extra ? ", " : "", extra);
    render(rel, st, frame, &kg);
    snprintf(st, sizeof st, "\"indirect\": \"tile-gather\"%s%s", *extra ? ", " : "", extra);
    render(rel, st, frame, &kc);
    ck_assert_msg(find(&kg, main_buffer) && total(find(&kg, main_buffer)) > 0.0, "%s: %s is black", rel, main_buffer);
    int gather = 0;
    for (int i = 0; i < kg.count; i++)
        gather += !strncmp(kg.bufs[i].name, "gather.", 7);
    ck_assert_int_eq(gather, buffers); /* gather.* plus tile_count */
    assert_close(&kg, &kc, rel, 8);
    keeper_clear(&kg);
    keeper_clear(&kc);
}

START_TEST(equals_cpu_tile_gather_on_the_cornell_box)
{
    compare("scenes/cornell-box/cornell-box-ci.json", "", 1, "indirect.radiance", 3);
}
END_TEST

/* The ring is metallic: the GGX term of photon_glossy. */
START_TEST(equals_cpu_tile_gather_on_metal)
{
    compare("scenes/caustic-ring/caustic-ring-ci.json", "", 1, "indirect.radiance", 3);
}
END_TEST

/* Irradiance, count and the glossy part for the filters, at half resolution. */
START_TEST(equals_cpu_tile_gather_in_irradiance_mode)
{
    compare("scenes/caustic-ring/caustic-ring-ci.json", "\"splat_subsample\": 2", 1, "gather.glossy", 4);
}
END_TEST

/* The camera inside kernels: whole-screen rectangles, long lists (this sequence captures
 * indirect.radiance but no gather.* buffers). */
START_TEST(equals_cpu_tile_gather_at_the_near_plane)
{
    compare("scenes/stress/near-plane.json", "", 5, "indirect.radiance", 0);
}
END_TEST

START_TEST(bit_identical_for_threads_1_and_2)
{
    static keeper a, b;
    const char *rel = "scenes/cornell-box/cornell-box-ci.json";
    keeper_clear(&a);
    keeper_clear(&b);
    render(rel, "\"indirect\": \"tile-gather-gl\", \"threads\": 2", 3, &a);
    render(rel, "\"indirect\": \"tile-gather-gl\", \"threads\": 1", 3, &b);
    ck_assert_int_ge(b.count, 4);
    for (int i = 0; i < b.count; i++) {
        const kept *y = &b.bufs[i], *x = find(&a, y->name);
        ck_assert_msg(x && x->w == y->w && x->h == y->h && x->n == y->n, "%s", y->name);
        ck_assert_msg(!memcmp(x->data, y->data, (size_t)x->w * x->h * x->n * sizeof(float)), "%s differs",
                      y->name);
    }
    keeper_clear(&a);
    keeper_clear(&b);
}
END_TEST

static Suite *tilegather_gl_suite(void)
{
    Suite *s = suite_create("tilegather_gl");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 600);
    tcase_add_test(tc, equals_cpu_tile_gather_on_the_cornell_box);
    tcase_add_test(tc, equals_cpu_tile_gather_on_metal);
    tcase_add_test(tc, equals_cpu_tile_gather_in_irradiance_mode);
    tcase_add_test(tc, equals_cpu_tile_gather_at_the_near_plane);
    tcase_add_test(tc, bit_identical_for_threads_1_and_2);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(tilegather_gl_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
