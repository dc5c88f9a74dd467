/* settings.h — what a sequence's "settings" object sets: the enums of the settings that name
 * an alternative, their names, eng_settings with its defaults, and settings.def's table at run
 * time. */
#ifndef ISPM_SETTINGS_H
#define ISPM_SETTINGS_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum eng_indirect {
    ENG_INDIRECT_DEFAULT = 0, /* = ISPM */
    ENG_INDIRECT_NONE,        /* direct light only */
    ENG_INDIRECT_ISPM,        /* bounce map + CPU trace + photon volumes (ISPM §3) */
    ENG_INDIRECT_KDGATHER,    /* the same photon map, gathered per pixel from a k-d tree on the
                               * CPU (traditional photon mapping, ISPM Appendix A): the baseline */
    ENG_INDIRECT_QUADS,       /* camera-independent photon quads on the tangent plane (001 §3.3) */
    ENG_INDIRECT_TILEGATHER,  /* photons binned to screen tiles, each tile evaluating its list
                               * (002 §6.3); the same estimate as the k-d gather, bit for bit */
    ENG_INDIRECT_TILEGATHER_GL, /* the same tile lists evaluated in a GL compute shader (002 §6.3
                                 * as the paper runs it); equal up to llvmpipe's rounding */
    ENG_INDIRECT_FINALGATHER  /* the photon map looked up one bounce away: final gathering
                               * (003 Appendix A; Jensen 1996), rays traced with Embree */
} eng_indirect;

/* What the À-Trous filter keeps of its detail coefficients (002_… §7.3.1). */
typedef enum eng_atrous_detail {
    ENG_DETAIL_DEFAULT = 0, /* = clipped */
    ENG_DETAIL_CLIPPED,     /* clamp(D_i, −γσ_i, γσ_i), Eq. 7.8 */
    ENG_DETAIL_NONE,        /* scaling coefficients only (Dammertz et al.; 002 Fig. 7.2a) */
    ENG_DETAIL_ALL          /* every detail kept: reconstructs the input (a test of the transform) */
} eng_atrous_detail;

typedef enum eng_random_mode {
    ENG_RANDOM_DEFAULT = 0,   /* = maps */
    ENG_RANDOM_MAPS,          /* precomputed random maps seeded by scene quantities (ISPM §4.1) */
    ENG_RANDOM_PER_FRAME,     /* the same maps, seeds salted with the frame index (for comparison) */
    ENG_RANDOM_STRATIFIED     /* the maps' numbers rotated to one stratum per frame of a cycle of
                               * stratified_cycle frames (002 §4.2); repeats every cycle */
} eng_random_mode;

/* How each photon's kernel radius r_xy is chosen (ind_photon_radii, engine/indirect/ind_common.c). */
typedef enum eng_kernel_scaling {
    ENG_SCALING_DEFAULT = 0,  /* = path-density */
    ENG_SCALING_PATH_DENSITY, /* kernel_radius · clamp((1000 ρp)^(−1/4), 1/4, 2) (splat_radius) */
    ENG_SCALING_RAY_LENGTH,   /* 002 Eq. 6.1: the incoming ray's length over a scene-sized l_max */
    ENG_SCALING_TILE_DENSITY, /* 002 Eq. 6.2: the photon density of the screen tile it lands in */
    ENG_SCALING_BANDWIDTH,    /* 004 §6: variable bandwidth C = C0/√p, p = cos θ / d² */
    ENG_SCALING_ANISOTROPIC   /* 002 Eq. 6.3–6.5: path-density's r_xy, the ellipsoid stretched along
                               * ω_i's projection on the kernel plane by min(1/cos θ, s_max) */
} eng_kernel_scaling;

/* How the soft shadows of lights with a size find their occluders (shadow_pcss.c, 001 §3.4). */
typedef enum eng_pcss_blocker {
    ENG_PCSS_DEFAULT = 0, /* = map */
    ENG_PCSS_MAP,         /* the average occluder depth of a blocker map, a filter of the penumbra
                           * width it implies (percentage-closer soft shadows) */
    ENG_PCSS_RAYS         /* rays from the receiver to points of the light marched through the
                           * shadow map, an occluder where one crosses a stored surface (a
                           * receiver hidden behind an occluder's top still sees the light past
                           * its edge); no blocker map */
} eng_pcss_blocker;

