/* photonset.c — photons.map compared as a set of photons keyed by their path, not pixel by
 * pixel.
 *
 * photons.map stores one photon per pixel, in trace order: the photons of one bounce-map photon's
 * path are consecutive, with increasing bounce numbers (photon_trace.c stores bounce 2 + k at
 * the k-th surface hit), and unused pixels are zero. One extra path shifts every later photon
 * by a pixel, so a pixel comparison calls the whole map different. Here both maps are cut into
 * paths (a new path starts where the bounce number does not increase) and the two sequences
 * of paths are aligned with Myers' O(ND) difference algorithm (E. W. Myers, "An O(ND)
 * Difference Algorithm and Its Variations", Algorithmica 1986, §3 and §4b) on each path's
 * content hash: a path present on one side only is added or removed whole; within a run of
 * edits, removed and added paths are paired in order and their photons compared by bounce (the
 * key of a photon is thus its path — the aligned position standing for the bounce-map texel,
 * which the map does not record — and its bounce). A matched photon changes when some channel
 * differs by more than fail and failrelative; the buffer then fails like any other: more
 * photons added, removed or changed than failpercent % of the larger map, or a matched
 * difference over hardfail.
 *
 * The alignment is bounded (REP_PHOTON_MAX_EDITS path edits): beyond it the maps are called
 * different whole (every path of the smaller map changed, the rest added or removed).
 */
#include "rep_compare.h"
#include "rep_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define REP_PHOTON_MAX_EDITS 500

static const char *const CH[14] = {"position.X", "position.Y", "position.Z", "direction.X", "direction.Y",
                                   "direction.Z", "power.R",    "power.G",    "power.B",     "normal.X",
                                   "normal.Y",   "normal.Z",   "density",    "bounce"};
#define BOUNCE 13

typedef struct pmap {
    size_t n;      /* photons */
    float *ph;     /* n × 14, canonical channel order */
    size_t paths;
    size_t *start; /* paths + 1 offsets into the photons */
    uint64_t *hash;
} pmap;

static int index_of(const eng_buffer *b, const char *name)
{
    for (int c = 0; c < b->channel_count; c++)
        if (strcmp(b->channels[c], name) == 0)
            return c;
    return -1;
}

int rep_is_photon_map(const eng_buffer *b)
{
    if (strcmp(b->name ? b->name : "", "photons.map") != 0 || b->channel_count != 14)
        return 0;
    for (int k = 0; k < 14; k++)
        if (index_of(b, CH[k]) < 0)
            return 0;
    return 1;
}

static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const unsigned char *c = p;
    for (size_t i = 0; i < n; i++)
        h = (h ^ c[i]) * 1099511628211ull;
    return h;
}

static void load(const eng_buffer *b, pmap *m)
{
    int idx[14];
    for (int k = 0; k < 14; k++)
        idx[k] = index_of(b, CH[k]);
    size_t px = (size_t)b->width * (size_t)b->height, nc = (size_t)b->channel_count;
    m->ph = rep_xcalloc(px ? px : 1, 14 * sizeof *m->ph);
    m->n = 0;
    for (size_t i = 0; i < px; i++) {
        const float *s = b->data + i * nc;
        if (!(s[idx[BOUNCE]] > 0))
            continue; /* an unused pixel */
        for (int k = 0; k < 14; k++)
            m->ph[m->n * 14 + (size_t)k] = s[idx[k]];
        m->n++;
    }
    m->start = rep_xcalloc(m->n + 1, sizeof *m->start);
    m->paths = 0;
    for (size_t i = 0; i < m->n; i++)
        if (i == 0 || !(m->ph[i * 14 + BOUNCE] > m->ph[(i - 1) * 14 + BOUNCE]))
            m->start[m->paths++] = i;
    m->start[m->paths] = m->n;
    m->hash = rep_xcalloc(m->paths + 1, sizeof *m->hash);
    for (size_t p = 0; p < m->paths; p++)
        m->hash[p] = fnv(1469598103934665603ull, &m->ph[m->start[p] * 14],
                         (m->start[p + 1] - m->start[p]) * 14 * sizeof(float));
}

