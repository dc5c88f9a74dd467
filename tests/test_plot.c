/* test_plot.c — Check suite for replay/report/plot.c (PLplot charts): a chart file has the requested
 * size, is drawn (not blank, the series' colours present), log axes skip values <= 0, marked
 * points add markers, stacked bars scale with their values, and bad input fails with an error
 * naming the file and leaves no file behind. */
#define _POSIX_C_SOURCE 200809L
#include "oiio_shim.h"
#include "plot.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char tmpdir[256];

static void setup(void)
{
    snprintf(tmpdir, sizeof tmpdir, "/tmp/ispm_test_plot_XXXXXX");
    ck_assert_ptr_nonnull(mkdtemp(tmpdir));
}

static void teardown(void)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmpdir);
    ck_assert_int_eq(system(cmd), 0);
}

/* Pixels whose colour is close to (r,g,b). */
static long count_colour(const unsigned char *px, int w, int h, int nch, int r, int g, int b)
{
    long n = 0;
    for (long i = 0; i < (long)w * h; i++) {
        const unsigned char *p = px + i * nch;
        if (abs(p[0] - r) < 24 && abs(p[1] - g) < 24 && abs(p[2] - b) < 24)
            n++;
    }
    return n;
}

static unsigned char *load(const char *path, int *w, int *h, int *nch)
{
    unsigned char *px = NULL;
    eng_error err = {{0}};
    eng_result r = rep_oiio_read_image8(path, w, h, nch, &px, &err);
    ck_assert_msg(r == ENG_OK, "%s", err.msg);
    ck_assert_int_ge(*nch, 3);
    return px;
}

START_TEST(xy_chart_png)
{
    double x[20], y[20], y2[20];
    for (int i = 0; i < 20; i++) {
        x[i] = i + 1;
        y[i] = 0.5 * (i + 1);
        y2[i] = 10.0 - 0.4 * i;
    }
    int marked[20] = {0};
    marked[3] = marked[7] = 1;
    plot_chart c;
    memset(&c, 0, sizeof c);
    c.title = "test";
    c.x_label = "frame";
    c.y_label = "value";
    c.series_count = 2;
    c.series[0] = (plot_series){"rising", x, y, 20, PLOT_LINES, NULL};
    c.series[1] = (plot_series){"falling", x, y2, 20, PLOT_LINES_POINTS, marked};
    c.width = 640;
    c.height = 400;
    char path[512];
    snprintf(path, sizeof path, "%s/chart.png", tmpdir);
    eng_error err = {{0}};
    ck_assert_msg(plot_xy(path, &c, &err) == ENG_OK, "%s", err.msg);
    int w, h, nch;
    unsigned char *px = load(path, &w, &h, &nch);
    ck_assert_int_eq(w, 640);
    ck_assert_int_eq(h, 400);
    long white = count_colour(px, w, h, nch, 255, 255, 255);
    long blue = count_colour(px, w, h, nch, 0, 114, 178);    /* series 0 */
    long orange = count_colour(px, w, h, nch, 213, 94, 0);   /* series 1 */
    ck_assert_int_gt(white, (long)w * h / 2);                /* a white page ... */
    ck_assert_int_gt(blue, 200);                             /* ... with both lines drawn */
    ck_assert_int_gt(orange, 200);
    free(px);

    /* The same chart as SVG: a text file naming the series in its legend. */
    snprintf(path, sizeof path, "%s/chart.svg", tmpdir);
    ck_assert_msg(plot_xy(path, &c, &err) == ENG_OK, "%s", err.msg);
    FILE *f = fopen(path, "rb");
    ck_assert_ptr_nonnull(f);
    char head[64] = {0};
    ck_assert_uint_gt(fread(head, 1, sizeof head - 1, f), 10);
    fclose(f);
    ck_assert_ptr_nonnull(strstr(head, "<?xml"));
}
END_TEST

