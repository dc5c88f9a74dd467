/* ind_tilegather.c — `"indirect": "tile-gather"`: tile-based gather (002_… §6.3, compared with
 * splatting in §6.4 / Table 6.1). The eye G-buffer is read back; every photon's kernel
 * (003 §5.1: an ellipsoid inside the sphere of radius r_xy about the photon) is projected to
 * a conservative screen rectangle, and the photon is appended to the list of every 16×16
 * tile that rectangle touches; lists are filled in photon order (a stable counting sort).
 * Then each tile, on one thread, walks its list in that order and, for each photon, visits
 * the pixels of the photon's rectangle inside the tile: the same distance test, kernel and
 * BSDF as the k-d gather (gather_kernel.h), so every pixel sums exactly the photons the k-d
 * gather sums, in the same order — the two agree bit for bit, for any thread count.
 *
 * Buffers "gather.*" (like the k-d gather) and gather.tile_count: the length of each tile's
 * list, one value per tile (where the work goes).
 *
 * The planes, boxes, rectangles and lists are built by ind_tilelists.c, which the GL compute
 * evaluation of the same lists (ind_tilegather_gl.c, "tile-gather-gl") shares.
 *
 * Why the CPU: on llvmpipe a GL compute shader runs each invocation's loop iterations as
 * scalar work per SIMD lane with heavy per-iteration overhead, while the per-pixel work here
 * is a few dozen flops; the CPU evaluation reads the same G-buffer the scatter does
 * (docs/indirect.md measures both). */
#include "ind_tilelists.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define TG_AVX 1
#endif

#define TILE TL_TILE
#define ROW (TILE + 8)  /* a tile row of the local planes: room for an 8-wide step past its end */
#define LANES (TILE * ROW) /* floats per plane of a tile's local block */

/* Planes of a tile's local copy: ind_tilelists.h's. */
enum { P_SX = TL_SX, P_SY = TL_SY, P_SZ = TL_SZ, P_NX = TL_NX, P_NY = TL_NY, P_NZ = TL_NZ, P_FR = TL_FR,
       P_FG = TL_FG, P_FB = TL_FB, P_METAL = TL_METAL, PLANES = TL_PLANES };

typedef struct tg_state {
    int width, height, irradiance;
    int avx; /* evaluate 8 pixels at a time (photon_avx) */
    glu_cpu_target target;
    glu_gbuffer gb;
    float *out, *glossy;
    gk_pixel *px; /* per pixel, for the scalar path (metallic pixels) */
    float *reach; /* per photon s_u·r_xy under the anisotropic kernel (the lists' radius) */
    size_t reach_capacity;
    tl_lists tl;  /* G-buffer planes, tile boxes and lists (ind_tilelists.h) */
} tg_state;

static void tg_destroy(void *state)
{
    tg_state *t = state;
    if (!t)
        return;
    glu_cpu_target_destroy(&t->target);
    glu_gbuffer_free(&t->gb);
    free(t->out);
    free(t->glossy);
    free(t->px);
    free(t->reach);
    tl_destroy(&t->tl);
    free(t);
}

static eng_result tg_create(int width, int height, int irradiance, void **state, eng_error *err)
{
    tg_state *t = calloc(1, sizeof *t);
    if (!t)
        return eng_fail(err, ENG_ERR_NOMEM, "tile-gather: out of memory");
    t->width = width;
    t->height = height;
    t->irradiance = irradiance;
#if defined(TG_AVX)
    t->avx = __builtin_cpu_supports("avx") && !getenv("ISPM_TILEGATHER_SCALAR");
#endif
    size_t n = (size_t)width * (size_t)height;
    t->out = eng_xmalloc(n * 4 * sizeof(float));
    t->glossy = irradiance ? eng_xmalloc(n * 4 * sizeof(float)) : NULL;
    t->px = eng_xmalloc(n * sizeof *t->px);
    tl_create(&t->tl, width, height, 1);
    eng_result r = glu_cpu_target_create(&t->target, width, height, irradiance, err);
    if (r != ENG_OK) {
        tg_destroy(t);
        return r;
    }
    *state = t;
    return ENG_OK;
}

