/* ref.h — the reference renderer (reference.c): CPU ground truth for the engine's images.
 *
 * It renders the scene the engine renders (eng_pose: the same draws, lights, camera and
 * Embree scene at the same frame time) with an unbiased-in-the-limit estimator on Embree:
 * path tracing with next-event estimation to the punctual lights, combined (balance
 * heuristic) with light vertices connected to the eye path, plus probabilistic
 * progressive photon mapping for the caustic paths a path tracer cannot sample from a point
 * light. Each frame announces three buffers to its listeners, like the engine does:
 *   reference.direct    light that reached the camera after exactly one surface (the
 *                       meaning of the engine's direct.radiance)
 *   reference.indirect  everything else (the meaning of indirect.radiance)
 *   reference.full      direct + indirect
 * all RGB linear radiance in W/m²/sr, width × height of the sequence, top row first.
 *
 * Deterministic: every random number is a hash of (pixel or photon, sample, dimension, frame,
 * seed), and every sum is taken in a fixed order, so the images are bit-identical for any
 * thread count. Errors return an eng_result with a one-line message naming the file. */
#ifndef ISPM_REF_H
#define ISPM_REF_H

#include "eng.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Zero means default for every number. */
typedef struct ref_desc {
    eng_engine *engine;           /* required: made from `sequence` with indirect "none"; borrowed */
    const seq_sequence *sequence; /* required: the engine's sequence (frame rate, file name); borrowed */
    int spp;          /* samples per pixel (= photon passes); default 64 */
    int max_depth;    /* surfaces an eye path visits, and specular surfaces a caustic photon
                       * crosses before the surface it is stored on; default 64 */
    int photons;      /* caustic photons emitted per pass over all lights; default 16384 */
    float radius;     /* gather radius of the first photon pass in metres; default 1/256 of the
                       * diagonal of the scene's bounds at frame 0 */
    float alpha;      /* radius reduction of probabilistic PPM, in (0, 1); default 2/3 */
    uint32_t seed;    /* salt of every random number; default 0 (any value is as good) */
    int threads;      /* OpenMP threads; default the engine's settings.threads */
    int no_caustics;  /* 1: no photon passes (tests compare with and without) */
    int pixel_center; /* 1: every camera ray through its pixel's centre, as the engine's G-buffers
                       * sample the scene (no antialiasing: what an image-space method computes at
                       * each pixel); 0: jittered over the pixel's square (a box-filtered image) */
    int quiet;        /* 1: no progress line on stderr */
} ref_desc;

typedef struct ref_renderer ref_renderer;

/* Validates desc (ENG_ERR_INVALID with a message naming the sequence file for values out of
 * range: spp 1..1<<20, max_depth 1..256, photons 1..1<<24, radius and alpha) and fills in the
 * defaults. On failure *out is NULL. */
eng_result ref_create(const ref_desc *desc, ref_renderer **out, eng_error *err);
void ref_destroy(ref_renderer *r); /* accepts NULL */

/* Listeners see frame_begin, the three buffers, frame_end (with pass times "photons" and
 * "trace", the camera, and the caustic photons emitted/stored summed over passes), as from
 * the engine. At most 8. */
eng_result ref_add_listener(ref_renderer *r, const eng_listener *l);

/* The settings in use (defaults filled in). */
const ref_desc *ref_settings(const ref_renderer *r);

/* The settings as the text of a JSON object (for the run's manifest): spp, max_depth,
 * photons, radius, alpha, seed, caustics, estimators. Returns the length written (snprintf
 * semantics). */
int ref_settings_json(const ref_renderer *r, char *out, size_t size);

/* Renders frame `frame` (t = frame / fps) and announces its buffers. ENG_ERR_INVALID for a
 * frame outside the sequence, ENG_ERR_ABORTED when a listener refused. */
eng_result ref_render_frame(ref_renderer *r, int frame, eng_error *err);

#ifdef __cplusplus
}
#endif

#endif
