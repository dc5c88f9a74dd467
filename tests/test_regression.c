/* test_regression.c — the daily regression suite's tools: local block gates (compare.c,
 * tolerance.c), expectations (compare/expect.c, report/expect_report.c), the trend over
 * replayed runs (report/trend.c) and suggested limits (suggest.c). Blocks are worked by hand on
 * small buffers: alignment to (0, 0), partial edge blocks averaged over their own pixels, the
 * relative measure's floor. */
#define _POSIX_C_SOURCE 200809L
#include "rep_regress.h"
#include "rep_report.h"
#include "rep_trend.h"

#include <check.h>
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char *const RG[2] = {"R", "G"};
static const char *const Y[1] = {"Y"};

static eng_buffer buf(const char *name, int w, int h, int nch, const char *const *ch, float *data)
{
    return (eng_buffer){name, w, h, nch, ch, data};
}

static float *filled(int n, float v)
{
    float *p = malloc((size_t)n * sizeof *p);
    for (int i = 0; i < n; i++)
        p[i] = v;
    return p;
}

/* Loose per-pixel thresholds: only the block gates decide. */
static rep_tol loose(void)
{
    rep_tol t;
    rep_tol_builtin(&t);
    t.fail = t.warn = t.hardfail = 10;
    t.failpercent = t.warnpercent = 100;
    return t;
}

START_TEST(block_partial_edge)
{
    /* 20×12, two channels: blocks at x 0, 8, 16 (the last 4 wide) and y 0, 8 (the last 4 high). */
    float *g = filled(20 * 12 * 2, 0.5f), *a = filled(20 * 12 * 2, 0.5f);
    a[(9 * 20 + 17) * 2 + 0] = 1.3f; /* one value of pixel (17, 9): |Δ| 0.8 */
    eng_buffer run = buf("final.display", 20, 12, 2, RG, a), gold = buf("final.display", 20, 12, 2, RG, g);
    rep_tol t = loose();
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&run, &gold, &t, &m), REP_V_WITHIN);
    ck_assert_int_eq(m.block_size, 8);
    ck_assert_int_eq(m.block_abs.x, 16);
    ck_assert_int_eq(m.block_abs.y, 8);
    ck_assert_int_eq(m.block_abs.w, 4);
    ck_assert_int_eq(m.block_abs.h, 4);
    ck_assert_double_eq_tol(m.block_abs.value, 0.8 / 32, 1e-6); /* 4×4 pixels × 2 channels */
    ck_assert_double_eq_tol(m.block_rel.value, (0.8 / 32) / 0.5, 1e-6);
    t.block_fail = 0.02;
    ck_assert_int_eq(rep_compare(&run, &gold, &t, &m), REP_V_FAIL);
    ck_assert_uint_eq(m.fail_why, REP_WHY_BLOCK);
    t.block_fail = 0.03;
    ck_assert_int_eq(rep_compare(&run, &gold, &t, &m), REP_V_WITHIN);
    t.block_failrelative = 0.04;
    ck_assert_int_eq(rep_compare(&run, &gold, &t, &m), REP_V_FAIL);
    t.block_failrelative = 0.06;
    ck_assert_int_eq(rep_compare(&run, &gold, &t, &m), REP_V_WITHIN);
    t.block_warn = 0.02;
    ck_assert_int_eq(rep_compare(&run, &gold, &t, &m), REP_V_WARN);
    ck_assert_uint_eq(m.warn_why, REP_WHY_BLOCK);
    /* The same difference spread over a full block: the same sum, a quarter of the mean. */
    free(a);
    a = filled(20 * 12 * 2, 0.5f);
    a[(1 * 20 + 1) * 2 + 0] = 1.3f;
    run.data = a;
    t = loose();
    rep_compare(&run, &gold, &t, &m);
    ck_assert_int_eq(m.block_abs.x, 0);
    ck_assert_int_eq(m.block_abs.w, 8);
    ck_assert_double_eq_tol(m.block_abs.value, 0.8 / 128, 1e-6);
    free(a);
    free(g);
}
END_TEST

