/* bsdf.h — the photon scattering model shared by the CPU photon tracer (photon_trace.c) and
 * mirrored by the GLSL bounce-map shader. Internal to the engine. Formulas and their paper
 * sections are in bsdf.c's opening paragraph. */
#ifndef ISPM_BSDF_H
#define ISPM_BSDF_H

#include "trace.h"
/* Constants, lobe ids and lobe order shared with the GLSL twin (valid C and GLSL). */
#include "shaders/bsdf_constants.glsl"

#include <math.h>

typedef enum bsdf_lobe {
    BSDF_ABSORBED = BSDF_LOBE_ABSORBED, /* Russian roulette ended the path (or the sample left below the surface) */
    BSDF_DIFFUSE = BSDF_LOBE_DIFFUSE,   /* Lambertian, cosine-sampled */
    BSDF_GLOSSY = BSDF_LOBE_GLOSSY,     /* GGX metal */
    BSDF_MIRROR = BSDF_LOBE_MIRROR,     /* smooth metal (roughness < BSDF_MIRROR_ROUGHNESS): delta reflection */
    BSDF_REFLECT = BSDF_LOBE_REFLECT,   /* glass: Fresnel or total internal reflection (delta) */
    BSDF_REFRACT = BSDF_LOBE_REFRACT    /* glass: refraction (delta) */
} bsdf_lobe;

/* Random numbers one scattering event consumes: u = 4 uniforms in [0,1) (u[BSDF_U_LOBE] lobe
 * choice, u[BSDF_U_ROULETTE] Russian roulette, u[BSDF_U_DIR0..1] GGX half-vector or the
 * Fresnel choice in u[BSDF_U_DIR0]) and cosdir = a cosine-weighted direction about +Z with its
 * pdf (an eng_random_maps cosine entry, or bsdf_stratify's). */
typedef struct bsdf_sample {
    const float *u;      /* 4 floats */
    const float *cosdir; /* 4 floats */
} bsdf_sample;

/* What scattering reads of a resolved material (eng_material_at): the photon tracer fills
 * it per hit from the draw's material and the hit's texture factors (bsdf_params_at), which
 * costs a few floats instead of a copy of the whole scn_material. */
typedef struct bsdf_params {
    float base_color[3];
    float metallic, roughness, transmission, ior;
} bsdf_params;

static inline void bsdf_params_of(const scn_material *m, bsdf_params *p)
{
    for (int c = 0; c < 3; c++)
        p->base_color[c] = m->base_color[c];
    p->metallic = m->metallic;
    p->roughness = m->roughness;
    p->transmission = m->transmission;
    p->ior = m->ior;
}

/* bsdf_params_of(eng_material_at(scene, h)) with m = eng_material_of(scene, h->material):
 * the same products eng_material_at forms, so the result is bit-identical. */
static inline void bsdf_params_at(const scn_material *m, const rt_hit *h, bsdf_params *p)
{
    for (int c = 0; c < 3; c++)
        p->base_color[c] = m->base_color[c] * h->base_tex[c];
    p->metallic = m->metallic * h->metallic_tex;
    p->roughness = m->roughness * h->roughness_tex;
    p->transmission = m->transmission;
    p->ior = m->ior;
}

/* Scatters a photon at a surface point (bsdf_scatter_params on bsdf_params_of(m)).
 *   m       resolved material (eng_material_of)
 *   n       unit shading normal of the surface as authored (outward), NOT oriented to wi:
 *           glass uses its side to tell entering from leaving; opaque lobes use the side wi
 *           lies on (surfaces are two-sided for photons).
 *   wi      unit, from the surface toward where the photon came from (−ray direction)
 *   eta     in: index of refraction of the medium the photon travels in; out: the medium of
 *           the scattered photon (changes on refraction only)
 * On return wo is the unit outgoing direction, weight the per-channel factor by which the
 * photon's power is multiplied (f·cos/pdf divided by the Russian-roulette survival
 * probability, so that E[weight] = f·cos/pdf per channel), density_factor the factor by which
 * the path density ρp is multiplied (003_… §4.3). BSDF_ABSORBED: wo, weight are zero and the
 * path ends. */
