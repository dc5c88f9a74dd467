/* test_overlap.c — the photon stage's worker (engine/frame/overlap.c): with 2+ threads a job runs on
 * another thread, concurrently with the caller, and ovl_join waits for it; with 1 thread (or a
 * NULL overlap) ovl_start runs the job at once on the caller's thread; many start/join cycles,
 * joining with nothing in flight and destroying with a job pending all work. The frame loop's
 * bit-identity for 1 and 2+ threads is e2e_regression's and test_engine's. */
#include "overlap.h"

#include <check.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <time.h>

typedef struct job {
    pthread_t ran_on;
    atomic_int go;   /* the caller releases the job */
    atomic_int done;
    int runs;
} job;

static void waiting_job(void *arg)
{
    job *j = arg;
    j->ran_on = pthread_self();
    while (!atomic_load(&j->go)) {
        struct timespec ts = {0, 100000};
        nanosleep(&ts, NULL);
    }
    j->runs++;
    atomic_store(&j->done, 1);
}

static void counting_job(void *arg)
{
    job *j = arg;
    j->ran_on = pthread_self();
    j->runs++;
}

START_TEST(one_thread_runs_inline)
{
    ck_assert_ptr_null(ovl_create(1));
    ck_assert_ptr_null(ovl_create(0));
    job j = {0};
    ovl_start(NULL, counting_job, &j);
    ck_assert_int_eq(j.runs, 1); /* before ovl_start returned */
    ck_assert(pthread_equal(j.ran_on, pthread_self()));
    ovl_join(NULL);
    ovl_destroy(NULL);
}
END_TEST

START_TEST(two_threads_run_beside_the_caller)
{
    eng_overlap *o = ovl_create(2);
    ck_assert_ptr_nonnull(o);
    job j = {0};
    ovl_start(o, waiting_job, &j);
    /* The job waits for the caller: it can only finish if it runs on another thread. */
    ck_assert_int_eq(atomic_load(&j.done), 0);
    atomic_store(&j.go, 1);
    ovl_join(o);
    ck_assert_int_eq(atomic_load(&j.done), 1);
    ck_assert_int_eq(j.runs, 1);
    ck_assert(!pthread_equal(j.ran_on, pthread_self()));
    ovl_destroy(o);
}
END_TEST

START_TEST(many_cycles_and_idle_joins)
{
    eng_overlap *o = ovl_create(3);
    ck_assert_ptr_nonnull(o);
    ovl_join(o); /* nothing in flight */
    job j = {0};
    for (int i = 0; i < 1000; i++) {
        ovl_start(o, counting_job, &j);
        ovl_join(o);
        ck_assert_int_eq(j.runs, i + 1);
    }
    ovl_join(o);
    /* Destroying with a job in flight waits for it. */
    job w = {0};
    atomic_store(&w.go, 1);
    ovl_start(o, waiting_job, &w);
    ovl_destroy(o);
    ck_assert_int_eq(atomic_load(&w.done), 1);
}
END_TEST

static Suite *overlap_suite(void)
{
    Suite *s = suite_create("overlap");
    TCase *tc = tcase_create("worker");
    tcase_add_test(tc, one_thread_runs_inline);
    tcase_add_test(tc, two_threads_run_beside_the_caller);
    tcase_add_test(tc, many_cycles_and_idle_joins);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(overlap_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
