/* workq.c — the bounded, ordered, error-sticky work queue of workq.h: a ring of job pointers
 * under one mutex, two condition variables (not empty for the workers, not full for the
 * pusher) and POSIX threads. Nothing here knows what a job is. */
#define _POSIX_C_SOURCE 200809L

#include "workq.h"
#include "cap_internal.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct cap_wq {
    pthread_mutex_t lock;
    pthread_cond_t not_empty, not_full;
    void **ring;
    int depth, head, count; /* count jobs wait in ring[head], ring[head+1], ... (mod depth) */
    int closed;             /* no more pushes: workers end when the ring is empty */
    int error;              /* sticky, 0 if none */
    int workers, joined;
    pthread_t *threads;
    cap_wq_run_fn run;
    cap_wq_drop_fn drop;
    void *ctx;
};

/* Takes every waiting job out of the ring (under the lock) to be dropped outside it. */
static int take_all(cap_wq *q, void **out)
{
    int n = q->count;
    for (int i = 0; i < n; i++)
        out[i] = q->ring[(q->head + i) % q->depth];
    q->head = q->count = 0;
    return n;
}

static void *worker(void *arg)
{
    cap_wq *q = arg;
    void **dropped = cap__xcalloc((size_t)q->depth, sizeof *dropped);
    pthread_mutex_lock(&q->lock);
    for (;;) {
        while (q->count == 0 && !q->closed && !q->error)
            pthread_cond_wait(&q->not_empty, &q->lock);
        if (q->error || (q->count == 0 && q->closed))
            break;
        void *job = q->ring[q->head];
        q->head = (q->head + 1) % q->depth;
        q->count--;
        pthread_cond_signal(&q->not_full);
        pthread_mutex_unlock(&q->lock);
        int r = q->run(q->ctx, job);
        pthread_mutex_lock(&q->lock);
        if (r && !q->error) {
            q->error = r;
            pthread_cond_broadcast(&q->not_empty);
            pthread_cond_broadcast(&q->not_full);
        }
    }
    int n = q->error ? take_all(q, dropped) : 0;
    pthread_mutex_unlock(&q->lock);
    for (int i = 0; i < n; i++)
        q->drop(q->ctx, dropped[i]);
    free(dropped);
    return NULL;
}

cap_wq *cap_wq_create(int workers, int depth, cap_wq_run_fn run, cap_wq_drop_fn drop, void *ctx)
{
    cap_wq *q = cap__xcalloc(1, sizeof *q);
    q->workers = workers < 1 ? 1 : workers;
    q->depth = depth < 1 ? 1 : depth;
    q->ring = cap__xcalloc((size_t)q->depth, sizeof *q->ring);
    q->threads = cap__xcalloc((size_t)q->workers, sizeof *q->threads);
    q->run = run;
    q->drop = drop;
    q->ctx = ctx;
    pthread_mutex_init(&q->lock, NULL);
    pthread_cond_init(&q->not_empty, NULL);
    pthread_cond_init(&q->not_full, NULL);
    for (int i = 0; i < q->workers; i++)
        if (pthread_create(&q->threads[i], NULL, worker, q) != 0) {
            fprintf(stderr, "ispm: cannot start a capture thread\n");
            abort();
        }
    return q;
}

int cap_wq_push(cap_wq *q, void *job)
{
    pthread_mutex_lock(&q->lock);
    while (q->count == q->depth && !q->error && !q->closed)
        pthread_cond_wait(&q->not_full, &q->lock);
    int r = q->error ? q->error : q->closed ? -1 : 0;
    if (!r) {
        q->ring[(q->head + q->count) % q->depth] = job;
        q->count++;
        pthread_cond_signal(&q->not_empty);
    }
    pthread_mutex_unlock(&q->lock);
    if (r)
        q->drop(q->ctx, job);
    return r;
}

int cap_wq_error(cap_wq *q)
{
    pthread_mutex_lock(&q->lock);
    int r = q->error;
    pthread_mutex_unlock(&q->lock);
    return r;
}

int cap_wq_finish(cap_wq *q)
{
    pthread_mutex_lock(&q->lock);
    q->closed = 1;
    pthread_cond_broadcast(&q->not_empty);
    pthread_cond_broadcast(&q->not_full);
    int join = !q->joined;
    q->joined = 1;
    pthread_mutex_unlock(&q->lock);
    if (join)
        for (int i = 0; i < q->workers; i++)
            pthread_join(q->threads[i], NULL);
    return cap_wq_error(q);
}

void cap_wq_destroy(cap_wq *q)
{
    if (!q)
        return;
    cap_wq_finish(q);
    pthread_mutex_destroy(&q->lock);
    pthread_cond_destroy(&q->not_empty);
    pthread_cond_destroy(&q->not_full);
    free(q->threads);
    free(q->ring);
    free(q);
}
