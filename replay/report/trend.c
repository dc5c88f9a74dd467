/* trend.c — ispm trend: the metrics that creep, over a series of replayed runs.
 *
 * A replay judges one run against its golden; a regression that creeps (ꟻLIP mean up a little
 * every week, a pass's share of the frame growing) passes every single judgement. Here the runs'
 * own reports (RUN/replay/report.json) and manifests are read in the order given (the caller
 * orders them: by date, or by commit), and every metric becomes a series over the runs: per
 * buffer max |Δ|, RMSE, ꟻLIP mean and p99 and flicker, per pass its time and share of the frame,
 * and the frame time. Each series records the step between consecutive runs where it moved most,
 * the first place to look; trend.json holds everything, trend.html charts it (plot.h, PLplot as
 * the bench draws) with that step ringed. Reading only: no pixel is decoded.
 */
#define _POSIX_C_SOURCE 200809L

#include "plot.h"
#include "rep_report.h"
#include "rep_trend.h"
#include "rep_util.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { M_MAX, M_RMSE, M_FLIPMEAN, M_FLIPP99, M_FLICKER_R, M_FLICKER_S, M_COUNT };
static const char *const METRIC[M_COUNT] = {"max_abs", "rmse", "flip_mean", "flip_p99", "flicker_reprojected",
                                            "flicker_static"};
static const char *const METRIC_TITLE[M_COUNT] = {"max |Δ| (max over frames)", "RMSE (over all frames)",
                                                  "ꟻLIP mean (mean over frames)", "ꟻLIP p99 (max over frames)",
                                                  "flicker, reprojected mean", "flicker, static mean"};

typedef struct tbuf {
    char *name;
    double v[M_COUNT];
    double rmse_sq;
    int rmse_n, flip_n;
} tbuf;

typedef struct tpass {
    char *name;
    double ms, share;
} tpass;

typedef struct trun {
    char *dir, *git, *verdict;
    int exit_code;
    double frame_ms;
    int nbuf, npass;
    tbuf *b;
    tpass *p;
} trun;

/* One series: a metric of one buffer or pass over the runs (NAN where a run lacks it). */
typedef struct series {
    char *metric, *name;
    double *v;
    int from, to; /* moved most: from run `from` to run `to` (-1: never moved) */
    double delta;
} series;

static void trun_free(trun *t)
{
    for (int i = 0; i < t->nbuf; i++)
        free(t->b[i].name);
    for (int i = 0; i < t->npass; i++)
        free(t->p[i].name);
    free(t->b);
    free(t->p);
    free(t->dir);
    free(t->git);
    free(t->verdict);
}

static eng_result read_json(const char *path, cJSON **out, eng_error *err)
{
    char *text = NULL;
    size_t len = 0;
    eng_result r = eng_read_file(path, REP_MAX_JSON_BYTES, &text, &len, err);
    if (r != ENG_OK)
        return r;
    *out = cJSON_ParseWithLength(text, len);
    free(text);
    if (!*out)
        return eng_fail(err, ENG_ERR_PARSE, "%s: not valid JSON", path);
    return ENG_OK;
}

static double num_at(const cJSON *o, const char *k)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, k);
    return cJSON_IsNumber(v) ? v->valuedouble : NAN;
}

static tbuf *buf_of(trun *t, const char *name)
{
    for (int i = 0; i < t->nbuf; i++)
        if (strcmp(t->b[i].name, name) == 0)
            return &t->b[i];
    t->b = rep_xrealloc(t->b, (size_t)(t->nbuf + 1) * sizeof *t->b);
    tbuf *b = &t->b[t->nbuf++];
    memset(b, 0, sizeof *b);
    b->name = rep_xstrdup(name);
    for (int k = 0; k < M_COUNT; k++)
        b->v[k] = NAN;
    return b;
}

static void fmax_into(double *slot, double v)
{
    if (isfinite(v) && (!isfinite(*slot) || v > *slot))
        *slot = v;
}

