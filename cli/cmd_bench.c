/* cmd_bench.c — `ispm bench CONFIG.json -o OUTDIR`: speed versus accuracy (issue 5). A config
 * names a sequence, a reference run (frames holding reference.indirect and reference.full),
 * the frames to render, repeats, a grid of engine settings to sweep and named methods (the
 * chart's series), each with fixed settings. Every grid point of every method is rendered in
 * this process (eng_create on a copy of the sequence with the point's settings, so the engine
 * validates them exactly as in a sequence file); the per-pass times of eng_frame_stats give
 * the medians over frames × repeats, and indirect.radiance and composite.radiance are measured
 * against the reference (replay/metrics.h). The k-d gather baseline (003_… Appendix A) and
 * ISPM's scatter (§5) compute the same estimator, so a method pair differing only in
 * `indirect` shows the cost of gathering at equal error; their images and difference are
 * written side by side.
 *
 * Output (OUTDIR): bench.csv and bench.json (one row/object per grid point), error_vs_time.png
 * and .svg (log–log, one series per method, the Pareto front marked), pass_times.png (stacked
 * per-pass medians), compare_scatter_vs_gather.png/.exr. Every file is written atomically, and
 * bench.json last: an OUTDIR without it is an unfinished bench. Old bench.csv/bench.json are
 * removed before anything is rendered. Exit: 0 done, 1 rendering or writing failed, 2 bad
 * arguments, config, sequence or reference (one line naming the file). */
#define _POSIX_C_SOURCE 200809L
#include "eng.h"
#include "metrics.h"
#include "plot.h"
#include "rep_internal.h"

#include <cjson/cJSON.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int cmd_bench(int argc, char **argv, const char *command_line);

enum { B_OK = 0, B_RUNTIME = 1, B_INPUT = 2 };

#define BENCH_MAX_POINTS 1000
#define BENCH_MAX_FRAMES 256
#define BENCH_MAX_KEYS 24
#define BENCH_MAX_METHODS (PLOT_MAX_SERIES - 1) /* one series is left for the Pareto front */

static const char *const CAPTURED[] = {"indirect.radiance", "composite.radiance", "gbuffer.position",
                                       "gbuffer.normal"};
#define BENCH_MAX_SERIES 16 /* report_frames */

/* ---------------------------------------------------------------- config */

typedef struct bench_config {
    const char *path;
    cJSON *root;                     /* owns everything below that points into it */
    char sequence[4096], reference[4096];
    int frames[BENCH_MAX_FRAMES], frame_count;
    int repeats, warmup, threads;    /* threads 0 = the sequence's */
    const cJSON *grid;               /* object: key → array of values; may be NULL */
    int grid_key_count;
    const cJSON *methods;            /* array of {"name", "settings"} */
    int method_count;
    const char *chart_metric, *chart_buffer;
    int reference_frame;             /* −1: bench frame i against reference frame i; else this one */
    int report_frames[BENCH_MAX_SERIES], report_count; /* indices into frames[] with a per-frame row */
} bench_config;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ispm bench CONFIG.json -o OUTDIR [--quiet]\n"
            "       ispm bench --check CONFIG.json\n"
            "\n"
            "Renders every grid point of every method of CONFIG in-process, times each pass\n"
            "(median over frames x repeats), measures indirect.radiance and composite.radiance\n"
            "against the reference run's reference.indirect and reference.full, and writes\n"
            "OUTDIR/bench.csv, bench.json, error_vs_time.png/.svg, pass_times.png and\n"
            "compare_scatter_vs_gather.png/.exr. See docs/bench.md for the config format.\n"
            "\n"
            "  -o, --output OUTDIR  where the results go (created if needed)\n"
            "  -q, --quiet          no per-point progress\n"
            "      --check          validate CONFIG, its sequence and scene and every point's\n"
            "                       settings, render nothing, need no reference run\n"
            "  -h, --help           this text\n"
            "\n"
            "exit: 0 done; 1 rendering or writing failed; 2 bad arguments, config, sequence or\n"
            "      reference run\n");
}

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

static eng_result config_load(const char *path, bench_config *c, eng_error *err)
{
    memset(c, 0, sizeof *c);
    c->path = path;
    char *text = NULL;
    size_t len = 0;
    eng_result r = eng_read_file(path, (size_t)1 << 20, &text, &len, err);
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
            static const char *const metrics[] = {"rmse", "rel_mse", "mae", "max_abs", "block_rmse", "block_p90"};
            c->chart_metric = NULL;
            for (int i = 0; i < 6 && cJSON_IsString(m); i++)
                if (!strcmp(m->valuestring, metrics[i]))
                    c->chart_metric = metrics[i];
            if (!c->chart_metric)
                return eng_fail(err, ENG_ERR_INVALID,
                                "%s: chart.metric: expected one of rmse, rel_mse, mae, max_abs, block_rmse, block_p90",
                                path);
        }
        if (b) {
            if (!cJSON_IsString(b) || (strcmp(b->valuestring, "indirect") && strcmp(b->valuestring, "full")))
                return eng_fail(err, ENG_ERR_INVALID, "%s: chart.buffer: expected \"indirect\" or \"full\"", path);
            c->chart_buffer = !strcmp(b->valuestring, "indirect") ? "indirect" : "full";
            if (!strcmp(c->chart_metric, "block_p90") && strcmp(c->chart_buffer, "indirect"))
                return eng_fail(err, ENG_ERR_INVALID, "%s: chart.metric block_p90 is measured on the indirect buffer only",
                                path);
        }
    }
    return ENG_OK;
}

/* ---------------------------------------------------------------- settings as text */

/* The value the engine uses for a settings key, as text; 0 for a key it does not know. */
static int setting_text(const eng_settings *s, const char *key, char *out, size_t size)
{
    const eng_setting *d = eng_setting_find(key);
    if (!d)
        return 0;
    eng_setting_format(d, s, out, size);
    return 1;
}

/* ---------------------------------------------------------------- grid points */

typedef struct bench_point {
    int method;                 /* index into config methods */
    const char *method_name;
    seq_sequence *seq;          /* the sequence with this point's settings */
    char label[160];            /* "<method> v1/v2/…" (grid values) */
    /* results */
    int sample_count;
    double *pass_samples;       /* sample_count × BENCH pass slots */
    double *frame_samples;
    double pass_ms[ENG_MAX_PASSES], frame_ms;
    rep_metrics_err indirect, full;
    rep_metrics_bias bias;      /* indirect.radiance: mean ratio, block p90, edges (issue 13) */
    /* Per report frame (config report_frames): the metrics of that frame alone, and the
     * frame time summed from the first bench frame through it (first repeat). */
    rep_metrics_err series_err[BENCH_MAX_SERIES];
    rep_metrics_bias series_bias[BENCH_MAX_SERIES];
    double series_ms[BENCH_MAX_SERIES];
    float *first_indirect;      /* indirect.radiance of the first bench frame */
    int pareto;
} bench_point;

/* The sequence file's JSON with a point's settings: grid values, the method's settings, the
 * config's threads, and capture limited to what the bench reads (so the engine reads back
 * nothing else). */
