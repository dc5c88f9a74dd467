/* trace.h — the trace room's face: the CPU side of photon mapping. Precomputed random maps,
 * the Embree scene and its hits, the photon trace of the bounces after the bounce map (one
 * method per file behind trace_method.h), and the materials at a hit. The BSDF (bsdf.h), the
 * photon k-d tree (kdtree.h) and the eye-path tracer through specular surfaces (eye_tracer.h)
 * are this room's other headers. */
#ifndef ISPM_TRACE_H
#define ISPM_TRACE_H

#include "frame.h"
#include "kernel.h"

typedef struct eng_rt eng_rt;

/* ---------------------------------------------------------------- photons (ISPM §4) */

/* Precomputed random maps (001_… §3.1 PRM; 003_… §4.1 and §6.1 "Random numbers"; 004_… §7):
 * tables made once per run from a fixed seed and never changed, so that a path seeded by the
 * same scene quantity reads the same numbers every frame. Entry k of a path seeded s is
 * table[(s + k) & (size − 1)]. */
typedef struct eng_random_maps {
    uint32_t size;   /* entries per table, a power of two */
    float *uniform;  /* size × 4 uniform numbers in [0,1) */
    float *cosine;   /* size × 4: cosine-weighted hemisphere direction about +Z (x,y,z), pdf */
    float *sphere;   /* size × 4: uniform sphere direction (x,y,z), pdf = 1/4π */
} eng_random_maps;

eng_result rmap_create(uint64_t seed, uint32_t size, eng_random_maps *out, eng_error *err);
void rmap_destroy(eng_random_maps *rm);
/* A 32-bit hash of the exact bits of a position (or any 3 floats) and a salt: the seed of a
 * CPU photon path (ISPM §4.1: "re-seed … with a hash of its world space [position] in the
 * bounce map"). The salt is 0 with random maps, the frame index with per-frame random. */
uint32_t rmap_hash3(const float p[3], uint32_t salt);
/* Same for a light position and a bounce-map pixel (x, y, face): the bounce map's seed. */
uint32_t rmap_hash_pixel(const float light[3], uint32_t x, uint32_t y, uint32_t face, uint32_t salt);
/* Stratified bounces (`"bounce_strata"`, bsdf_strata in bsdf.h): bounce-map texel (x, y) of
 * `face` lies in the 2^log2n-wide block (x, y) >> log2n; *index is its place in the block,
 * (y mod n)·n + x mod n, and *pattern the block's seed, rmap_hash_pixel(light, block, face,
 * strata_salt) with eng_rmap_frame's strata_salt: it depends on nothing but the light, the block,
 * the frame's salt and random_seed, so static parts of a scene keep their photons. The
 * bounce-map shader computes the same. */
void rmap_strata_texel(const float light[3], uint32_t x, uint32_t y, uint32_t face, uint32_t strata_salt, int log2n,
                       uint32_t *index, uint32_t *pattern);

/* How one frame reads the random maps, the same for the bounce-map shader and the CPU trace:
 * the salt of its seeds, and with stratified sampling across frames (002_… §4.2) the
 * Cranley–Patterson offsets of its stratum (bsdf_stratify). */
typedef struct eng_rmap_frame {
    uint32_t salt;     /* 0 = precomputed random maps; frame-dependent for per-frame random */
    int stratified;    /* 1: rotate every event's numbers by offset (bsdf_stratify) */
    float offset[4];   /* per random dimension, in [0,1) */
    int strata_log2;   /* "bounce_strata" = 2^strata_log2 (bsdf_strata); 0 = off */
    uint32_t strata_salt; /* salt of the blocks' patterns (rmap_strata_texel): the frame's salt,
                           * BSDF_STRATA_SALT and random_seed, so that another seed draws other
                           * permutations as well as other jitter */
} eng_rmap_frame;

/* The frame's eng_rmap_frame under settings s (random, stratified_cycle). Stratified: frame f
 * is stratum k = f mod K of a cycle of K = s->stratified_cycle frames, with offsets
 * frac(k·g_d / K) for g = (1, 1, 1, g₃), g₃ the integer coprime to K nearest K/φ: over a cycle
 * every dimension visits the K strata [j/K, (j+1)/K) once, and the direction pair (d = 2, 3)
 * follows a rank-1 (Fibonacci-like) lattice, so it covers the unit square evenly rather than
 * along its diagonal. Offsets are exact multiples of 1/K; frames f and f + K read the same. */