START_TEST(block_alignment_and_floor)
{
    float *g = filled(16 * 16, 0.0f), *a = filled(16 * 16, 0.0f);
    a[5 * 16 + 5] = 1e-4f;
    eng_buffer run = buf("x.y", 16, 16, 1, Y, a), gold = buf("x.y", 16, 16, 1, Y, g);
    rep_tol t = loose();
    t.block_size = 4;
    rep_metrics m;
    rep_compare(&run, &gold, &t, &m);
    ck_assert_int_eq(m.block_abs.x, 4); /* aligned to (0, 0): (5, 5) lies in the block at (4, 4) */
    ck_assert_int_eq(m.block_abs.y, 4);
    ck_assert_double_eq_tol(m.block_abs.value, 1e-4 / 16, 1e-10);
    /* a black golden block: the denominator is the floor, not 0 */
    ck_assert_double_eq_tol(m.block_rel.value, (1e-4 / 16) / REP_BLOCK_REL_FLOOR, 1e-8);
    /* bit-exact: no block */
    a[5 * 16 + 5] = 0;
    ck_assert_int_eq(rep_compare(&run, &gold, &t, &m), REP_V_BITEXACT);
    ck_assert_int_eq(m.block_abs.x, -1);
    free(a);
    free(g);
}
END_TEST

static eng_result tol_parse(const char *json)
{
    rep_tolerances *t = NULL;
    eng_error err = {{0}};
    eng_result r = rep_tol_parse("tol.json", json, strlen(json), &t, &err);
    rep_tol_free(t);
    return r;
}

START_TEST(block_keys_parsed)
{
    rep_tolerances *t = NULL;
    eng_error err = {{0}};
    const char *j = "{\"default\": {\"block_fail\": 0.02, \"note\": \"why\"}, \"buffers\": [{\"match\": \"a.*\","
                    " \"block_failrelative\": 0.5, \"block_warn\": 0.01, \"block_warnrelative\": 0.2, \"block_size\": 16,"
                    " \"note\": {\"block_fail\": \"run x frame 3\"}}]}";
    ck_assert_int_eq(rep_tol_parse("tol.json", j, strlen(j), &t, &err), ENG_OK);
    rep_tol tol;
    rep_tol_lookup(t, "a.b", &tol);
    ck_assert_double_eq(tol.block_fail, 0.02);
    ck_assert_double_eq(tol.block_failrelative, 0.5);
    ck_assert_double_eq(tol.block_warn, 0.01);
    ck_assert_double_eq(tol.block_warnrelative, 0.2);
    ck_assert_int_eq(tol.block_size, 16);
    rep_tol_lookup(t, "c", &tol);
    ck_assert_int_eq(tol.block_size, REP_BLOCK_SIZE);
    ck_assert(isinf(tol.block_failrelative));
    rep_tol_free(t);
    ck_assert_int_eq(tol_parse("{\"default\": {\"block_size\": 0}}"), ENG_ERR_INVALID);
    ck_assert_int_eq(tol_parse("{\"default\": {\"block_size\": 2.5}}"), ENG_ERR_INVALID);
    ck_assert_int_eq(tol_parse("{\"default\": {\"block_size\": 1e300}}"), ENG_ERR_INVALID);
    ck_assert_int_eq(tol_parse("{\"default\": {\"block_fail\": -1}}"), ENG_ERR_INVALID);
    ck_assert_int_eq(tol_parse("{\"default\": {\"block_fial\": 1}}"), ENG_ERR_INVALID);
    ck_assert_int_eq(tol_parse("{\"default\": {\"note\": 3}}"), ENG_ERR_INVALID);
    ck_assert_int_eq(tol_parse("{\"default\": {\"note\": {\"a\": 1}}}"), ENG_ERR_INVALID);
}
END_TEST

