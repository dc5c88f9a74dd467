/* ind_quads.c — `"indirect": "quads"`: photon quads (001_… §3.3). Not built yet. */
#include "indirect.h"

static eng_result quads_create(int width, int height, int irradiance, void **state, eng_error *err)
{
    (void)width;
    (void)height;
    (void)irradiance;
    *state = NULL;
    return eng_fail(err, ENG_ERR_UNSUPPORTED, "indirect \"quads\" is not built yet");
}

static eng_result quads_run(void *state, const ind_input *in, ind_output *out, eng_error *err)
{
    (void)state;
    (void)in;
    (void)out;
    return eng_fail(err, ENG_ERR_UNSUPPORTED, "indirect \"quads\" is not built yet");
}

static void quads_destroy(void *state) { (void)state; }

const ind_method ind_quads_method = {"quads", "quads", "quads", quads_create, quads_run, quads_destroy};