void rmap_frame(const eng_settings *s, int frame, eng_rmap_frame *out);

/* A photon leaving the first bounce (bounce map, ISPM Table 1): outgoing direction and power,
 * at the surface point of the light's G-buffer. Power 0 = absorbed. */
typedef struct eng_bounce_photon {
    float position[3];
    float direction[3]; /* outgoing, unit */
    float power[3];     /* W per channel */
    float path_density; /* ρp so far */
    float ior;          /* index of refraction of the medium the photon travels in */
    int delta;          /* 1: the bounce took a delta lobe (mirror, glass: BSDF_LOBE_MIRROR..REFRACT) */
} eng_bounce_photon;

/* A photon-map photon (ISPM Table 1): stored where a path hits a surface, before it
 * scatters again. */
typedef struct eng_photon_map {
    size_t count, capacity;
    eng_photon *photons;
    /* Optional (want_source = 1): per photon the index of the input (bounce-map) photon whose
     * path stored it, for pixel lineage; source_capacity entries allocated. */
    int want_source;
    uint32_t *source;
    size_t source_capacity;
    /* photon_trace's per-thread photon buffers (photon_trace.c), kept from one trace to the
     * next so that a frame reuses the last frame's memory; freed by photon_map_free. */
    struct pt_buf *trace_bufs;
    int trace_buf_count;
    struct pt_path *trace_paths; /* ... and where each path's photons are: trace_path_capacity, */
    size_t trace_path_capacity, trace_path_count; /* the last trace's trace_path_count */
    /* The last trace's rays and photons per batch of inputs (trace_batch_count of them; 0
     * before the first trace): where in the map the next trace puts each batch's photons. */
    struct eng_trace_batch *trace_batches;
    size_t trace_batch_count, trace_batch_capacity;
} eng_photon_map;
typedef struct eng_trace_batch {
    uint32_t rays, photons;
    /* During a trace, where the batch's photons are: PT_IN_MAP, at index `at` of the map (where
     * the last trace's counts put them), or thread `held`'s buffer from index `at` on. */
    uint32_t held;
    size_t at;
} eng_trace_batch;
#define PT_IN_MAP UINT32_MAX

typedef struct eng_trace_settings {
    int max_bounces;     /* optional cap on photons stored per path after the bounce map; 0 = none
                          * (Russian roulette alone ends a path, up to the safety limit) */
    int threads;
    uint32_t salt;       /* 0 = precomputed random maps; frame-dependent for per-frame random */
    int stratified;      /* eng_rmap_frame's: 1 = rotate the numbers by offset */
    float offset[4];
    /* The width of a photon's ray cone (photon_trace.c: its texture level of detail at each
     * hit); the engine passes the kernel's diameter 2·kernel_radius. 0: level 0 only. */
    float footprint;
} eng_trace_settings;

typedef struct eng_trace_stats {
    eng_trace_counts counts;        /* what the bounce-ray method counted (image-space methods) */
    uint64_t emitted;               /* bounce-map photons with power > 0 */
    uint64_t truncated;             /* paths still alive after ENG_PHOTON_MAX_HITS surface hits */
    uint64_t stored[ENG_PHOTON_BOUNCES];        /* photons stored at bounce index b (b = 2..) */
    double stored_power[ENG_PHOTON_BOUNCES][3]; /* their total power per channel */
} eng_trace_stats;

/* A ray hit (rt.c): distance along the unit ray, world position, interpolated shading
 * normal (unit; the material's normal texture applied, scn_normal_at) and Embree's geometric normal (unit), both in world space and NOT oriented
 * toward the ray (the caller does that); the draw's material (−1 = default) and the draw
 * index (= Embree geomID). */
typedef struct rt_hit {
    float t;
    float position[3];
    float normal[3];
    float geom_normal[3];
    int32_t material;
    uint32_t draw;
    /* What the material's base colour is multiplied by here (scn_base_color_at: its
     * texture at the hit's texcoord, COLOR_0); (1,1,1,1) without either. */
    float base_tex[4];
    /* What roughness and metallic are multiplied by here: the metallicRoughness texture's
     * G and B (glTF §3.9.2); 1 without one. */
    float roughness_tex, metallic_tex;
    /* What emissiveFactor is multiplied by here: the emissive texture's RGB (sRGB-decoded,
     * glTF §3.9.3); 1 without one. */
    float emissive_tex[3];
    /* Where on the draw's primitive (rt.c; tri = UINT32_MAX where the tracer does not know,
     * e.g. a multi-image hit): triangle, barycentrics of its vertices 1 and 2, and the
     * triangle's world-space area, for rt_hit_textures' footprint. */
    uint32_t tri;
    float bary[2];
    float world_area;
} rt_hit;

