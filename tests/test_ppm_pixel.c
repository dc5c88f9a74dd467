/* test_ppm_pixel.c — Check suite of progressive photon mapping's per-pixel radius in the engine
 * (`"progressive_radius": "pixel"`, engine/indirect/progressive.h; Hachisuka et al. 2008 §4) on a small
 * still Cornell box:
 *  - frame 1 evaluates every pixel at scale 1; frame 2 at √α where the k-d gather found photons
 *    in frame 1 (R² = (0 + αM)/(0 + M)) and at 1 where it found none; N = α·M after frame 1;
 *  - the radii differ from pixel to pixel after a few frames (it is not one scale a frame);
 *  - the tile gather gives the k-d gather's buffers bit for bit under it;
 *  - the scatter (a GL fragment program reading the scales) gives them up to llvmpipe's rounding;
 *  - the quads follow the same schedule on their own counts;
 *  - a method without per-pixel radii (the GL tile gather) or "pixel" without "progressive" is
 *    refused.
 * (engine/indirect/progressive.c's update itself: test_progressive.c, ppm_update_per_pixel.) */
#define _POSIX_C_SOURCE 200809L
#include "eng.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FRAMES 3
#define P "\"progressive\": true, " /* every run but the refused one */

typedef struct img {
    int w, h, n;
    float *data;
} img;

/* Per frame: the method's count, and the progressive buffers. */
typedef struct kept_run {
    img count[FRAMES], radius[FRAMES], photons[FRAMES], radiance[FRAMES];
} kept_run;

static int keep(void *user, int frame, const eng_buffer *b)
{
    kept_run *k = user;
    img *d = !strcmp(b->name, "gather.count") || !strcmp(b->name, "splat.count") ? &k->count[frame]
             : !strcmp(b->name, "progressive.radius")   ? &k->radius[frame]
             : !strcmp(b->name, "progressive.photons")  ? &k->photons[frame]
             : !strcmp(b->name, "progressive.radiance") ? &k->radiance[frame]
                                                        : NULL;
    if (!d || frame < 0 || frame >= FRAMES)
        return 0;
    d->w = b->width;
    d->h = b->height;
    d->n = b->channel_count;
    size_t sz = (size_t)b->width * b->height * b->channel_count * sizeof(float);
    free(d->data);
    d->data = malloc(sz);
    memcpy(d->data, b->data, sz);
    return 0;
}

static void kept_free(kept_run *k)
{
    for (int f = 0; f < FRAMES; f++) {
        free(k->count[f].data);
        free(k->radius[f].data);
        free(k->photons[f].data);
        free(k->radiance[f].data);
    }
    memset(k, 0, sizeof *k);
}

/* A still 48×48 view of the Cornell box, 4,096 photons, with extra settings. */
/* Returns seq_parse's or the engine's error; to_gl: the parsed settings' method becomes the GL
 * tile gather before the engine sees them (the engine's own check, behind the parser's). */
static eng_result run_with(const char *settings, int to_gl, kept_run *k, eng_error *err)
{
    char json[2048];
    snprintf(json, sizeof json,
             "{\"scene\": \"cornell-box.gltf\", \"frames\": %d, \"fps\": 8, \"resolution\": [48, 48], "
             "\"camera\": {\"node\": \"Camera\"}, \"still\": true, \"settings\": {%s, \"shadow_map_size\": "
             "256, \"photon_count\": 4096, \"kernel_radius\": 0.1, \"random\": \"per-frame\"}}",
             FRAMES, settings);
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/cornell-box/ppm-test.json", ISPM_SOURCE_DIR);
    seq_sequence *seq = calloc(1, sizeof *seq);
    eng_result r = seq_parse(path, json, strlen(json), seq, err);
    if (r != ENG_OK) {
        free(seq);
        return r;
    }
    if (to_gl)
        seq->settings.indirect = ENG_INDIRECT_TILEGATHER_GL;
    scn_scene *scene = NULL;
    ck_assert_msg(scn_load_gltf(seq->scene_path, &scene, err) == ENG_OK, "%s", err->msg);
    eng_engine *eng = NULL;
    eng_desc d = {.scene = scene, .sequence = seq};
    r = eng_create(&d, &eng, err);
    if (r == ENG_OK) {
        eng_listener l = {k, NULL, keep, NULL};
        ck_assert_int_eq(eng_add_listener(eng, &l), ENG_OK);
        for (int f = 0; f < FRAMES && r == ENG_OK; f++)
            r = eng_render_frame(eng, f, err);
        eng_destroy(eng);
    }
    scn_destroy(scene);
    free(seq);
    return r;
}

