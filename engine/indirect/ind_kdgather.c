/* ind_kdgather.c — traditional photon mapping's radiance estimate (003_… Appendix A), the baseline
 * that ISPM's scatter is measured against: the photon map is balanced into a k-d tree once
 * per frame, then every eye G-buffer pixel gathers the photons within a constant radius
 * (Appendix A, "Radiance estimates" step 2, the constant-radius variant) and sums step 3(a),
 * L_o += f(s, ω_i, ω_o) · Φ_i · κ(x − s) for photons with ω_i · n > 0 (no cosine: see
 * shaders/splat.frag.glsl on Eq. 1).
 *
 * The kernel and BSDF are those of shaders/splat.frag.glsl, evaluated in the same float
 * operations in the same order (ISPM §5 calls scatter and gather "mathematically identical";
 * here they are also numerically identical up to the GPU's rounding): κ of §5.1 Eq. 2–3 with
 * the photon's r_xy = splat_radius(kernel_radius, ρp) and r_z = normal_compression · r_xy,
 * Lambert for the non-metallic, non-transmissive part and a GGX lobe for metals. The gather
 * radius is the largest r_xy in the map: the ellipsoid never reaches farther than r_xy.
 *
 * Determinism: rows are shared among OpenMP threads, but each pixel is computed by one thread
 * and sums its photons in photon-index order (the order the GPU's instances are drawn in), so
 * the result is bit-identical for any thread count. Owns nothing between calls. */
#include "indirect.h"
#include "kdtree.h"
#include "gather_kernel.h"
#include "indirect.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- the tree */

static void oom(void)
{
    fprintf(stderr, "ispm: out of memory\n");
    abort();
}

typedef struct build_ctx {
    const float *points;
    size_t stride;
} build_ctx;

/* The total order of the median split: coordinate, then input index. */
static int before(const build_ctx *c, int axis, uint32_t a, uint32_t b)
{
    float fa = c->points[(size_t)a * c->stride + (size_t)axis];
    float fb = c->points[(size_t)b * c->stride + (size_t)axis];
    return fa < fb || (fa == fb && a < b);
}

static void swap_u32(uint32_t *a, uint32_t *b)
{
    uint32_t t = *a;
    *a = *b;
    *b = t;
}

/* Quickselect: puts the k-th smallest of idx[lo, hi) at k, smaller ones before it and larger
 * ones after (Lomuto partition around a median-of-three pivot; keys are unique, so the result
 * depends on nothing but the points). */
static void select_kth(const build_ctx *c, int axis, uint32_t *idx, size_t lo, size_t hi, size_t k)
{
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2, last = hi - 1;
        if (before(c, axis, idx[mid], idx[lo]))
            swap_u32(&idx[mid], &idx[lo]);
        if (before(c, axis, idx[last], idx[lo]))
            swap_u32(&idx[last], &idx[lo]);
        if (before(c, axis, idx[last], idx[mid]))
            swap_u32(&idx[last], &idx[mid]);
        swap_u32(&idx[mid], &idx[last]); /* the median of three becomes the pivot, at the end */
        uint32_t pivot = idx[last];
        size_t store = lo;
        for (size_t i = lo; i < last; i++)
            if (before(c, axis, idx[i], pivot))
                swap_u32(&idx[i], &idx[store++]);
        swap_u32(&idx[store], &idx[last]);
        if (k == store)
            return;
        if (k < store)
            hi = store;
        else
            lo = store + 1;
    }
}

static void build_range(const build_ctx *c, uint32_t *idx, uint8_t *axis, size_t lo, size_t hi)
{
    while (hi > lo) {
        float mn[3] = {INFINITY, INFINITY, INFINITY}, mx[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t i = lo; i < hi; i++) {
            const float *p = c->points + (size_t)idx[i] * c->stride;
            for (int a = 0; a < 3; a++) {
                mn[a] = fminf(mn[a], p[a]);
                mx[a] = fmaxf(mx[a], p[a]);
            }
        }
        int ax = 0;
        for (int a = 1; a < 3; a++)
            if (mx[a] - mn[a] > mx[ax] - mn[ax])
                ax = a;
        size_t mid = lo + (hi - lo) / 2;
        select_kth(c, ax, idx, lo, hi, mid);
        axis[mid] = (uint8_t)ax;
        build_range(c, idx, axis, lo, mid);
        lo = mid + 1; /* the right half iteratively: recursion depth stays log2(count) */
    }
}

