/* ind_quads.c — `"indirect": "quads"`: photon quads (Yao 2011, 001_… §3.3). Every photon-map
 * photon becomes one camera-independent square of two triangles on its tangent plane (centre
 * the photon position x, plane ⟂ the photon's surface normal n_p, half-size r_xy =
 * ind_input.radius, the kernel radius every method uses, 003_… §5.1), drawn instanced into
 * the eye view; shaders/quads.frag.glsl evaluates the photon estimate against the eye G-buffer
 * with a flat kernel (shaders/quad_kernel.glsl: 2D Epanechnikov on the tangent plane, a slab
 * |d·n_p| ≤ r_z = normal_compression · r_xy, 001 Eq. (1)'s normal weighting) and the photon
 * volumes' BSDF (003 §5 Eq. 1, splat.frag.glsl), and additive blending sums the contributions.
 * In irradiance mode (the filters) quads_irradiance.frag.glsl writes E and the glossy part.
 *
 * Depth test: none. The quad lies in the surface it lights, so its depth equals the G-buffer's
 * up to rounding and a depth test would z-fight (an offset would trade that for light on
 * occluders just in front); instead the fragment stage reads the visible point s of its pixel
 * and rejects it unless s lies in the quad's slab and disk — a pixel whose visible surface is
 * not at the quad fails that test, which is all a depth test would have rejected. The cost is
 * that quads hidden behind other surfaces are shaded (and rejected) too. No face culling: a
 * quad has no inside.
 * Near plane: a quad crossing the near plane is clipped, but only where it lies in front of
 * the near plane, where no visible surface is; the visible part of the surface keeps the whole
 * photon. So the photon volumes' clipping artifact (003 §6.3) cannot happen on the photon's own
 * plane (001 §5).
 * Corners: the kernel is flat, so the other surface of a corner receives nothing from the
 * photon (normal weighting 0 at a right angle) and corners are darker than with the volumes
 * or the gathers, whose ellipsoid reaches both surfaces (001 §5, Fig. 5.8/5.9).
 *
 * Determinism: llvmpipe bins primitives per tile and each tile is rasterised by one thread in
 * submission order (photon order here), so the float sums are the same whatever
 * LP_NUM_THREADS is (as in ind_scatter_splat.c).
 *
 * Buffers "splat.*" (a scatter, like the photon volumes), pass "quads". Owns its program, the unit quad, the instance buffer and its
 * target. */
#include "indirect.h"

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Per-instance attributes, 16 floats (the photon volumes' layout, ind_scatter_splat.c); stretch: the
 * anisotropic kernel's s_u (1: isotropic; quad_kernel.glsl). */
typedef struct quad_instance {
    float position[3], normal[3], power[3], direction[3], radius[2], stretch, pad;
} quad_instance;

typedef struct quads_state {
    glu_target target;
    GLuint program, program_aniso, vao, vbo_quad, vbo_inst; /* program_aniso: PHOTON_ANISO, on first use */
    GLuint program_scale[2]; /* PIXEL_SCALE (per-pixel radii; [1] also PHOTON_ANISO), on first use */
    GLuint scale_tex;        /* their u_pixel_scale (pixel_scale_upload) */
    float *scale_rows;
    int irradiance;
    size_t inst_capacity;
    quad_instance *inst; /* inst_capacity instances, CPU side */
} quads_state;

static void quads_destroy(void *state)
{
    quads_state *q = state;
    if (!q)
        return;
    glu_target_destroy(&q->target);
    if (q->vao)
        glDeleteVertexArrays(1, &q->vao);
    GLuint bufs[2] = {q->vbo_quad, q->vbo_inst};
    glDeleteBuffers(2, bufs);
    if (q->program)
        glDeleteProgram(q->program);
    if (q->program_aniso)
        glDeleteProgram(q->program_aniso);
    for (int k = 0; k < 2; k++)
        if (q->program_scale[k])
            glDeleteProgram(q->program_scale[k]);
    if (q->scale_tex)
        glDeleteTextures(1, &q->scale_tex);
    free(q->scale_rows);
    free(q->inst);
    free(q);
}

/* The quads program (PHOTON_ANISO with aniso, PIXEL_SCALE with scale) into *prog, samplers set. */
static eng_result quads_program(int irradiance, int aniso, int scale, GLuint *prog, eng_error *err)
{
    static const char *const defines[4] = {NULL, "#define PHOTON_ANISO\n", "#define PIXEL_SCALE\n",
                                            "#define PIXEL_SCALE\n#define PHOTON_ANISO\n"};
    eng_result r = glu_program_defines("quads.vert.glsl", irradiance ? "quads_irradiance.frag.glsl" : "quads.frag.glsl",
                                       defines[(aniso ? 1 : 0) + (scale ? 2 : 0)], prog, err);
    if (r != ENG_OK)
        return r;
    glUseProgram(*prog);
    glUniform1i(glGetUniformLocation(*prog, "u_position"), 0);
    glUniform1i(glGetUniformLocation(*prog, "u_normal"), 1);
    glUniform1i(glGetUniformLocation(*prog, "u_albedo"), 2);
    glUniform1i(glGetUniformLocation(*prog, "u_material"), 3);
    if (scale)
        glUniform1i(glGetUniformLocation(*prog, "u_pixel_scale"), 4);
    glUseProgram(0);
    return ENG_OK;
}

static eng_result quads_create(int width, int height, int irradiance, void **state, eng_error *err)
{
    *state = NULL;
    quads_state *q = calloc(1, sizeof *q);
    if (!q)
        return eng_fail(err, ENG_ERR_NOMEM, "quads: out of memory");
    q->irradiance = irradiance;
    eng_result r = quads_program(irradiance, 0, 0, &q->program, err);
    if (r == ENG_OK)
        r = glu_target_create(&q->target, irradiance ? 2 : 1, width, height, 0, err);
    if (r != ENG_OK) {
        quads_destroy(q);
        return r;
    }
    /* A triangle strip: (−1,−1) (1,−1) (−1,1) (1,1). The two triangles share the diagonal, and
     * GL's fill rule gives each pixel centre on it to exactly one of them. */
    static const float corners[8] = {-1, -1, 1, -1, -1, 1, 1, 1};
    glGenVertexArrays(1, &q->vao);
    glBindVertexArray(q->vao);
    glGenBuffers(1, &q->vbo_quad);
    glBindBuffer(GL_ARRAY_BUFFER, q->vbo_quad);
    glBufferData(GL_ARRAY_BUFFER, sizeof corners, corners, GL_STATIC_DRAW);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 0, NULL);
    glEnableVertexAttribArray(0);
    glGenBuffers(1, &q->vbo_inst);
    glBindBuffer(GL_ARRAY_BUFFER, q->vbo_inst);
    const GLsizei stride = sizeof(quad_instance);
    const size_t offs[6] = {offsetof(quad_instance, position), offsetof(quad_instance, normal),
                            offsetof(quad_instance, power),    offsetof(quad_instance, direction),
                            offsetof(quad_instance, radius),   offsetof(quad_instance, stretch)};
    for (int a = 0; a < 6; a++) {
        glVertexAttribPointer(1 + a, a == 5 ? 1 : a == 4 ? 2 : 3, GL_FLOAT, GL_FALSE, stride, (const void *)offs[a]);
        glVertexAttribDivisor(1 + a, 1);
        glEnableVertexAttribArray(1 + a);
    }
    glBindVertexArray(0);
    *state = q;
    return ENG_OK;
}

