#version 450 core
// Light-space G-buffer, fragment stage. Outputs (RGBA32F): 0 world position (w = 1 where a
// surface was drawn), 1 world shading normal as modelled (normal texture applied; not flipped: the bounce pass needs
// to know whether a photon enters or leaves a transmissive surface), 2 albedo, 3 roughness,
// metallic, transmission, ior.
in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv0;
in vec2 v_uv1;
in vec4 v_color;
in vec4 v_tangent;
#pragma ispm_include "base_color.glsl"
#pragma ispm_include "normal_map.glsl"

uniform vec4 u_base_color;
uniform vec4 u_material;

layout(location = 0) out vec4 o_position;
layout(location = 1) out vec4 o_normal;
layout(location = 2) out vec4 o_albedo;
layout(location = 3) out vec4 o_material;

void main()
{
    o_position = vec4(v_position, 1.0);
    o_normal = vec4(normal_mapped(normalize(v_normal)), 0.0);
    o_albedo = vec4(base_color(u_base_color).rgb, 1.0);
    o_material = material_params(u_material);
}
