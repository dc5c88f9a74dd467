/* tool_pbo_readback.c — issue 22: does reading a float render target back through a pixel
 * buffer object (GL_PIXEL_PACK_BUFFER, then glMapBufferRange) beat glReadPixels into client
 * memory on the context the engine uses (OSMesa/llvmpipe, or --gl egl)? Each iteration
 * clears the target (so the read waits for llvmpipe's deferred work, as after a pass) and reads
 * it back as RGBA float, alternating the two ways; prints the median thread CPU and wall
 * milliseconds per read, and for the PBO how much of it the glReadPixels call itself takes
 * (the part that would stay on the render thread if mapping were deferred). Also checks that
 * both give the same bytes (exit 1 if not).
 *
 * usage: ispm_test_pbo [SIZE [ITERATIONS [osmesa|egl]]]   (default 160 200 osmesa) */
#define _POSIX_C_SOURCE 200809L

#include "gl.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "tool_timing.h"

int main(int argc, char **argv)
{
    int size = argc > 1 ? atoi(argv[1]) : 160, iters = argc > 2 ? atoi(argv[2]) : 200;
    const char *backend = argc > 3 ? argv[3] : "osmesa";
    if (size < 1 || size > 4096 || iters < 1 || iters > 10000) {
        fprintf(stderr, "usage: ispm_test_pbo [SIZE 1..4096 [ITERATIONS 1..10000 [osmesa|egl]]]\n");
        return 2;
    }
    eng_glctx *ctx = NULL;
    eng_error err = {{0}};
    if (glctx_create_on(backend, 0, 0, &ctx, &err) != ENG_OK) {
        fprintf(stderr, "ispm_test_pbo: %s\n", err.msg);
        return 2;
    }
    glu_target t;
    if (glu_target_create(&t, 1, size, size, 0, &err) != ENG_OK) {
        fprintf(stderr, "ispm_test_pbo: %s\n", err.msg);
        return 2;
    }
    size_t bytes = (size_t)size * (size_t)size * 4 * sizeof(float);
    float *a = malloc(bytes), *b = malloc(bytes);
    double *cd = calloc((size_t)iters, sizeof *cd), *wd = calloc((size_t)iters, sizeof *wd);
    double *cp = calloc((size_t)iters, sizeof *cp), *wp = calloc((size_t)iters, sizeof *wp);
    double *wcall = calloc((size_t)iters, sizeof *wcall);
    if (!a || !b || !cd || !wd || !cp || !wp || !wcall)
        return 2;
    GLuint pbo;
    glGenBuffers(1, &pbo);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, pbo);
    glBufferData(GL_PIXEL_PACK_BUFFER, (GLsizeiptr)bytes, NULL, GL_STREAM_READ);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glViewport(0, 0, size, size);
    int same = 1;
    for (int i = 0; i < iters; i++) {
        float v = (float)(i % 7) * 0.25f;
        glClearColor(v, 0.5f, 1.0f - v, 1.0f);
        glClear(GL_COLOR_BUFFER_BIT);
        double c0 = tool_ms(CLOCK_THREAD_CPUTIME_ID), w0 = tool_ms(CLOCK_MONOTONIC);
        glReadPixels(0, 0, size, size, GL_RGBA, GL_FLOAT, a);
        cd[i] = tool_ms(CLOCK_THREAD_CPUTIME_ID) - c0;
        wd[i] = tool_ms(CLOCK_MONOTONIC) - w0;

        glClear(GL_COLOR_BUFFER_BIT);
        c0 = tool_ms(CLOCK_THREAD_CPUTIME_ID);
        w0 = tool_ms(CLOCK_MONOTONIC);
        glBindBuffer(GL_PIXEL_PACK_BUFFER, pbo);
        glReadPixels(0, 0, size, size, GL_RGBA, GL_FLOAT, NULL);
        wcall[i] = tool_ms(CLOCK_MONOTONIC) - w0;
        const void *m = glMapBufferRange(GL_PIXEL_PACK_BUFFER, 0, (GLsizeiptr)bytes, GL_MAP_READ_BIT);
        if (!m) {
            fprintf(stderr, "ispm_test_pbo: glMapBufferRange failed\n");
            return 2;
        }
        memcpy(b, m, bytes);
        glUnmapBuffer(GL_PIXEL_PACK_BUFFER);
        glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
        cp[i] = tool_ms(CLOCK_THREAD_CPUTIME_ID) - c0;
        wp[i] = tool_ms(CLOCK_MONOTONIC) - w0;
        same = same && memcmp(a, b, bytes) == 0;
    }
    printf("%s %s, %dx%d RGBA32F, %d reads each (median ms per read)\n", glctx_renderer(ctx), backend, size, size,
           iters);
    printf("  glReadPixels to memory: cpu %.3f  wall %.3f\n", tool_median(cd, iters), tool_median(wd, iters));
    printf("  PBO + map + copy:       cpu %.3f  wall %.3f  (of which the glReadPixels call: wall %.3f)\n",
           tool_median(cp, iters), tool_median(wp, iters), tool_median(wcall, iters));
    printf("  same bytes: %s\n", same ? "yes" : "NO");
    glDeleteBuffers(1, &pbo);
    glu_target_destroy(&t);
    glctx_destroy(ctx);
    free(a);
    free(b);
    free(cd);
    free(wd);
    free(cp);
    free(wp);
    free(wcall);
    return same ? 0 : 1;
}
