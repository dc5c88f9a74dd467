/* eng.h — the engine's one public header.
 *
 * Three groups of names live here:
 *   scn_*  the scene: what a glTF 2.0 file holds once validated (meshes, node hierarchy,
 *          cameras, KHR_lights_punctual lights, materials, animations), and its evaluation
 *          at a frame time t (animation sampling, world matrices).
 *   seq_*  the sequence file (JSON): which scene, how many frames at what rate, resolution,
 *          camera, engine settings and what to capture.
 *   eng_*  the renderer: an OSMesa GL context and the passes, which announce every buffer
 *          they produce to registered listeners. The engine knows nothing about files.
 *
 * Conventions shared by every module (tests rely on them):
 *   - Units: metres, right-handed, Y up (glTF). Matrices are column-major float[16] as in GL
 *     and glTF: element (row r, column c) is m[c*4 + r].
 *   - Quaternions are (x, y, z, w) as in glTF.
 *   - Light intensity: point and spot lights carry radiant intensity in W/sr per colour
 *     channel (glTF `intensity` × `color`); directional lights carry irradiance in W/m²
 *     (glTF's photometric units are deliberately read as radiometric ones).
 *   - Announced pixel data is float32, channels interleaved, row-major, row 0 is the TOP
 *     row of the image (the EXR convention; the GL passes flip when they read back).
 *   - Errors: functions that can fail on input or environment return an eng_result and fill
 *     an eng_error whose message names the file and the problem in one line.
 */
#ifndef ISPM_ENG_H
#define ISPM_ENG_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- errors */

typedef enum eng_result {
    ENG_OK = 0,
    ENG_ERR_IO,          /* file missing, unreadable, unwritable, disk full */
    ENG_ERR_PARSE,       /* syntax: not JSON / not glTF */
    ENG_ERR_INVALID,     /* well-formed but wrong: bad index, accessor overrun, cycle, NaN... */
    ENG_ERR_UNSUPPORTED, /* valid glTF that this tool does not handle (e.g. orthographic) */
    ENG_ERR_GL,          /* GL context or shader failure */
    ENG_ERR_NOMEM,
    ENG_ERR_ABORTED      /* a listener asked to stop */
} eng_result;

typedef struct eng_error {
    char msg[1024]; /* one line: "<file>: <where>: <problem>" */
} eng_error;

