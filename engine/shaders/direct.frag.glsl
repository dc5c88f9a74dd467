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
// Visibility: percentage-closer filtering over (2r+1)² texels of the light's shadow map,
// comparing metric distances (see shadow.frag.glsl), with a normal offset that grows with
// the shadow texel's world size.
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

layout(location = 0) out vec4 o_radiance;

int cube_face(vec3 d)
{
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z)
        return d.x > 0.0 ? 0 : 1;
    if (a.y >= a.z)
        return d.y > 0.0 ? 2 : 3;
    return d.z > 0.0 ? 4 : 5;
}

float visibility(int i, vec3 p, vec3 n)
{
    int type = u_light_type[i];
    float dist = distance(p, u_light_position[i]);
    // Normal offset: a few millimetres plus 1.5 texels of the map at this distance.
    float texel = type == 2 ? u_shadow_texel[i] : u_shadow_texel[i] * dist;
    vec3 q = p + n * (u_shadow_bias + 1.5 * texel);
    int face = 0;
    float value;
    if (type == 2) {
        value = dot(q - u_light_position[i], u_light_direction[i]);
    } else {
        value = distance(q, u_light_position[i]);
        if (type == 0)
            face = cube_face(q - u_light_position[i]);
    }
    vec4 c = u_shadow_view_proj[i * 6 + face] * vec4(q, 1.0);
    vec2 uv = c.xy / c.w * 0.5 + 0.5;
    if (type != 0 && (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0))
        return type == 2 ? 1.0 : 0.0; // outside a spot frustum: unlit; outside the ortho box: lit
    ivec2 base = ivec2(floor(uv * float(u_shadow_size)));
    float lit = 0.0;
    float taps = 0.0;
    for (int dy = -u_pcf_radius; dy <= u_pcf_radius; dy++)
        for (int dx = -u_pcf_radius; dx <= u_pcf_radius; dx++) {
            ivec2 t = clamp(base + ivec2(dx, dy), ivec2(0), ivec2(u_shadow_size - 1));
            float stored = texelFetch(u_shadow[i], ivec3(t, face), 0).r;
            lit += value <= stored + texel ? 1.0 : 0.0;
            taps += 1.0;
        }
    return lit / taps;
}

#pragma ispm_include "ggx.glsl"

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 pos = texelFetch(u_position, px, 0);
    if (pos.w == 0.0) {
        o_radiance = vec4(0.0);
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
        float vis = visibility(i, p, n);
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
}
