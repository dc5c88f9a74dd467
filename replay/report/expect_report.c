/* expect_report.c — what expectations.json (compare/expect.c) does to a replay's report.
 *
 * A failing entry that a rule in force names becomes an expected failure: it stays in every
 * report, with the rule's reason, but does not fail the run. A buffer that a rule in force names
 * and that fails in no frame compared is an unexpected pass (the bug was fixed, or the rule is
 * too broad): a warning, so that the rule is removed before it excuses the next regression. A
 * rule past its date excuses nothing and is a warning too. A rule whose match names no buffer of
 * the run or the golden is refused when the file is loaded: such a rule is a typo or a
 * stale name, and would otherwise never tell anyone.
 */
#define _POSIX_C_SOURCE 200809L

#include "rep_compare.h"
#include "rep_report.h"
#include "rep_run.h"
#include "rep_util.h"

#include <cjson/cJSON.h>
#include <fnmatch.h>
#include <stdlib.h>
#include <string.h>

void rep_expect_outcome_free(rep_expect_outcome *x)
{
    if (!x)
        return;
    for (int i = 0; i < x->unexpected_count; i++)
        free(x->unexpected[i].buffer);
    free(x->unexpected);
    free(x->expired);
    rep_expect_free(x->set);
    free(x);
}

static int names_match(const rep_run *side, const char *glob)
{
    for (int f = 0; side && f < side->frame_count; f++)
        for (int b = 0; b < side->frames[f].buffer_count; b++)
            if (fnmatch(glob, side->frames[f].buffers[b].name, 0) == 0)
                return 1;
    return 0;
}

eng_result rep_report_expect_load(rep_report *r, const char *path, const char *golden_dir, const rep_run *run,
                                  const rep_run *gold, const char *today, eng_error *err)
{
    char *own = NULL;
    if (!path && golden_dir) {
        own = rep_path_join(golden_dir, "expectations.json");
        if (!rep_is_file(own)) {
            free(own);
            return ENG_OK;
        }
        path = own;
    }
    if (!path)
        return ENG_OK;
    if (today && !rep_date_valid(today)) {
        free(own);
        return eng_fail(err, ENG_ERR_INVALID, "today: '%s' is not a date YYYY-MM-DD", today);
    }
    rep_expectations *set = NULL;
    eng_result res = rep_expect_load(path, &set, err);
    for (int i = 0; res == ENG_OK && i < set->count; i++)
        if (!names_match(run, set->rules[i].match) && !names_match(gold, set->rules[i].match))
            res = eng_fail(err, ENG_ERR_INVALID, "%s: rules[%d]: \"match\" \"%s\" names no buffer of the run or the golden",
                           path, i, set->rules[i].match);
    free(own);
    if (res != ENG_OK) {
        rep_expect_free(set);
        return res;
    }
    r->expect = rep_xcalloc(1, sizeof *r->expect);
    r->expect->set = set;
    if (today)
        memcpy(r->expect->today, today, 11);
    else
        rep_date_today(r->expect->today);
    return ENG_OK;
}

static void note_add(rep_expect_note **v, int *n, int rule, const char *buffer)
{
    *v = rep_xrealloc(*v, (size_t)(*n + 1) * sizeof **v);
    (*v)[*n] = (rep_expect_note){rule, buffer ? rep_xstrdup(buffer) : NULL};
    (*n)++;
}

void rep_report_expect_apply(rep_report *r)
{
    rep_expect_outcome *x = r->expect;
    if (!x)
        return;
    const rep_expectations *set = x->set;
    for (int k = 0; k < set->count; k++)
        if (rep_expect_expired(&set->rules[k], x->today))
            note_add(&x->expired, &x->expired_count, k, NULL);
    for (size_t i = 0; i < r->count; i++) {
        rep_entry *e = &r->entries[i];
        if (e->verdict != REP_V_FAIL && e->verdict != REP_V_SIZE)
            continue;
        int k = rep_expect_find(set, e->buffer, r->run_renderer, x->today);
        if (k >= 0) {
            e->expected = 1;
            e->expect_rule = k;
            x->expected++;
        }
    }
    /* Unexpected passes: per buffer name that a rule in force names, in the report's order. */
    for (size_t i = 0; i < r->count; i++) {
        const rep_entry *e = &r->entries[i];
        int k = rep_expect_find(set, e->buffer, r->run_renderer, x->today);
        if (k < 0)
            continue;
        int seen = 0, failed = 0;
        for (size_t j = 0; j < r->count && !seen; j++) {
            if (strcmp(r->entries[j].buffer, e->buffer) != 0)
                continue;
            seen = j < i;
            failed |= r->entries[j].expected;
        }
        if (!seen && !failed)
            note_add(&x->unexpected, &x->unexpected_count, k, e->buffer);
    }
}

