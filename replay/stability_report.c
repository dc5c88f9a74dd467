/* stability_report.c — what replay says about temporal stability: the verdicts against the
 * "stability" limits of tolerances.json, the per-pixel flicker written as a run folder of its
 * own (RUN/replay/stability: frames/NNNNNN.exr with one Y part stability.<part> per measured
 * pass, manifest.json last, so ispm-view opens it like any run), and the stability sections of
 * report.txt, report.json and report.html, whose charts (flicker per pass over frames) are drawn
 * through plot.h. The stability run is written into a temporary folder that replaces the old
 * one only once its manifest is complete (replay.c does the rename).
 */
#define _POSIX_C_SOURCE 200809L

#include "cap.h"
#include "plot.h"
#include "stability_internal.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void add_num(cJSON *o, const char *k, double v)
{
    if (isfinite(v))
        cJSON_AddNumberToObject(o, k, v);
    else
        cJSON_AddNullToObject(o, k);
}

static char *print_json(cJSON *o)
{
    char *t = cJSON_PrintUnformatted(o);
    if (!t) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    char *s = rep_xstrdup(t);
    cJSON_free(t);
    return s;
}

/* ---------------------------------------------------------------- verdicts */

static void over(rep_sb *why, const char *what, double v, double lim)
{
    if (isfinite(lim) && v > lim)
        rep_sb_printf(why, "%s%s %.3g over %.3g", why->len ? "; " : "", what, v, lim);
}

/* Only where the golden measured some pixels: a golden recorded without cameras has no
 * reprojected pixels, and 0 is then no value to hold a run to. */
static void over_golden(rep_sb *why, const char *what, double v, const rep_stab_stats *gs, double g, double margin)
{
    if (margin >= 0 && gs->pixels > 0 && isfinite(g) && isfinite(v) && v > g * (1.0 + margin))
        rep_sb_printf(why, "%s%s %.3g over golden %.3g × %.3g", why->len ? "; " : "", what, v, g, 1.0 + margin);
}

void rep_stab_judge(rep_stab_report *s, const rep_tolerances *tols)
{
    s->verdicts = rep_xcalloc((size_t)s->run.buffer_count ? (size_t)s->run.buffer_count : 1, sizeof *s->verdicts);
    s->failed = 0;
    for (int k = 0; k < s->run.buffer_count; k++) {
        const rep_stab_buffer *b = &s->run.buffers[k];
        rep_stab_verdict *v = &s->verdicts[k];
        if (!tols)
            continue;
        rep_tol t;
        v->tol_match = rep_xstrdup(rep_tol_lookup(tols, b->name, &t));
        v->tol = t.stab;
        v->checked = t.stab.set;
        if (!v->checked)
            continue;
        rep_sb why = {0};
        over(&why, "static mean", b->st.mean, t.stab.static_mean);
        over(&why, "static p99", b->st.p99, t.stab.static_p99);
        over(&why, "reprojected mean", b->rp.mean, t.stab.reprojected_mean);
        over(&why, "reprojected p99", b->rp.p99, t.stab.reprojected_p99);
        if (b->reference) {
            over(&why, "temporal std mean", b->tstd_mean, t.stab.temporal_std_mean);
            over(&why, "temporal std p99", b->tstd_p99, t.stab.temporal_std_p99);
        }
        const rep_stab_buffer *g = s->has_golden ? rep_stab_find(&s->golden, b->name) : NULL;
        if (g && t.stab.golden_margin >= 0) {
            over_golden(&why, "static mean", b->st.mean, &g->st, g->st.mean, t.stab.golden_margin);
            over_golden(&why, "static p99", b->st.p99, &g->st, g->st.p99, t.stab.golden_margin);
            over_golden(&why, "reprojected mean", b->rp.mean, &g->rp, g->rp.mean, t.stab.golden_margin);
            over_golden(&why, "reprojected p99", b->rp.p99, &g->rp, g->rp.p99, t.stab.golden_margin);
        } else if (!g && t.stab.golden_margin >= 0 && s->has_golden) {
            rep_sb_printf(&why, "%sgolden_margin: the golden has no %s to compare with", why.len ? "; " : "", b->name);
        }
        if (why.len) {
            v->failed = 1;
            v->why = why.s;
            s->failed++;
        }
    }
}

