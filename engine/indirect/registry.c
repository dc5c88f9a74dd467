/* registry.c — the indirect-light methods by name (indirect.h): the `indirect` setting's value
 * finds its method here, and the bench and the tests walk the same list. */
#include "indirect.h"

#include <string.h>

static const ind_method *const methods[] = {
    &ind_scatter_method,  &ind_quads_method,       &ind_tilegather_method,
    &ind_tilegather_gl_method, &ind_kdgather_method, &ind_finalgather_method,
};

int ind_method_count(void)
{
    return (int)(sizeof methods / sizeof methods[0]);
}

const ind_method *ind_method_at(int i)
{
    return i >= 0 && i < ind_method_count() ? methods[i] : NULL;
}

const ind_method *ind_method_find(const char *name)
{
    for (int i = 0; name && i < ind_method_count(); i++)
        if (strcmp(methods[i]->name, name) == 0)
            return methods[i];
    return NULL;
}
