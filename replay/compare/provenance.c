/* provenance.c — what made the run and what made the golden, compared before any pixel.
 *
 * Both manifests record how the run was made: the sequence and scene (path and content
 * digest), the resolution, frame rate and frame count, the engine settings, the tool version
 * and git revision, the GL version and renderer (which name the Mesa and LLVM releases), and the
 * determinism pins (llvmpipe's vector width and CPU caps, Embree's ISA and version, thread
 * counts). Every difference becomes one line, at one of three levels:
 *   - info: expected to differ between commits or machines without changing a pixel (tool
 *     version, git revision, command line, thread counts) or telling where a difference may come
 *     from (Mesa, LLVM, Embree, pins): reported, never judged;
 *   - warn: the inputs differ (sequence or scene content, resolution, fps, frame count, camera,
 *     any setting but the thread count): the pixels are expected to differ, and a person should
 *     know why before looking at them. With --provenance-fail these fail.
 *
 * The same manifests carry every frame's per-pass times. Timing is compared as each pass's
 * share of its frame (median over frames), so that a slower machine does not count and a pass
 * that grew at the expense of the others does: ratio = run share / golden share. A pass fails
 * only when the caller asks (timing_fail > 0) and its ratio is over that.
 */
#define _POSIX_C_SOURCE 200809L

#include "rep_compare.h"
#include "rep_util.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *rep_prov_level_name(int level)
{
    return level == REP_PROV_FAIL ? "fail" : level == REP_PROV_WARN ? "warn" : "info";
}

static void add_item(rep_prov *p, const char *key, const cJSON *a, const cJSON *b, int level)
{
    p->items = rep_xrealloc(p->items, (p->count + 1) * sizeof *p->items);
    rep_prov_item *it = &p->items[p->count++];
    it->key = rep_xstrdup(key);
    it->run = a ? cJSON_PrintUnformatted(a) : NULL;
    it->golden = b ? cJSON_PrintUnformatted(b) : NULL;
    it->level = level;
    if (level == REP_PROV_WARN)
        p->warn++;
    if (level == REP_PROV_FAIL)
        p->fail++;
}

/* The level of a difference at key (dotted path from the manifest's root). */
static int level_of(const char *key, int provenance_fail)
{
    static const char *const judged[] = {"sequence.digest", "scene.digest", "resolution", "fps",
                                         "frame_count", "camera", "settings"};
    if (strcmp(key, "settings.threads") == 0)
        return REP_PROV_INFO; /* determinism: the thread count changes no bit */
    for (size_t i = 0; i < sizeof judged / sizeof judged[0]; i++) {
        size_t n = strlen(judged[i]);
        if (strncmp(key, judged[i], n) == 0 && (key[n] == 0 || key[n] == '.'))
            return provenance_fail ? REP_PROV_FAIL : REP_PROV_WARN;
    }
    return REP_PROV_INFO;
}

/* Walks two JSON values side by side; objects key by key (run's keys, then the golden's extra
 * ones), anything else compared whole. */
static void diff(rep_prov *p, const char *key, const cJSON *a, const cJSON *b, int provenance_fail)
{
    if (!a && !b)
        return;
    if (cJSON_IsObject(a) && cJSON_IsObject(b)) {
        for (const cJSON *c = a->child; c; c = c->next) {
            char *k = rep_xprintf("%s.%s", key, c->string);
            diff(p, k, c, cJSON_GetObjectItemCaseSensitive(b, c->string), provenance_fail);
            free(k);
        }
        for (const cJSON *c = b->child; c; c = c->next)
            if (!cJSON_GetObjectItemCaseSensitive(a, c->string)) {
                char *k = rep_xprintf("%s.%s", key, c->string);
                diff(p, k, NULL, c, provenance_fail);
                free(k);
            }
        return;
    }
    if (a && b && cJSON_Compare(a, b, 1))
        return;
    add_item(p, key, a, b, level_of(key, provenance_fail));
}

