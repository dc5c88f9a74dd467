/* bench_output.c — the results of an `ispm bench` run, written once every point has run:
 * bench.csv and bench.json (one row/object per point: its settings as the engine used them,
 * per-pass and frame medians, errors and bias measures against the reference, the Pareto flag),
 * error_vs_time.png and .svg (log–log, one series per method, the Pareto front marked),
 * pass_times.png (stacked per-pass medians), the convergence charts of report_frames, and
 * compare_scatter_vs_gather.png/.exr. The k-d gather baseline (003_… Appendix A) and ISPM's
 * scatter (§5) compute the same estimator, so a pair of points differing only in `indirect`
 * shows the cost of gathering at equal error: their first frames' indirect light is written
 * side by side with the difference, and every method's speed-up against the k-d gather at the
 * same settings is reported, each method's time read from the pass its entry in the engine's
 * registry of indirect methods names (indirect.h). Every file is written atomically and
 * bench.json last, so an OUTDIR without it is an unfinished bench. It owns nothing past the
 * call. */
#define _POSIX_C_SOURCE 200809L /* unlink */
#include "bench_output.h"
#include "indirect.h"
#include "plot.h"
#include "rep.h"
#include "rep_run.h"
#include "rep_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---------------------------------------------------------------- settings as text */

/* The value the engine uses for a settings key, as text (the settings table formats it); 0 for
 * a key it does not know. */
static int setting_text(const eng_settings *s, const char *key, char *out, size_t size)
{
    const eng_setting *d = eng_setting_find(key);
    if (!d)
        return 0;
    eng_setting_format(d, s, out, size);
    return 1;
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
    if (!strcmp(c->chart_metric, "block_p90")) /* indirect only (rep_metric_bias) */
        return p->bias.block_p90;
    if (!strcmp(c->chart_metric, "flat_block_p90"))
        return p->bias.flat_block_p90;
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
    rep_sb_printf(sb, ",%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g", m->mean_ratio, m->block_p90, m->edge_ratio,
                  m->edge_rel_rmse, m->flat_ratio, m->flat_rel_rmse, m->edge_fraction, m->flat_block_p90);
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
    cJSON_AddNumberToObject(o, "flat_block_p90", m->flat_block_p90);
    return o;
}

static char *make_csv(const bench_point *pts, int n, const columns *cols, const bench_passes *passes)
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
                       "indirect_flat_ratio,indirect_flat_rel_rmse,indirect_edge_fraction,indirect_flat_block_p90");
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

/* A method's speed against the k-d gather at the same settings ("speedup vs
 * kd-gather"), and how far its first frame's indirect light is from the k-d gather's. */
typedef struct speedup {
    int point, baseline;
    double frame, pass;           /* kd-gather ms / method ms */
    double pass_ms, base_pass_ms; /* the indirect pass of each */
    double max_abs, max_rel;      /* first frame's indirect.radiance, max_rel as pair_stats */
} speedup;

/* The pass an indirect method's time is reported under: its entry in the engine's registry of
 * indirect methods (indirect.h), found by the setting's name; NULL for "none", which has no
 * method and no pass. */
static const char *indirect_pass(eng_indirect m)
{
    const ind_method *im = ind_method_find(eng_indirect_name(m));
    return im ? im->pass : NULL;
}

static int same_but_indirect(const bench_point *a, const bench_point *b);

static double pass_of(const bench_point *p, const bench_passes *passes, const char *name)
{
    for (int s = 0; name && s < passes->count; s++)
        if (!strcmp(passes->name[s], name))
            return p->pass_ms[s];
    return 0.0;
}

/* Every non-k-d-gather point paired with the k-d gather point of the same other settings;
 * returns how many (out has room for n). */
static int find_speedups(const bench_point *pts, int n, const bench_passes *passes, speedup *out)
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
            u->base_pass_ms = pass_of(&pts[j], passes, indirect_pass(ENG_INDIRECT_KDGATHER));
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
                       const columns *cols, const bench_passes *passes, const pair_stats *pair, const speedup *ups,
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
                               const bench_passes *passes, eng_error *err)
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

eng_result bench_write_results(const bench_config *c, const char *outdir, const char *command_line,
                               bench_point *pts, int n, const bench_passes *passes, const bench_reference *ref,
                               int quiet, eng_error *err)
{
    mark_pareto(c, pts, n);
    columns cols = {0};
    column_add(&cols, "indirect");
    for (const cJSON *it = c->grid ? c->grid->child : NULL; it; it = it->next)
        column_add(&cols, it->string);
    for (const cJSON *m = c->methods->child; m; m = m->next) {
        const cJSON *s = cJSON_GetObjectItemCaseSensitive(m, "settings");
        for (const cJSON *it = s ? s->child : NULL; it; it = it->next)
            column_add(&cols, it->string);
    }
    pair_stats pair;
    speedup *ups = rep_xcalloc((size_t)n, sizeof *ups);
    int nups = find_speedups(pts, n, passes, ups);
    eng_result r = write_comparison(outdir, pts, n, ref->indirect, &pair, err);
    if (r == ENG_OK)
        r = write_charts(c, outdir, pts, n, passes, err);
    if (r == ENG_OK)
        r = write_convergence(c, outdir, pts, n, err);
    if (r == ENG_OK) {
        char *csv = make_csv(pts, n, &cols, passes);
        char *path = rep_path_join(outdir, "bench.csv");
        r = rep_write_atomic(path, csv, strlen(csv), err);
        free(path);
        free(csv);
    }
    if (r == ENG_OK) {
        char *json = make_json(c, command_line, pts, n, &cols, passes, &pair, ups, nups, ref->pixel);
        char *path = rep_path_join(outdir, "bench.json");
        r = rep_write_atomic(path, json, strlen(json), err);
        free(path);
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
    return r;
}
