/* specular.h — one interface for what the eye sees in and through specular surfaces
 * (003_d0bf8e920b03f4e1.txt §3 step 5 and its discussion of the options), one file
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
 * (eye_scene_has_specular): a scene without one renders and announces exactly what it did
 * before the method existed. */
#ifndef ISPM_SPECULAR_H
#define ISPM_SPECULAR_H

#include "eye_tracer.h"

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

/* The registry (registry.c): the method named `name` (the `specular` setting's value), or NULL
 * for "off" and for a name no method has; and the methods in order. */
const spec_method *spec_method_find(const char *name);
int spec_method_count(void);
const spec_method *spec_method_at(int i); /* NULL past the last */

/* What both methods keep between frames (spec_common.c): the G-buffer read back, the output
 * images and the texture they are uploaded to. */
typedef struct spec_buffers {
    int width, height, target_ok;
    glu_cpu_target target;
    glu_gbuffer gb;
    float *rgba, *radiance, *depth, *throughput;
} spec_buffers;
eng_result spec_buffers_create(spec_buffers *b, int width, int height, eng_error *err);
void spec_buffers_destroy(spec_buffers *b);
/* The material of G-buffer pixel i (background: nothing specular). */
void spec_buffers_material(const spec_buffers *b, size_t i, scn_material *m);
/* Uploads radiance (and depth in A) and points out at the buffers. */
void spec_buffers_finish(spec_buffers *b, spec_output *out);

#endif