void rep_stab_report_free(rep_stab_report *s)
{
    if (!s)
        return;
    if (s->verdicts)
        for (int k = 0; k < s->run.buffer_count; k++) {
            free(s->verdicts[k].tol_match);
            free(s->verdicts[k].why);
        }
    free(s->verdicts);
    rep_stab_free(&s->run);
    rep_stab_free(&s->golden);
    free(s->reference_dir);
    free(s->out_dir);
    free(s);
}

/* ---------------------------------------------------------------- the stability run */

eng_result rep_stab_write_frame(const char *run_dir, const rep_frame_info *f, const rep_stab_run *st, float **flicker,
                                int count, char **rec, eng_error *err)
{
    static const char *const Y[] = {"Y"};
    *rec = NULL;
    char *file = rep_xprintf("frames/%06d.exr", f->index);
    char *path = rep_path_join(run_dir, file);
    eng_buffer *bufs = rep_xcalloc((size_t)(count ? count : 1), sizeof *bufs);
    char **names = rep_xcalloc((size_t)(count ? count : 1), sizeof *names);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "index", f->index);
    cJSON_AddNumberToObject(o, "time", f->time);
    cJSON_AddStringToObject(o, "file", file);
    if (f->has_camera) {
        cJSON *cam = cJSON_AddObjectToObject(o, "camera");
        cJSON *vp = cJSON_AddArrayToObject(cam, "view_proj"), *eye = cJSON_AddArrayToObject(cam, "eye");
        for (int k = 0; k < 16; k++)
            cJSON_AddItemToArray(vp, cJSON_CreateNumber(f->view_proj[k]));
        for (int k = 0; k < 3; k++)
            cJSON_AddItemToArray(eye, cJSON_CreateNumber(f->eye[k]));
    }
    cJSON *jb = cJSON_AddArrayToObject(o, "buffers");
    for (int k = 0; k < count; k++) {
        names[k] = rep_xprintf("stability.%s", st->buffers[k].name);
        bufs[k].name = names[k];
        bufs[k].width = st->width;
        bufs[k].height = st->height;
        bufs[k].channel_count = 1;
        bufs[k].channels = Y;
        bufs[k].data = flicker[k];
        char dg[40];
        eng_buffer_digest(&bufs[k], dg);
        cJSON *b = cJSON_CreateObject();
        cJSON_AddStringToObject(b, "name", names[k]);
        cJSON_AddNumberToObject(b, "width", st->width);
        cJSON_AddNumberToObject(b, "height", st->height);
        cJSON_AddItemToObject(b, "channels", cJSON_CreateStringArray(Y, 1));
        cJSON_AddStringToObject(b, "digest", dg);
        cJSON_AddNumberToObject(b, "nan", 0);
        cJSON_AddNumberToObject(b, "inf", 0);
        cJSON_AddItemToArray(jb, b);
    }
    /* Written like a recorded frame (capture's OpenEXR writer), so replay loads no OpenImageIO;
     * unsynced, as OpenImageIO wrote it (the folder is renamed into place whole). */
    const eng_buffer **ptrs = rep_xcalloc((size_t)(count ? count : 1), sizeof *ptrs);
    for (int k = 0; k < count; k++)
        ptrs[k] = &bufs[k];
    eng_result r = count > 0 ? cap_write_exr_unsynced(path, ptrs, count, err)
                             : eng_fail(err, ENG_ERR_INVALID, "%s: no image pass to measure", path);
    free(ptrs);
    if (r == ENG_OK)
        *rec = print_json(o);
    cJSON_Delete(o);
    for (int k = 0; k < count; k++)
        free(names[k]);
    free(names);
    free(bufs);
    free(path);
    free(file);
    return r;
}

