/* eng.h — the engine's public face: an OSMesa (or EGL) GL context and the passes, which
 * announce every buffer they produce to registered listeners. The engine knows nothing about
 * files. It includes the rooms below it that its callers need: the core (errors, buffers,
 * listeners, settings: eng_core.h), the scene (scn.h) and the sequence (seq.h). */
#ifndef ISPM_ENG_H
#define ISPM_ENG_H

#include <stddef.h>
#include <stdint.h>

#include "eng_core.h"
#include "scn.h"
#include "seq.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- engine */

typedef struct eng_engine eng_engine;

typedef struct eng_desc {
    const scn_scene *scene;      /* borrowed; must outlive the engine */
    const seq_sequence *sequence;/* borrowed */
    /* The GL context's backend (a property of the machine, not of the sequence: ispm record
     * --gl): NULL or "osmesa" (the default, the goldens' reference) or "egl". With "egl",
     * gl_use_device chooses EGL device gl_device (EGL_EXT_platform_device, --gl-device N);
     * without it Mesa's surfaceless platform. */
    const char *gl;
    int gl_use_device, gl_device;
    /* 1: also announce photons.origin (each photon's light, face, bounce-map texel and kernel
     * radius: ispm lineage, ispm record --lineage). Off by default so that runs keep their
     * buffers. */
    int lineage;
} eng_desc;

/* 1 if name is a GL backend eng_desc.gl accepts. */
int eng_gl_backend_known(const char *name);

/* Pins what follows the host's SIMD width before any GL or Embree object exists:
 * LP_NATIVE_VECTOR_WIDTH=128, GALLIUM_OVERRIDE_CPU_CAPS=sse4.1, LP_NUM_THREADS=threads,
 * Embree isa=sse2. Idempotent; eng_create calls it. */
void eng_pin_determinism(int threads);

/* Key/value pairs of the pinned settings, for the manifest. NULL-terminated array of
 * {key, value} pairs, static storage. */
const char *const *eng_determinism_info(void);

eng_result eng_create(const eng_desc *desc, eng_engine **out, eng_error *err);
void eng_destroy(eng_engine *e);

eng_result eng_add_listener(eng_engine *e, const eng_listener *l);

/* Renders frame i at t = i / fps, announcing every buffer to the listeners. Frames may be
 * rendered in any order, but motion vectors refer to frame i-1's transforms (frame 0: zero). */
eng_result eng_render_frame(eng_engine *e, int frame, eng_error *err);

/* Frame shards (ispm record --frames A-B --warmup W): the temporal state a frame rendered out
 * of order rebuilds (silently, without announcing) begins at frame first instead of frame 0,
 * so a shard's first frame renders frames first .. A-1 as its warm-up. first = 0 is the
 * default (an uninterrupted run's history). A frame before first rebuilds from frame 0. */
void eng_set_history_start(eng_engine *e, int first);

/* 1 when some pass carries state from frame to frame at these settings (temporal or
 * progressive accumulation, or an indirect method with a history, ind_method.history): a
 * frame then depends on the frames before it. */
int eng_stateful(const eng_engine *e);

/* `"exposure": "auto"` (settings.exposure_auto): frame 0 is metered at its composite
 * (eng_exposure_key over the pixels the eye G-buffer covers) and its display, like every later
 * frame's, uses the stops found; a first frame other than 0 renders frame 0 first, without
 * announcing it. eng_exposure returns 1 once frame 0 was metered (*stops gets the stops, *info
 * the metering: counted 0 and 0 stops for a frame 0 without a lit pixel), 2 when eng_set_exposure
 * gave the stops, 0 before either or for a numeric exposure (*stops then gets the setting).
 * Either pointer may be NULL. */
int eng_exposure(const eng_engine *e, float *stops, eng_exposure_key_info *info);
/* Fixes the "auto" exposure at stops recorded by an earlier run of the same sequence (record
 * --resume), so that frame 0 is not rendered again to meter it. No effect on a numeric exposure. */
void eng_set_exposure(eng_engine *e, float stops);

/* Is the segment from a to b blocked by scene geometry, as posed at the last rendered frame
 * (Embree occlusion query; the end points themselves are excluded by a small epsilon)?
 * Returns 1 blocked, 0 clear. Before the first frame the scene is at t = 0. */
int eng_occluded(eng_engine *e, const float a[3], const float b[3]);

/* GL_VERSION and GL_RENDERER of the engine's context (for the manifest). */
const char *eng_gl_version(const eng_engine *e);
const char *eng_gl_renderer(const eng_engine *e);
/* The backend's name ("osmesa", "egl") and what it runs on ("offscreen", "surfaceless",
 * "device 0 (/dev/dri/renderD128)"), for the manifest. */
const char *eng_gl_backend(const eng_engine *e);
const char *eng_gl_where(const eng_engine *e);

#ifdef __cplusplus
}
#endif

#endif