/* Fills hit's base_tex, roughness_tex, metallic_tex and emissive_tex from its material's
 * textures on primitive p at (tri, bary) (hit_textures.c). width ≤ 0: level 0 as each
 * sampler's magFilter says (no mip levels); width > 0: the ray-cone
 * width over |cos| at the hit (world units), the level chosen from it (scn_texref_at_cone). */
void rt_hit_textures(const scn_scene *scene, const scn_primitive *p, rt_hit *hit, float width);

/* Closest hit of the ray org + t·dir, t in [tnear, tfar], dir unit, against the scene as
 * last posed by rt_update. Returns 1 and fills hit, or 0 (hit untouched). Thread-safe. */
int rt_intersect(const eng_rt *rt, const float org[3], const float dir[3], float tnear, float tfar, rt_hit *hit);
/* Whether material m names a texture (base colour, metallic-roughness or emissive): the hits on
 * which the photon trace looks textures up at its footprint (photon_trace.c), and so the hits
 * rt_intersect_untextured leaves to it. One definition for both, which must agree. */
static inline int rt_material_textured(const scn_material *m)
{
    return m->base_color_tex.texture >= 0 || m->metallic_roughness_tex.texture >= 0 || m->emissive_tex.texture >= 0;
}

/* rt_intersect for the photon trace, which looks up a textured material's textures itself at
 * the width of its photons' footprint (photon_trace.c): on a draw whose material names a
 * texture the hit's texture factors are left at 1 (world_area is set), everything else is as
 * rt_intersect returns it. */
int rt_intersect_untextured(const eng_rt *rt, const float org[3], const float dir[3], float tnear, float tfar,
                            rt_hit *hit);
/* rt_intersect_untextured (tfar = ∞) on n ≤ 4 rays at once, one rtcIntersect4 packet:
 * found[i] and hits[i] are what rt_intersect_untextured returns for rays[i], given that Embree
 * answers a packet's rays as it answers them one by one (tracebench checks it on every run). */
typedef struct rt_ray {
    float org[3], dir[3], tnear;
} rt_ray;
void rt_intersect4_untextured(const eng_rt *rt, int n, const rt_ray *rays, rt_hit *hits, int *found);
/* alphaMode BLEND geometry (rt.c, pass_translucent.c) is not seen by rt_intersect and
 * rt_occluded; rt_intersect_blend sees only it (lamps ignored), as rt_intersect does. */
int rt_intersect_blend(const eng_rt *rt, const float org[3], const float dir[3], float tnear, float tfar, rt_hit *hit);
int rt_has_blend(const eng_rt *rt); /* posed at least once with a BLEND draw */
int rt_is_blend(const scn_scene *scene, int32_t material); /* material index → alphaMode BLEND */
/* The lamps of lights with a size (rt.c): the light index of the nearest lamp the ray enters
 * at t in (tmin, tmax), other than light skip (−1: none skipped), with *t; −1 when none. A
 * ray that starts inside a lamp ignores it. rt_intersect returns 0 where a lamp comes first. */
int rt_lamp_hit(const eng_rt *rt, const float org[3], const float dir[3], float tmin, float tmax, int skip,
                float *t);

/* CPU photon trace (photon_trace.c, ISPM §4.3): traces every bounce-map photon with power > 0
 * through the scene posed in rt and fills out (its previous contents are replaced; out may
 * start zeroed) with the photons of every path (at most s->max_bounces per path when that is
 * > 0), in input order and, within a path, in hit order. A path ends by Russian roulette, by
 * leaving the scene, at the cap, or after ENG_PHOTON_MAX_HITS surface hits (counted in
 * stats->truncated). The result is bit-identical for any s->threads. stats (may be NULL)
 * gets the emitted and truncated counts and stored count/power per bounce index. fs->scene
 * resolves the materials of the draws rt was built from. ENG_ERR_INVALID on bad settings
 * (max_bounces outside 0..ENG_PHOTON_MAX_HITS, random maps not created), ENG_ERR_NOMEM when
 * out of memory. */
eng_result photon_trace(const eng_rt *rt, const eng_frame_scene *fs, const eng_random_maps *rm,
                        const eng_bounce_photon *in, size_t count, const eng_trace_settings *s,
                        eng_photon_map *out, eng_trace_stats *stats, eng_error *err);
