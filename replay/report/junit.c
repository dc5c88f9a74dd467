/* junit.c — report.junit.xml, so that a CI system (Jenkins, GitLab, GitHub test reporters)
 * shows one test case per buffer of every frame.
 *
 * The document is the common JUnit dialect: <testsuites> around one <testsuite> for the run,
 * whose counts are those of its test cases. A test case is named after the buffer; its
 * classname "ispm.<sequence>.frameNNNNNN" groups the buffers of one frame, so a CI tree reads
 * sequence → frame → buffer. What replay counts as a failure (over tolerance, size mismatch,
 * non-finite values, a missing or extra buffer or frame) is a <failure> carrying report.txt's
 * line for the entry; warnings and differences within tolerance pass and say so in
 * <system-out>; an expected failure (expectations.json) is <skipped> with the rule's reason, and
 * each unexpected pass or expired rule is a passing test case of classname
 * ispm.<sequence>.expectations that says so. The worst block is a property. An unreadable input
 * is one extra test case with <error>.
 * Every name and message passes through rep_sb_xml, so a hostile buffer name cannot make the
 * document malformed. No times are written: the output is a pure function of the report.
 */
#include "rep_compare.h"
#include "rep_report.h"
#include "rep_stab.h"
#include "rep_util.h"

#include <stdlib.h>
#include <string.h>

static const char *failure_type(const rep_entry *e)
{
    if (e->verdict == REP_V_SIZE)
        return "size";
    switch (e->problem) {
    case REP_PROB_MISSING:
    case REP_PROB_FRAME_MISSING: return "missing";
    case REP_PROB_EXTRA:
    case REP_PROB_FRAME_EXTRA: return "extra";
    case REP_PROB_NONE: break;
    }
    if (e->m.fail_why & REP_WHY_NONFINITE)
        return "nonfinite";
    return "fail";
}

/* report.txt's line for e without its trailing newline and the run of spaces that pads it. */
static char *entry_line(const rep_report *r, const rep_entry *e)
{
    rep_sb sb = {0};
    rep_report_line(&sb, r, e);
    while (sb.len > 0 && (sb.s[sb.len - 1] == '\n' || sb.s[sb.len - 1] == ' '))
        sb.s[--sb.len] = 0;
    return sb.s;
}

static void attr(rep_sb *sb, const char *name, const char *value)
{
    rep_sb_printf(sb, " %s=\"", name);
    rep_sb_xml(sb, value ? value : "");
    rep_sb_printf(sb, "\"");
}

/* One testcase: a <failure> of `type` with text when failed, else the text in <system-out>. */
static void text_case(rep_sb *sb, const char *cls, const char *name, int failed, const char *type, const char *text)
{
    rep_sb_printf(sb, "    <testcase");
    attr(sb, "classname", cls);
    attr(sb, "name", name);
    rep_sb_printf(sb, ">\n");
    if (failed) {
        rep_sb_printf(sb, "      <failure");
        attr(sb, "type", type);
        attr(sb, "message", text);
        rep_sb_printf(sb, ">");
        rep_sb_xml(sb, text);
        rep_sb_printf(sb, "</failure>\n");
    } else {
        rep_sb_printf(sb, "      <system-out>");
        rep_sb_xml(sb, text);
        rep_sb_printf(sb, "</system-out>\n");
    }
    rep_sb_printf(sb, "    </testcase>\n");
}

/* The manifests compared, as two test cases of classname ispm.<suite>.manifest: provenance
 * (every difference in its output; a failure only under --provenance-fail) and timing. */
static void prov_cases_xml(rep_sb *sb, const rep_prov *p, const char *sname)
{
    char *cls = rep_xprintf("%s.manifest", sname);
    rep_sb t = {0};
    rep_prov_text(&t, p);
    text_case(sb, cls, "provenance", p->fail > 0, "provenance", t.s);
    free(t.s);
    t = (rep_sb){0};
    rep_timing_text(&t, p);
    text_case(sb, cls, "timing", p->timing_failed > 0, "timing", t.s ? t.s : "no per-pass times");
    free(t.s);
    free(cls);
}

