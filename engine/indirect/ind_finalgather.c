/* ind_finalgather.c — the "final-gather" indirect method (indirect.h): the photon map looked
 * up one bounce away from the eye. 003_d0bf8e920b03f4e1.txt Appendix A: "Final gathering is a
 * variance reduction technique that can extend any global illumination algorithm. It adds one
 * level of backwards tracing by sampling the incoming illumination at a visible point from
 * other, randomly sampled points. Those other points are where the pure technique is applied."
 * (Jensen 1996, "Global Illumination using Photon Maps", §3.)
 *
 * At every eye G-buffer pixel x with a diffuse or glossy lobe, N = `final_gather_rays` rays
 * leave the surface in cosine-weighted directions ω_k (pdf cos θ/π); each finds, with Embree,
 * the radiance L_k arriving back along it the way the traced specular pass finds it
 * (eye_tracer_gather_ray): at the first non-specular surface y, the direct light of every
 * lamp by a shadow ray plus the k-d gather of the photon map at y (kd_gather_point: the same
 * kernel and BSDF as the k-d gather's pixels), continued through mirrors and glass; emitters
 * add nothing (they are seen only after delta lobes, as in the reference renderer). Then
 *   radiance mode:   L_o(x) = 1/N Σ f(ω_k, ω_o) L_k cos θ_k / pdf_k
 *   irradiance mode: E(x) = 1/N Σ L_k cos θ_k / pdf_k, glossy = 1/N Σ f_glossy(ω_k) L_k cos θ_k / pdf_k
 * (the Monte Carlo estimate of the rendering equation's integral at x), A = the rays that met
 * a surface. The photons' kernels are evaluated only at the y's, so their blur reaches the
 * image one bounce removed: where the pixel's own neighbourhood matters (corners, contact
 * shadows) the rays see it exactly.
 *
 * Random numbers: pixel (x, y)'s N directions are a correlated multi-jittered set (Kensler
 * 2013; bsdf_strata, the bounce map's stratification, with log2n = log4 N), its pattern a hash
 * of the eye position, the pixel and the frame's strata salt, the jitter inside each stratum
 * read from the random maps at a hash of the same with the frame's salt, then the frame's
 * Cranley–Patterson rotation of "random": "stratified" (002 §4.2; bsdf_stratify): a still
 * camera draws the same directions every frame with the precomputed maps, new ones per frame or
 * per stratum otherwise. `"final_gather_seed": "surface"` hashes, instead of the eye and the
 * pixel, the surface point's world cell (`final_gather_cell`, the point first moved half a cell
 * along its normal so that a wall's cells do not straddle it) and its normal rounded to halves,
 * as the random maps are seeded by scene quantities (003 §4.1): a still surface seen from a
 * moving camera gathers along the same directions, so its light does not flicker with the eye.
 *
 * Reuse (`"final_gather_reuse": N` > 1): each pixel keeps its gathered light with an age. A
 * pixel whose surface point the previous frame's camera projects onto a pixel that showed the
 * same surface (same material and albedo, normals within 0.9, positions within the pixel's
 * footprint) takes that pixel's light when its age is below N - 1 and nothing in the scene moved
 * since (no draw's transform, no deformed draw, no light pose changed); every other pixel
 * gathers. A pixel's first gather gets an age from a hash of the pixel in 0..N-1, so that about
 * 1/N of the pixels gather afresh in each frame of a still view rather than all of them every
 * N frames. Disocclusions and changed lighting gather at once. The glossy share (irradiance mode)
 * is reused with it, view-dependent as it is; in radiance mode glossy pixels always gather.
 * With a still camera and the precomputed maps a reused pixel holds the bits a new gather would
 * give, so the frames are bit-identical to those of N = 1.
 *
 * Determinism: every pixel is computed by one thread with a fixed amount of work (its rays in
 * order, each gather summing in photon-index order), so the image is bit-identical for any
 * thread count. */
#include "indirect.h"

#include "bsdf.h"
#include "gather_kernel.h"
#include "kdtree.h"
#include "eye_tracer.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define FG_SALT 0x6a09e667u /* the final gather's seeds apart from the bounce map's (√2's bits) */

