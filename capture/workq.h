/* workq.h — capture's bounded work queue: jobs handed from the thread that renders to worker
 * threads that encode and write them, so that writing a frame overlaps rendering the next.
 *
 * Bounded: at most `depth` jobs wait; cap_wq_push blocks while the queue is full, so the
 * memory the jobs hold is bounded by depth + workers jobs whatever the number pushed.
 * Ordered: workers take jobs in the order they were pushed (one worker runs them in that order).
 * Errors: a job's non-zero result is sticky; from then on no further job starts (each is given
 * to drop instead, which frees it), a push drops its job and returns that result (also a push
 * blocked on a full queue wakes for it), and cap_wq_finish returns it. The first error wins.
 */
#ifndef ISPM_CAP_WORKQ_H
#define ISPM_CAP_WORKQ_H

/* Runs one job on a worker thread; owns it (frees it). 0 on success. */
typedef int (*cap_wq_run_fn)(void *ctx, void *job);
/* Frees a job that will not run (after an error). */
typedef void (*cap_wq_drop_fn)(void *ctx, void *job);

typedef struct cap_wq cap_wq;

/* workers >= 1, depth >= 1. Out of memory or no thread ends the process (cap__xmalloc's
 * hook), so creation does not fail. */
cap_wq *cap_wq_create(int workers, int depth, cap_wq_run_fn run, cap_wq_drop_fn drop, void *ctx);

/* Queues job (blocking while depth jobs wait). 0, or the sticky error (job dropped). Calling
 * it after cap_wq_finish drops the job and returns -1. */
int cap_wq_push(cap_wq *q, void *job);

/* The sticky error, 0 if none (does not wait). */
int cap_wq_error(cap_wq *q);

/* Waits until every queued job has run (or been dropped after an error) and the workers have
 * ended; returns the sticky error. Idempotent. */
int cap_wq_finish(cap_wq *q);

/* cap_wq_finish, then frees the queue. Accepts NULL. */
void cap_wq_destroy(cap_wq *q);

#endif