/* Per buffer metrics from report.json. */
static eng_result read_report(const char *path, trun *t, eng_error *err)
{
    cJSON *root = NULL;
    eng_result r = read_json(path, &root, err);
    if (r != ENG_OK)
        return r;
    const cJSON *fmt = cJSON_GetObjectItemCaseSensitive(root, "format");
    const cJSON *verdict = cJSON_GetObjectItemCaseSensitive(root, "verdict");
    const cJSON *frames = cJSON_GetObjectItemCaseSensitive(root, "frames");
    if (!cJSON_IsString(fmt) || strcmp(fmt->valuestring, "ispm-replay-report") != 0 || !cJSON_IsString(verdict) ||
        !cJSON_IsArray(frames)) {
        cJSON_Delete(root);
        return eng_fail(err, ENG_ERR_INVALID, "%s: not a replay report (format ispm-replay-report with verdict and frames)",
                        path);
    }
    t->verdict = rep_xstrdup(verdict->valuestring);
    t->exit_code = (int)num_at(root, "exit_code");
    const cJSON *f, *b;
    cJSON_ArrayForEach(f, frames)
    {
        cJSON_ArrayForEach(b, cJSON_GetObjectItemCaseSensitive(f, "buffers"))
        {
            const cJSON *name = cJSON_GetObjectItemCaseSensitive(b, "name");
            const cJSON *m = cJSON_GetObjectItemCaseSensitive(b, "metrics");
            if (!cJSON_IsString(name) || !cJSON_IsObject(m))
                continue;
            tbuf *tb = buf_of(t, name->valuestring);
            fmax_into(&tb->v[M_MAX], num_at(m, "max_abs_error"));
            double rmse = num_at(m, "rmse");
            if (isfinite(rmse)) {
                tb->rmse_sq += rmse * rmse;
                tb->rmse_n++;
            }
            const cJSON *fl = cJSON_GetObjectItemCaseSensitive(b, "flip");
            if (cJSON_IsObject(fl) && isfinite(num_at(fl, "mean"))) {
                tb->v[M_FLIPMEAN] = (isfinite(tb->v[M_FLIPMEAN]) ? tb->v[M_FLIPMEAN] : 0) + num_at(fl, "mean");
                tb->flip_n++;
                fmax_into(&tb->v[M_FLIPP99], num_at(fl, "p99"));
            }
        }
    }
    for (int i = 0; i < t->nbuf; i++) {
        tbuf *tb = &t->b[i];
        if (tb->rmse_n)
            tb->v[M_RMSE] = sqrt(tb->rmse_sq / tb->rmse_n);
        if (tb->flip_n)
            tb->v[M_FLIPMEAN] /= tb->flip_n;
    }
    const cJSON *st = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(root, "stability"), "buffers");
    cJSON_ArrayForEach(b, st)
    {
        const cJSON *name = cJSON_GetObjectItemCaseSensitive(b, "name");
        if (!cJSON_IsString(name))
            continue;
        tbuf *tb = buf_of(t, name->valuestring);
        tb->v[M_FLICKER_R] = num_at(cJSON_GetObjectItemCaseSensitive(b, "reprojected"), "mean");
        tb->v[M_FLICKER_S] = num_at(cJSON_GetObjectItemCaseSensitive(b, "static"), "mean");
    }
    cJSON_Delete(root);
    return ENG_OK;
}

