/* test_progressive.c — Check suite of the convergence features: progressive
 * accumulation (engine/indirect/progressive.c: running mean, bit-wise restarts, PPM's radius shrink),
 * the kernel scalings of ind_photon_radii (engine/indirect/ind_common.c; 002 Eq. 6.1, 6.2, 004 §6) on
 * hand-made photon maps, and the bench's bias measures (replay/compare/metrics.c: rep_metric_bias,
 * rep_edge_mask). No GL: these are CPU functions. */
#include "eng.h"
#include "indirect.h"
#include "indirect.h"
#include "metrics.h"
#include "progressive.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define W 8
#define H 4
#define N (W * H)

static uint64_t rng_state = 99;
static float uni(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return (float)(z >> 40) * (1.0f / 16777216.0f);
}

/* A G-buffer of W×H surface pixels (pixel N−1 is background). */
static void make_gbuffer(glu_gbuffer *g)
{
    g->width = W;
    g->height = H;
    g->position = calloc(N * 4, sizeof(float));
    g->normal = calloc(N * 3, sizeof(float));
    g->albedo = calloc(N * 3, sizeof(float));
    g->material = calloc(N * 4, sizeof(float));
    for (int i = 0; i < N; i++) {
        g->position[4 * i] = (float)(i % W);
        g->position[4 * i + 1] = (float)(i / W);
        g->position[4 * i + 3] = i == N - 1 ? 0.0f : 1.0f;
        g->normal[3 * i + 2] = i == N - 1 ? 0.0f : 1.0f;
        g->albedo[3 * i] = 0.5f;
    }
}

static void make_scene(eng_frame_scene *fs, eng_light_pose *light)
{
    memset(fs, 0, sizeof *fs);
    memset(light, 0, sizeof *light);
    m4_identity(fs->camera.view_proj);
    light->position[1] = 1.0f;
    light->radiance_scale[0] = 1.0f;
    fs->lights = light;
    fs->light_count = 1;
}

static void random_frame(float *rgba)
{
    for (int i = 0; i < N * 4; i++)
        rgba[i] = uni();
}

/* Where nothing moves, the mean after n frames is the arithmetic mean of the n estimates (to
 * float rounding of one division); A is the current frame's; the count is n. */
START_TEST(running_mean_is_the_arithmetic_mean)
{
    glu_gbuffer g;
    make_gbuffer(&g);
    eng_frame_scene fs;
    eng_light_pose light;
    make_scene(&fs, &light);
    prog_state *p = prog_create();
    enum { FRAMES = 9 };
    static float in[FRAMES][N * 4];
    float mean[N * 4], count[N], radius[N];
    for (int f = 0; f < FRAMES; f++) {
        random_frame(in[f]);
        prog_begin(p, &fs);
        const float *ins[1] = {in[f]};
        float *outs[1] = {mean};
        prog_accumulate(p, &g, 1, ins, outs, count, radius);
        for (int i = 0; i < N - 1; i++) {
            ck_assert_float_eq(count[i], (float)(f + 1));
            for (int c = 0; c < 3; c++) {
                double s = 0.0;
                for (int k = 0; k <= f; k++)
                    s += in[k][4 * i + c];
                ck_assert_msg(fabs(mean[4 * i + c] - s / (f + 1)) <= 1e-6 * (s / (f + 1)) + 1e-9,
                              "frame %d pixel %d: %g vs %g", f, i, mean[4 * i + c], s / (f + 1));
            }
            ck_assert_float_eq(mean[4 * i + 3], in[f][4 * i + 3]);
            ck_assert_float_eq(radius[i], (float)prog_radius_scale(f + 1));
        }
        /* The background passes through, uncounted. */
        ck_assert_float_eq(count[N - 1], 0.0f);
        ck_assert_int_eq(memcmp(mean + 4 * (N - 1), in[f] + 4 * (N - 1), 4 * sizeof(float)), 0);
    }
    /* A mean of identical estimates is that estimate, bit for bit. */
    prog_reset(p);
    for (int f = 0; f < 5; f++) {
        prog_begin(p, &fs);
        const float *ins[1] = {in[0]};
        float *outs[1] = {mean};
        prog_accumulate(p, &g, 1, ins, outs, count, radius);
        for (int i = 0; i < N - 1; i++)
            for (int c = 0; c < 3; c++)
                ck_assert_float_eq(mean[4 * i + c], in[0][4 * i + c]);
    }
    prog_destroy(p);
    glu_gbuffer_free(&g);
}
END_TEST