/* The kernel's boundary correction (engine/indirect/boundary.h). */
typedef enum eng_boundary {
    ENG_BOUNDARY_DEFAULT = 0, /* = none */
    ENG_BOUNDARY_NONE,
    ENG_BOUNDARY_RENORMALIZE  /* each pixel's estimate over the kernel mass on its surface */
} eng_boundary;
/* What the eye sees in and through specular surfaces (mirrors, glass; 003 §3 step 5). */
typedef enum eng_specular {
    ENG_SPECULAR_DEFAULT = 0, /* = traced */
    ENG_SPECULAR_TRACED,      /* eye rays continued on the CPU with Embree (003 §3 option 1) */
    ENG_SPECULAR_ENVMAP,      /* a cube map per specular object, made at its centre (003 §3 option 3) */
    ENG_SPECULAR_OFF          /* specular surfaces show only their non-specular lobes */
} eng_specular;

/* How photon bounces after the bounce map are traced (trace_method.h, one file each). */
typedef enum eng_photon_trace {
    ENG_TRACE_DEFAULT = 0,   /* = embree */
    ENG_TRACE_EMBREE,        /* CPU ray tracing with Embree (003 §3 step 2) */
    ENG_TRACE_MULTI_IMAGE    /* image space, against cube G-buffers (004 §4–5) */
} eng_photon_trace;

/* What the multi-image trace does with a ray no map resolves (004 §5.2). */
typedef enum eng_miss_mode {
    ENG_MISS_DEFAULT = 0,    /* = embree */
    ENG_MISS_EMBREE,         /* trace it with Embree instead */
    ENG_MISS_DROP            /* end the path there (the paper's behaviour) */
} eng_miss_mode;

/* How the final gather seeds each pixel's gather directions (ind_finalgather.c). */
typedef enum eng_fg_seed {
    ENG_FG_SEED_DEFAULT = 0, /* = pixel */
    ENG_FG_SEED_PIXEL,       /* a hash of the eye position and the pixel */
    ENG_FG_SEED_SURFACE      /* a hash of the surface point's world cell and normal (003 §4.1) */
} eng_fg_seed;

/* A named bundle of settings (engine/scene/presets.c) that a sequence's own keys override. */
typedef enum eng_preset {
    ENG_PRESET_DEFAULT = 0, /* = none */
    ENG_PRESET_NONE,        /* no bundle: every setting its own default */
    ENG_PRESET_DRAFT,
    ENG_PRESET_INTERACTIVE,
    ENG_PRESET_CONVERGED
} eng_preset;

const char *eng_indirect_name(eng_indirect m);
const char *eng_trace_name(eng_photon_trace m);
const char *eng_miss_name(eng_miss_mode m);
const char *eng_specular_name(eng_specular m);
const char *eng_scaling_name(eng_kernel_scaling m);
const char *eng_random_name(eng_random_mode m);
const char *eng_detail_name(eng_atrous_detail m);
const char *eng_boundary_name(eng_boundary m);
const char *eng_pcss_blocker_name(eng_pcss_blocker m);

/* Engine settings. A zero-initialised struct means defaults (eng_settings_defaults fills
 * them in explicitly so the manifest can record the values used). */
