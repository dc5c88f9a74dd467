/* shadow_registry.c — the shadow methods by name (shadow.h). A light's method follows from
 * its size: "pcss" for a light with a radius, "pcf" for a punctual one. */
#include "shadow.h"

#include <string.h>

const shadow_method *const shadow_methods[SHADOW_METHOD_COUNT] = {&shadow_pcf_method, &shadow_pcss_method};

int shadow_method_find(const char *name)
{
    for (int i = 0; name && i < SHADOW_METHOD_COUNT; i++)
        if (strcmp(shadow_methods[i]->name, name) == 0)
            return i;
    return -1;
}

int shadow_method_index(const eng_light_pose *l)
{
    return shadow_method_find(l->radius > 0.0f ? "pcss" : "pcf");
}
