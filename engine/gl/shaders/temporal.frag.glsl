#version 450 core
// Temporal accumulation, 002_… §7.2: an exponential moving average of the irradiance with the
// previous frame's result reprojected by the motion vectors,
//   S_i = (1 − α) E_i + α S_{i−1}(q)                                   (Eq. 7.3)
//   α = 0.95 · w_z(p, q) · w_n(p, q)                                   (Eq. 7.4)
// q is the texel of the previous frame that p's surface point fell into (gbuffer motion, in
// image pixels with y down, so y flips for GL). w_z compares the depth this surface point had
// in the previous frame (G-buffer normal.w, exact for moving objects too) with the previous
// frame's depth at q extrapolated along its gradient to the exact reprojected position, so a
// disoccluded pixel (q showed another surface) gets α → 0; w_n compares normals. The history
// is fetched at the texel q (no bilinear blending of history).
// Outputs: 0 = S_i (RGB) and α (A); 1 = the reprojected history S_{i−1}(q) (RGB).
uniform sampler2D u_irradiance;
uniform sampler2D u_normal;
uniform sampler2D u_misc;
uniform sampler2D u_prev_result;
uniform sampler2D u_prev_normal;
uniform sampler2D u_prev_misc;
uniform int u_has_history;
uniform float u_alpha;

layout(location = 0) out vec4 o_result;
layout(location = 1) out vec4 o_history;

#pragma ispm_include "edge_stop.glsl"

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 m = texelFetch(u_misc, px, 0);
    vec4 n = texelFetch(u_normal, px, 0);
    if (!edge_covered(n)) {
        o_result = vec4(0.0);
        o_history = vec4(0.0);
        return;
    }
    vec3 e = texelFetch(u_irradiance, px, 0).rgb;
    float alpha = 0.0;
    vec3 hist = vec3(0.0);
    if (u_has_history == 1) {
        vec2 qf = vec2(px) + 0.5 + vec2(m.z, -m.w);
        ivec2 q = ivec2(floor(qf));
        ivec2 size = textureSize(u_prev_misc, 0);
        if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, size))) {
            vec4 pm = texelFetch(u_prev_misc, q, 0);
            vec4 pn = texelFetch(u_prev_normal, q, 0);
            if (edge_covered(pn)) {
                vec2 grad = edge_depth_gradient(u_prev_misc, u_prev_normal, q);
                vec2 offset = qf - (vec2(q) + 0.5);
                /* q's depth extrapolated to the exact reprojected position first: the
                 * nearest-texel fetch alone would cost a sloped surface e^-1 of its history */
                float wz = edge_w_depth(n.w, pm.x + dot(grad, offset), grad, offset);
                float wn = edge_w_normal(n.xyz, pn.xyz);
                alpha = u_alpha * wz * wn;
                hist = texelFetch(u_prev_result, q, 0).rgb;
            }
        }
    }
    o_result = vec4((1.0 - alpha) * e + alpha * hist, alpha);
    o_history = vec4(hist, 0.0);
}
