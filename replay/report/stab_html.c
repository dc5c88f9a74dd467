/* stab_html.c — the stability section of report.html (part of the HTML writer,
 * report_html.c): a table per measured pass and two charts of the flicker per frame, drawn
 * through plot.h into the report's img/ folder.
 */
#define _POSIX_C_SOURCE 200809L

#include "plot.h"
#include "rep_report.h"
#include "rep_stab.h"
#include "rep_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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
