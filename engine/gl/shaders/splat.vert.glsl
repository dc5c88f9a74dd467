#version 450 core
// Photon volumes (ISPM 003_… §5), drawn as one screen-aligned rectangle per photon, two
// triangles, vertices pulled from a buffer (no instancing): ind_scatter_splat.c and ind_scatter_bounds.c
// compute on the CPU the pixel rectangle that holds every pixel whose G-buffer point can lie
// in the photon's kernel ellipsoid (radius r_xy in the plane of the surface the photon hit,
// r_z = compression · r_xy along that surface's normal n_p; §5.1, Fig. 4 right), and the NDC
// depth of the ellipsoid's far side, so the GEQUAL depth test still drops pixels whose
// surface lies behind the whole volume. Each pixel of the rectangle is shaded once.
// Per photon, 5 vec4: rect (x0, y0, x1 + 1, y1 + 1 in window pixels), (x, z_far),
// (n_p, r_xy), (Φ_i, r_z), (ω_i, s_u): s_u the anisotropic kernel's stretch (1: isotropic;
// photon_kernel.glsl, read only by the PHOTON_ANISO fragment programs).
layout(std430, binding = 0) readonly buffer splat_photons { vec4 u_photons[]; };

uniform vec2 u_viewport;

flat out vec3 v_position;
flat out vec3 v_normal;
flat out vec3 v_power;
flat out vec3 v_direction;
flat out vec2 v_radius;
flat out float v_stretch;

void main()
{
    int i = gl_VertexID >> 2, corner = gl_VertexID & 3;
    vec4 rect = u_photons[5 * i];
    vec4 pz = u_photons[5 * i + 1];
    vec4 nr = u_photons[5 * i + 2];
    vec4 pw = u_photons[5 * i + 3];
    v_position = pz.xyz;
    v_normal = nr.xyz;
    v_power = pw.xyz;
    vec4 ds = u_photons[5 * i + 4];
    v_direction = ds.xyz;
    v_stretch = ds.w;
    v_radius = vec2(nr.w, pw.w);
    vec2 px = vec2((corner & 1) != 0 ? rect.z : rect.x, (corner & 2) != 0 ? rect.w : rect.y);
    gl_Position = vec4(px / u_viewport * 2.0 - 1.0, pz.w, 1.0);
}
