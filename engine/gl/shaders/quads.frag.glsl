#version 450 core
// Photon quads, fragment stage (001_… §3.3 Eq. (1), with 003_… §5 Eq. 1's BSDF and sums): at the
// eye G-buffer's surface point s of this pixel, ΔL_o = f(s, ω_i, ω_o) · Φ_i · κ, κ the quad
// kernel of quad_kernel.glsl, for photons arriving from the front (ω_i · n > 0). The BSDF,
// the front test and the missing extra cosine are splat.frag.glsl's, so on a plane the quads
// give what the photon volumes give. No depth test (ind_quads.c): the quad lies in the surface
// it lights, so a depth test against the G-buffer would fight it; the slab and disk tests on s
// reject every pixel whose visible surface is not near the quad. Additive blending sums ΔL in
// RGB and the number of photons whose kernel reached the pixel in A.
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
    vec3 albedo = texelFetch(u_albedo, px, 0).rgb;
    vec4 mat = texelFetch(u_material, px, 0);
    vec3 f = albedo * (1.0 - mat.y) * (1.0 - mat.z) / PI;
    if (mat.y > 0.0)
        f += photon_glossy(n, s.xyz, u_eye, v_direction, cos_i, albedo, mat);
    o_radiance = vec4(f * v_power * kappa, 1.0);
}
