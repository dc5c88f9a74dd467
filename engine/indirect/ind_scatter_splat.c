/* ind_scatter_splat.c — indirect light by scattering photon volumes (ISPM 003_… §5, Eq. 1–3): every
 * photon-map photon whose kernel can reach a visible surface is drawn as one screen-aligned
 * rectangle (two triangles, one draw, vertices pulled from a storage buffer) holding every
 * pixel whose G-buffer point can lie in its kernel ellipsoid (ind_scatter_bounds.c, from the
 * G-buffer's positions read back and boxed per 8×8 tile); the fragment shader evaluates Eq. 1
 * against the eye G-buffer and additive blending sums the contributions (see
 * shaders/splat.frag.glsl for the kernel). The rectangles are drawn at the NDC depth of the
 * ellipsoid's far side and depth-tested (GEQUAL, no writes) against the eye G-buffer's own
 * depth buffer, so a pixel whose surface lies behind the whole volume costs no shading. A
 * pixel gets each photon once, in photon order, and exactly the pixels whose point lies in
 * the kernel pass the shader's test, so the sums are those of the earlier instanced
 * icosahedra, less their losses at the kernel's rim (docs/scatter.md: the same image, ~3×
 * cheaper on llvmpipe). The rectangles are never clipped, and a volume that reaches the eye
 * plane covers the tiles it can reach, so the §6.3 near-plane artifact does not occur.
 * The fragment program is picked per frame from the drawn materials (no metallic: no glossy
 * term; no transmission either: no material fetch), which sums the same floats.
 *
 * Determinism: llvmpipe bins primitives per tile and each tile is rasterised by one thread in
 * submission order, so the float sums are the same whatever LP_NUM_THREADS is; the CPU
 * bounds are per photon, packed in photon order.
 * Owns its programs, the photon and index buffers, the read-back positions and its target. */
#include "indirect.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct pass_splat {
    glu_target target;
    /* 0 the full BSDF, 1 SPLAT_NO_METALLIC (no glossy term), 2 also SPLAT_NO_TRANSMISSION
     * (Lambert only, no material fetch); 3–5 the same with PHOTON_ANISO (the anisotropic
     * kernel, photon_kernel.glsl), compiled on first use; 6–11 the same six with
     * PIXEL_SCALE (per-pixel radius scales, pass_splat_set_pixel_scale; pixel_scale.glsl). */
    GLuint program[12], vao, ssbo, ibo;
    GLuint scale_tex;     /* R32F per-pixel radius scales (0 until first set) */
    int use_scale;        /* the next run applies them */
    float *scale_rows;    /* upload scratch, GL row order */
    int irradiance;
    size_t capacity;    /* photons the CPU arrays hold (pass_splat_reserve) */
    size_t gl_capacity; /* photons the GL buffers hold (at most capacity) */
    uint32_t *idx;      /* the index buffer's data for capacity photons */
    float *position;  /* read-back G-buffer positions, GL row order */
    float *packed;    /* SPLAT_VEC4 vec4 per drawn photon */
    splat_bounds *bounds; /* per photon */
    unsigned char *keep;  /* per photon: drawn */
    splat_tiles tiles;
};

/* Per drawn photon: rect, (x, z_far), (n_p, r_xy), (Φ_i, r_z), (ω_i, s_u); splat.vert.glsl. */
#define SPLAT_VEC4 5

/* Photons per draw call when the splat is drawn in pieces (see draw_pipelined). */
#define SPLAT_CHUNK 4096

