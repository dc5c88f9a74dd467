/* glctx_registry.c — the GL backends by name (glctx_backend.h): --gl's value finds its backend
 * here. */
#include "glctx_backend.h"

#include <string.h>

static const glctx_backend *const backends[] = {&glctx_osmesa_backend, &glctx_egl_backend};

const glctx_backend *glctx_backend_find(const char *name)
{
    for (size_t i = 0; name && i < sizeof backends / sizeof backends[0]; i++)
        if (strcmp(backends[i]->name, name) == 0)
            return backends[i];
    return NULL;
}