eng_result kd_tree_build(const float *points, size_t count, size_t stride, kd_tree *t, eng_error *err)
{
    memset(t, 0, sizeof *t);
    if (count >= UINT32_MAX || stride < 3)
        return eng_fail(err, ENG_ERR_INVALID, "kd-gather: %zu points of stride %zu cannot be indexed", count, stride);
    t->index = malloc((count ? count : 1) * sizeof *t->index);
    t->point = malloc((count ? count : 1) * 3 * sizeof *t->point);
    t->axis = malloc(count ? count : 1);
    if (!t->index || !t->point || !t->axis) {
        kd_tree_free(t);
        return eng_fail(err, ENG_ERR_NOMEM, "kd-gather: out of memory for a tree of %zu points", count);
    }
    t->count = count;
    for (size_t i = 0; i < count; i++)
        t->index[i] = (uint32_t)i;
    build_ctx c = {points, stride};
    build_range(&c, t->index, t->axis, 0, count);
    for (size_t i = 0; i < count; i++)
        memcpy(t->point + 3 * i, points + (size_t)t->index[i] * stride, 3 * sizeof(float));
    return ENG_OK;
}

void kd_tree_free(kd_tree *t)
{
    free(t->index);
    free(t->point);
    free(t->axis);
    memset(t, 0, sizeof *t);
}

void kd_tree_range(const kd_tree *t, const float q[3], float r, uint32_t **out, size_t *n, size_t *cap)
{
    /* Explicit stack of index ranges; depth <= log2(count) + 1 < 64. */
    size_t stack_lo[64], stack_hi[64];
    int top = 0;
    if (t->count == 0)
        return;
    stack_lo[0] = 0;
    stack_hi[0] = t->count;
    top = 1;
    const float r2 = r * r;
    while (top > 0) {
        top--;
        size_t lo = stack_lo[top], hi = stack_hi[top];
        while (hi > lo) {
            size_t mid = lo + (hi - lo) / 2;
            const float *p = t->point + 3 * mid;
            float dx = p[0] - q[0], dy = p[1] - q[1], dz = p[2] - q[2];
            if (dx * dx + dy * dy + dz * dz <= r2) {
                if (*n == *cap) {
                    *cap = *cap ? 2 * *cap : 256;
                    uint32_t *grown = realloc(*out, *cap * sizeof **out);
                    if (!grown)
                        oom();
                    *out = grown;
                }
                (*out)[(*n)++] = t->index[mid];
            }
            int a = t->axis[mid];
            float split = p[a];
            int go_left = q[a] - r <= split && mid > lo;
            int go_right = q[a] + r >= split && hi > mid + 1;
            if (go_left && go_right) {
                stack_lo[top] = mid + 1;
                stack_hi[top] = hi;
                top++;
                hi = mid;
            } else if (go_left) {
                hi = mid;
            } else if (go_right) {
                lo = mid + 1;
            } else {
                break;
            }
        }
    }
}

