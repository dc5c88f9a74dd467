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
 * Streams: the inputs are cut into batches of PT_BATCH; a thread traces
 * a consecutive range of batches, keeping PT_LANES paths of its batch in flight (lanes). Each
 * round casts the next ray of every path in flight at once (the tracer's intersect_n: Embree
 * rtcIntersect4 packets, rt.c), then moves each path on; the diffuse BSDF is sampled four hits
 * at a time (bsdf_diffuse4, SSE2, the scalar code's operations in its order). A path that ends
 * hands its lane to the next input of the batch. Packets form within a batch only, so which rays
 * share one does not depend on the thread count; a packet's hits are its rays' single-ray hits
 * (tracebench and test_photon check it), so the map is the one-by-one trace's.
 *
 * Determinism and the map: a batch's photons belong where the last trace's per-batch counts
 * put them; each path writes its photons into its slot (as many as it stored last time) in the
 * thread's near buffer, a copy of the batch's place in the map that stays in the cache, and
 * those beyond it go to the batch's stage, linked path by path. A batch whose paths all fill
 * their slots exactly is in place (a static scene: every batch) and is streamed into the map in
 * whole cache lines as it ends (stream_photons); any other is gathered
 * in input order into the buffer of the thread that traced it. After the trace, batches that
 * are not where their photons belong are moved and the gathered ones copied, so the map is in
 * input order for any thread count, whichever thread traced a batch and whatever the last trace
 * left; the statistics are summed sequentially after that. The threads take the batches as
 * they become free (OpenMP guided: long runs of consecutive batches first, single ones last).
 *
 * Speed also: the random-map entries of an event are prefetched as its ray
 * is set up, the BSDF reads a bsdf_params rather than a copy of the material, and the per-thread
 * buffers, path records and batch figures stay in the map from one trace to the next.
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
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <stdlib.h>
#include <string.h>

/* A growable list of photons, one per thread. */
typedef struct pt_buf {
    eng_photon *p; /* the photons of its batches that could not go to the map at once */
    size_t n, cap;
    eng_photon *stage; /* the batch in hand: its paths' photons that have no slot in the map, */
    uint32_t *link;    /* each linked to the next of its path (UINT32_MAX: the last) */
    size_t stage_n, stage_cap;
    eng_photon *near; /* the batch in hand's slots, in the cache until the batch ends (batch_done) */
    size_t near_cap;
    int moved; /* a path of the batch in hand stored another count than its slot holds */
    int oom; /* a photon did not fit */
    eng_trace_counts counts; /* the tracer's counts on this thread (integer sums: order-free) */
    char apart[64]; /* the next thread's buffer starts a cache line later: no line shared */
} pt_buf;

/* A path's photons (count of them): the first `room` in its slot (from index `slot` of its
 * batch's place, in the near buffer until the batch ends: as many as it stored in the last
 * trace, where that trace put them),
 * the rest until its batch ends in the batch's stage from index `extra` on, each linked to the
 * next (pt_buf.link). A batch traced elsewhere than in place gives its paths no room. */
typedef struct pt_path {
    size_t slot;
    uint32_t count, room, extra;
    uint8_t truncated;
} pt_path;



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

/* A path in flight: what the loop over its surfaces carries from one hit to the next. */
typedef struct pt_lane {
    size_t path; /* index of its bounce-map photon */
    uint32_t seed, k; /* k: surface hits so far */
    int delta_only; /* every scatter so far a delta lobe (eng_photon.caustic) */
    float power[3], rho, eta;
    rt_ray ray; /* the next ray */
    uint32_t n; /* photons stored so far: the first room at slot, the rest in the stage from */
    uint32_t first, last; /* index first on, linked (pt_buf.link) */
    uint32_t room;
    eng_photon *slot; /* in the thread's near buffer (pt_buf.near) */
} pt_lane;

/* Event k's random numbers sit at a scattered place in maps of a few MB: ask for them as the
 * ray is set up, so that the memory fetch overlaps the ray instead of following it. */
static void lane_prefetch(const pt_lane *l, const eng_random_maps *rm)
{
    const uint32_t e = (l->seed + l->k) & (rm->size - 1);
    __builtin_prefetch(rm->uniform + 4 * (size_t)e);
    __builtin_prefetch(rm->cosine + 4 * (size_t)e);
}

/* Starts bounce-map photon bp's path in l (rec gets its flags); 0 when it has nothing to trace. */
static int lane_start(pt_lane *l, size_t path, const eng_bounce_photon *bp, const eng_random_maps *rm,
                      const eng_trace_settings *s, eng_photon *place, pt_path *rec)
{
    rec->count = 0;
    rec->truncated = 0;
    if (!has_power(bp->power))
        return 0;
    l->path = path;
    l->room = rec->room;
    l->slot = place ? place + rec->slot : NULL;
    l->seed = rmap_hash3(bp->position, s->salt);
    l->k = 0;
    l->n = 0;
    memcpy(l->power, bp->power, sizeof l->power);
    l->rho = bp->path_density;
    l->delta_only = bp->delta;
    l->eta = bp->ior > 0.0f ? bp->ior : 1.0f;
    float dir[3] = {bp->direction[0], bp->direction[1], bp->direction[2]};
    float len = sqrtf(dot3(dir, dir));
    if (!(len > 0.0f) || !isfinite(len))
        return 0;
    for (int i = 0; i < 3; i++) {
        l->ray.org[i] = bp->position[i];
        l->ray.dir[i] = dir[i] / len;
    }
    /* The bounce-map photon sits on the surface it left; no normal is known there, so the
     * first ray skips a short distance instead of offsetting its origin. */
    l->ray.tnear = bsdf_offset_eps(l->ray.org);
    lane_prefetch(l, rm);
    return 1;
}

/* n photons copied into the map past the caches (non-temporal stores: the map, 4.4 MB for
 * cornell-box-perf, is not read again by the trace, and an ordinary store first reads the line
 * it writes). Whole 64-byte lines only: the batch's photons are gathered in its thread's
 * near buffer (ordinary stores, in the cache) and streamed when the batch ends, so that the
 * write-combining buffers always fill a line; the two lines a batch shares with its neighbours
 * are written with ordinary stores. Photons streamed one by one as each path stored them wrote
 * lines piecemeal, four paths interleaved, which a busy memory system made slow (tracebench, 2
 * threads, busy spells on an AMD EPYC machine). Visible to other threads after the
 * writer's sfence (photon_trace_with). */
static void stream_photons(eng_photon *to, const eng_photon *from, size_t n)
{
    unsigned char *d = (unsigned char *)to;
    const unsigned char *f = (const unsigned char *)from;
    size_t bytes = n * sizeof *to;
    if (!bytes)
        return;
#if defined(__SSE2__)
    size_t head = (64 - ((uintptr_t)d & 63)) & 63;
    if (head < bytes) {
        memcpy(d, f, head);
        d += head, f += head, bytes -= head;
        for (; bytes >= 64; d += 64, f += 64, bytes -= 64)
            for (int k = 0; k < 64; k += 16)
                _mm_stream_si128((__m128i *)(d + k), _mm_loadu_si128((const __m128i *)(f + k)));
    }
#endif
    memcpy(d, f, bytes);
}

/* A photon of l's path beyond its slot, appended to the stage and linked after the path's last
 * there; NULL when out of memory (buf->oom set). */
static eng_photon *stage_push(pt_buf *buf, pt_lane *l)
{
    if (buf->stage_n == buf->stage_cap) {
        size_t cap = buf->stage_cap ? 2 * buf->stage_cap : 1024;
        eng_photon *p = realloc(buf->stage, cap * sizeof *p);
        if (p)
            buf->stage = p;
        uint32_t *k = p ? realloc(buf->link, cap * sizeof *k) : NULL;
        if (!k) {
            buf->oom = 1;
            return NULL;
        }
        buf->link = k;
        buf->stage_cap = cap;
    }
    const uint32_t j = (uint32_t)buf->stage_n++;
    buf->link[j] = UINT32_MAX;
    if (l->n++ == l->room)
        l->first = j;
    else
        buf->link[l->last] = j;
    l->last = j;
    return &buf->stage[j];
}

/* A hit on its way through the BSDF (lane_surface → scattering → lane_next). */
typedef struct pt_shade {
    float n[3], wi[3];
    bsdf_params m;
    bsdf_sample rnd;
    float su[4], scd[4]; /* the stratified numbers rnd points to */
    int diffuse; /* the BSDF takes its diffuse lobe (bsdf_takes_diffuse) */
    float wo[3], w[3], density;
    bsdf_lobe lobe;
} pt_shade;

/* What l's path does at the surface its ray found (found = 0: none) before it scatters: stores a
 * photon and sets up sh for the BSDF. 0 when the path ends here. */
static int lane_surface(pt_lane *l, rt_hit *h, int found, const eng_frame_scene *fs,
                        const scn_material *default_material, const eng_random_maps *rm, const eng_trace_settings *s,
                        pt_buf *buf, pt_shade *sh)
{
    if (!found)
        return 0;
    const scn_scene *scene = fs->scene;
    const float *dir = l->ray.dir;
    /* Texture level of detail (texture_mip.c, Akenine-Möller et al. 2019 ray cones): the
     * photon's cone has the constant width s->footprint, the diameter of the kernel its
     * photons are gathered with (spread angle 0): texture detail finer than the kernel
     * cannot show in the photon map, so the colour a photon carries on is the texture
     * averaged over that width, over |cos| of the geometric normal and the ray. Looked up
     * here only (the Embree tracer leaves a textured hit's factors to this,
     * rt_intersect_untextured); without a footprint at level 0, as rt_intersect would. */
    if (h->tri != UINT32_MAX && h->draw < fs->draw_count && textured(scene, h->material)) {
        float c = fabsf(dot3(h->geom_normal, dir));
        rt_hit_textures(scene, &scene->primitives[fs->draws[h->draw].primitive], h,
                        s->footprint > 0.0f ? s->footprint / (c > 1e-3f ? c : 1e-3f) : 0.0f);
    }
    float *wi = sh->wi, *n = sh->n;
    for (int i = 0; i < 3; i++)
        wi[i] = -dir[i];
    /* Shading normal, unless interpolation put wi on the other side of it than the true
     * surface: then the geometric normal, so scattering stays on the photon's side. */
    float cg = dot3(h->geom_normal, wi), cs = dot3(h->normal, wi);
    memcpy(n, ((cg >= 0.0f) == (cs >= 0.0f)) ? h->normal : h->geom_normal, sizeof sh->n);
    /* eng_material_at's material, reduced to what scattering reads (bsdf_params_at). */
    bsdf_params_at(h->material >= 0 && (uint32_t)h->material < scene->material_count ? &scene->materials[h->material]
                                                                                      : default_material,
                   h, &sh->m);
    if (bsdf_stores_photons_params(&sh->m)) {
        eng_photon ph;
        float side = dot3(n, wi) >= 0.0f ? 1.0f : -1.0f;
        for (int i = 0; i < 3; i++) {
            ph.position[i] = h->position[i];
            ph.direction[i] = wi[i];
            ph.power[i] = l->power[i];
            ph.normal[i] = side * n[i];
        }
        ph.path_density = l->rho;
        ph.bounce = (uint16_t)(2 + l->k);
        ph.caustic = (uint16_t)l->delta_only;
        ph.ray_length = h->t;
        if (l->n < l->room) {
            l->slot[l->n++] = ph;
        } else {
            eng_photon *to = stage_push(buf, l);
            if (!to)
                return 0;
            *to = ph;
        }
        if (s->max_bounces > 0 && l->n == (uint32_t)s->max_bounces)
            return 0;
    }
    const uint32_t e = (l->seed + l->k) & (rm->size - 1);
    sh->rnd = (bsdf_sample){rm->uniform + 4 * (size_t)e, rm->cosine + 4 * (size_t)e};
    if (s->stratified) {
        bsdf_stratify(sh->rnd.u, s->offset, sh->su, sh->scd);
        sh->rnd.u = sh->su;
        sh->rnd.cosdir = sh->scd;
    }
    sh->diffuse = bsdf_takes_diffuse(&sh->m, n, wi, sh->rnd.u);
    return 1;
}

/* The BSDF at one hit, ray by ray. */
static void scatter_one(pt_lane *l, pt_shade *sh)
{
    sh->lobe = bsdf_scatter_params(&sh->m, sh->n, sh->wi, &l->eta, &sh->rnd, sh->wo, sh->w, &sh->density);
}

/* The diffuse lobe at up to four hits at once (bsdf_diffuse4), which answers each as
 * scatter_one would; without SSE2, one by one. */
static void scatter_diffuse(pt_lane *const *lanes, pt_shade *const *sh, int n)
{
#if defined(__SSE2__)
    const float *nn[4], *wi[4], *cd[4], *albedo[4];
    float ur[4], *wo[4], *w[4], *density[4];
    int alive[4];
    for (int k = 0; k < 4; k++) {
        pt_shade *x = sh[k < n ? k : 0];
        nn[k] = x->n;
        wi[k] = x->wi;
        cd[k] = x->rnd.cosdir;
        albedo[k] = x->m.base_color;
        ur[k] = x->rnd.u[BSDF_U_ROULETTE];
        wo[k] = x->wo;
        w[k] = x->w;
        density[k] = &x->density;
    }
    bsdf_diffuse4(nn, wi, cd, albedo, ur, wo, w, density, alive);
    for (int k = 0; k < n; k++)
        sh[k]->lobe = alive[k] ? BSDF_DIFFUSE : BSDF_ABSORBED;
#else
    for (int k = 0; k < n; k++)
        scatter_one(lanes[k], sh[k]);
#endif
    (void)lanes;
}

/* After the BSDF: the path's power and density, and its next ray. 1 when the path goes on; 0
 * when it ended (rec->truncated set when the hit limit cut it). */
static int lane_next(pt_lane *l, const rt_hit *h, const pt_shade *sh, const eng_random_maps *rm, pt_path *rec)
{
    const bsdf_lobe lobe = sh->lobe;
    if (lobe == BSDF_ABSORBED)
        return 0;
    l->delta_only = l->delta_only && (lobe == BSDF_MIRROR || lobe == BSDF_REFLECT || lobe == BSDF_REFRACT);
    for (int i = 0; i < 3; i++)
        l->power[i] *= sh->w[i];
    l->rho *= sh->density;
    if (!has_power(l->power))
        return 0;
    float eps = bsdf_offset_eps(h->position);
    float side = dot3(h->geom_normal, sh->wo) >= 0.0f ? eps : -eps;
    for (int i = 0; i < 3; i++) {
        l->ray.org[i] = h->position[i] + side * h->geom_normal[i];
        l->ray.dir[i] = sh->wo[i];
    }
    l->ray.tnear = 0.0f;
    if (++l->k == ENG_PHOTON_MAX_HITS) {
        rec->truncated = 1;
        return 0;
    }
    lane_prefetch(l, rm);
    return 1;
}

/* How many photons l's path stored, and where those beyond its room are (until batch_done). */
static void lane_finish(const pt_lane *l, pt_buf *buf, pt_path *rec)
{
    rec->extra = l->first;
    rec->count = l->n;
    buf->moved |= l->n != l->room;
}

/* Where the batch's photons are once it ends. Traced in place (place: where the last trace put
 * the batch's photons in the map) with every path storing as many as then: there already
 * (stat->held = PT_IN_MAP). Otherwise they are put, in input order (paths end in any order), at
 * the end of the thread's buffer (stat->held = self): each path's from its slot, then from the
 * stage. Returns the batch's photon count. */
static size_t batch_done(pt_buf *buf, uint32_t self, const pt_path *paths, size_t b0, size_t b1,
                         eng_photon *place, eng_trace_batch *stat)
{
    size_t stored = 0;
    for (size_t i = b0; i < b1; i++)
        stored += paths[i].count;
    buf->stage_n = 0;
    if (place && !buf->moved) { /* every slot filled: near holds the batch's photons in order */
        stream_photons(place, buf->near, stored);
        stat->held = PT_IN_MAP;
        return stored;
    }
    if (buf->n + stored > buf->cap) {
        size_t cap = buf->cap ? buf->cap : 1024;
        while (cap < buf->n + stored)
            cap *= 2;
        eng_photon *p = realloc(buf->p, cap * sizeof *p);
        if (!p) {
            buf->oom = 1;
            return stored;
        }
        buf->p = p;
        buf->cap = cap;
    }
    eng_photon *to = buf->p + buf->n;
    stat->held = self;
    stat->at = buf->n;
    buf->n += stored;
    for (size_t i = b0; i < b1; i++) {
        const uint32_t c = paths[i].count, in_slot = c < paths[i].room ? c : paths[i].room;
        if (in_slot) {
            memcpy(to, buf->near + paths[i].slot, in_slot * sizeof *to);
            to += in_slot;
        }
        uint32_t from = paths[i].extra;
        for (uint32_t k = in_slot; k < c; k++, from = buf->link[from])
            *to++ = buf->stage[from];
    }
    return stored;
}

/* Bounce-map photons a batch: a thread traces whole batches, and paths share packets only
 * within one, so which rays travel together does not depend on the thread count. */
#define PT_BATCH 256

/* Traces the paths of in[b0, b1) with `width` paths in flight (1: one after the other): every
 * round asks the tracer for the next surface of each path in flight at once, then moves each
 * on; a path that ends hands its lane to the next photon of the batch. A path does the same
 * whatever travels beside it, so the photons are those of tracing the paths one by one. */
static void trace_batch(const pt_tracer *tr, const eng_frame_scene *fs, const scn_material *default_material,
                        const eng_random_maps *rm, const eng_bounce_photon *in, size_t b0, size_t b1,
                        const eng_trace_settings *s, int width, pt_lane *lanes, pt_buf *buf, uint32_t self,
                        pt_path *paths, size_t last_paths, eng_photon *map, eng_trace_batch *stat)
{
    /* In place when the last trace's counts of the batch's paths (those of its first last_paths
     * inputs) add up to its count there: each path's slot is where that trace put its photons. */
    eng_photon *place = NULL;
    if (map) {
        uint64_t sum = 0;
        for (size_t i = b0; i < b1 && i < last_paths; i++)
            sum += paths[i].count;
        if (sum == stat->photons)
            place = map + stat->at;
    }
    size_t at = 0;
    for (size_t i = b0; i < b1; i++) {
        paths[i].room = place && i < last_paths ? paths[i].count : 0;
        paths[i].slot = at;
        at += paths[i].room;
    }
    if (at > buf->near_cap) {
        eng_photon *q = realloc(buf->near, at * sizeof *q);
        if (!q) { /* the trace fails (photon_trace_with reads buf->oom); the batch holds nothing */
            buf->oom = 1;
            stat->held = self;
            stat->at = buf->n;
            stat->photons = 0;
            stat->rays = 0;
            return;
        }
        buf->near = q;
        buf->near_cap = at;
    }
    buf->moved = 0;
    uint32_t rays_cast = 0;
    pt_lane *act[PT_LANES], *spare[PT_LANES];
    rt_ray rays[PT_LANES];
    rt_hit hits[PT_LANES];
    int found[PT_LANES];
    pt_shade shade[PT_LANES];
    int active = 0, free_count = width;
    for (int i = 0; i < width; i++)
        spare[i] = &lanes[width - 1 - i];
    size_t next = b0;
    for (;;) {
        while (active < width && next < b1) {
            pt_lane *l = spare[free_count - 1];
            if (lane_start(l, next, &in[next], rm, s, place ? buf->near : NULL, &paths[next])) {
                act[active++] = l;
                free_count--;
            } else {
                buf->moved |= paths[next].room != 0;
            }
            next++;
        }
        if (active == 0) {
            stat->photons = (uint32_t)batch_done(buf, self, paths, b0, b1, place, stat);
            stat->rays = rays_cast;
            return;
        }
        rays_cast += (uint32_t)active;
        for (int i = 0; i < active; i++) {
            rays[i] = act[i]->ray;
            hits[i].tri = UINT32_MAX;
        }
        if (tr->intersect_n) {
            tr->intersect_n(tr->state, active, rays, hits, found, &buf->counts);
        } else {
            for (int i = 0; i < active; i++)
                found[i] = tr->intersect(tr->state, rays[i].org, rays[i].dir, rays[i].tnear, &hits[i], &buf->counts);
        }
        /* At each hit: the surface (photon store), the BSDF (the diffuse lobe four hits at a
         * time), the next ray; each step over all paths in flight before the next step. */
        int on[PT_LANES], diffuse[PT_LANES], nd = 0;
        for (int i = 0; i < active; i++) {
            on[i] = lane_surface(act[i], &hits[i], found[i], fs, default_material, rm, s, buf, &shade[i]);
            if (on[i] && shade[i].diffuse)
                diffuse[nd++] = i;
            else if (on[i])
                scatter_one(act[i], &shade[i]);
        }
        for (int j = 0; j < nd; j += 4) {
            pt_lane *dl[4];
            pt_shade *ds[4];
            const int m = nd - j < 4 ? nd - j : 4;
            for (int k = 0; k < m; k++) {
                dl[k] = act[diffuse[j + k]];
                ds[k] = &shade[diffuse[j + k]];
            }
            scatter_diffuse(dl, ds, m);
        }
        int keep = 0;
        for (int i = 0; i < active; i++) {
            pt_lane *l = act[i];
            pt_path *rec = &paths[l->path];
            if (on[i] && lane_next(l, &hits[i], &shade[i], rm, rec)) {
                act[keep++] = l;
            } else {
                lane_finish(l, buf, rec);
                spare[free_count++] = l;
            }
        }
        active = keep;
    }
}

int pt_embree_intersect(const void *state, const float org[3], const float dir[3], float tnear, rt_hit *hit,
                        eng_trace_counts *counts)
{
    (void)counts;
    return rt_intersect_untextured(state, org, dir, tnear, INFINITY, hit);
}

void pt_embree_intersect_n(const void *state, int n, const rt_ray *rays, rt_hit *hits, int *found,
                           eng_trace_counts *counts)
{
    (void)counts;
    for (int i = 0; i < n; i += 4)
        rt_intersect4_untextured(state, n - i < 4 ? n - i : 4, rays + i, hits + i, found + i);
}

eng_result photon_trace(const eng_rt *rt, const eng_frame_scene *fs, const eng_random_maps *rm,
                        const eng_bounce_photon *in, size_t count, const eng_trace_settings *s,
                        eng_photon_map *out, eng_trace_stats *stats, eng_error *err)
{
    const pt_tracer tr = {pt_embree_intersect, rt, pt_embree_intersect_n};
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
     * the trace will use); a buffer only grows, by the doubling batch_done would have done. */
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
    if (count > out->trace_path_capacity) {
        pt_path *more = realloc(out->trace_paths, count * sizeof *more);
        if (!more)
            return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu photons", count);
        out->trace_paths = more;
        out->trace_path_capacity = count;
    }
    pt_path *paths = out->trace_paths;
    if (!ensure_bufs(out, threads))
        return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu photons", count);
    const size_t batches = (count + PT_BATCH - 1) / PT_BATCH;
    const int coherent = out->trace_batch_count == batches; /* the last trace had as many batches */
    if (batches > out->trace_batch_capacity) {
        eng_trace_batch *more = realloc(out->trace_batches, batches * sizeof *more);
        if (!more)
            return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu photons", count);
        out->trace_batches = more;
        out->trace_batch_capacity = batches;
    }
    eng_trace_batch *stat = out->trace_batches;
    /* Where each batch's photons go (frame coherence: what did not move traces the same paths
     * again): where the last trace's counts put them, the map's photons being in input order
     * (trace_batch gives each path its slot there). A batch whose paths store as many as then
     * is then in place; one whose paths store other counts, or any batch of a trace whose
     * batches are not the last trace's, is gathered into the buffer of the thread that traced
     * it. The photons do not depend on where they wait. */
    eng_photon *home = NULL;
    const size_t last_paths = coherent ? out->trace_path_count : 0;
    if (coherent) {
        size_t stored = 0;
        for (size_t b = 0; b < batches; b++) {
            stat[b].at = stored;
            stored += stat[b].photons;
        }
        if (stored > out->capacity) {
            eng_photon *p = realloc(out->photons, stored * sizeof *p);
            if (p) {
                out->photons = p;
                out->capacity = stored;
            }
        }
        if (stored <= out->capacity)
            home = out->photons;
    }
    pt_buf *bufs = out->trace_bufs;
    for (int t = 0; t < threads; t++) {
        bufs[t].n = bufs[t].stage_n = 0;
        bufs[t].oom = 0;
        memset(&bufs[t].counts, 0, sizeof bufs[t].counts);
    }
    const scn_material default_material = eng_material_of(fs->scene, -1);
    const int width = tr->intersect_n ? PT_LANES : 1;
    int lanes_oom = 0;
#pragma omp parallel num_threads(threads) reduction(| : lanes_oom)
    {
        const int t = omp_get_thread_num();
        pt_buf *mine = &bufs[t];
        /* whole cache lines of its own: the threads' lanes never share one */
        pt_lane *lanes = aligned_alloc(64, ((size_t)width * sizeof *lanes + 63) / 64 * 64);
        lanes_oom = !lanes;
        /* The batches go to whichever thread is free (guided: long runs of consecutive batches
         * first, single ones at the end): the threads finish together whatever else the cores
         * run (a frame's GL passes beside the trace). */
#pragma omp for schedule(guided) nowait
        for (ptrdiff_t b = 0; b < (ptrdiff_t)batches; b++) {
            const size_t b0 = (size_t)b * PT_BATCH, b1 = b0 + PT_BATCH < count ? b0 + PT_BATCH : count;
            if (lanes)
                trace_batch(tr, fs, &default_material, rm, in, b0, b1, s, width, lanes, mine, (uint32_t)t, paths,
                            last_paths, home, &stat[b]);
        }
#if defined(__SSE2__)
        _mm_sfence(); /* the photons streamed into the map, visible before the team's barrier */
#endif
        free(lanes);
    }
    out->trace_batch_count = lanes_oom ? 0 : batches;
    out->trace_path_count = lanes_oom ? 0 : count;
    if (lanes_oom)
        return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu photons", count);

    size_t total = 0, away = 0;
    int oom = 0;
    for (int t = 0; t < threads; t++)
        oom |= bufs[t].oom;
    for (size_t b = 0; b < batches; b++) {
        total += stat[b].photons;
        away += stat[b].held != PT_IN_MAP;
    }
    if (!oom && total > out->capacity) {
        eng_photon *p = realloc(out->photons, total * sizeof *p); /* keeps the photons in place */
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
        out->trace_batch_count = out->trace_path_count = 0;
        return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu stored photons", total);
    }
    if (out->want_source) {
        size_t k = 0;
        for (size_t i = 0; i < count; i++)
            for (uint32_t c = 0; c < paths[i].count; c++)
                out->source[k++] = (uint32_t)i;
    }
    /* The map: batch b's photons belong after those of the batches before it (fin). Where no
     * batch stored another count than last time, every batch is there already. Otherwise those
     * in the map that must move up move first, from the last batch down, then those that must
     * move down, from the first up (no move overwrites photons still to move: the batches keep
     * their order), then the batches in the threads' buffers are copied, on all threads. */
    if (away) {
        size_t *fin = malloc(batches * sizeof *fin);
        if (!fin) {
            out->trace_batch_count = out->trace_path_count = 0;
            return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu stored photons", total);
        }
        for (size_t b = 0, f = 0; b < batches; b++) {
            fin[b] = f;
            f += stat[b].photons;
        }
        eng_photon *map = out->photons;
        for (size_t b = batches; b-- > 0;)
            if (stat[b].held == PT_IN_MAP && fin[b] > stat[b].at)
                memmove(map + fin[b], map + stat[b].at, stat[b].photons * sizeof *map);
        for (size_t b = 0; b < batches; b++)
            if (stat[b].held == PT_IN_MAP && fin[b] < stat[b].at)
                memmove(map + fin[b], map + stat[b].at, stat[b].photons * sizeof *map);
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads)
        for (ptrdiff_t b = 0; b < (ptrdiff_t)batches; b++)
            if (stat[b].held != PT_IN_MAP && stat[b].photons)
                memcpy(map + fin[b], bufs[stat[b].held].p + stat[b].at, stat[b].photons * sizeof *map);
        free(fin);
    }
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
    return ENG_OK;
}

void photon_map_free(eng_photon_map *m)
{
    if (!m)
        return;
    free(m->photons);
    free(m->source);
    for (int t = 0; t < m->trace_buf_count; t++) {
        free(m->trace_bufs[t].p);
        free(m->trace_bufs[t].stage);
        free(m->trace_bufs[t].link);
        free(m->trace_bufs[t].near);
    }
    free(m->trace_bufs);
    free(m->trace_paths);
    free(m->trace_batches);
    memset(m, 0, sizeof *m);
}
