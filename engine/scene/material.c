/* material.c — a draw's material resolved: the glTF default material (glTF 2.0 §3.9.2) where
 * a primitive names none. */
#include "scn.h"

#include <stdio.h>
#include <string.h>

/* glTF 2.0 §3.9.2: the default material when a primitive names none. */
scn_material eng_material_of(const scn_scene *scene, int32_t index)
{
    if (index >= 0 && (uint32_t)index < scene->material_count)
        return scene->materials[index];
    scn_material m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "default");
    m.base_color[0] = m.base_color[1] = m.base_color[2] = m.base_color[3] = 1.0f;
    m.metallic = 1.0f;
    m.roughness = 1.0f;
    m.ior = 1.5f;
    m.alpha_cutoff = 0.5f;
    scn_texref *refs[5] = {&m.base_color_tex, &m.metallic_roughness_tex, &m.normal_tex, &m.occlusion_tex,
                           &m.emissive_tex};
    for (int i = 0; i < 5; i++) {
        refs[i]->texture = -1;
        refs[i]->transform[0] = refs[i]->transform[3] = 1.0f;
    }
    return m;
}
