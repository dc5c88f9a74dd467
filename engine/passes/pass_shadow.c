/* pass_shadow.c — one shadow map per light (ISPM 003_… §3: "render a shadow map per light";
 * the light-space G-buffer of the photon passes will share these views). Point lights get
 * six 90° cube faces in the layers of a 2D array texture (GL's cube-face order +X −X +Y −Y
 * +Z −Z), spot lights one perspective view covering the outer cone, directional lights one
 * orthographic box around the scene bounds. Texels hold metric distances (see
 * shaders/shadow.frag.glsl), so a lookup needs only the face's view-projection matrix. */
#include "passes.h"

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

/* Light <i>'s shadow map, per face: metric depth. */
const pass_output pass_shadow_outputs[] = {
    {.name = "shadow.light<i>[.face<f>]", .attachment = 0, .pick = {0}, .channels = {"Z"}},
    {0},
};

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
