// bsdf_sample.glsl — the GLSL twin of engine/bsdf.c: how a photon scatters at a surface
// (lobe choice, importance sampling, Russian roulette, path-density factor), function for
// function and line for line, so the bounce map (GPU, first bounce) and the CPU trace (later
// bounces) sample one BSDF. Formulas and paper sections are in bsdf.c's opening paragraph;
// constants, lobe ids and the lobe order come from bsdf_constants.glsl, which the shader must
// splice in first. tests/test_bsdf.c compares this file with bsdf.c on the same numbers.

float bsdf_max3(vec3 v)
{
    float m = v.x > v.y ? v.x : v.y;
    return m > v.z ? m : v.z;
}

float bsdf_clamp01(float x)
{
    return x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
}

vec3 bsdf_normalize(vec3 v)
{
    float l = sqrt(dot(v, v));
    return l > 0.0 ? v / l : v;
}

// Orthonormal basis about unit n (Duff et al. 2017), as bsdf_basis in bsdf.h.
void bsdf_basis(vec3 n, out vec3 t, out vec3 b)
{
    float sign = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sign + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0 + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b = vec3(c, sign + n.y * n.y * a, -n.y);
}

vec3 bsdf_to_world(vec3 local, vec3 n)
{
    vec3 t, b;
    bsdf_basis(n, t, b);
    return local.x * t + local.y * b + local.z * n;
}

vec3 bsdf_reflect(vec3 wi, vec3 n)
{
    float d = 2.0 * dot(wi, n);
    return d * n - wi;
}

float bsdf_schlick1(float f0, float cos_t)
{
    float k = 1.0 - bsdf_clamp01(cos_t);
    float k2 = k * k;
    return f0 + (1.0 - f0) * k2 * k2 * k;
}

float bsdf_ggx_g1(float ndotv, float alpha)
{
    float a2 = alpha * alpha;
    return 2.0 * ndotv / (ndotv + sqrt(a2 + (1.0 - a2) * ndotv * ndotv));
}