/* Frame time and per-pass times and shares (medians over frames) from the manifest. */
static eng_result read_manifest(const char *path, trun *t, eng_error *err)
{
    cJSON *root = NULL;
    eng_result r = read_json(path, &root, err);
    if (r != ENG_OK)
        return r;
    const cJSON *frames = cJSON_GetObjectItemCaseSensitive(root, "frames");
    const cJSON *git = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(root, "tool"), "git");
    if (cJSON_IsString(git))
        t->git = rep_xstrdup(git->valuestring);
    int nf = cJSON_GetArraySize(frames);
    double *frame = rep_xcalloc((size_t)nf + 1, sizeof *frame), *tmp = rep_xcalloc((size_t)nf + 1, sizeof *tmp);
    const cJSON *f, *p;
    int i = 0;
    cJSON_ArrayForEach(f, frames)
    {
        cJSON_ArrayForEach(p, cJSON_GetObjectItemCaseSensitive(f, "passes"))
        {
            const cJSON *name = cJSON_GetObjectItemCaseSensitive(p, "name");
            double ms = num_at(p, "ms");
            if (!cJSON_IsString(name) || !isfinite(ms))
                continue;
            frame[i] += ms;
            int k = 0;
            while (k < t->npass && strcmp(t->p[k].name, name->valuestring) != 0)
                k++;
            if (k == t->npass) {
                t->p = rep_xrealloc(t->p, (size_t)(t->npass + 1) * sizeof *t->p);
                t->p[t->npass++] = (tpass){rep_xstrdup(name->valuestring), NAN, NAN};
            }
        }
        i++;
    }
    for (int k = 0; k < t->npass; k++) {
        for (int pass = 0; pass < 2; pass++) {
            int n = 0;
            i = 0;
            cJSON_ArrayForEach(f, frames)
            {
                cJSON_ArrayForEach(p, cJSON_GetObjectItemCaseSensitive(f, "passes"))
                {
                    const cJSON *name = cJSON_GetObjectItemCaseSensitive(p, "name");
                    if (n < nf && cJSON_IsString(name) && strcmp(name->valuestring, t->p[k].name) == 0 &&
                        isfinite(num_at(p, "ms")))
                        tmp[n++] = pass == 0 ? num_at(p, "ms") : (frame[i] > 0 ? num_at(p, "ms") / frame[i] : NAN);
                }
                i++;
            }
            if (pass == 0)
                t->p[k].ms = rep_median(tmp, n);
            else
                t->p[k].share = rep_median(tmp, n);
        }
    }
    t->frame_ms = rep_median(frame, nf);
    free(frame);
    free(tmp);
    cJSON_Delete(root);
    return ENG_OK;
}

char *rep_trend_run_git(const char *run_dir)
{
    char *path = rep_path_join(run_dir, "manifest.json");
    cJSON *root = NULL;
    eng_error ignored;
    char *git = NULL;
    if (read_json(path, &root, &ignored) == ENG_OK) {
        const cJSON *g = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(root, "tool"), "git");
        if (cJSON_IsString(g) && g->valuestring[0]) {
            git = rep_xstrdup(g->valuestring);
            char *d = strstr(git, "-dirty");
            if (d)
                *d = 0;
        }
        cJSON_Delete(root);
    }
    free(path);
    return git;
}

static void moved_most(series *s, int n)
{
    s->from = s->to = -1;
    s->delta = 0;
    for (int i = 1; i < n; i++)
        if (isfinite(s->v[i]) && isfinite(s->v[i - 1]) && fabs(s->v[i] - s->v[i - 1]) > fabs(s->delta)) {
            s->delta = s->v[i] - s->v[i - 1];
            s->from = i - 1;
            s->to = i;
        }
}

static void add_series(series **all, int *count, const char *metric, const char *name, double *v, int n)
{
    *all = rep_xrealloc(*all, (size_t)(*count + 1) * sizeof **all);
    series *s = &(*all)[(*count)++];
    s->metric = rep_xstrdup(metric);
    s->name = rep_xstrdup(name);
    s->v = v;
    moved_most(s, n);
}

