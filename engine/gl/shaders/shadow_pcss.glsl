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
