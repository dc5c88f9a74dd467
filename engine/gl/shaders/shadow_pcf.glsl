// Hard shadows by percentage-closer filtering (shadow method "pcf", engine/shadow_pcf.c):
// (2r+1)² texels of the light's shadow map around the lookup, comparing metric distances
// (see shadow.frag.glsl), with a normal offset that grows with the shadow texel's world
// size. Included by direct.frag.glsl, whose uniforms it reads.
int cube_face(vec3 d)
{
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z)
        return d.x > 0.0 ? 0 : 1;
    if (a.y >= a.z)
        return d.y > 0.0 ? 2 : 3;
    return d.z > 0.0 ? 4 : 5;
}

// Where light i's map is read for surface point p (normal n): the normal-offset point q, the
// world size of a texel there, the face, the metric value to compare and the map coordinates.
struct shadow_at {
    float texel;
    int face;
    float value;
    vec2 uv;
    vec3 q;
};

shadow_at shadow_lookup(int i, vec3 p, vec3 n)
{
    shadow_at s;
    int type = u_light_type[i];
    float dist = distance(p, u_light_position[i]);
    // Normal offset: a few millimetres plus 1.5 texels of the map at this distance.
    s.texel = type == 2 ? u_shadow_texel[i] : u_shadow_texel[i] * dist;
    s.q = p + n * (u_shadow_bias + 1.5 * s.texel);
    s.face = 0;
    if (type == 2) {
        s.value = dot(s.q - u_light_position[i], u_light_direction[i]);
    } else {
        s.value = distance(s.q, u_light_position[i]);
        if (type == 0)
            s.face = cube_face(s.q - u_light_position[i]);
    }
    vec4 c = u_shadow_view_proj[i * 6 + s.face] * vec4(s.q, 1.0);
    s.uv = c.xy / c.w * 0.5 + 0.5;
    return s;
}

// Outside a spot frustum: unlit (0); outside the ortho box: lit (1); inside: −1.
float shadow_outside(int i, vec2 uv)
{
    int type = u_light_type[i];
    if (type != 0 && (uv.x < 0.0 || uv.x > 1.0 || uv.y < 0.0 || uv.y > 1.0))
        return type == 2 ? 1.0 : 0.0;
    return -1.0;
}

float visibility(int i, vec3 p, vec3 n)
{
    shadow_at s = shadow_lookup(i, p, n);
    float outside = shadow_outside(i, s.uv);
    if (outside >= 0.0)
        return outside;
    ivec2 base = ivec2(floor(s.uv * float(u_shadow_size)));
    float lit = 0.0;
    float taps = 0.0;
    for (int dy = -u_pcf_radius; dy <= u_pcf_radius; dy++)
        for (int dx = -u_pcf_radius; dx <= u_pcf_radius; dx++) {
            ivec2 t = clamp(base + ivec2(dx, dy), ivec2(0), ivec2(u_shadow_size - 1));
            float stored = texelFetch(u_shadow[i], ivec3(t, s.face), 0).r;
            lit += s.value <= stored + s.texel ? 1.0 : 0.0;
            taps += 1.0;
        }
    return lit / taps;
}
