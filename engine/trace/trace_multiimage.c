/* trace_multiimage.c — multi-image photon tracing (trace_method.h, "photon_trace":
 * "multi-image"; 004_77cf4e8ac7e68a89.txt, Yao et al. EGSR 2010): photon bounces find their
 * next surface in image space, against `multi_image_maps` cube G-buffers (position, normal,
 * material per texel) instead of a ray tracer.
 *
 * Map placement (§4.1–4.2): 48 candidate centres (§4.1: "30 to 50"; a Halton sequence in the
 * scene's bounding box, 5 % in from its faces); each casts a coarse cube of rays, 32×32 per
 * face as §4.2 renders its coverage maps, whose hits are its sample pixels with Eq. 1's
 * areas; a candidate that sees back faces in more than 5 % of its hits is inside an object
 * and gets no area. mi_select picks the centres greedily
 * by new coverage A(v|C) and runs the paper's update steps (add the best outsider, remove the
 * weakest member) until they change nothing. Whether candidate c sees a sample point is an
 * Embree occlusion query from c plus the point's facing (the paper renders shadow maps for
 * it; the query is the exact answer). The selection is a pure function of the frame's pose
 * and runs again whenever a draw moved — not the paper's progressive one-step update every
 * 5 frames, whose result would depend on the frames rendered before (record --resume must
 * give the same frame). The cube G-buffers, multi_image_size texels per face side, are
 * ray-cast on the CPU with Embree from each centre (deterministic; the GL G-buffer shaders
 * would need a cube-map variant) and re-cast when a draw moved.
 *
 * Intersection (§5.1–5.2): mi_intersect_map per map (false position along the ray, Eq. 2's
 * angular test with ε = 0.001), mi_classify across maps (types A–D, nearest accepted point
 * wins). A ray no map resolves is traced by Embree or dropped (multi_image_miss), counted per
 * frame. With multi_image_compare every ray is also traced by Embree and the hits that lie on
 * the same draw within 1 cm are counted (the bench's agreement measure).
 *
 * Determinism: every ray and texel is a pure function of the maps; the parallel loops write
 * per-index slots and the counts are integer sums. */
#include "bsdf.h"
#include "multiimage.h"
#include "trace_method.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MI_CANDIDATES 48      /* 004 §4.1: "a set U of 30 to 50 random points" */
#define MI_COVERAGE_SIZE 32   /* texels per face side of a candidate's coverage cube (§4.2) */
#define MI_UPDATES 5          /* 004 §4.1: "the initial updating needs only 2 to 5 update steps" */
#define MI_BACKFACE_SHARE 0.05
#define MI_STEPS 32           /* samples along the ray that bracket a crossing */
#define MI_ITERATIONS 12      /* false-position iterations per crossing (§5.1: "3 to 5" suffice) */
#define MI_ON_SURFACE 1e-3f  /* m: a ray point this close to the plane the map sees there is on it */
#define MI_AGREE 0.01f        /* 1 cm: hits that agree with Embree's, and one point seen twice */

/* ---------------------------------------------------------------- cube addressing */

void mi_face_axis(int face, float axis[3])
{
    axis[0] = axis[1] = axis[2] = 0.0f;
    axis[face / 2] = (face & 1) ? -1.0f : 1.0f;
}

/* GL's cube-map table (major axis, sc, tc) and its inverse. */
static void face_dir(int face, float sc, float tc, float d[3])
{
    switch (face) {
    case 0: d[0] = 1.0f; d[1] = -tc; d[2] = -sc; break;
    case 1: d[0] = -1.0f; d[1] = -tc; d[2] = sc; break;
    case 2: d[0] = sc; d[1] = 1.0f; d[2] = tc; break;
    case 3: d[0] = sc; d[1] = -1.0f; d[2] = -tc; break;
    case 4: d[0] = sc; d[1] = -tc; d[2] = 1.0f; break;
    default: d[0] = -sc; d[1] = -tc; d[2] = -1.0f; break;
    }
}