eng_result rep_stab_write_manifest(const char *run_dir, const char *sequence_name, const rep_stab_run *st,
                                   char **records, int count, eng_error *err)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "format", "ispm-run");
    cJSON_AddNumberToObject(root, "format_version", 1);
    cJSON *tool = cJSON_AddObjectToObject(root, "tool");
    cJSON_AddStringToObject(tool, "name", "ispm replay (stability)");
    cJSON *seq = cJSON_AddObjectToObject(root, "sequence");
    char *name = rep_xprintf("%s.stability", sequence_name ? sequence_name : "run");
    cJSON_AddStringToObject(seq, "name", name);
    free(name);
    cJSON *res = cJSON_AddArrayToObject(root, "resolution");
    cJSON_AddItemToArray(res, cJSON_CreateNumber(st->width));
    cJSON_AddItemToArray(res, cJSON_CreateNumber(st->height));
    cJSON_AddStringToObject(root, "meaning",
                            "stability.<part>: per-pixel reprojected flicker max_c |a_c - b_c| / (max(|a_c|,|b_c|) + 1e-3) "
                            "against the previous frame; -1 where the pixel has no valid history (frame 0, "
                            "background, off-screen, moving, disoccluded)");
    cJSON_AddNumberToObject(root, "frame_count", count);
    cJSON *frames = cJSON_AddArrayToObject(root, "frames");
    for (int i = 0; i < count; i++)
        cJSON_AddItemToArray(frames, cJSON_Parse(records[i]));
    cJSON_AddBoolToObject(root, "complete", 1);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    char *path = rep_path_join(run_dir, "manifest.json");
    eng_result r = rep_write_atomic(path, text, strlen(text), err);
    free(path);
    cJSON_free(text);
    return r;
}

/* ---------------------------------------------------------------- text */

void rep_stab_text(rep_sb *sb, const rep_report *r)
{
    const rep_stab_report *s = r->stab;
    if (!s)
        return;
    const rep_stab_run *st = &s->run;
    uint64_t surf = 0;
    for (int c = 0; c < REP_REPRO_COUNT; c++)
        if (c != REP_REPRO_BACKGROUND)
            surf += st->classes[c];
    rep_sb_printf(sb, "stability: %d frames, flicker f = max_c |Δ| / (max(|a|,|b|) + %g); surface pixels: %llu static",
                  st->frames, REP_STAB_EPS, (unsigned long long)st->static_pixels);
    for (int c = 0; c < REP_REPRO_COUNT; c++)
        if (c != REP_REPRO_BACKGROUND)
            rep_sb_printf(sb, ", %llu %s", (unsigned long long)st->classes[c], rep_repro_class_name((rep_repro_class)c));
    rep_sb_printf(sb, " (of %llu)\n", (unsigned long long)surf);
    for (int k = 0; k < st->buffer_count; k++) {
        const rep_stab_buffer *b = &st->buffers[k];
        const rep_stab_verdict *v = s->verdicts ? &s->verdicts[k] : NULL;
        const char *tag = v && v->failed ? "FAIL" : v && v->checked ? "PASS" : "    ";
        rep_sb_printf(sb, "%-5s %-22s static mean %.3g p99 %.3g (%llu/%llu changed)  reprojected mean %.3g p99 %.3g "
                          "(%llu/%llu changed)",
                      tag, b->name, b->st.mean, b->st.p99, (unsigned long long)b->st.changed,
                      (unsigned long long)b->st.pixels, b->rp.mean, b->rp.p99, (unsigned long long)b->rp.changed,
                      (unsigned long long)b->rp.pixels);
        if (b->reference)
            rep_sb_printf(sb, "  vs %s: std mean %.3g p99 %.3g, |bias| %.3g", b->reference, b->tstd_mean, b->tstd_p99,
                          b->bias_mean);
        const rep_stab_buffer *g = s->has_golden ? rep_stab_find(&s->golden, b->name) : NULL;
        if (g)
            rep_sb_printf(sb, "  (golden static %.3g, reprojected %.3g)", g->st.mean, g->rp.mean);
        if (v && v->failed)
            rep_sb_printf(sb, "  %s", v->why);
        rep_sb_printf(sb, "\n");
    }
    if (s->out_dir)
        rep_sb_printf(sb, "stability: per-pixel flicker in %s (open with ispm-view)\n", s->out_dir);
}