/* Every series over the runs: per buffer metric, per pass ms and share, the frame time. */
static series *make_series(const trun *t, int n, int *count)
{
    series *all = NULL;
    *count = 0;
    for (int m = 0; m < M_COUNT; m++)
        for (int r = 0; r < n; r++)
            for (int i = 0; i < t[r].nbuf; i++) {
                const char *name = t[r].b[i].name;
                int seen = 0;
                for (int q = 0; q < r && !seen; q++)
                    for (int j = 0; j < t[q].nbuf && !seen; j++)
                        seen = strcmp(t[q].b[j].name, name) == 0;
                if (seen)
                    continue;
                double *v = rep_xcalloc((size_t)n, sizeof *v);
                int any = 0;
                for (int q = 0; q < n; q++) {
                    v[q] = NAN;
                    for (int j = 0; j < t[q].nbuf; j++)
                        if (strcmp(t[q].b[j].name, name) == 0)
                            v[q] = t[q].b[j].v[m];
                    any |= isfinite(v[q]);
                }
                if (any)
                    add_series(&all, count, METRIC[m], name, v, n);
                else
                    free(v);
            }
    for (int w = 0; w < 2; w++)
        for (int r = 0; r < n; r++)
            for (int i = 0; i < t[r].npass; i++) {
                const char *name = t[r].p[i].name;
                int seen = 0;
                for (int q = 0; q < r && !seen; q++)
                    for (int j = 0; j < t[q].npass && !seen; j++)
                        seen = strcmp(t[q].p[j].name, name) == 0;
                if (seen)
                    continue;
                double *v = rep_xcalloc((size_t)n, sizeof *v);
                for (int q = 0; q < n; q++) {
                    v[q] = NAN;
                    for (int j = 0; j < t[q].npass; j++)
                        if (strcmp(t[q].p[j].name, name) == 0)
                            v[q] = w == 0 ? t[q].p[j].ms : t[q].p[j].share;
                }
                add_series(&all, count, w == 0 ? "pass_ms" : "pass_share", name, v, n);
            }
    double *v = rep_xcalloc((size_t)n, sizeof *v);
    for (int q = 0; q < n; q++)
        v[q] = t[q].frame_ms;
    add_series(&all, count, "frame_ms", "frame", v, n);
    return all;
}

static void add_num(cJSON *o, const char *k, double v)
{
    if (isfinite(v))
        cJSON_AddNumberToObject(o, k, v);
    else
        cJSON_AddNullToObject(o, k);
}

static char *trend_json(const trun *t, int n, const series *s, int ns)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "format", "ispm-trend");
    cJSON_AddNumberToObject(root, "format_version", 1);
    cJSON *runs = cJSON_AddArrayToObject(root, "runs");
    for (int r = 0; r < n; r++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "run", t[r].dir);
        if (t[r].git)
            cJSON_AddStringToObject(o, "git", t[r].git);
        else
            cJSON_AddNullToObject(o, "git");
        cJSON_AddStringToObject(o, "verdict", t[r].verdict);
        cJSON_AddNumberToObject(o, "exit_code", t[r].exit_code);
        add_num(o, "frame_ms", t[r].frame_ms);
        cJSON *ps = cJSON_AddObjectToObject(o, "passes");
        for (int i = 0; i < t[r].npass; i++) {
            cJSON *p = cJSON_AddObjectToObject(ps, t[r].p[i].name);
            add_num(p, "ms", t[r].p[i].ms);
            add_num(p, "share", t[r].p[i].share);
        }
        cJSON *bs = cJSON_AddObjectToObject(o, "buffers");
        for (int i = 0; i < t[r].nbuf; i++) {
            cJSON *b = cJSON_AddObjectToObject(bs, t[r].b[i].name);
            for (int m = 0; m < M_COUNT; m++)
                add_num(b, METRIC[m], t[r].b[i].v[m]);
        }
        cJSON_AddItemToArray(runs, o);
    }
    cJSON *sa = cJSON_AddArrayToObject(root, "series");
    for (int i = 0; i < ns; i++) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "metric", s[i].metric);
        cJSON_AddStringToObject(o, "name", s[i].name);
        cJSON *v = cJSON_AddArrayToObject(o, "values");
        for (int r = 0; r < n; r++)
            cJSON_AddItemToArray(v, isfinite(s[i].v[r]) ? cJSON_CreateNumber(s[i].v[r]) : cJSON_CreateNull());
        if (s[i].from >= 0) {
            cJSON *mm = cJSON_AddObjectToObject(o, "moved_most");
            cJSON_AddNumberToObject(mm, "from", s[i].from);
            cJSON_AddNumberToObject(mm, "to", s[i].to);
            cJSON_AddNumberToObject(mm, "delta", s[i].delta);
        } else {
            cJSON_AddNullToObject(o, "moved_most");
        }
        cJSON_AddItemToArray(sa, o);
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    char *out = rep_xprintf("%s\n", text);
    cJSON_free(text);
    return out;
}

