/* suggest.c — tolerances from evidence: ispm tolerances suggest RUN... --golden DIR -o FILE.
 *
 * A tolerance is a claim that some difference is acceptable; here the claim is made from runs a
 * person already judged acceptable (other seeds, another renderer, a change that was reviewed),
 * instead of guessed. Every run is replayed against the golden under the base tolerances (the
 * golden's, or --tolerances), whose per-pixel thresholds (fail, failrelative, warn,
 * warnrelative) are kept: they define what a failing pixel is, and failpercent is measured under
 * them. For every buffer, each buffer-level limit becomes the largest value any run and frame
 * measured, times the margin, rounded up to three significant digits; the rule's note names the
 * run and frame that set each limit, so that the next person to loosen it knows what they are
 * arguing with. Runs made by another GL renderer than the golden's fill the cross_renderer
 * section, which replay uses for such runs (report/renderer.c). Stability limits are not
 * suggested: they come from the sequence, not from a pair of images.
 */
#define _POSIX_C_SOURCE 200809L

#include "rep_regress.h"
#include "rep.h"
#include "rep_compare.h"
#include "rep_report.h"
#include "rep_util.h"
#include "replay_internal.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { L_HARDFAIL, L_FAILPERCENT, L_WARNPERCENT, L_RMSE, L_BLOCK, L_BLOCKREL, L_FLIPMEAN, L_FLIPP99, L_COUNT };
static const char *const LIMIT_KEYS[L_COUNT] = {"hardfail",   "failpercent",        "warnpercent",    "rmse_fail",
                                                "block_fail", "block_failrelative", "flip_mean_fail", "flip_p99_fail"};

/* One buffer of one section: the largest value of each measure, where it was seen. */
typedef struct sbuf {
    char *name;
    rep_tol base;        /* the base rule the runs were compared under */
    int differs, flip;   /* some run not bit-exact; ꟻLIP measured */
    double v[L_COUNT];
    const char *run[L_COUNT];
    int frame[L_COUNT];
} sbuf;

typedef struct section {
    int count, cap;
    sbuf *b;
    int runs;
} section;

static sbuf *find_or_add(section *s, const char *name, const rep_tol *base)
{
    for (int i = 0; i < s->count; i++)
        if (strcmp(s->b[i].name, name) == 0)
            return &s->b[i];
    if (s->count == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 32;
        s->b = rep_xrealloc(s->b, (size_t)s->cap * sizeof *s->b);
    }
    sbuf *b = &s->b[s->count++];
    memset(b, 0, sizeof *b);
    b->name = rep_xstrdup(name);
    b->base = *base;
    for (int k = 0; k < L_COUNT; k++)
        b->frame[k] = -1;
    return b;
}

static void see(sbuf *b, int k, double v, const char *run, int frame)
{
    if (isfinite(v) && (b->frame[k] < 0 || v > b->v[k])) {
        b->v[k] = v;
        b->run[k] = run;
        b->frame[k] = frame;
    }
}

double rep_suggest_round(double v, double margin)
{
    double x = v * margin;
    if (!(x > 0))
        return 0;
    double unit = pow(10.0, floor(log10(x)) - 2);
    double r = ceil(x / unit) * unit;
    char text[64];
    for (int i = 0; i < 4; i++) {
        snprintf(text, sizeof text, "%.3g", r);
        if (strtod(text, NULL) >= x)
            return strtod(text, NULL);
        r += unit;
    }
    return r;
}

/* A buffer name as an fnmatch pattern that matches only it. */
static char *literal_glob(const char *name)
{
    rep_sb sb = {0};
    rep_sb_printf(&sb, "%s", "");
    for (const char *p = name; *p; p++)
        rep_sb_printf(&sb, strchr("*?[]\\", *p) ? "\\%c" : "%c", *p);
    return sb.s;
}

