/* indirect.h — one interface for the indirect-light methods (issue 12): each turns the eye
 * G-buffer and the photon map into the photon estimate of Eq. 1 (003_… §5) at every pixel,
 * one file each, chosen by the `indirect` setting:
 *
 *   ind_scatter.c     "ispm"         photon volumes rasterised (003 §5)
 *   ind_quads.c       "quads"        camera-independent photon quads (001 §3.3)
 *   ind_tilegather.c  "tile-gather"  screen tiles, each evaluating its photon list (002 §6.3)
 *   ind_tilegather_gl.c "tile-gather-gl" the same lists evaluated in a GL compute shader (002 §6.3)
 *   kdgather.c        "kd-gather"    per-pixel k-d tree gather, the baseline (003 App. A)
 *   ind_finalgather.c "final-gather" the k-d gather one bounce away, at the surfaces that rays
 *                                    from each pixel meet: final gathering (003 App. A)
 *
 * The frame loop (engine.c) only sees this table: it creates the method once, runs it once
 * per frame, announces the returned target's attachments under the method's buffer prefix
 * (`<prefix>.indirect`/`.count`, or `.irradiance`/`.count`/`.glossy` in irradiance mode) and
 * any extra buffers the method lists, and times it as the method's pass. Methods of other
 * kinds (photon trace, eye specular) follow the same pattern in their own headers. */
#ifndef ISPM_INDIRECT_H
#define ISPM_INDIRECT_H

#include "eng_internal.h"

/* What a method is given each frame. */
typedef struct ind_input {
    const eng_frame_scene *fs;   /* camera (eye, view_proj) */
    const glu_target *gbuf;      /* eye G-buffer at the method's resolution (pass_gbuffer layout) */
    const eng_photon_map *map;
    const float *radius;         /* per photon: kernel radius r_xy (m), r_z = normal_compression·r_xy;
                                  * the engine computes it once per frame (ind_photon_radii) */
    const eng_settings *s;
    const float *aniso;          /* NULL (isotropic), or per photon 4 floats: the anisotropic kernel's
                                  * stretch vector and s_u (gather_kernel.h, gk_aniso_of; 002 Eq.
                                  * 6.3–6.5); its support reaches s_u·r_xy from the photon */
    const float *pixel_scale;    /* NULL, or per eye pixel (top row first) a factor ≤ 1 on every
                                  * photon's r_xy (and reach) when evaluated at that pixel:
                                  * progressive photon mapping's per-pixel radius (progressive.h,
                                  * `"progressive_radius": "pixel"`); only for methods whose
                                  * per_pixel_radius is 1 */
    /* For methods that trace rays from the eye's surfaces (final-gather): the Embree scene
     * posed for this frame, the random maps and how this frame reads them (rmap_frame). */
    const eng_rt *rt;
    const eng_random_maps *rm;
    const eng_rmap_frame *rf;
} ind_input;

/* A CPU-side buffer a method wants announced besides its target (e.g. gather.tile_count). */
#define IND_MAX_EXTRA 2
typedef struct ind_extra {
    const char *name; /* full buffer name */
    int width, height, channels;
    const char *const *channel_names;
    const float *data; /* top row first, owned by the method until its next run */
} ind_extra;

/* What it returns: a target of its own whose attachment 0 holds RGB and, in A, the number of
 * kernels that reached the pixel. Radiance mode: RGB = outgoing radiance (W/m²/sr).
 * Irradiance mode (the reconstruction filters): RGB = Σ Φ_i κ (W/m², no BSDF) and attachment
 * 1 the glossy radiance (002 §7.4). */
typedef struct ind_output {
    const glu_target *target;
    int extra_count;
    ind_extra extra[IND_MAX_EXTRA];
} ind_output;

typedef struct ind_method {
    const char *name;   /* the `indirect` setting's value */
    const char *prefix; /* buffer name prefix: "splat", "gather", "quads" */
    const char *pass;   /* pass name in the timings */
    /* width×height: the G-buffer it will run against; irradiance: see ind_output. */
    eng_result (*create)(int width, int height, int irradiance, void **state, eng_error *err);
    eng_result (*run)(void *state, const ind_input *in, ind_output *out, eng_error *err);
    void (*destroy)(void *state); /* accepts NULL */
    int per_pixel_radius; /* 1: run honours ind_input.pixel_scale (all but tile-gather-gl) */
    /* Optional, NULL for none: makes room for `photons` map photons, calling no GL; the photon
     * stage calls it on the overlap worker with 2+ threads (issue 22 item 3). */
    void (*reserve)(void *state, size_t photons, int threads);
    /* 1: the estimate at a pixel comes from rays traced from it (final-gather), not from photon
     * kernels evaluated there, so the boundary correction (boundary.h) has nothing to correct
     * and the engine refuses it; 0 for the kernel methods. */
    int traced_gather;
} ind_method;

