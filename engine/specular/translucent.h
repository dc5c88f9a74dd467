/* translucent.h — alphaMode BLEND surfaces (003_d0bf8e920b03f4e1.txt §3 step
 * 5: translucent surfaces are rendered back to front after the opaque passes and receive
 * direct, mirror and refracted light only). pass_translucent.c. */
#ifndef ISPM_TRANSLUCENT_H
#define ISPM_TRANSLUCENT_H

#include "eye_tracer.h"

/* One translucent surface a pixel's eye ray crosses in front of the opaque surface. */
typedef struct tl_layer {
    float t;            /* distance along the eye ray */
    float alpha;        /* coverage: baseColorFactor alpha × texture alpha (glTF §3.9.4), in [0, 1] */
    float radiance[3];  /* what it sends toward the eye */
} tl_layer;

/* Sorts layers back to front (largest t first; equal t: the later index first, so the order is
 * total) and composites them with "over" (Porter & Duff 1984) into premultiplied rgba:
 * rgb = Σ_i α_i L_i Π_{j in front of i} (1 − α_j), a = 1 − Π_i (1 − α_i); the final image is
 * rgb + (1 − a)·opaque. n = 0 gives (0, 0, 0, 0). */
void tl_composite(tl_layer *layers, int n, float rgba[4]);

/* Does any draw of the scene use an alphaMode BLEND material? */
int tl_scene_has_blend(const scn_scene *scene);

/* The CPU work of the pass, for tests: w×h premultiplied RGBA (top row first) of the BLEND
 * surfaces in front of position (the eye G-buffer's, 4 per pixel, w = coverage; NULL: no opaque
 * surface), with s->threads threads (bit-identical for any count). */
eng_result tl_render(const eng_frame_scene *fs, const eng_rt *rt, const float *position, int w, int h,
                     const eng_photon_map *map, const float *radius, const eng_settings *s, float *rgba, eng_error *err);

typedef struct pass_translucent pass_translucent;
eng_result pass_translucent_create(int width, int height, pass_translucent **out, eng_error *err);
/* The frame's translucent layer: per pixel, the BLEND surfaces between the near plane and the
 * eye G-buffer's opaque surface (rt_intersect_blend), each shaded by eye_tracer_translucent,
 * composited back to front. *rgba: w×h×4 premultiplied, top row first (translucent.radiance);
 * *tex: the same as a texture for the composite. map/radius: the photon map the mirror and
 * refracted branches gather from (NULL: direct light only there). */
eng_result pass_translucent_run(pass_translucent *p, const eng_frame_scene *fs, const eng_rt *rt,
                                const glu_target *gbuf, const eng_photon_map *map, const float *radius,
                                const eng_settings *s, const float **rgba, GLuint *tex, eng_error *err);
void pass_translucent_destroy(pass_translucent *p); /* accepts NULL */

#endif
