/* pass_splat.c — indirect light by scattering photon volumes (ISPM 003_… §5, Eq. 1–3): every
 * photon-map photon becomes an instanced icosahedron bounding its kernel ellipsoid; the
 * fragment shader evaluates Eq. 1 against the eye G-buffer and additive blending sums the
 * contributions (see shaders/splat.frag.glsl for the kernel). The volumes are depth-tested
 * against the eye G-buffer's own depth buffer, so a volume entirely in front of or behind the
 * visible surface costs no shading; back faces only, so each pixel is shaded once per photon.
 * Known artifact (§6.3): where the near plane clips a volume's back faces, the surface behind
 * gets nothing from that photon.
 *
 * Determinism: llvmpipe bins primitives per tile and each tile is rasterised by one thread in
 * submission order, so the float sums are the same whatever LP_NUM_THREADS is.
 * Owns its program, the icosahedron, the instance buffer and its target. */
#include "eng_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct pass_splat {
    glu_target target;
    GLuint program, vao, vbo_ico, ibo_ico, vbo_inst;
    size_t inst_capacity;
};

/* Per-instance attributes, 16 floats. */
typedef struct splat_instance {
    float position[3], normal[3], power[3], direction[3], radius[2], pad[2];
} splat_instance;

float splat_radius(float kernel_radius, float rho)
{
    float s = rho > 0.0f ? powf(1000.0f * rho, -0.25f) : 2.0f;
    if (s < 0.25f)
        s = 0.25f;
    if (s > 2.0f)
        s = 2.0f;
    return kernel_radius * s;
}

float splat_kernel(const float d[3], const float n_p[3], float r_xy, float r_z)
{
    double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
    double t = 0.0;
    if (len > 0.0) {
        double c = fabs((double)d[0] * n_p[0] + (double)d[1] * n_p[1] + (double)d[2] * n_p[2]) / len;
        t = len / r_xy * (1.0 + c * (r_xy - r_z) / r_z);
    }
    if (t >= 1.0)
        return 0.0f;
    return (float)(2.0 / (ENG_PI * (double)r_xy * r_xy) * (1.0 - t * t));
}

static void make_icosahedron(float v[12][3], unsigned idx[60])
{
    const float t = (1.0f + sqrtf(5.0f)) * 0.5f;
    const float raw[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    const unsigned faces[60] = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4,
                                11, 10, 2, 10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8,
                                3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    float len = sqrtf(1.0f + t * t);
    for (int i = 0; i < 12; i++)
        for (int c = 0; c < 3; c++)
            v[i][c] = raw[i][c] / len; /* circumradius 1; the shader scales by 1/inradius */
    memcpy(idx, faces, sizeof faces);
}

eng_result pass_splat_create(int width, int height, int irradiance, pass_splat **out, eng_error *err)
{
    *out = NULL;
    pass_splat *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "splat: out of memory");
    eng_result r = glu_program("splat.vert.glsl", irradiance ? "splat_irradiance.frag.glsl" : "splat.frag.glsl",
                               &p->program, err);
    if (r == ENG_OK)
        r = glu_target_create(&p->target, irradiance ? 2 : 1, width, height, 0, err);
    if (r != ENG_OK) {
        pass_splat_destroy(p);
        return r;
    }
    float v[12][3];
    unsigned idx[60];
    make_icosahedron(v, idx);
    glGenVertexArrays(1, &p->vao);
    glBindVertexArray(p->vao);
    glGenBuffers(1, &p->vbo_ico);
    glBindBuffer(GL_ARRAY_BUFFER, p->vbo_ico);
    glBufferData(GL_ARRAY_BUFFER, sizeof v, v, GL_STATIC_DRAW);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, NULL);
    glEnableVertexAttribArray(0);
    glGenBuffers(1, &p->ibo_ico);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, p->ibo_ico);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, sizeof idx, idx, GL_STATIC_DRAW);
    glGenBuffers(1, &p->vbo_inst);
    glBindBuffer(GL_ARRAY_BUFFER, p->vbo_inst);
    const GLsizei stride = sizeof(splat_instance);
    const size_t offs[5] = {offsetof(splat_instance, position), offsetof(splat_instance, normal),
                            offsetof(splat_instance, power), offsetof(splat_instance, direction),
                            offsetof(splat_instance, radius)};
    for (int a = 0; a < 5; a++) {
        glVertexAttribPointer(1 + a, a == 4 ? 2 : 3, GL_FLOAT, GL_FALSE, stride, (const void *)offs[a]);
        glVertexAttribDivisor(1 + a, 1);
        glEnableVertexAttribArray(1 + a);
    }
    glBindVertexArray(0);
    glUseProgram(p->program);
    glUniform1i(glGetUniformLocation(p->program, "u_position"), 0);
    glUniform1i(glGetUniformLocation(p->program, "u_normal"), 1);
    glUniform1i(glGetUniformLocation(p->program, "u_albedo"), 2);
    glUniform1i(glGetUniformLocation(p->program, "u_material"), 3);
    *out = p;
    return ENG_OK;
}

