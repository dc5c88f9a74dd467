/* glutil.c — the small pieces every GL pass needs and none should own: column-major 4×4
 * matrix helpers (same layout as GL and glTF), shader programs built from the embedded
 * engine/shaders/ GLSL files, float render targets, and read-back into the announced
 * buffer layout (top row first, channels interleaved). */
#include "eng_internal.h"
#include "glsl_sources.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- matrices */

void m4_identity(float m[16])
{
    memset(m, 0, 16 * sizeof(float));
    m[0] = m[5] = m[10] = m[15] = 1.0f;
}

void m4_mul(float out[16], const float a[16], const float b[16])
{
    float r[16];
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++)
                s += (double)a[k * 4 + row] * (double)b[c * 4 + k];
            r[c * 4 + row] = (float)s;
        }
    memcpy(out, r, sizeof r);
}

int m4_invert(float out[16], const float m[16])
{
    /* Cofactor expansion in double: the matrices are small and this runs a few times a
     * frame, so precision wins over speed. */
    double a[16], inv[16];
    for (int i = 0; i < 16; i++)
        a[i] = m[i];
    inv[0] = a[5] * a[10] * a[15] - a[5] * a[11] * a[14] - a[9] * a[6] * a[15] + a[9] * a[7] * a[14] + a[13] * a[6] * a[11] - a[13] * a[7] * a[10];
    inv[4] = -a[4] * a[10] * a[15] + a[4] * a[11] * a[14] + a[8] * a[6] * a[15] - a[8] * a[7] * a[14] - a[12] * a[6] * a[11] + a[12] * a[7] * a[10];
    inv[8] = a[4] * a[9] * a[15] - a[4] * a[11] * a[13] - a[8] * a[5] * a[15] + a[8] * a[7] * a[13] + a[12] * a[5] * a[11] - a[12] * a[7] * a[9];
    inv[12] = -a[4] * a[9] * a[14] + a[4] * a[10] * a[13] + a[8] * a[5] * a[14] - a[8] * a[6] * a[13] - a[12] * a[5] * a[10] + a[12] * a[6] * a[9];
    inv[1] = -a[1] * a[10] * a[15] + a[1] * a[11] * a[14] + a[9] * a[2] * a[15] - a[9] * a[3] * a[14] - a[13] * a[2] * a[11] + a[13] * a[3] * a[10];
    inv[5] = a[0] * a[10] * a[15] - a[0] * a[11] * a[14] - a[8] * a[2] * a[15] + a[8] * a[3] * a[14] + a[12] * a[2] * a[11] - a[12] * a[3] * a[10];
    inv[9] = -a[0] * a[9] * a[15] + a[0] * a[11] * a[13] + a[8] * a[1] * a[15] - a[8] * a[3] * a[13] - a[12] * a[1] * a[11] + a[12] * a[3] * a[9];
    inv[13] = a[0] * a[9] * a[14] - a[0] * a[10] * a[13] - a[8] * a[1] * a[14] + a[8] * a[2] * a[13] + a[12] * a[1] * a[10] - a[12] * a[2] * a[9];
    inv[2] = a[1] * a[6] * a[15] - a[1] * a[7] * a[14] - a[5] * a[2] * a[15] + a[5] * a[3] * a[14] + a[13] * a[2] * a[7] - a[13] * a[3] * a[6];
    inv[6] = -a[0] * a[6] * a[15] + a[0] * a[7] * a[14] + a[4] * a[2] * a[15] - a[4] * a[3] * a[14] - a[12] * a[2] * a[7] + a[12] * a[3] * a[6];
    inv[10] = a[0] * a[5] * a[15] - a[0] * a[7] * a[13] - a[4] * a[1] * a[15] + a[4] * a[3] * a[13] + a[12] * a[1] * a[7] - a[12] * a[3] * a[5];
    inv[14] = -a[0] * a[5] * a[14] + a[0] * a[6] * a[13] + a[4] * a[1] * a[14] - a[4] * a[2] * a[13] - a[12] * a[1] * a[6] + a[12] * a[2] * a[5];
    inv[3] = -a[1] * a[6] * a[11] + a[1] * a[7] * a[10] + a[5] * a[2] * a[11] - a[5] * a[3] * a[10] - a[9] * a[2] * a[7] + a[9] * a[3] * a[6];
    inv[7] = a[0] * a[6] * a[11] - a[0] * a[7] * a[10] - a[4] * a[2] * a[11] + a[4] * a[3] * a[10] + a[8] * a[2] * a[7] - a[8] * a[3] * a[6];
    inv[11] = -a[0] * a[5] * a[11] + a[0] * a[7] * a[9] + a[4] * a[1] * a[11] - a[4] * a[3] * a[9] - a[8] * a[1] * a[7] + a[8] * a[3] * a[5];
    inv[15] = a[0] * a[5] * a[10] - a[0] * a[6] * a[9] - a[4] * a[1] * a[10] + a[4] * a[2] * a[9] + a[8] * a[1] * a[6] - a[8] * a[2] * a[5];
    double det = a[0] * inv[0] + a[1] * inv[4] + a[2] * inv[8] + a[3] * inv[12];
    if (det == 0.0 || !isfinite(det))
        return 0;
    for (int i = 0; i < 16; i++)
        out[i] = (float)(inv[i] / det);
    return 1;
}

