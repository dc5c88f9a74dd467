/* test_renderer.c — goldens per renderer (replay/report/renderer.c, tolerance.c's "cross_renderer"):
 * a run from another GL renderer than its golden is compared under the golden's separate
 * cross-renderer set, or the built-in one where the file has none; the same renderer (or a
 * manifest that names none) keeps the golden's own tolerances; the section is validated as
 * strictly as the rest, and the report says "different renderer". */
#include "rep_report.h"

#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static rep_tolerances *parse(const char *json, eng_result expect, eng_error *err)
{
    rep_tolerances *t = NULL;
    eng_result r = rep_tol_parse("tol.json", json, strlen(json), &t, err);
    ck_assert_msg(r == expect, "got %s (%s)", eng_result_name(r), err->msg);
    return t;
}

START_TEST(cross_section_is_a_separate_set)
{
    eng_error err = {{0}};
    rep_tolerances *t = parse("{\"default\": {\"fail\": 1e-5},"
                              " \"buffers\": [{\"match\": \"gbuffer.*\", \"exact\": true}],"
                              " \"cross_renderer\": {\"default\": {\"fail\": 0.05, \"failpercent\": 2},"
                              "   \"buffers\": [{\"match\": \"indirect.*\", \"rmse_fail\": 0.01}]}}",
                              ENG_OK, &err);
    rep_tol tol;
    ck_assert_str_eq(rep_tol_lookup(t, "gbuffer.albedo", &tol), "gbuffer.*");
    ck_assert_int_eq(tol.exact, 1);
    ck_assert_ptr_nonnull(t->cross);
    ck_assert_str_eq(t->cross->path, "tol.json#cross_renderer");
    ck_assert_str_eq(rep_tol_lookup(t->cross, "gbuffer.albedo", &tol), "default");
    ck_assert_int_eq(tol.exact, 0); /* the regular rules do not leak into the cross set */
    ck_assert_double_eq(tol.fail, 0.05);
    ck_assert_double_eq(tol.failpercent, 2);
    ck_assert_double_eq(tol.hardfail, 1e-2); /* keys it leaves out: the built-in defaults */
    ck_assert_str_eq(rep_tol_lookup(t->cross, "indirect.radiance", &tol), "indirect.*");
    ck_assert_double_eq(tol.rmse_fail, 0.01);
    ck_assert_double_eq(tol.fail, 0.05);
    rep_tol_free(t);
}
END_TEST

START_TEST(no_section_gives_builtin_cross_set)
{
    eng_error err = {{0}};
    rep_tolerances *t = parse("{\"default\": {\"fail\": 1e-5}}", ENG_OK, &err);
    ck_assert_ptr_nonnull(t->cross);
    ck_assert_ptr_null(t->cross->path);
    rep_tol want, tol;
    rep_tol_cross_builtin(&want);
    rep_tol_lookup(t->cross, "composite.radiance", &tol);
    ck_assert_double_eq(tol.fail, want.fail);
    ck_assert_double_eq(tol.failpercent, want.failpercent);
    ck_assert_double_eq(tol.rmse_fail, want.rmse_fail);
    ck_assert(isinf(tol.hardfail));
    ck_assert(tol.fail > 1e-4 && tol.failpercent > 0); /* looser than the built-in defaults */
    rep_tol_free(t);
    /* A golden without tolerances.json gets the built-in cross set too. */
    ck_assert_int_eq(rep_tol_load("/nonexistent/tolerances.json", 1, &t, &err), ENG_OK);
    ck_assert_ptr_nonnull(t->cross);
    rep_tol_free(t);
}
END_TEST

START_TEST(cross_section_validated)
{
    static const char *const bad[] = {
        "{\"cross_renderer\": 3}",
        "{\"cross_renderer\": {\"defualt\": {}}}",
        "{\"cross_renderer\": {\"default\": {\"fail\": -1}}}",
        "{\"cross_renderer\": {\"cross_renderer\": {}}}",
        "{\"cross_renderer\": {\"buffers\": [{\"fail\": 1}]}}",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        eng_error err = {{0}};
        rep_tolerances *t = parse(bad[i], ENG_ERR_INVALID, &err);
        ck_assert_ptr_null(t);
        ck_assert_msg(strstr(err.msg, "tol.json#cross_renderer") != NULL, "%s", err.msg);
    }
}
END_TEST

START_TEST(renderer_picks_the_set)
{
    eng_error err = {{0}};
    rep_tolerances *t = parse("{\"cross_renderer\": {\"default\": {\"fail\": 0.5}}}", ENG_OK, &err);
    rep_run run = {0}, gold = {0};
    char llvm[] = "llvmpipe (LLVM 15.0.6, 128 bits)", gpu[] = "NVIDIA H200/PCIe/SSE2";
    struct {
        char *run, *gold;
        int differs;
    } cases[] = {{llvm, llvm, 0}, {gpu, llvm, 1}, {llvm, gpu, 1}, {NULL, llvm, 0}, {gpu, NULL, 0}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        rep_report r;
        memset(&r, 0, sizeof r);
        r.golden_dir = "golden/x";
        run.gl_renderer = cases[i].run;
        gold.gl_renderer = cases[i].gold;
        const rep_tolerances *use = rep_renderer_tolerances(&r, &run, &gold, t);
        ck_assert_int_eq(r.renderer_differs, cases[i].differs);
        ck_assert_ptr_eq(use, cases[i].differs ? t->cross : t);
        char *note = rep_renderer_note(&r);
        if (cases[i].differs) {
            ck_assert_msg(note && strstr(note, "different renderer") && strstr(note, gpu), "%s", note);
            char *json = rep_report_json(&r);
            ck_assert_msg(strstr(json, "\"different\":\ttrue") != NULL, "%s", json);
            free(json);
        } else {
            ck_assert_ptr_null(note);
        }
        free(note);
        rep_report_free(&r);
    }
    rep_tol_free(t);
}
END_TEST

static Suite *renderer_suite(void)
{
    Suite *s = suite_create("renderer");
    TCase *t = tcase_create("unit");
    tcase_add_test(t, cross_section_is_a_separate_set);
    tcase_add_test(t, no_section_gives_builtin_cross_set);
    tcase_add_test(t, cross_section_validated);
    tcase_add_test(t, renderer_picks_the_set);
    suite_add_tcase(s, t);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(renderer_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