/* A tolerance rule whose pattern names no buffer of the golden judges nothing: one warning line
 * per such rule, naming the file and the pattern, in the report model (text, JSON, HTML show it). */
START_TEST(tolerance_rules_matching_nothing)
{
    rep_tolerances *t = NULL;
    eng_error err = {{0}};
    const char *j = "{\"buffers\": [{\"match\": \"gbuffer.*\", \"fail\": 0.1}, {\"match\": \"shadow.*\", \"fail\": 0.1},"
                    " {\"match\": \"final.display\", \"fail\": 0.1}]}";
    ck_assert_int_eq(rep_tol_parse("tol.json", j, strlen(j), &t, &err), ENG_OK);
    rep_buffer_info b0[2], b1[1];
    memset(b0, 0, sizeof b0);
    memset(b1, 0, sizeof b1);
    b0[0].name = "gbuffer.albedo";
    b0[1].name = "direct.radiance";
    b1[0].name = "final.display"; /* a rule matched in a later frame only still matches */
    rep_frame_info frames[2];
    memset(frames, 0, sizeof frames);
    frames[0].buffer_count = 2;
    frames[0].buffers = b0;
    frames[1].buffer_count = 1;
    frames[1].buffers = b1;
    rep_run gold;
    memset(&gold, 0, sizeof gold);
    gold.frame_count = 2;
    gold.frames = frames;
    rep_report r;
    memset(&r, 0, sizeof r);
    rep_report_tol_warnings(&r, t, &gold);
    ck_assert_int_eq(r.tol_warning_count, 1);
    ck_assert_str_eq(r.tol_warnings[0], "tol.json: rule \"shadow.*\" matches no buffer of the golden");
    rep_report_tol_warnings(&r, t, NULL); /* no golden: nothing to judge against */
    ck_assert_int_eq(r.tol_warning_count, 1);
    rep_report_free(&r);
    rep_tol_free(t);
}
END_TEST

static rep_expectations *expect_parse(const char *json, eng_result want)
{
    rep_expectations *x = NULL;
    eng_error err = {{0}};
    eng_result r = rep_expect_parse("expectations.json", json, strlen(json), &x, &err);
    ck_assert_msg(r == want, "%s: got %s (%s)", json, eng_result_name(r), err.msg);
    if (r != ENG_OK)
        ck_assert_msg(strncmp(err.msg, "expectations.json:", 18) == 0, "message names the file: %s", err.msg);
    return x;
}

