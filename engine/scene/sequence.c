/* sequence.c — sequence files: which scene, how many frames at what rate, the image size,
 * the camera, engine settings and which buffers to capture (seq_load, seq_parse, seq_wants).
 *
 * The format is a JSON object read with cJSON:
 *   name        optional; [A-Za-z0-9._-], not starting with '.', < SCN_NAME_MAX bytes;
 *               default: the file name without its extension
 *   scene       required; path of the glTF, relative to the sequence file's folder or absolute
 *   frames      required; integer 1..100000; frame i is at t = i / fps
 *   fps         required; finite number > 0
 *   still       optional; true: every frame is rendered at t = 0 (a still view whose frames
 *               differ only in their random numbers); default false
 *   resolution  required; [width, height], integers 1..16384
 *   camera      optional; {"node": "<glTF node with a camera>"} or
 *               {"keys": [{"time", "position", "target"}, ...], "up", "yfov_deg", "znear", "zfar"}
 *               (up to SEQ_MAX_CAMKEYS keys, times strictly increasing; defaults up (0,1,0),
 *               40°, 0.05, 100) or {"frame": "scene", "direction", "up", "yfov_deg"} (the
 *               scene's bounds framed, seq_frame_scene); absent: framed along the default
 *               direction SEQ_FRAME_DIRECTION
 *   settings    optional; the keys of engine/core/settings.def (docs/settings.md), each
 *               checked as its line says; absent ones get eng_settings_defaults. A "preset"
 *               key applies its bundle (presets.c) first; the other keys override it
 *   capture     optional; 1..SEQ_MAX_CAPTURE fnmatch globs of buffer names; absent means all
 *   scene_index optional; which of the glTF's scenes is played (default: its default scene)
 *   animations  optional; [name or index, ...] of the glTF animations played (default: all)
 *   lights      optional; up to SEQ_MAX_LIGHTS lights added to the scene's own (parse_lights)
 * camera.node may also be a glTF node index (an unnamed camera node).
 * Every key is checked: an unknown or duplicated key, a wrong type or a value out of range is
 * ENG_ERR_INVALID naming the key and the value, so a typo never falls back to a default. Zero
 * is refused for settings whose struct encoding reads 0 as "default" (shadow_bias), since
 * accepting it would silently mean something else. Broken JSON is ENG_ERR_PARSE with the
 * line and column cJSON stopped at. The parsed sequence owns no memory. */
#define _POSIX_C_SOURCE 200809L

#include "seq.h"

#include <cjson/cJSON.h>
#include <fnmatch.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SEQ_MAX_FILE ((size_t)16 << 20)
#define PI 3.14159265358979323846

typedef struct parser {
    const char *path;
    eng_error *err;
} parser;

