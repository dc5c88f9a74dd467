/* pass_composite.c — the last pass (ISPM 003_… §3: "composite direct and indirect"): linear
 * radiance = direct + indirect + specular (what the eye sees through mirrors and glass,
 * specular.h) + emission (gbuffer.emission), then the translucent surfaces laid over it
 * (translucent.radiance, premultiplied: rgb + (1 − a)·opaque; pass_translucent.c), and a display-referred copy (exposure, clamp, sRGB). The
 * indirect input is 0 until the photon passes exist; the pass is written for both. */
#include "passes.h"

#include <stdlib.h>

struct pass_composite {
    glu_pass pass;
    GLuint occlusion_tex; /* 0: indirect light not multiplied */
};

eng_result pass_composite_create(int width, int height, pass_composite **out, eng_error *err)
{
    *out = NULL;
    pass_composite *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "composite: out of memory");
    eng_result r = glu_pass_create(&p->pass, "composite.frag.glsl", 2, width, height, err);
    if (r != ENG_OK) {
        free(p);
        return r;
    }
    GLuint g = p->pass.program;
    glUseProgram(g);
    glUniform1i(glGetUniformLocation(g, "u_direct"), 0);
    glUniform1i(glGetUniformLocation(g, "u_indirect"), 1);
    glUniform1i(glGetUniformLocation(g, "u_specular"), 2);
    glUniform1i(glGetUniformLocation(g, "u_emission"), 3);
    glUniform1i(glGetUniformLocation(g, "u_translucent"), 4);
    glUniform1i(glGetUniformLocation(g, "u_occlusion"), 5);
    *out = p;
    return ENG_OK;
}

void pass_composite_set_occlusion(pass_composite *p, GLuint tex)
{
    p->occlusion_tex = tex;
}

const pass_output pass_composite_outputs[] = {
    {.name = "composite.radiance", .attachment = 0, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {.name = "final.display", .attachment = 1, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {0},
};

const glu_target *pass_composite_run(pass_composite *p, GLuint direct_tex, GLuint indirect_tex,
                                     GLuint specular_tex, GLuint emission_tex, GLuint translucent_tex,
                                     const eng_settings *s)
{
    GLuint g = p->pass.program;
    glUseProgram(g);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, direct_tex);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, indirect_tex);
    glUniform1i(glGetUniformLocation(g, "u_has_indirect"), indirect_tex ? 1 : 0);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, specular_tex);
    glUniform1i(glGetUniformLocation(g, "u_has_specular"), specular_tex ? 1 : 0);
    glActiveTexture(GL_TEXTURE3);
    glBindTexture(GL_TEXTURE_2D, emission_tex);
    glUniform1i(glGetUniformLocation(g, "u_has_emission"), emission_tex ? 1 : 0);
    glActiveTexture(GL_TEXTURE4);
    glBindTexture(GL_TEXTURE_2D, translucent_tex);
    glUniform1i(glGetUniformLocation(g, "u_has_translucent"), translucent_tex ? 1 : 0);
    glActiveTexture(GL_TEXTURE5);
    glBindTexture(GL_TEXTURE_2D, p->occlusion_tex);
    glUniform1i(glGetUniformLocation(g, "u_has_occlusion"), p->occlusion_tex ? 1 : 0);
    glActiveTexture(GL_TEXTURE0);
    glUniform1f(glGetUniformLocation(g, "u_exposure"), s->exposure);
    glu_pass_draw(&p->pass);
    return &p->pass.target;
}

void pass_composite_destroy(pass_composite *p)
{
    if (!p)
        return;
    glu_pass_destroy(&p->pass);
    free(p);
}
