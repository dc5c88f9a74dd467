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
 * Why the CPU: on llvmpipe a GL compute shader runs each invocation's loop iterations as
 * scalar work per SIMD lane with heavy per-iteration overhead, while the per-pixel work here
 * is a few dozen flops; the CPU evaluation reads the same G-buffer the scatter does. */
#include "gather_kernel.h"
#include "indirect.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define TG_AVX 1
#endif

#define TILE 16
#define ROW (TILE + 8)  /* a tile row of the local planes: room for an 8-wide step past its end */
#define LANES (TILE * ROW) /* floats per plane of a tile's local block */
#define FAR 1e30f       /* the position of an uncovered pixel: no distance test passes */
#define MAX_CHUNKS 64   /* photon chunks of the parallel list building */

/* Planes of tg_state.plane and of a tile's local copy. */
enum { P_SX, P_SY, P_SZ, P_NX, P_NY, P_NZ, P_FR, P_FG, P_FB, P_METAL, PLANES };

typedef struct tg_entry {
    uint32_t photon;
    uint8_t xa, xb, ya, yb; /* columns and rows of the tile (0..TILE−1) to visit */
} tg_entry;

/* A photon-tile pair found while counting, kept for the fill. */
typedef struct tg_pair {
    uint32_t tile;
    tg_entry entry;
} tg_pair;

typedef struct tg_state {
    int width, height, irradiance;
    int tiles_x, tiles_y;
    int avx; /* evaluate 8 pixels at a time (photon_avx) */
    ind_cpu_target target;
    ind_gbuffer gb;
    float *out, *glossy;
    gk_pixel *px;      /* per pixel, for the scalar path (metallic pixels) */
    /* The G-buffer as planes of w×h: surface point (FAR where not covered), normal, diffuse
     * BSDF Kd(1−m)(1−t)/π as gather_kernel.h computes it, metallic (1/0). */
    float *plane;
    float *tile_box;   /* per tile: min xyz, max xyz of its covered points (min > max: none) */
    float *tile_count; /* tiles_x × tiles_y, top row first */
    /* Per photon chunk: the photon-tile pairs it found, in photon order. */
    tg_pair *pairs[MAX_CHUNKS];
    size_t pair_count[MAX_CHUNKS], pair_capacity[MAX_CHUNKS];
    /* Tile lists: offsets (tiles + 1) into entries; per chunk counts while building. An
     * entry carries its photon's rectangle clipped to the tile, so a tile reads its list
     * sequentially. */
    uint32_t *offset;
    uint32_t *chunk_count; /* MAX_CHUNKS × tiles */
    tg_entry *entries;
    size_t entry_capacity;
} tg_state;

static void tg_destroy(void *state)
{
    tg_state *t = state;
    if (!t)
        return;
    ind_cpu_target_destroy(&t->target);
    ind_gbuffer_free(&t->gb);
    free(t->out);
    free(t->glossy);
    free(t->px);
    free(t->plane);
    free(t->tile_box);
    free(t->tile_count);
    for (int c = 0; c < MAX_CHUNKS; c++)
        free(t->pairs[c]);
    free(t->offset);
    free(t->chunk_count);
    free(t->entries);
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
    t->tiles_x = (width + TILE - 1) / TILE;
    t->tiles_y = (height + TILE - 1) / TILE;
    size_t n = (size_t)width * (size_t)height, tiles = (size_t)t->tiles_x * (size_t)t->tiles_y;
    t->out = eng_xmalloc(n * 4 * sizeof(float));
    t->glossy = irradiance ? eng_xmalloc(n * 4 * sizeof(float)) : NULL;
    t->px = eng_xmalloc(n * sizeof *t->px);
    t->plane = eng_xmalloc(PLANES * n * sizeof(float));
    t->tile_box = eng_xmalloc(tiles * 6 * sizeof(float));
    t->tile_count = eng_xmalloc(tiles * sizeof(float));
    t->offset = eng_xmalloc((tiles + 1) * sizeof(uint32_t));
    t->chunk_count = eng_xmalloc(MAX_CHUNKS * tiles * sizeof(uint32_t));
    eng_result r = ind_cpu_target_create(&t->target, width, height, irradiance, err);
    if (r != ENG_OK) {
        tg_destroy(t);
        return r;
    }
    *state = t;
    return ENG_OK;
}

/* The screen rectangle (pixels, rows top first) of the pixel centres onto which a point of
 * the box c ± ext can project; the whole screen when part of the box lies behind the eye (w
 * at or below a small positive bound). Returns 0 when the rectangle misses the screen. */
