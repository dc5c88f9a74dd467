/* spec_common.c — what both specular methods keep between frames: the eye G-buffer read back,
 * the output images and the texture they are uploaded to. */
#include "specular.h"

#include <stdlib.h>
#include <string.h>

eng_result spec_buffers_create(spec_buffers *b, int width, int height, eng_error *err)
{
    memset(b, 0, sizeof *b);
    b->width = width;
    b->height = height;
    size_t n = (size_t)width * (size_t)height;
    b->rgba = eng_xmalloc(n * 4 * sizeof(float));
    b->radiance = eng_xmalloc(n * 3 * sizeof(float));
    b->depth = eng_xmalloc(n * sizeof(float));
    b->throughput = eng_xmalloc(n * 3 * sizeof(float));
    eng_result r = glu_cpu_target_create(&b->target, width, height, 0, err);
    if (r != ENG_OK)
        spec_buffers_destroy(b);
    else
        b->target_ok = 1;
    return r;
}

void spec_buffers_destroy(spec_buffers *b)
{
    if (b->target_ok)
        glu_cpu_target_destroy(&b->target);
    glu_gbuffer_free(&b->gb);
    free(b->rgba);
    free(b->radiance);
    free(b->depth);
    free(b->throughput);
    memset(b, 0, sizeof *b);
}

void spec_buffers_material(const spec_buffers *b, size_t i, scn_material *m)
{
    const float *mat = b->gb.material + 4 * i;
    memset(m, 0, sizeof *m);
    memcpy(m->base_color, b->gb.albedo + 3 * i, 3 * sizeof(float));
    m->roughness = mat[0];
    m->metallic = mat[1];
    m->transmission = mat[2];
    m->ior = mat[3];
    if (b->gb.position[4 * i + 3] == 0.0f)
        m->metallic = m->transmission = 0.0f; /* background: nothing to continue */
}

void spec_buffers_finish(spec_buffers *b, spec_output *out)
{
    size_t n = (size_t)b->width * (size_t)b->height;
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++)
            b->rgba[4 * i + (size_t)c] = b->radiance[3 * i + (size_t)c];
        b->rgba[4 * i + 3] = b->depth[i];
    }
    glu_cpu_target_upload(&b->target, 0, b->rgba);
    out->target = &b->target.target;
    out->radiance = b->radiance;
    out->depth = b->depth;
    out->throughput = b->throughput;
}

/* ---------------------------------------------------------------- the method */
