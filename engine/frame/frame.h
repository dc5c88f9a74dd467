/* frame.h — the frame room's face: the scene as one frame draws it (draws at this frame's and
 * the previous frame's transforms, deformed vertices, the camera, the lights' poses), the
 * views of each light every light-space pass shares, camera rays and the light model for the
 * CPU renderers, and the job that runs beside the GL thread (overlap.h). */
#ifndef ISPM_FRAME_H
#define ISPM_FRAME_H

#include "gl.h"
#include "scn.h"
#include "overlap.h"

/* ---------------------------------------------------------------- scene as drawn */

typedef struct eng_gpu_prim { /* vertex attribute 5: the previous frame's position */
    GLuint vao, vbo_pos, vbo_nrm, ibo;
    GLuint vbo_uv[2], vbo_col; /* TEXCOORD_0/1 (location 2, 3), COLOR_0 (4); 0 where absent */
    GLsizei index_count;
    GLuint vbo_tan; /* TANGENT xyzw (location 6, normal_map.glsl); 0 where the primitive has none */
} eng_gpu_prim;

/* One draw: a primitive at a node's world transform this frame and the previous one. */
typedef struct eng_draw {
    uint32_t primitive;
    int32_t material;  /* -1 = default material */
    float world[16];
    float prev_world[16];
    const struct eng_gpu_prim *gpu; /* the primitive's buffers, or this draw's deformed copy */
    /* A skinned or morphed draw (deform_gl.c): its vertices this frame in the space `world`
     * maps from (world space, world = identity, when skinned); NULL: the primitive's own. */
    const float *positions, *normals;
    const float *tangents; /* deformed tangents (4 per vertex) beside them, or NULL */
} eng_draw;

/* The object-space positions of draw d (deformed or the primitive's). */
static inline const float *eng_draw_positions(const scn_scene *s, const eng_draw *d)
{
    return d->positions ? d->positions : s->primitives[d->primitive].positions;
}

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
    float radius; /* scn_light.radius: sphere radius (m) or disc angular radius (rad); 0 punctual */
} eng_light_pose;

typedef struct eng_frame_scene {
    const scn_scene *scene;
    const eng_gpu_prim *gpu;  /* per scene primitive */
    const GLuint *textures;   /* per scene texture (scn_scene.textures) */
    uint32_t draw_count;
    eng_draw *draws;
    eng_view camera, prev_camera;
    uint32_t light_count;
    eng_light_pose *lights;
    float bounds_min[3], bounds_max[3]; /* world AABB of all geometry this frame */
} eng_frame_scene;

/* Skinned and morphed draws (deform_gl.c): per deformed draw its own vertex
 * buffers (positions, normals, previous positions) beside the primitive's texcoords, colours
 * and indices. eng_deform_pose runs after the draws are set for the frame: it deforms each
 * on the CPU at t and at tp (scn_deform), points the draw at the result and at its buffers,
 * sets world/prev_world to identity for skinned ones, and uploads the vertices. */
typedef struct eng_deform eng_deform;
eng_deform *eng_deform_create(const scn_scene *s, const eng_gpu_prim *gpu);
void eng_deform_pose(eng_deform *d, eng_frame_scene *fs, const float *world, const float *prev_world, double t,
                     double tp);
void eng_deform_destroy(eng_deform *d); /* accepts NULL; needs the GL context current */


/* Sets base_color.glsl's uniforms of prog for drawing d with material m: its base colour
 * texture (bound to texture unit ENG_BASE_TEX_UNIT), texcoord set and transform, COLOR_0,
 * and the MASK cutoff. */
#define ENG_BASE_TEX_UNIT 7
void eng_bind_material(GLuint prog, const eng_frame_scene *fs, const eng_draw *d, const scn_material *m);

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

/* The faces of light l's views (6 cube faces, a spot frustum, or a directional ortho box),
 * their view-projection matrices and the far value, in sm (its target is untouched). The
 * shadow maps, light G-buffers and bounce maps of a light all use these views. */
void light_views(const eng_light_pose *l, const eng_frame_scene *fs, shadow_map *sm);

/* tan of a point light face's or spot frustum's half-angle, or a directional box's
 * half-width: what one texel of a map of `size` texels spans is 2·extent/size. */
float light_view_extent(const eng_light_pose *l, const shadow_map *sm);

/* Irradiance at normal incidence that light l delivers to p (no visibility), the unit
 * direction toward it and the distance (INFINITY for directional): shaders/direct.frag.glsl's
 * light model on the CPU (reference.c; the specular pass shades with it too). Returns 0 when
 * the light delivers nothing there. */
/* A spot light's KHR_lights_punctual falloff t² for cd, the cosine between its axis and the
 * direction light leaves it by. */
float frame_spot_falloff(const eng_light_pose *l, float cd);
int frame_light_at(const eng_light_pose *l, const float p[3], float wl[3], float *dist, float e[3]);

/* Camera ray through (px, py) in pixels from the top-left corner of a width×height image: the
 * inverse of the view-projection (GL: NDC y up, so row 0 is NDC y = +1), from the near to the
 * far plane (*tnear, *tfar along the unit dir), so it sees what the rasteriser sees
 * (reference.c; pass_translucent.c). */
void frame_camera_ray(const double inv_view_proj[16], const float eye[3], int width, int height, double px, double py,
                    float org[3], float dir[3], float *tnear, float *tfar);

#endif