static eng_result point_sequence(const bench_config *c, const cJSON *seq_root, const cJSON *method, const int *choice,
                                 seq_sequence *out, char *label, size_t label_size, eng_error *err)
{
    cJSON *root = cJSON_Duplicate(seq_root, 1);
    if (!root) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    cJSON *settings = cJSON_GetObjectItemCaseSensitive(root, "settings");
    if (!settings) {
        settings = cJSON_CreateObject();
        cJSON_AddItemToObject(root, "settings", settings);
    }
    const char *mname = cJSON_GetObjectItemCaseSensitive(method, "name")->valuestring;
    size_t used = (size_t)snprintf(label, label_size, "%s", mname);
    char what[512];
    size_t wused = (size_t)snprintf(what, sizeof what, "method \"%s\"", mname);
    int k = 0;
    for (const cJSON *it = c->grid ? c->grid->child : NULL; it; it = it->next, k++) {
        const cJSON *val = cJSON_GetArrayItem(it, choice[k]);
        cJSON_DeleteItemFromObjectCaseSensitive(settings, it->string);
        cJSON_AddItemToObject(settings, it->string, cJSON_Duplicate(val, 1));
        char *txt = cJSON_PrintUnformatted(val);
        if (used < label_size)
            used += (size_t)snprintf(label + used, label_size - used, "%s%s", k ? "/" : " ", txt);
        if (wused < sizeof what)
            wused += (size_t)snprintf(what + wused, sizeof what - wused, " %s=%s", it->string, txt);
        free(txt);
    }
    const cJSON *ms = cJSON_GetObjectItemCaseSensitive(method, "settings");
    for (const cJSON *it = ms ? ms->child : NULL; it; it = it->next) {
        cJSON_DeleteItemFromObjectCaseSensitive(settings, it->string);
        cJSON_AddItemToObject(settings, it->string, cJSON_Duplicate(it, 1));
    }
    if (c->threads) {
        cJSON_DeleteItemFromObjectCaseSensitive(settings, "threads");
        cJSON_AddNumberToObject(settings, "threads", c->threads);
    }
    cJSON_DeleteItemFromObjectCaseSensitive(root, "capture");
    cJSON *cap = cJSON_AddArrayToObject(root, "capture");
    for (size_t i = 0; i < sizeof CAPTURED / sizeof CAPTURED[0]; i++)
        cJSON_AddItemToArray(cap, cJSON_CreateString(CAPTURED[i]));
    char *text = cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    eng_error perr = {{0}};
    eng_result r = seq_parse(c->sequence, text, strlen(text), out, &perr);
    free(text);
    if (r != ENG_OK)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: %s", c->path, what, perr.msg);
    return ENG_OK;
}

/* ---------------------------------------------------------------- rendering */

typedef struct grab {
    int w, h;
    float *indirect, *full, *position, *normal;
    int have_indirect, have_full, have_position, have_normal;
    eng_frame_stats stats;
    int have_stats;
} grab;

static int grab_begin(void *user, int frame, double time)
{
    (void)frame;
    (void)time;
    grab *g = user;
    g->have_indirect = g->have_full = g->have_stats = g->have_position = g->have_normal = 0;
    return 0;
}

static int grab_buffer(void *user, int frame, const eng_buffer *b)
{
    (void)frame;
    grab *g = user;
    float *dst = !strcmp(b->name, "indirect.radiance")    ? g->indirect
                 : !strcmp(b->name, "composite.radiance") ? g->full
                 : !strcmp(b->name, "gbuffer.position")   ? g->position
                 : !strcmp(b->name, "gbuffer.normal")     ? g->normal
                                                          : NULL;
    if (!dst)
        return 0;
    if (b->width != g->w || b->height != g->h || b->channel_count != 3)
        return 1;
    memcpy(dst, b->data, (size_t)g->w * (size_t)g->h * 3 * sizeof(float));
    if (dst == g->indirect)
        g->have_indirect = 1;
    else if (dst == g->full)
        g->have_full = 1;
    else if (dst == g->position)
        g->have_position = 1;
    else
        g->have_normal = 1;
    return 0;
}

static int grab_end(void *user, const eng_frame_stats *st)
{
    grab *g = user;
    g->stats = *st;
    g->have_stats = 1;
    return 0;
}

/* Pass names seen over all points, in first-seen order. */
typedef struct pass_names {
    int count;
    char name[ENG_MAX_PASSES][SCN_NAME_MAX];
} pass_names;

static int pass_slot(pass_names *p, const char *name)
{
    for (int i = 0; i < p->count; i++)
        if (!strcmp(p->name[i], name))
            return i;
    if (p->count == ENG_MAX_PASSES)
        return -1;
    snprintf(p->name[p->count], sizeof p->name[0], "%s", name);
    return p->count++;
}

static void bias_add(rep_metrics_bias *acc, const rep_metrics_bias *m, double weight)
{
    acc->mean_ratio += m->mean_ratio * weight;
    acc->block_p90 += m->block_p90 * weight;
    acc->edge_ratio += m->edge_ratio * weight;
    acc->edge_rel_rmse += m->edge_rel_rmse * weight;
    acc->flat_ratio += m->flat_ratio * weight;
    acc->flat_rel_rmse += m->flat_rel_rmse * weight;
    acc->edge_fraction += m->edge_fraction * weight;
}

static void metrics_add(rep_metrics_err *acc, const rep_metrics_err *m, double weight)
{
    acc->rmse += m->rmse * weight;
    acc->rel_mse += m->rel_mse * weight;
    acc->mae += m->mae * weight;
    acc->block_rmse += m->block_rmse * weight;
    if (m->max_abs > acc->max_abs)
        acc->max_abs = m->max_abs;
}

typedef struct reference_frames {
    float *indirect, *full; /* frame_count × w × h × 3 */
    /* How its pixels sample the scene: "centre" (ispm reference --pixel-center: the points the
     * engine's G-buffers shade), "box" (jittered over the pixel: at silhouettes a mix of the
     * surfaces a pixel covers), "unknown" (not made by ispm reference). */
    const char *pixel;
} reference_frames;

/* ref->pixel from the reference run's manifest (renderer.settings.pixel; runs of ispm reference
 * from before the key were box-filtered). */
static void reference_pixel(const char *dir, reference_frames *ref)
{
    ref->pixel = "unknown";
    char *path = rep_path_join(dir, "manifest.json"), *text = NULL;
    size_t len = 0;
    eng_error err;
    cJSON *root = NULL;
    if (eng_read_file(path, (size_t)64 << 20, &text, &len, &err) == ENG_OK &&
        (root = cJSON_ParseWithLength(text, len))) {
        const cJSON *rd = cJSON_GetObjectItemCaseSensitive(root, "renderer");
        const cJSON *name = cJSON_GetObjectItemCaseSensitive(rd, "name");
        const cJSON *px = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(rd, "settings"), "pixel");
        if (cJSON_IsString(px) && !strcmp(px->valuestring, "centre"))
            ref->pixel = "centre";
        else if (cJSON_IsString(name) && !strcmp(name->valuestring, "reference"))
            ref->pixel = "box";
    }
    cJSON_Delete(root);
    free(text);
    free(path);
}

