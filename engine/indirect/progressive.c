/* progressive.c — running mean of the indirect estimate with PPM's shrinking radius
 * (progressive.h; Hachisuka, Ogaki, Jensen 2008, "Progressive Photon Mapping", §4). */
#include "progressive.h"
#include "indirect.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct prog_state {
    int width, height, attachments;
    int frames;        /* since the last global restart; 0 = none yet */
    double r2;         /* (r_i / r_1)² */
    int restart_all;   /* prog_begin decided a global restart for this frame */
    int have_view;
    eng_view camera;
    uint32_t light_count;
    eng_light_pose lights[8];
    double *sum[2];    /* per pixel RGB sums */
    uint32_t *count;
    glu_gbuffer prev;  /* the previous frame's G-buffer, for the bit-wise test */
    int have_prev;
    uint8_t *restart;  /* per pixel: restarts this frame (mark_restarts) */
    int marked;        /* restart[] is this frame's */
    /* Per-pixel radii (prog_set_per_pixel). */
    int per_pixel;
    double *r2px, *npx; /* R² and N per pixel */
    float *scale, *photons;
};

prog_state *prog_create(void)
{
    prog_state *p = eng_xcalloc(1, sizeof *p);
    return p;
}

static void free_buffers(prog_state *p)
{
    free(p->sum[0]);
    free(p->sum[1]);
    free(p->count);
    free(p->restart);
    free(p->r2px);
    free(p->npx);
    free(p->scale);
    free(p->photons);
    p->sum[0] = p->sum[1] = NULL;
    p->count = NULL;
    p->restart = NULL;
    p->r2px = p->npx = NULL;
    p->scale = p->photons = NULL;
    glu_gbuffer_free(&p->prev);
    p->have_prev = 0;
    p->width = p->height = p->attachments = 0;
}

void prog_destroy(prog_state *p)
{
    if (!p)
        return;
    free_buffers(p);
    free(p);
}

void prog_reset(prog_state *p)
{
    p->frames = 0;
    p->r2 = 1.0;
    p->have_view = 0;
    p->have_prev = 0;
    p->marked = 0;
}

void prog_set_per_pixel(prog_state *p, int on) { p->per_pixel = on ? 1 : 0; }

void prog_ppm_update(double *r2, double *n, double m)
{
    /* Hachisuka et al. 2008 §4: N_{i+1} = N_i + αM_i, R_{i+1}² = R_i² (N_i + αM_i)/(N_i + M_i). */
    const double found = *n + m;
    if (!(found > 0.0))
        return;
    const double kept = *n + PROG_ALPHA * m;
    *r2 *= kept / found;
    *n = kept;
}

double prog_radius_scale(int i)
{
    double r2 = 1.0;
    for (int k = 1; k < i; k++)
        r2 *= ((double)k + PROG_ALPHA) / ((double)k + 1.0);
    return sqrt(r2);
}

int prog_frames(const prog_state *p) { return p->frames; }

static int same_light(const eng_light_pose *a, const eng_light_pose *b)
{
    return a->type == b->type && !memcmp(a->position, b->position, sizeof a->position) &&
           !memcmp(a->direction, b->direction, sizeof a->direction) &&
           !memcmp(a->radiance_scale, b->radiance_scale, sizeof a->radiance_scale) &&
           !memcmp(&a->range, &b->range, sizeof a->range) && !memcmp(&a->inner_cone, &b->inner_cone, sizeof(float)) &&
           !memcmp(&a->outer_cone, &b->outer_cone, sizeof(float));
}

float prog_begin(prog_state *p, const eng_frame_scene *fs)
{
    int moved = !p->have_view || p->frames == 0 || memcmp(&p->camera, &fs->camera, sizeof p->camera) != 0 ||
                p->light_count != fs->light_count;
    uint32_t nl = fs->light_count < 8 ? fs->light_count : 8;
    for (uint32_t l = 0; l < nl && !moved; l++)
        moved = !same_light(&p->lights[l], &fs->lights[l]);
    p->camera = fs->camera;
    p->light_count = fs->light_count;
    for (uint32_t l = 0; l < nl; l++)
        p->lights[l] = fs->lights[l];
    p->have_view = 1;
    if (moved) {
        p->frames = 1;
        p->r2 = 1.0;
    } else {
        /* PPM Eq. 8 with N_i/M_i replaced by one frame: r_{i+1}² = r_i² (i + α)/(i + 1). */
        p->r2 *= ((double)p->frames + PROG_ALPHA) / ((double)p->frames + 1.0);
        p->frames++;
    }
    p->restart_all = moved;
    p->marked = 0;
    return p->per_pixel ? 1.0f : (float)sqrt(p->r2);
}

static int same_pixel(const glu_gbuffer *a, const glu_gbuffer *b, size_t i)
{
    return !memcmp(a->position + 4 * i, b->position + 4 * i, 4 * sizeof(float)) &&
           !memcmp(a->normal + 3 * i, b->normal + 3 * i, 3 * sizeof(float)) &&
           !memcmp(a->albedo + 3 * i, b->albedo + 3 * i, 3 * sizeof(float)) &&
           !memcmp(a->material + 4 * i, b->material + 4 * i, 4 * sizeof(float));
}

