#version 450 core
// Bounce map (ISPM 003_… §4.2 "Initial Bounce"): one photon per light G-buffer texel, emitted
// through the texel centre, scattered once by importance sampling the surface BSDF with
// Russian roulette, stored as the OUTGOING photon (Table 1). Absorbed photons have power 0.
//
// Power (§4.2): the light's share of all photons is set on the CPU by the map size; within a
// map each texel carries the light's power through its own solid angle, so both of §4.2's
// corrections (size round-off and the inverse-cosine solid-angle factor) are exact here:
//   point, spot: Φ = I · dω,  dω = (2a/n)² / (1 + x² + y²)^{3/2}  (a = tan of the half-angle,
//                x, y the texel centre on the plane at unit distance; a = 1 for cube faces);
//                spot lights times the KHR_lights_punctual cone falloff;
//   directional: Φ = E · (2h/n)²  for an ortho box of half-width h.
// Random numbers come from the precomputed random maps (001_… §3.1), read from entry
// seed + k, with seed = hash(light position, texel, face) (003_… §4.1), so texels that see
// the same surface get the same photon every frame. The hash is XXH32 of the six 32-bit
// words (light x, y, z bits with −0 made +0; texel x, y; face) seeded with the salt, i.e.
// exactly rmap_hash_pixel in engine/random_maps.c, so the CPU can recompute any seed.
//
// BSDF sampling (kept in step with engine/bsdf.c): opaque dielectrics Lambertian (cosine
// sampling, weight = albedo, ρ factor ρL/1000 per §4.3); metals GGX (Walter et al. 2007,
// 002_… §4.1) or a perfect mirror below roughness 0.01 (weight F, ρ factor ρS/10 glossy, ρS
// mirror); glass a Fresnel Bernoulli choice between reflection and refraction (002_… §4.5),
// weight 1 or the tint, ρ factor 1. Russian roulette (002_… §4.4): survive with
// P = max channel of the weight, power /= P.
#define PI 3.14159265358979323846

uniform sampler2DArray u_lpos;
uniform sampler2DArray u_lnrm;
uniform sampler2DArray u_lalb;
uniform sampler2DArray u_lmat;
uniform sampler2DArray u_rmap;   // layers: 0 uniform, 1 cosine hemisphere, 2 sphere
uniform int u_rmap_size;
uniform int u_layer;
uniform int u_size;              // texels per side of this map
uniform int u_type;              // 0 point, 1 spot, 2 directional
uniform vec3 u_light_position;
uniform vec3 u_light_direction;
uniform vec3 u_light_scale;      // I (W/sr) or E (W/m²) per channel
uniform vec3 u_light_params;     // range, cos inner, cos outer
uniform float u_extent;          // tan(half-angle) (point: 1, spot) or half-width (directional)
uniform uint u_salt;

layout(location = 0) out vec4 o_power;     // Φ_o RGB, path density ρp
layout(location = 1) out vec4 o_direction; // ω_o, index of refraction of the medium after the bounce

// XXH32 (Yann Collet) of 6 little-endian 32-bit words: one 16-byte stripe, then 2 words.
const uint P1 = 2654435761u, P2 = 2246822519u, P3 = 3266489917u, P4 = 668265263u, P5 = 374761393u;

uint rotl(uint x, int r)
{
    return (x << r) | (x >> (32 - r));
}

uint xxh_round(uint acc, uint w)
{
    return rotl(acc + w * P2, 13) * P1;
}

uint xxh32_6(uint w0, uint w1, uint w2, uint w3, uint w4, uint w5, uint seed)
{
    uint v1 = xxh_round(seed + P1 + P2, w0);
    uint v2 = xxh_round(seed + P2, w1);
    uint v3 = xxh_round(seed, w2);
    uint v4 = xxh_round(seed - P1, w3);
    uint h = rotl(v1, 1) + rotl(v2, 7) + rotl(v3, 12) + rotl(v4, 18);
    h += 24u;
    h = rotl(h + w4 * P3, 17) * P4;
    h = rotl(h + w5 * P3, 17) * P4;
    h ^= h >> 15; h *= P2;
    h ^= h >> 13; h *= P3;
    h ^= h >> 16;
    return h;
}

vec4 rmap(int table, uint seed, uint k)
{
    uint i = (seed + k) & uint(u_rmap_size - 1);
    return texelFetch(u_rmap, ivec3(int(i & 255u), int(i >> 8), table), 0);
}

void frame_of(vec3 n, out vec3 t, out vec3 b)
{
    vec3 a = abs(n.x) > 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    t = normalize(cross(a, n));
    b = cross(n, t);
}

