/* gltf_shim.h — internal: a C view of what tinygltf parsed, for gltf_load.c only.
 *
 * tinygltf is C++; this header is the one place its model crosses into C. The shim parses
 * (JSON syntax, glTF schema shapes as far as tinygltf checks them, data URIs, external
 * buffers, the GLB container) and exposes the result as plain arrays of plain structs. It
 * judges nothing: indices are passed through unchecked, vectors keep whatever length the
 * file gave, numbers keep whatever value. All semantic validation is gltf_load.c's.
 *
 * Everything reachable from a gls_model (strings, arrays, buffer bytes) is owned by it and
 * lives until gls_free. Integer fields that tinygltf defaults to -1 mean "absent".
 */
#ifndef ISPM_GLTF_SHIM_H
#define ISPM_GLTF_SHIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* glTF accessor componentType and (tinygltf's encoding of) type; the .cpp checks that these
 * equal TINYGLTF_COMPONENT_TYPE_* / TINYGLTF_TYPE_*. */
#define GLS_COMPONENT_BYTE 5120
#define GLS_COMPONENT_UNSIGNED_BYTE 5121
#define GLS_COMPONENT_SHORT 5122
#define GLS_COMPONENT_UNSIGNED_SHORT 5123
#define GLS_COMPONENT_UNSIGNED_INT 5125
#define GLS_COMPONENT_FLOAT 5126
#define GLS_TYPE_VEC2 2
#define GLS_TYPE_VEC3 3
#define GLS_TYPE_VEC4 4
#define GLS_TYPE_MAT2 34
#define GLS_TYPE_MAT3 35
#define GLS_TYPE_MAT4 36
#define GLS_TYPE_SCALAR 65

typedef enum gls_status {
    GLS_OK = 0,
    GLS_ERR_IO,     /* an external buffer is missing or unreadable */
    GLS_ERR_SYNTAX, /* not JSON, not a GLB container, or no glTF asset object */
    GLS_ERR_GLTF,   /* JSON, but tinygltf rejected the glTF structure */
    GLS_ERR_NOMEM,
    GLS_ERR_UNSUPPORTED /* valid glTF the tool cannot read */
} gls_status;

/* A number from an extension object, where tinygltf keeps untyped JSON values. */
typedef enum gls_num_state { GLS_NUM_ABSENT = 0, GLS_NUM_PRESENT, GLS_NUM_NOT_A_NUMBER } gls_num_state;
typedef struct gls_number {
    gls_num_state state;
    double value;
} gls_number;

/* A number array exactly as long as the file wrote it (len 0: absent). */
typedef struct gls_doubles {
    uint32_t len;
    const double *v;
} gls_doubles;

typedef struct gls_buffer {
    const unsigned char *data;
    uint64_t size;
    int external; /* loaded from a file beside the glTF (not a data URI, not the GLB chunk) */
} gls_buffer;

typedef struct gls_buffer_view {
    int buffer;
    uint64_t byte_offset, byte_length, byte_stride; /* stride 0: tightly packed */
} gls_buffer_view;

typedef struct gls_accessor {
    int buffer_view; /* -1: none (all zeros, or sparse only) */
    uint64_t byte_offset;
    int component_type;
    int type;
    uint64_t count;
    int normalized;
    int sparse;
    /* sparse: sparse_count substitutions; indices (sparse_index_type) and values (the
     * accessor's type and componentType, tightly packed) each in a buffer view at an offset. */
    uint64_t sparse_count;
    int sparse_index_view, sparse_index_type, sparse_value_view;
    uint64_t sparse_index_offset, sparse_value_offset;
} gls_accessor;

typedef struct gls_attribute {
    const char *semantic; /* "POSITION", "NORMAL", "TEXCOORD_0", ... */
    int accessor;
} gls_attribute;