static eng_result run(const char *settings, kept_run *k, eng_error *err) { return run_with(settings, 0, k, err); }

static int same(const img *a, const img *b)
{
    return a->data && b->data && a->w == b->w && a->h == b->h && a->n == b->n &&
           !memcmp(a->data, b->data, (size_t)a->w * a->h * a->n * sizeof(float));
}

/* Σ M over frame f's pixels. */
static double count_sum(const kept_run *k, int f)
{
    double sum = 0.0;
    for (size_t i = 0; i < (size_t)k->count[f].w * k->count[f].h; i++)
        sum += k->count[f].data[i * (size_t)k->count[f].n];
    return sum;
}

/* The kernels really shrink per pixel: frame 2's photon counts under "pixel" (R² = 2/3 almost
 * everywhere) against "frame" (R² = 5/6, the same photons): about 4/5 of them. */
static void check_shrinks(const kept_run *pixel, const kept_run *frame, const char *what)
{
    const double ratio = count_sum(pixel, 1) / count_sum(frame, 1);
    printf("test_ppm_pixel: %s: frame 2 photons found, pixel / frame radii: %.4f\n", what, ratio);
    ck_assert_msg(ratio > 0.7 && ratio < 0.9, "%s: %g", what, ratio);
    ck_assert(fabs(count_sum(pixel, 0) / count_sum(frame, 0) - 1.0) < 1e-9);
}

/* PPM's schedule in a run's buffers: frame 1 at scale 1 with N = αM, frame 2 at √α where frame 1
 * found photons (R² = (0 + αM)/(0 + M)) and at 1 where it found none; the third frame's scales
 * differ from pixel to pixel. Returns the pixel count. */
static size_t check_schedule(const kept_run *k, const char *what)
{
    for (int f = 0; f < FRAMES; f++)
        ck_assert_msg(k->count[f].data && k->radius[f].data && k->photons[f].data && k->radiance[f].data,
                      "%s frame %d: a buffer is missing", what, f);
    const size_t n = (size_t)k->radius[0].w * k->radius[0].h;
    const float alpha = 2.0f / 3.0f, sqa = sqrtf(alpha);
    size_t found = 0, empty = 0, surface = 0;
    float lo = 2.0f, hi = 0.0f;
    for (size_t i = 0; i < n; i++) {
        const float m = k->count[0].data[i], r0 = k->radius[0].data[i], r1 = k->radius[1].data[i];
        if (r0 == 0.0f) /* background */
            continue;
        surface++;
        ck_assert_float_eq(r0, 1.0f);
        ck_assert_msg(fabsf(k->photons[0].data[i] - alpha * m) <= 1e-5f * (1.0f + m), "pixel %zu: N %g, M %g", i,
                      k->photons[0].data[i], m);
        if (m > 0.0f) {
            ck_assert_msg(fabsf(r1 - sqa) < 1e-6f, "pixel %zu: frame 2 scale %g, want sqrt(2/3)", i, r1);
            found++;
        } else {
            ck_assert_float_eq(r1, 1.0f);
            empty++;
        }
        const float r2 = k->radius[2].data[i];
        lo = fminf(lo, r2);
        hi = fmaxf(hi, r2);
    }
    ck_assert_msg(surface > n / 2 && found > surface / 2, "%zu surface pixels, %zu with photons", surface, found);
    /* The third frame's scales depend on each pixel's own counts. */
    ck_assert_msg(hi - lo > 0.01f, "frame 3 scales all within [%g, %g]", lo, hi);
    printf("test_ppm_pixel: %s: %zu surface pixels, %zu found photons in frame 1, %zu none; frame 3 scale %g..%g\n",
           what, surface, found, empty, lo, hi);
    return n;
}