/* Adds photon ph to pixel p the scalar way (gather_kernel.h), on accumulators acc[c·lanes]. */
static void add_scalar(const tg_state *t, size_t p, float *acc, int lanes, const eng_photon *ph, float r,
                       float compression)
{
    float a[4] = {acc[0], acc[lanes], acc[2 * lanes], acc[3 * lanes]};
    gk_add(&t->px[p], ph, r, compression, a, t->glossy ? t->glossy + 4 * p : NULL);
    for (int c = 0; c < 4; c++)
        acc[c * lanes] = a[c];
}

#if defined(TG_AVX)
/* Photon ph over the rows ya..yb, columns xa..xb of a tile's local block (tile coordinates),
 * eight pixels of a row at a time. Each lane computes the IEEE operations of gather_kernel.h
 * in the same order as the scalar code (no FMA: -ffp-contract=off and no "fma" target), so
 * the sums are the scalar sums bit for bit. Lanes past the photon's rectangle are pixels of
 * this tile (or padding, FAR): the kernel test decides for them exactly as for the others.
 * Metallic pixels take the scalar path. */
__attribute__((target("avx"))) static void photon_avx(const tg_state *t, const eng_photon *ph, float r,
                                                      float compression, const float *loc, float *acc, int x0,
                                                      int y0, int xa, int xb, int ya, int yb)
{
    const float r2 = r * r * 1.001f, rz = r * compression;
    const float K = 2.0f / ((float)ENG_PI * r * r); /* gk_kappa's factor, the same operations */
    const __m256 px = _mm256_set1_ps(ph->position[0]), py = _mm256_set1_ps(ph->position[1]),
                 pz = _mm256_set1_ps(ph->position[2]);
    const __m256 qx = _mm256_set1_ps(ph->normal[0]), qy = _mm256_set1_ps(ph->normal[1]),
                 qz = _mm256_set1_ps(ph->normal[2]);
    const __m256 wx = _mm256_set1_ps(ph->direction[0]), wy = _mm256_set1_ps(ph->direction[1]),
                 wz = _mm256_set1_ps(ph->direction[2]);
    const __m256 vr2 = _mm256_set1_ps(r2), vr = _mm256_set1_ps(r), vK = _mm256_set1_ps(K);
    const __m256 vdiff = _mm256_set1_ps(r - rz), vrz = _mm256_set1_ps(rz);
    const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
    const __m256 absmask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
    const __m256 P0 = _mm256_set1_ps(ph->power[0]), P1 = _mm256_set1_ps(ph->power[1]),
                 P2 = _mm256_set1_ps(ph->power[2]);
    const int irradiance = t->glossy != NULL, w = t->width;
    for (int y = ya; y <= yb; y++) {
        for (int x = xa; x <= xb; x += 8) {
            const int l = y * ROW + x;
            __m256 dx = _mm256_sub_ps(_mm256_loadu_ps(loc + P_SX * LANES + l), px);
            __m256 dy = _mm256_sub_ps(_mm256_loadu_ps(loc + P_SY * LANES + l), py);
            __m256 dz = _mm256_sub_ps(_mm256_loadu_ps(loc + P_SZ * LANES + l), pz);
            __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                      _mm256_mul_ps(dz, dz));
            __m256 m = _mm256_cmp_ps(d2, vr2, _CMP_LE_OQ);
            if (!_mm256_movemask_ps(m))
                continue;
            /* t = len/r·(1 + |d·n_p|/len·(r − r_z)/r_z), 0 at len = 0 (gk_kappa) */
            __m256 len = _mm256_sqrt_ps(d2);
            __m256 dn = _mm256_and_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, qx), _mm256_mul_ps(dy, qy)),
                                                    _mm256_mul_ps(dz, qz)),
                                      absmask);
            __m256 tt = _mm256_mul_ps(
                _mm256_div_ps(len, vr),
                _mm256_add_ps(one, _mm256_div_ps(_mm256_mul_ps(_mm256_div_ps(dn, len), vdiff), vrz)));
            tt = _mm256_and_ps(tt, _mm256_cmp_ps(len, zero, _CMP_GT_OQ));
            m = _mm256_and_ps(m, _mm256_cmp_ps(tt, one, _CMP_LT_OQ));
            __m256 cosi = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(wx, _mm256_loadu_ps(loc + P_NX * LANES + l)),
                                                      _mm256_mul_ps(wy, _mm256_loadu_ps(loc + P_NY * LANES + l))),
                                        _mm256_mul_ps(wz, _mm256_loadu_ps(loc + P_NZ * LANES + l)));
            m = _mm256_and_ps(m, _mm256_cmp_ps(cosi, zero, _CMP_GT_OQ));
            int bits = _mm256_movemask_ps(m);
            if (!bits)
                continue;
            __m256 metal = _mm256_cmp_ps(_mm256_loadu_ps(loc + P_METAL * LANES + l), zero, _CMP_GT_OQ);
            int metal_bits = bits & _mm256_movemask_ps(metal);
            m = _mm256_andnot_ps(metal, m);
            __m256 kappa = _mm256_mul_ps(vK, _mm256_sub_ps(one, _mm256_mul_ps(tt, tt)));
            __m256 c0, c1, c2;
            if (irradiance) {
                c0 = _mm256_mul_ps(P0, kappa);
                c1 = _mm256_mul_ps(P1, kappa);
                c2 = _mm256_mul_ps(P2, kappa);
            } else {
                c0 = _mm256_mul_ps(_mm256_mul_ps(_mm256_loadu_ps(loc + P_FR * LANES + l), P0), kappa);
                c1 = _mm256_mul_ps(_mm256_mul_ps(_mm256_loadu_ps(loc + P_FG * LANES + l), P1), kappa);
                c2 = _mm256_mul_ps(_mm256_mul_ps(_mm256_loadu_ps(loc + P_FB * LANES + l), P2), kappa);
            }
            float *a = acc + l;
            _mm256_storeu_ps(a, _mm256_add_ps(_mm256_loadu_ps(a), _mm256_and_ps(m, c0)));
            _mm256_storeu_ps(a + LANES, _mm256_add_ps(_mm256_loadu_ps(a + LANES), _mm256_and_ps(m, c1)));
            _mm256_storeu_ps(a + 2 * LANES, _mm256_add_ps(_mm256_loadu_ps(a + 2 * LANES), _mm256_and_ps(m, c2)));
            _mm256_storeu_ps(a + 3 * LANES, _mm256_add_ps(_mm256_loadu_ps(a + 3 * LANES), _mm256_and_ps(m, one)));
            for (int k = 0; metal_bits && k < 8; k++)
                if (metal_bits & (1 << k))
                    add_scalar(t, (size_t)(y0 + y) * (size_t)w + (size_t)(x0 + x + k), a + k, LANES, ph, r,
                               compression);
        }
    }
}
#endif

