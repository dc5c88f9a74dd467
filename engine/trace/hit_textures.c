/* hit_textures.c — a CPU hit's texture lookups (rt_hit_textures): what the material's base
 * colour, roughness, metallic and emission are multiplied by at the hit, as the G-buffers
 * fetch them (scn_base_color_at, scn_texref_at), at level 0 or at the level a ray-cone
 * footprint selects (texture_mip.c). */
#include "trace.h"

#include <string.h>

void rt_hit_textures(const scn_scene *scene, const scn_primitive *p, rt_hit *hit, float width)
{
    const uint32_t tri = hit->tri;
    const float u = hit->bary[0], v = hit->bary[1], area = hit->world_area;
    const int has_mat = hit->material >= 0 && (uint32_t)hit->material < scene->material_count;
    const scn_material *m = has_mat ? &scene->materials[hit->material] : NULL;
    hit->base_tex[0] = hit->base_tex[1] = hit->base_tex[2] = hit->base_tex[3] = 1.0f;
    if (has_mat && width > 0.0f) {
        scn_texref_at_cone(scene, &m->base_color_tex, p, tri, u, v, width, area, hit->base_tex);
        if (p->colors) {
            float c[4];
            scn_base_color_at(scene, &(scn_material){.base_color_tex = {.texture = -1}}, p, tri, u, v, c);
            for (int k = 0; k < 4; k++)
                hit->base_tex[k] *= c[k];
        }
    } else if (has_mat) {
        scn_base_color_at(scene, m, p, tri, u, v, hit->base_tex);
    } else if (p->colors) {
        scn_base_color_at(scene, &(scn_material){.base_color_tex = {.texture = -1}}, p, tri, u, v, hit->base_tex);
    }
    hit->roughness_tex = hit->metallic_tex = 1.0f;
    hit->emissive_tex[0] = hit->emissive_tex[1] = hit->emissive_tex[2] = 1.0f;
    if (!has_mat)
        return;
    float t[4];
    if (scn_texref_at_cone(scene, &m->metallic_roughness_tex, p, tri, u, v, width, area, t)) {
        hit->roughness_tex = t[1];
        hit->metallic_tex = t[2];
    }
    if (scn_texref_at_cone(scene, &m->emissive_tex, p, tri, u, v, width, area, t))
        memcpy(hit->emissive_tex, t, sizeof hit->emissive_tex);
}

scn_material eng_material_at(const scn_scene *scene, const rt_hit *hit)
{
    scn_material m = eng_material_of(scene, hit->material);
    for (int c = 0; c < 4; c++)
        m.base_color[c] *= hit->base_tex[c];
    m.roughness *= hit->roughness_tex;
    m.metallic *= hit->metallic_tex;
    for (int c = 0; c < 3; c++)
        m.emissive[c] *= hit->emissive_tex[c];
    return m;
}
