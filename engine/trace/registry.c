/* registry.c — the photon-trace methods by name (trace_method.h): the `photon_trace` setting's
 * value finds its method here. */
#include "trace_method.h"

#include <string.h>

static const pt_method *const methods[] = {&pt_embree_method, &pt_multiimage_method};

int pt_method_count(void)
{
    return (int)(sizeof methods / sizeof methods[0]);
}

const pt_method *pt_method_at(int i)
{
    return i >= 0 && i < pt_method_count() ? methods[i] : NULL;
}

const pt_method *pt_method_find(const char *name)
{
    for (int i = 0; name && i < pt_method_count(); i++)
        if (strcmp(methods[i]->name, name) == 0)
            return methods[i];
    return NULL;
}