/* Photon ph of the anisotropic kernel (gather_kernel.h, s_u > 1) over its rectangle in the
 * tile, one pixel at a time: the k-d gather's test on d² against (s_u r)²·1.001 and
 * gk_add_aniso, the same bits. */
static void photon_aniso(const tg_state *t, const eng_photon *ph, float r, const float *aniso, float compression,
                         const float *loc, float *acc, int x0, int y0, const tl_entry *e)
{
    const float ra = r * aniso[3], r2 = ra * ra * 1.001f;
    for (int y = e->ya; y <= e->yb; y++)
        for (int x = e->xa; x <= e->xb; x++) {
            const int l = y * ROW + x;
            float dx = loc[P_SX * LANES + l] - ph->position[0], dy = loc[P_SY * LANES + l] - ph->position[1],
                  dz = loc[P_SZ * LANES + l] - ph->position[2];
            if (!(dx * dx + dy * dy + dz * dz <= r2))
                continue;
            const size_t p = (size_t)(y0 + y) * (size_t)t->width + (size_t)(x0 + x);
            float *a = acc + l;
            float v[4] = {a[0], a[LANES], a[2 * LANES], a[3 * LANES]};
            gk_add_aniso(&t->px[p], ph, r, aniso, compression, v, t->glossy ? t->glossy + 4 * p : NULL);
            for (int c = 0; c < 4; c++)
                a[c * LANES] = v[c];
        }
}

