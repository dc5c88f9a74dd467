/* test_exposure.c — Check suite for `"exposure": "auto"`: the key value of engine/core/exposure.c
 * (eng_exposure_key) on images with known answers — a geometric, not arithmetic, mean of Rec. 709
 * luminance; background (coverage 0), black, NaN and ±Inf pixels left out; an all-black frame
 * 0 stops; the clamp — and the setting's word in the sequence parser and the settings table. */
#include "eng_core.h"
#include "seq.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* n pixels of grey g (R = G = B: luminance g). */
static float *grey(size_t n, float g)
{
    float *p = malloc(3 * n * sizeof *p);
    ck_assert_ptr_nonnull(p);
    for (size_t i = 0; i < 3 * n; i++)
        p[i] = g;
    return p;
}

static void set_px(float *rgb, size_t i, float r, float g, float b)
{
    rgb[3 * i] = r;
    rgb[3 * i + 1] = g;
    rgb[3 * i + 2] = b;
}

START_TEST(middle_grey_is_zero_stops)
{
    float *p = grey(64, 0.18f);
    eng_exposure_key_info k;
    eng_exposure_key(p, NULL, 64, &k);
    ck_assert_uint_eq(k.counted, 64);
    ck_assert_uint_eq(k.nonfinite, 0);
    ck_assert_double_eq_tol(k.log_average, 0.18 + ENG_EXPOSURE_DELTA, 1e-7);
    ck_assert_float_eq_tol(k.stops, 0.0f, 1e-4f);
    free(p);
}
END_TEST

/* Half the pixels at luminance 1, half at 4: the log average is their geometric mean 2
 * (the arithmetic mean, 2.5, would give −3.796 stops), so log2(0.18 / 2) = −3.4739 stops. */
START_TEST(geometric_mean)
{
    float *p = grey(100, 1.0f);
    for (size_t i = 50; i < 100; i++)
        set_px(p, i, 4.0f, 4.0f, 4.0f);
    eng_exposure_key_info k;
    eng_exposure_key(p, NULL, 100, &k);
    ck_assert_uint_eq(k.counted, 100);
    ck_assert_double_eq_tol(k.log_average, 2.0, 1e-5);
    ck_assert_float_eq_tol(k.stops, (float)log2(0.09), 1e-5f);
    printf("exposure: 50 px at 1, 50 at 4: L = %.6f, %.5f stops (by hand 2, %.5f)\n", k.log_average,
           (double)k.stops, log2(0.09));
    free(p);
}
END_TEST