float bsdf_fresnel_dielectric(float cos_i, float n1, float n2)
{
    cos_i = bsdf_clamp01(cos_i);
    float e = n1 / n2;
    float sin2t = e * e * (1.0 - cos_i * cos_i);
    if (sin2t >= 1.0)
        return 1.0;
    float cos_t = sqrt(1.0 - sin2t);
    float rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    float rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Russian roulette on the lobe weight (bsdf.c roulette).
int bsdf_roulette(int lobe, float u, inout vec3 weight, inout vec3 wo, inout float density_factor)
{
    for (int i = 0; i < 3; i++)
        if (!(weight[i] > 0.0))
            weight[i] = 0.0;
    float p = bsdf_clamp01(bsdf_max3(weight));
    if (!(u < p)) {
        wo = vec3(0.0);
        weight = vec3(0.0);
        density_factor = 0.0;
        return BSDF_LOBE_ABSORBED;
    }
    weight /= p;
    return lobe;
}

// bsdf_scatter of bsdf.h: mat = (roughness, metallic, transmission, ior), n the unit shading
// normal as authored, wi unit toward where the photon came from, eta in/out the medium's
// index, u the event's 4 uniforms, cosdir its cosine-weighted direction about +Z.
int bsdf_scatter(vec3 base_color, vec4 mat, vec3 n, vec3 wi, inout float eta, vec4 u, vec4 cosdir,
                 out vec3 wo, out vec3 weight, out float density_factor)
{
    wo = vec3(0.0);
    weight = vec3(0.0);
    density_factor = 0.0;
    float roughness = mat.x, ior = mat.w;
    float metallic = bsdf_clamp01(mat.y), transmission = bsdf_clamp01(mat.z);
    float cos_n = dot(wi, n);
    float s = cos_n >= 0.0 ? 1.0 : -1.0;
    vec3 ns = s * n;
    float cos_i = abs(cos_n);
    if (!(cos_i > 0.0))
        return BSDF_LOBE_ABSORBED;

    float pick = u[BSDF_U_LOBE];
    if (pick < metallic) {
        vec3 f0 = base_color;
        if (roughness < BSDF_MIRROR_ROUGHNESS) {
            wo = bsdf_reflect(wi, ns);
            for (int i = 0; i < 3; i++)
                weight[i] = bsdf_schlick1(f0[i], cos_i);
            density_factor = bsdf_max3(weight);
            return bsdf_roulette(BSDF_LOBE_MIRROR, u[BSDF_U_ROULETTE], weight, wo, density_factor);
        }
        float alpha = roughness * roughness;
        if (alpha < BSDF_MIN_ALPHA)
            alpha = BSDF_MIN_ALPHA;
        float u2 = u[BSDF_U_DIR0];
        float theta = atan(alpha * sqrt(u2) / sqrt(1.0 - u2));
        float phi = BSDF_TWO_PI * u[BSDF_U_DIR1];
        vec3 local = vec3(sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta));
        vec3 h = bsdf_to_world(local, ns);
        h = bsdf_normalize(h);
        float hdotwi = dot(h, wi);
        wo = bsdf_reflect(wi, h);
        wo = bsdf_normalize(wo);
        float cos_o = dot(wo, ns), cos_h = dot(h, ns);
        if (!(cos_o > 0.0) || !(hdotwi > 0.0) || !(cos_h > 0.0)) {
            wo = vec3(0.0);
            return BSDF_LOBE_ABSORBED;
        }
        float g = bsdf_ggx_g1(cos_i, alpha) * bsdf_ggx_g1(cos_o, alpha);
        float k = g * hdotwi / (cos_i * cos_h); // wo·h = wi·h
        for (int i = 0; i < 3; i++)
            weight[i] = bsdf_schlick1(f0[i], hdotwi) * k;
        density_factor = bsdf_max3(f0) / BSDF_DENSITY_GLOSSY;
        return bsdf_roulette(BSDF_LOBE_GLOSSY, u[BSDF_U_ROULETTE], weight, wo, density_factor);
    }
    float rest = metallic < 1.0 ? (pick - metallic) / (1.0 - metallic) : 1.0;
    if (rest < transmission) {
        bool entering = cos_n > 0.0;
        float n1 = entering ? eta : ior;
        float n2 = entering ? ior : 1.0;
        float r = bsdf_fresnel_dielectric(cos_i, n1, n2);
        if (u[BSDF_U_DIR0] < r) {
            wo = bsdf_reflect(wi, ns);
            weight = vec3(1.0);
            density_factor = r;
            return bsdf_roulette(BSDF_LOBE_REFLECT, u[BSDF_U_ROULETTE], weight, wo, density_factor);
        }
        // Refraction (002_… §4.5): ωr = −e·wi + (e·cosθi − cosθt)·ns, e = n1/n2.
        float e = n1 / n2;
        float cos_t = sqrt(1.0 - e * e * (1.0 - cos_i * cos_i));
        wo = -e * wi + (e * cos_i - cos_t) * ns;
        wo = bsdf_normalize(wo);
        weight = base_color;
        density_factor = (1.0 - r) * bsdf_max3(weight);
        eta = n2;
        return bsdf_roulette(BSDF_LOBE_REFRACT, u[BSDF_U_ROULETTE], weight, wo, density_factor);
    }
    wo = bsdf_to_world(cosdir.xyz, ns);
    wo = bsdf_normalize(wo);
    weight = base_color;
    density_factor = bsdf_max3(weight) / BSDF_DENSITY_DIFFUSE;
    return bsdf_roulette(BSDF_LOBE_DIFFUSE, u[BSDF_U_ROULETTE], weight, wo, density_factor);
}

// bsdf_stratify of bsdf.h: Cranley–Patterson rotation of u by offset (002_… §4.2) and the
// cosine-weighted direction of the rotated u[BSDF_U_DIR0..1] (concentric map).
void bsdf_stratify(vec4 u, vec4 offset, out vec4 out_u, out vec4 out_cosdir)
{
    for (int d = 0; d < 4; d++) {
        float s = u[d] + offset[d];
        out_u[d] = s >= 1.0 ? s - 1.0 : s;
    }
    float a = 2.0 * out_u[BSDF_U_DIR0] - 1.0, b = 2.0 * out_u[BSDF_U_DIR1] - 1.0, r, phi;
    if (a == 0.0 && b == 0.0) {
        r = 0.0;
        phi = 0.0;
    } else if (abs(a) > abs(b)) {
        r = a;
        phi = (BSDF_PI / 4.0) * (b / a);
    } else {
        r = b;
        phi = BSDF_PI / 2.0 - (BSDF_PI / 4.0) * (a / b);
    }
    float x = r * cos(phi), y = r * sin(phi);
    float z = sqrt(max(0.0, 1.0 - x * x - y * y));
    out_cosdir = vec4(x, y, z, z / BSDF_PI);
}

