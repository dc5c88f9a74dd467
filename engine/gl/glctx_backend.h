/* glctx_backend.h — how glctx.c makes a GL 4.5 core context: one backend per file
 * (glctx_osmesa.c, glctx_egl.c), chosen by name (ispm record --gl). A backend only creates
 * the context, makes it current and hands out GetProcAddress; glctx.c loads every GL function
 * through it (gl_loader.h), so the passes call the same pointers whatever made the context.
 * This header includes no GL header, so a backend may include its API's own (GL/osmesa.h). */
#ifndef ISPM_GLCTX_BACKEND_H
#define ISPM_GLCTX_BACKEND_H

#include "eng_core.h"

#include <stddef.h>

typedef void (*glctx_proc)(void);

typedef struct glctx_backend {
    const char *name; /* as given to --gl */
    /* Creates a GL 4.5 core context with no window and makes it current on this thread.
     * use_device: the EGL device index `device` was asked for (--gl-device). where: filled
     * with what the context runs on, for the manifest (e.g. "surfaceless", "device 0"). */
    eng_result (*open)(int use_device, int device, void **impl, char *where, size_t where_size, eng_error *err);
    glctx_proc (*get_proc)(void *impl, const char *name);
    void (*close)(void *impl);
} glctx_backend;

extern const glctx_backend glctx_osmesa_backend; /* glctx_osmesa.c */
extern const glctx_backend glctx_egl_backend;    /* glctx_egl.c */

/* The backend named `name` (glctx_registry.c), or NULL. */
const glctx_backend *glctx_backend_find(const char *name);

#endif
