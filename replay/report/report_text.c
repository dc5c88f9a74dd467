/* report_text.c — what replay tells people and machines in text: report.txt, the summary, and
 * report.json.
 *
 * The text is for a person scanning a CI log: a header saying what was compared, then one line
 * per buffer that is not bit-exact, worst first (the model's order and lines), then one verdict
 * line. report.json carries the same results per frame and per buffer with every metric and
 * the tolerance applied, for tools. Both are strings; report_write.c writes them to files.
 */
#include "flip.h"
#include "rep_compare.h"
#include "rep_report.h"
#include "rep_stab.h"
#include "rep_util.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int is_failure(const rep_entry *e)
{
    return rep_entry_failed(e);
}

/* Failed entries that are expected failures. */
static size_t expected_count(const rep_report *r)
{
    size_t n = 0;
    for (size_t i = 0; i < r->count; i++)
        n += r->entries[i].expected != 0;
    return n;
}

char *rep_report_text(const rep_report *r, int quiet)
{
    rep_sb sb = {0};
    if (!quiet) {
        rep_sb_printf(&sb, "replay: run %s\n", r->run_dir ? r->run_dir : "(none)");
        if (r->golden_dir)
            rep_sb_printf(&sb, "        golden %s (tolerances %s%s%s)\n", r->golden_dir,
                          r->tol_path ? r->tol_path : "built-in", r->flags_text ? ", default entry overridden by " : "",
                          r->flags_text ? r->flags_text : "");
        else
            rep_sb_printf(&sb, "        no golden: integrity and non-finite values only\n");
        char *note = rep_renderer_note(r);
        if (note)
            rep_sb_printf(&sb, "        %s\n", note);
        free(note);
        rep_sb_printf(&sb, "        %d frames, %d buffers per frame\n", r->frames, r->buffers_per_frame);
        if (r->scope_text)
            rep_sb_printf(&sb, "        compared: %s only\n", r->scope_text);
        for (int i = 0; i < r->display_warning_count; i++)
            rep_sb_printf(&sb, "        display warning: %s frame %d: %s\n",
                          r->display_warnings[i].golden ? "golden" : "run", r->display_warnings[i].frame,
                          r->display_warnings[i].text);
        for (int i = 0; i < r->tol_warning_count; i++)
            rep_sb_printf(&sb, "        tolerance warning: %s\n", r->tol_warnings[i]);
        if (r->golden_dir && r->exit != REP_UNREADABLE) {
            if (r->digest_frame >= 0)
                rep_sb_printf(&sb, "        first digest difference (manifests): frame %d %s (%s)\n", r->digest_frame,
                              r->digest_buffer, r->digest_why);
            else
                rep_sb_printf(&sb, "        manifests: every digest matches the golden's\n");
        }
    }
    /* provenance first: why the pixels may differ, before how they do */
    if (r->prov && (!quiet || r->prov->fail))
        rep_prov_text(&sb, r->prov);
    rep_expect_text(&sb, r);
    /* The model's worst-first order is total (ties broken by manifest position), so the entries
     * picked from it come in the order they would sort to among themselves. */
    size_t all;
    const rep_entry **order = rep_report_sorted(r, &all);
    size_t n = 0;
    for (size_t i = 0; i < all; i++)
        if (rep_entry_listed(order[i]) && (!quiet || is_failure(order[i])))
            order[n++] = order[i];
    for (size_t i = 0; i < n; i++)
        rep_report_line(&sb, r, order[i]);
    free(order);

    if (r->exit == REP_UNREADABLE) {
        rep_sb_printf(&sb, "replay: UNREADABLE — %s\n", r->error.msg);
        return sb.s;
    }
    if (r->stab && (!quiet || r->stab->failed))
        rep_stab_text(&sb, r);
    if (r->prov && (!quiet || r->prov->timing_failed))
        rep_timing_text(&sb, r->prov);
    const rep_entry *wb = rep_report_worst_block(r);
    if (wb && r->golden_dir) {
        rep_sb_printf(&sb, "replay: ");
        rep_block_text(&sb, wb);
        rep_sb_printf(&sb, "\n");
    }
    size_t cnt[REP_V_COUNT] = {0};
    for (size_t i = 0; i < r->count; i++)
        cnt[r->entries[i].verdict] += !r->entries[i].expected; /* expected failures counted apart */
    rep_sb_printf(&sb, "replay: %s — ", rep_exit_word(r->exit));
    if (cnt[REP_V_SIZE])
        rep_sb_printf(&sb, "%zu size mismatch, ", cnt[REP_V_SIZE]);
    if (r->stab && r->stab->failed)
        rep_sb_printf(&sb, "stability: %d buffer%s over %s limits, ", r->stab->failed, r->stab->failed == 1 ? "" : "s",
                      r->stab->failed == 1 ? "its" : "their");
    if (r->expect && (r->expect->unexpected_count || r->expect->expired_count))
        rep_sb_printf(&sb, "expectations: %d unexpected pass%s, %d expired rule%s; ", r->expect->unexpected_count,
                      r->expect->unexpected_count == 1 ? "" : "es", r->expect->expired_count,
                      r->expect->expired_count == 1 ? "" : "s");
    if (r->prov && (r->prov->warn || r->prov->fail))
        rep_sb_printf(&sb, "provenance: %d difference%s %s; buffers: ", r->prov->warn + r->prov->fail,
                      r->prov->warn + r->prov->fail == 1 ? "" : "s", r->prov->fail ? "failing" : "warning");
    if (r->prov && r->prov->timing_failed)
        rep_sb_printf(&sb, "timing: %d pass%s over --timing-fail, ", r->prov->timing_failed,
                      r->prov->timing_failed == 1 ? "" : "es");
    size_t xf = expected_count(r);
    if (xf)
        rep_sb_printf(&sb, "%zu expected failure%s, ", xf, xf == 1 ? "" : "s");
    if (r->golden_dir)
        rep_sb_printf(&sb, "%zu failed, %zu warned, %zu within tolerance, %zu bit-exact (%zu buffers, %d frames)\n",
                      cnt[REP_V_FAIL], cnt[REP_V_WARN], cnt[REP_V_WITHIN], cnt[REP_V_BITEXACT], r->count, r->frames);
    else
        rep_sb_printf(&sb, "%zu failed, %zu checked (%zu buffers, %d frames; no golden: integrity and non-finite only)\n",
                      cnt[REP_V_FAIL], cnt[REP_V_CHECKED], r->count, r->frames);
    return sb.s;
}

