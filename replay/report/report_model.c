/* report_model.c — the report model: one replay's result as entries (one per buffer of a frame)
 * and what every writer reads off them alike.
 *
 * An entry's rank orders the reports worst first: size mismatches, then failures, warnings,
 * differences within tolerance; inside each, the largest error first, non-finite and missing
 * buffers counting as infinite, then frame and manifest order. The model also owns the words
 * the writers share (an entry's report.txt line with why it failed, the run's verdict word)
 * and the XML escaping of report.junit.xml and report.html, so that no writer needs another.
 * The report's entries, strings, stability report, provenance and kept parts are owned by
 * rep_report and freed whole by rep_report_free.
 */
#include "flip.h"
#include "rep_compare.h"
#include "rep_report.h"
#include "rep_run.h"
#include "rep_stab.h" /* rep_stab_report_free, the stability verdict's count */
#include "rep_util.h"

#include <fnmatch.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

rep_entry *rep_report_add(rep_report *r, int frame, const char *buffer)
{
    if (r->count == r->cap) {
        r->cap = r->cap ? r->cap * 2 : 64;
        r->entries = rep_xrealloc(r->entries, r->cap * sizeof *r->entries);
    }
    rep_entry *e = &r->entries[r->count++];
    memset(e, 0, sizeof *e);
    e->frame = frame;
    e->buffer = rep_xstrdup(buffer);
    return e;
}

void rep_report_display_warnings(rep_report *r, const rep_run *run, const rep_run *gold)
{
    const rep_run *sides[2] = {run, gold};
    for (int s = 0; s < 2; s++)
        for (int f = 0; sides[s] && f < sides[s]->frame_count; f++) {
            const char *t = sides[s]->frames[f].display_warning;
            if (!t)
                continue;
            r->display_warnings = rep_xrealloc(r->display_warnings,
                                               (size_t)(r->display_warning_count + 1) * sizeof *r->display_warnings);
            rep_display_warning *w = &r->display_warnings[r->display_warning_count++];
            w->golden = s;
            w->frame = f;
            w->text = rep_xstrdup(t);
        }
}

void rep_report_tol_warnings(rep_report *r, const rep_tolerances *t, const rep_run *gold)
{
    for (int i = 0; t && gold && i < t->rule_count; i++) {
        int found = 0;
        for (int f = 0; f < gold->frame_count && !found; f++)
            for (int b = 0; b < gold->frames[f].buffer_count && !found; b++)
                found = fnmatch(t->rules[i].match, gold->frames[f].buffers[b].name, 0) == 0;
        if (found)
            continue;
        r->tol_warnings = rep_xrealloc(r->tol_warnings, (size_t)(r->tol_warning_count + 1) * sizeof *r->tol_warnings);
        r->tol_warnings[r->tol_warning_count++] =
            rep_xprintf("%s: rule \"%s\" matches no buffer of the golden", t->path ? t->path : "tolerances",
                        t->rules[i].match);
    }
}

void rep_report_free(rep_report *r)
{
    for (size_t i = 0; i < r->count; i++) {
        free(r->entries[i].buffer);
        free(r->entries[i].tol_match);
        free(r->entries[i].run_shape);
        free(r->entries[i].golden_shape);
    }
    free(r->entries);
    for (int i = 0; i < r->display_warning_count; i++)
        free(r->display_warnings[i].text);
    free(r->display_warnings);
    for (int i = 0; i < r->tol_warning_count; i++)
        free(r->tol_warnings[i]);
    free(r->tol_warnings);
    free(r->digest_buffer);
    free(r->tol_path);
    free(r->run_renderer);
    free(r->golden_renderer);
    free(r->renderer_set);
    free(r->renderer_set_dir);
    r->renderer_set = r->renderer_set_dir = NULL;
    rep_stab_report_free(r->stab);
    r->stab = NULL;
    rep_prov_free(r->prov);
    r->prov = NULL;
    rep_keep_free(r->keep);
    r->keep = NULL;
    rep_expect_outcome_free(r->expect);
    r->expect = NULL;
    free(r->flags_text);
    free(r->scope_text);
    r->flags_text = r->scope_text = NULL;
    r->entries = NULL;
    r->digest_buffer = NULL;
    r->tol_path = NULL;
    r->run_renderer = r->golden_renderer = NULL;
    r->count = r->cap = 0;
}

