/* bench_run.c — makes the points of an `ispm bench` config and renders them. Each point is the
 * config's sequence file with the point's settings, parsed by seq_parse so the engine checks
 * them exactly as in a sequence file; it is rendered in this process (eng_create, a listener
 * that grabs indirect.radiance, composite.radiance and the G-buffer's position and normal),
 * and the per-pass times of eng_frame_stats give the medians over frames × repeats. The
 * radiance buffers are measured against the reference run's reference.indirect and
 * reference.full (replay/compare/metrics.h), and the indirect light's bias near geometric edges
 * against the same reference. It owns the points' sequences, samples and first-frame images
 * (bench_points_free) and the reference frames (bench_reference_free). */
#include "bench_run.h"
#include "rep.h"
#include "rep_run.h"
#include "rep_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const CAPTURED[] = {"indirect.radiance", "composite.radiance", "gbuffer.position",
                                       "gbuffer.normal"};
#define BENCH_MAX_SERIES 16 /* report_frames */

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

eng_result bench_points_make(const bench_config *c, bench_point **out, int *out_n, eng_error *err)
{
    *out = NULL;
    *out_n = 0;
    bench_point *pts = NULL;
    int n = 0;
    char *seq_text = NULL;
    cJSON *seq_root = NULL;
    /* The sequence file as JSON, to derive each point's sequence from. */
    size_t len = 0;
    eng_result r = eng_read_file(c->sequence, (size_t)16 << 20, &seq_text, &len, err);
    if (r == ENG_OK)
        r = eng_json_precheck(c->sequence, seq_text, len, ENG_JSON_MAX_DEPTH, err);
    if (r == ENG_OK && !(seq_root = cJSON_ParseWithLength(seq_text, len)))
        r = eng_fail(err, ENG_ERR_PARSE, "%s: not valid JSON", c->sequence);
    /* Every grid point's settings validated before anything is rendered. */
    int choice[BENCH_MAX_KEYS] = {0}, sizes[BENCH_MAX_KEYS] = {0}, total = 1;
    if (r == ENG_OK) {
        int k = 0;
        for (const cJSON *it = c->grid ? c->grid->child : NULL; it; it = it->next, k++) {
            sizes[k] = cJSON_GetArraySize(it);
            total *= sizes[k];
            if (total * c->method_count > BENCH_MAX_POINTS) {
                r = eng_fail(err, ENG_ERR_INVALID, "%s: more than %d grid points", c->path, BENCH_MAX_POINTS);
                break;
            }
        }
    }
    if (r == ENG_OK) {
        pts = rep_xcalloc((size_t)total * (size_t)c->method_count, sizeof *pts);
        int mi = 0;
        for (const cJSON *m = c->methods->child; m && r == ENG_OK; m = m->next, mi++) {
            memset(choice, 0, sizeof choice);
            for (int t = 0; t < total && r == ENG_OK; t++) {
                bench_point *p = &pts[n++];
                p->method = mi;
                p->method_name = cJSON_GetObjectItemCaseSensitive(m, "name")->valuestring;
                p->seq = rep_xcalloc(1, sizeof *p->seq);
                r = point_sequence(c, seq_root, m, choice, p->seq, p->label, sizeof p->label, err);
                for (int k = c->grid_key_count - 1; k >= 0; k--) { /* odometer, last key fastest */
                    if (++choice[k] < sizes[k])
                        break;
                    choice[k] = 0;
                }
            }
        }
    }
    if (r == ENG_OK)
        for (int i = 0; i < c->frame_count && r == ENG_OK; i++)
            if (c->frames[i] >= pts[0].seq->frame_count)
                r = eng_fail(err, ENG_ERR_INVALID, "%s: frame %d requested, the sequence %s has %d frames", c->path,
                             c->frames[i], c->sequence, pts[0].seq->frame_count);
    cJSON_Delete(seq_root);
    free(seq_text);
    if (r != ENG_OK) {
        bench_points_free(pts, n);
        return r;
    }
    *out = pts;
    *out_n = n;
    return ENG_OK;
}