START_TEST(expectations_parsed_and_validated)
{
    ck_assert(rep_date_valid("2024-02-29"));
    ck_assert(!rep_date_valid("2025-02-29"));
    ck_assert(!rep_date_valid("2025-13-01"));
    ck_assert(!rep_date_valid("2025-1-01"));
    ck_assert(!rep_date_valid("tomorrow"));
    char today[11];
    rep_date_today(today);
    ck_assert(rep_date_valid(today));
    rep_expectations *x = expect_parse(
        "[{\"match\": \"indirect.*\", \"expect\": \"fail\", \"reason\": \"GPU bias\", \"renderer\": \"NVIDIA*\"},"
        " {\"match\": \"final.display\", \"expect\": \"fail\", \"reason\": \"leak\", \"until\": \"2026-06-30\"}]",
        ENG_OK);
    ck_assert_int_eq(x->count, 2);
    ck_assert_int_eq(rep_expect_find(x, "indirect.radiance", "NVIDIA RTX", "2026-01-01"), 0);
    ck_assert_int_eq(rep_expect_find(x, "indirect.radiance", "llvmpipe (LLVM 15)", "2026-01-01"), -1);
    ck_assert_int_eq(rep_expect_find(x, "indirect.radiance", NULL, "2026-01-01"), -1);
    ck_assert_int_eq(rep_expect_find(x, "final.display", NULL, "2026-06-30"), 1); /* until is inclusive */
    ck_assert_int_eq(rep_expect_find(x, "final.display", NULL, "2026-07-01"), -1);
    ck_assert(rep_expect_expired(&x->rules[1], "2026-07-01"));
    rep_expect_free(x);
    x = expect_parse("{\"rules\": [{\"match\": \"a\", \"expect\": \"fail\", \"reason\": \"r\"}]}", ENG_OK);
    ck_assert_int_eq(x->count, 1);
    rep_expect_free(x);
    static const char *const bad[] = {
        "[{\"match\": \"a\", \"expect\": \"fail\", \"reason\": \"r\", \"untill\": \"2026-01-01\"}]",
        "[{\"match\": \"a\", \"expect\": \"fail\", \"reason\": \"r\", \"until\": \"2026-02-30\"}]",
        "[{\"match\": \"a\", \"expect\": \"pass\", \"reason\": \"r\"}]",
        "[{\"match\": \"a\", \"expect\": \"fail\"}]",
        "[{\"match\": \"a\", \"expect\": \"fail\", \"reason\": \"\"}]",
        "[{\"expect\": \"fail\", \"reason\": \"r\"}]",
        "[{\"match\": \"a\", \"reason\": \"r\"}]",
        "[3]",
        "{\"rulez\": []}",
        "{\"rules\": 3}",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        ck_assert_ptr_null(expect_parse(bad[i], ENG_ERR_INVALID));
    ck_assert_ptr_null(expect_parse("[{", ENG_ERR_PARSE));
}
END_TEST

/* A report of two frames of two buffers: a.x fails in frame 0 only, b.y passes in both. */
static void two_frames(rep_report *r, const char *rules, const char *today)
{
    memset(r, 0, sizeof *r);
    r->run_dir = "run";
    r->golden_dir = "golden";
    r->frames = 2;
    r->digest_frame = -1;
    for (int f = 0; f < 2; f++) {
        rep_entry *e = rep_report_add(r, f, "a.x");
        e->compared = 1;
        e->verdict = f == 0 ? REP_V_FAIL : REP_V_WITHIN;
        e->m.fail_why = f == 0 ? REP_WHY_PERCENT : 0;
        e = rep_report_add(r, f, "b.y");
        e->compared = 1;
        e->verdict = REP_V_WITHIN;
    }
    rep_expectations *x = NULL;
    eng_error err = {{0}};
    ck_assert_int_eq(rep_expect_parse("ex.json", rules, strlen(rules), &x, &err), ENG_OK);
    r->expect = calloc(1, sizeof *r->expect);
    r->expect->set = x;
    memcpy(r->expect->today, today, 11);
    rep_report_expect_apply(r);
    r->exit = rep_report_exit(r);
}

START_TEST(expectations_applied)
{
    rep_report r;
    /* a.x fails as expected: the run passes, every report names the reason */
    two_frames(&r, "[{\"match\": \"a.*\", \"expect\": \"fail\", \"reason\": \"known leak\"}]", "2026-01-01");
    ck_assert_int_eq(r.exit, REP_OK);
    ck_assert_int_eq(r.expect->expected, 1);
    ck_assert_int_eq(r.expect->unexpected_count, 0);
    ck_assert(r.entries[0].expected);
    ck_assert(!rep_entry_failed(&r.entries[0]));
    char *junit = rep_report_junit(&r, "seq");
    ck_assert_ptr_nonnull(strstr(junit, "skipped=\"1\""));
    ck_assert_ptr_nonnull(strstr(junit, "<skipped message=\"expected failure: known leak\"/>"));
    ck_assert_ptr_nonnull(strstr(junit, "failures=\"0\""));
    free(junit);
    char *json = rep_report_json(&r);
    cJSON *root = cJSON_Parse(json);
    const cJSON *b0 = cJSON_GetArrayItem(
        cJSON_GetObjectItem(cJSON_GetArrayItem(cJSON_GetObjectItem(root, "frames"), 0), "buffers"), 0);
    ck_assert_str_eq(cJSON_GetObjectItem(cJSON_GetObjectItem(b0, "expected_failure"), "reason")->valuestring,
                     "known leak");
    ck_assert_int_eq(cJSON_GetObjectItem(cJSON_GetObjectItem(root, "counts"), "expected failure")->valueint, 1);
    ck_assert_int_eq(cJSON_GetObjectItem(cJSON_GetObjectItem(root, "counts"), "fail")->valueint, 0);
    cJSON_Delete(root);
    free(json);
    rep_report_free(&r);

    /* a rule naming b.y, which passes in every frame: an unexpected pass, a warning */
    two_frames(&r, "[{\"match\": \"b.y\", \"expect\": \"fail\", \"reason\": \"flaky\"}]", "2026-01-01");
    ck_assert_int_eq(r.exit, REP_FAIL); /* a.x still fails */
    ck_assert_int_eq(r.expect->unexpected_count, 1);
    ck_assert_str_eq(r.expect->unexpected[0].buffer, "b.y");
    junit = rep_report_junit(&r, "seq");
    ck_assert_ptr_nonnull(strstr(junit, "name=\"unexpected pass: b.y\""));
    free(junit);
    rep_report_free(&r);
    two_frames(&r, "[{\"match\": \"*\", \"expect\": \"fail\", \"reason\": \"all\"}]", "2026-01-01");
    ck_assert_int_eq(r.exit, REP_WARN); /* a.x expected; b.y passes unexpectedly */
    ck_assert_int_eq(r.expect->unexpected_count, 1);
    rep_report_free(&r);

    /* an expired rule excuses nothing and warns */
    two_frames(&r, "[{\"match\": \"a.*\", \"expect\": \"fail\", \"reason\": \"old\", \"until\": \"2025-12-31\"}]",
               "2026-01-01");
    ck_assert_int_eq(r.exit, REP_FAIL);
    ck_assert_int_eq(r.expect->expired_count, 1);
    ck_assert_int_eq(r.expect->expected, 0);
    char *text = rep_report_text(&r, 0);
    ck_assert_ptr_nonnull(strstr(text, "EXPIRED"));
    free(text);
    rep_report_free(&r);

    /* a renderer glob that does not match the run's renderer: the rule does not apply */
    two_frames(&r, "[{\"match\": \"a.*\", \"expect\": \"fail\", \"reason\": \"gpu\", \"renderer\": \"NVIDIA*\"}]",
               "2026-01-01");
    ck_assert_int_eq(r.exit, REP_FAIL);
    ck_assert_int_eq(r.expect->unexpected_count, 0);
    rep_report_free(&r);
}
END_TEST

START_TEST(worst_block_in_every_format)
{
    rep_report r;
    memset(&r, 0, sizeof r);
    r.run_dir = "run";
    r.golden_dir = "golden";
    r.frames = 2;
    r.digest_frame = -1;
    for (int f = 0; f < 2; f++) {
        rep_entry *e = rep_report_add(&r, f, "final.display");
        e->compared = 1;
        e->verdict = f == 1 ? REP_V_FAIL : REP_V_WITHIN;
        e->m.fail_why = f == 1 ? REP_WHY_BLOCK : 0;
        e->m.width = 40;
        e->m.height = 20;
        e->m.block_size = 8;
        e->m.block_abs = (rep_block){f == 1 ? 0.05 : 0.01, 32, 16, 8, 4};
        e->m.block_rel = (rep_block){0.5, 32, 16, 8, 4};
        rep_tol_builtin(&e->tol);
        e->tol.block_fail = 0.02;
    }
    r.exit = rep_report_exit(&r);
    ck_assert_int_eq(r.exit, REP_FAIL);
    const rep_entry *w = rep_report_worst_block(&r);
    ck_assert_ptr_eq(w, &r.entries[1]);
    char *json = rep_report_json(&r);
    cJSON *root = cJSON_Parse(json);
    const cJSON *wb = cJSON_GetObjectItem(root, "worst_block");
    ck_assert_int_eq(cJSON_GetObjectItem(wb, "frame")->valueint, 1);
    ck_assert_int_eq(cJSON_GetObjectItem(wb, "x")->valueint, 32);
    ck_assert_int_eq(cJSON_GetObjectItem(wb, "h")->valueint, 4); /* a partial bottom block */
    const cJSON *b1 = cJSON_GetArrayItem(
        cJSON_GetObjectItem(cJSON_GetArrayItem(cJSON_GetObjectItem(root, "frames"), 1), "buffers"), 0);
    const cJSON *why = cJSON_GetObjectItem(cJSON_GetObjectItem(b1, "metrics"), "fail_reasons");
    ck_assert_str_eq(cJSON_GetArrayItem(why, 0)->valuestring, "block");
    ck_assert_double_eq(cJSON_GetObjectItem(cJSON_GetObjectItem(b1, "tolerance"), "block_fail")->valuedouble, 0.02);
    cJSON_Delete(root);
    free(json);
    char *junit = rep_report_junit(&r, "seq");
    ck_assert_ptr_nonnull(strstr(junit, "<property name=\"worst_block\" value=\"worst 8×8 block: frame 1 final.display (32,16)"));
    free(junit);
    char *text = rep_report_text(&r, 0);
    ck_assert_ptr_nonnull(strstr(text, "worst 8×8 block: frame 1 final.display (32,16) 8×4"));
    ck_assert_ptr_nonnull(strstr(text, "block over block_fail 0.02"));
    free(text);
    char dir[] = "/tmp/ispm-test-block-XXXXXX";
    ck_assert_ptr_nonnull(mkdtemp(dir));
    eng_error err = {{0}};
    ck_assert_int_eq(rep_report_html_write(&r, NULL, NULL, dir, &err), ENG_OK);
    char p[600];
    snprintf(p, sizeof p, "%s/report.html", dir);
    char *html = NULL;
    size_t len = 0;
    ck_assert_int_eq(eng_read_file(p, 1 << 22, &html, &len, &err), ENG_OK);
    ck_assert_ptr_nonnull(strstr(html, "id=\"worst-block\"><a href=\"#e1\">"));
    ck_assert_ptr_nonnull(strstr(html, "worst block"));
    free(html);
    snprintf(p, sizeof p, "rm -rf %s", dir);
    ck_assert_int_eq(system(p), 0);
    rep_report_free(&r);
}
END_TEST

START_TEST(suggest_rounding)
{
    ck_assert_double_eq(rep_suggest_round(0, 1.25), 0);
    ck_assert_double_eq_tol(rep_suggest_round(0.0832, 1.25), 0.104, 1e-12);
    ck_assert_double_eq_tol(rep_suggest_round(0.01681, 1.25), 0.0211, 1e-12); /* 0.0210125 rounded up */
    ck_assert_double_eq_tol(rep_suggest_round(123456, 1), 124000, 1e-6);
    for (double v = 1e-7; v < 1e3; v *= 1.37) {
        double s = rep_suggest_round(v, 1.1);
        ck_assert_msg(s >= v * 1.1 && s <= v * 1.1 * 1.011, "%g -> %g", v, s);
        char text[32];
        snprintf(text, sizeof text, "%.3g", s);
        ck_assert(strtod(text, NULL) >= v * 1.1);
    }
    /* refusals: no run, a margin under 1, an unreadable run */
    eng_error err = {{0}};
    const char *runs[1] = {"/nonexistent/run"};
    rep_suggest_options o = {runs, 1, "/nonexistent/golden", NULL, 0.5, "/tmp/x.json"};
    ck_assert_int_eq(rep_tol_suggest(&o, NULL, &err), ENG_ERR_INVALID);
    o.margin = 1.25;
    ck_assert_int_ne(rep_tol_suggest(&o, NULL, &err), ENG_OK);
    ck_assert_ptr_nonnull(strstr(err.msg, "/nonexistent/"));
}
END_TEST

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fputs(text, f);
    fclose(f);
}

