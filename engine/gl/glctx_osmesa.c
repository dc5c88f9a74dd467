/* glctx_osmesa.c — the default GL backend: an offscreen GL 4.5 core context from OSMesa
 * (Mesa's llvmpipe), so recording needs no display and no GPU. The reference for goldens. */
#include "glctx_backend.h"

#include <GL/osmesa.h>
#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct osm_ctx {
    OSMesaContext ctx;
    unsigned char dummy[16 * 16 * 4]; /* the context's own framebuffer; passes use FBOs */
} osm_ctx;

/* libOSMesa is opened when the first context is (like libEGL in glctx_egl.c), not linked: it
 * brings libLLVM, whose relocation costs every process ~67 ms at start (an empty program linked
 * with -lOSMesa: 71 ms against 4 ms, this 2-core VM), and most commands (replay, bless, inspect,
 * the viewer's reader) never render. Kept open for the process's life. $ISPM_OSMESA_LIB names
 * another build of it (a path or a soname). */
#define OSM_LIB "libOSMesa.so.8"
static struct {
    OSMesaContext (*CreateContextAttribs)(const int *attribs, OSMesaContext share);
    GLboolean (*MakeCurrent)(OSMesaContext ctx, void *buffer, GLenum type, GLsizei width, GLsizei height);
    void (*DestroyContext)(OSMesaContext ctx);
    OSMESAproc (*GetProcAddress)(const char *name);
    char error[320]; /* why loading failed; empty when it did not */
} osm;
static pthread_once_t osm_once = PTHREAD_ONCE_INIT;

static void osm_load_once(void)
{
    const char *env = getenv("ISPM_OSMESA_LIB");
    const char *name = env && *env ? env : OSM_LIB;
    void *lib = dlopen(name, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        snprintf(osm.error, sizeof osm.error, "cannot load %s (install libosmesa6): %s", name, dlerror());
        return;
    }
    /* POSIX: a dlsym result converts to a function pointer. */
#define SYM(field, sym)                                                                     \
    if (!(*(void **)&osm.field = dlsym(lib, sym))) {                                        \
        snprintf(osm.error, sizeof osm.error, "%s has no %s", name, sym);                    \
        return;                                                                             \
    }
    SYM(CreateContextAttribs, "OSMesaCreateContextAttribs")
    SYM(MakeCurrent, "OSMesaMakeCurrent")
    SYM(DestroyContext, "OSMesaDestroyContext")
    SYM(GetProcAddress, "OSMesaGetProcAddress")
#undef SYM
}

static void osm_load(void)
{
    pthread_once(&osm_once, osm_load_once);
}

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
    osm_load();
    if (osm.error[0]) {
        free(c);
        return eng_fail(err, ENG_ERR_GL, "OSMesa: %s", osm.error);
    }
    c->ctx = osm.CreateContextAttribs(attribs, NULL);
    if (!c->ctx) {
        free(c);
        return eng_fail(err, ENG_ERR_GL, "OSMesa: cannot create a GL 4.5 core context (is libosmesa6 from Mesa >= 20 installed?)");
    }
    if (!osm.MakeCurrent(c->ctx, c->dummy, GL_UNSIGNED_BYTE, 16, 16)) {
        osm.DestroyContext(c->ctx);
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
    return (glctx_proc)osm.GetProcAddress(name);
}

static void osm_close(void *impl)
{
    osm_ctx *c = impl;
    osm.DestroyContext(c->ctx);
    free(c);
}

const glctx_backend glctx_osmesa_backend = {
    .name = "osmesa",
    .open = osm_open,
    .get_proc = osm_get_proc,
    .close = osm_close,
};