void bench_points_free(bench_point *pts, int n)
{
    for (int i = 0; pts && i < n; i++) {
        free(pts[i].seq);
        free(pts[i].pass_samples);
        free(pts[i].frame_samples);
        free(pts[i].first_indirect);
    }
    free(pts);
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

static int pass_slot(bench_passes *p, const char *name)
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
    acc->flat_block_p90 += m->flat_block_p90 * weight;
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

/* ref->pixel from the reference run's manifest (renderer.settings.pixel; runs of ispm reference
 * from before the key were box-filtered). */
static void reference_pixel(const char *dir, bench_reference *ref)
{
    ref->pixel = "unknown";
    char *path = rep_path_join(dir, "manifest.json"), *text = NULL;
    size_t len = 0;
    eng_error err;
    cJSON *root = NULL;
    if (eng_read_input(path, ENG_IN_NOFOLLOW, (size_t)64 << 20, &text, &len, &err) == ENG_OK &&
        eng_json_precheck(path, text, len, ENG_JSON_MAX_DEPTH, &err) == ENG_OK &&
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

eng_result bench_reference_load(const bench_config *c, int w, int h, bench_reference *ref, eng_error *err)
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

void bench_reference_free(bench_reference *ref)
{
    free(ref->indirect);
    free(ref->full);
    ref->indirect = ref->full = NULL;
}

/* Renders one grid point: warm-up, then frames × repeats; metrics from the first repeat. */
static eng_result run_point(const bench_config *c, const scn_scene *scene, bench_point *p, bench_passes *passes,
                            const bench_reference *ref, eng_error *err)
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
            char what[512]; /* names the point in an error message */
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
            /* Bias near edges: within one kernel radius of a geometric edge. */
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

/* The bias measures of a point on stderr (beside the per-point line). */
static void print_bias(const bench_config *c, const bench_point *p)
{
    const rep_metrics_bias *b = &p->bias;
    fprintf(stderr, "        indirect mean ratio %.4f  block p90 %.4f (away from edges %.4f)  edges (%.0f%% of pixels): "
                    "ratio %.4f rel rmse %.4f  elsewhere: ratio %.4f rel rmse %.4f\n",
            b->mean_ratio, b->block_p90, b->flat_block_p90, 100.0 * b->edge_fraction, b->edge_ratio, b->edge_rel_rmse,
            b->flat_ratio, b->flat_rel_rmse);
    for (int k = 0; k < c->report_count; k++)
        fprintf(stderr, "        frame %3d (%3d rendered, %9.1f ms): rmse %.4g  mean ratio %.4f  block p90 %.4f  edge ratio %.4f\n",
                c->frames[c->report_frames[k]], c->report_frames[k] + 1, p->series_ms[k], p->series_err[k].rmse,
                p->series_bias[k].mean_ratio, p->series_bias[k].block_p90, p->series_bias[k].edge_ratio);
}

eng_result bench_run_points(const bench_config *c, const scn_scene *scene, bench_point *pts, int n,
                            const bench_reference *ref, int quiet, bench_passes *passes, eng_error *err)
{
    rep_progress prog;
    rep_progress_begin(&prog, quiet ? NULL : stderr, "ispm bench", "point", n);
    prog.tty = 0; /* the per-point bias lines follow each step: plain lines */
    eng_result r = ENG_OK;
    for (int i = 0; i < n && r == ENG_OK; i++) {
        r = run_point(c, scene, &pts[i], passes, ref, err);
        if (r == ENG_OK && !quiet) {
            char detail[256];
            snprintf(detail, sizeof detail, "%-32s frame %8.2f ms  indirect rmse %.4g  full rmse %.4g", pts[i].label,
                     pts[i].frame_ms, pts[i].indirect.rmse, pts[i].full.rmse);
            rep_progress_step(&prog, i + 1, detail);
        }
        if (r == ENG_OK && !quiet)
            print_bias(c, &pts[i]);
    }
    return r;
}
