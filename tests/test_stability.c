/* test_stability.c — the replay module's temporal stability metrics (replay/compare/stability.c) on
 * synthetic frames with known answers: identical frames give zero flicker, a known change gives
 * known statistics, a disocclusion is masked, reprojection under a known camera motion is exact,
 * and the "stability" tolerance object is parsed strictly and enforced. */
#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "rep_stab.h"

#define W 16
#define H 8

static const char *const XYZ[] = {"X", "Y", "Z"};
static const char *const XY[] = {"X", "Y"};
static const char *const RGB[] = {"R", "G", "B"};
static const char *const MAT[] = {"roughness", "metallic", "transmission", "ior", "id"};

/* A synthetic frame: a plane z = depth seen by an affine camera (clip = (x, y, 0, 1) of the
 * world point scaled so that pixel (i, j) shows world (i + 0.5 + shift, j + 0.5)), plus an
 * optional occluder (id 1, nearer) over pixel columns [occ0, occ1). */
typedef struct frame {
    float pos[W * H * 3], nrm[W * H * 3], mat[W * H * 5], mot[W * H * 2], img[W * H * 3];
    rep_part parts[5];
    rep_frame_info info;
} frame;

static void set_part(rep_part *p, const char *name, int n, const char *const *ch, float *data)
{
    memset(p, 0, sizeof *p);
    p->name = (char *)name;
    p->width = W;
    p->height = H;
    p->channel_count = n;
    for (int c = 0; c < n; c++)
        p->channels[c] = (char *)ch[c];
    p->data = data;
}

/* Camera that maps world x in [shift, shift + W) to the image's columns (y down: world y = row). */
static void camera(float *vp, double shift)
{
    memset(vp, 0, 16 * sizeof(float));
    vp[0] = (float)(2.0 / W);                /* x_clip = 2 (X - shift) / W - 1 */
    vp[12] = (float)(-2.0 * shift / W - 1.0);
    vp[5] = (float)(-2.0 / H);               /* y_clip = 1 - 2 Y / H */
    vp[13] = 1.0f;
    vp[15] = 1.0f;
}

static float shade(double x, double y)
{
    return (float)(0.1 + 0.01 * x + 0.02 * y);
}

/* shift: camera position in world x; prev_shift: the previous frame's (for motion vectors);
 * occ0..occ1: occluder columns (none if occ0 == occ1), occ_prev: its columns one frame before. */
static void make(frame *f, int index, double shift, double prev_shift, int occ0, int occ1, int pocc0, int pocc1)
{
    memset(f, 0, sizeof *f);
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            size_t k = (size_t)j * W + (size_t)i;
            double X = i + 0.5 + shift, Y = j + 0.5;
            int occ = i >= occ0 && i < occ1;
            f->pos[3 * k] = (float)X;
            f->pos[3 * k + 1] = (float)Y;
            f->pos[3 * k + 2] = occ ? 5.0f : 0.0f; /* five pixel footprints in front */
            f->nrm[3 * k + 2] = 1.0f;
            f->mat[5 * k + 3] = 1.5f;
            f->mat[5 * k + 4] = occ ? 1.0f : 0.0f;
            if (occ) {
                /* the occluder moved from [pocc0, pocc1) to [occ0, occ1) on screen */
                f->mot[2 * k] = (float)(pocc0 - occ0);
            } else {
                f->mot[2 * k] = (float)(shift - prev_shift);
            }
            float v = occ ? 0.9f : shade(X, Y);
            f->img[3 * k] = f->img[3 * k + 1] = f->img[3 * k + 2] = v;
        }
    (void)pocc1;
    set_part(&f->parts[0], "gbuffer.position", 3, XYZ, f->pos);
    set_part(&f->parts[1], "gbuffer.normal", 3, XYZ, f->nrm);
    set_part(&f->parts[2], "gbuffer.material", 5, MAT, f->mat);
    set_part(&f->parts[3], "gbuffer.motion", 2, XY, f->mot);
    set_part(&f->parts[4], "indirect.radiance", 3, RGB, f->img);
    f->info.index = index;
    f->info.has_camera = 1;
    camera(f->info.view_proj, shift);
}

