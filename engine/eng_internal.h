/* eng_internal.h — what the engine's own files share and nobody else sees: small matrix
 * helpers, the GL context and resource helpers, the per-frame view of the scene that the
 * passes draw (eng_frame_scene), and each pass's entry point.
 *
 * Passes take their inputs as arguments and return their outputs (textures owned by the
 * pass object); no pass reaches into another's state. engine.c wires them together and
 * announces every buffer they produce. */
#ifndef ISPM_ENG_INTERNAL_H
#define ISPM_ENG_INTERNAL_H

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>

#include "eng.h"

#define ENG_PI 3.14159265358979323846

/* ---------------------------------------------------------------- math (column-major) */

void m4_identity(float m[16]);
void m4_mul(float out[16], const float a[16], const float b[16]); /* out = a·b; out may alias */
int m4_invert(float out[16], const float m[16]);                  /* 0 if singular */
void m4_perspective(float m[16], float yfov, float aspect, float znear, float zfar);
void m4_look_at(float m[16], const float eye[3], const float target[3], const float up[3]);
void m4_transform_point(const float m[16], const float p[3], float out[3]);
/* Upper 3×3 of the inverse transpose, as a column-major 3×3 (for normals). */
void m4_normal_matrix(float out9[9], const float m[16]);

/* ---------------------------------------------------------------- GL helpers (glutil.c) */

/* Compiles and links vertex + fragment shaders from engine/shaders/<name>; the error names
 * the shader file and carries the driver's log (flattened to one line). */
eng_result glu_program(const char *vert_name, const char *frag_name, GLuint *out, eng_error *err);

/* A framebuffer with `count` RGBA32F colour attachments of w×h and a 32F depth buffer.
 * layers > 0 makes each colour attachment a 2D array texture of that many layers (attach
 * one layer at a time with glu_target_bind_layer). */
typedef struct glu_target {
    GLuint fbo;
    GLuint color[8];
    GLuint depth;
    int count, width, height, layers;
} glu_target;

eng_result glu_target_create(glu_target *t, int count, int width, int height, int layers, eng_error *err);
void glu_target_destroy(glu_target *t);
void glu_target_bind_layer(glu_target *t, int layer);

/* Reads attachment `index` (layer `layer` for array targets) as RGBA float, converts to top
 * row first and keeps `channels` of the 4 components listed in `pick` (e.g. {0,1,2}) into
 * out (w*h*channels floats, interleaved). */
void glu_read(const glu_target *t, int index, int layer, int channels, const int *pick, float *out);

GLuint glu_fullscreen_vao(void); /* an empty VAO: the fullscreen triangle is made in the VS */

/* ---------------------------------------------------------------- scene as drawn */

typedef struct eng_gpu_prim {
    GLuint vao, vbo_pos, vbo_nrm, ibo;
    GLsizei index_count;
} eng_gpu_prim;

/* One draw: a primitive at a node's world transform this frame and the previous one. */
typedef struct eng_draw {
    uint32_t primitive;
    int32_t material;  /* -1 = default material */
    float world[16];
    float prev_world[16];
} eng_draw;

typedef struct eng_view {
    float view[16], proj[16], view_proj[16];
    float eye[3];
    float znear, zfar;
} eng_view;

typedef struct eng_light_pose {
    scn_light_type type;
    float position[3];  /* world (point, spot) */
    float direction[3]; /* world, unit, where the light points (spot, directional) */
    float radiance_scale[3]; /* colour × intensity: W/sr (point, spot) or W/m² (directional) */
    float range, inner_cone, outer_cone;
} eng_light_pose;

typedef struct eng_frame_scene {
    const scn_scene *scene;
    const eng_gpu_prim *gpu;  /* per scene primitive */
    uint32_t draw_count;
    eng_draw *draws;
    eng_view camera, prev_camera;
    uint32_t light_count;
    eng_light_pose *lights;
    float bounds_min[3], bounds_max[3]; /* world AABB of all geometry this frame */
} eng_frame_scene;

