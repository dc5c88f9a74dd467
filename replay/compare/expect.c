/* expect.c — expectations.json: the buffers a team knows fail, and why, so that a known-bad
 * buffer on one renderer or one method does not block CI and its fix is noticed.
 *
 * A file is a list of rules (or an object whose only key "rules" holds that list):
 *   {"match": GLOB, "expect": "fail", "reason": "...", "until": "YYYY-MM-DD", "renderer": GLOB}
 * match is an fnmatch pattern against buffer names, as in tolerances.json; reason is required
 * (an expected failure nobody can explain is a failure); until (inclusive) ends the rule, after
 * which it excuses nothing and is reported as expired; renderer is matched against the run's
 * GL renderer (the manifest's gl.renderer), so a rule can excuse a GPU's known bug without
 * excusing llvmpipe. The file is validated strictly, as tolerances.json is: a typo'd key or an
 * impossible date silently ignored would hide a regression. What the rules do to a replay is the
 * report room's (expect_report.c); here they are parsed and looked up.
 */
#define _POSIX_C_SOURCE 200809L

#include "rep_compare.h"
#include "rep_util.h"

#include <cjson/cJSON.h>
#include <fnmatch.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

int rep_date_valid(const char *s)
{
    if (!s || strlen(s) != 10 || s[4] != '-' || s[7] != '-')
        return 0;
    for (int i = 0; i < 10; i++)
        if (i != 4 && i != 7 && (s[i] < '0' || s[i] > '9'))
            return 0;
    int y = atoi(s), m = atoi(s + 5), d = atoi(s + 8);
    static const int days[12] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
    if (y < 1 || m < 1 || m > 12 || d < 1)
        return 0;
    int leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    return d <= days[m - 1] + (m == 2 && leap);
}

void rep_date_today(char out[11])
{
    time_t t = time(NULL);
    struct tm tm;
    gmtime_r(&t, &tm);
    if (strftime(out, 11, "%Y-%m-%d", &tm) != 10)
        memcpy(out, "0000-00-00", 11);
}

int rep_expect_expired(const rep_expect_rule *rule, const char *today)
{
    return rule->until[0] && strcmp(today, rule->until) > 0; /* ISO dates sort as strings */
}

int rep_expect_applies(const rep_expect_rule *rule, const char *renderer)
{
    if (!rule->renderer)
        return 1;
    return renderer && fnmatch(rule->renderer, renderer, 0) == 0;
}

int rep_expect_find(const rep_expectations *x, const char *buffer, const char *renderer, const char *today)
{
    for (int i = 0; x && i < x->count; i++) {
        const rep_expect_rule *r = &x->rules[i];
        if (rep_expect_applies(r, renderer) && !rep_expect_expired(r, today) && fnmatch(r->match, buffer, 0) == 0)
            return i;
    }
    return -1;
}

void rep_expect_free(rep_expectations *x)
{
    if (!x)
        return;
    for (int i = 0; i < x->count; i++) {
        free(x->rules[i].match);
        free(x->rules[i].reason);
        free(x->rules[i].renderer);
    }
    free(x->rules);
    free(x->path);
    free(x);
}

/* A string member that must be non-empty when present; *out gets a copy (NULL if absent). */
static eng_result text_key(const char *path, int i, const cJSON *v, const char *key, char **out, eng_error *err)
{
    if (!cJSON_IsString(v) || !v->valuestring[0])
        return eng_fail(err, ENG_ERR_INVALID, "%s: rules[%d]: \"%s\" must be a non-empty string", path, i, key);
    *out = rep_xstrdup(v->valuestring);
    return ENG_OK;
}

