/* glctx_egl.c — a GL backend with no window and no X: EGL, on Mesa's surfaceless platform
 * (EGL_MESA_platform_surfaceless: llvmpipe on a machine without a GPU, bit-identical to
 * OSMesa under the same pinned settings) or on EGL device N (EGL_EXT_platform_device,
 * --gl-device N: a GPU vendor's EGL, e.g. NVIDIA's). libEGL is opened at run time, so the
 * binary starts, and records through OSMesa, where no EGL is installed. The context is GL 4.5
 * core with no surface (EGL_KHR_surfaceless_context): the passes render into their own
 * framebuffer objects as on OSMesa. */
#define _POSIX_C_SOURCE 200809L
#include "glctx_backend.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define EGL_MAX_DEVICES 64

typedef struct egl_api {
    PFNEGLGETPROCADDRESSPROC GetProcAddress;
    PFNEGLQUERYSTRINGPROC QueryString;
    PFNEGLGETERRORPROC GetError;
    PFNEGLINITIALIZEPROC Initialize;
    PFNEGLBINDAPIPROC BindAPI;
    PFNEGLCHOOSECONFIGPROC ChooseConfig;
    PFNEGLCREATECONTEXTPROC CreateContext;
    PFNEGLDESTROYCONTEXTPROC DestroyContext;
    PFNEGLMAKECURRENTPROC MakeCurrent;
    PFNEGLRELEASETHREADPROC ReleaseThread;
    PFNEGLQUERYDEVICESEXTPROC QueryDevicesEXT;
    PFNEGLQUERYDEVICESTRINGEXTPROC QueryDeviceStringEXT;
    PFNEGLGETPLATFORMDISPLAYEXTPROC GetPlatformDisplayEXT;
} egl_api;

typedef struct egl_ctx {
    egl_api f;
    EGLDisplay dpy;
    EGLContext ctx;
} egl_ctx;

