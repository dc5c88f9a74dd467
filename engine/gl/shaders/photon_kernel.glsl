// The photon volume kernel, ISPM 003_… §5.1 Eq. 2–3, shared by splat.frag.glsl and
// splat_irradiance.frag.glsl (and mirrored on the CPU by splat_kernel() in ind_scatter_splat.c).
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

// The anisotropic kernel of 002_… §6.1.2 (Eq. 6.3–6.5), gather_kernel.h's gk_aniso_of and
// gk_kappa_aniso in the same operations: the ellipsoid stretched by s_u = min(1/(n_p·ω_i), s_max)
// along û, ω_i projected onto the kernel plane. aniso = (a, s_u), a = √(1 − 1/s_u) û, or
// (0, 0, 0, 1) for the isotropic kernel; κ is photon_kappa's at d' = d − (d·a) a, divided by s_u
// (still 1 integrated over the plane). Compiled only into the programs of
// "kernel_scaling": "anisotropic" (PHOTON_ANISO), so the isotropic programs do not change.
vec4 photon_aniso(vec3 w_i, vec3 n_p, float su)
{
    float c = dot(w_i, n_p);
    vec3 u = w_i - c * n_p;
    float ul = sqrt(dot(u, u));
    if (!(su > 1.0) || !(ul > 0.0))
        return vec4(0.0, 0.0, 0.0, 1.0);
    return vec4(u * (sqrt(1.0 - 1.0 / su) / ul), su);
}

float photon_kappa_aniso(vec3 s, vec3 x, vec3 n_p, vec2 radius, vec4 aniso)
{
    if (aniso.w == 1.0)
        return photon_kappa(s, x, n_p, radius);
    vec3 d = s - x;
    vec3 e = d - dot(d, aniso.xyz) * aniso.xyz;
    float len = length(e);
    float r_xy = radius.x, r_z = radius.y;
    float t = len > 0.0 ? len / r_xy * (1.0 + abs(dot(e, n_p)) / len * (r_xy - r_z) / r_z) : 0.0;
    if (t >= 1.0)
        return -1.0;
    return 2.0 / (3.14159265358979323846 * r_xy * r_xy * aniso.w) * (1.0 - t * t);
}
