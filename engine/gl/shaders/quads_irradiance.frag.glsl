#version 450 core
// Photon quads for the reconstruction filters: quads.frag.glsl's kernel and tests (001_… §3.3),
// with splat_irradiance.frag.glsl's outputs (the diffuse BSDF left out so the filters work on
// irradiance, 002_… §7.4, 003_… §5.2). Outputs, additively blended:
//   0  E = Σ Φ_i κ over photons arriving from the front (W/m²), A = number of kernels reaching
//      the pixel
//   1  the glossy part Σ f_glossy Φ_i κ (radiance), upsampled but not filtered.
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
#pragma ispm_include "quad_kernel.glsl"
#pragma ispm_include "pixel_scale.glsl"

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 s = texelFetch(u_position, px, 0);
    if (s.w == 0.0)
        discard;
    vec3 n = texelFetch(u_normal, px, 0).xyz;
#ifdef PHOTON_ANISO
    float kappa = quad_kappa_aniso(s.xyz, n, v_position, v_normal, KERNEL_RADIUS, photon_aniso(v_direction, v_normal, v_stretch));
#else
    float kappa = quad_kappa(s.xyz, n, v_position, v_normal, KERNEL_RADIUS);
#endif
    if (kappa < 0.0)
        discard;
    float cos_i = dot(v_direction, n);
    if (cos_i <= 0.0)
        discard;
    vec4 mat = texelFetch(u_material, px, 0);
    vec3 e = v_power * kappa;
    o_irradiance = vec4(e, 1.0);
    vec3 g = vec3(0.0);
    if (mat.y > 0.0)
        g = photon_glossy(n, s.xyz, u_eye, v_direction, cos_i, texelFetch(u_albedo, px, 0).rgb, mat) * e;
    o_glossy = vec4(g, 0.0);
}