/* A pixel whose G-buffer changes by one bit restarts; the others keep their means. Both
 * attachments (irradiance mode) restart together. A camera or light that moves restarts all. */
START_TEST(restarts_where_the_gbuffer_changes)
{
    glu_gbuffer g;
    make_gbuffer(&g);
    eng_frame_scene fs;
    eng_light_pose light;
    make_scene(&fs, &light);
    prog_state *p = prog_create();
    static float in[2][N * 4], mean[2][N * 4];
    float count[N], radius[N];
    const float *ins[2] = {in[0], in[1]};
    float *outs[2] = {mean[0], mean[1]};
    for (int f = 0; f < 4; f++) {
        random_frame(in[0]);
        random_frame(in[1]);
        prog_begin(p, &fs);
        prog_accumulate(p, &g, 2, ins, outs, count, radius);
    }
    ck_assert_float_eq(count[5], 4.0f);
    const int fields = 4;
    for (int which = 0; which < fields; which++) {
        float *v = which == 0 ? &g.position[4 * 5 + 2] : which == 1 ? &g.normal[3 * 5] : which == 2 ? &g.albedo[3 * 5 + 1] : &g.material[4 * 5];
        *v = nextafterf(*v, 1.0f); /* one ulp */
        random_frame(in[0]);
        random_frame(in[1]);
        prog_begin(p, &fs);
        prog_accumulate(p, &g, 2, ins, outs, count, radius);
        ck_assert_float_eq(count[5], 1.0f);
        ck_assert_float_eq(count[6], (float)(5 + which));
        for (int a = 0; a < 2; a++)
            for (int c = 0; c < 3; c++)
                ck_assert_float_eq(mean[a][4 * 5 + c], in[a][4 * 5 + c]);
    }
    /* The light moves: every pixel restarts and the radius is back to 1. */
    light.position[0] = nextafterf(light.position[0], 1.0f);
    float s = prog_begin(p, &fs);
    ck_assert_float_eq(s, 1.0f);
    ck_assert_int_eq(prog_frames(p), 1);
    prog_accumulate(p, &g, 2, ins, outs, count, radius);
    for (int i = 0; i < N - 1; i++)
        ck_assert_float_eq(count[i], 1.0f);
    /* The camera moves: the same. */
    prog_begin(p, &fs);
    ck_assert_int_eq(prog_frames(p), 2);
    fs.camera.eye[2] = 1e-7f;
    ck_assert_float_eq(prog_begin(p, &fs), 1.0f);
    ck_assert_int_eq(prog_frames(p), 1);
    prog_destroy(p);
    glu_gbuffer_free(&g);
}
END_TEST

/* Hachisuka et al. 2008 Eq. 8 with one frame a pass: r_{i+1}² = r_i² (i + 2/3)/(i + 1). */
START_TEST(radius_shrinks_as_ppm)
{
    ck_assert_double_eq(prog_radius_scale(1), 1.0);
    ck_assert(fabs(prog_radius_scale(2) - sqrt(5.0 / 6.0)) < 1e-12);
    ck_assert(fabs(prog_radius_scale(3) - sqrt(5.0 / 6.0 * (8.0 / 3.0) / 3.0)) < 1e-12);
    eng_frame_scene fs;
    eng_light_pose light;
    make_scene(&fs, &light);
    prog_state *p = prog_create();
    double prev = 2.0;
    for (int i = 1; i <= 256; i++) {
        float s = prog_begin(p, &fs);
        ck_assert_int_eq(prog_frames(p), i);
        ck_assert(fabs(s - prog_radius_scale(i)) < 1e-6);
        ck_assert(s < prev);
        prev = s;
    }
    /* r_i² ~ C i^(α−1): r² i^(1/3) settles to a constant (Γ(1+α)^−1 ≈ 1.108 for α = 2/3). */
    double a = pow(prog_radius_scale(128), 2) * cbrt(128.0), b = pow(prog_radius_scale(256), 2) * cbrt(256.0);
    ck_assert_msg(fabs(a - b) < 0.01 * b && b > 1.0 && b < 1.25, "%g %g", a, b);
    prog_destroy(p);
}
END_TEST

