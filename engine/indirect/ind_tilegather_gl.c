/* ind_tilegather_gl.c — `"indirect": "tile-gather-gl"`: the tile-based gather of 002_… §6.3
 * with the evaluation in a GL compute shader, as the paper does it on a GPU (its §6.4 /
 * Table 6.1 compares it with splatting). The CPU builds the same tile lists as the CPU tile
 * gather (ind_tilelists.c: tile boxes from the read-back G-buffer positions, conservative photon
 * rectangles, per-tile lists in photon order); they are uploaded with the photons as shader
 * storage buffers, and shaders/tile_gather.comp.glsl runs one 16×16 workgroup per tile, one
 * invocation per pixel, each summing its tile's list in order with splat.frag.glsl's kernel
 * and BSDF, straight into this method's RGBA32F target (imageStore). The sums are in photon
 * order like the CPU gathers', so they equal them up to llvmpipe's rounding of sqrt,
 * normalize and division, and do not depend on the thread count.
 *
 * Buffers "gather.*" and gather.tile_count, like the CPU tile gather. Owns its program,
 * three buffers, the target and the lists. On llvmpipe this is slower than the CPU
 * evaluation (docs/indirect.md: "tile-gather-gl"); it exists to measure the paper's design. */
#include "ind_tilelists.h"

#include <stdlib.h>
#include <string.h>

/* The shader reads an entry as a uvec2: the photon, then the clipped rectangle's four bytes. */
_Static_assert(sizeof(tl_entry) == 8, "tl_entry is the shader's uvec2");

enum { BUF_PHOTONS, BUF_OFFSETS, BUF_ENTRIES, BUFS };

typedef struct tgl_state {
    int width, height, irradiance;
    GLuint program;
    GLint loc_eye, loc_irradiance;
    GLuint buf[BUFS];
    glu_target target;
    glu_gbuffer gb;  /* positions only: the tile boxes */
    float *packed;   /* 16 floats per photon, as the shader's `photon` */
    size_t packed_capacity;
    float *reach; /* per photon s_u·r_xy under the anisotropic kernel (the lists' radius) */
    size_t reach_capacity;
    tl_lists tl;
} tgl_state;

static void tgl_destroy(void *state)
{
    tgl_state *t = state;
    if (!t)
        return;
    glu_target_destroy(&t->target);
    if (t->buf[0])
        glDeleteBuffers(BUFS, t->buf);
    if (t->program)
        glDeleteProgram(t->program);
    free(t->gb.position);
    free(t->packed);
    free(t->reach);
    tl_destroy(&t->tl);
    free(t);
}

static eng_result tgl_create(int width, int height, int irradiance, void **state, eng_error *err)
{
    tgl_state *t = calloc(1, sizeof *t);
    if (!t)
        return eng_fail(err, ENG_ERR_NOMEM, "tile-gather-gl: out of memory");
    t->width = width;
    t->height = height;
    t->irradiance = irradiance;
    tl_create(&t->tl, width, height, 0);
    t->gb.width = width;
    t->gb.height = height;
    t->gb.position = eng_xmalloc((size_t)width * (size_t)height * 4 * sizeof(float));
    eng_result r = glu_compute_program("tile_gather.comp.glsl", &t->program, err);
    if (r == ENG_OK)
        r = glu_target_create(&t->target, irradiance ? 2 : 1, width, height, 0, err);
    if (r != ENG_OK) {
        tgl_destroy(t);
        return r;
    }
    glGenBuffers(BUFS, t->buf);
    glUseProgram(t->program);
    static const char *const samplers[] = {"u_position", "u_normal", "u_albedo", "u_material"};
    for (int i = 0; i < 4; i++)
        glUniform1i(glGetUniformLocation(t->program, samplers[i]), i);
    t->loc_eye = glGetUniformLocation(t->program, "u_eye");
    t->loc_irradiance = glGetUniformLocation(t->program, "u_irradiance");
    glUniform1i(t->loc_irradiance, irradiance);
    glUseProgram(0);
    *state = t;
    return ENG_OK;
}

/* Uploads `bytes` of data to buffer b (at least 4 bytes: an empty list is still bound). */
static void upload(GLuint b, size_t bytes, const void *data)
{
    static const uint32_t zero = 0;
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, b);
    glBufferData(GL_SHADER_STORAGE_BUFFER, bytes ? (GLsizeiptr)bytes : 4, bytes ? data : &zero, GL_STREAM_DRAW);
}

