#version 450 core
// Photon quads (Yao 2011, 001_… §3.3): each photon becomes one camera-independent square on
// its tangent plane — centre x (the photon position), plane ⟂ n_p (the normal of the surface it
// hit), half-size r_xy (the photon volume's radius, 003_… §5.1, so both methods spread a photon
// over the same disk). Instanced two-triangle strip; the tangent frame is splat.vert.glsl's.
// The square is 1 % larger than the disk of radius r_xy it bounds, so that float rounding of
// the projected corners never loses a pixel whose surface point lies inside the disk (the
// fragment stage, quad_kernel.glsl, does the exact cut-off).
layout(location = 0) in vec2 a_corner;       // (±1, ±1)
layout(location = 1) in vec3 a_position;     // photon x
layout(location = 2) in vec3 a_normal;       // n_p
layout(location = 3) in vec3 a_power;        // Φ_i
layout(location = 4) in vec3 a_direction;    // ω_i
layout(location = 5) in vec2 a_radius;       // r_xy, r_z (the slab's half-thickness)
layout(location = 6) in float a_stretch;     // s_u of the anisotropic kernel (1: isotropic)

uniform mat4 u_view_proj;

flat out vec3 v_position;
flat out vec3 v_normal;
flat out vec3 v_power;
flat out vec3 v_direction;
flat out vec2 v_radius;
flat out float v_stretch;

void main()
{
    vec3 n = a_normal;
    vec3 a = abs(n.x) > 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 t = normalize(cross(a, n));
    vec3 b = cross(n, t);
    // The anisotropic ellipse (quad_kernel.glsl) lies in the disk of radius s_u·r_xy.
    vec2 c = a_corner * (1.01 * a_radius.x) * a_stretch;
    vec3 world = a_position + t * c.x + b * c.y;
    v_position = a_position;
    v_normal = n;
    v_power = a_power;
    v_direction = a_direction;
    v_radius = a_radius;
    v_stretch = a_stretch;
    gl_Position = u_view_proj * vec4(world, 1.0);
}
