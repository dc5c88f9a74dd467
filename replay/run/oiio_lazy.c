/* oiio_lazy.c — oiio_shim.h's entry points, with OpenImageIO loaded on first use.
 *
 * OpenImageIO pulls about 240 shared libraries into a process (OpenCV, FFmpeg, OpenVDB, DCMTK,
 * ...); loading and relocating them cost `ispm record` ~0.9 s of serial start-up on the 2-core
 * machine although recording never reads or writes an image through it. The
 * C++ shims (oiio_shim.cpp, png_shim.cpp) are therefore a separate module, libispm_oiio.so,
 * which the first call here dlopens (once, thread-safely: replay decodes on several threads).
 * Where: $ISPM_OIIO_MODULE if set, else the path CMake built it at (ISPM_OIIO_MODULE_PATH), else
 * where `cmake --install` puts it beside the program (ISPM_OIIO_MODULE_FROM_BIN, relative to the
 * executable's folder, whatever the install prefix), so that an installed ispm works once its
 * build folder is gone. A module that cannot be loaded is an ENG_ERR_IO naming the file asked
 * for and the module.
 * rep_parts_free only frees C memory and needs no module.
 */
#define _GNU_SOURCE
#include "oiio_shim.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#ifndef ISPM_OIIO_MODULE_PATH
#error "ISPM_OIIO_MODULE_PATH (the built libispm_oiio.so) must be defined by the build"
#endif
#ifndef ISPM_OIIO_MODULE_FROM_BIN
#define ISPM_OIIO_MODULE_FROM_BIN "../lib/ispm/libispm_oiio.so"
#endif

typedef eng_result (*read_parts_fn)(const char *, size_t, rep_part **, int *, eng_error *);
typedef eng_result (*write_parts_fn)(const char *, const eng_buffer *, int, eng_error *);
typedef eng_result (*write_png_fn)(const char *, int, int, int, const unsigned char *, eng_error *);
typedef eng_result (*read_image8_fn)(const char *, int *, int *, int *, unsigned char **, eng_error *);

static struct {
    pthread_once_t once;
    const char *where;
    char why[256]; /* dlerror() of a failed load; empty when loaded */
    read_parts_fn read_parts;
    write_parts_fn write_parts;
    write_png_fn write_png;
    read_image8_fn read_image8;
} g_mod = {PTHREAD_ONCE_INIT, NULL, "", NULL, NULL, NULL, NULL};

static void copy_why(const char *s)
{
    snprintf(g_mod.why, sizeof g_mod.why, "%s", s ? s : "unknown dlopen error");
}

static void load_module(void)
{
    const char *env = getenv("ISPM_OIIO_MODULE");
    g_mod.where = env && *env ? env : ISPM_OIIO_MODULE_PATH;
    void *h = dlopen(g_mod.where, RTLD_NOW | RTLD_LOCAL);
    if (!h && !(env && *env)) {
        /* The installed layout: bin/ispm and lib.../ispm/libispm_oiio.so under one prefix. */
        static char installed[4096];
        ssize_t n = readlink("/proc/self/exe", installed, sizeof installed - 1);
        char *slash = n > 0 ? memrchr(installed, '/', (size_t)n) : NULL;
        if (slash && (size_t)(slash + 1 - installed) + sizeof ISPM_OIIO_MODULE_FROM_BIN <= sizeof installed) {
            memcpy(slash + 1, ISPM_OIIO_MODULE_FROM_BIN, sizeof ISPM_OIIO_MODULE_FROM_BIN);
            void *hi = dlopen(installed, RTLD_NOW | RTLD_LOCAL);
            if (hi) {
                h = hi;
                g_mod.where = installed;
            }
        }
        if (!h) /* report the first failure: the build's module */
            h = dlopen(g_mod.where, RTLD_NOW | RTLD_LOCAL);
    }
    if (!h) {
        copy_why(dlerror());
        return;
    }
    /* POSIX: a data pointer from dlsym may be converted to a function pointer this way. */
    *(void **)&g_mod.read_parts = dlsym(h, "rep_oiio_read_parts");
    *(void **)&g_mod.write_parts = dlsym(h, "rep_oiio_write_parts");
    *(void **)&g_mod.write_png = dlsym(h, "rep_oiio_write_png");
    *(void **)&g_mod.read_image8 = dlsym(h, "rep_oiio_read_image8");
    if (!g_mod.read_parts || !g_mod.write_parts || !g_mod.write_png || !g_mod.read_image8)
        copy_why("a rep_oiio_* entry point is missing");
    /* The handle is kept for the life of the process (OpenImageIO's own threads live there). */
}

/* ENG_OK when the module is loaded, else ENG_ERR_IO with err naming path and the module. */
static eng_result unavailable(const char *path, eng_error *err)
{
    pthread_once(&g_mod.once, load_module);
    if (!g_mod.why[0])
        return ENG_OK;
    return eng_fail(err, ENG_ERR_IO, "%s: cannot load the OpenImageIO module %s: %s", path, g_mod.where, g_mod.why);
}

eng_result rep_oiio_load(eng_error *err)
{
    return unavailable("OpenImageIO", err);
}

eng_result rep_oiio_read_parts(const char *path, size_t max_floats, rep_part **parts, int *count, eng_error *err)
{
    *parts = NULL;
    *count = 0;
    eng_result r = unavailable(path, err);
    if (r != ENG_OK)
        return r;
    return g_mod.read_parts(path, max_floats, parts, count, err);
}

void rep_part_clear(rep_part *p)
{
    free(p->name);
    for (int c = 0; c < ENG_MAX_CHANNELS; c++)
        free(p->channels[c]);
    free(p->data);
    memset(p, 0, sizeof *p);
}

void rep_parts_free(rep_part *parts, int count)
{
    if (!parts)
        return;
    for (int i = 0; i < count; i++)
        rep_part_clear(&parts[i]);
    free(parts);
}

eng_result rep_oiio_write_parts(const char *path, const eng_buffer *parts, int count, eng_error *err)
{
    eng_result r = unavailable(path, err);
    if (r != ENG_OK)
        return r;
    return g_mod.write_parts(path, parts, count, err);
}

eng_result rep_oiio_write_png(const char *path, int width, int height, int channel_count,
                              const unsigned char *pixels, eng_error *err)
{
    eng_result r = unavailable(path, err);
    if (r != ENG_OK)
        return r;
    return g_mod.write_png(path, width, height, channel_count, pixels, err);
}

eng_result rep_oiio_read_image8(const char *path, int *width, int *height, int *channel_count,
                                unsigned char **pixels, eng_error *err)
{
    *pixels = NULL;
    eng_result r = unavailable(path, err);
    if (r != ENG_OK)
        return r;
    return g_mod.read_image8(path, width, height, channel_count, pixels, err);
}