static eng_result parse_rule(const char *path, int i, const cJSON *jr, rep_expect_rule *r, eng_error *err)
{
    if (!cJSON_IsObject(jr))
        return eng_fail(err, ENG_ERR_INVALID, "%s: rules[%d]: must be an object", path, i);
    int expect = 0;
    eng_result res = ENG_OK;
    for (const cJSON *v = jr->child; v && res == ENG_OK; v = v->next) {
        const char *k = v->string;
        if (strcmp(k, "match") == 0) {
            res = text_key(path, i, v, k, &r->match, err);
        } else if (strcmp(k, "reason") == 0) {
            res = text_key(path, i, v, k, &r->reason, err);
        } else if (strcmp(k, "renderer") == 0) {
            res = text_key(path, i, v, k, &r->renderer, err);
        } else if (strcmp(k, "expect") == 0) {
            if (!cJSON_IsString(v) || strcmp(v->valuestring, "fail") != 0)
                res = eng_fail(err, ENG_ERR_INVALID, "%s: rules[%d]: \"expect\" must be \"fail\"", path, i);
            expect = 1;
        } else if (strcmp(k, "until") == 0) {
            if (!cJSON_IsString(v) || !rep_date_valid(v->valuestring))
                res = eng_fail(err, ENG_ERR_INVALID, "%s: rules[%d]: \"until\" must be a date YYYY-MM-DD", path, i);
            else
                memcpy(r->until, v->valuestring, 11);
        } else {
            res = eng_fail(err, ENG_ERR_INVALID, "%s: rules[%d]: unknown key \"%s\"", path, i, k);
        }
    }
    if (res != ENG_OK)
        return res;
    if (!r->match)
        return eng_fail(err, ENG_ERR_INVALID, "%s: rules[%d]: no \"match\"", path, i);
    if (!expect)
        return eng_fail(err, ENG_ERR_INVALID, "%s: rules[%d]: no \"expect\" (\"fail\")", path, i);
    if (!r->reason)
        return eng_fail(err, ENG_ERR_INVALID, "%s: rules[%d]: no \"reason\"", path, i);
    return ENG_OK;
}

eng_result rep_expect_parse(const char *path, const char *json, size_t len, rep_expectations **out, eng_error *err)
{
    *out = NULL;
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(json, len, &end, 0);
    if (!root) {
        size_t at = end && end >= json ? (size_t)(end - json) : 0;
        return eng_fail(err, ENG_ERR_PARSE, "%s: byte %zu: not valid JSON", path, at);
    }
    const cJSON *list = root;
    eng_result res = ENG_OK;
    if (cJSON_IsObject(root)) {
        for (const cJSON *v = root->child; v && res == ENG_OK; v = v->next)
            if (strcmp(v->string, "rules") != 0)
                res = eng_fail(err, ENG_ERR_INVALID, "%s: unknown key \"%s\"", path, v->string);
        list = cJSON_GetObjectItemCaseSensitive(root, "rules");
    }
    if (res == ENG_OK && !cJSON_IsArray(list))
        res = eng_fail(err, ENG_ERR_INVALID, "%s: must be a list of rules (or {\"rules\": [...]})", path);
    rep_expectations *x = rep_xcalloc(1, sizeof *x);
    if (res == ENG_OK) {
        int n = cJSON_GetArraySize(list);
        x->rules = rep_xcalloc((size_t)n + 1, sizeof *x->rules);
        for (const cJSON *jr = list->child; jr && res == ENG_OK; jr = jr->next) {
            res = parse_rule(path, x->count, jr, &x->rules[x->count], err);
            x->count++; /* a half-parsed rule is freed with the rest */
        }
    }
    cJSON_Delete(root);
    if (res != ENG_OK) {
        rep_expect_free(x);
        return res;
    }
    x->path = rep_xstrdup(path);
    *out = x;
    return ENG_OK;
}

eng_result rep_expect_load(const char *path, rep_expectations **out, eng_error *err)
{
    *out = NULL;
    char *text = NULL;
    size_t len = 0;
    eng_result r = eng_read_file(path, REP_MAX_JSON_BYTES, &text, &len, err);
    if (r != ENG_OK)
        return r;
    r = rep_expect_parse(path, text, len, out, err);
    free(text);
    return r;
}
