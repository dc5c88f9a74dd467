/* photon_trace.c — the CPU part of photon tracing (003_d0bf8e920b03f4e1.txt §3 step 2 and
 * §4.3 "Remaining Bounces"): every photon of the bounce maps is traced through the scene with
 * Embree (rt.c); at each surface it hits, a photon-map photon is stored (ISPM Table 1:
 * position, ω_i, Φ_i, n_p, ρp) before it scatters again (bsdf.c: importance sampling, Russian
 * roulette, path density).
 *
 * Frame coherence (§4.1 "Precomputed random numbers"): a path is re-seeded with
 * s = rmap_hash3(bounce-map position, salt) and its k-th scattering event reads entry
 * (s + k) & (size − 1) of the random maps. A path depends on nothing but its input photon,
 * the geometry it hits and the maps — no counters, no thread ids — so a path that misses
 * everything that moved is bit-identical from frame to frame.
 *
 * Stratified sampling across frames (002_558366c451cd32fd.txt §4.2): with
 * s->stratified every event's numbers are Cranley–Patterson rotated by the frame's offsets
 * (bsdf_stratify), exactly as the bounce-map shader rotates the first bounce's.
 *
 * Path length (003_… §4, 002_… §4.4): Russian roulette alone ends a path, so the photon map
 * is an unbiased sample of all bounces; s->max_bounces > 0 is an optional cap on the photons
 * stored per path (a biased, cheaper estimate), and ENG_PHOTON_MAX_HITS surface hits is a
 * safety limit for pathological paths (e.g. between perfect mirrors). A path cut by the limit
 * while it still carries power is counted in stats->truncated, so a manifest shows whether
 * the limit ever mattered.
 *
 * Determinism across thread counts: a path's photons go to the buffer of the thread that
 * traced it, and the path records where (thread, offset, count); the map is then compacted
 * in input order (runs of consecutive paths, each copied whole), and the statistics are
 * summed sequentially after that.
 *
 * Speed (issue 22 item 4): the random-map entries of an event are prefetched before its ray
 * is traced, the BSDF reads a bsdf_params rather than a copy of the material, and the
 * per-thread buffers stay in the map from one trace to the next.
 *
 * Which surface a ray hits next is asked of a tracer (trace_method.h: Embree, rt.c, or the
 * multi-image trace of 004); what happens at the surface is the same for every tracer.
 *
 * Storage rule: a photon is stored only on surfaces with a diffuse or glossy lobe
 * (bsdf_stores_photons): the photon map feeds the final gather, which cannot use photons on
 * purely specular surfaces (mirror, glass); such surfaces only redirect the path (caustics). */
#include "bsdf.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* A growable list of photons, one per thread. */
typedef struct pt_buf {
    eng_photon *p;
    size_t n, cap;
    eng_trace_counts counts; /* the tracer's counts on this thread (integer sums: order-free) */
} pt_buf;

static eng_photon *pt_push(pt_buf *b)
{
    if (b->n == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 1024;
        eng_photon *p = realloc(b->p, cap * sizeof *p);
        if (!p)
            return NULL;
        b->p = p;
        b->cap = cap;
    }
    return &b->p[b->n++];
}

/* Where a path's photons are: buffer `thread`, [at, at + count). */
typedef struct pt_path {
    size_t at;
    uint32_t count;
    uint16_t thread;
    uint8_t truncated, oom;
} pt_path;

/* n photons of buffer `thread` from index `from`, going to index `to` of the map. */
typedef struct pt_run {
    uint16_t thread;
    size_t from, to, n;
} pt_run;

static float dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static int has_power(const float p[3])
{
    return p[0] > 0.0f || p[1] > 0.0f || p[2] > 0.0f;
}

/* Whether material m has a texture whose level a footprint chooses. */
static int textured(const scn_scene *scene, int32_t m)
{
    if (m < 0 || (uint32_t)m >= scene->material_count)
        return 0;
    return rt_material_textured(&scene->materials[m]);
}

