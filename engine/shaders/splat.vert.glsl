#version 450 core
// Photon volumes (ISPM 003_… §5): one instanced icosahedron per photon, scaled to bound the
// photon's kernel ellipsoid — radius r_xy in the plane of the surface the photon hit and
// r_z = compression · r_xy along that surface's normal n_p (§5.1, Fig. 4 right). The unit
// icosahedron's vertices lie on a sphere of radius 1/0.79465 so its faces enclose the unit
// sphere (inradius/circumradius of a regular icosahedron = 0.79465).
layout(location = 0) in vec3 a_vertex;       // unit icosahedron
layout(location = 1) in vec3 a_position;     // photon x
layout(location = 2) in vec3 a_normal;       // n_p
layout(location = 3) in vec3 a_power;        // Φ_i
layout(location = 4) in vec3 a_direction;    // ω_i
layout(location = 5) in vec2 a_radius;       // r_xy, r_z

uniform mat4 u_view_proj;

flat out vec3 v_position;
flat out vec3 v_normal;
flat out vec3 v_power;
flat out vec3 v_direction;
flat out vec2 v_radius;

void main()
{
    vec3 n = a_normal;
    vec3 a = abs(n.x) > 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 t = normalize(cross(a, n));
    vec3 b = cross(n, t);
    vec3 p = a_vertex * 1.2584;
    vec3 world = a_position + (t * p.x + b * p.y) * a_radius.x + n * (p.z * a_radius.y);
    v_position = a_position;
    v_normal = n;
    v_power = a_power;
    v_direction = a_direction;
    v_radius = a_radius;
    gl_Position = u_view_proj * vec4(world, 1.0);
}
