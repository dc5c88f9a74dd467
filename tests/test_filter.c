/* test_filter.c — Check suite of the reconstruction filters (engine/passes/pass_filter.c and the
 * shaders upsample/temporal/atrous/resolve): each filter on synthetic G-buffers and images with
 * known answers (constant images stay constant, depth and normal edges stop the filters, a
 * step survives variance clipping, the temporal filter is exactly the EMA of Eq. 7.3 and
 * rejects disocclusions), then the engine with every filter on: the announced levels, the
 * disocclusion behind the moving box, and that rendering out of order (record --resume)
 * gives the same temporal result as rendering in order.
 *
 * Synthetic textures are written and read in GL's row order (row 0 at the bottom): only the
 * engine-level tests look at announced (top row first) buffers. */
#include "eng.h"
#include "passes.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CORNELL_GLTF ISPM_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define W 32
#define H 16

static eng_glctx *ctx;

static void gl_setup(void)
{
    eng_error err;
    eng_pin_determinism(2);
    ck_assert_msg(glctx_create(&ctx, &err) == ENG_OK, "%s", err.msg);
}

static void gl_teardown(void)
{
    glctx_destroy(ctx);
    ctx = NULL;
}

static void upload(GLuint tex, int w, int h, const float *rgba)
{
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, rgba);
}

static float *download(GLuint tex, int w, int h)
{
    float *rgba = malloc((size_t)w * h * 4 * sizeof(float));
    glBindTexture(GL_TEXTURE_2D, tex);
    glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, rgba);
    return rgba;
}

/* A synthetic G-buffer: per texel a normal, an eye depth, the depth the point had in the
 * previous frame, and a motion vector (image pixels, y down). Albedo 0.5 grey, Lambertian. */
typedef struct gb_texel {
    float n[3], z, prev_z, motion[2];
} gb_texel;

static void make_gbuffer(glu_target *gb, int w, int h, gb_texel (*at)(int x, int y, void *u), void *u)
{
    eng_error err;
    ck_assert_msg(glu_target_create(gb, 5, w, h, 0, &err) == ENG_OK, "%s", err.msg);
    size_t n = (size_t)w * h * 4;
    float *pos = calloc(n, sizeof(float)), *nrm = calloc(n, sizeof(float)), *alb = calloc(n, sizeof(float));
    float *mat = calloc(n, sizeof(float)), *misc = calloc(n, sizeof(float));
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = ((size_t)y * w + x) * 4;
            gb_texel t = at(x, y, u);
            pos[i + 0] = (float)x;
            pos[i + 1] = (float)y;
            pos[i + 2] = -t.z;
            pos[i + 3] = 1.0f;
            memcpy(nrm + i, t.n, sizeof t.n);
            nrm[i + 3] = t.prev_z;
            alb[i] = alb[i + 1] = alb[i + 2] = 0.5f;
            mat[i] = 1.0f;   /* roughness */
            mat[i + 3] = 1.5f;
            misc[i] = t.z;
            misc[i + 1] = 0.0f; /* material id */
            misc[i + 2] = t.motion[0];
            misc[i + 3] = t.motion[1];
        }
    float *all[5] = {pos, nrm, alb, mat, misc};
    for (int a = 0; a < 5; a++) {
        upload(gb->color[a], w, h, all[a]);
        free(all[a]);
    }
}

static gb_texel plane(int x, int y, void *u)
{
    (void)y;
    (void)u;
    /* a plane sloping away in x: depth changes by 1 cm per pixel */
    gb_texel t = {{0, 0, 1}, 2.0f + 0.01f * (float)x, 2.0f + 0.01f * (float)x, {0, 0}};
    return t;
}

static gb_texel normal_edge(int x, int y, void *u)
{
    gb_texel t = plane(x, y, u);
    if (x >= W / 2) {
        t.n[0] = 1.0f;
        t.n[2] = 0.0f;
    }
    return t;
}

static gb_texel depth_edge(int x, int y, void *u)
{
    gb_texel t = plane(x, y, u);
    if (x >= W / 2)
        t.z = t.prev_z = t.z + 1.0f;
    return t;
}

