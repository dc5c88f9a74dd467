/* ind_tilelists.c — the CPU half of the tile-based gather (002_… §6.3: tile culling, counting,
 * allocation and copy, done here on the CPU), shared by its CPU (ind_tilegather.c) and GL
 * compute (ind_tilegather_gl.c) evaluations: per-tile boxes of the visible points,
 * conservative per-photon screen rectangles, and per-tile photon lists in photon order
 * (ind_tilelists.h). Owns nothing but the tl_lists arrays. */
#include "ind_tilelists.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void tl_create(tl_lists *t, int width, int height, int planes)
{
    memset(t, 0, sizeof *t);
    t->width = width;
    t->height = height;
    t->tiles_x = (width + TL_TILE - 1) / TL_TILE;
    t->tiles_y = (height + TL_TILE - 1) / TL_TILE;
    size_t n = (size_t)width * (size_t)height, tiles = (size_t)t->tiles_x * (size_t)t->tiles_y;
    t->plane = planes ? eng_xmalloc(TL_PLANES * n * sizeof(float)) : NULL;
    t->tile_box = eng_xmalloc(tiles * 6 * sizeof(float));
    t->tile_count = eng_xmalloc(tiles * sizeof(float));
    t->offset = eng_xmalloc((tiles + 1) * sizeof(uint32_t));
    t->chunk_count = eng_xmalloc(TL_MAX_CHUNKS * tiles * sizeof(uint32_t));
}

