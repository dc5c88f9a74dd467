#version 450 core
// Blocker search of the soft-shadow method (shadow_pcss.glsl, engine/shadow_pcss.c): for each
// texel of one face of a light's shadow map, the average depth of the occluders in front of
// the surface that texel sees (001 §3.4 step 1: Eq. 3 with ω = 1 and γ = 1 over a disc, the
// search radius R_p of Eq. 2 being the light's radius projected to the map: r·(z − z_n)/(z·z_n)
// per texel for a sphere light at distance z, tan α·z for a directional disc). A sample is an
// occluder when it is nearer than the texel's surface continued as a plane (the slope of the
// map's smaller one-sided differences), by more than the tolerance. 0 where there is none.
// The map is at half the shadow map's resolution (the average occluder depth varies slowly);
// texel (x, y) stands for the shadow texels (2x..2x+1, 2y..2y+1), of which the one farthest
// from the light is the receiver, so that a lit receiver next to an occluder's edge always
// finds the occluder.
#define BLOCKER_TAPS 16
#define BLOCKER_MAX_RADIUS 48.0
#define GOLDEN_ANGLE 2.39996322972865332

uniform sampler2DArray u_shadow;
uniform int u_face;
uniform int u_size;        // of the shadow map
uniform int u_directional;
uniform float u_radius;    // light radius (m) or tan of the angular radius
uniform float u_texel;     // world size of a texel at unit distance (or absolute, directional)
uniform float u_near;      // nearest occluder distance the search allows for (perspective)
uniform float u_far;       // what an empty texel holds

layout(location = 0) out vec4 o_blocker;

float fetch(ivec2 t)
{
    return texelFetch(u_shadow, ivec3(clamp(t, ivec2(0), ivec2(u_size - 1)), u_face), 0).r;
}

float smaller(float a, float b)
{
    return abs(a) < abs(b) ? a : b;
}

void main()
{
    ivec2 h = ivec2(gl_FragCoord.xy) * 2;
    ivec2 t0 = h;
    float z = -1.0;
    for (int k = 0; k < 4; k++) {
        ivec2 t = clamp(h + ivec2(k & 1, k >> 1), ivec2(0), ivec2(u_size - 1));
        float v = fetch(t);
        if (v < u_far && v > z) {
            z = v;
            t0 = t;
        }
    }
    if (z < 0.0) {
        o_blocker = vec4(0.0);
        return;
    }
    vec2 slope = vec2(smaller(fetch(t0 + ivec2(1, 0)) - z, z - fetch(t0 - ivec2(1, 0))),
                      smaller(fetch(t0 + ivec2(0, 1)) - z, z - fetch(t0 - ivec2(0, 1))));
    float radius = u_directional != 0 ? u_radius * z / u_texel
                                      : u_radius * max(z - u_near, 0.0) / (z * u_near * u_texel);
    radius = clamp(radius, 1.0, BLOCKER_MAX_RADIUS);
    float tol = 3.0 * (u_directional != 0 ? u_texel : u_texel * z) + 0.002;
    float sum = 0.0, count = 0.0;
    for (int k = 0; k < BLOCKER_TAPS; k++) {
        float r = radius * sqrt((float(k) + 0.5) / float(BLOCKER_TAPS));
        float a = float(k) * GOLDEN_ANGLE;
        vec2 off = r * vec2(cos(a), sin(a));
        ivec2 t = t0 + ivec2(round(off));
        if (any(lessThan(t, ivec2(0))) || any(greaterThanEqual(t, ivec2(u_size))))
            continue; // beyond the face: no continuation of the receiver to compare with
        float s = texelFetch(u_shadow, ivec3(t, u_face), 0).r;
        float plane = z + dot(slope, round(off));
        if (s + tol < plane) {
            sum += s;
            count += 1.0;
        }
    }
    o_blocker = vec4(count > 0.0 ? sum / count : 0.0, 0.0, 0.0, 1.0);
}