static eng_result bad(parser *P, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static eng_result bad(parser *P, const char *fmt, ...)
{
    char what[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return eng_fail(P->err, ENG_ERR_INVALID, "%s: %s", P->path, what);
}

/* A JSON value as text for messages, cut to fit. */
static const char *show(const cJSON *item, char *buf, size_t size)
{
    char *text = cJSON_PrintUnformatted(item);
    if (!text) {
        snprintf(buf, size, "(value)");
        return buf;
    }
    size_t n = strlen(text);
    if (n < size) {
        memcpy(buf, text, n + 1);
    } else {
        memcpy(buf, text, size - 4);
        memcpy(buf + size - 4, "...", 4);
    }
    cJSON_free(text);
    return buf;
}

static eng_result check_keys(parser *P, const cJSON *obj, const char *where, const char *const *allowed)
{
    for (const cJSON *it = obj->child; it; it = it->next) {
        int ok = 0;
        for (const char *const *a = allowed; *a; a++)
            ok |= strcmp(it->string, *a) == 0;
        if (!ok)
            return bad(P, "%s%sunknown key \"%s\"", where, *where ? ": " : "", it->string);
        for (const cJSON *prev = obj->child; prev != it; prev = prev->next)
            if (strcmp(prev->string, it->string) == 0)
                return bad(P, "%s%sduplicate key \"%s\"", where, *where ? ": " : "", it->string);
    }
    return ENG_OK;
}

static eng_result get_number(parser *P, const cJSON *item, const char *where, double *out)
{
    char v[80];
    if (!cJSON_IsNumber(item))
        return bad(P, "%s: expected a number, got %s", where, show(item, v, sizeof v));
    if (!isfinite(item->valuedouble))
        return bad(P, "%s: %s is not a finite number", where, show(item, v, sizeof v));
    *out = item->valuedouble;
    return ENG_OK;
}

static eng_result get_int(parser *P, const cJSON *item, const char *where, int lo, int hi, int *out)
{
    char v[80];
    if (!cJSON_IsNumber(item) || !isfinite(item->valuedouble) || item->valuedouble != floor(item->valuedouble))
        return bad(P, "%s: expected an integer, got %s", where, show(item, v, sizeof v));
    if (item->valuedouble < lo || item->valuedouble > hi)
        return bad(P, "%s: %s is out of range %d..%d", where, show(item, v, sizeof v), lo, hi);
    *out = (int)item->valuedouble;
    return ENG_OK;
}

/* A non-empty string shorter than size bytes. */
static eng_result get_string(parser *P, const cJSON *item, const char *where, char *out, size_t size)
{
    char v[80];
    if (!cJSON_IsString(item))
        return bad(P, "%s: expected a string, got %s", where, show(item, v, sizeof v));
    size_t n = strlen(item->valuestring);
    if (n == 0 || n >= size)
        return bad(P, "%s: %s must be 1..%zu bytes long", where, show(item, v, sizeof v), size - 1);
    memcpy(out, item->valuestring, n + 1);
    return ENG_OK;
}

static eng_result get_vec3(parser *P, const cJSON *item, const char *where, float out[3])
{
    char v[80], w[96];
    if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 3)
        return bad(P, "%s: expected an array of 3 numbers, got %s", where, show(item, v, sizeof v));
    int i = 0;
    for (const cJSON *e = item->child; e; e = e->next, i++) {
        double d = 0.0;
        snprintf(w, sizeof w, "%s[%d]", where, i);
        eng_result r = get_number(P, e, w, &d);
        if (r)
            return r;
        if (fabs(d) > 3.0e38)
            return bad(P, "%s: %g does not fit a float", w, d);
        out[i] = (float)d;
    }
    return ENG_OK;
}

/* One setting's value, checked as its settings.def line says. The messages name the key as
 * "settings.<key>" and the range or the names as the table gives them. */
static eng_result parse_setting(parser *P, const eng_setting *d, const cJSON *it, eng_settings *s)
{
    char v[80], where[96];
    eng_result r;
    snprintf(where, sizeof where, "settings.%s", d->key);
    switch (d->type) {
    case ENG_SETTING_INT: {
        int n = 0;
        if ((r = get_int(P, it, where, (int)d->lo, (int)d->hi, &n)))
            return r;
        if (d->step > 1) {
            int f = n;
            while (f > 1 && f % d->step == 0)
                f /= d->step;
            if (f != 1)
                return bad(P, "%s: %s is not %s", where, show(it, v, sizeof v), d->step_text);
        }
        d->set(s, n);
        return ENG_OK;
    }
    case ENG_SETTING_FLOAT: {
        double x = 0.0;
        if (d->word && cJSON_IsString(it) && !strcmp(it->valuestring, d->word)) {
            d->set(s, d->def);
            d->word_set(s, 1);
            return ENG_OK;
        }
        if (d->word && !cJSON_IsNumber(it))
            return bad(P, "%s: expected a number or \"%s\", got %s", where, d->word, show(it, v, sizeof v));
        if ((r = get_number(P, it, where, &x)))
            return r;
        switch (d->ends) {
        case ENG_ENDS_CLOSED:
            if (!(x >= d->lo && x <= d->hi))
                return bad(P, "%s: %s is out of range %g..%g%s", where, show(it, v, sizeof v), d->lo, d->hi, d->note);
            break;
        case ENG_ENDS_OPEN_LO:
            if (!(x > d->lo && x <= d->hi))
                return bad(P, "%s: %s is out of range (%g, %g]%s", where, show(it, v, sizeof v), d->lo, d->hi,
                           d->note);
            break;
        case ENG_ENDS_OPEN:
            if (!(x > d->lo && x < d->hi))
                return bad(P, "%s: %s is out of range (%g, %g)%s", where, show(it, v, sizeof v), d->lo, d->hi,
                           d->note);
            break;
        case ENG_ENDS_POSITIVE:
            if (!(x > d->lo) || x > d->hi || (float)x == 0.0f)
                return bad(P, "%s: %s must be positive (0 would mean the default)", where, show(it, v, sizeof v));
            break;
        }
        d->set(s, x);
        if (d->word)
            d->word_set(s, 0);
        return ENG_OK;
    }
    case ENG_SETTING_BOOL:
        if (!cJSON_IsBool(it))
            return bad(P, "%s: expected true or false, got %s", where, show(it, v, sizeof v));
        d->set(s, cJSON_IsTrue(it) ? 1 : 0);
        return ENG_OK;
    case ENG_SETTING_ENUM:
    case ENG_SETTING_NAME:
        for (int i = 0; cJSON_IsString(it) && i < d->name_count; i++)
            if (!strcmp(it->valuestring, d->names[i].name)) {
                if (d->type == ENG_SETTING_ENUM) {
                    d->set(s, d->names[i].value);
                } else {
                    size_t n = 0;
                    char *t = d->text(s, &n);
                    snprintf(t, n, "%s", d->names[i].name);
                }
                return ENG_OK;
            }
        {
            char list[400];
            size_t at = 0;
            list[0] = 0;
            for (int i = 0; i < d->name_count && at < sizeof list; i++)
                at += (size_t)snprintf(list + at, sizeof list - at, "%s\"%s\"", i ? ", " : "", d->names[i].name);
            return bad(P, "%s: %s is not one of %s%s", where, show(it, v, sizeof v), list, d->note);
        }
    }
    return ENG_OK;
}

/* Every key of settings.def, then the checks across keys that no one line can state. */
static eng_result parse_settings(parser *P, const cJSON *obj, eng_settings *s)
{
    int count = 0;
    const eng_setting *table = eng_settings_table(&count);
    const char *keys[128];
    if (count >= (int)(sizeof keys / sizeof keys[0])) { /* a programmer error: settings.def outgrew keys */
        fprintf(stderr, "ispm: %d settings, room for %d\n", count, (int)(sizeof keys / sizeof keys[0]) - 1);
        abort();
    }
    for (int i = 0; i < count; i++)
        keys[i] = table[i].key;
    keys[count] = NULL;
    char v[80];
    eng_result r;
    if (!cJSON_IsObject(obj))
        return bad(P, "settings: expected an object, got %s", show(obj, v, sizeof v));
    if ((r = check_keys(P, obj, "settings", keys)))
        return r;
    /* A preset's settings first (checked as the sequence's own would be), then the sequence's
     * own keys over them. */
    const eng_setting *pd = eng_setting_find("preset");
    const cJSON *pit = cJSON_GetObjectItemCaseSensitive(obj, "preset");
    if (pd && pit) {
        if ((r = parse_setting(P, pd, pit, s)))
            return r;
        const char *text = seq_preset_settings(s->preset);
        cJSON *preset = text ? cJSON_Parse(text) : NULL;
        if (text && !preset) { /* a programmer error: presets.c's text is not JSON */
            fprintf(stderr, "ispm: preset %s: not a JSON object\n", pit->valuestring);
            abort();
        }
        for (int i = 0; preset && i < count; i++) {
            const cJSON *it = cJSON_GetObjectItemCaseSensitive(preset, table[i].key);
            if (it && (r = parse_setting(P, &table[i], it, s))) {
                cJSON_Delete(preset);
                return r;
            }
        }
        cJSON_Delete(preset);
    }
    for (int i = 0; i < count; i++) {
        const cJSON *it = cJSON_GetObjectItemCaseSensitive(obj, table[i].key);
        if (it && (r = parse_setting(P, &table[i], it, s)))
            return r;
    }
    /* Per-pixel progressive radii: only where the method evaluates a pixel-dependent kernel
     * (ind_method.per_pixel_radius; the engine checks the same). */
    if (s->progressive_pixel &&
        (!s->progressive || s->indirect == ENG_INDIRECT_TILEGATHER_GL || s->indirect == ENG_INDIRECT_FINALGATHER))
        return bad(P, "settings.progressive_radius \"pixel\" needs \"progressive\": true and an indirect method "
                      "other than \"tile-gather-gl\" and \"final-gather\"");
    /* The final gather has no kernel at the pixel (ind_method.traced_gather; the engine checks
     * the same). */
    if (s->boundary == ENG_BOUNDARY_RENORMALIZE && s->indirect == ENG_INDIRECT_FINALGATHER)
        return bad(P, "settings.boundary \"renormalize\" corrects a kernel at the pixel; \"final-gather\" has none");
    return ENG_OK;
}

static eng_result parse_camera_keys(parser *P, const cJSON *keys, seq_sequence *out)
{
    static const char *const key_keys[] = {"time", "position", "target", NULL};
    char v[80], w[96];
    eng_result r;
    int n = cJSON_IsArray(keys) ? cJSON_GetArraySize(keys) : -1;
    if (n < 1 || n > SEQ_MAX_CAMKEYS)
        return bad(P, "camera.keys: expected an array of 1..%d keys, got %s", SEQ_MAX_CAMKEYS,
                   show(keys, v, sizeof v));
    int i = 0;
    for (const cJSON *k = keys->child; k; k = k->next, i++) {
        seq_camera_key *d = &out->camera_keys[i];
        snprintf(w, sizeof w, "camera.keys[%d]", i);
        if (!cJSON_IsObject(k))
            return bad(P, "%s: expected an object, got %s", w, show(k, v, sizeof v));
        if ((r = check_keys(P, k, w, key_keys)))
            return r;
        static const char *const required[] = {"time", "position", "target"};
        for (int q = 0; q < 3; q++)
            if (!cJSON_GetObjectItemCaseSensitive(k, required[q]))
                return bad(P, "%s: missing required key \"%s\"", w, required[q]);
        char f[112];
        snprintf(f, sizeof f, "%s.time", w);
        if ((r = get_number(P, cJSON_GetObjectItemCaseSensitive(k, "time"), f, &d->time)))
            return r;
        if (d->time < 0.0)
            return bad(P, "%s: %g is negative", f, d->time);
        if (i > 0 && !(d->time > out->camera_keys[i - 1].time))
            return bad(P, "%s: %g does not come after the previous key's %g", f, d->time,
                       out->camera_keys[i - 1].time);
        snprintf(f, sizeof f, "%s.position", w);
        if ((r = get_vec3(P, cJSON_GetObjectItemCaseSensitive(k, "position"), f, d->position)))
            return r;
        snprintf(f, sizeof f, "%s.target", w);
        if ((r = get_vec3(P, cJSON_GetObjectItemCaseSensitive(k, "target"), f, d->target)))
            return r;
        if (d->position[0] == d->target[0] && d->position[1] == d->target[1] && d->position[2] == d->target[2])
            return bad(P, "%s: position and target coincide", w);
    }
    out->camera_key_count = n;
    return ENG_OK;
}

/* The look-at frame needs up not parallel to a viewing direction. */
static int parallel(const double dir[3], const float up[3])
{
    double c[3], u[3] = {up[0], up[1], up[2]};
    c[0] = dir[1] * u[2] - dir[2] * u[1];
    c[1] = dir[2] * u[0] - dir[0] * u[2];
    c[2] = dir[0] * u[1] - dir[1] * u[0];
    double cl = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    double dl = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    return !(cl > 1e-6 * dl * ul);
}

/* {"frame": "scene", "direction", "up", "yfov_deg"}, or no camera at all (cam NULL). */
static eng_result parse_frame(parser *P, const cJSON *cam, seq_sequence *out)
{
    static const char *const frame_keys[] = {"frame", "direction", "up", "yfov_deg", NULL};
    static const float fallback[3] = SEQ_FRAME_DIRECTION;
    char v[80];
    eng_result r;
    const cJSON *it;
    out->camera_frame = 1;
    memcpy(out->camera_direction, fallback, sizeof fallback);
    if (cam) {
        if ((r = check_keys(P, cam, "camera (with \"frame\")", frame_keys)))
            return r;
        it = cJSON_GetObjectItemCaseSensitive(cam, "frame");
        if (!cJSON_IsString(it) || strcmp(it->valuestring, "scene") != 0)
            return bad(P, "camera.frame: expected \"scene\", got %s", show(it, v, sizeof v));
        if ((it = cJSON_GetObjectItemCaseSensitive(cam, "direction")) &&
            (r = get_vec3(P, it, "camera.direction", out->camera_direction)))
            return r;
        if ((it = cJSON_GetObjectItemCaseSensitive(cam, "up")) && (r = get_vec3(P, it, "camera.up", out->camera_up)))
            return r;
        if ((it = cJSON_GetObjectItemCaseSensitive(cam, "yfov_deg"))) {
            double d;
            if ((r = get_number(P, it, "camera.yfov_deg", &d)))
                return r;
            if (!(d > 0.0 && d < 180.0))
                return bad(P, "camera.yfov_deg: %s is outside (0, 180)", show(it, v, sizeof v));
            out->camera_yfov = (float)(d * PI / 180.0);
        }
    }
    float *dv = out->camera_direction;
    double len = sqrt((double)dv[0] * dv[0] + (double)dv[1] * dv[1] + (double)dv[2] * dv[2]);
    if (!(len > 0.0) || !isfinite(len))
        return bad(P, "camera.direction: is the zero vector");
    const float *u = out->camera_up;
    if (u[0] == 0.0f && u[1] == 0.0f && u[2] == 0.0f)
        return bad(P, "camera.up: is the zero vector");
    double dir[3];
    for (int j = 0; j < 3; j++)
        dv[j] = (float)(dv[j] / len), dir[j] = dv[j];
    if (parallel(dir, out->camera_up))
        return bad(P, "camera.direction: is parallel to camera.up");
    return ENG_OK;
}

static eng_result parse_camera(parser *P, const cJSON *cam, seq_sequence *out)
{
    static const char *const node_keys[] = {"node", NULL};
    static const char *const look_keys[] = {"keys", "up", "yfov_deg", "znear", "zfar", NULL};
    char v[80];
    eng_result r;
    out->camera_up[0] = 0.0f;
    out->camera_up[1] = 1.0f;
    out->camera_up[2] = 0.0f;
    out->camera_yfov = (float)(40.0 * PI / 180.0);
    out->camera_znear = 0.05f;
    out->camera_zfar = 100.0f;
    if (!cam)
        return parse_frame(P, NULL, out);
    if (!cJSON_IsObject(cam))
        return bad(P, "camera: expected an object, got %s", show(cam, v, sizeof v));
    const cJSON *node = cJSON_GetObjectItemCaseSensitive(cam, "node");
    const cJSON *keys = cJSON_GetObjectItemCaseSensitive(cam, "keys");
    const cJSON *frame = cJSON_GetObjectItemCaseSensitive(cam, "frame");
    if ((node != NULL) + (keys != NULL) + (frame != NULL) > 1)
        return bad(P, "camera: has more than one of \"node\", \"keys\" and \"frame\"; give one");
    if (frame)
        return parse_frame(P, cam, out);
    if (!node && !keys)
        return bad(P, "camera: needs \"node\", \"keys\" or \"frame\"");
    if (node) {
        if ((r = check_keys(P, cam, "camera (with \"node\")", node_keys)))
            return r;
        out->camera_by_index = cJSON_IsNumber(node);
        if (out->camera_by_index) /* a glTF node index: unnamed camera nodes can be chosen too */
            return get_int(P, node, "camera.node", 0, 0x7fffffff, &out->camera_node_index);
        return get_string(P, node, "camera.node", out->camera_node, sizeof out->camera_node);
    }
    if ((r = check_keys(P, cam, "camera (with \"keys\")", look_keys)) || (r = parse_camera_keys(P, keys, out)))
        return r;
    const cJSON *it;
    double d = 0.0;
    if ((it = cJSON_GetObjectItemCaseSensitive(cam, "up"))) {
        if ((r = get_vec3(P, it, "camera.up", out->camera_up)))
            return r;
        const float *u = out->camera_up;
        if (u[0] == 0.0f && u[1] == 0.0f && u[2] == 0.0f)
            return bad(P, "camera.up: is the zero vector");
    }
    if ((it = cJSON_GetObjectItemCaseSensitive(cam, "yfov_deg"))) {
        if ((r = get_number(P, it, "camera.yfov_deg", &d)))
            return r;
        if (!(d > 0.0 && d < 180.0))
            return bad(P, "camera.yfov_deg: %s is outside (0, 180)", show(it, v, sizeof v));
        out->camera_yfov = (float)(d * PI / 180.0);
    }
    if ((it = cJSON_GetObjectItemCaseSensitive(cam, "znear"))) {
        if ((r = get_number(P, it, "camera.znear", &d)))
            return r;
        if (!(d > 0.0) || (float)d == 0.0f || d > 1.0e30)
            return bad(P, "camera.znear: %s must be positive", show(it, v, sizeof v));
        out->camera_znear = (float)d;
    }
    if ((it = cJSON_GetObjectItemCaseSensitive(cam, "zfar"))) {
        if ((r = get_number(P, it, "camera.zfar", &d)))
            return r;
        if (d > 1.0e30)
            return bad(P, "camera.zfar: %s is too large", show(it, v, sizeof v));
        out->camera_zfar = (float)d;
    }
    if (!(out->camera_zfar > out->camera_znear))
        return bad(P, "camera: zfar %g is not beyond znear %g", out->camera_zfar, out->camera_znear);
    /* The look-at frame needs up not parallel to any viewing direction. */
    for (int i = 0; i < out->camera_key_count; i++) {
        const seq_camera_key *k = &out->camera_keys[i];
        double dir[3];
        for (int j = 0; j < 3; j++)
            dir[j] = (double)k->target[j] - k->position[j];
        if (parallel(dir, out->camera_up))
            return bad(P, "camera.keys[%d]: viewing direction is parallel to camera.up", i);
    }
    return ENG_OK;
}

/* "lights": [{"type", "position", "direction", "color", "intensity", "range",
 * "inner_cone_deg", "outer_cone_deg", "name"}], the glTF KHR_lights_punctual fields with the
 * same defaults and limits (color (1,1,1), intensity 1, range 0 = infinite, cones 0° and 45°,
 * 0 <= inner < outer <= 90°); spot and directional lights need a direction. */
static eng_result parse_lights(parser *P, const cJSON *arr, seq_sequence *out)
{
    static const char *const keys[] = {"type", "position", "direction", "color", "intensity", "range",
                                       "inner_cone_deg", "outer_cone_deg", "name", NULL};
    char v[80], w[48], f[96];
    eng_result r;
    int n = cJSON_IsArray(arr) ? cJSON_GetArraySize(arr) : -1;
    if (n < 1 || n > SEQ_MAX_LIGHTS)
        return bad(P, "lights: expected an array of 1..%d lights, got %s", SEQ_MAX_LIGHTS, show(arr, v, sizeof v));
    int i = 0;
    for (const cJSON *o = arr->child; o; o = o->next, i++) {
        seq_light *d = &out->lights[i];
        scn_light *l = &d->light;
        snprintf(w, sizeof w, "lights[%d]", i);
        if (!cJSON_IsObject(o))
            return bad(P, "%s: expected an object, got %s", w, show(o, v, sizeof v));
        if ((r = check_keys(P, o, w, keys)))
            return r;
        const cJSON *it = cJSON_GetObjectItemCaseSensitive(o, "type");
        if (!it)
            return bad(P, "%s: missing required key \"type\"", w);
        if (cJSON_IsString(it) && !strcmp(it->valuestring, "point"))
            l->type = SCN_LIGHT_POINT;
        else if (cJSON_IsString(it) && !strcmp(it->valuestring, "spot"))
            l->type = SCN_LIGHT_SPOT;
        else if (cJSON_IsString(it) && !strcmp(it->valuestring, "directional"))
            l->type = SCN_LIGHT_DIRECTIONAL;
        else
            return bad(P, "%s.type: %s is not one of \"point\", \"spot\", \"directional\"", w, show(it, v, sizeof v));
        snprintf(l->name, sizeof l->name, "sequence-light%d", i);
        if ((it = cJSON_GetObjectItemCaseSensitive(o, "name"))) {
            snprintf(f, sizeof f, "%s.name", w);
            if ((r = get_string(P, it, f, l->name, sizeof l->name)))
                return r;
        }
        l->color[0] = l->color[1] = l->color[2] = 1.0f;
        l->intensity = 1.0f;
        l->outer_cone = (float)(PI / 4.0);
        d->direction[2] = -1.0f;
        if ((it = cJSON_GetObjectItemCaseSensitive(o, "position"))) {
            snprintf(f, sizeof f, "%s.position", w);
            if ((r = get_vec3(P, it, f, d->position)))
                return r;
        }
        it = cJSON_GetObjectItemCaseSensitive(o, "direction");
        if (!it && l->type != SCN_LIGHT_POINT)
            return bad(P, "%s: a %s light needs \"direction\"", w, l->type == SCN_LIGHT_SPOT ? "spot" : "directional");
        if (it) {
            snprintf(f, sizeof f, "%s.direction", w);
            if ((r = get_vec3(P, it, f, d->direction)))
                return r;
            double len = sqrt((double)d->direction[0] * d->direction[0] + (double)d->direction[1] * d->direction[1] +
                              (double)d->direction[2] * d->direction[2]);
            if (!(len > 1e-20) || !isfinite(len))
                return bad(P, "%s: is the zero vector", f);
            for (int c = 0; c < 3; c++)
                d->direction[c] = (float)(d->direction[c] / len);
        }
        if ((it = cJSON_GetObjectItemCaseSensitive(o, "color"))) {
            snprintf(f, sizeof f, "%s.color", w);
            if ((r = get_vec3(P, it, f, l->color)))
                return r;
            if (l->color[0] < 0.0f || l->color[1] < 0.0f || l->color[2] < 0.0f)
                return bad(P, "%s: %s has a negative component", f, show(it, v, sizeof v));
        }
        static const char *const scalars[] = {"intensity", "range", "inner_cone_deg", "outer_cone_deg"};
        double val[4] = {1.0, 0.0, 0.0, 45.0};
        for (int k = 0; k < 4; k++) {
            if (!(it = cJSON_GetObjectItemCaseSensitive(o, scalars[k])))
                continue;
            snprintf(f, sizeof f, "%s.%s", w, scalars[k]);
            if ((r = get_number(P, it, f, &val[k])))
                return r;
            if (val[k] < 0.0 || val[k] > 3.0e38)
                return bad(P, "%s: %s is negative or too large", f, show(it, v, sizeof v));
        }
        if (l->type == SCN_LIGHT_SPOT && !(val[2] < val[3] && val[3] <= 90.0))
            return bad(P, "%s: cone angles inner %g°, outer %g° violate 0 <= inner < outer <= 90", w, val[2], val[3]);
        l->intensity = (float)val[0];
        l->range = (float)val[1];
        if (l->type == SCN_LIGHT_SPOT) {
            l->inner_cone = (float)(val[2] * PI / 180.0);
            l->outer_cone = (float)(val[3] * PI / 180.0);
        }
    }
    out->light_count = n;
    return ENG_OK;
}

/* "animations": [name or index, ...]: the glTF animations played (absent: all of them). */
static eng_result parse_animations(parser *P, const cJSON *arr, seq_sequence *out)
{
    char v[80], w[48];
    eng_result r;
    int n = cJSON_IsArray(arr) ? cJSON_GetArraySize(arr) : -1;
    if (n < 0 || n > SEQ_MAX_ANIMATIONS)
        return bad(P, "animations: expected an array of 0..%d animation names or indices, got %s",
                   SEQ_MAX_ANIMATIONS, show(arr, v, sizeof v));
    int i = 0;
    for (const cJSON *e = arr->child; e; e = e->next, i++) {
        snprintf(w, sizeof w, "animations[%d]", i);
        out->animations[i].index = -1;
        if (cJSON_IsNumber(e))
            r = get_int(P, e, w, 0, 0x7fffffff, &out->animations[i].index);
        else
            r = get_string(P, e, w, out->animations[i].name, sizeof out->animations[i].name);
        if (r)
            return r;
    }
    out->animation_count = n;
    out->has_animations = 1;
    return ENG_OK;
}

static int valid_name(const char *s)
{
    if (s[0] == '.')
        return 0;
    for (; *s; s++)
        if (!((*s >= 'A' && *s <= 'Z') || (*s >= 'a' && *s <= 'z') || (*s >= '0' && *s <= '9') || *s == '.' ||
              *s == '_' || *s == '-'))
            return 0;
    return 1;
}

static void default_name(const char *path, char out[SCN_NAME_MAX])
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    size_t n = strlen(base);
    const char *dot = strrchr(base, '.');
    if (dot && dot != base)
        n = (size_t)(dot - base);
    if (n > SCN_NAME_MAX - 1)
        n = SCN_NAME_MAX - 1;
    memcpy(out, base, n);
    out[n] = 0;
}

