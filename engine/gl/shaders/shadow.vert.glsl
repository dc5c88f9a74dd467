#version 450 core
// Shadow map, vertex stage: one light view (a cube face, a spot frustum or a directional
// ortho box).
layout(location = 0) in vec3 a_position;
layout(location = 2) in vec2 a_uv0;   // for alphaMode MASK (base_color.glsl)
layout(location = 3) in vec2 a_uv1;
layout(location = 4) in vec4 a_color;

uniform mat4 u_world;
uniform mat4 u_view_proj;

out vec3 v_position;
out vec2 v_uv0;
out vec2 v_uv1;
out vec4 v_color;

void main()
{
    vec4 wp = u_world * vec4(a_position, 1.0);
    v_position = wp.xyz;
    v_uv0 = a_uv0;
    v_uv1 = a_uv1;
    v_color = a_color;
    gl_Position = u_view_proj * wp;
}
