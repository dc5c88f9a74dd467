/* test_metrics.c — Check suite of the bench's error metrics (replay/compare/metrics.c) against values
 * computed by hand, and their refusal of NaN/Inf. */
#include "metrics.h"

#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define EPS REP_METRIC_EPSILON

/* 2×1 pixels, 3 channels. Differences: pixel 0 (1, 0, −2), pixel 1 (3, 0, 0); reference
 * values chosen so the relative terms are easy: ref pixel 0 (1, 0, 2), pixel 1 (0, 5, 1).
 *   rmse: R sqrt((1+9)/2) = sqrt5, G 0, B sqrt(4/2) = sqrt2 → (sqrt5 + sqrt2)/3
 *   mae:  R (1+3)/2 = 2, G 0, B 1 → 1
 *   max:  3
 *   rel:  R (1/(1+ε) + 9/ε)/2, G 0, B (4/(4+ε) + 0)/2 → mean over channels
 *   block (one 8×8 block holds both pixels): mean differences R 2, G 0, B −1 → RMSE over one
 *   block: (2 + 0 + 1)/3 = 1 */
START_TEST(hand_computed_two_pixels)
{
    const float ref[6] = {1, 0, 2, 0, 5, 1};
    const float test[6] = {2, 0, 0, 3, 5, 1};
    rep_metrics_err m;
    eng_error err;
    ck_assert_int_eq(rep_metric_compute(test, ref, 2, 1, 3, "t", &m, &err), ENG_OK);
    ck_assert_double_eq_tol(m.rmse, (sqrt(5.0) + sqrt(2.0)) / 3.0, 1e-12);
    ck_assert_double_eq_tol(m.mae, 1.0, 1e-12);
    ck_assert_double_eq_tol(m.max_abs, 3.0, 1e-12);
    double rel = ((1.0 / (1.0 + EPS) + 9.0 / EPS) / 2.0 + (4.0 / (4.0 + EPS)) / 2.0) / 3.0;
    ck_assert_double_eq_tol(m.rel_mse, rel, 1e-9 * rel);
    ck_assert_double_eq_tol(m.block_rmse, 1.0, 1e-12);
}
END_TEST

/* Identical images: every metric is exactly 0. */
START_TEST(identical_images_have_zero_error)
{
    float img[10 * 7 * 3];
    for (int i = 0; i < 10 * 7 * 3; i++)
        img[i] = (float)(i % 11) * 0.37f;
    rep_metrics_err m;
    eng_error err;
    ck_assert_int_eq(rep_metric_compute(img, img, 10, 7, 3, "t", &m, &err), ENG_OK);
    ck_assert(m.rmse == 0.0 && m.rel_mse == 0.0 && m.mae == 0.0 && m.max_abs == 0.0 && m.block_rmse == 0.0);
}
END_TEST

/* Zero-mean noise inside each 8×8 block (a checkerboard of ±a) cancels in the block metric
 * but not in RMSE; a constant bias b survives both. 16×8 one-channel image, two blocks. Partial
 * blocks: a 9×1 image is two blocks, of 8 and 1 pixels, each averaging what it has. */
START_TEST(block_metric_cancels_noise_not_bias)
{
    float ref[16 * 8], test[16 * 8];
    const float a = 0.5f, b = 0.25f;
    for (int y = 0; y < 8; y++)
        for (int x = 0; x < 16; x++) {
            ref[y * 16 + x] = 1.0f;
            test[y * 16 + x] = 1.0f + (((x + y) & 1) ? a : -a);
        }
    rep_metrics_err m;
    eng_error err;
    ck_assert_int_eq(rep_metric_compute(test, ref, 16, 8, 1, "t", &m, &err), ENG_OK);
    ck_assert_double_eq_tol(m.rmse, a, 1e-12);
    ck_assert_double_eq_tol(m.block_rmse, 0.0, 1e-12);
    for (int i = 0; i < 16 * 8; i++)
        test[i] += b;
    ck_assert_int_eq(rep_metric_compute(test, ref, 16, 8, 1, "t", &m, &err), ENG_OK);
    ck_assert_double_eq_tol(m.rmse, sqrt(a * a + b * b), 1e-6);
    ck_assert_double_eq_tol(m.block_rmse, b, 1e-7);

    /* 9×1: block 0 = pixels 0..7 with difference 1 each, block 1 = pixel 8 with difference 4:
     * block means 1 and 4 → sqrt((1 + 16)/2). */
    float r9[9] = {0}, t9[9] = {1, 1, 1, 1, 1, 1, 1, 1, 4};
    ck_assert_int_eq(rep_metric_compute(t9, r9, 9, 1, 1, "t", &m, &err), ENG_OK);
    ck_assert_double_eq_tol(m.block_rmse, sqrt(17.0 / 2.0), 1e-12);
    ck_assert_double_eq_tol(m.rmse, sqrt((8.0 + 16.0) / 9.0), 1e-12);
}
END_TEST

/* NaN or Inf in either image is an error, whichever image and wherever. */
START_TEST(nonfinite_is_an_error)
{
    float ref[4 * 3] = {0}, test[4 * 3] = {0};
    rep_metrics_err m;
    eng_error err;
    test[7] = NAN;
    ck_assert_int_eq(rep_metric_compute(test, ref, 2, 2, 3, "frame 0 x", &m, &err), ENG_ERR_INVALID);
    ck_assert(strstr(err.msg, "frame 0 x") != NULL);
    test[7] = 0.0f;
    ref[11] = INFINITY;
    ck_assert_int_eq(rep_metric_compute(test, ref, 2, 2, 3, "x", &m, &err), ENG_ERR_INVALID);
    ref[11] = -INFINITY;
    ck_assert_int_eq(rep_metric_compute(test, ref, 2, 2, 3, "x", &m, &err), ENG_ERR_INVALID);
    ref[11] = 0.0f;
    ck_assert_int_eq(rep_metric_compute(test, ref, 2, 2, 3, "x", &m, &err), ENG_OK);
    ck_assert_int_eq(rep_metric_compute(test, ref, 0, 2, 3, "x", &m, &err), ENG_ERR_INVALID);
}
END_TEST

static Suite *metrics_suite(void)
{
    Suite *s = suite_create("metrics");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, hand_computed_two_pixels);
    tcase_add_test(tc, identical_images_have_zero_error);
    tcase_add_test(tc, block_metric_cancels_noise_not_bias);
    tcase_add_test(tc, nonfinite_is_an_error);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(metrics_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