void m4_perspective(float m[16], float yfov, float aspect, float znear, float zfar)
{
    double f = 1.0 / tan((double)yfov * 0.5);
    memset(m, 0, 16 * sizeof(float));
    m[0] = (float)(f / aspect);
    m[5] = (float)f;
    m[10] = (float)(((double)zfar + znear) / ((double)znear - zfar));
    m[11] = -1.0f;
    m[14] = (float)(2.0 * zfar * znear / ((double)znear - zfar));
}

static void normalize3(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (l > 0.0)
        for (int i = 0; i < 3; i++)
            v[i] /= l;
}

void m4_look_at(float m[16], const float eye[3], const float target[3], const float up[3])
{
    double f[3] = {(double)target[0] - eye[0], (double)target[1] - eye[1], (double)target[2] - eye[2]};
    normalize3(f);
    double u0[3] = {up[0], up[1], up[2]};
    double s[3] = {f[1] * u0[2] - f[2] * u0[1], f[2] * u0[0] - f[0] * u0[2], f[0] * u0[1] - f[1] * u0[0]};
    normalize3(s);
    double u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]};
    m4_identity(m);
    m[0] = (float)s[0]; m[4] = (float)s[1]; m[8] = (float)s[2];
    m[1] = (float)u[0]; m[5] = (float)u[1]; m[9] = (float)u[2];
    m[2] = (float)-f[0]; m[6] = (float)-f[1]; m[10] = (float)-f[2];
    m[12] = (float)-(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]);
    m[13] = (float)-(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]);
    m[14] = (float)(f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2]);
}

void m4_transform_point(const float m[16], const float p[3], float out[3])
{
    double r[4];
    for (int row = 0; row < 4; row++)
        r[row] = (double)m[row] * p[0] + (double)m[4 + row] * p[1] + (double)m[8 + row] * p[2] + m[12 + row];
    double w = r[3] != 0.0 ? r[3] : 1.0;
    for (int i = 0; i < 3; i++)
        out[i] = (float)(r[i] / w);
}

void m4_normal_matrix(float out9[9], const float m[16])
{
    float inv[16];
    if (!m4_invert(inv, m))
        m4_identity(inv);
    /* (M^-1)^T: element (r, c) of the result is inv(c, r). */
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++)
            out9[c * 3 + r] = inv[r * 4 + c];
}

/* ---------------------------------------------------------------- shaders */