/* The order series are charted in: largest step first (a series that never moved last). */
static int by_delta(const void *pa, const void *pb)
{
    const series *a = *(const series *const *)pa, *b = *(const series *const *)pb;
    double da = fabs(a->delta), db = fabs(b->delta);
    if (da != db)
        return da < db ? 1 : -1;
    return strcmp(a->name, b->name);
}

/* One chart of the series of one metric (the 8 that moved most), its step ringed; its section. */
static void chart(rep_sb *html, const char *dir, const char *metric, const char *title, const series *s, int ns, int n,
                  double *xs)
{
    const series **pick = rep_xcalloc((size_t)ns + 1, sizeof *pick);
    int np = 0;
    for (int i = 0; i < ns; i++)
        if (strcmp(s[i].metric, metric) == 0)
            pick[np++] = &s[i];
    if (!np) {
        free(pick);
        return;
    }
    qsort(pick, (size_t)np, sizeof *pick, by_delta);
    int shown = np < 8 ? np : 8;
    plot_chart c;
    memset(&c, 0, sizeof c);
    c.title = title;
    c.x_label = "run (in the order given)";
    c.y_label = metric;
    c.marked_label = "moved most";
    int *marks = rep_xcalloc((size_t)(shown * n) + 1, sizeof *marks);
    for (int i = 0; i < shown; i++) {
        if (pick[i]->to >= 0)
            marks[i * n + pick[i]->to] = 1;
        c.series[c.series_count++] =
            (plot_series){pick[i]->name, xs, pick[i]->v, n, PLOT_LINES_POINTS, marks + (size_t)i * (size_t)n};
    }
    char *rel = rep_xprintf("img/trend-%s.png", metric);
    char *path = rep_path_join(dir, rel);
    eng_error err;
    rep_sb_printf(html, "<section id=\"%s\"><h2>%s</h2>\n", metric, title);
    if (plot_xy(path, &c, &err) == ENG_OK)
        rep_sb_printf(html, "<img src=\"%s\" width=\"900\" height=\"600\" alt=\"%s\">\n", rel, metric);
    else {
        rep_sb_printf(html, "<p class=\"note\">no chart: ");
        rep_sb_xml(html, err.msg);
        rep_sb_printf(html, "</p>\n");
    }
    rep_sb_printf(html, "<p>The ringed point is where each series moved most (largest step from the run before).</p>"
                        "<table><tr><th>series</th><th>moved most</th><th>step</th></tr>\n");
    for (int i = 0; i < np; i++) {
        rep_sb_printf(html, "<tr><td><code>");
        rep_sb_xml(html, pick[i]->name);
        if (pick[i]->to >= 0)
            rep_sb_printf(html, "</code></td><td>run %d → %d</td><td>%+.4g</td></tr>\n", pick[i]->from, pick[i]->to,
                          pick[i]->delta);
        else
            rep_sb_printf(html, "</code></td><td>never</td><td></td></tr>\n");
    }
    rep_sb_printf(html, "</table></section>\n");
    free(rel);
    free(path);
    free(marks);
    free(pick);
}

static char *trend_html(const char *dir, const trun *t, int n, const series *s, int ns)
{
    rep_sb h = {0};
    rep_sb_printf(&h, "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>ispm trend</title>\n"
                      "<style>body{font:14px/1.45 system-ui,sans-serif;margin:24px;max-width:1000px}"
                      "table{border-collapse:collapse;font-size:12px}td,th{padding:2px 8px;border-bottom:1px solid #ddd;"
                      "text-align:left}code{font-family:monospace}.note{color:#b42318}</style>\n</head>\n<body>\n"
                      "<h1>ispm trend: %d run%s</h1>\n<table><tr><th>#</th><th>run</th><th>git</th><th>verdict</th>"
                      "<th>frame ms</th></tr>\n", n, n == 1 ? "" : "s");
    for (int r = 0; r < n; r++) {
        rep_sb_printf(&h, "<tr><td>%d</td><td><code>", r);
        rep_sb_xml(&h, t[r].dir);
        rep_sb_printf(&h, "</code></td><td><code>");
        rep_sb_xml(&h, t[r].git ? t[r].git : "?");
        rep_sb_printf(&h, "</code></td><td>");
        rep_sb_xml(&h, t[r].verdict);
        rep_sb_printf(&h, "</td><td>%.1f</td></tr>\n", t[r].frame_ms);
    }
    rep_sb_printf(&h, "</table>\n");
    double *xs = rep_xcalloc((size_t)n, sizeof *xs);
    for (int r = 0; r < n; r++)
        xs[r] = r;
    for (int m = 0; m < M_COUNT; m++)
        chart(&h, dir, METRIC[m], METRIC_TITLE[m], s, ns, n, xs);
    chart(&h, dir, "pass_share", "pass share of the frame (median over frames)", s, ns, n, xs);
    chart(&h, dir, "pass_ms", "pass time, ms (median over frames)", s, ns, n, xs);
    chart(&h, dir, "frame_ms", "frame time, ms (median over frames)", s, ns, n, xs);
    rep_sb_printf(&h, "</body>\n</html>\n");
    free(xs);
    return h.s;
}

