#version 450 core
// Applies the surface BSDF to the reconstructed irradiance, 002_… §7.4 Eq. 7.9:
// L = E · f_BRDF, with the diffuse part of the BSDF the splat would have applied,
// albedo (1 − metallic)(1 − transmission)/π (splat.frag.glsl), at full resolution from the
// G-buffer (003 §5.2: the upsampled radiance is applied to the high-resolution BSDF
// parameters), plus the glossy part, which the splat summed per photon (it depends on ω_i).
#define PI 3.14159265358979323846
uniform sampler2D u_irradiance;
uniform sampler2D u_glossy;
uniform sampler2D u_albedo;
uniform sampler2D u_material;
uniform sampler2D u_normal;

layout(location = 0) out vec4 o_radiance;

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec3 n = texelFetch(u_normal, px, 0).xyz;
    if (dot(n, n) < 0.25) { /* background */
        o_radiance = vec4(0.0);
        return;
    }
    vec3 albedo = texelFetch(u_albedo, px, 0).rgb;
    vec4 mat = texelFetch(u_material, px, 0);
    vec3 f = albedo * (1.0 - mat.y) * (1.0 - mat.z) / PI;
    o_radiance = vec4(f * texelFetch(u_irradiance, px, 0).rgb + texelFetch(u_glossy, px, 0).rgb, 1.0);
}
