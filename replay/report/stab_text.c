/* stab_text.c — the stability section of report.txt and report.json (part of the text writer,
 * report_text.c): per measured pass the static and reprojected flicker, the temporal error
 * against a reference, the golden's values and the verdict, with the pixel classes of the
 * reprojection test.
 */
#include "rep_compare.h"
#include "rep_report.h"
#include "rep_stab.h"
#include "rep_util.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

static void add_num(cJSON *o, const char *k, double v)
{
    if (isfinite(v))
        cJSON_AddNumberToObject(o, k, v);
    else
        cJSON_AddNullToObject(o, k);
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