/* Extracts R, G, B of part `name` of frame f into out (w × h × 3). */
static eng_result take_rgb(const rep_run *run, int f, const rep_part *parts, const char *name, float *out,
                           eng_error *err)
{
    int j = rep_frame_find(&run->frames[f], name);
    if (j < 0)
        return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d has no buffer %s (not a reference run?)", run->dir,
                        f, name);
    const rep_part *p = &parts[j];
    int ch[3] = {-1, -1, -1};
    static const char *const rgb[3] = {"R", "G", "B"};
    for (int c = 0; c < p->channel_count; c++)
        for (int k = 0; k < 3; k++)
            if (!strcmp(p->channels[c], rgb[k]))
                ch[k] = c;
    if (ch[0] < 0 || ch[1] < 0 || ch[2] < 0)
        return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d: %s has no R, G, B channels", run->dir, f, name);
    size_t n = (size_t)p->width * (size_t)p->height;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            out[3 * i + (size_t)k] = p->data[i * (size_t)p->channel_count + (size_t)ch[k]];
    return ENG_OK;
}

static eng_result load_reference(const bench_config *c, int w, int h, reference_frames *ref, eng_error *err)
{
    rep_run *run = NULL;
    eng_result r = rep_run_open(c->reference, &run, err);
    if (r != ENG_OK)
        return r;
    if (run->width != w || run->height != h) {
        r = eng_fail(err, ENG_ERR_INVALID, "%s: reference run is %dx%d, the sequence %s renders %dx%d", c->reference,
                     run->width, run->height, c->sequence, w, h);
        rep_run_close(run);
        return r;
    }
    size_t plane = (size_t)w * (size_t)h * 3;
    ref->indirect = rep_xmalloc(plane * (size_t)c->frame_count * sizeof(float));
    ref->full = rep_xmalloc(plane * (size_t)c->frame_count * sizeof(float));
    for (int i = 0; i < c->frame_count && r == ENG_OK; i++) {
        int f = c->reference_frame >= 0 ? c->reference_frame : c->frames[i];
        if (f >= run->frame_count) {
            r = eng_fail(err, ENG_ERR_INVALID, "%s: frame %d requested, the reference run has %d frames", c->path, f,
                         run->frame_count);
            break;
        }
        rep_part *parts = NULL;
        r = rep_run_read_frame(run, f, &parts, err);
        if (r != ENG_OK)
            break;
        r = take_rgb(run, f, parts, "reference.indirect", ref->indirect + plane * (size_t)i, err);
        if (r == ENG_OK)
            r = take_rgb(run, f, parts, "reference.full", ref->full + plane * (size_t)i, err);
        rep_parts_free(parts, run->frames[f].buffer_count);
    }
    rep_run_close(run);
    if (r == ENG_OK)
        reference_pixel(c->reference, ref);
    return r;
}

/* Renders one grid point: warm-up, then frames × repeats; metrics from the first repeat. */
static eng_result run_point(const bench_config *c, const scn_scene *scene, bench_point *p, pass_names *passes,
                            const reference_frames *ref, eng_error *err)
{
    const int w = p->seq->width, h = p->seq->height;
    const size_t plane = (size_t)w * (size_t)h * 3;
    grab g = {w,
              h,
              rep_xmalloc(plane * sizeof(float)),
              rep_xmalloc(plane * sizeof(float)),
              rep_xmalloc(plane * sizeof(float)),
              rep_xmalloc(plane * sizeof(float)),
              0,
              0,
              0,
              0,
              {0},
              0};
    /* The edge mask of rep_metric_bias, recomputed only when the G-buffer changes. */
    signed char *mask = rep_xmalloc((size_t)w * (size_t)h);
    float *mask_position = rep_xcalloc(plane, sizeof(float));
    int have_mask = 0;
    double elapsed = 0.0;

    eng_engine *eng = NULL;
    eng_desc d = {.scene = scene, .sequence = p->seq};
    eng_result r = eng_create(&d, &eng, err);
    if (r == ENG_OK) {
        eng_listener l = {&g, grab_begin, grab_buffer, grab_end};
        r = eng_add_listener(eng, &l);
    }
    for (int i = 0; i < c->warmup && r == ENG_OK; i++)
        r = eng_render_frame(eng, c->frames[0], err);
    p->sample_count = 0;
    p->pass_samples = rep_xcalloc((size_t)c->frame_count * (size_t)c->repeats * ENG_MAX_PASSES, sizeof(double));
    p->frame_samples = rep_xcalloc((size_t)c->frame_count * (size_t)c->repeats, sizeof(double));
    memset(&p->indirect, 0, sizeof p->indirect);
    memset(&p->full, 0, sizeof p->full);
    memset(&p->bias, 0, sizeof p->bias);
    for (int rep = 0; rep < c->repeats && r == ENG_OK; rep++)
        for (int i = 0; i < c->frame_count && r == ENG_OK; i++) {
            r = eng_render_frame(eng, c->frames[i], err);
            if (r != ENG_OK)
                break;
            if (!g.have_stats || !g.have_full) {
                r = eng_fail(err, ENG_ERR_INVALID, "%s: frame %d: the engine announced no composite.radiance",
                             p->seq->path, c->frames[i]);
                break;
            }
            double *slot = p->pass_samples + (size_t)p->sample_count * ENG_MAX_PASSES;
            double total = 0.0;
            for (int k = 0; k < g.stats.pass_count; k++) {
                int s = pass_slot(passes, g.stats.passes[k].name);
                if (s >= 0)
                    slot[s] += g.stats.passes[k].ms;
                /* The read-back for announcing serves the listeners, not the method. */
                if (strcmp(g.stats.passes[k].name, "readback"))
                    total += g.stats.passes[k].ms;
            }
            p->frame_samples[p->sample_count++] = total;
            if (rep > 0)
                continue;
            elapsed += total;
            if (!g.have_indirect) /* indirect "none": no indirect light at all */
                memset(g.indirect, 0, plane * sizeof(float));
            char what[160];
            rep_metrics_err mi, mf;
            snprintf(what, sizeof what, "%s: %s frame %d indirect.radiance", c->path, p->label, c->frames[i]);
            r = rep_metric_compute(g.indirect, ref->indirect + plane * (size_t)i, w, h, 3, what, &mi, err);
            if (r != ENG_OK)
                break;
            snprintf(what, sizeof what, "%s: %s frame %d composite.radiance", c->path, p->label, c->frames[i]);
            r = rep_metric_compute(g.full, ref->full + plane * (size_t)i, w, h, 3, what, &mf, err);
            if (r != ENG_OK)
                break;
            metrics_add(&p->indirect, &mi, 1.0 / c->frame_count);
            metrics_add(&p->full, &mf, 1.0 / c->frame_count);
            /* Bias near edges: within one kernel radius of a geometric edge (issue 13). */
            if (g.have_position && g.have_normal &&
                (!have_mask || memcmp(mask_position, g.position, plane * sizeof(float)))) {
                rep_edge_mask(g.position, g.normal, w, h, g.stats.camera_view_proj, g.stats.camera_eye,
                              p->seq->settings.kernel_radius, mask);
                memcpy(mask_position, g.position, plane * sizeof(float));
                have_mask = 1;
            }
            rep_metrics_bias mb;
            rep_metric_bias(g.indirect, ref->indirect + plane * (size_t)i, w, h, have_mask ? mask : NULL, &mb);
            bias_add(&p->bias, &mb, 1.0 / c->frame_count);
            for (int k = 0; k < c->report_count; k++)
                if (c->report_frames[k] == i) {
                    p->series_err[k] = mi;
                    p->series_bias[k] = mb;
                    p->series_ms[k] = elapsed;
                }
            if (i == 0) {
                p->first_indirect = rep_xmalloc(plane * sizeof(float));
                memcpy(p->first_indirect, g.indirect, plane * sizeof(float));
            }
        }
    eng_destroy(eng);
    free(g.indirect);
    free(g.full);
    free(g.position);
    free(g.normal);
    free(mask);
    free(mask_position);
    if (r != ENG_OK)
        return r;
    double *tmp = rep_xmalloc((size_t)p->sample_count * sizeof(double));
    for (int s = 0; s < passes->count; s++) {
        for (int k = 0; k < p->sample_count; k++)
            tmp[k] = p->pass_samples[(size_t)k * ENG_MAX_PASSES + (size_t)s];
        p->pass_ms[s] = rep_median(tmp, p->sample_count);
    }
    p->frame_ms = rep_median(p->frame_samples, p->sample_count);
    free(tmp);
    return ENG_OK;
}

