/* progressive.h — progressive accumulation of the indirect estimate for still views (issue 13;
 * the `progressive` setting). While nothing moves, each pixel keeps the running (arithmetic)
 * mean of the indirect method's per-frame estimates, and the kernel radius shrinks from frame
 * to frame as in progressive photon mapping (Hachisuka et al. 2008, Eq. 8 with α = 2/3:
 * r_{i+1}² = r_i² (i + α)/(i + 1)), so that both the noise (the mean of more photon maps) and
 * the kernel bias (smaller kernels) go to zero.
 *
 * Restarts: a pixel whose eye G-buffer (position, normal, albedo, material) differs bit-wise
 * from the previous frame's starts a new mean; everything restarts (mean and radius) on the
 * first frame and when the camera or any light differs bit-wise from the previous frame.
 *
 * The radius is one scale for the whole frame (passed to ind_photon_radii, so every method
 * gets it without a branch of its own), not a per-pixel radius as in PPM: per-pixel radii would
 * need every method (the scatter's photon volumes included) to evaluate a pixel-dependent
 * kernel. The scale follows the frames since the last global restart; a pixel restarted
 * locally (a moving object) takes the current, already shrunken scale, so its first samples
 * are noisier than after a global restart. `progressive.radius` records, per pixel, the scale
 * its latest sample was estimated with. CPU pass, single-threaded: the same for any thread
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
void prog_accumulate(prog_state *p, const ind_gbuffer *gb, int attachments, const float *const *in, float **mean,
                     float *count, float *radius);

/* Frames since the last global restart (the `i` of the current radius scale). */
int prog_frames(const prog_state *p);

#endif
