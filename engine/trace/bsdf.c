/* bsdf.c — how a photon scatters at a surface: lobe choice, importance sampling, Russian
 * roulette and the path-density factor. Used by the CPU tracer (photon_trace.c). The
 * bounce-map shader calls its GLSL twin, shaders/bsdf_sample.glsl, which follows this file
 * line for line on the constants and lobe order of shaders/bsdf_constants.glsl (read by both);
 * tests/test_bsdf.c runs both on the same random numbers. Formulas are kept few and simple.
 *
 * Material model (glTF metallic-roughness + KHR_materials_transmission/ior, base colour only):
 *   lobe choice  u0 < metallic → metal; else (u0 − metallic)/(1 − metallic) < transmission →
 *                glass; else diffuse. Picking a lobe with the probability of its weight in the
 *                glTF mixture makes each lobe's weight below the lobe's own f·cos/pdf.
 *   diffuse      Lambert, f = albedo/π with albedo = base_color; wo from the cosine table
 *                (002_558366c451cd32fd.txt §4.1, cosine-weighted sampling), so
 *                f·cos/pdf = albedo.
 *   metal        GGX / Trowbridge–Reitz with α = roughness² (≥ BSDF_MIN_ALPHA), half-vector
 *                sampled from D(m)(m·n) (002_… §4.1: θh = atan(α√u/√(1−u)), φh = 2πu'),
 *                wo = 2(m·wi)m − wi. pdf(wo) = D(m)(m·n)/(4(wo·m)), so with Cook–Torrance
 *                f = D·G2·F/(4(wi·n)(wo·n)) the weight is f·cos/pdf = F·G2·(wo·m)/((wi·n)(m·n)),
 *                G2 = G1(wi)·G1(wo) (separable Smith), G1(v) = 2(n·v)/((n·v) + √(α² + (1−α²)(n·v)²)),
 *                F = Schlick with F0 = base_color. roughness < BSDF_MIRROR_ROUGHNESS is a perfect
 *                mirror: wo = reflect(wi, n), weight = F(wi·n).
 *   glass        smooth dielectric (002_… §4.5): exact Fresnel R = (rs² + rp²)/2 with
 *                rs = (n1cosθi − n2cosθt)/(n1cosθi + n2cosθt), rp = (n2cosθi − n1cosθt)/(n2cosθi + n1cosθt);
 *                reflect with probability R (weight 1), else refract (weight = base_color,
 *                the transmission tint); sin²θt = (n1/n2)²(1 − cos²θi) ≥ 1 is total internal
 *                reflection (weight 1). Entering when wi is on the side n points to
 *                (n1 = *eta, n2 = ior), leaving otherwise (n1 = ior, n2 = 1, air outside).
 *                Photons carry power, not radiance, so refraction has no η² factor.
 * Russian roulette (002_… §4.4, Eq. 4.2–4.8 and Jensen's single trial of §4.4.2): the photon
 * survives with P = clamp(max channel of the lobe weight w, 0, 1) and its power becomes Φ·w/P,
 * so E[Φ_out] = Φ·w per channel (unbiased). With the max channel of w rather than Eq. 4.9's
 * power-weighted ratio the outcome does not depend on the photon's power, so the GLSL shader
 * and the CPU agree without passing Φ, and a grey surface keeps photon powers constant.
 * Path density (003_d0bf8e920b03f4e1.txt §4.3): ρp is multiplied by ρL/1000 for a diffuse
 * scatter, ρS/10 for a glossy one and ρS for mirror reflection and refraction, where ρ is the
 * max channel of the lobe's reflectance: albedo for diffuse, F0 for glossy, F(wi·n) for the
 * mirror, R for glass reflection (1 under total internal reflection), (1 − R)·max(tint) for
 * refraction. The factor does not include the lobe-choice probability (the paper's constants
 * are per code path). */
#include "bsdf.h"

#include <math.h>

static float dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static float max3(const float v[3])
{
    float m = v[0] > v[1] ? v[0] : v[1];
    return m > v[2] ? m : v[2];
}


static inline void normalize3(float v[3])
{
    float l = sqrtf(dot3(v, v));
    if (l > 0.0f) {
        v[0] /= l;
        v[1] /= l;
        v[2] /= l;
    }
}


static inline void to_world(const float local[3], const float n[3], float out[3])
{
    float t[3], b[3];
    bsdf_basis(n, t, b);
    for (int i = 0; i < 3; i++)
        out[i] = local[0] * t[i] + local[1] * b[i] + local[2] * n[i];
}