/* ---------------------------------------------------------------- outputs */

static double chart_error(const bench_config *c, const bench_point *p)
{
    const rep_metrics_err *m = !strcmp(c->chart_buffer, "indirect") ? &p->indirect : &p->full;
    if (!strcmp(c->chart_metric, "rel_mse"))
        return m->rel_mse;
    if (!strcmp(c->chart_metric, "mae"))
        return m->mae;
    if (!strcmp(c->chart_metric, "max_abs"))
        return m->max_abs;
    if (!strcmp(c->chart_metric, "block_rmse"))
        return m->block_rmse;
    if (!strcmp(c->chart_metric, "block_p90")) /* issue 13's measure: indirect only (rep_metric_bias) */
        return p->bias.block_p90;
    return m->rmse;
}

/* Pareto front over all points: no other point is at least as fast and as accurate and
 * strictly better in one of the two. */
static void mark_pareto(const bench_config *c, bench_point *pts, int n)
{
    for (int i = 0; i < n; i++) {
        double ti = pts[i].frame_ms, ei = chart_error(c, &pts[i]);
        pts[i].pareto = 1;
        for (int j = 0; j < n && pts[i].pareto; j++) {
            double tj = pts[j].frame_ms, ej = chart_error(c, &pts[j]);
            if (j != i && tj <= ti && ej <= ei && (tj < ti || ej < ei))
                pts[i].pareto = 0;
        }
    }
}

/* Columns of settings: indirect, then grid keys, then keys methods fix, without repeats. */
typedef struct columns {
    int count;
    const char *key[BENCH_MAX_KEYS * 2 + 1];
} columns;

static void column_add(columns *cols, const char *key)
{
    for (int i = 0; i < cols->count; i++)
        if (!strcmp(cols->key[i], key))
            return;
    if (cols->count < (int)(sizeof cols->key / sizeof cols->key[0]))
        cols->key[cols->count++] = key;
}

static void metric_csv(rep_sb *sb, const rep_metrics_err *m)
{
    rep_sb_printf(sb, ",%.9g,%.9g,%.9g,%.9g,%.9g", m->rmse, m->rel_mse, m->mae, m->max_abs, m->block_rmse);
}

static void bias_csv(rep_sb *sb, const rep_metrics_bias *m)
{
    rep_sb_printf(sb, ",%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", m->mean_ratio, m->block_p90, m->edge_ratio,
                  m->edge_rel_rmse, m->flat_ratio, m->flat_rel_rmse, m->edge_fraction);
}

static cJSON *bias_json(const rep_metrics_bias *m)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "mean_ratio", m->mean_ratio);
    cJSON_AddNumberToObject(o, "block_p90", m->block_p90);
    cJSON_AddNumberToObject(o, "edge_ratio", m->edge_ratio);
    cJSON_AddNumberToObject(o, "edge_rel_rmse", m->edge_rel_rmse);
    cJSON_AddNumberToObject(o, "flat_ratio", m->flat_ratio);
    cJSON_AddNumberToObject(o, "flat_rel_rmse", m->flat_rel_rmse);
    cJSON_AddNumberToObject(o, "edge_fraction", m->edge_fraction);
    return o;
}

static char *make_csv(const bench_point *pts, int n, const columns *cols, const pass_names *passes)
{
    rep_sb sb = {0};
    rep_sb_printf(&sb, "point,method");
    for (int k = 0; k < cols->count; k++)
        rep_sb_printf(&sb, ",%s", cols->key[k]);
    for (int s = 0; s < passes->count; s++)
        rep_sb_printf(&sb, ",%s_ms", passes->name[s]);
    rep_sb_printf(&sb, ",frame_ms,samples");
    static const char *const which[2] = {"indirect", "full"};
    for (int b = 0; b < 2; b++)
        rep_sb_printf(&sb, ",%s_rmse,%s_rel_mse,%s_mae,%s_max_abs,%s_block_rmse", which[b], which[b], which[b],
                      which[b], which[b]);
    rep_sb_printf(&sb, ",indirect_mean_ratio,indirect_block_p90,indirect_edge_ratio,indirect_edge_rel_rmse,"
                       "indirect_flat_ratio,indirect_flat_rel_rmse,indirect_edge_fraction");
    rep_sb_printf(&sb, ",pareto\n");
    for (int i = 0; i < n; i++) {
        const bench_point *p = &pts[i];
        rep_sb_printf(&sb, "%d,%s", i, p->method_name);
        for (int k = 0; k < cols->count; k++) {
            char v[64] = "";
            setting_text(&p->seq->settings, cols->key[k], v, sizeof v);
            rep_sb_printf(&sb, ",%s", v);
        }
        for (int s = 0; s < passes->count; s++)
            rep_sb_printf(&sb, ",%.4f", p->pass_ms[s]);
        rep_sb_printf(&sb, ",%.4f,%d", p->frame_ms, p->sample_count);
        metric_csv(&sb, &p->indirect);
        metric_csv(&sb, &p->full);
        bias_csv(&sb, &p->bias);
        rep_sb_printf(&sb, ",%d\n", p->pareto);
    }
    return sb.s;
}

static cJSON *metric_json(const rep_metrics_err *m)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "rmse", m->rmse);
    cJSON_AddNumberToObject(o, "rel_mse", m->rel_mse);
    cJSON_AddNumberToObject(o, "mae", m->mae);
    cJSON_AddNumberToObject(o, "max_abs", m->max_abs);
    cJSON_AddNumberToObject(o, "block_rmse", m->block_rmse);
    return o;
}

typedef struct pair_stats {
    int scatter, gather;     /* point indices, −1 when the grid has no such pair */
    double max_abs, max_rel; /* max_rel over values above 1e-3 of the scatter's peak */
} pair_stats;

/* A method's speed against the k-d gather at the same settings (issue 12: "speedup vs
 * kd-gather"), and how far its first frame's indirect light is from the k-d gather's. */
typedef struct speedup {
    int point, baseline;
    double frame, pass;           /* kd-gather ms / method ms */
    double pass_ms, base_pass_ms; /* the indirect pass of each */
    double max_abs, max_rel;      /* first frame's indirect.radiance, max_rel as pair_stats */
} speedup;

/* The pass an indirect method's time is reported under (engine/indirect.h). */
static const char *indirect_pass(eng_indirect m)
{
    switch (m) {
    case ENG_INDIRECT_QUADS: return "quads";
    case ENG_INDIRECT_TILEGATHER:
    case ENG_INDIRECT_TILEGATHER_GL:
    case ENG_INDIRECT_KDGATHER: return "gather";
    case ENG_INDIRECT_FINALGATHER: return "final_gather";
    case ENG_INDIRECT_NONE: return NULL;
    case ENG_INDIRECT_ISPM:
    case ENG_INDIRECT_DEFAULT: break;
    }
    return "splat";
}

