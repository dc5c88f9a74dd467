/* passes.h — the passes room's face: the GL passes every indirect method shares. Eye
 * G-buffer, shadow maps (with their methods, shadow.h), light-space G-buffers and bounce maps,
 * direct light, the reconstruction filters and the composite; translucency (translucent.h).
 * Passes take their inputs as arguments and return their outputs (targets owned by the pass
 * object); no pass reaches into another's state. */
#ifndef ISPM_PASSES_H
#define ISPM_PASSES_H

#include "trace.h"

/* ---------------------------------------------------------------- outputs */

/* One buffer a pass announces (DESIGN.md "Buffer (EXR part) names"). Each pass declares its
 * outputs as a table next to its code, ended by an entry whose name is NULL; the frame loop
 * (engine.c) announces a pass's target by walking its table, in table order, so the tables,
 * not hand-written calls, name the buffers. name is the part's name as DESIGN.md spells it;
 * pass_output_name fills its placeholders from a pass_output_at: <i> the light, <f> the face,
 * [...] written only for lights with more than one face (cube maps), <k> the level or
 * iteration plus level_offset, <m> the indirect method's buffer prefix (ind_method.prefix). */
#define PASS_OUT_CPU (-1) /* attachment of a buffer the frame loop assembles on the CPU */
#define PASS_OUT_MAX_CHANNELS 8
typedef struct pass_output {
    const char *name;
    int attachment; /* colour attachment of the pass's target it is read from, or PASS_OUT_CPU */
    int pick[4];    /* the components read, in channel order (attachment >= 0 only) */
    const char *channels[PASS_OUT_MAX_CHANNELS]; /* channel names, NULL after the last */
    int level_offset;                            /* added to pass_output_at.level for <k> */
    int optional; /* 1: announced only where the frame loop says so (direct.penumbra) */
} pass_output;

/* Where in the frame loop a table is walked: what the placeholders stand for. */
typedef struct pass_output_at {
    uint32_t light;
    int faces, face; /* faces > 1 writes [...] */
    int level;
    const char *prefix;
} pass_output_at;

/* The number of channels of o (1..PASS_OUT_MAX_CHANNELS). */
int pass_output_channels(const pass_output *o);
/* o's name with its placeholders filled from at (NULL: all zero, no prefix) into out; returns
 * 0, or -1 when it does not fit or a placeholder is unknown. */
int pass_output_name(const pass_output *o, const pass_output_at *at, char *out, size_t size);

/* The tables (each pass's file): the eye G-buffer (gbuffer.material assembled on the CPU from
 * attachments 3 and 4), its subsampled levels, the shadow maps, the light G-buffers and bounce
 * maps (bounce.* assembled on the CPU from the bounce target), direct light, the filters and
 * the composite. pass_resolve_outputs is also the layout of a method's (or the boundary or
 * progressive pass's) output target when no filter runs: indirect.radiance in attachment 0. */
extern const pass_output pass_gbuffer_outputs[];
extern const pass_output pass_gbuffer_level_outputs[];
extern const pass_output pass_shadow_outputs[];
extern const pass_output pass_lightmaps_outputs[];
extern const pass_output pass_direct_outputs[];
extern const pass_output pass_upsample_outputs[];
extern const pass_output pass_temporal_outputs[];
extern const pass_output pass_atrous_outputs[];        /* per iteration, from its target */
extern const pass_output pass_atrous_result_outputs[]; /* from the last iteration's target */
extern const pass_output pass_resolve_outputs[];
extern const pass_output pass_composite_outputs[];

/* ---------------------------------------------------------------- passes */

/* Eye G-buffer (pass_gbuffer.c). Attachments: 0 position.xyz + coverage in w, 1 normal.xyz,
 * 2 albedo.rgb, 3 (roughness, metallic, transmission, ior), 4 (eye depth, material id,
 * motion x, motion y). Background: zeros, id −1. */
typedef struct pass_gbuffer pass_gbuffer;
eng_result pass_gbuffer_create(int width, int height, pass_gbuffer **out, eng_error *err);
const glu_target *pass_gbuffer_run(pass_gbuffer *p, const eng_frame_scene *fs);
void pass_gbuffer_destroy(pass_gbuffer *p);

typedef struct pass_shadow pass_shadow;
eng_result pass_shadow_create(int size, uint32_t light_count, pass_shadow **out, eng_error *err);
/* Renders light i's map; returns it (owned by the pass). */
const shadow_map *pass_shadow_run(pass_shadow *p, const eng_frame_scene *fs, uint32_t light);
void pass_shadow_destroy(pass_shadow *p);

/* Direct light (pass_direct.c): deferred shading of the G-buffer with all lights and PCF
 * shadow lookups; attachment 0 holds radiance RGB. */
typedef struct pass_direct pass_direct;
/* pcss_rays: the soft shadows of lights with a size by rays (shadow_pcss.glsl, compiled in with
 * PCSS_RAYS) instead of the blocker map's filter. */
eng_result pass_direct_create(int width, int height, int pcss_rays, pass_direct **out, eng_error *err);
/* extra[l]: light l's shadow-method map (shadow.h; the blocker map of a light with a size). */
/* World size of one shadow texel of light l (u_shadow_texel of shadow_pcf.glsl): per metre of
 * distance for point and spot lights, absolute for directional ones. */
float pass_direct_shadow_texel(const eng_light_pose *l, const shadow_map *sm, const eng_settings *s);
const glu_target *pass_direct_run(pass_direct *p, const eng_frame_scene *fs, const glu_target *gbuf,
                                  const shadow_map *const *shadows, const glu_target *const *extra,
                                  const eng_settings *s);
