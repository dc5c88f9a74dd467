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
 *     boundary correction (a kernel at the pixel) is refused, by the parser and the engine;
 *   - surface seeds: a camera moved by 0.1 mm leaves a surface-seeded gather nearly unchanged,
 *     where pixel seeds draw new noise;
 *   - reuse: the reprojection test (fg_reproject, fg_same_surface); a still view with the maps
 *     gives the bits of gathering every frame; with per-frame random most pixels keep the
 *     previous frame's light; a frame asked out of order rebuilds the history;
 *   - presets: expanded before the sequence's own keys, which override them. */
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


/* ---------------------------------------------------------------- stability and reuse */

/* A frames-long sequence of the Cornell box, size² pixels, camera at eye looking down -z,
 * settings `extra`, rendered frame by frame (frames listed in `order`) into one keeper per
 * frame: final_gather.indirect only. */
typedef struct fg_frames {
    keeper k[4];
} fg_frames;

static int keep_by_frame(void *user, int frame, const eng_buffer *b)
{
    fg_frames *f = user;
    return frame >= 0 && frame < 4 ? keep_buffer(&f->k[frame], frame, b) : 0;
}

static void render_frames(const float eye[3], int size, int frames, const char *extra, const int *order, int n,
                          fg_frames *out)
{
    char json[2048];
    snprintf(json, sizeof json,
             "{\"name\":\"fg\",\"scene\":\"cornell-box.gltf\",\"frames\":%d,\"fps\":4,\"resolution\":[%d,%d],"
             "\"camera\":{\"keys\":[{\"time\":0,\"position\":[%.9g,%.9g,%.9g],\"target\":[0,1,-2]}],"
             "\"yfov_deg\":50},\"still\":true,"
             "\"settings\":{\"shadow_map_size\":256,\"photon_count\":4096,\"kernel_radius\":0.15,"
             "\"indirect\":\"final-gather\",\"final_gather_rays\":16%s%s}}",
             frames, size, size, eye[0], eye[1], eye[2], extra[0] ? "," : "", extra);
    seq_sequence seq;
    scn_scene *scene = NULL;
    eng_engine *e = NULL;
    eng_error err = {{0}};
    ck_assert_msg(seq_parse(CORNELL_DIR "fg.json", json, strlen(json), &seq, &err) == ENG_OK, "%s", err.msg);
    ck_assert_msg(scn_load_gltf(seq.scene_path, &scene, &err) == ENG_OK, "%s", err.msg);
    eng_desc d = {.scene = scene, .sequence = &seq};
    ck_assert_msg(eng_create(&d, &e, &err) == ENG_OK, "%s", err.msg);
    memset(out, 0, sizeof *out);
    for (int i = 0; i < 4; i++)
        out->k[i].all = 1;
    eng_listener l = {out, NULL, keep_by_frame, NULL};
    ck_assert_int_eq(eng_add_listener(e, &l), ENG_OK);
    for (int i = 0; i < n; i++)
        ck_assert_msg(eng_render_frame(e, order[i], &err) == ENG_OK, "%s", err.msg);
    eng_destroy(e);
    scn_destroy(scene);
}

static void frames_clear(fg_frames *f)
{
    for (int i = 0; i < 4; i++)
        keeper_clear(&f->k[i]);
}

static const kept *fg_buffer(const fg_frames *f, int frame)
{
    const kept *b = find(&f->k[frame], "final_gather.indirect");
    ck_assert_msg(b != NULL, "frame %d: no final_gather.indirect", frame);
    return b;
}

/* Mean over lit pixels (either image not black) of |a − b| / (a + b + ε) on R+G+B; *same: the
 * share of those pixels whose floats are bit-identical. */
static double mean_rel_diff(const kept *a, const kept *b, double *same)
{
    ck_assert(a->w == b->w && a->h == b->h && a->n == b->n);
    double sum = 0.0;
    int n = 0, eq = 0;
    for (int i = 0; i < a->w * a->h; i++) {
        const float *p = a->data + (size_t)a->n * i, *q = b->data + (size_t)b->n * i;
        double x = (double)p[0] + p[1] + p[2], y = (double)q[0] + q[1] + q[2];
        if (x == 0.0 && y == 0.0)
            continue;
        sum += fabs(x - y) / (x + y + 1e-6);
        eq += !memcmp(p, q, (size_t)a->n * sizeof *p);
        n++;
    }
    ck_assert_int_gt(n, 0);
    if (same)
        *same = (double)eq / n;
    return sum / n;
}