void mi_texel_dir(int size, size_t texel, float dir[3])
{
    size_t per = (size_t)size * (size_t)size;
    int face = (int)(texel / per);
    size_t in = texel % per;
    float sc = 2.0f * ((float)(in % (size_t)size) + 0.5f) / (float)size - 1.0f;
    float tc = 2.0f * ((float)(in / (size_t)size) + 0.5f) / (float)size - 1.0f;
    face_dir(face, sc, tc, dir);
}

size_t mi_cube_texel(int size, const float d[3])
{
    float ax = fabsf(d[0]), ay = fabsf(d[1]), az = fabsf(d[2]);
    int face;
    float ma, sc, tc;
    if (ax >= ay && ax >= az) {
        face = d[0] >= 0.0f ? 0 : 1;
        ma = ax;
        sc = d[0] >= 0.0f ? -d[2] : d[2];
        tc = -d[1];
    } else if (ay >= az) {
        face = d[1] >= 0.0f ? 2 : 3;
        ma = ay;
        sc = d[0];
        tc = d[1] >= 0.0f ? d[2] : -d[2];
    } else {
        face = d[2] >= 0.0f ? 4 : 5;
        ma = az;
        sc = d[2] >= 0.0f ? d[0] : -d[0];
        tc = -d[1];
    }
    if (!(ma > 0.0f))
        return 0;
    int i = (int)floorf((sc / ma + 1.0f) * 0.5f * (float)size);
    int j = (int)floorf((tc / ma + 1.0f) * 0.5f * (float)size);
    i = i < 0 ? 0 : i >= size ? size - 1 : i;
    j = j < 0 ? 0 : j >= size ? size - 1 : j;
    return ((size_t)face * (size_t)size + (size_t)j) * (size_t)size + (size_t)i;
}