static eng_result tgl_run(void *state, const ind_input *in, ind_output *out, eng_error *err)
{
    tgl_state *t = state;
    const eng_photon_map *map = in->map;
    const eng_settings *s = in->s;
    const int threads = s->threads > 0 ? s->threads : 2;
    const int tx = t->tl.tiles_x, ty = t->tl.tiles_y;
    const size_t tiles = (size_t)tx * (size_t)ty, n = map->count;

    /* The lists (ind_tilelists.c); only the positions are read back, for the tile boxes. */
    static const int p4[] = {0, 1, 2, 3};
    glu_read(in->gbuf, 0, 0, 4, p4, t->gb.position);
    tl_prepare(&t->tl, &t->gb, in->fs->camera.eye, NULL, threads);
    tl_build(&t->tl, map, ind_reach(in, &t->reach, &t->reach_capacity), s->normal_compression,
             in->fs->camera.view_proj, threads);

    /* Photons as the shader's `photon`; r_z and the d² bound in the C gathers' float
     * operations (gather_kernel.h: rz = r·compression, r2 = r·r·1.001). */
    if (n > t->packed_capacity) {
        free(t->packed);
        t->packed = eng_xmalloc(n * 16 * sizeof(float));
        t->packed_capacity = n;
    }
    for (size_t i = 0; i < n; i++) {
        const eng_photon *ph = &map->photons[i];
        const float r = in->radius[i], su = in->aniso ? in->aniso[4 * i + 3] : 1.0f, ra = r * su;
        float *q = t->packed + 16 * i;
        for (int c = 0; c < 3; c++) {
            q[c] = ph->position[c];
            q[4 + c] = ph->normal[c];
            q[8 + c] = ph->direction[c];
            q[12 + c] = ph->power[c];
        }
        q[3] = r;
        q[7] = r * s->normal_compression;
        q[11] = ra * ra * 1.001f;
        q[15] = su; /* the anisotropic kernel's s_u (1: isotropic; photon_kernel.glsl) */
    }
    upload(t->buf[BUF_PHOTONS], n * 16 * sizeof(float), t->packed);
    upload(t->buf[BUF_OFFSETS], (tiles + 1) * sizeof(uint32_t), t->tl.offset);
    upload(t->buf[BUF_ENTRIES], (size_t)t->tl.offset[tiles] * sizeof(tl_entry), t->tl.entries);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);

    glUseProgram(t->program);
    glUniform3fv(t->loc_eye, 1, in->fs->camera.eye);
    for (int i = 0; i < BUFS; i++)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, (GLuint)i, t->buf[i]);
    for (int i = 0; i < 4; i++) {
        glActiveTexture(GL_TEXTURE0 + (GLenum)i);
        glBindTexture(GL_TEXTURE_2D, in->gbuf->color[i]);
    }
    for (int i = 0; i < t->target.count; i++)
        glBindImageTexture((GLuint)i, t->target.color[i], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glDispatchCompute((GLuint)tx, (GLuint)ty, 1);
    /* Later passes sample the result, and the frame loop reads it back. */
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT |
                    GL_PIXEL_BUFFER_BARRIER_BIT);
    for (int i = 0; i < t->target.count; i++)
        glBindImageTexture((GLuint)i, 0, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    for (int i = 3; i >= 0; i--) {
        glActiveTexture(GL_TEXTURE0 + (GLenum)i);
        glBindTexture(GL_TEXTURE_2D, 0);
    }
    for (int i = 0; i < BUFS; i++)
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, (GLuint)i, 0);
    glUseProgram(0);
    if (glGetError() != GL_NO_ERROR)
        return eng_fail(err, ENG_ERR_GL, "tile-gather-gl: GL error in the compute dispatch (%zu photons, %u entries)",
                        n, t->tl.offset[tiles]);

    static const char *const CH_Y[] = {"Y"};
    out->target = &t->target;
    out->extra_count = 1;
    out->extra[0] = (ind_extra){"gather.tile_count", tx, ty, 1, CH_Y, t->tl.tile_count};
    return ENG_OK;
}

const ind_method ind_tilegather_gl_method = {
    .name = "tile-gather-gl",
    .prefix = "gather",
    .pass = "gather",
    .create = tgl_create,
    .run = tgl_run,
    .destroy = tgl_destroy,
};