/* Per-pixel progressive radii (ind_input.pixel_scale ≤ 1, so the lists built with the unscaled
 * reach still hold every photon that can reach): photon ph over its rectangle one pixel at a
 * time, its r_xy times that pixel's scale — the k-d gather's test and kernel with the same
 * radius, the same bits. aniso: NULL or the photon's 4 floats. */
static void photon_scaled(const tg_state *t, const eng_photon *ph, float r, const float *aniso, const float *pscale,
                          float compression, const float *loc, float *acc, int x0, int y0, const tl_entry *e)
{
    for (int y = e->ya; y <= e->yb; y++)
        for (int x = e->xa; x <= e->xb; x++) {
            const int l = y * ROW + x;
            const size_t p = (size_t)(y0 + y) * (size_t)t->width + (size_t)(x0 + x);
            const float rp = r * pscale[p], ra = aniso ? rp * aniso[3] : rp;
            float dx = loc[P_SX * LANES + l] - ph->position[0], dy = loc[P_SY * LANES + l] - ph->position[1],
                  dz = loc[P_SZ * LANES + l] - ph->position[2];
            if (!(dx * dx + dy * dy + dz * dz <= ra * ra * 1.001f))
                continue;
            float *a = acc + l;
            float v[4] = {a[0], a[LANES], a[2 * LANES], a[3 * LANES]};
            if (aniso)
                gk_add_aniso(&t->px[p], ph, rp, aniso, compression, v, t->glossy ? t->glossy + 4 * p : NULL);
            else
                gk_add(&t->px[p], ph, rp, compression, v, t->glossy ? t->glossy + 4 * p : NULL);
            for (int c = 0; c < 4; c++)
                a[c * LANES] = v[c];
        }
}

/* One tile: its photons in list order, each over the pixels of its rectangle inside the tile.
 * Per pixel the k-d gather's distance test (d² <= r²·1.001), then gather_kernel.h's kernel
 * and BSDF: with AVX where the processor has it (photon_avx, the same bits), else one pixel
 * at a time. The tile's planes
 * are copied to a local block first (it fits in L1); accumulates locally and writes only the
 * tile's own pixels at the end. */
