/* multiimage.h — the parts of the multi-image photon trace (trace_multiimage.c, 004 §4–5)
 * that are pure functions of their arguments, exposed for the unit tests: cube-map texel
 * addressing, the per-texel coverage area of Eq. 1, the greedy centre selection of §4.1, the
 * false-position intersection of a ray with one cube G-buffer (§5.1), the angular error of
 * Eq. 2 and the type A–D classification of §5.2. */
#ifndef ISPM_MULTIIMAGE_H
#define ISPM_MULTIIMAGE_H

#include <stddef.h>
#include <stdint.h>

/* Eq. 2's threshold (004 §5.2: "ε = 0.001 in practice"). */
#define MI_EPSILON 0.001f

/* One cube G-buffer: 6 faces of size×size texels, GL face order +X −X +Y −Y +Z −Z, texel
 * (face f, row j, column i) at index (f·size + j)·size + i. */
typedef struct mi_map {
    float centre[3];
    int size;
    float *position;  /* 3 per texel, world */
    float *normal;    /* 3 per texel, unit shading normal (not oriented) */
    int32_t *draw;    /* the draw hit, −1 = nothing in that direction */
    int32_t *material;/* its material index (−1 = default material) */
    float *tex;       /* 6 per texel: the hit's base_tex[4], roughness_tex, metallic_tex (rt_hit) */
} mi_map;

/* Direction (not unit) through the centre of texel `texel` of a cube of `size`. */
void mi_texel_dir(int size, size_t texel, float dir[3]);
/* The texel a direction (not necessarily unit, not zero) falls in. */
size_t mi_cube_texel(int size, const float dir[3]);
/* The forward axis of face f (+X −X +Y −Y +Z −Z). */
void mi_face_axis(int face, float axis[3]);

/* Eq. 1's term: the surface area a texel of a size×size face with forward axis `fwd` covers
 * at x (normal n, either orientation) seen from v: (4/N)·((x−v)·r)³ / |(v−x)·n|, N = size²,
 * the cosine clamped at 0.05 so grazing texels stay finite. */
double mi_texel_area(const float v[3], const float x[3], const float n[3], const float fwd[3], int size);

/* Greedy selection of k centres among ncand candidates (004 §4.1). Candidate v owns npix
 * sample pixels with areas area[v·npix + p]; visible(user, c, v, p) says whether candidate c
 * sees candidate v's pixel p (c == v must be 1). A(v|C) = Σ_p area·[no c ∈ C sees p]. k
 * steps add the candidate of largest A(v|C); then at most `updates` update steps add the best
 * outside candidate u and remove the member w of least A(w|C ∪ {u} − {w}), stopping when
 * w = u. Ties go to the lower index. chosen gets k candidate indices (k ≤ ncand). Sequential
 * and deterministic; visible is called from this thread only. */
typedef int (*mi_visible_fn)(void *user, int centre, int cand, int pixel);
void mi_select(int ncand, int npix, const double *area, mi_visible_fn visible, void *user, int k, int updates,
               int *chosen);

/* The classification of §5.2 of one map's answer for a ray. */
typedef enum mi_type { MI_TYPE_A = 0, MI_TYPE_B, MI_TYPE_C, MI_TYPE_D } mi_type;

typedef struct mi_candidate {
    mi_type type;   /* A: no crossing; B: rejected by Eq. 2; C/D set by mi_classify */
    float d;        /* distance along the ray to p */
    float p[3];     /* the map's surface point */
    size_t texel;
    float error;    /* Eq. 2's e of the last crossing tried */
} mi_candidate;

/* Eq. 2: e = 1 − ((p − x)/|p − x|)·r ≈ θ²/2; 2 (the largest) when p = x. */
float mi_angular_error(const float x[3], const float r[3], const float p[3]);

/* Ray org + d·dir (dir unit), d in [dmin, dmax], against one map (004 §5.1, after
 * [SKALP05]): f(d) is the signed distance of the ray point behind the plane of the texel the
 * map sees in its direction (negative in front, −∞ where the map sees nothing); `steps`
 * samples bracket the first −→+ crossing (also one where the ray meets a sample texel's
 * plane between two samples), false-position iteration (at most `iterations`) refines it,
 * and the crossing's surface point p — the ray's own crossing of the texel's plane where the
 * map sees a surface through it (within 1 mm), else the texel's plane on the line from the
 * centre through the ray point — is accepted when Eq. 2's error ≤ eps; else the scan goes on
 * to the next crossing. Returns the type: MI_TYPE_D for an accepted point (mi_classify
 * decides C or D across maps), B when only rejected crossings were found, A for none. */
mi_type mi_intersect_map(const mi_map *m, const float org[3], const float dir[3], float dmin, float dmax, int steps,
                         int iterations, float eps, mi_candidate *out);

/* §5.2 across maps: among the accepted candidates (type D on entry) the nearest is the hit;
 * the others farther than `same` behind it become type C (an intersection, not the first),
 * those within `same` stay D (the same point seen from another map). A nearer surface hidden
 * from every map cannot be told apart (the paper's limit): the nearest accepted point is the
 * hit. Returns its index (lowest index on ties), or −1. */
int mi_classify(mi_candidate *c, int n, float same);

#endif
