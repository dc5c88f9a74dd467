/* test_shadow.c — Check suite for the shadow methods (engine/passes/shadow.h, shadow_pcss.c) and the
 * light sizes of the glTF loader (issue 15).
 *
 * Topics: the penumbra radius of 001 Eq. 5 against hand-computed values (sphere and
 * directional disc); the blocker search on synthetic shadow maps (a flat receiver with a
 * square occluder, a sloped receiver that must not shadow itself, an empty map); the method
 * table; the rays of pcss_blocker "rays" on synthetic ortho maps (a flat floor, a half-plane
 * occluder against the disc segments it hides, receivers hidden behind it, a box standing on
 * the floor, a sloped receiver); the lamps of lights with a size in the Embree scene (rt_lamp_hit, rt_intersect);
 * light sizes read from glTF extras, and one malformed file per rule. Tests check
 * result codes, never message text. */
#include "shadow.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DATA ISPM_SOURCE_DIR "/tests/data/gltf/"

/* ---------------------------------------------------------------- penumbra (Eq. 5) */

START_TEST(penumbra_sphere)
{
    /* R = 0.3 m, receiver 2 m, blocker 1.5 m: R·(D−d_b)/d_b = 0.1 m at the receiver, which
     * spans 0.1/2 = 0.05 of unit distance, i.e. 25 texels of 0.002. */
    ck_assert_float_eq_tol(shadow_penumbra_texels(0, 0.3f, 2.0f, 1.5f, 0.002f), 25.0f, 1e-3f);
    /* Contact: the blocker at the receiver makes no penumbra. */
    ck_assert_float_eq_tol(shadow_penumbra_texels(0, 0.3f, 2.0f, 2.0f, 0.002f), 0.0f, 1e-6f);
    /* Linear in the light's radius. */
    float a = shadow_penumbra_texels(0, 0.05f, 2.2f, 1.7f, 0.002f);
    float b = shadow_penumbra_texels(0, 0.15f, 2.2f, 1.7f, 0.002f);
    ck_assert_float_eq_tol(b, 3.0f * a, 1e-4f);
}
END_TEST

START_TEST(penumbra_directional)
{
    /* tan α = 0.01, blocker 0.5 m in front of the receiver, texels of 1 cm: 0.5 texel. */
    ck_assert_float_eq_tol(shadow_penumbra_texels(1, 0.01f, 3.0f, 2.5f, 0.01f), 0.5f, 1e-5f);
}
END_TEST

START_TEST(search_radius)
{
    /* A sphere light: r·(z − near)/(z·near·texel). */
    ck_assert_float_eq_tol(shadow_search_texels(0, 0.1f, 2.0f, 0.5f, 0.002f), 0.1f * 1.5f / (1.0f * 0.002f), 1e-2f);
    ck_assert_float_eq_tol(shadow_search_texels(0, 0.1f, 0.4f, 0.5f, 0.002f), 0.0f, 1e-6f);
    ck_assert_float_eq_tol(shadow_search_texels(1, 0.01f, 2.0f, 0.0f, 0.01f), 2.0f, 1e-5f);
}
END_TEST

/* ---------------------------------------------------------------- blocker search */

#define N 64

/* A flat receiver at depth 2 with a square occluder at depth 1.5 over texels [20, 40)². */
static float *square_map(void)
{
    float *m = malloc(N * N * sizeof *m);
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++)
            m[y * N + x] = x >= 20 && x < 40 && y >= 20 && y < 40 ? 1.5f : 2.0f;
    return m;
}

