#version 450 core
// Eye G-buffer, vertex stage (ISPM §3 step 1: "render the eye G-buffer"). World-space
// position and normal go to the fragment stage; the clip positions of this frame and of the
// previous one give the per-pixel motion vector.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv0;   // TEXCOORD_0 (base_color.glsl)
layout(location = 3) in vec2 a_uv1;   // TEXCOORD_1
layout(location = 4) in vec4 a_color; // COLOR_0
layout(location = 6) in vec4 a_tangent; // TANGENT xyz, handedness w (normal_map.glsl)
// The previous frame's object-space position: a_position for rigid primitives (their motion
// is in u_prev_world), the previous deformed pose for skinned and morphed ones (deform_gl.c).
layout(location = 5) in vec3 a_prev_position;

uniform mat4 u_world;
uniform mat4 u_prev_world;
uniform mat3 u_normal_matrix;
uniform mat4 u_view;
uniform mat4 u_view_proj;
uniform mat4 u_prev_view_proj;
uniform mat4 u_prev_view;

out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv0;
out vec2 v_uv1;
out vec4 v_color;
out vec4 v_tangent;
out vec4 v_clip;
out vec4 v_prev_clip;
out float v_eye_depth;
out float v_prev_eye_depth; // this point's eye depth in the previous frame (temporal filter)

void main()
{
    vec4 wp = u_world * vec4(a_position, 1.0);
    v_position = wp.xyz;
    v_normal = u_normal_matrix * a_normal;
    v_uv0 = a_uv0;
    v_uv1 = a_uv1;
    v_color = a_color;
    v_tangent = vec4(mat3(u_world) * a_tangent.xyz, a_tangent.w);
    v_clip = u_view_proj * wp;
    vec4 prev_wp = u_prev_world * vec4(a_prev_position, 1.0);
    v_prev_clip = u_prev_view_proj * prev_wp;
    v_prev_eye_depth = -(u_prev_view * prev_wp).z;
    v_eye_depth = -(u_view * wp).z;
    gl_Position = v_clip;
}
