/* test_specular.c — Check suite of the specular eye paths (specular.h, spec_traced.c): the
 * Fresnel split of glass into both weighted branches (energy kept, Snell's law, 4% at normal
 * incidence), total internal reflection, a smooth metal's Schlick weight, which materials
 * count as specular, the depth cap between two mirrors, the radiance of a diffuse ceiling
 * seen in a mirror against its closed form, an emitter seen in a mirror, and bit-identical
 * results for any thread count, and the two settings as the sequence parser reads them. */
#include "bsdf.h"
#include "seq.h"
#include "specular.h"

#include <check.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static scn_material material(float grey, float metallic, float roughness, float transmission)
{
    scn_material m;
    memset(&m, 0, sizeof m);
    m.base_color[0] = m.base_color[1] = m.base_color[2] = grey;
    m.base_color[3] = 1.0f;
    m.metallic = metallic;
    m.roughness = roughness;
    m.transmission = transmission;
    m.ior = 1.5f;
    return m;
}

START_TEST(split_glass_fresnel)
{
    scn_material glass = material(1.0f, 0.0f, 0.0f, 1.0f);
    const float n[3] = {0.0f, 0.0f, 1.0f};
    eye_branch b[2];
    /* Normal incidence: R = ((1 − 1.5)/(1 + 1.5))² = 0.04. */
    const float up[3] = {0.0f, 0.0f, 1.0f};
    ck_assert_int_eq(eye_split(&glass, n, up, 1.0f, b), 2);
    ck_assert_float_eq_tol(b[0].weight[0], 0.04f, 1e-6f);
    ck_assert_float_eq_tol(b[1].weight[0], 0.96f, 1e-6f);
    ck_assert_float_eq_tol(b[1].dir[2], -1.0f, 1e-6f);
    ck_assert_float_eq(b[1].eta, 1.5f);
    /* Oblique: weights sum to 1 (white glass), reflection is the mirror image, refraction obeys
     * Snell's law sinθt = sinθi / 1.5 and goes into the glass. */
    for (int k = 1; k < 9; k++) {
        float th = (float)k * 0.17f;
        float wi[3] = {sinf(th), 0.0f, cosf(th)};
        ck_assert_int_eq(eye_split(&glass, n, wi, 1.0f, b), 2);
        ck_assert_float_eq_tol(b[0].weight[1] + b[1].weight[1], 1.0f, 1e-6f);
        ck_assert_float_eq_tol(b[0].dir[0], -wi[0], 1e-6f);
        ck_assert_float_eq_tol(b[0].dir[2], wi[2], 1e-6f);
        ck_assert_float_eq_tol(-b[1].dir[0], sinf(th) / 1.5f, 1e-5f);
        ck_assert(b[1].dir[2] < 0.0f);
        ck_assert(b[0].weight[0] > 0.04f - 1e-6f); /* R grows toward grazing */
    }
    /* A tinted glass tints only the refracted branch. */
    glass.base_color[1] = 0.5f;
    ck_assert_int_eq(eye_split(&glass, n, up, 1.0f, b), 2);
    ck_assert_float_eq_tol(b[0].weight[1], 0.04f, 1e-6f);
    ck_assert_float_eq_tol(b[1].weight[1], 0.48f, 1e-6f);
}
END_TEST