/* A replayed run: manifest with per-pass times, report with one buffer over two frames. */
static void fake_run(const char *dir, const char *git, double flip0, double flip1, double max0, double splat_ms)
{
    char p[512];
    snprintf(p, sizeof p, "mkdir -p %s/replay", dir);
    ck_assert_int_eq(system(p), 0);
    char text[2048];
    snprintf(text, sizeof text,
             "{\"tool\": {\"git\": \"%s\"}, \"frames\": ["
             "{\"passes\": [{\"name\": \"gbuffer\", \"ms\": 10}, {\"name\": \"splat\", \"ms\": %g}]},"
             "{\"passes\": [{\"name\": \"gbuffer\", \"ms\": 10}, {\"name\": \"splat\", \"ms\": %g}]}]}",
             git, splat_ms, splat_ms);
    snprintf(p, sizeof p, "%s/manifest.json", dir);
    write_file(p, text);
    snprintf(text, sizeof text,
             "{\"format\": \"ispm-replay-report\", \"verdict\": \"OK\", \"exit_code\": 0, \"frames\": ["
             "{\"index\": 0, \"buffers\": [{\"name\": \"final.display\", \"metrics\": {\"max_abs_error\": %g, \"rmse\": 0.3},"
             " \"flip\": {\"mean\": %g, \"p99\": 0.5}}]},"
             "{\"index\": 1, \"buffers\": [{\"name\": \"final.display\", \"metrics\": {\"max_abs_error\": 0.1, \"rmse\": 0.4},"
             " \"flip\": {\"mean\": %g, \"p99\": 0.7}}]}],"
             " \"stability\": {\"buffers\": [{\"name\": \"final.display\", \"reprojected\": {\"mean\": 0.01},"
             " \"static\": {\"mean\": 0.002}}]}}",
             max0, flip0, flip1);
    snprintf(p, sizeof p, "%s/replay/report.json", dir);
    write_file(p, text);
}