/* Rec. 709 weights: pure red 1 has luminance 0.2126, pure green 0.7152, pure blue 0.0722. */
START_TEST(rec709_weights)
{
    const float c[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    const double y[3] = {0.2126, 0.7152, 0.0722};
    for (int i = 0; i < 3; i++) {
        float px[3] = {c[i][0], c[i][1], c[i][2]};
        eng_exposure_key_info k;
        eng_exposure_key(px, NULL, 1, &k);
        ck_assert_double_eq_tol(k.log_average, y[i] + ENG_EXPOSURE_DELTA, 1e-7);
        ck_assert_float_eq_tol(k.stops, (float)log2(0.18 / (y[i] + ENG_EXPOSURE_DELTA)), 1e-5f);
    }
}
END_TEST

/* Background pixels (coverage 0), even very bright ones, covered black pixels, NaN and ±Inf
 * pixels are all left out: the answer is that of the lit pixels alone. */
START_TEST(background_black_and_nonfinite_left_out)
{
    const size_t n = 40;
    float *p = grey(n, 0.5f), cov[40];
    for (size_t i = 0; i < n; i++)
        cov[i] = 1.0f;
    eng_exposure_key_info want;
    eng_exposure_key(p, cov, 20, &want); /* the first 20 pixels: grey 0.5 */
    for (size_t i = 20; i < 30; i++) { /* background, bright (a visible emitter behind nothing) */
        set_px(p, i, 1000.0f, 1000.0f, 1000.0f);
        cov[i] = 0.0f;
    }
    for (size_t i = 30; i < 35; i++) /* covered but black: in shadow */
        set_px(p, i, 0.0f, 0.0f, 0.0f);
    set_px(p, 35, NAN, 0.5f, 0.5f);
    set_px(p, 36, 0.5f, INFINITY, 0.5f);
    set_px(p, 37, 0.5f, 0.5f, -INFINITY);
    set_px(p, 38, -1.0f, -1.0f, -1.0f); /* negative luminance: not light */
    set_px(p, 39, 0.5f, 0.5f, 0.5f);    /* one more lit pixel, same grey */
    eng_exposure_key_info k;
    eng_exposure_key(p, cov, n, &k);
    ck_assert_uint_eq(k.counted, 21);
    ck_assert_uint_eq(k.nonfinite, 3);
    ck_assert(k.stops == want.stops);
    ck_assert_float_eq_tol(k.stops, (float)log2(0.18 / (0.5 + ENG_EXPOSURE_DELTA)), 1e-5f);
    /* Without the mask, the background's 1000s count and the exposure drops by 3.5 stops. */
    eng_exposure_key_info all;
    eng_exposure_key(p, NULL, n, &all);
    ck_assert_uint_eq(all.counted, 31);
    ck_assert_float_lt(all.stops, k.stops - 3.0f); /* 21 px at 0.5, 10 at 1000: −5.01 stops, not −1.47 */
    free(p);
}
END_TEST

/* Nothing lit: 0 stops, nothing counted (the caller warns). */
START_TEST(all_black_falls_back_to_zero)
{
    float *p = grey(16, 0.0f), cov[16] = {0};
    eng_exposure_key_info k;
    eng_exposure_key(p, NULL, 16, &k);
    ck_assert_uint_eq(k.counted, 0);
    ck_assert(k.stops == 0.0f && k.log_average == 0.0);
    set_px(p, 3, 1.0f, 1.0f, 1.0f); /* lit, but background */
    eng_exposure_key(p, cov, 16, &k);
    ck_assert_uint_eq(k.counted, 0);
    ck_assert(k.stops == 0.0f);
    eng_exposure_key(p, NULL, 0, &k);
    ck_assert_uint_eq(k.counted, 0);
    ck_assert(k.stops == 0.0f);
    free(p);
}
END_TEST

/* δ bounds the stops of a nearly black frame; the setting's range bounds those of a blinding one. */
START_TEST(bounds)
{
    float dim[3] = {1e-30f, 1e-30f, 1e-30f}, hot[3] = {3e38f, 3e38f, 3e38f};
    eng_exposure_key_info k;
    eng_exposure_key(dim, NULL, 1, &k);
    ck_assert_uint_eq(k.counted, 1);
    ck_assert_float_eq_tol(k.stops, (float)log2(0.18 / ENG_EXPOSURE_DELTA), 1e-4f);
    eng_exposure_key(hot, NULL, 1, &k);
    ck_assert(k.stops == (float)-ENG_EXPOSURE_MAX);
}
END_TEST

static eng_result parse_settings(const char *settings, seq_sequence *q, eng_error *err)
{
    char json[512];
    snprintf(json, sizeof json,
             "{\"scene\": \"s.gltf\", \"frames\": 1, \"fps\": 1, \"resolution\": [8, 8], \"settings\": %s}", settings);
    memset(q, 0, sizeof *q);
    return seq_parse("/d/seq.json", json, strlen(json), q, err);
}

START_TEST(setting_word)
{
    seq_sequence *q = malloc(sizeof *q);
    ck_assert_ptr_nonnull(q);
    eng_error err = {{0}};
    ck_assert_int_eq(parse_settings("{\"exposure\": \"auto\"}", q, &err), ENG_OK);
    ck_assert_int_eq(q->settings.exposure_auto, 1);
    ck_assert(q->settings.exposure == 0.0f); /* frame 0 is metered at 0 stops */
    const eng_setting *d = eng_setting_find("exposure");
    ck_assert_ptr_nonnull(d);
    ck_assert_str_eq(d->word, "auto");
    char text[32];
    eng_setting_format(d, &q->settings, text, sizeof text);
    ck_assert_str_eq(text, "auto");
    ck_assert_int_eq(parse_settings("{\"exposure\": -2.5}", q, &err), ENG_OK);
    ck_assert_int_eq(q->settings.exposure_auto, 0);
    ck_assert(q->settings.exposure == -2.5f);
    eng_setting_format(d, &q->settings, text, sizeof text);
    ck_assert_str_eq(text, "-2.5");
    /* A number after the word (a preset's "auto" under a sequence's number) clears it. */
    d->word_set(&q->settings, 1);
    ck_assert_int_eq(parse_settings("{\"exposure\": 1}", q, &err), ENG_OK);
    ck_assert_int_eq(q->settings.exposure_auto, 0);
    /* Any other string, or a number out of range, is one line naming the key. */
    ck_assert_int_eq(parse_settings("{\"exposure\": \"Auto\"}", q, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "settings.exposure: expected a number or \"auto\"") != NULL, "%s", err.msg);
    ck_assert_int_eq(parse_settings("{\"exposure\": 101}", q, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "settings.exposure") != NULL, "%s", err.msg);
    /* Other float settings take no word. */
    ck_assert_ptr_null(eng_setting_find("shadow_bias")->word);
    ck_assert_int_eq(parse_settings("{\"shadow_bias\": \"auto\"}", q, &err), ENG_ERR_INVALID);
    free(q);
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("exposure");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, middle_grey_is_zero_stops);
    tcase_add_test(tc, geometric_mean);
    tcase_add_test(tc, rec709_weights);
    tcase_add_test(tc, background_black_and_nonfinite_left_out);
    tcase_add_test(tc, all_black_falls_back_to_zero);
    tcase_add_test(tc, bounds);
    tcase_add_test(tc, setting_word);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
