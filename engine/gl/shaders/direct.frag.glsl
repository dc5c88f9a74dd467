#version 450 core
// Direct light by deferred shading of the eye G-buffer (ISPM §3: direct illumination is
// computed by ordinary deferred shading with shadow maps; the photon passes add only the
// indirect part).
//
// BSDF: opaque dielectrics are Lambertian, f = albedo/π, with no specular coat: the
// canonical scenes specify Lambertian surfaces, and glTF's metallic-roughness default
// (metallic 1 → we read metallicFactor as given) would otherwise add a 4% GGX coat that the
// reference renderers do not have. Metals (metallic > 0) add a GGX lobe (Walter et al.
// 2007; 002_… §4.1) with F0 = base colour and α = roughness². Transmission removes the
// diffuse part (glass gets its light from photons, not from a point light's delta).
//
// Lights: point and spot are radiant intensity I (W/sr): E = I·cosθ/d²; spot cones use the
// KHR_lights_punctual smooth falloff; directional lights are irradiance E (W/m²).
// Visibility: lights without a size, percentage-closer filtering (shadow_pcf.glsl); lights
// with a size, percentage-closer soft shadows or rays through the shadow map
// (shadow_pcss.glsl, 001 §3.4; setting pcss_blocker). The shadow
// methods are listed in engine/shadow.h.
#define MAX_LIGHTS 8
#define PI 3.14159265358979323846

uniform sampler2D u_position;
uniform sampler2D u_normal;
uniform sampler2D u_albedo;
uniform sampler2D u_material;

uniform int u_light_count;
uniform int u_light_type[MAX_LIGHTS];        // 0 point, 1 spot, 2 directional
uniform vec3 u_light_position[MAX_LIGHTS];
uniform vec3 u_light_direction[MAX_LIGHTS];  // where the light points
uniform vec3 u_light_scale[MAX_LIGHTS];      // colour × intensity
uniform vec3 u_light_params[MAX_LIGHTS];     // range, cos(inner), cos(outer)
uniform sampler2DArray u_shadow[MAX_LIGHTS];
uniform mat4 u_shadow_view_proj[MAX_LIGHTS * 6];
uniform int u_shadow_size;
uniform float u_shadow_texel[MAX_LIGHTS];    // world size of a texel at unit distance (or absolute, directional)
uniform int u_pcf_radius;
uniform float u_shadow_bias;
uniform vec3 u_eye;
uniform float u_light_radius[MAX_LIGHTS];    // light size (shadow_pcss.glsl); 0: hard shadows
uniform sampler2DArray u_blocker[MAX_LIGHTS]; // blocker maps of the lights with a size
uniform mat4 u_inv_view_proj;                // the camera's, for the rays of background pixels
uniform vec2 u_viewport;

layout(location = 0) out vec4 o_radiance;
layout(location = 1) out vec4 o_penumbra;    // x: widest penumbra at the pixel (texels), y: its blocker

#pragma ispm_include "shadow_pcf.glsl"
#pragma ispm_include "shadow_pcss.glsl"

#pragma ispm_include "ggx.glsl"

