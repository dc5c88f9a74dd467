/* kernel.h — the photon record and the density-estimation kernel every indirect method and
 * every tool that reads photons shares (ISPM 003 §5.1 Eq. 2-3). No GL: the tools that read
 * runs (ispm lineage, the viewer) link this room alone. */
#ifndef ISPM_KERNEL_H
#define ISPM_KERNEL_H

#include "eng_core.h"

typedef struct eng_photon {
    float position[3];
    float direction[3]; /* ω_i: unit, from the surface toward where the light came from */
    float power[3];     /* Φ_i, W per channel */
    float normal[3];    /* n_p: shading normal of the surface hit, facing the incoming photon */
    float path_density; /* ρp */
    uint16_t bounce;    /* 2 = second surface of the path (the first stored), 3, ... */
    uint16_t caustic;   /* 1: every scatter before this surface took a delta lobe (a path L S+ D:
                         * the caustic photons of Jensen 1996, which the final gather adds at its
                         * pixels, ind_finalgather.c) */
    float ray_length;   /* length of the ray segment that brought it here (m): 002 Eq. 6.1, 004 §6 */
} eng_photon;


/* ISPM §5.1 Eq. 2–3 on the CPU, the same kernel shaders/splat.frag.glsl evaluates: d = s − x
 * (surface point minus photon), n_p the photon's surface normal. Returns κ in 1/m²; 0 outside
 * the ellipsoid. Integrates to 1 over the photon's surface plane. */
float splat_kernel(const float d[3], const float n_p[3], float r_xy, float r_z);

/* The kernel radius r_xy of a photon of path density rho (ISPM §2.5/§4.3: large kernels for
 * improbable paths, small for caustics): kernel_radius · clamp((1000 ρ)^(−1/4), 1/4, 2). */
float splat_radius(float kernel_radius, float rho);

/* One photon's contribution to one eye pixel under the CPU kernel every indirect method
 * shares (gather_kernel.h, lineage_kernel.c in ispm_kernel): photon = photons.map's 14
 * channels (position, direction, power, normal, density, bounce), radius its kernel radius
 * r_xy (photons.origin), compression the normal_compression setting; the pixel's surface
 * point s, normal n, albedo, material (roughness, metallic, transmission, ior) and the eye.
 * Radiance mode (irradiance 0): rgb = f Φ κ. Irradiance mode: rgb = Φ κ and glossy =
 * f_glossy Φ κ (glossy may be NULL). Returns 1 when the photon passes every test (it then
 * counts in <prefix>.count), 0 with rgb = 0 otherwise. */
int eng_photon_contribution(const float photon[14], float radius, float compression, const float s[3],
                            const float n[3], const float albedo[3], const float mat[4], const float eye[3],
                            int irradiance, float rgb[3], float glossy[3]);

#endif
