#version 450 core
// Photon volumes, fragment stage: ISPM 003_… §5 Eq. 1 at the G-buffer surface point s of this
// pixel:  ΔL_o = f(s, ω_i, ω_o) · max(0, ω_i · n) · Φ_i · κ(x − s, n_p),
// with κ from Eq. 2–3. Eq. 2 as printed, t = |d|/r_xy · (1 − |d̂·n_p| (r_xy − r_z)/r_z),
// goes negative along n_p once r_z < r_xy/2; we use the form that maps the ellipsoid's surface
// to t = 1, which is what the text describes: t = |d|/r_xy · (1 + |d̂·n_p| (r_xy − r_z)/r_z)
// (t = |d|/r_xy in the plane, |d|/r_z along the normal). kernel1D is the 2D Epanechnikov
// kernel normalised over the disk of radius r_xy: κ = 2/(π r_xy²) · (1 − t²), which
// integrates to 1 over the photon's surface plane. Each pixel is shaded once per photon:
// back faces only, depth test GEQUAL against the eye G-buffer's depth (the volume's far side
// lies behind the surface it contains). Additive blending accumulates ΔL in RGB and the
// number of photons whose kernel covers the pixel in A.
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

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 s = texelFetch(u_position, px, 0);
    if (s.w == 0.0)
        discard;
    vec3 d = s.xyz - v_position;
    float len = length(d);
    float r_xy = v_radius.x, r_z = v_radius.y;
    float t = len > 0.0 ? len / r_xy * (1.0 + abs(dot(d, v_normal)) / len * (r_xy - r_z) / r_z) : 0.0;
    if (t >= 1.0)
        discard;
    float kappa = 2.0 / (PI * r_xy * r_xy) * (1.0 - t * t);
    vec3 n = texelFetch(u_normal, px, 0).xyz;
    float cos_i = dot(v_direction, n);
    if (cos_i <= 0.0)
        discard;
    vec3 albedo = texelFetch(u_albedo, px, 0).rgb;
    vec4 mat = texelFetch(u_material, px, 0);
    vec3 f = albedo * (1.0 - mat.y) * (1.0 - mat.z) / PI;
    if (mat.y > 0.0) {
        vec3 v = normalize(u_eye - s.xyz);
        float nov = max(dot(n, v), 1e-4);
        vec3 h = normalize(v_direction + v);
        float a = max(mat.x * mat.x, 1e-2), a2 = a * a;
        vec3 fr = albedo + (1.0 - albedo) * pow(1.0 - max(dot(v, h), 0.0), 5.0);
        f += mat.y * fr * ggx_d(max(dot(n, h), 0.0), a2) * smith_g1(cos_i, a2) * smith_g1(nov, a2) / (4.0 * cos_i * nov);
    }
    o_radiance = vec4(f * cos_i * v_power * kappa, 1.0);
}
