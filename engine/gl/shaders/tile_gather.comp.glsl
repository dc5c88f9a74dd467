#version 450 core
// Tile-based gathering in a compute shader, 002_… §6.3: one 16×16 workgroup per screen tile,
// one invocation per pixel of it; each walks its tile's photon list (built on the CPU by
// engine/ind_tilelists.c, in photon order) and sums the photons whose kernel reaches its G-buffer
// surface point, with the kernel and BSDF of splat.frag.glsl / splat_irradiance.frag.glsl
// (003_… §5 Eq. 1, κ of §5.1 Eq. 2–3; photon_kernel.glsl, ggx.glsl) and the k-d gather's
// distance test (gather_kernel.h). Each pixel's sum runs in list order in one invocation, so
// the result does not depend on how llvmpipe schedules the invocations. Tile rows count from
// the top of the image (as ind_tilelists.c's); GL's texture rows from the bottom.
//
// u_irradiance = 0: image 0 RGB = Σ f Φ κ (radiance), A = number of photons that passed.
// u_irradiance = 1: image 0 RGB = Σ Φ κ (irradiance), A = count; image 1 RGB = the glossy part
// Σ f_glossy Φ κ (002 §7.4).
#define PI 3.14159265358979323846

layout(local_size_x = 16, local_size_y = 16) in;

// One photon: position and r_xy, normal n_p and r_z, ω_i and the k-d gather's bound
// (s_u r_xy)²·1.001 on d², power Φ and s_u, the anisotropic kernel's stretch (1: isotropic;
// photon_kernel.glsl, 002 Eq. 6.3–6.5).
struct photon {
    vec4 position_r;
    vec4 normal_rz;
    vec4 direction_r2;
    vec4 power;
};
layout(std430, binding = 0) readonly buffer Photons { photon u_photons[]; };
layout(std430, binding = 1) readonly buffer Offsets { uint u_offset[]; }; // tiles + 1
// Entries (ind_tilelists.h tl_entry): x the photon, y its rectangle clipped to the tile (bytes xa,
// xb, ya, yb, tile coordinates, rows top first). Pixels outside it are skipped before any
// arithmetic (the rectangle is conservative: the CPU gathers visit only those pixels too).
layout(std430, binding = 2) readonly buffer Entries { uvec2 u_entry[]; };

uniform sampler2D u_position;
uniform sampler2D u_normal;
uniform sampler2D u_albedo;
uniform sampler2D u_material;
uniform vec3 u_eye;
uniform int u_irradiance;

layout(rgba32f, binding = 0) uniform writeonly image2D u_out;
layout(rgba32f, binding = 1) uniform writeonly image2D u_glossy;

#pragma ispm_include "ggx.glsl"
#pragma ispm_include "photon_kernel.glsl"

// The list's photons, 256 at a time: each invocation loads one into shared memory, then every
// invocation walks the batch (002 §6.3, "Gathering": the tile's photon data is loaded to
// shared memory, as all of the tile's pixels read it). On llvmpipe this is about as fast as
// reading the storage buffer in the loop (docs/indirect.md).
shared vec4 sh_position_r[256];
shared vec4 sh_normal_rz[256];
shared vec4 sh_direction_r2[256];
shared vec4 sh_power[256];
shared uint sh_rect[256];

void main()
{
    ivec2 size = textureSize(u_position, 0);
    int x = int(gl_GlobalInvocationID.x), y_top = int(gl_GlobalInvocationID.y);
    bool inside = x < size.x && y_top < size.y; // every invocation takes part in the barriers
    ivec2 px = ivec2(x, size.y - 1 - y_top);
    uint tile = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    vec4 acc = vec4(0.0);
    vec3 glossy = vec3(0.0);
    vec4 s = inside ? texelFetch(u_position, px, 0) : vec4(0.0);
    vec3 n = vec3(0.0), albedo = vec3(0.0), f_diffuse = vec3(0.0);
    vec4 mat = vec4(0.0);
    if (s.w != 0.0) {
        n = texelFetch(u_normal, px, 0).xyz;
        albedo = texelFetch(u_albedo, px, 0).rgb;
        mat = texelFetch(u_material, px, 0);
        f_diffuse = albedo * (1.0 - mat.y) * (1.0 - mat.z) / PI;
    }
    uint lx = gl_LocalInvocationID.x, ly = gl_LocalInvocationID.y;
    uint lid = gl_LocalInvocationIndex, end = u_offset[tile + 1];
    for (uint base = u_offset[tile]; base < end; base += 256u) {
        uint count = min(256u, end - base);
        barrier(); // the previous batch is done with
        if (lid < count) {
            uvec2 entry = u_entry[base + lid];
            photon q = u_photons[entry.x];
            sh_rect[lid] = entry.y;
            sh_position_r[lid] = q.position_r;
            sh_normal_rz[lid] = q.normal_rz;
            sh_direction_r2[lid] = q.direction_r2;
            sh_power[lid] = q.power;
        }
        barrier();
        if (s.w == 0.0)
            continue;
        for (uint k = 0u; k < count; k++) {
            uint rc = sh_rect[k];
            if (lx < (rc & 255u) || lx > ((rc >> 8) & 255u) || ly < ((rc >> 16) & 255u) || ly > (rc >> 24))
                continue;
            vec4 position_r = sh_position_r[k];
            vec3 d = s.xyz - position_r.xyz;
            vec4 direction_r2 = sh_direction_r2[k];
            if (!(d.x * d.x + d.y * d.y + d.z * d.z <= direction_r2.w))
                continue;
            vec4 normal_rz = sh_normal_rz[k];
            vec4 power_su = sh_power[k];
            float kappa = power_su.w == 1.0
                              ? photon_kappa(s.xyz, position_r.xyz, normal_rz.xyz, vec2(position_r.w, normal_rz.w))
                              : photon_kappa_aniso(s.xyz, position_r.xyz, normal_rz.xyz, vec2(position_r.w, normal_rz.w),
                                                   photon_aniso(direction_r2.xyz, normal_rz.xyz, power_su.w));
            if (kappa < 0.0)
                continue;
            float cos_i = dot(direction_r2.xyz, n);
            if (cos_i <= 0.0)
                continue;
            vec3 power = power_su.rgb;
            if (u_irradiance != 0) {
                vec3 e3 = power * kappa;
                acc.rgb += e3;
                if (mat.y > 0.0)
                    glossy += photon_glossy(n, s.xyz, u_eye, direction_r2.xyz, cos_i, albedo, mat) * e3;
            } else {
                vec3 f = f_diffuse;
                if (mat.y > 0.0)
                    f += photon_glossy(n, s.xyz, u_eye, direction_r2.xyz, cos_i, albedo, mat);
                acc.rgb += f * power * kappa;
            }
            acc.a += 1.0;
        }
    }
    if (!inside)
        return;
    imageStore(u_out, px, acc);
    if (u_irradiance != 0)
        imageStore(u_glossy, px, vec4(glossy, 0.0));
}