/* Traces one bounce-map photon, appending its stored photons to buf; fills rec. */
static void trace_path(const pt_tracer *tr, const eng_frame_scene *fs, const scn_material *default_material,
                       const eng_random_maps *rm, const eng_bounce_photon *bp, const eng_trace_settings *s, pt_buf *buf,
                       pt_path *rec)
{
    const scn_scene *scene = fs->scene;
    rec->at = buf->n;
    rec->count = 0;
    rec->truncated = rec->oom = 0;
    if (!has_power(bp->power))
        return;
    const uint32_t mask = rm->size - 1;
    const uint32_t seed = rmap_hash3(bp->position, s->salt);
    float power[3] = {bp->power[0], bp->power[1], bp->power[2]};
    float rho = bp->path_density;
    int delta_only = bp->delta; /* every scatter so far a delta lobe (eng_photon.caustic) */
    float eta = bp->ior > 0.0f ? bp->ior : 1.0f;
    float org[3] = {bp->position[0], bp->position[1], bp->position[2]};
    float dir[3] = {bp->direction[0], bp->direction[1], bp->direction[2]};
    float len = sqrtf(dot3(dir, dir));
    if (!(len > 0.0f) || !isfinite(len))
        return;
    for (int i = 0; i < 3; i++)
        dir[i] /= len;
    /* The bounce-map photon sits on the surface it left; no normal is known there, so the
     * first ray skips a short distance instead of offsetting its origin. */
    float tnear = bsdf_offset_eps(org);
    for (uint32_t k = 0;; k++) {
        if (k == ENG_PHOTON_MAX_HITS) {
            rec->truncated = 1;
            break;
        }
        /* Event k's random numbers sit at a scattered place in maps of a few MB: ask for
         * them now, so that the memory fetch overlaps the ray instead of following it. */
        const uint32_t e = (seed + k) & mask;
        __builtin_prefetch(rm->uniform + 4 * (size_t)e);
        __builtin_prefetch(rm->cosine + 4 * (size_t)e);
        rt_hit h;
        h.tri = UINT32_MAX;
        if (!tr->intersect(tr->state, org, dir, tnear, &h, &buf->counts))
            break;
        /* Texture level of detail (texture_mip.c, Akenine-Möller et al. 2019 ray cones): the
         * photon's cone has the constant width s->footprint, the diameter of the kernel its
         * photons are gathered with (spread angle 0): texture detail finer than the kernel
         * cannot show in the photon map, so the colour a photon carries on is the texture
         * averaged over that width, over |cos| of the geometric normal and the ray. Looked up
         * here only (the Embree tracer leaves a textured hit's factors to this,
         * rt_intersect_untextured); without a footprint at level 0, as rt_intersect would. */
        if (h.tri != UINT32_MAX && h.draw < fs->draw_count && textured(scene, h.material)) {
            float c = fabsf(dot3(h.geom_normal, dir));
            rt_hit_textures(scene, &scene->primitives[fs->draws[h.draw].primitive], &h,
                            s->footprint > 0.0f ? s->footprint / (c > 1e-3f ? c : 1e-3f) : 0.0f);
        }
        const float wi[3] = {-dir[0], -dir[1], -dir[2]};
        /* Shading normal, unless interpolation put wi on the other side of it than the true
         * surface: then the geometric normal, so scattering stays on the photon's side. */
        float n[3];
        float cg = dot3(h.geom_normal, wi), cs = dot3(h.normal, wi);
        memcpy(n, ((cg >= 0.0f) == (cs >= 0.0f)) ? h.normal : h.geom_normal, sizeof n);
        /* eng_material_at's material, reduced to what scattering reads (bsdf_params_at). */
        bsdf_params m;
        bsdf_params_at(h.material >= 0 && (uint32_t)h.material < scene->material_count ? &scene->materials[h.material]
                                                                                        : default_material,
                       &h, &m);
        if (bsdf_stores_photons_params(&m)) {
            eng_photon *ph = pt_push(buf);
            if (!ph) {
                rec->oom = 1;
                return;
            }
            rec->count++;
            float side = dot3(n, wi) >= 0.0f ? 1.0f : -1.0f;
            for (int i = 0; i < 3; i++) {
                ph->position[i] = h.position[i];
                ph->direction[i] = wi[i];
                ph->power[i] = power[i];
                ph->normal[i] = side * n[i];
            }
            ph->path_density = rho;
            ph->bounce = (uint16_t)(2 + k);
            ph->caustic = (uint16_t)delta_only;
            ph->ray_length = h.t;
            if (s->max_bounces > 0 && rec->count == (uint32_t)s->max_bounces)
                break;
        }
        bsdf_sample rnd = {rm->uniform + 4 * (size_t)e, rm->cosine + 4 * (size_t)e};
        float su[4], scd[4];
        if (s->stratified) {
            bsdf_stratify(rnd.u, s->offset, su, scd);
            rnd.u = su;
            rnd.cosdir = scd;
        }
        float wo[3], w[3], density;
        const bsdf_lobe lobe = bsdf_scatter_params(&m, n, wi, &eta, &rnd, wo, w, &density);
        if (lobe == BSDF_ABSORBED)
            break;
        delta_only = delta_only && (lobe == BSDF_MIRROR || lobe == BSDF_REFLECT || lobe == BSDF_REFRACT);
        for (int i = 0; i < 3; i++)
            power[i] *= w[i];
        rho *= density;
        if (!has_power(power))
            break;
        float eps = bsdf_offset_eps(h.position);
        float side = dot3(h.geom_normal, wo) >= 0.0f ? eps : -eps;
        for (int i = 0; i < 3; i++) {
            org[i] = h.position[i] + side * h.geom_normal[i];
            dir[i] = wo[i];
        }
        tnear = 0.0f;
    }
}