// Lamps (issue 15): a point or spot light with a size is an opaque sphere of uniform radiance
// I/(πR²) (times the spot falloff toward the eye). True when one is nearer along the pixel's
// eye ray than the G-buffer's surface (or the pixel is background); its radiance in le.
bool lamp_in_front(vec4 pos, out vec3 le)
{
    vec3 d;
    float t_surface;
    if (pos.w != 0.0) {
        d = pos.xyz - u_eye;
        t_surface = length(d);
        d /= t_surface;
    } else {
        vec4 f = u_inv_view_proj * vec4(gl_FragCoord.xy / u_viewport * 2.0 - 1.0, 1.0, 1.0);
        d = normalize(f.xyz / f.w - u_eye);
        t_surface = 1e30;
    }
    int lamp = -1;
    for (int i = 0; i < u_light_count; i++) {
        float r = u_light_radius[i];
        if (!(r > 0.0) || u_light_type[i] == 2)
            continue;
        vec3 oc = u_eye - u_light_position[i];
        float b = dot(oc, d), c = dot(oc, oc) - r * r;
        float disc = b * b - c;
        if (c < 0.0 || disc <= 0.0)
            continue;
        float t = -b - sqrt(disc);
        if (t > 0.0 && t < t_surface) {
            t_surface = t;
            lamp = i;
        }
    }
    if (lamp < 0)
        return false;
    float r = u_light_radius[lamp];
    le = u_light_scale[lamp] / (PI * r * r);
    if (u_light_type[lamp] == 1) {
        float cd = dot(u_light_direction[lamp], -d);
        float cos_inner = u_light_params[lamp].y, cos_outer = u_light_params[lamp].z;
        float t = clamp((cd - cos_outer) / max(cos_inner - cos_outer, 1e-4), 0.0, 1.0);
        le *= t * t;
    }
    return true;
}

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 pos = texelFetch(u_position, px, 0);
    vec3 le;
    if (lamp_in_front(pos, le)) {
        o_radiance = vec4(le, 1.0);
        o_penumbra = vec4(0.0);
        return;
    }
    if (pos.w == 0.0) {
        o_radiance = vec4(0.0);
        o_penumbra = vec4(0.0);
        return;
    }
    vec3 p = pos.xyz;
    vec3 n = normalize(texelFetch(u_normal, px, 0).xyz);
    vec3 albedo = texelFetch(u_albedo, px, 0).rgb;
    vec4 mat = texelFetch(u_material, px, 0); // roughness, metallic, transmission, ior
    vec3 v = normalize(u_eye - p);
    float nov = max(dot(n, v), 1e-4);
    vec3 kd = albedo * (1.0 - mat.y) * (1.0 - mat.z) / PI;
    float alpha = max(mat.x * mat.x, 1e-2);
    float a2 = alpha * alpha;

    vec3 sum = vec3(0.0);
    vec2 widest = vec2(0.0);
    for (int i = 0; i < u_light_count; i++) {
        vec3 l;
        vec3 e;
        if (u_light_type[i] == 2) {
            l = -u_light_direction[i];
            e = u_light_scale[i];
        } else {
            vec3 to_light = u_light_position[i] - p;
            float d2 = dot(to_light, to_light);
            l = to_light * inversesqrt(d2);
            e = u_light_scale[i] / d2;
            float range = u_light_params[i].x;
            if (range > 0.0) {
                float r = sqrt(d2) / range;
                float w = clamp(1.0 - r * r * r * r, 0.0, 1.0);
                e *= w * w;
            }
            if (u_light_type[i] == 1) {
                float cd = dot(u_light_direction[i], -l);
                float cos_inner = u_light_params[i].y, cos_outer = u_light_params[i].z;
                float t = clamp((cd - cos_outer) / max(cos_inner - cos_outer, 1e-4), 0.0, 1.0);
                e *= t * t;
            }
        }
        float nol = dot(n, l);
        if (nol <= 0.0)
            continue;
        float vis;
        if (u_light_radius[i] > 0.0) {
            vec2 pen;
#ifdef PCSS_RAYS
            vis = pcss_rays_visibility(i, p, n, pen); // pcss_blocker "rays": no blocker maps
#else
            vis = pcss_visibility(i, p, n, pen);
#endif
            if (pen.x > widest.x)
                widest = pen;
        } else {
            vis = visibility(i, p, n);
        }
        if (vis == 0.0)
            continue;
        vec3 f = kd;
        if (mat.y > 0.0) {
            vec3 h = normalize(l + v);
            float noh = max(dot(n, h), 0.0);
            float voh = max(dot(v, h), 0.0);
            vec3 f0 = albedo;
            vec3 fresnel = f0 + (1.0 - f0) * pow(1.0 - voh, 5.0);
            float g = smith_g1(nol, a2) * smith_g1(nov, a2);
            f += mat.y * fresnel * ggx_d(noh, a2) * g / (4.0 * nol * nov);
        }
        sum += f * e * nol * vis;
    }
    o_radiance = vec4(sum, 1.0);
    o_penumbra = vec4(widest, 0.0, 1.0);
}