START_TEST(log_axes_skip_nonpositive)
{
    double x[4] = {0.0, 1.0, 10.0, 100.0}, y[4] = {1.0, -1.0, 0.01, 0.001};
    plot_chart c;
    memset(&c, 0, sizeof c);
    c.log_x = c.log_y = 1;
    c.series_count = 1;
    c.series[0] = (plot_series){"s", x, y, 4, PLOT_POINTS, NULL};
    char path[512];
    snprintf(path, sizeof path, "%s/log.png", tmpdir);
    eng_error err = {{0}};
    ck_assert_msg(plot_xy(path, &c, &err) == ENG_OK, "%s", err.msg);
    /* Only non-positive values: nothing to draw is an error, and no file is left. */
    double bad[2] = {0.0, -2.0};
    c.series[0] = (plot_series){"s", bad, bad, 2, PLOT_POINTS, NULL};
    snprintf(path, sizeof path, "%s/none.png", tmpdir);
    ck_assert_int_eq(plot_xy(path, &c, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "none.png"));
    struct stat st;
    ck_assert_int_ne(stat(path, &st), 0);
    /* NaN is skipped like a non-positive value. */
    double xn[3] = {1.0, 2.0, 3.0}, yn[3] = {NAN, 2.0, INFINITY};
    c.log_x = c.log_y = 0;
    c.series[0] = (plot_series){"s", xn, yn, 3, PLOT_LINES_POINTS, NULL};
    snprintf(path, sizeof path, "%s/nan.png", tmpdir);
    ck_assert_msg(plot_xy(path, &c, &err) == ENG_OK, "%s", err.msg);
}
END_TEST

START_TEST(bad_paths)
{
    double x[2] = {1, 2}, y[2] = {1, 2};
    plot_chart c;
    memset(&c, 0, sizeof c);
    c.series_count = 1;
    c.series[0] = (plot_series){"s", x, y, 2, PLOT_LINES, NULL};
    eng_error err = {{0}};
    char path[512];
    snprintf(path, sizeof path, "%s/chart.bmp", tmpdir);
    ck_assert_int_eq(plot_xy(path, &c, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "chart.bmp"));
    snprintf(path, sizeof path, "%s/missing/dir/chart.png", tmpdir);
    ck_assert_int_eq(plot_xy(path, &c, &err), ENG_ERR_IO);
    ck_assert_ptr_nonnull(strstr(err.msg, "missing/dir/chart.png"));
}
END_TEST

START_TEST(stacked_bars)
{
    const char *labels[3] = {"a", "b", "c"};
    const char *series[2] = {"shadow", "splat"};
    /* bar c is the tallest: its top segment reaches the highest row of the plot area */
    double v[6] = {1.0, 2.0, 3.0, /* shadow */ 1.0, 1.0, 5.0 /* splat */};
    char path[512];
    snprintf(path, sizeof path, "%s/bars.png", tmpdir);
    eng_error err = {{0}};
    ck_assert_msg(plot_stacked_bars(path, "pass times", "ms", 3, labels, 2, series, v, &err) == ENG_OK, "%s",
                  err.msg);
    int w, h, nch;
    unsigned char *px = load(path, &w, &h, &nch);
    long blue = count_colour(px, w, h, nch, 0, 114, 178), orange = count_colour(px, w, h, nch, 213, 94, 0);
    /* Areas are proportional to the values: shadow 6 units, splat 7 units (+ legend boxes). */
    ck_assert_int_gt(blue, 1000);
    ck_assert_int_gt(orange, 1000);
    double ratio = (double)orange / (double)blue;
    ck_assert_msg(ratio > 1.0 && ratio < 1.4, "splat/shadow area ratio %.3f, expected ~7/6", ratio);
    free(px);
    v[2] = -1.0;
    ck_assert_int_eq(plot_stacked_bars(path, "t", "ms", 3, labels, 2, series, v, &err), ENG_ERR_INVALID);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("plot");
    TCase *tc = tcase_create("plot");
    tcase_add_checked_fixture(tc, setup, teardown);
    tcase_add_test(tc, xy_chart_png);
    tcase_add_test(tc, log_axes_skip_nonpositive);
    tcase_add_test(tc, bad_paths);
    tcase_add_test(tc, stacked_bars);
    suite_add_tcase(s, tc);
    SRunner *sr = srunner_create(s);
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
