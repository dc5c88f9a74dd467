/* scene_choice.c — a sequence's scene as the sequence chooses it (seq_load_scene): which of
 * the glTF's scenes, which animations, which lights besides the file's own; and the scene's
 * warnings (scn_warn), among them the one that says a scene has no light at all, so no
 * frame renders black without saying why. */
#include "seq.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Keeps only the animations q names, in the file's order. */
static eng_result choose_animations(const seq_sequence *q, scn_scene *s, eng_error *err)
{
    unsigned char *keep = calloc(s->animation_count ? s->animation_count : 1, 1);
    if (!keep)
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory", q->path);
    for (int i = 0; i < q->animation_count; i++) {
        const seq_animation *a = &q->animations[i];
        int32_t found = -1;
        if (a->name[0]) {
            for (uint32_t k = 0; k < s->animation_count && found < 0; k++)
                if (strcmp(s->animations[k].name, a->name) == 0)
                    found = (int32_t)k;
        } else if (a->index >= 0 && (uint32_t)a->index < s->animation_count) {
            found = a->index;
        }
        if (found < 0) {
            free(keep);
            if (a->name[0])
                return eng_fail(err, ENG_ERR_INVALID, "%s: animations[%d]: \"%s\" is not an animation of %s",
                                q->path, i, a->name, s->path);
            return eng_fail(err, ENG_ERR_INVALID, "%s: animations[%d]: %d is out of range (%s has %u animations)",
                            q->path, i, a->index, s->path, s->animation_count);
        }
        keep[found] = 1;
    }
    uint32_t kept = 0;
    for (uint32_t k = 0; k < s->animation_count; k++) {
        if (keep[k]) {
            s->animations[kept++] = s->animations[k];
            continue;
        }
        for (uint32_t c = 0; c < s->animations[k].channel_count; c++) {
            free(s->animations[k].channels[c].times);
            free(s->animations[k].channels[c].values);
        }
        free(s->animations[k].channels);
    }
    s->animation_count = kept;
    free(keep);
    return ENG_OK;
}

/* The unit quaternion (x, y, z, w) that turns -Z (a glTF light's direction) onto d (unit). */
static void quat_from_minus_z(const float d[3], float q[4])
{
    /* q = (a × d, 1 + a·d) normalised, a = (0, 0, -1); opposite vectors: half a turn about Y. */
    double x = d[1], y = -(double)d[0], z = 0.0, w = 1.0 - (double)d[2];
    double len = sqrt(x * x + y * y + z * z + w * w);
    if (w < 1e-9) {
        q[0] = 0.0f, q[1] = 1.0f, q[2] = 0.0f, q[3] = 0.0f;
        return;
    }
    q[0] = (float)(x / len);
    q[1] = (float)(y / len);
    q[2] = (float)(z / len);
    q[3] = (float)(w / len);
}

/* Appends q's lights to the scene's, each on a new root node after the glTF's nodes. */
static eng_result add_lights(const seq_sequence *q, scn_scene *s, eng_error *err)
{
    uint32_t n = (uint32_t)q->light_count;
    scn_light *lights = realloc(s->lights, (s->light_count + n) * sizeof *lights);
    if (lights)
        s->lights = lights;
    scn_node *nodes = realloc(s->nodes, (s->node_count + n) * sizeof *nodes);
    if (nodes)
        s->nodes = nodes;
    if (!lights || !nodes)
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory", q->path);
    for (uint32_t i = 0; i < n; i++) {
        const seq_light *l = &q->lights[i];
        scn_node *d = &s->nodes[s->node_count + i];
        s->lights[s->light_count + i] = l->light;
        memset(d, 0, sizeof *d);
        snprintf(d->name, sizeof d->name, "%s", l->light.name);
        d->source = -1;
        d->parent = -1;
        d->mesh = -1;
        d->camera = -1;
        d->skin = -1;
        d->weight_first = s->weight_count;
        d->light = (int32_t)(s->light_count + i);
        for (int k = 0; k < 16; k++)
            d->matrix[k] = (k % 5 == 0) ? 1.0f : 0.0f;
        memcpy(d->translation, l->position, sizeof d->translation);
        quat_from_minus_z(l->direction, d->rotation);
        d->scale[0] = d->scale[1] = d->scale[2] = 1.0f;
    }
    s->light_count += n;
    s->node_count += n;
    return ENG_OK;
}

eng_result seq_load_scene(const seq_sequence *q, scn_scene **out, eng_error *err)
{
    scn_scene *s = NULL;
    eng_result r = scn_load_gltf_scene(q->scene_path, q->has_scene_index ? q->scene_index : -1, &s, err);
    if (r)
        return r;
    if ((q->has_animations && (r = choose_animations(q, s, err))) || (q->light_count > 0 && (r = add_lights(q, s, err)))) {
        scn_destroy(s);
        return r;
    }
    int lit = 0;
    for (uint32_t i = 0; i < s->node_count; i++) {
        const scn_light *l = s->nodes[i].light >= 0 ? &s->lights[s->nodes[i].light] : NULL;
        if (l && l->intensity > 0.0f && (l->color[0] > 0.0f || l->color[1] > 0.0f || l->color[2] > 0.0f))
            lit = 1;
    }
    if (!lit)
        scn_warn(s, "no light: neither %s nor the sequence has a light that emits, so every frame is black "
                    "(add \"lights\" to the sequence)", s->path);
    *out = s;
    return ENG_OK;
}
