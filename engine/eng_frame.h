/* eng_frame.h — the engine's posed frame for the CPU renderers and tools above the engine
 * (the reference renderer, the trace bench): what the passes see, without rendering it. */
#ifndef ISPM_ENG_FRAME_H
#define ISPM_ENG_FRAME_H

#include "eng.h"
#include "trace.h"

/* Poses the scene at frame `frame` (t = frame / fps) exactly as eng_render_frame does (world
 * matrices, draws, lights, camera, Embree scene) without rendering anything, and returns the
 * posed scene and the Embree scene (owned by the engine; valid until the next call or
 * eng_render_frame). For CPU renderers that must see what the passes see. */
void eng_pose(eng_engine *e, int frame, const eng_frame_scene **fs, const eng_rt **rt);
const eng_settings *eng_settings_of(const eng_engine *e);
void eng_image_size(const eng_engine *e, int *width, int *height);

/* ---------------------------------------------------------------- the trace bench (cli/bench) */

/* What the photon trace of one frame gets (eng_render_frame's arguments to it). */
typedef struct eng_trace_inputs {
    const eng_rt *rt;
    const eng_frame_scene *fs;
    const eng_random_maps *rm;
    const eng_bounce_photon *in;
    size_t count;
    eng_trace_settings settings;
} eng_trace_inputs;
/* Poses frame `frame`, renders its light G-buffers and bounce maps (announced to the listeners
 * as in eng_render_frame) and fills out with the photon trace's inputs, valid until the next
 * frame. ENG_ERR_INVALID for a frame outside the sequence or without indirect light. */
eng_result eng_frame_trace_inputs(eng_engine *e, int frame, eng_trace_inputs *out, eng_error *err);

#endif
