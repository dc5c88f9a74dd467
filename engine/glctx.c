/* glctx.c — the engine's GL 4.5 core context, made offscreen with OSMesa (Mesa's llvmpipe),
 * so recording needs no display and no GPU. It also pins everything in the rasterizer and
 * the ray tracer that follows the host's SIMD width, because goldens recorded on one CPU are
 * replayed on others: llvmpipe's vector width and CPU feature set (AVX/FMA change rounding)
 * and Embree's ISA. The pinned values go into every run's manifest. */
#define _POSIX_C_SOURCE 200809L /* setenv */
#include "eng_internal.h"

#include <GL/osmesa.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct eng_glctx {
    OSMesaContext ctx;
    unsigned char dummy[16 * 16 * 4]; /* the context's own framebuffer; passes use FBOs */
    char version[128];
    char renderer[128];
};

static char g_threads[16] = "2";
static char g_embree_cfg[64] = "isa=sse2,threads=2";
static const char *g_info[] = {
    "LP_NATIVE_VECTOR_WIDTH", "128",
    "GALLIUM_OVERRIDE_CPU_CAPS", "sse4.1",
    "LP_NUM_THREADS", g_threads,
    "embree_config", g_embree_cfg,
    "fp", "-ffp-contract=off, no fast-math",
    NULL, NULL,
};

void eng_pin_determinism(int threads)
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

const char *const *eng_determinism_info(void)
{
    return g_info;
}

eng_result glctx_create(eng_glctx **out, eng_error *err)
{
    *out = NULL;
    eng_glctx *c = calloc(1, sizeof *c);
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

void glctx_destroy(eng_glctx *c)
{
    if (!c)
        return;
    OSMesaDestroyContext(c->ctx);
    free(c);
}

const char *glctx_version(const eng_glctx *c) { return c->version; }
const char *glctx_renderer(const eng_glctx *c) { return c->renderer; }