START_TEST(blocker_square)
{
    float *m = square_map();
    /* Blocker-map texels (half resolution) just outside the occluder find it (exactly its
     * depth)... */
    ck_assert_float_eq_tol(shadow_blocker_cpu(m, N, 100.0f, 0, 0.3f, 0.45f, 0.02f, 21, 15), 1.5f, 1e-6f);
    ck_assert_float_eq_tol(shadow_blocker_cpu(m, N, 100.0f, 0, 0.3f, 0.45f, 0.02f, 15, 9), 1.5f, 1e-6f);
    /* ...far from it they find nothing, and the occluder itself has nothing in front. */
    ck_assert_float_eq(shadow_blocker_cpu(m, N, 100.0f, 0, 0.3f, 0.45f, 0.02f, 1, 1), 0.0f);
    ck_assert_float_eq(shadow_blocker_cpu(m, N, 100.0f, 0, 0.3f, 0.45f, 0.02f, 15, 15), 0.0f);
    /* A tiny light searches only its neighbours (radius clamps to 1 texel). */
    ck_assert_float_eq(shadow_blocker_cpu(m, N, 100.0f, 0, 1e-5f, 0.45f, 0.02f, 23, 15), 0.0f);
    free(m);
}
END_TEST

START_TEST(blocker_block_receiver)
{
    /* Blocker-map texels 19 and 20 cover shadow texels 38–39 (occluder) and 40–41 (floor):
     * the first finds nothing in front of the occluder, the second finds the occluder. With
     * texel 40 made occluder too, block 20 straddles the edge and its farther texel (41, the
     * floor) is the receiver, so it still finds the occluder. */
    float *m = square_map();
    ck_assert_float_eq(shadow_blocker_cpu(m, N, 100.0f, 0, 0.3f, 0.45f, 0.02f, 19, 15), 0.0f);
    ck_assert_float_eq_tol(shadow_blocker_cpu(m, N, 100.0f, 0, 0.3f, 0.45f, 0.02f, 20, 15), 1.5f, 1e-6f);
    for (int y = 0; y < N; y++)
        m[y * N + 40] = 1.5f;
    ck_assert_float_eq_tol(shadow_blocker_cpu(m, N, 100.0f, 0, 0.3f, 0.45f, 0.02f, 20, 15), 1.5f, 1e-6f);
    free(m);
}
END_TEST

START_TEST(blocker_sloped_receiver)
{
    /* A plane rising 2 cm per texel along x, with no occluder: never its own blocker. */
    float *m = malloc(N * N * sizeof *m);
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++)
            m[y * N + x] = 1.0f + 0.02f * (float)x;
    for (int x = 4; x < N / 2 - 4; x += 3)
        ck_assert_float_eq(shadow_blocker_cpu(m, N, 100.0f, 0, 0.3f, 0.45f, 0.002f, x, 15), 0.0f);
    /* A step of 0.5 m toward the light at x >= 40: blockers for x just below 40. */
    for (int y = 0; y < N; y++)
        for (int x = 40; x < N; x++)
            m[y * N + x] -= 0.5f;
    float b = shadow_blocker_cpu(m, N, 100.0f, 0, 0.3f, 0.45f, 0.002f, 18, 15);
    ck_assert(b >= 1.3f && b <= 1.76f); /* the stepped plane between x = 40 and 63 */
    free(m);
}
END_TEST

START_TEST(blocker_empty)
{
    float *m = malloc(N * N * sizeof *m);
    for (int i = 0; i < N * N; i++)
        m[i] = 50.0f;
    ck_assert_float_eq(shadow_blocker_cpu(m, N, 50.0f, 0, 0.3f, 0.45f, 0.02f, 15, 15), 0.0f);
    free(m);
}
END_TEST

/* ---------------------------------------------------------------- rays */

/* The share of a disc of radius 1 beyond a chord at distance d from its centre (d in −1..1). */
static double disc_beyond(double d)
{
    if (d <= -1.0)
        return 1.0;
    if (d >= 1.0)
        return 0.0;
    return (acos(d) - d * sqrt(1.0 - d * d)) / 3.14159265358979323846;
}

/* A floor at depth 2 and, where x < edge, an occluder at depth occ (ortho texels of 1 cm). */
static float *half_plane_map(int edge, float occ)
{
    float *m = malloc(N * N * sizeof *m);
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++)
            m[y * N + x] = x < edge ? occ : 2.0f;
    return m;
}

