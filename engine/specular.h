/* specular.h — one interface for what the eye sees in and through specular surfaces
 * (issue 14; 003_d0bf8e920b03f4e1.txt §3 step 5 and its discussion of the options), one file
 * per method, chosen by the `specular` setting:
 *
 *   spec_traced.c   "traced"  eye rays continued on the CPU with Embree (003 §3, option 1)
 *   spec_envmap.c   "envmap"  a cube map per specular object, made at its centre every frame,
 *                             looked up by the reflected/refracted direction (003 §3, option 3)
 *   (none)          "off"     specular surfaces show only their non-specular lobes
 *
 * A surface is specular where the material has a delta lobe, the same rule the photon tracer
 * and the reference renderer use (bsdf.c): a metal with roughness below BSDF_MIRROR_ROUGHNESS
 * (0.01, shaders/bsdf_constants.glsl) is a perfect mirror, and any transmission is smooth
 * glass (bsdf.c has no rough dielectric). The passes that shade the G-buffer (direct light,
 * the indirect method) already give such a pixel its non-specular lobes; a specular method
 * adds only what the delta lobes reflect and refract toward the eye, which the composite adds
 * as `specular.radiance`.
 *
 * The frame loop (engine.c) runs the method only when some material of the scene is specular
 * (spec_scene_has_specular): a scene without one renders and announces exactly what it did
 * before the method existed. */
#ifndef ISPM_SPECULAR_H
#define ISPM_SPECULAR_H

#include "eng_internal.h"
#include "indirect.h"

/* What a method is given each frame. */
typedef struct spec_input {
    const eng_frame_scene *fs;
    const eng_rt *rt;          /* posed for this frame */
    const glu_target *gbuf;    /* the eye G-buffer (pass_gbuffer layout) */
    const eng_photon_map *map; /* the frame's photon map; NULL with indirect "none" */
    const float *radius;       /* per photon r_xy, as the indirect method uses them */
    const eng_settings *s;
} spec_input;

/* What it returns: w×h images, top row first, owned by the method until its next run, and a
 * texture (attachment 0 of target: RGB radiance) for the composite. */
typedef struct spec_output {
    const glu_target *target;
    const float *radiance;   /* 3 per pixel: radiance reaching the eye via the delta lobes (W/m²/sr) */
    const float *depth;      /* 1: the most specular surfaces one branch of the pixel crossed */
    const float *throughput; /* 3: Σ over the non-specular surfaces reached of the weight they are seen with
                              * (envmap: Σ of the weights of the branches looked up) */
} spec_output;

typedef struct spec_method {
    const char *name; /* the `specular` setting's value */
    eng_result (*create)(int width, int height, void **state, eng_error *err);
    eng_result (*run)(void *state, const spec_input *in, spec_output *out, eng_error *err);
    void (*destroy)(void *state); /* accepts NULL */
} spec_method;

extern const spec_method spec_traced_method;
extern const spec_method spec_envmap_method;

/* The method of a setting, or NULL for "off". */
const spec_method *spec_method_of(eng_specular m);

/* Does material m have a delta lobe of non-zero weight (a mirror, or glass)? */
int spec_is_specular(const scn_material *m);
/* Does any primitive of the scene use such a material? */
int spec_scene_has_specular(const scn_scene *scene);

/* The delta lobes of material m at a surface with authored (outward, unoriented) unit normal n,
 * seen from unit direction wi (toward the viewer), the viewer in a medium of index eta. Both
 * branches with their weights, no random choice (so the image has no noise):
 *   reflect  ω = reflect(wi, n_s), weight = metallic·F_Schlick(F0 = base colour, cos θi)
 *            (metal below BSDF_MIRROR_ROUGHNESS) + (1 − metallic)·transmission·R,
 *   refract  ω = −e·wi + (e·cosθi − cosθt)·n_s, e = n1/n2, weight =
 *            (1 − metallic)·transmission·(1 − R)·base colour, medium n2,
 * with R the exact dielectric Fresnel reflectance (bsdf_fresnel_dielectric; 002_… §4.5),
 * entering (n1 = eta, n2 = ior) when wi is on n's side, leaving (n1 = ior, n2 = 1) otherwise;
 * R = 1 under total internal reflection, so there is no refracted branch. These are the
 * weights with which bsdf_scatter picks the same lobes (bsdf.c), so a path's expected weight
 * in the photon tracer and the reference is the branch weight here. Returns the number of
 * branches (0..2) written to out, zero-weight ones left out. */