static void reflect(const float wi[3], const float n[3], float out[3])
{
    float d = 2.0f * dot3(wi, n);
    for (int i = 0; i < 3; i++)
        out[i] = d * n[i] - wi[i];
}

static float schlick1(float f0, float cos_t)
{
    float k = 1.0f - bsdf_clamp01(cos_t);
    float k2 = k * k;
    return f0 + (1.0f - f0) * k2 * k2 * k;
}

static float ggx_g1(float ndotv, float alpha)
{
    float a2 = alpha * alpha;
    return 2.0f * ndotv / (ndotv + sqrtf(a2 + (1.0f - a2) * ndotv * ndotv));
}

float bsdf_fresnel_dielectric(float cos_i, float n1, float n2)
{
    cos_i = bsdf_clamp01(cos_i);
    float e = n1 / n2;
    float sin2t = e * e * (1.0f - cos_i * cos_i);
    if (sin2t >= 1.0f)
        return 1.0f;
    float cos_t = sqrtf(1.0f - sin2t);
    float rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    float rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    return 0.5f * (rs * rs + rp * rp);
}

int bsdf_stores_photons(const scn_material *m)
{
    bsdf_params p;
    bsdf_params_of(m, &p);
    return bsdf_stores_photons_params(&p);
}

static bsdf_lobe absorbed(float wo[3], float weight[3], float *density_factor)
{
    for (int i = 0; i < 3; i++)
        wo[i] = weight[i] = 0.0f;
    *density_factor = 0.0f;
    return BSDF_ABSORBED;
}

/* Russian roulette on the lobe weight w (see the opening paragraph). */
static inline bsdf_lobe roulette(bsdf_lobe lobe, float u, float weight[3], float wo[3], float *density_factor)
{
    for (int i = 0; i < 3; i++)
        if (!(weight[i] > 0.0f))
            weight[i] = 0.0f; /* also drops NaN */
    float p = bsdf_clamp01(max3(weight));
    if (!(u < p))
        return absorbed(wo, weight, density_factor);
    for (int i = 0; i < 3; i++)
        weight[i] /= p;
    return lobe;
}

bsdf_lobe bsdf_scatter(const scn_material *m, const float n[3], const float wi[3], float *eta,
                       const bsdf_sample *rnd, float wo[3], float weight[3], float *density_factor)
{
    bsdf_params p;
    bsdf_params_of(m, &p);
    return bsdf_scatter_params(&p, n, wi, eta, rnd, wo, weight, density_factor);
}

