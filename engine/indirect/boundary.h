/* boundary.h — boundary renormalisation of the photon kernel (the `boundary` setting).
 *
 * Every method sums Σ Φ κ over the photons whose kernel reaches a pixel; κ integrates to 1 over
 * the photon's tangent plane (003 §5.1 Eq. 2–3; shaders/photon_kernel.glsl). Within one kernel
 * radius of a place where the pixel's surface ends — a wall meets the floor (concave), the top
 * of a box ends (convex) — part of the disc around the pixel lies off the surface, no photons
 * land there, and the estimate is low by the kernel mass that lies off it: at the edge itself
 * half the light is missing (the "boundary bias" of photon mapping, 003 §2 on Lavignotte and
 * Paulin 2003; 004 §9 "darken on edges").
 *
 * The correction divides each pixel's estimate by W, the part of its kernel's mass that lies
 * on its surface, estimated in image space from the eye G-buffer: in N directions u_j of the
 * pixel's tangent plane, it walks out from the pixel's point s to the kernel radius R in M steps,
 * q = s + ρ u_j, projects q into the G-buffer and asks whether the surface seen there continues
 * s's surface (coverage, normal within 45° of s's, and within the kernel's half-thickness
 * r_z = normal_compression · R of q along the normal). The first step that fails ends the surface
 * in that direction at e_j (half-way between the last step on it and the first off it); W is
 * the kernel's mass within the star-shaped region ρ < e(φ):
 *
 *     W = (1/N) Σ_j g(e_j / R),   g(x) = 2x² − x⁴
 *
 * (g: ∫₀^e κ(ρ) 2πρ dρ of κ = 2/(πR²)(1 − ρ²/R²), the kernel on its plane, Eq. 2–3 with t = ρ/R).
 * Where the G-buffer cannot tell — q off screen, behind the camera or clipped by the near or far
 * plane, or hidden behind an object
 * that is more than R away from it (something in front of the surface, not a wall ending it) —
 * the surface is assumed to continue (e_j = R). R is the mean kernel radius of the photons that
 * land in the pixel's 16×16 screen tile (the radii of ind_photon_radii, any kernel scaling,
 * progressive scale included), the map's mean where none does. W is clamped to ≥ 1/4 (a
 * quarter disc: the corner of a box).
 *
 * It runs after the method on its output (RGB of every attachment divided by W, A kept), so it
 * is the same for every method, GL or CPU, and the methods stay bit-identical to each other.
 * CPU, rows shared among `threads` OpenMP threads, each pixel computed alone: the same for any
 * thread count. */
#ifndef ISPM_BOUNDARY_H
#define ISPM_BOUNDARY_H

#include "indirect.h"

#define BND_DIRECTIONS 16 /* N */
#define BND_STEPS 8       /* M */
#define BND_TILE 16       /* screen tile of the mean radius */
#define BND_WMIN 0.25f

/* g(x) = 2x² − x⁴ for x in [0, 1]: the kernel mass within x·R of its centre. */
double bnd_mass(double x);

/* W per pixel (w×h, top row first, 1 on the background) for the G-buffer gb seen through
 * view_proj (column-major, as eng_view.view_proj) from eye, with the photons of map and their
 * radii (map->count); `threads` OpenMP threads (≤ 0: one). */
void bnd_weights(const glu_gbuffer *gb, const float view_proj[16], const float eye[3], const eng_photon_map *map,
                 const float *radius, float compression, int threads, float *weight);
/* The same with each pixel's radius times pixel_scale[pixel] (progressive photon mapping's
 * per-pixel radius, ind_input.pixel_scale; NULL: bnd_weights). */
void bnd_weights_scaled(const glu_gbuffer *gb, const float view_proj[16], const float eye[3],
                        const eng_photon_map *map, const float *radius, const float *pixel_scale, float compression,
                        int threads, float *weight);

/* Divides the RGB of n RGBA pixels by weight (A untouched). */
void bnd_apply(size_t n, const float *weight, float *rgba);

/* The pass as the engine runs it after the method: a w×h target of 1 or 2 attachments. */
typedef struct bnd_pass bnd_pass;
eng_result bnd_pass_create(int width, int height, int attachments, bnd_pass **out, eng_error *err);
void bnd_pass_destroy(bnd_pass *b); /* accepts NULL */
/* Reads back the G-buffer gb and the method's output *sp, divides every attachment's RGB by W
 * and uploads the result into the pass's target, which replaces *sp. Returns W (w×h, top row
 * first; owned by the pass until its next run). */
const float *bnd_pass_run(bnd_pass *b, const glu_target *gb, const glu_target **sp, const ind_input *in);

#endif