static void pmap_free(pmap *m)
{
    free(m->ph);
    free(m->start);
    free(m->hash);
}

/* Compares two photons; returns whether one differs over tol, and folds |Δ| into m. */
static int photon_diff(const float *a, const float *b, const rep_tol *tol, rep_metrics *m)
{
    int over = 0;
    for (int k = 0; k < 14; k++) {
        double x = a[k], y = b[k];
        if (!isfinite(x) || !isfinite(y)) {
            if (memcmp(&a[k], &b[k], sizeof(float)) != 0) {
                m->nonfinite_mismatch++;
                over = 1;
            }
            continue;
        }
        double d = fabs(x - y), big = fmax(fabs(x), fabs(y)), rel = big > 0 ? d / big : 0;
        if (d > m->max_abs) {
            m->max_abs = d;
            snprintf(m->max_channel, sizeof m->max_channel, "%s", CH[k]);
        }
        if (d > tol->fail && rel > tol->failrelative)
            over = 1;
    }
    return over;
}

/* Paired paths a (run) and b (golden): photons matched by bounce. */
static void pair_paths(const pmap *r, size_t pa, const pmap *g, size_t pb, const rep_tol *tol, rep_metrics *m,
                       rep_photon_diff *pd)
{
    size_t i = r->start[pa], ie = r->start[pa + 1], j = g->start[pb], je = g->start[pb + 1];
    while (i < ie || j < je) {
        float bi = i < ie ? r->ph[i * 14 + BOUNCE] : INFINITY, bj = j < je ? g->ph[j * 14 + BOUNCE] : INFINITY;
        if (bi < bj) {
            pd->added++;
            i++;
        } else if (bj < bi) {
            pd->removed++;
            j++;
        } else {
            if (memcmp(&r->ph[i * 14], &g->ph[j * 14], 14 * sizeof(float)) != 0) {
                m->values_differing++;
                if (photon_diff(&r->ph[i * 14], &g->ph[j * 14], tol, m))
                    pd->changed++;
                else
                    pd->within++;
            }
            i++;
            j++;
        }
    }
}

static size_t path_len(const pmap *m, size_t p)
{
    return m->start[p + 1] - m->start[p];
}

/* A run of edits: del golden paths [g0, g1) replaced by run paths [r0, r1). */
static void hunk(const pmap *r, size_t r0, size_t r1, const pmap *g, size_t g0, size_t g1, const rep_tol *tol,
                 rep_metrics *m, rep_photon_diff *pd)
{
    size_t k = 0;
    for (; r0 + k < r1 && g0 + k < g1; k++)
        pair_paths(r, r0 + k, g, g0 + k, tol, m, pd);
    for (size_t p = r0 + k; p < r1; p++) {
        pd->added += path_len(r, p);
        pd->paths_added++;
    }
    for (size_t p = g0 + k; p < g1; p++) {
        pd->removed += path_len(g, p);
        pd->paths_removed++;
    }
}

/* Myers' greedy forward search with the V array of every d kept for the walk back. Returns the
 * edit distance, or -1 beyond max_d. */
static long myers(const uint64_t *a, long n, const uint64_t *b, long mm, long max_d, long **trace_out)
{
    long off = max_d + 1, width = 2 * max_d + 3;
    long *v = rep_xcalloc((size_t)width, sizeof *v);
    long *trace = NULL;
    for (long d = 0; d <= max_d; d++) {
        for (long k = -d; k <= d; k += 2) {
            long x = (k == -d || (k != d && v[off + k - 1] < v[off + k + 1])) ? v[off + k + 1] : v[off + k - 1] + 1;
            long y = x - k;
            while (x < n && y < mm && a[x] == b[y])
                x++, y++;
            v[off + k] = x;
            if (x >= n && y >= mm) {
                trace = rep_xrealloc(trace, (size_t)(d + 1) * (size_t)width * sizeof *trace);
                memcpy(trace + (size_t)d * (size_t)width, v, (size_t)width * sizeof *v);
                *trace_out = trace;
                free(v);
                return d;
            }
        }
        trace = rep_xrealloc(trace, (size_t)(d + 1) * (size_t)width * sizeof *trace);
        memcpy(trace + (size_t)d * (size_t)width, v, (size_t)width * sizeof *v);
    }
    free(v);
    free(trace);
    return -1;
}