static eng_result compile(GLenum kind, const char *name, const char *defines, GLuint *out, eng_error *err)
{
    const char *src = eng_glsl_source(name);
    if (!src)
        return eng_fail(err, ENG_ERR_GL, "engine/shaders/%s: no such embedded shader", name);
    /* A line `#pragma ispm_include "NAME"` splices in engine/shaders/NAME (GLSL has no
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
            return eng_fail(err, ENG_ERR_GL, "engine/shaders/%s: no line after #version", name);
        parts[nparts] = src;
        lens[nparts++] = (GLint)(eol + 1 - src);
        parts[nparts] = defines;
        lens[nparts++] = -1;
        rest = eol + 1;
    }
    for (const char *at; (at = strstr(rest, directive));) {
        if (nparts == 2 * MAX_INCLUDES)
            return eng_fail(err, ENG_ERR_GL, "engine/shaders/%s: more than %d ispm_include lines", name, MAX_INCLUDES);
        const char *name_start = at + sizeof directive - 1;
        const char *name_end = strchr(name_start, '"');
        char lib_name[64];
        if (!name_end || (size_t)(name_end - name_start) >= sizeof lib_name)
            return eng_fail(err, ENG_ERR_GL, "engine/shaders/%s: malformed ispm_include", name);
        memcpy(lib_name, name_start, (size_t)(name_end - name_start));
        lib_name[name_end - name_start] = 0;
        const char *lib = eng_glsl_source(lib_name);
        if (!lib)
            return eng_fail(err, ENG_ERR_GL, "engine/shaders/%s: includes %s, which is not embedded", name, lib_name);
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
        return eng_fail(err, ENG_ERR_GL, "engine/shaders/%s: compile failed: %s", name, log);
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
        return eng_fail(err, ENG_ERR_GL, "engine/shaders/%s + %s: link failed: %s", vert_name, frag_name, log);
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
        return eng_fail(err, ENG_ERR_GL, "engine/shaders/%s: link failed: %s", name, log);
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

void glu_read(const glu_target *t, int index, int layer, int channels, const int *pick, float *out)
{
    size_t w = (size_t)t->width, h = (size_t)t->height;
    float *rgba = malloc(w * h * 4 * sizeof(float));
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
    free(rgba);
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

/* One texture reference: "<prefix>_tex_on", "_uv_set", "_uv_xf", "_tex" on unit `unit`. */
static void bind_texref(GLuint prog, const eng_frame_scene *fs, const eng_gpu_prim *g, const scn_texref *r,
                        const char *prefix, int unit)
{
    char name[32];
    int on = r->texture >= 0 && (uint32_t)r->texture < fs->scene->texture_count && g->vbo_uv[r->texcoord];
    snprintf(name, sizeof name, "%s_tex_on", prefix);
    glUniform1i(glGetUniformLocation(prog, name), on);
    if (!on)
        return;
    const float *t = r->transform;
    const float xf[9] = {t[0], t[1], 0.0f, t[2], t[3], 0.0f, t[4], t[5], 1.0f};
    snprintf(name, sizeof name, "%s_uv_xf", !strcmp(prefix, "u_base") ? "u" : prefix);
    glUniformMatrix3fv(glGetUniformLocation(prog, name), 1, GL_FALSE, xf);
    snprintf(name, sizeof name, "%s_uv_set", !strcmp(prefix, "u_base") ? "u" : prefix);
    glUniform1i(glGetUniformLocation(prog, name), r->texcoord);
    snprintf(name, sizeof name, "%s_tex", prefix);
    glUniform1i(glGetUniformLocation(prog, name), unit);
    glActiveTexture(GL_TEXTURE0 + (GLenum)unit);
    glBindTexture(GL_TEXTURE_2D, fs->textures[r->texture]);
    glActiveTexture(GL_TEXTURE0);
}

void eng_bind_material(GLuint prog, const eng_frame_scene *fs, const eng_draw *d, const scn_material *m)
{
    const eng_gpu_prim *g = d->gpu;
    glUniform1i(glGetUniformLocation(prog, "u_has_color"), g->vbo_col != 0);
    glUniform1f(glGetUniformLocation(prog, "u_alpha_cutoff"), m->alpha_mode == SCN_ALPHA_MASK ? m->alpha_cutoff : -1.0f);
    bind_texref(prog, fs, g, &m->base_color_tex, "u_base", ENG_BASE_TEX_UNIT);
    bind_texref(prog, fs, g, &m->metallic_roughness_tex, "u_mr", ENG_BASE_TEX_UNIT + 1);
    bind_texref(prog, fs, g, &m->emissive_tex, "u_em", ENG_BASE_TEX_UNIT + 2);
    bind_texref(prog, fs, g, &m->occlusion_tex, "u_occ", ENG_BASE_TEX_UNIT + 3);
    glUniform1f(glGetUniformLocation(prog, "u_occ_strength"), m->occlusion_strength);
    /* Normal texture (normal_map.glsl): only where the draw has tangents. */
    bind_texref(prog, fs, g, &m->normal_tex, "u_nrm", ENG_BASE_TEX_UNIT + 4);
    if (!g->vbo_tan)
        glUniform1i(glGetUniformLocation(prog, "u_nrm_tex_on"), 0);
    glUniform1f(glGetUniformLocation(prog, "u_nrm_scale"), m->normal_scale);
}