/* Draws the drawn photons' rectangles (the bound VAO's index buffer, 6 indices each). llvmpipe
 * shades the vertices of a draw and bins its triangles on the calling thread, alone, and
 * rasterises the binned scene on its LP_NUM_THREADS threads only once the scene is flushed
 * (cornell-box-perf, 65,536 photons, 2 threads: one draw ~560 ms a frame, in
 * pieces ~360 ms, measured under chrt on the 2-core machine). With 2 or more threads
 * the photons are therefore drawn SPLAT_CHUNK at a time with a glFlush after each, so that
 * llvmpipe rasterises piece k while this thread bins piece k+1. The pixels are the same: the
 * pieces are rasterised in submission order, each tile by one thread in primitive order, so
 * every pixel sums the same photons in the same order. With 1 thread it stays one draw (a
 * 1-thread run keeps one core busy at a time, as before). */
static void draw_pipelined(size_t drawn, int threads)
{
    const size_t chunk = threads > 1 ? SPLAT_CHUNK : drawn;
    for (size_t at = 0; at < drawn; at += chunk) {
        const size_t m = drawn - at < chunk ? drawn - at : chunk;
        glDrawElements(GL_TRIANGLES, (GLsizei)(m * 6), GL_UNSIGNED_INT, (const void *)(at * 6 * sizeof(GLuint)));
        if (m < drawn)
            glFlush();
    }
}

/* Compiles variant k (0–11, see struct pass_splat) into p->program[k] and sets its samplers. */
static eng_result splat_program(pass_splat *p, int k, eng_error *err)
{
    char defs[160];
    static const char *const defines[6] = {
        NULL,
        "#define SPLAT_NO_METALLIC\n",
        "#define SPLAT_NO_METALLIC\n#define SPLAT_NO_TRANSMISSION\n",
        "#define PHOTON_ANISO\n",
        "#define PHOTON_ANISO\n#define SPLAT_NO_METALLIC\n",
        "#define PHOTON_ANISO\n#define SPLAT_NO_METALLIC\n#define SPLAT_NO_TRANSMISSION\n"};
    const char *frag = p->irradiance ? "splat_irradiance.frag.glsl" : "splat.frag.glsl";
    snprintf(defs, sizeof defs, "%s%s", k >= 6 ? "#define PIXEL_SCALE\n" : "", defines[k % 6] ? defines[k % 6] : "");
    eng_result r = glu_program_defines("splat.vert.glsl", frag, defs[0] ? defs : NULL, &p->program[k], err);
    if (r != ENG_OK)
        return r;
    GLuint prog = p->program[k];
    glUseProgram(prog);
    glUniform1i(glGetUniformLocation(prog, "u_position"), 0);
    glUniform1i(glGetUniformLocation(prog, "u_normal"), 1);
    glUniform1i(glGetUniformLocation(prog, "u_albedo"), 2);
    glUniform1i(glGetUniformLocation(prog, "u_material"), 3);
    if (k >= 6)
        glUniform1i(glGetUniformLocation(prog, "u_pixel_scale"), 4);
    glUniform2f(glGetUniformLocation(prog, "u_viewport"), (float)p->target.width, (float)p->target.height);
    glUseProgram(0);
    return ENG_OK;
}

eng_result pass_splat_create(int width, int height, int irradiance, pass_splat **out, eng_error *err)
{
    *out = NULL;
    pass_splat *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "splat: out of memory");
    p->irradiance = irradiance;
    eng_result r = glu_target_create(&p->target, irradiance ? 2 : 1, width, height, 0, err);
    for (int k = 0; k < 3 && r == ENG_OK; k++)
        r = splat_program(p, k, err);
    if (r != ENG_OK) {
        pass_splat_destroy(p);
        return r;
    }
    p->position = eng_xmalloc((size_t)width * (size_t)height * 4 * sizeof(float));
    glGenVertexArrays(1, &p->vao);
    glGenBuffers(1, &p->ssbo);
    glGenBuffers(1, &p->ibo);
    *out = p;
    return ENG_OK;
}

