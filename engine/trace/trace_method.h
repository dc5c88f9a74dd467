/* trace_method.h — one interface for the ways photon bounces after the bounce map find their
 * next surface, one file each, chosen by the `photon_trace` setting:
 *
 *   trace_embree.c      "embree"       CPU ray tracing with Embree (003 §3 step 2, rt.c)
 *   trace_multiimage.c  "multi-image"  image space, against cube G-buffers (004 §4–5)
 *
 * The frame loop (engine.c) only sees this table: it creates the method once, calls prepare
 * once per frame after the scene is posed (a method builds what it traces against there, and
 * returns the pt_tracer photon_trace_with calls per ray, or per packet of rays), announces the
 * buffers the method lists, copies its frame info into the frame's statistics, and times
 * prepare as the method's pass when it names one. What a path does at a surface (BSDF sampling, random maps, storage)
 * is photon_trace.c's, the same for every method. */
#ifndef ISPM_TRACE_METHOD_H
#define ISPM_TRACE_METHOD_H

#include "trace.h"

typedef struct pt_method {
    const char *name; /* the `photon_trace` setting's value */
    const char *pass; /* pass name of prepare in the timings, or NULL: not timed (nothing to do) */
    eng_result (*create)(const eng_settings *s, void **state, eng_error *err);
    /* rt is posed at this frame (rt_update), fs is the frame's scene. */
    eng_result (*prepare)(void *state, const eng_rt *rt, const eng_frame_scene *fs, pt_tracer *tracer,
                          eng_error *err);
    /* Buffer `index` (0, 1, ...) to announce after prepare: returns 0 past the last one. The
     * data stays valid until the next prepare. */
    int (*buffer)(const void *state, int index, eng_buffer *out);
    /* The frame's trace_maps and trace_centres (eng_frame_stats). */
    void (*frame_info)(const void *state, eng_frame_stats *stats);
    void (*destroy)(void *state); /* accepts NULL */
} pt_method;

extern const pt_method pt_embree_method;
extern const pt_method pt_multiimage_method;

/* The registry (registry.c): the method named `name` (the `photon_trace` setting's value), or
 * NULL; and the methods in order. */
const pt_method *pt_method_find(const char *name);
int pt_method_count(void);
const pt_method *pt_method_at(int i); /* NULL past the last */

#endif
