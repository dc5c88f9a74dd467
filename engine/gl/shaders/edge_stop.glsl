// Edge-stopping weights of the reconstruction filters, 002_… §7.1 (after Schied et al.):
//   w_z(p,q) = exp(−|z(p) − z(q)| / (σ_z |∇z(p)·(p − q)| + ε))        (Eq. 7.1)
//   w_n(p,q) = max(0, n(p)·n(q))^σ_n                                  (Eq. 7.2)
// with σ_z = 1 and σ_n = 32 as in the thesis. z is eye depth in metres, ∇z its screen-space
// gradient in metres per pixel, p − q the offset in pixels. The thesis leaves ε open; we use
// 0.1% of z(p), so a flat surface seen head-on (∇z = 0) still tolerates depth rounding.
const float EDGE_SIGMA_Z = 1.0;
const float EDGE_SIGMA_N = 32.0;

float edge_w_depth(float zp, float zq, vec2 grad, vec2 offset)
{
    float denom = EDGE_SIGMA_Z * abs(dot(grad, offset)) + 1e-3 * zp;
    return exp(-abs(zp - zq) / denom);
}

float edge_w_normal(vec3 np, vec3 nq)
{
    return pow(max(0.0, dot(np, nq)), EDGE_SIGMA_N);
}

// Is there a surface at this G-buffer texel? The normal target is cleared to zero and
// surfaces write unit normals (the material id cannot tell: −1 is also the default material).
bool edge_covered(vec4 normal)
{
    return dot(normal.xyz, normal.xyz) > 0.25;
}

// Screen-space gradient of the eye depth (channel x of a G-buffer misc texture) at px, from
// the one-sided difference of smaller magnitude on each axis, so that a depth edge next to p
// does not make a flat surface look steep. Background texels are ignored.
vec2 edge_depth_gradient(sampler2D misc, sampler2D normal, ivec2 px)
{
    ivec2 size = textureSize(misc, 0);
    float z = texelFetch(misc, px, 0).x;
    vec2 g = vec2(0.0);
    for (int axis = 0; axis < 2; axis++) {
        ivec2 step = axis == 0 ? ivec2(1, 0) : ivec2(0, 1);
        ivec2 a = px + step, b = px - step;
        bool ha = all(lessThan(a, size)) && edge_covered(texelFetch(normal, a, 0));
        bool hb = all(greaterThanEqual(b, ivec2(0))) && edge_covered(texelFetch(normal, b, 0));
        float da = ha ? texelFetch(misc, a, 0).x - z : 0.0;
        float db = hb ? z - texelFetch(misc, b, 0).x : 0.0;
        float d = ha && hb ? (abs(da) < abs(db) ? da : db) : (ha ? da : db);
        g[axis] = d;
    }
    return g;
}