START_TEST(split_total_internal_reflection)
{
    scn_material glass = material(1.0f, 0.0f, 0.0f, 1.0f);
    const float n[3] = {0.0f, 0.0f, 1.0f}; /* outward; the viewer is inside (wi·n < 0) */
    eye_branch b[2];
    float crit = asinf(1.0f / 1.5f);
    float beyond[3] = {sinf(crit + 0.05f), 0.0f, -cosf(crit + 0.05f)};
    ck_assert_int_eq(eye_split(&glass, n, beyond, 1.5f, b), 1);
    for (int c = 0; c < 3; c++)
        ck_assert_float_eq(b[0].weight[c], 1.0f);
    ck_assert_float_eq_tol(b[0].dir[2], beyond[2], 1e-6f); /* mirrored about n: stays inside */
    ck_assert_float_eq_tol(b[0].dir[0], -beyond[0], 1e-6f);
    ck_assert_float_eq(b[0].eta, 1.5f);
    float below[3] = {sinf(crit - 0.05f), 0.0f, -cosf(crit - 0.05f)};
    ck_assert_int_eq(eye_split(&glass, n, below, 1.5f, b), 2);
    ck_assert(b[1].dir[2] > 0.0f); /* leaves into the air */
    ck_assert_float_eq(b[1].eta, 1.0f);
    ck_assert_float_eq_tol(b[0].weight[0] + b[1].weight[0], 1.0f, 1e-6f);
}
END_TEST

START_TEST(split_metal_and_opaque)
{
    const float n[3] = {0.0f, 1.0f, 0.0f};
    const float wi[3] = {0.6f, 0.8f, 0.0f};
    eye_branch b[2];
    scn_material mirror = material(0.5f, 1.0f, 0.0f, 0.0f);
    ck_assert(eye_is_specular(&mirror));
    ck_assert_int_eq(eye_split(&mirror, n, wi, 1.0f, b), 1);
    float k = 1.0f - 0.8f, schlick = 0.5f + 0.5f * k * k * k * k * k;
    ck_assert_float_eq_tol(b[0].weight[0], schlick, 1e-6f);
    ck_assert_float_eq_tol(b[0].dir[0], -0.6f, 1e-6f);
    ck_assert_float_eq_tol(b[0].dir[1], 0.8f, 1e-6f);
    /* Half mirror, half diffuse: half the weight. */
    scn_material half = material(0.5f, 0.5f, 0.0f, 0.0f);
    ck_assert_int_eq(eye_split(&half, n, wi, 1.0f, b), 1);
    ck_assert_float_eq_tol(b[0].weight[0], 0.5f * schlick, 1e-6f);
    /* At the threshold and above, and diffuse surfaces: nothing specular. */
    scn_material rough = material(0.5f, 1.0f, BSDF_MIRROR_ROUGHNESS, 0.0f);
    scn_material diffuse = material(0.5f, 0.0f, 0.0f, 0.0f);
    ck_assert(!eye_is_specular(&rough));
    ck_assert(!eye_is_specular(&diffuse));
    ck_assert_int_eq(eye_split(&rough, n, wi, 1.0f, b), 0);
    ck_assert_int_eq(eye_split(&diffuse, n, wi, 1.0f, b), 0);
}
END_TEST

/* ---------------------------------------------------------------- a hand-made scene */

/* Two horizontal squares of half-size 4: a floor at y = 0 (material 0, normal +y) and a
 * ceiling at y = 1 (material 1, normal −y), one point light of intensity I at (0, 0.5, 0). */
typedef struct two_planes {
    float pos[2][12], nrm[2][12];
    uint32_t idx[2][6];
    scn_primitive prim[2];
    scn_material mat[2];
    scn_scene scene;
    eng_draw draws[2];
    eng_light_pose light;
    eng_frame_scene fs;
    eng_rt *rt;
} two_planes;