typedef struct eng_settings {
    int shadow_map_size;  /* texels per side (per cube face for point lights); default 1024 */
    int pcf_radius;       /* PCF kernel half-width in texels: (2r+1)^2 taps; default 1 */
    float shadow_bias;    /* world-space offset along the normal before the lookup; default 0.002 */
    eng_pcss_blocker pcss_blocker; /* soft shadows' occluder search (shadow_pcss.c); default map */
    float exposure;       /* display transform: stops applied before sRGB encoding; default 0 */
    int exposure_auto;    /* `"exposure": "auto"`: the engine sets exposure from frame 0's
                           * log-average luminance (eng_exposure_key) and keeps it */
    int threads;          /* CPU worker threads (OpenMP, Embree, llvmpipe); 0 = default 2 */
    /* Indirect light (ISPM). */
    eng_indirect indirect;
    int photon_count;         /* bounce-map photons over all lights; default 32768 */
    int bounces;              /* optional cap on photon-map photons stored per path after the bounce
                               * map; 0 (default) = no cap: Russian roulette ends paths (003 §4) */
    float kernel_radius;      /* photon volume radius r_xy in metres at unit path-density scale; default 0.1 */
    float normal_compression; /* r_z / r_xy of the kernel ellipsoid (ISPM §5.1); default 0.25 */
    eng_random_mode random;
    int random_map_size;      /* entries per random table, a power of two; default 65536 */
    int random_seed;          /* seed of the random tables; default 1 */
    int stratified_cycle;     /* frames per stratification cycle (random = stratified); default 16 */
    /* Reconstruction filters (DESIGN.md step 7). With all of them off (the defaults) the
     * splat writes outgoing radiance directly, as before; with any on, it writes irradiance
     * (splat.irradiance) that the filters work on and the BSDF is applied last (002 Eq. 7.9). */
    int splat_subsample;      /* 1 (full resolution), 2, 4 or 8: photon volumes at 1/k resolution,
                               * joint bilateral upsampling level by level (003 §5.2); default 1 */
    int temporal;             /* 1: temporal accumulation (002 §7.2, Eq. 7.3–7.4); default 0 */
    float temporal_alpha;     /* the 0.95 of Eq. 7.4 (history weight); default 0.95 */
    int temporal_window;      /* > 0: the temporal and progressive state restarts at every frame that
                               * is a multiple of it (a bounded history: frame shards converge after
                               * a warm-up of window - 1 frames); 0 (default): never */
    int atrous_iterations;    /* À-Trous wavelet iterations (002 §7.3, Eq. 7.5), 0 = off; default 0 */
    eng_atrous_detail atrous_detail; /* default clipped */
    float atrous_gamma;       /* γ of Eq. 7.7; default 0.05 (002 §8.2's table) */
    /* Convergence for still views. */
    eng_kernel_scaling kernel_scaling; /* default path-density */
    int progressive;          /* 1: running mean of the indirect estimate while nothing moves, the
                               * kernel shrinking as in progressive photon mapping; default 0 */
    eng_boundary boundary;    /* kernel boundary correction after the method; default none */
    /* Photon trace method (trace_method.h). */
    eng_photon_trace photon_trace; /* default embree */
    int multi_image_maps;     /* cube maps (centres) of the multi-image trace, 1..8; default 2 */
    int multi_image_size;     /* texels per cube-map face side, 4..1024; default 64 */
    eng_miss_mode multi_image_miss; /* rays no map resolves: embree (default) or drop */
    int multi_image_compare;  /* 1: also trace every multi-image ray with Embree and count the
                               * hits that agree (the bench's measure); default 0 */
    /* Specular eye paths (specular.h). */
    eng_specular specular;    /* default traced */
    int specular_depth;       /* specular surfaces an eye path crosses, 1..16; default 4 */
    /* The frame files' EXR compression by name, one of settings.def's list; the engine passes it
     * on to capture, which knows what the names mean (cap_compression_parse). Default "by-kind". */
    char capture_compression[8];
    int capture_whole_frames; /* 1: no buffer stored once in an earlier frame's file (capture) */
    /* `"progressive_radius": "pixel"` (1): progressive photon mapping's radius per pixel
     * (progressive.h; every method but tile-gather-gl); "frame" (0, default): one scale per frame. */
    int progressive_pixel;
    /* `"bounce_strata": N` (2, 4, …, 64): the bounce map's first-bounce numbers
     * stratified within each N×N block of texels (bsdf_strata, bsdf.h); 0 (default) or 1: off. */
    int bounce_strata;
    /* `"final_gather_rays": N` (4, 16, 64, …, 4096): gather rays per pixel of the
     * "final-gather" method (ind_finalgather.c), a correlated multi-jittered set; default 64. */
    int final_gather_rays;
    /* `"final_gather_radius"`: the factor (0, 1] on every photon's kernel radius r_xy at the
     * final gather's lookups, which the gather's rays average, so a small kernel's noise matters
     * less than its edge bias; default 0.25. */
    float final_gather_radius;
    /* `"final_gather_seed"`: "pixel" (default) or "surface": a still surface seen from a moving
     * camera gathers along the same directions (ind_finalgather.c). */
    eng_fg_seed final_gather_seed;
    /* `"final_gather_cell"`: the world cell (m) that "surface" seeds quantise positions to;
     * default 0.01. */
    float final_gather_cell;
    /* `"final_gather_reuse": N`: a pixel's gathered light is reused by reprojection for up to
     * N frames while it shows the same surface and nothing in the scene moved; 1 (default): off. */
    int final_gather_reuse;
    /* `"preset"`: the bundle the sequence's settings were expanded from (recorded only). */
    eng_preset preset;
} eng_settings;

