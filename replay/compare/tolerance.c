/* tolerance.c — tolerances.json: how far each buffer of a run may stray from its golden.
 *
 * The keys follow idiff's options (-warn/-fail/-failrelative/-failpercent/-hardfail, and the
 * warn twins) plus "exact" (bit-identical or fail) and RMSE limits. A file has a "default"
 * block and an ordered "buffers" list of rules, each with an fnmatch "match" pattern; the
 * first rule that matches a buffer name wins, keys it leaves out come from "default", and
 * keys "default" leaves out from the built-in defaults. The file is validated strictly: a
 * typo'd key or a negative threshold silently falling back to a default would make a
 * regression test pass that should fail. rep_tolerances owns its patterns and path.
 *
 * A block may also hold "stability": an object of upper limits on the buffer's temporal
 * stability over the sequence (stability.c): static_mean, static_p99, reprojected_mean,
 * reprojected_p99, temporal_std_mean, temporal_std_p99 (absolute limits), and golden_margin
 * (the run may flicker at most the golden run's own value × (1 + golden_margin)). A rule's
 * stability object replaces the default's whole: limits do not merge key by key, so what a
 * rule checks is what it says.
 *
 * Local gates (compare.c): block_fail, block_failrelative, block_warn, block_warnrelative (off
 * unless set) limit the mean |Δ| of the worst block_size × block_size block (default 8); "note"
 * (a string, or an object of strings per key) says why a limit is what it is and is not read.
 *
 * Colour buffers also take ꟻLIP limits (flip.h): flip_mean_fail and flip_p99_fail (off unless set),
 * flip_exposure [start, stop] (HDR-ꟻLIP's pinned range in stops, start <= stop; default −4..4) and
 * flip_ppd (0: the papers' 67).
 *
 * A file may also hold "cross_renderer": a separate, looser set with the same "default" and
 * "buffers" keys, used instead of the rest when the run was rendered by another GL renderer
 * than the golden (a GPU through EGL against an llvmpipe golden: renderer.c). Without it such
 * a run is compared under the built-in cross-renderer defaults (rep_tol_cross_builtin).
 */
#define _POSIX_C_SOURCE 200809L

#include "flip.h"
#include "rep_compare.h"
#include "rep_util.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <fnmatch.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const char *const KEYS[] = {"warn", "warnrelative", "warnpercent", "hardwarn", "fail", "failrelative",
                                   "failpercent", "hardfail", "rmse_warn", "rmse_fail",
                                   "flip_mean_fail", "flip_p99_fail", "flip_ppd", "block_fail",
                                   "block_failrelative", "block_warn", "block_warnrelative"};
#define KEY_COUNT (sizeof KEYS / sizeof KEYS[0])

static double *field(rep_tol *t, size_t k)
{
    double *f[KEY_COUNT] = {&t->warn, &t->warnrelative, &t->warnpercent, &t->hardwarn, &t->fail,
                            &t->failrelative, &t->failpercent, &t->hardfail, &t->rmse_warn, &t->rmse_fail,
                            &t->flip_mean_fail, &t->flip_p99_fail, &t->flip_ppd, &t->block_fail,
                            &t->block_failrelative, &t->block_warn, &t->block_warnrelative};
    return f[k];
}

void rep_tol_builtin(rep_tol *t)
{
    memset(t, 0, sizeof *t);
    t->warn = 0;
    t->warnrelative = 0;
    t->warnpercent = 0;
    t->hardwarn = INFINITY;
    t->fail = 1e-4;
    t->failrelative = 1e-4;
    t->failpercent = 0;
    t->hardfail = 1e-2;
    t->rmse_warn = INFINITY;
    t->rmse_fail = INFINITY;
    t->flip_mean_fail = INFINITY;
    t->flip_p99_fail = INFINITY;
    t->flip_ppd = 0;
    t->block_fail = t->block_failrelative = t->block_warn = t->block_warnrelative = INFINITY;
    t->block_size = REP_BLOCK_SIZE;
    t->flip_exposure[0] = REP_FLIP_EXPOSURE_START;
    t->flip_exposure[1] = REP_FLIP_EXPOSURE_STOP;
    t->stab.set = 0;
    t->stab.static_mean = t->stab.static_p99 = t->stab.reprojected_mean = t->stab.reprojected_p99 = INFINITY;
    t->stab.temporal_std_mean = t->stab.temporal_std_p99 = INFINITY;
    t->stab.golden_margin = -1;
}

static const char *const STAB_KEYS[] = {"static_mean",       "static_p99",        "reprojected_mean",
                                        "reprojected_p99",   "temporal_std_mean", "temporal_std_p99",
                                        "golden_margin"};
