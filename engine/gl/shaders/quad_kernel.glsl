// The photon-quad kernel (001_… §3.3), shared by quads.frag.glsl and quads_irradiance.frag.glsl
// (and mirrored on the CPU by tests/test_quads.c). The surface point s of a pixel (normal n)
// receives the photon at x (normal n_p, radii r_xy, r_z) when
//   - it lies in the slab |d·n_p| ≤ r_z about the quad's plane, d = s − x: a photon on one wall
//     does not light a parallel wall behind it (the role the compressed ellipsoid's short axis
//     plays in 003_… §5.1); r_z = normal_compression · r_xy, as the photon volume's;
//   - its distance from x within that plane is below r_xy: t = |d − (d·n_p) n_p| / r_xy < 1.
// κ is the 2D Epanechnikov kernel on the tangent plane, the photon volume's kernel1D,
// 2/(π r_xy²) · (1 − t²) (003 §5.1; it integrates to 1 over the plane), times 001 Eq. (1)'s
// normal weighting max(0, n_p·n): 1 on the photon's own plane, so there the quads sum exactly
// what the photon volumes and the gathers sum; 0 on a wall meeting that plane at a right angle.
// That is the documented difference by design (001 §3.3 and §5, Fig. 5.8/5.9): the kernel is
// flat, so at a corner the other surface does not receive the photon and corners come out
// darker than with the volume (which straddles both surfaces, 003 Fig. 4).
// Returns κ in 1/m², or a negative value when s does not receive the photon.
float quad_kappa(vec3 s, vec3 n, vec3 x, vec3 n_p, vec2 radius)
{
    vec3 d = s - x;
    float h = dot(d, n_p);
    if (abs(h) > radius.y)
        return -1.0;
    float w = dot(n, n_p);
    if (w <= 0.0)
        return -1.0;
    vec3 dt = d - h * n_p;
    float r_xy = radius.x;
    float t2 = dot(dt, dt) / (r_xy * r_xy);
    if (t2 >= 1.0)
        return -1.0;
    return 2.0 / (3.14159265358979323846 * r_xy * r_xy) * (1.0 - t2) * w;
}

// The anisotropic kernel (002_… Eq. 6.3–6.5; photon_kernel.glsl's photon_aniso gives aniso):
// the disk becomes the ellipse of semi-axes s_u·r_xy along û and r_xy across it: quad_kappa at
// the point x + d − (d·a) a (a ⟂ n_p, so the slab test sees the same height), divided by s_u
// (still 1 over the plane). aniso.w = 1: quad_kappa itself.
float quad_kappa_aniso(vec3 s, vec3 n, vec3 x, vec3 n_p, vec2 radius, vec4 aniso)
{
    if (aniso.w == 1.0)
        return quad_kappa(s, n, x, n_p, radius);
    vec3 d = s - x;
    float k = quad_kappa(x + (d - dot(d, aniso.xyz) * aniso.xyz), n, x, n_p, radius);
    return k < 0.0 ? k : k / aniso.w;
}
