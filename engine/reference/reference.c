/* reference.c — the reference renderer (ref.h): ground truth for the engine's direct and
 * indirect light, on the CPU with Embree, for the scene exactly as eng_pose poses it.
 *
 * Light and BSDF models are the engine's: point and spot lights of radiant intensity I (W/sr)
 * with the KHR_lights_punctual range window and the smooth spot falloff t² of
 * shaders/direct.frag.glsl, directional lights of irradiance E (W/m²); surfaces scatter with
 * bsdf_scatter (bsdf.c: Lambert, GGX metal, delta mirror below roughness 0.01, smooth
 * dielectric with exact Fresnel and total internal reflection, Russian roulette), and
 * next-event estimation evaluates the same mixture's non-delta lobes (eval_f; Walter et al.
 * 2007 GGX with separable Smith G, as bsdf.c samples it). Emission (emissiveFactor × strength)
 * is seen, as in the engine, where an eye path meets an emitter after delta lobes only (directly:
 * reference.direct; through mirrors and glass: reference.indirect); emitters are not light
 * sources (no photons, no next-event estimation), as in the engine.
 *
 * Estimators and the path classes they cover (light side first; a vertex is "D" when the
 * scattering there uses a diffuse or glossy lobe, "S" when it uses a delta lobe):
 *   1a. Path tracing from the camera with next-event estimation (Veach 1997 §10.4.1, pbrt's
 *       PathIntegrator): at every D vertex x_k of an eye path, a shadow ray to each light.
 *   1b. Light vertices (Keller 1997 instant radiosity; bidirectional path tracing with one
 *       light vertex, Veach 1997 §10.2): at every D vertex x_k, one ray sampled from a light
 *       (light ∝ power, direction uniform over its sphere or cone); if its first surface x' is
 *       D, x' is connected to x_k by a shadow ray. It samples the surfaces near a light in
 *       proportion to their irradiance, where 1a's BSDF sampling makes fireflies (the Cornell
 *       box ceiling 0.19 m above its light).
 *       1a and 1b both make every path L D D (D|S)* E, the last D from the light being x_k;
 *       they are combined by the balance heuristic (Veach 1997 §9.2.2) in area measure at x'.
 *       Paths L D (S) ... and the camera's first vertex (L D E) only 1a makes (weight 1).
 *       Together they cover every path L D (D|S)* E whose first vertex after the light is D.
 *       The NEE at the camera's first vertex is "direct" (L D E: one surface); the rest
 *       "indirect".
 *   2. Probabilistic progressive photon mapping for caustics (Knaus & Zwicker 2011, "Progressive
 *      Photon Mapping: A Probabilistic Approach", Eq. 15–16; Hachisuka et al. 2008): one photon
 *      pass per sample; photons leave the lights toward the bounding sphere of the surfaces
 *      with a delta lobe, cross one or more S vertices and are stored at the next surface with
 *      a D lobe (then continue only if that surface scatters them specularly again); every D
 *      vertex of every eye path of sample s gathers pass s's photons within radius r_s,
 *      L = Σ f·Φ_p / (π r_s²), with r_{s+1}² = r_s² (s + α)/(s + 1). Covers every path
 *      L S+ D (D|S)* E: the first D vertex after the light is the gather point. Always
 *      "indirect" (at least two surfaces).
 * The classes are disjoint and together hold every path with at least one D vertex: split a
 * path at its first D vertex counted from the light (estimator 1 when it is the first vertex,
 * 2 otherwise); paths L S* E carry no energy to a pinhole from a punctual light. Photons and
 * light vertices whose first surface is S are dropped by 1b and stored only after it by 2, and
 * an eye path never hits a light. The photon pass's bias (the kernel radius) vanishes as
 * r_s → 0; 1a and 1b are unbiased. Paths are at most max_depth eye vertices long (1b adds one
 * vertex only where 1a could still continue).
 * Refraction carries no η² factor (bsdf.c: photons carry power); for an eye path that both
 * enters and leaves a dielectric the factors cancel, so the estimate is exact whenever the
 * camera and the D surfaces lie in air, as in every scene the project ships.
 *
 * Determinism: a random number is mix64 of (stream, pixel or photon index, sample, frame,
 * seed, dimension) — no generator state; an eye vertex uses 9 dimensions (6 to scatter, 3 for
 * its light vertex). Pixels are independent and each pixel's sums are
 * taken in sample order; a pass's photons are sorted by (photon index, hit index) before the
 * hash grid is built (stable counting sort), and a gather visits buckets and photons in a
 * fixed order. So results are bit-identical for any thread count (tests/test_reference.c).
 *
 * Owns: its settings and listeners; per frame the sums, the photon buffers and the grid. */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "ref.h"
#include "eng_frame.h"

#include "bsdf.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define REF_MAX_LISTENERS 8
#define REF_PRIMARY_SKIPS 16 /* back faces of single-sided surfaces a camera ray may pass */

struct ref_renderer {
    ref_desc d;
    int width, height;
    int listener_count;
    eng_listener listeners[REF_MAX_LISTENERS];
};

/* ---------------------------------------------------------------- small helpers */

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static float dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static float clamp01(float x)
{
    return x < 0.0f ? 0.0f : (x > 1.0f ? 1.0f : x);
}

static int nonzero3(const float v[3])
{
    return v[0] > 0.0f || v[1] > 0.0f || v[2] > 0.0f;
}

static void normalize3(float v[3])
{
    float l = sqrtf(dot3(v, v));
    if (l > 0.0f)
        for (int i = 0; i < 3; i++)
            v[i] /= l;
}

/* ---------------------------------------------------------------- random numbers */

