#version 450 core
// Light-space G-buffer, vertex stage (ISPM 003_… §3 step 1b: "render G-buffer from the
// emitter's view"): one cube face, spot frustum or directional box, as the shadow map.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv0;   // TEXCOORD_0 (base_color.glsl)
layout(location = 3) in vec2 a_uv1;   // TEXCOORD_1
layout(location = 4) in vec4 a_color; // COLOR_0
layout(location = 6) in vec4 a_tangent; // TANGENT xyz, handedness w (normal_map.glsl)

uniform mat4 u_world;
uniform mat3 u_normal_matrix;
uniform mat4 u_view_proj;

out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv0;
out vec2 v_uv1;
out vec4 v_color;
out vec4 v_tangent;

void main()
{
    vec4 wp = u_world * vec4(a_position, 1.0);
    v_position = wp.xyz;
    v_normal = u_normal_matrix * a_normal;
    v_uv0 = a_uv0;
    v_uv1 = a_uv1;
    v_color = a_color;
    v_tangent = vec4(mat3(u_world) * a_tangent.xyz, a_tangent.w);
    gl_Position = u_view_proj * wp;
}
