#version 450 core
// bsdf_probe.frag.glsl — a test fixture, not a pass: runs bsdf_sample.glsl's bsdf_scatter and
// bsdf_stratify and bsdf_strata once per fragment on inputs read from textures, so tests/test_bsdf.c can feed
// the GLSL twin and engine/bsdf.c the same random numbers and compare what they return. Input
// texel (x, y) of every texture is one sample; output texel (x, y) its result.
uniform sampler2D u_base;   // base colour RGB, eta of the medium the photon travels in
uniform sampler2D u_mat;    // roughness, metallic, transmission, ior
uniform sampler2D u_n;      // shading normal as authored (xyz)
uniform sampler2D u_wi;     // toward where the photon came from (xyz)
uniform sampler2D u_u;      // the event's 4 uniforms
uniform sampler2D u_cosdir; // its cosine-weighted direction (xyz, pdf)
uniform sampler2D u_offset; // Cranley–Patterson offsets for bsdf_stratify
uniform sampler2D u_strata; // bsdf_strata: index, log2n, pattern's low and high 16 bits

layout(location = 0) out vec4 o_wo;      // wo, lobe
layout(location = 1) out vec4 o_weight;  // weight RGB, path-density factor
layout(location = 2) out vec4 o_eta;     // eta after the event
layout(location = 3) out vec4 o_su;      // bsdf_stratify's rotated uniforms
layout(location = 4) out vec4 o_scosdir; // and its cosine-weighted direction
layout(location = 5) out vec4 o_strata;  // bsdf_strata's stratified uniforms

#pragma ispm_include "bsdf_constants.glsl"
#pragma ispm_include "bsdf_sample.glsl"
#pragma ispm_include "bsdf_strata.glsl"

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 base = texelFetch(u_base, px, 0);
    float eta = base.w;
    vec3 wo, weight;
    float density;
    int lobe = bsdf_scatter(base.rgb, texelFetch(u_mat, px, 0), texelFetch(u_n, px, 0).xyz,
                            texelFetch(u_wi, px, 0).xyz, eta, texelFetch(u_u, px, 0),
                            texelFetch(u_cosdir, px, 0), wo, weight, density);
    o_wo = vec4(wo, float(lobe));
    o_weight = vec4(weight, density);
    o_eta = vec4(eta, 0.0, 0.0, 0.0);
    vec4 su, scd;
    bsdf_stratify(texelFetch(u_u, px, 0), texelFetch(u_offset, px, 0), su, scd);
    o_su = su;
    o_scosdir = scd;
    vec4 st = texelFetch(u_strata, px, 0);
    bsdf_strata(texelFetch(u_u, px, 0), uint(st.x), uint(st.y), uint(st.z) | (uint(st.w) << 16), o_strata);
}