typedef struct fg_state {
    ind_cpu_state c;         /* target, G-buffer read-back, output images */
    float *radius;           /* the lookups' r_xy per photon */
    size_t radius_cap;
    eng_photon_map caustic;  /* the frame's caustic photons (eng_photon.caustic) */
    float *caustic_radius;   /* their r_xy, as the kernel methods use them */
    size_t caustic_cap;
    /* Reuse (final_gather_reuse > 1): the previous frame's G-buffer, light, ages, camera and
     * scene key; have_prev 0 after a reset. */
    int have_prev;
    float *prev_pos, *prev_nrm, *prev_alb, *prev_mat, *prev_out, *prev_glossy;
    int *age, *prev_age;
    float prev_vp[16];
    uint64_t prev_key;
} fg_state;

static void fg_destroy(void *state)
{
    fg_state *k = state;
    if (!k)
        return;
    ind_cpu_state_free(&k->c);
    free(k->radius);
    free(k->caustic.photons);
    free(k->caustic_radius);
    free(k->prev_pos);
    free(k->prev_nrm);
    free(k->prev_alb);
    free(k->prev_mat);
    free(k->prev_out);
    free(k->prev_glossy);
    free(k->age);
    free(k->prev_age);
    free(k);
}

static void fg_reset(void *state)
{
    ((fg_state *)state)->have_prev = 0;
}

static int fg_history(const eng_settings *s)
{
    return s->final_gather_reuse > 1;
}

static eng_result fg_create(int width, int height, int irradiance, void **state, eng_error *err)
{
    fg_state *k = calloc(1, sizeof *k);
    if (!k)
        return eng_fail(err, ENG_ERR_NOMEM, "final-gather: out of memory");
    eng_result r = ind_cpu_state_init(&k->c, "final-gather", width, height, irradiance, err);
    if (r != ENG_OK) {
        free(k);
        return r;
    }
    *state = k;
    return ENG_OK;
}

/* log4 of the ray count (a power of 4 from 4 to 4^BSDF_STRATA_MAX_LOG2; the sequence parser
 * checks it). */
static uint32_t rays_log4(int rays)
{
    uint32_t l = 1;
    while (l < BSDF_STRATA_MAX_LOG2 && (1 << (2 * l)) < rays)
        l++;
    return l;
}

typedef struct fg_ctx {
    const eye_tracer *tracer;
    const kd_tree *ctree; /* NULL: no caustic photons this frame */
    const eng_photon_map *cmap;
    const float *cradius;
    float creach, compression;
    const eng_random_maps *rm;
    const eng_rmap_frame *rf;
    const glu_gbuffer *gb;
    const float *eye;
    uint32_t log2n, rays;
    float *out, *glossy;
    int surface;    /* final_gather_seed "surface" */
    float cell;     /* its world cell (m) */
} fg_ctx;

/* The pattern and jitter seeds of a pixel's gather directions (the header's Random numbers). */
static void fg_seeds(const fg_ctx *c, int x, int y, const float p[3], const float n[3], uint32_t *pattern,
                     uint32_t *seed)
{
    if (!c->surface) {
        *pattern = rmap_hash_pixel(c->eye, (uint32_t)x, (uint32_t)y, 0u, c->rf->strata_salt ^ FG_SALT);
        *seed = rmap_hash_pixel(c->eye, (uint32_t)x, (uint32_t)y, 1u, c->rf->salt ^ FG_SALT);
        return;
    }
    float q[3];
    uint32_t nq = 0;
    for (int k = 0; k < 3; k++) {
        q[k] = floorf((p[k] + 0.5f * c->cell * n[k]) / c->cell) + 0.0f; /* + 0: no -0 */
        nq = nq * 5u + (uint32_t)(lrintf(n[k] * 2.0f) + 2);
    }
    *pattern = rmap_hash_pixel(q, nq, 0u, 2u, c->rf->strata_salt ^ FG_SALT);
    *seed = rmap_hash_pixel(q, nq, 1u, 2u, c->rf->salt ^ FG_SALT);
}

