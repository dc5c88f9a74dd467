/* glutil.c — the small pieces every GL pass needs and none should own: column-major 4×4
 * matrix helpers (same layout as GL and glTF), shader programs built from the embedded
 * engine/gl/shaders/ GLSL files, float render targets, and read-back into the announced
 * buffer layout (top row first, channels interleaved). */
#include "gl.h"
#include "glsl_sources.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- matrices */

/* ---------------------------------------------------------------- shaders */

static eng_result compile(GLenum kind, const char *name, const char *defines, GLuint *out, eng_error *err)
{
    const char *src = eng_glsl_source(name);
    if (!src)
        return eng_fail(err, ENG_ERR_GL, "engine/gl/shaders/%s: no such embedded shader", name);
    /* A line `#pragma ispm_include "NAME"` splices in engine/gl/shaders/NAME (GLSL has no
     * include): the shader is compiled from the strings between the directives and the
     * included files, in order. Included files do not include further. */
    static const char directive[] = "#pragma ispm_include \"";
    enum { MAX_INCLUDES = 8 };
    const char *parts[2 * MAX_INCLUDES + 3];
    GLint lens[2 * MAX_INCLUDES + 3];
    int nparts = 0;
    const char *rest = src;
    if (defines) { /* after the #version line, which must come first */
        const char *eol = strchr(src, '\n');
        if (!eol)
            return eng_fail(err, ENG_ERR_GL, "engine/gl/shaders/%s: no line after #version", name);
        parts[nparts] = src;
        lens[nparts++] = (GLint)(eol + 1 - src);
        parts[nparts] = defines;
        lens[nparts++] = -1;
        rest = eol + 1;
    }
    for (const char *at; (at = strstr(rest, directive));) {
        if (nparts == 2 * MAX_INCLUDES)
            return eng_fail(err, ENG_ERR_GL, "engine/gl/shaders/%s: more than %d ispm_include lines", name, MAX_INCLUDES);
        const char *name_start = at + sizeof directive - 1;
        const char *name_end = strchr(name_start, '"');
        char lib_name[64];
        if (!name_end || (size_t)(name_end - name_start) >= sizeof lib_name)
            return eng_fail(err, ENG_ERR_GL, "engine/gl/shaders/%s: malformed ispm_include", name);
        memcpy(lib_name, name_start, (size_t)(name_end - name_start));
        lib_name[name_end - name_start] = 0;
        const char *lib = eng_glsl_source(lib_name);
        if (!lib)
            return eng_fail(err, ENG_ERR_GL, "engine/gl/shaders/%s: includes %s, which is not embedded", name, lib_name);
        parts[nparts] = rest;
        lens[nparts++] = (GLint)(at - rest);
        parts[nparts] = lib;
        lens[nparts++] = -1;
        const char *after = strchr(name_end, '\n');
        rest = after ? after : "";
    }
    parts[nparts] = rest;
    lens[nparts++] = -1;
    GLuint sh = glCreateShader(kind);
    glShaderSource(sh, nparts, parts, lens);
    glCompileShader(sh);
    GLint ok = 0;
    glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[768];
        glGetShaderInfoLog(sh, sizeof log, NULL, log);
        glDeleteShader(sh);
        return eng_fail(err, ENG_ERR_GL, "engine/gl/shaders/%s: compile failed: %s", name, log);
    }
    *out = sh;
    return ENG_OK;
}

eng_result glu_program(const char *vert_name, const char *frag_name, GLuint *out, eng_error *err)
{
    return glu_program_defines(vert_name, frag_name, NULL, out, err);
}

eng_result glu_program_defines(const char *vert_name, const char *frag_name, const char *frag_defines, GLuint *out,
                               eng_error *err)
{
    GLuint vs, fs;
    eng_result r = compile(GL_VERTEX_SHADER, vert_name, NULL, &vs, err);
    if (r != ENG_OK)
        return r;
    r = compile(GL_FRAGMENT_SHADER, frag_name, frag_defines, &fs, err);
    if (r != ENG_OK) {
        glDeleteShader(vs);
        return r;
    }
    GLuint prog = glCreateProgram();
    glAttachShader(prog, vs);
    glAttachShader(prog, fs);
    glLinkProgram(prog);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[768];
        glGetProgramInfoLog(prog, sizeof log, NULL, log);
        glDeleteProgram(prog);
        return eng_fail(err, ENG_ERR_GL, "engine/gl/shaders/%s + %s: link failed: %s", vert_name, frag_name, log);
    }
    *out = prog;
    return ENG_OK;
}

eng_result glu_compute_program(const char *name, GLuint *out, eng_error *err)
{
    GLuint cs;
    eng_result r = compile(GL_COMPUTE_SHADER, name, NULL, &cs, err);
    if (r != ENG_OK)
        return r;
    GLuint prog = glCreateProgram();
    glAttachShader(prog, cs);
    glLinkProgram(prog);
    glDeleteShader(cs);
    GLint ok = 0;
    glGetProgramiv(prog, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[768];
        glGetProgramInfoLog(prog, sizeof log, NULL, log);
        glDeleteProgram(prog);
        return eng_fail(err, ENG_ERR_GL, "engine/gl/shaders/%s: link failed: %s", name, log);
    }
    *out = prog;
    return ENG_OK;
}