bsdf_lobe bsdf_scatter_params(const bsdf_params *m, const float n[3], const float wi[3], float *eta,
                              const bsdf_sample *rnd, float wo[3], float weight[3], float *density_factor)
{
    const float *u = rnd->u;
    float cos_n = dot3(wi, n);
    /* ns: n turned to the side wi lies on. */
    float s = cos_n >= 0.0f ? 1.0f : -1.0f;
    float ns[3] = {s * n[0], s * n[1], s * n[2]};
    float cos_i = fabsf(cos_n);
    const bsdf_lobe lobe = bsdf_lobe_of(m, cos_n, u);
    if (lobe == BSDF_ABSORBED)
        return absorbed(wo, weight, density_factor);

    if (lobe == BSDF_GLOSSY) {
        const float *f0 = m->base_color;
        if (m->roughness < BSDF_MIRROR_ROUGHNESS) {
            reflect(wi, ns, wo);
            for (int i = 0; i < 3; i++)
                weight[i] = schlick1(f0[i], cos_i);
            *density_factor = max3(weight);
            return roulette(BSDF_MIRROR, u[BSDF_U_ROULETTE], weight, wo, density_factor);
        }
        float alpha = m->roughness * m->roughness;
        if (alpha < BSDF_MIN_ALPHA)
            alpha = BSDF_MIN_ALPHA;
        float u2 = u[BSDF_U_DIR0];
        float theta = atanf(alpha * sqrtf(u2) / sqrtf(1.0f - u2));
        float phi = BSDF_TWO_PI * u[BSDF_U_DIR1];
        float local[3] = {sinf(theta) * cosf(phi), sinf(theta) * sinf(phi), cosf(theta)};
        float h[3];
        to_world(local, ns, h);
        normalize3(h);
        float hdotwi = dot3(h, wi);
        reflect(wi, h, wo);
        normalize3(wo);
        float cos_o = dot3(wo, ns), cos_h = dot3(h, ns);
        if (!(cos_o > 0.0f) || !(hdotwi > 0.0f) || !(cos_h > 0.0f))
            return absorbed(wo, weight, density_factor);
        float g = ggx_g1(cos_i, alpha) * ggx_g1(cos_o, alpha);
        float k = g * hdotwi / (cos_i * cos_h); /* wo·h = wi·h */
        for (int i = 0; i < 3; i++)
            weight[i] = schlick1(f0[i], hdotwi) * k;
        *density_factor = max3(f0) / BSDF_DENSITY_GLOSSY;
        return roulette(BSDF_GLOSSY, u[BSDF_U_ROULETTE], weight, wo, density_factor);
    }
    if (lobe == BSDF_REFRACT) {
        int entering = cos_n > 0.0f;
        float n1 = entering ? *eta : m->ior;
        float n2 = entering ? m->ior : 1.0f;
        float r = bsdf_fresnel_dielectric(cos_i, n1, n2);
        if (u[BSDF_U_DIR0] < r) {
            reflect(wi, ns, wo);
            weight[0] = weight[1] = weight[2] = 1.0f;
            *density_factor = r;
            return roulette(BSDF_REFLECT, u[BSDF_U_ROULETTE], weight, wo, density_factor);
        }
        /* Refraction (002_… §4.5): ωr = −e·wi + (e·cosθi − cosθt)·ns, e = n1/n2. */
        float e = n1 / n2;
        float cos_t = sqrtf(1.0f - e * e * (1.0f - cos_i * cos_i)); /* r < 1: no TIR here */
        for (int i = 0; i < 3; i++)
            wo[i] = -e * wi[i] + (e * cos_i - cos_t) * ns[i];
        normalize3(wo);
        for (int i = 0; i < 3; i++)
            weight[i] = m->base_color[i];
        *density_factor = (1.0f - r) * max3(weight);
        *eta = n2;
        return roulette(BSDF_REFRACT, u[BSDF_U_ROULETTE], weight, wo, density_factor);
    }
    to_world(rnd->cosdir, ns, wo);
    normalize3(wo);
    for (int i = 0; i < 3; i++)
        weight[i] = m->base_color[i];
    *density_factor = max3(weight) / BSDF_DENSITY_DIFFUSE;
    return roulette(BSDF_DIFFUSE, u[BSDF_U_ROULETTE], weight, wo, density_factor);
}

#if defined(__SSE2__)
#include <emmintrin.h>

/* SSE2 twins of the scalar helpers above, one ray a lane: the same operations in the same
 * order (IEEE single precision per lane, no fused multiply-add), so each lane's result is the
 * scalar code's bit for bit. */
static inline __m128 sel4(__m128 mask, __m128 a, __m128 b)
{
    return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}

static inline __m128 dot4(const __m128 a[3], const __m128 b[3])
{
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(a[0], b[0]), _mm_mul_ps(a[1], b[1])), _mm_mul_ps(a[2], b[2]));
}

/* max3: (a > b ? a : b), then (m > c ? m : c), as maxps orders its operands. */
static inline __m128 max4(const __m128 v[3])
{
    return _mm_max_ps(_mm_max_ps(v[0], v[1]), v[2]);
}

static inline __m128 load_lanes(const float *const p[4], int i)
{
    return _mm_setr_ps(p[0][i], p[1][i], p[2][i], p[3][i]);
}

