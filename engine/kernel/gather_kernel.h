/* gather_kernel.h — one photon's contribution to one pixel on the CPU: shaders/splat.frag.glsl
 * (radiance) and splat_irradiance.frag.glsl (irradiance + glossy) in the same float
 * operations, shared by the CPU methods (ind_kdgather.c, ind_tilegather.c) so that they sum the
 * same numbers in the same order and agree bit for bit. Engine-private.
 *
 * ISPM 003_… §5 Eq. 1 without the extra cosine (see splat.frag.glsl), κ of §5.1 Eq. 2–3 in
 * the form that maps the ellipsoid's surface to t = 1 (photon_kernel.glsl), Lambert for the
 * non-metallic, non-transmissive part and GGX for metals (ggx.glsl). */
#ifndef ISPM_GATHER_KERNEL_H
#define ISPM_GATHER_KERNEL_H

#include <math.h>

#include "kernel.h"

/* The per-photon adds are inlined into the gathers' loops whatever the compiler's size
 * heuristics (a call per photon costs the k-d gather, the speed baseline, ~5 %). */
#if defined(__GNUC__)
#define GK_INLINE inline __attribute__((always_inline))
#else
#define GK_INLINE inline
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

/* The anisotropic kernel of 002_… §6.1.2 ("Adjusting the kernel's shape", Eq. 6.3–6.5): the
 * ellipsoid keeps its short axis r_z along the photon's surface normal n_p and its axis r_xy
 * along t̂, and is stretched along û, ω_i projected onto the kernel plane, by
 * s_u = min(1 / (n_p·ω_i), s_max) (Eq. 6.3), the growth of a ray cone's footprint at grazing
 * incidence. Per photon four floats: the stretch vector a = √(1 − 1/s_u) û and s_u. The
 * kernel is the isotropic one (gk_kappa) at the point d' = d − (d·a) a, which divides d's û
 * component by s_u and leaves d·n_p alone (û ⟂ n_p): Eq. 6.5's tri-axial ellipsoid
 * (semi-axes s_u r_xy, r_xy, r_z) maps to the isotropic one, and κ is divided by s_u, the
 * Jacobian, so it still integrates to 1 over the photon's plane (Eq. 6.6's area A = π s_u r²).
 * At normal incidence s_u = 1 and it is gk_kappa exactly. The ellipsoid lies inside the
 * sphere of radius s_u r_xy: a method's culling uses that reach. */
#define GK_STRETCH_MAX 4.0f /* s_max of Eq. 6.3 (the thesis leaves it a constant) */

static inline void gk_aniso_of(const eng_photon *ph, float out[4])
{
    float c = gk_dot3(ph->direction, ph->normal);
    float su = c * GK_STRETCH_MAX > 1.0f ? 1.0f / c : GK_STRETCH_MAX;
    float u[3];
    for (int k = 0; k < 3; k++)
        u[k] = ph->direction[k] - c * ph->normal[k];
    float ul = sqrtf(gk_dot3(u, u));
    if (!(su > 1.0f) || !(ul > 0.0f)) {
        out[0] = out[1] = out[2] = 0.0f;
        out[3] = 1.0f;
        return;
    }
    float m = sqrtf(1.0f - 1.0f / su) / ul;
    for (int k = 0; k < 3; k++)
        out[k] = u[k] * m;
    out[3] = su;
}

/* κ of the anisotropic kernel (aniso: gk_aniso_of's four floats), negative outside it. */
static inline float gk_kappa_aniso(const eng_photon *ph, const float s[3], float rxy, const float aniso[4],
                                   float compression)
{
    const float su = aniso[3];
    if (su == 1.0f)
        return gk_kappa(ph, s, rxy, compression);
    const float PI_F = (float)ENG_PI;
    float rz = rxy * compression;
    float d[3] = {s[0] - ph->position[0], s[1] - ph->position[1], s[2] - ph->position[2]};
    float da = gk_dot3(d, aniso);
    float e[3] = {d[0] - da * aniso[0], d[1] - da * aniso[1], d[2] - da * aniso[2]};
    float len = sqrtf(gk_dot3(e, e));
    float t = len > 0.0f ? len / rxy * (1.0f + fabsf(gk_dot3(e, ph->normal)) / len * (rxy - rz) / rz) : 0.0f;
    if (t >= 1.0f)
        return -1.0f;
    return 2.0f / (PI_F * rxy * rxy * su) * (1.0f - t * t);
}

/* Adds photon ph with kernel value kappa (>= 0) to the pixel. Radiance mode (glossy ==
 * NULL): acc RGB += f Φ κ. Irradiance mode: acc RGB += Φ κ and glossy RGB += f_glossy Φ κ.
 * acc[3] counts the photons that passed every test. */
static GK_INLINE void gk_add_kappa(const gk_pixel *px, const eng_photon *ph, float kappa, float acc[4], float *glossy)
{
    const float PI_F = (float)ENG_PI;
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

/* Adds photon ph (kernel radius rxy) to the pixel: gk_add_kappa with the isotropic κ. */
static GK_INLINE void gk_add(const gk_pixel *px, const eng_photon *ph, float rxy, float compression, float acc[4],
                          float *glossy)
{
    float kappa = gk_kappa(ph, px->s, rxy, compression);
    if (kappa < 0.0f)
        return;
    gk_add_kappa(px, ph, kappa, acc, glossy);
}

/* The same with the anisotropic κ (gk_kappa_aniso). */
static GK_INLINE void gk_add_aniso(const gk_pixel *px, const eng_photon *ph, float rxy, const float aniso[4],
                                float compression, float acc[4], float *glossy)
{
    float kappa = gk_kappa_aniso(ph, px->s, rxy, aniso, compression);
    if (kappa < 0.0f)
        return;
    gk_add_kappa(px, ph, kappa, acc, glossy);
}

#endif
