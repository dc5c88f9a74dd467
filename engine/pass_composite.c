/* pass_composite.c — the last pass (ISPM 003_… §3: "composite direct and indirect"): linear
 * radiance = direct + indirect, and a display-referred copy (exposure, clamp, sRGB). The
 * indirect input is 0 until the photon passes exist; the pass is written for both. */
#include "eng_internal.h"

#include <stdlib.h>

struct pass_composite {
    glu_target target;
    GLuint program, vao;
};

eng_result pass_composite_create(int width, int height, pass_composite **out, eng_error *err)
{
    *out = NULL;
    pass_composite *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "composite: out of memory");
    eng_result r = glu_program("fullscreen.vert.glsl", "composite.frag.glsl", &p->program, err);
    if (r == ENG_OK)
        r = glu_target_create(&p->target, 2, width, height, 0, err);
    if (r != ENG_OK) {
        pass_composite_destroy(p);
        return r;
    }
    p->vao = glu_fullscreen_vao();
    glUseProgram(p->program);
    glUniform1i(glGetUniformLocation(p->program, "u_direct"), 0);
    glUniform1i(glGetUniformLocation(p->program, "u_indirect"), 1);
    *out = p;
    return ENG_OK;
}

const glu_target *pass_composite_run(pass_composite *p, GLuint direct_tex, GLuint indirect_tex,
                                     const eng_settings *s)
{
    glUseProgram(p->program);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, direct_tex);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, indirect_tex);
    glUniform1i(glGetUniformLocation(p->program, "u_has_indirect"), indirect_tex ? 1 : 0);
    glUniform1f(glGetUniformLocation(p->program, "u_exposure"), s->exposure);
    glBindFramebuffer(GL_FRAMEBUFFER, p->target.fbo);
    glViewport(0, 0, p->target.width, p->target.height);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(p->vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glActiveTexture(GL_TEXTURE0);
    return &p->target;
}

void pass_composite_destroy(pass_composite *p)
{
    if (!p)
        return;
    glu_target_destroy(&p->target);
    if (p->vao)
        glDeleteVertexArrays(1, &p->vao);
    if (p->program)
        glDeleteProgram(p->program);
    free(p);
}
