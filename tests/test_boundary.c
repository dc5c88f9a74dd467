/* test_boundary.c — Check suite of the kernel's boundary correction (engine/indirect/boundary.c): the
 * kernel mass g(x), W on a synthetic G-buffer with a known straight edge (convex: a table top
 * ending above a floor; and the background), and the recovered energy: a uniform photon density
 * on the table top gathered with the methods' kernel (gather_kernel.h) is low by the kernel mass
 * off the table near its edge, and equal to the true irradiance once divided by W. Plus the
 * sequence key. No GL: CPU functions. */
#include "boundary.h"
#include "eng.h"
#include "indirect.h"
#include "gather_kernel.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GW 200
#define GH 100
#define R 0.1f    /* kernel radius */
#define EDGE 0.0  /* the table ends at X = EDGE */

/* An orthographic view from above: world X ∈ [−1, 1] → screen x, Y ∈ [−0.5, 0.5] → screen y. */
static void ortho(float vp[16])
{
    memset(vp, 0, 16 * sizeof(float));
    vp[0] = 1.0f;
    vp[5] = 2.0f;
    vp[10] = -1.0f;
    vp[15] = 1.0f;
}

static double world_x(int x) { return (x + 0.5) / GW * 2.0 - 1.0; }
static double world_y(int y) { return 0.5 - (y + 0.5) / GH; }

/* Table top z = 0 (normal +z) for X < EDGE; beyond it a floor at z = −1 (below = 1) or
 * background (below = 0). */
static void make_gbuffer(glu_gbuffer *g, int below)
{
    g->width = GW;
    g->height = GH;
    g->position = calloc(GW * GH * 4, sizeof(float));
    g->normal = calloc(GW * GH * 3, sizeof(float));
    g->albedo = calloc(GW * GH * 3, sizeof(float));
    g->material = calloc(GW * GH * 4, sizeof(float));
    for (int y = 0; y < GH; y++)
        for (int x = 0; x < GW; x++) {
            size_t i = (size_t)y * GW + x;
            int top = world_x(x) < EDGE;
            g->position[4 * i] = (float)world_x(x);
            g->position[4 * i + 1] = (float)world_y(y);
            g->position[4 * i + 2] = top ? 0.0f : -1.0f;
            g->position[4 * i + 3] = top || below ? 1.0f : 0.0f;
            g->normal[3 * i + 2] = 1.0f;
        }
}

/* Photons of flux density E (W/m²) on a 2.5 mm grid over the table top, each of radius R. */
static void make_photons(eng_photon_map *m, float **radius, double E)
{
    const double h = 0.0025;
    size_t n = 0, cap = (size_t)(2.0 / h + 1) * (size_t)(1.0 / h + 1);
    m->photons = calloc(cap, sizeof *m->photons);
    *radius = calloc(cap, sizeof **radius);
    for (double X = -1.0 + h / 2; X < EDGE; X += h)
        for (double Y = -0.5 + h / 2; Y < 0.5; Y += h) {
            eng_photon *p = &m->photons[n];
            p->position[0] = (float)X;
            p->position[1] = (float)Y;
            p->direction[2] = p->normal[2] = 1.0f;
            p->power[0] = p->power[1] = p->power[2] = (float)(E * h * h);
            (*radius)[n++] = R;
        }
    m->count = m->capacity = n;
}

/* A synthetic case: the G-buffer, photons of flux density E, the view from above at eye, and W. */
typedef struct fixture {
    glu_gbuffer g;
    eng_photon_map m;
    float *radius, vp[16], eye[3], *w;
} fixture;

static void setup(fixture *f, int below, double E)
{
    memset(f, 0, sizeof *f);
    make_gbuffer(&f->g, below);
    make_photons(&f->m, &f->radius, E);
    ortho(f->vp);
    f->eye[2] = 10.0f;
    f->w = calloc(GW * GH, sizeof *f->w);
}

static void weigh(fixture *f, int threads, float *w)
{
    bnd_weights(&f->g, f->vp, f->eye, &f->m, f->radius, 0.25f, threads, w);
}

static void teardown(fixture *f)
{
    free(f->w);
    free(f->radius);
    free(f->m.photons);
    glu_gbuffer_free(&f->g);
}

