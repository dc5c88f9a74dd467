/* trace_bench.c — the photon trace's ray rate against Embree's raw rtcIntersect1 rate on the
 * same rays in the same process (tracebench.h). The rays are recorded from a
 * one-thread trace through a recording tracer (trace_method.h's interface, ray by ray, the
 * reference the engine's trace must match bit for bit); then, alternating, the engine's photon
 * trace of the frame (photon_trace: what eng_render_frame runs for "photon_trace": "embree"; the
 * repeats after the first find the last trace's figures in the map, as a static scene's frames
 * do)
 * and rt_cast_raw over the recorded rays (rtcIntersect1, and rtcIntersect4 packets of
 * consecutive rays for comparison), each on the engine's thread count. A trace ray costs
 * more than a raw one by what the trace does around it: hit attributes (shading normal, base
 * colour), the BSDF and the photon store. */
#define _POSIX_C_SOURCE 200809L
#include "tracebench.h"

#include "eng_frame.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

typedef struct recorder {
    const eng_rt *rt;
    float *rays;
    size_t n, cap;
    int oom;
} recorder;

/* pt_intersect_fn that appends the ray to the recorder (one thread only: the recording trace
 * runs with threads = 1) and answers as the Embree tracer does. */
static int record_intersect(const void *state, const float org[3], const float dir[3], float tnear, rt_hit *hit,
                            eng_trace_counts *counts)
{
    recorder *r = (recorder *)(uintptr_t)state;
    if (r->n == r->cap && !r->oom) {
        size_t cap = r->cap ? 2 * r->cap : 65536;
        float *p = realloc(r->rays, cap * RT_RAW_FLOATS * sizeof *p);
        if (p) {
            r->rays = p;
            r->cap = cap;
        } else {
            r->oom = 1;
        }
    }
    if (r->n < r->cap) {
        float *d = r->rays + RT_RAW_FLOATS * r->n++;
        const float v[RT_RAW_FLOATS] = {org[0], org[1], org[2], dir[0], dir[1], dir[2], tnear};
        memcpy(d, v, sizeof v);
    }
    return pt_embree_intersect(r->rt, org, dir, tnear, hit, counts);
}

static int same_map(const eng_photon_map *a, const eng_photon_map *b)
{
    return a->count == b->count && (a->count == 0 || memcmp(a->photons, b->photons, a->count * sizeof *a->photons) == 0);
}

eng_result tb_run(eng_engine *e, int frame, int repeats, tb_result *out, eng_error *err)
{
    memset(out, 0, sizeof *out);
    if (repeats < 1 || repeats > TB_MAX_REPEATS)
        return eng_fail(err, ENG_ERR_INVALID, "tracebench: %d repeats outside 1..%d", repeats, TB_MAX_REPEATS);
    eng_trace_inputs ti;
    eng_result r = eng_frame_trace_inputs(e, frame, &ti, err);
    if (r != ENG_OK)
        return r;
    recorder rec = {ti.rt, NULL, 0, 0, 0};
    const pt_tracer tr = {record_intersect, &rec, NULL}; /* ray by ray, path by path */
    eng_trace_settings one = ti.settings;
    one.threads = 1;
    eng_photon_map ref = {0}, map = {0};
    r = photon_trace_with(&tr, ti.fs, ti.rm, ti.in, ti.count, &one, &ref, NULL, err);
    if (r == ENG_OK && rec.oom)
        r = eng_fail(err, ENG_ERR_NOMEM, "tracebench: out of memory recording the rays");
    out->photons = ti.count;
    out->rays = rec.n;
    out->stored = ref.count;
    out->threads = ti.settings.threads;
    out->lanes = PT_LANES;
    out->repeats = repeats;
    out->maps_identical = 1;
    /* Each side runs after the other as often as before it (the trace first in even repeats, the
     * raw casts first in odd ones), so that what one leaves in the caches weighs on both alike. */
    for (int k = 0; k < repeats && r == ENG_OK; k++) {
        for (int step = 0; step < 2 && r == ENG_OK; step++) {
            if ((step == 0) == (k % 2 == 0)) {
                double t0 = now_ms();
                r = photon_trace(ti.rt, ti.fs, ti.rm, ti.in, ti.count, &ti.settings, &map, NULL, err);
                out->trace_ms[k] = now_ms() - t0;
                out->maps_identical &= same_map(&map, &ref);
            } else {
                double t0 = now_ms();
                out->hits = rt_cast_raw(ti.rt, rec.rays, rec.n, ti.settings.threads, 1, NULL);
                out->raw_ms[k] = now_ms() - t0;
                t0 = now_ms();
                rt_cast_raw(ti.rt, rec.rays, rec.n, ti.settings.threads, 4, NULL);
                out->packet_ms[k] = now_ms() - t0;
            }
        }
    }
    if (r == ENG_OK) {
        rt_raw_hit *one = malloc((rec.n ? rec.n : 1) * sizeof *one), *four = malloc((rec.n ? rec.n : 1) * sizeof *four);
        if (!one || !four) {
            r = eng_fail(err, ENG_ERR_NOMEM, "tracebench: out of memory for %zu ray results", rec.n);
        } else {
            rt_cast_raw(ti.rt, rec.rays, rec.n, ti.settings.threads, 1, one);
            rt_cast_raw(ti.rt, rec.rays, rec.n, ti.settings.threads, 4, four);
            out->packets_identical = memcmp(one, four, rec.n * sizeof *one) == 0;
        }
        free(one);
        free(four);
    }
    photon_map_free(&ref);
    photon_map_free(&map);
    free(rec.rays);
    return r;
}
