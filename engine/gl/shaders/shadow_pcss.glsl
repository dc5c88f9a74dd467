// Soft shadows of lights with a size (shadow method "pcss", engine/shadow_pcss.c): the
// image-space soft shadows of 001 §3.4 done in the light's shadow map (percentage-closer soft
// shadows). Step 1, the average occluder depth d_b (001 Eq. 3), comes from the blocker map
// (blocker.frag.glsl); step 2 turns it into the penumbra radius of 001 Eq. 5,
// R_g = L·d/(D−d), with L the light's radius, D the receiver's distance to the light and
// d = D − d_b its distance to the occluder, and divides by D·texel instead of Z_eye to get
// it in shadow-map texels; step 3 filters the map over a disc of that radius (001 Eq. 3 with
// ω = 1 over the disc), laid out in directions about the receiver's (one tap may fall on
// another cube face). For a directional light of angular radius α the same step gives
// tan α·(D − d_b) over the ortho box's texel size. Each tap compares the stored distance with
// the receiver's tangent plane intersected along the tap's own ray, so a flat receiver never
// shadows itself however wide the disc. Included by direct.frag.glsl, whose uniforms it reads
// (after shadow_pcf.glsl: cube_face, shadow_lookup).
#define PCSS_TAPS 64
#define PCSS_MAX_RADIUS 64.0 // texels
#define PCSS_GOLDEN_ANGLE 2.39996322972865332

// A unit vector's two perpendiculars.
void pcss_basis(vec3 w, out vec3 t, out vec3 b)
{
    t = normalize(abs(w.x) > 0.5 ? cross(w, vec3(0.0, 1.0, 0.0)) : cross(w, vec3(1.0, 0.0, 0.0)));
    b = cross(w, t);
}

// Penumbra radius in texels, 001 Eq. 5 (see the header).
float pcss_penumbra_texels(int i, float receiver, float blocker, float texel)
{
    float r = u_light_radius[i];
    float w = u_light_type[i] == 2 ? r * (receiver - blocker) / texel
                                   : r * (receiver - blocker) / (receiver * blocker * texel);
    return clamp(w, 0.0, PCSS_MAX_RADIUS);
}

// Visibility of light i at p (normal n); pen = (penumbra radius in texels, blocker depth).
float pcss_visibility(int i, vec3 p, vec3 n, out vec2 pen)
{
    pen = vec2(0.0);
    int type = u_light_type[i];
    float texel_unit = u_shadow_texel[i];
    shadow_at sa = shadow_lookup(i, p, n);
    float outside = shadow_outside(i, sa.uv);
    if (outside >= 0.0)
        return outside;
    float texel = sa.texel, value = sa.value;
    int face = sa.face;
    vec2 uv = sa.uv;
    vec3 q = sa.q;
    ivec2 size = ivec2(u_shadow_size - 1);
    ivec2 base = clamp(ivec2(floor(uv * float(u_shadow_size))), ivec2(0), size);
    // Average occluder depth: the blocker map where the receiver is the surface the light
    // sees; where something else is in front of the receiver, that surface itself.
    float stored = texelFetch(u_shadow[i], ivec3(base, face), 0).r;
    float blocker = texelFetch(u_blocker[i], ivec3(base / 2, face), 0).r; // half resolution
    if (value > stored + texel)
        blocker = blocker > 0.0 && blocker < stored ? blocker : stored;
    if (!(blocker > 0.0) || blocker >= value)
        return 1.0; // nothing between the receiver and the light
    float radius = pcss_penumbra_texels(i, value, blocker, texel_unit);
    pen = vec2(2.0 * radius, blocker);
    // The disc in the light's own measure, so that it is as wide wherever it falls on the map
    // (a cube face's texels shrink away from its centre): radians about the direction to the
    // receiver for perspective maps, metres across the light direction for the ortho box.
    float extent = max(radius, 0.5) * texel_unit;
    vec3 o0, w;
    if (type == 2) {
        w = u_light_direction[i];
        o0 = q - w * value; // on the box's near plane, where the stored depths start
    } else {
        w = normalize(q - u_light_position[i]);
        o0 = u_light_position[i];
    }
    vec3 tb, bb;
    pcss_basis(w, tb, bb);
    // Filtered lookup over the disc (Vogel spiral: equal area per tap).
    float lit = 0.0;
    for (int k = 0; k < PCSS_TAPS; k++) {
        float r = extent * sqrt((float(k) + 0.5) / float(PCSS_TAPS));
        float a = float(k) * PCSS_GOLDEN_ANGLE;
        vec3 off = r * (cos(a) * tb + sin(a) * bb);
        vec3 o = type == 2 ? o0 + off : o0;
        vec3 d = type == 2 ? w : normalize(w + off);
        int f = type == 0 ? cube_face(d) : 0;
        vec4 ct = u_shadow_view_proj[i * 6 + f] * vec4(o + d, 1.0);
        ivec2 t = clamp(ivec2(floor((ct.xy / ct.w * 0.5 + 0.5) * float(u_shadow_size))), ivec2(0), size);
        float dn = dot(n, d);
        // The receiver's plane along this tap's ray (its own distance where the ray grazes it).
        float expect = dn < -0.05 ? dot(n, p - o) / dn : value;
        float s = texelFetch(u_shadow[i], ivec3(t, f), 0).r;
        float tol = u_shadow_bias + 2.0 * (type == 2 ? texel_unit : texel_unit * expect) / max(-dn, 0.25);
        lit += s + tol >= expect ? 1.0 : 0.0;
    }
    return lit / float(PCSS_TAPS);
}

