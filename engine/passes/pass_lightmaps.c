/* pass_lightmaps.c — per light, the light-space G-buffer (ISPM 003_… §3 step 1b, §4.1: "an
 * emitter's G-buffer") and the bounce map (§4.2: emit one photon per texel, bounce it once
 * in a fragment shader, store the outgoing photon). Both use the light's views from
 * light_views (six cube faces for point lights, one frustum or ortho box otherwise), one
 * texture layer per face. The bounce shader reads the precomputed random maps as a 2D array
 * texture (layers: uniform, cosine hemisphere, sphere), uploaded once at creation.
 * Owns: the two programs and the random-map texture; the light_maps targets belong to the
 * caller (engine.c keeps one per light). */
#include "passes.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct pass_lightmaps {
    GLuint gprog, bprog, vao, rmap_tex;
    int rmap_size;
};

eng_result pass_lightmaps_create(const eng_random_maps *rm, pass_lightmaps **out, eng_error *err)
{
    *out = NULL;
    pass_lightmaps *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "lightmaps: out of memory");
    eng_result r = glu_program("lightgbuffer.vert.glsl", "lightgbuffer.frag.glsl", &p->gprog, err);
    if (r == ENG_OK)
        r = glu_program("fullscreen.vert.glsl", "bounce.frag.glsl", &p->bprog, err);
    if (r != ENG_OK) {
        pass_lightmaps_destroy(p);
        return r;
    }
    p->vao = glu_fullscreen_vao();
    /* Random maps as 256 × (size/256) texels per table. */
    p->rmap_size = (int)rm->size;
    int h = (int)(rm->size / 256);
    glGenTextures(1, &p->rmap_tex);
    glBindTexture(GL_TEXTURE_2D_ARRAY, p->rmap_tex);
    glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA32F, 256, h, 3, 0, GL_RGBA, GL_FLOAT, NULL);
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, 0, 256, h, 1, GL_RGBA, GL_FLOAT, rm->uniform);
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, 1, 256, h, 1, GL_RGBA, GL_FLOAT, rm->cosine);
    glTexSubImage3D(GL_TEXTURE_2D_ARRAY, 0, 0, 0, 2, 256, h, 1, GL_RGBA, GL_FLOAT, rm->sphere);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glUseProgram(p->bprog);
    glUniform1i(glGetUniformLocation(p->bprog, "u_lpos"), 0);
    glUniform1i(glGetUniformLocation(p->bprog, "u_lnrm"), 1);
    glUniform1i(glGetUniformLocation(p->bprog, "u_lalb"), 2);
    glUniform1i(glGetUniformLocation(p->bprog, "u_lmat"), 3);
    glUniform1i(glGetUniformLocation(p->bprog, "u_rmap"), 4);
    glUniform1i(glGetUniformLocation(p->bprog, "u_rmap_size"), p->rmap_size);
    *out = p;
    return ENG_OK;
}

void light_maps_release(light_maps *lm)
{
    glu_target_destroy(&lm->gbuffer);
    glu_target_destroy(&lm->bounce);
    lm->size = 0;
}

static void draw_scene(const pass_lightmaps *p, const eng_frame_scene *fs)
{
    GLint u_world = glGetUniformLocation(p->gprog, "u_world");
    GLint u_nm = glGetUniformLocation(p->gprog, "u_normal_matrix");
    GLint u_base = glGetUniformLocation(p->gprog, "u_base_color");
    GLint u_mat = glGetUniformLocation(p->gprog, "u_material");
    for (uint32_t i = 0; i < fs->draw_count; i++) {
        const eng_draw *d = &fs->draws[i];
        scn_material m = eng_material_of(fs->scene, d->material);
        if (m.alpha_mode == SCN_ALPHA_BLEND)
            continue; /* translucent: drawn by pass_translucent.c */
        float nm[9];
        m4_normal_matrix(nm, d->world);
        glUniformMatrix4fv(u_world, 1, GL_FALSE, d->world);
        glUniformMatrix3fv(u_nm, 1, GL_FALSE, nm);
        glUniform4fv(u_base, 1, m.base_color);
        glUniform4f(u_mat, m.roughness, m.metallic, m.transmission, m.ior);
        eng_bind_material(p->gprog, fs, d, &m);
        const eng_gpu_prim *g = d->gpu;
        glBindVertexArray(g->vao);
        glDrawElements(GL_TRIANGLES, g->index_count, GL_UNSIGNED_INT, NULL);
    }
    glBindVertexArray(0);
}

/* Per light <i> and face <f>: the light G-buffer's position, normal and albedo, then the bounce
 * map, assembled on the CPU from the bounce target's attachments (power RGB, direction XYZ,
 * path density ρp, ior). */
