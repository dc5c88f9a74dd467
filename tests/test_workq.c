/* test_workq.c — capture's bounded work queue (capture/workq.c): one worker runs jobs in push order,
 * at most `depth` wait (a push on a full queue blocks until a worker takes one), a job's error
 * is sticky (later pushes fail and drop their job, finish returns it, queued jobs are dropped,
 * never run), a push blocked on a full queue wakes with the error, and every job is either run
 * or dropped exactly once. */
#define _POSIX_C_SOURCE 200809L

#include "workq.h"

#include <check.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { MAX_JOBS = 256 };

/* What the jobs did, shared by the test and the workers. */
typedef struct log_t {
    pthread_mutex_t lock;
    pthread_cond_t changed;
    int started[MAX_JOBS], nstarted; /* job ids in start order */
    int ran[MAX_JOBS], dropped[MAX_JOBS];
    int running, max_running;
    int gate_open;      /* jobs wait for it when gated */
    int fail_id, fail_code;
} log_t;

typedef struct job_t {
    log_t *log;
    int id;
    int gated;
} job_t;

static void log_init(log_t *l)
{
    memset(l, 0, sizeof *l);
    pthread_mutex_init(&l->lock, NULL);
    pthread_cond_init(&l->changed, NULL);
    l->gate_open = 1;
    l->fail_id = -1;
}

static void log_free(log_t *l)
{
    pthread_mutex_destroy(&l->lock);
    pthread_cond_destroy(&l->changed);
}

static int run_job(void *ctx, void *p)
{
    log_t *l = ctx;
    job_t *j = p;
    pthread_mutex_lock(&l->lock);
    l->started[l->nstarted++] = j->id;
    if (++l->running > l->max_running)
        l->max_running = l->running;
    pthread_cond_broadcast(&l->changed);
    while (j->gated && !l->gate_open)
        pthread_cond_wait(&l->changed, &l->lock);
    l->running--;
    l->ran[j->id]++;
    int r = j->id == l->fail_id ? l->fail_code : 0;
    pthread_cond_broadcast(&l->changed);
    pthread_mutex_unlock(&l->lock);
    free(j);
    return r;
}

static void drop_job(void *ctx, void *p)
{
    log_t *l = ctx;
    job_t *j = p;
    pthread_mutex_lock(&l->lock);
    l->dropped[j->id]++;
    pthread_mutex_unlock(&l->lock);
    free(j);
}

static job_t *job(log_t *l, int id, int gated)
{
    job_t *j = calloc(1, sizeof *j);
    ck_assert_ptr_nonnull(j);
    j->log = l;
    j->id = id;
    j->gated = gated;
    return j;
}

static void open_gate(log_t *l)
{
    pthread_mutex_lock(&l->lock);
    l->gate_open = 1;
    pthread_cond_broadcast(&l->changed);
    pthread_mutex_unlock(&l->lock);
}

/* Waits until n jobs have started. */
static void wait_started(log_t *l, int n)
{
    pthread_mutex_lock(&l->lock);
    while (l->nstarted < n)
        pthread_cond_wait(&l->changed, &l->lock);
    pthread_mutex_unlock(&l->lock);
}

static void sleep_ms(int ms)
{
    struct timespec ts = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&ts, NULL);
}

/* A push on another thread, to see whether it blocks. */
typedef struct pusher {
    cap_wq *q;
    job_t *j;
    int result;
    volatile int done;
    pthread_mutex_t *lock;
} pusher;

static void *push_thread(void *p)
{
    pusher *u = p;
    int r = cap_wq_push(u->q, u->j);
    pthread_mutex_lock(u->lock);
    u->result = r;
    u->done = 1;
    pthread_mutex_unlock(u->lock);
    return NULL;
}

static int pusher_done(pusher *u)
{
    pthread_mutex_lock(u->lock);
    int d = u->done;
    pthread_mutex_unlock(u->lock);
    return d;
}

START_TEST(test_order)
{
    for (int workers = 1; workers <= 3; workers++) {
        log_t l;
        log_init(&l);
        cap_wq *q = cap_wq_create(workers, 2, run_job, drop_job, &l);
        for (int i = 0; i < 100; i++)
            ck_assert_int_eq(cap_wq_push(q, job(&l, i, 0)), 0);
        ck_assert_int_eq(cap_wq_finish(q), 0);
        ck_assert_int_eq(cap_wq_finish(q), 0); /* idempotent */
        cap_wq_destroy(q);
        ck_assert_int_eq(l.nstarted, 100);
        for (int i = 0; i < 100; i++) {
            if (workers == 1)
                ck_assert_int_eq(l.started[i], i); /* FIFO (several workers take jobs in push order,
                                                     * but may start them in another) */
            ck_assert_int_eq(l.ran[i], 1);
            ck_assert_int_eq(l.dropped[i], 0);
        }
        ck_assert_int_le(l.max_running, workers);
        log_free(&l);
    }
}
END_TEST