START_TEST(surface_seeds_follow_the_surface)
{
    const float e0[3] = {0.0f, 1.0f, 1.5f}, e1[3] = {0.0f, 1.0f, 1.5001f};
    const int first[1] = {0};
    double diff[2];
    for (int m = 0; m < 2; m++) {
        const char *extra = m ? "\"final_gather_seed\":\"surface\"" : "";
        fg_frames a, b;
        render_frames(e0, 32, 1, extra, first, 1, &a);
        render_frames(e1, 32, 1, extra, first, 1, &b);
        diff[m] = mean_rel_diff(fg_buffer(&a, 0), fg_buffer(&b, 0), NULL);
        frames_clear(&a);
        frames_clear(&b);
    }
    printf("eye moved 0.1 mm: mean relative change %.4f with pixel seeds, %.4f with surface seeds\n", diff[0],
           diff[1]);
    ck_assert_msg(diff[0] > 0.02, "pixel seeds: %g", diff[0]);
    ck_assert_msg(diff[1] < 0.25 * diff[0], "surface %g vs pixel %g", diff[1], diff[0]);
}
END_TEST

START_TEST(reuse_test_by_reprojection)
{
    /* A view_proj that maps x, y ∈ [−1, 1] to the image and w = 1: the identity. */
    float vp[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    int x = -1, y = -1;
    const float centre[3] = {0.0f, 0.0f, 0.5f}, top_left[3] = {-0.99f, 0.99f, 0.0f}, off[3] = {1.5f, 0.0f, 0.0f};
    ck_assert(fg_reproject(vp, 8, 4, centre, &x, &y) && x == 4 && y == 2);
    ck_assert(fg_reproject(vp, 8, 4, top_left, &x, &y) && x == 0 && y == 0); /* top row first */
    ck_assert(!fg_reproject(vp, 8, 4, off, &x, &y));
    vp[15] = -1.0f; /* behind the camera */
    ck_assert(!fg_reproject(vp, 8, 4, centre, &x, &y));

    const float p[4] = {1, 2, 3, 1}, n[3] = {0, 1, 0}, alb[3] = {0.5f, 0.5f, 0.5f}, mat[4] = {0.5f, 0, 0, 1.5f};
    ck_assert(fg_same_surface(p, n, alb, mat, p, n, alb, mat, 0.01f));
    const float near[4] = {1.005f, 2, 3, 1}, far[4] = {1.05f, 2, 3, 1}, bare[4] = {1, 2, 3, 0};
    ck_assert(fg_same_surface(p, n, alb, mat, near, n, alb, mat, 0.01f));
    ck_assert(!fg_same_surface(p, n, alb, mat, far, n, alb, mat, 0.01f));   /* disoccluded */
    ck_assert(!fg_same_surface(p, n, alb, mat, bare, n, alb, mat, 0.01f));  /* background */
    const float n2[3] = {0, 0.8f, 0.6f}, alb2[3] = {0.5f, 0.5f, 0.4f}, mat2[4] = {0.5f, 0.1f, 0, 1.5f};
    ck_assert(!fg_same_surface(p, n, alb, mat, p, n2, alb, mat, 0.01f));    /* another face */
    ck_assert(!fg_same_surface(p, n, alb, mat, p, n, alb2, mat, 0.01f));    /* another material */
    ck_assert(!fg_same_surface(p, n, alb, mat, p, n, alb, mat2, 0.01f));
}
END_TEST

START_TEST(reuse_keeps_gathered_light)
{
    const float eye[3] = {0.0f, 1.0f, 1.5f};
    const int in_order[3] = {0, 1, 2}, last_only[1] = {2};
    /* Still view with the maps: every frame the bits of gathering every frame. */
    fg_frames a, b;
    render_frames(eye, 24, 3, "\"final_gather_seed\":\"surface\"", in_order, 3, &a);
    render_frames(eye, 24, 3, "\"final_gather_seed\":\"surface\",\"final_gather_reuse\":4", in_order, 3, &b);
    for (int f = 0; f < 3; f++) {
        const kept *x = fg_buffer(&a, f), *y = fg_buffer(&b, f);
        ck_assert_msg(!memcmp(x->data, y->data, (size_t)x->w * x->h * x->n * sizeof(float)), "frame %d differs", f);
    }
    frames_clear(&a);
    frames_clear(&b);
    /* Per-frame random: without reuse every pixel draws anew; with reuse 4 about 3/4 keep the
     * previous frame's light. */
    double same[2];
    for (int m = 0; m < 2; m++) {
        render_frames(eye, 24, 3, m ? "\"random\":\"per-frame\",\"final_gather_reuse\":4" : "\"random\":\"per-frame\"",
                      in_order, 3, &a);
        mean_rel_diff(fg_buffer(&a, 1), fg_buffer(&a, 2), &same[m]);
        if (m) { /* frame 2 alone: the engine rebuilds the history, the same bits */
            render_frames(eye, 24, 3, "\"random\":\"per-frame\",\"final_gather_reuse\":4", last_only, 1, &b);
            const kept *x = fg_buffer(&a, 2), *y = fg_buffer(&b, 2);
            ck_assert_msg(!memcmp(x->data, y->data, (size_t)x->w * x->h * x->n * sizeof(float)),
                          "frame 2 alone differs from frame 2 in order");
            frames_clear(&b);
        }
        frames_clear(&a);
    }
    printf("per-frame random, frames 1 -> 2: %.3f of pixels unchanged without reuse, %.3f with reuse 4\n", same[0],
           same[1]);
    ck_assert_msg(same[0] < 0.05, "without reuse %g", same[0]);
    ck_assert_msg(same[1] > 0.6 && same[1] < 0.9, "with reuse %g", same[1]);
}
END_TEST

START_TEST(presets_expand_before_own_keys)
{
    const char *base = "{\"name\":\"x\",\"scene\":\"cornell-box.gltf\",\"frames\":1,\"fps\":1,\"resolution\":[8,8],"
                       "\"camera\":{\"node\":\"Camera\"},\"settings\":{%s}}";
    char json[512];
    seq_sequence seq;
    eng_error err = {{0}};
    snprintf(json, sizeof json, base, "\"preset\":\"interactive\"");
    ck_assert_msg(seq_parse(CORNELL_DIR "p.json", json, strlen(json), &seq, &err) == ENG_OK, "%s", err.msg);
    const eng_settings *s = &seq.settings;
    ck_assert_int_eq(s->preset, ENG_PRESET_INTERACTIVE);
    ck_assert_int_eq(s->indirect, ENG_INDIRECT_FINALGATHER);
    ck_assert_int_eq(s->final_gather_seed, ENG_FG_SEED_SURFACE);
    ck_assert_int_gt(s->final_gather_reuse, 1);
    ck_assert_int_gt(s->splat_subsample, 1);
    /* The sequence's own keys win, wherever they stand. */
    snprintf(json, sizeof json, base, "\"final_gather_rays\":16,\"preset\":\"interactive\",\"splat_subsample\":1");
    ck_assert_msg(seq_parse(CORNELL_DIR "p.json", json, strlen(json), &seq, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(seq.settings.final_gather_rays, 16);
    ck_assert_int_eq(seq.settings.splat_subsample, 1);
    ck_assert_int_eq(seq.settings.final_gather_seed, ENG_FG_SEED_SURFACE);
    /* Every preset parses; none is the defaults. */
    static const char *const names[] = {"draft", "interactive", "converged"};
    for (int i = 0; i < 3; i++) {
        char kv[64];
        snprintf(kv, sizeof kv, "\"preset\":\"%s\"", names[i]);
        snprintf(json, sizeof json, base, kv);
        ck_assert_msg(seq_parse(CORNELL_DIR "p.json", json, strlen(json), &seq, &err) == ENG_OK, "%s", err.msg);
        ck_assert_ptr_nonnull(seq_preset_settings(seq.settings.preset));
        ck_assert_int_ne(seq.settings.indirect, ENG_INDIRECT_ISPM);
    }
    snprintf(json, sizeof json, base, "\"preset\":\"none\"");
    ck_assert_msg(seq_parse(CORNELL_DIR "p.json", json, strlen(json), &seq, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(seq.settings.indirect, ENG_INDIRECT_ISPM);
    ck_assert_ptr_null(seq_preset_settings(seq.settings.preset));
    /* Bad values: one message naming the file and the key. */
    static const char *const bad[] = {"\"preset\":\"fast\"", "\"preset\":3", "\"final_gather_seed\":\"eye\"",
                                      "\"final_gather_cell\":0", "\"final_gather_reuse\":0",
                                      "\"final_gather_reuse\":1000"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(json, sizeof json, base, bad[i]);
        ck_assert_msg(seq_parse(CORNELL_DIR "bad.json", json, strlen(json), &seq, &err) == ENG_ERR_INVALID,
                      "accepted: %s", bad[i]);
        ck_assert_msg(strstr(err.msg, "bad.json") && (strstr(err.msg, "preset") || strstr(err.msg, "final_gather")),
                      "%s: %s", bad[i], err.msg);
    }
}
END_TEST

static Suite *finalgather_suite(void)
{
    Suite *s = suite_create("finalgather");
    TCase *tc = tcase_create("finalgather");
    tcase_set_timeout(tc, 600);
    tcase_add_test(tc, bad_settings);
    tcase_add_test(tc, presets_expand_before_own_keys);
    tcase_add_test(tc, reuse_test_by_reprojection);
    tcase_add_test(tc, surface_seeds_follow_the_surface);
    tcase_add_test(tc, reuse_keeps_gathered_light);
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
