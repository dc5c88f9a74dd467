/* bench_config.c — reads an `ispm bench` config (docs/bench.md) into a bench_config and checks
 * everything that can be checked without the engine: known keys only, the frame list, repeats,
 * warm-up and threads in range, a grid of non-empty value lists, 1..BENCH_MAX_METHODS methods
 * with distinct names and no setting both swept and fixed, and the chart's metric and buffer.
 * Paths in the config are resolved against its folder. It owns the parsed JSON (bench_config.root):
 * the grid and methods point into it. */
#include "bench_config.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Resolves p relative to the folder of `file` unless absolute. */
static void resolve(const char *file, const char *p, char *out, size_t size)
{
    const char *slash = strrchr(file, '/');
    if (p[0] == '/' || !slash)
        snprintf(out, size, "%s", p);
    else
        snprintf(out, size, "%.*s/%s", (int)(slash - file), file, p);
}

static int get_int_in(const cJSON *v, int lo, int hi, int *out)
{
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) || v->valuedouble != floor(v->valuedouble) ||
        v->valuedouble < lo || v->valuedouble > hi)
        return 0;
    *out = (int)v->valuedouble;
    return 1;
}

static int valid_name(const char *s)
{
    if (!s[0] || strlen(s) > 48)
        return 0;
    for (; *s; s++)
        if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') || (*s >= '0' && *s <= '9') || strchr("_-+.", *s)))
            return 0;
    return 1;
}

static eng_result check_keys(const char *path, const cJSON *obj, const char *where, const char *const *allowed,
                             eng_error *err)
{
    for (const cJSON *it = obj->child; it; it = it->next) {
        int ok = 0;
        for (const char *const *a = allowed; *a && !ok; a++)
            ok = !strcmp(it->string, *a);
        if (!ok)
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: unknown key \"%s\"", path, where, it->string);
    }
    return ENG_OK;
}