/* Per-pixel radii (`"progressive_radius": "pixel"`): PPM §4's update N' = N + αM,
 * R'² = R² (N + αM)/(N + M), exact fractions for α = 2/3. */
START_TEST(ppm_update_per_pixel)
{
    double r2 = 1.0, n = 0.0;
    prog_ppm_update(&r2, &n, 0.0); /* nothing found, nothing kept: unchanged */
    ck_assert(r2 == 1.0 && n == 0.0);
    prog_ppm_update(&r2, &n, 9.0); /* N = 6, R² = 6/9 */
    ck_assert(fabs(n - 6.0) < 1e-12 && fabs(r2 - 2.0 / 3.0) < 1e-12);
    prog_ppm_update(&r2, &n, 3.0); /* N = 8, R² = 2/3 · 8/9 */
    ck_assert(fabs(n - 8.0) < 1e-12 && fabs(r2 - 16.0 / 27.0) < 1e-12);
    prog_ppm_update(&r2, &n, 0.0); /* N > 0, M = 0: R and N stay */
    ck_assert(fabs(n - 8.0) < 1e-12 && fabs(r2 - 16.0 / 27.0) < 1e-12);

    /* Through prog_state: M comes from the method's A channel, per pixel. */
    glu_gbuffer g;
    make_gbuffer(&g);
    eng_frame_scene fs;
    eng_light_pose light;
    make_scene(&fs, &light);
    float in[N * 4], mean[N * 4], count[N], radius[N];
    const float *ins[1] = {in};
    float *outs[1] = {mean};
    prog_state *p = prog_create();
    prog_set_per_pixel(p, 1);
    const int m1[3] = {9, 0, 3}; /* photons found at pixel i, frames 1 and 2: i·m1[f] */
    for (int f = 0; f < 2; f++) {
        ck_assert_float_eq(prog_begin(p, &fs), 1.0f); /* the photons' radii are not scaled */
        const float *sc = prog_pixel_scales(p, &g);
        for (int i = 0; i < N; i++) {
            in[4 * i] = in[4 * i + 1] = in[4 * i + 2] = 1.0f;
            in[4 * i + 3] = (float)(i % 3 == 0 ? m1[f] : m1[f] + 3);
        }
        for (int i = 0; i < N - 1; i++) {
            /* frame 1: R = 1; frame 2: R² = (αM)/M = 2/3 wherever M > 0 */
            double want = f == 0 ? 1.0 : sqrt(2.0 / 3.0);
            ck_assert_msg(fabs(sc[i] - want) < 1e-6, "frame %d pixel %d: scale %g want %g", f, i, sc[i], want);
        }
        prog_accumulate(p, &g, 1, ins, outs, count, radius);
        for (int i = 0; i < N - 1; i++)
            ck_assert_float_eq(radius[i], sc[i]);
    }
    /* After two frames: M = (9, 0) → N = 6, R² = 2/3 (unchanged by M = 0); M = (12, 3) →
     * N = 8 + 2 = 10, R² = 2/3 · 10/11. */
    const float *sc = prog_pixel_scales(p, &g);
    for (int i = 0; i < N - 1; i++) {
        double n_want = i % 3 == 0 ? 6.0 : 10.0, r2_want = i % 3 == 0 ? 2.0 / 3.0 : 2.0 / 3.0 * 10.0 / 11.0;
        ck_assert_msg(fabs(prog_photons(p)[i] - n_want) < 1e-5, "pixel %d: N %g", i, prog_photons(p)[i]);
        ck_assert_msg(fabs(sc[i] - sqrt(r2_want)) < 1e-6, "pixel %d: R %g", i, sc[i]);
    }
    ck_assert_float_eq(prog_photons(p)[N - 1], 0.0f); /* background */
    /* A changed pixel restarts alone (R = 1, N = 0); the others keep theirs. */
    prog_accumulate(p, &g, 1, ins, outs, count, radius);
    prog_begin(p, &fs);
    g.albedo[3 * 5] = 0.25f;
    sc = prog_pixel_scales(p, &g);
    ck_assert_float_eq(sc[5], 1.0f);
    ck_assert(sc[4] < 0.8f);
    /* The camera moves: every pixel restarts. */
    prog_accumulate(p, &g, 1, ins, outs, count, radius);
    fs.camera.eye[0] = 1.0f;
    prog_begin(p, &fs);
    sc = prog_pixel_scales(p, &g);
    for (int i = 0; i < N; i++)
        ck_assert_float_eq(sc[i], 1.0f);
    prog_destroy(p);
    glu_gbuffer_free(&g);
}
END_TEST