#define STAB_KEY_COUNT (sizeof STAB_KEYS / sizeof STAB_KEYS[0])

static double *stab_field(rep_tol_stab *s, size_t k)
{
    double *f[STAB_KEY_COUNT] = {&s->static_mean,       &s->static_p99,        &s->reprojected_mean,
                                 &s->reprojected_p99,   &s->temporal_std_mean, &s->temporal_std_p99,
                                 &s->golden_margin};
    return f[k];
}

static eng_result parse_stability(const char *path, const char *where, const cJSON *obj, rep_tol_stab *s,
                                  eng_error *err)
{
    if (!cJSON_IsObject(obj))
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"stability\" must be an object", path, where);
    rep_tol b;
    rep_tol_builtin(&b);
    *s = b.stab;
    s->set = 1;
    if (!obj->child)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"stability\" sets no limit", path, where);
    for (const cJSON *v = obj->child; v; v = v->next) {
        size_t k = 0;
        while (k < STAB_KEY_COUNT && strcmp(STAB_KEYS[k], v->string) != 0)
            k++;
        if (k == STAB_KEY_COUNT)
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: stability: unknown key \"%s\"", path, where, v->string);
        if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) || v->valuedouble < 0)
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: stability: \"%s\" must be a finite number >= 0", path,
                            where, v->string);
        *stab_field(s, k) = v->valuedouble;
    }
    return ENG_OK;
}

/* Overrides t with the keys of one JSON block. allow_match: the block is a rule. */
static eng_result parse_block(const char *path, const char *where, const cJSON *obj, rep_tol *t,
                              int allow_match, unsigned *keys_set, eng_error *err)
{
    if (!cJSON_IsObject(obj))
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: must be an object", path, where);
    for (const cJSON *v = obj->child; v; v = v->next) {
        const char *key = v->string;
        if (allow_match && strcmp(key, "match") == 0)
            continue;
        if (strcmp(key, "exact") == 0) {
            if (!cJSON_IsBool(v))
                return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"exact\" must be true or false", path, where);
            t->exact = cJSON_IsTrue(v);
            continue;
        }
        if (strcmp(key, "flip_exposure") == 0) { /* HDR-ꟻLIP's pinned range: [start, stop], stops */
            const cJSON *a = cJSON_GetArrayItem(v, 0), *b = cJSON_GetArrayItem(v, 1);
            if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 2 || !cJSON_IsNumber(a) || !cJSON_IsNumber(b) ||
                !isfinite(a->valuedouble) || !isfinite(b->valuedouble) || a->valuedouble > b->valuedouble ||
                b->valuedouble - a->valuedouble > 64)
                return eng_fail(err, ENG_ERR_INVALID,
                                "%s: %s: \"flip_exposure\" must be [start, stop], finite, start <= stop, at most 64 apart",
                                path, where);
            t->flip_exposure[0] = a->valuedouble;
            t->flip_exposure[1] = b->valuedouble;
            continue;
        }
        if (strcmp(key, "note") == 0) { /* why the limits are what they are: for people, unused */
            if (!cJSON_IsString(v) && !cJSON_IsObject(v))
                return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"note\" must be a string or an object", path, where);
            for (const cJSON *n = cJSON_IsObject(v) ? v->child : NULL; n; n = n->next)
                if (!cJSON_IsString(n))
                    return eng_fail(err, ENG_ERR_INVALID, "%s: %s: note \"%s\" must be a string", path, where,
                                    n->string);
            continue;
        }
        if (strcmp(key, "block_size") == 0) {
            if (!cJSON_IsNumber(v) || !(v->valuedouble >= 1 && v->valuedouble <= 4096) ||
                v->valuedouble != floor(v->valuedouble))
                return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"block_size\" must be a whole number from 1 to 4096",
                                path, where);
            t->block_size = (int)v->valuedouble;
            continue;
        }
        if (strcmp(key, "stability") == 0) {
            eng_result r = parse_stability(path, where, v, &t->stab, err);
            if (r != ENG_OK)
                return r;
            continue;
        }
        size_t k = 0;
        while (k < KEY_COUNT && strcmp(KEYS[k], key) != 0)
            k++;
        if (k == KEY_COUNT)
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: unknown key \"%s\"", path, where, key);
        if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) || v->valuedouble < 0)
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"%s\" must be a finite number >= 0", path, where,
                            key);
        if (strstr(key, "percent") && v->valuedouble > 100)
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"%s\" is %g, a percentage of pixels (0..100)", path,
                            where, key, v->valuedouble);
        *field(t, k) = v->valuedouble;
        if (keys_set && k < 8)
            *keys_set |= 1u << k; /* KEYS' first eight are REP_FLAG_*'s order */
    }
    return ENG_OK;
}

