// bsdf_constants.glsl — the constants of the photon scattering model, in the one file that
// both processors read: it is valid C and valid GLSL (only comments and #defines), included
// by engine/bsdf.h and spliced into the bounce-map shader with `#pragma ispm_include`.
// engine/bsdf.c and shaders/bsdf_sample.glsl implement the same sampling on top of it, line
// for line; tests/test_bsdf.c feeds both the same random numbers and compares the results.
#ifndef ISPM_BSDF_CONSTANTS_GLSL
#define ISPM_BSDF_CONSTANTS_GLSL

// Lobes a scattering event can take (bsdf_lobe in bsdf.h, the int bsdf_scatter returns in GLSL).
#define BSDF_LOBE_ABSORBED 0 // Russian roulette ended the path (or the sample left below the surface)
#define BSDF_LOBE_DIFFUSE 1  // Lambertian, cosine-sampled
#define BSDF_LOBE_GLOSSY 2   // GGX metal
#define BSDF_LOBE_MIRROR 3   // smooth metal: delta reflection
#define BSDF_LOBE_REFLECT 4  // glass: Fresnel or total internal reflection (delta)
#define BSDF_LOBE_REFRACT 5  // glass: refraction (delta)

// Lobe order of the glTF mixture, tested with the lobe-choice number u[BSDF_U_LOBE]:
// metal first (u < metallic), then glass on the rest ((u − metallic)/(1 − metallic) <
// transmission), then diffuse. Which of the four uniforms of an event does what:
#define BSDF_U_LOBE 0     // lobe choice
#define BSDF_U_ROULETTE 1 // Russian roulette (002_… §4.4)
#define BSDF_U_DIR0 2     // GGX half-vector θ, or the glass Fresnel choice (002_… §4.5)
#define BSDF_U_DIR1 3     // GGX half-vector φ

#define BSDF_MIRROR_ROUGHNESS 0.01f // metal below this roughness is a perfect mirror
#define BSDF_MIN_ALPHA 1e-3f        // GGX α = roughness², at least this
#define BSDF_PI 3.14159265358979323846f
#define BSDF_TWO_PI 6.28318530717958647692f

// Path-density factors (003_d0bf8e920b03f4e1.txt §4.3): ρL/1000 for a diffuse scatter,
// ρS/10 for a glossy one, ρS for mirror reflection and refraction.
#define BSDF_DENSITY_DIFFUSE 1000.0f
#define BSDF_DENSITY_GLOSSY 10.0f

// Stratified first bounces within one frame (`"bounce_strata"`, bsdf_strata): blocks of
// 2^k × 2^k bounce-map texels, k = 1..BSDF_STRATA_MAX_LOG2; a block's permutations are seeded
// by the texel hash of its block coordinates with this salt XORed into the frame's salt (and
// random_seed·0x9e3779b9; rmap_frame), so that they do not repeat the random-map entry of the
// texel with the same coordinates.
#define BSDF_STRATA_MAX_LOG2 6
#define BSDF_STRATA_SALT 0x5bd1e995u

#endif