void bsdf_diffuse4(const float *const n[4], const float *const wi[4], const float *const cosdir[4],
                   const float *const albedo[4], const float u_roulette[4], float *const wo[4],
                   float *const weight[4], float *const density_factor[4], int alive[4])
{
    const __m128 one = _mm_set1_ps(1.0f), zero = _mm_setzero_ps(), minus = _mm_set1_ps(-0.0f);
    __m128 vn[3], vwi[3], ns[3], t[3], b[3], o[3], w[3];
    for (int i = 0; i < 3; i++) {
        vn[i] = load_lanes(n, i);
        vwi[i] = load_lanes(wi, i);
    }
    const __m128 cos_n = dot4(vwi, vn);
    const __m128 s = sel4(_mm_cmpge_ps(cos_n, zero), one, _mm_xor_ps(one, minus));
    for (int i = 0; i < 3; i++)
        ns[i] = _mm_mul_ps(s, vn[i]);
    /* bsdf_basis(ns, t, b) */
    const __m128 sign = sel4(_mm_cmpge_ps(ns[2], zero), one, _mm_xor_ps(one, minus));
    const __m128 a = _mm_div_ps(_mm_xor_ps(one, minus), _mm_add_ps(sign, ns[2]));
    const __m128 c = _mm_mul_ps(_mm_mul_ps(ns[0], ns[1]), a);
    t[0] = _mm_add_ps(one, _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(sign, ns[0]), ns[0]), a));
    t[1] = _mm_mul_ps(sign, c);
    t[2] = _mm_mul_ps(_mm_xor_ps(sign, minus), ns[0]);
    b[0] = c;
    b[1] = _mm_add_ps(sign, _mm_mul_ps(_mm_mul_ps(ns[1], ns[1]), a));
    b[2] = _mm_xor_ps(ns[1], minus);
    /* to_world(cosdir, ns, wo), then normalize3(wo) */
    const __m128 l0 = load_lanes(cosdir, 0), l1 = load_lanes(cosdir, 1), l2 = load_lanes(cosdir, 2);
    for (int i = 0; i < 3; i++)
        o[i] = _mm_add_ps(_mm_add_ps(_mm_mul_ps(l0, t[i]), _mm_mul_ps(l1, b[i])), _mm_mul_ps(l2, ns[i]));
    const __m128 len = _mm_sqrt_ps(dot4(o, o)), pos = _mm_cmpgt_ps(len, zero);
    for (int i = 0; i < 3; i++)
        o[i] = sel4(pos, _mm_div_ps(o[i], len), o[i]);
    /* weight = albedo, density = max3(weight) / BSDF_DENSITY_DIFFUSE, then roulette() */
    for (int i = 0; i < 3; i++)
        w[i] = load_lanes(albedo, i);
    const __m128 density = _mm_div_ps(max4(w), _mm_set1_ps(BSDF_DENSITY_DIFFUSE));
    for (int i = 0; i < 3; i++)
        w[i] = _mm_and_ps(_mm_cmpgt_ps(w[i], zero), w[i]); /* !(w > 0): 0, also NaN */
    const __m128 m = max4(w);
    const __m128 p = sel4(_mm_cmplt_ps(m, zero), zero, _mm_min_ps(one, m)); /* clamp01 */
    const __m128 live = _mm_cmplt_ps(_mm_loadu_ps(u_roulette), p);
    for (int i = 0; i < 3; i++)
        w[i] = _mm_and_ps(live, _mm_div_ps(w[i], p));
    /* Lane k to wo[k], weight[k], density_factor[k]: transpose the 3 × 4 results to 4 × 4
     * (the fourth row unused) and store each lane's first three. */
    __m128 ro = _mm_and_ps(live, o[0]), go = _mm_and_ps(live, o[1]), bo = _mm_and_ps(live, o[2]), zo = zero;
    __m128 rw = w[0], gw = w[1], bw = w[2], zw = zero;
    _MM_TRANSPOSE4_PS(ro, go, bo, zo);
    _MM_TRANSPOSE4_PS(rw, gw, bw, zw);
    const __m128 lo[4] = {ro, go, bo, zo}, lw[4] = {rw, gw, bw, zw};
    float d[4];
    _mm_storeu_ps(d, _mm_and_ps(live, density));
    const int lm = _mm_movemask_ps(live);
    for (int k = 0; k < 4; k++) {
        float a[4], b[4];
        _mm_storeu_ps(a, lo[k]);
        _mm_storeu_ps(b, lw[k]);
        for (int i = 0; i < 3; i++) {
            wo[k][i] = a[i];
            weight[k][i] = b[i];
        }
        *density_factor[k] = d[k];
        alive[k] = (lm >> k) & 1;
    }
}
#endif

void bsdf_stratify(const float u[4], const float offset[4], float out_u[4], float out_cosdir[4])
{
    for (int d = 0; d < 4; d++) {
        float s = u[d] + offset[d];
        out_u[d] = s >= 1.0f ? s - 1.0f : s;
    }
    float a = 2.0f * out_u[BSDF_U_DIR0] - 1.0f, b = 2.0f * out_u[BSDF_U_DIR1] - 1.0f, r, phi;
    if (a == 0.0f && b == 0.0f) {
        r = 0.0f;
        phi = 0.0f;
    } else if (fabsf(a) > fabsf(b)) {
        r = a;
        phi = (BSDF_PI / 4.0f) * (b / a);
    } else {
        r = b;
        phi = BSDF_PI / 2.0f - (BSDF_PI / 4.0f) * (a / b);
    }
    float x = r * cosf(phi), y = r * sinf(phi);
    float z = sqrtf(fmaxf(0.0f, 1.0f - x * x - y * y));
    out_cosdir[0] = x;
    out_cosdir[1] = y;
    out_cosdir[2] = z;
    out_cosdir[3] = z / BSDF_PI;
}

/* bsdf_permute and bsdf_strata: one definition for C and GLSL. */
#include "shaders/bsdf_strata.glsl"
