/* glctx_osmesa.c — the default GL backend: an offscreen GL 4.5 core context from OSMesa
 * (Mesa's llvmpipe), so recording needs no display and no GPU. The reference for goldens. */
#include "glctx_backend.h"

#include <GL/osmesa.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct osm_ctx {
    OSMesaContext ctx;
    unsigned char dummy[16 * 16 * 4]; /* the context's own framebuffer; passes use FBOs */
} osm_ctx;

static eng_result osm_open(int use_device, int device, void **impl, char *where, size_t where_size,
                           eng_error *err)
{
    (void)use_device;
    (void)device;
    *impl = NULL;
    osm_ctx *c = calloc(1, sizeof *c);
    if (!c)
        return eng_fail(err, ENG_ERR_NOMEM, "GL: out of memory");
    const int attribs[] = {
        OSMESA_FORMAT, OSMESA_RGBA,
        OSMESA_DEPTH_BITS, 24,
        OSMESA_PROFILE, OSMESA_CORE_PROFILE,
        OSMESA_CONTEXT_MAJOR_VERSION, 4,
        OSMESA_CONTEXT_MINOR_VERSION, 5,
        0,
    };
    c->ctx = OSMesaCreateContextAttribs(attribs, NULL);
    if (!c->ctx) {
        free(c);
        return eng_fail(err, ENG_ERR_GL, "OSMesa: cannot create a GL 4.5 core context (is libosmesa6 from Mesa >= 20 installed?)");
    }
    if (!OSMesaMakeCurrent(c->ctx, c->dummy, GL_UNSIGNED_BYTE, 16, 16)) {
        OSMesaDestroyContext(c->ctx);
        free(c);
        return eng_fail(err, ENG_ERR_GL, "OSMesa: cannot make the context current");
    }
    snprintf(where, where_size, "offscreen");
    *impl = c;
    return ENG_OK;
}

static glctx_proc osm_get_proc(void *impl, const char *name)
{
    (void)impl;
    return (glctx_proc)OSMesaGetProcAddress(name);
}

static void osm_close(void *impl)
{
    osm_ctx *c = impl;
    OSMesaDestroyContext(c->ctx);
    free(c);
}

const glctx_backend glctx_osmesa_backend = {"osmesa", osm_open, osm_get_proc, osm_close};