/* Formats msg into err (if err is non-NULL) and returns code. */
eng_result eng_fail(eng_error *err, eng_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

const char *eng_result_name(eng_result r);

/* ---------------------------------------------------------------- scene */

#define SCN_NAME_MAX 64
#define SCN_MAX_WARNINGS 16
#define SCN_WARNING_MAX 240

typedef enum scn_light_type {
    SCN_LIGHT_POINT = 0,
    SCN_LIGHT_SPOT,
    SCN_LIGHT_DIRECTIONAL
} scn_light_type;

typedef enum scn_wrap { SCN_WRAP_REPEAT = 0, SCN_WRAP_CLAMP, SCN_WRAP_MIRROR } scn_wrap;

/* A glTF texture as one use decodes it: RGBA floats, linear (sRGB-decoded for base colour
 * and emissive, glTF §3.9.2), row 0 the TOP of the image (uv (0,0) is its top-left corner,
 * glTF §3.8.4), with its sampler's wrap modes and filters. */
#define SCN_MAX_MIPS 32
typedef struct scn_texture {
    uint32_t width, height;
    float *texels;
    int srgb;
    scn_wrap wrap_s, wrap_t;
    int mag_linear;  /* magFilter LINEAR (the default) or NEAREST */
    int min_filter;  /* the GL enum; default LINEAR_MIPMAP_LINEAR */
    /* The mip chain (texture_mip.c), made by the loader where min_filter uses mipmaps and
     * uploaded as is to GL, so CPU and GPU sample the same levels: level l is max(1, w >> l) ×
     * max(1, h >> l) texels, mips[0] = texels; levels = 1 without mipmaps. */
    uint32_t levels;
    float *mips[SCN_MAX_MIPS];
} scn_texture;

/* A material's texture: which scn_texture, which TEXCOORD set, and KHR_texture_transform
 * as uv' = (t[0] t[2] t[4]; t[1] t[3] t[5]) · (u, v, 1). */
typedef struct scn_texref {
    int32_t texture; /* into scn_scene.textures; -1: none */
    int texcoord;    /* 0 or 1 */
    float transform[6];
} scn_texref;

typedef enum scn_alpha_mode { SCN_ALPHA_OPAQUE = 0, SCN_ALPHA_MASK, SCN_ALPHA_BLEND } scn_alpha_mode;

typedef struct scn_material {
    char name[SCN_NAME_MAX];
    float base_color[4]; /* linear RGBA baseColorFactor; times base_color_tex where it has one */
    float metallic;      /* metallicFactor, default 1 per glTF */
    float roughness;     /* roughnessFactor, default 1 */
    float transmission;  /* KHR_materials_transmission transmissionFactor, default 0 */
    float ior;           /* KHR_materials_ior, default 1.5 */
    float emissive[3];   /* emissiveFactor × KHR_materials_emissive_strength (W/m²/sr) */
    int double_sided;
    /* Textures (glTF §3.9): base colour and metallicRoughness are used by every pass
     * (scn_base_color_at, rt_hit); emissive by the eye G-buffer (gbuffer.emission) and at
     * CPU hits (rt_hit.emissive_tex); occlusion by the eye G-buffer, on indirect light in
     * the composite; normal (tangent space, glTF §3.9.3) wherever a shading normal is read:
     * both G-buffers (normal_map.glsl) and CPU hits (scn_normal_at). */
    scn_texref base_color_tex, metallic_roughness_tex, normal_tex, occlusion_tex, emissive_tex;
    float normal_scale; /* normalTexture.scale: the map's X and Y are multiplied by it; default 1 */
    scn_alpha_mode alpha_mode;
    float alpha_cutoff; /* default 0.5 */
    /* occlusionTexture.strength: indirect light × (1 + strength·(R − 1)) (glTF §3.9.3) */
    float occlusion_strength;
} scn_material;

/* One triangle list. Positions and normals in the mesh's object space, 3 floats per vertex.
 * Normals are always present: where the glTF has none, the loader computes flat normals
 * (and un-shares the vertices so each triangle has its own). */
typedef struct scn_primitive {
    uint32_t vertex_count;
    float *positions;
    float *normals;
    uint32_t index_count; /* multiple of 3 */
    uint32_t *indices;
    float *texcoords[2];  /* TEXCOORD_0/1, 2 floats per vertex, or NULL */
    float *colors;        /* COLOR_0 as linear RGBA, 4 floats per vertex, or NULL */
    int32_t material;     /* index into materials, or -1 for the glTF default material */
    /* Skinning (glTF §3.7.3): JOINTS_0[/1] (indices into the drawing node's skin joints) and
     * WEIGHTS_0[/1], `influences` per vertex (4, or 8 with JOINTS_1/WEIGHTS_1), or NULL. */
    uint32_t *joints;
    float *weights;
    uint32_t influences;
    /* Morph targets (glTF §3.7.2.2): target_count × vertex_count × 3 POSITION and NORMAL
     * deltas (NULL where no target has that attribute; a target without it adds 0). */
    uint32_t target_count;
    float *target_positions, *target_normals;
    int flat; /* normals were computed flat by the loader: deformation recomputes them */
    /* Tangents (glTF §3.7.2.1 TANGENT: xyz unit, w = ±1 the bitangent's handedness), 4 floats
     * per vertex: the glTF's, or generated by scn_generate_tangents where the material has a
     * normal texture and the glTF gives none; NULL otherwise. target_tangents: morph TANGENT
     * deltas (xyz), target_count × vertex_count × 3, or NULL. */
    float *tangents;
    float *target_tangents;
} scn_primitive;

typedef struct scn_mesh {
    char name[SCN_NAME_MAX];
    uint32_t first_primitive; /* into scn_scene.primitives */
    uint32_t primitive_count;
    uint32_t weight_count; /* morph targets of its primitives (all have the same number) */
    float *weights;        /* mesh.weights, or zeros: the default morph weights */
} scn_mesh;

/* A glTF skin: joint nodes (scene node indices) and their inverse bind matrices
 * (column-major, identity where the file gives none). */
typedef struct scn_skin {
    uint32_t joint_count;
    int32_t *joints;
    float *inverse_bind;
} scn_skin;

typedef struct scn_camera {
    char name[SCN_NAME_MAX];
    float yfov;        /* radians */
    float aspect;      /* 0 = use the image's */
    float znear, zfar; /* zfar 0 = infinite in glTF; the loader replaces it by 1000·znear */
} scn_camera;

typedef struct scn_light {
    char name[SCN_NAME_MAX];
    scn_light_type type;
    float color[3];
    float intensity;  /* W/sr (point, spot) or W/m² (directional); see header comment */
    float range;      /* 0 = infinite */
    float inner_cone; /* spot only, radians */
    float outer_cone;
    /* Size (issue 15; glTF extras.ispm): point and spot lights with radius > 0 are spheres of
     * that radius (metres) with the same radiant intensity, i.e. uniform radiance
     * I/(π·radius²), opaque; directional lights with angular_radius > 0 are discs of that
     * angular radius (radians). 0 = today's punctual light. */
    float radius;
} scn_light;

typedef struct scn_node {
    char name[SCN_NAME_MAX];
    int32_t source; /* its index among the glTF's nodes; -1 for a node the sequence added */
    int32_t parent; /* -1 for roots */
    int32_t mesh;   /* -1 none */
    int32_t camera; /* -1 none */
    int32_t light;  /* -1 none */
    int32_t skin;   /* -1 none (only with a mesh) */
    uint32_t weight_first; /* its morph weights in scn_scene.weights (its mesh's weight_count) */
    /* Rest pose. If has_matrix, matrix is used and TRS ignored (glTF forbids animating it). */
    int has_matrix;
    float matrix[16];
    float translation[3];
    float rotation[4]; /* x,y,z,w */
    float scale[3];
} scn_node;

typedef enum scn_anim_path { SCN_PATH_TRANSLATION = 0, SCN_PATH_ROTATION, SCN_PATH_SCALE, SCN_PATH_WEIGHTS } scn_anim_path;
typedef enum scn_interp { SCN_INTERP_LINEAR = 0, SCN_INTERP_STEP, SCN_INTERP_CUBICSPLINE } scn_interp;

typedef struct scn_channel {
    int32_t node;
    scn_anim_path path;
    scn_interp interp;
    uint32_t key_count;
    float *times;  /* key_count, strictly increasing */
    /* key_count × comps floats (comps = 3, or 4 for rotation); for CUBICSPLINE
     * key_count × 3 × comps laid out (in-tangent, value, out-tangent) per key as in glTF. */
    float *values;
    uint32_t comps; /* SCN_PATH_WEIGHTS: the node's morph weight count (others: 3, rotation 4) */
} scn_channel;

typedef struct scn_animation {
    char name[SCN_NAME_MAX];
    uint32_t channel_count;
    scn_channel *channels;
} scn_animation;

/* A loaded scene: one owner, freed whole by scn_destroy. Nodes are listed so that every
 * parent comes before its children (the loader sorts them), so world matrices can be
 * computed in one forward pass. Only nodes reachable from the glTF's default scene are kept. */
typedef struct scn_scene {
    char path[4096];
    uint32_t node_count;      scn_node *nodes;
    uint32_t mesh_count;      scn_mesh *meshes;
    uint32_t primitive_count; scn_primitive *primitives;
    uint32_t material_count;  scn_material *materials;
    uint32_t camera_count;    scn_camera *cameras;
    uint32_t light_count;     scn_light *lights;
    uint32_t animation_count; scn_animation *animations;
    uint32_t texture_count;   scn_texture *textures;
    uint32_t skin_count;      scn_skin *skins;
    uint32_t weight_count;    float *weights; /* every node's rest morph weights (scn_node.weight_first) */
    char digest[40];          /* hex XXH3-128 of the .gltf file and its buffers */
    /* What was skipped or is suspicious but not fatal (an unused orthographic camera, a
     * POINTS primitive, an unknown optional extension, no light at all): one line each,
     * for stderr and the manifest's "warnings". The first SCN_MAX_WARNINGS are kept;
     * warning_count counts them all. */
    uint32_t warning_count;
    char warnings[SCN_MAX_WARNINGS][SCN_WARNING_MAX];
} scn_scene;

/* Adds a warning line to the scene (printf-style; kept if there is room). */
void scn_warn(scn_scene *scene, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* Loads and validates a .gltf/.glb (accessor bounds, index ranges, node cycles, NaN in
 * transforms, light types, ...). On failure *out is NULL and err names file and problem. */
eng_result scn_load_gltf(const char *path, scn_scene **out, eng_error *err);
/* Same, keeping the nodes of the glTF's scene scene_index (-1: the default scene, else
 * scene 0, else every root node). */
eng_result scn_load_gltf_scene(const char *path, int scene_index, scn_scene **out, eng_error *err);
/* Same, from len bytes in memory (.glb if they start with the GLB magic, JSON otherwise);
 * name stands for the file in messages and in scene->path, and external buffers are looked
 * up beside it. Borrows bytes. For the fuzz targets and tests. */
eng_result scn_load_gltf_memory(const char *name, const void *bytes, size_t len, scn_scene **out, eng_error *err);
void scn_destroy(scn_scene *scene);

/* World matrices of every node at time t (seconds), all animations applied; animations are
 * clamped at their ends (no looping). world must hold node_count*16 floats. */
void scn_evaluate(const scn_scene *scene, double t, float *world);

/* Morph weights of every node at time t (scene->weight_count floats into weights: the rest
 * weights, then the "weights" channels of every animation). */
void scn_evaluate_weights(const scn_scene *scene, double t, float *weights);

/* Whether node's mesh deforms (a skin, or morph targets). */
int scn_node_deforms(const scn_scene *scene, uint32_t node);

/* Primitive prim of node's mesh deformed (deform.c): morph targets with the node's weights
 * (weights as scn_evaluate_weights gives them), then the skin with joint matrices
 * world(joint) · inverseBind from world (scn_evaluate). Writes vertex_count × 3 positions and
 * unit normals; returns 1 if they are in world space (skinned: glTF ignores the node's own
 * transform), 0 if in the node's object space (morph only). Double arithmetic, one rounding
 * per output: the same bits whatever the thread count. */
int scn_deform(const scn_scene *scene, uint32_t node, uint32_t prim, const float *world, const float *weights,
               float *positions, float *normals);
/* scn_deform that also moves the tangents (morph TANGENT deltas, then the skin matrix's upper
 * 3×3, renormalised, w kept) into tangents (vertex_count × 4) when the primitive has them and
 * tangents is not NULL. */
int scn_deform_tangents(const scn_scene *scene, uint32_t node, uint32_t prim, const float *world,
                        const float *weights, float *positions, float *normals, float *tangents);

/* Per-vertex tangents of p from its positions, normals and TEXCOORD_set (normal_map.c): each
 * triangle's dP/du and dP/dv (Lengyel 2001) summed per vertex, T Gram-Schmidt orthogonalised
 * against the vertex normal, w = the sign of (N × T) · (−dP/dv) (glTF's v runs down the
 * image). MikkTSpace is not packaged by Debian; this is the accumulation it refines. Returns
 * a malloc'd vertex_count × 4 array, or NULL when out of memory or p lacks that set. */
float *scn_generate_tangents(const scn_primitive *p, int set);

/* The shading normal with material m's normal texture applied (glTF §3.9.3) at barycentrics
 * (b1, b2) of triangle tri of p: n the interpolated unit world normal, t0..t2 the triangle's
 * world tangents (xyz, w). n' = normalize(T·x·s + B·y·s + N·z), (x, y, z) = 2·texel − 1,
 * s = normalTexture.scale, T Gram-Schmidt against N, B = (N × T)·w. Returns 0 and leaves n
 * alone where m has no normal texture or p lacks its texcoord set. The same arithmetic as
 * normal_map.glsl. */
int scn_normal_at(const scn_scene *scene, const scn_material *m, const scn_primitive *p, uint32_t tri, float b1,
                  float b2, const float *t0, const float *t1, const float *t2, float n[3]);

/* Samples one channel at time t into out (ch->comps floats). Rotation results are normalised;
 * LINEAR rotation uses slerp (shortest arc). Exposed for tests. */
void scn_sample_channel(const scn_channel *ch, double t, float *out);

int32_t scn_find_node(const scn_scene *scene, const char *name); /* -1 if absent */

/* A texture at (u, v), the texel or the bilinear mix of four as its magFilter says, wrapped
 * as its sampler says, from the full-resolution level (a CPU hit has no footprint). */
void scn_texture_sample(const scn_texture *t, float u, float v, float out[4]);

/* Builds t's mip chain (texture_mip.c): each level the 2×2 box filter of the one above, the
 * last row or column of an odd level folded into its neighbour's average; returns 0 when out
 * of memory. */
int scn_texture_build_mips(scn_texture *t);
/* A texture at (u, v) and level of detail lod as OpenGL 4.5 §8.14 samples it: lod ≤ 0 (or a
 * texture without mips) magnifies with magFilter from level 0, exactly scn_texture_sample;
 * lod > 0 minifies with minFilter (NEAREST/LINEAR: level 0; *_MIPMAP_NEAREST: the nearest
 * level; *_MIPMAP_LINEAR: the mix of the two around lod). */
void scn_texture_sample_lod(const scn_texture *t, float u, float v, float lod, float out[4]);
/* scn_texref_at with a ray-cone footprint (texture_mip.c): width the cone's width over
 * |cos| at the hit (world units), world_area the triangle's world-space area; width ≤ 0 is
 * scn_texref_at. */
int scn_texref_at_cone(const scn_scene *scene, const scn_texref *r, const scn_primitive *p, uint32_t tri, float b1,
                       float b2, float width, float world_area, float out[4]);

/* Texture reference r sampled at barycentrics (b1, b2) of triangle tri of primitive p
 * (interpolated texcoord, KHR_texture_transform, scn_texture_sample) into out; returns 0
 * and (1,1,1,1) where r names no texture or p lacks its texcoord set. */
int scn_texref_at(const scn_scene *scene, const scn_texref *r, const scn_primitive *p, uint32_t tri, float b1,
                  float b2, float out[4]);

/* The factor the material's base colour is multiplied by at barycentrics (b1, b2) of
 * triangle tri of primitive p: its base colour texture at the interpolated, transformed
 * texcoord times COLOR_0; (1,1,1,1) where it has neither. The same value every pass uses. */
void scn_base_color_at(const scn_scene *scene, const scn_material *m, const scn_primitive *p, uint32_t tri,
                       float b1, float b2, float out[4]);

/* ---------------------------------------------------------------- settings & sequence */

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

/* How each photon's kernel radius r_xy is chosen (ind_photon_radii, engine/ind_common.c). */
typedef enum eng_kernel_scaling {
    ENG_SCALING_DEFAULT = 0,  /* = path-density */
    ENG_SCALING_PATH_DENSITY, /* kernel_radius · clamp((1000 ρp)^(−1/4), 1/4, 2) (splat_radius) */
    ENG_SCALING_RAY_LENGTH,   /* 002 Eq. 6.1: the incoming ray's length over a scene-sized l_max */
    ENG_SCALING_TILE_DENSITY, /* 002 Eq. 6.2: the photon density of the screen tile it lands in */
    ENG_SCALING_BANDWIDTH,    /* 004 §6: variable bandwidth C = C0/√p, p = cos θ / d² */
    ENG_SCALING_ANISOTROPIC   /* 002 Eq. 6.3–6.5: path-density's r_xy, the ellipsoid stretched along
                               * ω_i's projection on the kernel plane by min(1/cos θ, s_max) */
} eng_kernel_scaling;

/* The kernel's boundary correction (engine/boundary.h). */
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

/* How capture compresses each EXR part (lossless only: what replay decodes is bit-exact what
 * was announced whatever the choice; only the file's bytes and size change). */
typedef enum eng_capture_compression {
    ENG_COMPRESSION_DEFAULT = 0, /* record's default: none (issue 22 row 1) */
    ENG_COMPRESSION_NONE,
    ENG_COMPRESSION_RLE,
    ENG_COMPRESSION_ZIPS,        /* zlib, one scanline per block */
    ENG_COMPRESSION_ZIP,         /* zlib, 16 scanlines per block */
    ENG_COMPRESSION_PIZ          /* wavelet + Huffman */
} eng_capture_compression;
const char *eng_compression_name(eng_capture_compression m);
/* "none", "rle", "zips", "zip", "piz" → *out; 0 if name is none of them. */
int eng_compression_parse(const char *name, eng_capture_compression *out);

const char *eng_indirect_name(eng_indirect m);
const char *eng_trace_name(eng_photon_trace m);
const char *eng_miss_name(eng_miss_mode m);
const char *eng_specular_name(eng_specular m);
const char *eng_scaling_name(eng_kernel_scaling m);
const char *eng_random_name(eng_random_mode m);
const char *eng_detail_name(eng_atrous_detail m);
const char *eng_boundary_name(eng_boundary m);

/* Engine settings. A zero-initialised struct means defaults (eng_settings_defaults fills
 * them in explicitly so the manifest can record the values used). */
typedef struct eng_settings {
    int shadow_map_size;  /* texels per side (per cube face for point lights); default 1024 */
    int pcf_radius;       /* PCF kernel half-width in texels: (2r+1)^2 taps; default 1 */
    float shadow_bias;    /* world-space offset along the normal before the lookup; default 0.002 */
    float exposure;       /* display transform: stops applied before sRGB encoding; default 0 */
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
    /* Convergence for still views (issue 13). */
    eng_kernel_scaling kernel_scaling; /* default path-density */
    int progressive;          /* 1: running mean of the indirect estimate while nothing moves, the
                               * kernel shrinking as in progressive photon mapping; default 0 */
    eng_boundary boundary;    /* kernel boundary correction after the method; default none */
    /* Photon trace method (issue 16). */
    eng_photon_trace photon_trace; /* default embree */
    int multi_image_maps;     /* cube maps (centres) of the multi-image trace, 1..8; default 2 */
    int multi_image_size;     /* texels per cube-map face side, 4..1024; default 64 */
    eng_miss_mode multi_image_miss; /* rays no map resolves: embree (default) or drop */
    int multi_image_compare;  /* 1: also trace every multi-image ray with Embree and count the
                               * hits that agree (the bench's measure); default 0 */
    /* Specular eye paths (issue 14, specular.h). */
    eng_specular specular;    /* default traced */
    int specular_depth;       /* specular surfaces an eye path crosses, 1..16; default 4 */
    /* Capture (issue 22): EXR compression of the frame files; default zip. */
    eng_capture_compression capture_compression;
    /* Issue 13: `"progressive_radius": "pixel"` (1): progressive photon mapping's radius per pixel
     * (progressive.h; every method but tile-gather-gl); "frame" (0, default): one scale per frame. */
    int progressive_pixel;
    /* Issue 13: `"bounce_strata": N` (2, 4, …, 64): the bounce map's first-bounce numbers
     * stratified within each N×N block of texels (bsdf_strata, bsdf.h); 0 (default) or 1: off. */
    int bounce_strata;
    /* Issue 13: `"final_gather_rays": N` (4, 16, 64, …, 4096): gather rays per pixel of the
     * "final-gather" method (ind_finalgather.c), a correlated multi-jittered set; default 64. */
    int final_gather_rays;
    /* `"final_gather_radius"`: the factor (0, 1] on every photon's kernel radius r_xy at the
     * final gather's lookups, which the gather's rays average, so a small kernel's noise matters
     * less than its edge bias; default 0.25. */
    float final_gather_radius;
} eng_settings;

void eng_settings_defaults(eng_settings *s);

#define SEQ_MAX_CAPTURE 32
#define SEQ_MAX_CAMKEYS 64
#define SEQ_MAX_LIGHTS 8
#define SEQ_MAX_ANIMATIONS 32

/* A light the sequence adds to the scene's own ("lights"): a root node at position whose
 * -Z axis points along direction (spot, directional), carrying this light. */
typedef struct seq_light {
    scn_light light;
    float position[3];  /* default (0,0,0) */
    float direction[3]; /* default (0,0,-1); normalised */
} seq_light;

/* One entry of "animations": a glTF animation by name (name[0] != 0) or by index. */
typedef struct seq_animation {
    char name[SCN_NAME_MAX];
    int index;
} seq_animation;

typedef struct seq_camera_key {
    double time;
    float position[3];
    float target[3];
} seq_camera_key;

typedef struct seq_sequence {
    char path[4096];        /* the sequence file */
    char scene_path[4096];  /* resolved relative to the sequence file's folder */
    char name[SCN_NAME_MAX];
    int frame_count;        /* >= 1 */
    double fps;             /* > 0; frame i is at t = i / fps */
    int still;              /* "still": true: every frame at t = 0 (a still view, e.g. for
                             * progressive accumulation); default 0 */
    int width, height;      /* pixels, 1..16384 */
    /* Camera: either a glTF camera node (camera_node[0] != 0) or explicit look-at keys,
     * linearly interpolated and clamped (camera_key_count >= 1). */
    char camera_node[SCN_NAME_MAX];
    int camera_by_index;    /* {"node": <index>}: camera_node_index is a glTF node index */
    int camera_node_index;
    int camera_key_count;
    seq_camera_key camera_keys[SEQ_MAX_CAMKEYS];
    float camera_up[3];     /* look-at keys only; default (0,1,0) */
    float camera_yfov;      /* radians; look-at keys only; default 40° */
    float camera_znear, camera_zfar; /* defaults 0.05, 100 */
    eng_settings settings;
    /* Glob patterns (fnmatch) of buffer names to capture; none means "*". */
    int capture_count;
    char capture[SEQ_MAX_CAPTURE][SCN_NAME_MAX];
    char digest[40];        /* hex XXH3-128 of the sequence file bytes */
    /* What of the glTF is played: "scene_index" (which of its scenes, when has_scene_index;
     * else the default), "animations" (when has_animations; else all of them) and "lights"
     * added to its own. Zero-initialised fields mean the glTF's defaults. */
    int has_scene_index, scene_index;
    int has_animations, animation_count;
    seq_animation animations[SEQ_MAX_ANIMATIONS];
    int light_count;
    seq_light lights[SEQ_MAX_LIGHTS];
} seq_sequence;

/* Parses and validates a sequence file. Unknown keys are errors (a typo must not silently
 * fall back to a default). */
eng_result seq_load(const char *path, seq_sequence *out, eng_error *err);
/* Same, from memory; path is only used in messages and to resolve the scene path. */
eng_result seq_parse(const char *path, const char *json, size_t len, seq_sequence *out, eng_error *err);

/* Loads the sequence's scene (seq->scene_path) as the sequence chooses it: its glTF scene
 * scene_index, only the animations it names (an unknown name or index is ENG_ERR_INVALID),
 * its lights added as root nodes after the glTF's, and a warning when the result has no
 * light at all (every frame would be black). The one way the tools load a sequence's scene. */
eng_result seq_load_scene(const seq_sequence *seq, scn_scene **out, eng_error *err);

/* Does the sequence ask for this buffer to be captured? */
int seq_wants(const seq_sequence *seq, const char *buffer_name);
/* The scene time of frame i: i / fps, or 0 for a still sequence. */
double seq_frame_time(const seq_sequence *seq, int frame);

/* ---------------------------------------------------------------- buffers & listeners */

#define ENG_MAX_CHANNELS 16

typedef struct eng_buffer {
    const char *name;              /* "<pass>.<buffer>[.light<i>][.face<f>]" */
    int width, height;
    int channel_count;
    const char *const *channels;   /* EXR channel names, e.g. {"R","G","B"} */
    const float *data;             /* width*height*channel_count, interleaved, top row first */
} eng_buffer;

typedef struct eng_pass_time {
    char name[SCN_NAME_MAX]; /* "gbuffer", "shadow", "direct", "composite", ... */
    double ms;
} eng_pass_time;

#define ENG_MAX_PASSES 32

/* Safety limit on the surface hits of one photon path after the bounce map (Russian roulette
 * ends paths; this only bounds pathological ones, e.g. between two perfect mirrors), and the
 * number of bounce indices a photon can be stored with (2 .. ENG_PHOTON_MAX_HITS + 1). */
#define ENG_PHOTON_MAX_HITS 64
#define ENG_PHOTON_BOUNCES (ENG_PHOTON_MAX_HITS + 2)

/* Cube maps of the multi-image trace at most (ENG_TRACE_MULTI_IMAGE). */
#define ENG_MAX_TRACE_MAPS 8

/* Per frame counts of an image-space photon trace (004 §5.2), summed over its bounce rays. */
typedef struct eng_trace_counts {
    uint64_t rays;      /* bounce rays asked of the method */
    uint64_t resolved;  /* found by some map (an accepted type C/D point) */
    uint64_t fallback;  /* resolved by none, traced with Embree (multi_image_miss = embree) */
    uint64_t dropped;   /* resolved by none, path ended (multi_image_miss = drop) */
    uint64_t types[4];  /* per ray and map: A (no hit), B (rejected by Eq. 2), C (accepted, not
                         * the nearest), D (the nearest accepted) */
    uint64_t compared;  /* with multi_image_compare: rays where Embree finds a hit */
    uint64_t agree;     /* ... and the multi-image hit is on the same draw within 1 cm */
} eng_trace_counts;

/* One light's shadow views as the direct pass used them: type (0 point, 1 spot, 2
 * directional, as shaders/shadow_pcf.glsl), position, direction, the world size of a shadow
 * texel (per metre of distance for point and spot lights: u_shadow_texel), the value of an
 * empty texel, and per face the view-projection (world → clip, column-major). */
#define ENG_MAX_LIGHT_RECORDS 8
typedef struct eng_light_record {
    int type, faces;
    float position[3], direction[3];
    float texel, far_value;
    float view_proj[6][16];
} eng_light_record;

/* One photon's contribution to one eye pixel under the CPU kernel every indirect method
 * shares (gather_kernel.h, lineage_kernel.c in ispm_kernel): photon = photons.map's 14
 * channels (position, direction, power, normal, density, bounce), radius its kernel radius
 * r_xy (photons.origin), compression the normal_compression setting; the pixel's surface
 * point s, normal n, albedo, material (roughness, metallic, transmission, ior) and the eye.
 * Radiance mode (irradiance 0): rgb = f Φ κ. Irradiance mode: rgb = Φ κ and glossy =
 * f_glossy Φ κ (glossy may be NULL). Returns 1 when the photon passes every test (it then
 * counts in <prefix>.count), 0 with rgb = 0 otherwise. */
int eng_photon_contribution(const float photon[14], float radius, float compression, const float s[3],
                            const float n[3], const float albedo[3], const float mat[4], const float eye[3],
                            int irradiance, float rgb[3], float glossy[3]);

/* A manifest frame's "lights" (a cJSON array, or NULL: none) into lights (count set); an
 * invalid entry is ENG_ERR_INVALID naming path (light_record.c, in ispm_core). */
eng_result eng_light_records_parse(const char *path, const void *json, int *count, eng_light_record *lights,
                                   eng_error *err);

typedef struct eng_frame_stats {
    int frame;
    double time;
    int pass_count;
    eng_pass_time passes[ENG_MAX_PASSES];
    /* Photon attrition (ISPM Fig. 10): bounce-map photons that survived the first bounce, and
     * photon-map photons stored at bounce index b (b = 2 is the second surface of a path). */
    uint64_t photons_emitted;
    uint64_t photons_stored[ENG_PHOTON_BOUNCES];
    /* Paths the trace cut at ENG_PHOTON_MAX_HITS surface hits while they still carried power
     * (the estimate's only bias besides the kernels; should be ~0). */
    uint64_t photons_truncated;
    /* Image-space photon trace (multi-image): its map centres this frame and its counts;
     * trace_maps = 0 for the Embree trace. */
    int trace_maps;
    float trace_centres[ENG_MAX_TRACE_MAPS][3];
    eng_trace_counts trace;
    /* The eye camera of this frame: world → clip (column-major, GL conventions) and its
     * position, so tools can project world-space data (e.g. photons) into the image. */
    float camera_view_proj[16];
    float camera_eye[3];
    /* The earliest frame this frame's temporal state (temporal accumulation, progressive
     * accumulation) depends on: the last reset of that state (frame 0, a temporal_window
     * boundary, a progressive global restart, or where the history of a shard was rebuilt
     * from). -1: nothing in the engine carries state from frame to frame at these settings. */
    int history_from;
    /* The lights' shadow views of this frame (pass_shadow.c light_views, pass_direct.c), so
     * tools can find the shadow-map texel an eye pixel was tested against (ispm lineage). */
    int light_count;
    eng_light_record lights[ENG_MAX_LIGHT_RECORDS];
} eng_frame_stats;

/* A listener sees every announced buffer. Any callback may be NULL. A non-zero return
 * aborts the frame: eng_render_frame then returns ENG_ERR_ABORTED. */
typedef struct eng_listener {
    void *user;
    int (*frame_begin)(void *user, int frame, double time);
    int (*buffer)(void *user, int frame, const eng_buffer *buf);
    int (*frame_end)(void *user, const eng_frame_stats *stats);
} eng_listener;

/* ---------------------------------------------------------------- engine */

typedef struct eng_engine eng_engine;

typedef struct eng_desc {
    const scn_scene *scene;      /* borrowed; must outlive the engine */
    const seq_sequence *sequence;/* borrowed */
    /* The GL context's backend (a property of the machine, not of the sequence: ispm record
     * --gl): NULL or "osmesa" (the default, the goldens' reference) or "egl". With "egl",
     * gl_use_device chooses EGL device gl_device (EGL_EXT_platform_device, --gl-device N);
     * without it Mesa's surfaceless platform. */
    const char *gl;
    int gl_use_device, gl_device;
    /* 1: also announce photons.origin (each photon's light, face, bounce-map texel and kernel
     * radius: ispm lineage, ispm record --lineage). Off by default so that runs keep their
     * buffers. */
    int lineage;
} eng_desc;

#define ENG_GL_DEFAULT "osmesa"
#define ENG_GL_BACKENDS "osmesa, egl" /* for messages */
/* 1 if name is a GL backend eng_desc.gl accepts. */
int eng_gl_backend_known(const char *name);

/* Pins what follows the host's SIMD width before any GL or Embree object exists:
 * LP_NATIVE_VECTOR_WIDTH=128, GALLIUM_OVERRIDE_CPU_CAPS=sse4.1, LP_NUM_THREADS=threads,
 * Embree isa=sse2. Idempotent; eng_create calls it. */
void eng_pin_determinism(int threads);

/* Key/value pairs of the pinned settings, for the manifest. NULL-terminated array of
 * {key, value} pairs, static storage. */
const char *const *eng_determinism_info(void);

eng_result eng_create(const eng_desc *desc, eng_engine **out, eng_error *err);
void eng_destroy(eng_engine *e);

eng_result eng_add_listener(eng_engine *e, const eng_listener *l);

/* Renders frame i at t = i / fps, announcing every buffer to the listeners. Frames may be
 * rendered in any order, but motion vectors refer to frame i-1's transforms (frame 0: zero). */
eng_result eng_render_frame(eng_engine *e, int frame, eng_error *err);

/* Frame shards (ispm record --frames A-B --warmup W): the temporal state a frame rendered out
 * of order rebuilds (silently, without announcing) begins at frame first instead of frame 0,
 * so a shard's first frame renders frames first .. A-1 as its warm-up. first = 0 is the
 * default (an uninterrupted run's history). A frame before first rebuilds from frame 0. */
void eng_set_history_start(eng_engine *e, int first);

/* 1 when some pass carries state from frame to frame at these settings (temporal or
 * progressive accumulation): a frame then depends on the frames before it. */
int eng_stateful(const eng_engine *e);

/* Is the segment from a to b blocked by scene geometry, as posed at the last rendered frame
 * (Embree occlusion query; the end points themselves are excluded by a small epsilon)?
 * Returns 1 blocked, 0 clear. Before the first frame the scene is at t = 0. */
int eng_occluded(eng_engine *e, const float a[3], const float b[3]);

/* GL_VERSION and GL_RENDERER of the engine's context (for the manifest). */
const char *eng_gl_version(const eng_engine *e);
const char *eng_gl_renderer(const eng_engine *e);
/* The backend's name ("osmesa", "egl") and what it runs on ("offscreen", "surfaceless",
 * "device 0 (/dev/dri/renderD128)"), for the manifest. */
const char *eng_gl_backend(const eng_engine *e);
const char *eng_gl_where(const eng_engine *e);

/* ---------------------------------------------------------------- small shared helpers */

/* Hex XXH3-128 of bytes (32 hex chars + NUL). */
void eng_digest_hex(const void *data, size_t len, char out[40]);

/* Content digest of a buffer, the one capture writes to the manifest and replay recomputes
 * from decoded files: XXH3-128 over each channel plane in strcmp order of channel names,
 * each plane width*height float32 (little-endian, top row first). The order of channels in
 * memory therefore does not matter; -0.0 and 0.0 differ, as do NaN payloads. */
void eng_buffer_digest(const eng_buffer *b, char out[40]);

/* Counts of NaN and ±Inf values in a buffer; first_x/first_y get the first non-finite pixel
 * in row-major order (-1 if none). */
void eng_buffer_nonfinite(const eng_buffer *b, uint64_t *nan_count, uint64_t *inf_count,
                          int *first_x, int *first_y);

/* Reads a whole file (NUL-terminated; *len excludes the NUL). Caller frees. Refuses files
 * over max_bytes with ENG_ERR_INVALID. */
eng_result eng_read_file(const char *path, size_t max_bytes, char **data, size_t *len, eng_error *err);

/* Process-wide, once: freed memory stays in the heap for reuse, every thread allocates from
 * one heap, and a range of it is advised for transparent huge pages (fewer page faults; see
 * core.c). Returns the bytes advised, 0 where nothing was (not glibc, a replaced allocator). */
size_t eng_keep_freed_memory(void);

#ifdef __cplusplus
}
#endif

#endif