/* ---------------------------------------------------------------- kernel scalings */

static eng_photon photon(float x, float y, float z, float len, float cos_theta, float rho)
{
    eng_photon ph;
    memset(&ph, 0, sizeof ph);
    ph.position[0] = x;
    ph.position[1] = y;
    ph.position[2] = z;
    ph.normal[2] = 1.0f;
    ph.direction[0] = sqrtf(1.0f - cos_theta * cos_theta);
    ph.direction[2] = cos_theta;
    ph.power[0] = ph.power[1] = ph.power[2] = 1.0f;
    ph.path_density = rho;
    ph.bounce = 2;
    ph.ray_length = len;
    return ph;
}

START_TEST(each_kernel_scaling_on_a_hand_made_map)
{
    eng_photon ph[6];
    eng_photon_map map = {.count = 6, .capacity = 6, .photons = ph};
    eng_settings s;
    memset(&s, 0, sizeof s);
    eng_settings_defaults(&s);
    s.kernel_radius = 0.2f;
    eng_frame_scene fs;
    eng_light_pose light;
    make_scene(&fs, &light);
    /* The scene box: diagonal 10 → l_max = 5. */
    fs.bounds_max[0] = 6.0f;
    fs.bounds_max[1] = 8.0f;
    float r[6];

    /* path-density: splat_radius, and the progressive scale multiplies. */
    for (int i = 0; i < 6; i++)
        ph[i] = photon(0, 0, 0, 1.0f, 1.0f, 0.0001f * powf(10.0f, (float)i));
    ind_photon_radii(&map, &s, &fs, 16, 16, 1.0f, r);
    for (int i = 0; i < 6; i++)
        ck_assert_float_eq(r[i], splat_radius(0.2f, ph[i].path_density));
    ind_photon_radii(&map, &s, &fs, 16, 16, 0.5f, r);
    for (int i = 0; i < 6; i++)
        ck_assert_float_eq(r[i], splat_radius(0.2f, ph[i].path_density) * 0.5f);

    /* ray-length (002 Eq. 6.1): r = 2 kr max(min(l / l_max, 1), 1/8). */
    s.kernel_scaling = ENG_SCALING_RAY_LENGTH;
    const float len[6] = {0.0f, 0.5f, 2.5f, 4.0f, 5.0f, 50.0f};
    const float want_l[6] = {0.05f, 0.05f, 0.2f, 0.32f, 0.4f, 0.4f};
    for (int i = 0; i < 6; i++)
        ph[i] = photon(0, 0, 0, len[i], 1.0f, 0.001f);
    ind_photon_radii(&map, &s, &fs, 16, 16, 1.0f, r);
    for (int i = 0; i < 6; i++)
        ck_assert_msg(fabsf(r[i] - want_l[i]) < 1e-6f, "l=%g: r=%g want %g", len[i], r[i], want_l[i]);

    /* bandwidth (004 §6): h = kr √(p̄/p), p = cos θ / d², p̄ the geometric mean, clamped. */
    s.kernel_scaling = ENG_SCALING_BANDWIDTH;
    ph[0] = photon(0, 0, 0, 1.0f, 1.0f, 0.001f); /* p = 1 */
    ph[1] = photon(0, 0, 0, 2.0f, 1.0f, 0.001f); /* p = 1/4 */
    map.count = 2;
    ind_photon_radii(&map, &s, &fs, 16, 16, 1.0f, r); /* p̄ = 1/2 */
    ck_assert(fabsf(r[0] - 0.2f * sqrtf(0.5f)) < 1e-6f);
    ck_assert(fabsf(r[1] - 0.2f * sqrtf(2.0f)) < 1e-6f);
    ck_assert(fabsf(r[1] / r[0] - 2.0f) < 1e-5f); /* twice the distance: twice the bandwidth */
    ph[1] = photon(0, 0, 0, 1.0f, 0.25f, 0.001f); /* grazing: p = 1/4 as well */
    ind_photon_radii(&map, &s, &fs, 16, 16, 1.0f, r);
    ck_assert(fabsf(r[1] / r[0] - 2.0f) < 1e-5f);
    ph[1] = photon(0, 0, 0, 100.0f, 1.0f, 0.001f); /* far: clamped to 2 kr */
    ind_photon_radii(&map, &s, &fs, 16, 16, 1.0f, r);
    ck_assert_float_eq(r[1], 0.4f);
    ck_assert_float_eq(r[0], 0.05f);

    /* tile-density (002 Eq. 6.2): identity view_proj except w = −z (a perspective divide
     * with tan(α/2) = 1), 32×32 pixels → 2×2 tiles of 16. Photons at depth z = 2. */
    s.kernel_scaling = ENG_SCALING_TILE_DENSITY;
    s.kernel_radius = 1.5f;
    float *vp = fs.camera.view_proj;
    memset(vp, 0, 16 * sizeof(float));
    vp[0] = vp[5] = 1.0f;
    vp[10] = -1.0f;
    vp[11] = -1.0f; /* w = −z */
    vp[14] = -0.1f;
    m4_identity(fs.camera.proj); /* proj[0] = proj[5] = 1 */
    /* Four photons in the top-left tile (x < 0, y > 0), one in the bottom-right, one behind. */
    ph[0] = photon(-1.0f, 1.0f, -2.0f, 1, 1, 0.001f);
    ph[1] = photon(-1.5f, 1.2f, -2.0f, 1, 1, 0.001f);
    ph[2] = photon(-0.5f, 0.5f, -2.0f, 1, 1, 0.001f);
    ph[3] = photon(-30.0f, 30.0f, -2.0f, 1, 1, 0.001f); /* off screen: the nearest tile, the same */
    ph[4] = photon(1.0f, -1.0f, -2.0f, 1, 1, 0.001f);
    ph[5] = photon(0.0f, 0.0f, 3.0f, 1, 1, 0.001f);
    map.count = 6;
    ind_photon_radii(&map, &s, &fs, 32, 32, 1.0f, r);
    /* a_view = z² · 4 · 16·16 / (32·32) = 4; r = √(16 a / (π n)) clamped to [kr/4, 2 kr] = [0.375, 3]. */
    double r4 = sqrt(16.0 * 4.0 / (ENG_PI * 4.0)), r1 = sqrt(16.0 * 4.0 / (ENG_PI * 1.0));
    for (int i = 0; i < 4; i++)
        ck_assert_msg(fabs(r[i] - fmin(r4, 3.0)) < 1e-5, "photon %d: %g want %g", i, r[i], fmin(r4, 3.0));
    ck_assert(fabs(r[4] - fmin(r1, 3.0)) < 1e-5);
    ck_assert_float_eq(r[5], 1.5f); /* behind the camera: kernel_radius */
    ck_assert(r[0] < r[4]);          /* denser tile, smaller kernels */
}
END_TEST

