/* core.c — the engine's file-free, GL-free helpers that every module may link: error
 * formatting, content digests (XXH3-128 from libxxhash), non-finite counting (file reads are
 * files.c's). Replay and the viewer link this (through
 * the ispm_core target) without pulling in OSMesa or Embree. */
#define _DEFAULT_SOURCE /* sbrk, madvise */
#include "eng_core.h"

#include <errno.h>
#ifdef __GLIBC__
#include <malloc.h>
#include <pthread.h>
#include <sys/mman.h>
#include <unistd.h>
#endif
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <xxhash.h>

eng_result eng_fail(eng_error *err, eng_result code, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
        /* One line: a message is never allowed to spill over. */
        for (char *p = err->msg; *p; p++)
            if (*p == '\n' || *p == '\r')
                *p = ' ';
    }
    return code;
}

const char *eng_result_name(eng_result r)
{
    switch (r) {
    case ENG_OK: return "ok";
    case ENG_ERR_IO: return "io";
    case ENG_ERR_PARSE: return "parse";
    case ENG_ERR_INVALID: return "invalid";
    case ENG_ERR_UNSUPPORTED: return "unsupported";
    case ENG_ERR_GL: return "gl";
    case ENG_ERR_NOMEM: return "nomem";
    case ENG_ERR_ABORTED: return "aborted";
    }
    return "unknown";
}

static void hex128(XXH128_hash_t h, char out[40])
{
    snprintf(out, 40, "%016llx%016llx", (unsigned long long)h.high64, (unsigned long long)h.low64);
}

void eng_digest_hex(const void *data, size_t len, char out[40])
{
    hex128(XXH3_128bits(data, len), out);
}

void eng_buffer_digest(const eng_buffer *b, char out[40])
{
    int order[ENG_MAX_CHANNELS];
    int n = b->channel_count;
    for (int i = 0; i < n; i++)
        order[i] = i;
    for (int i = 1; i < n; i++) { /* insertion sort by name: n is tiny */
        int k = order[i], j = i - 1;
        while (j >= 0 && strcmp(b->channels[order[j]], b->channels[k]) > 0) {
            order[j + 1] = order[j];
            j--;
        }
        order[j + 1] = k;
    }
    XXH3_state_t *st = XXH3_createState();
    if (!st) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    XXH3_128bits_reset(st);
    size_t npix = (size_t)b->width * (size_t)b->height;
    float plane[1024];
    for (int c = 0; c < n; c++) {
        const float *src = b->data + order[c];
        size_t done = 0;
        while (done < npix) {
            size_t m = npix - done < 1024 ? npix - done : 1024;
            for (size_t i = 0; i < m; i++)
                plane[i] = src[(done + i) * (size_t)n];
            XXH3_128bits_update(st, plane, m * sizeof(float));
            done += m;
        }
    }
    hex128(XXH3_128bits_digest(st), out);
    XXH3_freeState(st);
}

/* Whether every value of v[0..n) is finite. With the sign cleared, a float's bits are at least
 * infinity's (0x7f800000) exactly when it is NaN or infinite, and adding 0x00800000 then carries
 * into bit 31: so OR the sums and test that bit. Blocks of 16 lanes with a fixed inner loop, so
 * that -O2 vectorises it (and, pand, paddd, por a vector); the tail one at a time. */
static int all_finite(const float *v, size_t n)
{
    enum { BLOCK = 16 };
    uint32_t acc[BLOCK] = {0};
    size_t i = 0;
    for (; i + BLOCK <= n; i += BLOCK)
#pragma GCC unroll 16
        for (int k = 0; k < BLOCK; k++) {
            uint32_t u;
            memcpy(&u, v + i + k, sizeof u);
            acc[k] |= (u & 0x7fffffffu) + 0x00800000u;
        }
    uint32_t m = 0;
    for (int k = 0; k < BLOCK; k++)
        m |= acc[k];
    for (; i < n; i++) {
        uint32_t u;
        memcpy(&u, v + i, sizeof u);
        m |= (u & 0x7fffffffu) + 0x00800000u;
    }
    return !(m & 0x80000000u);
}

void eng_buffer_nonfinite(const eng_buffer *b, uint64_t *nan_count, uint64_t *inf_count,
                          int *first_x, int *first_y)
{
    uint64_t nn = 0, ni = 0;
    int fx = -1, fy = -1;
    size_t npix = (size_t)b->width * (size_t)b->height;
    /* Most buffers have none: one pass over the bits decides (the counting loop below, per
     * value with two tests and a branch, was 1.3-2.3 ms of the capture's CPU a frame for the 43
     * buffers of cornell-box-ci, perf). The counts and the first pixel are the loop's either way. */
    if (!all_finite(b->data, npix * (size_t)b->channel_count)) {
        for (size_t p = 0; p < npix; p++) {
            int bad = 0;
            for (int c = 0; c < b->channel_count; c++) {
                float v = b->data[p * (size_t)b->channel_count + (size_t)c];
                if (isnan(v)) {
                    nn++;
                    bad = 1;
                } else if (isinf(v)) {
                    ni++;
                    bad = 1;
                }
            }
            if (bad && fx < 0) {
                fx = (int)(p % (size_t)b->width);
                fy = (int)(p / (size_t)b->width);
            }
        }
    }
    if (nan_count) *nan_count = nn;
    if (inf_count) *inf_count = ni;
    if (first_x) *first_x = fx;
    if (first_y) *first_y = fy;
}