#ifdef PCSS_RAYS
// pcss_blocker "rays" (engine/shadow_pcss.c; the same march on the CPU: shadow_rays_cpu): the
// light's disc seen from the receiver is sampled at PCSS_RAY_SAMPLES points (a Vogel spiral,
// equal area each, turned by an angle of the receiver's shadow texel), and the segment from the
// receiver to each point is walked through the shadow map in steps of at most PCSS_RAY_STEP
// texels, equal in the map (linear in t/(1−t) along the segment for a perspective map, in depth
// for the ortho box), as far as PCSS_RAY_REACH texels at the disc's rim (nearer occluders are
// missed). The map is a height field seen from the light's centre: a ray is blocked where it
// crosses a stored surface. Over each step the ray's own value (distance from the light, or
// depth) falls; where it passes the value stored at either end of the step, the ray is taken to
// that exact value and blocked if the map there holds that surface (within PCSS_RAY_HIT
// tolerances: a face seen at a grazing angle changes fast from texel to texel). Where the map
// instead steps from an occluder to what lies beyond it, the ray passes: a receiver hidden from
// the centre by a box's top (the floor beside a box standing on it) still sees the light's far
// side past the box's edge, which a single blocker depth cannot express. A ray still behind a
// surface at its last step is blocked. Visibility: the unblocked share of the rays, with no
// filter. Comparisons allow u_shadow_bias and PCSS_RAY_TOL texels at the point's distance; the
// first step ignores surfaces within that of the receiver (its own). Compiled in only with
// PCSS_RAYS (pass_direct.c), so that the direct pass of "map" is the filter alone.
#define PCSS_RAY_SAMPLES 16
#define PCSS_RAY_STEP 1.5    // texels
#define PCSS_RAY_REACH 48.0 // texels
#define PCSS_RAY_HIT 8.0
#define PCSS_RAY_TOL 2.0 // texels

// Light i's map at world point x: (stored value, x's own value, comparison tolerance).
vec3 pcss_ray_map(int i, vec3 x)
{
    int type = u_light_type[i];
    int f = type == 0 ? cube_face(x - u_light_position[i]) : 0;
    float v = type == 2 ? dot(x - u_light_position[i], u_light_direction[i]) : distance(x, u_light_position[i]);
    vec4 c = u_shadow_view_proj[i * 6 + f] * vec4(x, 1.0);
    ivec2 t = clamp(ivec2(floor((c.xy / c.w * 0.5 + 0.5) * float(u_shadow_size))), ivec2(0),
                    ivec2(u_shadow_size - 1));
    float tol = u_shadow_bias + PCSS_RAY_TOL * u_shadow_texel[i] * (type == 2 ? 1.0 : v);
    return vec3(texelFetch(u_shadow[i], ivec3(t, f), 0).r, v, tol);
}

// The point at parameter s of ray k: to light point l (perspective; s = t/(1−t)) or along
// direction d from q (ortho; s = depth travelled).
vec3 pcss_ray_point(int type, vec3 q, vec3 l, float s)
{
    return type == 2 ? q + s * l : mix(q, l, s / (1.0 + s));
}

