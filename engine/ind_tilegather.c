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

#define TILE 16

typedef struct tg_state {
    int width, height, irradiance;
    int tiles_x, tiles_y;
    ind_cpu_target target;
    ind_gbuffer gb;
    float *out, *glossy;
    gk_pixel *px;
    float *tile_count; /* tiles_x × tiles_y, top row first */
    /* Per photon, grown as needed: screen rectangle (x0, y0, x1, y1
     * inclusive, rows top first; x0 > x1 when off screen). */
    size_t photon_capacity;
    int32_t *rect;
    /* Tile lists: offsets (tiles + 1) into entries. */
    uint32_t *offset;
    uint32_t *cursor;
    uint32_t *entries;
    size_t entry_capacity;
} tg_state;

static void *xmalloc(size_t size)
{
    void *p = malloc(size ? size : 1);
    if (!p) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    return p;
}

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
    free(t->tile_count);
    free(t->rect);
    free(t->offset);
    free(t->cursor);
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
    t->tiles_x = (width + TILE - 1) / TILE;
    t->tiles_y = (height + TILE - 1) / TILE;
    size_t n = (size_t)width * (size_t)height, tiles = (size_t)t->tiles_x * (size_t)t->tiles_y;
    t->out = xmalloc(n * 4 * sizeof(float));
    t->glossy = irradiance ? xmalloc(n * 4 * sizeof(float)) : NULL;
    t->px = xmalloc(n * sizeof *t->px);
    t->tile_count = xmalloc(tiles * sizeof(float));
    t->offset = xmalloc((tiles + 1) * sizeof(uint32_t));
    t->cursor = xmalloc(tiles * sizeof(uint32_t));
    eng_result r = ind_cpu_target_create(&t->target, width, height, irradiance, err);
    if (r != ENG_OK) {
        tg_destroy(t);
        return r;
    }
    *state = t;
    return ENG_OK;
}

/* The screen rectangle (pixels, rows top first) that holds the projection of every point
 * within `radius` of c, widened by a pixel; the whole screen when part of that sphere's box
 * lies behind the eye (w at or below a small positive bound). Returns 0 when the rectangle
 * misses the screen. */