static int same_but_indirect(const bench_point *a, const bench_point *b);

static double pass_of(const bench_point *p, const pass_names *passes, const char *name)
{
    for (int s = 0; name && s < passes->count; s++)
        if (!strcmp(passes->name[s], name))
            return p->pass_ms[s];
    return 0.0;
}

/* Every non-k-d-gather point paired with the k-d gather point of the same other settings;
 * returns how many (out has room for n). */
static int find_speedups(const bench_point *pts, int n, const pass_names *passes, speedup *out)
{
    int count = 0;
    for (int i = 0; i < n; i++) {
        eng_indirect mi = pts[i].seq->settings.indirect;
        if (mi == ENG_INDIRECT_KDGATHER || mi == ENG_INDIRECT_NONE)
            continue;
        for (int j = 0; j < n; j++) {
            if (pts[j].seq->settings.indirect != ENG_INDIRECT_KDGATHER || !same_but_indirect(&pts[i], &pts[j]))
                continue;
            speedup *u = &out[count++];
            u->point = i;
            u->baseline = j;
            u->frame = pts[i].frame_ms > 0.0 ? pts[j].frame_ms / pts[i].frame_ms : 0.0;
            u->pass_ms = pass_of(&pts[i], passes, indirect_pass(mi));
            u->base_pass_ms = pass_of(&pts[j], passes, "gather");
            u->pass = u->pass_ms > 0.0 ? u->base_pass_ms / u->pass_ms : 0.0;
            u->max_abs = u->max_rel = 0.0;
            const size_t plane = (size_t)pts[i].seq->width * (size_t)pts[i].seq->height * 3;
            const float *a = pts[j].first_indirect, *b = pts[i].first_indirect;
            double peak = 0.0;
            for (size_t k = 0; a && b && k < plane; k++)
                peak = fmax(peak, fabs(a[k]));
            for (size_t k = 0; a && b && k < plane; k++) {
                double d = fabs((double)b[k] - (double)a[k]);
                u->max_abs = fmax(u->max_abs, d);
                if (fabs(a[k]) > 1e-3 * peak)
                    u->max_rel = fmax(u->max_rel, d / fabs(a[k]));
            }
            break;
        }
    }
    return count;
}

static char *make_json(const bench_config *c, const char *command_line, const bench_point *pts, int n,
                       const columns *cols, const pass_names *passes, const pair_stats *pair, const speedup *ups,
                       int nups, const char *reference_pixel)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "format", "ispm-bench");
    cJSON_AddNumberToObject(root, "version", 1);
    cJSON_AddStringToObject(root, "command_line", command_line);
    cJSON_AddStringToObject(root, "config", c->path);
    cJSON_AddStringToObject(root, "sequence", c->sequence);
    cJSON_AddStringToObject(root, "reference", c->reference);
    cJSON_AddStringToObject(root, "reference_pixel", reference_pixel);
    cJSON_AddItemToObject(root, "frames", cJSON_CreateIntArray(c->frames, c->frame_count));
    cJSON_AddNumberToObject(root, "repeats", c->repeats);
    cJSON_AddNumberToObject(root, "warmup", c->warmup);
    cJSON_AddNumberToObject(root, "metric_epsilon", REP_METRIC_EPSILON);
    cJSON_AddNumberToObject(root, "reference_frame", c->reference_frame);
    cJSON *chart = cJSON_AddObjectToObject(root, "chart");
    cJSON_AddStringToObject(chart, "metric", c->chart_metric);
    cJSON_AddStringToObject(chart, "buffer", c->chart_buffer);
    cJSON *pl = cJSON_AddArrayToObject(root, "passes");
    for (int s = 0; s < passes->count; s++)
        cJSON_AddItemToArray(pl, cJSON_CreateString(passes->name[s]));
    cJSON *arr = cJSON_AddArrayToObject(root, "points");
    for (int i = 0; i < n; i++) {
        const bench_point *p = &pts[i];
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "point", i);
        cJSON_AddStringToObject(o, "method", p->method_name);
        cJSON_AddStringToObject(o, "label", p->label);
        cJSON *st = cJSON_AddObjectToObject(o, "settings");
        for (int k = 0; k < cols->count; k++) {
            char v[64] = "";
            setting_text(&p->seq->settings, cols->key[k], v, sizeof v);
            cJSON_AddStringToObject(st, cols->key[k], v);
        }
        cJSON *pm = cJSON_AddObjectToObject(o, "pass_ms");
        for (int s = 0; s < passes->count; s++)
            cJSON_AddNumberToObject(pm, passes->name[s], p->pass_ms[s]);
        cJSON_AddNumberToObject(o, "frame_ms", p->frame_ms);
        cJSON_AddNumberToObject(o, "samples", p->sample_count);
        cJSON_AddItemToObject(o, "indirect", metric_json(&p->indirect));
        cJSON_AddItemToObject(o, "full", metric_json(&p->full));
        cJSON_AddItemToObject(o, "indirect_bias", bias_json(&p->bias));
        if (c->report_count) {
            cJSON *ser = cJSON_AddArrayToObject(o, "series");
            for (int k = 0; k < c->report_count; k++) {
                cJSON *e = cJSON_CreateObject();
                cJSON_AddNumberToObject(e, "frame", c->frames[c->report_frames[k]]);
                cJSON_AddNumberToObject(e, "frames_rendered", c->report_frames[k] + 1);
                cJSON_AddNumberToObject(e, "elapsed_ms", p->series_ms[k]);
                cJSON_AddItemToObject(e, "indirect", metric_json(&p->series_err[k]));
                cJSON_AddItemToObject(e, "indirect_bias", bias_json(&p->series_bias[k]));
                cJSON_AddItemToArray(ser, e);
            }
        }
        cJSON_AddBoolToObject(o, "pareto", p->pareto);
        cJSON_AddItemToArray(arr, o);
    }
    cJSON *sg = cJSON_AddObjectToObject(root, "scatter_vs_gather");
    if (pair->scatter >= 0) {
        cJSON_AddNumberToObject(sg, "scatter_point", pair->scatter);
        cJSON_AddNumberToObject(sg, "gather_point", pair->gather);
        cJSON_AddNumberToObject(sg, "max_abs", pair->max_abs);
        cJSON_AddNumberToObject(sg, "max_rel", pair->max_rel);
    }
    cJSON *su = cJSON_AddArrayToObject(root, "speedup_vs_kd_gather");
    for (int k = 0; k < nups; k++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "point", ups[k].point);
        cJSON_AddNumberToObject(o, "kd_gather_point", ups[k].baseline);
        cJSON_AddStringToObject(o, "label", pts[ups[k].point].label);
        cJSON_AddNumberToObject(o, "frame_speedup", ups[k].frame);
        cJSON_AddNumberToObject(o, "pass_speedup", ups[k].pass);
        cJSON_AddNumberToObject(o, "pass_ms", ups[k].pass_ms);
        cJSON_AddNumberToObject(o, "kd_gather_pass_ms", ups[k].base_pass_ms);
        cJSON_AddNumberToObject(o, "max_abs", ups[k].max_abs);
        cJSON_AddNumberToObject(o, "max_rel", ups[k].max_rel);
        cJSON_AddItemToArray(su, o);
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    size_t len = strlen(text);
    char *withnl = rep_xmalloc(len + 2);
    memcpy(withnl, text, len);
    withnl[len] = '\n';
    withnl[len + 1] = 0;
    free(text);
    return withnl;
}