static void add_num(cJSON *o, const char *k, double v)
{
    if (isfinite(v))
        cJSON_AddNumberToObject(o, k, v);
    else
        cJSON_AddNullToObject(o, k);
}

static void add_str(cJSON *o, const char *k, const char *v)
{
    if (v)
        cJSON_AddStringToObject(o, k, v);
    else
        cJSON_AddNullToObject(o, k);
}

static cJSON *xy(int x, int y, const char *channel)
{
    if (x < 0)
        return cJSON_CreateNull();
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "x", x);
    cJSON_AddNumberToObject(o, "y", y);
    if (channel)
        cJSON_AddStringToObject(o, "channel", channel);
    return o;
}

static cJSON *why_json(unsigned why)
{
    cJSON *a = cJSON_CreateArray();
    if (why & REP_WHY_PERCENT) cJSON_AddItemToArray(a, cJSON_CreateString("percent"));
    if (why & REP_WHY_HARD) cJSON_AddItemToArray(a, cJSON_CreateString("hard"));
    if (why & REP_WHY_RMSE) cJSON_AddItemToArray(a, cJSON_CreateString("rmse"));
    if (why & REP_WHY_NONFINITE) cJSON_AddItemToArray(a, cJSON_CreateString("nonfinite"));
    if (why & REP_WHY_EXACT) cJSON_AddItemToArray(a, cJSON_CreateString("exact"));
    if (why & REP_WHY_FLIP) cJSON_AddItemToArray(a, cJSON_CreateString("flip"));
    if (why & REP_WHY_BLOCK) cJSON_AddItemToArray(a, cJSON_CreateString("block"));
    return a;
}