rep_exit rep_report_exit(const rep_report *r)
{
    rep_exit x = REP_OK;
    for (size_t i = 0; i < r->count; i++) {
        rep_exit e = REP_OK;
        if (r->entries[i].expected)
            continue; /* an expected failure does not fail the run */
        switch (r->entries[i].verdict) {
        case REP_V_SIZE: e = REP_SIZE; break;
        case REP_V_FAIL: e = REP_FAIL; break;
        case REP_V_WARN: e = REP_WARN; break;
        default: break;
        }
        if (e > x)
            x = e;
    }
    if (r->stab && r->stab->failed && x < REP_FAIL)
        x = REP_FAIL;
    if (r->prov && (r->prov->fail || r->prov->timing_failed) && x < REP_FAIL)
        x = REP_FAIL;
    if (r->prov && r->prov->warn && x < REP_WARN)
        x = REP_WARN;
    if (r->expect && (r->expect->unexpected_count || r->expect->expired_count) && x < REP_WARN)
        x = REP_WARN;
    return x;
}

const char *rep_exit_word(rep_exit x)
{
    switch (x) {
    case REP_OK: return "OK";
    case REP_WARN: return "WARN";
    case REP_FAIL: return "FAIL";
    case REP_SIZE: return "SIZE MISMATCH";
    case REP_UNREADABLE: return "UNREADABLE";
    case REP_UNWRITABLE: return "REPORT NOT WRITTEN";
    }
    return "UNREADABLE";
}

/* Expected failures rank below warnings (known) and above differences within tolerance. */
static int rank(const rep_entry *e)
{
    if (e->expected)
        return 5;
    switch (e->verdict) {
    case REP_V_SIZE: return 10;
    case REP_V_FAIL: return 8;
    case REP_V_WARN: return 6;
    case REP_V_WITHIN: return 4;
    case REP_V_CHECKED: return 2;
    default: return 0;
    }
}

static double severity(const rep_entry *e)
{
    if (e->problem != REP_PROB_NONE || (e->m.fail_why & REP_WHY_NONFINITE))
        return INFINITY;
    return e->m.max_abs;
}

static int worst_first(const void *pa, const void *pb)
{
    const rep_entry *a = *(const rep_entry *const *)pa, *b = *(const rep_entry *const *)pb;
    if (rank(a) != rank(b))
        return rank(b) - rank(a);
    double sa = severity(a), sb = severity(b);
    if (sa != sb)
        return sa < sb ? 1 : -1;
    if (a->frame != b->frame)
        return a->frame - b->frame;
    return a < b ? -1 : a > b; /* entries sit in manifest order: keep it */
}

int rep_entry_failed(const rep_entry *e)
{
    return (e->verdict == REP_V_FAIL || e->verdict == REP_V_SIZE) && !e->expected;
}

const rep_entry *rep_report_worst_block(const rep_report *r)
{
    const rep_entry *w = NULL;
    for (size_t i = 0; i < r->count; i++) {
        const rep_entry *e = &r->entries[i];
        if (e->compared && e->m.block_size > 0 && e->m.block_abs.x >= 0 &&
            (!w || e->m.block_abs.value > w->m.block_abs.value))
            w = e;
    }
    return w;
}

void rep_block_text(rep_sb *sb, const rep_entry *e)
{
    if (!e || e->m.block_size <= 0 || e->m.block_abs.x < 0)
        return;
    const rep_metrics *m = &e->m;
    rep_sb_printf(sb, "worst %d×%d block: frame %d %s (%d,%d) %d×%d mean |Δ| %.3g", m->block_size, m->block_size,
                  e->frame, e->buffer, m->block_abs.x, m->block_abs.y, m->block_abs.w, m->block_abs.h,
                  m->block_abs.value);
    if (m->block_rel.x >= 0)
        rep_sb_printf(sb, " (worst relative %.3g at (%d,%d))", m->block_rel.value, m->block_rel.x, m->block_rel.y);
}

int rep_entry_listed(const rep_entry *e)
{
    return e->verdict != REP_V_BITEXACT && e->verdict != REP_V_CHECKED;
}

const rep_entry **rep_report_sorted(const rep_report *r, size_t *n)
{
    const rep_entry **order = rep_xcalloc(r->count, sizeof *order);
    for (size_t i = 0; i < r->count; i++)
        order[i] = &r->entries[i];
    qsort(order, r->count, sizeof *order, worst_first);
    *n = r->count;
    return order;
}

/* "3.25%", or where two decimals would round to 0.00% "1/25600 px": a failing pixel is never shown
 * as none. */
static void share_text(rep_sb *sb, uint64_t count, uint64_t of, double percent, const char *unit)
{
    if (count && percent < 0.005)
        rep_sb_printf(sb, "%llu/%llu %s", (unsigned long long)count, (unsigned long long)of, unit);
    else
        rep_sb_printf(sb, "%.2f%%", percent);
}

