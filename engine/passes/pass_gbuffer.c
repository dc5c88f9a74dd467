/* pass_gbuffer.c — the eye G-buffer (ISPM 003_… §3, step "render the G-buffer from the eye";
 * §4.1 Table 1 lists what later passes read from it). One rasterisation of every draw into
 * six RGBA32F targets: world position, world normal, albedo, material parameters, eye
 * depth + material id + screen-space motion vector (from the previous frame's object and
 * camera transforms, or deformed poses; zero on frame 0), and emitted radiance. Owns its program and targets. */
#include "passes.h"

#include <stdlib.h>

struct pass_gbuffer {
    glu_target target;
    GLuint program;
    GLint u_world, u_prev_world, u_normal_matrix, u_view, u_view_proj, u_prev_view_proj, u_prev_view;
    GLint u_eye, u_base_color, u_material, u_material_id, u_double_sided, u_viewport, u_emissive;
};

eng_result pass_gbuffer_create(int width, int height, pass_gbuffer **out, eng_error *err)
{
    *out = NULL;
    pass_gbuffer *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "gbuffer: out of memory");
    eng_result r = glu_program("gbuffer.vert.glsl", "gbuffer.frag.glsl", &p->program, err);
    if (r == ENG_OK)
        r = glu_target_create(&p->target, 6, width, height, 0, err);
    if (r != ENG_OK) {
        pass_gbuffer_destroy(p);
        return r;
    }
    GLuint g = p->program;
    p->u_world = glGetUniformLocation(g, "u_world");
    p->u_prev_world = glGetUniformLocation(g, "u_prev_world");
    p->u_normal_matrix = glGetUniformLocation(g, "u_normal_matrix");
    p->u_view = glGetUniformLocation(g, "u_view");
    p->u_view_proj = glGetUniformLocation(g, "u_view_proj");
    p->u_prev_view_proj = glGetUniformLocation(g, "u_prev_view_proj");
    p->u_prev_view = glGetUniformLocation(g, "u_prev_view");
    p->u_eye = glGetUniformLocation(g, "u_eye");
    p->u_base_color = glGetUniformLocation(g, "u_base_color");
    p->u_material = glGetUniformLocation(g, "u_material");
    p->u_material_id = glGetUniformLocation(g, "u_material_id");
    p->u_double_sided = glGetUniformLocation(g, "u_double_sided");
    p->u_viewport = glGetUniformLocation(g, "u_viewport");
    p->u_emissive = glGetUniformLocation(g, "u_emissive");
    *out = p;
    return ENG_OK;
}

/* What the frame loop announces of the eye G-buffer, in this order. */
const pass_output pass_gbuffer_outputs[] = {
    {.name = "gbuffer.position", .attachment = 0, .pick = {0, 1, 2}, .channels = {"X", "Y", "Z"}},
    {.name = "gbuffer.normal", .attachment = 1, .pick = {0, 1, 2}, .channels = {"X", "Y", "Z"}},
    {.name = "gbuffer.albedo", .attachment = 2, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    /* Five channels from two attachments (3: the parameters, 4.y: the id), assembled on the CPU. */
    {.name = "gbuffer.material",
     .attachment = PASS_OUT_CPU,
     .channels = {"roughness", "metallic", "transmission", "ior", "id"}},
    {.name = "gbuffer.depth", .attachment = 4, .pick = {0}, .channels = {"Z"}},
    {.name = "gbuffer.motion", .attachment = 4, .pick = {2, 3}, .channels = {"X", "Y"}},
    {0},
};

/* The G-buffers of the subsampled levels the filters run on (<k>: the level, 1 = half size). */
const pass_output pass_gbuffer_level_outputs[] = {
    {.name = "gbuffer.level<k>.position", .attachment = 0, .pick = {0, 1, 2}, .channels = {"X", "Y", "Z"}},
    {.name = "gbuffer.level<k>.normal", .attachment = 1, .pick = {0, 1, 2}, .channels = {"X", "Y", "Z"}},
    {.name = "gbuffer.level<k>.depth", .attachment = 4, .pick = {0}, .channels = {"Z"}},
    {0},
};

const glu_target *pass_gbuffer_run(pass_gbuffer *p, const eng_frame_scene *fs)
{
    glu_target *t = &p->target;
    glBindFramebuffer(GL_FRAMEBUFFER, t->fbo);
    glViewport(0, 0, t->width, t->height);
    const float zero[4] = {0, 0, 0, 0};
    const float misc[4] = {0, -1, 0, 0}; /* background: no depth, material id −1, no motion */
    for (int i = 0; i < 4; i++)
        glClearBufferfv(GL_COLOR, i, zero);
    glClearBufferfv(GL_COLOR, 4, misc);
    glClearBufferfv(GL_COLOR, 5, zero);
    const float one = 1.0f;
    glClearBufferfv(GL_DEPTH, 0, &one);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glUseProgram(p->program);
    glUniformMatrix4fv(p->u_view, 1, GL_FALSE, fs->camera.view);
    glUniformMatrix4fv(p->u_view_proj, 1, GL_FALSE, fs->camera.view_proj);
    glUniformMatrix4fv(p->u_prev_view_proj, 1, GL_FALSE, fs->prev_camera.view_proj);
    glUniformMatrix4fv(p->u_prev_view, 1, GL_FALSE, fs->prev_camera.view);
    glUniform3fv(p->u_eye, 1, fs->camera.eye);
    glUniform2f(p->u_viewport, (float)t->width, (float)t->height);
    for (uint32_t i = 0; i < fs->draw_count; i++) {
        const eng_draw *d = &fs->draws[i];
        scn_material m = eng_material_of(fs->scene, d->material);
        if (m.alpha_mode == SCN_ALPHA_BLEND)
            continue; /* translucent: drawn by pass_translucent.c */
        float nm[9];
        m4_normal_matrix(nm, d->world);
        glUniformMatrix4fv(p->u_world, 1, GL_FALSE, d->world);
        glUniformMatrix4fv(p->u_prev_world, 1, GL_FALSE, d->prev_world);
        glUniformMatrix3fv(p->u_normal_matrix, 1, GL_FALSE, nm);
        glUniform4fv(p->u_base_color, 1, m.base_color);
        glUniform4f(p->u_material, m.roughness, m.metallic, m.transmission, m.ior);
        glUniform1f(p->u_material_id, (float)d->material);
        glUniform1i(p->u_double_sided, m.double_sided ? 1 : 0);
        glUniform3fv(p->u_emissive, 1, m.emissive);
        eng_bind_material(p->program, fs, d, &m);
        /* glTF: single-sided materials are culled from behind. */
        if (m.double_sided)
            glDisable(GL_CULL_FACE);
        else
            glEnable(GL_CULL_FACE);
        const eng_gpu_prim *g = d->gpu;
        glBindVertexArray(g->vao);
        glDrawElements(GL_TRIANGLES, g->index_count, GL_UNSIGNED_INT, NULL);
    }
    glBindVertexArray(0);
    glDisable(GL_CULL_FACE);
    glDisable(GL_DEPTH_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return t;
}

void pass_gbuffer_destroy(pass_gbuffer *p)
{
    if (!p)
        return;
    glu_target_destroy(&p->target);
    if (p->program)
        glDeleteProgram(p->program);
    free(p);
}