const pass_output pass_lightmaps_outputs[] = {
    {.name = "lightgbuffer.light<i>[.face<f>].position", .attachment = 0, .pick = {0, 1, 2}, .channels = {"X", "Y", "Z"}},
    {.name = "lightgbuffer.light<i>[.face<f>].normal", .attachment = 1, .pick = {0, 1, 2}, .channels = {"X", "Y", "Z"}},
    {.name = "lightgbuffer.light<i>[.face<f>].albedo", .attachment = 2, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {.name = "bounce.light<i>[.face<f>]",
     .attachment = PASS_OUT_CPU,
     .channels = {"R", "G", "B", "X", "Y", "Z", "density", "ior"}},
    {0},
};

eng_result pass_lightmaps_run(pass_lightmaps *p, const eng_frame_scene *fs, uint32_t light, int size,
                              const eng_rmap_frame *rf, light_maps *lm, eng_error *err)
{
    const eng_light_pose *l = &fs->lights[light];
    light_views(l, fs, &lm->views);
    int faces = lm->views.faces;
    if (lm->size != size || lm->gbuffer.layers != faces) {
        light_maps_release(lm);
        eng_result r = glu_target_create(&lm->gbuffer, 4, size, size, faces, err);
        if (r == ENG_OK)
            r = glu_target_create(&lm->bounce, 3, size, size, faces, err);
        if (r != ENG_OK) {
            light_maps_release(lm);
            return r;
        }
        lm->size = size;
    }

    /* Light-space G-buffer, one layer per face. */
    glUseProgram(p->gprog);
    GLint u_vp = glGetUniformLocation(p->gprog, "u_view_proj");
    glViewport(0, 0, size, size);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_CULL_FACE);
    const float zero[4] = {0, 0, 0, 0};
    const float one = 1.0f;
    for (int f = 0; f < faces; f++) {
        glu_target_bind_layer(&lm->gbuffer, f);
        for (int i = 0; i < 4; i++)
            glClearBufferfv(GL_COLOR, i, zero);
        glClearBufferfv(GL_DEPTH, 0, &one);
        glUniformMatrix4fv(u_vp, 1, GL_FALSE, lm->views.view_proj[f]);
        draw_scene(p, fs);
    }
    glDisable(GL_DEPTH_TEST);

    /* Bounce map over each layer of the light G-buffer. */
    glUseProgram(p->bprog);
    int type = l->type == SCN_LIGHT_POINT ? 0 : l->type == SCN_LIGHT_SPOT ? 1 : 2;
    GLuint g = p->bprog;
    glUniform1i(glGetUniformLocation(g, "u_size"), size);
    glUniform1i(glGetUniformLocation(g, "u_type"), type);
    glUniform3fv(glGetUniformLocation(g, "u_light_position"), 1, l->position);
    glUniform3fv(glGetUniformLocation(g, "u_light_direction"), 1, l->direction);
    glUniform3fv(glGetUniformLocation(g, "u_light_scale"), 1, l->radiance_scale);
    glUniform3f(glGetUniformLocation(g, "u_light_params"), l->range, cosf(l->inner_cone), cosf(l->outer_cone));
    glUniform1f(glGetUniformLocation(g, "u_extent"), light_view_extent(l, &lm->views));
    /* Lights with a size: a sphere's radius, or tan of a disc's angular radius. */
    glUniform1f(glGetUniformLocation(g, "u_radius"), type == 2 ? tanf(l->radius) : l->radius);
    glUniform1ui(glGetUniformLocation(g, "u_salt"), rf->salt);
    glUniform1i(glGetUniformLocation(g, "u_stratified"), rf->stratified);
    glUniform4fv(glGetUniformLocation(g, "u_offset"), 1, rf->offset);
    glUniform1i(glGetUniformLocation(g, "u_strata_log2"), rf->strata_log2);
    glUniform1ui(glGetUniformLocation(g, "u_strata_salt"), rf->strata_salt);
    GLint u_layer = glGetUniformLocation(g, "u_layer");
    for (int i = 0; i < 4; i++) {
        glActiveTexture(GL_TEXTURE0 + i);
        glBindTexture(GL_TEXTURE_2D_ARRAY, lm->gbuffer.color[i]);
    }
    glActiveTexture(GL_TEXTURE4);
    glBindTexture(GL_TEXTURE_2D_ARRAY, p->rmap_tex);
    glBindVertexArray(p->vao);
    for (int f = 0; f < faces; f++) {
        glu_target_bind_layer(&lm->bounce, f);
        glUniform1i(u_layer, f);
        glDrawArrays(GL_TRIANGLES, 0, 3);
    }
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glActiveTexture(GL_TEXTURE0);
    return ENG_OK;
}

void pass_lightmaps_destroy(pass_lightmaps *p)
{
    if (!p)
        return;
    if (p->rmap_tex)
        glDeleteTextures(1, &p->rmap_tex);
    if (p->vao)
        glDeleteVertexArrays(1, &p->vao);
    if (p->gprog)
        glDeleteProgram(p->gprog);
    if (p->bprog)
        glDeleteProgram(p->bprog);
    free(p);
}
