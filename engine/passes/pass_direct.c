/* pass_direct.c — direct illumination by deferred shading (ISPM 003_… §3: direct light and
 * shadows are rasterised as usual; only indirect light comes from photons). A fullscreen
 * pass over the eye G-buffer with every light's shadow map; the BSDF and light models are
 * documented in shaders/direct.frag.glsl. Owns its program and its radiance target. */
#include "passes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define DIRECT_MAX_LIGHTS 8
#define SHADOW_UNIT0 4
#define BLOCKER_UNIT0 (SHADOW_UNIT0 + DIRECT_MAX_LIGHTS)

struct pass_direct {
    glu_pass pass;
};

eng_result pass_direct_create(int width, int height, int pcss_rays, pass_direct **out, eng_error *err)
{
    *out = NULL;
    pass_direct *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "direct: out of memory");
    /* Attachments: 0 radiance, 1 penumbra (shadow_pcss.glsl). */
    eng_result r = glu_pass_create(&p->pass, "direct.frag.glsl", 2, width, height, err);
    if (r != ENG_OK) {
        free(p);
        return r;
    }
    if (pcss_rays) { /* the same pass with the rays compiled in instead of the filter */
        glDeleteProgram(p->pass.program);
        p->pass.program = 0;
        r = glu_program_defines("fullscreen.vert.glsl", "direct.frag.glsl", "#define PCSS_RAYS 1\n", &p->pass.program,
                                err);
        if (r != ENG_OK) {
            pass_direct_destroy(p);
            return r;
        }
    }
    GLuint g = p->pass.program;
    glUseProgram(g);
    glUniform1i(glGetUniformLocation(g, "u_position"), 0);
    glUniform1i(glGetUniformLocation(g, "u_normal"), 1);
    glUniform1i(glGetUniformLocation(g, "u_albedo"), 2);
    glUniform1i(glGetUniformLocation(g, "u_material"), 3);
    for (int i = 0; i < DIRECT_MAX_LIGHTS; i++) {
        char name[32];
        snprintf(name, sizeof name, "u_shadow[%d]", i);
        glUniform1i(glGetUniformLocation(g, name), SHADOW_UNIT0 + i);
        snprintf(name, sizeof name, "u_blocker[%d]", i);
        glUniform1i(glGetUniformLocation(g, name), BLOCKER_UNIT0 + i);
    }
    *out = p;
    return ENG_OK;
}

static GLint loc(GLuint prog, const char *fmt, int i)
{
    char name[64];
    snprintf(name, sizeof name, fmt, i);
    return glGetUniformLocation(prog, name);
}

float pass_direct_shadow_texel(const eng_light_pose *l, const shadow_map *sm, const eng_settings *s)
{
    /* World size of one shadow texel: per unit distance for perspective views, absolute for
     * the directional ortho box (whose far value is its depth = 2·half-width). */
    if (l->type == SCN_LIGHT_POINT)
        return 2.0f / (float)s->shadow_map_size;
    if (l->type == SCN_LIGHT_SPOT)
        return 2.0f * tanf(shadow_spot_half_angle(l->outer_cone)) / (float)s->shadow_map_size;
    return sm->far_value / (float)s->shadow_map_size;
}

/* Radiance, and the penumbra width where a light has a size (optional: runs of punctual lights
 * announce no direct.penumbra). */
const pass_output pass_direct_outputs[] = {
    {.name = "direct.radiance", .attachment = 0, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {.name = "direct.penumbra", .attachment = 1, .pick = {0}, .channels = {"Y"}, .optional = 1},
    {0},
};

const glu_target *pass_direct_run(pass_direct *p, const eng_frame_scene *fs, const glu_target *gbuf,
                                  const shadow_map *const *shadows, const glu_target *const *extra,
                                  const eng_settings *s)
{
    GLuint g = p->pass.program;
    glUseProgram(g);
    for (int i = 0; i < 4; i++) {
        glActiveTexture(GL_TEXTURE0 + i);
        glBindTexture(GL_TEXTURE_2D, gbuf->color[i]);
    }
    int n = (int)(fs->light_count < DIRECT_MAX_LIGHTS ? fs->light_count : DIRECT_MAX_LIGHTS);
    glUniform1i(glGetUniformLocation(g, "u_light_count"), n);
    for (int i = 0; i < n; i++) {
        const eng_light_pose *l = &fs->lights[i];
        const shadow_map *sm = shadows[i];
        int type = l->type == SCN_LIGHT_POINT ? 0 : l->type == SCN_LIGHT_SPOT ? 1 : 2;
        glUniform1i(loc(g, "u_light_type[%d]", i), type);
        glUniform3fv(loc(g, "u_light_position[%d]", i), 1, l->position);
        glUniform3fv(loc(g, "u_light_direction[%d]", i), 1, l->direction);
        glUniform3fv(loc(g, "u_light_scale[%d]", i), 1, l->radiance_scale);
        glUniform3f(loc(g, "u_light_params[%d]", i), l->range, cosf(l->inner_cone), cosf(l->outer_cone));
        float texel = pass_direct_shadow_texel(l, sm, s);
        glUniform1f(loc(g, "u_shadow_texel[%d]", i), texel);
        for (int f = 0; f < sm->faces; f++)
            glUniformMatrix4fv(loc(g, "u_shadow_view_proj[%d]", i * 6 + f), 1, GL_FALSE, sm->view_proj[f]);
        glActiveTexture(GL_TEXTURE0 + SHADOW_UNIT0 + i);
        glBindTexture(GL_TEXTURE_2D_ARRAY, sm->target.color[0]);
        /* Soft shadows (shadow_pcss.glsl) where the light has a size (shadow_method_index):
         * a sphere's radius, or tan of a disc's angular radius, and the blocker map unless
         * the rays find the occluders. */
        float radius = l->radius > 0.0f ? (type == 2 ? tanf(l->radius) : l->radius) : 0.0f;
        glUniform1f(loc(g, "u_light_radius[%d]", i), radius);
        if (extra[i]) {
            glActiveTexture(GL_TEXTURE0 + BLOCKER_UNIT0 + i);
            glBindTexture(GL_TEXTURE_2D_ARRAY, extra[i]->color[0]);
        }
    }
    glUniform1i(glGetUniformLocation(g, "u_shadow_size"), s->shadow_map_size);
    glUniform1i(glGetUniformLocation(g, "u_pcf_radius"), s->pcf_radius);
    glUniform1f(glGetUniformLocation(g, "u_shadow_bias"), s->shadow_bias);
    glUniform3fv(glGetUniformLocation(g, "u_eye"), 1, fs->camera.eye);
    float inv[16];
    m4_invert(inv, fs->camera.view_proj);
    glUniformMatrix4fv(glGetUniformLocation(g, "u_inv_view_proj"), 1, GL_FALSE, inv);
    glUniform2f(glGetUniformLocation(g, "u_viewport"), (float)p->pass.target.width, (float)p->pass.target.height);

    glu_pass_draw(&p->pass);
    return &p->pass.target;
}

void pass_direct_destroy(pass_direct *p)
{
    if (!p)
        return;
    glu_pass_destroy(&p->pass);
    free(p);
}
