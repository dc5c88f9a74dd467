/* pass_shadow.c — one shadow map per light (ISPM 003_… §3: "render a shadow map per light";
 * the light-space G-buffer of the photon passes will share these views). Point lights get
 * six 90° cube faces in the layers of a 2D array texture (GL's cube-face order +X −X +Y −Y
 * +Z −Z), spot lights one perspective view covering the outer cone, directional lights one
 * orthographic box around the scene bounds. Texels hold metric distances (see
 * shaders/shadow.frag.glsl), so a lookup needs only the face's view-projection matrix. */
#include "eng_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct pass_shadow {
    int size;
    uint32_t light_count;
    shadow_map *maps;
    GLuint program;
    GLint u_world, u_view_proj, u_mode, u_light_position, u_light_direction;
};

eng_result pass_shadow_create(int size, uint32_t light_count, pass_shadow **out, eng_error *err)
{
    *out = NULL;
    pass_shadow *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "shadow: out of memory");
    p->size = size;
    p->light_count = light_count;
    p->maps = calloc(light_count ? light_count : 1, sizeof *p->maps);
    if (!p->maps) {
        free(p);
        return eng_fail(err, ENG_ERR_NOMEM, "shadow: out of memory");
    }
    eng_result r = glu_program("shadow.vert.glsl", "shadow.frag.glsl", &p->program, err);
    if (r != ENG_OK) {
        pass_shadow_destroy(p);
        return r;
    }
    p->u_world = glGetUniformLocation(p->program, "u_world");
    p->u_view_proj = glGetUniformLocation(p->program, "u_view_proj");
    p->u_mode = glGetUniformLocation(p->program, "u_mode");
    p->u_light_position = glGetUniformLocation(p->program, "u_light_position");
    p->u_light_direction = glGetUniformLocation(p->program, "u_light_direction");
    *out = p;
    return ENG_OK;
}

static void ortho(float m[16], float half, float znear, float zfar)
{
    memset(m, 0, 16 * sizeof(float));
    m[0] = 1.0f / half;
    m[5] = 1.0f / half;
    m[10] = -2.0f / (zfar - znear);
    m[14] = -(zfar + znear) / (zfar - znear);
    m[15] = 1.0f;
}

void light_views(const eng_light_pose *l, const eng_frame_scene *fs, shadow_map *sm)
{
    float far = 0.0f;
    for (int c = 0; c < 8; c++) {
        float corner[3] = {(c & 1) ? fs->bounds_max[0] : fs->bounds_min[0],
                           (c & 2) ? fs->bounds_max[1] : fs->bounds_min[1],
                           (c & 4) ? fs->bounds_max[2] : fs->bounds_min[2]};
        float d[3] = {corner[0] - l->position[0], corner[1] - l->position[1], corner[2] - l->position[2]};
        float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (len > far)
            far = len;
    }
    far = far * 1.01f + 0.1f;
    float proj[16], view[16];
    if (l->type == SCN_LIGHT_POINT) {
        static const float dirs[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        static const float ups[6][3] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
        sm->faces = 6;
        m4_perspective(proj, (float)(ENG_PI / 2.0), 1.0f, 0.01f, far);
        for (int f = 0; f < 6; f++) {
            float target[3] = {l->position[0] + dirs[f][0], l->position[1] + dirs[f][1], l->position[2] + dirs[f][2]};
            m4_look_at(view, l->position, target, ups[f]);
            m4_mul(sm->view_proj[f], proj, view);
        }
        sm->far_value = far;
    } else if (l->type == SCN_LIGHT_SPOT) {
        sm->faces = 1;
        m4_perspective(proj, 2.0f * shadow_spot_half_angle(l->outer_cone), 1.0f, 0.01f, far);
        float target[3] = {l->position[0] + l->direction[0], l->position[1] + l->direction[1], l->position[2] + l->direction[2]};
        float up[3] = {0, 1, 0};
        if (fabsf(l->direction[1]) > 0.99f) {
            up[1] = 0;
            up[2] = 1;
        }
        m4_look_at(view, l->position, target, up);
        m4_mul(sm->view_proj[0], proj, view);
        sm->far_value = far;
    } else {
        /* Directional: the box's near plane sits one scene radius behind the scene centre;
         * eng_frame_scene gives directional lights that plane's centre as position. */
        float half = 0.0f;
        for (int i = 0; i < 3; i++) {
            float e = 0.5f * (fs->bounds_max[i] - fs->bounds_min[i]);
            half += e * e;
        }
        half = sqrtf(half) * 1.01f + 0.01f;
        sm->faces = 1;
        ortho(proj, half, 0.0f, 2.0f * half);
        float target[3] = {l->position[0] + l->direction[0], l->position[1] + l->direction[1], l->position[2] + l->direction[2]};
        float up[3] = {0, 1, 0};
        if (fabsf(l->direction[1]) > 0.99f) {
            up[1] = 0;
            up[2] = 1;
        }
        m4_look_at(view, l->position, target, up);
        m4_mul(sm->view_proj[0], proj, view);
        sm->far_value = 2.0f * half;
    }
}

const shadow_map *pass_shadow_run(pass_shadow *p, const eng_frame_scene *fs, uint32_t light)
{
    const eng_light_pose *l = &fs->lights[light];
    shadow_map *sm = &p->maps[light];
    light_views(l, fs, sm);
    if (sm->target.fbo && sm->target.layers != sm->faces)
        glu_target_destroy(&sm->target);
    if (!sm->target.fbo) {
        eng_error e;
        if (glu_target_create(&sm->target, 1, p->size, p->size, sm->faces, &e) != ENG_OK)
            return NULL;
    }
    glUseProgram(p->program);
    glUniform1i(p->u_mode, l->type == SCN_LIGHT_DIRECTIONAL ? 1 : 0);
    glUniform3fv(p->u_light_position, 1, l->position);
    glUniform3fv(p->u_light_direction, 1, l->direction);
    glViewport(0, 0, p->size, p->size);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE); /* both sides cast shadows */
    for (int f = 0; f < sm->faces; f++) {
        glu_target_bind_layer(&sm->target, f);
        const float clear[4] = {sm->far_value, 0, 0, 1};
        glClearBufferfv(GL_COLOR, 0, clear);
        const float one = 1.0f;
        glClearBufferfv(GL_DEPTH, 0, &one);
        glUniformMatrix4fv(p->u_view_proj, 1, GL_FALSE, sm->view_proj[f]);
        for (uint32_t i = 0; i < fs->draw_count; i++) {
            const eng_draw *d = &fs->draws[i];
            glUniformMatrix4fv(p->u_world, 1, GL_FALSE, d->world);
            scn_material m = eng_material_of(fs->scene, d->material);
            if (m.alpha_mode == SCN_ALPHA_BLEND)
                continue; /* translucent: pass_translucent.c */
            glUniform4fv(glGetUniformLocation(p->program, "u_base_color"), 1, m.base_color);
            eng_bind_material(p->program, fs, d, &m);
            const eng_gpu_prim *g = d->gpu;
            glBindVertexArray(g->vao);
            glDrawElements(GL_TRIANGLES, g->index_count, GL_UNSIGNED_INT, NULL);
        }
    }
    glBindVertexArray(0);
    glDisable(GL_DEPTH_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return sm;
}

void pass_shadow_destroy(pass_shadow *p)
{
    if (!p)
        return;
    for (uint32_t i = 0; i < p->light_count; i++)
        glu_target_destroy(&p->maps[i].target);
    free(p->maps);
    if (p->program)
        glDeleteProgram(p->program);
    free(p);
}