static float dot3(const float a[3], const float b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* ---------------------------------------------------------------- §4: map placement */

double mi_texel_area(const float v[3], const float x[3], const float n[3], const float fwd[3], int size)
{
    /* 004 §4.2 Eq. 1 (derived in its Appendix A): a texel spans 4/N of the unit-distance face
     * plane; its footprint grows with the cube of the depth along r and with 1/cos α. */
    double xv[3] = {(double)x[0] - v[0], (double)x[1] - v[1], (double)x[2] - v[2]};
    double depth = xv[0] * fwd[0] + xv[1] * fwd[1] + xv[2] * fwd[2];
    double dist = sqrt(xv[0] * xv[0] + xv[1] * xv[1] + xv[2] * xv[2]);
    double den = fabs(xv[0] * n[0] + xv[1] * n[1] + xv[2] * n[2]);
    if (den < 0.05 * dist)
        den = 0.05 * dist;
    if (!(den > 0.0))
        return 0.0;
    return 4.0 / ((double)size * size) * depth * depth * depth / den;
}

/* A(v|C) with C given as a membership list, skipping member `except` (−1: none). */
static double new_area(int npix, const double *area, mi_visible_fn visible, void *user, int v, const int *set,
                       int set_n, int except)
{
    double sum = 0.0;
    for (int p = 0; p < npix; p++) {
        double a = area[(size_t)v * (size_t)npix + (size_t)p];
        if (a <= 0.0)
            continue;
        int seen = 0;
        for (int i = 0; i < set_n && !seen; i++)
            if (set[i] != except)
                seen = visible(user, set[i], v, p);
        if (!seen)
            sum += a;
    }
    return sum;
}

static int in_set(const int *set, int n, int v)
{
    for (int i = 0; i < n; i++)
        if (set[i] == v)
            return 1;
    return 0;
}

/* The outside candidate of largest A(v|C); ties to the lower index. */
static int best_outside(int ncand, int npix, const double *area, mi_visible_fn visible, void *user, const int *set,
                        int n)
{
    int best = -1;
    double best_a = -1.0;
    for (int v = 0; v < ncand; v++) {
        if (in_set(set, n, v))
            continue;
        double a = new_area(npix, area, visible, user, v, set, n, -1);
        if (a > best_a) {
            best_a = a;
            best = v;
        }
    }
    return best;
}

void mi_select(int ncand, int npix, const double *area, mi_visible_fn visible, void *user, int k, int updates,
               int *chosen)
{
    int set[ENG_MAX_TRACE_MAPS + 1];
    int n = 0;
    if (k > ncand)
        k = ncand;
    if (k > ENG_MAX_TRACE_MAPS)
        k = ENG_MAX_TRACE_MAPS;
    while (n < k) {
        int b = best_outside(ncand, npix, area, visible, user, set, n);
        set[n++] = b;
    }
    for (int step = 0; step < updates && k < ncand; step++) {
        int u = best_outside(ncand, npix, area, visible, user, set, n);
        set[n] = u;
        int worst = -1;
        double worst_a = INFINITY;
        for (int i = 0; i <= n; i++) {
            double a = new_area(npix, area, visible, user, set[i], set, n + 1, set[i]);
            if (a < worst_a) {
                worst_a = a;
                worst = i;
            }
        }
        if (worst == n) /* the added one is the weakest: the set is stable */
            break;
        set[worst] = u;
    }
    memcpy(chosen, set, (size_t)k * sizeof *chosen);
}

/* ---------------------------------------------------------------- §5: intersection */

float mi_angular_error(const float x[3], const float r[3], const float p[3])
{
    /* 004 §5.2 Eq. 2: e = 1 − (p − x)/‖p − x‖ · r ≈ θ²/2. */
    float d[3] = {p[0] - x[0], p[1] - x[1], p[2] - x[2]};
    float len = sqrtf(dot3(d, d));
    if (!(len > 0.0f))
        return 2.0f;
    return 1.0f - dot3(d, r) / len;
}

/* f(d) of mi_intersect_map; *texel gets the texel looked up. */
static float signed_depth(const mi_map *m, const float org[3], const float dir[3], float d, size_t *texel)
{
    float w[3];
    for (int i = 0; i < 3; i++)
        w[i] = org[i] + d * dir[i] - m->centre[i];
    size_t t = mi_cube_texel(m->size, w);
    *texel = t;
    if (m->draw[t] < 0)
        return -INFINITY; /* nothing in that direction: the ray point is in front of "infinity" */
    const float *p = m->position + 3 * t, *n = m->normal + 3 * t;
    float pc[3] = {m->centre[0] - p[0], m->centre[1] - p[1], m->centre[2] - p[2]};
    float side = dot3(pc, n) >= 0.0f ? 1.0f : -1.0f;
    float q[3] = {w[0] + pc[0], w[1] + pc[1], w[2] + pc[2]}; /* ray point − p */
    return -side * dot3(q, n);
}

/* df/dd along the ray for texel t's plane (f of signed_depth is linear in d there); +∞ where
 * the ray runs parallel to it or away from it, so a step a − f/slope goes nowhere. */
static float plane_slope(const mi_map *m, const float dir[3], size_t t)
{
    const float *p = m->position + 3 * t, *n = m->normal + 3 * t;
    float pc[3] = {m->centre[0] - p[0], m->centre[1] - p[1], m->centre[2] - p[2]};
    float side = dot3(pc, n) >= 0.0f ? 1.0f : -1.0f;
    float slope = -side * dot3(dir, n);
    return slope > 0.0f ? slope : INFINITY;
}

/* The point of texel t's plane on the line from the centre through the ray point at d. */
static int plane_point(const mi_map *m, const float org[3], const float dir[3], float d, size_t t, float out[3])
{
    if (m->draw[t] < 0)
        return 0;
    const float *p = m->position + 3 * t, *n = m->normal + 3 * t;
    float w[3], pc[3];
    for (int i = 0; i < 3; i++) {
        w[i] = org[i] + d * dir[i] - m->centre[i];
        pc[i] = p[i] - m->centre[i];
    }
    float den = dot3(w, n);
    if (fabsf(den) < 1e-12f) {
        memcpy(out, p, 3 * sizeof(float));
        return 1;
    }
    float s = dot3(pc, n) / den;
    for (int i = 0; i < 3; i++)
        out[i] = m->centre[i] + s * w[i];
    return 1;
}

mi_type mi_intersect_map(const mi_map *m, const float org[3], const float dir[3], float dmin, float dmax, int steps,
                         int iterations, float eps, mi_candidate *out)
{
    out->type = MI_TYPE_A;
    out->error = 0.0f;
    if (!(dmax > dmin) || steps < 1)
        return MI_TYPE_A;
    const float h = (dmax - dmin) / (float)steps;
    size_t ta;
    float a = dmin, fa = signed_depth(m, org, dir, a, &ta);
    const float tol = 1e-6f * (1.0f + dmax);
    for (int i = 1; i <= steps; i++) {
        size_t tb;
        float b = i == steps ? dmax : dmin + h * (float)i;
        float fb = signed_depth(m, org, dir, b, &tb);
        if (fa < 0.0f && fb < 0.0f && isfinite(fa)) {
            /* No sign change between the samples, but the plane of a's texel may still be
             * crossed before b (§5.1's planar approximation): a surface seen only over a
             * short stretch of the ray, e.g. floor next to an object's foot. Its crossing is
             * an overshoot when f there is ≥ 0: the bracket ends there. */
            float dp = a + (-fa) / plane_slope(m, dir, ta);
            if (dp > a && dp < b) {
                size_t tp;
                float fp = signed_depth(m, org, dir, dp, &tp);
                if (fp >= 0.0f) {
                    b = dp;
                    fb = fp;
                    tb = tp;
                }
            }
        }
        if (fa < 0.0f && fb >= 0.0f) {
            /* 004 §5.1: false position between an undershoot and an overshoot, in the
             * Illinois variant: an end kept twice has its f halved, so the bracket shrinks
             * from both sides where f bends (a corner seen across texels). */
            float lo = a, flo = fa, hi = b, fhi = fb, d = b, fd = fb;
            size_t td = tb;
            int kept = 0;
            for (int it = 0; it < iterations; it++) {
                d = isfinite(flo) && fhi > flo ? lo - flo * (hi - lo) / (fhi - flo) : 0.5f * (lo + hi);
                if (!(d >= lo && d <= hi))
                    d = 0.5f * (lo + hi);
                fd = signed_depth(m, org, dir, d, &td);
                if (fd < 0.0f) {
                    lo = d;
                    flo = fd;
                    if (kept > 0)
                        fhi *= 0.5f;
                    kept = kept > 0 ? kept + 1 : 1;
                } else {
                    hi = d;
                    fhi = fd;
                    if (kept < 0)
                        flo *= 0.5f;
                    kept = kept < 0 ? kept - 1 : -1;
                }
                if (fabsf(fd) <= tol)
                    break;
            }
            if (fd < 0.0f) { /* end on the overshoot: the surface the map sees there */
                d = hi;
                signed_depth(m, org, dir, d, &td);
            }
            /* Planar approximation (§5.1): where the texel's plane is crossed by the ray and
             * the map sees a surface through that point (f there within MI_ON_SURFACE of 0),
             * that crossing is the hit, exactly on the ray. */
            float p[3];
            int have = 0;
            if (m->draw[td] >= 0) {
                float fs = signed_depth(m, org, dir, d, &td);
                float dp = d - fs / plane_slope(m, dir, td);
                size_t tp;
                if (dp >= a && dp <= b && fabsf(signed_depth(m, org, dir, dp, &tp)) <= MI_ON_SURFACE) {
                    for (int c = 0; c < 3; c++)
                        p[c] = org[c] + dp * dir[c];
                    have = 1;
                }
            }
            if (have || plane_point(m, org, dir, d, td, p)) {
                float e = mi_angular_error(org, dir, p);
                out->error = e;
                out->type = MI_TYPE_B;
                if (e <= eps) { /* Eq. 2 accepts it: a candidate of type C or D */
                    float q[3] = {p[0] - org[0], p[1] - org[1], p[2] - org[2]};
                    out->type = MI_TYPE_D;
                    out->d = dot3(q, dir);
                    memcpy(out->p, p, sizeof p);
                    out->texel = td;
                    return MI_TYPE_D;
                }
            }
        }
        if (b < (i == steps ? dmax : dmin + h * (float)i)) { /* cut at a plane crossing: resume after it */
            b = i == steps ? dmax : dmin + h * (float)i;
            fb = signed_depth(m, org, dir, b, &tb);
        }
        a = b;
        fa = fb;
        ta = tb;
    }
    return out->type;
}

int mi_classify(mi_candidate *c, int n, float same)
{
    int best = -1;
    for (int i = 0; i < n; i++)
        if (c[i].type == MI_TYPE_D && (best < 0 || c[i].d < c[best].d))
            best = i;
    if (best < 0)
        return -1;
    for (int i = 0; i < n; i++)
        if (c[i].type == MI_TYPE_D && c[i].d > c[best].d + same)
            c[i].type = MI_TYPE_C;
    return best;
}

/* ---------------------------------------------------------------- the method */

typedef struct mi_state {
    eng_settings s;
    int maps, size;
    mi_map map[ENG_MAX_TRACE_MAPS];
    float *material6[ENG_MAX_TRACE_MAPS]; /* announced material part: 6 channels per texel */
    char names[ENG_MAX_TRACE_MAPS][6][3][64];
    /* the pose the maps were made for */
    float *worlds;
    uint32_t world_count;
    int valid;
    /* per frame */
    const eng_rt *rt;
    float bmin[3], bmax[3];
} mi_state;

static eng_result mi_create(const eng_settings *s, void **state, eng_error *err)
{
    mi_state *st = calloc(1, sizeof *st);
    if (!st)
        return eng_fail(err, ENG_ERR_NOMEM, "multi-image trace: out of memory");
    st->s = *s;
    st->maps = s->multi_image_maps;
    st->size = s->multi_image_size;
    size_t texels = 6 * (size_t)st->size * (size_t)st->size;
    for (int k = 0; k < st->maps; k++) {
        mi_map *m = &st->map[k];
        m->size = st->size;
        m->position = malloc(texels * 3 * sizeof(float));
        m->normal = malloc(texels * 3 * sizeof(float));
        m->draw = malloc(texels * sizeof(int32_t));
        m->material = malloc(texels * sizeof(int32_t));
        m->tex = malloc(texels * 6 * sizeof(float));
        st->material6[k] = malloc(texels * 6 * sizeof(float));
        if (!m->position || !m->normal || !m->draw || !m->material || !m->tex || !st->material6[k]) {
            *state = st;
            return eng_fail(err, ENG_ERR_NOMEM, "multi-image trace: out of memory for %d maps of %d²×6 texels",
                            st->maps, st->size);
        }
        static const char *const kind[3] = {"position", "normal", "material"};
        for (int f = 0; f < 6; f++)
            for (int b = 0; b < 3; b++)
                snprintf(st->names[k][f][b], sizeof st->names[k][f][b], "multiimage.map%d.face%d.%s", k, f, kind[b]);
    }
    *state = st;
    return ENG_OK;
}

/* Candidate centre i: Halton (2, 3, 5) in the box, 5 % in from its faces. */
static double halton(unsigned i, unsigned base)
{
    double f = 1.0, r = 0.0;
    while (i > 0) {
        f /= base;
        r += f * (double)(i % base);
        i /= base;
    }
    return r;
}

typedef struct cover {
    const eng_rt *rt;
    float cand[MI_CANDIDATES][3];
    float *x, *n;         /* per candidate pixel: point and normal facing the candidate */
    double *area;
    uint8_t *vis[MI_CANDIDATES]; /* lazily: which candidate pixels candidate c sees */
    int npix, threads;
} cover;

static int cover_visible(void *user, int c, int v, int p)
{
    cover *cv = user;
    if (c == v)
        return 1;
    if (!cv->vis[c]) {
        size_t total = (size_t)MI_CANDIDATES * (size_t)cv->npix;
        uint8_t *vis = eng_xmalloc(total);
#pragma omp parallel for schedule(static) num_threads(cv->threads)
        for (ptrdiff_t i = 0; i < (ptrdiff_t)total; i++) {
            const float *x = cv->x + 3 * i, *n = cv->n + 3 * i;
            float to[3] = {cv->cand[c][0] - x[0], cv->cand[c][1] - x[1], cv->cand[c][2] - x[2]};
            vis[i] = cv->area[i] > 0.0 && dot3(to, n) > 0.0f && !rt_occluded(cv->rt, cv->cand[c], x);
        }
        cv->vis[c] = vis;
    }
    return cv->vis[c][(size_t)v * (size_t)cv->npix + (size_t)p];
}

static void select_centres(mi_state *st, const eng_rt *rt, const eng_frame_scene *fs)
{
    cover cv;
    memset(&cv, 0, sizeof cv);
    cv.rt = rt;
    cv.threads = st->s.threads > 0 ? st->s.threads : 1;
    cv.npix = 6 * MI_COVERAGE_SIZE * MI_COVERAGE_SIZE;
    for (int i = 0; i < MI_CANDIDATES; i++) {
        double u[3] = {halton((unsigned)i + 1, 2), halton((unsigned)i + 1, 3), halton((unsigned)i + 1, 5)};
        for (int c = 0; c < 3; c++) {
            double lo = fs->bounds_min[c], ext = (double)fs->bounds_max[c] - lo;
            cv.cand[i][c] = (float)(lo + (0.05 + 0.9 * u[c]) * ext);
        }
    }
    size_t total = (size_t)MI_CANDIDATES * (size_t)cv.npix;
    cv.x = eng_xmalloc(total * 3 * sizeof(float));
    cv.n = eng_xmalloc(total * 3 * sizeof(float));
    cv.area = eng_xmalloc(total * sizeof(double));
    uint8_t *back = eng_xmalloc(total);
#pragma omp parallel for schedule(static) num_threads(st->s.threads > 0 ? st->s.threads : 1)
    for (ptrdiff_t i = 0; i < (ptrdiff_t)total; i++) {
        int v = (int)(i / cv.npix), p = (int)(i % cv.npix);
        float d[3], axis[3];
        mi_texel_dir(MI_COVERAGE_SIZE, (size_t)p, d);
        mi_face_axis(p / (MI_COVERAGE_SIZE * MI_COVERAGE_SIZE), axis);
        float len = sqrtf(dot3(d, d));
        for (int c = 0; c < 3; c++)
            d[c] /= len;
        rt_hit h;
        cv.area[i] = 0.0;
        back[i] = 0;
        memset(cv.x + 3 * i, 0, 3 * sizeof(float));
        memset(cv.n + 3 * i, 0, 3 * sizeof(float));
        if (!rt_intersect(rt, cv.cand[v], d, 0.0f, INFINITY, &h))
            continue;
        float s = dot3(h.normal, d) > 0.0f ? -1.0f : 1.0f; /* facing the candidate */
        back[i] = s < 0.0f;
        for (int c = 0; c < 3; c++) {
            cv.x[3 * i + c] = h.position[c];
            cv.n[3 * i + c] = s * h.normal[c];
        }
        cv.area[i] = mi_texel_area(cv.cand[v], h.position, h.normal, axis, MI_COVERAGE_SIZE);
    }
    /* A candidate inside a closed object sees back faces: it covers nothing. */
    for (int v = 0; v < MI_CANDIDATES; v++) {
        int hits = 0, backs = 0;
        for (int p = 0; p < cv.npix; p++) {
            size_t i = (size_t)v * (size_t)cv.npix + (size_t)p;
            hits += cv.area[i] > 0.0;
            backs += back[i];
        }
        if (backs > MI_BACKFACE_SHARE * hits)
            for (int p = 0; p < cv.npix; p++)
                cv.area[(size_t)v * (size_t)cv.npix + (size_t)p] = 0.0;
    }
    free(back);
    int chosen[ENG_MAX_TRACE_MAPS];
    mi_select(MI_CANDIDATES, cv.npix, cv.area, cover_visible, &cv, st->maps, MI_UPDATES, chosen);
    for (int k = 0; k < st->maps; k++)
        memcpy(st->map[k].centre, cv.cand[chosen[k]], sizeof st->map[k].centre);
    for (int c = 0; c < MI_CANDIDATES; c++)
        free(cv.vis[c]);
    free(cv.x);
    free(cv.n);
    free(cv.area);
}

/* Ray-casts map m's cube G-buffer from its centre. */
static void render_map(mi_state *st, int k, const eng_rt *rt, const eng_frame_scene *fs)
{
    mi_map *m = &st->map[k];
    float *mat6 = st->material6[k];
    size_t texels = 6 * (size_t)m->size * (size_t)m->size;
#pragma omp parallel for schedule(static) num_threads(st->s.threads > 0 ? st->s.threads : 1)
    for (ptrdiff_t i = 0; i < (ptrdiff_t)texels; i++) {
        float d[3];
        mi_texel_dir(m->size, (size_t)i, d);
        float len = sqrtf(dot3(d, d));
        for (int c = 0; c < 3; c++)
            d[c] /= len;
        rt_hit h;
        float *mo = mat6 + 6 * i;
        if (!rt_intersect(rt, m->centre, d, 0.0f, INFINITY, &h)) {
            memset(m->position + 3 * i, 0, 3 * sizeof(float));
            memset(m->normal + 3 * i, 0, 3 * sizeof(float));
            m->draw[i] = -1;
            m->material[i] = -1;
            for (int c = 0; c < 6; c++)
                m->tex[6 * i + c] = 1.0f;
            for (int c = 0; c < 4; c++)
                mo[c] = 0.0f;
            mo[4] = mo[5] = -1.0f;
            continue;
        }
        memcpy(m->position + 3 * i, h.position, 3 * sizeof(float));
        memcpy(m->normal + 3 * i, h.normal, 3 * sizeof(float));
        m->draw[i] = (int32_t)h.draw;
        m->material[i] = h.material;
        /* The texel's texture factors (texture and COLOR_0 at the cast ray's hit): a map
         * stores the material as the surface shows it there, as a G-buffer would. */
        float *tx = m->tex + 6 * i;
        memcpy(tx, h.base_tex, 4 * sizeof(float));
        tx[4] = h.roughness_tex;
        tx[5] = h.metallic_tex;
        scn_material mt = eng_material_of(fs->scene, h.material);
        mo[0] = mt.roughness;
        mo[1] = mt.metallic;
        mo[2] = mt.transmission;
        mo[3] = mt.ior;
        mo[4] = (float)h.material;
        mo[5] = (float)h.draw;
    }
}

/* Exit distance of the ray from the scene's box (enlarged a little), 0 if it misses it. */
static float box_exit(const float bmin[3], const float bmax[3], const float org[3], const float dir[3])
{
    float tfar = INFINITY;
    for (int c = 0; c < 3; c++) {
        float pad = 1e-3f + 0.01f * (bmax[c] - bmin[c]);
        if (dir[c] > 0.0f)
            tfar = fminf(tfar, (bmax[c] + pad - org[c]) / dir[c]);
        else if (dir[c] < 0.0f)
            tfar = fminf(tfar, (bmin[c] - pad - org[c]) / dir[c]);
    }
    return isfinite(tfar) && tfar > 0.0f ? tfar : 0.0f;
}

static int mi_intersect(const void *state, const float org[3], const float dir[3], float tnear, rt_hit *hit,
                        eng_trace_counts *counts)
{
    const mi_state *st = state;
    counts->rays++;
    float dmin = fmaxf(tnear, bsdf_offset_eps(org));
    float dmax = box_exit(st->bmin, st->bmax, org, dir);
    mi_candidate cand[ENG_MAX_TRACE_MAPS];
    for (int k = 0; k < st->maps; k++)
        mi_intersect_map(&st->map[k], org, dir, dmin, dmax, MI_STEPS, MI_ITERATIONS, MI_EPSILON, &cand[k]);
    int best = mi_classify(cand, st->maps, MI_AGREE);
    for (int k = 0; k < st->maps; k++)
        counts->types[cand[k].type]++;
    rt_hit eh;
    int ehit = 0;
    if (st->s.multi_image_compare) {
        ehit = rt_intersect(st->rt, org, dir, tnear, INFINITY, &eh);
        counts->compared += (uint64_t)ehit;
    }
    if (best >= 0) {
        const mi_map *m = &st->map[best];
        size_t t = cand[best].texel;
        hit->t = cand[best].d;
        memcpy(hit->position, cand[best].p, sizeof hit->position);
        memcpy(hit->normal, m->normal + 3 * t, sizeof hit->normal);
        memcpy(hit->geom_normal, m->normal + 3 * t, sizeof hit->geom_normal);
        hit->material = m->material[t];
        hit->draw = (uint32_t)m->draw[t];
        memcpy(hit->base_tex, m->tex + 6 * t, 4 * sizeof(float));
        hit->roughness_tex = m->tex[6 * t + 4];
        hit->metallic_tex = m->tex[6 * t + 5];
        counts->resolved++;
        if (ehit && eh.draw == hit->draw) {
            float q[3] = {eh.position[0] - hit->position[0], eh.position[1] - hit->position[1],
                          eh.position[2] - hit->position[2]};
            counts->agree += dot3(q, q) <= MI_AGREE * MI_AGREE;
        }
        return 1;
    }
    if (st->s.multi_image_miss == ENG_MISS_DROP) {
        counts->dropped++;
        return 0;
    }
    counts->fallback++;
    if (st->s.multi_image_compare) {
        if (ehit)
            *hit = eh;
        return ehit;
    }
    return rt_intersect(st->rt, org, dir, tnear, INFINITY, hit);
}

static int same_pose(const mi_state *st, const eng_frame_scene *fs)
{
    if (!st->valid || st->world_count != fs->draw_count)
        return 0;
    for (uint32_t i = 0; i < fs->draw_count; i++)
        if (memcmp(st->worlds + 16 * (size_t)i, fs->draws[i].world, 16 * sizeof(float)) != 0)
            return 0;
    return 1;
}

static eng_result mi_prepare(void *state, const eng_rt *rt, const eng_frame_scene *fs, pt_tracer *tracer,
                             eng_error *err)
{
    (void)err;
    mi_state *st = state;
    st->rt = rt;
    memcpy(st->bmin, fs->bounds_min, sizeof st->bmin);
    memcpy(st->bmax, fs->bounds_max, sizeof st->bmax);
    if (!same_pose(st, fs)) {
        /* §4.1: "the update process is carried out ... when the scene is changed". */
        select_centres(st, rt, fs);
        for (int k = 0; k < st->maps; k++)
            render_map(st, k, rt, fs);
        if (st->world_count != fs->draw_count) {
            free(st->worlds);
            st->worlds = eng_xmalloc((fs->draw_count ? fs->draw_count : 1) * 16 * sizeof(float));
            st->world_count = fs->draw_count;
        }
        for (uint32_t i = 0; i < fs->draw_count; i++)
            memcpy(st->worlds + 16 * (size_t)i, fs->draws[i].world, 16 * sizeof(float));
        st->valid = 1;
    }
    tracer->intersect = mi_intersect;
    tracer->intersect_n = NULL; /* ray by ray */
    tracer->state = st;
    return ENG_OK;
}

static const char *const CH_XYZ[] = {"X", "Y", "Z"};
static const char *const CH_MAT[] = {"roughness", "metallic", "transmission", "ior", "id", "draw"};

static int mi_buffer(const void *state, int index, eng_buffer *out)
{
    const mi_state *st = state;
    if (index < 0 || index >= st->maps * 18)
        return 0;
    int k = index / 18, f = (index / 3) % 6, b = index % 3;
    const mi_map *m = &st->map[k];
    size_t face = (size_t)f * (size_t)m->size * (size_t)m->size;
    out->name = st->names[k][f][b];
    out->width = out->height = m->size;
    out->channel_count = b == 2 ? 6 : 3;
    out->channels = b == 2 ? CH_MAT : CH_XYZ;
    out->data = b == 0 ? m->position + 3 * face : b == 1 ? m->normal + 3 * face : st->material6[k] + 6 * face;
    return 1;
}

static void mi_frame_info(const void *state, eng_frame_stats *stats)
{
    const mi_state *st = state;
    stats->trace_maps = st->maps;
    for (int k = 0; k < st->maps; k++)
        memcpy(stats->trace_centres[k], st->map[k].centre, sizeof stats->trace_centres[k]);
}

static void mi_destroy(void *state)
{
    mi_state *st = state;
    if (!st)
        return;
    for (int k = 0; k < ENG_MAX_TRACE_MAPS; k++) {
        free(st->map[k].position);
        free(st->map[k].normal);
        free(st->map[k].draw);
        free(st->map[k].material);
        free(st->map[k].tex);
        free(st->material6[k]);
    }
    free(st->worlds);
    free(st);
}

const pt_method pt_multiimage_method = {
    .name = "multi-image",
    .pass = "multiimage",
    .create = mi_create,
    .prepare = mi_prepare,
    .buffer = mi_buffer,
    .frame_info = mi_frame_info,
    .destroy = mi_destroy,
};