static void copy_gbuffer(glu_gbuffer *dst, const glu_gbuffer *src)
{
    size_t n = (size_t)src->width * (size_t)src->height;
    if (dst->width != src->width || dst->height != src->height || !dst->position) {
        glu_gbuffer_free(dst);
        dst->width = src->width;
        dst->height = src->height;
        dst->position = eng_xcalloc(n * 4, sizeof(float));
        dst->normal = eng_xcalloc(n * 3, sizeof(float));
        dst->albedo = eng_xcalloc(n * 3, sizeof(float));
        dst->material = eng_xcalloc(n * 4, sizeof(float));
    }
    memcpy(dst->position, src->position, n * 4 * sizeof(float));
    memcpy(dst->normal, src->normal, n * 3 * sizeof(float));
    memcpy(dst->albedo, src->albedo, n * 3 * sizeof(float));
    memcpy(dst->material, src->material, n * 4 * sizeof(float));
}

/* The per-pixel buffers for a w×h image (a new size forgets everything). */
static void ensure_size(prog_state *p, int w, int h)
{
    if (p->width == w && p->height == h && p->count)
        return;
    free_buffers(p);
    const size_t n = (size_t)w * (size_t)h;
    p->width = w;
    p->height = h;
    p->count = eng_xcalloc(n, sizeof(uint32_t));
    p->restart = eng_xcalloc(n, 1);
    p->r2px = eng_xcalloc(n, sizeof(double));
    p->npx = eng_xcalloc(n, sizeof(double));
    p->scale = eng_xcalloc(n, sizeof(float));
    p->photons = eng_xcalloc(n, sizeof(float));
}

/* This frame's restarts against gb, once per frame: every pixel after a global restart, else
 * the pixels whose G-buffer changed; per-pixel radii restart there (R = 1, N = 0). */
static void mark_restarts(prog_state *p, const glu_gbuffer *gb)
{
    if (p->marked)
        return;
    const size_t n = (size_t)gb->width * (size_t)gb->height;
    const int all = p->restart_all || !p->have_prev;
    for (size_t i = 0; i < n; i++) {
        p->restart[i] = (uint8_t)(all || !same_pixel(gb, &p->prev, i));
        if (p->restart[i]) {
            p->r2px[i] = 1.0;
            p->npx[i] = 0.0;
        }
    }
    p->marked = 1;
}

const float *prog_pixel_scales(prog_state *p, const glu_gbuffer *gb)
{
    ensure_size(p, gb->width, gb->height);
    mark_restarts(p, gb);
    const size_t n = (size_t)gb->width * (size_t)gb->height;
    for (size_t i = 0; i < n; i++)
        p->scale[i] = (float)sqrt(p->r2px[i]);
    return p->scale;
}

const float *prog_photons(const prog_state *p) { return p->photons; }

void prog_accumulate(prog_state *p, const glu_gbuffer *gb, int attachments, const float *const *in, float **mean,
                     float *count, float *radius)
{
    const int w = gb->width, h = gb->height;
    const size_t n = (size_t)w * (size_t)h;
    ensure_size(p, w, h);
    if (p->attachments != attachments) {
        for (int a = 0; a < 2; a++) {
            free(p->sum[a]);
            p->sum[a] = a < attachments ? eng_xcalloc(n * 3, sizeof(double)) : NULL;
        }
        p->attachments = attachments;
        p->have_prev = 0; /* a new layout restarts everything */
        p->marked = 0;
    }
    mark_restarts(p, gb);
    const float scale = (float)sqrt(p->r2);
    for (size_t i = 0; i < n; i++) {
        int surface = gb->position[4 * i + 3] > 0.0f;
        if (p->restart[i]) {
            p->count[i] = 0;
            for (int a = 0; a < attachments; a++)
                p->sum[a][3 * i] = p->sum[a][3 * i + 1] = p->sum[a][3 * i + 2] = 0.0;
        }
        if (surface)
            p->count[i]++;
        const uint32_t k = p->count[i];
        for (int a = 0; a < attachments; a++) {
            const float *x = in[a] + 4 * i;
            float *m = mean[a] + 4 * i;
            if (!surface) {
                memcpy(m, x, 4 * sizeof(float));
                continue;
            }
            for (int c = 0; c < 3; c++) {
                p->sum[a][3 * i + c] += (double)x[c];
                m[c] = (float)(p->sum[a][3 * i + c] / (double)k);
            }
            m[3] = x[3];
        }
        count[i] = (float)k;
        if (p->per_pixel) {
            /* The scale this frame's sample used, then PPM's update with the M photons the
             * method found (its A channel). */
            radius[i] = surface ? (float)sqrt(p->r2px[i]) : 0.0f;
            if (surface)
                prog_ppm_update(&p->r2px[i], &p->npx[i], (double)in[0][4 * i + 3]);
            p->photons[i] = surface ? (float)p->npx[i] : 0.0f;
        } else {
            radius[i] = surface ? scale : 0.0f;
        }
    }
    copy_gbuffer(&p->prev, gb);
    p->have_prev = 1;
    p->restart_all = 0;
    p->marked = 0;
}