static void eval_tile(tg_state *t, const eng_photon_map *map, const float *radius, const float *aniso,
                      const float *pscale, float compression, int x0, int y0, const tl_entry *list, uint32_t count)
{
    const int w = t->width, h = t->height;
    const size_t npix = (size_t)w * (size_t)h;
    const int x1 = x0 + TILE - 1 < w - 1 ? x0 + TILE - 1 : w - 1;
    const int y1 = y0 + TILE - 1 < h - 1 ? y0 + TILE - 1 : h - 1;
    float loc[PLANES * LANES];
    float acc[4 * LANES];
    memset(acc, 0, sizeof acc);
    for (int q = 0; q < PLANES; q++) {
        float *d = loc + q * LANES;
        const float pad = q <= P_SZ ? TL_FAR : 0.0f;
        for (int y = 0; y < TILE; y++)
            for (int x = 0; x < ROW; x++)
                d[y * ROW + x] = x0 + x <= x1 && y0 + y <= y1
                                     ? t->tl.plane[(size_t)q * npix + (size_t)(y0 + y) * (size_t)w + (size_t)(x0 + x)]
                                     : pad;
    }
    for (uint32_t e = 0; e < count; e++) {
        const uint32_t i = list[e].photon;
        if (e + 8 < count) /* the photons are read in index order, but sparsely */
            __builtin_prefetch(&map->photons[list[e + 8].photon]);
        const eng_photon *ph = &map->photons[i];
        const float r = radius[i], r2 = r * r * 1.001f;
        const int ya = list[e].ya, yb = list[e].yb, xa = list[e].xa, xb = list[e].xb;
        if (pscale) {
            photon_scaled(t, ph, r, aniso ? aniso + 4 * (size_t)i : NULL, pscale, compression, loc, acc, x0, y0,
                          &list[e]);
            continue;
        }
        if (aniso && aniso[4 * (size_t)i + 3] != 1.0f) {
            photon_aniso(t, ph, r, aniso + 4 * (size_t)i, compression, loc, acc, x0, y0, &list[e]);
            continue;
        }
#if defined(TG_AVX)
        if (t->avx) {
            photon_avx(t, ph, r, compression, loc, acc, x0, y0, xa, xb, ya, yb);
            continue;
        }
#endif
        for (int y = ya; y <= yb; y++)
            for (int x = xa; x <= xb; x++) {
                const int l = y * ROW + x;
                float dx = loc[P_SX * LANES + l] - ph->position[0], dy = loc[P_SY * LANES + l] - ph->position[1],
                      dz = loc[P_SZ * LANES + l] - ph->position[2];
                if (!(dx * dx + dy * dy + dz * dz <= r2))
                    continue;
                add_scalar(t, (size_t)(y0 + y) * (size_t)w + (size_t)(x0 + x), acc + l, LANES, ph, r, compression);
            }
    }
    for (int y = y0; y <= y1; y++)
        for (int x = x0; x <= x1; x++) {
            const int l = (y - y0) * ROW + (x - x0);
            float *o = t->out + 4 * ((size_t)y * (size_t)w + (size_t)x);
            for (int c = 0; c < 4; c++)
                o[c] = acc[c * LANES + l];
        }
}

static eng_result tg_run(void *state, const ind_input *in, ind_output *out, eng_error *err)
{
    (void)err;
    tg_state *t = state;
    const eng_photon_map *map = in->map;
    const eng_settings *s = in->s;
    const int w = t->width, h = t->height, tx = t->tl.tiles_x, ty = t->tl.tiles_y;
    const size_t npix = (size_t)w * (size_t)h, tiles = (size_t)tx * (size_t)ty;
    const int threads = s->threads > 0 ? s->threads : 2;
    glu_gbuffer_read(in->gbuf, &t->gb);
    if (t->glossy)
        memset(t->glossy, 0, npix * 4 * sizeof(float));

    /* Planes, per-pixel terms and tile boxes, then the tile lists (ind_tilelists.c). */
    tl_prepare(&t->tl, &t->gb, in->fs->camera.eye, t->px, threads);
    tl_build(&t->tl, map, ind_reach(in, &t->reach, &t->reach_capacity), s->normal_compression,
             in->fs->camera.view_proj, threads);

    /* Each tile on one thread, its photons in order. */
    const float compression = s->normal_compression;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (size_t k = 0; k < tiles; k++)
        eval_tile(t, map, in->radius, in->aniso, in->pixel_scale, compression, (int)(k % (size_t)tx) * TILE,
                  (int)(k / (size_t)tx) * TILE, t->tl.entries + t->tl.offset[k], t->tl.offset[k + 1] - t->tl.offset[k]);

    glu_cpu_target_upload(&t->target, 0, t->out);
    if (t->irradiance)
        glu_cpu_target_upload(&t->target, 1, t->glossy);
    static const char *const CH_Y[] = {"Y"};
    out->target = &t->target.target;
    out->extra_count = 1;
    out->extra[0] = (ind_extra){"gather.tile_count", tx, ty, 1, CH_Y, t->tl.tile_count};
    return ENG_OK;
}

const ind_method ind_tilegather_method = {
    .name = "tile-gather",
    .prefix = "gather",
    .pass = "gather",
    .create = tg_create,
    .run = tg_run,
    .destroy = tg_destroy,
    .per_pixel_radius = 1,
};
