/* test_finalgather.c — Check suite of the final-gather indirect method (engine/indirect/ind_finalgather.c;
 * 003_… Appendix A, Jensen 1996):
 *   - the furnace (scenes/furnace: a closed sphere of albedo ρ with a point light at its
 *     centre): the area mean of indirect.radiance equals the energy balance of any closed
 *     enclosure, ρ²Φ/((1−ρ)πA), as the reference renderer's does (test_reference.c);
 *   - caustics: on the glass-sphere Cornell box the light focused by the sphere onto the floor
 *     (paths L S+ D, which no gather ray can close on a point light) comes from the caustic
 *     photons evaluated at the pixel (eng_photon.caustic, set by the photon trace from the
 *     bounce map's lobe): there the final gather holds what the k-d gather holds, where without
 *     that term it held 0.4 of it;
 *   - emitters add nothing to a gather ray (eye_tracer_gather_ray): they are seen only after
 *     delta lobes, as in the reference renderer;
 *   - determinism: 1 and 3 threads give bit-identical buffers;
 *   - settings: final_gather_rays must be a power of 4, final_gather_radius in (0, 1], and the
 *     boundary correction (a kernel at the pixel) is refused, by the parser and the engine. */
#include "eng.h"
#include "eng_frame.h"
#include "indirect.h"
#include "furnace_test_util.h"
#include "specular.h"
#include "tile_test_util.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CORNELL_DIR ISPM_SOURCE_DIR "/scenes/cornell-box/"
#define FURNACE_DIR ISPM_SOURCE_DIR "/scenes/furnace/"

/* Loads the sequence file seq_path with the settings `extra` merged in (JSON members, no
 * braces), size² pixels, and renders frame 0 into k. */
typedef struct scene_run {
    seq_sequence seq;
    scn_scene *scene;
    eng_engine *engine;
} scene_run;

static void run_open(scene_run *r, const char *seq_path, int size, const char *extra)
{
    eng_error err = {{0}};
    memset(r, 0, sizeof *r);
    ck_assert_msg(seq_load(seq_path, &r->seq, &err) == ENG_OK, "%s", err.msg);
    /* The sequence's own settings, then ours on top, through the parser. */
    char json[4096 + 512];
    snprintf(json, sizeof json,
             "{\"name\":\"fg\",\"scene\":\"%s\",\"frames\":1,\"fps\":1,\"resolution\":[%d,%d],"
             "\"camera\":{\"node\":\"Camera\"},\"settings\":{\"shadow_map_size\":%d,%s}}",
             r->seq.scene_path, size, size, r->seq.settings.shadow_map_size, extra);
    ck_assert_msg(seq_parse(seq_path, json, strlen(json), &r->seq, &err) == ENG_OK, "%s", err.msg);
    ck_assert_msg(scn_load_gltf(r->seq.scene_path, &r->scene, &err) == ENG_OK, "%s", err.msg);
    eng_desc d = {.scene = r->scene, .sequence = &r->seq};
    ck_assert_msg(eng_create(&d, &r->engine, &err) == ENG_OK, "%s", err.msg);
}

static void run_frame(scene_run *r, keeper *k)
{
    eng_error err = {{0}};
    eng_listener l = {k, NULL, keep_buffer, NULL};
    ck_assert_int_eq(eng_add_listener(r->engine, &l), ENG_OK);
    ck_assert_msg(eng_render_frame(r->engine, 0, &err) == ENG_OK, "%s", err.msg);
}

static void run_close(scene_run *r)
{
    eng_destroy(r->engine);
    scn_destroy(r->scene);
}

static void render_sized(const char *seq_path, int size, const char *extra, keeper *k)
{
    k->all = 1;
    scene_run r;
    run_open(&r, seq_path, size, extra);
    run_frame(&r, k);
    run_close(&r);
}

/* ---------------------------------------------------------------- furnace */

static double dot3_d(const float a[3], const double b[3])
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

