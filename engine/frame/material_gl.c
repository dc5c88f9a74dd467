/* material_gl.c — a draw's material bound for the rasterising passes: base colour texture,
 * texcoord set and transform, COLOR_0 and the MASK cutoff (shaders/base_color.glsl). */
#include "frame.h"

#include <stdio.h>
#include <string.h>

/* One texture reference: "<prefix>_tex_on", "_uv_set", "_uv_xf", "_tex" on unit `unit`. */
static void bind_texref(GLuint prog, const eng_frame_scene *fs, const eng_gpu_prim *g, const scn_texref *r,
                        const char *prefix, int unit)
{
    char name[32];
    int on = r->texture >= 0 && (uint32_t)r->texture < fs->scene->texture_count && g->vbo_uv[r->texcoord];
    snprintf(name, sizeof name, "%s_tex_on", prefix);
    glUniform1i(glGetUniformLocation(prog, name), on);
    if (!on)
        return;
    const float *t = r->transform;
    const float xf[9] = {t[0], t[1], 0.0f, t[2], t[3], 0.0f, t[4], t[5], 1.0f};
    snprintf(name, sizeof name, "%s_uv_xf", !strcmp(prefix, "u_base") ? "u" : prefix);
    glUniformMatrix3fv(glGetUniformLocation(prog, name), 1, GL_FALSE, xf);
    snprintf(name, sizeof name, "%s_uv_set", !strcmp(prefix, "u_base") ? "u" : prefix);
    glUniform1i(glGetUniformLocation(prog, name), r->texcoord);
    snprintf(name, sizeof name, "%s_tex", prefix);
    glUniform1i(glGetUniformLocation(prog, name), unit);
    glActiveTexture(GL_TEXTURE0 + (GLenum)unit);
    glBindTexture(GL_TEXTURE_2D, fs->textures[r->texture]);
    glActiveTexture(GL_TEXTURE0);
}

void eng_bind_material(GLuint prog, const eng_frame_scene *fs, const eng_draw *d, const scn_material *m)
{
    const eng_gpu_prim *g = d->gpu;
    glUniform1i(glGetUniformLocation(prog, "u_has_color"), g->vbo_col != 0);
    glUniform1f(glGetUniformLocation(prog, "u_alpha_cutoff"), m->alpha_mode == SCN_ALPHA_MASK ? m->alpha_cutoff : -1.0f);
    bind_texref(prog, fs, g, &m->base_color_tex, "u_base", ENG_BASE_TEX_UNIT);
    bind_texref(prog, fs, g, &m->metallic_roughness_tex, "u_mr", ENG_BASE_TEX_UNIT + 1);
    bind_texref(prog, fs, g, &m->emissive_tex, "u_em", ENG_BASE_TEX_UNIT + 2);
    bind_texref(prog, fs, g, &m->occlusion_tex, "u_occ", ENG_BASE_TEX_UNIT + 3);
    glUniform1f(glGetUniformLocation(prog, "u_occ_strength"), m->occlusion_strength);
    /* Normal texture (normal_map.glsl): only where the draw has tangents. */
    bind_texref(prog, fs, g, &m->normal_tex, "u_nrm", ENG_BASE_TEX_UNIT + 4);
    if (!g->vbo_tan)
        glUniform1i(glGetUniformLocation(prog, "u_nrm_tex_on"), 0);
    glUniform1f(glGetUniformLocation(prog, "u_nrm_scale"), m->normal_scale);
}