static eng_result parse_root(parser *P, const cJSON *root, seq_sequence *out)
{
    static const char *const keys[] = {"name", "scene", "frames", "fps", "resolution", "camera", "settings",
                                       "capture", "still", "scene_index", "animations", "lights", NULL};
    static const char *const required[] = {"scene", "frames", "fps", "resolution"};
    char v[80];
    eng_result r;
    if (!cJSON_IsObject(root))
        return bad(P, "the sequence must be a JSON object, got %s", show(root, v, sizeof v));
    if ((r = check_keys(P, root, "", keys)))
        return r;
    for (size_t i = 0; i < sizeof required / sizeof required[0]; i++)
        if (!cJSON_GetObjectItemCaseSensitive(root, required[i]))
            return bad(P, "missing required key \"%s\"", required[i]);

    const cJSON *it = cJSON_GetObjectItemCaseSensitive(root, "name");
    if (it) {
        if ((r = get_string(P, it, "name", out->name, sizeof out->name)))
            return r;
        if (!valid_name(out->name))
            return bad(P, "name: %s may hold only A-Z a-z 0-9 . _ - and must not start with '.'",
                       show(it, v, sizeof v));
    } else {
        default_name(P->path, out->name);
    }

    char scene[4096];
    if ((r = get_string(P, cJSON_GetObjectItemCaseSensitive(root, "scene"), "scene", scene, sizeof scene)))
        return r;
    const char *slash = strrchr(P->path, '/');
    int n;
    if (scene[0] == '/' || !slash)
        n = snprintf(out->scene_path, sizeof out->scene_path, "%s", scene);
    else
        n = snprintf(out->scene_path, sizeof out->scene_path, "%.*s/%s", (int)(slash - P->path), P->path, scene);
    if (n < 0 || (size_t)n >= sizeof out->scene_path)
        return bad(P, "scene: the resolved path is longer than %zu bytes", sizeof out->scene_path - 1);

    if ((r = get_int(P, cJSON_GetObjectItemCaseSensitive(root, "frames"), "frames", 1, 100000, &out->frame_count)))
        return r;
    it = cJSON_GetObjectItemCaseSensitive(root, "fps");
    if ((r = get_number(P, it, "fps", &out->fps)))
        return r;
    if (!(out->fps > 0.0))
        return bad(P, "fps: %s must be positive", show(it, v, sizeof v));
    if ((it = cJSON_GetObjectItemCaseSensitive(root, "still"))) {
        if (!cJSON_IsBool(it))
            return bad(P, "still: expected true or false, got %s", show(it, v, sizeof v));
        out->still = cJSON_IsTrue(it) ? 1 : 0;
    }

    it = cJSON_GetObjectItemCaseSensitive(root, "resolution");
    if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) != 2)
        return bad(P, "resolution: expected [width, height], got %s", show(it, v, sizeof v));
    if ((r = get_int(P, it->child, "resolution[0]", 1, 16384, &out->width)) ||
        (r = get_int(P, it->child->next, "resolution[1]", 1, 16384, &out->height)))
        return r;

    if ((r = parse_camera(P, cJSON_GetObjectItemCaseSensitive(root, "camera"), out)))
        return r;

    if ((it = cJSON_GetObjectItemCaseSensitive(root, "scene_index"))) {
        if ((r = get_int(P, it, "scene_index", 0, 0x7fffffff, &out->scene_index)))
            return r;
        out->has_scene_index = 1;
    }
    if ((it = cJSON_GetObjectItemCaseSensitive(root, "animations")) && (r = parse_animations(P, it, out)))
        return r;
    if ((it = cJSON_GetObjectItemCaseSensitive(root, "lights")) && (r = parse_lights(P, it, out)))
        return r;

    if ((it = cJSON_GetObjectItemCaseSensitive(root, "settings")) && (r = parse_settings(P, it, &out->settings)))
        return r;
    eng_settings_defaults(&out->settings);

    if ((it = cJSON_GetObjectItemCaseSensitive(root, "capture"))) {
        int count = cJSON_IsArray(it) ? cJSON_GetArraySize(it) : -1;
        if (count < 1 || count > SEQ_MAX_CAPTURE)
            return bad(P, "capture: expected an array of 1..%d glob patterns (omit it to capture all), got %s",
                       SEQ_MAX_CAPTURE, show(it, v, sizeof v));
        int i = 0;
        for (const cJSON *e = it->child; e; e = e->next, i++) {
            char w[32];
            snprintf(w, sizeof w, "capture[%d]", i);
            if ((r = get_string(P, e, w, out->capture[i], sizeof out->capture[i])))
                return r;
        }
        out->capture_count = count;
    }
    return ENG_OK;
}