/* The area mean of indirect.radiance over the furnace sphere's pixels (each pixel weighted by
 * the area it sees, as test_reference.c's furnace_sphere does) against ρ²Φ/((1−ρ)πA). */
static double furnace_ratio(const char *extra, int size)
{
    static keeper k;
    k.all = 1;
    scene_run r;
    run_open(&r, FURNACE_DIR "furnace.json", size, extra);
    run_frame(&r, &k);
    const kept *ind = find(&k, "indirect.radiance");
    ck_assert_ptr_nonnull(ind);
    const double area = furnace_area(r.scene);
    const eng_frame_scene *fs;
    const eng_rt *rt;
    eng_pose(r.engine, 0, &fs, &rt);
    /* The furnace's camera sits at the centre looking down −Z with a 90° field of view. */
    double sum_w = 0.0, sum_wl = 0.0;
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            double d[3] = {(2.0 * (x + 0.5) / size - 1.0), (1.0 - 2.0 * (y + 0.5) / size), -1.0};
            double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int i = 0; i < 3; i++)
                d[i] /= len;
            float dir[3] = {(float)d[0], (float)d[1], (float)d[2]}, org[3] = {0, 0, 0};
            rt_hit h;
            ck_assert(rt_intersect(rt, org, dir, 0.0f, 100.0f, &h));
            double cos_s = fabs(dot3_d(h.geom_normal, d)), cz = -d[2];
            double w = (double)h.t * h.t * cz * cz * cz / cos_s;
            size_t i = 3 * ((size_t)y * (size_t)size + (size_t)x);
            sum_w += w;
            sum_wl += w * (ind->data[i] + ind->data[i + 1] + ind->data[i + 2]) / 3.0;
        }
    const double want = furnace_indirect_mean(area);
    keeper_clear(&k);
    run_close(&r);
    return sum_wl / sum_w / want;
}

START_TEST(furnace_energy_balance)
{
    /* normal_compression 1: a spherical kernel, whose support on a sphere has exactly the disk's
     * area (Archimedes). The default ellipsoid (r_z = r_xy/4) loses the light of photons that
     * the sphere's curvature lifts out of it: measured here 0.72 of the balance for the k-d
     * gather with kernel_radius 0.1 on this 1 m sphere, 0.92 for the final gather (whose
     * lookups use r_xy/4). */
    const char *common = "\"photon_count\":16384,\"normal_compression\":1";
    char fg_s[256], kd_s[256];
    snprintf(fg_s, sizeof fg_s, "\"indirect\":\"final-gather\",\"final_gather_rays\":16,%s", common);
    snprintf(kd_s, sizeof kd_s, "\"indirect\":\"kd-gather\",%s", common);
    const double fg = furnace_ratio(fg_s, 48), kd = furnace_ratio(kd_s, 48);
    printf("furnace, indirect area mean / energy balance: final-gather %.4f, kd-gather %.4f\n", fg, kd);
    /* Photon noise of 16,384 photons and the gather's 16 rays a pixel: ~1 %. */
    ck_assert_msg(fabs(kd - 1.0) < 0.02, "k-d gather: area mean %.4f of the energy balance", kd);
    ck_assert_msg(fabs(fg - 1.0) < 0.025, "final gather: area mean %.4f of the energy balance", fg);
}
END_TEST

/* ---------------------------------------------------------------- caustics */

/* Σ indirect over the floor pixels (normal y > 0.9) where the k-d gather's indirect exceeds
 * 3 × its floor median: the sphere's caustic. */