void pass_splat_reserve(pass_splat *p, size_t n, int prefault)
{
    if (n <= p->capacity)
        return;
    n += n / 8; /* room for the next frames' few more photons */
    p->capacity = n;
    free(p->packed);
    free(p->bounds);
    free(p->keep);
    free(p->idx);
    p->packed = eng_xmalloc(n * SPLAT_VEC4 * 4 * sizeof(float));
    p->bounds = eng_xmalloc(n * sizeof *p->bounds);
    p->keep = eng_xmalloc(n);
    if (prefault) { /* take the page faults here, off the GL thread (pass_splat_reserve) */
        memset(p->packed, 0, n * SPLAT_VEC4 * 4 * sizeof(float));
        memset(p->bounds, 0, n * sizeof *p->bounds);
        memset(p->keep, 0, n);
    }
    p->idx = eng_xmalloc(n * 6 * sizeof *p->idx);
    for (size_t i = 0; i < n; i++) {
        const uint32_t b = (uint32_t)(4 * i);
        const uint32_t q[6] = {b, b + 1, b + 2, b + 2, b + 1, b + 3};
        memcpy(p->idx + 6 * i, q, sizeof q);
    }
}

/* Grows the photon and index buffers to hold n photons (two triangles of 4 vertices each) and
 * a few more, within the CPU arrays' capacity (at least n: pass_splat_reserve). */
static void reserve_gl(pass_splat *p, size_t n)
{
    if (n <= p->gl_capacity)
        return;
    n += n / 8;
    if (n > p->capacity)
        n = p->capacity;
    p->gl_capacity = n;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, p->ssbo);
    glBufferData(GL_SHADER_STORAGE_BUFFER, (GLsizeiptr)(n * SPLAT_VEC4 * 4 * sizeof(float)), NULL, GL_STREAM_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    glBindVertexArray(p->vao);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, p->ibo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(n * 6 * sizeof *p->idx), p->idx, GL_STATIC_DRAW);
    glBindVertexArray(0);
}

const glu_target *pass_splat_run(pass_splat *p, const eng_frame_scene *fs, const glu_target *gbuf,
                                 const eng_photon_map *map, const float *radius, const float *aniso,
                                 const eng_settings *s)
{
    glu_target *t = &p->target;
    const int w = t->width, h = t->height;
    /* The G-buffer's positions, for the CPU bounds (the G-buffer is finished before any
     * indirect method runs, so this read waits for nothing the splat does not need). */
    glBindFramebuffer(GL_READ_FRAMEBUFFER, gbuf->fbo);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, p->position);
    splat_tiles_build(&p->tiles, p->position, w, h);

    /* Share the eye G-buffer's depth buffer for the depth test. */
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, gbuf->depth);
    glViewport(0, 0, w, h);
    const float zero[4] = {0, 0, 0, 0};
    for (int i = 0; i < t->count; i++)
        glClearBufferfv(GL_COLOR, i, zero);
    pass_splat_reserve(p, map->count, 0);
    reserve_gl(p, map->count);
    /* Bounds per photon on the CPU threads (independent), then the drawn ones packed in
     * photon order: the order the blending sums them in. */
    const long n = (long)map->count;
    const int threads = s->threads > 0 ? s->threads : 1;
