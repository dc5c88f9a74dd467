/* indirect.h — one interface for the indirect-light methods: each turns the eye
 * G-buffer and the photon map into the photon estimate of Eq. 1 (003_… §5) at every pixel,
 * one file each, chosen by the `indirect` setting:
 *
 *   ind_scatter.c     "ispm"         photon volumes rasterised (003 §5)
 *   ind_quads.c       "quads"        camera-independent photon quads (001 §3.3)
 *   ind_tilegather.c  "tile-gather"  screen tiles, each evaluating its photon list (002 §6.3)
 *   ind_tilegather_gl.c "tile-gather-gl" the same lists evaluated in a GL compute shader (002 §6.3)
 *   ind_kdgather.c        "kd-gather"    per-pixel k-d tree gather, the baseline (003 App. A)
 *   ind_finalgather.c "final-gather" the k-d gather one bounce away, at the surfaces that rays
 *                                    from each pixel meet: final gathering (003 App. A)
 *
 * The frame loop (engine.c) only sees this table: it creates the method once, runs it once
 * per frame, announces the returned target's attachments under the method's buffer prefix
 * by walking ind_radiance_outputs (`<prefix>.indirect`/`.count`) or, in irradiance mode,
 * ind_irradiance_outputs (`.irradiance`/`.count`/`.glossy`), and any extra buffers the method lists, and times it as the method's pass. Methods of other
 * kinds (photon trace, eye specular) follow the same pattern in their own headers. */
#ifndef ISPM_INDIRECT_H
#define ISPM_INDIRECT_H

#include "passes.h"

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
     * stage calls it on the overlap worker with 2+ threads. */
    void (*reserve)(void *state, size_t photons, int threads);
    /* 1: the estimate at a pixel comes from rays traced from it (final-gather), not from photon
     * kernels evaluated there, so the boundary correction (boundary.h) has nothing to correct
     * and the engine refuses it; 0 for the kernel methods. */
    int traced_gather;
    /* Optional, NULL for none: 1 when, under settings s, a run's result depends on earlier
     * frames (the method keeps a history, as temporal accumulation does). The engine then
     * renders frames in order (rebuilding the history for a frame asked out of order) and calls
     * reset wherever it restarts the temporal state. */
    int (*history)(const eng_settings *s);
    void (*reset)(void *state);
} ind_method;

/* What the frame loop announces of a method's target (ind_output), <m> its prefix: radiance
 * mode, and irradiance mode (the reconstruction filters). */
extern const pass_output ind_radiance_outputs[];
extern const pass_output ind_irradiance_outputs[];

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

/* The registry (registry.c): the method named `name` (the `indirect` setting's value), or NULL
 * for "none" and for a name no method has; and the methods in order, for the bench and tests. */
const ind_method *ind_method_find(const char *name);
int ind_method_count(void);
const ind_method *ind_method_at(int i); /* NULL past the last */

/* CPU helpers shared by the CPU methods (ind_kdgather.c, ind_finalgather.c). ------------------- */

/* What a CPU method that writes per-pixel images keeps between frames (ind_kdgather.c,
 * ind_finalgather.c): its target, the G-buffer read back and the w×h×4 output images, glossy
 * in irradiance mode only. */
typedef struct ind_cpu_state {
    int width, height, irradiance;
    glu_cpu_target target;
    glu_gbuffer gb;
    float *out, *glossy;
} ind_cpu_state;
/* ENG_ERR_NOMEM naming `method` when the images cannot be allocated. */
eng_result ind_cpu_state_init(ind_cpu_state *c, const char *method, int width, int height, int irradiance,
                              eng_error *err);
void ind_cpu_state_free(ind_cpu_state *c);
/* Uploads out (and glossy) into the target and points o at it, no extra buffers. */
void ind_cpu_state_output(ind_cpu_state *c, ind_output *o);

/* Photon volumes (ind_scatter_splat.c, ISPM §5): accumulates Eq. 1 of every photon into an RGBA32F
 * target (RGB radiance, A = number of kernels covering the pixel), depth-tested against the
 * eye G-buffer's depth buffer. */
typedef struct pass_splat pass_splat;
/* irradiance = 0: one attachment, RGB outgoing radiance (splat.frag.glsl). irradiance = 1:
 * for the reconstruction filters, two attachments: 0 irradiance RGB + count, 1 the glossy
 * radiance (splat_irradiance.frag.glsl). width×height must be the G-buffer's it runs against.
 * aniso: NULL, or the anisotropic kernel's 4 floats per photon (indirect.h, ind_input). */