/* An RGBA image from a function of (x, y). */
static GLuint image(glu_target *holder, int w, int h, float (*f)(int x, int y, int c))
{
    eng_error err;
    ck_assert_msg(glu_target_create(holder, 1, w, h, 0, &err) == ENG_OK, "%s", err.msg);
    float *px = malloc((size_t)w * h * 4 * sizeof(float));
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 4; c++)
                px[((size_t)y * w + x) * 4 + c] = c < 3 ? f(x, y, c) : 0.0f;
    upload(holder->color[0], w, h, px);
    free(px);
    return holder->color[0];
}

static float constant(int x, int y, int c)
{
    (void)x;
    (void)y;
    return 0.25f + 0.25f * (float)c;
}

static float step_image(int x, int y, int c)
{
    (void)y;
    (void)c;
    return x < W / 2 ? 1.0f : 0.0f;
}

static uint64_t noise_state;
static float noise(int x, int y, int c)
{
    (void)x;
    (void)y;
    (void)c;
    noise_state = noise_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return 0.5f + ((float)(noise_state >> 40) / (float)(1 << 24) - 0.5f);
}

static double img_std(const float *rgba, int w, int h, int c)
{
    double s = 0, s2 = 0;
    for (int i = 0; i < w * h; i++) {
        s += rgba[i * 4 + c];
        s2 += (double)rgba[i * 4 + c] * rgba[i * 4 + c];
    }
    s /= w * h;
    return sqrt(fmax(s2 / (w * h) - s * s, 0.0));
}

/* ---------------------------------------------------------------- À-Trous */

static float *run_atrous(gb_texel (*geo)(int, int, void *), float (*img)(int, int, int), int iterations,
                         eng_atrous_detail detail, float gamma, float **input)
{
    eng_error err;
    glu_target gb, in;
    make_gbuffer(&gb, W, H, geo, NULL);
    GLuint tex = image(&in, W, H, img);
    pass_atrous *p;
    ck_assert_msg(pass_atrous_create(W, H, iterations, &p, &err) == ENG_OK, "%s", err.msg);
    const glu_target *lv = pass_atrous_run(p, &gb, tex, detail, gamma);
    float *out = download(lv[iterations - 1].color[3], W, H);
    if (input)
        *input = download(tex, W, H);
    pass_atrous_destroy(p);
    glu_target_destroy(&gb);
    glu_target_destroy(&in);
    return out;
}

START_TEST(atrous_keeps_a_constant_image)
{
    for (int mode = 0; mode < 3; mode++) {
        eng_atrous_detail d = mode == 0 ? ENG_DETAIL_CLIPPED : mode == 1 ? ENG_DETAIL_NONE : ENG_DETAIL_ALL;
        float *out = run_atrous(plane, constant, 4, d, 0.05f, NULL);
        for (int i = 0; i < W * H; i++)
            for (int c = 0; c < 3; c++)
                ck_assert_msg(fabsf(out[i * 4 + c] - constant(0, 0, c)) < 1e-6f, "mode %d texel %d: %g", mode, i,
                              out[i * 4 + c]);
        free(out);
    }
}
END_TEST

START_TEST(atrous_stops_at_normal_and_depth_edges)
{
    /* Control: on a plane the scaling coefficients blur the step ... */
    float *blur = run_atrous(plane, step_image, 3, ENG_DETAIL_NONE, 0.05f, NULL);
    int left = (H / 2) * W + W / 2 - 1, right = left + 1;
    ck_assert_msg(blur[left * 4] < 0.85f && blur[right * 4] > 0.15f, "no blur on a plane: %g %g", blur[left * 4],
                  blur[right * 4]);
    free(blur);
    /* ... but nothing crosses a normal edge (w_n = 0 for perpendicular normals) or a 1 m depth
     * edge (w_z = exp(−1/(ε z)) = 0), whatever the iteration's step. */
    gb_texel (*geos[2])(int, int, void *) = {normal_edge, depth_edge};
    for (int g = 0; g < 2; g++) {
        float *out = run_atrous(geos[g], step_image, 3, ENG_DETAIL_NONE, 0.05f, NULL);
        for (int i = 0; i < W * H; i++) {
            float want = (i % W) < W / 2 ? 1.0f : 0.0f;
            ck_assert_msg(fabsf(out[i * 4] - want) < 1e-6f, "edge %d texel (%d,%d): %g", g, i % W, i / W, out[i * 4]);
        }
        free(out);
    }
}
END_TEST

