/* shadow_pcf.c — hard shadows (shadow.h "pcf"): percentage-closer filtering of the shadow
 * map in shaders/shadow_pcf.glsl; it needs no map of its own. */
#include "shadow.h"

#include <stddef.h>

static eng_result pcf_create(const eng_settings *s, uint32_t light_count, void **state, eng_error *err)
{
    (void)s;
    (void)light_count;
    (void)err;
    *state = NULL;
    return ENG_OK;
}

static const glu_target *pcf_run(void *state, const eng_light_pose *l, const shadow_map *sm, uint32_t light,
                                 int *failed)
{
    (void)state;
    (void)l;
    (void)sm;
    (void)light;
    *failed = 0;
    return NULL;
}

static void pcf_destroy(void *state)
{
    (void)state;
}

const shadow_method shadow_pcf_method = {
    .name = "pcf",
    .create = pcf_create,
    .run = pcf_run,
    .destroy = pcf_destroy,
};