/* ---------------------------------------------------------------- JSON */

static cJSON *stats_json(const rep_stab_stats *st)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "pixels", (double)st->pixels);
    cJSON_AddNumberToObject(o, "changed", (double)st->changed);
    add_num(o, "mean", st->mean);
    add_num(o, "p99", st->p99);
    add_num(o, "max", st->max);
    return o;
}

static cJSON *series_json(const double *v, int n)
{
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; i < n; i++)
        cJSON_AddItemToArray(a, isfinite(v[i]) ? cJSON_CreateNumber(v[i]) : cJSON_CreateNull());
    return a;
}

static cJSON *limits_json(const rep_tol_stab *t)
{
    cJSON *o = cJSON_CreateObject();
    add_num(o, "static_mean", t->static_mean);
    add_num(o, "static_p99", t->static_p99);
    add_num(o, "reprojected_mean", t->reprojected_mean);
    add_num(o, "reprojected_p99", t->reprojected_p99);
    add_num(o, "temporal_std_mean", t->temporal_std_mean);
    add_num(o, "temporal_std_p99", t->temporal_std_p99);
    add_num(o, "golden_margin", t->golden_margin >= 0 ? t->golden_margin : NAN);
    return o;
}

void *rep_stab_json(const rep_report *r)
{
    const rep_stab_report *s = r->stab;
    if (!s)
        return NULL;
    const rep_stab_run *st = &s->run;
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "epsilon", REP_STAB_EPS);
    cJSON_AddStringToObject(o, "flicker", "max over channels of |a - b| / (max(|a|,|b|) + epsilon)");
    cJSON_AddNumberToObject(o, "frames", st->frames);
    cJSON_AddStringToObject(o, "verdict", s->failed ? "FAIL" : "OK");
    cJSON_AddNumberToObject(o, "failed", s->failed);
    cJSON *px = cJSON_AddObjectToObject(o, "pixels");
    cJSON_AddNumberToObject(px, "static", (double)st->static_pixels);
    for (int c = 0; c < REP_REPRO_COUNT; c++)
        cJSON_AddNumberToObject(px, rep_repro_class_name((rep_repro_class)c), (double)st->classes[c]);
    if (s->out_dir)
        cJSON_AddStringToObject(o, "run", s->out_dir);
    else
        cJSON_AddNullToObject(o, "run");
    if (s->reference_dir)
        cJSON_AddStringToObject(o, "reference", s->reference_dir);
    else
        cJSON_AddNullToObject(o, "reference");
    cJSON *bufs = cJSON_AddArrayToObject(o, "buffers");
    for (int k = 0; k < st->buffer_count; k++) {
        const rep_stab_buffer *b = &st->buffers[k];
        const rep_stab_verdict *v = s->verdicts ? &s->verdicts[k] : NULL;
        cJSON *jb = cJSON_CreateObject();
        cJSON_AddStringToObject(jb, "name", b->name);
        cJSON_AddStringToObject(jb, "verdict", v && v->failed ? "fail" : v && v->checked ? "pass" : "unchecked");
        if (v && v->why)
            cJSON_AddStringToObject(jb, "why", v->why);
        if (v && v->checked) {
            cJSON *lim = limits_json(&v->tol);
            cJSON_AddStringToObject(lim, "match", v->tol_match);
            cJSON_AddItemToObject(jb, "limits", lim);
        }
        cJSON_AddNumberToObject(jb, "pairs", b->pairs);
        cJSON_AddItemToObject(jb, "static", stats_json(&b->st));
        cJSON_AddItemToObject(jb, "reprojected", stats_json(&b->rp));
        if (b->reference) {
            cJSON *t = cJSON_AddObjectToObject(jb, "temporal_error");
            cJSON_AddStringToObject(t, "reference", b->reference);
            cJSON_AddNumberToObject(t, "frames", b->ref_frames);
            add_num(t, "std_mean", b->tstd_mean);
            add_num(t, "std_p99", b->tstd_p99);
            add_num(t, "abs_bias_mean", b->bias_mean);
        }
        const rep_stab_buffer *g = s->has_golden ? rep_stab_find(&s->golden, b->name) : NULL;
        if (g) {
            cJSON *jg = cJSON_AddObjectToObject(jb, "golden");
            cJSON_AddItemToObject(jg, "static", stats_json(&g->st));
            cJSON_AddItemToObject(jg, "reprojected", stats_json(&g->rp));
        }
        cJSON *pf = cJSON_AddObjectToObject(jb, "per_frame");
        cJSON_AddItemToObject(pf, "static_mean", series_json(b->static_mean, st->frame_count));
        cJSON_AddItemToObject(pf, "static_p99", series_json(b->static_p99, st->frame_count));
        cJSON_AddItemToObject(pf, "reprojected_mean", series_json(b->repro_mean, st->frame_count));
        cJSON_AddItemToObject(pf, "reprojected_p99", series_json(b->repro_p99, st->frame_count));
        cJSON_AddItemToArray(bufs, jb);
    }
    return o;
}