START_TEST(atrous_variance_clipping_keeps_a_step)
{
    /* All details kept: the transform reconstructs its input (Eq. 7.6). */
    noise_state = 7;
    float *in = NULL;
    float *all = run_atrous(plane, noise, 4, ENG_DETAIL_ALL, 0.05f, &in);
    for (int i = 0; i < W * H * 4; i++)
        if (i % 4 != 3)
            ck_assert_msg(fabsf(all[i] - in[i]) < 1e-5f, "reconstruction %d: %g vs %g", i, all[i], in[i]);
    free(all);
    free(in);
    /* A step has a large local σ, so its detail coefficients survive clipping at γ = 3 … */
    float *kept = run_atrous(plane, step_image, 3, ENG_DETAIL_CLIPPED, 3.0f, NULL);
    for (int i = 0; i < W * H; i++) {
        float want = (i % W) < W / 2 ? 1.0f : 0.0f;
        ck_assert_msg(fabsf(kept[i * 4] - want) < 1e-4f, "step lost at (%d,%d): %g", i % W, i / W, kept[i * 4]);
    }
    free(kept);
    /* … while low-amplitude noise is still smoothed at a small γ. */
    noise_state = 11;
    float *smooth = run_atrous(plane, noise, 4, ENG_DETAIL_CLIPPED, 0.05f, &in);
    double ratio = img_std(smooth, W, H, 0) / img_std(in, W, H, 0);
    ck_assert_msg(ratio < 0.5, "noise std ratio %.3f", ratio);
    free(smooth);
    free(in);
}
END_TEST

/* ---------------------------------------------------------------- upsampling */

static gb_texel depth_edge_half(int x, int y, void *u)
{
    /* the same scene at half resolution: x maps to 2x + 0.5 at full resolution */
    (void)u;
    gb_texel t = {{0, 0, 1}, 2.0f, 2.0f, {0, 0}};
    (void)y;
    if (2 * x + 1 >= W / 2)
        t.z = t.prev_z = 3.0f;
    return t;
}

static gb_texel depth_edge_full(int x, int y, void *u)
{
    (void)u;
    (void)y;
    gb_texel t = {{0, 0, 1}, 2.0f, 2.0f, {0, 0}};
    if (x >= W / 2)
        t.z = t.prev_z = 3.0f;
    return t;
}

static float step_half(int x, int y, int c)
{
    (void)y;
    (void)c;
    return 2 * x + 1 < W / 2 ? 1.0f : 0.0f;
}

START_TEST(upsampling_keeps_constants_and_edges)
{
    eng_error err;
    glu_target lo, hi, irr, glossy;
    pass_upsample *p;
    ck_assert_msg(pass_upsample_create(W, H, &p, &err) == ENG_OK, "%s", err.msg);
    /* Constant irradiance on a plane stays constant. */
    make_gbuffer(&lo, W / 2, H / 2, plane, NULL);
    make_gbuffer(&hi, W, H, plane, NULL);
    GLuint e = image(&irr, W / 2, H / 2, constant), g = image(&glossy, W / 2, H / 2, constant);
    const glu_target *t = pass_upsample_run(p, &lo, e, g, &hi);
    float *out = download(t->color[0], W, H);
    for (int i = 0; i < W * H; i++)
        for (int c = 0; c < 3; c++)
            ck_assert_msg(fabsf(out[i * 4 + c] - constant(0, 0, c)) < 1e-6f, "texel %d: %g", i, out[i * 4 + c]);
    free(out);
    glu_target_destroy(&lo);
    glu_target_destroy(&hi);
    glu_target_destroy(&irr);
    glu_target_destroy(&glossy);
    /* Across a depth edge each side keeps its own value, where bilinear would mix them. */
    make_gbuffer(&lo, W / 2, H / 2, depth_edge_half, NULL);
    make_gbuffer(&hi, W, H, depth_edge_full, NULL);
    e = image(&irr, W / 2, H / 2, step_half);
    g = image(&glossy, W / 2, H / 2, step_half);
    t = pass_upsample_run(p, &lo, e, g, &hi);
    out = download(t->color[0], W, H);
    for (int i = 0; i < W * H; i++) {
        float want = (i % W) < W / 2 ? 1.0f : 0.0f;
        ck_assert_msg(fabsf(out[i * 4] - want) < 1e-6f, "texel (%d,%d): %g", i % W, i / W, out[i * 4]);
    }
    free(out);
    glu_target_destroy(&lo);
    glu_target_destroy(&hi);
    glu_target_destroy(&irr);
    glu_target_destroy(&glossy);
    pass_upsample_destroy(p);
}
END_TEST

