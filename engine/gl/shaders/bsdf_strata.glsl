// bsdf_strata.glsl — stratified first bounces within one frame (`"bounce_strata"`; bsdf.h,
// bsdf_strata), in the one file that both processors read: valid C (engine/bsdf.c includes it)
// and valid GLSL (spliced after bsdf_constants.glsl into the bounce-map shader with
// `#pragma ispm_include`), so the two cannot drift; tests/test_bsdf.c still runs both on the
// same inputs. Kensler, "Correlated Multi-Jittered Sampling", Pixar Technical Memo 13-01 (2013):
// §3 the hashed permutation (bsdf_permute), §5–6 the correlated multi-jittered set (bsdf_strata).
// 002_558366c451cd32fd.txt §4.2 stratifies across frames; this stratifies within one frame.
#ifdef __STDC__
#include <stdint.h>
#include <string.h>
#define BSDF_UINT uint32_t
#define BSDF_FLOAT(x) ((float)(x))
#define BSDF_IN4(v) const float v[4]
#define BSDF_OUT4(v) float v[4]
#define BSDF_LOCAL static
static inline float bsdf_bits_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}
#else
#define BSDF_UINT uint
#define BSDF_FLOAT(x) float(x)
#define BSDF_IN4(v) vec4 v
#define BSDF_OUT4(v) out vec4 v
#define BSDF_LOCAL
#define bsdf_bits_float uintBitsToFloat
#endif

// Element i of permutation p of [0, l) (Kensler 2013 §3, cycle-walking: one pass when l is a
// power of two).
BSDF_UINT bsdf_permute(BSDF_UINT i, BSDF_UINT l, BSDF_UINT p)
{
    BSDF_UINT w = l - 1u;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    do {
        i ^= p;
        i *= 0xe170893du;
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i *= 0x0929eb3fu;
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i *= 1u | p >> 27;
        i *= 0x6935fa69u;
        i ^= (i & w) >> 11;
        i *= 0x74dcb303u;
        i ^= (i & w) >> 2;
        i *= 0x9e501cc3u;
        i ^= (i & w) >> 2;
        i *= 0xc860a3dfu;
        i &= w;
        i ^= i >> 5;
    } while (i >= l);
    return (i + p) % l;
}

// (stratum + jitter)·inv, kept below 1 (the sum may round up to the next integer).
BSDF_LOCAL float bsdf_strata_unit(BSDF_UINT stratum, float jitter, float inv)
{
    float x = (BSDF_FLOAT(stratum) + jitter) * inv;
    return x < 1.0f ? x : bsdf_bits_float(0x3f7fffffu); // 1 − 2⁻²⁴
}

// Sample `index` (0..N²−1) of the block pattern `pattern`, N = 2^log2n, the event's own numbers u
// as the jitter within each stratum (bsdf.h).
void bsdf_strata(BSDF_IN4(u), BSDF_UINT index, BSDF_UINT log2n, BSDF_UINT pattern, BSDF_OUT4(out_u))
{
    BSDF_UINT n = 1u << log2n, m = n * n;
    float inv = bsdf_bits_float((127u - 2u * log2n) << 23); // 2^−2·log2n = 1/m, exactly
    // Kensler 2013 §6 cmj(): the sample order, then the two coarse permutations.
    BSDF_UINT s = bsdf_permute(index, m, pattern * 0x51633e2du);
    BSDF_UINT cx = s % n, cy = s / n;
    BSDF_UINT sx = bsdf_permute(cx, n, pattern * 0xa511e9b3u);
    BSDF_UINT sy = bsdf_permute(cy, n, pattern * 0x63d83595u);
    out_u[BSDF_U_DIR0] = bsdf_strata_unit(cx * n + sy, u[BSDF_U_DIR0], inv);
    out_u[BSDF_U_DIR1] = bsdf_strata_unit(cy * n + sx, u[BSDF_U_DIR1], inv);
    // 1D strata of the lobe choice and Russian roulette, independent of the direction's.
    out_u[BSDF_U_LOBE] = bsdf_strata_unit(bsdf_permute(index, m, pattern * 0xa399d265u), u[BSDF_U_LOBE], inv);
    out_u[BSDF_U_ROULETTE] = bsdf_strata_unit(bsdf_permute(index, m, pattern * 0x711ad6a5u), u[BSDF_U_ROULETTE], inv);
}