int pt_embree_intersect(const void *state, const float org[3], const float dir[3], float tnear, rt_hit *hit,
                        eng_trace_counts *counts)
{
    (void)counts;
    return rt_intersect_untextured(state, org, dir, tnear, INFINITY, hit);
}

eng_result photon_trace(const eng_rt *rt, const eng_frame_scene *fs, const eng_random_maps *rm,
                        const eng_bounce_photon *in, size_t count, const eng_trace_settings *s,
                        eng_photon_map *out, eng_trace_stats *stats, eng_error *err)
{
    const pt_tracer tr = {pt_embree_intersect, rt};
    return photon_trace_with(&tr, fs, rm, in, count, s, out, stats, err);
}

static void add_counts(eng_trace_counts *a, const eng_trace_counts *b)
{
    a->rays += b->rays;
    a->resolved += b->resolved;
    a->fallback += b->fallback;
    a->dropped += b->dropped;
    for (int i = 0; i < 4; i++)
        a->types[i] += b->types[i];
    a->compared += b->compared;
    a->agree += b->agree;
}

static int trace_threads(int threads) { return threads > 0 ? (threads < 1024 ? threads : 1024) : 1; }

/* out has a trace buffer per thread; 0 when out of memory. */
static int ensure_bufs(eng_photon_map *out, int threads)
{
    if (out->trace_buf_count < threads) {
        pt_buf *more = realloc(out->trace_bufs, (size_t)threads * sizeof *more);
        if (!more)
            return 0;
        memset(more + out->trace_buf_count, 0, (size_t)(threads - out->trace_buf_count) * sizeof *more);
        out->trace_bufs = more;
        out->trace_buf_count = threads;
    }
    return 1;
}

/* Grows *p (holding *cap photons) to want photons and zeroes the new ones, so that their pages
 * are touched now; left as is when out of memory. */
static void grow_touched(eng_photon **p, size_t *cap, size_t want)
{
    if (want <= *cap)
        return;
    eng_photon *q = realloc(*p, want * sizeof *q);
    if (!q)
        return;
    memset(q + *cap, 0, (want - *cap) * sizeof *q);
    *p = q;
    *cap = want;
}

void photon_map_reserve(eng_photon_map *m, int threads, size_t photons)
{
    threads = trace_threads(threads);
    if (!ensure_bufs(m, threads))
        return;
    /* Each thread's buffer grown and touched by that thread (its OpenMP team is then the one
     * the trace will use); a buffer only grows, by the doubling pt_push would have done. */
    const size_t per = photons / (size_t)threads + 1;
    pt_buf *bufs = m->trace_bufs;
#pragma omp parallel num_threads(threads)
    {
        pt_buf *b = &bufs[omp_get_thread_num()];
        size_t cap = b->cap ? b->cap : 1024;
        while (cap < per)
            cap *= 2;
        grow_touched(&b->p, &b->cap, cap);
    }
    grow_touched(&m->photons, &m->capacity, photons);
}