/* ---------------------------------------------------------------- temporal */

static gb_texel moved_right(int x, int y, void *u)
{
    /* the camera moved: every pixel's surface point was 3 pixels to the right last frame */
    gb_texel t = plane(x, y, u);
    t.z = t.prev_z = 2.0f;
    t.motion[0] = 3.0f;
    return t;
}

static gb_texel flat(int x, int y, void *u)
{
    gb_texel t = plane(x, y, u);
    t.z = t.prev_z = 2.0f;
    return t;
}

static gb_texel uncovered(int x, int y, void *u)
{
    /* the left half was hidden last frame behind something 1 m closer: prev depth says 2 m,
     * but the previous frame's depth buffer there held 1 m */
    gb_texel t = flat(x, y, u);
    (void)t;
    return t;
}

static gb_texel occluder(int x, int y, void *u)
{
    gb_texel t = flat(x, y, u);
    if (x < W / 2)
        t.z = t.prev_z = 1.0f;
    return t;
}

static float ramp(int x, int y, int c)
{
    (void)y;
    (void)c;
    return (float)x;
}

static float zero_image(int x, int y, int c)
{
    (void)x;
    (void)y;
    (void)c;
    return 0.0f;
}

START_TEST(temporal_is_the_ema_of_eq_7_3)
{
    eng_error err;
    glu_target gb, in;
    pass_temporal *p;
    ck_assert_msg(pass_temporal_create(W, H, &p, &err) == ENG_OK, "%s", err.msg);
    make_gbuffer(&gb, W, H, flat, NULL);
    const float alpha = 0.95f;
    double *ema = calloc((size_t)W * H * 4, sizeof(double));
    double *mean = calloc((size_t)W * H * 4, sizeof(double));
    float *first = NULL, *last = NULL;
    const int frames = 60;
    noise_state = 3;
    for (int k = 0; k < frames; k++) {
        GLuint tex = image(&in, W, H, noise);
        float *e = download(tex, W, H);
        const glu_target *t = pass_temporal_run(p, &gb, tex, alpha);
        float *s = download(t->color[0], W, H);
        for (int i = 0; i < W * H * 4; i++) {
            if (i % 4 == 3)
                continue;
            ema[i] = k == 0 ? e[i] : (1.0 - alpha) * e[i] + alpha * ema[i];
            mean[i] += e[i] / frames;
            ck_assert_msg(fabs(s[i] - ema[i]) < 1e-5 * fmax(1.0, fabs(ema[i])), "frame %d value %d: %g vs %g", k, i,
                          s[i], ema[i]);
        }
        for (int i = 0; i < W * H; i++)
            ck_assert_float_eq_tol(s[i * 4 + 3], k == 0 ? 0.0f : alpha, 1e-6f); /* α of Eq. 7.4 */
        if (k == 0)
            first = e;
        else
            free(e);
        free(last);
        last = s;
        glu_target_destroy(&in);
    }
    /* Converged toward the mean of the inputs: the spread is a fraction of one frame's. */
    double spread = 0.0;
    for (int i = 0; i < W * H; i++)
        spread += fabs(last[i * 4] - mean[i * 4]) / (W * H);
    ck_assert_msg(img_std(last, W, H, 0) < 0.3 * img_std(first, W, H, 0), "std %g vs %g", img_std(last, W, H, 0),
                  img_std(first, W, H, 0));
    ck_assert_msg(spread < 0.05, "mean distance to the per-pixel mean %g", spread);
    free(first);
    free(last);
    free(ema);
    free(mean);
    glu_target_destroy(&gb);
    pass_temporal_destroy(p);
}
END_TEST