/* The radii and the accumulation are single-threaded loops with a fixed order: the thread
 * setting does not enter them. Here: the same inputs give the same bits twice, whatever the
 * `threads` setting says. */
START_TEST(radii_do_not_depend_on_threads)
{
    enum { M = 500 };
    eng_photon *ph = malloc(M * sizeof *ph);
    for (int i = 0; i < M; i++)
        ph[i] = photon(uni() * 4 - 2, uni() * 4 - 2, -1 - uni() * 3, uni() * 6, 0.1f + 0.9f * uni(), uni() * 0.01f);
    eng_photon_map map = {.count = M, .capacity = M, .photons = ph};
    eng_frame_scene fs;
    eng_light_pose light;
    make_scene(&fs, &light);
    fs.bounds_max[0] = fs.bounds_max[1] = fs.bounds_max[2] = 5.0f;
    float *vp = fs.camera.view_proj;
    memset(vp, 0, 16 * sizeof(float));
    vp[0] = vp[5] = 1.0f;
    vp[10] = vp[11] = -1.0f;
    m4_identity(fs.camera.proj);
    float a[M], b[M];
    for (int k = ENG_SCALING_PATH_DENSITY; k <= ENG_SCALING_BANDWIDTH; k++) {
        eng_settings s1, s2;
        memset(&s1, 0, sizeof s1);
        s1.threads = 1;
        s1.kernel_scaling = (eng_kernel_scaling)k;
        eng_settings_defaults(&s1);
        s2 = s1;
        s2.threads = 7;
        ind_photon_radii(&map, &s1, &fs, 64, 48, 0.75f, a);
        ind_photon_radii(&map, &s2, &fs, 64, 48, 0.75f, b);
        ck_assert_int_eq(memcmp(a, b, sizeof a), 0);
        for (int i = 0; i < M; i++)
            ck_assert(isfinite(a[i]) && a[i] > 0.0f);
    }
    free(ph);
}
END_TEST

