/* random_maps.c — precomputed random maps and the hashes that seed paths into them
 * (001_e4bbaad47450cc5a.txt §3.1 "precomputed random map"; 003_d0bf8e920b03f4e1.txt §4.1
 * "Precomputed random numbers"; 004_77cf4e8ac7e68a89.txt §7).
 *
 * The tables are made once per run from a fixed 64-bit seed and never change, so a photon
 * path seeded by the same scene quantity (its bounce-map position) reads the same numbers
 * every frame and static parts of the scene get the same photons frame after frame.
 *
 * Generator (portable, integer-only up to the final conversions, so every machine makes the
 * same tables): splitmix64 (Steele, Lea & Flood 2014; the reference constants of
 * Vigna's splitmix64.c). The j-th output of the run is mix(seed + (j + 1)·0x9E3779B97F4A7C15)
 * and a uniform number is its top 24 bits × 2⁻²⁴, exact in a float. Table t (0 uniform,
 * 1 cosine, 2 sphere), entry i, number d (0..3) uses j = (t·size + i)·4 + d, so the tables are
 * independent streams of one generator. The direction tables use the midpoint form
 * (bits + ½)·2⁻²⁴ ∈ (0,1) so that no direction lies exactly in the tangent plane (pdf 0).
 *
 * Hashes: XXH32 (libxxhash) of the little-endian words of the input, seeded by the salt.
 * Floats enter as their IEEE-754 bits with −0.0 replaced by +0.0, so the two zeros seed the
 * same path. The GLSL bounce-map shader computes the same XXH32 of the same words. */
#include "bsdf.h"
#include "trace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
/* libxxhash's own XXH32, compiled into this file (its header's inline mode) so that the path
 * seeds, one a traced path, hash their 12 bytes without a library call; the same function. */
#define XXH_INLINE_ALL
#include <xxhash.h>

#define SPLITMIX_GAMMA 0x9E3779B97F4A7C15ull

