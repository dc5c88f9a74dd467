#version 450 core
// Photon volumes, fragment stage: ISPM 003_… §5 Eq. 1 at the G-buffer surface point s of this
// pixel, ΔL_o = f(s, ω_i, ω_o) · Φ_i · κ(x − s, n_p) with κ from Eq. 2–3 (photon_kernel.glsl),
// for photons arriving from the front (ω_i · n > 0). Eq. 1 as printed also multiplies by
// max(0, ω_i · n); that cosine is already in the photons' density on the surface (a photon's
// power is flux through the surface: Jensen's estimate L = Σ f ΔΦ / area has no cosine), and
// with it the indirect light of the Cornell box came out at 0.53× the reference renderer's
// (0.91× without it, the rest being kernel bias and the bounce limit; docs/filters.md). Each pixel is shaded once per photon: back faces only, depth test
// GEQUAL against the eye G-buffer's depth (the volume's far side lies behind the surface it
// contains). Additive blending accumulates ΔL in RGB and the number of photons whose kernel
// covers the pixel in A.
#define PI 3.14159265358979323846

flat in vec3 v_position;
flat in vec3 v_normal;
flat in vec3 v_power;
flat in vec3 v_direction;
flat in vec2 v_radius;

uniform sampler2D u_position;
uniform sampler2D u_normal;
uniform sampler2D u_albedo;
uniform sampler2D u_material;
uniform vec3 u_eye;

layout(location = 0) out vec4 o_radiance;

#pragma ispm_include "ggx.glsl"
#pragma ispm_include "photon_kernel.glsl"

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 s = texelFetch(u_position, px, 0);
    if (s.w == 0.0)
        discard;
    float kappa = photon_kappa(s.xyz, v_position, v_normal, v_radius);
    if (kappa < 0.0)
        discard;
    vec3 n = texelFetch(u_normal, px, 0).xyz;
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
