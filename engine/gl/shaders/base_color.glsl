// base_color.glsl — a material's base colour at a fragment (glTF §3.9.2): baseColorFactor
// times (its base colour texture at TEXCOORD_0 or _1 through KHR_texture_transform, times
// COLOR_0), the same product, in the same order, that scn_base_color_at and
// eng_material_at compute for a CPU hit. The including stage declares v_uv0, v_uv1, v_color;
// eng_bind_material (glutil.c) sets the uniforms.
uniform sampler2D u_base_tex;
uniform int u_base_tex_on;    // 1: the material has a base colour texture
uniform int u_uv_set;         // 0 or 1
uniform mat3 u_uv_xf;         // KHR_texture_transform: (u, v, 1) -> (u', v', 1)
uniform int u_has_color;      // 1: the primitive has COLOR_0
uniform float u_alpha_cutoff; // alphaMode MASK: fragments whose alpha is below are cut; < 0 otherwise
uniform sampler2D u_mr_tex;   // metallicRoughness: G roughness, B metallic (glTF §3.9.2)
uniform int u_mr_tex_on;
uniform int u_mr_uv_set;
uniform mat3 u_mr_uv_xf;
uniform sampler2D u_em_tex;   // emissive (sRGB-decoded): emission = emissiveFactor × texture (glTF §3.9.3)
uniform int u_em_tex_on;
uniform int u_em_uv_set;
uniform mat3 u_em_uv_xf;

uniform sampler2D u_occ_tex;  // occlusion: R, scaled by strength (glTF §3.9.3)
uniform int u_occ_tex_on;
uniform int u_occ_uv_set;
uniform mat3 u_occ_uv_xf;
uniform float u_occ_strength;

// What indirect light is multiplied by: 1 + strength·(occlusion − 1); 1 without a texture.
float occlusion()
{
    if (u_occ_tex_on != 1)
        return 1.0;
    float o = texture(u_occ_tex, (u_occ_uv_xf * vec3(u_occ_uv_set == 1 ? v_uv1 : v_uv0, 1.0)).xy).r;
    return 1.0 + u_occ_strength * (o - 1.0);
}

// Emitted radiance: the factor (× KHR_materials_emissive_strength) times the emissive texture.
vec3 emission(vec3 factor)
{
    if (u_em_tex_on == 1)
        factor *= texture(u_em_tex, (u_em_uv_xf * vec3(u_em_uv_set == 1 ? v_uv1 : v_uv0, 1.0)).xy).rgb;
    return factor;
}

// (roughness, metallic, transmission, ior) with the metallicRoughness texture applied.
vec4 material_params(vec4 m)
{
    if (u_mr_tex_on == 1) {
        vec4 t = texture(u_mr_tex, (u_mr_uv_xf * vec3(u_mr_uv_set == 1 ? v_uv1 : v_uv0, 1.0)).xy);
        m.x *= t.g;
        m.y *= t.b;
    }
    return m;
}

vec4 base_color(vec4 factor)
{
    vec4 c = factor;
    if (u_base_tex_on == 1 || u_has_color == 1) {
        vec4 t = vec4(1.0);
        if (u_base_tex_on == 1)
            t = texture(u_base_tex, (u_uv_xf * vec3(u_uv_set == 1 ? v_uv1 : v_uv0, 1.0)).xy);
        if (u_has_color == 1)
            t *= v_color;
        c = factor * t;
    }
    if (c.a < u_alpha_cutoff)
        discard;
    return c;
}
