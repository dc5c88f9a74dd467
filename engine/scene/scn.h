/* scn.h — the scene room's face: what a glTF 2.0 file holds once validated (meshes, node
 * hierarchy, cameras, KHR_lights_punctual lights, materials, animations), and its evaluation
 * at a frame time t (animation sampling, world matrices, skinning and morphing, textures).
 *   - Quaternions are (x, y, z, w) as in glTF.
 *   - Light intensity: point and spot lights carry radiant intensity in W/sr per colour
 *     channel (glTF `intensity` x `color`); directional lights carry irradiance in W/m²
 *     (glTF's photometric units are deliberately read as radiometric ones). */
#ifndef ISPM_SCN_H
#define ISPM_SCN_H

#include "eng_core.h"

#ifdef __cplusplus
extern "C" {
#endif

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
    /* Size (glTF extras.ispm): point and spot lights with radius > 0 are spheres of
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
/* KHR_materials_pbrSpecularGlossiness factors as metal-roughness (Khronos' conversion):
 * diffuse RGBA, specular RGB and glossiness in [0, 1] -> base colour RGBA, metallic, roughness. */
void scn_spec_gloss_to_metal_rough(const double diffuse[4], const double specular[3], double glossiness,
                                   float base_color[4], float *metallic, float *roughness);

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

/* Resolved material values for a draw (the glTF default material for index -1). */
scn_material eng_material_of(const scn_scene *scene, int32_t index);

#ifdef __cplusplus
}
#endif

#endif