static const cJSON *series_of(const cJSON *root, const char *metric, const char *name)
{
    const cJSON *s;
    cJSON_ArrayForEach(s, cJSON_GetObjectItem(root, "series"))
    {
        if (strcmp(cJSON_GetObjectItem(s, "metric")->valuestring, metric) == 0 &&
            strcmp(cJSON_GetObjectItem(s, "name")->valuestring, name) == 0)
            return s;
    }
    return NULL;
}

START_TEST(trend_aggregates_and_marks)
{
    char dir[] = "/tmp/ispm-test-trend-XXXXXX";
    ck_assert_ptr_nonnull(mkdtemp(dir));
    char a[600], b[600], c[600], out[600];
    snprintf(a, sizeof a, "%s/a", dir);
    snprintf(b, sizeof b, "%s/b", dir);
    snprintf(c, sizeof c, "%s/c", dir);
    snprintf(out, sizeof out, "%s/out", dir);
    fake_run(a, "aaaa", 0.01, 0.03, 0.2, 30);
    fake_run(b, "bbbb-dirty", 0.02, 0.04, 0.2, 30);
    fake_run(c, "cccc", 0.10, 0.12, 0.05, 90);
    const char *runs[3] = {a, b, c};
    eng_error err = {{0}};
    ck_assert_msg(rep_trend_write(runs, NULL, 3, out, NULL, &err) == ENG_OK, "%s", err.msg);
    char p[700];
    snprintf(p, sizeof p, "%s/trend.json", out);
    char *text = NULL;
    size_t len = 0;
    ck_assert_int_eq(eng_read_file(p, 1 << 20, &text, &len, &err), ENG_OK);
    cJSON *root = cJSON_ParseWithLength(text, len);
    free(text);
    ck_assert_ptr_nonnull(root);
    const cJSON *r0 = cJSON_GetArrayItem(cJSON_GetObjectItem(root, "runs"), 0);
    const cJSON *fd = cJSON_GetObjectItem(cJSON_GetObjectItem(r0, "buffers"), "final.display");
    ck_assert_double_eq_tol(cJSON_GetObjectItem(fd, "flip_mean")->valuedouble, 0.02, 1e-12); /* mean over frames */
    ck_assert_double_eq_tol(cJSON_GetObjectItem(fd, "flip_p99")->valuedouble, 0.7, 1e-12);   /* max over frames */
    ck_assert_double_eq_tol(cJSON_GetObjectItem(fd, "max_abs")->valuedouble, 0.2, 1e-12);
    ck_assert_double_eq_tol(cJSON_GetObjectItem(fd, "rmse")->valuedouble, sqrt((0.09 + 0.16) / 2), 1e-12);
    ck_assert_double_eq_tol(cJSON_GetObjectItem(fd, "flicker_reprojected")->valuedouble, 0.01, 1e-12);
    ck_assert_double_eq_tol(cJSON_GetObjectItem(r0, "frame_ms")->valuedouble, 40, 1e-12);
    const cJSON *splat = cJSON_GetObjectItem(cJSON_GetObjectItem(r0, "passes"), "splat");
    ck_assert_double_eq_tol(cJSON_GetObjectItem(splat, "share")->valuedouble, 0.75, 1e-12);
    const cJSON *s = series_of(root, "flip_mean", "final.display");
    ck_assert_ptr_nonnull(s);
    const cJSON *mm = cJSON_GetObjectItem(s, "moved_most");
    ck_assert_int_eq(cJSON_GetObjectItem(mm, "from")->valueint, 1);
    ck_assert_int_eq(cJSON_GetObjectItem(mm, "to")->valueint, 2);
    ck_assert_double_eq_tol(cJSON_GetObjectItem(mm, "delta")->valuedouble, 0.08, 1e-12);
    mm = cJSON_GetObjectItem(series_of(root, "max_abs", "final.display"), "moved_most");
    ck_assert_double_eq_tol(cJSON_GetObjectItem(mm, "delta")->valuedouble, -0.1, 1e-12); /* max over frames: 0.2, 0.2, 0.1 */
    ck_assert(cJSON_IsNull(cJSON_GetObjectItem(series_of(root, "flicker_static", "final.display"), "moved_most")));
    ck_assert_ptr_nonnull(series_of(root, "pass_share", "splat"));
    ck_assert_ptr_nonnull(series_of(root, "frame_ms", "frame"));
    cJSON_Delete(root);
    snprintf(p, sizeof p, "%s/trend.html", out);
    ck_assert(access(p, R_OK) == 0);
    char *git = rep_trend_run_git(b);
    ck_assert_str_eq(git, "bbbb");
    free(git);
    /* a run not replayed, and a report that is not replay's: one line naming the file */
    snprintf(p, sizeof p, "rm %s/replay/report.json", c);
    ck_assert_int_eq(system(p), 0);
    ck_assert_int_eq(rep_trend_write(runs, NULL, 3, out, NULL, &err), ENG_ERR_IO);
    ck_assert_ptr_nonnull(strstr(err.msg, "report.json"));
    snprintf(p, sizeof p, "%s/replay/report.json", c);
    write_file(p, "{\"format\": \"something else\"}");
    ck_assert_int_eq(rep_trend_write(runs, NULL, 3, out, NULL, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, p));
    snprintf(p, sizeof p, "rm -rf %s", dir);
    ck_assert_int_eq(system(p), 0);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("regression");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, block_partial_edge);
    tcase_add_test(tc, block_alignment_and_floor);
    tcase_add_test(tc, block_keys_parsed);
    tcase_add_test(tc, tolerance_rules_matching_nothing);
    tcase_add_test(tc, expectations_parsed_and_validated);
    tcase_add_test(tc, expectations_applied);
    tcase_add_test(tc, worst_block_in_every_format);
    tcase_add_test(tc, suggest_rounding);
    tcase_add_test(tc, trend_aggregates_and_marks);
    suite_add_tcase(s, tc);
    SRunner *sr = srunner_create(s);
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