static void why_text(rep_sb *sb, unsigned why, const rep_metrics *m, int fail, const rep_tol *t)
{
    if (why & REP_WHY_HARD)
        rep_sb_printf(sb, "  over %s %g", fail ? "hardfail" : "hardwarn", fail ? t->hardfail : t->hardwarn);
    if (why & REP_WHY_RMSE)
        rep_sb_printf(sb, "  rmse over %g", fail ? t->rmse_fail : t->rmse_warn);
    if (why & REP_WHY_EXACT)
        rep_sb_printf(sb, "  exact: %llu values differ", (unsigned long long)m->values_differing);
    if (why & REP_WHY_FLIP)
        rep_sb_printf(sb, "  FLIP over flip_mean_fail %g / flip_p99_fail %g", t->flip_mean_fail, t->flip_p99_fail);
    if (why & REP_WHY_BLOCK)
        rep_sb_printf(sb, "  block over %s %g / %s %g", fail ? "block_fail" : "block_warn", fail ? t->block_fail : t->block_warn,
                      fail ? "block_failrelative" : "block_warnrelative",
                      fail ? t->block_failrelative : t->block_warnrelative);
}

/* "  FLIP mean 0.0123 p99 0.2 (HDR)" for a colour buffer (flip.h). */
static void flip_text(rep_sb *sb, const rep_entry *e)
{
    if (e->flip_kind != REP_FLIP_NONE)
        rep_sb_printf(sb, "  FLIP mean %.3g p99 %.3g (%s)", e->flip.mean, e->flip.p99,
                      e->flip_kind == REP_FLIP_HDR ? "HDR" : "LDR");
}

void rep_report_line(rep_sb *sb, const rep_report *r, const rep_entry *e)
{
    const rep_metrics *m = &e->m;
    const char *tag = "PASS";
    if (e->verdict == REP_V_SIZE)
        tag = "SIZE";
    else if (e->problem == REP_PROB_MISSING || e->problem == REP_PROB_FRAME_MISSING)
        tag = "MISS";
    else if (e->problem == REP_PROB_EXTRA || e->problem == REP_PROB_FRAME_EXTRA)
        tag = "EXTRA";
    else if (m->fail_why & REP_WHY_NONFINITE)
        tag = (m->run_nan || m->golden_nan) ? "NAN" : "INF";
    else if (e->expected)
        tag = "XFAIL";
    else if (e->verdict == REP_V_FAIL)
        tag = "FAIL";
    else if (e->verdict == REP_V_WARN)
        tag = "WARN";
    rep_sb_printf(sb, "%-5s frame %d  %-22s ", tag, e->frame, e->buffer);
    const char *reason = rep_entry_expect_reason(r, e);
    const char *problem = NULL;
    switch (e->problem) {
    case REP_PROB_MISSING: problem = "in golden, missing from run"; break;
    case REP_PROB_EXTRA: problem = "in run, not in golden"; break;
    case REP_PROB_FRAME_MISSING: problem = "frame missing from run"; break;
    case REP_PROB_FRAME_EXTRA: problem = "frame not in golden"; break;
    case REP_PROB_NONE: break;
    }
    if (problem) {
        rep_sb_printf(sb, "%s%s%s\n", problem, reason ? "  expected failure: " : "", reason ? reason : "");
        return;
    }
    if (e->verdict == REP_V_SIZE) {
        rep_sb_printf(sb, "run %s, golden %s%s%s\n", e->run_shape ? e->run_shape : "?",
                      e->golden_shape ? e->golden_shape : "?", reason ? "  expected failure: " : "", reason ? reason : "");
        return;
    }
    if (m->fail_why & REP_WHY_NONFINITE) {
        if (!r->golden_dir) {
            rep_sb_printf(sb, "%llu NaN, %llu Inf in run (no golden) first at (%d,%d)\n",
                          (unsigned long long)m->run_nan, (unsigned long long)m->run_inf, m->nf_x, m->nf_y);
            return;
        }
        rep_sb_printf(sb, "%llu NaN, %llu Inf in run (golden %llu) first at (%d,%d).%s: run %g, golden %g",
                      (unsigned long long)m->run_nan, (unsigned long long)m->run_inf,
                      (unsigned long long)(m->golden_nan + m->golden_inf), m->nf_x, m->nf_y, m->nf_channel,
                      (double)m->nf_run, (double)m->nf_golden);
        if (m->max_x >= 0)
            rep_sb_printf(sb, "  max |Δ| %.2e at (%d,%d).%s", m->max_abs, m->max_x, m->max_y, m->max_channel);
        rep_sb_printf(sb, "%s%s\n", reason ? "  expected failure: " : "", reason ? reason : "");
        return;
    }
    if (e->photon_set)
        rep_sb_printf(sb, "photons %llu → %llu: %llu added, %llu removed, %llu changed, %llu within tolerance%s; max |Δ| %.2e%s%s",
                      (unsigned long long)e->pd.golden, (unsigned long long)e->pd.run, (unsigned long long)e->pd.added,
                      (unsigned long long)e->pd.removed, (unsigned long long)e->pd.changed,
                      (unsigned long long)e->pd.within, e->pd.unaligned ? " (too many edits to align paths)" : "",
                      m->max_abs, m->max_channel[0] ? " in " : "", m->max_channel);
    else if (m->max_x >= 0)
        rep_sb_printf(sb, "max |Δ| %.2e at (%d,%d).%s  rmse %.1e", m->max_abs, m->max_x, m->max_y,
                      m->max_channel, m->rmse);
    else
        rep_sb_printf(sb, "max |Δ| 0 (%llu values differ in bits only)", (unsigned long long)m->values_differing);
    flip_text(sb, e);
    if (m->block_size > 0 && m->block_abs.x >= 0)
        rep_sb_printf(sb, "  block %.3g at (%d,%d)", m->block_abs.value, m->block_abs.x, m->block_abs.y);
    if (e->verdict == REP_V_FAIL) {
        rep_sb_printf(sb, "  over fail ");
        share_text(sb, m->fail_pixels, m->pixels, m->fail_percent, e->photon_set ? "photons" : "px");
        rep_sb_printf(sb, " (tol fail %g, %g%%)", e->tol.fail, e->tol.failpercent);
        why_text(sb, m->fail_why, m, 1, &e->tol);
    } else if (e->verdict == REP_V_WARN) {
        rep_sb_printf(sb, "  over warn ");
        share_text(sb, m->warn_pixels, m->pixels, m->warn_percent, e->photon_set ? "photons" : "px");
        rep_sb_printf(sb, " (tol warn %g, %g%%)", e->tol.warn, e->tol.warnpercent);
        why_text(sb, m->warn_why, m, 0, &e->tol);
    } else {
        rep_sb_printf(sb, "  within tolerance (tol fail %g, %g%%)", e->tol.fail, e->tol.failpercent);
    }
    if (reason)
        rep_sb_printf(sb, "  expected failure: %s", reason);
    rep_sb_printf(sb, "\n");
}

