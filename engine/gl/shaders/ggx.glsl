// ggx.glsl — the GGX microfacet terms shared by the direct, bounce and splat shaders
// (Walter et al. 2007; 002_… §4.1), spliced in where a shader says
// `#pragma ispm_include "ggx.glsl"` (see glu_program in engine/glutil.c).

// Normal distribution D(h) for n·h and α².
float ggx_d(float noh, float a2)
{
    float d = noh * noh * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

// Smith's masking term G1 for n·x and α².
float smith_g1(float c, float a2)
{
    return 2.0 * c / (c + sqrt(a2 + (1.0 - a2) * c * c));
}