eng_result pass_splat_create(int width, int height, int irradiance, pass_splat **out, eng_error *err);
/* Per-pixel radius scales (w×h, top row first, each ≤ 1) the next pass_splat_run applies to
 * every photon's r_xy and r_z at that pixel (progressive photon mapping's per-pixel radius,
 * progressive.h); NULL: none (the default). */
void pass_splat_set_pixel_scale(pass_splat *p, const float *scale);
/* Grows the pass's CPU arrays to n photons and builds its index data, calling no GL (so the
 * photon stage may call it on the overlap worker once the map's size is known; pass_splat_run
 * grows the GL buffers to match). prefault: touch the new arrays now, so that their page faults
 * are taken on the calling thread rather than when the GL thread fills them. */
void pass_splat_reserve(pass_splat *p, size_t n, int prefault);
const glu_target *pass_splat_run(pass_splat *p, const eng_frame_scene *fs, const glu_target *gbuf,
                                 const eng_photon_map *map, const float *radius,
                                 const float *aniso, const eng_settings *s);
void pass_splat_destroy(pass_splat *p);

/* Where photon volumes can reach the G-buffer (ind_scatter_bounds.c): per SPLAT_TILE² tile of the
 * eye G-buffer, the bounding box of its surface points. position: width×height RGBA (xyz, w
 * = coverage; w = 0 pixels are background and left out), GL row order (bottom row first).
 * A zero-initialised splat_tiles is empty; build (re)allocates. */
#define SPLAT_TILE 8
#define SPLAT_COARSE 4 /* tiles per side of a coarse tile */
typedef struct splat_tiles {
    int width, height, tiles_x, tiles_y, coarse_x, coarse_y;
    float *box;    /* per tile, rows bottom first: min xyz, max xyz; min > max without surface */
    float *coarse; /* the same per coarse tile */
} splat_tiles;
void splat_tiles_build(splat_tiles *t, const float *position, int width, int height);
void splat_tiles_free(splat_tiles *t); /* accepts NULL */

/* A photon volume as drawn: inclusive pixel rectangle in GL window coordinates (x right, y up
 * from the bottom row) and the NDC depth of its far side. */
typedef struct splat_bounds {
    int x0, y0, x1, y1;
    float z;
} splat_bounds;
/* Whether the kernel of a photon at x (surface normal n, radii r_xy ≥ r_z) can reach a pixel
 * of t's G-buffer seen through view_proj (proj: its projection part), and if so the
 * rectangle that holds every such pixel (returns 1), else 0. Conservative: every pixel whose
 * G-buffer point lies in the kernel's support (t < 1 in Eq. 2, as the shaders evaluate it in
 * float) is inside the rectangle. */
int splat_photon_bounds(const float view_proj[16], const float proj[16], const splat_tiles *t, const float x[3],
                        const float n[3], float r_xy, float r_z, splat_bounds *out);

/* The final gather's reuse test (ind_finalgather.c), for its tests. fg_reproject: the pixel of a
 * w×h image (top row first) onto which view_proj projects world point p; 0 when p is behind the
 * camera or off the image. fg_same_surface: whether G-buffer samples (position with coverage,
 * normal, albedo, material) p and q show the same surface: q covered, the same albedo and
 * material bits, normals within 0.9 and positions within `tolerance` metres. */
int fg_reproject(const float view_proj[16], int w, int h, const float p[3], int *x, int *y);
int fg_same_surface(const float p[4], const float n[3], const float alb[3], const float mat[4], const float q[4],
                    const float nq[3], const float albq[3], const float matq[4], float tolerance);

/* k-d tree gather (ind_kdgather.c), the traditional photon mapping baseline (003_… Appendix A):
 * outgoing indirect radiance at each eye G-buffer pixel from the photons of `map` whose
 * kernel reaches the pixel's surface point, with the same kernel (splat_kernel, splat_radius,
 * s->kernel_radius, s->normal_compression) and the same BSDF as shaders/splat.frag.glsl, so
 * that it matches the photon-volume scatter up to float rounding. Inputs are w×h images, top
 * row first: position (x,y,z, coverage; coverage 0 = background), normal (x,y,z), albedo
 * (r,g,b), material (roughness, metallic, transmission, ior). out gets w×h×4 floats: radiance
 * R,G,B and the number of photons whose kernel covers the pixel. Multi-threaded (s->threads),
 * bit-identical for any thread count. */
eng_result kd_gather(const eng_photon_map *map, int w, int h, const float *position, const float *normal,
                     const float *albedo, const float *material, const float eye[3], const eng_settings *s,
                     float *out, eng_error *err);

#endif