/* splitmix64's finaliser (Steele et al. 2014): a bijective 64-bit mix. */
static uint64_t mix64(uint64_t z)
{
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

enum { STREAM_EYE = 1, STREAM_PHOTON = 2 };

/* The key of one path: stream, pixel (or photon) index, sample (or pass), frame, seed. */
static uint64_t path_key(uint32_t stream, uint32_t index, uint32_t sample, uint32_t frame, uint32_t seed)
{
    uint64_t k = mix64(((uint64_t)seed << 32) | stream);
    k = mix64(k ^ frame);
    return mix64(k ^ (((uint64_t)index << 32) | sample));
}

/* Dimension `dim` of a path: a uniform float in [0, 1) (24 bits). */
static float rnd(uint64_t key, uint32_t dim)
{
    return (float)(mix64(key ^ ((uint64_t)dim * 0xD1B54A32D192ED03ull)) >> 40) * (1.0f / 16777216.0f);
}

/* The 6 numbers one scattering event takes (bsdf.h): u[0..3] and a cosine-weighted
 * direction about +Z with its pdf (Malley's method: uniform disk, projected up). */
static void scatter_numbers(uint64_t key, uint32_t dim0, float u[4], float cosdir[4])
{
    for (int i = 0; i < 4; i++)
        u[i] = rnd(key, dim0 + (uint32_t)i);
    float r = sqrtf(rnd(key, dim0 + 4)), phi = (float)(2.0 * ENG_PI) * rnd(key, dim0 + 5);
    cosdir[0] = r * cosf(phi);
    cosdir[1] = r * sinf(phi);
    cosdir[2] = sqrtf(fmaxf(0.0f, 1.0f - r * r));
    cosdir[3] = cosdir[2] / (float)ENG_PI;
}

#define DIMS_PER_BOUNCE 6u
#define EYE_DIMS_PER_VERTEX 9u /* scattering (6) and the light vertex of estimator 1b (3) */
#define EYE_DIM0 2u    /* dims 0, 1: the position inside the pixel */
#define PHOTON_DIM0 4u /* dims 0..3: the emitted direction (and disk position) */

/* ---------------------------------------------------------------- BSDF evaluation */

static float schlick1(float f0, float c)
{
    float k = 1.0f - clamp01(c);
    float k2 = k * k;
    return f0 + (1.0f - f0) * k2 * k2 * k;
}

static float ggx_g1(float ndotv, float alpha)
{
    float a2 = alpha * alpha;
    return 2.0f * ndotv / (ndotv + sqrtf(a2 + (1.0f - a2) * ndotv * ndotv));
}

/* f(wi, wo) of the non-delta lobes of bsdf.c's mixture: (1 − metallic)(1 − transmission)·
 * albedo/π + metallic·GGX (Walter et al. 2007 Eq. 20: D·G·F/(4|wi·n||wo·n|), D Eq. 33, Smith
 * G1 Eq. 34, Schlick F with F0 = base colour), which is what bsdf_scatter samples with weight
 * f·cos/pdf. ns is the shading normal turned toward wi. Returns 0 (f zero) when wi or wo lie
 * below it. */
static int eval_f(const scn_material *m, const float ns[3], const float wi[3], const float wo[3], float f[3])
{
    float ci = dot3(ns, wi), co = dot3(ns, wo);
    if (!(ci > 0.0f) || !(co > 0.0f))
        return 0;
    float metallic = clamp01(m->metallic), transmission = clamp01(m->transmission);
    float kd = (1.0f - metallic) * (1.0f - transmission) / (float)ENG_PI;
    for (int i = 0; i < 3; i++)
        f[i] = kd * m->base_color[i];
    if (metallic > 0.0f && m->roughness >= BSDF_MIRROR_ROUGHNESS) {
        float alpha = m->roughness * m->roughness;
        if (alpha < BSDF_MIN_ALPHA)
            alpha = BSDF_MIN_ALPHA;
        float h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
        normalize3(h);
        float nh = dot3(ns, h), hw = dot3(h, wi);
        if (nh > 0.0f && hw > 0.0f) {
            float a2 = alpha * alpha, q = nh * nh * (a2 - 1.0f) + 1.0f;
            float d = a2 / ((float)ENG_PI * q * q);
            float k = metallic * d * ggx_g1(ci, alpha) * ggx_g1(co, alpha) / (4.0f * ci * co);
            for (int i = 0; i < 3; i++)
                f[i] += k * schlick1(m->base_color[i], hw);
        }
    }
    return nonzero3(f);
}

/* Does the material have a delta lobe (delta mirror, or dielectric) with non-zero weight? */
static int has_delta(const scn_material *m)
{
    float metallic = clamp01(m->metallic), transmission = clamp01(m->transmission);
    return (metallic > 0.0f && m->roughness < BSDF_MIRROR_ROUGHNESS) || (metallic < 1.0f && transmission > 0.0f);
}

/* Solid-angle density with which bsdf_scatter picks wo through the non-delta lobes
 * (lobe-choice probability × lobe pdf, Russian roulette left out): metallic·D(h)(n·h)/(4|wo·h|)
 * (Walter et al. 2007 Eq. 38 with the Jacobian of Eq. 14) + (1 − metallic)(1 − transmission)·
 * cos/π. ns is turned toward wi. */
static float pdf_mix(const scn_material *m, const float ns[3], const float wi[3], const float wo[3])
{
    float co = dot3(ns, wo);
    if (!(co > 0.0f) || !(dot3(ns, wi) > 0.0f))
        return 0.0f;
    float metallic = clamp01(m->metallic), transmission = clamp01(m->transmission);
    float p = (1.0f - metallic) * (1.0f - transmission) * co / (float)ENG_PI;
    if (metallic > 0.0f && m->roughness >= BSDF_MIRROR_ROUGHNESS) {
        float alpha = m->roughness * m->roughness;
        if (alpha < BSDF_MIN_ALPHA)
            alpha = BSDF_MIN_ALPHA;
        float h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
        normalize3(h);
        float nh = dot3(ns, h), oh = dot3(wo, h);
        if (nh > 0.0f && oh > 0.0f) {
            float a2 = alpha * alpha, q = nh * nh * (a2 - 1.0f) + 1.0f;
            p += metallic * a2 / ((float)ENG_PI * q * q) * nh / (4.0f * oh);
        }
    }
    return p;
}

/* ---------------------------------------------------------------- lights */

/* Lights with a size (scn_light.radius): the point a shadow ray aims at and the
 * direction wl toward it, from two uniform numbers. A sphere of radius R and uniform radiance
 * I/(πR²) seen from p delivers light_at's irradiance I/d² (d to its centre) spread over its
 * disc, so the sample is uniform on the disc through the centre facing p; a directional disc
 * of angular radius α, uniform on the disc of radius tan α about the direction. Punctual
 * lights keep the centre (target = position, wl unchanged). */
#define REF_AREA_DIM0 0x40000000u /* random dimensions of the samples: apart from the path's */
static void light_area_point(const eng_light_pose *l, const float p[3], float u1, float u2, float target[3],
                             float wl[3])
{
    memcpy(target, l->position, 3 * sizeof(float));
    if (!(l->radius > 0.0f))
        return;
    float r = sqrtf(u1), phi = (float)(2.0 * ENG_PI) * u2;
    float w[3] = {wl[0], wl[1], wl[2]}, t[3], b[3];
    bsdf_basis(w, t, b);
    float rad = l->type == SCN_LIGHT_DIRECTIONAL ? tanf(l->radius) : l->radius;
    float a = rad * r * cosf(phi), bb = rad * r * sinf(phi);
    if (l->type == SCN_LIGHT_DIRECTIONAL) {
        float d[3], len2 = 0.0f;
        for (int i = 0; i < 3; i++) {
            d[i] = w[i] + a * t[i] + bb * b[i];
            len2 += d[i] * d[i];
        }
        float inv = 1.0f / sqrtf(len2);
        for (int i = 0; i < 3; i++)
            wl[i] = d[i] * inv;
        return;
    }
    float d[3], len2 = 0.0f;
    for (int i = 0; i < 3; i++) {
        target[i] = l->position[i] + a * t[i] + bb * b[i];
        d[i] = target[i] - p[i];
        len2 += d[i] * d[i];
    }
    float inv = 1.0f / sqrtf(len2);
    for (int i = 0; i < 3; i++)
        wl[i] = d[i] * inv;
}

/* ---------------------------------------------------------------- caustic photons */

typedef struct ref_photon {
    float position[3];
    float wi[3];     /* unit, toward where the photon came from */
    float power[3];  /* W */
    float normal[3]; /* shading normal turned toward wi */
} ref_photon;

typedef struct keyed_photon {
    uint64_t key; /* photon index · (max_depth + 2) + hit index: the deterministic order */
    ref_photon p;
} keyed_photon;

typedef struct photon_buf {
    size_t count, cap;
    keyed_photon *v;
} photon_buf;

static void photon_push(photon_buf *b, uint64_t key, const ref_photon *p)
{
    if (b->count == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 1024;
        keyed_photon *v = realloc(b->v, cap * sizeof *v);
        if (!v) {
            fprintf(stderr, "ispm: out of memory\n");
            abort();
        }
        b->v = v;
        b->cap = cap;
    }
    b->v[b->count].key = key;
    b->v[b->count].p = *p;
    b->count++;
}

/* A hash grid of cells 2r wide, so a sphere of radius r touches at most 2×2×2 cells. */
typedef struct photon_grid {
    float radius, inv_cell;
    uint32_t mask;    /* buckets − 1 */
    uint32_t *start;  /* buckets + 1 */
    ref_photon *photons;
    size_t count;
} photon_grid;

static uint32_t cell_bucket(int64_t x, int64_t y, int64_t z, uint32_t mask)
{
    uint64_t h = mix64((uint64_t)x * 0x9E3779B1ull ^ mix64((uint64_t)y * 0x85EBCA77ull ^ mix64((uint64_t)z)));
    return (uint32_t)h & mask;
}

static void cell_of(const photon_grid *g, const float p[3], int64_t c[3])
{
    for (int i = 0; i < 3; i++)
        c[i] = (int64_t)floorf(p[i] * g->inv_cell);
}

/* How the photons of one frame's passes are emitted: per light the photon count and the
 * cone (or disk) toward the bounding sphere of the surfaces with a delta lobe. */
typedef struct emit_plan {
    int any;              /* a surface with a delta lobe exists and some light reaches it */
    float centre[3], rad; /* bounding sphere of the delta surfaces */
    uint32_t count[8], first[8], total;
    float cos_max[8];     /* point/spot: cone of directions sampled; 1 − cos_max > 0 */
    float axis[8][3];
    float power[8][3];    /* W per photon before spot falloff and range window */
} emit_plan;

typedef struct frame_ctx {
    const eng_frame_scene *fs;
    const eng_rt *rt;
    double inv_view_proj[16];
    int width, height;
    uint32_t frame, seed;
    int max_depth, pixel_center;
    float far_dist;           /* longer than any segment inside the scene's bounds */
    const photon_grid *grid;  /* this pass's caustic photons, or NULL */
    const emit_plan *plan;
    /* Light vertices of estimator 1b: light l is picked with probability light_q[l] (its
     * power share), then a direction uniform over its sphere (point), its outer cone (spot),
     * or a point uniform on the disk of the scene's bounding sphere (directional). */
    float light_q[8];
    float light_cos_max[8];   /* −1 (point) or cos(outer cone) (spot) */
    float scene_centre[3], scene_rad;
} frame_ctx;

static void bounds_sphere(const eng_frame_scene *fs, int delta_only, float centre[3], float *rad, int *found)
{
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    *found = 0;
    for (uint32_t i = 0; i < fs->draw_count; i++) {
        const eng_draw *d = &fs->draws[i];
        scn_material m = eng_material_of(fs->scene, d->material);
        if (delta_only && !has_delta(&m))
            continue;
        const scn_primitive *p = &fs->scene->primitives[d->primitive];
        const float *pos = eng_draw_positions(fs->scene, d);
        for (uint32_t v = 0; v < p->vertex_count; v++) {
            float q[3];
            m4_transform_point(d->world, pos + 3 * v, q);
            for (int c = 0; c < 3; c++) {
                lo[c] = fminf(lo[c], q[c]);
                hi[c] = fmaxf(hi[c], q[c]);
            }
            *found = 1;
        }
    }
    float r2 = 0.0f;
    for (int c = 0; c < 3; c++) {
        centre[c] = *found ? 0.5f * (lo[c] + hi[c]) : 0.0f;
        float e = *found ? 0.5f * (hi[c] - lo[c]) : 0.0f;
        r2 += e * e;
    }
    /* A little margin: the sphere must hold every vertex after float rounding. */
    *rad = sqrtf(r2) * 1.001f + 1e-4f;
}

static void make_plan(const eng_frame_scene *fs, int photons, emit_plan *pl)
{
    memset(pl, 0, sizeof *pl);
    int found;
    bounds_sphere(fs, 1, pl->centre, &pl->rad, &found);
    if (!found)
        return;
    double share[8] = {0}, total = 0.0;
    for (uint32_t l = 0; l < fs->light_count && l < 8; l++) {
        const eng_light_pose *lp = &fs->lights[l];
        double mean = (lp->radiance_scale[0] + lp->radiance_scale[1] + lp->radiance_scale[2]) / 3.0;
        double extent; /* solid angle (sr) or disk area (m²) photons are spread over */
        if (lp->type == SCN_LIGHT_DIRECTIONAL) {
            memcpy(pl->axis[l], lp->direction, sizeof pl->axis[l]);
            extent = ENG_PI * (double)pl->rad * pl->rad;
        } else {
            float a[3] = {pl->centre[0] - lp->position[0], pl->centre[1] - lp->position[1],
                          pl->centre[2] - lp->position[2]};
            float d = sqrtf(dot3(a, a));
            if (d > pl->rad) {
                float s = pl->rad / d;
                pl->cos_max[l] = sqrtf(1.0f - s * s);
                for (int c = 0; c < 3; c++)
                    pl->axis[l][c] = a[c] / d;
            } else { /* the light is inside the sphere: the whole sphere of directions */
                pl->cos_max[l] = -1.0f;
                pl->axis[l][0] = pl->axis[l][1] = 0.0f;
                pl->axis[l][2] = 1.0f;
            }
            extent = 2.0 * ENG_PI * (1.0 - (double)pl->cos_max[l]);
        }
        share[l] = mean > 0.0 ? mean * extent : 0.0;
        total += share[l];
        for (int c = 0; c < 3; c++)
            pl->power[l][c] = (float)(lp->radiance_scale[c] * extent);
    }
    if (!(total > 0.0))
        return;
    for (uint32_t l = 0; l < fs->light_count && l < 8; l++) {
        uint32_t n = share[l] > 0.0 ? (uint32_t)ceil((double)photons * share[l] / total) : 0u;
        pl->first[l] = pl->total;
        pl->count[l] = n;
        pl->total += n;
        for (int c = 0; c < 3 && n; c++)
            pl->power[l][c] /= (float)n;
    }
    pl->any = pl->total > 0;
}

/* Picks the normal scattering happens about: the interpolated shading normal unless it puts
 * wi on the other side than the true surface does (photon_trace.c's rule). */
static void scatter_normal(const rt_hit *h, const float wi[3], float n[3])
{
    float cg = dot3(h->geom_normal, wi), cs = dot3(h->normal, wi);
    memcpy(n, ((cg >= 0.0f) == (cs >= 0.0f)) ? h->normal : h->geom_normal, 3 * sizeof(float));
}

/* ---------------------------------------------------------------- lamps */

/* Lamps: the emitters of point and spot lights with a size are opaque spheres
 * that reflect nothing (rt.c's rt_lamp_hit; rt_intersect already stops at them, rt_occluded
 * does not). */

/* Whether a lamp other than light skip is on the segment from → to. */
static int lamp_blocks(const eng_rt *rt, const float from[3], const float to[3], int skip)
{
    float d[3] = {to[0] - from[0], to[1] - from[1], to[2] - from[2]};
    float len = sqrtf(dot3(d, d)), t;
    if (!(len > 0.0f))
        return 0;
    for (int i = 0; i < 3; i++)
        d[i] /= len;
    return rt_lamp_hit(rt, from, d, 0.0f, len, skip, &t) >= 0;
}

/* Radiance a lamp sends along -dir from its surface: uniform I/(πR²), times the spot cone
 * falloff for the direction it leaves the centre by. */
static void lamp_radiance(const eng_light_pose *lp, const float dir[3], float out[3])
{
    float k = 1.0f / ((float)ENG_PI * lp->radius * lp->radius);
    if (lp->type == SCN_LIGHT_SPOT)
        k *= frame_spot_falloff(lp, -dot3(lp->direction, dir));
    for (int i = 0; i < 3; i++)
        out[i] = lp->radiance_scale[i] * k;
}

/* Area density (1/m² at x, geometric normal ng) with which estimator 1b's light sampling
 * lands on x as the first surface light l reaches: q_l · p_ω · |cos|/d² for point and spot
 * lights, q_l · |cos|/(πR²) for directional ones (0 outside a spot's cone). */
static float light_vertex_pdf(const frame_ctx *c, uint32_t l, const float x[3], const float ng[3])
{
    const eng_light_pose *lp = &c->fs->lights[l];
    float q = c->light_q[l];
    if (!(q > 0.0f))
        return 0.0f;
    if (lp->type == SCN_LIGHT_DIRECTIONAL)
        return q * fabsf(dot3(ng, lp->direction)) / ((float)ENG_PI * c->scene_rad * c->scene_rad);
    float d[3] = {x[0] - lp->position[0], x[1] - lp->position[1], x[2] - lp->position[2]};
    float d2 = dot3(d, d);
    if (!(d2 > 0.0f))
        return 0.0f;
    float len = sqrtf(d2);
    float cos_max = c->light_cos_max[l];
    if (lp->type == SCN_LIGHT_SPOT && dot3(lp->direction, d) < cos_max * len)
        return 0.0f;
    float p_omega = 1.0f / ((float)(2.0 * ENG_PI) * (1.0f - cos_max));
    return q * p_omega * fabsf(dot3(ng, d)) / (len * d2);
}

/* A ray leaving a light as estimator 1b samples it (light choice u0, direction u1, u2). */
static uint32_t sample_light_ray(const frame_ctx *c, float u0, float u1, float u2, float org[3], float dir[3])
{
    const eng_frame_scene *fs = c->fs;
    uint32_t l = 0;
    float acc = c->light_q[0];
    while (l + 1 < fs->light_count && !(u0 < acc))
        acc += c->light_q[++l];
    const eng_light_pose *lp = &fs->lights[l];
    float t[3], b[3];
    if (lp->type == SCN_LIGHT_DIRECTIONAL) {
        bsdf_basis(lp->direction, t, b);
        float r = c->scene_rad * sqrtf(u1), phi = (float)(2.0 * ENG_PI) * u2;
        for (int i = 0; i < 3; i++) {
            org[i] = c->scene_centre[i] + r * cosf(phi) * t[i] + r * sinf(phi) * b[i] - c->far_dist * lp->direction[i];
            dir[i] = lp->direction[i];
        }
        return l;
    }
    static const float up[3] = {0.0f, 0.0f, 1.0f};
    const float *axis = lp->type == SCN_LIGHT_SPOT ? lp->direction : up;
    bsdf_basis(axis, t, b);
    float ct = 1.0f - u1 * (1.0f - c->light_cos_max[l]);
    float st = sqrtf(fmaxf(0.0f, 1.0f - ct * ct)), phi = (float)(2.0 * ENG_PI) * u2;
    for (int i = 0; i < 3; i++) {
        org[i] = lp->position[i];
        dir[i] = st * cosf(phi) * t[i] + st * sinf(phi) * b[i] + ct * axis[i];
    }
    normalize3(dir);
    return l;
}

/* Traces photon g of pass `pass`; stores its caustic photons in out. Returns how many. */
static int trace_photon(const frame_ctx *c, uint32_t g, uint32_t pass, photon_buf *out)
{
    const emit_plan *pl = c->plan;
    const eng_frame_scene *fs = c->fs;
    uint32_t l = 0;
    while (l + 1 < fs->light_count && g >= pl->first[l] + pl->count[l])
        l++;
    const eng_light_pose *lp = &fs->lights[l];
    uint64_t key = path_key(STREAM_PHOTON, g, pass, c->frame, c->seed);
    float org[3], dir[3], power[3];
    float t[3], b[3];
    bsdf_basis(pl->axis[l], t, b);
    if (lp->type == SCN_LIGHT_DIRECTIONAL) {
        /* Uniform on the disk of the sphere's radius facing the light (power = E·πR²/N). */
        float r = pl->rad * sqrtf(rnd(key, 0)), phi = (float)(2.0 * ENG_PI) * rnd(key, 1);
        float back = c->far_dist;
        for (int i = 0; i < 3; i++) {
            org[i] = pl->centre[i] + r * cosf(phi) * t[i] + r * sinf(phi) * b[i] - back * lp->direction[i];
            dir[i] = lp->direction[i];
            power[i] = pl->power[l][i];
        }
    } else {
        /* Uniform in the cone toward the sphere (power = I·Ω/N); spot falloff per direction. */
        float ct = 1.0f - rnd(key, 0) * (1.0f - pl->cos_max[l]);
        float st = sqrtf(fmaxf(0.0f, 1.0f - ct * ct)), phi = (float)(2.0 * ENG_PI) * rnd(key, 1);
        float k = 1.0f;
        for (int i = 0; i < 3; i++) {
            org[i] = lp->position[i];
            dir[i] = st * cosf(phi) * t[i] + st * sinf(phi) * b[i] + ct * pl->axis[l][i];
        }
        normalize3(dir);
        if (lp->type == SCN_LIGHT_SPOT)
            k = frame_spot_falloff(lp, dot3(lp->direction, dir));
        for (int i = 0; i < 3; i++)
            power[i] = pl->power[l][i] * k;
    }
    if (!nonzero3(power))
        return 0;
    float eta = 1.0f, tnear = 0.0f;
    int stored = 0;
    for (int k = 0; k <= c->max_depth; k++) {
        rt_hit h;
        if (!rt_intersect(c->rt, org, dir, tnear, INFINITY, &h))
            break; /* left the scene, or absorbed by a lamp */
        if (k == 0 && lp->type != SCN_LIGHT_DIRECTIONAL && lp->range > 0.0f) {
            float r = h.t / lp->range; /* the range window at the distance the light reaches */
            float w = clamp01(1.0f - r * r * r * r);
            for (int i = 0; i < 3; i++)
                power[i] *= w * w;
        }
        const float wi[3] = {-dir[0], -dir[1], -dir[2]};
        float n[3];
        scatter_normal(&h, wi, n);
        scn_material m = eng_material_at(fs->scene, &h);
        if (k >= 1 && bsdf_stores_photons(&m)) {
            ref_photon ph;
            float side = dot3(n, wi) >= 0.0f ? 1.0f : -1.0f;
            for (int i = 0; i < 3; i++) {
                ph.position[i] = h.position[i];
                ph.wi[i] = wi[i];
                ph.power[i] = power[i];
                ph.normal[i] = side * n[i];
            }
            photon_push(out, (uint64_t)g * (uint64_t)(c->max_depth + 2) + (uint64_t)k, &ph);
            stored++;
        }
        if (k == c->max_depth)
            break;
        float u[4], cosdir[4], wo[3], w[3], density;
        scatter_numbers(key, PHOTON_DIM0 + DIMS_PER_BOUNCE * (uint32_t)k, u, cosdir);
        bsdf_sample rs = {u, cosdir};
        bsdf_lobe lobe = bsdf_scatter(&m, n, wi, &eta, &rs, wo, w, &density);
        /* A D scatter ends the caustic path: what follows is estimator 1's. */
        if (lobe == BSDF_ABSORBED || lobe == BSDF_DIFFUSE || lobe == BSDF_GLOSSY)
            break;
        for (int i = 0; i < 3; i++)
            power[i] *= w[i];
        if (!nonzero3(power))
            break;
        float eps = bsdf_offset_eps(h.position);
        float side = dot3(h.geom_normal, wo) >= 0.0f ? eps : -eps;
        for (int i = 0; i < 3; i++) {
            org[i] = h.position[i] + side * h.geom_normal[i];
            dir[i] = wo[i];
        }
    }
    return stored;
}

static int key_cmp(const void *a, const void *b)
{
    uint64_t x = ((const keyed_photon *)a)->key, y = ((const keyed_photon *)b)->key;
    return x < y ? -1 : x > y;
}

/* One photon pass: traces every photon, orders them, builds the grid of radius r. */
static void photon_pass(const frame_ctx *c, uint32_t pass, float radius, int threads, photon_grid *g,
                        uint64_t *stored_total)
{
    const emit_plan *pl = c->plan;
    photon_buf *bufs = eng_xcalloc((size_t)threads, sizeof *bufs);
#pragma omp parallel num_threads(threads)
    {
        photon_buf *mine = &bufs[omp_get_thread_num()];
#pragma omp for schedule(dynamic, 256)
        for (int64_t i = 0; i < (int64_t)pl->total; i++)
            trace_photon(c, (uint32_t)i, pass, mine);
    }
    size_t n = 0;
    for (int t = 0; t < threads; t++)
        n += bufs[t].count;
    keyed_photon *all = eng_xcalloc(n, sizeof *all);
    size_t at = 0;
    for (int t = 0; t < threads; t++) {
        if (bufs[t].count)
            memcpy(all + at, bufs[t].v, bufs[t].count * sizeof *all);
        at += bufs[t].count;
        free(bufs[t].v);
    }
    free(bufs);
    qsort(all, n, sizeof *all, key_cmp); /* keys are unique: the order is the photons' own */
    *stored_total += n;

    uint32_t buckets = 1024;
    while (buckets < 2 * n && buckets < (1u << 30))
        buckets <<= 1;
    free(g->start);
    free(g->photons);
    g->radius = radius;
    g->inv_cell = 1.0f / (2.0f * radius);
    g->mask = buckets - 1;
    g->start = eng_xcalloc((size_t)buckets + 1, sizeof *g->start);
    g->photons = eng_xcalloc(n, sizeof *g->photons);
    g->count = n;
    uint32_t *bucket_of = eng_xcalloc(n, sizeof *bucket_of);
    for (size_t i = 0; i < n; i++) {
        int64_t cc[3];
        cell_of(g, all[i].p.position, cc);
        bucket_of[i] = cell_bucket(cc[0], cc[1], cc[2], g->mask);
        g->start[bucket_of[i] + 1]++;
    }
    for (uint32_t b = 0; b < buckets; b++)
        g->start[b + 1] += g->start[b];
    uint32_t *fill = eng_xcalloc((size_t)buckets, sizeof *fill);
    for (size_t i = 0; i < n; i++) {
        uint32_t b = bucket_of[i];
        g->photons[g->start[b] + fill[b]++] = all[i].p;
    }
    free(fill);
    free(bucket_of);
    free(all);
}

/* Estimator 2 at a D vertex: Σ f·Φ_p / (π r²) over the pass's photons within r on the same
 * surface side (Hachisuka et al. 2008 Eq. 8 with a fixed per-pass radius). */
static void gather(const frame_ctx *c, const scn_material *m, const float p[3], const float ns[3],
                   const float wi[3], float out[3])
{
    const photon_grid *g = c->grid;
    out[0] = out[1] = out[2] = 0.0f;
    if (!g || !g->count)
        return;
    float r = g->radius, r2 = r * r;
    float lo[3] = {p[0] - r, p[1] - r, p[2] - r}, hi[3] = {p[0] + r, p[1] + r, p[2] + r};
    int64_t a[3], z[3];
    cell_of(g, lo, a);
    cell_of(g, hi, z);
    uint32_t seen[8];
    int nseen = 0;
    double sum[3] = {0.0, 0.0, 0.0};
    for (int64_t x = a[0]; x <= z[0]; x++)
        for (int64_t y = a[1]; y <= z[1]; y++)
            for (int64_t w = a[2]; w <= z[2]; w++) {
                uint32_t b = cell_bucket(x, y, w, g->mask);
                int dup = 0;
                for (int i = 0; i < nseen; i++)
                    dup |= seen[i] == b;
                if (dup || nseen == 8)
                    continue;
                seen[nseen++] = b;
                for (uint32_t i = g->start[b]; i < g->start[b + 1]; i++) {
                    const ref_photon *ph = &g->photons[i];
                    float d[3] = {ph->position[0] - p[0], ph->position[1] - p[1], ph->position[2] - p[2]};
                    if (dot3(d, d) >= r2 || dot3(ph->normal, ns) < 0.5f)
                        continue;
                    float f[3];
                    if (!eval_f(m, ns, wi, ph->wi, f))
                        continue;
                    for (int k = 0; k < 3; k++)
                        sum[k] += (double)f[k] * ph->power[k];
                }
            }
    double norm = 1.0 / (ENG_PI * (double)r2);
    for (int k = 0; k < 3; k++)
        out[k] = (float)(sum[k] * norm);
}

/* Estimator 1a's shadow rays at a D vertex: Σ_l w_l·f·E_l·cos·V. ng is the geometric normal.
 * When the eye path reached p from a D vertex prev by sampling that vertex's non-delta lobes
 * with solid-angle density prev_pdf (prev NULL otherwise), estimator 1b could have made the
 * same path, and w_l is the balance heuristic (Veach 1997 §9.2.2) p_A/(p_A + p_B,l) in area
 * measure at p; otherwise w_l = 1. */
static void next_event(const frame_ctx *c, const scn_material *m, const float p[3], const float ng[3],
                       const float ns[3], const float wi[3], const float *prev, float prev_pdf, uint64_t key,
                       uint32_t dim, float out[3])
{
    out[0] = out[1] = out[2] = 0.0f;
    float gi = dot3(ng, wi);
    float p_a = 0.0f;
    if (prev) {
        float d[3] = {prev[0] - p[0], prev[1] - p[1], prev[2] - p[2]};
        float d2 = dot3(d, d);
        p_a = d2 > 0.0f ? prev_pdf * fabsf(dot3(ng, d)) / (sqrtf(d2) * d2) : 0.0f;
    }
    for (uint32_t l = 0; l < c->fs->light_count; l++) {
        const eng_light_pose *lp = &c->fs->lights[l];
        float wl[3], dist, e[3], f[3];
        if (!frame_light_at(lp, p, wl, &dist, e))
            continue;
        float target[3];
        light_area_point(lp, p, rnd(key, REF_AREA_DIM0 + 16u * dim + 2u * l),
                         rnd(key, REF_AREA_DIM0 + 16u * dim + 2u * l + 1u), target, wl);
        float cosl = dot3(ns, wl), gl = dot3(ng, wl);
        if (!(cosl > 0.0f) || (gl >= 0.0f) != (gi >= 0.0f)) /* light behind the true surface */
            continue;
        if (!eval_f(m, ns, wi, wl, f))
            continue;
        float w = 1.0f;
        if (prev) {
            float p_b = light_vertex_pdf(c, l, p, ng);
            w = p_a + p_b > 0.0f ? p_a / (p_a + p_b) : 0.0f;
        }
        float eps = gl >= 0.0f ? bsdf_offset_eps(p) : -bsdf_offset_eps(p);
        float from[3], to[3];
        for (int i = 0; i < 3; i++) {
            from[i] = p[i] + eps * ng[i];
            to[i] = isinf(dist) ? p[i] + c->far_dist * wl[i] : target[i];
        }
        if (rt_occluded(c->rt, from, to) || lamp_blocks(c->rt, from, to, (int)l))
            continue;
        for (int i = 0; i < 3; i++)
            out[i] += w * f[i] * e[i] * cosl;
    }
}

/* Estimator 1b at a D vertex x1 (geometric normal ng1, shading normal ns1 toward wi1): a
 * light vertex x2, the first surface a ray sampled from a light meets, connected to x1 with a
 * shadow ray (instant-radiosity style, Keller 1997; the light-tracing half of bidirectional
 * path tracing with one light vertex, Veach 1997 §10.2). Path L x2 x1: f1·cos1·G·f2·E·cos2 / (p_A
 * + p_B), the balance heuristic with 1a's BSDF sampling at x1, both in area measure at x2.
 * The light vertex's class is 1a's (its first vertex after the light is D), never a caustic. */
static void light_vertex(const frame_ctx *c, uint64_t key, uint32_t dim0, const scn_material *m1, const float x1[3],
                         const float ng1[3], const float ns1[3], const float wi1[3], float out[3])
{
    out[0] = out[1] = out[2] = 0.0f;
    float org[3], dir[3];
    uint32_t l = sample_light_ray(c, rnd(key, dim0), rnd(key, dim0 + 1), rnd(key, dim0 + 2), org, dir);
    rt_hit h;
    if (!rt_intersect(c->rt, org, dir, 0.0f, INFINITY, &h))
        return;
    scn_material m2 = eng_material_at(c->fs->scene, &h);
    if (!bsdf_stores_photons(&m2))
        return; /* a specular first surface: a caustic path, estimator 2's */
    const float *x2 = h.position, *ng2 = h.geom_normal;
    float d[3] = {x1[0] - x2[0], x1[1] - x2[1], x1[2] - x2[2]};
    float d2 = dot3(d, d);
    if (!(d2 > 0.0f))
        return;
    float len = sqrtf(d2);
    float w21[3] = {d[0] / len, d[1] / len, d[2] / len}, w12[3] = {-w21[0], -w21[1], -w21[2]};
    /* x1's side: what trace_eye's scattering would accept. */
    float f1[3];
    if (!eval_f(m1, ns1, wi1, w12, f1) || (dot3(ng1, w12) >= 0.0f) != (dot3(ng1, wi1) >= 0.0f))
        return;
    /* x2's side: what next_event at x2 would accept, seen from x1. */
    float n2[3];
    scatter_normal(&h, w21, n2);
    float s2 = dot3(n2, w21) >= 0.0f ? 1.0f : -1.0f;
    float ns2[3] = {s2 * n2[0], s2 * n2[1], s2 * n2[2]};
    float wl[3], dist, e[3], f2[3];
    if (!frame_light_at(&c->fs->lights[l], x2, wl, &dist, e))
        return;
    float cosl = dot3(ns2, wl), gl = dot3(ng2, wl), gi = dot3(ng2, w21);
    if (!(cosl > 0.0f) || (gl >= 0.0f) != (gi >= 0.0f) || !eval_f(&m2, ns2, w21, wl, f2))
        return;
    float p_b = light_vertex_pdf(c, l, x2, ng2);
    float g2 = fabsf(gi) / d2;
    float p_a = pdf_mix(m1, ns1, wi1, w12) * g2;
    if (!(p_b > 0.0f))
        return;
    float e1 = dot3(ng1, wi1) >= 0.0f ? bsdf_offset_eps(x1) : -bsdf_offset_eps(x1);
    float e2 = gi >= 0.0f ? bsdf_offset_eps(x2) : -bsdf_offset_eps(x2);
    float from[3], to[3];
    for (int i = 0; i < 3; i++) {
        from[i] = x1[i] + e1 * ng1[i];
        to[i] = x2[i] + e2 * ng2[i];
    }
    if (rt_occluded(c->rt, from, to) || lamp_blocks(c->rt, from, to, -1))
        return;
    float k = dot3(ns1, w12) * g2 * cosl / (p_a + p_b);
    for (int i = 0; i < 3; i++)
        out[i] = f1[i] * f2[i] * e[i] * k;
}

/* ---------------------------------------------------------------- eye paths */

/* Camera ray through (px, py) in pixels from the top-left corner: the inverse of the engine's
 * view-projection (GL: NDC y up, so image row 0 is NDC y = +1), from the near to the far
 * plane, so it sees what the rasteriser sees. */
static void camera_ray(const frame_ctx *c, double px, double py, float org[3], float dir[3], float *tnear,
                       float *tfar)
{
    frame_camera_ray(c->inv_view_proj, c->fs->camera.eye, c->width, c->height, px, py, org, dir, tnear, tfar);
}

/* alphaMode BLEND (pass_translucent.c): the primary ray meets the translucent
 * surfaces between tnear and tend (the opaque hit) front to back; at each, the path stops on it
 * with probability alpha (base colour factor × texture alpha) and continues straight through
 * with probability 1 − alpha, so a surface covers alpha of what lies behind it, as the
 * engine's back-to-front "over" compositing does. A single-sided surface seen from behind is
 * culled, as the rasteriser culls it. Returns 1 with *h, *m the surface stopped on. */
#define REF_BLEND_DIM0 0x30000000u
#define REF_BLEND_LAYERS 16
static int blend_layer(const frame_ctx *c, uint64_t key, const float org[3], const float dir[3], float tnear,
                       float tend, rt_hit *h, scn_material *m)
{
    rt_hit b;
    for (uint32_t k = 0; k < REF_BLEND_LAYERS && rt_intersect_blend(c->rt, org, dir, tnear, tend, &b); k++) {
        scn_material mb = eng_material_at(c->fs->scene, &b);
        tnear = b.t + bsdf_offset_eps(b.position);
        if (!mb.double_sided && dot3(b.normal, dir) >= 0.0f)
            continue;
        if (rnd(key, REF_BLEND_DIM0 + k) < clamp01(mb.base_color[3])) {
            *h = b;
            *m = mb;
            return 1;
        }
    }
    return 0;
}

/* One sample of pixel (x, y): adds the direct and indirect radiance it estimates. */
static void trace_eye(const frame_ctx *c, int x, int y, uint32_t sample, double *direct, double *indirect)
{
    uint64_t key = path_key(STREAM_EYE, (uint32_t)y * (uint32_t)c->width + (uint32_t)x, sample, c->frame, c->seed);
    float org[3], dir[3], tnear, tfar;
    if (c->pixel_center)
        camera_ray(c, x + 0.5, y + 0.5, org, dir, &tnear, &tfar);
    else
        camera_ray(c, x + (double)rnd(key, 0), y + (double)rnd(key, 1), org, dir, &tnear, &tfar);
    const float tnear0 = tnear; /* the near plane: translucent surfaces in front of a culled back face count */
    float thr[3] = {1.0f, 1.0f, 1.0f}, eta = 1.0f;
    const scn_scene *scene = c->fs->scene;
    float prev[3] = {0.0f, 0.0f, 0.0f}, prev_pdf = 0.0f; /* the last D vertex, if the path left it by a D lobe */
    int prev_ok = 0;
    int seen = 1; /* every vertex so far scattered by a delta lobe: emission reaches the eye */
    int translucent = 0; /* the primary vertex is on an alphaMode BLEND surface */
    for (int depth = 0; depth < c->max_depth; depth++) {
        rt_hit h;
        scn_material m;
        if (depth == 0) {
            /* The rasteriser culls single-sided surfaces seen from behind (glTF); so does this. */
            int hit = 0;
            for (int skip = 0; skip < REF_PRIMARY_SKIPS; skip++) {
                if (!rt_intersect(c->rt, org, dir, tnear, tfar, &h))
                    break;
                m = eng_material_at(scene, &h);
                if (m.double_sided || dot3(h.normal, dir) < 0.0f) {
                    hit = 1;
                    break;
                }
                tnear = h.t + bsdf_offset_eps(h.position);
            }
            translucent = blend_layer(c, key, org, dir, tnear0, hit ? h.t : tfar, &h, &m);
            hit = hit || translucent;
            /* A lamp in front: the camera sees its emission (path L E, direct light). */
            float tl;
            int lamp = hit ? -1 : rt_lamp_hit(c->rt, org, dir, tnear, tfar, -1, &tl);
            if (lamp >= 0) {
                float le[3];
                lamp_radiance(&c->fs->lights[lamp], dir, le);
                for (int i = 0; i < 3; i++)
                    direct[i] += (double)le[i];
                return;
            }
            if (!hit)
                return;
        } else {
            /* Later vertices: a lamp ends the path (rt_intersect; next-event estimation
             * counted its light). */
            if (!rt_intersect(c->rt, org, dir, 0.0f, INFINITY, &h))
                return;
            m = eng_material_at(scene, &h);
        }
        const float wi[3] = {-dir[0], -dir[1], -dir[2]};
        if (seen)
            for (int i = 0; i < 3; i++)
                (depth == 0 ? direct : indirect)[i] += (double)(thr[i] * m.emissive[i]);
        float n[3];
        scatter_normal(&h, wi, n);
        uint32_t dim = EYE_DIM0 + EYE_DIMS_PER_VERTEX * (uint32_t)depth;
        int d_vertex = bsdf_stores_photons(&m), last = depth + 1 == c->max_depth;
        float s = dot3(n, wi) >= 0.0f ? 1.0f : -1.0f;
        float ns[3] = {s * n[0], s * n[1], s * n[2]};
        if (d_vertex) {
            float l[3];
            next_event(c, &m, h.position, h.geom_normal, ns, wi, prev_ok ? prev : NULL, prev_pdf, key, dim, l);
            double *dst = depth == 0 ? direct : indirect;
            for (int i = 0; i < 3; i++)
                dst[i] += (double)(thr[i] * l[i]);
            if (c->grid && !translucent) {
                gather(c, &m, h.position, ns, wi, l);
                for (int i = 0; i < 3; i++)
                    indirect[i] += (double)(thr[i] * l[i]);
            }
            /* Paths one surface longer than this vertex: only if 1a could make them too. */
            if (!last && !translucent) {
                light_vertex(c, key, dim + DIMS_PER_BOUNCE, &m, h.position, h.geom_normal, ns, wi, l);
                for (int i = 0; i < 3; i++)
                    indirect[i] += (double)(thr[i] * l[i]);
            }
        }
        if (last)
            return;
        float u[4], cosdir[4], wo[3], w[3], density;
        scatter_numbers(key, dim, u, cosdir);
        bsdf_sample rs = {u, cosdir};
        bsdf_lobe lobe = bsdf_scatter(&m, n, wi, &eta, &rs, wo, w, &density);
        if (lobe == BSDF_ABSORBED || (translucent && lobe != BSDF_MIRROR && lobe != BSDF_REFLECT && lobe != BSDF_REFRACT))
            return; /* a translucent surface's light: direct, mirror and refracted only */
        translucent = 0;
        prev_ok = d_vertex && (lobe == BSDF_DIFFUSE || lobe == BSDF_GLOSSY);
        seen = seen && (lobe == BSDF_MIRROR || lobe == BSDF_REFLECT || lobe == BSDF_REFRACT);
        if (prev_ok) {
            memcpy(prev, h.position, sizeof prev);
            prev_pdf = pdf_mix(&m, ns, wi, wo);
        }
        for (int i = 0; i < 3; i++)
            thr[i] *= w[i];
        if (!nonzero3(thr))
            return;
        float eps = bsdf_offset_eps(h.position);
        float side = dot3(h.geom_normal, wo) >= 0.0f ? eps : -eps;
        for (int i = 0; i < 3; i++) {
            org[i] = h.position[i] + side * h.geom_normal[i];
            dir[i] = wo[i];
        }
    }
}

/* Estimator 1b's light choice: probabilities ∝ the power each light sends over what is
 * sampled (4πI, the outer cone's solid angle × I, or E × the scene disk's area). */
static void light_plan(frame_ctx *c)
{
    int found;
    bounds_sphere(c->fs, 0, c->scene_centre, &c->scene_rad, &found);
    double power[8] = {0}, total = 0.0;
    for (uint32_t l = 0; l < c->fs->light_count && l < 8; l++) {
        const eng_light_pose *lp = &c->fs->lights[l];
        double mean = (lp->radiance_scale[0] + lp->radiance_scale[1] + lp->radiance_scale[2]) / 3.0;
        c->light_cos_max[l] = lp->type == SCN_LIGHT_SPOT ? cosf(lp->outer_cone) : -1.0f;
        if (lp->type == SCN_LIGHT_SPOT && !(c->light_cos_max[l] < 1.0f))
            c->light_cos_max[l] = 1.0f - 1e-6f;
        double extent = lp->type == SCN_LIGHT_DIRECTIONAL ? ENG_PI * (double)c->scene_rad * c->scene_rad
                                                          : 2.0 * ENG_PI * (1.0 - (double)c->light_cos_max[l]);
        power[l] = mean > 0.0 ? mean * extent : 0.0;
        total += power[l];
    }
    for (uint32_t l = 0; l < c->fs->light_count && l < 8; l++)
        c->light_q[l] = total > 0.0 ? (float)(power[l] / total) : 0.0f;
}

/* ---------------------------------------------------------------- public API */

eng_result ref_create(const ref_desc *desc, ref_renderer **out, eng_error *err)
{
    *out = NULL;
    if (!desc || !desc->engine || !desc->sequence)
        return eng_fail(err, ENG_ERR_INVALID, "reference: ref_create needs the engine and its sequence");
    const char *file = desc->sequence->path;
    ref_desc d = *desc;
    if (d.spp == 0)
        d.spp = 64;
    if (d.max_depth == 0)
        d.max_depth = 64;
    if (d.photons == 0)
        d.photons = 16384;
    if (d.alpha == 0.0f)
        d.alpha = 2.0f / 3.0f;
    if (d.threads == 0)
        d.threads = eng_settings_of(d.engine)->threads;
    if (d.threads < 1)
        d.threads = 1;
    if (d.spp < 1 || d.spp > (1 << 20))
        return eng_fail(err, ENG_ERR_INVALID, "%s: reference: spp %d outside 1..%d", file, d.spp, 1 << 20);
    if (d.max_depth < 1 || d.max_depth > 256)
        return eng_fail(err, ENG_ERR_INVALID, "%s: reference: max depth %d outside 1..256", file, d.max_depth);
    if (d.photons < 1 || d.photons > (1 << 24))
        return eng_fail(err, ENG_ERR_INVALID, "%s: reference: photons %d outside 1..%d", file, d.photons, 1 << 24);
    if (!(d.alpha > 0.0f && d.alpha < 1.0f))
        return eng_fail(err, ENG_ERR_INVALID, "%s: reference: alpha %g outside (0, 1)", file, (double)d.alpha);
    if (!(d.radius >= 0.0f) || !isfinite(d.radius))
        return eng_fail(err, ENG_ERR_INVALID, "%s: reference: radius %g is not a length", file, (double)d.radius);
    if (d.radius == 0.0f) {
        const eng_frame_scene *fs;
        const eng_rt *rt;
        eng_pose(d.engine, 0, &fs, &rt);
        float diag = 0.0f;
        for (int i = 0; i < 3; i++) {
            float e = fs->bounds_max[i] - fs->bounds_min[i];
            diag += e * e;
        }
        d.radius = sqrtf(diag) / 256.0f;
        if (!(d.radius > 0.0f))
            d.radius = 0.01f;
    }
    ref_renderer *r = eng_xcalloc(1, sizeof *r);
    r->d = d;
    eng_image_size(d.engine, &r->width, &r->height);
    *out = r;
    return ENG_OK;
}

void ref_destroy(ref_renderer *r)
{
    free(r);
}

eng_result ref_add_listener(ref_renderer *r, const eng_listener *l)
{
    if (r->listener_count >= REF_MAX_LISTENERS)
        return ENG_ERR_INVALID;
    r->listeners[r->listener_count++] = *l;
    return ENG_OK;
}

const ref_desc *ref_settings(const ref_renderer *r)
{
    return &r->d;
}

int ref_settings_json(const ref_renderer *r, char *out, size_t size)
{
    const ref_desc *d = &r->d;
    return snprintf(out, size,
                    "{\"spp\": %d, \"max_depth\": %d, \"photons_per_pass\": %d, \"radius\": %.9g, "
                    "\"alpha\": %.9g, \"seed\": %u, \"caustics\": %s, \"pixel\": \"%s\", \"estimators\": "
                    "\"path tracing with next-event estimation + light vertices, balance heuristic "
                    "(L D (D|S)* E); probabilistic progressive photon mapping of caustics (L S+ D (D|S)* E)\"}",
                    d->spp, d->max_depth, d->photons, (double)d->radius, (double)d->alpha, d->seed,
                    d->no_caustics ? "false" : "true", d->pixel_center ? "centre" : "box");
}

static const char *const CH_RGB[] = {"R", "G", "B"};

static eng_result announce(ref_renderer *r, int frame, const char *name, const float *data, eng_error *err)
{
    eng_buffer b = {name, r->width, r->height, 3, CH_RGB, data};
    for (int i = 0; i < r->listener_count; i++)
        if (r->listeners[i].buffer && r->listeners[i].buffer(r->listeners[i].user, frame, &b) != 0)
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: capture failed at %s", frame, name);
    return ENG_OK;
}

eng_result ref_render_frame(ref_renderer *r, int frame, eng_error *err)
{
    const ref_desc *d = &r->d;
    const seq_sequence *seq = d->sequence;
    if (frame < 0 || frame >= seq->frame_count)
        return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d outside 0..%d", seq->path, frame, seq->frame_count - 1);
    double t = seq_frame_time(seq, frame);
    for (int i = 0; i < r->listener_count; i++)
        if (r->listeners[i].frame_begin && r->listeners[i].frame_begin(r->listeners[i].user, frame, t) != 0)
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: a listener refused the frame", frame);

    double t_start = now_ms();
    frame_ctx c;
    memset(&c, 0, sizeof c);
    eng_pose(d->engine, frame, &c.fs, &c.rt);
    c.width = r->width;
    c.height = r->height;
    c.frame = (uint32_t)frame;
    c.seed = d->seed;
    c.pixel_center = d->pixel_center;
    c.max_depth = d->max_depth;
    {
        float vp_inv[16];
        if (!m4_invert(vp_inv, c.fs->camera.view_proj))
            return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d: the camera's view-projection is singular",
                            seq->path, frame);
        for (int i = 0; i < 16; i++)
            c.inv_view_proj[i] = vp_inv[i];
        float diag = 0.0f;
        for (int i = 0; i < 3; i++) {
            float e = c.fs->bounds_max[i] - c.fs->bounds_min[i];
            diag += e * e;
        }
        c.far_dist = 2.0f * sqrtf(diag) + 1.0f;
    }
    light_plan(&c);
    emit_plan plan;
    make_plan(c.fs, d->photons, &plan);
    c.plan = &plan;
    int caustics = !d->no_caustics && plan.any;

    size_t npix = (size_t)r->width * (size_t)r->height;
    double *sum_d = eng_xcalloc(npix * 3, sizeof *sum_d), *sum_i = eng_xcalloc(npix * 3, sizeof *sum_i);
    photon_grid grid;
    memset(&grid, 0, sizeof grid);
    double r2 = (double)d->radius * d->radius, photon_ms = 0.0, trace_ms = 0.0;
    uint64_t stored = 0;
    const int w = r->width, h = r->height, threads = d->threads;
    for (int s = 0; s < d->spp; s++) {
        double t0 = now_ms();
        if (caustics) {
            photon_pass(&c, (uint32_t)s, (float)sqrt(r2), threads, &grid, &stored);
            c.grid = &grid;
        }
        double t1 = now_ms();
        photon_ms += t1 - t0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                size_t i = 3 * ((size_t)y * (size_t)w + (size_t)x);
                trace_eye(&c, x, y, (uint32_t)s, sum_d + i, sum_i + i);
            }
        trace_ms += now_ms() - t1;
        /* Knaus & Zwicker 2011 Eq. 15: r_{i+1}² = r_i² (i + α)/(i + 1), pass i = s + 1. */
        r2 *= (s + 1.0 + d->alpha) / (s + 2.0);
        if (!d->quiet)
            fprintf(stderr, "\rreference: frame %d: %d/%d spp, %.1f s", frame, s + 1, d->spp,
                    (now_ms() - t_start) * 1e-3);
    }
    if (!d->quiet)
        fprintf(stderr, "\n");
    free(grid.start);
    free(grid.photons);

    float *img = eng_xcalloc(npix * 9, sizeof *img);
    float *fd = img, *fi = img + npix * 3, *ff = img + npix * 6;
    for (size_t i = 0; i < npix * 3; i++) {
        fd[i] = (float)(sum_d[i] / d->spp);
        fi[i] = (float)(sum_i[i] / d->spp);
        ff[i] = fd[i] + fi[i];
    }
    free(sum_d);
    free(sum_i);
    eng_result res = announce(r, frame, "reference.direct", fd, err);
    if (res == ENG_OK)
        res = announce(r, frame, "reference.indirect", fi, err);
    if (res == ENG_OK)
        res = announce(r, frame, "reference.full", ff, err);
    free(img);
    if (res != ENG_OK)
        return res;

    eng_frame_stats st;
    memset(&st, 0, sizeof st);
    st.frame = frame;
    st.time = t;
    st.pass_count = 2;
    snprintf(st.passes[0].name, sizeof st.passes[0].name, "photons");
    st.passes[0].ms = photon_ms;
    snprintf(st.passes[1].name, sizeof st.passes[1].name, "trace");
    st.passes[1].ms = trace_ms;
    st.photons_emitted = caustics ? (uint64_t)plan.total * (uint64_t)d->spp : 0u;
    st.photons_stored[2] = stored;
    memcpy(st.camera_view_proj, c.fs->camera.view_proj, sizeof st.camera_view_proj);
    memcpy(st.camera_eye, c.fs->camera.eye, sizeof st.camera_eye);
    for (int i = 0; i < r->listener_count; i++)
        if (r->listeners[i].frame_end && r->listeners[i].frame_end(r->listeners[i].user, &st) != 0)
            return eng_fail(err, ENG_ERR_ABORTED, "frame %d: a listener failed to finish the frame", frame);
    return ENG_OK;
}