bsdf_lobe bsdf_scatter(const scn_material *m, const float n[3], const float wi[3], float *eta,
                       const bsdf_sample *rnd, float wo[3], float weight[3], float *density_factor);
bsdf_lobe bsdf_scatter_params(const bsdf_params *m, const float n[3], const float wi[3], float *eta,
                              const bsdf_sample *rnd, float wo[3], float weight[3], float *density_factor);

static inline float bsdf_clamp01(float x)
{
    return x < 0.0f ? 0.0f : (x > 1.0f ? 1.0f : x);
}

/* The lobe bsdf_scatter_params samples for cos_n = wi·n and the random numbers u:
 * BSDF_ABSORBED when wi lies in the surface, else BSDF_GLOSSY for the metal lobe (mirror or
 * GGX), BSDF_REFRACT for the glass lobe (reflection or refraction) or BSDF_DIFFUSE. */
static inline bsdf_lobe bsdf_lobe_of(const bsdf_params *m, float cos_n, const float u[4])
{
    float metallic = bsdf_clamp01(m->metallic), transmission = bsdf_clamp01(m->transmission);
    if (!(fabsf(cos_n) > 0.0f))
        return BSDF_ABSORBED;
    float pick = u[BSDF_U_LOBE];
    if (pick < metallic)
        return BSDF_GLOSSY;
    /* (pick − 0)/(1 − 0) compares as pick does: no division for a non-metal */
    float rest = metallic == 0.0f ? pick : metallic < 1.0f ? (pick - metallic) / (1.0f - metallic) : 1.0f;
    return rest < transmission ? BSDF_REFRACT : BSDF_DIFFUSE;
}

/* Whether bsdf_scatter_params would take the diffuse lobe for (m, n, wi) with the random
 * numbers u (not absorbed for wi in the surface, neither metal nor glass picked). */
static inline int bsdf_takes_diffuse(const bsdf_params *m, const float n[3], const float wi[3], const float u[4])
{
    return bsdf_lobe_of(m, wi[0] * n[0] + wi[1] * n[1] + wi[2] * n[2], u) == BSDF_DIFFUSE;
}
#if defined(__SSE2__)
/* bsdf_scatter_params on four rays at once, each known to take the diffuse lobe
 * (bsdf_takes_diffuse) with albedo k = the base colour and cosine direction cosdir[k]: wo,
 * weight and density factor of lane k are the scalar function's bit for bit, alive[k] = 0 where
 * it returns BSDF_ABSORBED (Russian roulette; wo, weight and density then 0), else 1 for
 * BSDF_DIFFUSE; each lane's outputs go where its own pointers say. A lane may repeat another's
 * pointers when fewer than four rays are at hand (it then writes the same values there). */
void bsdf_diffuse4(const float *const n[4], const float *const wi[4], const float *const cosdir[4],
                   const float *const albedo[4], const float u_roulette[4], float *const wo[4],
                   float *const weight[4], float *const density_factor[4], int alive[4]);
#endif

/* Stratified sampling across frames (002_558366c451cd32fd.txt §4.2): a Cranley–Patterson
 * rotation of one event's random numbers, out_u[d] = frac(u[d] + offset[d]), and the
 * cosine-weighted direction made from the rotated out_u[BSDF_U_DIR0..1] by the concentric
 * map (Shirley–Chiu, lifted to the hemisphere; pdf cosθ/π), both in float so that the
 * bounce-map shader (bsdf_sample.glsl, bsdf_stratify) computes the same. The frame's offsets
 * come from rmap_stratum. */
void bsdf_stratify(const float u[4], const float offset[4], float out_u[4], float out_cosdir[4]);