/* The heap, tuned for frames (record, replay). glibc only; a no-op elsewhere and where the
 * allocator is replaced (the sanitizers'), and idempotent.
 *
 * Freed memory kept in the heap instead of returned to the system (allocations up to 32 MiB
 * from the heap, no trimming below 512 MiB free). A frame allocates and frees the same large
 * blocks every frame (replay: a frame's buffers, 6 MB for the CI run per side; record:
 * llvmpipe's binned scene, which a 1-thread splat bins in one piece), and glibc serves each from
 * fresh mmap'd or trimmed-and-regrown memory, so every page is faulted in anew. Measured
 * (idle machine): replay of the CI run ~24,000 faults fewer; record of cornell-box-perf,
 * 1 thread, 66,886 -> 39,708 minor faults, 2.51 -> 2.21 s, the same peak RSS (220 MB).
 *
 * Transparent huge pages: the heap is grown once by HEAP_THP_BYTES of
 * address space (glibc's M_TOP_PAD for one growth: no page is touched; less than the trim
 * threshold, so that it stays) and that range is madvise(MADV_HUGEPAGE)d, so first touches
 * fault 2 MiB at a time instead of 4 KiB (what glibc's own glibc.malloc.hugetlb=1 tunable
 * does, which must be set before the process starts), and every thread allocates from it
 * (one arena: M_ARENA_MAX 1; the other arenas would be fresh mmap'd heaps outside the range).
 * The pages llvmpipe's textures, the photon buffers and the capture's copies first touch were
 * most of record's 37,000 minor faults, each costly on a virtual machine. Measured (2-core VM;
 * record of cornell-box-perf, 3 frames, 65,536 photons; bench/perf_threads.sh against the
 * build before, 5 alternated runs): 36,700 -> 5,000 minor faults; start-up (one 32x32 frame)
 * 0.65x the time, 1 thread 0.89x, 2 threads 0.84x; replay of the CI run against its golden
 * unchanged (0.58 vs 0.57 s), against cornell-box-quads-ci 1.10 -> 0.98 s; peak RSS +12-15 MB
 * (pages are 2 MiB). With THP "never" the advice is kept and nothing changes; with "always"
 * it changes nothing either. Only where memory comes from: no result depends on it.
 * Returns the bytes advised (0 when none: not glibc, allocator replaced, heap not contiguous,
 * or madvise refused). */
#define HEAP_TRIM_BYTES (512 << 20)
#define HEAP_THP_BYTES ((size_t)384 << 20)
/* Below the trim threshold with the probe block: freeing the probe must not give it back. */
_Static_assert(HEAP_THP_BYTES + ((size_t)8 << 20) < (size_t)HEAP_TRIM_BYTES, "advised range would be trimmed");
#define HEAP_THP_ALIGN ((uintptr_t)2 << 20)

#ifdef __GLIBC__
static size_t heap_advised;

static void heap_tune_once(void)
{
    mallopt(M_MMAP_THRESHOLD, 32 << 20); /* glibc's largest */
    mallopt(M_TRIM_THRESHOLD, HEAP_TRIM_BYTES);
    mallopt(M_ARENA_MAX, 1);
    /* One growth of the main heap padded to HEAP_THP_BYTES, then the pad back to glibc's
     * default (128 KiB): [b0, b1) is the new, untouched range. */
    uintptr_t b0 = (uintptr_t)sbrk(0);
    mallopt(M_TOP_PAD, (int)HEAP_THP_BYTES);
    /* More than the top chunk can hold: the heap grows. Through a volatile, or the compiler
     * may drop a malloc whose block is never used, and its free with it. */
    void *volatile probe = malloc((size_t)4 << 20);
    uintptr_t b1 = (uintptr_t)sbrk(0);
    mallopt(M_TOP_PAD, 128 << 10);
    free(probe);
    if (b0 == (uintptr_t)-1 || b1 == (uintptr_t)-1 || b1 <= b0 || b1 - b0 < HEAP_THP_BYTES / 2)
        return; /* the allocator is not glibc's brk heap (sanitizers), or the heap could not grow */
    uintptr_t lo = (b0 + HEAP_THP_ALIGN - 1) & ~(HEAP_THP_ALIGN - 1);
    if (lo < b1 && madvise((void *)lo, b1 - lo, MADV_HUGEPAGE) == 0)
        heap_advised = b1 - lo;
}
#endif

size_t eng_keep_freed_memory(void)
{
#ifdef __GLIBC__
    static pthread_once_t once = PTHREAD_ONCE_INIT;
    pthread_once(&once, heap_tune_once);
    return heap_advised;
#else
    return 0;
#endif
}