/* ---------------------------------------------------------------- HTML */

/* One chart of a per-frame series of every buffer; returns the page-relative name or NULL. */
static char *chart(const rep_stab_run *st, const char *dir, const char *leaf, const char *title, int reprojected)
{
    plot_chart c;
    memset(&c, 0, sizeof c);
    c.title = title;
    c.x_label = "frame";
    c.y_label = "mean flicker";
    double *x = rep_xmalloc((size_t)st->frame_count * sizeof *x);
    for (int i = 0; i < st->frame_count; i++)
        x[i] = i;
    int finite = 0;
    for (int k = 0; k < st->buffer_count && c.series_count < PLOT_MAX_SERIES; k++) {
        const rep_stab_buffer *b = &st->buffers[k];
        plot_series *s = &c.series[c.series_count++];
        s->label = b->name;
        s->x = x;
        s->y = reprojected ? b->repro_mean : b->static_mean;
        s->count = st->frame_count;
        s->style = PLOT_LINES_POINTS;
        for (int i = 0; i < st->frame_count; i++)
            finite += isfinite(s->y[i]);
    }
    char *rel = NULL;
    if (finite) {
        rel = rep_xprintf("img/%s", leaf);
        char *path = rep_path_join(dir, rel);
        eng_error err;
        if (plot_xy(path, &c, &err) != ENG_OK) {
            free(rel);
            rel = NULL;
        }
        free(path);
    }
    free(x);
    return rel;
}

static void cell(rep_sb *sb, double v)
{
    if (isfinite(v))
        rep_sb_printf(sb, "<td>%.3g</td>", v);
    else
        rep_sb_printf(sb, "<td>–</td>");
}

void rep_stab_charts(const rep_report *r, const char *dir, char *rel[2])
{
    rel[0] = rel[1] = NULL;
    if (!r->stab)
        return;
    rel[0] = chart(&r->stab->run, dir, "stability-static.png", "Static-pixel flicker per pass", 0);
    rel[1] = chart(&r->stab->run, dir, "stability-reprojected.png", "Reprojected flicker per pass", 1);
}

