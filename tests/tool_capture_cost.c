/* tool_capture_cost.c — issue 22's capture_compression trade-off: for every frame file of a
 * recorded run, decodes its parts once, then per lossless compression writes the frame as
 * capture does (cap__write_exr: encode, write, fsync, rename) and decodes it back as replay
 * does (rep_read_parts: OpenEXR's C API, OpenImageIO for what it leaves), REPEATS times, and
 * prints per frame the file size and the median thread CPU and wall milliseconds of each. CPU time is what a loaded machine does
 * not distort much; on 2 shared cores, read the wall times with care. Also checks that every
 * compression decodes to the same bits (exit 1 if not).
 *
 * usage: ispm_test_capture_cost RUN [REPEATS]   (default 3; writes RUN/../capture-cost.tmp.exr)
 *        ispm_test_capture_cost --per-buffer FRAME.exr [REPEATS]   (default 1; each part alone) */
#define _POSIX_C_SOURCE 200809L

#include "cap_internal.h"
#include "oiio_shim.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "tool_timing.h"

/* --per-buffer: every part of one frame file on its own, per compression (and zlib level 1 for
 * the zlib ones): bytes against the raw floats and the median thread CPU ms of the encode, the
 * table capture's choice by kind of buffer (cap_compression_for) comes from. */
