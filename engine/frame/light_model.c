/* light_model.c — shaders/direct.frag.glsl's light model on the CPU: what a light delivers to a
 * point (KHR_lights_punctual's range window and spot cone), for the CPU renderers (the
 * reference renderer, the eye tracer). */
#include "frame.h"

#include <math.h>

static float dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static float clamp01(float x)
{
    return x < 0.0f ? 0.0f : (x > 1.0f ? 1.0f : x);
}

static int nonzero3(const float v[3])
{
    return v[0] > 0.0f || v[1] > 0.0f || v[2] > 0.0f;
}

float frame_spot_falloff(const eng_light_pose *l, float cd)
{
    float ci = cosf(l->inner_cone), co = cosf(l->outer_cone);
    float t = clamp01((cd - co) / fmaxf(ci - co, 1e-4f));
    return t * t;
}

/* Irradiance at normal incidence that light l delivers to p (no visibility), the unit
 * direction toward it and the distance (INFINITY for directional): direct.frag.glsl's model. */
int frame_light_at(const eng_light_pose *l, const float p[3], float wl[3], float *dist, float e[3])
{
    if (l->type == SCN_LIGHT_DIRECTIONAL) {
        for (int i = 0; i < 3; i++) {
            wl[i] = -l->direction[i];
            e[i] = l->radiance_scale[i];
        }
        *dist = INFINITY;
        return nonzero3(e);
    }
    float d[3] = {l->position[0] - p[0], l->position[1] - p[1], l->position[2] - p[2]};
    float d2 = dot3(d, d);
    if (!(d2 > 0.0f))
        return 0;
    float len = sqrtf(d2);
    float k = 1.0f / d2;
    for (int i = 0; i < 3; i++)
        wl[i] = d[i] / len;
    if (l->range > 0.0f) {
        float r = len / l->range;
        float w = clamp01(1.0f - r * r * r * r);
        k *= w * w;
    }
    if (l->type == SCN_LIGHT_SPOT)
        k *= frame_spot_falloff(l, -dot3(l->direction, wl));
    for (int i = 0; i < 3; i++)
        e[i] = l->radiance_scale[i] * k;
    *dist = len;
    return nonzero3(e);
}

