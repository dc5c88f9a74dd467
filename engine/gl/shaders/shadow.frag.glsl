#version 450 core
// Shadow map, fragment stage. Stores a metric value rather than window depth so lookups do
// not depend on the projection: distance to the light for point and spot lights (mode 0),
// distance along the light direction from the ortho box's near plane for directional
// lights (mode 1).
in vec3 v_position;
in vec2 v_uv0;
in vec2 v_uv1;
in vec4 v_color;
#pragma ispm_include "base_color.glsl"
uniform vec4 u_base_color;

uniform int u_mode;
uniform vec3 u_light_position;
uniform vec3 u_light_direction;

layout(location = 0) out vec4 o_depth;

void main()
{
    if (u_alpha_cutoff >= 0.0) // alphaMode MASK: cut-outs cast no shadow
        base_color(u_base_color);
    float d = u_mode == 0 ? distance(v_position, u_light_position)
                          : dot(v_position - u_light_position, u_light_direction);
    o_depth = vec4(d, 0.0, 0.0, 1.0);
}