START_TEST(rays_flat_floor)
{
    float *m = half_plane_map(0, 1.0f);
    for (int x = 2; x < N - 2; x += 5)
        ck_assert_float_eq(shadow_rays_cpu(m, N, 0.1f, 0.01f, 0.002f, (float)x + 0.5f, 31.5f, 2.0f), 1.0f);
    free(m);
}
END_TEST

START_TEST(rays_half_plane)
{
    /* tan α = 0.1, the occluder's plane 1 m above the floor: the penumbra is 0.1 m either side of
     * the edge's projection (x = 32), 10 texels. A ray from receiver x toward the disc's point
     * (ρ, a) reaches the occluder's depth at x + 1 m · ρ cos a / 1 cm: it is blocked when that is
     * left of the edge, so the visibility is the disc's share beyond the chord at
     * (32 − x) texels / 10. Hidden receivers (x < 32, behind the occluder from the light's
     * centre) see the light past the edge too. Sixteen rays, their spiral turned per texel:
     * each texel within 3/16 of the exact share, and their mean error over the penumbra (the
     * texels of several rows) within 1/32. */
    float *m = half_plane_map(32, 1.0f);
    double sum = 0.0, count = 0.0;
    for (int y = 20; y < 44; y += 3)
        for (int x = 18; x < 46; x++) {
            float v = shadow_rays_cpu(m, N, 0.1f, 0.01f, 0.002f, (float)x + 0.5f, (float)y + 0.5f, 2.0f);
            double want = disc_beyond((32.0 - ((double)x + 0.5)) / 10.0);
            ck_assert_msg(fabs(v - want) <= 0.1875, "x %d: visibility %g, the disc beyond the edge %g", x, v, want);
            sum += v - want;
            count += 1.0;
        }
    ck_assert_msg(fabs(sum / count) <= 1.0 / 32.0, "mean error %g", sum / count);
    ck_assert_float_eq(shadow_rays_cpu(m, N, 0.1f, 0.01f, 0.002f, 20.5f, 31.5f, 2.0f), 0.0f);
    ck_assert_float_eq(shadow_rays_cpu(m, N, 0.1f, 0.01f, 0.002f, 44.5f, 31.5f, 2.0f), 1.0f);
    /* A hidden receiver 3 texels in from the edge still sees a quarter of the light. */
    float hidden = shadow_rays_cpu(m, N, 0.1f, 0.01f, 0.002f, 29.5f, 31.5f, 2.0f);
    ck_assert(hidden >= 0.125f && hidden <= 0.5f);
    free(m);
}
END_TEST

START_TEST(rays_contact)
{
    /* A box 0.6 m high standing on the floor over x < 32 (its top at depth 1.4; the ortho light
     * above sees none of its sides). The penumbra beside it narrows to the box's height:
     * 0.6 m · 0.1 = 6 texels where the half plane 1 m up gave 10. */
    float *m = half_plane_map(32, 1.4f);
    for (int y = 20; y < 44; y += 3)
        for (int x = 32; x < 40; x++) {
            float v = shadow_rays_cpu(m, N, 0.1f, 0.01f, 0.002f, (float)x + 0.5f, (float)y + 0.5f, 2.0f);
            double want = disc_beyond((32.0 - ((double)x + 0.5)) / 6.0);
            ck_assert_msg(fabs(v - want) <= 0.1875, "x %d: visibility %g, the disc beyond the edge %g", x, v, want);
        }
    ck_assert_float_eq(shadow_rays_cpu(m, N, 0.1f, 0.01f, 0.002f, 38.5f, 31.5f, 2.0f), 1.0f);
    free(m);
}
END_TEST

