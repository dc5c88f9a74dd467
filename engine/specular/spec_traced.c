/* spec_traced.c — the "traced" specular method (specular.h): from every eye G-buffer pixel
 * whose surface has a delta lobe, the eye path is traced on with Embree through mirrors and
 * glass (003_d0bf8e920b03f4e1.txt §3 step 5, option 1: "trace the specular eye paths on the
 * CPU"); eye_tracer.c does the tracing, this file walks the pixels. */
#include "specular.h"

#include <stdlib.h>
#include <string.h>

static void traced_destroy(void *state)
{
    if (!state)
        return;
    spec_buffers_destroy(state);
    free(state);
}

static eng_result traced_create(int width, int height, void **state, eng_error *err)
{
    spec_buffers *b = calloc(1, sizeof *b);
    if (!b)
        return eng_fail(err, ENG_ERR_NOMEM, "specular: out of memory");
    eng_result r = spec_buffers_create(b, width, height, err);
    if (r != ENG_OK) {
        free(b);
        return r;
    }
    *state = b;
    return ENG_OK;
}

/* Read-back, tracing and upload all count as the method's time. */
static eng_result traced_run(void *state, const spec_input *in, spec_output *out, eng_error *err)
{
    spec_buffers *st = state;
    glu_gbuffer_read(in->gbuf, &st->gb);
    eye_tracer *t = eye_tracer_create(in->fs, in->rt, in->map, in->radius, in->s, err);
    if (!t)
        return ENG_ERR_NOMEM;
    const int w = st->width, h = st->height;
    const float *eye = in->fs->camera.eye;
    int threads = in->s->threads > 0 ? in->s->threads : 2;
#pragma omp parallel num_threads(threads)
    {
        eye_scratch sc = {NULL, 0};
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < h; y++) {
            for (int x = 0; x < w; x++) {
                size_t i = (size_t)y * (size_t)w + (size_t)x;
                scn_material m;
                spec_buffers_material(st, i, &m);
                eye_tracer_pixel(t, st->gb.position + 4 * i, st->gb.normal + 3 * i, &m, eye, &sc,
                                  st->radiance + 3 * i, &st->depth[i], st->throughput + 3 * i);
            }
        }
        free(sc.list);
    }
    eye_tracer_destroy(t);
    spec_buffers_finish(st, out);
    return ENG_OK;
}

const spec_method spec_traced_method = {
    .name = "traced",
    .create = traced_create,
    .run = traced_run,
    .destroy = traced_destroy,
};