static rep_stab_run *feed(frame *const *frames, int n)
{
    rep_stab_run *st = calloc(1, sizeof *st);
    st->frame_count = n;
    for (int i = 0; i < n; i++)
        ck_assert_int_eq(rep_stab_frame(st, &frames[i]->info, frames[i]->parts, 5, NULL, 0, NULL, NULL), 1);
    rep_stab_finish(st);
    return st;
}

START_TEST(identical_frames_zero)
{
    frame *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    make(a, 0, 0, 0, 0, 0, 0, 0);
    make(b, 1, 0, 0, 0, 0, 0, 0);
    rep_stab_run *st = feed((frame *[]){a, b}, 2);
    ck_assert_int_eq(st->buffer_count, 1);
    rep_stab_buffer *r = rep_stab_find(st, "indirect.radiance");
    ck_assert_ptr_nonnull(r);
    ck_assert_uint_eq(r->st.pixels, W * H);
    ck_assert_uint_eq(r->st.changed, 0);
    ck_assert(r->st.mean == 0 && r->st.p99 == 0);
    ck_assert_uint_eq(r->rp.pixels, W * H);
    ck_assert(r->rp.mean == 0 && r->rp.p99 == 0);
    ck_assert(isnan(r->static_mean[0]) && r->static_mean[1] == 0);
    rep_stab_free(st);
    free(st);
    free(a);
    free(b);
}
END_TEST

START_TEST(known_change_known_statistics)
{
    frame *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    make(a, 0, 0, 0, 0, 0, 0, 0);
    make(b, 1, 0, 0, 0, 0, 0, 0);
    /* Two pixels change: one doubles its G channel, one goes from 0 to 1 in R. */
    size_t p = 3 * W + 5, q = 0;
    float g = a->img[3 * p + 1];
    b->img[3 * p + 1] = 2 * g;
    a->img[3 * q] = 0;
    b->img[3 * q] = 1;
    rep_stab_run *st = feed((frame *[]){a, b}, 2);
    rep_stab_buffer *r = rep_stab_find(st, "indirect.radiance");
    double f1 = (double)g / (2.0 * g + REP_STAB_EPS), f2 = 1.0 / (1.0 + REP_STAB_EPS);
    ck_assert_uint_eq(r->st.changed, 2);
    ck_assert_double_eq_tol(r->st.mean, (f1 + f2) / (W * H), 1e-7);
    ck_assert_double_eq_tol(r->st.max, f2, 1e-7);
    /* 128 values, 2 non-zero: the 99th percentile (127th smallest) is the smaller of them. */
    ck_assert_double_eq_tol(r->st.p99, f1, 1e-7);
    ck_assert(rep_stab_flicker((float[]){1, 2, 3}, (float[]){1, 2, 3}, 3) == 0);
    ck_assert(rep_stab_flicker((float[]){NAN}, (float[]){0}, 1) == 1);
    rep_stab_free(st);
    free(st);
    free(a);
    free(b);
}
END_TEST

START_TEST(summarise_nearest_rank)
{
    float v[200];
    for (int i = 0; i < 200; i++)
        v[i] = (float)(199 - i);
    rep_stab_stats s = {0};
    rep_stab_summarise(v, 200, &s);
    ck_assert_double_eq(s.p99, 197); /* ceil(0.99 * 200) = 198th smallest */
    ck_assert_double_eq(s.max, 199);
    ck_assert_double_eq_tol(s.mean, 99.5, 1e-9);
}
END_TEST