/* ---------------------------------------------------------------- the gather */

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* One surface point's gather: the per-pixel body of gather() below, inlined there (it is the
 * speed baseline), and exported as kd_gather_point for the traced specular pass. aniso: NULL
 * (the isotropic kernel; a constant at every call site, so the default path compiles to what
 * it was), or the anisotropic kernel's 4 floats per photon, whose support reaches s_u·r_xy
 * (gather_kernel.h; radius is then the largest reach). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void gather_point(const kd_tree *tree, const eng_photon_map *map, const float *r_xy, const float *aniso,
                                float radius, float compression, float ps, const gk_pixel *px, uint32_t **list,
                                size_t *cap, float acc[4], float *glossy)
{
    /* ps: the pixel's progressive radius scale (progressive.h; 1 = none): every photon's r_xy
     * and reach times ps here (x·1 is x: without it the sums are the same bits). */
    const float *p = px->s;
    size_t n = 0, kept = 0;
    kd_tree_range(tree, p, radius * ps, list, &n, cap);
    /* Photons whose own kernel cannot reach s (t >= |d|/r_xy >= 1) are dropped before
     * sorting; the margin keeps every photon the kernel could accept. */
    uint32_t *l = *list;
    for (size_t k = 0; k < n; k++) {
        const float *x = map->photons[l[k]].position;
        float dx = p[0] - x[0], dy = p[1] - x[1], dz = p[2] - x[2], r = r_xy[l[k]] * ps;
        if (aniso)
            r *= aniso[4 * (size_t)l[k] + 3];
        if (dx * dx + dy * dy + dz * dz <= r * r * 1.001f)
            l[kept++] = l[k];
    }
    n = kept;
    if (n > 1)
        qsort(l, n, sizeof *l, cmp_u32);
    /* shaders/splat.frag.glsl's main() summed over the photons in index order. */
    for (size_t k = 0; k < n; k++) {
        if (aniso)
            gk_add_aniso(px, &map->photons[l[k]], r_xy[l[k]] * ps, aniso + 4 * (size_t)l[k], compression, acc,
                         glossy);
        else
            gk_add(px, &map->photons[l[k]], r_xy[l[k]] * ps, compression, acc, glossy);
    }
}

void kd_gather_point(const kd_tree *tree, const eng_photon_map *map, const float *r_xy, float radius,
                     float compression, const gk_pixel *px, uint32_t **list, size_t *cap, float acc[4], float *glossy)
{
    gather_point(tree, map, r_xy, NULL, radius, compression, 1.0f, px, list, cap, acc, glossy);
}

/* One row of gather(): the isotropic kernel, or (aniso not NULL) the anisotropic one, with or
 * without per-pixel radius scales; one function each so that the choice is made once per row,
 * outside the per-pixel loop, and the unscaled rows compile without the scale (x·1.0f folds to
 * x: the k-d gather baseline pays nothing for progressive_radius "pixel"). */
typedef struct row_ctx {
    const kd_tree *tree;
    const eng_photon_map *map;
    const float *r_xy, *aniso, *position, *normal, *albedo, *material, *eye;
    float radius, compression;
    const float *pscale; /* per-pixel radius scale, or NULL */
    int w;
    float *out, *glossy;
} row_ctx;

#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void gather_row(const row_ctx *c, const float *aniso, const float *pscale, int y, uint32_t **list,
                              size_t *cap)
{
    for (int x = 0; x < c->w; x++) {
        size_t i = (size_t)y * (size_t)c->w + (size_t)x;
        const float *p = c->position + 4 * i;
        if (p[3] == 0.0f)
            continue;
        gk_pixel px;
        gk_pixel_init(&px, p, c->normal + 3 * i, c->albedo + 3 * i, c->material + 4 * i, c->eye);
        gather_point(c->tree, c->map, c->r_xy, aniso, c->radius, c->compression, pscale ? pscale[i] : 1.0f,
                     &px, list, cap, c->out + 4 * i, c->glossy ? c->glossy + 4 * i : NULL);
    }
}

static void gather_row_iso(const row_ctx *c, int y, uint32_t **list, size_t *cap)
{
    gather_row(c, NULL, NULL, y, list, cap);
}

static void gather_row_aniso(const row_ctx *c, int y, uint32_t **list, size_t *cap)
{
    gather_row(c, c->aniso, NULL, y, list, cap);
}

static void gather_row_scaled(const row_ctx *c, int y, uint32_t **list, size_t *cap)
{
    gather_row(c, c->aniso, c->pscale, y, list, cap);
}