void tl_destroy(tl_lists *t)
{
    free(t->plane);
    free(t->tile_box);
    free(t->tile_count);
    for (int c = 0; c < TL_MAX_CHUNKS; c++)
        free(t->pairs[c]);
    free(t->offset);
    free(t->chunk_count);
    free(t->entries);
    memset(t, 0, sizeof *t);
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
static int touches_tile(const tl_lists *t, size_t k, const float c[3], float r)
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

void tl_prepare(tl_lists *t, const glu_gbuffer *gb, const float eye[3], gk_pixel *px, int threads)
{
    const int w = t->width, h = t->height, tx = t->tiles_x, ty = t->tiles_y;
    const size_t npix = (size_t)w * (size_t)h, tiles = (size_t)tx * (size_t)ty;
    /* Per-pixel terms and planes, computed once (the k-d gather computes the same per pixel),
     * and each tile's box of visible points. */
#pragma omp parallel for num_threads(threads) schedule(static)
    for (size_t k = 0; k < tiles; k++) {
        float *b = t->tile_box + 6 * k;
        b[0] = b[1] = b[2] = INFINITY;
        b[3] = b[4] = b[5] = -INFINITY;
        const int x0 = (int)(k % (size_t)tx) * TL_TILE, y0 = (int)(k / (size_t)tx) * TL_TILE;
        for (int y = y0; y < y0 + TL_TILE && y < h; y++)
            for (int x = x0; x < x0 + TL_TILE && x < w; x++) {
                size_t i = (size_t)y * (size_t)w + (size_t)x;
                const float *sp = gb->position + 4 * i;
                int covered = sp[3] != 0.0f;
                if (t->plane) {
                    const float *nr = gb->normal + 3 * i, *al = gb->albedo + 3 * i, *mt = gb->material + 4 * i;
                    if (covered && px)
                        gk_pixel_init(&px[i], sp, nr, al, mt, eye);
                    float *pl = t->plane + i;
                    for (int c = 0; c < 3; c++) {
                        pl[(TL_SX + c) * npix] = covered ? sp[c] : TL_FAR;
                        pl[(TL_NX + c) * npix] = covered ? nr[c] : 0.0f;
                        /* gk_add's f[c] for the diffuse part, the same operations */
                        pl[(TL_FR + c) * npix] =
                            covered ? al[c] * (1.0f - mt[1]) * (1.0f - mt[2]) / (float)ENG_PI : 0.0f;
                    }
                    pl[TL_METAL * npix] = covered && mt[1] > 0.0f ? 1.0f : 0.0f;
                }
                if (!covered)
                    continue;
                for (int a = 0; a < 3; a++) {
                    b[a] = fminf(b[a], sp[a]);
                    b[3 + a] = fmaxf(b[3 + a], sp[a]);
                }
            }
    }
}

void tl_build(tl_lists *t, const eng_photon_map *map, const float *radius, float normal_compression,
              const float view_proj[16], int threads)
{
    const int w = t->width, h = t->height, tx = t->tiles_x, ty = t->tiles_y;
    const size_t tiles = (size_t)tx * (size_t)ty;
    /* Screen rectangles (made below, with the counts). Where κ > 0 (t < 1 in gather_kernel.h):
     * t >= |d·n_p|/r_z and t >= |d_tangent|/r_xy, so the support lies in the cylinder of radius r_xy and half-height
     * r_z about n_p, whose box has half-extent r_xy·√(1 − n_k²) + r_z·|n_k| along axis k
     * (widened by 0.1 % and 1e-6 m, never beyond the sphere's). */
    const size_t n = map->count;
    const float *vp = view_proj;

    /* Tile lists in photon order: a stable counting sort over photon chunks (each chunk makes
     * its photons' rectangles, counts and keeps its photon-tile pairs, then fills its own
     * slots of every tile from them), photon-tile pairs whose sphere misses the tile's box
     * left out. The lists do not depend on the number
     * of chunks. */
    int chunks = threads < TL_MAX_CHUNKS ? threads : TL_MAX_CHUNKS;
    if (chunks < 1)
        chunks = 1;
#pragma omp parallel for num_threads(threads) schedule(static, 1)
    for (int c = 0; c < chunks; c++) {
        uint32_t *cnt = t->chunk_count + (size_t)c * tiles;
        memset(cnt, 0, tiles * sizeof *cnt);
        t->pair_count[c] = 0;
        for (size_t i = n * (size_t)c / (size_t)chunks; i < n * (size_t)(c + 1) / (size_t)chunks; i++) {
            const eng_photon *ph = &map->photons[i];
            const float r = radius[i], rz = r * normal_compression, rr = reach(r);
            float ext[3];
            for (int k = 0; k < 3; k++) {
                float nk = ph->normal[k], q = 1.0f - nk * nk;
                ext[k] = fminf((r * sqrtf(q > 0.0f ? q : 0.0f) + rz * fabsf(nk)) * 1.001f + 1e-6f, rr);
            }
            int32_t rc[4];
            if (!screen_rect(vp, ph->position, ext, w, h, rc))
                continue;
            for (int j = rc[1] / TL_TILE; j <= rc[3] / TL_TILE; j++)
                for (int k = rc[0] / TL_TILE; k <= rc[2] / TL_TILE; k++) {
                    const size_t tile = (size_t)j * tx + k;
                    if (!touches_tile(t, tile, ph->position, rr))
                        continue;
                    cnt[tile]++;
                    if (t->pair_count[c] == t->pair_capacity[c]) {
                        t->pair_capacity[c] = t->pair_capacity[c] ? 2 * t->pair_capacity[c] : 4096;
                        tl_pair *grown = realloc(t->pairs[c], t->pair_capacity[c] * sizeof *grown);
                        if (!grown) {
                            fprintf(stderr, "ispm: out of memory\n");
                            abort();
                        }
                        t->pairs[c] = grown;
                    }
                    const int x0 = k * TL_TILE, y0 = j * TL_TILE;
                    tl_pair *pr = &t->pairs[c][t->pair_count[c]++];
                    pr->tile = (uint32_t)tile;
                    pr->entry.photon = (uint32_t)i;
                    pr->entry.xa = (uint8_t)((rc[0] > x0 ? rc[0] : x0) - x0);
                    pr->entry.xb = (uint8_t)((rc[2] < x0 + TL_TILE - 1 ? rc[2] : x0 + TL_TILE - 1) - x0);
                    pr->entry.ya = (uint8_t)((rc[1] > y0 ? rc[1] : y0) - y0);
                    pr->entry.yb = (uint8_t)((rc[3] < y0 + TL_TILE - 1 ? rc[3] : y0 + TL_TILE - 1) - y0);
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
}
