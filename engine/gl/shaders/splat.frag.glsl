#version 450 core
// Photon volumes, fragment stage: ISPM 003_… §5 Eq. 1 at the G-buffer surface point s of this
// pixel, ΔL_o = f(s, ω_i, ω_o) · Φ_i · κ(x − s, n_p) with κ from Eq. 2–3 (photon_kernel.glsl),
// for photons arriving from the front (ω_i · n > 0). Eq. 1 as printed also multiplies by
// max(0, ω_i · n); that cosine is already in the photons' density on the surface (a photon's
// power is flux through the surface: Jensen's estimate L = Σ f ΔΦ / area has no cosine), and
// with it the indirect light of the Cornell box came out at 0.53× the reference renderer's
// (0.91× without it, the rest being kernel bias and the bounce limit; docs/filters.md). Each
// pixel is shaded once per photon: one screen rectangle per photon (splat.vert.glsl) at the
// depth of the volume's far side, depth test GEQUAL against the eye G-buffer's depth (the far
// side lies behind every surface point the volume contains). Additive blending accumulates ΔL in RGB and the number of photons whose kernel
// covers the pixel in A.
// ind_scatter_splat.c compiles variants for frames whose scene has no metallic material
// (SPLAT_NO_METALLIC: mat.y = 0 at every pixel; llvmpipe evaluates both sides of a branch
// that differs between pixels, so the glossy term would cost every pixel) and, besides, no
// transmissive one (SPLAT_NO_TRANSMISSION: no material fetch at all). They sum the same floats.
#define PI 3.14159265358979323846

flat in vec3 v_position;
flat in vec3 v_normal;
flat in vec3 v_power;
flat in vec3 v_direction;
flat in vec2 v_radius;
flat in float v_stretch;

uniform sampler2D u_position;
uniform sampler2D u_normal;
uniform sampler2D u_albedo;
uniform sampler2D u_material;
uniform vec3 u_eye;

layout(location = 0) out vec4 o_radiance;

#pragma ispm_include "ggx.glsl"
#pragma ispm_include "photon_kernel.glsl"
#pragma ispm_include "pixel_scale.glsl"

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 s = texelFetch(u_position, px, 0);
    if (s.w == 0.0)
        discard;
#ifdef PHOTON_ANISO
    float kappa = photon_kappa_aniso(s.xyz, v_position, v_normal, KERNEL_RADIUS, photon_aniso(v_direction, v_normal, v_stretch));
#else
    float kappa = photon_kappa(s.xyz, v_position, v_normal, KERNEL_RADIUS);
#endif
    if (kappa < 0.0)
        discard;
    vec3 n = texelFetch(u_normal, px, 0).xyz;
    float cos_i = dot(v_direction, n);
    if (cos_i <= 0.0)
        discard;
    vec3 albedo = texelFetch(u_albedo, px, 0).rgb;
#if defined(SPLAT_NO_METALLIC) && defined(SPLAT_NO_TRANSMISSION)
    vec3 f = albedo / PI; // (1 − metallic)(1 − transmission) = 1 exactly: the same value
#else
    vec4 mat = texelFetch(u_material, px, 0);
    vec3 f = albedo * (1.0 - mat.y) * (1.0 - mat.z) / PI;
#ifndef SPLAT_NO_METALLIC
    if (mat.y > 0.0)
        f += photon_glossy(n, s.xyz, u_eye, v_direction, cos_i, albedo, mat);
#endif
#endif
    o_radiance = vec4(f * v_power * kappa, 1.0);
}
