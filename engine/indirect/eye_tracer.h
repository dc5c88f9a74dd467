/* eye_tracer.h — eye paths continued on the CPU through specular surfaces (mirrors, glass),
 * with the photon map gathered where they end: the "traced" specular method's work per pixel,
 * the final gather's per ray, and translucency's per blended surface. */
#ifndef ISPM_EYE_TRACER_H
#define ISPM_EYE_TRACER_H

#include "indirect.h"

/* Does material m have a delta lobe of non-zero weight (a mirror, or glass)? */
int eye_is_specular(const scn_material *m);
/* Does any primitive of the scene use such a material? */
int eye_scene_has_specular(const scn_scene *scene);

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
typedef struct eye_branch {
    float dir[3];
    float weight[3];
    float eta; /* the medium the branch travels in */
} eye_branch;
int eye_split(const scn_material *m, const float n[3], const float wi[3], float eta, eye_branch out[2]);

/* The traced method's work for one eye G-buffer pixel, for tests: the surface point p with
 * authored normal n and material m seen from eye; adds nothing where m has no delta lobe.
 * Returns the radiance through its delta lobes, the depth and the throughput (spec_output).
 * map may be NULL (direct light only at the surfaces reached). */
typedef struct eye_tracer eye_tracer;
typedef struct eye_scratch {
    uint32_t *list; /* k-d range results; grown with realloc, the caller frees it */
    size_t cap;
} eye_scratch;
eye_tracer *eye_tracer_create(const eng_frame_scene *fs, const eng_rt *rt, const eng_photon_map *map,
                                const float *radius, const eng_settings *s, eng_error *err);
void eye_tracer_pixel(const eye_tracer *t, const float p[3], const float n[3], const scn_material *m,
                       const float eye[3], eye_scratch *scratch, float radiance[3], float *depth,
                       float throughput[3]);
void eye_tracer_destroy(eye_tracer *t); /* accepts NULL */
/* Radiance arriving at org from unit direction −dir, found the way eye_tracer_pixel finds it
 * (the ray counts as having crossed one specular surface), passing through the draw
 * skip_draw until it meets another surface (UINT32_MAX: none). For the envmap method. */
/* What a translucent (alphaMode BLEND) surface at hit h with material m sends toward the eye
 * (pass_translucent.c; 003 §3 step 5: direct, mirror and refracted light only): direct light
 * through its non-specular lobes (shadow rays, no photon gather), its emission, and what its
 * delta lobes reflect and refract (as eye_tracer_pixel, photons gathered where they end). */
void eye_tracer_translucent(const eye_tracer *t, const rt_hit *h, const scn_material *m, const float eye[3],
                             eye_scratch *sc, float radiance[3]);
void eye_tracer_ray(const eye_tracer *t, const float org[3], const float dir[3], uint32_t skip_draw,
                     eye_scratch *sc, float radiance[3]);
/* Radiance arriving at org from unit direction −dir along a ray that leaves a diffuse or glossy
 * lobe at org (the final gather, ind_finalgather.c): found as eye_tracer_ray finds it, but the
 * emitters met add nothing (an emitter is seen only after delta lobes: reference.c). */
void eye_tracer_gather_ray(const eye_tracer *t, const float org[3], const float dir[3], eye_scratch *sc,
                            float radiance[3]);

#endif