/* Points i (scatter) and j (gather) with every other setting equal. */
static int same_but_indirect(const bench_point *a, const bench_point *b)
{
    int count = 0;
    const eng_setting *table = eng_settings_table(&count);
    for (int i = 0; i < count; i++) {
        const char *k = table[i].key;
        if (!strcmp(k, "indirect") || !strcmp(k, "threads"))
            continue;
        char va[64], vb[64];
        setting_text(&a->seq->settings, k, va, sizeof va);
        setting_text(&b->seq->settings, k, vb, sizeof vb);
        if (strcmp(va, vb))
            return 0;
    }
    return 1;
}

/* Writes OUTDIR/compare_scatter_vs_gather.png (scatter | gather | |difference| heat map |
 * reference, radiance thumbnails on a shared scale) and .exr (the float images), for the first
 * scatter/gather pair of the grid. */
static eng_result write_comparison(const char *outdir, const bench_point *pts, int n, const float *ref_indirect,
                                   pair_stats *pair, eng_error *err)
{
    pair->scatter = pair->gather = -1;
    pair->max_abs = pair->max_rel = 0.0;
    for (int i = 0; i < n && pair->scatter < 0; i++)
        for (int j = 0; j < n && pair->scatter < 0; j++)
            if (pts[i].seq->settings.indirect == ENG_INDIRECT_ISPM &&
                pts[j].seq->settings.indirect == ENG_INDIRECT_KDGATHER && same_but_indirect(&pts[i], &pts[j])) {
                pair->scatter = i;
                pair->gather = j;
            }
    if (pair->scatter < 0)
        return ENG_OK;
    const bench_point *a = &pts[pair->scatter], *b = &pts[pair->gather];
    const int w = a->seq->width, h = a->seq->height;
    const size_t plane = (size_t)w * (size_t)h * 3;
    float *diff = rep_xmalloc(plane * sizeof(float));
    double peak = 0.0;
    for (size_t i = 0; i < plane; i++)
        peak = fmax(peak, fabs(a->first_indirect[i]));
    for (size_t i = 0; i < plane; i++) {
        double sa = a->first_indirect[i], gb = b->first_indirect[i];
        diff[i] = (float)(gb - sa);
        pair->max_abs = fmax(pair->max_abs, fabs(gb - sa));
        if (fabs(sa) > 1e-3 * peak)
            pair->max_rel = fmax(pair->max_rel, fabs(gb - sa) / fabs(sa));
    }
    static const char *const RGB[3] = {"R", "G", "B"};
    eng_buffer parts[4] = {
        {"scatter.indirect", w, h, 3, RGB, a->first_indirect},
        {"gather.indirect", w, h, 3, RGB, b->first_indirect},
        {"difference.indirect", w, h, 3, RGB, diff},
        {"reference.indirect", w, h, 3, RGB, ref_indirect},
    };
    char *path = rep_xprintf("%s/compare_scatter_vs_gather.exr", outdir);
    char *tmp = rep_xprintf("%s/compare_scatter_vs_gather.tmp.exr", outdir);
    eng_result r = rep_oiio_write_parts(tmp, parts, 4, err);
    if (r == ENG_OK && rename(tmp, path) != 0)
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot rename into place", path);
    if (r != ENG_OK)
        unlink(tmp);
    free(path);
    free(tmp);
    if (r == ENG_OK) {
        /* One radiance map for all three radiance panels, so brightness compares. */
        rep_thumb_map m;
        rep_thumb_map_make("indirect.radiance", &parts[0], &parts[3], &m);
        int tw = 0, th = 0, dw = 0, dh = 0;
        double scale = 0.0;
        unsigned char *panel[4] = {rep_thumb_render(&parts[0], &m, &tw, &th), rep_thumb_render(&parts[1], &m, &tw, &th),
                                   rep_thumb_diff(&parts[1], &parts[0], &scale, &dw, &dh),
                                   rep_thumb_render(&parts[3], &m, &tw, &th)};
        const int gap = 4, W = 4 * tw + 3 * gap;
        unsigned char *img = rep_xcalloc((size_t)W * (size_t)th * 3, 1);
        for (int k = 0; k < 4; k++)
            for (int y = 0; y < th && panel[k]; y++)
                memcpy(img + ((size_t)y * W + (size_t)k * (tw + gap)) * 3, panel[k] + (size_t)y * tw * 3,
                       (size_t)tw * 3);
        path = rep_xprintf("%s/compare_scatter_vs_gather.png", outdir);
        tmp = rep_xprintf("%s/compare_scatter_vs_gather.png.tmp", outdir);
        r = rep_oiio_write_png(tmp, W, th, 3, img, err);
        if (r == ENG_OK && rename(tmp, path) != 0)
            r = eng_fail(err, ENG_ERR_IO, "%s: cannot rename into place", path);
        if (r != ENG_OK)
            unlink(tmp);
        free(path);
        free(tmp);
        free(img);
        for (int k = 0; k < 4; k++)
            free(panel[k]);
    }
    free(diff);
    return r;
}

/* With report_frames: the indirect error of every point against the frames rendered and
 * against the time spent (first repeat), one series per point (at most PLOT_MAX_SERIES). */
static eng_result write_convergence(const bench_config *c, const char *outdir, const bench_point *pts, int n,
                                    eng_error *err)
{
    if (!c->report_count)
        return ENG_OK;
    static const char *const what[3] = {"block_p90", "rmse", "block_p90"};
    static const char *const file[3] = {"convergence_frames", "convergence_rmse_frames", "convergence_time"};
    int np = n < PLOT_MAX_SERIES ? n : PLOT_MAX_SERIES;
    double *xs = rep_xcalloc((size_t)np * BENCH_MAX_SERIES, sizeof(double));
    double *ys = rep_xcalloc((size_t)np * BENCH_MAX_SERIES, sizeof(double));
    eng_result r = ENG_OK;
    for (int k = 0; k < 3 && r == ENG_OK; k++) {
        plot_chart ch;
        memset(&ch, 0, sizeof ch);
        char title[256], ylabel[128];
        snprintf(title, sizeof title, "Convergence: %.200s", n > 0 ? pts[0].seq->name : "");
        snprintf(ylabel, sizeof ylabel, "indirect %s vs reference", what[k]);
        ch.title = title;
        ch.x_label = k == 2 ? "time spent (ms, sum of frame times)" : "frames rendered";
        ch.y_label = ylabel;
        ch.log_x = ch.log_y = 1;
        for (int i = 0; i < np; i++) {
            plot_series *se = &ch.series[ch.series_count++];
            double *x = xs + (size_t)i * BENCH_MAX_SERIES, *y = ys + (size_t)i * BENCH_MAX_SERIES;
            for (int j = 0; j < c->report_count; j++) {
                x[j] = k == 2 ? pts[i].series_ms[j] : c->report_frames[j] + 1;
                y[j] = k == 1 ? pts[i].series_err[j].rmse : pts[i].series_bias[j].block_p90;
            }
            se->label = pts[i].label;
            se->x = x;
            se->y = y;
            se->count = c->report_count;
            se->style = PLOT_LINES_POINTS;
        }
        char *path = rep_xprintf("%s/%s.png", outdir, file[k]);
        r = plot_xy(path, &ch, err);
        free(path);
    }
    free(xs);
    free(ys);
    return r;
}