START_TEST(reprojection_known_motion_exact)
{
    /* The camera moves 3 pixels right: every pixel shows the point that was 3 pixels to its
     * right, and the image moves with it, so reprojected flicker is exactly zero where the
     * history is on screen and the last 3 columns are off screen. No pixel is static. */
    frame *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    make(a, 0, 0, 0, 0, 0, 0, 0);
    make(b, 1, 3, 0, 0, 0, 0, 0);
    rep_stab_gbuffer ga, gb;
    ck_assert(rep_stab_gbuffer_from_parts(a->parts, 5, &a->info, &ga));
    ck_assert(rep_stab_gbuffer_from_parts(b->parts, 5, &b->info, &gb));
    int32_t src[W * H];
    uint8_t cls[W * H];
    rep_stab_reproject(&ga, &gb, src, cls);
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            size_t k = (size_t)j * W + (size_t)i;
            if (i + 3 < W) {
                ck_assert_int_eq(cls[k], REP_REPRO_VALID);
                ck_assert_int_eq(src[k], j * W + i + 3);
            } else {
                ck_assert_int_eq(cls[k], REP_REPRO_OFFSCREEN);
                ck_assert_int_eq(src[k], -1);
            }
        }
    rep_stab_gbuffer_free(&ga);
    rep_stab_gbuffer_free(&gb);
    rep_stab_run *st = feed((frame *[]){a, b}, 2);
    rep_stab_buffer *r = rep_stab_find(st, "indirect.radiance");
    ck_assert_uint_eq(r->st.pixels, 0);
    ck_assert_uint_eq(r->rp.pixels, (W - 3) * H);
    ck_assert_uint_eq(r->rp.changed, 0);
    ck_assert(r->rp.mean == 0);
    ck_assert_uint_eq(st->classes[REP_REPRO_OFFSCREEN], 3 * H);
    rep_stab_free(st);
    free(st);
    free(a);
    free(b);
}
END_TEST

START_TEST(wrong_motion_is_moving)
{
    /* A motion vector that the camera does not explain belongs to a moving object: left out. */
    frame *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    make(a, 0, 0, 0, 0, 0, 0, 0);
    make(b, 1, 3, 0, 0, 0, 0, 0);
    b->mot[2 * (2 * W + 4)] = 2.0f;
    rep_stab_gbuffer ga, gb;
    ck_assert(rep_stab_gbuffer_from_parts(a->parts, 5, &a->info, &ga));
    ck_assert(rep_stab_gbuffer_from_parts(b->parts, 5, &b->info, &gb));
    int32_t src[W * H];
    uint8_t cls[W * H];
    rep_stab_reproject(&ga, &gb, src, cls);
    ck_assert_int_eq(cls[2 * W + 4], REP_REPRO_MOVING);
    ck_assert_int_eq(cls[2 * W + 5], REP_REPRO_VALID);
    rep_stab_gbuffer_free(&ga);
    rep_stab_gbuffer_free(&gb);
    free(a);
    free(b);
}
END_TEST

START_TEST(disocclusion_masked)
{
    /* Static camera; an occluder (id 1) covered columns 4..7 and now covers 8..11: columns 4..7
     * are disoccluded (the previous frame shows the occluder there), the occluder's own pixels
     * moved (left out), the rest are static and valid. The background's shading is unchanged,
     * so every valid pixel has zero flicker even though the occluder's pixels changed a lot. */
    frame *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    make(a, 0, 0, 0, 4, 8, 4, 8);
    make(b, 1, 0, 0, 8, 12, 4, 8);
    rep_stab_gbuffer ga, gb;
    ck_assert(rep_stab_gbuffer_from_parts(a->parts, 5, &a->info, &ga));
    ck_assert(rep_stab_gbuffer_from_parts(b->parts, 5, &b->info, &gb));
    int32_t src[W * H];
    uint8_t cls[W * H];
    rep_stab_reproject(&ga, &gb, src, cls);
    for (int i = 0; i < W; i++) {
        int want = i >= 4 && i < 8 ? REP_REPRO_DISOCCLUDED : i >= 8 && i < 12 ? REP_REPRO_MOVING : REP_REPRO_VALID;
        ck_assert_int_eq(cls[W + i], want);
    }
    rep_stab_gbuffer_free(&ga);
    rep_stab_gbuffer_free(&gb);
    rep_stab_run *st = feed((frame *[]){a, b}, 2);
    rep_stab_buffer *r = rep_stab_find(st, "indirect.radiance");
    ck_assert_uint_eq(r->rp.pixels, 8 * H);
    ck_assert(r->rp.mean == 0);
    /* static pixels: where nothing covered the background in either frame (8 columns) */
    ck_assert_uint_eq(r->st.pixels, 8 * H);
    ck_assert(r->st.mean == 0);
    rep_stab_free(st);
    free(st);
    free(a);
    free(b);
}
END_TEST