eng_result seq_parse(const char *path, const char *json, size_t len, seq_sequence *out, eng_error *err)
{
    parser P = {path, err};
    memset(out, 0, sizeof *out);
    if (strlen(path) >= sizeof out->path)
        return eng_fail(err, ENG_ERR_INVALID, "%.200s...: path longer than %zu bytes", path, sizeof out->path - 1);
    eng_result pr = eng_json_precheck(path, json, len, ENG_JSON_MAX_DEPTH, err);
    if (pr != ENG_OK && pr != ENG_ERR_PARSE) /* text after the value: named below by line and column */
        return pr;
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(json, len, &end, 0);
    size_t stop = root ? (size_t)(end - json) : (end ? (size_t)(end - json) : 0);
    if (root) { /* cJSON stops after the value; anything but whitespace after it is an error */
        while (stop < len && (json[stop] == ' ' || json[stop] == '\t' || json[stop] == '\n' || json[stop] == '\r'))
            stop++;
        if (stop < len) {
            cJSON_Delete(root);
            root = NULL;
        }
    }
    if (!root) {
        int line = 1, col = 1;
        for (size_t i = 0; i < stop && i < len; i++) {
            if (json[i] == '\n') {
                line++;
                col = 1;
            } else {
                col++;
            }
        }
        memset(out, 0, sizeof *out);
        return eng_fail(err, ENG_ERR_PARSE, "%s:%d:%d: not valid JSON", path, line, col);
    }
    eng_result r = parse_root(&P, root, out);
    cJSON_Delete(root);
    if (r) {
        memset(out, 0, sizeof *out);
        return r;
    }
    memcpy(out->path, path, strlen(path) + 1);
    eng_digest_hex(json, len, out->digest);
    return ENG_OK;
}

eng_result seq_load(const char *path, seq_sequence *out, eng_error *err)
{
    char *data;
    size_t len;
    memset(out, 0, sizeof *out);
    eng_result r = eng_read_file(path, SEQ_MAX_FILE, &data, &len, err);
    if (r)
        return r;
    r = seq_parse(path, data, len, out, err);
    free(data);
    return r;
}

int seq_wants(const seq_sequence *seq, const char *buffer_name)
{
    if (seq->capture_count == 0)
        return 1;
    for (int i = 0; i < seq->capture_count; i++)
        if (fnmatch(seq->capture[i], buffer_name, 0) == 0)
            return 1;
    return 0;
}

double seq_frame_time(const seq_sequence *seq, int frame)
{
    return seq->still ? 0.0 : frame / seq->fps;
}