void rep_tol_cross_builtin(rep_tol *t)
{
    rep_tol_builtin(t);
    t->warn = 1e-4;
    t->fail = 0.02;
    t->failrelative = 0.05;
    t->failpercent = 1;
    t->hardfail = INFINITY;
    t->rmse_fail = 0.02;
}

void rep_tol_free(rep_tolerances *t)
{
    if (!t)
        return;
    rep_tol_free(t->cross);
    for (int i = 0; i < t->rule_count; i++)
        free(t->rules[i].match);
    free(t->rules);
    free(t->path);
    free(t);
}

/* Whether every '[' of a glob has its ']' (fnmatch takes an unclosed '[' as a literal
 * character, so such a rule silently matches nothing). */
static int glob_well_formed(const char *g)
{
    for (const char *p = g; *p; p++) {
        if (*p == '\\' && p[1]) {
            p++;
        } else if (*p == '[') {
            const char *q = p + 1;
            if (*q == '!' || *q == '^')
                q++;
            if (*q == ']')
                q++;
            while (*q && *q != ']')
                q++;
            if (!*q)
                return 0;
            p = q;
        }
    }
    return 1;
}

/* A "cross_renderer" section, or the built-in cross-renderer set where the file has none. */
static eng_result parse_cross(const char *path, const cJSON *root, rep_tolerances *t, eng_error *err);

static eng_result parse_root(const char *path, const cJSON *root, rep_tolerances *t, eng_error *err)
{
    if (!cJSON_IsObject(root))
        return eng_fail(err, ENG_ERR_INVALID, "%s: must be a JSON object", path);
    for (const cJSON *v = root->child; v; v = v->next)
        if (strcmp(v->string, "default") != 0 && strcmp(v->string, "buffers") != 0 &&
            (t->cross || strcmp(v->string, "cross_renderer") != 0))
            return eng_fail(err, ENG_ERR_INVALID, "%s: unknown key \"%s\"", path, v->string);
    const cJSON *def = cJSON_GetObjectItemCaseSensitive(root, "default");
    eng_result r;
    if (def && (r = parse_block(path, "default", def, &t->def, 0, NULL, err)) != ENG_OK)
        return r;
    const cJSON *rules = cJSON_GetObjectItemCaseSensitive(root, "buffers");
    if (!rules)
        return ENG_OK;
    if (!cJSON_IsArray(rules))
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"buffers\" must be an array", path);
    int n = cJSON_GetArraySize(rules);
    t->rules = rep_xcalloc((size_t)n, sizeof *t->rules);
    int i = 0;
    for (const cJSON *jr = rules->child; jr; jr = jr->next, i++) {
        char where[64];
        snprintf(where, sizeof where, "buffers[%d]", i);
        const cJSON *m = cJSON_GetObjectItemCaseSensitive(jr, "match");
        if (!cJSON_IsString(m) || !m->valuestring[0])
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"match\" must be a non-empty pattern", path, where);
        if (!glob_well_formed(m->valuestring))
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"match\" \"%s\" has a '[' without its ']'", path, where,
                            m->valuestring);
        rep_tol_rule *rule = &t->rules[t->rule_count++];
        rule->match = rep_xstrdup(m->valuestring);
        rule->tol = t->def;
        if ((r = parse_block(path, where, jr, &rule->tol, 1, &rule->keys_set, err)) != ENG_OK)
            return r;
    }
    return ENG_OK;
}

static rep_tolerances *cross_builtin(void)
{
    rep_tolerances *c = rep_xcalloc(1, sizeof *c);
    rep_tol_cross_builtin(&c->def);
    return c;
}

static eng_result parse_cross(const char *path, const cJSON *root, rep_tolerances *t, eng_error *err)
{
    const cJSON *sec = cJSON_GetObjectItemCaseSensitive(root, "cross_renderer");
    t->cross = cross_builtin();
    if (!sec)
        return ENG_OK;
    /* The section starts from the built-in defaults, not the cross-renderer ones: what it
     * checks is what it says. A non-NULL cross marks it as a section (no nested one). */
    rep_tol_builtin(&t->cross->def);
    t->cross->cross = t->cross;
    char *where = rep_xprintf("%s#cross_renderer", path);
    eng_result r = parse_root(where, sec, t->cross, err);
    t->cross->cross = NULL;
    t->cross->path = where;
    return r;
}

