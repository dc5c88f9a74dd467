/* lineage_kernel.c — one photon's contribution to one eye pixel for tools that read runs
 * (ispm lineage, the viewer): the CPU indirect methods' kernel (gather_kernel.h: ISPM 003_…
 * §5 Eq. 1, κ of §5.1 Eq. 2–3, the same float operations as shaders/splat.frag.glsl) applied
 * to a photon as photons.map records it. Its own library (ispm_kernel): it includes the
 * engine's private header for gk_add, but links no GL. */
#include "gather_kernel.h"

int eng_photon_contribution(const float photon[14], float radius, float compression, const float s[3],
                            const float n[3], const float albedo[3], const float mat[4], const float eye[3],
                            int irradiance, float rgb[3], float glossy[3])
{
    eng_photon ph;
    for (int c = 0; c < 3; c++) {
        ph.position[c] = photon[c];
        ph.direction[c] = photon[3 + c];
        ph.power[c] = photon[6 + c];
        ph.normal[c] = photon[9 + c];
    }
    ph.path_density = photon[12];
    ph.bounce = (uint32_t)photon[13];
    ph.ray_length = 0.0f; /* read only by the kernel scalings, which radius already carries */
    gk_pixel px;
    gk_pixel_init(&px, s, n, albedo, mat, eye);
    float acc[4] = {0.0f, 0.0f, 0.0f, 0.0f}, g[3] = {0.0f, 0.0f, 0.0f};
    gk_add(&px, &ph, radius, compression, acc, irradiance ? g : NULL);
    for (int c = 0; c < 3; c++) {
        rgb[c] = acc[c];
        if (glossy)
            glossy[c] = g[c];
    }
    return acc[3] > 0.0f;
}