static cJSON *tol_json(const rep_entry *e)
{
    const rep_tol *t = &e->tol;
    cJSON *o = cJSON_CreateObject();
    add_str(o, "match", e->tol_match);
    cJSON_AddBoolToObject(o, "exact", t->exact);
    add_num(o, "warn", t->warn);
    add_num(o, "warnrelative", t->warnrelative);
    add_num(o, "warnpercent", t->warnpercent);
    add_num(o, "hardwarn", t->hardwarn);
    add_num(o, "fail", t->fail);
    add_num(o, "failrelative", t->failrelative);
    add_num(o, "failpercent", t->failpercent);
    add_num(o, "hardfail", t->hardfail);
    add_num(o, "rmse_warn", t->rmse_warn);
    add_num(o, "rmse_fail", t->rmse_fail);
    add_num(o, "flip_mean_fail", t->flip_mean_fail);
    add_num(o, "flip_p99_fail", t->flip_p99_fail);
    cJSON *ex = cJSON_AddArrayToObject(o, "flip_exposure");
    cJSON_AddItemToArray(ex, cJSON_CreateNumber(t->flip_exposure[0]));
    cJSON_AddItemToArray(ex, cJSON_CreateNumber(t->flip_exposure[1]));
    add_num(o, "flip_ppd", t->flip_ppd > 0 ? t->flip_ppd : REP_FLIP_PPD_DEFAULT);
    add_num(o, "block_fail", t->block_fail);
    add_num(o, "block_failrelative", t->block_failrelative);
    add_num(o, "block_warn", t->block_warn);
    add_num(o, "block_warnrelative", t->block_warnrelative);
    cJSON_AddNumberToObject(o, "block_size", t->block_size > 0 ? t->block_size : REP_BLOCK_SIZE);
    return o;
}

static cJSON *block_json(const rep_block *b)
{
    if (b->x < 0)
        return cJSON_CreateNull();
    cJSON *o = cJSON_CreateObject();
    add_num(o, "value", b->value);
    cJSON_AddNumberToObject(o, "x", b->x);
    cJSON_AddNumberToObject(o, "y", b->y);
    cJSON_AddNumberToObject(o, "w", b->w);
    cJSON_AddNumberToObject(o, "h", b->h);
    return o;
}

static cJSON *metrics_json(const rep_report *r, const rep_metrics *m)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "pixels", (double)m->pixels);
    if (r->golden_dir) {
        cJSON_AddNumberToObject(o, "values_differing", (double)m->values_differing);
        add_num(o, "max_abs_error", m->max_abs);
        cJSON_AddItemToObject(o, "max_at", xy(m->max_x, m->max_y, m->max_channel));
        add_num(o, "mean_abs_error", m->mean_abs);
        add_num(o, "rmse", m->rmse);
        add_num(o, "psnr", m->psnr);
        cJSON_AddNumberToObject(o, "fail_pixels", (double)m->fail_pixels);
        add_num(o, "fail_percent", m->fail_percent);
        cJSON_AddItemToObject(o, "first_fail", xy(m->first_fail_x, m->first_fail_y, NULL));
        cJSON_AddNumberToObject(o, "warn_pixels", (double)m->warn_pixels);
        add_num(o, "warn_percent", m->warn_percent);
        if (m->block_size > 0) { /* the worst blocks (compare.c); null where nothing differs */
            cJSON *bl = cJSON_AddObjectToObject(o, "block");
            cJSON_AddNumberToObject(bl, "size", m->block_size);
            cJSON_AddItemToObject(bl, "abs", block_json(&m->block_abs));
            cJSON_AddItemToObject(bl, "relative", block_json(&m->block_rel));
        }
    }
    cJSON *rn = cJSON_AddObjectToObject(o, "run");
    cJSON_AddNumberToObject(rn, "nan", (double)m->run_nan);
    cJSON_AddNumberToObject(rn, "inf", (double)m->run_inf);
    if (r->golden_dir) {
        cJSON *gn = cJSON_AddObjectToObject(o, "golden");
        cJSON_AddNumberToObject(gn, "nan", (double)m->golden_nan);
        cJSON_AddNumberToObject(gn, "inf", (double)m->golden_inf);
        cJSON_AddNumberToObject(o, "nonfinite_mismatch", (double)m->nonfinite_mismatch);
        cJSON_AddItemToObject(o, "first_nonfinite_mismatch", xy(m->nf_x, m->nf_y, m->nf_channel));
    } else {
        cJSON_AddItemToObject(o, "first_nonfinite", xy(m->nf_x, m->nf_y, NULL));
    }
    cJSON_AddItemToObject(o, "fail_reasons", why_json(m->fail_why));
    cJSON_AddItemToObject(o, "warn_reasons", why_json(m->warn_why));
    return o;
}

static const char *problem_name(rep_problem p)
{
    switch (p) {
    case REP_PROB_MISSING: return "missing from run";
    case REP_PROB_EXTRA: return "not in golden";
    case REP_PROB_FRAME_MISSING: return "frame missing from run";
    case REP_PROB_FRAME_EXTRA: return "frame not in golden";
    case REP_PROB_NONE: break;
    }
    return NULL;
}

