/* test_translucent.c — Check suite for alphaMode BLEND surfaces (issue 14 item 3;
 * engine/specular/pass_translucent.c, rt.c's BLEND scene): back-to-front ordering and "over"
 * compositing on synthetic layers, BLEND geometry invisible to the opaque rays and seen by
 * rt_intersect_blend, a pane's value (half its direct light over what lies behind), and the
 * image bit-identical for 1 and 3 threads. */
#include "translucent.h"
#include "specular.h"
#include "translucent.h"

#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static tl_layer layer(float t, float alpha, float r, float g, float b)
{
    tl_layer l = {t, alpha, {r, g, b}};
    return l;
}

START_TEST(composite_back_to_front)
{
    /* Front (t 1, α 0.5, red) over back (t 3, α 0.25, green), given in every order:
     * rgb = 0.5·red + 0.5·0.25·green, a = 1 − 0.5·0.75. */
    const tl_layer in[3] = {layer(1.0f, 0.5f, 1, 0, 0), layer(3.0f, 0.25f, 0, 1, 0), layer(2.0f, 0.0f, 7, 7, 7)};
    const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    float first[4];
    for (int p = 0; p < 6; p++) {
        tl_layer l[3];
        for (int k = 0; k < 3; k++)
            l[k] = in[perms[p][k]];
        float rgba[4];
        tl_composite(l, 3, rgba);
        ck_assert(l[0].t == 3.0f && l[1].t == 2.0f && l[2].t == 1.0f); /* sorted back to front */
        ck_assert_float_eq_tol(rgba[0], 0.5f, 1e-7f);
        ck_assert_float_eq_tol(rgba[1], 0.125f, 1e-7f);
        ck_assert_float_eq(rgba[2], 0.0f); /* the α = 0 layer adds nothing */
        ck_assert_float_eq_tol(rgba[3], 0.625f, 1e-7f);
        if (p == 0)
            memcpy(first, rgba, sizeof first);
        ck_assert(memcmp(first, rgba, sizeof first) == 0); /* the same bits for any input order */
    }
    /* An opaque layer in front hides everything behind it; none gives (0, 0, 0, 0). */
    tl_layer l[2] = {layer(5.0f, 0.8f, 0, 0, 9), layer(0.5f, 1.0f, 0.25f, 0.5f, 0.75f)};
    float rgba[4];
    tl_composite(l, 2, rgba);
    ck_assert(rgba[0] == 0.25f && rgba[1] == 0.5f && rgba[2] == 0.75f && rgba[3] == 1.0f);
    tl_composite(l, 0, rgba);
    ck_assert(rgba[0] == 0.0f && rgba[1] == 0.0f && rgba[2] == 0.0f && rgba[3] == 0.0f);
}
END_TEST

START_TEST(composite_matches_front_to_back)
{
    /* "over" back to front, then rgb + (1 − a)·opaque, equals the front-to-back sum
     * Σ α_i L_i Π_{j<i}(1 − α_j) + Π(1 − α_j)·opaque for random layers. */
    unsigned seed = 12345u;
    for (int trial = 0; trial < 200; trial++) {
        tl_layer l[6];
        int n = 1 + trial % 6;
        for (int k = 0; k < n; k++) {
            seed = seed * 1664525u + 1013904223u;
            float t = (float)(seed >> 8) / 16777216.0f;
            seed = seed * 1664525u + 1013904223u;
            float a = (float)(seed >> 8) / 16777216.0f;
            l[k] = layer(1.0f + 9.0f * t, a, a * 2.0f, 1.0f - a, t);
        }
        tl_layer sorted[6];
        memcpy(sorted, l, sizeof l);
        /* front to back by hand (selection by t) */
        double want[3] = {0, 0, 0}, trans = 1.0;
        int used[6] = {0};
        for (int k = 0; k < n; k++) {
            int best = -1;
            for (int j = 0; j < n; j++)
                if (!used[j] && (best < 0 || l[j].t < l[best].t))
                    best = j;
            used[best] = 1;
            for (int c = 0; c < 3; c++)
                want[c] += trans * l[best].alpha * l[best].radiance[c];
            trans *= 1.0 - l[best].alpha;
        }
        const float opaque[3] = {0.3f, 0.6f, 0.9f};
        float rgba[4];
        tl_composite(sorted, n, rgba);
        for (int c = 0; c < 3; c++)
            ck_assert_double_eq_tol(rgba[c] + (1.0 - rgba[3]) * opaque[c], want[c] + trans * opaque[c], 1e-5);
    }
}
END_TEST

/* A floor at y = 0 (opaque, grey) and a BLEND pane at y = 0.5 (half-size 1, α 0.5, blue),
 * a point light at (0, 1, 0) of intensity I, a camera at (0, 2, 0) looking down. */
typedef struct pane_scene {
    float pos[2][12], nrm[2][12];
    uint32_t idx[2][6];
    scn_primitive prim[2];
    scn_material mat[2];
    scn_scene scene;
    eng_draw draws[2];
    eng_light_pose light;
    eng_frame_scene fs;
    eng_rt *rt;
} pane_scene;

static scn_material diffuse(float r, float g, float b, float a)
{
    scn_scene none;
    memset(&none, 0, sizeof none);
    scn_material m = eng_material_of(&none, -1); /* glTF's default material, then diffuse */
    m.base_color[0] = r;
    m.base_color[1] = g;
    m.base_color[2] = b;
    m.base_color[3] = a;
    m.metallic = 0.0f;
    m.double_sided = 1;
    return m;
}

