#version 450 core
// Photon volumes for the reconstruction filters (DESIGN.md step 7): the same kernel and test
// as splat.frag.glsl (ISPM 003_… §5 Eq. 1), but the diffuse BSDF is left out so the filters
// work on irradiance, and applied after them (002_… §7.4 Eq. 7.9; 003 §5.2: "we do not perform
// shading and then interpolate pixel color"). Outputs, additively blended:
//   0  E = Σ Φ_i κ over photons arriving from the front (W/m²; no cosine, see splat.frag.glsl),
//      A = number of kernels covering the pixel
//   1  the glossy part Σ f_glossy Φ_i κ (radiance), which depends on ω_i and
//      so cannot be factored out of the sum; it is upsampled but not filtered.
// SPLAT_NO_METALLIC: the variant for scenes without metallic materials (splat.frag.glsl).
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

layout(location = 0) out vec4 o_irradiance;
layout(location = 1) out vec4 o_glossy;

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
    vec4 mat = texelFetch(u_material, px, 0);
    vec3 e = v_power * kappa;
    o_irradiance = vec4(e, 1.0);
    vec3 g = vec3(0.0);
#ifndef SPLAT_NO_METALLIC
    if (mat.y > 0.0)
        g = photon_glossy(n, s.xyz, u_eye, v_direction, cos_i, texelFetch(u_albedo, px, 0).rgb, mat) * e;
#endif
    o_glossy = vec4(g, 0.0);
}