static void two_planes_init(two_planes *t, scn_material floor, scn_material ceiling, float intensity)
{
    memset(t, 0, sizeof *t);
    const float corners[4][2] = {{-4, -4}, {4, -4}, {4, 4}, {-4, 4}};
    for (int p = 0; p < 2; p++) {
        for (int v = 0; v < 4; v++) {
            t->pos[p][3 * v] = corners[v][0];
            t->pos[p][3 * v + 1] = (float)p;
            t->pos[p][3 * v + 2] = corners[v][1];
            t->nrm[p][3 * v + 1] = p ? -1.0f : 1.0f;
        }
        const uint32_t q[6] = {0, 1, 2, 0, 2, 3};
        memcpy(t->idx[p], q, sizeof q);
        t->prim[p] = (scn_primitive){.vertex_count = 4, .positions = t->pos[p], .normals = t->nrm[p], .index_count = 6,
                                     .indices = t->idx[p], .material = p};
        t->draws[p].primitive = (uint32_t)p;
        t->draws[p].material = p;
        const float id[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
        memcpy(t->draws[p].world, id, sizeof id);
        memcpy(t->draws[p].prev_world, id, sizeof id);
    }
    t->mat[0] = floor;
    t->mat[1] = ceiling;
    t->mat[0].double_sided = t->mat[1].double_sided = 1;
    t->scene.primitive_count = 2;
    t->scene.primitives = t->prim;
    t->scene.material_count = 2;
    t->scene.materials = t->mat;
    t->light.type = SCN_LIGHT_POINT;
    t->light.position[1] = 0.5f;
    t->light.radiance_scale[0] = t->light.radiance_scale[1] = t->light.radiance_scale[2] = intensity;
    t->fs.scene = &t->scene;
    t->fs.draw_count = 2;
    t->fs.draws = t->draws;
    t->fs.light_count = 1;
    t->fs.lights = &t->light;
    t->fs.bounds_min[0] = t->fs.bounds_min[2] = -4.0f;
    t->fs.bounds_max[0] = t->fs.bounds_max[2] = 4.0f;
    t->fs.bounds_max[1] = 1.0f;
    eng_error err;
    ck_assert_int_eq(rt_create(&t->scene, 2, &t->rt, &err), ENG_OK);
    rt_update(t->rt, &t->fs);
}

static eye_tracer *tracer(const two_planes *t, int depth)
{
    eng_settings s;
    memset(&s, 0, sizeof s);
    s.specular_depth = depth;
    eng_settings_defaults(&s);
    eng_error err;
    eye_tracer *tr = eye_tracer_create(&t->fs, t->rt, NULL, NULL, &s, &err);
    ck_assert_ptr_nonnull(tr);
    return tr;
}

START_TEST(mirror_shows_lit_ceiling)
{
    two_planes t;
    const float intensity = 3.0f;
    two_planes_init(&t, material(1.0f, 1.0f, 0.0f, 0.0f), material(0.5f, 0.0f, 1.0f, 0.0f), intensity);
    eye_tracer *tr = tracer(&t, 4);
    eye_scratch sc = {NULL, 0};
    /* The eye at (−0.5, 0.5, 0) sees the mirror at the origin at 45°; the reflected ray meets
     * the ceiling at (1, 1, 0), lit by the light at distance √1.25 and cosine 0.5/√1.25. */
    const float p[3] = {0, 0, 0}, n[3] = {0, 1, 0}, eye[3] = {-0.5f, 0.5f, 0.0f};
    float rad[3], thr[3], depth;
    eye_tracer_pixel(tr, p, n, &t.mat[0], eye, &sc, rad, &depth, thr);
    double d2 = 1.25, cosl = 0.5 / sqrt(d2);
    double want = 0.5 / ENG_PI * intensity / d2 * cosl; /* mirror weight 1: F0 = 1 */
    /* The reflected ray starts bsdf_offset_eps above the mirror: ~1e-4 of the distances. */
    ck_assert_double_eq_tol(rad[0], want, 1e-3 * want);
    ck_assert_float_eq(depth, 1.0f);
    ck_assert_float_eq_tol(thr[1], 1.0f, 1e-6f);
    /* A diffuse G-buffer surface gets nothing from this pass. */
    eye_tracer_pixel(tr, p, n, &t.mat[1], eye, &sc, rad, &depth, thr);
    ck_assert(rad[0] == 0.0f && depth == 0.0f && thr[0] == 0.0f);
    eye_tracer_destroy(tr);
    free(sc.list);
    rt_destroy(t.rt);
}
END_TEST

START_TEST(mirror_shows_emitter)
{
    two_planes t;
    scn_material ceiling = material(0.5f, 0.0f, 1.0f, 0.0f);
    ceiling.emissive[0] = 2.0f;
    ceiling.emissive[2] = 0.5f;
    two_planes_init(&t, material(1.0f, 1.0f, 0.0f, 0.0f), ceiling, 0.0f); /* no light: emission only */
    eye_tracer *tr = tracer(&t, 4);
    eye_scratch sc = {NULL, 0};
    const float p[3] = {0, 0, 0}, n[3] = {0, 1, 0}, eye[3] = {-0.5f, 0.5f, 0.0f};
    float rad[3], thr[3], depth;
    eye_tracer_pixel(tr, p, n, &t.mat[0], eye, &sc, rad, &depth, thr);
    ck_assert_float_eq_tol(rad[0], 2.0f, 1e-6f);
    ck_assert_float_eq(rad[1], 0.0f);
    ck_assert_float_eq_tol(rad[2], 0.5f, 1e-6f);
    eye_tracer_destroy(tr);
    free(sc.list);
    rt_destroy(t.rt);
}
END_TEST

START_TEST(ray_passes_through_its_object)
{
    /* eye_tracer_ray, what the envmap's texels are made with: from below the mirror floor
     * straight up, passing through the floor (draw 0) to the lit ceiling; without the pass the
     * floor's underside mirrors the ray down into nothing. */
    two_planes t;
    const float intensity = 2.0f;
    two_planes_init(&t, material(1.0f, 1.0f, 0.0f, 0.0f), material(0.5f, 0.0f, 1.0f, 0.0f), intensity);
    eye_tracer *tr = tracer(&t, 4);
    eye_scratch sc = {NULL, 0};
    const float org[3] = {0.0f, -0.5f, 0.0f}, up[3] = {0.0f, 1.0f, 0.0f};
    float rad[3];
    eye_tracer_ray(tr, org, up, 0, &sc, rad);
    double want = 0.5 / ENG_PI * intensity / 0.25; /* ceiling 0.5 m above the light, cos 1 */
    ck_assert_double_eq_tol(rad[0], want, 1e-3 * want);
    eye_tracer_ray(tr, org, up, UINT32_MAX, &sc, rad);
    ck_assert_float_eq(rad[0], 0.0f);
    eye_tracer_destroy(tr);
    free(sc.list);
    rt_destroy(t.rt);
}
END_TEST

START_TEST(depth_cap_between_mirrors)
{
    two_planes t;
    two_planes_init(&t, material(1.0f, 1.0f, 0.0f, 0.0f), material(1.0f, 1.0f, 0.0f, 0.0f), 1.0f);
    eye_scratch sc = {NULL, 0};
    const float p[3] = {0, 0, 0}, n[3] = {0, 1, 0}, eye[3] = {-0.05f, 0.5f, 0.0f};
    for (int cap = 1; cap <= 8; cap++) {
        eye_tracer *tr = tracer(&t, cap);
        float rad[3], thr[3], depth;
        eye_tracer_pixel(tr, p, n, &t.mat[0], eye, &sc, rad, &depth, thr);
        /* Every bounce lands on a mirror: the path stops at the cap and adds nothing. */
        ck_assert_float_eq(depth, (float)cap);
        ck_assert(rad[0] == 0.0f && thr[0] == 0.0f);
        eye_tracer_destroy(tr);
    }
    free(sc.list);
    rt_destroy(t.rt);
}
END_TEST

START_TEST(same_for_any_thread_count)
{
    two_planes t;
    scn_material glassy = material(0.9f, 0.0f, 0.0f, 0.5f); /* half glass, half diffuse */
    two_planes_init(&t, glassy, material(0.5f, 0.3f, 0.4f, 0.0f), 2.0f);
    eye_tracer *tr = tracer(&t, 4);
    enum { N = 64 };
    float out[2][N * N * 3];
    for (int run = 0; run < 2; run++) {
#pragma omp parallel num_threads(run ? 3 : 1)
        {
            eye_scratch sc = {NULL, 0};
#pragma omp for schedule(dynamic, 1)
            for (int i = 0; i < N * N; i++) {
                float p[3] = {-2.0f + 4.0f * (float)(i % N) / N, 0.0f, -2.0f + 4.0f * (float)(i / N) / N};
                const float n[3] = {0, 1, 0}, eye[3] = {0.1f, 0.7f, 0.2f};
                float thr[3], depth;
                eye_tracer_pixel(tr, p, n, &t.mat[0], eye, &sc, out[run] + 3 * i, &depth, thr);
            }
            free(sc.list);
        }
    }
    ck_assert(memcmp(out[0], out[1], sizeof out[0]) == 0);
    float sum = 0.0f;
    for (int i = 0; i < N * N * 3; i++)
        sum += out[0][i];
    ck_assert(sum > 0.0f); /* the ceiling is seen through the glass half and lit */
    eye_tracer_destroy(tr);
    rt_destroy(t.rt);
}
END_TEST

/* The settings: "specular" is one of three words, "specular_depth" 1..16, defaults traced/4. */
static eng_result parse_settings(const char *settings, seq_sequence *q, eng_error *err)
{
    char json[512];
    snprintf(json, sizeof json,
             "{\"name\": \"s\", \"scene\": \"x.gltf\", \"frames\": 1, \"fps\": 1, \"resolution\": [8, 8], "
             "\"camera\": {\"node\": \"Camera\"}, \"settings\": {%s}}",
             settings);
    return seq_parse("/d/seq.json", json, strlen(json), q, err);
}

START_TEST(settings_parsed)
{
    static seq_sequence q;
    eng_error err;
    ck_assert_int_eq(parse_settings("", &q, &err), ENG_OK);
    eng_settings_defaults(&q.settings);
    ck_assert_int_eq(q.settings.specular, ENG_SPECULAR_TRACED);
    ck_assert_int_eq(q.settings.specular_depth, 4);
    ck_assert_ptr_eq(spec_method_find(eng_specular_name(q.settings.specular)), &spec_traced_method);
    ck_assert_int_eq(parse_settings("\"specular\": \"envmap\", \"specular_depth\": 16", &q, &err), ENG_OK);
    ck_assert_int_eq(q.settings.specular, ENG_SPECULAR_ENVMAP);
    ck_assert_int_eq(q.settings.specular_depth, 16);
    ck_assert_ptr_eq(spec_method_find(eng_specular_name(q.settings.specular)), &spec_envmap_method);
    ck_assert_int_eq(parse_settings("\"specular\": \"off\"", &q, &err), ENG_OK);
    ck_assert_ptr_null(spec_method_find(eng_specular_name(q.settings.specular)));
    ck_assert_str_eq(eng_specular_name(q.settings.specular), "off");
    ck_assert_int_eq(parse_settings("\"specular\": \"mirror\"", &q, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "/d/seq.json") && strstr(err.msg, "settings.specular"), "%s", err.msg);
    ck_assert_int_eq(parse_settings("\"specular_depth\": 0", &q, &err), ENG_ERR_INVALID);
    ck_assert_int_eq(parse_settings("\"specular_depth\": 17", &q, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "settings.specular_depth"), "%s", err.msg);
}
END_TEST

static Suite *specular_suite(void)
{
    Suite *s = suite_create("specular");
    TCase *t = tcase_create("specular");
    tcase_add_test(t, split_glass_fresnel);
    tcase_add_test(t, split_total_internal_reflection);
    tcase_add_test(t, split_metal_and_opaque);
    tcase_add_test(t, mirror_shows_lit_ceiling);
    tcase_add_test(t, mirror_shows_emitter);
    tcase_add_test(t, ray_passes_through_its_object);
    tcase_add_test(t, depth_cap_between_mirrors);
    tcase_add_test(t, same_for_any_thread_count);
    tcase_add_test(t, settings_parsed);
    suite_add_tcase(s, t);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(specular_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