static cJSON *rule_json(const sbuf *b, double margin)
{
    cJSON *o = cJSON_CreateObject();
    char *glob = literal_glob(b->name);
    cJSON_AddStringToObject(o, "match", glob);
    free(glob);
    if (!b->differs) {
        cJSON_AddBoolToObject(o, "exact", 1);
        cJSON_AddStringToObject(o, "note", "bit-exact in every run");
        return o;
    }
    const rep_tol *t = &b->base;
    cJSON_AddNumberToObject(o, "warn", t->warn);
    cJSON_AddNumberToObject(o, "warnrelative", t->warnrelative);
    cJSON_AddNumberToObject(o, "fail", t->fail);
    cJSON_AddNumberToObject(o, "failrelative", t->failrelative);
    cJSON *note = cJSON_CreateObject();
    for (int k = 0; k < L_COUNT; k++) {
        if ((k == L_FLIPMEAN || k == L_FLIPP99) && !b->flip)
            continue;
        if ((k == L_BLOCK || k == L_BLOCKREL) && b->frame[k] < 0)
            continue;
        double lim = rep_suggest_round(b->v[k], margin);
        if ((k == L_FAILPERCENT || k == L_WARNPERCENT) && lim > 100)
            lim = 100; /* every pixel: the margin cannot go further */
        cJSON_AddNumberToObject(o, LIMIT_KEYS[k], lim);
        char *why = b->frame[k] >= 0 ? rep_xprintf("%.4g in %s frame %d, x %g", b->v[k], b->run[k], b->frame[k], margin)
                                     : rep_xstrdup("not measured");
        cJSON_AddStringToObject(note, LIMIT_KEYS[k], why);
        free(why);
    }
    if (t->flip_exposure[0] != REP_FLIP_EXPOSURE_START || t->flip_exposure[1] != REP_FLIP_EXPOSURE_STOP) {
        cJSON *ex = cJSON_AddArrayToObject(o, "flip_exposure");
        cJSON_AddItemToArray(ex, cJSON_CreateNumber(t->flip_exposure[0]));
        cJSON_AddItemToArray(ex, cJSON_CreateNumber(t->flip_exposure[1]));
    }
    if (t->flip_ppd > 0)
        cJSON_AddNumberToObject(o, "flip_ppd", t->flip_ppd);
    if (t->block_size != REP_BLOCK_SIZE)
        cJSON_AddNumberToObject(o, "block_size", t->block_size);
    cJSON_AddItemToObject(o, "note", note);
    return o;
}

/* A section ("default" and "buffers") of the file. */
static cJSON *section_json(const section *s, const rep_tol *def, const char *origin, double margin)
{
    cJSON *o = cJSON_CreateObject();
    cJSON *d = cJSON_AddObjectToObject(o, "default");
    cJSON_AddNumberToObject(d, "warn", def->warn);
    cJSON_AddNumberToObject(d, "warnrelative", def->warnrelative);
    cJSON_AddNumberToObject(d, "fail", def->fail);
    cJSON_AddNumberToObject(d, "failrelative", def->failrelative);
    cJSON_AddNumberToObject(d, "failpercent", def->failpercent);
    if (isfinite(def->hardfail))
        cJSON_AddNumberToObject(d, "hardfail", def->hardfail);
    cJSON_AddStringToObject(d, "note", origin);
    cJSON *rules = cJSON_AddArrayToObject(o, "buffers");
    for (int i = 0; i < s->count; i++)
        cJSON_AddItemToArray(rules, rule_json(&s->b[i], margin));
    return o;
}

static void section_free(section *s)
{
    for (int i = 0; i < s->count; i++)
        free(s->b[i].name);
    free(s->b);
}

/* Measures one run's entries into its section; refuses what no tolerance can pass. */
static eng_result measure(const rep_report *r, const char *run, section *s, eng_error *err)
{
    for (size_t i = 0; i < r->count; i++) {
        const rep_entry *e = &r->entries[i];
        const char *why = e->verdict == REP_V_SIZE ? "a different size or channel set"
                        : e->problem == REP_PROB_MISSING || e->problem == REP_PROB_FRAME_MISSING ? "missing from the run"
                        : e->problem == REP_PROB_EXTRA || e->problem == REP_PROB_FRAME_EXTRA ? "not in the golden"
                        : e->m.fail_why & REP_WHY_NONFINITE ? "a non-finite value changed class"
                        : NULL;
        if (why)
            return eng_fail(err, ENG_ERR_UNSUPPORTED, "%s: frame %d %s: %s: no tolerance makes it pass", run, e->frame,
                            e->buffer, why);
        if (!e->compared)
            continue;
        sbuf *b = find_or_add(s, e->buffer, &e->tol);
        if (e->verdict == REP_V_BITEXACT)
            continue;
        b->differs = 1;
        see(b, L_HARDFAIL, e->m.max_abs, run, e->frame);
        see(b, L_FAILPERCENT, e->m.fail_percent, run, e->frame);
        see(b, L_WARNPERCENT, e->m.warn_percent, run, e->frame);
        see(b, L_RMSE, e->m.rmse, run, e->frame);
        if (e->m.block_size > 0 && e->m.block_abs.x >= 0) {
            see(b, L_BLOCK, e->m.block_abs.value, run, e->frame);
            see(b, L_BLOCKREL, e->m.block_rel.value, run, e->frame);
        }
        if (e->flip_kind != REP_FLIP_NONE) {
            b->flip = 1;
            see(b, L_FLIPMEAN, e->flip.mean, run, e->frame);
            see(b, L_FLIPP99, e->flip.p99, run, e->frame);
        }
    }
    return ENG_OK;
}