START_TEST(disocclusion_same_id_by_position)
{
    /* Same material id on both sides: the position test alone must catch the disocclusion. */
    frame *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    make(a, 0, 0, 0, 4, 8, 4, 8);
    make(b, 1, 0, 0, 8, 12, 4, 8);
    for (int k = 0; k < W * H; k++)
        a->mat[5 * k + 4] = b->mat[5 * k + 4] = 0;
    rep_stab_gbuffer ga, gb;
    ck_assert(rep_stab_gbuffer_from_parts(a->parts, 5, &a->info, &ga));
    ck_assert(rep_stab_gbuffer_from_parts(b->parts, 5, &b->info, &gb));
    int32_t src[W * H];
    uint8_t cls[W * H];
    rep_stab_reproject(&ga, &gb, src, cls);
    ck_assert_int_eq(cls[W + 5], REP_REPRO_DISOCCLUDED);
    ck_assert_int_eq(cls[W + 1], REP_REPRO_VALID);
    /* a flipped normal at the same place (the other side of a thin wall) is another surface */
    for (int k = 0; k < W * H; k++)
        ga.normal[3 * k + 2] = -1;
    rep_stab_reproject(&ga, &gb, src, cls);
    ck_assert_int_eq(cls[W + 1], REP_REPRO_DISOCCLUDED);
    rep_stab_gbuffer_free(&ga);
    rep_stab_gbuffer_free(&gb);
    free(a);
    free(b);
}
END_TEST

START_TEST(reference_temporal_std)
{
    /* Frames alternate between reference + 0.1 and reference − 0.1 in R: std 0.1, bias 0. */
    frame *f[4];
    frame *ref = malloc(sizeof *ref);
    make(ref, 0, 0, 0, 0, 0, 0, 0);
    ref->parts[4].name = "reference.indirect";
    rep_stab_run *st = calloc(1, sizeof *st);
    st->frame_count = 4;
    for (int i = 0; i < 4; i++) {
        f[i] = malloc(sizeof *f[i]);
        make(f[i], i, 0, 0, 0, 0, 0, 0);
        for (int k = 0; k < W * H; k++)
            f[i]->img[3 * k] += i % 2 ? -0.1f : 0.1f;
        ck_assert_int_eq(rep_stab_frame(st, &f[i]->info, f[i]->parts, 5, ref->parts, 5, NULL, NULL), 1);
    }
    rep_stab_finish(st);
    rep_stab_buffer *r = rep_stab_find(st, "indirect.radiance");
    ck_assert_str_eq(r->reference, "reference.indirect");
    ck_assert_int_eq(r->ref_frames, 4);
    ck_assert_double_eq_tol(r->tstd_mean, 0.1, 1e-6);
    ck_assert_double_eq_tol(r->tstd_p99, 0.1, 1e-6);
    ck_assert_double_eq_tol(r->bias_mean, 0, 1e-6);
    rep_stab_free(st);
    free(st);
    for (int i = 0; i < 4; i++)
        free(f[i]);
    free(ref);
}
END_TEST