static eng_result gather(const eng_photon_map *map, const float *radii, const float *aniso, const float *pscale, int w,
                         int h,
                         const float *position, const float *normal, const float *albedo, const float *material,
                         const float eye[3], const eng_settings *s, float *out, float *glossy, eng_error *err)
{
    memset(out, 0, (size_t)w * (size_t)h * 4 * sizeof(float));
    if (glossy)
        memset(glossy, 0, (size_t)w * (size_t)h * 4 * sizeof(float));
    if (map->count == 0)
        return ENG_OK;
    kd_tree tree;
    eng_result r = kd_tree_build(map->photons[0].position, map->count, sizeof(eng_photon) / sizeof(float), &tree, err);
    if (r != ENG_OK)
        return r;
    float *r_xy = malloc(map->count * sizeof *r_xy);
    if (!r_xy) {
        kd_tree_free(&tree);
        return eng_fail(err, ENG_ERR_NOMEM, "kd-gather: out of memory for %zu photons", map->count);
    }
    float radius = 0.0f;
    for (size_t i = 0; i < map->count; i++) {
        r_xy[i] = radii ? radii[i] : splat_radius(s->kernel_radius, map->photons[i].path_density);
        radius = fmaxf(radius, aniso ? r_xy[i] * aniso[4 * i + 3] : r_xy[i]);
    }
    const row_ctx c = {&tree, map, r_xy, aniso, position, normal, albedo, material, eye, radius,
                       s->normal_compression, pscale, w, out, glossy};
    void (*const row)(const row_ctx *, int, uint32_t **, size_t *) =
        pscale ? gather_row_scaled : aniso ? gather_row_aniso : gather_row_iso;
    int threads = s->threads > 0 ? s->threads : 2;
#pragma omp parallel num_threads(threads)
    {
        uint32_t *list = NULL;
        size_t cap = 0;
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < h; y++)
            row(&c, y, &list, &cap);
        free(list);
    }
    free(r_xy);
    kd_tree_free(&tree);
    return ENG_OK;
}

eng_result kd_gather(const eng_photon_map *map, int w, int h, const float *position, const float *normal,
                     const float *albedo, const float *material, const float eye[3], const eng_settings *s,
                     float *out, eng_error *err)
{
    return gather(map, NULL, NULL, NULL, w, h, position, normal, albedo, material, eye, s, out, NULL, err);
}

/* ---------------------------------------------------------------- the method (indirect.h) */

static void kd_destroy(void *state)
{
    if (!state)
        return;
    ind_cpu_state_free(state);
    free(state);
}

static eng_result kd_create(int width, int height, int irradiance, void **state, eng_error *err)
{
    ind_cpu_state *k = calloc(1, sizeof *k);
    if (!k)
        return eng_fail(err, ENG_ERR_NOMEM, "kd-gather: out of memory");
    eng_result r = ind_cpu_state_init(k, "kd-gather", width, height, irradiance, err);
    if (r != ENG_OK) {
        free(k);
        return r;
    }
    *state = k;
    return ENG_OK;
}

/* Read-back, gather and upload all count as the method's time: it cannot do without them. */
static eng_result kd_run(void *state, const ind_input *in, ind_output *out, eng_error *err)
{
    ind_cpu_state *k = state;
    glu_gbuffer_read(in->gbuf, &k->gb);
    eng_result r = gather(in->map, in->radius, in->aniso, in->pixel_scale, k->width, k->height, k->gb.position,
                          k->gb.normal, k->gb.albedo, k->gb.material,
                          in->fs->camera.eye, in->s, k->out, k->glossy, err);
    if (r != ENG_OK)
        return r;
    ind_cpu_state_output(k, out);
    return ENG_OK;
}

const ind_method ind_kdgather_method = {
    .name = "kd-gather",
    .prefix = "gather",
    .pass = "gather",
    .create = kd_create,
    .run = kd_run,
    .destroy = kd_destroy,
    .per_pixel_radius = 1,
};