typedef struct gls_target { /* one morph target: its attributes (POSITION, NORMAL, ...) */
    uint32_t attribute_count;
    const gls_attribute *attributes;
} gls_target;

typedef struct gls_primitive {
    int mode; /* 4 (TRIANGLES) when absent */
    int indices;
    int material;
    uint32_t attribute_count;
    const gls_attribute *attributes;
    uint32_t target_count; /* morph targets */
    const gls_target *targets;
} gls_primitive;

typedef struct gls_mesh {
    const char *name;
    uint32_t primitive_count;
    const gls_primitive *primitives;
    gls_doubles weights; /* default morph weights */
} gls_mesh;

typedef struct gls_skin {
    const char *name;
    int inverse_bind_matrices; /* accessor, -1: identities */
    int skeleton;
    uint32_t joint_count;
    const int *joints;
} gls_skin;

typedef struct gls_node {
    const char *name;
    int mesh, camera, skin;
    int has_light;     /* carries a KHR_lights_punctual extension object */
    gls_number light;  /* its "light" member */
    uint32_t child_count;
    const int *children;
    gls_doubles translation, rotation, scale, matrix;
    gls_doubles weights; /* morph weights overriding the mesh's */
} gls_node;

typedef struct gls_camera {
    const char *name;
    const char *type; /* "perspective" or "orthographic" (tinygltf refuses others) */
    double yfov, aspect_ratio, znear, zfar; /* perspective; 0 where absent */
} gls_camera;

typedef struct gls_light {
    const char *name;
    const char *type;
    gls_doubles color;
    double intensity, range;           /* tinygltf defaults: 1, 0 */
    double inner_cone, outer_cone;     /* tinygltf defaults: 0, pi/4 */
    /* extras.ispm.radius / extras.ispm.angular_radius (lights with a size);
     * NOT_A_NUMBER also where extras.ispm is there but not an object. */
    gls_number radius, angular_radius;
} gls_light;

/* A material's reference to a texture (glTF textureInfo) with its KHR_texture_transform. */
typedef struct gls_texinfo {
    int index;    /* -1: none */
    int texcoord; /* TEXCOORD_n; KHR_texture_transform's texCoord overrides it when present */
    int has_transform;
    gls_doubles offset, scale; /* transform: [0,0] and [1,1] where absent (len 0) */
    gls_number rotation;
    gls_number transform_texcoord;
    double strength; /* occlusionTexture.strength, normalTexture.scale (1 for the others) */
} gls_texinfo;

/* A glTF image as the file stores it; its pixels come from gls_decode_image, on demand. */
typedef struct gls_image {
    const char *uri;       /* the file URI ("" for a bufferView or a data URI) */
    const char *mime_type; /* as the file or its data URI names it ("" where absent) */
    int has_bytes;         /* encoded bytes were found (0: e.g. an external file not read) */
} gls_image;

/* Decoded pixels: width*height*4 components of bits 8 or 16, top row first. */
typedef struct gls_pixels {
    int width, height, bits;
    const unsigned char *rgba;
} gls_pixels;

typedef struct gls_texture {
    int source, sampler; /* -1: absent */
    int webp_source;     /* EXT_texture_webp.source; -1: absent, -2: present but not an integer */
} gls_texture;

typedef struct gls_tex_sampler {
    int mag_filter, min_filter, wrap_s, wrap_t; /* glTF/GL enums; -1 filter: absent */
} gls_tex_sampler;

