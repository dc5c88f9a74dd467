#version 450 core
// Shadow map, vertex stage: one light view (a cube face, a spot frustum or a directional
// ortho box).
layout(location = 0) in vec3 a_position;

uniform mat4 u_world;
uniform mat4 u_view_proj;

out vec3 v_position;

void main()
{
    vec4 wp = u_world * vec4(a_position, 1.0);
    v_position = wp.xyz;
    gl_Position = u_view_proj * wp;
}