/* Resolved material values for a draw (the glTF default material for -1). */
scn_material eng_material_of(const scn_scene *scene, int32_t index);

/* ---------------------------------------------------------------- passes */

/* Eye G-buffer (pass_gbuffer.c). Attachments: 0 position.xyz + coverage in w, 1 normal.xyz,
 * 2 albedo.rgb, 3 (roughness, metallic, transmission, ior), 4 (eye depth, material id,
 * motion x, motion y). Background: zeros, id −1. */
typedef struct pass_gbuffer pass_gbuffer;
eng_result pass_gbuffer_create(int width, int height, pass_gbuffer **out, eng_error *err);
const glu_target *pass_gbuffer_run(pass_gbuffer *p, const eng_frame_scene *fs);
void pass_gbuffer_destroy(pass_gbuffer *p);

/* Shadow maps (pass_shadow.c): per light a 2D array R32F texture holding, for point lights
 * 6 cube faces of distance to the light, for spot lights 1 layer of distance to the light,
 * for directional lights 1 layer of depth along the light direction. */
#define SHADOW_MAX_FACES 6
typedef struct shadow_map {
    glu_target target;
    int faces;
    float view_proj[SHADOW_MAX_FACES][16];
    float far_value; /* what a texel with no geometry holds */
} shadow_map;

/* Half-angle of a spot light's shadow frustum: a little wider than the outer cone, so that
 * the normal offset of a lookup near the cone's edge still lands inside the map. */
static inline float shadow_spot_half_angle(float outer_cone)
{
    float a = outer_cone * 1.05f + 0.02f;
    return a < 1.5f ? a : 1.5f;
}

typedef struct pass_shadow pass_shadow;
eng_result pass_shadow_create(int size, uint32_t light_count, pass_shadow **out, eng_error *err);
/* Renders light i's map; returns it (owned by the pass). */
const shadow_map *pass_shadow_run(pass_shadow *p, const eng_frame_scene *fs, uint32_t light);
void pass_shadow_destroy(pass_shadow *p);

/* Direct light (pass_direct.c): deferred shading of the G-buffer with all lights and PCF
 * shadow lookups; attachment 0 holds radiance RGB. */
typedef struct pass_direct pass_direct;
eng_result pass_direct_create(int width, int height, pass_direct **out, eng_error *err);
const glu_target *pass_direct_run(pass_direct *p, const eng_frame_scene *fs, const glu_target *gbuf,
                                  const shadow_map *const *shadows, const eng_settings *s);
void pass_direct_destroy(pass_direct *p);

/* Composite (pass_composite.c): attachment 0 = direct + indirect (linear radiance),
 * attachment 1 = display transform (exposure, clamp, sRGB encoding). indirect may be 0. */
typedef struct pass_composite pass_composite;
eng_result pass_composite_create(int width, int height, pass_composite **out, eng_error *err);
const glu_target *pass_composite_run(pass_composite *p, GLuint direct_tex, GLuint indirect_tex,
                                     const eng_settings *s);
void pass_composite_destroy(pass_composite *p);

/* ---------------------------------------------------------------- GL context (glctx.c) */

typedef struct eng_glctx eng_glctx;
eng_result glctx_create(eng_glctx **out, eng_error *err);
void glctx_destroy(eng_glctx *c);
const char *glctx_version(const eng_glctx *c);
const char *glctx_renderer(const eng_glctx *c);

/* ---------------------------------------------------------------- Embree scene (rt.c) */

typedef struct eng_rt eng_rt;
eng_result rt_create(const scn_scene *scene, int threads, eng_rt **out, eng_error *err);
/* Poses every instance at this frame's world matrices: static geometry is built once,
 * geometry whose matrix changed is re-transformed and refit. */
void rt_update(eng_rt *rt, const eng_frame_scene *fs);
int rt_occluded(const eng_rt *rt, const float a[3], const float b[3]);
void rt_destroy(eng_rt *rt);

#endif