static eng_result write_charts(const bench_config *c, const char *outdir, const bench_point *pts, int n,
                               const pass_names *passes, eng_error *err)
{
    plot_chart ch;
    memset(&ch, 0, sizeof ch);
    char title[256], ylabel[128];
    snprintf(title, sizeof title, "Error vs frame time: %.200s", n > 0 ? pts[0].seq->name : "");
    snprintf(ylabel, sizeof ylabel, "%s of %s radiance vs reference", c->chart_metric, c->chart_buffer);
    ch.title = title;
    ch.x_label = "frame time (ms, median)";
    ch.y_label = ylabel;
    ch.log_x = ch.log_y = 1;
    double *xs = rep_xcalloc((size_t)n * 2, sizeof(double)), *ys = rep_xcalloc((size_t)n * 2, sizeof(double));
    int *marked = rep_xcalloc((size_t)n, sizeof(int));
    int at = 0;
    for (int m = 0; m < c->method_count; m++) {
        plot_series *s = &ch.series[ch.series_count];
        int start = at;
        for (int i = 0; i < n; i++)
            if (pts[i].method == m) {
                xs[at] = pts[i].frame_ms;
                ys[at] = chart_error(c, &pts[i]);
                marked[at] = pts[i].pareto;
                at++;
            }
        if (at == start)
            continue;
        s->label = c->method_count > 0 ? pts[0].method_name : "";
        for (int i = 0; i < n; i++)
            if (pts[i].method == m) {
                s->label = pts[i].method_name;
                break;
            }
        s->x = xs + start;
        s->y = ys + start;
        s->marked = marked + start;
        s->count = at - start;
        s->style = PLOT_POINTS;
        ch.series_count++;
    }
    /* The front as a line, by increasing time. */
    int front = 0;
    double *fx = xs + n, *fy = ys + n;
    for (int i = 0; i < n; i++)
        if (pts[i].pareto) {
            int k = front++;
            while (k > 0 && fx[k - 1] > pts[i].frame_ms) {
                fx[k] = fx[k - 1];
                fy[k] = fy[k - 1];
                k--;
            }
            fx[k] = pts[i].frame_ms;
            fy[k] = chart_error(c, &pts[i]);
        }
    if (front > 1) {
        plot_series *s = &ch.series[ch.series_count++];
        s->label = "Pareto front";
        s->x = fx;
        s->y = fy;
        s->count = front;
        s->style = PLOT_LINES;
    }
    char *p1 = rep_xprintf("%s/error_vs_time.png", outdir), *p2 = rep_xprintf("%s/error_vs_time.svg", outdir);
    eng_result r = plot_xy(p1, &ch, err);
    if (r == ENG_OK)
        r = plot_xy(p2, &ch, err);
    free(p1);
    free(p2);
    free(xs);
    free(ys);
    free(marked);
    if (r != ENG_OK)
        return r;

    /* The bars add up to frame_ms: the read-back for the listeners is left out. */
    const char **labels = rep_xcalloc((size_t)n, sizeof *labels);
    const char *series[ENG_MAX_PASSES];
    double *values = rep_xcalloc((size_t)passes->count * (size_t)n, sizeof(double));
    int ns = 0;
    for (int i = 0; i < n; i++)
        labels[i] = pts[i].label;
    for (int s = 0; s < passes->count; s++) {
        if (!strcmp(passes->name[s], "readback"))
            continue;
        series[ns] = passes->name[s];
        for (int i = 0; i < n; i++)
            values[(size_t)ns * n + (size_t)i] = pts[i].pass_ms[s];
        ns++;
    }
    char *p3 = rep_xprintf("%s/pass_times.png", outdir);
    r = plot_stacked_bars(p3, "Per-pass time (median; frame_ms = the stack)", "ms", n, labels, ns, series, values,
                          err);
    free(p3);
    free(labels);
    free(values);
    return r;
}

/* ---------------------------------------------------------------- the command */

/* The bias measures of a point on stderr (beside the per-point line). */
static void print_bias(const bench_config *c, const bench_point *p)
{
    const rep_metrics_bias *b = &p->bias;
    fprintf(stderr, "        indirect mean ratio %.4f  block p90 %.4f  edges (%.0f%% of pixels): ratio %.4f rel rmse %.4f"
                    "  elsewhere: ratio %.4f rel rmse %.4f\n",
            b->mean_ratio, b->block_p90, 100.0 * b->edge_fraction, b->edge_ratio, b->edge_rel_rmse, b->flat_ratio,
            b->flat_rel_rmse);
    for (int k = 0; k < c->report_count; k++)
        fprintf(stderr, "        frame %3d (%3d rendered, %9.1f ms): rmse %.4g  mean ratio %.4f  block p90 %.4f  edge ratio %.4f\n",
                c->frames[c->report_frames[k]], c->report_frames[k] + 1, p->series_ms[k], p->series_err[k].rmse,
                p->series_bias[k].mean_ratio, p->series_bias[k].block_p90, p->series_bias[k].edge_ratio);
}

