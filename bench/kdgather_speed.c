/* kdgather_speed.c — bench/kdgather-speed.sh's driver: kd_gather (this tree) against
 * kd_gather_old (an older ind_kdgather.c compiled beside it) on one synthetic frame, alternating,
 * 7 rounds; prints both medians and their ratio, and whether the images agree bit for bit. */
#define _POSIX_C_SOURCE 200809L
#include "indirect.h"
#include "indirect.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

eng_result kd_gather_old(const eng_photon_map *map, int w, int h, const float *position, const float *normal,
                         const float *albedo, const float *material, const float eye[3], const eng_settings *s,
                         float *out, eng_error *err);

/* ind_scatter_splat.c's, which the gathers call (that file is not linked: it needs GL). */
float splat_radius(float kernel_radius, float rho)
{
    float s = rho > 0.0f ? powf(1000.0f * rho, -0.25f) : 2.0f;
    if (s < 0.25f)
        s = 0.25f;
    if (s > 2.0f)
        s = 2.0f;
    return kernel_radius * s;
}

/* What the method wrappers of ind_kdgather.c reference besides the gather; never called here. */
eng_result eng_fail(eng_error *err, eng_result code, const char *fmt, ...)
{
    (void)err;
    fprintf(stderr, "kdgather_speed: %s\n", fmt);
    return code;
}
eng_result glu_cpu_target_create(glu_cpu_target *t, int width, int height, int irradiance, eng_error *err)
{
    (void)t, (void)width, (void)height, (void)irradiance, (void)err;
    abort();
}
void glu_cpu_target_destroy(glu_cpu_target *t) { (void)t; }
void glu_cpu_target_upload(glu_cpu_target *t, int index, const float *rgba) { (void)t, (void)index, (void)rgba; }
void glu_gbuffer_read(const glu_target *gb, glu_gbuffer *out) { (void)gb, (void)out; }
void glu_gbuffer_free(glu_gbuffer *g) { (void)g; }
/* The method wrapper's state (indirect.h, since the final gather shares it): never called here. */
eng_result ind_cpu_state_init(ind_cpu_state *c, const char *method, int width, int height, int irradiance,
                              eng_error *err)
{
    (void)c, (void)method, (void)width, (void)height, (void)irradiance, (void)err;
    abort();
}
void ind_cpu_state_free(ind_cpu_state *c) { (void)c; }
void ind_cpu_state_output(ind_cpu_state *c, ind_output *o) { (void)c, (void)o; }

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(void)
{
    enum { W = 256, H = 256, N = 32768, ROUNDS = 9 };
    static float pos[W * H * 4], nrm[W * H * 3], alb[W * H * 3], mat[W * H * 4];
    for (int i = 0; i < W * H; i++) {
        pos[4 * i] = (float)(i % W) / W * 2.0f - 1.0f;
        pos[4 * i + 1] = (float)(i / W) / H * 2.0f - 1.0f;
        pos[4 * i + 2] = 0.0f;
        pos[4 * i + 3] = 1.0f;
        nrm[3 * i + 2] = 1.0f;
        alb[3 * i] = alb[3 * i + 1] = alb[3 * i + 2] = 0.7f;
        mat[4 * i] = 1.0f;
    }
    eng_photon *ph = calloc(N, sizeof *ph);
    unsigned seed = 1u;
    for (int i = 0; i < N; i++) {
        for (int c = 0; c < 2; c++) {
            seed = seed * 1664525u + 1013904223u;
            ph[i].position[c] = (float)(seed >> 8) / 16777216.0f * 2.2f - 1.1f;
        }
        seed = seed * 1664525u + 1013904223u;
        ph[i].direction[0] = 0.6f;
        ph[i].direction[2] = 0.8f;
        ph[i].normal[2] = 1.0f;
        ph[i].power[0] = ph[i].power[1] = ph[i].power[2] = 1e-4f;
        ph[i].path_density = (float)(seed >> 8) / 16777216.0f * 0.01f;
    }
    eng_photon_map map = {0};
    map.photons = ph;
    map.count = N;
    eng_settings s;
    memset(&s, 0, sizeof s);
    s.kernel_radius = 0.1f;
    s.normal_compression = 0.1f;
    s.threads = 2;
    const float eye[3] = {0.0f, 0.0f, 3.0f};
    float *a = malloc(sizeof(float) * W * H * 4), *b = malloc(sizeof(float) * W * H * 4);
    double tn[ROUNDS], to[ROUNDS];
    eng_error err;
    for (int r = 0; r < ROUNDS; r++) {
        /* Alternating which goes first. */
        for (int k = 0; k < 2; k++) {
            double t0 = now();
            if ((k ^ r) & 1)
                kd_gather(&map, W, H, pos, nrm, alb, mat, eye, &s, a, &err);
            else
                kd_gather_old(&map, W, H, pos, nrm, alb, mat, eye, &s, b, &err);
            ((k ^ r) & 1 ? tn : to)[r] = now() - t0;
        }
    }
    qsort(tn, ROUNDS, sizeof *tn, cmp_d);
    qsort(to, ROUNDS, sizeof *to, cmp_d);
    int same = !memcmp(a, b, sizeof(float) * W * H * 4);
    printf("kd-gather 256x256, %d photons, 2 threads: old %.1f ms, new %.1f ms (medians of %d), new/old %.3f, "
           "images %s\n",
           N, 1e3 * to[ROUNDS / 2], 1e3 * tn[ROUNDS / 2], ROUNDS, tn[ROUNDS / 2] / to[ROUNDS / 2],
           same ? "bit-identical" : "DIFFER");
    free(a);
    free(b);
    free(ph);
    return same ? 0 : 1;
}
