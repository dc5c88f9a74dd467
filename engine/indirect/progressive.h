/* progressive.h — progressive accumulation of the indirect estimate for still views (the
 * `progressive` setting). While nothing moves, each pixel keeps the running (arithmetic)
 * mean of the indirect method's per-frame estimates, and the kernel radius shrinks from frame
 * to frame as in progressive photon mapping (Hachisuka et al. 2008, Eq. 8 with α = 2/3:
 * r_{i+1}² = r_i² (i + α)/(i + 1)), so that both the noise (the mean of more photon maps) and
 * the kernel bias (smaller kernels) go to zero.
 *
 * Restarts: a pixel whose eye G-buffer (position, normal, albedo, material) differs bit-wise
 * from the previous frame's starts a new mean; everything restarts (mean and radius) on the
 * first frame and when the camera or any light differs bit-wise from the previous frame.
 *
 * By default the radius is one scale for the whole frame (passed to ind_photon_radii, so every method
 * gets it without a branch of its own), not a per-pixel radius as in PPM: per-pixel radii would
 * need every method (the scatter's photon volumes included) to evaluate a pixel-dependent
 * kernel. The scale follows the frames since the last global restart; a pixel restarted
 * locally (a moving object) takes the current, already shrunken scale, so its first samples
 * are noisier than after a global restart. `progressive.radius` records, per pixel, the scale
 * its latest sample was estimated with. `"progressive_radius": "pixel"` gives every pixel its own
 * radius instead (below; every indirect method but tile-gather-gl). CPU pass, single-threaded: the same for any thread
 * count. */
#ifndef ISPM_PROGRESSIVE_H
#define ISPM_PROGRESSIVE_H

#include "indirect.h"

#define PROG_ALPHA (2.0 / 3.0) /* Hachisuka et al. 2008 §4.2 */

typedef struct prog_state prog_state;

prog_state *prog_create(void);
void prog_destroy(prog_state *p); /* accepts NULL */
/* Forgets everything: the next frame restarts globally. */
void prog_reset(prog_state *p);

/* r_i / r_1 for the i-th frame (1-based) since a global restart: r_1 = 1,
 * r_{i+1}² = r_i² (i + α)/(i + 1). */
double prog_radius_scale(int i);

/* Before the photon radii of a frame: compares the camera and lights of fs with the previous
 * frame's (bit-wise) and returns the frame's radius scale. */
float prog_begin(prog_state *p, const eng_frame_scene *fs);

/* After the method: adds this frame's estimate to every pixel's mean. gb: the G-buffer the
 * method ran against (top row first); in[a] (a < attachments, 1 or 2): the method's output,
 * w×h RGBA, top row first. Writes mean[a] (RGB: the mean; A: this frame's A, the kernel count),
 * count (w×h: frames in the mean) and radius (w×h: the scale of the latest sample; 0 on the
 * background). Background pixels (coverage 0) pass through with count 0. */
void prog_accumulate(prog_state *p, const glu_gbuffer *gb, int attachments, const float *const *in, float **mean,
                     float *count, float *radius);

/* Frames since the last global restart (the `i` of the current radius scale). */
int prog_frames(const prog_state *p);

/* ---- Per-pixel radii (`"progressive_radius": "pixel"`): PPM's own schedule (Hachisuka,
 * Ogaki, Jensen 2008, §4: radius reduction and flux correction). Every pixel keeps its radius
 * scale R (relative to the photons' own r_xy; 1 after a restart) and its accumulated photon
 * count N (0 after a restart). A frame evaluates every photon's kernel at the pixel with r_xy·R;
 * the pass finds M photons there (the method's A channel: the kernels that reached the pixel);
 * then
 *   N' = N + αM,  R'² = R² (N + αM)/(N + M),
 * and the accumulated flux is scaled by the same area ratio R'²/R². The estimate
 * τ/(πR²·emitted) after that scaling is Σ_k Φ_k/(πR_k²)/(k·n): exactly the running mean of the
 * frames' estimates that prog_accumulate keeps, so the mean needs no change; only the radius
 * goes per pixel. A pixel that finds no photon (N + M = 0) keeps its radius. Restarts as above:
 * a moving camera or light restarts every pixel (R = 1, N = 0), a changed G-buffer pixel
 * restarts alone. The photons' radii stay at scale 1 (prog_begin returns 1). */

/* One pixel's PPM update after a pass that found m photons with radius scale sqrt(*r2):
 * *n ← *n + αm, *r2 ← *r2 (*n + αm)/(*n + m) (unchanged when *n + m = 0). */
void prog_ppm_update(double *r2, double *n, double m);

/* Switches p to per-pixel radii (on = 1) or the one-scale-per-frame schedule (0, the default). */
void prog_set_per_pixel(prog_state *p, int on);

/* Per-pixel mode, after prog_begin and before the method: marks the pixels of gb (the G-buffer
 * the method will run against) that restart this frame, resets their R and N, and returns the
 * w×h radius scales (top row first) the method must apply to every photon's r_xy at each pixel
 * (ind_input.pixel_scale). Owned by p, valid until the next call. prog_accumulate then takes
 * M from in[0]'s A channel and updates R and N. */
const float *prog_pixel_scales(prog_state *p, const glu_gbuffer *gb);

/* Per-pixel mode: N per pixel after the latest prog_accumulate (w×h; 0 on the background). */
const float *prog_photons(const prog_state *p);

#endif