/* Stratified first bounces within one frame (`"bounce_strata"`; 002_558366c451cd32fd.txt §4.2
 * stratifies across frames, this within one): the N² = 4^log2n bounce-map texels of an N×N
 * block share one pattern (a hash of the block) and each takes sample `index` (its place in the
 * block, 0..N²−1) of a correlated multi-jittered set (Kensler, "Correlated Multi-Jittered
 * Sampling", Pixar Technical Memo 13-01, 2013, §5–6: the pattern's own permutations, the
 * sample order permuted too): out_u[BSDF_U_DIR0..1] lie one in each cell of the N×N grid and
 * one in each of the N² columns and rows; out_u[BSDF_U_LOBE] and out_u[BSDF_U_ROULETTE] one in
 * each of N² intervals (permuted independently). The event's own numbers u are the jitter
 * within the stratum: out_u = (stratum + u)·N⁻², the sum rounded to float (u keeps 24 − 2·log2n
 * bits at worst), the scaling exact (N² is a power of two), at most 1 − 2⁻²⁴.
 * The cosine-weighted direction then comes from out_u by bsdf_stratify's concentric map, after
 * the frame's Cranley–Patterson rotation (zero offsets without "random": "stratified"). Both
 * are defined once, in shaders/bsdf_strata.glsl (valid C and GLSL), for bsdf.c and the
 * bounce-map shader. */
void bsdf_strata(const float u[4], uint32_t index, uint32_t log2n, uint32_t pattern, float out_u[4]);
/* Kensler 2013 §3's hashed permutation of [0, l): element i of permutation p. */
uint32_t bsdf_permute(uint32_t i, uint32_t l, uint32_t p);

/* Does the material have a diffuse or glossy lobe with non-zero probability? The photon map
 * keeps photons only on such surfaces: the final gather estimates radiance from photons with
 * a smooth BRDF, and a photon on a purely specular surface (mirror, glass) would only be
 * splatted onto that surface's own pixels, where the delta BSDF cannot reflect it toward the
 * eye from any other direction. */
int bsdf_stores_photons(const scn_material *m);
static inline int bsdf_stores_photons_params(const bsdf_params *m)
{
    float metallic = bsdf_clamp01(m->metallic), transmission = bsdf_clamp01(m->transmission);
    float diffuse = (1.0f - metallic) * (1.0f - transmission);
    float glossy = m->roughness >= BSDF_MIRROR_ROUGHNESS ? metallic : 0.0f;
    return diffuse > 0.0f || glossy > 0.0f;
}

/* Exact unpolarised Fresnel reflectance of a smooth dielectric interface, light arriving in
 * the medium of index n1 at cosine cos_i (>= 0) onto a medium n2; 1 under total internal
 * reflection. */
float bsdf_fresnel_dielectric(float cos_i, float n1, float n2);

/* Orthonormal basis about unit n (Duff et al., "Building an Orthonormal Basis, Revisited",
 * JCGT 2017): branch on the sign only, so it is the same on every machine. */
static inline void bsdf_basis(const float n[3], float t[3], float b[3])
{
    float sign = n[2] >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n[2]);
    float c = n[0] * n[1] * a;
    t[0] = 1.0f + sign * n[0] * n[0] * a;
    t[1] = sign * c;
    t[2] = -sign * n[0];
    b[0] = c;
    b[1] = sign + n[1] * n[1] * a;
    b[2] = -n[1];
}

/* Distance by which a ray leaves the surface it starts on: relative to the magnitude of the
 * coordinates so that float rounding of the hit point cannot put the origin behind it
 * (photon_trace.c, reference.c). */
static inline float bsdf_offset_eps(const float p[3])
{
    float m = fabsf(p[0]);
    if (fabsf(p[1]) > m)
        m = fabsf(p[1]);
    if (fabsf(p[2]) > m)
        m = fabsf(p[2]);
    return 1e-4f * (1.0f + m);
}

#endif