extern const ind_method ind_scatter_method;
extern const ind_method ind_quads_method;
extern const ind_method ind_tilegather_method;
extern const ind_method ind_tilegather_gl_method;
extern const ind_method ind_kdgather_method;
extern const ind_method ind_finalgather_method;

/* Fills radius[i] (map->count floats) with photon i's kernel radius r_xy under the
 * `kernel_scaling` setting: path-density (ISPM §4.3, splat_radius), ray-length (002 Eq. 6.1),
 * tile-density (002 Eq. 6.2; needs the camera of fs and the width×height image) or bandwidth
 * (004 §6), each in [kernel_radius/4, 2·kernel_radius] ("anisotropic" takes path-density's and
 * changes the shape: ind_photon_aniso), then times `scale` (progressive
 * photon mapping's shrinking radius; 1 otherwise). Every method reads this array, so a kernel
 * scaling is defined in one place for all of them. Single-threaded: the same for any thread
 * count. */
void ind_photon_radii(const eng_photon_map *map, const eng_settings *s, const eng_frame_scene *fs, int width,
                      int height, float scale, float *radius);

/* `"kernel_scaling": "anisotropic"`: fills aniso (4 floats per photon, gk_aniso_of) and returns 1;
 * any other scaling: returns 0 and leaves aniso alone (the kernel is isotropic). */
int ind_photon_aniso(const eng_photon_map *map, const eng_settings *s, float *aniso);

/* How far each photon's kernel reaches: in->radius when in->aniso is NULL, else s_u·r_xy per
 * photon in *buf (grown to *cap floats as needed). For a method's culling. */
const float *ind_reach(const ind_input *in, float **buf, size_t *cap);

/* The method of a setting, or NULL for ENG_INDIRECT_NONE. */
const ind_method *ind_method_of(eng_indirect m);

/* CPU helpers shared by the CPU methods (kdgather.c). ------------------------------------ */

/* A CPU method's output target: 1 or 2 RGBA32F attachments of w×h. */
typedef struct ind_cpu_target {
    glu_target target;
    float *upload; /* w×h×4 scratch for flipping rows */
} ind_cpu_target;
eng_result ind_cpu_target_create(ind_cpu_target *t, int width, int height, int irradiance, eng_error *err);
void ind_cpu_target_destroy(ind_cpu_target *t);
/* Uploads w×h RGBA (top row first) into attachment `index`. */
void ind_cpu_target_upload(ind_cpu_target *t, int index, const float *rgba);

/* The eye G-buffer read back for a CPU method: top row first. */
typedef struct ind_gbuffer {
    int width, height;
    float *position; /* 4 per pixel, w = coverage */
    float *normal;   /* 3 */
    float *albedo;   /* 3 */
    float *material; /* 4: roughness, metallic, transmission, ior */
} ind_gbuffer;
void ind_gbuffer_read(const glu_target *gb, ind_gbuffer *out); /* (re)allocates out's arrays */
void ind_gbuffer_free(ind_gbuffer *g);

/* What a CPU method that writes per-pixel images keeps between frames (kdgather.c,
 * ind_finalgather.c): its target, the G-buffer read back and the w×h×4 output images, glossy
 * in irradiance mode only. */
typedef struct ind_cpu_state {
    int width, height, irradiance;
    ind_cpu_target target;
    ind_gbuffer gb;
    float *out, *glossy;
} ind_cpu_state;
/* ENG_ERR_NOMEM naming `method` when the images cannot be allocated. */
eng_result ind_cpu_state_init(ind_cpu_state *c, const char *method, int width, int height, int irradiance,
                              eng_error *err);
void ind_cpu_state_free(ind_cpu_state *c);
/* Uploads out (and glossy) into the target and points o at it, no extra buffers. */
void ind_cpu_state_output(ind_cpu_state *c, ind_output *o);

#endif