START_TEST(rays_sloped_receiver)
{
    /* A plane rising 2 mm per texel along x (toward the light), no occluder: never its own
     * occluder, whatever the direction of the rays. */
    float *m = malloc(N * N * sizeof *m);
    for (int y = 0; y < N; y++)
        for (int x = 0; x < N; x++)
            m[y * N + x] = 2.0f - 0.002f * (float)x;
    for (int x = 4; x < N - 4; x += 7) {
        float v = 2.0f - 0.002f * ((float)x + 0.5f);
        ck_assert_float_eq(shadow_rays_cpu(m, N, 0.05f, 0.01f, 0.002f, (float)x + 0.5f, 20.5f, v), 1.0f);
    }
    free(m);
}
END_TEST

/* ---------------------------------------------------------------- method table */

START_TEST(method_of_light)
{
    eng_light_pose l;
    memset(&l, 0, sizeof l);
    ck_assert_int_eq(shadow_method_index(&l), 0);
    ck_assert_str_eq(shadow_methods[0]->name, "pcf");
    ck_assert_ptr_null(shadow_methods[0]->outputs);
    l.radius = 0.1f;
    ck_assert_int_eq(shadow_method_index(&l), 1);
    ck_assert_str_eq(shadow_methods[1]->name, "pcss");
    ck_assert_str_eq(shadow_methods[1]->outputs[0].name, "shadow.light<i>[.face<f>].blocker");
}
END_TEST

/* ---------------------------------------------------------------- lamps (rt.c) */

START_TEST(lamp_hits)
{
    /* A wall (two triangles) at x = 1 and a 0.5 m lamp at the origin. */
    float pos[12] = {1, -5, -5, 1, 5, -5, 1, 5, 5, 1, -5, 5}, nrm[12] = {-1, 0, 0, -1, 0, 0, -1, 0, 0, -1, 0, 0};
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    scn_primitive prim = {.vertex_count = 4, .positions = pos, .normals = nrm, .index_count = 6, .indices = idx, .material = -1};
    scn_scene scene;
    memset(&scene, 0, sizeof scene);
    scene.primitive_count = 1;
    scene.primitives = &prim;
    eng_draw draw;
    memset(&draw, 0, sizeof draw);
    m4_identity(draw.world);
    memcpy(draw.prev_world, draw.world, sizeof draw.world);
    eng_light_pose lights[2];
    memset(lights, 0, sizeof lights);
    lights[0].type = SCN_LIGHT_POINT;
    lights[0].radius = 0.5f;
    lights[1].type = SCN_LIGHT_POINT; /* punctual at (0, 3, 0): never a lamp */
    lights[1].position[1] = 3.0f;
    eng_frame_scene fs;
    memset(&fs, 0, sizeof fs);
    fs.scene = &scene;
    fs.draw_count = 1;
    fs.draws = &draw;
    fs.light_count = 2;
    fs.lights = lights;
    eng_rt *rt = NULL;
    eng_error err;
    ck_assert_int_eq(rt_create(&scene, 1, &rt, &err), ENG_OK);
    rt_update(rt, &fs);
    const float from[3] = {-2, 0, 0}, px[3] = {1, 0, 0};
    float t = 0.0f;
    ck_assert_int_eq(rt_lamp_hit(rt, from, px, 0.0f, 100.0f, -1, &t), 0);
    ck_assert_float_eq_tol(t, 1.5f, 1e-5f);
    ck_assert_int_eq(rt_lamp_hit(rt, from, px, 0.0f, 100.0f, 0, &t), -1); /* skipped */
    ck_assert_int_eq(rt_lamp_hit(rt, from, px, 0.0f, 1.0f, -1, &t), -1);  /* beyond tmax */
    const float origin[3] = {0, 0, 0}, beside[3] = {-2, 0.6f, 0}, above[3] = {-2, 3, 0};
    ck_assert_int_eq(rt_lamp_hit(rt, origin, px, 0.0f, 100.0f, -1, &t), -1); /* starts inside */
    ck_assert_int_eq(rt_lamp_hit(rt, beside, px, 0.0f, 100.0f, -1, &t), -1); /* misses */
    ck_assert_int_eq(rt_lamp_hit(rt, above, px, 0.0f, 100.0f, -1, &t), -1);  /* punctual light */
    /* rt_intersect: the wall behind the lamp is not reached; from inside the lamp, beside it
     * and past it, it is. */
    rt_hit h;
    ck_assert_int_eq(rt_intersect(rt, from, px, 0.0f, 100.0f, &h), 0);
    ck_assert_int_eq(rt_intersect(rt, origin, px, 0.0f, 100.0f, &h), 1);
    ck_assert_float_eq_tol(h.t, 1.0f, 1e-5f);
    ck_assert_int_eq(rt_intersect(rt, beside, px, 0.0f, 100.0f, &h), 1);
    ck_assert_float_eq_tol(h.t, 3.0f, 1e-5f);
    /* Without a size the same light is no lamp. */
    lights[0].radius = 0.0f;
    rt_update(rt, &fs);
    ck_assert_int_eq(rt_intersect(rt, from, px, 0.0f, 100.0f, &h), 1);
    rt_destroy(rt);
}
END_TEST