char *rep_report_json(const rep_report *r)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "format", "ispm-replay-report");
    cJSON_AddNumberToObject(root, "format_version", 1);
    add_str(root, "run", r->run_dir);
    add_str(root, "golden", r->golden_dir);
    add_str(root, "tolerances", r->golden_dir ? (r->tol_path ? r->tol_path : "built-in") : NULL);
    add_str(root, "tolerance_flags", r->flags_text);
    add_str(root, "scope", r->scope_text);
    if (r->golden_dir && (r->run_renderer || r->golden_renderer)) {
        cJSON *rd = cJSON_AddObjectToObject(root, "renderer");
        add_str(rd, "run", r->run_renderer);
        add_str(rd, "golden", r->golden_renderer);
        cJSON_AddBoolToObject(rd, "different", r->renderer_differs);
        add_str(rd, "set", r->renderer_set ? r->renderer_set : "canonical");
    }
    cJSON_AddStringToObject(root, "verdict", rep_exit_word(r->exit));
    cJSON_AddNumberToObject(root, "exit_code", (double)r->exit);
    if (r->exit == REP_UNREADABLE)
        cJSON_AddStringToObject(root, "error", r->error.msg);
    const rep_entry *wb = rep_report_worst_block(r);
    if (wb && r->golden_dir) {
        cJSON *w = cJSON_AddObjectToObject(root, "worst_block");
        cJSON_AddNumberToObject(w, "frame", wb->frame);
        cJSON_AddStringToObject(w, "buffer", wb->buffer);
        cJSON_AddNumberToObject(w, "size", wb->m.block_size);
        cJSON_AddNumberToObject(w, "x", wb->m.block_abs.x);
        cJSON_AddNumberToObject(w, "y", wb->m.block_abs.y);
        cJSON_AddNumberToObject(w, "w", wb->m.block_abs.w);
        cJSON_AddNumberToObject(w, "h", wb->m.block_abs.h);
        add_num(w, "value", wb->m.block_abs.value);
    } else {
        cJSON_AddNullToObject(root, "worst_block");
    }
    cJSON_AddItemToObject(root, "expectations", (cJSON *)rep_expect_json(r));
    cJSON_AddNumberToObject(root, "frame_count", r->frames);
    cJSON_AddNumberToObject(root, "buffer_count", (double)r->count);
    if (r->display_warning_count) {
        cJSON *dws = cJSON_AddArrayToObject(root, "display_warnings");
        for (int i = 0; i < r->display_warning_count; i++) {
            cJSON *o = cJSON_CreateObject();
            cJSON_AddStringToObject(o, "side", r->display_warnings[i].golden ? "golden" : "run");
            cJSON_AddNumberToObject(o, "frame", r->display_warnings[i].frame);
            cJSON_AddStringToObject(o, "warning", r->display_warnings[i].text);
            cJSON_AddItemToArray(dws, o);
        }
    }
    if (r->tol_warning_count) {
        cJSON *tws = cJSON_AddArrayToObject(root, "tolerance_warnings");
        for (int i = 0; i < r->tol_warning_count; i++)
            cJSON_AddItemToArray(tws, cJSON_CreateString(r->tol_warnings[i]));
    }
    cJSON *counts = cJSON_AddObjectToObject(root, "counts");
    size_t cnt[REP_V_COUNT] = {0};
    for (size_t i = 0; i < r->count; i++)
        cnt[r->entries[i].verdict] += !r->entries[i].expected; /* expected failures counted apart */
    for (int v = 0; v < REP_V_COUNT; v++)
        if (v != REP_V_CHECKED || !r->golden_dir)
            cJSON_AddNumberToObject(counts, rep_verdict_name((rep_verdict)v),
                                    (double)cnt[v]);
    cJSON_AddNumberToObject(counts, "expected failure", (double)expected_count(r));
    if (r->golden_dir && r->digest_frame >= 0) {
        cJSON *d = cJSON_AddObjectToObject(root, "first_digest_difference");
        cJSON_AddNumberToObject(d, "frame", r->digest_frame);
        cJSON_AddStringToObject(d, "buffer", r->digest_buffer);
        cJSON_AddStringToObject(d, "reason", r->digest_why);
    } else {
        cJSON_AddNullToObject(root, "first_digest_difference");
    }
    const rep_entry *first = NULL;
    for (size_t i = 0; i < r->count && !first; i++)
        if (rep_entry_listed(&r->entries[i]))
            first = &r->entries[i];
    if (first) {
        cJSON *d = cJSON_AddObjectToObject(root, "first_difference");
        cJSON_AddNumberToObject(d, "frame", first->frame);
        cJSON_AddStringToObject(d, "buffer", first->buffer);
        cJSON_AddStringToObject(d, "verdict", rep_verdict_name(first->verdict));
    } else {
        cJSON_AddNullToObject(root, "first_difference");
    }
    cJSON *frames = cJSON_AddArrayToObject(root, "frames");
    cJSON *bufs = NULL;
    int cur = -1;
    for (size_t i = 0; i < r->count; i++) {
        const rep_entry *e = &r->entries[i];
        if (e->frame != cur || !bufs) {
            cur = e->frame;
            cJSON *f = cJSON_CreateObject();
            cJSON_AddNumberToObject(f, "index", cur);
            bufs = cJSON_AddArrayToObject(f, "buffers");
            cJSON_AddItemToArray(frames, f);
        }
        cJSON *b = cJSON_CreateObject();
        cJSON_AddStringToObject(b, "name", e->buffer);
        cJSON_AddStringToObject(b, "verdict", rep_verdict_name(e->verdict));
        add_str(b, "problem", problem_name(e->problem));
        if (e->expected) {
            cJSON *xf = cJSON_AddObjectToObject(b, "expected_failure");
            cJSON_AddNumberToObject(xf, "rule", e->expect_rule);
            cJSON_AddStringToObject(xf, "reason", rep_entry_expect_reason(r, e));
        }
        if (e->verdict == REP_V_SIZE) {
            add_str(b, "run_shape", e->run_shape);
            add_str(b, "golden_shape", e->golden_shape);
        }
        if (e->photon_set) {
            cJSON *ps = cJSON_AddObjectToObject(b, "photon_set");
            cJSON_AddNumberToObject(ps, "run", (double)e->pd.run);
            cJSON_AddNumberToObject(ps, "golden", (double)e->pd.golden);
            cJSON_AddNumberToObject(ps, "added", (double)e->pd.added);
            cJSON_AddNumberToObject(ps, "removed", (double)e->pd.removed);
            cJSON_AddNumberToObject(ps, "changed", (double)e->pd.changed);
            cJSON_AddNumberToObject(ps, "within", (double)e->pd.within);
            cJSON_AddNumberToObject(ps, "paths_added", (double)e->pd.paths_added);
            cJSON_AddNumberToObject(ps, "paths_removed", (double)e->pd.paths_removed);
            cJSON_AddBoolToObject(ps, "aligned", !e->pd.unaligned);
        }
        if (e->compared) {
            if (r->golden_dir)
                cJSON_AddItemToObject(b, "tolerance", tol_json(e));
            cJSON_AddItemToObject(b, "metrics", metrics_json(r, &e->m));
        }
        if (e->flip_kind != REP_FLIP_NONE) { /* ꟻLIP (flip.h): 0 without computing when bit-exact */
            cJSON *fl = cJSON_AddObjectToObject(b, "flip");
            cJSON_AddStringToObject(fl, "kind", e->flip_kind == REP_FLIP_HDR ? "HDR" : "LDR");
            add_num(fl, "mean", e->flip.mean);
            add_num(fl, "p50", e->flip.p50);
            add_num(fl, "p95", e->flip.p95);
            add_num(fl, "p99", e->flip.p99);
            add_num(fl, "max", e->flip.max);
            cJSON_AddNumberToObject(fl, "exposures", e->flip.exposures);
            cJSON_AddBoolToObject(fl, "computed", e->verdict != REP_V_BITEXACT);
        }
        cJSON_AddItemToArray(bufs, b);
    }
    if (r->stab)
        cJSON_AddItemToObject(root, "stability", (cJSON *)rep_stab_json(r));
    if (r->prov) {
        cJSON_AddItemToObject(root, "provenance", (cJSON *)rep_prov_json(r->prov));
        cJSON_AddItemToObject(root, "timing", (cJSON *)rep_timing_json(r->prov));
    } else {
        cJSON_AddNullToObject(root, "provenance");
        cJSON_AddNullToObject(root, "timing");
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    char *out = rep_xprintf("%s\n", text);
    cJSON_free(text);
    return out;
}

