/* ind_tilelists.h — the screen-tile photon lists of the tile-based gather (002_… §6.3), built on
 * the CPU and shared by the two tile-gather methods: ind_tilegather.c (evaluates the lists on
 * the CPU) and ind_tilegather_gl.c (uploads them and evaluates them in a GL compute shader).
 * Engine-private.
 *
 * Per frame: (1) from the read-back eye G-buffer, each 16×16 tile's box of visible points and
 * (optionally) the per-pixel planes the CPU evaluation reads; (2) per photon a conservative
 * screen rectangle of its kernel's support; (3) per tile the list of photons whose rectangle
 * touches the tile and whose sphere reaches its box, each with its rectangle clipped to the
 * tile, in photon order whatever the thread count (a stable counting sort over photon
 * chunks), and each list's length (gather.tile_count). */
#ifndef ISPM_TILELISTS_H
#define ISPM_TILELISTS_H

#include "gather_kernel.h"
#include "indirect.h"

#define TL_TILE 16
#define TL_FAR 1e30f   /* the position of an uncovered pixel: no distance test passes */
#define TL_MAX_CHUNKS 64 /* photon chunks of the parallel list building */

/* Planes of tl_lists.plane. */
enum { TL_SX, TL_SY, TL_SZ, TL_NX, TL_NY, TL_NZ, TL_FR, TL_FG, TL_FB, TL_METAL, TL_PLANES };

/* A list entry: the photon and its rectangle clipped to the tile. */
typedef struct tl_entry {
    uint32_t photon;
    uint8_t xa, xb, ya, yb; /* columns and rows of the tile (0..TL_TILE−1) to visit, inclusive */
} tl_entry;

/* A photon-tile pair found while counting, kept for the fill. */
typedef struct tl_pair {
    uint32_t tile;
    tl_entry entry;
} tl_pair;

typedef struct tl_lists {
    int width, height;
    int tiles_x, tiles_y;
    /* The G-buffer as planes of w×h (NULL when created without): surface point (TL_FAR where
     * not covered), normal, diffuse BSDF Kd(1−m)(1−t)/π as gather_kernel.h computes it,
     * metallic (1/0). */
    float *plane;
    float *tile_box;   /* per tile: min xyz, max xyz of its covered points (min > max: none) */
    float *tile_count; /* tiles_x × tiles_y, top row first: each list's length */
    /* Per photon chunk: the photon-tile pairs it found, in photon order. */
    tl_pair *pairs[TL_MAX_CHUNKS];
    size_t pair_count[TL_MAX_CHUNKS], pair_capacity[TL_MAX_CHUNKS];
    /* Tile lists: offsets (tiles + 1) into entries; per chunk counts while building. An
     * entry carries its photon's rectangle clipped to the tile, so a tile reads its list
     * sequentially. */
    uint32_t *offset;
    uint32_t *chunk_count; /* TL_MAX_CHUNKS × tiles */
    tl_entry *entries;
    size_t entry_capacity;
} tl_lists;

/* Allocates for a w×h G-buffer; planes: whether tl_prepare fills tl->plane. */
void tl_create(tl_lists *tl, int width, int height, int planes);
void tl_destroy(tl_lists *tl); /* accepts a zeroed tl */

/* Step (1): each tile's box of visible points (only gb->position is read when created without
 * planes) and, when created with planes, the planes and, if px (w×h) is not NULL,
 * gk_pixel_init for every covered pixel. */
void tl_prepare(tl_lists *tl, const glu_gbuffer *gb, const float eye[3], gk_pixel *px, int threads);

/* Steps (2)–(3) for the frame's photons (radius: r_xy per photon), camera view_proj. */
void tl_build(tl_lists *tl, const eng_photon_map *map, const float *radius, float normal_compression,
              const float view_proj[16], int threads);

#endif