eng_result rep_trend_write(const char *const *runs, const char *const *report_dirs, int run_count, const char *out_dir,
                           FILE *summary, eng_error *err)
{
    if (run_count < 1 || !out_dir)
        return eng_fail(err, ENG_ERR_INVALID, "trend: runs and an output folder are needed");
    trun *t = rep_xcalloc((size_t)run_count, sizeof *t);
    eng_result res = ENG_OK;
    for (int r = 0; r < run_count && res == ENG_OK; r++) {
        t[r].dir = rep_xstrdup(runs[r]);
        char *rdir = report_dirs ? rep_xstrdup(report_dirs[r]) : rep_path_join(runs[r], "replay");
        char *rep = rep_path_join(rdir, "report.json"), *man = rep_path_join(runs[r], "manifest.json");
        if (!rep_is_file(man))
            res = eng_fail(err, ENG_ERR_IO, "%s: no manifest.json: not a complete run", runs[r]);
        else if (!rep_is_file(rep))
            res = eng_fail(err, ENG_ERR_IO, "%s: no report.json: replay the run first (ispm replay RUN --golden DIR)",
                           rdir);
        if (res == ENG_OK)
            res = read_report(rep, &t[r], err);
        if (res == ENG_OK)
            res = read_manifest(man, &t[r], err);
        free(rdir);
        free(rep);
        free(man);
    }
    int ns = 0;
    series *s = NULL;
    char *img = rep_path_join(out_dir, "img");
    if (res == ENG_OK)
        res = rep_mkdirs(out_dir, err);
    if (res == ENG_OK && (res = rep_remove_tree(img, err)) == ENG_OK)
        res = rep_mkdirs(img, err);
    if (res == ENG_OK) {
        s = make_series(t, run_count, &ns);
        char *json = trend_json(t, run_count, s, ns);
        char *jp = rep_path_join(out_dir, "trend.json");
        res = rep_write_atomic(jp, json, strlen(json), err);
        free(json);
        free(jp);
    }
    if (res == ENG_OK) {
        char *html = trend_html(out_dir, t, run_count, s, ns);
        char *hp = rep_path_join(out_dir, "trend.html");
        res = rep_write_atomic(hp, html, strlen(html), err);
        free(html);
        free(hp);
    }
    if (res == ENG_OK && summary) {
        const series *most = NULL;
        for (int i = 0; i < ns; i++)
            if (strcmp(s[i].metric, "flip_mean") == 0 && s[i].from >= 0 && (!most || fabs(s[i].delta) > fabs(most->delta)))
                most = &s[i];
        fprintf(summary, "trend: %d run%s, %d series: %s/trend.json, %s/trend.html", run_count, run_count == 1 ? "" : "s",
                ns, out_dir, out_dir);
        if (most)
            fprintf(summary, "; FLIP mean moved most in %s, run %d -> %d (%+.4g)", most->name, most->from, most->to,
                    most->delta);
        fprintf(summary, "\n");
    }
    for (int i = 0; i < ns; i++) {
        free(s[i].metric);
        free(s[i].name);
        free(s[i].v);
    }
    free(s);
    free(img);
    for (int r = 0; r < run_count; r++)
        trun_free(&t[r]);
    free(t);
    return res;
}
