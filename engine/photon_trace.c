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
 * Determinism across thread counts: input photon i writes only slots
 * [i·max_bounces, (i+1)·max_bounces) of a scratch array; the map is then compacted
 * sequentially in input order, and the statistics are summed sequentially after that.
 *
 * Storage rule: a photon is stored only on surfaces with a diffuse or glossy lobe
 * (bsdf_stores_photons): the photon map feeds the final gather, which cannot use photons on
 * purely specular surfaces (mirror, glass); such surfaces only redirect the path (caustics).
 * A path ends when it has stored max_bounces photons, is absorbed, leaves the scene, or
 * reaches bounce index PT_MAX_BOUNCE (a bound on specular chains). */
#include "bsdf.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PT_MAX_BOUNCE 15 /* last bounce index a photon can be stored with (eng_trace_stats has 16) */
#define PT_MAX_STORED (PT_MAX_BOUNCE - 1)

static float dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static int has_power(const float p[3])
{
    return p[0] > 0.0f || p[1] > 0.0f || p[2] > 0.0f;
}

/* Traces one bounce-map photon; writes its stored photons to slot[0..] and returns how many. */
static int trace_path(const eng_rt *rt, const scn_scene *scene, const eng_random_maps *rm,
                      const eng_bounce_photon *bp, int max_stored, uint32_t salt, eng_photon *slot)
{
    if (!has_power(bp->power))
        return 0;
    const uint32_t mask = rm->size - 1;
    const uint32_t seed = rmap_hash3(bp->position, salt);
    float power[3] = {bp->power[0], bp->power[1], bp->power[2]};
    float rho = bp->path_density;
    float eta = bp->ior > 0.0f ? bp->ior : 1.0f;
    float org[3] = {bp->position[0], bp->position[1], bp->position[2]};
    float dir[3] = {bp->direction[0], bp->direction[1], bp->direction[2]};
    float len = sqrtf(dot3(dir, dir));
    if (!(len > 0.0f) || !isfinite(len))
        return 0;
    for (int i = 0; i < 3; i++)
        dir[i] /= len;
    /* The bounce-map photon sits on the surface it left; no normal is known there, so the
     * first ray skips a short distance instead of offsetting its origin. */
    float tnear = bsdf_offset_eps(org);
    int stored = 0;
    for (uint32_t k = 0; 2 + k <= PT_MAX_BOUNCE; k++) {
        rt_hit h;
        if (!rt_intersect(rt, org, dir, tnear, INFINITY, &h))
            break;
        const float wi[3] = {-dir[0], -dir[1], -dir[2]};
        /* Shading normal, unless interpolation put wi on the other side of it than the true
         * surface: then the geometric normal, so scattering stays on the photon's side. */
        float n[3];
        float cg = dot3(h.geom_normal, wi), cs = dot3(h.normal, wi);
        memcpy(n, ((cg >= 0.0f) == (cs >= 0.0f)) ? h.normal : h.geom_normal, sizeof n);
        scn_material m = eng_material_of(scene, h.material);
        if (bsdf_stores_photons(&m)) {
            eng_photon *ph = &slot[stored++];
            float side = dot3(n, wi) >= 0.0f ? 1.0f : -1.0f;
            for (int i = 0; i < 3; i++) {
                ph->position[i] = h.position[i];
                ph->direction[i] = wi[i];
                ph->power[i] = power[i];
                ph->normal[i] = side * n[i];
            }
            ph->path_density = rho;
            ph->bounce = 2 + k;
            if (stored == max_stored)
                break;
        }
        uint32_t e = (seed + k) & mask;
        bsdf_sample rnd = {rm->uniform + 4 * (size_t)e, rm->cosine + 4 * (size_t)e};
        float wo[3], w[3], density;
        if (bsdf_scatter(&m, n, wi, &eta, &rnd, wo, w, &density) == BSDF_ABSORBED)
            break;
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
    return stored;
}

eng_result photon_trace(const eng_rt *rt, const eng_frame_scene *fs, const eng_random_maps *rm,
                        const eng_bounce_photon *in, size_t count, const eng_trace_settings *s,
                        eng_photon_map *out, eng_trace_stats *stats, eng_error *err)
{
    if (s->max_bounces < 1 || s->max_bounces > PT_MAX_STORED)
        return eng_fail(err, ENG_ERR_INVALID, "photon trace: max_bounces %d outside 1..%d", s->max_bounces,
                        PT_MAX_STORED);
    if (rm->size == 0 || (rm->size & (rm->size - 1)) != 0 || !rm->uniform || !rm->cosine)
        return eng_fail(err, ENG_ERR_INVALID, "photon trace: random maps not created");
    const size_t per = (size_t)s->max_bounces;
    if (count > SIZE_MAX / per / sizeof(eng_photon))
        return eng_fail(err, ENG_ERR_NOMEM, "photon trace: %zu photons × %zu bounces overflow", count, per);
    eng_photon *slots = malloc((count ? count * per : 1) * sizeof *slots);
    unsigned char *n_stored = calloc(count ? count : 1, 1);
    if (!slots || !n_stored) {
        free(slots);
        free(n_stored);
        return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu photons", count);
    }
    const int threads = s->threads > 0 ? s->threads : 1;
    const scn_scene *scene = fs->scene;
    const uint32_t salt = s->salt;
    const int max_stored = s->max_bounces;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (ptrdiff_t i = 0; i < (ptrdiff_t)count; i++)
        n_stored[i] = (unsigned char)trace_path(rt, scene, rm, &in[i], max_stored, salt, slots + (size_t)i * per);

    size_t total = 0;
    for (size_t i = 0; i < count; i++)
        total += n_stored[i];
    if (total > out->capacity) {
        eng_photon *p = realloc(out->photons, total * sizeof *p);
        if (!p) {
            free(slots);
            free(n_stored);
            return eng_fail(err, ENG_ERR_NOMEM, "photon trace: out of memory for %zu stored photons", total);
        }
        out->photons = p;
        out->capacity = total;
    }
    size_t at = 0;
    for (size_t i = 0; i < count; i++) {
        if (n_stored[i] == 0)
            continue; /* out->photons may still be NULL when nothing was stored */
        memcpy(out->photons + at, slots + i * per, n_stored[i] * sizeof(eng_photon));
        at += n_stored[i];
    }
    out->count = total;
    free(slots);
    free(n_stored);

    if (stats) {
        memset(stats, 0, sizeof *stats);
        for (size_t i = 0; i < count; i++)
            if (has_power(in[i].power))
                stats->emitted++;
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
    memset(m, 0, sizeof *m);
}