static int screen_rect(const float vp[16], const float c[3], const float ext[3], int w, int h, int32_t rect[4])
{
    /* Clip coordinates are affine in the point: the centre's plus ± ext_k times column k. */
    float cx = vp[0] * c[0] + vp[4] * c[1] + vp[8] * c[2] + vp[12];
    float cy = vp[1] * c[0] + vp[5] * c[1] + vp[9] * c[2] + vp[13];
    float cw = vp[3] * c[0] + vp[7] * c[1] + vp[11] * c[2] + vp[15];
    float ax[3], ay[3], aw[3], wmin = cw;
    for (int k = 0; k < 3; k++) {
        ax[k] = vp[4 * k] * ext[k];
        ay[k] = vp[4 * k + 1] * ext[k];
        aw[k] = vp[4 * k + 3] * ext[k];
        wmin -= fabsf(aw[k]);
    }
    if (!(wmin > 1e-6f)) {
        rect[0] = 0;
        rect[1] = 0;
        rect[2] = w - 1;
        rect[3] = h - 1;
        return 1;
    }
    float xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (int k = 0; k < 8; k++) {
        float sx = (k & 1) ? 1.0f : -1.0f, sy = (k & 2) ? 1.0f : -1.0f, sz = (k & 4) ? 1.0f : -1.0f;
        float px = cx + sx * ax[0] + sy * ax[1] + sz * ax[2];
        float py = cy + sx * ay[0] + sy * ay[1] + sz * ay[2];
        float inv = 1.0f / (cw + sx * aw[0] + sy * aw[1] + sz * aw[2]);
        xmin = fminf(xmin, px * inv);
        xmax = fmaxf(xmax, px * inv);
        ymin = fminf(ymin, py * inv);
        ymax = fmaxf(ymax, py * inv);
    }
    /* NDC → window coordinates X = (x+1)/2·w; pixel x's centre is at X = x + 0.5 and a
     * G-buffer point is interpolated at its pixel's centre, so the pixels whose centres lie
     * in [Xmin, Xmax] widened by a quarter pixel (against rounding) are the ones to visit.
     * GL rows count from the bottom; the rectangle is turned to rows top first below. */
    const double m = 0.25;
    double px0 = ceil(((double)xmin + 1.0) * 0.5 * w - 0.5 - m);
    double px1 = floor(((double)xmax + 1.0) * 0.5 * w - 0.5 + m);
    double pb0 = ceil(((double)ymin + 1.0) * 0.5 * h - 0.5 - m);
    double pb1 = floor(((double)ymax + 1.0) * 0.5 * h - 0.5 + m);
    if (px0 > px1 || pb0 > pb1)
        return 0;
    if (px1 < 0.0 || pb1 < 0.0 || px0 > w - 1 || pb0 > h - 1)
        return 0;
    rect[0] = px0 < 0.0 ? 0 : (int32_t)px0;
    rect[2] = px1 > w - 1 ? w - 1 : (int32_t)px1;
    int32_t b0 = pb0 < 0.0 ? 0 : (int32_t)pb0, b1 = pb1 > h - 1 ? h - 1 : (int32_t)pb1;
    rect[1] = h - 1 - b1;
    rect[3] = h - 1 - b0;
    return 1;
}

/* Whether the sphere (c, r) meets tile k's box of visible points. */
static int touches_tile(const tg_state *t, size_t k, const float c[3], float r)
{
    const float *b = t->tile_box + 6 * k;
    float d2 = 0.0f;
    for (int a = 0; a < 3; a++) {
        float d = c[a] < b[a] ? b[a] - c[a] : c[a] > b[3 + a] ? c[a] - b[3 + a] : 0.0f;
        d2 += d * d;
    }
    return b[0] <= b[3] && d2 <= r * r;
}

/* The sphere that holds everything the k-d gather's test d² <= r²·1.001 accepts, with a
 * margin for rounding. */
static float reach(float r) { return r * 1.001f + 1e-6f; }

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

/* One tile: its photons in list order, each over the pixels of its rectangle inside the tile.
 * Per pixel the k-d gather's distance test (d² <= r²·1.001), then gather_kernel.h's kernel
 * and BSDF: with AVX where the processor has it (photon_avx, the same bits), else one pixel
 * at a time. The tile's planes
 * are copied to a local block first (it fits in L1); accumulates locally and writes only the
 * tile's own pixels at the end. */