/* Pixel (x, y): out (and glossy in irradiance mode) as the header says. */
static void fg_pixel(const fg_ctx *c, int x, int y, eye_scratch *sc)
{
    const int w = c->gb->width;
    const size_t i = (size_t)y * (size_t)w + (size_t)x;
    float *acc = c->out + 4 * i, *gl = c->glossy ? c->glossy + 4 * i : NULL;
    const float *p = c->gb->position + 4 * i, *mat = c->gb->material + 4 * i, *alb = c->gb->albedo + 3 * i;
    if (p[3] == 0.0f)
        return;
    const float kd = (1.0f - mat[1]) * (1.0f - mat[2]) / (float)ENG_PI;
    const int glossy = mat[1] > 0.0f;
    if (!(kd > 0.0f) && !glossy)
        return; /* a mirror or clear glass: no lobe for the photon estimate */
    /* The normal on the side the eye sees. */
    float n[3] = {c->gb->normal[3 * i], c->gb->normal[3 * i + 1], c->gb->normal[3 * i + 2]};
    float v[3] = {c->eye[0] - p[0], c->eye[1] - p[1], c->eye[2] - p[2]};
    if (gk_dot3(n, v) < 0.0f)
        for (int k = 0; k < 3; k++)
            n[k] = -n[k];
    gk_pixel px;
    gk_pixel_init(&px, p, n, alb, mat, c->eye);
    float t[3], b[3], org[3];
    bsdf_basis(n, t, b);
    const float eps = bsdf_offset_eps(p);
    for (int k = 0; k < 3; k++)
        org[k] = p[k] + eps * n[k];
    uint32_t pattern, seed;
    fg_seeds(c, x, y, p, n, &pattern, &seed);
    const uint32_t mask = c->rm->size - 1u;
    const float inv_n = 1.0f / (float)c->rays;
    float sum[3] = {0.0f, 0.0f, 0.0f}, gsum[3] = {0.0f, 0.0f, 0.0f};
    float met = 0.0f;
    for (uint32_t k = 0; k < c->rays; k++) {
        float us[4], u[4], cd[4];
        bsdf_strata(c->rm->uniform + 4 * (size_t)((seed + k) & mask), k, c->log2n, pattern, us);
        bsdf_stratify(us, c->rf->offset, u, cd);
        if (!(cd[3] > 0.0f) || !(cd[2] > 0.0f))
            continue;
        float dir[3], L[3];
        for (int j = 0; j < 3; j++)
            dir[j] = cd[0] * t[j] + cd[1] * b[j] + cd[2] * n[j];
        eye_tracer_gather_ray(c->tracer, org, dir, sc, L);
        if (L[0] == 0.0f && L[1] == 0.0f && L[2] == 0.0f)
            continue;
        met += 1.0f;
        const float wgt = cd[2] / cd[3]; /* cos θ / pdf */
        float g[3] = {0.0f, 0.0f, 0.0f};
        if (glossy)
            gk_glossy(&px, dir, cd[2], g);
        for (int j = 0; j < 3; j++) {
            if (gl) {
                sum[j] += L[j] * wgt;
                gsum[j] += g[j] * L[j] * wgt;
            } else {
                sum[j] += (kd * alb[j] + g[j]) * L[j] * wgt;
            }
        }
    }
    /* The caustic photons (paths L S+ D, which no gather ray can close on a point light) with
     * the kernel at the pixel itself, as the k-d gather evaluates them (Jensen 1996 §3: the
     * caustic photon map is used directly). */
    float cacc[4] = {0.0f, 0.0f, 0.0f, 0.0f}, cgl[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    if (c->ctree)
        kd_gather_point(c->ctree, c->cmap, c->cradius, c->creach, c->compression, &px, &sc->list, &sc->cap, cacc,
                        gl ? cgl : NULL);
    for (int j = 0; j < 3; j++) {
        acc[j] = sum[j] * inv_n + cacc[j];
        if (gl)
            gl[j] = gsum[j] * inv_n + cgl[j];
    }
    acc[3] = met;
}

/* FNV-1a over n bytes, continuing from h. */
static uint64_t fnv64(uint64_t h, const void *data, size_t n)
{
    const unsigned char *b = data;
    for (size_t i = 0; i < n; i++)
        h = (h ^ b[i]) * 0x100000001b3ull;
    return h;
}

/* The key of what the gathered light depends on besides the camera: every draw's transform
 * and every light's pose. *comparable 0 when a draw is deformed (its vertices move without a
 * transform changing), so no frame's light may be reused. */
static uint64_t scene_key(const eng_frame_scene *fs, int *comparable)
{
    uint64_t h = 0xcbf29ce484222325ull;
    *comparable = 1;
    for (uint32_t i = 0; i < fs->draw_count; i++) {
        h = fnv64(h, fs->draws[i].world, sizeof fs->draws[i].world);
        if (fs->draws[i].positions)
            *comparable = 0;
    }
    for (uint32_t i = 0; i < fs->light_count; i++) {
        const eng_light_pose *l = &fs->lights[i];
        h = fnv64(h, l->position, sizeof l->position);
        h = fnv64(h, l->direction, sizeof l->direction);
        h = fnv64(h, l->radiance_scale, sizeof l->radiance_scale);
        h = fnv64(h, &l->range, sizeof l->range);
        h = fnv64(h, &l->inner_cone, sizeof l->inner_cone);
        h = fnv64(h, &l->outer_cone, sizeof l->outer_cone);
        h = fnv64(h, &l->radius, sizeof l->radius);
    }
    return h;
}

int fg_reproject(const float vp[16], int w, int h, const float p[3], int *x, int *y)
{
    float c[4];
    for (int r = 0; r < 4; r++)
        c[r] = vp[r] * p[0] + vp[4 + r] * p[1] + vp[8 + r] * p[2] + vp[12 + r];
    if (!(c[3] > 0.0f))
        return 0;
    const float fx = (c[0] / c[3] * 0.5f + 0.5f) * (float)w, fy = (0.5f - c[1] / c[3] * 0.5f) * (float)h;
    if (!(fx >= 0.0f && fx < (float)w && fy >= 0.0f && fy < (float)h))
        return 0;
    *x = (int)fx;
    *y = (int)fy;
    return 1;
}

int fg_same_surface(const float p[4], const float n[3], const float alb[3], const float mat[4], const float q[4],
                    const float nq[3], const float albq[3], const float matq[4], float tolerance)
{
    if (q[3] == 0.0f || memcmp(alb, albq, 3 * sizeof *alb) != 0 || memcmp(mat, matq, 4 * sizeof *mat) != 0)
        return 0;
    if (n[0] * nq[0] + n[1] * nq[1] + n[2] * nq[2] < 0.9f)
        return 0;
    const float d[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
    return d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= tolerance * tolerance;
}

/* A pixel's first age: a hash of the pixel in 0..n-1, so that first gathers expire spread over
 * n frames. */
static int first_age(int x, int y, int n)
{
    uint32_t h = (uint32_t)x * 0x9e3779b1u ^ (uint32_t)y * 0x85ebca77u;
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    return (int)(h % (uint32_t)n);
}

typedef struct fg_reuse {
    const fg_state *k;
    int n;          /* final_gather_reuse */
    int valid;      /* the previous frame's light may be reused at all */
    int irradiance;
    const float *eye;
    float px_scale; /* world size of a pixel at unit distance */
} fg_reuse;

/* Pixel (x, y) takes the previous frame's light when the header's test allows it: returns 1
 * with out/glossy/age filled, else 0 (the pixel gathers). */
static int fg_reuse_pixel(const fg_reuse *u, int x, int y, float *out, float *glossy, int *age)
{
    const fg_state *k = u->k;
    const glu_gbuffer *gb = &k->c.gb;
    const int w = gb->width, h = gb->height;
    const size_t i = (size_t)y * (size_t)w + (size_t)x;
    const float *p = gb->position + 4 * i, *mat = gb->material + 4 * i;
    if (!u->valid || p[3] == 0.0f || (!u->irradiance && mat[1] > 0.0f))
        return 0;
    int qx, qy;
    if (!fg_reproject(k->prev_vp, w, h, p, &qx, &qy))
        return 0;
    const size_t j = (size_t)qy * (size_t)w + (size_t)qx;
    if (k->prev_age[j] + 1 >= u->n)
        return 0;
    const float *n = gb->normal + 3 * i;
    const float v[3] = {u->eye[0] - p[0], u->eye[1] - p[1], u->eye[2] - p[2]};
    const float dist = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    const float cosv = dist > 0.0f ? fabsf(n[0] * v[0] + n[1] * v[1] + n[2] * v[2]) / dist : 1.0f;
    const float tol = 1.5f * u->px_scale * dist / fmaxf(cosv, 0.25f);
    if (!fg_same_surface(p, n, gb->albedo + 3 * i, mat, k->prev_pos + 4 * j, k->prev_nrm + 3 * j,
                         k->prev_alb + 3 * j, k->prev_mat + 4 * j, tol))
        return 0;
    memcpy(out, k->prev_out + 4 * j, 4 * sizeof *out);
    if (glossy)
        memcpy(glossy, k->prev_glossy + 4 * j, 4 * sizeof *glossy);
    *age = k->prev_age[j] + 1;
    return 1;
}

/* Grows the reuse arrays to the G-buffer's size (first use). */
static void reuse_alloc(fg_state *k)
{
    if (k->age)
        return;
    const size_t n = (size_t)k->c.width * (size_t)k->c.height;
    k->prev_pos = eng_xmalloc(4 * n * sizeof(float));
    k->prev_nrm = eng_xmalloc(3 * n * sizeof(float));
    k->prev_alb = eng_xmalloc(3 * n * sizeof(float));
    k->prev_mat = eng_xmalloc(4 * n * sizeof(float));
    k->prev_out = eng_xmalloc(4 * n * sizeof(float));
    k->prev_glossy = k->c.glossy ? eng_xmalloc(4 * n * sizeof(float)) : NULL;
    k->age = eng_xmalloc(n * sizeof(int));
    k->prev_age = eng_xmalloc(n * sizeof(int));
}

/* Keeps this frame's G-buffer, light, ages and camera for the next frame's reuse. */
static void reuse_keep(fg_state *k, const float vp[16], uint64_t key)
{
    const size_t n = (size_t)k->c.width * (size_t)k->c.height;
    memcpy(k->prev_pos, k->c.gb.position, 4 * n * sizeof(float));
    memcpy(k->prev_nrm, k->c.gb.normal, 3 * n * sizeof(float));
    memcpy(k->prev_alb, k->c.gb.albedo, 3 * n * sizeof(float));
    memcpy(k->prev_mat, k->c.gb.material, 4 * n * sizeof(float));
    memcpy(k->prev_out, k->c.out, 4 * n * sizeof(float));
    if (k->prev_glossy)
        memcpy(k->prev_glossy, k->c.glossy, 4 * n * sizeof(float));
    int *t = k->prev_age;
    k->prev_age = k->age;
    k->age = t;
    memcpy(k->prev_vp, vp, sizeof k->prev_vp);
    k->prev_key = key;
    k->have_prev = 1;
}

/* Copies the map's caustic photons and their radii into k->caustic; returns their count. */
static size_t caustic_photons(fg_state *k, const eng_photon_map *map, const float *radius, float *reach)
{
    size_t n = 0;
    *reach = 0.0f;
    for (size_t i = 0; i < map->count; i++)
        n += map->photons[i].caustic != 0;
    if (n > k->caustic_cap) {
        free(k->caustic.photons);
        free(k->caustic_radius);
        k->caustic.photons = eng_xmalloc(n * sizeof *k->caustic.photons);
        k->caustic_radius = eng_xmalloc(n * sizeof *k->caustic_radius);
        k->caustic_cap = n;
    }
    size_t j = 0;
    for (size_t i = 0; i < map->count; i++)
        if (map->photons[i].caustic) {
            k->caustic.photons[j] = map->photons[i];
            k->caustic_radius[j] = radius[i];
            *reach = fmaxf(*reach, radius[i]);
            j++;
        }
    k->caustic.count = n;
    return n;
}

/* Read-back, tracing and upload all count as the method's time. */
static eng_result fg_run(void *state, const ind_input *in, ind_output *out, eng_error *err)
{
    fg_state *k = state;
    if (!in->rt || !in->rm || !in->rf)
        return eng_fail(err, ENG_ERR_INVALID, "final-gather: no ray tracer or random maps given");
    glu_gbuffer_read(in->gbuf, &k->c.gb);
    const size_t n = (size_t)k->c.width * (size_t)k->c.height * 4;
    memset(k->c.out, 0, n * sizeof(float));
    if (k->c.glossy)
        memset(k->c.glossy, 0, n * sizeof(float));
    /* The lookups' kernels: every photon's r_xy times final_gather_radius. */
    const float f = in->s->final_gather_radius;
    if (in->map->count > k->radius_cap) { /* as caustic_photons grows its arrays */
        free(k->radius);
        k->radius = eng_xmalloc(in->map->count * sizeof *k->radius);
        k->radius_cap = in->map->count;
    }
    for (size_t i = 0; i < in->map->count; i++)
        k->radius[i] = in->radius[i] * f;
    eye_tracer *t = eye_tracer_create(in->fs, in->rt, in->map, k->radius, in->s, err);
    if (!t)
        return ENG_ERR_NOMEM;
    float creach = 0.0f;
    kd_tree ctree;
    int have_caustic = caustic_photons(k, in->map, in->radius, &creach) > 0;
    if (have_caustic && kd_tree_build(k->caustic.photons[0].position, k->caustic.count,
                                      sizeof(eng_photon) / sizeof(float), &ctree, err) != ENG_OK) {
        eye_tracer_destroy(t);
        return ENG_ERR_NOMEM;
    }
    const uint32_t log2n = rays_log4(in->s->final_gather_rays);
    const fg_ctx c = {t,
                      have_caustic ? &ctree : NULL,
                      &k->caustic,
                      k->caustic_radius,
                      creach,
                      in->s->normal_compression,
                      in->rm,
                      in->rf,
                      &k->c.gb,
                      in->fs->camera.eye,
                      log2n,
                      1u << (2 * log2n),
                      k->c.out,
                      k->c.glossy,
                      in->s->final_gather_seed == ENG_FG_SEED_SURFACE,
                      in->s->final_gather_cell};
    const int w = k->c.width, h = k->c.height;
    int threads = in->s->threads > 0 ? in->s->threads : 2;
    fg_reuse u = {k, in->s->final_gather_reuse, 0, k->c.glossy != NULL, in->fs->camera.eye, 0.0f};
    int comparable = 1;
    uint64_t key = 0;
    if (u.n > 1) {
        reuse_alloc(k);
        key = scene_key(in->fs, &comparable);
        u.valid = k->have_prev && comparable && key == k->prev_key;
        /* proj[5] = cot(fov_y / 2): a pixel spans 2·d / (proj[5]·h) at distance d. */
        const float p5 = in->fs->camera.proj[5];
        u.px_scale = p5 > 0.0f ? 2.0f / (p5 * (float)h) : 0.0f;
    }
#pragma omp parallel num_threads(threads)
    {
        eye_scratch sc = {NULL, 0};
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                if (u.n <= 1) {
                    fg_pixel(&c, x, y, &sc);
                    continue;
                }
                const size_t i = (size_t)y * (size_t)w + (size_t)x;
                if (fg_reuse_pixel(&u, x, y, k->c.out + 4 * i, k->c.glossy ? k->c.glossy + 4 * i : NULL,
                                   &k->age[i]))
                    continue;
                /* A pixel that had light to reuse but whose age ran out starts again at 0. */
                int qx, qy;
                const int expired = u.valid && fg_reproject(k->prev_vp, w, h, k->c.gb.position + 4 * i, &qx, &qy) &&
                                    k->prev_age[(size_t)qy * (size_t)w + (size_t)qx] + 1 >= u.n;
                k->age[i] = expired ? 0 : first_age(x, y, u.n);
                fg_pixel(&c, x, y, &sc);
            }
        free(sc.list);
    }
    if (u.n > 1)
        reuse_keep(k, in->fs->camera.view_proj, comparable ? key : ~key);
    eye_tracer_destroy(t);
    if (have_caustic)
        kd_tree_free(&ctree);
    ind_cpu_state_output(&k->c, out);
    return ENG_OK;
}

/* No kernel at the pixel: no per-pixel radii, no boundary correction (traced_gather). */
const ind_method ind_finalgather_method = {
    .name = "final-gather",
    .prefix = "final_gather",
    .pass = "final_gather",
    .create = fg_create,
    .run = fg_run,
    .destroy = fg_destroy,
    .traced_gather = 1,
    .history = fg_history,
    .reset = fg_reset,
};
