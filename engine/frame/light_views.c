/* light_views.c — the views of a light that its shadow map, light-space G-buffer and bounce
 * map share: 6 cube faces for a point light, one frustum for a spot light, an orthographic box
 * for a directional light, each fitted to the frame's scene bounds. */
#include "frame.h"

#include <math.h>
#include <string.h>

static void ortho(float m[16], float half, float znear, float zfar)
{
    memset(m, 0, 16 * sizeof(float));
    m[0] = 1.0f / half;
    m[5] = 1.0f / half;
    m[10] = -2.0f / (zfar - znear);
    m[14] = -(zfar + znear) / (zfar - znear);
    m[15] = 1.0f;
}

void light_views(const eng_light_pose *l, const eng_frame_scene *fs, shadow_map *sm)
{
    float far = 0.0f;
    for (int c = 0; c < 8; c++) {
        float corner[3] = {(c & 1) ? fs->bounds_max[0] : fs->bounds_min[0],
                           (c & 2) ? fs->bounds_max[1] : fs->bounds_min[1],
                           (c & 4) ? fs->bounds_max[2] : fs->bounds_min[2]};
        float d[3] = {corner[0] - l->position[0], corner[1] - l->position[1], corner[2] - l->position[2]};
        float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (len > far)
            far = len;
    }
    far = far * 1.01f + 0.1f;
    float proj[16], view[16];
    if (l->type == SCN_LIGHT_POINT) {
        static const float dirs[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
        static const float ups[6][3] = {{0, -1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {0, -1, 0}, {0, -1, 0}};
        sm->faces = 6;
        m4_perspective(proj, (float)(ENG_PI / 2.0), 1.0f, 0.01f, far);
        for (int f = 0; f < 6; f++) {
            float target[3] = {l->position[0] + dirs[f][0], l->position[1] + dirs[f][1], l->position[2] + dirs[f][2]};
            m4_look_at(view, l->position, target, ups[f]);
            m4_mul(sm->view_proj[f], proj, view);
        }
        sm->far_value = far;
    } else if (l->type == SCN_LIGHT_SPOT) {
        sm->faces = 1;
        m4_perspective(proj, 2.0f * shadow_spot_half_angle(l->outer_cone), 1.0f, 0.01f, far);
        float target[3] = {l->position[0] + l->direction[0], l->position[1] + l->direction[1], l->position[2] + l->direction[2]};
        float up[3] = {0, 1, 0};
        if (fabsf(l->direction[1]) > 0.99f) {
            up[1] = 0;
            up[2] = 1;
        }
        m4_look_at(view, l->position, target, up);
        m4_mul(sm->view_proj[0], proj, view);
        sm->far_value = far;
    } else {
        /* Directional: the box's near plane sits one scene radius behind the scene centre;
         * eng_frame_scene gives directional lights that plane's centre as position. */
        float half = 0.0f;
        for (int i = 0; i < 3; i++) {
            float e = 0.5f * (fs->bounds_max[i] - fs->bounds_min[i]);
            half += e * e;
        }
        half = sqrtf(half) * 1.01f + 0.01f;
        sm->faces = 1;
        ortho(proj, half, 0.0f, 2.0f * half);
        float target[3] = {l->position[0] + l->direction[0], l->position[1] + l->direction[1], l->position[2] + l->direction[2]};
        float up[3] = {0, 1, 0};
        if (fabsf(l->direction[1]) > 0.99f) {
            up[1] = 0;
            up[2] = 1;
        }
        m4_look_at(view, l->position, target, up);
        m4_mul(sm->view_proj[0], proj, view);
        sm->far_value = 2.0f * half;
    }
}

float light_view_extent(const eng_light_pose *l, const shadow_map *sm)
{
    if (l->type == SCN_LIGHT_POINT)
        return 1.0f;
    if (l->type == SCN_LIGHT_SPOT)
        return tanf(shadow_spot_half_angle(l->outer_cone));
    return 0.5f * sm->far_value; /* the ortho box is 2·half deep and 2·half wide */
}