const char *rep_entry_expect_reason(const rep_report *r, const rep_entry *e)
{
    if (!e->expected || !r->expect)
        return NULL;
    return r->expect->set->rules[e->expect_rule].reason;
}

void rep_expect_text(rep_sb *sb, const rep_report *r)
{
    const rep_expect_outcome *x = r->expect;
    if (!x)
        return;
    const rep_expectations *s = x->set;
    rep_sb_printf(sb, "expectations: %s (%d rule%s, judged on %s): %d expected failure%s, %d unexpected pass%s, %d expired\n",
                  s->path, s->count, s->count == 1 ? "" : "s", x->today, x->expected, x->expected == 1 ? "" : "s",
                  x->unexpected_count, x->unexpected_count == 1 ? "" : "es", x->expired_count);
    for (int i = 0; i < x->expired_count; i++) {
        const rep_expect_rule *k = &s->rules[x->expired[i].rule];
        rep_sb_printf(sb, "  EXPIRED rules[%d] \"%s\" until %s excuses nothing: %s\n", x->expired[i].rule, k->match,
                      k->until, k->reason);
    }
    for (int i = 0; i < x->unexpected_count; i++) {
        const rep_expect_rule *k = &s->rules[x->unexpected[i].rule];
        rep_sb_printf(sb, "  UNEXPECTED PASS %s: expected to fail (rules[%d] \"%s\": %s), passes in every frame\n",
                      x->unexpected[i].buffer, x->unexpected[i].rule, k->match, k->reason);
    }
}

void *rep_expect_json(const rep_report *r)
{
    const rep_expect_outcome *x = r->expect;
    if (!x)
        return cJSON_CreateNull();
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "file", x->set->path);
    cJSON_AddStringToObject(o, "today", x->today);
    cJSON_AddNumberToObject(o, "expected_failures", x->expected);
    cJSON *rules = cJSON_AddArrayToObject(o, "rules");
    for (int i = 0; i < x->set->count; i++) {
        const rep_expect_rule *k = &x->set->rules[i];
        cJSON *j = cJSON_CreateObject();
        cJSON_AddStringToObject(j, "match", k->match);
        cJSON_AddStringToObject(j, "reason", k->reason);
        if (k->until[0])
            cJSON_AddStringToObject(j, "until", k->until);
        if (k->renderer)
            cJSON_AddStringToObject(j, "renderer", k->renderer);
        cJSON_AddBoolToObject(j, "expired", rep_expect_expired(k, x->today));
        cJSON_AddBoolToObject(j, "applies", rep_expect_applies(k, r->run_renderer));
        cJSON_AddItemToArray(rules, j);
    }
    cJSON *up = cJSON_AddArrayToObject(o, "unexpected_passes");
    for (int i = 0; i < x->unexpected_count; i++) {
        cJSON *j = cJSON_CreateObject();
        cJSON_AddStringToObject(j, "buffer", x->unexpected[i].buffer);
        cJSON_AddNumberToObject(j, "rule", x->unexpected[i].rule);
        cJSON_AddStringToObject(j, "reason", x->set->rules[x->unexpected[i].rule].reason);
        cJSON_AddItemToArray(up, j);
    }
    cJSON *ex = cJSON_AddArrayToObject(o, "expired");
    for (int i = 0; i < x->expired_count; i++) {
        const rep_expect_rule *k = &x->set->rules[x->expired[i].rule];
        cJSON *j = cJSON_CreateObject();
        cJSON_AddNumberToObject(j, "rule", x->expired[i].rule);
        cJSON_AddStringToObject(j, "match", k->match);
        cJSON_AddStringToObject(j, "until", k->until);
        cJSON_AddItemToArray(ex, j);
    }
    return o;
}
