/* kdtree.h — the balanced 3-d tree of the k-d gather baseline (ind_kdgather.c; 003_… Appendix A:
 * "balance the photon map k-d tree once before any radiance estimates"). Engine-private: only
 * ind_kdgather.c and its test use it.
 *
 * The tree is implicit over a permutation of the input points: the node of the index range
 * [lo, hi) is element mid = lo + (hi − lo)/2, its left subtree [lo, mid), its right subtree
 * [mid + 1, hi). Each split is the median along the axis of largest extent of the range's
 * bounding box, under the total order (coordinate, input index), so the tree is a pure
 * function of the points: no ties are broken by chance. */
#ifndef ISPM_KDTREE_H
#define ISPM_KDTREE_H

#include <stddef.h>
#include <stdint.h>

#include "trace.h"
#include "gather_kernel.h"

typedef struct kd_tree {
    size_t count;
    uint32_t *index;  /* count: input index of tree element i */
    float *point;     /* count × 3: the points in tree order */
    uint8_t *axis;    /* count: split axis of the node at element i (0, 1, 2) */
} kd_tree;

/* Builds the tree over count points (x, y, z at points + i·stride, stride in floats >= 3).
 * count must be below 2³². ENG_ERR_NOMEM when out of memory (t is then zeroed). */
eng_result kd_tree_build(const float *points, size_t count, size_t stride, kd_tree *t, eng_error *err);
void kd_tree_free(kd_tree *t); /* accepts a zeroed tree */

/* Input indices of every point p with |p − q|² <= r², appended to *out (grown with realloc;
 * out of memory ends the process) in tree order, *n updated. Thread-safe (reads only). */
void kd_tree_range(const kd_tree *t, const float q[3], float r, uint32_t **out, size_t *n, size_t *cap);

/* The k-d gather's sum at one surface point px (ind_kdgather.c): the photons of map within
 * `radius` of px->s (the largest r_xy) whose own kernel (radius r_xy[i]) reaches it, added
 * with gk_add in photon-index order. list/cap: the caller's scratch (grown with realloc).
 * Used per eye pixel by the k-d gather and per secondary hit by the specular pass
 * (spec_traced.c), so both see the same estimate. Thread-safe with per-thread scratch. */
void kd_gather_point(const kd_tree *tree, const eng_photon_map *map, const float *r_xy, float radius,
                     float compression, const gk_pixel *px, uint32_t **list, size_t *cap, float acc[4], float *glossy);

#endif