typedef struct gls_material {
    const char *name;
    gls_texinfo base_color_texture, metallic_roughness_texture, normal_texture, occlusion_texture,
        emissive_texture;
    const char *alpha_mode; /* "OPAQUE", "MASK", "BLEND" */
    double alpha_cutoff;
    gls_doubles base_color; /* tinygltf default [1,1,1,1] */
    double metallic, roughness;
    gls_doubles emissive;   /* tinygltf default [0,0,0] */
    int double_sided;
    gls_number transmission; /* KHR_materials_transmission.transmissionFactor */
    gls_number ior;          /* KHR_materials_ior.ior */
    gls_number emissive_strength; /* KHR_materials_emissive_strength.emissiveStrength */
    /* Textures of extensions, index -1 where absent, -2 where the member is not a textureInfo
     * object with an integer index. */
    gls_texinfo transmission_texture; /* KHR_materials_transmission.transmissionTexture */
    int unlit;                        /* carries KHR_materials_unlit */
    int spec_gloss;                   /* carries KHR_materials_pbrSpecularGlossiness: */
    gls_doubles diffuse_factor;       /*   diffuseFactor (len 0: absent, default [1,1,1,1]) */
    gls_doubles specular_factor;      /*   specularFactor (len 0: absent, default [1,1,1]) */
    gls_number glossiness;            /*   glossinessFactor (default 1) */
    gls_texinfo diffuse_texture, spec_gloss_texture; /* diffuseTexture, specularGlossinessTexture */
} gls_material;

typedef struct gls_channel {
    int sampler;
    int target_node;
    const char *path;
} gls_channel;

typedef struct gls_sampler {
    int input, output;
    const char *interpolation; /* "LINEAR" when absent */
} gls_sampler;

typedef struct gls_animation {
    const char *name;
    uint32_t channel_count;
    const gls_channel *channels;
    uint32_t sampler_count;
    const gls_sampler *samplers;
} gls_animation;

typedef struct gls_scene {
    const char *name;
    uint32_t node_count;
    const int *nodes;
} gls_scene;

typedef struct gls_model {
    uint32_t buffer_count;      const gls_buffer *buffers;
    uint32_t buffer_view_count; const gls_buffer_view *buffer_views;
    uint32_t accessor_count;    const gls_accessor *accessors;
    uint32_t mesh_count;        const gls_mesh *meshes;
    uint32_t node_count;        const gls_node *nodes;
    uint32_t camera_count;      const gls_camera *cameras;
    uint32_t light_count;       const gls_light *lights;
    uint32_t material_count;    const gls_material *materials;
    uint32_t image_count;       const gls_image *images;
    uint32_t texture_count;     const gls_texture *textures;
    uint32_t tex_sampler_count; const gls_tex_sampler *tex_samplers;
    uint32_t animation_count;   const gls_animation *animations;
    uint32_t scene_count;       const gls_scene *scenes;
    uint32_t skin_count;        const gls_skin *skins;
    int default_scene; /* -1: the file names none */
    uint32_t extensions_required_count;
    const char *const *extensions_required;
    uint32_t extensions_used_count;
    const char *const *extensions_used;
    struct gls_impl *impl;
} gls_model;

/* Parses a glTF from memory: .glb when bytes start with the GLB magic, JSON otherwise.
 * path is the file the bytes came from; external buffers are looked up in its folder only, and
 * one larger than max_external bytes is refused before it is read (gltf_precheck.h).
 * Images are kept encoded (gls_decode_image decodes one when asked). On failure *out is NULL
 * and msg holds tinygltf's one-line complaint. Never throws. */
gls_status gls_load(const char *path, const void *bytes, size_t len, uint64_t max_external, gls_model **out,
                    char *msg, size_t msg_size);

/* Decodes image `index` to RGBA of 8 or 16 bits (PNG, JPEG and what else stb_image reads;
 * WebP with libwebp), once: the pixels are the model's until gls_free. On failure msg names
 * the image's index, URI and format and the decoder's reason (GLS_ERR_UNSUPPORTED for a
 * format no decoder here reads, GLS_ERR_GLTF for bytes that do not decode). */
gls_status gls_decode_image(const gls_model *model, int index, gls_pixels *out, char *msg, size_t msg_size);

/* Frees everything the model owns; accepts NULL. */
void gls_free(gls_model *model);

#ifdef __cplusplus
}
#endif

#endif