/* g(x) = 2x² − x⁴: 0, 1 at the ends, 7/16 at one half, the mass of κ within x R. */
START_TEST(kernel_mass)
{
    ck_assert(bnd_mass(0.0) == 0.0);
    ck_assert(bnd_mass(1.0) == 1.0);
    ck_assert(bnd_mass(2.0) == 1.0);
    ck_assert(fabs(bnd_mass(0.5) - 7.0 / 16.0) < 1e-12);
    /* The same mass by summing κ of gather_kernel.h over a fine grid of the disc of 0.5 R. */
    eng_photon ph;
    memset(&ph, 0, sizeof ph);
    ph.normal[2] = 1.0f;
    const double h = R / 400.0;
    double sum = 0.0;
    for (double x = -R; x < R; x += h)
        for (double y = -R; y < R; y += h) {
            float s[3] = {(float)(x + h / 2), (float)(y + h / 2), 0.0f};
            if (s[0] * s[0] + s[1] * s[1] >= 0.25 * R * R)
                continue;
            float k = gk_kappa(&ph, s, R, 0.25f);
            if (k > 0.0f)
                sum += k * h * h;
        }
    ck_assert_msg(fabs(sum - 7.0 / 16.0) < 2e-3, "mass within R/2 %g", sum);
}
END_TEST

/* W across the edge: 1 beyond one radius, ½ at the edge, g's half-plane mass in between. */
START_TEST(weight_at_a_known_edge)
{
    for (int below = 0; below < 2; below++) {
        fixture f;
        setup(&f, below, 1.0);
        weigh(&f, 2, f.w);
        const float *w = f.w;
        int y = GH / 2;
        for (int x = 0; x < GW; x++) {
            double a = EDGE - world_x(x); /* distance to the edge, > 0 on the table */
            float wi = w[(size_t)y * GW + x];
            if (a < 0.0) {
                /* background, or the floor: hidden under the table top, 1 m from it: unknown */
                ck_assert_msg(wi == 1.0f, "beyond the edge x %d: %g", x, wi);
                continue;
            }
            /* The half-plane's share of the kernel centred a from its edge (1 − the mass of
             * κ's marginal (8/(3π))(1 − x²)^{3/2} beyond a/R). */
            double t = a / R, off = 0.0, dx = 1e-4;
            for (double u = t; u + dx / 2 < 1.0; u += dx)
                off += 8.0 / (3.0 * ENG_PI) * pow(1.0 - (u + dx / 2) * (u + dx / 2), 1.5) * dx;
            double want = 1.0 - (t < 1.0 ? off : 0.0);
            ck_assert_msg(fabs(wi - want) < 0.04, "a = %.4f: W %g, half-plane %g", a, wi, want);
            if (a > R + 0.01)
                ck_assert(wi == 1.0f);
        }
        teardown(&f);
    }
}
END_TEST

/* Photons next to a known edge: the gathered irradiance is E·W low near the edge; divided by W
 * (bnd_apply) it is E again. */
