/* ind_scatter.c — `"indirect": "ispm"`: photon volumes scattered by the rasteriser (ISPM 003_…
 * §5; ind_scatter_splat.c draws them, shaders/splat*.frag.glsl evaluate Eq. 1). Buffers "splat.*". */
#include "indirect.h"

static eng_result scatter_create(int width, int height, int irradiance, void **state, eng_error *err)
{
    pass_splat *p = NULL;
    eng_result r = pass_splat_create(width, height, irradiance, &p, err);
    *state = p;
    return r;
}

static eng_result scatter_run(void *state, const ind_input *in, ind_output *out, eng_error *err)
{
    (void)err;
    pass_splat_set_pixel_scale(state, in->pixel_scale);
    out->target = pass_splat_run(state, in->fs, in->gbuf, in->map, in->radius, in->aniso, in->s);
    out->extra_count = 0;
    return ENG_OK;
}

static void scatter_destroy(void *state) { pass_splat_destroy(state); }

static void scatter_reserve(void *state, size_t photons, int threads)
{
    pass_splat_reserve(state, photons, threads > 1);
}

const ind_method ind_scatter_method = {
    .name = "ispm",
    .prefix = "splat",
    .pass = "splat",
    .create = scatter_create,
    .run = scatter_run,
    .destroy = scatter_destroy,
    .per_pixel_radius = 1,
    .reserve = scatter_reserve,
};