/* The manifest keys compared (in this order); "frames" is timing's, the rest is not provenance. */
static const char *const KEYS[] = {"sequence", "scene", "resolution", "fps", "frame_count", "camera",
                                   "settings", "tool", "gl", "determinism"};


/* Median over the manifest's frames of pass `name`'s share of its frame's time (and of its ms,
 * and of the frame's total ms). NAN when no frame has the pass. */
static void pass_stats(const cJSON *frames, const char *name, double *share, double *ms, double *frame_ms)
{
    int n = cJSON_GetArraySize(frames), k = 0, kf = 0;
    double *s = rep_xcalloc((size_t)n + 1, sizeof *s), *m = rep_xcalloc((size_t)n + 1, sizeof *m);
    double *f = rep_xcalloc((size_t)n + 1, sizeof *f);
    for (const cJSON *fr = frames ? frames->child : NULL; fr; fr = fr->next) {
        const cJSON *passes = cJSON_GetObjectItemCaseSensitive(fr, "passes");
        double total = 0, mine = -1;
        for (const cJSON *ps = passes ? passes->child : NULL; ps; ps = ps->next) {
            const cJSON *pn = cJSON_GetObjectItemCaseSensitive(ps, "name");
            const cJSON *pm = cJSON_GetObjectItemCaseSensitive(ps, "ms");
            if (!cJSON_IsNumber(pm) || !isfinite(pm->valuedouble) || pm->valuedouble < 0)
                continue;
            total += pm->valuedouble;
            if (cJSON_IsString(pn) && strcmp(pn->valuestring, name ? name : "") == 0)
                mine = pm->valuedouble;
        }
        if (total > 0)
            f[kf++] = total;
        if (mine >= 0 && total > 0) {
            s[k] = mine / total;
            m[k++] = mine;
        }
    }
    *share = rep_median(s, k);
    *ms = rep_median(m, k);
    *frame_ms = rep_median(f, kf);
    free(s);
    free(m);
    free(f);
}

static void add_pass(rep_prov *p, const char *name)
{
    for (int i = 0; i < p->timing_count; i++)
        if (strcmp(p->timing[i].name, name) == 0)
            return;
    p->timing = rep_xrealloc(p->timing, (size_t)(p->timing_count + 1) * sizeof *p->timing);
    rep_timing_pass *t = &p->timing[p->timing_count++];
    memset(t, 0, sizeof *t);
    t->name = rep_xstrdup(name);
}

static void timing(rep_prov *p, const cJSON *ra, const cJSON *ga, double timing_fail)
{
    const cJSON *fa = cJSON_GetObjectItemCaseSensitive(ra, "frames");
    const cJSON *fb = cJSON_GetObjectItemCaseSensitive(ga, "frames");
    for (const cJSON *side = fa; side; side = side == fa ? fb : NULL)
        for (const cJSON *fr = side->child; fr; fr = fr->next) {
            const cJSON *passes = cJSON_GetObjectItemCaseSensitive(fr, "passes");
            for (const cJSON *ps = passes ? passes->child : NULL; ps; ps = ps->next) {
                const cJSON *pn = cJSON_GetObjectItemCaseSensitive(ps, "name");
                if (cJSON_IsString(pn))
                    add_pass(p, pn->valuestring);
            }
        }
    p->timing_fail = timing_fail;
    for (int i = 0; i < p->timing_count; i++) {
        rep_timing_pass *t = &p->timing[i];
        pass_stats(fa, t->name, &t->run_share, &t->run_ms, &p->run_frame_ms);
        pass_stats(fb, t->name, &t->golden_share, &t->golden_ms, &p->golden_frame_ms);
        t->ratio = t->golden_share > 0 && isfinite(t->run_share) ? t->run_share / t->golden_share : NAN;
        if (timing_fail > 0 && isfinite(t->ratio) && t->ratio > timing_fail) {
            t->failed = 1;
            p->timing_failed++;
        }
    }
}