static void pane_init(pane_scene *t, float intensity)
{
    memset(t, 0, sizeof *t);
    const float half[2] = {4.0f, 1.0f}, y[2] = {0.0f, 0.5f};
    const float corners[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    for (int p = 0; p < 2; p++) {
        for (int v = 0; v < 4; v++) {
            t->pos[p][3 * v] = half[p] * corners[v][0];
            t->pos[p][3 * v + 1] = y[p];
            t->pos[p][3 * v + 2] = half[p] * corners[v][1];
            t->nrm[p][3 * v + 1] = 1.0f;
        }
        const uint32_t q[6] = {0, 2, 1, 0, 3, 2};
        memcpy(t->idx[p], q, sizeof q);
        t->prim[p] = (scn_primitive){.vertex_count = 4, .positions = t->pos[p], .normals = t->nrm[p], .index_count = 6,
                                     .indices = t->idx[p], .material = p};
        t->draws[p].primitive = (uint32_t)p;
        t->draws[p].material = p;
        m4_identity(t->draws[p].world);
        m4_identity(t->draws[p].prev_world);
    }
    t->mat[0] = diffuse(0.5f, 0.5f, 0.5f, 1.0f);
    t->mat[1] = diffuse(0.2f, 0.4f, 0.8f, 0.5f);
    t->mat[1].alpha_mode = SCN_ALPHA_BLEND;
    t->scene.primitive_count = 2;
    t->scene.primitives = t->prim;
    t->scene.material_count = 2;
    t->scene.materials = t->mat;
    t->light.type = SCN_LIGHT_POINT;
    t->light.position[1] = 1.0f;
    t->light.radiance_scale[0] = t->light.radiance_scale[1] = t->light.radiance_scale[2] = intensity;
    t->fs.scene = &t->scene;
    t->fs.draw_count = 2;
    t->fs.draws = t->draws;
    t->fs.light_count = 1;
    t->fs.lights = &t->light;
    t->fs.bounds_min[0] = t->fs.bounds_min[2] = -4.0f;
    t->fs.bounds_max[0] = t->fs.bounds_max[2] = 4.0f;
    t->fs.bounds_max[1] = 2.0f;
    const float eye[3] = {0, 2, 0}, target[3] = {0, 0, 0}, up[3] = {0, 0, -1};
    float view[16], proj[16];
    m4_look_at(view, eye, target, up);
    m4_perspective(proj, 1.2f, 1.0f, 0.1f, 10.0f);
    m4_mul(t->fs.camera.view_proj, proj, view);
    memcpy(t->fs.camera.eye, eye, sizeof eye);
    eng_error err;
    ck_assert_int_eq(rt_create(&t->scene, 2, &t->rt, &err), ENG_OK);
    rt_update(t->rt, &t->fs);
}

START_TEST(blend_only_in_its_scene)
{
    pane_scene t;
    pane_init(&t, 1.0f);
    ck_assert(rt_has_blend(t.rt));
    const float org[3] = {0, 2, 0}, down[3] = {0, -1, 0};
    rt_hit h;
    /* The opaque rays (photons, shadows, specular paths) pass through the pane to the floor. */
    ck_assert(rt_intersect(t.rt, org, down, 0.0f, INFINITY, &h));
    ck_assert_float_eq_tol(h.t, 2.0f, 1e-5f);
    ck_assert_int_eq(h.material, 0);
    const float below[3] = {0, 0.01f, 0}, light[3] = {0, 1, 0};
    ck_assert(!rt_occluded(t.rt, below, light));
    /* rt_intersect_blend sees the pane only. */
    ck_assert(rt_intersect_blend(t.rt, org, down, 0.0f, INFINITY, &h));
    ck_assert_float_eq_tol(h.t, 1.5f, 1e-5f);
    ck_assert_int_eq(h.material, 1);
    ck_assert(!rt_intersect_blend(t.rt, org, down, 0.0f, 1.4f, &h)); /* bounded by tfar (the opaque hit) */
    ck_assert(tl_scene_has_blend(&t.scene));
    rt_destroy(t.rt);
}
END_TEST

START_TEST(pane_value_and_threads)
{
    enum { W = 48, H = 48 };
    pane_scene t;
    const float intensity = 2.0f;
    pane_init(&t, intensity);
    eng_settings s;
    memset(&s, 0, sizeof s);
    eng_settings_defaults(&s);
    static float img[2][W * H * 4];
    eng_error err;
    for (int run = 0; run < 2; run++) {
        s.threads = run ? 3 : 1;
        ck_assert_int_eq(tl_render(&t.fs, t.rt, NULL, W, H, NULL, NULL, &s, img[run], &err), ENG_OK);
    }
    ck_assert(memcmp(img[0], img[1], sizeof img[0]) == 0);
    /* Centre pixel: the pane 0.5 m below the light, lit from its top side at cosine ~1 (the
     * light is above, the eye too): L = ρ/π · I/d² · cos, times α = 0.5; a = 0.5. */
    const float *c = img[0] + 4 * ((size_t)(H / 2) * W + W / 2);
    ck_assert_float_eq(c[3], 0.5f);
    for (int k = 0; k < 3; k++) {
        double want = 0.5 * t.mat[1].base_color[k] / ENG_PI * intensity / 0.25;
        ck_assert_double_eq_tol(c[k], want, 0.02 * want);
    }
    /* A corner pixel sees the floor beyond the pane's edge: no layer. */
    ck_assert(img[0][3] == 0.0f && img[0][0] == 0.0f);
    rt_destroy(t.rt);
}
END_TEST

static Suite *translucent_suite(void)
{
    Suite *s = suite_create("translucent");
    TCase *t = tcase_create("translucent");
    tcase_add_test(t, composite_back_to_front);
    tcase_add_test(t, composite_matches_front_to_back);
    tcase_add_test(t, blend_only_in_its_scene);
    tcase_add_test(t, pane_value_and_threads);
    suite_add_tcase(s, t);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(translucent_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