/* Fills every field still 0 (or "") with its default from settings.def. */
void eng_settings_defaults(eng_settings *s);

/* One line of settings.def at run time: what the parser, the manifest writer, the bench and
 * `ispm settings` read. Columns as settings.def describes them. */
typedef enum eng_setting_type {
    ENG_SETTING_INT,
    ENG_SETTING_FLOAT,
    ENG_SETTING_BOOL,
    ENG_SETTING_ENUM, /* a name that selects an enum value */
    ENG_SETTING_NAME  /* a name kept as text */
} eng_setting_type;

typedef enum eng_setting_ends {
    ENG_ENDS_CLOSED,  /* lo..hi */
    ENG_ENDS_OPEN_LO, /* (lo, hi] */
    ENG_ENDS_OPEN,    /* (lo, hi) */
    ENG_ENDS_POSITIVE /* (lo, hi], and the value's float not 0 */
} eng_setting_ends;

typedef struct eng_setting_name {
    const char *name;
    int value;
} eng_setting_name;

typedef struct eng_setting {
    const char *key;
    eng_setting_type type;
    const char *type_name; /* "int", "float", "bool", "enum", "name" */
    double def;            /* INT, FLOAT, BOOL, ENUM: the default value */
    const char *def_name;  /* ENUM, NAME: the default's name; NULL otherwise */
    double lo, hi;         /* INT, FLOAT */
    eng_setting_ends ends; /* FLOAT */
    int step;              /* INT: 2 or 4: a power of it; 1: any */
    const char *step_text; /* INT: what a value of the wrong step "is not" */
    int exact;             /* FLOAT: the manifest records the exact double, not the shortest decimal */
    const eng_setting_name *names; /* ENUM, NAME, in message order */
    int name_count;
    const char *note;      /* follows the range or the names in messages */
    const char *meaning;
    double (*get)(const eng_settings *s);              /* INT, FLOAT, BOOL, ENUM */
    void (*set)(eng_settings *s, double v);            /* INT, FLOAT, BOOL, ENUM */
    char *(*text)(eng_settings *s, size_t *size);      /* NAME: the field and its size */
    int (*recorded)(const eng_settings *s);            /* the manifest's "settings" holds it */
    const char *word;                                  /* FLOAT: a string taken for a number, or NULL */
    int (*word_get)(const eng_settings *s);            /* with word: 1 when the setting holds it */
    void (*word_set)(eng_settings *s, int on);
} eng_setting;

/* settings.def's lines in order; *count gets their number. */
const eng_setting *eng_settings_table(int *count);
/* The line of a key; NULL if there is none. */
const eng_setting *eng_setting_find(const char *key);
/* The name of an ENUM setting's value (0: the default's); "unknown" if it has none. */
const char *eng_setting_value_name(const eng_setting *d, int value);
/* The value s holds for d as text: %d, %g, true/false, the name or the word (the bench's
 * columns). */
void eng_setting_format(const eng_setting *d, const eng_settings *s, char *out, size_t size);

#ifdef __cplusplus
}
#endif

#endif