#pragma omp parallel for schedule(static, 1024) num_threads(threads)
    for (long i = 0; i < n; i++) {
        const eng_photon *ph = &map->photons[i];
        const float r_xy = radius[i], reach = aniso ? r_xy * aniso[4 * i + 3] : r_xy;
        /* The anisotropic ellipsoid lies inside the one of semi-axes (reach, reach, r_z). */
        p->keep[i] = (unsigned char)splat_photon_bounds(fs->camera.view_proj, fs->camera.proj, &p->tiles, ph->position,
                                                        ph->normal, reach, r_xy * s->normal_compression, &p->bounds[i]);
    }
    size_t drawn = 0;
    for (size_t i = 0; i < map->count; i++) {
        if (!p->keep[i])
            continue;
        const eng_photon *ph = &map->photons[i];
        const splat_bounds *b = &p->bounds[i];
        const float r_xy = radius[i];
        const float r_z = r_xy * s->normal_compression;
        float *d = p->packed + drawn * SPLAT_VEC4 * 4;
        const float v[SPLAT_VEC4 * 4] = {(float)b->x0, (float)b->y0, (float)(b->x1 + 1), (float)(b->y1 + 1),
                                         ph->position[0], ph->position[1], ph->position[2], b->z,
                                         ph->normal[0], ph->normal[1], ph->normal[2], r_xy,
                                         ph->power[0], ph->power[1], ph->power[2], r_z,
                                         ph->direction[0], ph->direction[1], ph->direction[2],
                                         aniso ? aniso[4 * i + 3] : 1.0f};
        memcpy(d, v, sizeof v);
        drawn++;
    }
    if (drawn > 0) {
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, p->ssbo);
        glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, (GLsizeiptr)(drawn * SPLAT_VEC4 * 4 * sizeof(float)), p->packed);
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, p->ssbo);

        /* The G-buffer's metallic and transmission channels are the drawn materials' factors
         * (pass_gbuffer.c): without such a material they are 0 at every pixel. */
        int metallic = 0, transmission = 0;
        for (uint32_t i = 0; i < fs->draw_count; i++) {
            scn_material m = eng_material_of(fs->scene, fs->draws[i].material);
            metallic |= m.metallic > 0.0f;
            transmission |= m.transmission != 0.0f;
        }
        const int k = (metallic ? 0 : transmission ? 1 : 2) + (aniso ? 3 : 0) + (p->use_scale ? 6 : 0);
        if (!p->program[k]) {
            eng_error e;
            if (splat_program(p, k, &e) != ENG_OK) {
                fprintf(stderr, "ispm: %s\n", e.msg);
                abort();
            }
        }
        const GLuint prog = p->program[k];
        glUseProgram(prog);
        glUniform3fv(glGetUniformLocation(prog, "u_eye"), 1, fs->camera.eye);
        for (int i = 0; i < 4; i++) {
            glActiveTexture(GL_TEXTURE0 + i);
            glBindTexture(GL_TEXTURE_2D, gbuf->color[i]);
        }
        if (p->use_scale) {
            glActiveTexture(GL_TEXTURE4);
            glBindTexture(GL_TEXTURE_2D, p->scale_tex);
        }
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_GEQUAL);
        glDepthMask(GL_FALSE);
        glEnable(GL_BLEND);
        glBlendFunc(GL_ONE, GL_ONE);
        glBlendEquation(GL_FUNC_ADD);
        glBindVertexArray(p->vao);
        draw_pipelined(drawn, s->threads);
        glBindVertexArray(0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
        glDisable(GL_BLEND);
        glDepthMask(GL_TRUE);
        glDepthFunc(GL_LESS);
        glDisable(GL_DEPTH_TEST);
        glActiveTexture(GL_TEXTURE0);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return t;
}

void pass_splat_destroy(pass_splat *p)
{
    if (!p)
        return;
    glu_target_destroy(&p->target);
    if (p->vao)
        glDeleteVertexArrays(1, &p->vao);
    GLuint bufs[2] = {p->ssbo, p->ibo};
    glDeleteBuffers(2, bufs);
    for (int k = 0; k < 12; k++)
        if (p->program[k])
            glDeleteProgram(p->program[k]);
    if (p->scale_tex)
        glDeleteTextures(1, &p->scale_tex);
    free(p->scale_rows);
    free(p->position);
    free(p->packed);
    free(p->bounds);
    free(p->keep);
    free(p->idx);
    splat_tiles_free(&p->tiles);
    free(p);
}

void pass_splat_set_pixel_scale(pass_splat *p, const float *scale)
{
    p->use_scale = scale != NULL;
    if (scale)
        pixel_scale_upload(&p->scale_tex, &p->scale_rows, p->target.width, p->target.height, scale);
}
