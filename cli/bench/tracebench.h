/* tracebench.h — the photon trace against Embree's raw rate (trace_bench.c; `ispm tracebench`):
 * one frame's photons traced through the engine's photon trace and the very
 * same rays (recorded from that trace) cast with nothing but rtcIntersect1, alternating. */
#ifndef ISPM_TRACEBENCH_H
#define ISPM_TRACEBENCH_H

#include "eng.h"

#ifdef __cplusplus
extern "C" {
#endif

#define TB_MAX_REPEATS 64

typedef struct tb_result {
    size_t photons;  /* bounce-map photons traced */
    size_t rays;     /* rays the trace cast (the recorded ones) */
    size_t stored;   /* photon-map photons */
    uint64_t hits;   /* rays of the recording that hit a surface (rtcIntersect1, no lamps) */
    int threads, repeats;
    int lanes; /* paths the trace keeps in flight per thread (PT_LANES), their rays cast as packets */
    double trace_ms[TB_MAX_REPEATS]; /* the engine's photon trace, repeat by repeat */
    double raw_ms[TB_MAX_REPEATS];   /* rtcIntersect1 over the recorded rays */
    double packet_ms[TB_MAX_REPEATS]; /* rtcIntersect4 over the same rays, 4 consecutive per packet */
    int packets_identical; /* rtcIntersect4 gave every ray rtcIntersect1's t, u, v, Ng, geomID, primID */
    int maps_identical; /* every repeat's map is bit-identical to the one-thread, ray-by-ray trace */
} tb_result;

/* Traces frame `frame` of e's sequence (e made with indirect light on) `repeats` times
 * (1..TB_MAX_REPEATS), each followed by the raw cast of the same rays, on the engine's
 * thread count. ENG_ERR_INVALID for a bad frame or repeat count, or without indirect light. */
eng_result tb_run(eng_engine *e, int frame, int repeats, tb_result *out, eng_error *err);

#ifdef __cplusplus
}
#endif

#endif