rep_verdict rep_photon_compare(const eng_buffer *run, const eng_buffer *golden, const rep_tol *tol, rep_metrics *m,
                               rep_photon_diff *pd)
{
    memset(m, 0, sizeof *m);
    memset(pd, 0, sizeof *pd);
    m->max_x = m->max_y = m->first_fail_x = m->first_fail_y = m->nf_x = m->nf_y = -1;
    pmap r, g;
    load(run, &r);
    load(golden, &g);
    pd->run = r.n;
    pd->golden = g.n;
    long max_d = REP_PHOTON_MAX_EDITS, *trace = NULL;
    long d = myers(r.hash, (long)r.paths, g.hash, (long)g.paths, max_d, &trace);
    if (d < 0) {
        pd->unaligned = 1;
        hunk(&r, 0, r.paths, &g, 0, g.paths, tol, m, pd);
    } else {
        /* Walk back from (n, m): each step is a diagonal run (equal paths) then one edit. Edits
         * between two equal runs form a hunk. */
        long off = max_d + 1, width = 2 * max_d + 3;
        long x = (long)r.paths, y = (long)g.paths;
        long hx1 = x, hy1 = y; /* end of the current hunk */
        for (long dd = d; dd > 0; dd--) {
            const long *v = trace + (size_t)(dd - 1) * (size_t)width;
            long k = x - y;
            long pk = (k == -dd || (k != dd && v[off + k - 1] < v[off + k + 1])) ? k + 1 : k - 1;
            long px = v[off + pk], py = px - pk;
            /* the snake (x, y) back to the edit's end */
            long ex = pk == k + 1 ? px : px + 1, ey = pk == k + 1 ? py + 1 : py;
            if (x != ex) { /* equal paths between: the hunk after them is closed */
                hunk(&r, (size_t)x, (size_t)hx1, &g, (size_t)y, (size_t)hy1, tol, m, pd);
                hx1 = ex;
                hy1 = ey;
            }
            x = px;
            y = py;
        }
        hunk(&r, (size_t)x, (size_t)hx1, &g, (size_t)y, (size_t)hy1, tol, m, pd);
    }
    free(trace);
    m->pixels = r.n > g.n ? r.n : g.n;
    m->values = m->pixels * 14;
    m->fail_pixels = pd->added + pd->removed + pd->changed;
    m->fail_percent = m->pixels ? fmin(100.0, 100.0 * (double)m->fail_pixels / (double)m->pixels) : 0;
    m->warn_pixels = m->fail_pixels + pd->within;
    m->warn_percent = m->pixels ? fmin(100.0, 100.0 * (double)m->warn_pixels / (double)m->pixels) : 0;
    if (m->max_abs > 0)
        m->max_x = m->max_y = 0; /* a photon has no pixel: the channel tells which quantity */
    pmap_free(&r);
    pmap_free(&g);
    if (pd->added + pd->removed + pd->changed + pd->within == 0 && m->values_differing == 0)
        return REP_V_BITEXACT;
    if (m->nonfinite_mismatch)
        m->fail_why |= REP_WHY_NONFINITE;
    if (m->fail_percent > tol->failpercent)
        m->fail_why |= REP_WHY_PERCENT;
    if (m->max_abs > tol->hardfail)
        m->fail_why |= REP_WHY_HARD;
    if (tol->exact)
        m->fail_why |= REP_WHY_EXACT;
    if (m->fail_why)
        return REP_V_FAIL;
    if (m->warn_percent > tol->warnpercent)
        m->warn_why |= REP_WHY_PERCENT;
    if (m->max_abs > tol->hardwarn)
        m->warn_why |= REP_WHY_HARD;
    return m->warn_why ? REP_V_WARN : REP_V_WITHIN;
}