float fresnel_dielectric(float cos_i, float eta_i, float eta_t)
{
    float sin_t = eta_i / eta_t * sqrt(max(0.0, 1.0 - cos_i * cos_i));
    if (sin_t >= 1.0)
        return 1.0;
    float cos_t = sqrt(max(0.0, 1.0 - sin_t * sin_t));
    float rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    float rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

#pragma ispm_include "ggx.glsl"

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 pos = texelFetch(u_lpos, ivec3(px, u_layer), 0);
    o_power = vec4(0.0);
    o_direction = vec4(0.0, 0.0, 0.0, 1.0);
    if (pos.w == 0.0)
        return;
    vec3 x = pos.xyz;
    vec2 c = (vec2(px) + 0.5) / float(u_size) * 2.0 - 1.0;
    vec3 wi; // toward the light
    vec3 power;
    if (u_type == 2) {
        float side = 2.0 * u_extent / float(u_size);
        power = u_light_scale * side * side;
        wi = -u_light_direction;
    } else {
        vec2 q = c * u_extent;
        float texel = 2.0 * u_extent / float(u_size);
        float d_omega = texel * texel / pow(1.0 + dot(q, q), 1.5);
        power = u_light_scale * d_omega;
        vec3 to_light = u_light_position - x;
        float dist = length(to_light);
        wi = to_light / dist;
        if (u_light_params.x > 0.0) {
            float r = dist / u_light_params.x;
            float w = clamp(1.0 - r * r * r * r, 0.0, 1.0);
            power *= w * w;
        }
        if (u_type == 1) {
            float cd = dot(u_light_direction, -wi);
            float t = clamp((cd - u_light_params.z) / max(u_light_params.y - u_light_params.z, 1e-4), 0.0, 1.0);
            power *= t * t;
        }
    }
    if (max(power.r, max(power.g, power.b)) <= 0.0)
        return;

    vec3 n = normalize(texelFetch(u_lnrm, ivec3(px, u_layer), 0).xyz);
    vec3 albedo = texelFetch(u_lalb, ivec3(px, u_layer), 0).rgb;
    vec4 mat = texelFetch(u_lmat, ivec3(px, u_layer), 0); // roughness, metallic, transmission, ior
    vec3 lp = u_light_position;
    uint seed = xxh32_6(lp.x == 0.0 ? 0u : floatBitsToUint(lp.x), lp.y == 0.0 ? 0u : floatBitsToUint(lp.y),
                        lp.z == 0.0 ? 0u : floatBitsToUint(lp.z), uint(px.x), uint(px.y), uint(u_layer), u_salt);
    vec4 u = rmap(0, seed, 0u);

    vec3 wo;
    vec3 weight;
    float density;
    float medium = 1.0;
    if (mat.z > 0.0 && u.x < mat.z) {
        // Glass: entering where the modelled normal faces the light, leaving otherwise.
        bool entering = dot(wi, n) > 0.0;
        vec3 nn = entering ? n : -n;
        float eta_i = entering ? 1.0 : mat.w, eta_t = entering ? mat.w : 1.0;
        float cos_i = dot(wi, nn);
        float f = fresnel_dielectric(cos_i, eta_i, eta_t);
        if (u.y < f) {
            wo = reflect(-wi, nn);
            weight = vec3(1.0);
            medium = eta_i;
        } else {
            wo = refract(-wi, nn, eta_i / eta_t);
            weight = albedo;
            medium = eta_t;
        }
        density = 1.0;
    } else {
        if (dot(n, wi) < 0.0)
            n = -n; // opaque surfaces shade alike on both sides
        float cos_i = dot(n, wi);
        float uu = mat.z > 0.0 ? (u.x - mat.z) / (1.0 - mat.z) : u.x;
        if (mat.y > 0.0 && uu < mat.y) {
            vec3 f0 = albedo;
            if (mat.x < 0.01) {
                wo = reflect(-wi, n);
                weight = f0 + (1.0 - f0) * pow(1.0 - cos_i, 5.0);
                density = max(weight.r, max(weight.g, weight.b));
            } else {
                float a = max(mat.x * mat.x, 1e-3), a2 = a * a;
                vec4 g = rmap(0, seed, 2u);
                float tan2 = a2 * g.x / max(1.0 - g.x, 1e-7);
                float cos_h = 1.0 / sqrt(1.0 + tan2), sin_h = sqrt(max(0.0, 1.0 - cos_h * cos_h));
                float phi = 2.0 * PI * g.y;
                vec3 t, b;
                frame_of(n, t, b);
                vec3 h = normalize(t * (sin_h * cos(phi)) + b * (sin_h * sin(phi)) + n * cos_h);
                wo = reflect(-wi, h);
                float nwo = dot(n, wo), woh = dot(wo, h);
                if (nwo <= 0.0 || woh <= 0.0) {
                    weight = vec3(0.0);
                } else {
                    vec3 fr = f0 + (1.0 - f0) * pow(1.0 - woh, 5.0);
                    float gg = smith_g1(cos_i, a2) * smith_g1(nwo, a2);
                    weight = fr * gg * woh / (cos_i * cos_h);
                }
                density = max(f0.r, max(f0.g, f0.b)) / 10.0;
            }
        } else {
            vec3 t, b;
            frame_of(n, t, b);
            vec3 d = rmap(1, seed, 1u).xyz;
            wo = normalize(t * d.x + b * d.y + n * d.z);
            weight = albedo;
            density = max(albedo.r, max(albedo.g, albedo.b)) / 1000.0;
        }
    }
    // Russian roulette (002_… §4.4).
    float p = clamp(max(weight.r, max(weight.g, weight.b)), 0.0, 1.0);
    if (p <= 0.0 || u.z >= p)
        return;
    o_power = vec4(power * weight / p, density);
    o_direction = vec4(wo, medium);
}
