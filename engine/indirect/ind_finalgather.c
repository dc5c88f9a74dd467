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
 * per stratum otherwise.
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
    free(k);
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
} fg_ctx;

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
    const uint32_t pattern = rmap_hash_pixel(c->eye, (uint32_t)x, (uint32_t)y, 0u, c->rf->strata_salt ^ FG_SALT);
    const uint32_t seed = rmap_hash_pixel(c->eye, (uint32_t)x, (uint32_t)y, 1u, c->rf->salt ^ FG_SALT);
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
                      k->c.glossy};
    const int w = k->c.width, h = k->c.height;
    int threads = in->s->threads > 0 ? in->s->threads : 2;
#pragma omp parallel num_threads(threads)
    {
        eye_scratch sc = {NULL, 0};
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++)
                fg_pixel(&c, x, y, &sc);
        free(sc.list);
    }
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
};