eng_result bench_config_load(const char *path, bench_config *c, eng_error *err)
{
    memset(c, 0, sizeof *c);
    c->path = path;
    char *text = NULL;
    size_t len = 0;
    eng_result r = eng_read_file(path, (size_t)1 << 20, &text, &len, err);
    if (r == ENG_OK && (r = eng_json_precheck(path, text, len, ENG_JSON_MAX_DEPTH, err)) != ENG_OK)
        free(text);
    if (r != ENG_OK)
        return r;
    const char *end = NULL;
    c->root = cJSON_ParseWithLengthOpts(text, len + 1, &end, 1); /* + its NUL: nothing may follow */
    if (!c->root) {
        size_t at = end && end >= text ? (size_t)(end - text) : 0;
        free(text);
        return eng_fail(err, ENG_ERR_PARSE, "%s: not valid JSON (near byte %zu)", path, at);
    }
    free(text);
    const cJSON *root = c->root, *v;
    if (!cJSON_IsObject(root))
        return eng_fail(err, ENG_ERR_INVALID, "%s: expected a JSON object", path);
    static const char *const keys[] = {"sequence", "reference", "frames", "repeats", "warmup", "threads",
                                       "grid", "methods", "chart", "reference_frame", "report_frames", NULL};
    if ((r = check_keys(path, root, "config", keys, err)))
        return r;
    v = cJSON_GetObjectItemCaseSensitive(root, "sequence");
    if (!cJSON_IsString(v) || !v->valuestring[0])
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"sequence\": expected the path of a sequence file", path);
    resolve(path, v->valuestring, c->sequence, sizeof c->sequence);
    v = cJSON_GetObjectItemCaseSensitive(root, "reference");
    if (!cJSON_IsString(v) || !v->valuestring[0])
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"reference\": expected the path of a reference run folder", path);
    resolve(path, v->valuestring, c->reference, sizeof c->reference);

    v = cJSON_GetObjectItemCaseSensitive(root, "frames");
    int n;
    if (cJSON_IsNumber(v)) {
        if (!get_int_in(v, 1, BENCH_MAX_FRAMES, &n))
            return eng_fail(err, ENG_ERR_INVALID, "%s: \"frames\": a count must be an integer in 1..%d", path,
                            BENCH_MAX_FRAMES);
        for (int i = 0; i < n; i++)
            c->frames[i] = i;
        c->frame_count = n;
    } else if (cJSON_IsArray(v)) {
        n = cJSON_GetArraySize(v);
        if (n < 1 || n > BENCH_MAX_FRAMES)
            return eng_fail(err, ENG_ERR_INVALID, "%s: \"frames\": expected 1..%d frame indices", path,
                            BENCH_MAX_FRAMES);
        int i = 0;
        for (const cJSON *it = v->child; it; it = it->next, i++) {
            if (!get_int_in(it, 0, 1 << 20, &c->frames[i]))
                return eng_fail(err, ENG_ERR_INVALID, "%s: \"frames\"[%d]: expected a frame index >= 0", path, i);
            for (int k = 0; k < i; k++)
                if (c->frames[k] == c->frames[i])
                    return eng_fail(err, ENG_ERR_INVALID, "%s: \"frames\": frame %d listed twice", path, c->frames[i]);
        }
        c->frame_count = n;
    } else {
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"frames\": expected a frame count or an array of frame indices",
                        path);
    }
    c->reference_frame = -1;
    if ((v = cJSON_GetObjectItemCaseSensitive(root, "reference_frame")) &&
        !get_int_in(v, 0, 1 << 20, &c->reference_frame))
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"reference_frame\": expected a frame index >= 0", path);
    if ((v = cJSON_GetObjectItemCaseSensitive(root, "report_frames"))) {
        int m = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : 0;
        if (m < 1 || m > BENCH_MAX_SERIES)
            return eng_fail(err, ENG_ERR_INVALID, "%s: \"report_frames\": expected a list of 1..%d frame indices",
                            path, BENCH_MAX_SERIES);
        int i = 0;
        for (const cJSON *it = v->child; it; it = it->next, i++) {
            int f = -1, k = 0;
            if (get_int_in(it, 0, 1 << 20, &f))
                for (k = 0; k < c->frame_count && c->frames[k] != f; k++)
                    ;
            if (f < 0 || k == c->frame_count)
                return eng_fail(err, ENG_ERR_INVALID, "%s: \"report_frames\"[%d]: expected one of the \"frames\"",
                                path, i);
            c->report_frames[i] = k;
        }
        c->report_count = m;
    }
    c->repeats = 1;
    c->warmup = 1;
    if ((v = cJSON_GetObjectItemCaseSensitive(root, "repeats")) && !get_int_in(v, 1, 100, &c->repeats))
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"repeats\": expected an integer in 1..100", path);
    if ((v = cJSON_GetObjectItemCaseSensitive(root, "warmup")) && !get_int_in(v, 0, 10, &c->warmup))
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"warmup\": expected an integer in 0..10", path);
    if ((v = cJSON_GetObjectItemCaseSensitive(root, "threads")) && !get_int_in(v, 1, 64, &c->threads))
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"threads\": expected an integer in 1..64", path);

    c->grid = cJSON_GetObjectItemCaseSensitive(root, "grid");
    if (c->grid) {
        if (!cJSON_IsObject(c->grid))
            return eng_fail(err, ENG_ERR_INVALID, "%s: \"grid\": expected an object of setting → list of values", path);
        for (const cJSON *it = c->grid->child; it; it = it->next) {
            if (++c->grid_key_count > BENCH_MAX_KEYS)
                return eng_fail(err, ENG_ERR_INVALID, "%s: \"grid\": more than %d settings", path, BENCH_MAX_KEYS);
            if (!strcmp(it->string, "threads"))
                return eng_fail(err, ENG_ERR_INVALID, "%s: grid.threads: set \"threads\" at the top level", path);
            if (!cJSON_IsArray(it) || cJSON_GetArraySize(it) < 1)
                return eng_fail(err, ENG_ERR_INVALID, "%s: grid.%s: expected a non-empty list of values", path,
                                it->string);
            for (const cJSON *x = it->child; x; x = x->next)
                if (!cJSON_IsNumber(x) && !cJSON_IsString(x) && !cJSON_IsBool(x))
                    return eng_fail(err, ENG_ERR_INVALID, "%s: grid.%s: values must be numbers, strings or booleans",
                                    path, it->string);
        }
    }
    c->methods = cJSON_GetObjectItemCaseSensitive(root, "methods");
    if (!cJSON_IsArray(c->methods) || cJSON_GetArraySize(c->methods) < 1 ||
        cJSON_GetArraySize(c->methods) > BENCH_MAX_METHODS)
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"methods\": expected a list of 1..%d methods", path,
                        BENCH_MAX_METHODS);
    int mi = 0;
    for (const cJSON *m = c->methods->child; m; m = m->next, mi++) {
        char where[64];
        snprintf(where, sizeof where, "methods[%d]", mi);
        static const char *const mkeys[] = {"name", "settings", NULL};
        if (!cJSON_IsObject(m))
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: expected an object {\"name\", \"settings\"}", path, where);
        if ((r = check_keys(path, m, where, mkeys, err)))
            return r;
        const cJSON *name = cJSON_GetObjectItemCaseSensitive(m, "name");
        if (!cJSON_IsString(name) || !valid_name(name->valuestring))
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s.name: expected 1..48 characters of A-Z a-z 0-9 _ - + .", path,
                            where);
        for (const cJSON *o = c->methods->child; o != m; o = o->next)
            if (!strcmp(cJSON_GetObjectItemCaseSensitive(o, "name")->valuestring, name->valuestring))
                return eng_fail(err, ENG_ERR_INVALID, "%s: %s.name: \"%s\" is used twice", path, where, name->valuestring);
        const cJSON *s = cJSON_GetObjectItemCaseSensitive(m, "settings");
        if (s && !cJSON_IsObject(s))
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s.settings: expected an object", path, where);
        for (const cJSON *it = s ? s->child : NULL; it; it = it->next) {
            if (c->grid && cJSON_GetObjectItemCaseSensitive(c->grid, it->string))
                return eng_fail(err, ENG_ERR_INVALID, "%s: %s.settings.%s: also swept in \"grid\"", path, where,
                                it->string);
            if (!strcmp(it->string, "threads"))
                return eng_fail(err, ENG_ERR_INVALID, "%s: %s.settings.threads: set \"threads\" at the top level",
                                path, where);
        }
    }
    c->method_count = mi;
    c->chart_metric = "rmse";
    c->chart_buffer = "indirect";
    if ((v = cJSON_GetObjectItemCaseSensitive(root, "chart"))) {
        static const char *const ckeys[] = {"metric", "buffer", NULL};
        if (!cJSON_IsObject(v))
            return eng_fail(err, ENG_ERR_INVALID, "%s: \"chart\": expected an object", path);
        if ((r = check_keys(path, v, "chart", ckeys, err)))
            return r;
        const cJSON *m = cJSON_GetObjectItemCaseSensitive(v, "metric"), *b = cJSON_GetObjectItemCaseSensitive(v, "buffer");
        if (m) {
            static const char *const metrics[] = {"rmse",       "rel_mse",   "mae",           "max_abs",
                                                  "block_rmse", "block_p90", "flat_block_p90"};
            c->chart_metric = NULL;
            for (int i = 0; i < 7 && cJSON_IsString(m); i++)
                if (!strcmp(m->valuestring, metrics[i]))
                    c->chart_metric = metrics[i];
            if (!c->chart_metric)
                return eng_fail(err, ENG_ERR_INVALID,
                                "%s: chart.metric: expected one of rmse, rel_mse, mae, max_abs, block_rmse, block_p90, "
                                "flat_block_p90",
                                path);
        }
        if (b) {
            if (!cJSON_IsString(b) || (strcmp(b->valuestring, "indirect") && strcmp(b->valuestring, "full")))
                return eng_fail(err, ENG_ERR_INVALID, "%s: chart.buffer: expected \"indirect\" or \"full\"", path);
            c->chart_buffer = !strcmp(b->valuestring, "indirect") ? "indirect" : "full";
            if ((!strcmp(c->chart_metric, "block_p90") || !strcmp(c->chart_metric, "flat_block_p90")) &&
                strcmp(c->chart_buffer, "indirect"))
                return eng_fail(err, ENG_ERR_INVALID, "%s: chart.metric %s is measured on the indirect buffer only",
                                path, c->chart_metric);
        }
    }
    return ENG_OK;
}

void bench_config_free(bench_config *c)
{
    cJSON_Delete(c->root);
    c->root = NULL;
}