eng_result rep_tol_suggest(const rep_suggest_options *o, FILE *summary, eng_error *err)
{
    if (!o || o->run_count < 1 || !o->golden_dir || !o->out_path)
        return eng_fail(err, ENG_ERR_INVALID, "tolerances suggest: runs, a golden and an output file are needed");
    if (!(o->margin >= 1) || !isfinite(o->margin))
        return eng_fail(err, ENG_ERR_INVALID, "tolerances suggest: margin %g: must be a number >= 1", o->margin);
    rep_tolerances *base = NULL;
    char *tpath = o->tolerances ? rep_xstrdup(o->tolerances) : rep_path_join(o->golden_dir, "tolerances.json");
    eng_result res = rep_tol_load(tpath, o->tolerances == NULL, &base, err);
    section same = {0}, cross = {0};
    for (int i = 0; res == ENG_OK && i < o->run_count; i++) {
        rep_options ro;
        memset(&ro, 0, sizeof ro);
        ro.run_dir = o->runs[i];
        ro.golden_dir = o->golden_dir;
        ro.tolerances = o->tolerances;
        ro.no_files = 1;
        rep_report r;
        if (rep_replay_report(&ro, &r, err) == REP_UNREADABLE) {
            res = ENG_ERR_IO; /* the run, the golden or a file of theirs: err names it */
        } else {
            section *s = r.renderer_differs ? &cross : &same;
            s->runs++;
            res = measure(&r, o->runs[i], s, err);
        }
        rep_report_free(&r);
    }
    if (res == ENG_OK) {
        rep_sb origin = {0};
        rep_sb_printf(&origin, "ispm tolerances suggest, margin %g, from", o->margin);
        for (int i = 0; i < o->run_count; i++)
            rep_sb_printf(&origin, " %s", o->runs[i]);
        rep_sb_printf(&origin, " against %s; pixel thresholds from %s", o->golden_dir,
                      base->path ? base->path : "the built-in defaults");
        cJSON *root = same.runs ? section_json(&same, &base->def, origin.s, o->margin) : cJSON_CreateObject();
        if (!same.runs) { /* only cross-renderer evidence: the golden's own renderer keeps the base default */
            cJSON *d = cJSON_AddObjectToObject(root, "default");
            cJSON_AddNumberToObject(d, "fail", base->def.fail);
            cJSON_AddNumberToObject(d, "failrelative", base->def.failrelative);
            cJSON_AddStringToObject(d, "note", origin.s);
        }
        if (cross.runs)
            cJSON_AddItemToObject(root, "cross_renderer", section_json(&cross, &base->cross->def, origin.s, o->margin));
        char *text = cJSON_Print(root);
        cJSON_Delete(root);
        char *out = rep_xprintf("%s\n", text);
        cJSON_free(text);
        res = rep_write_atomic(o->out_path, out, strlen(out), err);
        free(out);
        free(origin.s);
        if (res == ENG_OK && summary) {
            int exact = 0;
            for (int i = 0; i < same.count; i++)
                exact += !same.b[i].differs;
            fprintf(summary, "tolerances suggest: %s: %d buffer rules (%d bit-exact) from %d run%s", o->out_path,
                    same.count, exact, same.runs, same.runs == 1 ? "" : "s");
            if (cross.runs)
                fprintf(summary, ", cross_renderer: %d rules from %d run%s", cross.count, cross.runs,
                        cross.runs == 1 ? "" : "s");
            fprintf(summary, ", margin %g\n", o->margin);
        }
    }
    section_free(&same);
    section_free(&cross);
    rep_tol_free(base);
    free(tpath);
    return res;
}
