/* ind_common.c — the table of indirect-light methods (indirect.h) and what the CPU methods
 * share: the eye G-buffer read back, and an output target they upload into. */
#include "indirect.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const ind_method *ind_method_of(eng_indirect m)
{
    switch (m) {
    case ENG_INDIRECT_DEFAULT:
    case ENG_INDIRECT_ISPM: return &ind_scatter_method;
    case ENG_INDIRECT_QUADS: return &ind_quads_method;
    case ENG_INDIRECT_TILEGATHER: return &ind_tilegather_method;
    case ENG_INDIRECT_KDGATHER: return &ind_kdgather_method;
    case ENG_INDIRECT_NONE: break;
    }
    return NULL;
}

void ind_photon_radii(const eng_photon_map *map, const eng_settings *s, float *radius)
{
    for (size_t i = 0; i < map->count; i++)
        radius[i] = splat_radius(s->kernel_radius, map->photons[i].path_density);
}

eng_result ind_cpu_target_create(ind_cpu_target *t, int width, int height, int irradiance, eng_error *err)
{
    memset(t, 0, sizeof *t);
    eng_result r = glu_target_create(&t->target, irradiance ? 2 : 1, width, height, 0, err);
    if (r != ENG_OK)
        return r;
    t->upload = eng_xmalloc((size_t)width * (size_t)height * 4 * sizeof(float));
    return ENG_OK;
}

void ind_cpu_target_destroy(ind_cpu_target *t)
{
    glu_target_destroy(&t->target);
    free(t->upload);
    memset(t, 0, sizeof *t);
}

void ind_cpu_target_upload(ind_cpu_target *t, int index, const float *rgba)
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

void ind_gbuffer_read(const glu_target *gb, ind_gbuffer *g)
{
    const int p4[] = {0, 1, 2, 3}, p3[] = {0, 1, 2};
    if (g->width != gb->width || g->height != gb->height || !g->position) {
        ind_gbuffer_free(g);
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

void ind_gbuffer_free(ind_gbuffer *g)
{
    free(g->position);
    free(g->normal);
    free(g->albedo);
    free(g->material);
    memset(g, 0, sizeof *g);
}