static void eval_tile(tg_state *t, const eng_photon_map *map, const float *radius, float compression, int x0, int y0,
                      const tg_entry *list, uint32_t count)
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
        const float pad = q <= P_SZ ? FAR : 0.0f;
        for (int y = 0; y < TILE; y++)
            for (int x = 0; x < ROW; x++)
                d[y * ROW + x] = x0 + x <= x1 && y0 + y <= y1
                                     ? t->plane[(size_t)q * npix + (size_t)(y0 + y) * (size_t)w + (size_t)(x0 + x)]
                                     : pad;
    }
    for (uint32_t e = 0; e < count; e++) {
        const uint32_t i = list[e].photon;
        if (e + 8 < count) /* the photons are read in index order, but sparsely */
            __builtin_prefetch(&map->photons[list[e + 8].photon]);
        const eng_photon *ph = &map->photons[i];
        const float r = radius[i], r2 = r * r * 1.001f;
        const int ya = list[e].ya, yb = list[e].yb, xa = list[e].xa, xb = list[e].xb;
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
    const int w = t->width, h = t->height, tx = t->tiles_x, ty = t->tiles_y;
    const size_t npix = (size_t)w * (size_t)h, tiles = (size_t)tx * (size_t)ty;
    const int threads = s->threads > 0 ? s->threads : 2;
    ind_gbuffer_read(in->gbuf, &t->gb);
    if (t->glossy)
        memset(t->glossy, 0, npix * 4 * sizeof(float));

    /* Per-pixel terms and planes, computed once (the k-d gather computes the same per pixel),
     * and each tile's box of visible points. */
    const float *eye = in->fs->camera.eye;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (size_t k = 0; k < tiles; k++) {
        float *b = t->tile_box + 6 * k;
        b[0] = b[1] = b[2] = INFINITY;
        b[3] = b[4] = b[5] = -INFINITY;
        const int x0 = (int)(k % (size_t)tx) * TILE, y0 = (int)(k / (size_t)tx) * TILE;
        for (int y = y0; y < y0 + TILE && y < h; y++)
            for (int x = x0; x < x0 + TILE && x < w; x++) {
                size_t i = (size_t)y * (size_t)w + (size_t)x;
                const float *sp = t->gb.position + 4 * i, *nr = t->gb.normal + 3 * i, *al = t->gb.albedo + 3 * i,
                            *mt = t->gb.material + 4 * i;
                int covered = sp[3] != 0.0f;
                if (covered)
                    gk_pixel_init(&t->px[i], sp, nr, al, mt, eye);
                float *pl = t->plane + i;
                for (int c = 0; c < 3; c++) {
                    pl[(P_SX + c) * npix] = covered ? sp[c] : FAR;
                    pl[(P_NX + c) * npix] = covered ? nr[c] : 0.0f;
                    /* gk_add's f[c] for the diffuse part, the same operations */
                    pl[(P_FR + c) * npix] = covered ? al[c] * (1.0f - mt[1]) * (1.0f - mt[2]) / (float)ENG_PI : 0.0f;
                }
                pl[P_METAL * npix] = covered && mt[1] > 0.0f ? 1.0f : 0.0f;
                if (!covered)
                    continue;
                for (int a = 0; a < 3; a++) {
                    b[a] = fminf(b[a], sp[a]);
                    b[3 + a] = fmaxf(b[3 + a], sp[a]);
                }
            }
    }

    /* Screen rectangles (made below, with the counts). Where κ > 0 (t < 1 in gather_kernel.h): t >= |d·n_p|/r_z and
     * t >= |d_tangent|/r_xy, so the support lies in the cylinder of radius r_xy and half-height
     * r_z about n_p, whose box has half-extent r_xy·√(1 − n_k²) + r_z·|n_k| along axis k
     * (widened by 0.1 % and 1e-6 m, never beyond the sphere's). */
    const size_t n = map->count;
    const float *vp = in->fs->camera.view_proj;

    /* Tile lists in photon order: a stable counting sort over photon chunks (each chunk makes
     * its photons' rectangles, counts and keeps its photon-tile pairs, then fills its own
     * slots of every tile from them), photon-tile
     * pairs whose sphere misses the tile's box left out. The lists do not depend on the number
     * of chunks. */
    int chunks = threads < MAX_CHUNKS ? threads : MAX_CHUNKS;
    if (chunks < 1)
        chunks = 1;
#pragma omp parallel for num_threads(threads) schedule(static, 1)
    for (int c = 0; c < chunks; c++) {
        uint32_t *cnt = t->chunk_count + (size_t)c * tiles;
        memset(cnt, 0, tiles * sizeof *cnt);
        t->pair_count[c] = 0;
        for (size_t i = n * (size_t)c / (size_t)chunks; i < n * (size_t)(c + 1) / (size_t)chunks; i++) {
            const eng_photon *ph = &map->photons[i];
            const float r = in->radius[i], rz = r * s->normal_compression, rr = reach(r);
            float ext[3];
            for (int k = 0; k < 3; k++) {
                float nk = ph->normal[k], q = 1.0f - nk * nk;
                ext[k] = fminf((r * sqrtf(q > 0.0f ? q : 0.0f) + rz * fabsf(nk)) * 1.001f + 1e-6f, rr);
            }
            int32_t rc[4];
            if (!screen_rect(vp, ph->position, ext, w, h, rc))
                continue;
            for (int j = rc[1] / TILE; j <= rc[3] / TILE; j++)
                for (int k = rc[0] / TILE; k <= rc[2] / TILE; k++) {
                    const size_t tile = (size_t)j * tx + k;
                    if (!touches_tile(t, tile, ph->position, rr))
                        continue;
                    cnt[tile]++;
                    if (t->pair_count[c] == t->pair_capacity[c]) {
                        t->pair_capacity[c] = t->pair_capacity[c] ? 2 * t->pair_capacity[c] : 4096;
                        tg_pair *grown = realloc(t->pairs[c], t->pair_capacity[c] * sizeof *grown);
                        if (!grown) {
                            fprintf(stderr, "ispm: out of memory\n");
                            abort();
                        }
                        t->pairs[c] = grown;
                    }
                    const int x0 = k * TILE, y0 = j * TILE;
                    tg_pair *pr = &t->pairs[c][t->pair_count[c]++];
                    pr->tile = (uint32_t)tile;
                    pr->entry.photon = (uint32_t)i;
                    pr->entry.xa = (uint8_t)((rc[0] > x0 ? rc[0] : x0) - x0);
                    pr->entry.xb = (uint8_t)((rc[2] < x0 + TILE - 1 ? rc[2] : x0 + TILE - 1) - x0);
                    pr->entry.ya = (uint8_t)((rc[1] > y0 ? rc[1] : y0) - y0);
                    pr->entry.yb = (uint8_t)((rc[3] < y0 + TILE - 1 ? rc[3] : y0 + TILE - 1) - y0);
                }
        }
    }
    t->offset[0] = 0;
    for (size_t k = 0; k < tiles; k++) {
        uint32_t sum = 0;
        for (int c = 0; c < chunks; c++) {
            uint32_t v = t->chunk_count[(size_t)c * tiles + k];
            t->chunk_count[(size_t)c * tiles + k] = t->offset[k] + sum; /* becomes the chunk's cursor */
            sum += v;
        }
        t->tile_count[k] = (float)sum;
        t->offset[k + 1] = t->offset[k] + sum;
    }
    size_t total = t->offset[tiles];
    if (total > t->entry_capacity) {
        free(t->entries);
        t->entries = eng_xmalloc(total * sizeof *t->entries);
        t->entry_capacity = total;
    }
#pragma omp parallel for num_threads(threads) schedule(static, 1)
    for (int c = 0; c < chunks; c++) {
        uint32_t *cur = t->chunk_count + (size_t)c * tiles;
        for (size_t q = 0; q < t->pair_count[c]; q++)
            t->entries[cur[t->pairs[c][q].tile]++] = t->pairs[c][q].entry;
    }

    /* Each tile on one thread, its photons in order. */
    const float compression = s->normal_compression;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (size_t k = 0; k < tiles; k++)
        eval_tile(t, map, in->radius, compression, (int)(k % (size_t)tx) * TILE, (int)(k / (size_t)tx) * TILE,
                  t->entries + t->offset[k], t->offset[k + 1] - t->offset[k]);

    ind_cpu_target_upload(&t->target, 0, t->out);
    if (t->irradiance)
        ind_cpu_target_upload(&t->target, 1, t->glossy);
    static const char *const CH_Y[] = {"Y"};
    out->target = &t->target.target;
    out->extra_count = 1;
    out->extra[0] = (ind_extra){"gather.tile_count", tx, ty, 1, CH_Y, t->tile_count};
    return ENG_OK;
}

const ind_method ind_tilegather_method = {"tile-gather", "gather", "gather", tg_create, tg_run, tg_destroy};