typedef struct spec_branch {
    float dir[3];
    float weight[3];
    float eta; /* the medium the branch travels in */
} spec_branch;
int spec_split(const scn_material *m, const float n[3], const float wi[3], float eta, spec_branch out[2]);

/* The traced method's work for one eye G-buffer pixel, for tests: the surface point p with
 * authored normal n and material m seen from eye; adds nothing where m has no delta lobe.
 * Returns the radiance through its delta lobes, the depth and the throughput (spec_output).
 * map may be NULL (direct light only at the surfaces reached). */
typedef struct spec_tracer spec_tracer;
typedef struct spec_scratch {
    uint32_t *list; /* k-d range results; grown with realloc, the caller frees it */
    size_t cap;
} spec_scratch;
spec_tracer *spec_tracer_create(const eng_frame_scene *fs, const eng_rt *rt, const eng_photon_map *map,
                                const float *radius, const eng_settings *s, eng_error *err);
void spec_tracer_pixel(const spec_tracer *t, const float p[3], const float n[3], const scn_material *m,
                       const float eye[3], spec_scratch *scratch, float radiance[3], float *depth,
                       float throughput[3]);
void spec_tracer_destroy(spec_tracer *t); /* accepts NULL */
/* Radiance arriving at org from unit direction −dir, found the way spec_tracer_pixel finds it
 * (the ray counts as having crossed one specular surface), passing through the draw
 * skip_draw until it meets another surface (UINT32_MAX: none). For the envmap method. */
/* What a translucent (alphaMode BLEND) surface at hit h with material m sends toward the eye
 * (pass_translucent.c; 003 §3 step 5: direct, mirror and refracted light only): direct light
 * through its non-specular lobes (shadow rays, no photon gather), its emission, and what its
 * delta lobes reflect and refract (as spec_tracer_pixel, photons gathered where they end). */
void spec_tracer_translucent(const spec_tracer *t, const rt_hit *h, const scn_material *m, const float eye[3],
                             spec_scratch *sc, float radiance[3]);
void spec_tracer_ray(const spec_tracer *t, const float org[3], const float dir[3], uint32_t skip_draw,
                     spec_scratch *sc, float radiance[3]);
/* Radiance arriving at org from unit direction −dir along a ray that leaves a diffuse or glossy
 * lobe at org (the final gather, ind_finalgather.c): found as spec_tracer_ray finds it, but the
 * emitters met add nothing (an emitter is seen only after delta lobes: reference.c). */
void spec_tracer_gather_ray(const spec_tracer *t, const float org[3], const float dir[3], spec_scratch *sc,
                            float radiance[3]);

/* What both methods keep between frames (spec_traced.c): the G-buffer read back, the output
 * images and the texture they are uploaded to. */
typedef struct spec_buffers {
    int width, height, target_ok;
    ind_cpu_target target;
    ind_gbuffer gb;
    float *rgba, *radiance, *depth, *throughput;
} spec_buffers;
eng_result spec_buffers_create(spec_buffers *b, int width, int height, eng_error *err);
void spec_buffers_destroy(spec_buffers *b);
/* The material of G-buffer pixel i (background: nothing specular). */
void spec_buffers_material(const spec_buffers *b, size_t i, scn_material *m);
/* Uploads radiance (and depth in A) and points out at the buffers. */
void spec_buffers_finish(spec_buffers *b, spec_output *out);

#endif
