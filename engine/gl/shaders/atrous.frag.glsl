#version 450 core
// One iteration of the edge-avoiding À-Trous wavelet transform with variance-clipped detail
// coefficients, 002_… §7.3:
//   S_{i+1}(p) = Σ_q h(q) w(p,q) S_i(q) / Σ_q h(q) w(p,q),  q = p + 2^i·(dx,dy), dx,dy ∈ −2..2
//                                                                       (Eq. 7.5)
//   with h = (1/8, 1/4, 1/2, 1/4, 1/8) per axis and w = w_z · w_n (Eq. 7.1–7.2);
//   D_i = S_i − S_{i+1}                                                 (Eq. 7.6)
//   μ = M1/w_Ω, σ = sqrt(M2/w_Ω − μ²), CSB_i = γσ over the same taps and weights (Eq. 7.7)
//   E = S_N + Σ_i clamp(D_i, −CSB_i, CSB_i)                             (Eq. 7.8)
// (the thesis prints "S_N − Σ", but S_0 = S_N + Σ D_i with D_i = S_i − S_{i+1}: the detail is
// added back). u_detail: 0 clipped (Eq. 7.8), 1 none (scaling coefficients only), 2 all
// (every detail kept: E reconstructs S_0). Outputs: 0 S_{i+1}, 1 the kept detail D'_i,
// 2 Σ_{k≤i} D'_k (running sum), 3 S_{i+1} + Σ_{k≤i} D'_k (the result after this iteration).
uniform sampler2D u_scale;   // S_i
uniform sampler2D u_detail_sum;
uniform sampler2D u_normal;
uniform sampler2D u_misc;
uniform int u_step;
uniform int u_first;    // iteration 0: no details yet
uniform int u_detail;
uniform float u_gamma;

layout(location = 0) out vec4 o_scale;
layout(location = 1) out vec4 o_detail;
layout(location = 2) out vec4 o_detail_sum;
layout(location = 3) out vec4 o_result;

#pragma ispm_include "edge_stop.glsl"

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 m = texelFetch(u_misc, px, 0);
    vec3 np = texelFetch(u_normal, px, 0).xyz;
    if (!edge_covered(vec4(np, 0.0))) {
        o_scale = o_detail = o_detail_sum = o_result = vec4(0.0);
        return;
    }
    const float h[5] = float[5](0.125, 0.25, 0.5, 0.25, 0.125);
    ivec2 size = textureSize(u_misc, 0);
    vec2 grad = edge_depth_gradient(u_misc, u_normal, px);
    vec3 sum = vec3(0.0), m1 = vec3(0.0), m2 = vec3(0.0);
    float wsum = 0.0;
    for (int dy = -2; dy <= 2; dy++)
        for (int dx = -2; dx <= 2; dx++) {
            ivec2 off = ivec2(dx, dy) * u_step;
            ivec2 q = px + off;
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size)))
                continue;
            vec3 nq = texelFetch(u_normal, q, 0).xyz;
            if (!edge_covered(vec4(nq, 0.0)))
                continue;
            float w = h[dx + 2] * h[dy + 2];
            if (dx != 0 || dy != 0)
                w *= edge_w_depth(m.x, texelFetch(u_misc, q, 0).x, grad, vec2(off)) * edge_w_normal(np, nq);
            vec3 c = texelFetch(u_scale, q, 0).rgb;
            sum += w * c;
            m1 += w * c;
            m2 += w * c * c;
            wsum += w;
        }
    vec3 s0 = texelFetch(u_scale, px, 0).rgb;
    vec3 s1 = sum / wsum; /* the centre tap always counts: wsum >= 1/4 */
    vec3 d = s0 - s1;
    vec3 mu = m1 / wsum;
    vec3 sigma = sqrt(max(m2 / wsum - mu * mu, vec3(0.0)));
    vec3 kept = u_detail == 0 ? clamp(d, -u_gamma * sigma, u_gamma * sigma) : (u_detail == 1 ? vec3(0.0) : d);
    vec3 acc = (u_first == 1 ? vec3(0.0) : texelFetch(u_detail_sum, px, 0).rgb) + kept;
    o_scale = vec4(s1, 0.0);
    o_detail = vec4(kept, 0.0);
    o_detail_sum = vec4(acc, 0.0);
    o_result = vec4(s1 + acc, 0.0);
}