static void fffd(rep_sb *sb)
{
    rep_sb_printf(sb, "\xEF\xBF\xBD");
}

void rep_sb_xml(rep_sb *sb, const char *s)
{
    const unsigned char *p = (const unsigned char *)s;
    while (*p) {
        unsigned c = *p;
        if (c < 0x80) {
            switch (c) {
            case '&': rep_sb_printf(sb, "&amp;"); break;
            case '<': rep_sb_printf(sb, "&lt;"); break;
            case '>': rep_sb_printf(sb, "&gt;"); break;
            case '"': rep_sb_printf(sb, "&quot;"); break;
            case '\'': rep_sb_printf(sb, "&#39;"); break;
            default:
                if (c < 0x20 && c != '\t' && c != '\n' && c != '\r')
                    fffd(sb);
                else
                    rep_sb_printf(sb, "%c", (char)c);
            }
            p++;
            continue;
        }
        /* A multi-byte UTF-8 sequence: copied only when well-formed, shortest, not a surrogate,
         * at most U+10FFFF and not one of XML's excluded U+FFFE/U+FFFF. */
        int len = c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : c >= 0xC0 ? 2 : 0;
        unsigned cp = len == 4 ? c & 0x07 : len == 3 ? c & 0x0F : c & 0x1F;
        int ok = len > 0;
        for (int i = 1; ok && i < len; i++) {
            if ((p[i] & 0xC0) != 0x80)
                ok = 0;
            else
                cp = (cp << 6) | (p[i] & 0x3F);
        }
        if (!ok) {
            fffd(sb);
            p++;
            continue;
        }
        unsigned min = len == 2 ? 0x80 : len == 3 ? 0x800 : 0x10000;
        if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF) || cp == 0xFFFE || cp == 0xFFFF) {
            fffd(sb); /* well-formed bytes, forbidden character: one replacement for the lot */
            p += len;
            continue;
        }
        rep_sb_printf(sb, "%.*s", len, (const char *)p);
        p += len;
    }
}