START_TEST(glass_caustic_from_caustic_photons)
{
    static keeper kd, fg;
    const int size = 96;
    render_sized(CORNELL_DIR "cornell-glass-ci.json", size, "\"indirect\":\"kd-gather\",\"photon_count\":16384", &kd);
    render_sized(CORNELL_DIR "cornell-glass-ci.json", size,
           "\"indirect\":\"final-gather\",\"final_gather_rays\":16,\"photon_count\":16384", &fg);
    const kept *n = find(&kd, "gbuffer.normal"), *a = find(&kd, "indirect.radiance"), *b = find(&fg, "indirect.radiance");
    ck_assert(n && a && b);
    const int np = size * size;
    float *floor_v = malloc((size_t)np * sizeof *floor_v);
    int nf = 0;
    for (int i = 0; i < np; i++)
        if (n->data[3 * i + 1] > 0.9f)
            floor_v[nf++] = a->data[3 * i] + a->data[3 * i + 1] + a->data[3 * i + 2];
    ck_assert_int_gt(nf, np / 16);
    /* The median by counting (nf is small). */
    float median = 0.0f;
    for (int i = 0; i < nf; i++) {
        int below = 0;
        for (int j = 0; j < nf; j++)
            below += floor_v[j] < floor_v[i];
        if (below == nf / 2)
            median = floor_v[i];
    }
    double sa = 0.0, sb = 0.0;
    int px = 0;
    for (int i = 0; i < np; i++) {
        double va = a->data[3 * i] + a->data[3 * i + 1] + a->data[3 * i + 2];
        if (n->data[3 * i + 1] > 0.9f && va > 3.0 * median) {
            sa += va;
            sb += b->data[3 * i] + b->data[3 * i + 1] + b->data[3 * i + 2];
            px++;
        }
    }
    printf("glass caustic (%d floor pixels > 3 x median): final-gather / kd-gather %.3f\n", px, sb / sa);
    ck_assert_int_gt(px, 8);
    ck_assert_msg(sb > 0.85 * sa && sb < 1.15 * sa, "caustic: final gather %.4g, k-d gather %.4g", sb, sa);
    free(floor_v);
    keeper_clear(&kd);
    keeper_clear(&fg);
}
END_TEST

/* ---------------------------------------------------------------- emitters, threads, settings */

/* A ray that meets an emitter first: eye_tracer_ray sees its emission, a gather ray does not. */
START_TEST(gather_rays_do_not_see_emitters)
{
    scene_run r;
    run_open(&r, CORNELL_DIR "cornell-box-ci.json", 32, "\"indirect\":\"none\"");
    const eng_frame_scene *fs;
    const eng_rt *rt;
    eng_pose(r.engine, 0, &fs, &rt);
    /* Make every material of the posed scene an emitter (the tracer reads them from the scene). */
    scn_scene *sc = (scn_scene *)fs->scene;
    for (uint32_t m = 0; m < sc->material_count; m++)
        for (int c = 0; c < 3; c++)
            sc->materials[m].emissive[c] = 2.0f;
    eng_error err = {{0}};
    eye_tracer *t = eye_tracer_create(fs, rt, NULL, NULL, &r.seq.settings, &err);
    ck_assert_ptr_nonnull(t);
    eye_scratch scr = {NULL, 0};
    const float org[3] = {fs->camera.eye[0], fs->camera.eye[1], fs->camera.eye[2]};
    /* Toward the middle of the scene's bounds: the box's back wall or a box. */
    float dir[3], len = 0.0f;
    for (int c = 0; c < 3; c++) {
        dir[c] = 0.5f * (fs->bounds_min[c] + fs->bounds_max[c]) - org[c];
        len += dir[c] * dir[c];
    }
    for (int c = 0; c < 3; c++)
        dir[c] /= sqrtf(len);
    float seen[3], gathered[3];
    eye_tracer_ray(t, org, dir, UINT32_MAX, &scr, seen);
    eye_tracer_gather_ray(t, org, dir, &scr, gathered);
    ck_assert_msg(seen[0] >= 2.0f, "eye_tracer_ray: %g", seen[0]);
    ck_assert_msg(fabsf(seen[0] - gathered[0] - 2.0f) < 1e-5f, "seen %g, gathered %g", seen[0], gathered[0]);
    free(scr.list);
    eye_tracer_destroy(t);
    run_close(&r);
}
END_TEST