START_TEST(temporal_reprojects_and_rejects_disocclusions)
{
    eng_error err;
    glu_target gb, in;
    pass_temporal *p;
    ck_assert_msg(pass_temporal_create(W, H, &p, &err) == ENG_OK, "%s", err.msg);
    /* Frame A: a ramp, no history. Frame B: zero input, motion +3 px: the history is the ramp
     * three pixels to the right, weighted by α = 0.95. */
    make_gbuffer(&gb, W, H, flat, NULL);
    pass_temporal_run(p, &gb, image(&in, W, H, ramp), 0.95f);
    glu_target_destroy(&in);
    glu_target_destroy(&gb);
    make_gbuffer(&gb, W, H, moved_right, NULL);
    const glu_target *t = pass_temporal_run(p, &gb, image(&in, W, H, zero_image), 0.95f);
    float *s = download(t->color[0], W, H);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            float *v = s + ((size_t)y * W + x) * 4;
            if (x + 3 < W)
                ck_assert_msg(fabsf(v[0] - 0.95f * (float)(x + 3)) < 1e-4f && v[3] == 0.95f, "(%d,%d): %g α %g", x,
                              y, v[0], v[3]);
            else /* reprojected outside the previous image: no history */
                ck_assert_msg(v[0] == 0.0f && v[3] == 0.0f, "(%d,%d): %g α %g", x, y, v[0], v[3]);
        }
    free(s);
    glu_target_destroy(&in);
    glu_target_destroy(&gb);
    /* Disocclusion: last frame an occluder 1 m closer covered the left half; now the plane at
     * 2 m shows there. Its previous-frame depth (2 m) does not match what the previous depth
     * buffer holds (1 m): α = 0 on the left, full history on the right. */
    pass_temporal_reset(p);
    make_gbuffer(&gb, W, H, occluder, NULL);
    pass_temporal_run(p, &gb, image(&in, W, H, ramp), 0.95f);
    glu_target_destroy(&in);
    glu_target_destroy(&gb);
    make_gbuffer(&gb, W, H, uncovered, NULL);
    t = pass_temporal_run(p, &gb, image(&in, W, H, zero_image), 0.95f);
    s = download(t->color[0], W, H);
    for (int i = 0; i < W * H; i++) {
        int x = i % W;
        if (x < W / 2)
            ck_assert_msg(s[i * 4 + 3] < 1e-6f && s[i * 4] < 1e-6f, "disoccluded (%d,%d) kept history: α %g", x, i / W,
                          s[i * 4 + 3]);
        else
            ck_assert_msg(fabsf(s[i * 4 + 3] - 0.95f) < 1e-6f, "static (%d,%d) lost history: α %g", x, i / W,
                          s[i * 4 + 3]);
    }
    free(s);
    glu_target_destroy(&in);
    glu_target_destroy(&gb);
    pass_temporal_destroy(p);
}
END_TEST

START_TEST(resolve_applies_the_diffuse_bsdf)
{
    eng_error err;
    glu_target gb, irr, glossy;
    pass_resolve *p;
    ck_assert_msg(pass_resolve_create(W, H, &p, &err) == ENG_OK, "%s", err.msg);
    make_gbuffer(&gb, W, H, plane, NULL);
    GLuint e = image(&irr, W, H, constant), g = image(&glossy, W, H, ramp);
    float *out = download(pass_resolve_run(p, &gb, e, g)->color[0], W, H);
    for (int i = 0; i < W * H; i++)
        for (int c = 0; c < 3; c++) {
            double want = 0.5 / 3.14159265358979323846 * constant(0, 0, c) + (double)(i % W);
            ck_assert_msg(fabs(out[i * 4 + c] - want) < 1e-5 * fmax(1.0, want), "texel %d: %g vs %g", i,
                          out[i * 4 + c], want);
        }
    free(out);
    glu_target_destroy(&gb);
    glu_target_destroy(&irr);
    glu_target_destroy(&glossy);
    pass_resolve_destroy(p);
}
END_TEST

/* ---------------------------------------------------------------- the engine with filters */

typedef struct grab {
    const char *want[8];
    float *data[8];
    int w[8], h[8], n[8];
    int count;
    char names[64][64];
} grab;

static int grab_buffer(void *user, int frame, const eng_buffer *b)
{
    (void)frame;
    grab *g = user;
    if (g->count < 64)
        snprintf(g->names[g->count++], 64, "%s", b->name);
    for (int i = 0; i < 8 && g->want[i]; i++)
        if (!strcmp(g->want[i], b->name)) {
            size_t n = (size_t)b->width * b->height * b->channel_count;
            free(g->data[i]);
            g->data[i] = malloc(n * sizeof(float));
            memcpy(g->data[i], b->data, n * sizeof(float));
            g->w[i] = b->width;
            g->h[i] = b->height;
            g->n[i] = b->channel_count;
        }
    return 0;
}