void pass_direct_destroy(pass_direct *p);

/* Light-space G-buffer (pass_lightgbuffer.c, ISPM §3 step 1b) and bounce map
 * (pass_bounce.c, §4.2), per light, at `size` texels per face: layered targets with one
 * layer per face of light_views. The light G-buffer has 4 attachments (position + coverage,
 * modelled normal, albedo, material); the bounce map 2 (power RGB + ρp, direction + ior). */
typedef struct light_maps {
    shadow_map views;   /* faces and matrices (its target unused) */
    glu_target gbuffer; /* 4 attachments */
    glu_target bounce;  /* 2 attachments */
    int size;
} light_maps;

typedef struct pass_lightmaps pass_lightmaps;
eng_result pass_lightmaps_create(const eng_random_maps *rm, pass_lightmaps **out, eng_error *err);
/* Renders light `light`'s G-buffer and bounce map at size² texels per face into lm
 * (targets are (re)allocated when the size or face count changes). */
typedef struct eng_rmap_frame eng_rmap_frame;
/* rf: how this frame reads the random maps (rmap_frame), the same for the CPU trace. */
eng_result pass_lightmaps_run(pass_lightmaps *p, const eng_frame_scene *fs, uint32_t light, int size,
                              const eng_rmap_frame *rf, light_maps *lm, eng_error *err);
void light_maps_release(light_maps *lm);
void pass_lightmaps_destroy(pass_lightmaps *p);


/* Reconstruction filters (pass_filter.c; DESIGN.md step 7). G-buffer targets are laid out as
 * pass_gbuffer's: 0 position, 1 normal (w: the point's eye depth in the previous frame),
 * 2 albedo, 3 material, 4 (eye depth, material id, motion x, motion y). Every run returns the
 * pass's own target(s); inputs are textures. */

/* Joint bilateral upsampling by one level (003 §5.2, 004 §6): from a low-resolution G-buffer
 * and its irradiance + glossy textures to hi_gb's resolution. Returns 2 attachments:
 * 0 irradiance (A = weight sum, 0 where the closest-depth tap was taken alone), 1 glossy. */
typedef struct pass_upsample pass_upsample;
eng_result pass_upsample_create(int width, int height, pass_upsample **out, eng_error *err);
const glu_target *pass_upsample_run(pass_upsample *p, const glu_target *lo_gb, GLuint lo_irradiance,
                                    GLuint lo_glossy, const glu_target *hi_gb);
void pass_upsample_destroy(pass_upsample *p);

/* Temporal accumulation (002 §7.2, Eq. 7.3–7.4). Keeps its result and the G-buffer's normal
 * and depth for the next call; the first call after create or reset has no history (α = 0).
 * Returns 2 attachments: 0 result RGB + α in A, 1 the reprojected history RGB. */
typedef struct pass_temporal pass_temporal;
eng_result pass_temporal_create(int width, int height, pass_temporal **out, eng_error *err);
const glu_target *pass_temporal_run(pass_temporal *p, const glu_target *gb, GLuint irradiance, float alpha);
void pass_temporal_reset(pass_temporal *p);
void pass_temporal_destroy(pass_temporal *p);

/* Edge-avoiding À-Trous with variance-clipped details (002 §7.3, Eq. 7.5–7.8), `iterations`
 * iterations (1..8) at steps 1, 2, 4, ... Returns an array of `iterations` targets, one per
 * iteration i, with 4 attachments: 0 S_{i+1}, 1 the kept detail D'_i, 2 Σ_{k≤i} D'_k,
 * 3 S_{i+1} + Σ_{k≤i} D'_k (the last one's is the filter's result). */
typedef struct pass_atrous pass_atrous;
eng_result pass_atrous_create(int width, int height, int iterations, pass_atrous **out, eng_error *err);
const glu_target *pass_atrous_run(pass_atrous *p, const glu_target *gb, GLuint irradiance,
                                  eng_atrous_detail detail, float gamma);
void pass_atrous_destroy(pass_atrous *p);

/* The BSDF applied to reconstructed irradiance (002 §7.4 Eq. 7.9) plus the glossy radiance:
 * outgoing indirect radiance RGB in attachment 0. */
typedef struct pass_resolve pass_resolve;
eng_result pass_resolve_create(int width, int height, pass_resolve **out, eng_error *err);
const glu_target *pass_resolve_run(pass_resolve *p, const glu_target *gb, GLuint irradiance, GLuint glossy);
void pass_resolve_destroy(pass_resolve *p);

/* Composite (pass_composite.c): attachment 0 = direct + indirect + specular + emission
 * (linear radiance), attachment 1 = display transform (exposure, clamp, sRGB encoding).
 * indirect, specular and emission may be 0 (not added). */
typedef struct pass_composite pass_composite;
eng_result pass_composite_create(int width, int height, pass_composite **out, eng_error *err);
const glu_target *pass_composite_run(pass_composite *p, GLuint direct_tex, GLuint indirect_tex,
                                     GLuint specular_tex, GLuint emission_tex, GLuint translucent_tex, const eng_settings *s);
void pass_composite_destroy(pass_composite *p);
/* Indirect light × the A of tex (the eye G-buffer's attachment 5: occlusion textures) from now
 * on; 0: not multiplied (scenes without an occlusion texture). */
void pass_composite_set_occlusion(pass_composite *p, GLuint tex);

#endif