eng_result rep_tol_parse(const char *path, const char *json, size_t len, rep_tolerances **out, eng_error *err)
{
    *out = NULL;
    rep_tolerances *t = rep_xcalloc(1, sizeof *t);
    rep_tol_builtin(&t->def);
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(json, len, &end, 0);
    eng_result r;
    if (!root) {
        size_t at = end && end >= json ? (size_t)(end - json) : 0;
        r = eng_fail(err, ENG_ERR_PARSE, "%s: byte %zu: not valid JSON", path, at);
    } else {
        r = parse_root(path, root, t, err);
        if (r == ENG_OK)
            r = parse_cross(path, root, t, err);
    }
    cJSON_Delete(root);
    if (r != ENG_OK) {
        rep_tol_free(t);
        return r;
    }
    t->path = rep_xstrdup(path);
    *out = t;
    return ENG_OK;
}

eng_result rep_tol_load(const char *path, int missing_ok, rep_tolerances **out, eng_error *err)
{
    *out = NULL;
    /* Only a file that is not there at all means the defaults: a link to nothing, a FIFO or a
     * device is a tolerance file that cannot be read. */
    struct stat st;
    if (missing_ok && lstat(path, &st) != 0 && errno == ENOENT) {
        rep_tolerances *t = rep_xcalloc(1, sizeof *t);
        rep_tol_builtin(&t->def);
        t->cross = cross_builtin();
        *out = t;
        return ENG_OK;
    }
    char *text = NULL;
    size_t len = 0;
    eng_result r = eng_read_input(path, missing_ok ? ENG_IN_NOFOLLOW : 0, REP_MAX_JSON_BYTES, &text, &len, err);
    if (r == ENG_OK)
        r = eng_json_precheck(path, text, len, ENG_JSON_MAX_DEPTH, err);
    if (r != ENG_OK) {
        free(text);
        return r;
    }
    r = rep_tol_parse(path, text, len, out, err);
    free(text);
    return r;
}

const char *rep_tol_lookup(const rep_tolerances *t, const char *buffer, rep_tol *out)
{
    for (int i = 0; i < t->rule_count; i++)
        if (fnmatch(t->rules[i].match, buffer, 0) == 0) {
            *out = t->rules[i].tol;
            return t->rules[i].match;
        }
    *out = t->def;
    return "default";
}

char *rep_tol_default_json(void)
{
    rep_tol d;
    rep_tol_builtin(&d);
    return rep_xprintf("{\n"
                       "  \"default\": {\"warn\": %g, \"fail\": %g, \"failrelative\": %g, \"failpercent\": %g, "
                       "\"hardfail\": %g},\n"
                       "  \"buffers\": []\n"
                       "}\n",
                       d.warn, d.fail, d.failrelative, d.failpercent, d.hardfail);
}

int rep_tol_flag_parse(rep_tol_flags *f, const char *name, const char *value)
{
    while (*name == '-')
        name++;
    size_t k = 0;
    while (k < 8 && strcmp(KEYS[k], name) != 0)
        k++;
    if (k == 8)
        return 0;
    char *end = NULL;
    double v = value ? strtod(value, &end) : NAN;
    if (!value || !*value || *end || !isfinite(v) || v < 0)
        return -1;
    double *slot[8] = {&f->warn, &f->warnrelative, &f->warnpercent, &f->hardwarn,
                       &f->fail, &f->failrelative, &f->failpercent, &f->hardfail};
    *slot[k] = v;
    f->set |= 1u << k;
    return 1;
}

void rep_tol_apply_flags(rep_tolerances *t, const rep_tol_flags *f)
{
    if (!f || !f->set)
        return;
    const double v[8] = {f->warn, f->warnrelative, f->warnpercent, f->hardwarn,
                         f->fail, f->failrelative, f->failpercent, f->hardfail};
    for (size_t k = 0; k < 8; k++) {
        if (!(f->set & (1u << k)))
            continue;
        *field(&t->def, k) = v[k];
        for (int i = 0; i < t->rule_count; i++)
            if (!(t->rules[i].keys_set & (1u << k)))
                *field(&t->rules[i].tol, k) = v[k];
    }
}

char *rep_tol_flags_text(const rep_tol_flags *f)
{
    if (!f || !f->set)
        return NULL;
    const double v[8] = {f->warn, f->warnrelative, f->warnpercent, f->hardwarn,
                         f->fail, f->failrelative, f->failpercent, f->hardfail};
    rep_sb sb = {0};
    for (size_t k = 0; k < 8; k++)
        if (f->set & (1u << k))
            rep_sb_printf(&sb, "%s-%s %g", sb.len ? " " : "", KEYS[k], v[k]);
    return sb.s;
}