START_TEST(recovers_the_energy_at_the_edge)
{
    const double E = 2.0;
    fixture f;
    setup(&f, 1, E);
    weigh(&f, 2, f.w);
    const glu_gbuffer *g = &f.g;
    const eng_photon_map *m = &f.m;
    const float *radius = f.radius;
    float *w = f.w;
    const int y = GH / 2;
    for (int x = GW / 2 - 14; x < GW / 2; x++) { /* the last 14 pixels (0.14 m) of the table */
        size_t i = (size_t)y * GW + x;
        float rgba[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        for (size_t k = 0; k < m->count; k++) {
            float kap = gk_kappa(&m->photons[k], g->position + 4 * i, radius[k], 0.25f);
            if (kap > 0.0f) {
                for (int c = 0; c < 3; c++)
                    rgba[c] += m->photons[k].power[c] * kap;
                rgba[3] += 1.0f;
            }
        }
        double a = EDGE - world_x(x), raw = rgba[0];
        if (a < 0.2 * R)
            ck_assert_msg(raw < 0.75 * E, "a = %.3f: uncorrected %g should be low", a, raw);
        float count = rgba[3];
        bnd_apply(1, w + i, rgba);
        ck_assert_msg(fabs(rgba[0] / E - 1.0) < 0.05, "a = %.3f: corrected %g of E %g (raw %g, W %g)", a,
                      rgba[0], E, raw, w[i]);
        ck_assert(rgba[0] == rgba[2] && rgba[3] == count);
    }
    teardown(&f);
}
END_TEST

/* An object in front (hiding the table from the eye, far from it) is not an edge: W stays 1. */
START_TEST(occluder_is_not_an_edge)
{
    fixture f;
    setup(&f, 1, 1.0);
    float *pos = f.g.position, *nrm = f.g.normal;
    for (int y = 0; y < GH; y++)
        for (int x = 0; x < GW; x++) {
            size_t i = (size_t)y * GW + x;
            pos[4 * i + 2] = 0.0f; /* table everywhere … */
            if (world_x(x) >= EDGE) { /* … seen through a box top 1 m above it */
                pos[4 * i + 2] = 1.0f;
                nrm[3 * i + 2] = 1.0f;
            }
        }
    weigh(&f, 2, f.w);
    for (int x = 0; x < GW / 2; x++)
        ck_assert_msg(f.w[(size_t)(GH / 2) * GW + x] == 1.0f, "x %d: %g", x, f.w[(size_t)(GH / 2) * GW + x]);
    teardown(&f);
}
END_TEST

/* The same weights, bit for bit, with 1 and 3 threads. */
START_TEST(weights_do_not_depend_on_threads)
{
    fixture f;
    setup(&f, 1, 1.0);
    f.eye[0] = 0.3f;
    f.eye[1] = -0.2f;
    for (size_t k = 0; k < f.m.count; k++)
        f.radius[k] = R * (0.5f + (float)(k % 7) / 4.0f);
    float *w1 = f.w, *w3 = calloc(GW * GH, sizeof *w3);
    weigh(&f, 1, w1);
    weigh(&f, 3, w3);
    ck_assert(memcmp(w1, w3, GW * GH * sizeof *w1) == 0);
    int below1 = 0;
    for (size_t i = 0; i < GW * GH; i++)
        below1 += w1[i] < 1.0f;
    ck_assert(below1 > 0);
    free(w3);
    teardown(&f);
}
END_TEST

START_TEST(sequence_key)
{
    seq_sequence *q = calloc(1, sizeof *q);
    eng_error err;
    const char *fmt = "{\"scene\": \"x.gltf\", \"frames\": 1, \"fps\": 8, \"resolution\": [4, 4], "
                      "\"camera\": {\"node\": \"C\"}, \"settings\": {\"boundary\": %s}}";
    char text[512];
    snprintf(text, sizeof text, fmt, "\"renormalize\"");
    ck_assert_msg(seq_parse("t.json", text, strlen(text), q, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(q->settings.boundary, ENG_BOUNDARY_RENORMALIZE);
    snprintf(text, sizeof text, fmt, "\"none\"");
    ck_assert_msg(seq_parse("t.json", text, strlen(text), q, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(q->settings.boundary, ENG_BOUNDARY_NONE);
    snprintf(text, sizeof text, fmt, "true");
    ck_assert_int_eq(seq_parse("t.json", text, strlen(text), q, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "settings.boundary"), "%s", err.msg);
    ck_assert_str_eq(eng_boundary_name(ENG_BOUNDARY_RENORMALIZE), "renormalize");
    eng_settings s; /* default: none (the correction raises flicker under camera motion) */
    memset(&s, 0, sizeof s);
    eng_settings_defaults(&s);
    ck_assert_int_eq(s.boundary, ENG_BOUNDARY_NONE);
    free(q);
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("boundary");
    TCase *t = tcase_create("boundary");
    tcase_add_test(t, kernel_mass);
    tcase_add_test(t, weight_at_a_known_edge);
    tcase_add_test(t, recovers_the_energy_at_the_edge);
    tcase_add_test(t, occluder_is_not_an_edge);
    tcase_add_test(t, weights_do_not_depend_on_threads);
    tcase_add_test(t, sequence_key);
    suite_add_tcase(s, t);
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