/* ---------------------------------------------------------------- bench measures */

START_TEST(bias_measures_and_edge_mask)
{
    enum { BW = 32, BH = 16 };
    static float ref[BW * BH * 3], test[BW * BH * 3], pos[BW * BH * 3], nrm[BW * BH * 3];
    static signed char mask[BW * BH];
    /* A floor (y = 0, normal +y) on the left half, a wall (x = 0, normal +x) on the right,
     * meeting at pixel column 16; seen from a camera 10 m away with 2 px per metre. */
    for (int y = 0; y < BH; y++)
        for (int x = 0; x < BW; x++) {
            int i = y * BW + x;
            float u = (float)x * 0.5f;
            if (x < 16) {
                pos[3 * i] = 8.0f - u;
                pos[3 * i + 1] = 0.0f;
                nrm[3 * i + 1] = 1.0f;
            } else {
                pos[3 * i] = 0.0f;
                pos[3 * i + 1] = u - 8.0f;
                nrm[3 * i] = 1.0f;
            }
            pos[3 * i + 2] = (float)y * 0.5f;
        }
    float vp[16] = {0};
    vp[0] = 10.0f * 2.0f / (0.5f * BW); /* 2 px per metre at 10 m: view_proj x scale */
    vp[5] = vp[0];
    const float eye[3] = {10.0f, 10.0f, 0.0f};
    rep_edge_mask(pos, nrm, BW, BH, vp, eye, 1.0, mask);
    /* Within 1 m (2 px) of the crease: edge; far from it: not. */
    for (int y = 0; y < BH; y++) {
        ck_assert_int_eq(mask[y * BW + 15], 1);
        ck_assert_int_eq(mask[y * BW + 16], 1);
        ck_assert_int_eq(mask[y * BW + 5], 0);
        ck_assert_int_eq(mask[y * BW + 27], 0);
    }
    /* Test = reference × 0.75 at edges, × 1.0 elsewhere. */
    int edges = 0;
    for (int i = 0; i < BW * BH; i++) {
        edges += mask[i] == 1;
        for (int c = 0; c < 3; c++) {
            ref[3 * i + c] = 1.0f;
            test[3 * i + c] = mask[i] == 1 ? 0.75f : 1.0f;
        }
    }
    rep_metrics_bias b;
    rep_metric_bias(test, ref, BW, BH, mask, &b);
    ck_assert(fabs(b.edge_ratio - 0.75) < 1e-9);
    ck_assert(fabs(b.flat_ratio - 1.0) < 1e-9);
    ck_assert(fabs(b.flat_rel_rmse) < 1e-9);
    ck_assert(fabs(b.edge_rel_rmse - 0.25) < 1e-9);
    ck_assert(fabs(b.edge_fraction - (double)edges / (BW * BH)) < 1e-12);
    ck_assert(fabs(b.mean_ratio - (1.0 - 0.25 * edges / (BW * BH))) < 1e-9);
    /* Blocks away from edges (no pixel of the mask): the error is all at the edges, so they
     * have none, while over all blocks the edge blocks count. */
    ck_assert(b.block_p90 > 0.0 && b.block_p90 <= 0.25);
    ck_assert(fabs(b.flat_block_p90) < 1e-9);
    /* Blocks: 8 blocks of 8×8; p90 = the second largest block error. Without a mask every
     * block is away from edges. */
    rep_metric_bias(test, ref, BW, BH, NULL, &b);
    ck_assert(b.block_p90 > 0.0 && b.block_p90 <= 0.25);
    ck_assert(b.flat_block_p90 == b.block_p90);
    for (int i = 0; i < BW * BH * 3; i++)
        test[i] = 1.1f;
    rep_metric_bias(test, ref, BW, BH, NULL, &b);
    ck_assert(fabs(b.block_p90 - 0.1) < 1e-6);
    ck_assert(fabs(b.mean_ratio - 1.1) < 1e-6);
}
END_TEST

