/* test_heap.c — Check suite for the frame heap of engine/core/core.c (eng_keep_freed_memory): the
 * range it advises for transparent huge pages holds what the main thread and other threads
 * allocate afterwards (one arena), the call is idempotent, and it is a no-op where the
 * allocator is not glibc's (sanitizers) or the kernel has no transparent huge pages. */
#define _DEFAULT_SOURCE /* sbrk */
#include "eng_core.h"

#include <check.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#define REPLACED_ALLOCATOR 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(memory_sanitizer) || __has_feature(thread_sanitizer)
#define REPLACED_ALLOCATOR 1
#endif
#endif
#ifndef REPLACED_ALLOCATOR
#define REPLACED_ALLOCATOR 0
#endif

/* Whether the kernel can advise huge pages at all (CONFIG_TRANSPARENT_HUGEPAGE). */
static int kernel_has_thp(void)
{
    return access("/sys/kernel/mm/transparent_hugepage/enabled", F_OK) == 0;
}

/* The VmFlags line of /proc/self/smaps for the mapping holding p ("" when not found). */
static void vm_flags_of(const void *p, char *out, size_t size)
{
    out[0] = 0;
    FILE *f = fopen("/proc/self/smaps", "r");
    ck_assert_ptr_nonnull(f);
    char line[512];
    int inside = 0;
    while (fgets(line, sizeof line, f)) {
        unsigned long lo, hi;
        if (sscanf(line, "%lx-%lx ", &lo, &hi) == 2) { /* a mapping's first line */
            inside = (uintptr_t)p >= lo && (uintptr_t)p < hi;
            continue;
        }
        if (inside && strncmp(line, "VmFlags:", 8) == 0) {
            snprintf(out, size, "%s", line + 8);
            break;
        }
    }
    fclose(f);
}

/* Whether the middle of a 16 MiB block is advised (its first pages may lie before the range's
 * first 2 MiB boundary). */
static int advised(const char *block)
{
    const char *p = block + ((size_t)8 << 20);
    char flags[512];
    vm_flags_of(p, flags, sizeof flags);
    return strstr(flags, " hg") != NULL;
}

static void *alloc_in_thread(void *arg)
{
    (void)arg;
    return malloc((size_t)16 << 20);
}

START_TEST(advises_the_heap_every_thread_uses)
{
    size_t n = eng_keep_freed_memory();
    if (REPLACED_ALLOCATOR || !kernel_has_thp()) {
        ck_assert_uint_eq(n, 0); /* nothing to advise: the call changes nothing */
        return;
    }
    ck_assert_uint_ge(n, (size_t)256 << 20);
    /* A large block of the main thread and one of another thread (which would have had an
     * arena of its own, outside the range): both in advised memory. */
    char *mine = malloc((size_t)16 << 20);
    ck_assert_ptr_nonnull(mine);
    pthread_t t;
    ck_assert_int_eq(pthread_create(&t, NULL, alloc_in_thread, NULL), 0);
    char *theirs = NULL;
    void *got = NULL;
    ck_assert_int_eq(pthread_join(t, &got), 0);
    theirs = got;
    ck_assert_ptr_nonnull(theirs);
    ck_assert_msg(advised(mine), "the main thread's 16 MiB block is not in advised memory");
    ck_assert_msg(advised(theirs), "another thread's 16 MiB block is not in advised memory");
    free(mine);
    free(theirs);
}
END_TEST

START_TEST(idempotent)
{
    size_t n = eng_keep_freed_memory();
    void *brk0 = sbrk(0);
    ck_assert_uint_eq(eng_keep_freed_memory(), n);
    ck_assert_uint_eq(eng_keep_freed_memory(), n);
    ck_assert_ptr_eq(sbrk(0), brk0); /* the heap grew once, on the first call */
}
END_TEST

START_TEST(freed_memory_stays)
{
    eng_keep_freed_memory();
    if (REPLACED_ALLOCATOR)
        return;
    /* 24 MiB, under the 32 MiB mmap threshold: from the heap (below the break, not a mapping of
     * its own, which glibc's default threshold would give), and back to the heap when freed (no
     * trim below 512 MiB free), so the break does not move. */
    void *brk0 = sbrk(0);
    for (int i = 0; i < 8; i++) {
        char *p = malloc((size_t)24 << 20);
        ck_assert_ptr_nonnull(p);
        ck_assert_msg((uintptr_t)p + ((size_t)24 << 20) <= (uintptr_t)brk0, "a 24 MiB block is not from the heap");
        memset(p, i, 4096);
        free(p);
        ck_assert_ptr_eq(sbrk(0), brk0);
    }
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("heap");
    TCase *tc = tcase_create("core");
    tcase_add_test(tc, advises_the_heap_every_thread_uses);
    tcase_add_test(tc, idempotent);
    tcase_add_test(tc, freed_memory_stays);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