const glu_target *pass_splat_run(pass_splat *p, const eng_frame_scene *fs, const glu_target *gbuf,
                                 const eng_photon_map *map, const float *radius, const eng_settings *s)
{
    glu_target *t = &p->target;
    /* Share the eye G-buffer's depth buffer for the depth test. */
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, gbuf->depth);
    glViewport(0, 0, t->width, t->height);
    const float zero[4] = {0, 0, 0, 0};
    for (int i = 0; i < t->count; i++)
        glClearBufferfv(GL_COLOR, i, zero);
    if (map->count > 0) {
        if (map->count > p->inst_capacity) {
            p->inst_capacity = map->count;
            glBindBuffer(GL_ARRAY_BUFFER, p->vbo_inst);
            glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(p->inst_capacity * sizeof(splat_instance)), NULL,
                         GL_STREAM_DRAW);
        }
        splat_instance *inst = malloc(map->count * sizeof *inst);
        if (!inst) {
            fprintf(stderr, "ispm: out of memory\n");
            abort();
        }
        for (size_t i = 0; i < map->count; i++) {
            const eng_photon *ph = &map->photons[i];
            splat_instance *d = &inst[i];
            memcpy(d->position, ph->position, sizeof d->position);
            memcpy(d->normal, ph->normal, sizeof d->normal);
            memcpy(d->power, ph->power, sizeof d->power);
            memcpy(d->direction, ph->direction, sizeof d->direction);
            d->radius[0] = radius[i];
            d->radius[1] = d->radius[0] * s->normal_compression;
            d->pad[0] = d->pad[1] = 0.0f;
        }
        glBindBuffer(GL_ARRAY_BUFFER, p->vbo_inst);
        glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)(map->count * sizeof *inst), inst);
        free(inst);

        glUseProgram(p->program);
        glUniformMatrix4fv(glGetUniformLocation(p->program, "u_view_proj"), 1, GL_FALSE, fs->camera.view_proj);
        glUniform3fv(glGetUniformLocation(p->program, "u_eye"), 1, fs->camera.eye);
        for (int i = 0; i < 4; i++) {
            glActiveTexture(GL_TEXTURE0 + i);
            glBindTexture(GL_TEXTURE_2D, gbuf->color[i]);
        }
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_GEQUAL);
        glDepthMask(GL_FALSE);
        glEnable(GL_CULL_FACE);
        glCullFace(GL_FRONT);
        glEnable(GL_BLEND);
        glBlendFunc(GL_ONE, GL_ONE);
        glBlendEquation(GL_FUNC_ADD);
        glBindVertexArray(p->vao);
        glDrawElementsInstanced(GL_TRIANGLES, 60, GL_UNSIGNED_INT, NULL, (GLsizei)map->count);
        glBindVertexArray(0);
        glDisable(GL_BLEND);
        glCullFace(GL_BACK);
        glDisable(GL_CULL_FACE);
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
    GLuint bufs[3] = {p->vbo_ico, p->ibo_ico, p->vbo_inst};
    glDeleteBuffers(3, bufs);
    if (p->program)
        glDeleteProgram(p->program);
    free(p);
}
