/* glctx.c — the engine's GL 4.5 core context, made offscreen by one of the backends of
 * glctx_backend.h (OSMesa by default, EGL with ispm record --gl egl), and every GL function
 * loaded through that backend's GetProcAddress (gl_loader.h). It also pins everything in the
 * rasterizer and the ray tracer that follows the host's SIMD width, because goldens recorded
 * on one CPU are replayed on others: llvmpipe's vector width and CPU feature set (AVX/FMA
 * change rounding) and Embree's ISA. The same pins hold for Mesa's EGL, whose llvmpipe then
 * renders bit-identically to OSMesa's. The pinned values go into every run's manifest. */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include "gl.h"
#include "glctx_backend.h"

#include <embree3/rtcore_config.h> /* RTC_VERSION_STRING: the Embree the engine was built against */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct eng_glctx {
    const glctx_backend *backend;
    void *impl;
    char version[128];
    char renderer[128];
    char where[128];
};

static char g_threads[16] = "2";
static char g_embree_cfg[64] = "isa=sse2,threads=2";
static const char *g_info[] = {
    "LP_NATIVE_VECTOR_WIDTH", "128",
    "GALLIUM_OVERRIDE_CPU_CAPS", "sse4.1",
    "LP_NUM_THREADS", g_threads,
    "embree_config", g_embree_cfg,
    "embree_version", RTC_VERSION_STRING,
    "fp", "-ffp-contract=off, no fast-math",
    NULL, NULL,
};

void glctx_pin_determinism(int threads)
{
    if (threads < 1)
        threads = 1;
    snprintf(g_threads, sizeof g_threads, "%d", threads);
    snprintf(g_embree_cfg, sizeof g_embree_cfg, "isa=sse2,threads=%d", threads);
    /* Must be set before Mesa initialises gallivm (first context creation). */
    setenv("LP_NATIVE_VECTOR_WIDTH", "128", 1);
    setenv("GALLIUM_OVERRIDE_CPU_CAPS", "sse4.1", 1);
    setenv("LP_NUM_THREADS", g_threads, 1);
}

const char *const *glctx_determinism_info(void)
{
    return g_info;
}

int glctx_backend_known(const char *name)
{
    return name && glctx_backend_find(name) != NULL;
}

static ispm_gl_proc load_proc(void *user, const char *name)
{
    const eng_glctx *c = user;
    return c->backend->get_proc(c->impl, name);
}

eng_result glctx_create_on(const char *backend, int use_device, int device, eng_glctx **out, eng_error *err)
{
    *out = NULL;
    const glctx_backend *b = glctx_backend_find(backend ? backend : ENG_GL_DEFAULT);
    if (!b)
        return eng_fail(err, ENG_ERR_INVALID, "GL: unknown backend \"%s\" (%s)", backend, ENG_GL_BACKENDS);
    eng_glctx *c = calloc(1, sizeof *c);
    if (!c)
        return eng_fail(err, ENG_ERR_NOMEM, "GL: out of memory");
    c->backend = b;
    eng_result r = b->open(use_device, device, &c->impl, c->where, sizeof c->where, err);
    if (r != ENG_OK) {
        free(c);
        return r;
    }
    ispm_gl_load(load_proc, c);
    GLint major = 0, minor = 0;
    if (glGetIntegerv && glGetString) {
        glGetIntegerv(GL_MAJOR_VERSION, &major);
        glGetIntegerv(GL_MINOR_VERSION, &minor);
    }
    if (major * 10 + minor < 45) {
        b->close(c->impl);
        free(c);
        return eng_fail(err, ENG_ERR_GL, "%s: the context is GL %d.%d, the engine needs 4.5 core", b->name, major, minor);
    }
    snprintf(c->version, sizeof c->version, "%s", (const char *)glGetString(GL_VERSION));
    snprintf(c->renderer, sizeof c->renderer, "%s", (const char *)glGetString(GL_RENDERER));
    /* Pixel-exact behaviour the passes rely on: no dithering, no multisampling, no sRGB
     * conversion on write. */
    glDisable(GL_DITHER);
    glDisable(GL_MULTISAMPLE);
    glDisable(GL_FRAMEBUFFER_SRGB);
    *out = c;
    return ENG_OK;
}

eng_result glctx_create(eng_glctx **out, eng_error *err)
{
    return glctx_create_on(ENG_GL_DEFAULT, 0, 0, out, err);
}

void glctx_destroy(eng_glctx *c)
{
    if (!c)
        return;
    c->backend->close(c->impl);
    free(c);
}

const char *glctx_version(const eng_glctx *c) { return c->version; }
const char *glctx_renderer(const eng_glctx *c) { return c->renderer; }
const char *glctx_backend_name(const eng_glctx *c) { return c->backend->name; }
const char *glctx_where(const eng_glctx *c) { return c->where; }