static eng_result quads_run(void *state, const ind_input *in, ind_output *out, eng_error *err)
{
    quads_state *q = state;
    const eng_photon_map *map = in->map;
    const eng_settings *s = in->s;
    glu_target *t = &q->target;
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glViewport(0, 0, t->width, t->height);
    const float zero[4] = {0, 0, 0, 0};
    for (int i = 0; i < t->count; i++)
        glClearBufferfv(GL_COLOR, i, zero);
    if (map->count > 0) {
        if (map->count > q->inst_capacity) {
            free(q->inst);
            q->inst = malloc(map->count * sizeof(quad_instance));
            if (!q->inst) {
                fprintf(stderr, "ispm: out of memory\n");
                abort();
            }
            q->inst_capacity = map->count;
            glBindBuffer(GL_ARRAY_BUFFER, q->vbo_inst);
            glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(q->inst_capacity * sizeof(quad_instance)), NULL,
                         GL_STREAM_DRAW);
        }
        quad_instance *inst = q->inst;
        for (size_t i = 0; i < map->count; i++) {
            const eng_photon *ph = &map->photons[i];
            quad_instance *d = &inst[i];
            memcpy(d->position, ph->position, sizeof d->position);
            memcpy(d->normal, ph->normal, sizeof d->normal);
            memcpy(d->power, ph->power, sizeof d->power);
            memcpy(d->direction, ph->direction, sizeof d->direction);
            d->radius[0] = in->radius[i];
            d->radius[1] = d->radius[0] * s->normal_compression;
            d->stretch = in->aniso ? in->aniso[4 * i + 3] : 1.0f;
            d->pad = 0.0f;
        }
        glBindBuffer(GL_ARRAY_BUFFER, q->vbo_inst);
        glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)(map->count * sizeof *inst), inst);

        GLuint *slot = in->pixel_scale ? &q->program_scale[in->aniso ? 1 : 0]
                                       : in->aniso ? &q->program_aniso
                                                   : &q->program;
        if (!*slot) {
            eng_result r = quads_program(q->irradiance, in->aniso != NULL, in->pixel_scale != NULL, slot, err);
            if (r != ENG_OK)
                return r;
        }
        if (in->pixel_scale) { /* per-pixel radii (ind_input.pixel_scale): texture unit 4 */
            pixel_scale_upload(&q->scale_tex, &q->scale_rows, q->target.width, q->target.height, in->pixel_scale);
            glActiveTexture(GL_TEXTURE4);
            glBindTexture(GL_TEXTURE_2D, q->scale_tex);
        }
        const GLuint prog = *slot;
        glUseProgram(prog);
        glUniformMatrix4fv(glGetUniformLocation(prog, "u_view_proj"), 1, GL_FALSE, in->fs->camera.view_proj);
        glUniform3fv(glGetUniformLocation(prog, "u_eye"), 1, in->fs->camera.eye);
        for (int i = 0; i < 4; i++) {
            glActiveTexture(GL_TEXTURE0 + i);
            glBindTexture(GL_TEXTURE_2D, in->gbuf->color[i]);
        }
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glEnable(GL_BLEND);
        glBlendFunc(GL_ONE, GL_ONE);
        glBlendEquation(GL_FUNC_ADD);
        glBindVertexArray(q->vao);
        glDrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, (GLsizei)map->count);
        glBindVertexArray(0);
        glDisable(GL_BLEND);
        glActiveTexture(GL_TEXTURE0);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    out->target = t;
    out->extra_count = 0;
    return ENG_OK;
}

const ind_method ind_quads_method = {
    .name = "quads",
    .prefix = "splat",
    .pass = "quads",
    .create = quads_create,
    .run = quads_run,
    .destroy = quads_destroy,
    .per_pixel_radius = 1,
};