/* The sequence keys: "still", settings.progressive, settings.kernel_scaling (strict). */
START_TEST(sequence_keys)
{
    const char *ok = "{\"scene\": \"x.gltf\", \"frames\": 3, \"fps\": 8, \"resolution\": [4, 4], "
                     "\"camera\": {\"node\": \"C\"}, \"still\": true, "
                     "\"settings\": {\"progressive\": true, \"kernel_scaling\": \"tile-density\"}}";
    seq_sequence *q = calloc(1, sizeof *q);
    eng_error err;
    ck_assert_msg(seq_parse("t.json", ok, strlen(ok), q, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(q->still, 1);
    ck_assert_int_eq(q->settings.progressive, 1);
    ck_assert_int_eq(q->settings.kernel_scaling, ENG_SCALING_TILE_DENSITY);
    ck_assert(seq_frame_time(q, 2) == 0.0);
    q->still = 0;
    ck_assert(seq_frame_time(q, 2) == 0.25);
    const char *bad[] = {"\"still\": 1", "\"settings\": {\"progressive\": 1}",
                         "\"settings\": {\"kernel_scaling\": \"photon-density\"}"};
    for (int i = 0; i < 3; i++) {
        char text[512];
        snprintf(text, sizeof text,
                 "{\"scene\": \"x.gltf\", \"frames\": 3, \"fps\": 8, \"resolution\": [4, 4], "
                 "\"camera\": {\"node\": \"C\"}, %s}", bad[i]);
        ck_assert_int_eq(seq_parse("t.json", text, strlen(text), q, &err), ENG_ERR_INVALID);
    }
    /* Defaults: off, path-density. */
    eng_settings s;
    memset(&s, 0, sizeof s);
    eng_settings_defaults(&s);
    ck_assert_int_eq(s.progressive, 0);
    ck_assert_int_eq(s.kernel_scaling, ENG_SCALING_PATH_DENSITY);
    ck_assert_str_eq(eng_scaling_name(ENG_SCALING_BANDWIDTH), "bandwidth");
    free(q);
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("progressive");
    TCase *t = tcase_create("progressive");
    tcase_add_test(t, running_mean_is_the_arithmetic_mean);
    tcase_add_test(t, restarts_where_the_gbuffer_changes);
    tcase_add_test(t, radius_shrinks_as_ppm);
    tcase_add_test(t, ppm_update_per_pixel);
    suite_add_tcase(s, t);
    TCase *k = tcase_create("kernel_scaling");
    tcase_add_test(k, each_kernel_scaling_on_a_hand_made_map);
    tcase_add_test(k, radii_do_not_depend_on_threads);
    suite_add_tcase(s, k);
    TCase *b = tcase_create("bench");
    tcase_add_test(b, bias_measures_and_edge_mask);
    tcase_add_test(b, sequence_keys);
    suite_add_tcase(s, b);
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