/* ---------------------------------------------------------------- glTF light sizes */

START_TEST(gltf_light_sizes)
{
    scn_scene *s = NULL;
    eng_error err = {{0}};
    eng_result r = scn_load_gltf(DATA "valid-light-sizes.gltf", &s, &err);
    ck_assert_msg(r == ENG_OK, "%s", err.msg);
    ck_assert_uint_eq(s->light_count, 4);
    ck_assert_float_eq(s->lights[0].radius, 0.25f);
    ck_assert_float_eq(s->lights[1].radius, 0.05f);
    ck_assert_float_eq(s->lights[2].radius, 0.0f);
    ck_assert_float_eq(s->lights[3].radius, 0.0f);
    scn_destroy(s);
}
END_TEST

static const char *const BAD[] = {
    "bad-light-radius-negative.gltf",  "bad-light-radius-string.gltf",        "bad-light-radius-huge.gltf",
    "bad-light-ispm-not-object.gltf",  "bad-light-angular-on-point.gltf",     "bad-light-radius-on-directional.gltf",
    "bad-light-angular-radius.gltf",
};

START_TEST(gltf_bad_light_sizes)
{
    char path[1024];
    snprintf(path, sizeof path, DATA "%s", BAD[_i]);
    scn_scene *s = (scn_scene *)&path;
    eng_error err = {{0}};
    eng_result r = scn_load_gltf(path, &s, &err);
    ck_assert_msg(r == ENG_ERR_INVALID, "%s: got %s (%s)", BAD[_i], eng_result_name(r), err.msg);
    ck_assert_ptr_null(s);
    ck_assert(err.msg[0] != 0 && strchr(err.msg, '\n') == NULL);
    ck_assert_msg(strstr(err.msg, BAD[_i]) != NULL, "message does not name the file: %s", err.msg);
}
END_TEST

int main(void)
{
    Suite *su = suite_create("shadow");
    TCase *tc = tcase_create("penumbra");
    tcase_add_test(tc, penumbra_sphere);
    tcase_add_test(tc, penumbra_directional);
    tcase_add_test(tc, search_radius);
    suite_add_tcase(su, tc);
    tc = tcase_create("blocker");
    tcase_add_test(tc, blocker_square);
    tcase_add_test(tc, blocker_block_receiver);
    tcase_add_test(tc, blocker_sloped_receiver);
    tcase_add_test(tc, blocker_empty);
    tcase_add_test(tc, rays_flat_floor);
    tcase_add_test(tc, rays_half_plane);
    tcase_add_test(tc, rays_contact);
    tcase_add_test(tc, rays_sloped_receiver);
    tcase_add_test(tc, method_of_light);
    tcase_add_test(tc, lamp_hits);
    suite_add_tcase(su, tc);
    tc = tcase_create("gltf");
    tcase_add_test(tc, gltf_light_sizes);
    tcase_add_loop_test(tc, gltf_bad_light_sizes, 0, (int)(sizeof BAD / sizeof BAD[0]));
    suite_add_tcase(su, tc);
    SRunner *sr = srunner_create(su);
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? 1 : 0;
}
