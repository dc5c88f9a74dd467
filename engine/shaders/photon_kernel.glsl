// The photon volume kernel, ISPM 003_… §5.1 Eq. 2–3, shared by splat.frag.glsl and
// splat_irradiance.frag.glsl (and mirrored on the CPU by splat_kernel() in pass_splat.c).
// Eq. 2 as printed, t = |d|/r_xy · (1 − |d̂·n_p| (r_xy − r_z)/r_z), goes negative along n_p once
// r_z < r_xy/2; we use the form that maps the ellipsoid's surface to t = 1, which is what the
// text describes: t = |d|/r_xy · (1 + |d̂·n_p| (r_xy − r_z)/r_z) (t = |d|/r_xy in the plane,
// |d|/r_z along the normal). kernel1D is the 2D Epanechnikov kernel normalised over the disk
// of radius r_xy: κ = 2/(π r_xy²) · (1 − t²), which integrates to 1 over the photon's surface
// plane. Returns κ in 1/m², or a negative value outside the ellipsoid.
float photon_kappa(vec3 s, vec3 x, vec3 n_p, vec2 radius)
{
    vec3 d = s - x;
    float len = length(d);
    float r_xy = radius.x, r_z = radius.y;
    float t = len > 0.0 ? len / r_xy * (1.0 + abs(dot(d, n_p)) / len * (r_xy - r_z) / r_z) : 0.0;
    if (t >= 1.0)
        return -1.0;
    return 2.0 / (3.14159265358979323846 * r_xy * r_xy) * (1.0 - t * t);
}

// The glossy (GGX) part of the BSDF the splat evaluates, 002_… §4.1 (needs ggx.glsl).
vec3 photon_glossy(vec3 n, vec3 s, vec3 eye, vec3 w_i, float cos_i, vec3 albedo, vec4 mat)
{
    vec3 v = normalize(eye - s);
    float nov = max(dot(n, v), 1e-4);
    vec3 h = normalize(w_i + v);
    float a = max(mat.x * mat.x, 1e-2), a2 = a * a;
    vec3 fr = albedo + (1.0 - albedo) * pow(1.0 - max(dot(v, h), 0.0), 5.0);
    return mat.y * fr * ggx_d(max(dot(n, h), 0.0), a2) * smith_g1(cos_i, a2) * smith_g1(nov, a2) / (4.0 * cos_i * nov);
}
