/* shadow.h — one interface for the shadow methods, one file each, chosen per
 * light by its size (scn_light.radius):
 *
 *   shadow_pcf.c   "pcf"   hard shadows, percentage-closer filtering (shaders/shadow_pcf.glsl);
 *                          lights without a size
 *   shadow_pcss.c  "pcss"  soft shadows of lights with a size, by the setting pcss_blocker:
 *                          "map", blocker search in the shadow map, penumbra from the light's
 *                          size (001 §3.4 Eq. 2–5), filtered lookup of that width; "rays",
 *                          rays to points of the light marched through the shadow map
 *                          (shaders/shadow_pcss.glsl)
 *
 * The frame loop (engine.c) creates every method once, runs the method of each light after
 * that light's shadow map, announces the map it returns through the method's output table
 * (passes.h; `shadow.light<i>[.face<f>].<name>`) and hands them to the direct pass, which
 * binds them and lets the shader pick the method by u_light_radius (0: pcf) and u_pcss_rays. */
#ifndef ISPM_SHADOW_H
#define ISPM_SHADOW_H

#include "passes.h"

typedef struct shadow_method {
    const char *name;
    const pass_output *outputs; /* what the frame loop announces of the map run returns, or NULL */
    const char *pass;   /* pass name in the timings, or NULL */
    /* s: the run's settings (shadow_map_size, pcss_blocker), read once here. */
    eng_result (*create)(const eng_settings *s, uint32_t light_count, void **state, eng_error *err);
    /* After light `light`'s shadow map sm: the method's own map of it (one layer per face,
     * attachment 0, channel R), or NULL when it needs none; NULL with *failed set on a GL
     * failure. */
    const glu_target *(*run)(void *state, const eng_light_pose *l, const shadow_map *sm, uint32_t light,
                             int *failed);
    void (*destroy)(void *state); /* accepts NULL */
} shadow_method;

extern const shadow_method shadow_pcf_method;
extern const shadow_method shadow_pcss_method;

#define SHADOW_METHOD_COUNT 2
extern const shadow_method *const shadow_methods[SHADOW_METHOD_COUNT];

/* The registry (shadow_registry.c): the index in shadow_methods of the method named `name`, or
 * -1; and the method of a light, by name: "pcss" when it has a size, "pcf" otherwise. */
int shadow_method_find(const char *name);
int shadow_method_index(const eng_light_pose *l);

/* Penumbra radius in shadow-map texels (001 §3.4 Eq. 5, R_g = L·d/(D−d), in map texels
 * instead of pixels; shaders/shadow_pcss.glsl computes the same): light radius r (m; tan of
 * the angular radius for directional lights), receiver and blocker distances from the light
 * (depths along the light for directional lights), texel the map's texel size at unit
 * distance (absolute for directional lights). Not clamped. */
float shadow_penumbra_texels(int directional, float r, float receiver, float blocker, float texel);

/* Blocker search radius in texels for a texel at distance z (001 §3.4 Eq. 2 in the map; see
 * shaders/blocker.frag.glsl), before its clamp to [1, 48]. near: nearest occluder distance. */
float shadow_search_texels(int directional, float r, float z, float near, float texel);

/* The blocker search of shaders/blocker.frag.glsl on the CPU, for the unit tests and
 * tools: map is size×size metric values (row-major), far_value marks empty texels; returns
 * the average occluder depth at texel (hx, hy) of the half-resolution blocker map (shadow
 * texels 2hx..2hx+1, 2hy..2hy+1), 0 when there is none. */
float shadow_blocker_cpu(const float *map, int size, float far_value, int directional, float r, float near,
                         float texel, int hx, int hy);

/* The rays of pcss_blocker "rays" (shaders/shadow_pcss.glsl) on the CPU, for an ortho map
 * (a directional light of tan α = r whose disc's axes are the map's x and y): map is size×size
 * depths from the box's near plane (row-major), texel the texel's world size, bias the shadow
 * bias; the receiver at texel position (x, y) (continuous) and depth value (its normal offset
 * applied); the spiral of rays turned by the hash of texel (floor(x), floor(y)) as the shader
 * turns it. Returns the unblocked share of the rays, 0..1 in steps of 1/16. */
float shadow_rays_cpu(const float *map, int size, float r, float texel, float bias, float x, float y, float value);

#endif
