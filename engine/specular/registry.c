/* registry.c — the eye-specular methods by name (specular.h): the `specular` setting's value
 * finds its method here ("off" has none). */
#include "specular.h"

#include <string.h>

static const spec_method *const methods[] = {&spec_traced_method, &spec_envmap_method};

int spec_method_count(void)
{
    return (int)(sizeof methods / sizeof methods[0]);
}

const spec_method *spec_method_at(int i)
{
    return i >= 0 && i < spec_method_count() ? methods[i] : NULL;
}

const spec_method *spec_method_find(const char *name)
{
    for (int i = 0; name && i < spec_method_count(); i++)
        if (strcmp(methods[i]->name, name) == 0)
            return methods[i];
    return NULL;
}