static eng_result load(const char *dir, cJSON **out, eng_error *err)
{
    char *path = rep_path_join(dir, "manifest.json");
    eng_result r = rep_json_load(path, ENG_IN_NOFOLLOW, out, err);
    free(path);
    return r;
}

eng_result rep_prov_compare(const char *run_dir, const char *golden_dir, int provenance_fail, double timing_fail,
                            rep_prov **out, eng_error *err)
{
    *out = NULL;
    cJSON *a = NULL, *b = NULL;
    eng_result r = load(run_dir, &a, err);
    if (r == ENG_OK)
        r = load(golden_dir, &b, err);
    if (r == ENG_OK) {
        rep_prov *p = rep_xcalloc(1, sizeof *p);
        for (size_t i = 0; i < sizeof KEYS / sizeof KEYS[0]; i++)
            diff(p, KEYS[i], cJSON_GetObjectItemCaseSensitive(a, KEYS[i]),
                 cJSON_GetObjectItemCaseSensitive(b, KEYS[i]), provenance_fail);
        timing(p, a, b, timing_fail);
        *out = p;
    }
    cJSON_Delete(a);
    cJSON_Delete(b);
    return r;
}

void rep_prov_free(rep_prov *p)
{
    if (!p)
        return;
    for (size_t i = 0; i < p->count; i++) {
        free(p->items[i].key);
        cJSON_free(p->items[i].run);
        cJSON_free(p->items[i].golden);
    }
    for (int i = 0; i < p->timing_count; i++)
        free(p->timing[i].name);
    free(p->items);
    free(p->timing);
    free(p);
}

void rep_prov_line(rep_sb *sb, const rep_prov_item *it)
{
    rep_sb_printf(sb, "%-4s %s: golden %s, run %s\n", rep_prov_level_name(it->level), it->key,
                  it->golden ? it->golden : "(absent)", it->run ? it->run : "(absent)");
}

void rep_prov_text(rep_sb *sb, const rep_prov *p)
{
    if (!p->count) {
        rep_sb_printf(sb, "provenance: same sequence, scene, settings, tool, GL and pins as the golden\n");
        return;
    }
    rep_sb_printf(sb, "provenance: %zu difference%s from the golden (%d warn, %d fail; info is never judged)\n",
                  p->count, p->count == 1 ? "" : "s", p->warn, p->fail);
    for (int level = REP_PROV_FAIL; level >= REP_PROV_INFO; level--)
        for (size_t i = 0; i < p->count; i++)
            if (p->items[i].level == level) {
                rep_sb_printf(sb, "  ");
                rep_prov_line(sb, &p->items[i]);
            }
}

static void pct(rep_sb *sb, double share)
{
    if (isfinite(share))
        rep_sb_printf(sb, "%6.2f%%", 100 * share);
    else
        rep_sb_printf(sb, "%7s", "-");
}

void rep_timing_text(rep_sb *sb, const rep_prov *p)
{
    if (!p->timing_count)
        return;
    rep_sb_printf(sb, "timing: median frame %.1f ms (golden %.1f ms); pass share of the frame, run/golden%s\n",
                  p->run_frame_ms, p->golden_frame_ms,
                  p->timing_fail > 0 ? "" : " (reported only: --timing-fail RATIO judges it)");
    for (int i = 0; i < p->timing_count; i++) {
        const rep_timing_pass *t = &p->timing[i];
        rep_sb_printf(sb, "  %-5s %-12s ", t->failed ? "FAIL" : "", t->name);
        pct(sb, t->run_share);
        rep_sb_printf(sb, " vs ");
        pct(sb, t->golden_share);
        if (isfinite(t->ratio))
            rep_sb_printf(sb, "  ×%.2f", t->ratio);
        else
            rep_sb_printf(sb, "  (%s)", isfinite(t->run_share) ? "not in golden" : "not in run");
        if (isfinite(t->run_ms) && isfinite(t->golden_ms))
            rep_sb_printf(sb, "  (%.1f vs %.1f ms)", t->run_ms, t->golden_ms);
        if (t->failed)
            rep_sb_printf(sb, "  over --timing-fail %g", p->timing_fail);
        rep_sb_printf(sb, "\n");
    }
}