static int per_buffer(const char *frame, int reps)
{
    static const struct { cap_compression m; int level; const char *label; } modes[] = {
        {CAP_COMPRESSION_NONE, 0, "none"}, {CAP_COMPRESSION_RLE, 0, "rle"},   {CAP_COMPRESSION_ZIPS, 1, "zips1"},
        {CAP_COMPRESSION_ZIPS, 0, "zips"}, {CAP_COMPRESSION_ZIP, 1, "zip1"}, {CAP_COMPRESSION_ZIP, 0, "zip"},
        {CAP_COMPRESSION_PIZ, 0, "piz"}};
    enum { NM = sizeof modes / sizeof modes[0] };
    char tmp[4200];
    snprintf(tmp, sizeof tmp, "%s.per-buffer.tmp.exr", frame);
    rep_part *parts = NULL;
    int n = 0;
    eng_error err = {{0}};
    if (rep_read_parts(frame, (size_t)1 << 28, &parts, &n, &err) != ENG_OK) {
        fprintf(stderr, "ispm_test_capture_cost: %s\n", err.msg);
        return 2;
    }
    printf("%-34s %8s", "buffer", "raw MB");
    for (int k = 0; k < NM; k++)
        printf(" %6s%% %6sms", modes[k].label, "");
    printf("\n");
    for (int i = 0; i < n; i++) {
        eng_buffer v = rep_part_buffer(&parts[i]);
        const eng_buffer *b = &v;
        double raw = (double)v.width * v.height * v.channel_count * 4.0;
        printf("%-34s %8.2f", parts[i].name, raw / 1e6);
        for (int k = 0; k < NM; k++) {
            double tc[100];
            cap_exr_meta meta = {0, 0.0, modes[k].m, modes[k].level};
            for (int r = 0; r < reps; r++) {
                double c0 = tool_ms(CLOCK_THREAD_CPUTIME_ID);
                if (cap__write_exr(tmp, &b, 1, &meta, &err) != ENG_OK) {
                    fprintf(stderr, "ispm_test_capture_cost: %s\n", err.msg);
                    return 2;
                }
                tc[r] = tool_ms(CLOCK_THREAD_CPUTIME_ID) - c0;
            }
            struct stat st;
            stat(tmp, &st);
            printf(" %7.1f %8.1f", 100.0 * (double)st.st_size / raw, tool_median(tc, reps));
        }
        printf("\n");
        fflush(stdout);
    }
    remove(tmp);
    rep_parts_free(parts, n);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 3 && strcmp(argv[1], "--per-buffer") == 0)
        return per_buffer(argv[2], argc > 3 ? atoi(argv[3]) : 1);
    if (argc < 2 || argc > 3) {
        fprintf(stderr, "usage: ispm_test_capture_cost RUN [REPEATS]\n");
        return 2;
    }
    int reps = argc == 3 ? atoi(argv[2]) : 3;
    if (reps < 1 || reps > 100) {
        fprintf(stderr, "ispm_test_capture_cost: REPEATS must be 1..100\n");
        return 2;
    }
    char tmp[4200];
    snprintf(tmp, sizeof tmp, "%s/../capture-cost.tmp.exr", argv[1]);
    printf("%-5s %12s %12s %12s %12s %12s\n", "comp", "KiB/frame", "enc cpu ms", "enc wall ms", "dec cpu ms",
           "dec wall ms");
    int bad = 0;
    for (int m = CAP_COMPRESSION_NONE; m <= CAP_COMPRESSION_PIZ; m++) {
        double kib = 0, ec = 0, ew = 0, dc = 0, dw = 0;
        int frames = 0;
        for (int f = 0;; f++) {
            char path[4200];
            snprintf(path, sizeof path, "%s/frames/%06d.exr", argv[1], f);
            struct stat st;
            if (stat(path, &st) != 0)
                break;
            rep_part *parts = NULL;
            int n = 0;
            eng_error err = {{0}};
            if (rep_read_parts(path, (size_t)1 << 28, &parts, &n, &err) != ENG_OK) {
                fprintf(stderr, "ispm_test_capture_cost: %s\n", err.msg);
                return 2;
            }
            eng_buffer *views = calloc((size_t)n, sizeof *views);
            const eng_buffer **bufs = calloc((size_t)n, sizeof *bufs);
            for (int i = 0; i < n; i++) {
                views[i] = rep_part_buffer(&parts[i]);
                bufs[i] = &views[i];
            }
            double tc[100], tw[100], uc[100], uw[100];
            cap_exr_meta meta = {f, f / 8.0, (cap_compression)m, 0};
            for (int r = 0; r < reps; r++) {
                double c0 = tool_ms(CLOCK_THREAD_CPUTIME_ID), w0 = tool_ms(CLOCK_MONOTONIC);
                if (cap__write_exr(tmp, bufs, n, &meta, &err) != ENG_OK) {
                    fprintf(stderr, "ispm_test_capture_cost: %s\n", err.msg);
                    return 2;
                }
                tc[r] = tool_ms(CLOCK_THREAD_CPUTIME_ID) - c0;
                tw[r] = tool_ms(CLOCK_MONOTONIC) - w0;
                rep_part *back = NULL;
                int nb = 0;
                c0 = tool_ms(CLOCK_THREAD_CPUTIME_ID);
                w0 = tool_ms(CLOCK_MONOTONIC);
                if (rep_read_parts(tmp, (size_t)1 << 28, &back, &nb, &err) != ENG_OK) {
                    fprintf(stderr, "ispm_test_capture_cost: %s\n", err.msg);
                    return 2;
                }
                uc[r] = tool_ms(CLOCK_THREAD_CPUTIME_ID) - c0;
                uw[r] = tool_ms(CLOCK_MONOTONIC) - w0;
                for (int i = 0; i < n && r == 0; i++) {
                    char a[40], b[40];
                    eng_buffer_digest(&views[i], a);
                    eng_buffer vb = rep_part_buffer(&back[i]);
                    eng_buffer_digest(&vb, b);
                    if (nb != n || strcmp(a, b) != 0) {
                        fprintf(stderr, "ispm_test_capture_cost: %s: part %s decodes differently with %s\n", path,
                                parts[i].name, cap_compression_name((cap_compression)m));
                        bad = 1;
                    }
                }
                rep_parts_free(back, nb);
            }
            stat(tmp, &st);
            kib += (double)st.st_size / 1024.0;
            ec += tool_median(tc, reps);
            ew += tool_median(tw, reps);
            dc += tool_median(uc, reps);
            dw += tool_median(uw, reps);
            frames++;
            free(bufs);
            free(views);
            rep_parts_free(parts, n);
        }
        if (!frames) {
            fprintf(stderr, "ispm_test_capture_cost: %s/frames/000000.exr: no frame\n", argv[1]);
            return 2;
        }
        printf("%-5s %12.0f %12.1f %12.1f %12.1f %12.1f\n", cap_compression_name((cap_compression)m),
               kib / frames, ec / frames, ew / frames, dc / frames, dw / frames);
    }
    remove(tmp);
    return bad;
}