static void grab_free(grab *g)
{
    for (int i = 0; i < 8; i++)
        free(g->data[i]);
    memset(g->data, 0, sizeof g->data);
    g->count = 0;
}

static int grabbed(const grab *g, const char *name)
{
    for (int i = 0; i < g->count; i++)
        if (!strcmp(g->names[i], name))
            return 1;
    return 0;
}

typedef struct engine_fixture {
    seq_sequence seq;
    scn_scene *scene;
    eng_engine *eng;
} engine_fixture;

static void engine_open(engine_fixture *f, grab *g, int size, const char *settings)
{
    char json[1024];
    snprintf(json, sizeof json,
             "{\"name\":\"filters\",\"scene\":\"%s\",\"frames\":8,\"fps\":8,\"resolution\":[%d,%d],"
             "\"camera\":{\"node\":\"Camera\"},\"settings\":{\"shadow_map_size\":128,\"photon_count\":2048,"
             "\"kernel_radius\":0.2,%s}}",
             CORNELL_GLTF, size, size, settings);
    eng_error err;
    memset(f, 0, sizeof *f);
    ck_assert_msg(seq_parse("filters.json", json, strlen(json), &f->seq, &err) == ENG_OK, "%s", err.msg);
    ck_assert_msg(scn_load_gltf(f->seq.scene_path, &f->scene, &err) == ENG_OK, "%s", err.msg);
    eng_desc d = {.scene = f->scene, .sequence = &f->seq};
    ck_assert_msg(eng_create(&d, &f->eng, &err) == ENG_OK, "%s", err.msg);
    eng_listener l = {g, NULL, grab_buffer, NULL};
    ck_assert_int_eq(eng_add_listener(f->eng, &l), ENG_OK);
}

static void engine_close(engine_fixture *f)
{
    eng_destroy(f->eng);
    scn_destroy(f->scene);
}

