/* pass_translucent.c — alphaMode BLEND surfaces (translucent.h; 003_… §3
 * step 5: "render translucent surfaces back to front with direct, mirror and refracted
 * illumination only").
 *
 * Translucent surfaces take no part in the opaque passes: the G-buffers, shadow maps and
 * light G-buffers do not draw them, and the Embree scene that photons, shadow rays and the
 * specular eye paths see does not hold them (rt.c). So they cast no shadow, block and store no
 * photons, and receive none (003 §3 step 5: direct, mirror and refracted light only).
 *
 * Per pixel, the camera ray (frame_camera_ray, the rasteriser's ray through the pixel centre)
 * meets the BLEND surfaces between the near plane and the opaque surface of the eye G-buffer
 * (rt_intersect_blend, up to TL_MAX_LAYERS; a single-sided surface seen from behind is culled,
 * as the rasteriser culls it). Each is shaded by eye_tracer_translucent: direct light by
 * shadow rays through its non-specular lobes, its emission, and what its delta lobes (a mirror,
 * glass) reflect and refract, traced as the traced specular method traces them. The layers are
 * composited back to front (tl_composite) into a premultiplied RGBA image, which the composite
 * pass lays over the opaque result: final = rgb + (1 − a)·opaque.
 *
 * Determinism: each pixel is computed by one thread from its own rays; the layers are sorted
 * with a total order; so the image is bit-identical for any thread count. */
#include "translucent.h"

#include "bsdf.h"
#include "indirect.h"
#include "specular.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TL_MAX_LAYERS 16

struct pass_translucent {
    int width, height;
    glu_cpu_target target;
    int target_ok;
    glu_gbuffer gb;
    float *rgba;
};

int tl_scene_has_blend(const scn_scene *scene)
{
    for (uint32_t i = 0; i < scene->primitive_count; i++)
        if (rt_is_blend(scene, scene->primitives[i].material))
            return 1;
    return 0;
}

void tl_composite(tl_layer *layers, int n, float rgba[4])
{
    /* Insertion sort, back to front: stable and total (ties keep the later index behind). */
    for (int i = 1; i < n; i++) {
        tl_layer x = layers[i];
        int j = i - 1;
        while (j >= 0 && layers[j].t < x.t) {
            layers[j + 1] = layers[j];
            j--;
        }
        layers[j + 1] = x;
    }
    rgba[0] = rgba[1] = rgba[2] = rgba[3] = 0.0f;
    for (int i = 0; i < n; i++) {
        float a = fminf(fmaxf(layers[i].alpha, 0.0f), 1.0f);
        for (int c = 0; c < 3; c++)
            rgba[c] = a * layers[i].radiance[c] + (1.0f - a) * rgba[c];
        rgba[3] = a + (1.0f - a) * rgba[3];
    }
}

eng_result pass_translucent_create(int width, int height, pass_translucent **out, eng_error *err)
{
    *out = NULL;
    pass_translucent *p = calloc(1, sizeof *p);
    if (!p)
        return eng_fail(err, ENG_ERR_NOMEM, "translucent: out of memory");
    p->width = width;
    p->height = height;
    p->rgba = eng_xmalloc((size_t)width * (size_t)height * 4 * sizeof(float));
    eng_result r = glu_cpu_target_create(&p->target, width, height, 0, err);
    if (r != ENG_OK) {
        pass_translucent_destroy(p);
        return r;
    }
    p->target_ok = 1;
    *out = p;
    return ENG_OK;
}

void pass_translucent_destroy(pass_translucent *p)
{
    if (!p)
        return;
    if (p->target_ok)
        glu_cpu_target_destroy(&p->target);
    glu_gbuffer_free(&p->gb);
    free(p->rgba);
    free(p);
}

/* The layers of pixel (x, y): the BLEND surfaces its camera ray meets before the opaque one. */
static int pixel_layers(const eye_tracer *tr, const eng_frame_scene *fs, const eng_rt *rt, const double inv_vp[16],
                        const float *position, int w, int h, int x, int y, eye_scratch *sc,
                        tl_layer layers[TL_MAX_LAYERS])
{
    float org[3], dir[3], tnear, tfar;
    frame_camera_ray(inv_vp, fs->camera.eye, w, h, x + 0.5, y + 0.5, org, dir, &tnear, &tfar);
    const float *pos = position ? position + 4 * ((size_t)y * (size_t)w + (size_t)x) : NULL;
    if (pos && pos[3] > 0.0f) { /* the opaque surface the G-buffer shows */
        float t = 0.0f;
        for (int c = 0; c < 3; c++)
            t += (pos[c] - org[c]) * dir[c];
        tfar = fminf(tfar, t);
    }
    int n = 0;
    rt_hit hit;
    for (int k = 0; k < TL_MAX_LAYERS && rt_intersect_blend(rt, org, dir, tnear, tfar, &hit); k++) {
        tnear = hit.t + bsdf_offset_eps(hit.position);
        scn_material m = eng_material_at(fs->scene, &hit);
        if (!m.double_sided && hit.normal[0] * dir[0] + hit.normal[1] * dir[1] + hit.normal[2] * dir[2] >= 0.0f)
            continue;
        tl_layer *l = &layers[n++];
        l->t = hit.t;
        l->alpha = m.base_color[3];
        eye_tracer_translucent(tr, &hit, &m, org, sc, l->radiance);
    }
    return n;
}

eng_result tl_render(const eng_frame_scene *fs, const eng_rt *rt, const float *position, int w, int h,
                     const eng_photon_map *map, const float *radius, const eng_settings *s, float *rgba, eng_error *err)
{
    float vp_inv[16];
    if (!m4_invert(vp_inv, fs->camera.view_proj))
        return eng_fail(err, ENG_ERR_INVALID, "translucent: the camera's view-projection is singular");
    double inv_vp[16];
    for (int i = 0; i < 16; i++)
        inv_vp[i] = vp_inv[i];
    /* The photon map is gathered from only where a translucent mirror or glass sends a branch. */
    int delta = 0;
    for (uint32_t i = 0; i < fs->scene->material_count; i++)
        delta |= fs->scene->materials[i].alpha_mode == SCN_ALPHA_BLEND && eye_is_specular(&fs->scene->materials[i]);
    eye_tracer *tr = eye_tracer_create(fs, rt, delta ? map : NULL, radius, s, err);
    if (!tr)
        return ENG_ERR_NOMEM;
    int threads = s->threads > 0 ? s->threads : 2;
#pragma omp parallel num_threads(threads)
    {
        eye_scratch sc = {NULL, 0};
        tl_layer layers[TL_MAX_LAYERS];
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                int n = pixel_layers(tr, fs, rt, inv_vp, position, w, h, x, y, &sc, layers);
                tl_composite(layers, n, rgba + 4 * ((size_t)y * (size_t)w + (size_t)x));
            }
        free(sc.list);
    }
    eye_tracer_destroy(tr);
    return ENG_OK;
}

eng_result pass_translucent_run(pass_translucent *p, const eng_frame_scene *fs, const eng_rt *rt,
                                const glu_target *gbuf, const eng_photon_map *map, const float *radius,
                                const eng_settings *s, const float **rgba, GLuint *tex, eng_error *err)
{
    glu_gbuffer_read(gbuf, &p->gb);
    eng_result r = tl_render(fs, rt, p->gb.position, p->width, p->height, map, radius, s, p->rgba, err);
    if (r != ENG_OK)
        return r;
    glu_cpu_target_upload(&p->target, 0, p->rgba);
    *rgba = p->rgba;
    *tex = p->target.target.color[0];
    return ENG_OK;
}