char *rep_report_junit(const rep_report *r, const char *suite)
{
    size_t failures = 0, errors = r->exit == REP_UNREADABLE ? 1 : 0;
    size_t skipped = 0;
    for (size_t i = 0; i < r->count; i++) {
        failures += rep_entry_failed(&r->entries[i]) != 0;
        skipped += r->entries[i].expected != 0;
    }
    size_t expect_cases = r->expect ? (size_t)(r->expect->unexpected_count + r->expect->expired_count) : 0;
    /* Buffers with stability limits are test cases too (classname ispm.<suite>.stability). */
    size_t checked = 0;
    for (int k = 0; r->stab && r->stab->verdicts && k < r->stab->run.buffer_count; k++)
        checked += r->stab->verdicts[k].checked;
    failures += r->stab ? (size_t)r->stab->failed : 0;
    size_t prov_cases = r->prov ? 2 : 0; /* provenance and timing, before the buffers */
    if (r->prov)
        failures += (r->prov->fail ? 1 : 0) + (r->prov->timing_failed ? 1 : 0);
    size_t tests = r->count + errors + checked + prov_cases + expect_cases;
    char *sname = rep_xprintf("ispm.%s", suite);

    rep_sb sb = {0};
    rep_sb_printf(&sb, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    rep_sb_printf(&sb, "<testsuites name=\"ispm replay\" tests=\"%zu\" failures=\"%zu\" errors=\"%zu\" skipped=\"%zu\">\n",
                  tests, failures, errors, skipped);
    rep_sb_printf(&sb, "  <testsuite");
    attr(&sb, "name", sname);
    rep_sb_printf(&sb, " tests=\"%zu\" failures=\"%zu\" errors=\"%zu\" skipped=\"%zu\">\n", tests, failures, errors,
                  skipped);
    rep_sb_printf(&sb, "    <properties>\n");
    const char *props[][2] = {
        {"run", r->run_dir},
        {"golden", r->golden_dir ? r->golden_dir : "(none: integrity and non-finite values only)"},
        {"tolerances", r->golden_dir ? (r->tol_path ? r->tol_path : "built-in") : "(none)"},
        {"verdict", rep_exit_word(r->exit)},
    };
    for (size_t i = 0; i < sizeof props / sizeof props[0]; i++) {
        rep_sb_printf(&sb, "      <property");
        attr(&sb, "name", props[i][0]);
        attr(&sb, "value", props[i][1]);
        rep_sb_printf(&sb, "/>\n");
    }
    const rep_entry *wb = r->golden_dir ? rep_report_worst_block(r) : NULL;
    if (wb) {
        rep_sb w = {0};
        rep_block_text(&w, wb);
        rep_sb_printf(&sb, "      <property name=\"worst_block\"");
        attr(&sb, "value", w.s);
        rep_sb_printf(&sb, "/>\n");
        free(w.s);
    }
    rep_sb_printf(&sb, "    </properties>\n");

    if (r->exit == REP_UNREADABLE) {
        rep_sb_printf(&sb, "    <testcase");
        attr(&sb, "classname", sname);
        rep_sb_printf(&sb, " name=\"replay\">\n      <error type=\"unreadable\"");
        attr(&sb, "message", r->error.msg);
        rep_sb_printf(&sb, ">");
        rep_sb_xml(&sb, r->error.msg);
        rep_sb_printf(&sb, "</error>\n    </testcase>\n");
    }
    if (r->prov)
        prov_cases_xml(&sb, r->prov, sname);
    for (size_t i = 0; i < r->count; i++) {
        const rep_entry *e = &r->entries[i];
        char *cls = rep_xprintf("%s.frame%06d", sname, e->frame);
        rep_sb_printf(&sb, "    <testcase");
        attr(&sb, "classname", cls);
        attr(&sb, "name", e->buffer);
        free(cls);
        if (!rep_entry_listed(e)) {
            rep_sb_printf(&sb, "/>\n");
            continue;
        }
        char *text = entry_line(r, e);
        rep_sb_printf(&sb, ">\n");
        if (e->expected) {
            char *msg = rep_xprintf("expected failure: %s", rep_entry_expect_reason(r, e));
            rep_sb_printf(&sb, "      <skipped");
            attr(&sb, "message", msg);
            rep_sb_printf(&sb, "/>\n      <system-out>");
            rep_sb_xml(&sb, text);
            rep_sb_printf(&sb, "</system-out>\n");
            free(msg);
        } else if (e->verdict == REP_V_FAIL || e->verdict == REP_V_SIZE) {
            rep_sb_printf(&sb, "      <failure");
            attr(&sb, "type", failure_type(e));
            attr(&sb, "message", text);
            rep_sb_printf(&sb, ">");
            rep_sb_xml(&sb, text);
            rep_sb_printf(&sb, "</failure>\n");
        } else {
            rep_sb_printf(&sb, "      <system-out>");
            rep_sb_xml(&sb, text);
            rep_sb_printf(&sb, "</system-out>\n");
        }
        rep_sb_printf(&sb, "    </testcase>\n");
        free(text);
    }
    if (expect_cases) {
        char *cls = rep_xprintf("%s.expectations", sname);
        const rep_expect_outcome *x = r->expect;
        for (int i = 0; i < x->unexpected_count; i++) {
            const rep_expect_rule *k = &x->set->rules[x->unexpected[i].rule];
            char *name = rep_xprintf("unexpected pass: %s", x->unexpected[i].buffer);
            char *t = rep_xprintf("%s passes in every frame but rules[%d] \"%s\" of %s expects it to fail: %s",
                                  x->unexpected[i].buffer, x->unexpected[i].rule, k->match, x->set->path, k->reason);
            text_case(&sb, cls, name, 0, NULL, t);
            free(name);
            free(t);
        }
        for (int i = 0; i < x->expired_count; i++) {
            const rep_expect_rule *k = &x->set->rules[x->expired[i].rule];
            char *name = rep_xprintf("expired: rules[%d] %s", x->expired[i].rule, k->match);
            char *t = rep_xprintf("rules[%d] \"%s\" of %s expired on %s and excuses nothing: %s", x->expired[i].rule,
                                  k->match, x->set->path, k->until, k->reason);
            text_case(&sb, cls, name, 0, NULL, t);
            free(name);
            free(t);
        }
        free(cls);
    }
    for (int k = 0; checked && k < r->stab->run.buffer_count; k++) {
        const rep_stab_verdict *v = &r->stab->verdicts[k];
        if (!v->checked)
            continue;
        char *cls = rep_xprintf("%s.stability", sname);
        rep_sb_printf(&sb, "    <testcase");
        attr(&sb, "classname", cls);
        attr(&sb, "name", r->stab->run.buffers[k].name);
        free(cls);
        if (!v->failed) {
            rep_sb_printf(&sb, "/>\n");
            continue;
        }
        rep_sb_printf(&sb, ">\n      <failure type=\"stability\"");
        attr(&sb, "message", v->why);
        rep_sb_printf(&sb, ">");
        rep_sb_xml(&sb, v->why);
        rep_sb_printf(&sb, "</failure>\n    </testcase>\n");
    }
    rep_sb_printf(&sb, "  </testsuite>\n</testsuites>\n");
    free(sname);
    return sb.s;
}