START_TEST(engine_announces_every_filter_level)
{
    grab g = {.want = {NULL}};
    engine_fixture f;
    engine_open(&f, &g, 64,
                "\"splat_subsample\":4,\"temporal\":true,\"atrous_iterations\":2,\"atrous_detail\":\"clipped\"");
    eng_error err;
    ck_assert_msg(eng_render_frame(f.eng, 0, &err) == ENG_OK, "%s", err.msg);
    const char *names[] = {"gbuffer.level1.position", "gbuffer.level2.depth", "splat.irradiance", "splat.count",
                           "splat.glossy", "upsample.level1", "upsample.level0", "temporal.history",
                           "temporal.alpha", "temporal.result", "atrous.scale1", "atrous.detail0",
                           "atrous.scale2", "atrous.detail1", "atrous.result", "indirect.radiance",
                           "composite.radiance"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        ck_assert_msg(grabbed(&g, names[i]), "%s not announced", names[i]);
    ck_assert_msg(!grabbed(&g, "splat.indirect"), "the filtered path splats irradiance, not radiance");
    grab_free(&g);
    engine_close(&f);
}
END_TEST

START_TEST(engine_temporal_rejects_the_box_disocclusion)
{
    /* The short box slides and the camera dollies: floor pixels whose reprojected texel showed
     * another surface (the box, > 5 cm away) in the previous frame must take no history (α = 0); floor pixels whose reprojected neighbourhood showed
     * the floor keep α ≈ 0.95. The floor is the static plane y = 0. */
    const int S = 96;
    grab g = {.want = {"temporal.alpha", "gbuffer.position", "gbuffer.motion", NULL}};
    engine_fixture f;
    engine_open(&f, &g, S, "\"temporal\":true");
    eng_error err;
    int disoccluded = 0, kept = 0, floor_px = 0;
    for (int frame = 1; frame < 8; frame++) {
        ck_assert_msg(eng_render_frame(f.eng, frame - 1, &err) == ENG_OK, "%s", err.msg);
        float *prev = malloc(sizeof(float) * S * S * 3);
        memcpy(prev, g.data[1], sizeof(float) * S * S * 3);
        ck_assert_msg(eng_render_frame(f.eng, frame, &err) == ENG_OK, "%s", err.msg);
        const float *alpha = g.data[0], *pos = g.data[1], *motion = g.data[2];
        for (int y = 2; y < S - 2; y++)
            for (int x = 2; x < S - 2; x++) {
                int i = y * S + x;
                if (fabsf(pos[i * 3 + 1]) > 1e-4f || pos[i * 3 + 2] == 0.0f) /* not the floor */
                    continue;
                int qx = (int)floorf(x + 0.5f + motion[2 * i]), qy = (int)floorf(y + 0.5f + motion[2 * i + 1]);
                if (qx < 1 || qy < 1 || qx >= S - 1 || qy >= S - 1)
                    continue;
                /* what the previous frame showed at q, and around it */
                const float *pq = prev + ((size_t)qy * S + qx) * 3;
                float d = sqrtf((pq[0] - pos[i * 3]) * (pq[0] - pos[i * 3]) + (pq[1] - pos[i * 3 + 1]) * (pq[1] - pos[i * 3 + 1]) +
                                (pq[2] - pos[i * 3 + 2]) * (pq[2] - pos[i * 3 + 2]));
                int on_floor = 0;
                for (int dy = -1; dy <= 1; dy++)
                    for (int dx = -1; dx <= 1; dx++)
                        on_floor += fabsf(prev[((qy + dy) * S + qx + dx) * 3 + 1]) < 1e-4f;
                if (d > 0.05f) { /* q showed another surface (the box): p was hidden */
                    disoccluded++;
                    ck_assert_msg(alpha[i] < 1e-3f, "frame %d: disoccluded (%d,%d) took history: α %g", frame, x, y,
                                  alpha[i]);
                } else if (on_floor == 9) {
                    floor_px++;
                    kept += alpha[i] > 0.9f;
                }
            }
        free(prev);
    }
    ck_assert_int_gt(disoccluded, 0);
    ck_assert_msg(kept > 0.95 * floor_px, "only %d of %d floor pixels kept their history", kept, floor_px);
    grab_free(&g);
    engine_close(&f);
}
END_TEST

START_TEST(engine_out_of_order_matches_in_order)
{
    const char *settings = "\"splat_subsample\":2,\"temporal\":true,\"atrous_iterations\":2";
    grab a = {.want = {"temporal.result", "indirect.radiance", NULL}}, b = a;
    engine_fixture fa, fb;
    eng_error err;
    engine_open(&fa, &a, 48, settings);
    for (int k = 0; k <= 4; k++) {
        a.count = 0;
        ck_assert_msg(eng_render_frame(fa.eng, k, &err) == ENG_OK, "%s", err.msg);
    }
    engine_open(&fb, &b, 48, settings);
    ck_assert_msg(eng_render_frame(fb.eng, 4, &err) == ENG_OK, "%s", err.msg); /* as a resumed run would */
    ck_assert_int_eq(b.count, a.count); /* frames 0–3 were rendered without announcing */
    for (int i = 0; i < 2; i++)
        ck_assert_msg(memcmp(a.data[i], b.data[i], sizeof(float) * 48 * 48 * 3) == 0, "%s differs", a.want[i]);
    grab_free(&a);
    grab_free(&b);
    engine_close(&fa);
    engine_close(&fb);
}
END_TEST

static Suite *filter_suite(void)
{
    Suite *s = suite_create("filter");
    TCase *tc = tcase_create("synthetic");
    tcase_add_checked_fixture(tc, gl_setup, gl_teardown);
    tcase_add_test(tc, atrous_keeps_a_constant_image);
    tcase_add_test(tc, atrous_stops_at_normal_and_depth_edges);
    tcase_add_test(tc, atrous_variance_clipping_keeps_a_step);
    tcase_add_test(tc, upsampling_keeps_constants_and_edges);
    tcase_add_test(tc, temporal_is_the_ema_of_eq_7_3);
    tcase_add_test(tc, temporal_reprojects_and_rejects_disocclusions);
    tcase_add_test(tc, resolve_applies_the_diffuse_bsdf);
    suite_add_tcase(s, tc);
    TCase *te = tcase_create("engine");
    tcase_set_timeout(te, 600);
    tcase_add_test(te, engine_announces_every_filter_level);
    tcase_add_test(te, engine_temporal_rejects_the_box_disocclusion);
    tcase_add_test(te, engine_out_of_order_matches_in_order);
    suite_add_tcase(s, te);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(filter_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