/* Does the space-separated list exts name ext? */
static int has_ext(const char *exts, const char *ext)
{
    size_t n = strlen(ext);
    for (const char *p = exts; p && (p = strstr(p, ext)) != NULL; p += n)
        if ((p == exts || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0'))
            return 1;
    return 0;
}

/* libEGL.so.1 (glvnd's, which dispatches to Mesa's or the GPU vendor's EGL), kept open. */
static eng_result load_api(egl_api *f, eng_error *err)
{
    void *lib = dlopen("libEGL.so.1", RTLD_NOW | RTLD_LOCAL);
    if (!lib)
        return eng_fail(err, ENG_ERR_GL, "EGL: unavailable: cannot load libEGL.so.1 (install libegl1 and libegl-mesa0): %s",
                        dlerror());
    /* POSIX: a dlsym result converts to a function pointer. */
#define SYM(field, name)                                                                                        \
    if (!(*(void **)&f->field = dlsym(lib, name)))                                                             \
        return eng_fail(err, ENG_ERR_GL, "EGL: unavailable: libEGL.so.1 has no %s", name);
    SYM(GetProcAddress, "eglGetProcAddress")
    SYM(QueryString, "eglQueryString")
    SYM(GetError, "eglGetError")
    SYM(Initialize, "eglInitialize")
    SYM(BindAPI, "eglBindAPI")
    SYM(ChooseConfig, "eglChooseConfig")
    SYM(CreateContext, "eglCreateContext")
    SYM(DestroyContext, "eglDestroyContext")
    SYM(MakeCurrent, "eglMakeCurrent")
    SYM(ReleaseThread, "eglReleaseThread")
#undef SYM
    f->QueryDevicesEXT = (PFNEGLQUERYDEVICESEXTPROC)f->GetProcAddress("eglQueryDevicesEXT");
    f->QueryDeviceStringEXT = (PFNEGLQUERYDEVICESTRINGEXTPROC)f->GetProcAddress("eglQueryDeviceStringEXT");
    f->GetPlatformDisplayEXT = (PFNEGLGETPLATFORMDISPLAYEXTPROC)f->GetProcAddress("eglGetPlatformDisplayEXT");
    return ENG_OK;
}

/* The display of EGL device `device`; where gets "device N (its extensions or DRM node)". */
static eng_result device_display(egl_ctx *c, const char *client, int device, char *where, size_t where_size,
                                 eng_error *err)
{
    if (!has_ext(client, "EGL_EXT_platform_device") || !has_ext(client, "EGL_EXT_device_enumeration") ||
        !c->f.QueryDevicesEXT || !c->f.GetPlatformDisplayEXT)
        return eng_fail(err, ENG_ERR_GL, "EGL: unavailable: no EGL_EXT_platform_device / EGL_EXT_device_enumeration for --gl-device");
    EGLDeviceEXT devs[EGL_MAX_DEVICES];
    EGLint n = 0;
    if (!c->f.QueryDevicesEXT(EGL_MAX_DEVICES, devs, &n))
        n = 0;
    if (device < 0 || device >= n)
        return eng_fail(err, ENG_ERR_INVALID, "EGL: --gl-device %d: this machine has %d EGL device%s%s", device,
                        (int)n, n == 1 ? "" : "s", n ? " (numbered from 0)" : "");
    const char *dexts = c->f.QueryDeviceStringEXT ? c->f.QueryDeviceStringEXT(devs[device], EGL_EXTENSIONS) : NULL;
    const char *node = NULL;
    if (dexts && has_ext(dexts, "EGL_EXT_device_drm"))
        node = c->f.QueryDeviceStringEXT(devs[device], EGL_DRM_DEVICE_FILE_EXT);
    snprintf(where, where_size, "device %d (%s)", device,
             node ? node : dexts && has_ext(dexts, "EGL_MESA_device_software") ? "software" : "no DRM node");
    c->dpy = c->f.GetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devs[device], NULL);
    return ENG_OK;
}

static eng_result egl_open(int use_device, int device, void **impl, char *where, size_t where_size, eng_error *err)
{
    *impl = NULL;
    egl_ctx *c = calloc(1, sizeof *c);
    if (!c)
        return eng_fail(err, ENG_ERR_NOMEM, "GL: out of memory");
    c->dpy = EGL_NO_DISPLAY;
    c->ctx = EGL_NO_CONTEXT;
    eng_result r = load_api(&c->f, err);
    const char *client = r == ENG_OK ? c->f.QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS) : NULL;
    if (r == ENG_OK && !client)
        r = eng_fail(err, ENG_ERR_GL, "EGL: unavailable: no client extensions (EGL_EXT_client_extensions)");
    if (r == ENG_OK && use_device) {
        r = device_display(c, client, device, where, where_size, err);
    } else if (r == ENG_OK) {
        if (!has_ext(client, "EGL_MESA_platform_surfaceless") || !c->f.GetPlatformDisplayEXT)
            r = eng_fail(err, ENG_ERR_GL, "EGL: unavailable: no EGL offers Mesa's surfaceless platform (EGL_MESA_platform_surfaceless: install libegl-mesa0, or choose an EGL device with --gl-device N)");
        else
            c->dpy = c->f.GetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
        snprintf(where, where_size, "surfaceless");
    }
    EGLint major = 0, minor = 0;
    if (r == ENG_OK && (c->dpy == EGL_NO_DISPLAY || !c->f.Initialize(c->dpy, &major, &minor))) {
        EGLint e = c->f.GetError();
        c->dpy = EGL_NO_DISPLAY;
        r = eng_fail(err, ENG_ERR_GL, "EGL: unavailable: cannot initialise the %s display (EGL error 0x%x; is libegl-mesa0 or a GPU driver's EGL installed?)",
                     where, (unsigned)e);
    }
    const char *dexts = r == ENG_OK ? c->f.QueryString(c->dpy, EGL_EXTENSIONS) : NULL;
    if (r == ENG_OK && !has_ext(dexts, "EGL_KHR_surfaceless_context"))
        r = eng_fail(err, ENG_ERR_GL, "EGL: the %s display has no EGL_KHR_surfaceless_context", where);
    EGLConfig cfg = EGL_NO_CONFIG_KHR;
    if (r == ENG_OK && !has_ext(dexts, "EGL_KHR_no_config_context")) {
        const EGLint want[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLint n = 0;
        if (!c->f.ChooseConfig(c->dpy, want, &cfg, 1, &n) || n < 1)
            r = eng_fail(err, ENG_ERR_GL, "EGL: the %s display has no OpenGL config", where);
    }
    if (r == ENG_OK && !c->f.BindAPI(EGL_OPENGL_API))
        r = eng_fail(err, ENG_ERR_GL, "EGL: the %s display does not support desktop OpenGL", where);
    if (r == ENG_OK) {
        const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
        c->ctx = c->f.CreateContext(c->dpy, cfg, EGL_NO_CONTEXT, attribs);
        if (c->ctx == EGL_NO_CONTEXT)
            r = eng_fail(err, ENG_ERR_GL, "EGL: cannot create a GL 4.5 core context on the %s display (EGL error 0x%x)",
                         where, (unsigned)c->f.GetError());
    }
    if (r == ENG_OK && !c->f.MakeCurrent(c->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, c->ctx))
        r = eng_fail(err, ENG_ERR_GL, "EGL: cannot make the context current (EGL error 0x%x)", (unsigned)c->f.GetError());
    if (r != ENG_OK) {
        if (c->ctx != EGL_NO_CONTEXT)
            c->f.DestroyContext(c->dpy, c->ctx);
        free(c);
        return r;
    }
    *impl = c;
    return ENG_OK;
}

static glctx_proc egl_get_proc(void *impl, const char *name)
{
    egl_ctx *c = impl;
    return (glctx_proc)c->f.GetProcAddress(name);
}

static void egl_close(void *impl)
{
    egl_ctx *c = impl;
    c->f.MakeCurrent(c->dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    c->f.DestroyContext(c->dpy, c->ctx);
    /* No eglTerminate: the display stays initialised for the process (a later context reuses
     * it; EGL displays are per process). Terminating it makes Mesa unload its driver, whose
     * few never-freed allocations LeakSanitizer then reports from an unknown module that no
     * suppression can name. */
    c->f.ReleaseThread();
    free(c);
}

const glctx_backend glctx_egl_backend = {
    .name = "egl",
    .open = egl_open,
    .get_proc = egl_get_proc,
    .close = egl_close,
};