static uint64_t splitmix64_at(uint64_t seed, uint64_t j)
{
    uint64_t z = seed + (j + 1) * SPLITMIX_GAMMA;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static float unit_half_open(uint64_t x) /* [0,1) */
{
    return (float)(x >> 40) * (1.0f / 16777216.0f);
}

static float unit_open(uint64_t x) /* (0,1) */
{
    return ((float)(x >> 40) + 0.5f) * (1.0f / 16777216.0f);
}

/* Malley's method: a concentric (Shirley–Chiu) map of the unit square onto the unit disk,
 * lifted to the hemisphere; pdf = cosθ/π (002_… §4.1 "cosine-weighted sampling"). */
static void cosine_dir(float u0, float u1, float out[4])
{
    double a = 2.0 * u0 - 1.0, b = 2.0 * u1 - 1.0, r, phi;
    if (a == 0.0 && b == 0.0) {
        r = 0.0;
        phi = 0.0;
    } else if (fabs(a) > fabs(b)) {
        r = a;
        phi = (ENG_PI / 4.0) * (b / a);
    } else {
        r = b;
        phi = (ENG_PI / 2.0) - (ENG_PI / 4.0) * (a / b);
    }
    double x = r * cos(phi), y = r * sin(phi);
    double z = sqrt(fmax(0.0, 1.0 - x * x - y * y));
    out[0] = (float)x;
    out[1] = (float)y;
    out[2] = (float)z;
    out[3] = (float)(z / ENG_PI);
}

static void sphere_dir(float u0, float u1, float out[4])
{
    double z = 1.0 - 2.0 * u0;
    double r = sqrt(fmax(0.0, 1.0 - z * z));
    double phi = 2.0 * ENG_PI * u1;
    out[0] = (float)(r * cos(phi));
    out[1] = (float)(r * sin(phi));
    out[2] = (float)z;
    out[3] = (float)(1.0 / (4.0 * ENG_PI));
}

eng_result rmap_create(uint64_t seed, uint32_t size, eng_random_maps *out, eng_error *err)
{
    memset(out, 0, sizeof *out);
    if (size == 0 || (size & (size - 1)) != 0)
        return eng_fail(err, ENG_ERR_INVALID, "random maps: size %u is not a power of two", size);
    out->uniform = malloc((size_t)size * 4 * sizeof(float));
    out->cosine = malloc((size_t)size * 4 * sizeof(float));
    out->sphere = malloc((size_t)size * 4 * sizeof(float));
    if (!out->uniform || !out->cosine || !out->sphere) {
        rmap_destroy(out);
        return eng_fail(err, ENG_ERR_NOMEM, "random maps: out of memory for %u entries", size);
    }
    out->size = size;
    for (uint64_t i = 0; i < size; i++) {
        for (uint64_t d = 0; d < 4; d++)
            out->uniform[4 * i + d] = unit_half_open(splitmix64_at(seed, (0 * (uint64_t)size + i) * 4 + d));
        uint64_t c = (1 * (uint64_t)size + i) * 4, s = (2 * (uint64_t)size + i) * 4;
        cosine_dir(unit_open(splitmix64_at(seed, c)), unit_open(splitmix64_at(seed, c + 1)), out->cosine + 4 * i);
        sphere_dir(unit_open(splitmix64_at(seed, s)), unit_open(splitmix64_at(seed, s + 1)), out->sphere + 4 * i);
    }
    return ENG_OK;
}

void rmap_destroy(eng_random_maps *rm)
{
    if (!rm)
        return;
    free(rm->uniform);
    free(rm->cosine);
    free(rm->sphere);
    memset(rm, 0, sizeof *rm);
}

static uint32_t float_word(float f)
{
    if (f == 0.0f)
        f = 0.0f; /* −0.0 → +0.0 */
    uint32_t w;
    memcpy(&w, &f, sizeof w);
    return w;
}

static uint32_t hash_words(const uint32_t *w, size_t n, uint32_t salt)
{
    unsigned char bytes[8 * 4];
    for (size_t i = 0; i < n; i++)
        for (int b = 0; b < 4; b++)
            bytes[4 * i + (size_t)b] = (unsigned char)(w[i] >> (8 * b));
    return (uint32_t)XXH32(bytes, n * 4, salt);
}

uint32_t rmap_hash3(const float p[3], uint32_t salt)
{
    uint32_t w[3] = {float_word(p[0]), float_word(p[1]), float_word(p[2])};
    return hash_words(w, 3, salt);
}

uint32_t rmap_hash_pixel(const float light[3], uint32_t x, uint32_t y, uint32_t face, uint32_t salt)
{
    uint32_t w[6] = {float_word(light[0]), float_word(light[1]), float_word(light[2]), x, y, face};
    return hash_words(w, 6, salt);
}

void rmap_strata_texel(const float light[3], uint32_t x, uint32_t y, uint32_t face, uint32_t strata_salt, int log2n,
                       uint32_t *index, uint32_t *pattern)
{
    uint32_t n = 1u << log2n;
    *index = (y & (n - 1u)) * n + (x & (n - 1u));
    *pattern = rmap_hash_pixel(light, x >> log2n, y >> log2n, face, strata_salt);
}

static int gcd(int a, int b)
{
    while (b) {
        int t = a % b;
        a = b;
        b = t;
    }
    return a;
}

void rmap_frame(const eng_settings *s, int frame, eng_rmap_frame *out)
{
    memset(out, 0, sizeof *out);
    for (int k = 1; k <= BSDF_STRATA_MAX_LOG2; k++)
        if (s->bounce_strata == 1 << k)
            out->strata_log2 = k;
    if (s->random == ENG_RANDOM_PER_FRAME)
        out->salt = (uint32_t)frame + 1u;
    out->strata_salt = out->salt ^ BSDF_STRATA_SALT ^ ((uint32_t)s->random_seed * 0x9e3779b9u);
    if (s->random != ENG_RANDOM_STRATIFIED)
        return;
    int K = s->stratified_cycle > 0 ? s->stratified_cycle : 1;
    int k = ((frame % K) + K) % K;
    /* g₃: the g coprime to K nearest K/φ, in integer thousandths (1 always qualifies). */
    const long long target = (long long)K * 618034 / 1000;
    int g3 = 1;
    long long best = -1;
    for (int g = 1; g < K; g++) {
        long long dist = llabs((long long)g * 1000 - target);
        if (gcd(g, K) == 1 && (best < 0 || dist < best)) {
            best = dist;
            g3 = g;
        }
    }
    const int g[4] = {1, 1, 1, g3};
    out->stratified = 1;
    for (int d = 0; d < 4; d++)
        out->offset[d] = (float)((long long)k * g[d] % K) / (float)K;
}
