/* gather_kernel.h — one photon's contribution to one pixel on the CPU: shaders/splat.frag.glsl
 * (radiance) and splat_irradiance.frag.glsl (irradiance + glossy) in the same float
 * operations, shared by the CPU methods (kdgather.c, ind_tilegather.c) so that they sum the
 * same numbers in the same order and agree bit for bit. Engine-private.
 *
 * ISPM 003_… §5 Eq. 1 without the extra cosine (see splat.frag.glsl), κ of §5.1 Eq. 2–3 in
 * the form that maps the ellipsoid's surface to t = 1 (photon_kernel.glsl), Lambert for the
 * non-metallic, non-transmissive part and GGX for metals (ggx.glsl). */
#ifndef ISPM_GATHER_KERNEL_H
#define ISPM_GATHER_KERNEL_H

#include <math.h>

#include "eng_internal.h"

/* gk_add is the inner loop of the k-d gather (the speed baseline) and of the tile gather.
 * Since kdgather.c has two callers of it (the gather and kd_gather_point), GCC stopped
 * inlining it there: a call per photon cost the gather +0.9 % instructions (callgrind) and
 * 1.5-4 % time against 9941c82. Forced inline restores the old code. */
#if defined(__GNUC__)
#define GK_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define GK_ALWAYS_INLINE inline
#endif

/* shaders/ggx.glsl, in the same float operations. */
static inline float gk_ggx_d(float noh, float a2)
{
    float d = noh * noh * (a2 - 1.0f) + 1.0f;
    return a2 / ((float)ENG_PI * d * d);
}

static inline float gk_smith_g1(float c, float a2)
{
    return 2.0f * c / (c + sqrtf(a2 + (1.0f - a2) * c * c));
}

static inline float gk_dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* What a pixel needs besides the photon: its surface point, normal, albedo, material and
 * the view direction terms. */
typedef struct gk_pixel {
    const float *s, *nrm, *albedo, *mat;
    float v[3], nov, a2;
} gk_pixel;

static inline void gk_pixel_init(gk_pixel *px, const float s[3], const float nrm[3], const float albedo[3],
                                 const float mat[4], const float eye[3])
{
    px->s = s;
    px->nrm = nrm;
    px->albedo = albedo;
    px->mat = mat;
    float v[3] = {eye[0] - s[0], eye[1] - s[1], eye[2] - s[2]};
    float vlen = sqrtf(gk_dot3(v, v));
    for (int c = 0; c < 3; c++)
        px->v[c] = v[c] / vlen;
    px->nov = fmaxf(gk_dot3(nrm, px->v), 1e-4f);
    float a = fmaxf(mat[0] * mat[0], 1e-2f);
    px->a2 = a * a;
}

/* κ of the photon at s (Eq. 2–3), or a negative value outside its ellipsoid. */
static inline float gk_kappa(const eng_photon *ph, const float s[3], float rxy, float compression)
{
    const float PI_F = (float)ENG_PI;
    float rz = rxy * compression;
    float d[3] = {s[0] - ph->position[0], s[1] - ph->position[1], s[2] - ph->position[2]};
    float len = sqrtf(gk_dot3(d, d));
    float t = len > 0.0f ? len / rxy * (1.0f + fabsf(gk_dot3(d, ph->normal)) / len * (rxy - rz) / rz) : 0.0f;
    if (t >= 1.0f)
        return -1.0f;
    return 2.0f / (PI_F * rxy * rxy) * (1.0f - t * t);
}

/* The GGX part f_glossy of the BSDF for light arriving along ω_i (cos_i = ω_i·n > 0). */
static inline void gk_glossy(const gk_pixel *px, const float w_i[3], float cos_i, float out[3])
{
    float h[3] = {w_i[0] + px->v[0], w_i[1] + px->v[1], w_i[2] + px->v[2]};
    float hl = sqrtf(gk_dot3(h, h));
    for (int c = 0; c < 3; c++)
        h[c] = h[c] / hl;
    float voh = fmaxf(gk_dot3(px->v, h), 0.0f);
    float spec = gk_ggx_d(fmaxf(gk_dot3(px->nrm, h), 0.0f), px->a2) * gk_smith_g1(cos_i, px->a2) *
                 gk_smith_g1(px->nov, px->a2) / (4.0f * cos_i * px->nov);
    for (int c = 0; c < 3; c++) {
        float fr = px->albedo[c] + (1.0f - px->albedo[c]) * powf(1.0f - voh, 5.0f);
        out[c] = px->mat[1] * fr * spec;
    }
}

/* Adds photon ph (kernel radius rxy) to the pixel. Radiance mode (glossy == NULL): acc RGB
 * += f Φ κ. Irradiance mode: acc RGB += Φ κ and glossy RGB += f_glossy Φ κ. acc[3] counts
 * the photons that passed every test. */
static GK_ALWAYS_INLINE void gk_add(const gk_pixel *px, const eng_photon *ph, float rxy, float compression, float acc[4],
                          float *glossy)
{
    const float PI_F = (float)ENG_PI;
    float kappa = gk_kappa(ph, px->s, rxy, compression);
    if (kappa < 0.0f)
        return;
    float cos_i = gk_dot3(ph->direction, px->nrm);
    if (cos_i <= 0.0f)
        return;
    if (glossy) {
        float e[3];
        for (int c = 0; c < 3; c++) {
            e[c] = ph->power[c] * kappa;
            acc[c] += e[c];
        }
        if (px->mat[1] > 0.0f) {
            float g[3];
            gk_glossy(px, ph->direction, cos_i, g);
            for (int c = 0; c < 3; c++)
                glossy[c] += g[c] * e[c];
        }
        acc[3] += 1.0f;
        return;
    }
    float f[3];
    for (int c = 0; c < 3; c++)
        f[c] = px->albedo[c] * (1.0f - px->mat[1]) * (1.0f - px->mat[2]) / PI_F;
    if (px->mat[1] > 0.0f) {
        float g[3];
        gk_glossy(px, ph->direction, cos_i, g);
        for (int c = 0; c < 3; c++)
            f[c] += g[c];
    }
    for (int c = 0; c < 3; c++)
        acc[c] += f[c] * ph->power[c] * kappa;
    acc[3] += 1.0f;
}

#endif
