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
// BSDF sampling: bsdf_sample.glsl, the line-for-line twin of engine/bsdf.c that the CPU trace
// uses for every later bounce (lobe order, constants, Russian roulette with P = max channel of
// the weight (002_… §4.4), path-density factors of 003_… §4.3), reading entry seed + 0 of the
// uniform and cosine tables as the CPU reads entry seed + k at its k-th event. With stratified
// sampling across frames (002_… §4.2) the numbers are Cranley–Patterson rotated by this frame's
// offsets first, exactly as photon_trace.c does.
//
// Lights with a size (issue 15) emit from a point of their surface: see main.

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
uniform float u_radius;          // light size: sphere radius (m) or tan of the disc's angular radius
uniform uint u_salt;
uniform int u_stratified;        // 1: rotate the random numbers by u_offset (bsdf_stratify)
uniform vec4 u_offset;
uniform int u_strata_log2;       // "bounce_strata" = 2^u_strata_log2; 0 = off (bsdf_strata)
uniform uint u_strata_salt;      // eng_rmap_frame's strata_salt

layout(location = 0) out vec4 o_power;     // Φ_o RGB, path density ρp
layout(location = 1) out vec4 o_direction; // ω_o, index of refraction of the medium after the bounce
layout(location = 2) out vec4 o_lobe;      // x: the lobe the scatter took (BSDF_LOBE_*), for the final
                                           // gather's caustic photons (ind_finalgather.c); not captured

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

#pragma ispm_include "bsdf_constants.glsl"
#pragma ispm_include "bsdf_sample.glsl"
#pragma ispm_include "bsdf_strata.glsl"

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 pos = texelFetch(u_lpos, ivec3(px, u_layer), 0);
    o_power = vec4(0.0);
    o_direction = vec4(0.0, 0.0, 0.0, 1.0);
    o_lobe = vec4(0.0);
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
    uint lx = lp.x == 0.0 ? 0u : floatBitsToUint(lp.x), ly = lp.y == 0.0 ? 0u : floatBitsToUint(lp.y);
    uint lz = lp.z == 0.0 ? 0u : floatBitsToUint(lp.z);
    uint seed = xxh32_6(lx, ly, lz, uint(px.x), uint(px.y), uint(u_layer), u_salt);
    vec4 u = rmap(0, seed, 0u);
    vec4 cosdir = rmap(1, seed, 0u);
    if (u_radius > 0.0) {
        // A light with a size (issue 15): the photon leaves a point of the light's disc facing
        // x (sphere: radius u_radius about the centre; directional: tan α about −direction),
        // uniform on it from entry seed + 1 of the uniform table, so it is the same point every
        // frame. Its power stays the texel's: the sphere's intensity is the point light's.
        vec4 ua = rmap(0, seed, 1u);
        float r = sqrt(ua.x), phi = 6.28318530717958647692 * ua.y;
        vec3 t = normalize(abs(wi.x) > 0.5 ? cross(wi, vec3(0.0, 1.0, 0.0)) : cross(wi, vec3(1.0, 0.0, 0.0)));
        vec3 b = cross(wi, t);
        vec3 off = u_radius * r * (cos(phi) * t + sin(phi) * b);
        wi = u_type == 2 ? normalize(wi + off) : normalize(u_light_position + off - x);
    }
    if (u_strata_log2 > 0) {
        uint k = uint(u_strata_log2), mask = (1u << k) - 1u;
        uint index = ((uint(px.y) & mask) << k) + (uint(px.x) & mask);
        uint pattern = xxh32_6(lx, ly, lz, uint(px.x) >> k, uint(px.y) >> k, uint(u_layer), u_strata_salt);
        bsdf_strata(u, index, k, pattern, u);
    }
    if (u_stratified != 0 || u_strata_log2 > 0) // u_offset is zero unless stratified
        bsdf_stratify(u, u_offset, u, cosdir);
    // The photon arrives from the light through air.
    float eta = 1.0;
    vec3 wo, weight;
    float density;
    int lobe = bsdf_scatter(albedo, mat, n, wi, eta, u, cosdir, wo, weight, density);
    if (lobe == BSDF_LOBE_ABSORBED)
        return;
    o_power = vec4(power * weight, density);
    o_direction = vec4(wo, eta);
    o_lobe = vec4(float(lobe), 0.0, 0.0, 0.0);
}