int cmd_bench(int argc, char **argv, const char *command_line)
{
    static const struct option opts[] = {
        {"output", required_argument, NULL, 'o'}, {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'}, {"check", no_argument, NULL, 'c'}, {NULL, 0, NULL, 0},
    };
    const char *outdir = NULL;
    int quiet = 0, check = 0, opt;
    while ((opt = getopt_long(argc, argv, "o:qh", opts, NULL)) != -1) {
        switch (opt) {
        case 'o': outdir = optarg; break;
        case 'q': quiet = 1; break;
        case 'c': check = 1; break;
        case 'h': usage(stdout); return B_OK;
        default: usage(stderr); return B_INPUT;
        }
    }
    if (optind + 1 != argc || (!outdir && !check)) {
        usage(stderr);
        return B_INPUT;
    }
    eng_error err = {{0}};
    bench_config c;
    int rc = B_OK;
    bench_point *pts = NULL;
    int n = 0;
    char *seq_text = NULL;
    cJSON *seq_root = NULL;
    scn_scene *scene = NULL;
    reference_frames ref = {NULL, NULL, "unknown"};
    pass_names passes = {0};
    char *old_json = NULL, *old_csv = NULL;
    eng_result r = config_load(argv[optind], &c, &err);
    /* The sequence file as JSON, to derive each point's sequence from. */
    size_t len = 0;
    if (r == ENG_OK)
        r = eng_read_file(c.sequence, (size_t)16 << 20, &seq_text, &len, &err);
    if (r == ENG_OK && !(seq_root = cJSON_ParseWithLength(seq_text, len)))
        r = eng_fail(&err, ENG_ERR_PARSE, "%s: not valid JSON", c.sequence);
    /* Every grid point's settings validated before anything is rendered. */
    int choice[BENCH_MAX_KEYS] = {0}, sizes[BENCH_MAX_KEYS] = {0}, total = 1;
    if (r == ENG_OK) {
        int k = 0;
        for (const cJSON *it = c.grid ? c.grid->child : NULL; it; it = it->next, k++) {
            sizes[k] = cJSON_GetArraySize(it);
            total *= sizes[k];
            if (total * c.method_count > BENCH_MAX_POINTS) {
                r = eng_fail(&err, ENG_ERR_INVALID, "%s: more than %d grid points", c.path, BENCH_MAX_POINTS);
                break;
            }
        }
    }
    if (r == ENG_OK) {
        pts = rep_xcalloc((size_t)total * (size_t)c.method_count, sizeof *pts);
        int mi = 0;
        for (const cJSON *m = c.methods->child; m && r == ENG_OK; m = m->next, mi++) {
            memset(choice, 0, sizeof choice);
            for (int t = 0; t < total && r == ENG_OK; t++) {
                bench_point *p = &pts[n++];
                p->method = mi;
                p->method_name = cJSON_GetObjectItemCaseSensitive(m, "name")->valuestring;
                p->seq = rep_xcalloc(1, sizeof *p->seq);
                r = point_sequence(&c, seq_root, m, choice, p->seq, p->label, sizeof p->label, &err);
                for (int k = c.grid_key_count - 1; k >= 0; k--) { /* odometer, last key fastest */
                    if (++choice[k] < sizes[k])
                        break;
                    choice[k] = 0;
                }
            }
        }
    }
    if (r == ENG_OK)
        for (int i = 0; i < c.frame_count && r == ENG_OK; i++)
            if (c.frames[i] >= pts[0].seq->frame_count)
                r = eng_fail(&err, ENG_ERR_INVALID, "%s: frame %d requested, the sequence %s has %d frames", c.path,
                             c.frames[i], c.sequence, pts[0].seq->frame_count);
    if (r == ENG_OK && check) { /* everything but the reference run and the rendering */
        r = seq_load_scene(pts[0].seq, &scene, &err);
        if (r == ENG_OK)
            printf("ispm bench: %s: %d points (%d methods) valid\n", c.path, n, c.method_count);
        else
            fprintf(stderr, "ispm bench: %s\n", err.msg);
        rc = r == ENG_OK ? B_OK : B_INPUT;
        goto done;
    }
    if (r == ENG_OK && (r = load_reference(&c, pts[0].seq->width, pts[0].seq->height, &ref, &err)) != ENG_OK) {
        eng_error inner = err;
        eng_fail(&err, r, "%s: reference: %s", c.path, inner.msg);
    }
    if (r == ENG_OK && !strcmp(ref.pixel, "box"))
        fprintf(stderr, "ispm bench: note: %s is box-filtered: at silhouettes its pixels mix surfaces where the "
                        "engine shades the pixel centre (ispm reference --pixel-center)\n",
                c.reference);
    if (r == ENG_OK)
        r = seq_load_scene(pts[0].seq, &scene, &err);
    if (r != ENG_OK) { /* the config, sequence, scene or reference */
        fprintf(stderr, "ispm bench: %s\n", err.msg);
        rc = B_INPUT;
        goto done;
    }
    if ((r = rep_mkdirs(outdir, &err)) != ENG_OK) {
        fprintf(stderr, "ispm bench: %s\n", err.msg);
        rc = B_RUNTIME;
        goto done;
    }
    /* An old result must not pass for this one while it runs or if it fails. */
    old_json = rep_path_join(outdir, "bench.json");
    old_csv = rep_path_join(outdir, "bench.csv");
    unlink(old_json);
    unlink(old_csv);
    if (!quiet)
        fprintf(stderr, "ispm bench: %d points (%d methods), frames %d..., %d repeats, %dx%d\n", n, c.method_count,
                c.frames[0], c.repeats, pts[0].seq->width, pts[0].seq->height);
    rep_progress prog;
    rep_progress_begin(&prog, quiet ? NULL : stderr, "ispm bench", "point", n);
    prog.tty = 0; /* the per-point bias lines follow each step: plain lines */
    for (int i = 0; i < n && r == ENG_OK; i++) {
        r = run_point(&c, scene, &pts[i], &passes, &ref, &err);
        if (r == ENG_OK && !quiet) {
            char detail[256];
            snprintf(detail, sizeof detail, "%-32s frame %8.2f ms  indirect rmse %.4g  full rmse %.4g", pts[i].label,
                     pts[i].frame_ms, pts[i].indirect.rmse, pts[i].full.rmse);
            rep_progress_step(&prog, i + 1, detail);
        }
        if (r == ENG_OK && !quiet)
            print_bias(&c, &pts[i]);
    }
    if (r == ENG_OK) {
        mark_pareto(&c, pts, n);
        columns cols = {0};
        column_add(&cols, "indirect");
        for (const cJSON *it = c.grid ? c.grid->child : NULL; it; it = it->next)
            column_add(&cols, it->string);
        for (const cJSON *m = c.methods->child; m; m = m->next) {
            const cJSON *s = cJSON_GetObjectItemCaseSensitive(m, "settings");
            for (const cJSON *it = s ? s->child : NULL; it; it = it->next)
                column_add(&cols, it->string);
        }
        pair_stats pair;
        speedup *ups = rep_xcalloc((size_t)n, sizeof *ups);
        int nups = find_speedups(pts, n, &passes, ups);
        r = write_comparison(outdir, pts, n, ref.indirect, &pair, &err);
        if (r == ENG_OK)
            r = write_charts(&c, outdir, pts, n, &passes, &err);
        if (r == ENG_OK)
            r = write_convergence(&c, outdir, pts, n, &err);
        if (r == ENG_OK) {
            char *csv = make_csv(pts, n, &cols, &passes);
            r = rep_write_atomic(old_csv, csv, strlen(csv), &err);
            free(csv);
        }
        if (r == ENG_OK) {
            char *json = make_json(&c, command_line, pts, n, &cols, &passes, &pair, ups, nups, ref.pixel);
            r = rep_write_atomic(old_json, json, strlen(json), &err);
            free(json);
        }
        if (r == ENG_OK && !quiet && pair.scatter >= 0)
            fprintf(stderr, "ispm bench: scatter (point %d) vs k-d gather (point %d): max |diff| %.3g, max relative %.3g\n",
                    pair.scatter, pair.gather, pair.max_abs, pair.max_rel);
        /* Ratios measured side by side in this run: the k-d gather's time over the method's. */
        for (int k = 0; r == ENG_OK && k < nups; k++) {
            const speedup *u = &ups[k];
            const char *label = pts[u->point].label;
            const char *sp = strchr(label, ' ');
            printf("speedup vs kd-gather: %.*s %s %.1fx frame (%.1f vs %.1f ms), %.1fx pass (%.1f vs %.1f ms), "
                   "max relative difference %.2g\n",
                   sp ? (int)(sp - label) : (int)strlen(label), label, sp ? sp + 1 : "", u->frame, pts[u->point].frame_ms,
                   pts[u->baseline].frame_ms, u->pass, u->pass_ms, u->base_pass_ms, u->max_rel);
        }
        free(ups);
    }
    if (r != ENG_OK) {
        fprintf(stderr, "ispm bench: %s\n", err.msg);
        unlink(old_csv);
        rc = r == ENG_ERR_INVALID || r == ENG_ERR_UNSUPPORTED ? B_INPUT : B_RUNTIME;
    } else {
        printf("bench: %s\n", old_csv);
    }
done:
    free(old_json);
    free(old_csv);
    for (int i = 0; i < n; i++) {
        free(pts[i].seq);
        free(pts[i].pass_samples);
        free(pts[i].frame_samples);
        free(pts[i].first_indirect);
    }
    free(pts);
    free(ref.indirect);
    free(ref.full);
    scn_destroy(scene);
    cJSON_Delete(seq_root);
    free(seq_text);
    cJSON_Delete(c.root);
    return rc;
}