void rep_stab_html(rep_sb *sb, const rep_report *r, char *const charts[2])
{
    const rep_stab_report *s = r->stab;
    if (!s)
        return;
    const rep_stab_run *st = &s->run;
    rep_sb_printf(sb, "<section id=\"stability\"><h2>Temporal stability (%s)</h2>\n", s->failed ? "FAIL" : "OK");
    rep_sb_printf(sb, "<p>Flicker of a pixel between consecutive frames: max over channels of |Δ| / (max(|a|,|b|) + %g). "
                      "<b>Static</b>: surface pixels whose G-buffer (position, normal, material) is bit-identical. "
                      "<b>Reprojected</b>: history found through gbuffer.motion, accepted only where the previous "
                      "G-buffer shows the same surface point (disocclusions and moving objects masked). "
                      "Surface pixels over the sequence: %llu static",
                  REP_STAB_EPS, (unsigned long long)st->static_pixels);
    for (int c = 0; c < REP_REPRO_COUNT; c++)
        if (c != REP_REPRO_BACKGROUND)
            rep_sb_printf(sb, ", %llu %s", (unsigned long long)st->classes[c], rep_repro_class_name((rep_repro_class)c));
    rep_sb_printf(sb, ".</p>\n<table class=\"all\"><thead><tr><th>buffer</th><th>verdict</th><th>static mean</th>"
                      "<th>static p99</th><th>static changed</th><th>reprojected mean</th><th>reprojected p99</th>"
                      "<th>reprojected changed</th><th>golden static / reprojected mean</th><th>temporal std mean / p99 "
                      "vs reference</th><th>why</th></tr></thead><tbody>\n");
    for (int k = 0; k < st->buffer_count; k++) {
        const rep_stab_buffer *b = &st->buffers[k];
        const rep_stab_verdict *v = s->verdicts ? &s->verdicts[k] : NULL;
        rep_sb_printf(sb, "<tr class=\"%s\"><td><code>", v && v->failed ? "fail" : "ok");
        rep_sb_xml(sb, b->name);
        rep_sb_printf(sb, "</code></td><td>%s</td>", v && v->failed ? "FAIL" : v && v->checked ? "pass" : "unchecked");
        cell(sb, b->st.mean);
        cell(sb, b->st.p99);
        rep_sb_printf(sb, "<td>%llu / %llu</td>", (unsigned long long)b->st.changed, (unsigned long long)b->st.pixels);
        cell(sb, b->rp.mean);
        cell(sb, b->rp.p99);
        rep_sb_printf(sb, "<td>%llu / %llu</td>", (unsigned long long)b->rp.changed, (unsigned long long)b->rp.pixels);
        const rep_stab_buffer *g = s->has_golden ? rep_stab_find(&s->golden, b->name) : NULL;
        if (g)
            rep_sb_printf(sb, "<td>%.3g / %.3g</td>", g->st.mean, g->rp.mean);
        else
            rep_sb_printf(sb, "<td>–</td>");
        if (b->reference)
            rep_sb_printf(sb, "<td>%.3g / %.3g</td>", b->tstd_mean, b->tstd_p99);
        else
            rep_sb_printf(sb, "<td>–</td>");
        rep_sb_printf(sb, "<td>");
        rep_sb_xml(sb, v && v->why ? v->why : "");
        rep_sb_printf(sb, "</td></tr>\n");
    }
    rep_sb_printf(sb, "</tbody></table>\n");
    const char *c1 = charts[0], *c2 = charts[1];
    rep_sb_printf(sb, "<div class=\"previews\">");
    for (char *const *c = charts; c < charts + 2; c++) {
        if (!*c)
            continue;
        rep_sb_printf(sb, "<a href=\"");
        rep_sb_xml(sb, *c);
        rep_sb_printf(sb, "\"><img src=\"");
        rep_sb_xml(sb, *c);
        rep_sb_printf(sb, "\" width=\"450\" alt=\"flicker per pass over frames\"></a>");
    }
    if (!c1 && !c2)
        rep_sb_printf(sb, "<p>No chart: fewer than two frames measured.</p>");
    rep_sb_printf(sb, "</div>\n");
    if (s->out_dir)
        rep_sb_printf(sb, "<p>Per-pixel flicker (stability.&lt;pass&gt;, −1 where a pixel has no valid history) is "
                          "a run of its own: <a href=\"stability/manifest.json\">stability/</a> "
                          "(<code>ispm-view stability</code>).</p>\n");
    rep_sb_printf(sb, "</section>\n");
}
