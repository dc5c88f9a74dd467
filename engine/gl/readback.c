/* readback.c — CPU images and GL textures both ways: targets the CPU methods fill and upload
 * (rows flipped to GL order), the eye G-buffer read back in the announced layout (top row
 * first), and per-pixel scale textures. */
#include "gl.h"

#include <stdlib.h>
#include <string.h>

eng_result glu_cpu_target_create(glu_cpu_target *t, int width, int height, int irradiance, eng_error *err)
{
    memset(t, 0, sizeof *t);
    eng_result r = glu_target_create(&t->target, irradiance ? 2 : 1, width, height, 0, err);
    if (r != ENG_OK)
        return r;
    t->upload = eng_xmalloc((size_t)width * (size_t)height * 4 * sizeof(float));
    return ENG_OK;
}

void glu_cpu_target_destroy(glu_cpu_target *t)
{
    glu_target_destroy(&t->target);
    free(t->upload);
    memset(t, 0, sizeof *t);
}

void glu_cpu_target_upload(glu_cpu_target *t, int index, const float *rgba)
{
    const int w = t->target.width, h = t->target.height;
    /* Announced rows are top first, GL's row 0 is the bottom: upload flipped. */
    for (int y = 0; y < h; y++)
        memcpy(t->upload + 4 * (size_t)(h - 1 - y) * w, rgba + 4 * (size_t)y * w, 4 * (size_t)w * sizeof(float));
    glBindTexture(GL_TEXTURE_2D, t->target.color[index]);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, t->upload);
    glBindTexture(GL_TEXTURE_2D, 0);
}

void glu_gbuffer_read(const glu_target *gb, glu_gbuffer *g)
{
    const int p4[] = {0, 1, 2, 3}, p3[] = {0, 1, 2};
    if (g->width != gb->width || g->height != gb->height || !g->position) {
        glu_gbuffer_free(g);
        size_t n = (size_t)gb->width * (size_t)gb->height;
        g->width = gb->width;
        g->height = gb->height;
        g->position = eng_xmalloc(n * 4 * sizeof(float));
        g->normal = eng_xmalloc(n * 3 * sizeof(float));
        g->albedo = eng_xmalloc(n * 3 * sizeof(float));
        g->material = eng_xmalloc(n * 4 * sizeof(float));
    }
    glu_read(gb, 0, 0, 4, p4, g->position);
    glu_read(gb, 1, 0, 3, p3, g->normal);
    glu_read(gb, 2, 0, 3, p3, g->albedo);
    glu_read(gb, 3, 0, 4, p4, g->material);
}

void glu_gbuffer_free(glu_gbuffer *g)
{
    free(g->position);
    free(g->normal);
    free(g->albedo);
    free(g->material);
    memset(g, 0, sizeof *g);
}

void pixel_scale_upload(GLuint *tex, float **rows, int w, int h, const float *scale)
{
    if (!*tex) {
        *rows = eng_xmalloc((size_t)w * (size_t)h * sizeof(float));
        glGenTextures(1, tex);
        glBindTexture(GL_TEXTURE_2D, *tex);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, w, h, 0, GL_RED, GL_FLOAT, NULL);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }
    for (int y = 0; y < h; y++) /* top row first → GL's bottom row first */
        memcpy(*rows + (size_t)(h - 1 - y) * (size_t)w, scale + (size_t)y * (size_t)w, (size_t)w * sizeof(float));
    glBindTexture(GL_TEXTURE_2D, *tex);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, GL_RED, GL_FLOAT, *rows);
    glBindTexture(GL_TEXTURE_2D, 0);
}
