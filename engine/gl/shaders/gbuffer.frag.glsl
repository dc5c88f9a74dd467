#version 450 core
// Eye G-buffer, fragment stage. Outputs (all RGBA32F):
//   0 world position, w = 1 where a surface was drawn
//   1 world shading normal (normal texture applied, normal_map.glsl), unit; flipped toward
//     the viewer for double-sided materials (by the interpolated normal); w = the
//     surface point's eye depth in the previous frame (not captured; the temporal filter's
//     disocclusion test, 002_… Eq. 7.1 against the previous depth)
//   2 albedo (baseColorFactor times texture and COLOR_0, linear; base_color.glsl)
//   3 roughness, metallic, transmission, ior
//   4 eye depth (metres along the view axis), material id, motion x, motion y
//   5 emitted radiance RGB (emissiveFactor × strength × emissive texture; base_color.glsl),
//     A what indirect light is multiplied by (occlusion texture; 1 without)
// Motion is in pixels from this pixel to where the same surface point was in the previous
// frame, x to the right and y downward (image rows, top row first).
in vec3 v_position;
in vec3 v_normal;
in vec4 v_clip;
in vec4 v_prev_clip;
in float v_eye_depth;
in float v_prev_eye_depth;
in vec2 v_uv0;
in vec2 v_uv1;
in vec4 v_color;
in vec4 v_tangent;
#pragma ispm_include "base_color.glsl"
#pragma ispm_include "normal_map.glsl"

uniform vec3 u_eye;
uniform vec4 u_base_color;
uniform vec4 u_material;
uniform float u_material_id;
uniform int u_double_sided;
uniform vec2 u_viewport;
uniform vec3 u_emissive;

layout(location = 0) out vec4 o_position;
layout(location = 1) out vec4 o_normal;
layout(location = 2) out vec4 o_albedo;
layout(location = 3) out vec4 o_material;
layout(location = 4) out vec4 o_misc;
layout(location = 5) out vec4 o_emission;

void main()
{
    // Double-sided back faces flip the whole frame (N, T, B), hence the mapped normal.
    vec3 n = normalize(v_normal);
    bool back = u_double_sided == 1 && dot(n, u_eye - v_position) < 0.0;
    n = normal_mapped(n);
    if (back)
        n = -n;
    vec2 ndc = v_clip.xy / v_clip.w;
    vec2 prev_ndc = v_prev_clip.xy / v_prev_clip.w;
    vec2 motion = (prev_ndc - ndc) * 0.5 * u_viewport * vec2(1.0, -1.0);
    o_position = vec4(v_position, 1.0);
    o_normal = vec4(n, v_prev_eye_depth);
    vec4 albedo = base_color(u_base_color);
    o_albedo = vec4(albedo.rgb, albedo.a);
    o_material = material_params(u_material);
    o_misc = vec4(v_eye_depth, u_material_id, motion);
    o_emission = vec4(emission(u_emissive), occlusion());
}
