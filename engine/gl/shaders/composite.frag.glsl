#version 450 core
// Composite: final linear radiance = direct + indirect (ISPM §3 last step) + specular (eye
// paths continued through mirrors and glass, engine/specular.h) + emission of the visible
// surface (gbuffer.emission), the translucent surfaces over it, and the display
// transform: exposure in stops, clamp to [0,1], sRGB encoding (IEC 61966-2-1).
uniform sampler2D u_direct;
uniform sampler2D u_indirect;
uniform int u_has_indirect;
uniform sampler2D u_specular;
uniform int u_has_specular;
uniform sampler2D u_emission;
uniform int u_has_emission;
uniform sampler2D u_translucent; // premultiplied RGBA of the alphaMode BLEND surfaces (pass_translucent.c)
uniform int u_has_translucent;
uniform float u_exposure;
uniform sampler2D u_occlusion; // gbuffer attachment 5: A = occlusion (glTF §3.9.3), indirect only
uniform int u_has_occlusion;

layout(location = 0) out vec4 o_radiance;
layout(location = 1) out vec4 o_display;

vec3 srgb_encode(vec3 c)
{
    vec3 lo = c * 12.92;
    vec3 hi = 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055;
    return mix(lo, hi, step(vec3(0.0031308), c));
}

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec3 l = texelFetch(u_direct, px, 0).rgb;
    if (u_has_indirect == 1 && u_has_occlusion == 1)
        l += texelFetch(u_indirect, px, 0).rgb * texelFetch(u_occlusion, px, 0).a;
    else if (u_has_indirect == 1)
        l += texelFetch(u_indirect, px, 0).rgb;
    if (u_has_specular == 1)
        l += texelFetch(u_specular, px, 0).rgb;
    if (u_has_emission == 1)
        l += texelFetch(u_emission, px, 0).rgb;
    if (u_has_translucent == 1) { // back-to-front "over" of the translucent layers
        vec4 t = texelFetch(u_translucent, px, 0);
        l = t.rgb + (1.0 - t.a) * l;
    }
    o_radiance = vec4(l, 1.0);
    o_display = vec4(srgb_encode(clamp(l * exp2(u_exposure), 0.0, 1.0)), 1.0);
}