START_TEST(test_bound)
{
    enum { DEPTH = 3 };
    log_t l;
    log_init(&l);
    l.gate_open = 0;
    pthread_mutex_t plock = PTHREAD_MUTEX_INITIALIZER;
    cap_wq *q = cap_wq_create(1, DEPTH, run_job, drop_job, &l);
    ck_assert_int_eq(cap_wq_push(q, job(&l, 0, 1)), 0);
    wait_started(&l, 1); /* the worker holds job 0 */
    for (int i = 1; i <= DEPTH; i++)
        ck_assert_int_eq(cap_wq_push(q, job(&l, i, 1)), 0); /* fills the queue, never blocks */
    pusher u = {q, job(&l, DEPTH + 1, 1), -1, 0, &plock};
    pthread_t t;
    ck_assert_int_eq(pthread_create(&t, NULL, push_thread, &u), 0);
    sleep_ms(100);
    ck_assert_msg(!pusher_done(&u), "a push on a full queue returned");
    open_gate(&l);
    pthread_join(t, NULL);
    ck_assert_int_eq(u.result, 0);
    ck_assert_int_eq(cap_wq_finish(q), 0);
    cap_wq_destroy(q);
    ck_assert_int_eq(l.nstarted, DEPTH + 2);
    for (int i = 0; i < DEPTH + 2; i++)
        ck_assert_int_eq(l.ran[i], 1);
    pthread_mutex_destroy(&plock);
    log_free(&l);
}
END_TEST

START_TEST(test_error_sticky)
{
    for (int workers = 1; workers <= 2; workers++) {
        log_t l;
        log_init(&l);
        l.fail_id = 5;
        l.fail_code = 7;
        /* Jobs after the failing one wait at a closed gate, so that a second worker cannot run
         * the other 54 while job 5 is still returning its error: the pushes then block on the
         * full queue until the failure is seen, and the loop cannot end before it (before this,
         * a busy machine could finish every push first and find no error yet). */
        l.gate_open = 0;
        cap_wq *q = cap_wq_create(workers, 4, run_job, drop_job, &l);
        int first_fail = -1;
        for (int i = 0; i < 60; i++) {
            int r = cap_wq_push(q, job(&l, i, i > 5));
            ck_assert(r == 0 || r == 7);
            if (r && first_fail < 0)
                first_fail = i;
            if (first_fail >= 0)
                ck_assert_int_eq(r, 7); /* sticky */
            if (i == 5)
                wait_started(&l, 6);
        }
        ck_assert_int_eq(cap_wq_error(q), 7);
        open_gate(&l); /* a job taken before the failure was seen may be waiting there */
        ck_assert_int_eq(cap_wq_finish(q), 7);
        ck_assert_int_eq(cap_wq_push(q, job(&l, 60, 0)), 7);
        cap_wq_destroy(q);
        ck_assert_int_gt(first_fail, 5);
        ck_assert_int_eq(l.ran[5], 1);
        int ran = 0;
        for (int i = 0; i <= 60; i++) {
            ck_assert_int_eq(l.ran[i] + l.dropped[i], 1); /* each job once, none leaked */
            ran += l.ran[i];
        }
        /* After the failure no job started that was pushed after it was seen. */
        for (int i = first_fail; i <= 60; i++)
            ck_assert_int_eq(l.ran[i], 0);
        ck_assert_int_le(ran, first_fail);
        log_free(&l);
    }
}
END_TEST

START_TEST(test_error_wakes_blocked_push)
{
    log_t l;
    log_init(&l);
    l.gate_open = 0;
    l.fail_id = 0;
    l.fail_code = 3;
    pthread_mutex_t plock = PTHREAD_MUTEX_INITIALIZER;
    cap_wq *q = cap_wq_create(1, 1, run_job, drop_job, &l);
    ck_assert_int_eq(cap_wq_push(q, job(&l, 0, 1)), 0);
    wait_started(&l, 1);
    ck_assert_int_eq(cap_wq_push(q, job(&l, 1, 0)), 0); /* waits in the queue */
    pusher u = {q, job(&l, 2, 0), -1, 0, &plock};
    pthread_t t;
    ck_assert_int_eq(pthread_create(&t, NULL, push_thread, &u), 0);
    sleep_ms(50);
    ck_assert(!pusher_done(&u));
    open_gate(&l); /* job 0 ends with error 3 */
    pthread_join(t, NULL);
    ck_assert_int_eq(u.result, 3);
    ck_assert_int_eq(cap_wq_finish(q), 3);
    cap_wq_destroy(q);
    ck_assert_int_eq(l.ran[0], 1);
    ck_assert_int_eq(l.ran[1], 0); /* queued when the error came: dropped, never run */
    ck_assert_int_eq(l.dropped[1], 1);
    ck_assert_int_eq(l.dropped[2], 1);
    pthread_mutex_destroy(&plock);
    log_free(&l);
}
END_TEST

START_TEST(test_push_after_finish)
{
    log_t l;
    log_init(&l);
    cap_wq *q = cap_wq_create(2, 2, run_job, drop_job, &l);
    ck_assert_int_eq(cap_wq_finish(q), 0);
    ck_assert_int_eq(cap_wq_push(q, job(&l, 0, 0)), -1);
    ck_assert_int_eq(l.dropped[0], 1);
    cap_wq_destroy(q);
    cap_wq_destroy(NULL);
    log_free(&l);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("workq");
    TCase *tc = tcase_create("queue");
    tcase_add_test(tc, test_order);
    tcase_add_test(tc, test_bound);
    tcase_add_test(tc, test_error_sticky);
    tcase_add_test(tc, test_error_wakes_blocked_push);
    tcase_add_test(tc, test_push_after_finish);
    suite_add_tcase(s, tc);
    SRunner *sr = srunner_create(s);
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