/* ---------------------------------------------------------------- targets */

eng_result glu_target_create(glu_target *t, int count, int width, int height, int layers, eng_error *err)
{
    memset(t, 0, sizeof *t);
    t->count = count;
    t->width = width;
    t->height = height;
    t->layers = layers;
    GLenum kind = layers > 0 ? GL_TEXTURE_2D_ARRAY : GL_TEXTURE_2D;
    glGenFramebuffers(1, &t->fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glGenTextures(count, t->color);
    GLenum bufs[8];
    for (int i = 0; i < count; i++) {
        glBindTexture(kind, t->color[i]);
        if (layers > 0)
            glTexImage3D(kind, 0, GL_RGBA32F, width, height, layers, 0, GL_RGBA, GL_FLOAT, NULL);
        else
            glTexImage2D(kind, 0, GL_RGBA32F, width, height, 0, GL_RGBA, GL_FLOAT, NULL);
        /* Nearest everywhere: passes fetch texels explicitly, nothing is filtered by GL. */
        glTexParameteri(kind, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(kind, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTexParameteri(kind, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(kind, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        if (layers > 0)
            glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, t->color[i], 0, 0);
        else
            glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D, t->color[i], 0);
        bufs[i] = GL_COLOR_ATTACHMENT0 + i;
    }
    glGenRenderbuffers(1, &t->depth);
    glBindRenderbuffer(GL_RENDERBUFFER, t->depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, t->depth);
    glDrawBuffers(count, bufs);
    GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        glu_target_destroy(t);
        return eng_fail(err, ENG_ERR_GL, "GL: framebuffer %dx%d with %d float targets incomplete (0x%x)",
                        width, height, count, status);
    }
    if (glGetError() != GL_NO_ERROR) {
        glu_target_destroy(t);
        return eng_fail(err, ENG_ERR_GL, "GL: cannot allocate %dx%d float targets (out of memory?)", width, height);
    }
    return ENG_OK;
}

void glu_target_destroy(glu_target *t)
{
    if (!t || !t->fbo)
        return;
    glDeleteTextures(t->count, t->color);
    glDeleteRenderbuffers(1, &t->depth);
    glDeleteFramebuffers(1, &t->fbo);
    memset(t, 0, sizeof *t);
}

void glu_target_bind_layer(glu_target *t, int layer)
{
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    for (int i = 0; i < t->count; i++)
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, t->color[i], 0, layer);
}

/* glu_read's RGBA staging, kept between reads on the thread that owns the GL context: a 1080p
 * read is 33 MB, above glibc's largest mmap threshold, so a buffer per read would be mapped and
 * page-faulted in afresh every time (a quarter of an all-buffer recording's CPU). Grows to the
 * largest target read; held until the thread ends. */
static _Thread_local float *read_staging;
static _Thread_local size_t read_staging_floats;

void glu_read(const glu_target *t, int index, int layer, int channels, const int *pick, float *out)
{
    size_t w = (size_t)t->width, h = (size_t)t->height;
    if (read_staging_floats < w * h * 4) {
        free(read_staging);
        read_staging = malloc(w * h * 4 * sizeof(float));
        read_staging_floats = read_staging ? w * h * 4 : 0;
    }
    float *rgba = read_staging;
    if (!rgba) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    glBindFramebuffer(GL_READ_FRAMEBUFFER, t->fbo);
    if (t->layers > 0)
        glFramebufferTextureLayer(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + index, t->color[index], 0, layer);
    glReadBuffer(GL_COLOR_ATTACHMENT0 + index);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, t->width, t->height, GL_RGBA, GL_FLOAT, rgba);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    /* GL's row 0 is the bottom; announced buffers start at the top. */
    for (size_t y = 0; y < h; y++) {
        const float *src = rgba + (h - 1 - y) * w * 4;
        float *dst = out + y * w * (size_t)channels;
        for (size_t x = 0; x < w; x++)
            for (int c = 0; c < channels; c++)
                dst[x * (size_t)channels + (size_t)c] = src[x * 4 + (size_t)pick[c]];
    }
}

GLuint glu_fullscreen_vao(void)
{
    GLuint vao;
    glGenVertexArrays(1, &vao);
    return vao;
}

eng_result glu_pass_create(glu_pass *p, const char *frag_name, int count, int width, int height, eng_error *err)
{
    memset(p, 0, sizeof *p);
    eng_result r = glu_program("fullscreen.vert.glsl", frag_name, &p->program, err);
    if (r == ENG_OK)
        r = glu_target_create(&p->target, count, width, height, 0, err);
    if (r != ENG_OK) {
        glu_pass_destroy(p);
        return r;
    }
    p->vao = glu_fullscreen_vao();
    return ENG_OK;
}

void glu_pass_destroy(glu_pass *p)
{
    glu_target_destroy(&p->target);
    if (p->vao)
        glDeleteVertexArrays(1, &p->vao);
    if (p->program)
        glDeleteProgram(p->program);
    memset(p, 0, sizeof *p);
}

void glu_pass_draw(const glu_pass *p)
{
    glu_pass_draw_to(p, &p->target);
}

void glu_pass_draw_to(const glu_pass *p, const glu_target *t)
{
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glViewport(0, 0, t->width, t->height);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(p->vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glActiveTexture(GL_TEXTURE0);
}
