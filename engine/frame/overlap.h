/* overlap.h — one CPU job run beside the GL thread (two cores for record).
 *
 * llvmpipe runs each draw's vertex processing and binning on the thread that called GL, so in
 * a 2-thread run one core idles while the GL thread renders the eye G-buffer and the direct
 * light. The frame loop hands the CPU photon trace (which needs only the bounce maps) to this
 * worker, renders those passes meanwhile, and joins before anything reads the photon map.
 * It also takes eng_create's GL-free part (Embree's scene, the random maps) while the GL
 * thread creates the context and builds the programs, and, in the first frame, grows the
 * photon buffers and the splat's arrays (their page faults) while the GL thread renders the
 * shadow and bounce maps.
 * The job is the same code on the same inputs either way, so every buffer is bit-identical;
 * only when it runs changes. With fewer than 2 threads there is no worker: ovl_start runs the
 * job at once on the calling thread (a 1-thread run stays a 1-thread run).
 */
#ifndef ISPM_OVERLAP_H
#define ISPM_OVERLAP_H

typedef struct eng_overlap eng_overlap;

/* threads: the `threads` setting. Returns NULL only when out of memory or no thread could be
 * started; a NULL overlap runs every job inline (ovl_start and ovl_join accept NULL). */
eng_overlap *ovl_create(int threads);

/* Starts job(arg) on the worker (or runs it now, without one). At most one job is in flight:
 * call ovl_join before the next ovl_start. The job must not call GL. */
void ovl_start(eng_overlap *o, void (*job)(void *arg), void *arg);

/* Waits until the job started last has returned (at once when none is in flight). */
void ovl_join(eng_overlap *o);

/* Joins, stops the worker and frees; accepts NULL. */
void ovl_destroy(eng_overlap *o);

#endif