START_TEST(bit_identical_for_any_thread_count)
{
    static keeper k1, k3;
    render_sized(CORNELL_DIR "cornell-glass-ci.json", 40,
           "\"indirect\":\"final-gather\",\"final_gather_rays\":16,\"photon_count\":4096,\"threads\":1", &k1);
    render_sized(CORNELL_DIR "cornell-glass-ci.json", 40,
           "\"indirect\":\"final-gather\",\"final_gather_rays\":16,\"photon_count\":4096,\"threads\":3", &k3);
    int compared = 0;
    for (int i = 0; i < k1.count; i++) {
        const kept *a = &k1.bufs[i], *b = find(&k3, a->name);
        ck_assert_msg(b != NULL, "%s missing with 3 threads", a->name);
        ck_assert_msg(a->w == b->w && a->h == b->h && a->n == b->n &&
                          !memcmp(a->data, b->data, (size_t)a->w * a->h * a->n * sizeof(float)),
                      "%s differs between 1 and 3 threads", a->name);
        compared++;
    }
    const kept *fi = find(&k1, "final_gather.indirect");
    ck_assert_ptr_nonnull(fi);
    double sum = 0.0;
    for (int i = 0; i < fi->w * fi->h * 3; i++)
        sum += fi->data[i];
    ck_assert(sum > 0.0);
    printf("final gather, 1 vs 3 threads: %d buffers bit-identical\n", compared);
    keeper_clear(&k1);
    keeper_clear(&k3);
}
END_TEST

START_TEST(bad_settings)
{
    static const char *const bad[] = {
        "\"indirect\":\"final-gather\",\"final_gather_rays\":8",
        "\"indirect\":\"final-gather\",\"final_gather_rays\":2",
        "\"indirect\":\"final-gather\",\"final_gather_rays\":16384",
        "\"indirect\":\"final-gather\",\"final_gather_radius\":0",
        "\"indirect\":\"final-gather\",\"final_gather_radius\":1.5",
        "\"indirect\":\"final-gather\",\"boundary\":\"renormalize\"",
        "\"indirect\":\"final-gather\",\"progressive\":true,\"progressive_radius\":\"pixel\"",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char json[512];
        snprintf(json, sizeof json,
                 "{\"name\":\"x\",\"scene\":\"cornell-box.gltf\",\"frames\":1,\"fps\":1,\"resolution\":[8,8],"
                 "\"camera\":{\"node\":\"Camera\"},\"settings\":{%s}}",
                 bad[i]);
        seq_sequence seq;
        eng_error err = {{0}};
        ck_assert_msg(seq_parse(CORNELL_DIR "bad.json", json, strlen(json), &seq, &err) == ENG_ERR_INVALID,
                      "accepted: %s", bad[i]);
        ck_assert_msg(strstr(err.msg, "bad.json") && strstr(err.msg, "final"), "%s: %s", bad[i], err.msg);
    }
    /* The engine refuses the boundary correction too (a sequence made in code). */
    scene_run r;
    run_open(&r, CORNELL_DIR "cornell-box-ci.json", 16, "\"indirect\":\"final-gather\"");
    run_close(&r);
    r.seq.settings.boundary = ENG_BOUNDARY_RENORMALIZE;
    eng_error err = {{0}};
    ck_assert_msg(scn_load_gltf(r.seq.scene_path, &r.scene, &err) == ENG_OK, "%s", err.msg);
    eng_desc d = {.scene = r.scene, .sequence = &r.seq};
    eng_engine *e = NULL;
    ck_assert_int_eq(eng_create(&d, &e, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "final-gather"), "%s", err.msg);
    scn_destroy(r.scene);
}
END_TEST

static Suite *finalgather_suite(void)
{
    Suite *s = suite_create("finalgather");
    TCase *tc = tcase_create("finalgather");
    tcase_set_timeout(tc, 600);
    tcase_add_test(tc, bad_settings);
    tcase_add_test(tc, gather_rays_do_not_see_emitters);
    tcase_add_test(tc, bit_identical_for_any_thread_count);
    tcase_add_test(tc, furnace_energy_balance);
    tcase_add_test(tc, glass_caustic_from_caustic_photons);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(finalgather_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