static void num_or_null(cJSON *o, const char *k, double v)
{
    if (isfinite(v))
        cJSON_AddNumberToObject(o, k, v);
    else
        cJSON_AddNullToObject(o, k);
}

void *rep_prov_json(const rep_prov *p)
{
    cJSON *o = cJSON_CreateObject();
    cJSON *arr = cJSON_AddArrayToObject(o, "differences");
    for (size_t i = 0; i < p->count; i++) {
        cJSON *it = cJSON_CreateObject();
        cJSON_AddStringToObject(it, "key", p->items[i].key);
        cJSON_AddStringToObject(it, "level", rep_prov_level_name(p->items[i].level));
        /* the values as JSON text: a difference may be in type as well as in value */
        if (p->items[i].golden)
            cJSON_AddStringToObject(it, "golden", p->items[i].golden);
        else
            cJSON_AddNullToObject(it, "golden");
        if (p->items[i].run)
            cJSON_AddStringToObject(it, "run", p->items[i].run);
        else
            cJSON_AddNullToObject(it, "run");
        cJSON_AddItemToArray(arr, it);
    }
    cJSON_AddNumberToObject(o, "warn", p->warn);
    cJSON_AddNumberToObject(o, "fail", p->fail);
    return o;
}

void *rep_timing_json(const rep_prov *p)
{
    cJSON *o = cJSON_CreateObject();
    num_or_null(o, "run_frame_ms", p->run_frame_ms);
    num_or_null(o, "golden_frame_ms", p->golden_frame_ms);
    if (p->timing_fail > 0)
        cJSON_AddNumberToObject(o, "timing_fail", p->timing_fail);
    else
        cJSON_AddNullToObject(o, "timing_fail");
    cJSON *arr = cJSON_AddArrayToObject(o, "passes");
    for (int i = 0; i < p->timing_count; i++) {
        const rep_timing_pass *t = &p->timing[i];
        cJSON *it = cJSON_CreateObject();
        cJSON_AddStringToObject(it, "name", t->name);
        num_or_null(it, "run_share", t->run_share);
        num_or_null(it, "golden_share", t->golden_share);
        num_or_null(it, "ratio", t->ratio);
        num_or_null(it, "run_ms", t->run_ms);
        num_or_null(it, "golden_ms", t->golden_ms);
        cJSON_AddBoolToObject(it, "failed", t->failed);
        cJSON_AddItemToArray(arr, it);
    }
    cJSON_AddNumberToObject(o, "failed", p->timing_failed);
    return o;
}

static const char *str_at(const cJSON *root, const char *obj, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(root, obj), key);
    return cJSON_IsString(v) ? v->valuestring : "?";
}

char *rep_manifest_origin(const char *dir)
{
    cJSON *m = NULL;
    eng_error ignored;
    if (load(dir, &m, &ignored) != ENG_OK)
        return rep_xprintf("%s: manifest unreadable", dir);
    char *s = rep_xprintf("sequence %s (%s, digest %s), scene digest %s, ispm %s (git %s), %s, Embree %s",
                          str_at(m, "sequence", "name"), str_at(m, "sequence", "path"), str_at(m, "sequence", "digest"),
                          str_at(m, "scene", "digest"), str_at(m, "tool", "version"), str_at(m, "tool", "git"),
                          str_at(m, "gl", "renderer"), str_at(m, "determinism", "embree_version"));
    cJSON_Delete(m);
    return s;
}