START_TEST(tolerance_stability_strict)
{
    const char *ok = "{\"buffers\": [{\"match\": \"indirect.*\", \"stability\": {\"static_mean\": 0.01, \"golden_margin\": 0.1}}]}";
    rep_tolerances *t = NULL;
    eng_error err;
    ck_assert_int_eq(rep_tol_parse("t.json", ok, strlen(ok), &t, &err), ENG_OK);
    rep_tol tol;
    rep_tol_lookup(t, "indirect.radiance", &tol);
    ck_assert(tol.stab.set);
    ck_assert_double_eq(tol.stab.static_mean, 0.01);
    ck_assert(isinf(tol.stab.static_p99));
    ck_assert_double_eq(tol.stab.golden_margin, 0.1);
    rep_tol_lookup(t, "direct.radiance", &tol);
    ck_assert(!tol.stab.set);
    rep_tol_free(t);
    const char *bad[] = {
        "{\"buffers\": [{\"match\": \"x\", \"stability\": {\"static_maen\": 0.01}}]}",
        "{\"buffers\": [{\"match\": \"x\", \"stability\": {\"static_mean\": -1}}]}",
        "{\"buffers\": [{\"match\": \"x\", \"stability\": {\"static_mean\": \"0\"}}]}",
        "{\"buffers\": [{\"match\": \"x\", \"stability\": {}}]}",
        "{\"buffers\": [{\"match\": \"x\", \"stability\": 3}]}",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        ck_assert_int_eq(rep_tol_parse("t.json", bad[i], strlen(bad[i]), &t, &err), ENG_ERR_INVALID);
        ck_assert_ptr_null(t);
        ck_assert_ptr_null(strchr(err.msg, '\n'));
    }
}
END_TEST

START_TEST(judge_limits_and_golden_margin)
{
    frame *a = malloc(sizeof *a), *b = malloc(sizeof *b);
    make(a, 0, 0, 0, 0, 0, 0, 0);
    make(b, 1, 0, 0, 0, 0, 0, 0);
    b->img[0] += 0.05f; /* some flicker in the run */
    rep_stab_report *s = calloc(1, sizeof *s);
    rep_stab_run *run = feed((frame *[]){a, b}, 2);
    rep_stab_run *g = feed((frame *[]){a, a}, 2); /* the golden does not flicker */
    s->run = *run;
    s->golden = *g;
    free(run);
    free(g);
    s->has_golden = 1;
    const char *lim = "{\"buffers\": [{\"match\": \"indirect.radiance\", \"stability\": {\"static_mean\": 1}}]}";
    const char *mar = "{\"buffers\": [{\"match\": \"indirect.radiance\", \"stability\": {\"golden_margin\": 0.5}}]}";
    const char *tight = "{\"buffers\": [{\"match\": \"*\", \"stability\": {\"static_p99\": 0, \"static_mean\": 1e-9}}]}";
    const char *cases[] = {lim, mar, tight};
    const int want[] = {0, 1, 1};
    for (int c = 0; c < 3; c++) {
        rep_tolerances *t = NULL;
        eng_error err;
        ck_assert_int_eq(rep_tol_parse("t.json", cases[c], strlen(cases[c]), &t, &err), ENG_OK);
        rep_stab_judge(s, t);
        ck_assert_int_eq(s->failed, want[c]);
        ck_assert_int_eq(s->verdicts[0].checked, 1);
        for (int k = 0; k < s->run.buffer_count; k++) {
            free(s->verdicts[k].tol_match);
            free(s->verdicts[k].why);
        }
        free(s->verdicts);
        s->verdicts = NULL;
        rep_tol_free(t);
    }
    rep_stab_report_free(s);
    free(a);
    free(b);
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("stability");
    TCase *tc = tcase_create("metrics");
    tcase_add_test(tc, identical_frames_zero);
    tcase_add_test(tc, known_change_known_statistics);
    tcase_add_test(tc, summarise_nearest_rank);
    tcase_add_test(tc, reprojection_known_motion_exact);
    tcase_add_test(tc, wrong_motion_is_moving);
    tcase_add_test(tc, disocclusion_masked);
    tcase_add_test(tc, disocclusion_same_id_by_position);
    tcase_add_test(tc, reference_temporal_std);
    tcase_add_test(tc, tolerance_stability_strict);
    tcase_add_test(tc, judge_limits_and_golden_margin);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
