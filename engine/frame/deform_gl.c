/* deform_gl.c — skinned and morphed draws for the passes: eng_deform.
 *
 * A draw whose node has a skin or morph targets (scn_node_deforms) gets its own VAO with
 * three dynamic vertex buffers — this frame's positions (location 0) and normals (1) and the
 * previous frame's positions (5, for the eye G-buffer's motion vectors), and a fourth for
 * tangents (6) where the primitive has them (normal maps) — and shares the
 * primitive's texcoord, colour and index buffers. Every frame both poses are computed on the
 * CPU (scn_deform, deform.c) from the frame's and the previous frame's world matrices and
 * morph weights, so motion vectors follow the deformed surface; the CPU copies are what the
 * Embree scene re-poses from (rt.c refits moved geometry) and what the bounds are taken of. */
#include "frame.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct deformed {
    uint32_t draw, node, prim;
    eng_gpu_prim gpu; /* own vao, vbo_pos, vbo_nrm, vbo_prev; the rest the primitive's */
    GLuint vbo_prev;
    float *pos, *nrm, *prev_pos, *prev_nrm;
    float *tan; /* deformed tangents (location 6) where the primitive has them, else NULL */
} deformed;

struct eng_deform {
    const scn_scene *scene;
    uint32_t count;
    deformed *items;
    float *weights, *prev_weights;
};

static GLuint dynamic_vbo(GLuint location, uint32_t vertices, int comps)
{
    GLuint b;
    glGenBuffers(1, &b);
    glBindBuffer(GL_ARRAY_BUFFER, b);
    glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)((size_t)vertices * (size_t)comps * sizeof(float)), NULL, GL_DYNAMIC_DRAW);
    glVertexAttribPointer(location, comps, GL_FLOAT, GL_FALSE, 0, NULL);
    glEnableVertexAttribArray(location);
    return b;
}

eng_deform *eng_deform_create(const scn_scene *s, const eng_gpu_prim *gpu)
{
    eng_deform *d = eng_xcalloc(1, sizeof *d);
    d->scene = s;
    /* The draws in pose_frame's order: nodes in order, each mesh's primitives in order. */
    for (int pass = 0; pass < 2; pass++) {
        uint32_t k = 0, draw = 0;
        for (uint32_t i = 0; i < s->node_count; i++) {
            if (s->nodes[i].mesh < 0)
                continue;
            const scn_mesh *m = &s->meshes[s->nodes[i].mesh];
            int deforms = scn_node_deforms(s, i);
            for (uint32_t p = 0; p < m->primitive_count; p++, draw++) {
                if (!deforms)
                    continue;
                if (pass == 1) {
                    d->items[k].draw = draw;
                    d->items[k].node = i;
                    d->items[k].prim = m->first_primitive + p;
                }
                k++;
            }
        }
        if (pass == 0) {
            d->count = k;
            d->items = eng_xcalloc(k, sizeof *d->items);
        }
    }
    d->weights = eng_xcalloc(s->weight_count, sizeof(float));
    d->prev_weights = eng_xcalloc(s->weight_count, sizeof(float));
    for (uint32_t k = 0; k < d->count; k++) {
        deformed *it = &d->items[k];
        const scn_primitive *p = &s->primitives[it->prim];
        const eng_gpu_prim *sg = &gpu[it->prim];
        size_t n3 = (size_t)p->vertex_count * 3;
        it->pos = eng_xcalloc(n3, sizeof(float));
        it->nrm = eng_xcalloc(n3, sizeof(float));
        it->prev_pos = eng_xcalloc(n3, sizeof(float));
        it->prev_nrm = eng_xcalloc(n3, sizeof(float));
        eng_gpu_prim *g = &it->gpu;
        *g = *sg;
        glGenVertexArrays(1, &g->vao);
        glBindVertexArray(g->vao);
        g->vbo_pos = dynamic_vbo(0, p->vertex_count, 3);
        g->vbo_nrm = dynamic_vbo(1, p->vertex_count, 3);
        it->vbo_prev = dynamic_vbo(5, p->vertex_count, 3);
        g->vbo_tan = 0;
        if (p->tangents) {
            it->tan = eng_xcalloc(n3 / 3 * 4, sizeof(float));
            g->vbo_tan = dynamic_vbo(6, p->vertex_count, 4);
        }
        const GLuint shared[3] = {sg->vbo_uv[0], sg->vbo_uv[1], sg->vbo_col};
        for (int a = 0; a < 3; a++) {
            if (!shared[a])
                continue;
            glBindBuffer(GL_ARRAY_BUFFER, shared[a]);
            glVertexAttribPointer((GLuint)(2 + a), a == 2 ? 4 : 2, GL_FLOAT, GL_FALSE, 0, NULL);
            glEnableVertexAttribArray((GLuint)(2 + a));
        }
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, sg->ibo);
        glBindVertexArray(0);
    }
    return d;
}

static void upload(GLuint vbo, const float *v, uint32_t vertices, int comps)
{
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)((size_t)vertices * (size_t)comps * sizeof(float)), v);
}

void eng_deform_pose(eng_deform *d, eng_frame_scene *fs, const float *world, const float *prev_world, double t,
                     double tp)
{
    if (!d || d->count == 0)
        return;
    const scn_scene *s = d->scene;
    scn_evaluate_weights(s, t, d->weights);
    scn_evaluate_weights(s, tp, d->prev_weights);
    for (uint32_t k = 0; k < d->count; k++) {
        deformed *it = &d->items[k];
        eng_draw *dr = &fs->draws[it->draw];
        const scn_primitive *p = &s->primitives[dr->primitive];
        int skinned = scn_deform_tangents(s, it->node, dr->primitive, world, d->weights, it->pos, it->nrm, it->tan);
        scn_deform(s, it->node, dr->primitive, prev_world, d->prev_weights, it->prev_pos, it->prev_nrm);
        if (skinned) {
            m4_identity(dr->world);
            m4_identity(dr->prev_world);
        }
        dr->positions = it->pos;
        dr->normals = it->nrm;
        dr->tangents = it->tan;
        dr->gpu = &it->gpu;
        upload(it->gpu.vbo_pos, it->pos, p->vertex_count, 3);
        upload(it->gpu.vbo_nrm, it->nrm, p->vertex_count, 3);
        upload(it->vbo_prev, it->prev_pos, p->vertex_count, 3);
        if (it->tan)
            upload(it->gpu.vbo_tan, it->tan, p->vertex_count, 4);
    }
    glBindBuffer(GL_ARRAY_BUFFER, 0);
}

void eng_deform_destroy(eng_deform *d)
{
    if (!d)
        return;
    for (uint32_t k = 0; k < d->count; k++) {
        deformed *it = &d->items[k];
        glDeleteBuffers(1, &it->gpu.vbo_pos);
        glDeleteBuffers(1, &it->gpu.vbo_nrm);
        glDeleteBuffers(1, &it->vbo_prev);
        if (it->gpu.vbo_tan)
            glDeleteBuffers(1, &it->gpu.vbo_tan);
        glDeleteVertexArrays(1, &it->gpu.vao);
        free(it->pos);
        free(it->nrm);
        free(it->prev_pos);
        free(it->prev_nrm);
        free(it->tan);
    }
    free(d->items);
    free(d->weights);
    free(d->prev_weights);
    free(d);
}