START_TEST(per_pixel_radius_follows_ppm)
{
    static kept_run kd, tg;
    eng_error err;
    ck_assert_msg(run(P "\"indirect\": \"kd-gather\", \"progressive_radius\": \"pixel\"", &kd, &err) == ENG_OK, "%s",
                  err.msg);
    const size_t n = check_schedule(&kd, "kd-gather");
    /* The tile gather: the same bits. */
    ck_assert_msg(run(P "\"indirect\": \"tile-gather\", \"progressive_radius\": \"pixel\"", &tg, &err) == ENG_OK, "%s",
                  err.msg);
    for (int f = 0; f < FRAMES; f++) {
        ck_assert_msg(same(&kd.count[f], &tg.count[f]), "frame %d: gather.count differs", f);
        ck_assert_msg(same(&kd.radius[f], &tg.radius[f]), "frame %d: progressive.radius differs", f);
        ck_assert_msg(same(&kd.photons[f], &tg.photons[f]), "frame %d: progressive.photons differs", f);
        ck_assert_msg(same(&kd.radiance[f], &tg.radiance[f]), "frame %d: progressive.radiance differs", f);
    }
    kept_free(&tg);

    /* The scatter (splat.frag.glsl's SPLAT_PIXEL_SCALE programs on llvmpipe): the same up to the
     * GPU's rounding, i.e. photons exactly at a kernel's rim, which can change a pixel's count
     * M and so its next radius. Keeps splat.count instead of gather.count. */
    ck_assert_msg(run(P "\"indirect\": \"ispm\", \"progressive_radius\": \"pixel\"", &tg, &err) == ENG_OK, "%s",
                  err.msg);
    for (int f = 0; f < FRAMES; f++) {
        ck_assert(tg.radius[f].data && tg.radiance[f].data);
        size_t off = 0;
        double sa = 0.0, sb = 0.0;
        for (size_t i = 0; i < n; i++) {
            off += tg.radius[f].data[i] != kd.radius[f].data[i];
            for (int c = 0; c < 3; c++) {
                sa += tg.radiance[f].data[3 * i + c];
                sb += kd.radiance[f].data[3 * i + c];
            }
        }
        printf("test_ppm_pixel: scatter frame %d: %zu of %zu radii differ from the k-d gather's, radiance sum "
               "ratio %.6f\n", f, off, n, sa / sb);
        ck_assert_msg(off <= n / 100 && fabs(sa / sb - 1.0) < 1e-3, "scatter frame %d: %zu radii off, ratio %g", f,
                      off, sa / sb);
    }
    kept_free(&tg);

    /* The quads (quads.frag.glsl's PIXEL_SCALE programs): their own counts (a flat kernel on the
     * photon's plane, 001 §3.3), so their own schedule. */
    ck_assert_msg(run(P "\"indirect\": \"quads\", \"progressive_radius\": \"pixel\"", &tg, &err) == ENG_OK, "%s",
                  err.msg);
    check_schedule(&tg, "quads");
    static kept_run qf;
    ck_assert_msg(run(P "\"indirect\": \"quads\"", &qf, &err) == ENG_OK, "%s", err.msg);
    check_shrinks(&tg, &qf, "quads");
    kept_free(&qf);
    kept_free(&tg);

    /* "frame" (the default) gives one scale a frame, and no progressive.photons. */
    ck_assert_msg(run(P "\"indirect\": \"kd-gather\", \"progressive_radius\": \"frame\"", &tg, &err) == ENG_OK, "%s",
                  err.msg);
    ck_assert(tg.photons[0].data == NULL);
    check_shrinks(&kd, &tg, "kd-gather");
    float one = 0.0f;
    for (size_t i = 0; i < n; i++) {
        const float r = tg.radius[2].data[i];
        if (r != 0.0f && one == 0.0f)
            one = r;
        ck_assert_msg(r == 0.0f || r == one, "pixel %zu: %g, another %g", i, r, one);
    }
    ck_assert(one > 0.0f && one < 1.0f);
    kept_free(&tg);
    kept_free(&kd);
}
END_TEST

START_TEST(refused_where_it_cannot_apply)
{
    kept_run k;
    memset(&k, 0, sizeof k);
    eng_error err;
    /* The sequence parser (naming the file), for a method without them and without
     * "progressive"; the engine for a method switched after parsing. */
    ck_assert_int_ne(run(P "\"indirect\": \"tile-gather-gl\", \"progressive_radius\": \"pixel\"", &k, &err), ENG_OK);
    ck_assert_msg(strstr(err.msg, "ppm-test.json") && strstr(err.msg, "progressive_radius"), "%s", err.msg);
    ck_assert_int_ne(run("\"indirect\": \"kd-gather\", \"progressive\": false, \"progressive_radius\": \"pixel\"", &k,
                         &err),
                     ENG_OK);
    ck_assert_msg(strstr(err.msg, "progressive_radius") != NULL, "%s", err.msg);
    ck_assert_int_eq(run_with(P "\"indirect\": \"kd-gather\", \"progressive_radius\": \"pixel\"", 1, &k, &err),
                     ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "tile-gather-gl") != NULL, "%s", err.msg);
    kept_free(&k);
}
END_TEST

static Suite *ppm_suite(void)
{
    Suite *s = suite_create("ppm_pixel");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 300);
    tcase_add_test(tc, per_pixel_radius_follows_ppm);
    tcase_add_test(tc, refused_where_it_cannot_apply);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(ppm_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