static int screen_rect(const float vp[16], const float c[3], float radius, int w, int h, int32_t rect[4])
{
    float xmin = INFINITY, xmax = -INFINITY, ymin = INFINITY, ymax = -INFINITY;
    for (int k = 0; k < 8; k++) {
        float p[3] = {c[0] + ((k & 1) ? radius : -radius), c[1] + ((k & 2) ? radius : -radius),
                      c[2] + ((k & 4) ? radius : -radius)};
        float cx = vp[0] * p[0] + vp[4] * p[1] + vp[8] * p[2] + vp[12];
        float cy = vp[1] * p[0] + vp[5] * p[1] + vp[9] * p[2] + vp[13];
        float cw = vp[3] * p[0] + vp[7] * p[1] + vp[11] * p[2] + vp[15];
        if (!(cw > 1e-6f)) {
            rect[0] = 0;
            rect[1] = 0;
            rect[2] = w - 1;
            rect[3] = h - 1;
            return 1;
        }
        float x = cx / cw, y = cy / cw;
        xmin = fminf(xmin, x);
        xmax = fmaxf(xmax, x);
        ymin = fminf(ymin, y);
        ymax = fmaxf(ymax, y);
    }
    /* NDC → pixel centres: x_pix = (x+1)/2·w − 0.5; GL row yb = (y+1)/2·h − 0.5, top row h−1−yb. */
    double px0 = floor(((double)xmin + 1.0) * 0.5 * w - 0.5) - 1.0;
    double px1 = ceil(((double)xmax + 1.0) * 0.5 * w - 0.5) + 1.0;
    double pb0 = floor(((double)ymin + 1.0) * 0.5 * h - 0.5) - 1.0;
    double pb1 = ceil(((double)ymax + 1.0) * 0.5 * h - 0.5) + 1.0;
    if (px1 < 0.0 || pb1 < 0.0 || px0 > w - 1 || pb0 > h - 1)
        return 0;
    rect[0] = px0 < 0.0 ? 0 : (int32_t)px0;
    rect[2] = px1 > w - 1 ? w - 1 : (int32_t)px1;
    int32_t b0 = pb0 < 0.0 ? 0 : (int32_t)pb0, b1 = pb1 > h - 1 ? h - 1 : (int32_t)pb1;
    rect[1] = h - 1 - b1;
    rect[3] = h - 1 - b0;
    return 1;
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
    memset(t->out, 0, npix * 4 * sizeof(float));
    if (t->glossy)
        memset(t->glossy, 0, npix * 4 * sizeof(float));

    /* Per-pixel view terms, computed once (the k-d gather computes the same per pixel). */
    const float *eye = in->fs->camera.eye;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * (size_t)w + (size_t)x;
            if (t->gb.position[4 * i + 3] != 0.0f)
                gk_pixel_init(&t->px[i], t->gb.position + 4 * i, t->gb.normal + 3 * i, t->gb.albedo + 3 * i,
                              t->gb.material + 4 * i, eye);
        }

    /* Kernel radii and screen rectangles. */
    const size_t n = map->count;
    if (n > t->photon_capacity) {
        free(t->rect);
        t->rect = xmalloc(n * 4 * sizeof *t->rect);
        t->photon_capacity = n;
    }
    const float *vp = in->fs->camera.view_proj;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (size_t i = 0; i < n; i++) {
        const eng_photon *ph = &map->photons[i];
        float r = in->radius[i];
        int32_t *rc = t->rect + 4 * i;
        if (!screen_rect(vp, ph->position, r * 1.001f, w, h, rc)) {
            rc[0] = 1;
            rc[2] = 0;
        }
    }

    /* Tile lists in photon order: count, prefix sums, fill. */
    memset(t->offset, 0, (tiles + 1) * sizeof(uint32_t));
    for (size_t i = 0; i < n; i++) {
        const int32_t *rc = t->rect + 4 * i;
        if (rc[0] > rc[2])
            continue;
        for (int j = rc[1] / TILE; j <= rc[3] / TILE; j++)
            for (int k = rc[0] / TILE; k <= rc[2] / TILE; k++)
                t->offset[(size_t)j * tx + k + 1]++;
    }
    for (size_t k = 0; k < tiles; k++) {
        t->tile_count[k] = (float)t->offset[k + 1];
        t->offset[k + 1] += t->offset[k];
    }
    size_t total = t->offset[tiles];
    if (total > t->entry_capacity) {
        free(t->entries);
        t->entries = xmalloc(total * sizeof *t->entries);
        t->entry_capacity = total;
    }
    memcpy(t->cursor, t->offset, tiles * sizeof(uint32_t));
    for (size_t i = 0; i < n; i++) {
        const int32_t *rc = t->rect + 4 * i;
        if (rc[0] > rc[2])
            continue;
        for (int j = rc[1] / TILE; j <= rc[3] / TILE; j++)
            for (int k = rc[0] / TILE; k <= rc[2] / TILE; k++)
                t->entries[t->cursor[(size_t)j * tx + k]++] = (uint32_t)i;
    }

    /* Each tile on one thread, its photons in order; per pixel the k-d gather's distance test
     * (d² <= r²·1.001), then its kernel and BSDF. */
    const float compression = s->normal_compression;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1)
    for (size_t k = 0; k < tiles; k++) {
        const int x0 = (int)(k % (size_t)tx) * TILE, y0 = (int)(k / (size_t)tx) * TILE;
        const int x1 = x0 + TILE - 1 < w - 1 ? x0 + TILE - 1 : w - 1;
        const int y1 = y0 + TILE - 1 < h - 1 ? y0 + TILE - 1 : h - 1;
        for (uint32_t e = t->offset[k]; e < t->offset[k + 1]; e++) {
            uint32_t i = t->entries[e];
            const eng_photon *ph = &map->photons[i];
            const int32_t *rc = t->rect + 4 * (size_t)i;
            const float r = in->radius[i], r2 = r * r * 1.001f;
            const int ya = rc[1] > y0 ? rc[1] : y0, yb = rc[3] < y1 ? rc[3] : y1;
            const int xa = rc[0] > x0 ? rc[0] : x0, xb = rc[2] < x1 ? rc[2] : x1;
            for (int y = ya; y <= yb; y++)
                for (int x = xa; x <= xb; x++) {
                    size_t p = (size_t)y * (size_t)w + (size_t)x;
                    const float *sp = t->gb.position + 4 * p;
                    if (sp[3] == 0.0f)
                        continue;
                    float dx = sp[0] - ph->position[0], dy = sp[1] - ph->position[1], dz = sp[2] - ph->position[2];
                    if (!(dx * dx + dy * dy + dz * dz <= r2))
                        continue;
                    gk_add(&t->px[p], ph, r, compression, t->out + 4 * p, t->glossy ? t->glossy + 4 * p : NULL);
                }
        }
    }

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
