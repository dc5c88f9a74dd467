/* overlap.c — the worker thread of overlap.h: one persistent thread (so that the OpenMP team
 * the photon trace starts from it is created once, not per frame), a mutex and two condition
 * variables; a job is handed over and waited for, nothing else is shared.
 */
#include "overlap.h"

#include <pthread.h>
#include <stdlib.h>

struct eng_overlap {
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t wake; /* a job was posted, or stop */
    pthread_cond_t done; /* the posted job returned */
    void (*job)(void *arg);
    void *arg;
    int busy; /* a job is posted and has not returned */
    int stop;
};

static void *worker(void *p)
{
    eng_overlap *o = p;
    pthread_mutex_lock(&o->lock);
    for (;;) {
        while (!o->busy && !o->stop)
            pthread_cond_wait(&o->wake, &o->lock);
        if (!o->busy) /* stop, nothing pending */
            break;
        void (*job)(void *) = o->job;
        void *arg = o->arg;
        pthread_mutex_unlock(&o->lock);
        job(arg);
        pthread_mutex_lock(&o->lock);
        o->busy = 0;
        pthread_cond_broadcast(&o->done);
    }
    pthread_mutex_unlock(&o->lock);
    return NULL;
}

eng_overlap *ovl_create(int threads)
{
    if (threads < 2)
        return NULL;
    eng_overlap *o = calloc(1, sizeof *o);
    if (!o)
        return NULL;
    pthread_mutex_init(&o->lock, NULL);
    pthread_cond_init(&o->wake, NULL);
    pthread_cond_init(&o->done, NULL);
    if (pthread_create(&o->thread, NULL, worker, o) != 0) {
        pthread_cond_destroy(&o->done);
        pthread_cond_destroy(&o->wake);
        pthread_mutex_destroy(&o->lock);
        free(o);
        return NULL;
    }
    return o;
}

void ovl_start(eng_overlap *o, void (*job)(void *arg), void *arg)
{
    if (!o) {
        job(arg);
        return;
    }
    ovl_join(o);
    pthread_mutex_lock(&o->lock);
    o->job = job;
    o->arg = arg;
    o->busy = 1;
    pthread_cond_signal(&o->wake);
    pthread_mutex_unlock(&o->lock);
}

void ovl_join(eng_overlap *o)
{
    if (!o)
        return;
    pthread_mutex_lock(&o->lock);
    while (o->busy)
        pthread_cond_wait(&o->done, &o->lock);
    pthread_mutex_unlock(&o->lock);
}

void ovl_destroy(eng_overlap *o)
{
    if (!o)
        return;
    pthread_mutex_lock(&o->lock);
    o->stop = 1;
    pthread_cond_signal(&o->wake);
    pthread_mutex_unlock(&o->lock);
    pthread_join(o->thread, NULL);
    pthread_cond_destroy(&o->done);
    pthread_cond_destroy(&o->wake);
    pthread_mutex_destroy(&o->lock);
    free(o);
}