// The point of the ray from q toward l (perspective) or along l (ortho) whose own value is c:
// at distance c from the light (the nearer root of |q + t(l − q) − light|² = c²) or at depth c.
vec3 pcss_ray_at_value(int type, int i, vec3 q, vec3 l, float c)
{
    if (type == 2)
        return q + (dot(q - u_light_position[i], u_light_direction[i]) - c) * l;
    vec3 a = q - u_light_position[i], b = l - q;
    float bb = dot(b, b), ab = dot(a, b);
    float t = (-ab - sqrt(max(ab * ab - bb * (dot(a, a) - c * c), 0.0))) / bb;
    return q + t * b;
}

float pcss_rays_visibility(int i, vec3 p, vec3 n, out vec2 pen)
{
    pen = vec2(0.0);
    int type = u_light_type[i];
    float r = u_light_radius[i];
    float texel_unit = u_shadow_texel[i];
    shadow_at sa = shadow_lookup(i, p, n);
    float outside = shadow_outside(i, sa.uv);
    if (outside >= 0.0)
        return outside;
    float value = sa.value;
    vec3 q = sa.q;
    vec3 w = type == 2 ? u_light_direction[i] : normalize(q - u_light_position[i]);
    vec3 tb, bb;
    pcss_basis(w, tb, bb);
    vec3 m0 = pcss_ray_map(i, q);
    // The march's reach: PCSS_RAY_REACH texels at the rim, and no nearer to the light than just
    // outside the emitter (perspective) or the box's near plane (ortho).
    float near = max(1.5 * r, 0.05);
    float reach = type == 2 ? min(PCSS_RAY_REACH * texel_unit / r, value)
                            : min(PCSS_RAY_REACH * value * texel_unit / r, max(value - near, 0.0) / near);
    // The reach in texels at the rim.
    float reach_texels = type == 2 ? reach * r / texel_unit : reach * r / (value * texel_unit);
    // The spiral turned by an angle of the receiver's shadow texel (interleaved gradient noise):
    // the same for a surface point in every frame, different between neighbours, so that the
    // share of 16 rays varies in finer steps than 1/16 over an area.
    ivec2 tex = ivec2(floor(sa.uv * float(u_shadow_size)));
    float turn = 6.28318530717958648 * fract(52.9829189 * fract(0.06711056 * float(tex.x) + 0.00583715 * float(tex.y)));
    float lit = 0.0, crossings = 0.0, crossing_sum = 0.0;
    for (int k = 0; k < PCSS_RAY_SAMPLES; k++) {
        float rho = r * sqrt((float(k) + 0.5) / float(PCSS_RAY_SAMPLES));
        float a = float(k) * PCSS_GOLDEN_ANGLE + turn;
        vec3 off = rho * (cos(a) * tb + sin(a) * bb);
        vec3 l = type == 2 ? off - w : u_light_position[i] + off;
        bool blocked = false;
        float s_prev = 0.0;
        vec3 m_prev = m0;
        int steps = max(int(ceil(reach_texels * rho / (r * PCSS_RAY_STEP))), 1);
        for (int j = 1; j <= steps && !blocked; j++) {
            float s = reach * float(j) / float(steps);
            vec3 m = pcss_ray_map(i, pcss_ray_point(type, q, l, s));
            // The stored depths at either end of the step that the ray's depth passes over:
            // where the ray is at that depth, is that surface there?
            for (int e = 0; e < 2 && !blocked; e++) {
                float c = e == 0 ? m_prev.x : m.x;
                if (c >= m.y && c < m_prev.y - (j == 1 ? m_prev.z : 0.0)) {
                    vec3 mc = pcss_ray_map(i, pcss_ray_at_value(type, i, q, l, c));
                    if (abs(mc.y - mc.x) <= PCSS_RAY_HIT * mc.z) {
                        blocked = true;
                        crossing_sum += mc.x;
                    }
                }
            }
            s_prev = s;
            m_prev = m;
        }
        if (!blocked && m_prev.y > m_prev.x + m_prev.z) {
            blocked = true;
            crossing_sum += m_prev.x;
        }
        lit += blocked ? 0.0 : 1.0;
        crossings += blocked ? 1.0 : 0.0;
    }
    if (crossings > 0.0) {
        float blocker = crossing_sum / crossings;
        pen = vec2(2.0 * pcss_penumbra_texels(i, value, min(blocker, value), texel_unit), blocker);
    }
    return lit / float(PCSS_RAY_SAMPLES);
}
#endif
