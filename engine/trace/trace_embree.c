/* trace_embree.c — the Embree photon trace (trace_method.h, "photon_trace": "embree"; 003 §3
 * step 2: bounces after the first traced on the CPU): every bounce ray is rt_intersect's
 * closest hit in the scene rt.c keeps posed, cast four at a time (rtcIntersect4 packets,
 * intersect_n). Nothing to prepare, no buffers, no counts. Also the table of photon-trace
 * methods. */
#include "trace_method.h"

#include <stddef.h>

static eng_result embree_create(const eng_settings *s, void **state, eng_error *err)
{
    (void)s;
    (void)err;
    *state = NULL;
    return ENG_OK;
}

static eng_result embree_prepare(void *state, const eng_rt *rt, const eng_frame_scene *fs, pt_tracer *tracer,
                                 eng_error *err)
{
    (void)state;
    (void)fs;
    (void)err;
    tracer->intersect = pt_embree_intersect;
    tracer->intersect_n = pt_embree_intersect_n;
    tracer->state = rt;
    return ENG_OK;
}

static int embree_buffer(const void *state, int index, eng_buffer *out)
{
    (void)state;
    (void)index;
    (void)out;
    return 0;
}

static void embree_frame_info(const void *state, eng_frame_stats *stats)
{
    (void)state;
    stats->trace_maps = 0;
}

static void embree_destroy(void *state) { (void)state; }

const pt_method pt_embree_method = {
    .name = "embree",
    .create = embree_create,
    .prepare = embree_prepare,
    .buffer = embree_buffer,
    .frame_info = embree_frame_info,
    .destroy = embree_destroy,
};