eng_result photon_trace_with(const pt_tracer *tr, const eng_frame_scene *fs, const eng_random_maps *rm,
                             const eng_bounce_photon *in, size_t count, const eng_trace_settings *s,
                             eng_photon_map *out, eng_trace_stats *stats, eng_error *err)
{
    if (s->max_bounces < 0 || s->max_bounces > ENG_PHOTON_MAX_HITS)
        return eng_fail(err, ENG_ERR_INVALID, "photon trace: max_bounces %d outside 0..%d", s->max_bounces,
                        ENG_PHOTON_MAX_HITS);
    if (rm->size == 0 || (rm->size & (rm->size - 1)) != 0 || !rm->uniform || !rm->cosine)
        return eng_fail(err, ENG_ERR_INVALID, "photon trace: random maps not created");
    const int threads = trace_threads(s->threads);
    pt_path *paths = malloc((count ? count : 1) * sizeof *paths);
    if (!paths || !ensure_bufs(out, threads)) {
        free(paths);
        return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu photons", count);
    }
    pt_buf *bufs = out->trace_bufs;
    for (int t = 0; t < threads; t++) {
        bufs[t].n = 0;
        memset(&bufs[t].counts, 0, sizeof bufs[t].counts);
    }
    const scn_material default_material = eng_material_of(fs->scene, -1);
#pragma omp parallel num_threads(threads)
    {
        int t = omp_get_thread_num();
        pt_buf *mine = &bufs[t];
#pragma omp for schedule(static)
        for (ptrdiff_t i = 0; i < (ptrdiff_t)count; i++) {
            trace_path(tr, fs, &default_material, rm, &in[i], s, mine, &paths[i]);
            paths[i].thread = (uint16_t)t;
        }
    }

    size_t total = 0;
    int oom = 0;
    for (size_t i = 0; i < count; i++) {
        total += paths[i].count;
        oom |= paths[i].oom;
    }
    if (!oom && total > out->capacity) {
        eng_photon *p = realloc(out->photons, total * sizeof *p);
        if (p) {
            out->photons = p;
            out->capacity = total;
        } else {
            oom = 1;
        }
    }
    if (!oom && out->want_source && total > out->source_capacity) {
        uint32_t *src = realloc(out->source, total * sizeof *src);
        if (src) {
            out->source = src;
            out->source_capacity = total;
        } else {
            oom = 1;
        }
    }
    if (oom) {
        free(paths);
        return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu stored photons", total);
    }
    /* Compaction in input order. A thread's paths are consecutive in its buffer, and with
     * schedule(static) a thread traces one consecutive range of inputs, so the map is a few
     * runs (about one per thread): copied as such, on the threads. */
    pt_run *runs = NULL;
    size_t run_count = 0, run_cap = 0, at = 0;
    for (size_t i = 0; i < count; i++) {
        if (paths[i].count == 0)
            continue; /* out->photons may still be NULL when nothing was stored */
        pt_run *last = run_count ? &runs[run_count - 1] : NULL;
        if (last && last->thread == paths[i].thread && last->from + last->n == paths[i].at) {
            last->n += paths[i].count;
        } else {
            if (run_count == run_cap) {
                size_t cap = run_cap ? 2 * run_cap : (size_t)threads + 1;
                pt_run *r = realloc(runs, cap * sizeof *r);
                if (!r) {
                    free(runs);
                    free(paths);
                    return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu stored photons", total);
                }
                runs = r;
                run_cap = cap;
            }
            runs[run_count++] = (pt_run){paths[i].thread, paths[i].at, at, paths[i].count};
        }
        for (size_t k = 0; out->want_source && k < paths[i].count; k++)
            out->source[at + k] = (uint32_t)i;
        at += paths[i].count;
    }
#pragma omp parallel for schedule(static) num_threads(threads)
    for (ptrdiff_t r = 0; r < (ptrdiff_t)run_count; r++)
        memcpy(out->photons + runs[r].to, bufs[runs[r].thread].p + runs[r].from, runs[r].n * sizeof(eng_photon));
    free(runs);
    out->count = total;
    eng_trace_counts counts;
    memset(&counts, 0, sizeof counts);
    for (int t = 0; t < threads; t++)
        add_counts(&counts, &bufs[t].counts);

    if (stats) {
        memset(stats, 0, sizeof *stats);
        stats->counts = counts;
        for (size_t i = 0; i < count; i++) {
            if (has_power(in[i].power))
                stats->emitted++;
            stats->truncated += paths[i].truncated;
        }
        for (size_t j = 0; j < total; j++) {
            const eng_photon *ph = &out->photons[j];
            stats->stored[ph->bounce]++;
            for (int c = 0; c < 3; c++)
                stats->stored_power[ph->bounce][c] += ph->power[c];
        }
    }
    free(paths);
    return ENG_OK;
}

void photon_map_free(eng_photon_map *m)
{
    if (!m)
        return;
    free(m->photons);
    free(m->source);
    for (int t = 0; t < m->trace_buf_count; t++)
        free(m->trace_bufs[t].p);
    free(m->trace_bufs);
    memset(m, 0, sizeof *m);
}