/* How photon_trace_with finds the next surface of a path (trace_method.h): the closest hit of
 * org + t·dir, t ≥ tnear, dir unit, as rt_intersect reports it (1 and hit filled, or 0), with
 * the method's counts added to *counts (a per-thread accumulator). Must be thread-safe and a
 * pure function of its arguments and the method's per-frame state. */
typedef int (*pt_intersect_fn)(const void *state, const float org[3], const float dir[3], float tnear, rt_hit *hit,
                               eng_trace_counts *counts);
/* Optional, the same on n ≤ PT_LANES rays at once (a method that casts packets): found[i] and
 * hits[i] are what intersect returns for rays[i] alone. With it, photon_trace_with keeps
 * PT_LANES paths in flight per thread and asks for their next surfaces together. */
#define PT_LANES 4
typedef void (*pt_intersect_n_fn)(const void *state, int n, const rt_ray *rays, rt_hit *hits, int *found,
                                  eng_trace_counts *counts);
typedef struct pt_tracer {
    pt_intersect_fn intersect;
    const void *state;
    pt_intersect_n_fn intersect_n; /* NULL: ray by ray, one path after the other */
} pt_tracer;
/* The Embree tracer's intersect: state is the eng_rt; rt_intersect with tfar = ∞. */
int pt_embree_intersect(const void *state, const float org[3], const float dir[3], float tnear, rt_hit *hit,
                        eng_trace_counts *counts);
/* ... and its intersect_n: rt_intersect4_untextured packets of 4. */
void pt_embree_intersect_n(const void *state, int n, const rt_ray *rays, rt_hit *hits, int *found,
                           eng_trace_counts *counts);

/* photon_trace with the bounce rays traced by tr instead of Embree; stats->counts gets the
 * sum of what tr counted. photon_trace(rt, ...) is this with the Embree tracer. */
eng_result photon_trace_with(const pt_tracer *tr, const eng_frame_scene *fs, const eng_random_maps *rm,
                             const eng_bounce_photon *in, size_t count, const eng_trace_settings *s,
                             eng_photon_map *out, eng_trace_stats *stats, eng_error *err);
/* Frees the photons and zeroes the map; accepts a zeroed map. */
void photon_map_free(eng_photon_map *m);
/* Grows m's per-thread trace buffers (for a trace on `threads` threads) and its photon array
 * towards `photons` photons and touches the new memory, so that a first trace does not take
 * those page faults; the trace's results do not depend on it (out of memory: leaves m as is).
 * The frame loop calls it on the overlap worker while the GL thread renders. */
void photon_map_reserve(eng_photon_map *m, int threads, size_t photons);

/* ---------------------------------------------------------------- Embree scene (rt.c) */

eng_result rt_create(const scn_scene *scene, int threads, eng_rt **out, eng_error *err);
/* Poses every instance at this frame's world matrices: static geometry is built once,
 * geometry whose matrix changed is re-transformed and refit. */
void rt_update(eng_rt *rt, const eng_frame_scene *fs);
int rt_occluded(const eng_rt *rt, const float a[3], const float b[3]);
void rt_destroy(eng_rt *rt);

struct rt_hit;
/* The material at a CPU hit: eng_material_of with its base colour times hit->base_tex (the
 * texture and COLOR_0 there), as the G-buffers see it at the same surface point. */
scn_material eng_material_at(const scn_scene *scene, const struct rt_hit *hit);

/* n rays of RT_RAW_FLOATS floats each (org xyz, dir xyz, tnear; tfar = ∞) cast with nothing but
 * Embree against the scene rt_intersect sees (no lamps, no hit attributes), statically shared
 * among `threads` OpenMP threads: width 1 rtcIntersect1 ray by ray (the raw rate the photon
 * trace is measured against), width 4 rtcIntersect4 on packets of 4 consecutive rays. Returns
 * the hit count; out (n entries, may be NULL) gets each ray's Embree result. */
#define RT_RAW_FLOATS 7
typedef struct rt_raw_hit {
    float t, u, v, ng[3]; /* tfar after the call, barycentrics, unnormalised geometric normal */
    unsigned geom, prim;  /* RTC_INVALID_GEOMETRY_ID: no hit */
} rt_raw_hit;
uint64_t rt_cast_raw(const eng_rt *rt, const float *rays, size_t n, int threads, int width, rt_raw_hit *out);

#endif
