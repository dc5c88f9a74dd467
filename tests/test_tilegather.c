/* test_tilegather.c — Check suite of the tile-based gather (engine/indirect/ind_tilegather.c, 002_…
 * §6.3): it must sum exactly the photons the k-d gather sums, in the same order, so the two
 * agree bit for bit — on the Cornell box, on metallic surfaces (the scalar path of the SIMD
 * loop), in the reconstruction filters' irradiance mode, with the camera inside photon
 * kernels (the near-plane stress sequence: rectangles behind the eye), for any thread count,
 * and with the SIMD evaluation switched off. gather.tile_count is announced per tile. */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include "eng.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tile_test_util.h"

/* Every buffer of b is in a with the same size and bits (a may have more: tile_count). */
static void assert_same(const keeper *a, const keeper *b, const char *what)
{
    ck_assert_int_ge(b->count, 1);
    for (int i = 0; i < b->count; i++) {
        const kept *y = &b->bufs[i], *x = find(a, y->name);
        ck_assert_msg(x != NULL, "%s: %s missing", what, y->name);
        ck_assert_msg(x->w == y->w && x->h == y->h && x->n == y->n, "%s: %s size", what, y->name);
        size_t n = (size_t)x->w * x->h * x->n, differ = 0, first = 0;
        for (size_t j = 0; j < n; j++)
            if (memcmp(&x->data[j], &y->data[j], sizeof(float)) && !differ++)
                first = j;
        ck_assert_msg(differ == 0, "%s: %s: %zu values differ, first at %zu: %.9g vs %.9g", what, y->name, differ,
                      first, differ ? x->data[first] : 0.0, differ ? y->data[first] : 0.0);
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

static void compare(const char *rel, const char *extra, int frame, const char *irr_or_ind)
{
    static keeper kt, kk;
    keeper_clear(&kt); /* a failed check leaves the last test's buffers (the suites run unforked) */
    keeper_clear(&kk);
    char st[512];
    snprintf(st, sizeof st, "\"indirect\": \"tile-gather\"%s%s", *extra ? ", " : "", extra);
    render(rel, st, frame, &kt);
    snprintf(st, sizeof st, "\"indirect\": \"kd-gather\"%s%s", *extra ? ", " : "", extra);
    render(rel, st, frame, &kk);
    char name[64];
    snprintf(name, sizeof name, "%s", strcmp(irr_or_ind, "indirect") ? "gather.irradiance" : "indirect.radiance");
    ck_assert_msg(find(&kk, name) && total(find(&kk, name)) > 0.0, "%s: %s is black", rel, name);
    assert_same(&kt, &kk, rel);
    keeper_clear(&kt);
    keeper_clear(&kk);
}

START_TEST(equals_kd_gather_on_the_cornell_box)
{
    compare("scenes/cornell-box/cornell-box-ci.json", "", 1, "indirect");
}
END_TEST

/* The ring is metallic: those pixels take the scalar path beside the SIMD lanes. */
START_TEST(equals_kd_gather_on_metal)
{
    compare("scenes/caustic-ring/caustic-ring-ci.json", "", 1, "indirect");
}
END_TEST

/* Irradiance (Σ Φκ) and the glossy part for the filters, at half resolution. */
START_TEST(equals_kd_gather_in_irradiance_mode)
{
    compare("scenes/caustic-ring/caustic-ring-ci.json", "\"splat_subsample\": 2", 1, "irradiance");
}
END_TEST

/* The camera 1.5 cm from the back wall: kernels reach behind the eye (whole-screen rectangles)
 * and cover many pixels each. */
START_TEST(equals_kd_gather_at_the_near_plane)
{
    compare("scenes/stress/near-plane.json", "", 5, "indirect");
}
END_TEST

START_TEST(bit_identical_for_any_thread_count_and_without_simd)
{
    static keeper a, b;
    const char *rel = "scenes/cornell-box/cornell-box-ci.json";
    render(rel, "\"indirect\": \"tile-gather\", \"threads\": 2", 3, &a);
    const int threads[] = {1, 3, 5};
    for (int i = 0; i < 3; i++) {
        char st[128];
        snprintf(st, sizeof st, "\"indirect\": \"tile-gather\", \"threads\": %d", threads[i]);
        render(rel, st, 3, &b);
        assert_same(&a, &b, st);
        keeper_clear(&b);
    }
    setenv("ISPM_TILEGATHER_SCALAR", "1", 1);
    render(rel, "\"indirect\": \"tile-gather\", \"threads\": 2", 3, &b);
    unsetenv("ISPM_TILEGATHER_SCALAR");
    assert_same(&a, &b, "scalar evaluation");
    keeper_clear(&a);
    keeper_clear(&b);
}
END_TEST

/* One value per 16×16 tile: the length of its photon list, whole numbers, all photons placed
 * somewhere, more entries than photons (kernels straddle tiles). */
START_TEST(tile_count_per_tile)
{
    static keeper k;
    render("scenes/cornell-box/cornell-box-ci.json", "\"indirect\": \"tile-gather\"", 0, &k);
    const kept *tc = find(&k, "gather.tile_count"), *pm = find(&k, "photons.map");
    ck_assert(tc && pm);
    ck_assert_int_eq(tc->w, 10); /* 160 / 16 */
    ck_assert_int_eq(tc->h, 10);
    ck_assert_int_eq(tc->n, 1);
    size_t photons = 0;
    for (size_t i = 0; i < (size_t)pm->w * pm->h; i++)
        photons += pm->data[14 * i + 13] != 0.0f;
    double sum = 0.0;
    for (int i = 0; i < tc->w * tc->h; i++) {
        ck_assert(tc->data[i] >= 0.0f && tc->data[i] == floorf(tc->data[i]));
        sum += tc->data[i];
    }
    ck_assert_msg(sum > (double)photons, "%g list entries for %zu photons", sum, photons);
    keeper_clear(&k);
}
END_TEST

static Suite *tilegather_suite(void)
{
    Suite *s = suite_create("tilegather");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 600);
    tcase_add_test(tc, equals_kd_gather_on_the_cornell_box);
    tcase_add_test(tc, equals_kd_gather_on_metal);
    tcase_add_test(tc, equals_kd_gather_in_irradiance_mode);
    tcase_add_test(tc, equals_kd_gather_at_the_near_plane);
    tcase_add_test(tc, bit_identical_for_any_thread_count_and_without_simd);
    tcase_add_test(tc, tile_count_per_tile);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(tilegather_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
