#version 450 core
// Joint bilateral upsampling of subsampled photon irradiance, one level (×2) at a time:
// ISPM 003_… §5.2 ("a joint bilateral filter with a box filter and weights based on 2D
// bilinear interpolation, normals, and depth between the low- and high-resolution eye
// G-buffers"; Fig. 12), level by level as in 004_… §6. For a high-resolution pixel p the four
// nearest low-resolution texels q get weight bilinear(p,q) · w_n(p,q) · w_z(p,q) (the
// edge-stopping functions of 002 Eq. 7.1–7.2, edge_stop.glsl). Where every tap is rejected
// (p lies on a surface no low-resolution texel saw) the tap of closest depth is taken alone
// rather than leaving a hole; A of output 0 holds the weight sum (0 there), for inspection.
// Radiance is upsampled before any BSDF is applied (003 §5.2).
uniform sampler2D u_lo_irradiance;
uniform sampler2D u_lo_glossy;
uniform sampler2D u_lo_normal;
uniform sampler2D u_lo_misc;
uniform sampler2D u_hi_normal;
uniform sampler2D u_hi_misc;

layout(location = 0) out vec4 o_irradiance;
layout(location = 1) out vec4 o_glossy;

#pragma ispm_include "edge_stop.glsl"

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 hm = texelFetch(u_hi_misc, px, 0);
    vec3 np = texelFetch(u_hi_normal, px, 0).xyz;
    if (!edge_covered(vec4(np, 0.0))) { /* background */
        o_irradiance = vec4(0.0);
        o_glossy = vec4(0.0);
        return;
    }
    ivec2 lo_size = textureSize(u_lo_misc, 0);
    vec2 scale = vec2(textureSize(u_hi_misc, 0)) / vec2(lo_size);
    vec2 u = (vec2(px) + 0.5) / scale - 0.5;
    ivec2 base = ivec2(floor(u));
    vec2 f = u - vec2(base);
    float zp = hm.x;
    vec2 grad = edge_depth_gradient(u_hi_misc, u_hi_normal, px);
    vec3 e = vec3(0.0), g = vec3(0.0);
    float wsum = 0.0, best = 1e30;
    ivec2 best_q = ivec2(-1);
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            ivec2 q = clamp(base + ivec2(i, j), ivec2(0), lo_size - 1);
            vec4 qm = texelFetch(u_lo_misc, q, 0);
            vec3 nq = texelFetch(u_lo_normal, q, 0).xyz;
            if (!edge_covered(vec4(nq, 0.0)))
                continue;
            float bil = (i == 1 ? f.x : 1.0 - f.x) * (j == 1 ? f.y : 1.0 - f.y);
            vec2 offset = (vec2(q) + 0.5) * scale - (vec2(px) + 0.5);
            float w = bil * edge_w_normal(np, nq) * edge_w_depth(zp, qm.x, grad, offset);
            e += w * texelFetch(u_lo_irradiance, q, 0).rgb;
            g += w * texelFetch(u_lo_glossy, q, 0).rgb;
            wsum += w;
            float dz = abs(zp - qm.x);
            if (dz < best) {
                best = dz;
                best_q = q;
            }
        }
    if (wsum > 1e-6) {
        o_irradiance = vec4(e / wsum, wsum);
        o_glossy = vec4(g / wsum, 0.0);
    } else if (best_q.x >= 0) {
        o_irradiance = vec4(texelFetch(u_lo_irradiance, best_q, 0).rgb, 0.0);
        o_glossy = vec4(texelFetch(u_lo_glossy, best_q, 0).rgb, 0.0);
    } else {
        o_irradiance = vec4(0.0);
        o_glossy = vec4(0.0);
    }
}
