/* test_replay.c — the replay module's Check suite.
 *
 * Three tiers: pure logic (tolerance files, the per-buffer comparison on small synthetic
 * arrays, where every verdict rule and the non-finite rule are pinned down), the OIIO shim
 * round trip, and end-to-end replays of fixture runs. The capture module is built in parallel,
 * so fixture runs are made here: frames written with rep_oiio_write_parts, manifests with
 * cJSON and eng_buffer_digest, in the layout capture writes. Each end-to-end test damages a
 * copy of a good run in exactly one way and checks the exit code and what the report names.
 * Tests check result codes and report fields, never message text.
 */
#define _XOPEN_SOURCE 700

#include <check.h>
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cap.h"
#include "rep.h"
#include "replay_internal.h"
#include "rep_util.h"

#include <openexr.h>

/* ---------------------------------------------------------------- helpers */

static char g_tmp[4096];

static void tmp_setup(void)
{
    const char *base = getenv("TMPDIR");
    snprintf(g_tmp, sizeof g_tmp, "%s/ispm-test-replay-XXXXXX", base && base[0] ? base : "/tmp");
    ck_assert_ptr_nonnull(mkdtemp(g_tmp));
}

static void tmp_teardown(void)
{
    rep_remove_tree(g_tmp, NULL);
}

static char *tpath(const char *name)
{
    return rep_path_join(g_tmp, name);
}

/* A buffer of a fixture run. */
typedef struct fx_buf {
    char name[64];
    int w, h, nch;
    const char *ch[4];
    float *data;
} fx_buf;

typedef struct fx_frame {
    int count;
    fx_buf bufs[8];
} fx_frame;

#define FX_FRAMES 3

typedef struct fx_run {
    int frames;
    fx_frame f[FX_FRAMES];
} fx_run;

static void fx_set(fx_buf *b, const char *name, int w, int h, const char *c0, const char *c1, const char *c2,
                   unsigned seed)
{
    free(b->data);
    snprintf(b->name, sizeof b->name, "%s", name);
    b->w = w;
    b->h = h;
    b->ch[0] = c0;
    b->ch[1] = c1;
    b->ch[2] = c2;
    b->nch = c2 ? 3 : c1 ? 2 : 1;
    b->data = malloc(sizeof(float) * (size_t)(w * h * b->nch));
    ck_assert_ptr_nonnull(b->data);
    for (int i = 0; i < w * h * b->nch; i++)
        b->data[i] = 0.25f + (float)((i * 37u + seed * 101u) % 97u) / 97.0f;
}

static void fx_make(fx_run *r)
{
    memset(r, 0, sizeof *r);
    r->frames = FX_FRAMES;
    for (int i = 0; i < FX_FRAMES; i++) {
        fx_frame *f = &r->f[i];
        f->count = 3;
        fx_set(&f->bufs[0], "gbuffer.position", 8, 6, "X", "Y", "Z", (unsigned)(10 * i + 1));
        fx_set(&f->bufs[1], "direct.radiance", 8, 6, "R", "G", "B", (unsigned)(10 * i + 2));
        fx_set(&f->bufs[2], "shadow.light0", 4, 4, "Z", NULL, NULL, (unsigned)(10 * i + 3));
    }
}

static void fx_free(fx_run *r)
{
    for (int i = 0; i < FX_FRAMES; i++)
        for (int j = 0; j < 8; j++)
            free(r->f[i].bufs[j].data);
}

static eng_buffer fx_view(const fx_buf *b)
{
    eng_buffer e = {b->name, b->w, b->h, b->nch, b->ch, b->data};
    return e;
}

static float *fx_at(fx_run *r, int frame, int buf, int x, int y, int c)
{
    fx_buf *b = &r->f[frame].bufs[buf];
    return &b->data[((size_t)y * (size_t)b->w + (size_t)x) * (size_t)b->nch + (size_t)c];
}

/* Writes frames/NNNNNN.exr and manifest.json (unless no_manifest) into dir. */
static void fx_write_ex(const fx_run *r, const char *dir, int complete, int no_manifest)
{
    eng_error err = {{0}};
    char *frames = rep_path_join(dir, "frames");
    ck_assert_int_eq(rep_mkdirs(frames, &err), ENG_OK);
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "format", "ispm-run");
    cJSON_AddNumberToObject(root, "format_version", 1);
    cJSON *tool = cJSON_AddObjectToObject(root, "tool");
    cJSON_AddStringToObject(tool, "name", "ispm");
    cJSON_AddStringToObject(tool, "version", "0.1.0");
    cJSON_AddStringToObject(tool, "git", "test");
    cJSON_AddStringToObject(root, "command", "test_replay");
    cJSON *seq = cJSON_AddObjectToObject(root, "sequence");
    cJSON_AddStringToObject(seq, "path", "fixture.json");
    cJSON_AddStringToObject(seq, "name", "fixture");
    cJSON_AddStringToObject(seq, "digest", "00000000000000000000000000000000");
    cJSON *res = cJSON_AddArrayToObject(root, "resolution");
    cJSON_AddItemToArray(res, cJSON_CreateNumber(8));
    cJSON_AddItemToArray(res, cJSON_CreateNumber(6));
    cJSON_AddNumberToObject(root, "fps", 8);
    cJSON_AddNumberToObject(root, "frame_count", r->frames);
    cJSON_AddStringToObject(root, "camera", "Camera");
    cJSON *jframes = cJSON_AddArrayToObject(root, "frames");
    for (int i = 0; i < r->frames; i++) {
        const fx_frame *f = &r->f[i];
        char file[64], *path;
        snprintf(file, sizeof file, "frames/%06d.exr", i);
        path = rep_path_join(dir, file);
        eng_buffer views[8];
        cJSON *jf = cJSON_CreateObject();
        cJSON_AddNumberToObject(jf, "index", i);
        cJSON_AddNumberToObject(jf, "time", i / 8.0);
        cJSON_AddStringToObject(jf, "file", file);
        cJSON *jb = cJSON_AddArrayToObject(jf, "buffers");
        for (int j = 0; j < f->count; j++) {
            views[j] = fx_view(&f->bufs[j]);
            char dg[40];
            uint64_t nn, ni;
            int fx, fy;
            eng_buffer_digest(&views[j], dg);
            eng_buffer_nonfinite(&views[j], &nn, &ni, &fx, &fy);
            cJSON *b = cJSON_CreateObject();
            cJSON_AddStringToObject(b, "name", f->bufs[j].name);
            cJSON_AddNumberToObject(b, "width", f->bufs[j].w);
            cJSON_AddNumberToObject(b, "height", f->bufs[j].h);
            cJSON *ch = cJSON_AddArrayToObject(b, "channels");
            for (int c = 0; c < f->bufs[j].nch; c++)
                cJSON_AddItemToArray(ch, cJSON_CreateString(f->bufs[j].ch[c]));
            cJSON_AddStringToObject(b, "digest", dg);
            cJSON_AddNumberToObject(b, "nan", (double)nn);
            cJSON_AddNumberToObject(b, "inf", (double)ni);
            if (fx < 0) {
                cJSON_AddNullToObject(b, "first_nonfinite");
            } else {
                cJSON *p = cJSON_AddArrayToObject(b, "first_nonfinite");
                cJSON_AddItemToArray(p, cJSON_CreateNumber(fx));
                cJSON_AddItemToArray(p, cJSON_CreateNumber(fy));
            }
            cJSON_AddItemToArray(jb, b);
        }
        cJSON_AddItemToArray(jframes, jf);
        ck_assert_msg(rep_oiio_write_parts(path, views, f->count, &err) == ENG_OK, "%s", err.msg);
        free(path);
    }
    cJSON_AddBoolToObject(root, "complete", complete);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!no_manifest) {
        char *mp = rep_path_join(dir, "manifest.json");
        ck_assert_int_eq(rep_write_atomic(mp, text, strlen(text), &err), ENG_OK);
        free(mp);
    }
    cJSON_free(text);
    free(frames);
}

static void fx_write(const fx_run *r, const char *dir)
{
    fx_write_ex(r, dir, 1, 0);
}

/* Writes an unmodified fixture to <tmp>/golden and returns its path. */
static char *make_golden(void)
{
    fx_run g;
    fx_make(&g);
    char *dir = tpath("golden");
    fx_write(&g, dir);
    fx_free(&g);
    return dir;
}

static rep_exit replay(const char *run, const char *golden, eng_error *err)
{
    rep_options o = {0};
    o.run_dir = run;
    o.golden_dir = golden;
    o.quiet = 1;
    return rep_replay(&o, NULL, err);
}

static cJSON *load_json(const char *path)
{
    char *text = NULL;
    size_t len = 0;
    eng_error err;
    ck_assert_msg(eng_read_file(path, 1 << 24, &text, &len, &err) == ENG_OK, "%s", err.msg);
    cJSON *j = cJSON_Parse(text);
    free(text);
    ck_assert_ptr_nonnull(j);
    return j;
}

static cJSON *report_of(const char *run)
{
    char *dir = rep_path_join(run, "replay");
    char *p = rep_path_join(dir, "report.json");
    cJSON *j = load_json(p);
    free(p);
    free(dir);
    return j;
}

/* The buffer entry for (frame, name) in report.json, or NULL. */
static const cJSON *report_entry(const cJSON *rep, int frame, const char *name)
{
    const cJSON *frames = cJSON_GetObjectItem(rep, "frames");
    const cJSON *f;
    cJSON_ArrayForEach(f, frames)
    {
        if ((int)cJSON_GetObjectItem(f, "index")->valuedouble != frame)
            continue;
        const cJSON *b;
        cJSON_ArrayForEach(b, cJSON_GetObjectItem(f, "buffers"))
        if (strcmp(cJSON_GetObjectItem(b, "name")->valuestring, name) == 0)
            return b;
    }
    return NULL;
}

static const char *str_of(const cJSON *o, const char *k)
{
    const cJSON *v = cJSON_GetObjectItem(o, k);
    ck_assert_msg(cJSON_IsString(v), "key %s is not a string", k);
    return v->valuestring;
}

static double num_of(const cJSON *o, const char *k)
{
    const cJSON *v = cJSON_GetObjectItem(o, k);
    ck_assert_msg(cJSON_IsNumber(v), "key %s is not a number", k);
    return v->valuedouble;
}

/* ---------------------------------------------------------------- tolerances */

static rep_tolerances *parse_tol(const char *json, eng_result expect)
{
    rep_tolerances *t = NULL;
    eng_error err = {{0}};
    eng_result r = rep_tol_parse("tol.json", json, strlen(json), &t, &err);
    ck_assert_msg(r == expect, "got %s (%s), expected %s", eng_result_name(r), err.msg, eng_result_name(expect));
    return t;
}

START_TEST(tol_first_match_wins_and_defaults_fill)
{
    rep_tolerances *t = parse_tol("{\"default\": {\"fail\": 0.5, \"warn\": 0.1},"
                                  " \"buffers\": ["
                                  "  {\"match\": \"gbuffer.*\", \"exact\": true},"
                                  "  {\"match\": \"gbuffer.position\", \"fail\": 7},"
                                  "  {\"match\": \"direct.radiance\", \"fail\": 1e-5, \"failpercent\": 0.05,"
                                  "   \"rmse_fail\": 1e-5}]}",
                                  ENG_OK);
    rep_tol tol;
    ck_assert_str_eq(rep_tol_lookup(t, "gbuffer.position", &tol), "gbuffer.*");
    ck_assert_int_eq(tol.exact, 1);
    ck_assert_double_eq(tol.fail, 0.5); /* from "default", not from the later rule */
    ck_assert_str_eq(rep_tol_lookup(t, "direct.radiance", &tol), "direct.radiance");
    ck_assert_int_eq(tol.exact, 0);
    ck_assert_double_eq(tol.fail, 1e-5);
    ck_assert_double_eq(tol.failpercent, 0.05);
    ck_assert_double_eq(tol.rmse_fail, 1e-5);
    ck_assert_double_eq(tol.warn, 0.1);         /* from "default" */
    ck_assert_double_eq(tol.hardfail, 1e-2);    /* built-in */
    ck_assert_double_eq(tol.failrelative, 1e-4);
    ck_assert(isinf(tol.rmse_warn));
    ck_assert_str_eq(rep_tol_lookup(t, "shadow.light0", &tol), "default");
    ck_assert_double_eq(tol.fail, 0.5);
    rep_tol_free(t);
}
END_TEST

START_TEST(tol_flags_override_default_and_inherited_keys)
{
    rep_tol_flags f;
    memset(&f, 0, sizeof f);
    ck_assert_int_eq(rep_tol_flag_parse(&f, "-fail", "3"), 1);
    ck_assert_int_eq(rep_tol_flag_parse(&f, "--hardwarn", "0.5"), 1);
    ck_assert_int_eq(rep_tol_flag_parse(&f, "failpercent", "2"), 1);
    ck_assert_int_eq(rep_tol_flag_parse(&f, "-fail", "abc"), -1);
    ck_assert_int_eq(rep_tol_flag_parse(&f, "-fail", "-1"), -1);
    ck_assert_int_eq(rep_tol_flag_parse(&f, "-fail", "inf"), -1);
    ck_assert_int_eq(rep_tol_flag_parse(&f, "-golden", "1"), 0);
    ck_assert_uint_eq(f.set, REP_FLAG_FAIL | REP_FLAG_HARDWARN | REP_FLAG_FAILPERCENT);
    char *text = rep_tol_flags_text(&f);
    ck_assert_str_eq(text, "-hardwarn 0.5 -fail 3 -failpercent 2");
    free(text);
    rep_tolerances *t = parse_tol("{\"default\": {\"fail\": 0.5, \"failpercent\": 1},"
                                  " \"buffers\": [{\"match\": \"a*\", \"fail\": 0.2}, {\"match\": \"b*\", \"warn\": 0.1}]}",
                                  ENG_OK);
    rep_tol_apply_flags(t, &f);
    rep_tol tol;
    rep_tol_lookup(t, "zzz", &tol);
    ck_assert_double_eq(tol.fail, 3);
    ck_assert_double_eq(tol.failpercent, 2);
    ck_assert_double_eq(tol.hardwarn, 0.5);
    rep_tol_lookup(t, "a1", &tol); /* the rule's own fail stays; what it inherited is replaced */
    ck_assert_double_eq(tol.fail, 0.2);
    ck_assert_double_eq(tol.failpercent, 2);
    rep_tol_lookup(t, "b1", &tol);
    ck_assert_double_eq(tol.fail, 3);
    ck_assert_double_eq(tol.warn, 0.1);
    rep_tol_free(t);
}
END_TEST

START_TEST(progress_plain_lines_with_time_left)
{
    FILE *f = tmpfile();
    ck_assert_ptr_nonnull(f);
    rep_progress p;
    rep_progress_begin(&p, f, "ispm test", "frame", 4);
    rep_progress_step(&p, 1, NULL);
    rep_progress_step(&p, 2, "detail here");
    rep_progress_end(&p);
    rep_progress_begin(&p, NULL, "silent", "frame", 4); /* no stream: nothing, no crash */
    rep_progress_step(&p, 1, NULL);
    rep_progress_end(&p);
    rewind(f);
    char line[256];
    ck_assert_ptr_nonnull(fgets(line, sizeof line, f));
    ck_assert_ptr_nonnull(strstr(line, "ispm test: frame 1/4  elapsed "));
    ck_assert_ptr_nonnull(strstr(line, " left "));
    ck_assert_ptr_null(strchr(line, '\r')); /* not a terminal: plain lines */
    ck_assert_ptr_nonnull(fgets(line, sizeof line, f));
    ck_assert_ptr_nonnull(strstr(line, "frame 2/4"));
    ck_assert_ptr_nonnull(strstr(line, "detail here\n"));
    ck_assert_ptr_null(fgets(line, sizeof line, f));
    fclose(f);
}
END_TEST

/* A photon map of `paths` paths of 1 + (p % 3) photons (bounces 2, 3, ...), extra inserted
 * before path `at` when extra >= 0; width 16. */
static float *photon_map(int paths, int at, int extra_len, int *rows)
{
    int n = 0;
    for (int p = 0; p < paths; p++)
        n += 1 + p % 3;
    n += at >= 0 ? extra_len : 0;
    *rows = (n + 15) / 16;
    float *d = calloc((size_t)*rows * 16 * 14, sizeof *d);
    ck_assert_ptr_nonnull(d);
    int i = 0;
    for (int p = 0; p <= paths; p++) {
        if (p == at)
            for (int k = 0; k < extra_len; k++, i++) {
                for (int c = 0; c < 13; c++)
                    d[i * 14 + c] = 1000.0f + (float)(k * 13 + c);
                d[i * 14 + 13] = (float)(2 + k);
            }
        if (p == paths)
            break;
        for (int k = 0; k <= p % 3; k++, i++) {
            for (int c = 0; c < 13; c++)
                d[i * 14 + c] = (float)(p * 7 + k) + 0.01f * (float)c;
            d[i * 14 + 13] = (float)(2 + k);
        }
    }
    return d;
}

START_TEST(photon_map_compared_as_paths)
{
    static const char *const ch[14] = {"position.X", "position.Y", "position.Z", "direction.X", "direction.Y",
                                       "direction.Z", "power.R",    "power.G",    "power.B",     "normal.X",
                                       "normal.Y",   "normal.Z",   "density",    "bounce"};
    int gr, rr;
    float *g = photon_map(100, -1, 0, &gr), *r = photon_map(100, 40, 3, &rr);
    eng_buffer gb = {"photons.map", 16, gr, 14, ch, g}, rb = {"photons.map", 16, rr, 14, ch, r};
    ck_assert(rep_is_photon_map(&gb));
    rep_tol tol;
    rep_tol_builtin(&tol);
    rep_metrics m;
    rep_photon_diff pd;
    /* identical: bit-exact */
    ck_assert_int_eq(rep_photon_compare(&gb, &gb, &tol, &m, &pd), REP_V_BITEXACT);
    /* one extra path of 3 photons in the middle: 3 added, nothing else (pixel by pixel, every
     * later photon would differ) */
    ck_assert_int_eq(rep_photon_compare(&rb, &gb, &tol, &m, &pd), REP_V_FAIL);
    ck_assert_uint_eq(pd.added, 3);
    ck_assert_uint_eq(pd.removed, 0);
    ck_assert_uint_eq(pd.changed, 0);
    ck_assert_uint_eq(pd.paths_added, 1);
    ck_assert_uint_eq(pd.golden, 199);
    ck_assert_uint_eq(pd.run, 202);
    ck_assert_uint_eq(m.fail_pixels, 3);
    /* and the other way round: removed */
    ck_assert_int_eq(rep_photon_compare(&gb, &rb, &tol, &m, &pd), REP_V_FAIL);
    ck_assert_uint_eq(pd.removed, 3);
    ck_assert_uint_eq(pd.added, 0);
    /* one photon's power changed: one changed photon, matched by its path and bounce */
    float *c = photon_map(100, -1, 0, &rr);
    c[(3 + 4) * 14 + 6] += 0.5f; /* path 4's second photon (paths 0..3 hold 1+2+3+1 photons) */
    eng_buffer cb = {"photons.map", 16, rr, 14, ch, c};
    ck_assert_int_eq(rep_photon_compare(&cb, &gb, &tol, &m, &pd), REP_V_FAIL);
    ck_assert_uint_eq(pd.changed, 1);
    ck_assert_uint_eq(pd.added + pd.removed, 0);
    ck_assert_str_eq(m.max_channel, "power.R");
    ck_assert_double_eq_tol(m.max_abs, 0.5, 1e-6);
    /* within tolerance when loose */
    tol.fail = tol.hardfail = 1;
    ck_assert_int_eq(rep_photon_compare(&cb, &gb, &tol, &m, &pd), REP_V_WARN);
    ck_assert_uint_eq(pd.within, 1);
    free(c);
    free(g);
    free(r);
}
END_TEST

START_TEST(tol_builtin_defaults)
{
    rep_tol d;
    rep_tol_builtin(&d);
    ck_assert_double_eq(d.warn, 0);
    ck_assert_double_eq(d.fail, 1e-4);
    ck_assert_double_eq(d.failrelative, 1e-4);
    ck_assert_double_eq(d.failpercent, 0);
    ck_assert_double_eq(d.hardfail, 1e-2);
    ck_assert_int_eq(d.exact, 0);
    /* The default file bless writes parses to the same values. */
    char *json = rep_tol_default_json();
    rep_tolerances *t = parse_tol(json, ENG_OK);
    ck_assert_int_eq(memcmp(&t->def, &d, sizeof d), 0);
    rep_tol_free(t);
    free(json);
}
END_TEST

START_TEST(tol_rejects_bad_files)
{
    ck_assert_ptr_null(parse_tol("{\"default\": {\"fial\": 1}}", ENG_ERR_INVALID));
    ck_assert_ptr_null(parse_tol("{\"buffers\": [{\"match\": \"a\", \"tolerance\": 1}]}", ENG_ERR_INVALID));
    ck_assert_ptr_null(parse_tol("{\"default\": {\"fail\": -1}}", ENG_ERR_INVALID));
    ck_assert_ptr_null(parse_tol("{\"buffers\": [{\"match\": \"a\", \"hardfail\": -0.5}]}", ENG_ERR_INVALID));
    ck_assert_ptr_null(parse_tol("{\"default\": {\"fail\": 1e999}}", ENG_ERR_INVALID));
    ck_assert_ptr_null(parse_tol("{\"default\": {\"fail\": \"1\"}}", ENG_ERR_INVALID));
    ck_assert_ptr_null(parse_tol("{\"default\": {\"exact\": 1}}", ENG_ERR_INVALID));
    ck_assert_ptr_null(parse_tol("{\"buffers\": [{\"fail\": 1}]}", ENG_ERR_INVALID));
    ck_assert_ptr_null(parse_tol("{\"defaults\": {}}", ENG_ERR_INVALID));
    ck_assert_ptr_null(parse_tol("{\"default\": {\"fail\": 1}", ENG_ERR_PARSE));
}
END_TEST

START_TEST(tol_missing_file)
{
    rep_tolerances *t = NULL;
    eng_error err;
    char *p = tpath("nope.json");
    ck_assert_int_eq(rep_tol_load(p, 1, &t, &err), ENG_OK);
    ck_assert_ptr_null(t->path);
    ck_assert_double_eq(t->def.fail, 1e-4);
    rep_tol_free(t);
    ck_assert_int_eq(rep_tol_load(p, 0, &t, &err), ENG_ERR_IO);
    free(p);
}
END_TEST

/* ---------------------------------------------------------------- comparison */

enum { CW = 10, CH = 10 };

typedef struct cmp_pair {
    float a[CW * CH], b[CW * CH];
    eng_buffer run, golden;
} cmp_pair;

static const char *const Y_CH[] = {"Y"};

static void pair_init(cmp_pair *p, float v)
{
    for (int i = 0; i < CW * CH; i++)
        p->a[i] = p->b[i] = v;
    eng_buffer e = {"t", CW, CH, 1, Y_CH, NULL};
    p->run = p->golden = e;
    p->run.data = p->a;
    p->golden.data = p->b;
}

static rep_tol loose(void)
{
    rep_tol t;
    rep_tol_builtin(&t);
    t.warn = 1e30;
    t.fail = 1e30;
    t.failpercent = 100;
    t.warnpercent = 100;
    t.hardfail = 1e30;
    return t;
}

START_TEST(cmp_identical_is_bitexact)
{
    cmp_pair p;
    pair_init(&p, 0.5f);
    rep_tol t;
    rep_tol_builtin(&t);
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_BITEXACT);
    ck_assert_double_eq(m.max_abs, 0);
    ck_assert_int_eq(m.max_x, -1);
}
END_TEST

/* Negative thresholds make even equal values fail: the shortcut for bit-identical values
 * (compare.c) must then not apply. */
START_TEST(cmp_negative_thresholds_fail_equal_values)
{
    cmp_pair p;
    pair_init(&p, 0.5f);
    rep_tol t;
    rep_tol_builtin(&t);
    t.fail = -1;
    t.failrelative = -1;
    rep_metrics m;
    rep_compare(&p.run, &p.golden, &t, &m);
    ck_assert_uint_eq(m.fail_pixels, m.pixels);
    ck_assert_int_eq(m.first_fail_x, 0);
    ck_assert_int_eq(m.first_fail_y, 0);
    rep_tol_builtin(&t);
    rep_compare(&p.run, &p.golden, &t, &m);
    ck_assert_uint_eq(m.fail_pixels, 0);
}
END_TEST

START_TEST(cmp_tiny_diff_within_or_warn)
{
    cmp_pair p;
    pair_init(&p, 0.5f);
    p.a[37] = 0.5f + 1e-6f;
    rep_tol t;
    rep_tol_builtin(&t);
    t.warn = 1e-5;
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WITHIN);
    ck_assert_int_eq(m.max_x, 7);
    ck_assert_int_eq(m.max_y, 3);
    ck_assert_str_eq(m.max_channel, "Y");
    ck_assert_uint_eq(m.values_differing, 1);
    t.warn = 0; /* the built-in warn: any difference warns */
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WARN);
    ck_assert_uint_eq(m.warn_pixels, 1);
    ck_assert(m.warn_why & REP_WHY_PERCENT);
}
END_TEST

START_TEST(cmp_failpercent)
{
    cmp_pair p;
    pair_init(&p, 0.5f);
    p.a[55] = 0.501f; /* d 1e-3 > fail 1e-4 on 1 pixel of 100 */
    rep_tol t;
    rep_tol_builtin(&t);
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_FAIL);
    ck_assert(m.fail_why & REP_WHY_PERCENT);
    ck_assert_uint_eq(m.fail_pixels, 1);
    ck_assert_double_eq_tol(m.fail_percent, 1.0, 1e-12);
    ck_assert_int_eq(m.first_fail_x, 5);
    ck_assert_int_eq(m.first_fail_y, 5);
    t.failpercent = 2;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WARN);
    t.warn = 1e-2;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WITHIN);
}
END_TEST

START_TEST(cmp_hardfail)
{
    cmp_pair p;
    pair_init(&p, 0.5f);
    p.a[0] = 1.0f;
    rep_tol t = loose();
    t.hardfail = 0.1;
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_FAIL);
    ck_assert_uint_eq(m.fail_why, REP_WHY_HARD);
    t.hardfail = 0.5; /* equal to the threshold passes */
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WITHIN);
    t.hardwarn = 0.2;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WARN);
    ck_assert_uint_eq(m.warn_why, REP_WHY_HARD);
}
END_TEST

START_TEST(cmp_relative_threshold)
{
    cmp_pair p;
    pair_init(&p, 1000.0f);
    p.a[3] = 1000.0f + 0.0625f; /* d 6.25e-2 > fail, rel 6.2e-5 < failrelative 1e-4 */
    rep_tol t;
    rep_tol_builtin(&t);
    t.hardfail = 1;
    t.warn = 1;
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WITHIN);
    ck_assert_uint_eq(m.fail_pixels, 0);
    t.failrelative = 1e-5;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_FAIL);
    ck_assert_uint_eq(m.fail_pixels, 1);
    /* Both zero: rel is 0, so a relative threshold cannot make zero fail. */
    pair_init(&p, 0.0f);
    t.fail = 0;
    t.failrelative = 0;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_BITEXACT);
}
END_TEST

START_TEST(cmp_rmse_threshold)
{
    cmp_pair p;
    pair_init(&p, 0.5f);
    for (int i = 0; i < CW * CH; i++)
        p.a[i] = 0.5f + 0.0009765625f; /* 2^-10, exact in float */
    rep_tol t = loose();
    t.rmse_fail = 5e-4;
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_FAIL);
    ck_assert_uint_eq(m.fail_why, REP_WHY_RMSE);
    ck_assert_double_eq_tol(m.rmse, 0.0009765625, 1e-12);
    ck_assert_double_eq_tol(m.mean_abs, 0.0009765625, 1e-12);
    t.rmse_fail = 2e-3;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WITHIN);
    t.rmse_warn = 5e-4;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WARN);
}
END_TEST

START_TEST(cmp_exact_mode)
{
    cmp_pair p;
    pair_init(&p, 0.0f);
    p.a[9] = -0.0f; /* equal as numbers, different bits */
    rep_tol t = loose();
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WITHIN);
    t.exact = 1;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_FAIL);
    ck_assert_uint_eq(m.fail_why, REP_WHY_EXACT);
    pair_init(&p, 0.5f);
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_BITEXACT);
}
END_TEST

START_TEST(cmp_nan_in_run_fails_whatever_the_tolerance)
{
    cmp_pair p;
    pair_init(&p, 0.5f);
    p.a[23] = NAN;
    p.a[40] = NAN;
    rep_tol t = loose();
    t.failrelative = 1e30;
    t.rmse_fail = 1e30;
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_FAIL);
    ck_assert(m.fail_why & REP_WHY_NONFINITE);
    ck_assert_uint_eq(m.run_nan, 2);
    ck_assert_uint_eq(m.golden_nan, 0);
    ck_assert_uint_eq(m.nonfinite_mismatch, 2);
    ck_assert_int_eq(m.nf_x, 3);
    ck_assert_int_eq(m.nf_y, 2);
    ck_assert_str_eq(m.nf_channel, "Y");
    /* A NaN that disappears is a change too. */
    pair_init(&p, 0.5f);
    p.b[5] = NAN;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_FAIL);
    ck_assert_uint_eq(m.golden_nan, 1);
}
END_TEST

START_TEST(cmp_nan_in_both_is_not_a_failure)
{
    cmp_pair p;
    pair_init(&p, 0.5f);
    p.a[11] = p.b[11] = NAN;
    rep_tol t;
    rep_tol_builtin(&t);
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_BITEXACT);
    ck_assert_uint_eq(m.run_nan, 1);
    ck_assert_uint_eq(m.golden_nan, 1);
    ck_assert_uint_eq(m.nonfinite_mismatch, 0);
    p.a[12] = p.b[12] = INFINITY;
    p.a[13] = p.b[13] = -INFINITY;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_BITEXACT);
    ck_assert_uint_eq(m.run_inf, 2);
    /* Same class, different payload: not bit-exact, but no failure either. */
    uint32_t q = 0x7fc00001u;
    memcpy(&p.a[11], &q, 4);
    t.warn = 1;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_WITHIN);
    ck_assert_uint_eq(m.nonfinite_mismatch, 0);
}
END_TEST

START_TEST(cmp_pinf_vs_ninf_fails)
{
    cmp_pair p;
    pair_init(&p, 0.5f);
    p.a[99] = INFINITY;
    p.b[99] = -INFINITY;
    rep_tol t = loose();
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&p.run, &p.golden, &t, &m), REP_V_FAIL);
    ck_assert_uint_eq(m.fail_why, REP_WHY_NONFINITE);
    ck_assert_int_eq(m.nf_x, 9);
    ck_assert_int_eq(m.nf_y, 9);
    ck_assert(m.nf_run > 0 && m.nf_golden < 0);
}
END_TEST

START_TEST(cmp_size_and_channels)
{
    float a[12] = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}, b[12] = {3, 2, 1, 6, 5, 4, 9, 8, 7, 12, 11, 10};
    const char *rgb[] = {"R", "G", "B"}, *bgr[] = {"B", "G", "R"}, *xyz[] = {"X", "Y", "Z"};
    eng_buffer r = {"t", 2, 2, 3, rgb, a}, g = {"t", 2, 2, 3, bgr, b};
    rep_tol t;
    rep_tol_builtin(&t);
    rep_metrics m;
    ck_assert_int_eq(rep_compare(&r, &g, &t, &m), REP_V_BITEXACT); /* matched by name */
    g.channels = xyz;
    ck_assert_int_eq(rep_compare(&r, &g, &t, &m), REP_V_SIZE);
    g.channels = bgr;
    g.width = 4;
    g.height = 1;
    ck_assert_int_eq(rep_compare(&r, &g, &t, &m), REP_V_SIZE);
    g.width = 2;
    g.height = 2;
    g.channel_count = 2;
    ck_assert_int_eq(rep_compare(&r, &g, &t, &m), REP_V_SIZE);
}
END_TEST

/* ---------------------------------------------------------------- OIIO shim */

START_TEST(shim_round_trip)
{
    fx_run r;
    fx_make(&r);
    *fx_at(&r, 0, 1, 2, 3, 1) = NAN;
    *fx_at(&r, 0, 1, 2, 4, 0) = -INFINITY;
    *fx_at(&r, 0, 1, 2, 5, 2) = -0.0f;
    eng_buffer v[3];
    for (int j = 0; j < 3; j++)
        v[j] = fx_view(&r.f[0].bufs[j]);
    char *path = tpath("rt.exr");
    eng_error err;
    ck_assert_msg(rep_oiio_write_parts(path, v, 3, &err) == ENG_OK, "%s", err.msg);
    rep_part *parts = NULL;
    int n = 0;
    ck_assert_msg(rep_oiio_read_parts(path, REP_MAX_FLOATS, &parts, &n, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(n, 3);
    for (int j = 0; j < 3; j++) {
        int k = 0;
        while (k < n && strcmp(parts[k].name, v[j].name) != 0)
            k++;
        ck_assert_int_lt(k, n);
        eng_buffer b = rep_part_buffer(&parts[k]);
        char d1[40], d2[40];
        eng_buffer_digest(&v[j], d1);
        eng_buffer_digest(&b, d2);
        ck_assert_str_eq(d1, d2); /* bit-exact, NaN and -0 included */
        ck_assert_int_eq(b.width, v[j].width);
        ck_assert_int_eq(b.height, v[j].height);
    }
    rep_parts_free(parts, n);
    /* A cap below the largest part refuses the file before decoding it. */
    ck_assert_int_eq(rep_oiio_read_parts(path, 100, &parts, &n, &err), ENG_ERR_INVALID);
    ck_assert_ptr_null(parts);
    free(path);
    fx_free(&r);
}
END_TEST

START_TEST(shim_rejects_garbage)
{
    char *path = tpath("garbage.exr");
    eng_error err;
    const char junk[] = "this is not an EXR file at all, just text";
    ck_assert_int_eq(rep_write_atomic(path, junk, sizeof junk, &err), ENG_OK);
    rep_part *parts = NULL;
    int n = 0;
    ck_assert_int_ne(rep_oiio_read_parts(path, REP_MAX_FLOATS, &parts, &n, &err), ENG_OK);
    ck_assert_ptr_nonnull(strstr(err.msg, path));
    ck_assert_ptr_null(strchr(err.msg, '\n'));
    free(path);
    path = tpath("missing.exr");
    ck_assert_int_eq(rep_oiio_read_parts(path, REP_MAX_FLOATS, &parts, &n, &err), ENG_ERR_IO);
    free(path);
}
END_TEST

/* Frame 0 of the fixture, with a NaN, a -Inf and a -0 in direct.radiance, written through
 * OpenImageIO to tpath(name) (returned), its bytes in *bytes (caller frees). */
static char *fx_exr_file(const char *name, char **bytes, size_t *len)
{
    fx_run r;
    fx_make(&r);
    *fx_at(&r, 0, 1, 2, 3, 1) = NAN;
    *fx_at(&r, 0, 1, 2, 4, 0) = -INFINITY;
    *fx_at(&r, 0, 1, 2, 5, 2) = -0.0f;
    eng_buffer v[3];
    for (int j = 0; j < 3; j++)
        v[j] = fx_view(&r.f[0].bufs[j]);
    char *path = tpath(name);
    eng_error err;
    ck_assert_msg(rep_oiio_write_parts(path, v, 3, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(eng_read_file(path, 1 << 24, bytes, len, &err), ENG_OK);
    fx_free(&r);
    return path;
}

/* Offset of the first occurrence of needle (len bytes) in hay, or -1. */
static long find_bytes(const char *hay, size_t n, const char *needle, size_t len)
{
    for (size_t i = 0; i + len <= n; i++)
        if (memcmp(hay + i, needle, len) == 0)
            return (long)i;
    return -1;
}

/* OpenEXR 3.1 sizes allocations from header fields before checking them against the file
 * (found by fuzz_run_reader): the shim refuses an attribute longer than the file, a chunkCount
 * whose offset table the file cannot hold and a data window with more rows than it can hold,
 * quickly and with one line naming the attribute. */
START_TEST(shim_rejects_lying_header_sizes)
{
    char *orig = NULL;
    size_t len = 0;
    char *path = fx_exr_file("lying.exr", &orig, &len);
    eng_error err;
    static const struct { const char *key; size_t key_len; size_t at; uint32_t value; const char *says; } cases[] = {
        {"name\0string", 12, 12, 0x7ffffff0u, "claims"},           /* the attribute's size field */
        {"chunkCount\0int\0\4\0\0\0", 19, 19, 0x7fffffffu, "chunkCount"}, /* its value */
        {"dataWindow\0box2i\0\20\0\0\0", 21, 21 + 12, 0x7ffffff0u, "rows"}, /* yMax */
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        char *bytes = malloc(len);
        ck_assert_ptr_nonnull(bytes);
        memcpy(bytes, orig, len);
        long at = find_bytes(bytes, len, cases[c].key, cases[c].key_len);
        ck_assert_msg(at >= 0, "no %s in the file", cases[c].key);
        uint32_t v32 = cases[c].value; /* little-endian, as EXR */
        unsigned char le[4] = {(unsigned char)v32, (unsigned char)(v32 >> 8), (unsigned char)(v32 >> 16),
                               (unsigned char)(v32 >> 24)};
        memcpy(bytes + at + cases[c].at, le, 4);
        ck_assert_int_eq(rep_write_atomic(path, bytes, len, &err), ENG_OK);
        rep_part *parts = NULL;
        int n = 0;
        eng_result res = rep_oiio_read_parts(path, REP_MAX_FLOATS, &parts, &n, &err);
        ck_assert_msg(res == ENG_ERR_INVALID, "case %zu: %s: %s", c, eng_result_name(res), err.msg);
        char oiio_msg[sizeof err.msg];
        memcpy(oiio_msg, err.msg, sizeof oiio_msg);
        /* the OpenEXR C reader refuses it the same way, before the library sees it */
        res = rep_read_parts(path, REP_MAX_FLOATS, &parts, &n, &err);
        ck_assert_msg(res == ENG_ERR_INVALID, "case %zu: %s: %s", c, eng_result_name(res), err.msg);
        ck_assert_str_eq(err.msg, oiio_msg);
        ck_assert_ptr_null(parts);
        ck_assert_ptr_nonnull(strstr(err.msg, path));
        ck_assert_msg(strstr(err.msg, cases[c].says) != NULL, "case %zu: %s", c, err.msg);
        ck_assert_ptr_null(strchr(err.msg, '\n'));
        free(bytes);
    }
    /* A channel whose pixel type is none of uint/half/float (found by fuzz_run_reader in CI:
     * OpenImageIO 2.4 aborts on an assertion in TypeDesc_from_ImfPixelType instead of failing). */
    static const uint32_t bad_types[] = {3, 255, 0x80000000u};
    for (size_t k = 0; k < sizeof bad_types / sizeof bad_types[0]; k++) {
        uint32_t type = bad_types[k];
        char *bytes = malloc(len);
        ck_assert_ptr_nonnull(bytes);
        memcpy(bytes, orig, len);
        long at = find_bytes(bytes, len, "channels\0chlist\0", 16);
        ck_assert_msg(at >= 0, "no channel list in the file");
        size_t first = (size_t)at + 16 + 4; /* the list's size field, then the first name */
        size_t pt = first + strlen(bytes + first) + 1;
        unsigned char le[4] = {(unsigned char)type, (unsigned char)(type >> 8), (unsigned char)(type >> 16),
                               (unsigned char)(type >> 24)};
        memcpy(bytes + pt, le, 4);
        ck_assert_int_eq(rep_write_atomic(path, bytes, len, &err), ENG_OK);
        rep_part *parts = NULL;
        int n = 0;
        eng_result res = rep_read_parts(path, REP_MAX_FLOATS, &parts, &n, &err);
        ck_assert_msg(res == ENG_ERR_INVALID, "pixel type %u: %s: %s", type, eng_result_name(res), err.msg);
        ck_assert_ptr_null(parts);
        res = rep_oiio_read_parts(path, REP_MAX_FLOATS, &parts, &n, &err);
        ck_assert_msg(res == ENG_ERR_INVALID, "pixel type %u: %s: %s", type, eng_result_name(res), err.msg);
        ck_assert_ptr_null(parts);
        ck_assert_ptr_nonnull(strstr(err.msg, path));
        ck_assert_msg(strstr(err.msg, "pixel type") != NULL, "%s", err.msg);
        ck_assert_ptr_null(strchr(err.msg, '\n'));
        free(bytes);
    }
    free(orig);
    free(path);
}
END_TEST

/* ---------------------------------------------------------------- OpenEXR C reader (exr_read.c) */

typedef eng_result (*parts_reader)(const char *, size_t, rep_part **, int *, eng_error *);

/* read and OpenImageIO's reader give the same parts: count, order, names, sizes, channel names
 * in the same order and every float's bits. */
static void assert_reader_agrees(parts_reader read, const char *path)
{
    rep_part *a = NULL, *b = NULL;
    int na = 0, nb = 0;
    eng_error err;
    ck_assert_msg(read(path, REP_MAX_FLOATS, &a, &na, &err) == ENG_OK, "%s", err.msg);
    ck_assert_msg(rep_oiio_read_parts(path, REP_MAX_FLOATS, &b, &nb, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(na, nb);
    for (int i = 0; i < na; i++) {
        ck_assert_str_eq(a[i].name, b[i].name);
        ck_assert_int_eq(a[i].width, b[i].width);
        ck_assert_int_eq(a[i].height, b[i].height);
        ck_assert_int_eq(a[i].channel_count, b[i].channel_count);
        for (int c = 0; c < a[i].channel_count; c++)
            ck_assert_msg(strcmp(a[i].channels[c], b[i].channels[c]) == 0, "%s: part %s: channel %d: %s vs %s",
                          path, a[i].name, c, a[i].channels[c], b[i].channels[c]);
        size_t n = (size_t)a[i].width * (size_t)a[i].height * (size_t)a[i].channel_count;
        ck_assert_msg(memcmp(a[i].data, b[i].data, n * sizeof(float)) == 0, "%s: part %s: floats differ", path,
                      a[i].name);
    }
    rep_parts_free(a, na);
    rep_parts_free(b, nb);
}

/* The OpenEXR C reader gives OpenImageIO's parts. */
static void assert_readers_agree(const char *path)
{
    assert_reader_agrees(rep_exr_read_parts, path);
}

/* On recorded frames (43 parts: colour, G-buffer, photon-map channels such as direction.X) and
 * on the fixture writer's files (NaN, -Inf, -0), the OpenEXR C reader gives OpenImageIO's parts. */
START_TEST(exr_reader_matches_oiio)
{
    /* Goldens may store buffers as objects: their frames are written out as frame files first,
     * by the writer a recording uses. */
    static const struct {
        const char *golden, *frame;
    } goldens[] = {
        {ISPM_SOURCE_DIR "/golden/cornell-box-ci", "frames/000000.exr"},
        {ISPM_SOURCE_DIR "/golden/stress-random-maps", "frames/000005.exr"},
    };
    eng_error err;
    for (size_t i = 0; i < sizeof goldens / sizeof goldens[0]; i++) {
        char *dst = tpath(i == 0 ? "unpacked-0" : "unpacked-1");
        FILE *out = tmpfile();
        ck_assert_ptr_nonnull(out);
        ck_assert_msg(rep_golden_unpack(goldens[i].golden, dst, out, &err) == ENG_OK, "%s", err.msg);
        fclose(out);
        char *frame = rep_path_join(dst, goldens[i].frame);
        assert_readers_agree(frame);
        free(frame);
        free(dst);
    }
    char *bytes = NULL;
    size_t blen = 0;
    char *path = fx_exr_file("both.exr", &bytes, &blen);
    free(bytes);
    assert_readers_agree(path);
    /* Chunks whose byte count is no multiple of 16 (the unpacking's vector loops have tails). */
    static const char *const rgb3[] = {"R", "G", "B"}, *const y1[] = {"Y"};
    float odd_a[7 * 5 * 3], odd_b[13 * 3];
    for (size_t i = 0; i < sizeof odd_a / sizeof odd_a[0]; i++)
        odd_a[i] = (float)i * 0.37f - 3.0f;
    for (size_t i = 0; i < sizeof odd_b / sizeof odd_b[0]; i++)
        odd_b[i] = 1.0f / ((float)i + 0.5f);
    eng_buffer odd[2] = {{"odd.radiance", 7, 5, 3, rgb3, odd_a}, {"odd.depth", 13, 3, 1, y1, odd_b}};
    ck_assert_msg(rep_oiio_write_parts(path, odd, 2, &err) == ENG_OK, "%s", err.msg);
    assert_readers_agree(path);
    /* OpenEXR 3.1's C++ writer (under OpenImageIO) stores a ZIP chunk that compresses to exactly
     * its own size as is; both readers must take those bytes alike. */
    char *raw = NULL;
    size_t len = 0;
    ck_assert_int_eq(eng_read_file(ISPM_SOURCE_DIR "/tests/data/exr/zip-same-size-64x16-rgb.f32", 1 << 20, &raw, &len,
                                   &err), ENG_OK);
    static const char *const rgb[] = {"R", "G", "B"};
    eng_buffer zb = {"composite.radiance", 64, 16, 3, rgb, (const float *)raw};
    ck_assert_uint_eq(len, 64 * 16 * 3 * sizeof(float));
    ck_assert_msg(rep_oiio_write_parts(path, &zb, 1, &err) == ENG_OK, "%s", err.msg);
    assert_readers_agree(path);
    free(raw);
    free(path);
}
END_TEST

/* Files the C reader does not take (half channels, tiles; made with oiiotool) are left to
 * OpenImageIO: rep_read_parts then gives exactly OpenImageIO's parts. */
START_TEST(exr_reader_leaves_other_files_to_oiio)
{
    static const char *const files[] = {ISPM_SOURCE_DIR "/tests/data/exr/half-5x4-rgb.exr",
                                        ISPM_SOURCE_DIR "/tests/data/exr/tiled-9x7-rgb.exr"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        rep_part *parts = NULL;
        int n = 0;
        eng_error err;
        ck_assert_int_eq(rep_exr_read_parts(files[i], REP_MAX_FLOATS, &parts, &n, &err), ENG_ERR_UNSUPPORTED);
        ck_assert_ptr_null(parts);
        ck_assert_ptr_nonnull(strstr(err.msg, files[i]));
        assert_reader_agrees(rep_read_parts, files[i]);
    }
}
END_TEST

/* A truncated frame file: one line naming the file, whichever reader says it; the C reader
 * leaves it to OpenImageIO rather than guessing. A missing file is an I/O error. */
START_TEST(exr_reader_truncated_file)
{
    char *bytes = NULL;
    size_t len = 0;
    char *path = fx_exr_file("cut.exr", &bytes, &len);
    eng_error err;
    size_t cuts[] = {len - 7, len / 2, 300, 40};
    for (size_t k = 0; k < sizeof cuts / sizeof cuts[0]; k++) {
        ck_assert_int_eq(rep_write_atomic(path, bytes, cuts[k], &err), ENG_OK);
        rep_part *parts = NULL;
        int n = 0;
        eng_result res = rep_exr_read_parts(path, REP_MAX_FLOATS, &parts, &n, &err);
        ck_assert_msg(res != ENG_OK, "cut at %zu: read", cuts[k]);
        ck_assert_ptr_null(parts);
        res = rep_read_parts(path, REP_MAX_FLOATS, &parts, &n, &err);
        ck_assert_msg(res == ENG_ERR_IO || res == ENG_ERR_INVALID, "cut at %zu: %s", cuts[k], eng_result_name(res));
        ck_assert_ptr_null(parts);
        ck_assert_int_eq(n, 0);
        ck_assert_msg(strstr(err.msg, path) != NULL, "%s", err.msg);
        ck_assert_ptr_null(strchr(err.msg, '\n'));
    }
    free(bytes);
    free(path);
    path = tpath("absent.exr");
    rep_part *parts = NULL;
    int n = 0;
    ck_assert_int_eq(rep_read_parts(path, REP_MAX_FLOATS, &parts, &n, &err), ENG_ERR_IO);
    ck_assert_ptr_nonnull(strstr(err.msg, path));
    free(path);
}
END_TEST

/* A PNG's chunks other than IDAT, in order, as one byte string (length, type, data, CRC each);
 * caller frees. */
static char *png_meta_chunks(const char *bytes, size_t len, size_t *out_len)
{
    char *out = malloc(len + 1);
    ck_assert_ptr_nonnull(out);
    size_t o = 0;
    ck_assert_uint_ge(len, 8);
    for (size_t i = 8; i + 12 <= len;) {
        const unsigned char *b = (const unsigned char *)bytes + i;
        size_t n = (size_t)b[0] << 24 | (size_t)b[1] << 16 | (size_t)b[2] << 8 | (size_t)b[3];
        ck_assert_uint_le(i + 12 + n, len);
        if (memcmp(b + 4, "IDAT", 4) != 0) {
            memcpy(out + o, b, n + 12);
            o += n + 12;
        }
        i += n + 12;
    }
    *out_len = o;
    return out;
}

/* The report's PNGs (png_write.c, libpng) hold what OpenImageIO wrote before: the same chunks
 * (sRGB, gAMA, cHRM, oFFs, text) byte for byte and the same pixels; only the zlib level differs. */
START_TEST(png_writer_matches_oiio)
{
    static const int shapes[][3] = {{160, 160, 3}, {37, 5, 1}, {9, 300, 3}, {1, 1, 3}};
    for (size_t s = 0; s < sizeof shapes / sizeof shapes[0]; s++) {
        int w = shapes[s][0], h = shapes[s][1], nch = shapes[s][2];
        size_t n = (size_t)w * (size_t)h * (size_t)nch;
        unsigned char *px = malloc(n);
        ck_assert_ptr_nonnull(px);
        uint32_t x = 12345u + (uint32_t)s;
        for (size_t i = 0; i < n; i++) { /* smooth ramps with some noise: every filter gets used */
            x = x * 1664525u + 1013904223u;
            px[i] = (unsigned char)((i / (size_t)nch) % (size_t)w * 255 / (size_t)w + (x >> 29));
        }
        char *p1 = tpath("a.png"), *p2 = tpath("b.png");
        eng_error err;
        ck_assert_msg(rep_png_write(p1, w, h, nch, px, &err) == ENG_OK, "%s", err.msg);
        ck_assert_msg(rep_oiio_write_png(p2, w, h, nch, px, &err) == ENG_OK, "%s", err.msg);
        char *b1 = NULL, *b2 = NULL;
        size_t l1 = 0, l2 = 0;
        ck_assert_int_eq(eng_read_file(p1, 1 << 24, &b1, &l1, &err), ENG_OK);
        ck_assert_int_eq(eng_read_file(p2, 1 << 24, &b2, &l2, &err), ENG_OK);
        size_t m1 = 0, m2 = 0;
        char *c1 = png_meta_chunks(b1, l1, &m1), *c2 = png_meta_chunks(b2, l2, &m2);
        ck_assert_msg(m1 == m2 && memcmp(c1, c2, m1) == 0, "%dx%dx%d: chunks differ", w, h, nch);
        int rw = 0, rh = 0, rc = 0;
        unsigned char *back = NULL;
        ck_assert_msg(rep_oiio_read_image8(p1, &rw, &rh, &rc, &back, &err) == ENG_OK, "%s", err.msg);
        ck_assert_int_eq(rw, w);
        ck_assert_int_eq(rh, h);
        ck_assert_int_eq(rc, nch);
        ck_assert_int_eq(memcmp(back, px, n), 0);
        free(back);
        free(c1);
        free(c2);
        free(b1);
        free(b2);
        free(p1);
        free(p2);
        free(px);
    }
    char *bad = tpath("no/such/dir/x.png");
    unsigned char one[3] = {0, 0, 0};
    eng_error err;
    ck_assert_int_eq(rep_png_write(bad, 1, 1, 3, one, &err), ENG_ERR_IO);
    ck_assert_ptr_nonnull(strstr(err.msg, bad));
    ck_assert_int_eq(rep_png_write(bad, 0, 1, 3, one, &err), ENG_ERR_INVALID);
    ck_assert_int_eq(rep_png_write(bad, 1, 1, 4, one, &err), ENG_ERR_INVALID);
    free(bad);
}
END_TEST

/* ---------------------------------------------------------------- end to end */

START_TEST(e2e_identical_is_bitexact)
{
    char *golden = make_golden();
    fx_run r;
    fx_make(&r);
    char *run = tpath("run");
    fx_write(&r, run);
    eng_error err = {{0}};
    ck_assert_msg(replay(run, golden, &err) == REP_OK, "%s", err.msg);
    cJSON *rep = report_of(run);
    ck_assert_str_eq(str_of(rep, "verdict"), "OK");
    const cJSON *counts = cJSON_GetObjectItem(rep, "counts");
    ck_assert_double_eq(num_of(counts, "bit-exact"), 9);
    ck_assert_double_eq(num_of(counts, "fail"), 0);
    ck_assert_double_eq(num_of(rep, "buffer_count"), 9);
    ck_assert(cJSON_IsNull(cJSON_GetObjectItem(rep, "first_digest_difference")));
    ck_assert(cJSON_IsNull(cJSON_GetObjectItem(rep, "first_difference")));
    cJSON_Delete(rep);
    fx_free(&r);
    free(run);
    free(golden);
}
END_TEST

START_TEST(e2e_one_pixel_changed)
{
    char *golden = make_golden();
    fx_run r;
    fx_make(&r);
    *fx_at(&r, 1, 1, 3, 2, 1) += 0.5f;
    char *run = tpath("run");
    fx_write(&r, run);
    eng_error err;
    ck_assert_int_eq(replay(run, golden, &err), REP_FAIL);
    cJSON *rep = report_of(run);
    ck_assert_str_eq(str_of(rep, "verdict"), "FAIL");
    ck_assert_double_eq(num_of(rep, "exit_code"), 2);
    const cJSON *d = cJSON_GetObjectItem(rep, "first_digest_difference");
    ck_assert_double_eq(num_of(d, "frame"), 1);
    ck_assert_str_eq(str_of(d, "buffer"), "direct.radiance");
    d = cJSON_GetObjectItem(rep, "first_difference");
    ck_assert_double_eq(num_of(d, "frame"), 1);
    ck_assert_str_eq(str_of(d, "buffer"), "direct.radiance");
    const cJSON *e = report_entry(rep, 1, "direct.radiance");
    ck_assert_ptr_nonnull(e);
    ck_assert_str_eq(str_of(e, "verdict"), "fail");
    const cJSON *m = cJSON_GetObjectItem(e, "metrics");
    const cJSON *at = cJSON_GetObjectItem(m, "max_at");
    ck_assert_double_eq(num_of(at, "x"), 3);
    ck_assert_double_eq(num_of(at, "y"), 2);
    ck_assert_str_eq(str_of(at, "channel"), "G");
    ck_assert_double_eq_tol(num_of(m, "max_abs_error"), 0.5, 1e-6);
    ck_assert_double_eq(num_of(m, "fail_pixels"), 1);
    ck_assert_str_eq(str_of(report_entry(rep, 0, "direct.radiance"), "verdict"), "bit-exact");
    ck_assert_str_eq(str_of(report_entry(rep, 1, "gbuffer.position"), "verdict"), "bit-exact");
    ck_assert_double_eq(num_of(cJSON_GetObjectItem(rep, "counts"), "bit-exact"), 8);
    cJSON_Delete(rep);
    fx_free(&r);
    free(run);
    free(golden);
}
END_TEST

START_TEST(e2e_nan_fails)
{
    char *golden = make_golden();
    fx_run r;
    fx_make(&r);
    *fx_at(&r, 2, 0, 1, 1, 2) = NAN;
    char *run = tpath("run");
    fx_write(&r, run);
    /* Even tolerances that would accept anything finite do not accept the NaN. */
    char *tol = rep_path_join(golden, "tolerances.json");
    const char *loose_json = "{\"default\": {\"warn\": 1e30, \"fail\": 1e30, \"failpercent\": 100,"
                             " \"warnpercent\": 100, \"hardfail\": 1e30}}";
    eng_error err;
    ck_assert_int_eq(rep_write_atomic(tol, loose_json, strlen(loose_json), &err), ENG_OK);
    ck_assert_int_eq(replay(run, golden, &err), REP_FAIL);
    cJSON *rep = report_of(run);
    const cJSON *e = report_entry(rep, 2, "gbuffer.position");
    ck_assert_str_eq(str_of(e, "verdict"), "fail");
    const cJSON *m = cJSON_GetObjectItem(e, "metrics");
    ck_assert_double_eq(num_of(cJSON_GetObjectItem(m, "run"), "nan"), 1);
    const cJSON *at = cJSON_GetObjectItem(m, "first_nonfinite_mismatch");
    ck_assert_double_eq(num_of(at, "x"), 1);
    ck_assert_double_eq(num_of(at, "y"), 1);
    ck_assert_str_eq(str_of(at, "channel"), "Z");
    cJSON_Delete(rep);
    fx_free(&r);
    free(tol);
    free(run);
    free(golden);
}
END_TEST

START_TEST(e2e_missing_and_extra_buffer)
{
    char *golden = make_golden();
    eng_error err;
    fx_run r;
    fx_make(&r);
    r.f[1].count = 2; /* shadow.light0 gone from frame 1 */
    char *run = tpath("run-missing");
    fx_write(&r, run);
    ck_assert_int_eq(replay(run, golden, &err), REP_FAIL);
    cJSON *rep = report_of(run);
    const cJSON *e = report_entry(rep, 1, "shadow.light0");
    ck_assert_ptr_nonnull(e);
    ck_assert_str_eq(str_of(e, "verdict"), "fail");
    ck_assert_str_eq(str_of(e, "problem"), "missing from run");
    cJSON_Delete(rep);
    fx_free(&r);
    free(run);

    fx_make(&r);
    r.f[0].count = 4;
    fx_set(&r.f[0].bufs[3], "splat.count", 8, 6, "Y", NULL, NULL, 99);
    run = tpath("run-extra");
    fx_write(&r, run);
    ck_assert_int_eq(replay(run, golden, &err), REP_FAIL);
    rep = report_of(run);
    e = report_entry(rep, 0, "splat.count");
    ck_assert_ptr_nonnull(e);
    ck_assert_str_eq(str_of(e, "problem"), "not in golden");
    cJSON_Delete(rep);
    fx_free(&r);
    free(run);
    free(golden);
}
END_TEST

START_TEST(e2e_missing_frame)
{
    char *golden = make_golden();
    fx_run r;
    fx_make(&r);
    r.frames = 2;
    char *run = tpath("run");
    fx_write(&r, run);
    eng_error err;
    ck_assert_int_eq(replay(run, golden, &err), REP_FAIL);
    cJSON *rep = report_of(run);
    ck_assert_str_eq(str_of(report_entry(rep, 2, "direct.radiance"), "problem"), "frame missing from run");
    ck_assert_double_eq(num_of(rep, "frame_count"), 3);
    cJSON_Delete(rep);
    fx_free(&r);
    free(run);
    free(golden);
}
END_TEST

START_TEST(e2e_size_mismatch)
{
    char *golden = make_golden();
    fx_run r;
    fx_make(&r);
    fx_set(&r.f[0].bufs[2], "shadow.light0", 8, 8, "Z", NULL, NULL, 3);
    *fx_at(&r, 1, 1, 0, 0, 0) += 1.0f; /* a failure as well: size still wins */
    char *run = tpath("run");
    fx_write(&r, run);
    eng_error err;
    ck_assert_int_eq(replay(run, golden, &err), REP_SIZE);
    cJSON *rep = report_of(run);
    ck_assert_str_eq(str_of(rep, "verdict"), "SIZE MISMATCH");
    ck_assert_str_eq(str_of(report_entry(rep, 0, "shadow.light0"), "verdict"), "size mismatch");
    cJSON_Delete(rep);
    fx_free(&r);
    free(run);
    free(golden);
}
END_TEST

/* A good run at <tmp>/run; returns its path. */
static char *make_run(void)
{
    fx_run r;
    fx_make(&r);
    char *run = tpath("run");
    fx_write(&r, run);
    fx_free(&r);
    return run;
}

static long file_size(const char *p)
{
    struct stat st;
    ck_assert_int_eq(stat(p, &st), 0);
    return (long)st.st_size;
}

START_TEST(e2e_truncated_exr_is_unreadable)
{
    char *golden = make_golden();
    char *run = make_run();
    char *f = rep_path_join(run, "frames/000001.exr");
    ck_assert_int_eq(truncate(f, file_size(f) / 2), 0);
    eng_error err = {{0}};
    ck_assert_int_eq(replay(run, golden, &err), REP_UNREADABLE);
    ck_assert_ptr_nonnull(strstr(err.msg, "000001.exr"));
    cJSON *rep = report_of(run);
    ck_assert_str_eq(str_of(rep, "verdict"), "UNREADABLE");
    ck_assert_double_eq(num_of(rep, "exit_code"), 4);
    cJSON_Delete(rep);
    /* Truncated to nothing but the magic number. */
    ck_assert_int_eq(truncate(f, 4), 0);
    ck_assert_int_eq(replay(run, golden, &err), REP_UNREADABLE);
    free(f);
    free(run);
    free(golden);
}
END_TEST

START_TEST(e2e_tampered_exr_is_unreadable)
{
    char *golden = make_golden();
    char *run = make_run();
    char *f = rep_path_join(run, "frames/000002.exr");
    /* Flip bytes near the end of the file: inside the last part's compressed pixels. */
    FILE *fp = fopen(f, "r+b");
    ck_assert_ptr_nonnull(fp);
    long size = file_size(f);
    for (long off = size - 24; off < size - 8; off += 4) {
        ck_assert_int_eq(fseek(fp, off, SEEK_SET), 0);
        int c = fgetc(fp);
        ck_assert_int_eq(fseek(fp, off, SEEK_SET), 0);
        fputc(c ^ 0x5a, fp);
    }
    fclose(fp);
    eng_error err = {{0}};
    ck_assert_int_eq(replay(run, golden, &err), REP_UNREADABLE);
    ck_assert_ptr_nonnull(strstr(err.msg, "000002.exr"));
    free(f);
    free(run);
    free(golden);
}
END_TEST

START_TEST(e2e_pixels_disagree_with_manifest_digest)
{
    char *golden = make_golden();
    char *run = make_run();
    /* A well-formed EXR whose pixels are not the ones the manifest's digest describes. */
    fx_run r;
    fx_make(&r);
    *fx_at(&r, 0, 0, 4, 4, 0) += 0.25f;
    eng_buffer v[3];
    for (int j = 0; j < 3; j++)
        v[j] = fx_view(&r.f[0].bufs[j]);
    char *f = rep_path_join(run, "frames/000000.exr");
    eng_error err = {{0}};
    ck_assert_int_eq(rep_oiio_write_parts(f, v, 3, &err), ENG_OK);
    ck_assert_int_eq(replay(run, golden, &err), REP_UNREADABLE);
    ck_assert_ptr_nonnull(strstr(err.msg, "000000.exr"));
    ck_assert_ptr_nonnull(strstr(err.msg, "gbuffer.position"));
    /* The same damage in the golden is caught too. */
    ck_assert_int_eq(replay(golden, NULL, &err), REP_OK);
    ck_assert_int_eq(replay(run, NULL, &err), REP_UNREADABLE);
    fx_free(&r);
    free(f);
    free(run);
    free(golden);
}
END_TEST

START_TEST(e2e_manifest_missing_or_incomplete)
{
    char *golden = make_golden();
    fx_run r;
    fx_make(&r);
    char *run = tpath("run-nomanifest");
    fx_write_ex(&r, run, 1, 1);
    eng_error err = {{0}};
    ck_assert_int_eq(replay(run, golden, &err), REP_UNREADABLE);
    ck_assert_ptr_nonnull(strstr(err.msg, "manifest.json"));
    free(run);
    run = tpath("run-incomplete");
    fx_write_ex(&r, run, 0, 0);
    ck_assert_int_eq(replay(run, golden, &err), REP_UNREADABLE);
    /* The golden must be complete too. */
    ck_assert_int_eq(replay(golden, run, &err), REP_UNREADABLE);
    free(run);
    /* A missing frame file listed by the manifest. */
    run = tpath("run-nofile");
    fx_write(&r, run);
    char *f = rep_path_join(run, "frames/000001.exr");
    ck_assert_int_eq(unlink(f), 0);
    ck_assert_int_eq(replay(run, golden, &err), REP_UNREADABLE);
    ck_assert_ptr_nonnull(strstr(err.msg, "000001.exr"));
    /* A run folder that does not exist gets no report folder made for it. */
    char *none = tpath("no-such-run");
    ck_assert_int_eq(replay(none, golden, &err), REP_UNREADABLE);
    ck_assert(!rep_is_dir(none));
    free(none);
    free(f);
    free(run);
    fx_free(&r);
    free(golden);
}
END_TEST

/* Writes text as <run>/manifest.json after editing the good manifest with edit(). */
static void edit_manifest(const char *run, void (*edit)(cJSON *))
{
    char *mp = rep_path_join(run, "manifest.json");
    cJSON *j = load_json(mp);
    edit(j);
    char *text = cJSON_Print(j);
    eng_error err;
    ck_assert_int_eq(rep_write_atomic(mp, text, strlen(text), &err), ENG_OK);
    cJSON_free(text);
    cJSON_Delete(j);
    free(mp);
}

static cJSON *buf0(cJSON *j)
{
    cJSON *f0 = cJSON_GetArrayItem(cJSON_GetObjectItem(j, "frames"), 0);
    return cJSON_GetArrayItem(cJSON_GetObjectItem(f0, "buffers"), 0);
}

static void lie_size(cJSON *j)
{
    cJSON_ReplaceItemInObject(buf0(j), "width", cJSON_CreateNumber(65536));
    cJSON_ReplaceItemInObject(buf0(j), "height", cJSON_CreateNumber(65536));
}

static void lie_count(cJSON *j)
{
    cJSON_ReplaceItemInObject(j, "frame_count", cJSON_CreateNumber(4));
}

static void escape_path(cJSON *j)
{
    cJSON *f0 = cJSON_GetArrayItem(cJSON_GetObjectItem(j, "frames"), 0);
    cJSON_ReplaceItemInObject(f0, "file", cJSON_CreateString("../golden/frames/000000.exr"));
}

static void bad_digest(cJSON *j)
{
    cJSON_ReplaceItemInObject(buf0(j), "digest", cJSON_CreateString("not-a-digest"));
}

START_TEST(e2e_lying_manifests_are_unreadable)
{
    char *golden = make_golden();
    void (*edits[])(cJSON *) = {lie_size, lie_count, escape_path, bad_digest};
    for (size_t i = 0; i < sizeof edits / sizeof edits[0]; i++) {
        char *run = make_run();
        edit_manifest(run, edits[i]);
        eng_error err = {{0}};
        ck_assert_msg(replay(run, golden, &err) == REP_UNREADABLE, "edit %zu", i);
        ck_assert_ptr_nonnull(strstr(err.msg, "manifest.json"));
        ck_assert_int_eq(rep_remove_tree(run, &err), ENG_OK);
        free(run);
    }
    free(golden);
}
END_TEST

START_TEST(e2e_bad_tolerances_are_unreadable)
{
    char *golden = make_golden();
    char *run = make_run();
    char *tol = rep_path_join(golden, "tolerances.json");
    const char *bad = "{\"default\": {\"fail\": 1e-4, \"failprecent\": 1}}";
    eng_error err = {{0}};
    ck_assert_int_eq(rep_write_atomic(tol, bad, strlen(bad), &err), ENG_OK);
    ck_assert_int_eq(replay(run, golden, &err), REP_UNREADABLE);
    ck_assert_ptr_nonnull(strstr(err.msg, "failprecent"));
    /* An explicit tolerances file must exist. */
    rep_options o = {0};
    o.run_dir = run;
    o.golden_dir = golden;
    char *missing = tpath("missing-tol.json");
    o.tolerances = missing;
    ck_assert_int_eq(rep_replay(&o, NULL, &err), REP_UNREADABLE);
    free(missing);
    free(tol);
    free(run);
    free(golden);
}
END_TEST

START_TEST(e2e_no_golden_integrity_only)
{
    char *run = make_run();
    eng_error err = {{0}};
    ck_assert_msg(replay(run, NULL, &err) == REP_OK, "%s", err.msg);
    cJSON *rep = report_of(run);
    ck_assert_double_eq(num_of(cJSON_GetObjectItem(rep, "counts"), "checked"), 9);
    cJSON_Delete(rep);
    free(run);

    fx_run r;
    fx_make(&r);
    *fx_at(&r, 1, 1, 6, 5, 0) = NAN;
    *fx_at(&r, 1, 1, 7, 5, 0) = INFINITY;
    run = tpath("run-nan");
    fx_write(&r, run);
    ck_assert_int_eq(replay(run, NULL, &err), REP_FAIL);
    rep = report_of(run);
    const cJSON *e = report_entry(rep, 1, "direct.radiance");
    ck_assert_str_eq(str_of(e, "verdict"), "fail");
    const cJSON *m = cJSON_GetObjectItem(e, "metrics");
    ck_assert_double_eq(num_of(cJSON_GetObjectItem(m, "run"), "nan"), 1);
    ck_assert_double_eq(num_of(cJSON_GetObjectItem(m, "run"), "inf"), 1);
    ck_assert_double_eq(num_of(cJSON_GetObjectItem(m, "first_nonfinite"), "x"), 6);
    ck_assert_double_eq(num_of(cJSON_GetObjectItem(m, "first_nonfinite"), "y"), 5);
    cJSON_Delete(rep);
    fx_free(&r);
    free(run);
}
END_TEST

START_TEST(e2e_bless_then_replay_passes)
{
    char *run = make_run();
    char *golden = tpath("goldens/cornell");
    eng_error err = {{0}};
    ck_assert_msg(rep_bless(run, golden, &err) == ENG_OK, "%s", err.msg);
    char *p = rep_path_join(golden, "tolerances.json");
    ck_assert(rep_is_file(p));
    free(p);
    p = rep_path_join(golden, "frames/000002.exr");
    ck_assert(rep_is_file(p));
    free(p);
    p = rep_xprintf("%s.tmp", golden);
    ck_assert(!rep_is_dir(p));
    free(p);
    ck_assert_msg(replay(run, golden, &err) == REP_OK, "%s", err.msg);
    /* The run's report folder is not copied into the golden. */
    ck_assert_msg(rep_bless(run, golden, &err) == ENG_OK, "%s", err.msg);
    p = rep_path_join(golden, "replay");
    ck_assert(!rep_is_dir(p));
    free(p);
    /* Trailing slash on the golden path. */
    p = rep_xprintf("%s/", golden);
    ck_assert_msg(rep_bless(run, p, &err) == ENG_OK, "%s", err.msg);
    free(p);
    ck_assert_int_eq(rep_bless(run, run, &err), ENG_ERR_INVALID);
    /* A folder that is not a golden is never replaced. */
    char *other = tpath("precious");
    char *keep = rep_path_join(other, "notes.txt");
    ck_assert_int_eq(rep_mkdirs(other, &err), ENG_OK);
    ck_assert_int_eq(rep_write_atomic(keep, "x", 1, &err), ENG_OK);
    ck_assert_int_eq(rep_bless(run, other, &err), ENG_ERR_INVALID);
    ck_assert(rep_is_file(keep));
    free(keep);
    free(other);
    free(golden);
    free(run);
}
END_TEST

/* The compression of every part of an EXR if they all share one, else -1. */
static int exr_compression_of(const char *path)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t c = NULL;
    ck_assert_int_eq(exr_start_read(&c, path, &init), EXR_ERR_SUCCESS);
    int n = 0, out = -2;
    ck_assert_int_eq(exr_get_count(c, &n), EXR_ERR_SUCCESS);
    for (int p = 0; p < n; p++) {
        exr_compression_t t;
        ck_assert_int_eq(exr_get_compression(c, p, &t), EXR_ERR_SUCCESS);
        out = out == -2 || out == (int)t ? (int)t : -1;
    }
    exr_finish(&c);
    return out;
}

/* A run may be recorded in any compression (this test makes an rle run); goldens stay ZIP. bless recompresses a run's frame files to ZIP
 * (same pixels and digests, verified), its manifest then says so and nothing else changes; the
 * run is left as it was; a golden blessed from a ZIP run replays bit-exact against the same
 * pixels in rle (re-blessing is "unchanged"); a ZIP run is still copied byte for byte. */
START_TEST(e2e_bless_recompresses_to_zip)
{
    char *zrun = make_run(); /* OpenImageIO writes ZIP */
    fx_run r;
    fx_make(&r);
    char *run = tpath("run-rle");
    fx_write(&r, run);
    fx_free(&r);
    eng_error err = {{0}};
    for (int i = 0; i < FX_FRAMES; i++) {
        char file[64];
        snprintf(file, sizeof file, "frames/%06d.exr", i);
        char *p = rep_path_join(run, file);
        int rewritten = 0;
        ck_assert_msg(cap_recompress_exr(p, p, CAP_COMPRESSION_RLE, &rewritten, &err) == ENG_OK, "%s", err.msg);
        ck_assert_int_eq(rewritten, 1);
        ck_assert_int_eq(exr_compression_of(p), EXR_COMPRESSION_RLE);
        free(p);
    }
    char *gold = tpath("goldens/from-rle");
    ck_assert_msg(rep_bless(run, gold, &err) == ENG_OK, "%s", err.msg);
    for (int i = 0; i < FX_FRAMES; i++) {
        char file[64];
        snprintf(file, sizeof file, "frames/%06d.exr", i);
        char *g = rep_path_join(gold, file), *p = rep_path_join(run, file);
        ck_assert_int_eq(exr_compression_of(g), EXR_COMPRESSION_ZIP);
        ck_assert_int_eq(exr_compression_of(p), EXR_COMPRESSION_RLE); /* the run untouched */
        free(g);
        free(p);
    }
    char *gm = rep_path_join(gold, "manifest.json"), *rm = rep_path_join(run, "manifest.json");
    cJSON *gj = load_json(gm), *rj = load_json(rm);
    ck_assert_str_eq(str_of(cJSON_GetObjectItem(gj, "capture"), "compression"), "zip");
    cJSON_DeleteItemFromObject(gj, "capture");
    ck_assert(cJSON_Compare(gj, rj, 1)); /* nothing else in the manifest changed */
    cJSON_Delete(gj);
    cJSON_Delete(rj);
    free(gm);
    free(rm);
    ck_assert_msg(replay(run, gold, &err) == REP_OK, "%s", err.msg);
    cJSON *rep = report_of(run);
    ck_assert_double_eq(num_of(cJSON_GetObjectItem(rep, "counts"), "bit-exact"), 9);
    cJSON_Delete(rep);

    /* A golden blessed from the ZIP run: bit-exact against the rle run, nothing to bless. */
    char *zgold = tpath("goldens/from-zip");
    ck_assert_msg(rep_bless(zrun, zgold, &err) == ENG_OK, "%s", err.msg);
    const char *names[] = {"manifest.json", "frames/000000.exr", "frames/000002.exr"};
    for (int i = 0; i < 3; i++) {
        char *a = rep_path_join(zrun, names[i]), *b = rep_path_join(zgold, names[i]);
        char *x = NULL, *y = NULL;
        size_t lx = 0, ly = 0;
        ck_assert_int_eq(eng_read_file(a, 1 << 24, &x, &lx, &err), ENG_OK);
        ck_assert_int_eq(eng_read_file(b, 1 << 24, &y, &ly, &err), ENG_OK);
        ck_assert_msg(lx == ly && memcmp(x, y, lx) == 0, "%s: not copied byte for byte", names[i]);
        free(x);
        free(y);
        free(a);
        free(b);
    }
    rep_bless_options o = {run, zgold, 0, NULL};
    rep_bless_outcome out;
    ck_assert_msg(rep_bless_reviewed(&o, NULL, &out, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(out, REP_BLESS_SAME);
    free(zgold);
    free(gold);
    free(run);
    free(zrun);
}
END_TEST

/* A manifest with only what provenance reads: settings, tool, frames with two passes p and q. */
static char *prov_manifest(const char *name, double a, int threads, const char *git, double q_ms)
{
    char *dir = tpath(name);
    eng_error err = {{0}};
    ck_assert_int_eq(rep_mkdirs(dir, &err), ENG_OK);
    char *text = rep_xprintf("{\"tool\": {\"version\": \"0.1.0\", \"git\": \"%s\"},"
                             " \"settings\": {\"a\": %g, \"threads\": %d},"
                             " \"frames\": [{\"passes\": [{\"name\": \"p\", \"ms\": 1}, {\"name\": \"q\", \"ms\": %g}]},"
                             "  {\"passes\": [{\"name\": \"p\", \"ms\": 2}, {\"name\": \"q\", \"ms\": %g}]},"
                             "  {\"passes\": [{\"name\": \"p\", \"ms\": 1}, {\"name\": \"q\", \"ms\": %g}]}]}",
                             git, a, threads, q_ms, 2 * q_ms, q_ms);
    char *mp = rep_path_join(dir, "manifest.json");
    ck_assert_int_eq(rep_write_atomic(mp, text, strlen(text), &err), ENG_OK);
    free(mp);
    free(text);
    return dir;
}

static const rep_prov_item *prov_find(const rep_prov *p, const char *key)
{
    for (size_t i = 0; i < p->count; i++)
        if (strcmp(p->items[i].key, key) == 0)
            return &p->items[i];
    return NULL;
}

START_TEST(prov_settings_warn_git_and_threads_inform)
{
    char *run = prov_manifest("prun", 1, 2, "aaa", 3), *gold = prov_manifest("pgold", 2, 4, "bbb", 1);
    rep_prov *p = NULL;
    eng_error err = {{0}};
    ck_assert_msg(rep_prov_compare(run, gold, 0, 0, &p, &err) == ENG_OK, "%s", err.msg);
    ck_assert_uint_eq(p->count, 3);
    const rep_prov_item *it = prov_find(p, "settings.a");
    ck_assert_ptr_nonnull(it);
    ck_assert_int_eq(it->level, REP_PROV_WARN);
    ck_assert_str_eq(it->run, "1");
    ck_assert_str_eq(it->golden, "2");
    ck_assert_int_eq(prov_find(p, "settings.threads")->level, REP_PROV_INFO);
    ck_assert_int_eq(prov_find(p, "tool.git")->level, REP_PROV_INFO);
    ck_assert_int_eq(p->warn, 1);
    ck_assert_int_eq(p->fail, 0);
    /* timing: q is 3/4 of every run frame, 1/2 of every golden frame */
    ck_assert_int_eq(p->timing_count, 2);
    ck_assert_str_eq(p->timing[1].name, "q");
    ck_assert_double_eq_tol(p->timing[1].run_share, 0.75, 1e-12);
    ck_assert_double_eq_tol(p->timing[1].golden_share, 0.5, 1e-12);
    ck_assert_double_eq_tol(p->timing[1].ratio, 1.5, 1e-12);
    ck_assert_double_eq_tol(p->timing[0].ratio, 0.5, 1e-12);
    ck_assert_int_eq(p->timing_failed, 0); /* reported only */
    rep_prov_free(p);
    /* --provenance-fail and --timing-fail */
    ck_assert_int_eq(rep_prov_compare(run, gold, 1, 1.4, &p, &err), ENG_OK);
    ck_assert_int_eq(prov_find(p, "settings.a")->level, REP_PROV_FAIL);
    ck_assert_int_eq(prov_find(p, "tool.git")->level, REP_PROV_INFO);
    ck_assert_int_eq(p->fail, 1);
    ck_assert_int_eq(p->timing_failed, 1);
    ck_assert_int_eq(p->timing[1].failed, 1);
    rep_sb sb = {0};
    rep_prov_text(&sb, p);
    rep_timing_text(&sb, p);
    ck_assert_ptr_nonnull(strstr(sb.s, "fail settings.a: golden 2, run 1"));
    ck_assert_ptr_nonnull(strstr(sb.s, "over --timing-fail 1.4"));
    free(sb.s);
    rep_prov_free(p);
    /* the same manifest: nothing differs */
    ck_assert_int_eq(rep_prov_compare(run, run, 0, 0, &p, &err), ENG_OK);
    ck_assert_uint_eq(p->count, 0);
    ck_assert_double_eq(p->timing[0].ratio, 1);
    rep_prov_free(p);
    free(run);
    free(gold);
}
END_TEST

static char *read_text(const char *path); /* html and junit reports, below */

START_TEST(e2e_bless_reviewed_refuses_without_accept)
{
    char *run = make_run();
    char *golden = tpath("goldens/reviewed");
    char *bless_md = rep_path_join(golden, "BLESS.md");
    char *manifest = rep_path_join(golden, "manifest.json");
    eng_error err = {{0}};
    rep_bless_options o = {run, golden, 0, NULL};
    rep_bless_outcome out;
    ck_assert_msg(rep_bless_reviewed(&o, NULL, &out, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(out, REP_BLESS_NEW);
    ck_assert(rep_is_file(bless_md));
    char *md = read_text(bless_md);
    ck_assert_ptr_nonnull(strstr(md, "new golden"));
    free(md);
    ck_assert_int_eq(rep_bless_reviewed(&o, NULL, &out, &err), ENG_OK);
    ck_assert_int_eq(out, REP_BLESS_SAME);
    /* one pixel moves: refused without accept, the golden untouched */
    fx_run r;
    fx_make(&r);
    *fx_at(&r, 1, 1, 3, 2, 1) += 0.5f;
    char *run2 = tpath("run2");
    fx_write(&r, run2);
    fx_free(&r);
    char *before = read_text(manifest);
    o.run_dir = run2;
    ck_assert_int_eq(rep_bless_reviewed(&o, NULL, &out, &err), ENG_OK);
    ck_assert_int_eq(out, REP_BLESS_REFUSED);
    char *after = read_text(manifest);
    ck_assert_str_eq(before, after);
    free(after);
    md = read_text(bless_md);
    ck_assert_ptr_nonnull(strstr(md, "new golden")); /* still the first review */
    free(md);
    char *review = tpath("run2/bless/report.html");
    ck_assert(rep_is_file(review));
    free(review);
    /* accepted: replaced, and the review names the buffer that moved */
    o.accept = 1;
    ck_assert_int_eq(rep_bless_reviewed(&o, NULL, &out, &err), ENG_OK);
    ck_assert_int_eq(out, REP_BLESS_REPLACED);
    md = read_text(bless_md);
    ck_assert_ptr_nonnull(strstr(md, "direct.radiance"));
    ck_assert_ptr_nonnull(strstr(md, "**FAIL**"));
    free(md);
    ck_assert_msg(replay(run2, golden, &err) == REP_OK, "%s", err.msg);
    free(before);
    free(run2);
    free(manifest);
    free(bless_md);
    free(golden);
    free(run);
}
END_TEST

START_TEST(e2e_bless_keeps_tolerances)
{
    char *golden = make_golden();
    char *tol = rep_path_join(golden, "tolerances.json");
    const char *mine = "{\"buffers\": [{\"match\": \"direct.*\", \"fail\": 0.75, \"failpercent\": 1}]}\n";
    eng_error err = {{0}};
    ck_assert_int_eq(rep_write_atomic(tol, mine, strlen(mine), &err), ENG_OK);
    fx_run r;
    fx_make(&r);
    *fx_at(&r, 0, 1, 0, 0, 0) += 0.125f;
    char *run = tpath("run");
    fx_write(&r, run);
    ck_assert_msg(rep_bless(run, golden, &err) == ENG_OK, "%s", err.msg);
    char *text = NULL;
    size_t len;
    ck_assert_int_eq(eng_read_file(tol, 4096, &text, &len, &err), ENG_OK);
    ck_assert_str_eq(text, mine);
    free(text);
    /* The golden is now the changed run. */
    ck_assert_int_eq(replay(run, golden, &err), REP_OK);
    fx_free(&r);
    free(run);
    free(tol);
    free(golden);
}
END_TEST

START_TEST(e2e_bless_refuses_incomplete)
{
    fx_run r;
    fx_make(&r);
    char *golden = make_golden();
    char *run = tpath("run-incomplete");
    fx_write_ex(&r, run, 0, 0);
    eng_error err = {{0}};
    ck_assert_int_eq(rep_bless(run, golden, &err), ENG_ERR_INVALID);
    free(run);
    run = tpath("run-nomanifest");
    fx_write_ex(&r, run, 1, 1);
    ck_assert_int_eq(rep_bless(run, golden, &err), ENG_ERR_INVALID);
    free(run);
    run = tpath("run-truncated");
    fx_write(&r, run);
    char *f = rep_path_join(run, "frames/000000.exr");
    ck_assert_int_eq(truncate(f, file_size(f) - 50), 0);
    ck_assert_int_eq(rep_bless(run, golden, &err), ENG_ERR_INVALID);
    ck_assert_int_eq(unlink(f), 0);
    ck_assert_int_eq(rep_bless(run, golden, &err), ENG_ERR_INVALID);
    /* The old golden is untouched. */
    ck_assert_int_eq(replay(golden, NULL, &err), REP_OK);
    free(f);
    free(run);
    free(golden);
    fx_free(&r);
}
END_TEST

START_TEST(e2e_text_report_lists_worst_first)
{
    char *golden = make_golden();
    fx_run r;
    fx_make(&r);
    *fx_at(&r, 0, 0, 1, 1, 0) += 1e-6f;  /* frame 0: warn (built-in warn 0, under fail) */
    *fx_at(&r, 2, 1, 5, 5, 2) += 0.25f;  /* frame 2: fail */
    *fx_at(&r, 1, 1, 4, 4, 0) += 0.003f; /* frame 1: fail, smaller error */
    char *run = tpath("run");
    fx_write(&r, run);
    char *sp = tpath("summary.txt");
    FILE *summary = fopen(sp, "w");
    ck_assert_ptr_nonnull(summary);
    rep_options o = {0};
    o.run_dir = run;
    o.golden_dir = golden;
    eng_error err;
    ck_assert_int_eq(rep_replay(&o, summary, &err), REP_FAIL);
    fclose(summary);
    char *p = rep_path_join(run, "replay/report.txt");
    char *txt = NULL, *sum = NULL;
    size_t len;
    ck_assert_int_eq(eng_read_file(p, 1 << 20, &txt, &len, &err), ENG_OK);
    ck_assert_int_eq(eng_read_file(sp, 1 << 20, &sum, &len, &err), ENG_OK);
    ck_assert_str_eq(txt, sum);
    const char *f2 = strstr(txt, "FAIL  frame 2  direct.radiance");
    const char *f1 = strstr(txt, "FAIL  frame 1  direct.radiance");
    const char *w0 = strstr(txt, "WARN  frame 0  gbuffer.position");
    const char *verdict = strstr(txt, "replay: FAIL");
    ck_assert_ptr_nonnull(f2);
    ck_assert_ptr_nonnull(f1);
    ck_assert_ptr_nonnull(w0);
    ck_assert_ptr_nonnull(verdict);
    ck_assert(f2 < f1 && f1 < w0 && w0 < verdict);
    /* Nothing but the header and the provenance line comes before the first failure. */
    const char *first = txt;
    while (strncmp(first, "replay: run", 11) == 0 || strncmp(first, "        ", 8) == 0 ||
           strncmp(first, "provenance: same", 16) == 0)
        first = strchr(first, '\n') + 1;
    ck_assert_ptr_eq(first, f2);
    free(txt);
    free(sum);
    free(p);

    /* Quiet: only failures and the verdict line. */
    summary = fopen(sp, "w");
    o.quiet = 1;
    ck_assert_int_eq(rep_replay(&o, summary, &err), REP_FAIL);
    fclose(summary);
    ck_assert_int_eq(eng_read_file(sp, 1 << 20, &sum, &len, &err), ENG_OK);
    ck_assert_ptr_null(strstr(sum, "WARN"));
    ck_assert_ptr_null(strstr(sum, "golden "));
    ck_assert(strncmp(sum, "FAIL  frame 2", 13) == 0);
    ck_assert_ptr_nonnull(strstr(sum, "replay: FAIL — 2 failed, 1 warned, 0 within tolerance, 6 bit-exact (9 buffers, 3 frames)"));
    free(sum);
    free(sp);
    fx_free(&r);
    free(run);
    free(golden);
}
END_TEST

/* ---------------------------------------------------------------- html and junit reports */

static char *read_text(const char *path)
{
    char *text = NULL;
    size_t len = 0;
    eng_error err;
    ck_assert_msg(eng_read_file(path, 1 << 24, &text, &len, &err) == ENG_OK, "%s", err.msg);
    return text;
}

static int count_of(const char *hay, const char *needle)
{
    int n = 0;
    for (const char *p = strstr(hay, needle); p; p = strstr(p + 1, needle))
        n++;
    return n;
}

/* The value of attribute `name` in the first tag starting with `tag` at or after p. */
static char *attr_of(const char *p, const char *tag, const char *name)
{
    const char *t = strstr(p, tag);
    ck_assert_ptr_nonnull(t);
    const char *end = strchr(t, '>');
    char key[64];
    snprintf(key, sizeof key, " %s=\"", name);
    const char *a = strstr(t, key);
    ck_assert_msg(a && a < end, "%s has no %s", tag, name);
    a += strlen(key);
    return rep_xprintf("%.*s", (int)(strchr(a, '"') - a), a);
}

static int img_files(const char *run)
{
    char *dir = rep_path_join(run, "replay/img");
    char *cmd = rep_xprintf("ls '%s' 2>/dev/null | grep -c '\\.png$'", dir);
    FILE *f = popen(cmd, "r");
    int n = -1;
    ck_assert_ptr_nonnull(f);
    ck_assert_int_eq(fscanf(f, "%d", &n), 1);
    pclose(f);
    free(cmd);
    free(dir);
    return n;
}

/* The images report.html makes from what the walk kept (keep.c: parts and ꟻLIP maps) are the
 * bytes it makes when it decodes the frames and runs ꟻLIP again (no keep), whatever is kept. */
START_TEST(report_kept_parts_give_the_same_images)
{
    char *golden = make_golden();
    fx_run r;
    fx_make(&r);
    *fx_at(&r, 0, 1, 2, 3, 0) += 0.5f; /* frame 0 direct.radiance: a card with a ꟻLIP map */
    *fx_at(&r, 1, 0, 1, 1, 2) += 0.25f; /* frame 1 gbuffer.position: a card without */
    char *run = tpath("run");
    fx_write(&r, run);
    char *kept_dir = tpath("rep-kept"), *plain_dir = tpath("rep-plain");
    rep_options o = {0};
    o.run_dir = run;
    o.golden_dir = golden;
    o.quiet = 1;
    o.report_dir = kept_dir;
    rep_report rr;
    eng_error err;
    ck_assert_int_eq(rep_replay_report(&o, &rr, &err), REP_FAIL);
    ck_assert_ptr_nonnull(rr.keep);
    ck_assert_ptr_nonnull(rep_keep_find_part(rr.keep, 0, REP_KEEP_RUN, "direct.radiance"));
    ck_assert_ptr_nonnull(rep_keep_find_part(rr.keep, 0, REP_KEEP_GOLDEN, "direct.radiance"));
    ck_assert_ptr_nonnull(rep_keep_find_flip(rr.keep, 0, "direct.radiance"));
    ck_assert_ptr_nonnull(rep_keep_find_part(rr.keep, 1, REP_KEEP_RUN, "gbuffer.position"));
    ck_assert_ptr_null(rep_keep_find_part(rr.keep, 1, REP_KEEP_RUN, "shadow.light0")); /* bit-exact */
    rep_keep_free(rr.keep);
    rr.keep = NULL;
    ck_assert_msg(rep_report_write(&rr, plain_dir, &err) == ENG_OK, "%s", err.msg);
    static const char *const imgs[] = {"0000-f000000-direct.radiance-golden.png", "0001-f000000-direct.radiance-new.png",
                                       "0002-f000000-direct.radiance-diff.png", "0003-f000000-direct.radiance-flip.png",
                                       "0006-f000001-gbuffer.position-golden.png"};
    for (size_t i = 0; i < sizeof imgs / sizeof imgs[0]; i++) {
        char *rel = rep_xprintf("img/%s", imgs[i]);
        char *a = rep_path_join(kept_dir, rel), *b = rep_path_join(plain_dir, rel);
        char *ba = NULL, *bb = NULL;
        size_t la = 0, lb = 0;
        ck_assert_msg(eng_read_file(a, 1 << 24, &ba, &la, &err) == ENG_OK, "%s", err.msg);
        ck_assert_msg(eng_read_file(b, 1 << 24, &bb, &lb, &err) == ENG_OK, "%s", err.msg);
        ck_assert_msg(la == lb && memcmp(ba, bb, la) == 0, "%s differs", imgs[i]);
        free(ba);
        free(bb);
        free(a);
        free(b);
        free(rel);
    }
    rep_report_free(&rr);
    free(kept_dir);
    free(plain_dir);
    free(run);
    free(golden);
    fx_free(&r);
}
END_TEST

START_TEST(report_junit_and_html_name_the_failure)
{
    char *golden = make_golden();
    fx_run r;
    fx_make(&r);
    *fx_at(&r, 0, 0, 1, 1, 0) += 1e-6f; /* frame 0 gbuffer.position: a warning */
    *fx_at(&r, 1, 1, 3, 2, 1) += 0.5f;  /* frame 1 direct.radiance: the failure */
    char *run = tpath("run");
    fx_write(&r, run);
    eng_error err;
    ck_assert_int_eq(replay(run, golden, &err), REP_FAIL);

    char *xp = rep_path_join(run, "replay/report.junit.xml");
    char *xml = read_text(xp);
    const char *suite = strstr(xml, "<testsuite ");
    ck_assert_ptr_nonnull(suite);
    char *v = attr_of(suite, "<testsuite ", "tests");
    ck_assert_str_eq(v, "11"); /* 9 buffers, provenance and timing */
    free(v);
    v = attr_of(suite, "<testsuite ", "failures");
    ck_assert_str_eq(v, "1");
    free(v);
    v = attr_of(suite, "<testsuite ", "errors");
    ck_assert_str_eq(v, "0");
    free(v);
    v = attr_of(suite, "<testsuite ", "name");
    ck_assert_str_eq(v, "ispm.fixture");
    free(v);
    ck_assert_int_eq(count_of(xml, "<testcase "), 11);
    ck_assert_int_eq(count_of(xml, "<failure "), 1);
    ck_assert_int_eq(count_of(xml, "<skipped"), 0);
    ck_assert_int_eq(count_of(xml, "<system-out>"), 3); /* the warning, provenance and timing */
    /* The testcase that holds the failure is direct.radiance of frame 1. */
    const char *f = strstr(xml, "<failure ");
    const char *tc = xml;
    for (const char *p = strstr(xml, "<testcase "); p && p < f; p = strstr(p + 1, "<testcase "))
        tc = p;
    v = attr_of(tc, "<testcase ", "name");
    ck_assert_str_eq(v, "direct.radiance");
    free(v);
    v = attr_of(tc, "<testcase ", "classname");
    ck_assert_str_eq(v, "ispm.fixture.frame000001");
    free(v);
    v = attr_of(f, "<failure ", "type");
    ck_assert_str_eq(v, "fail");
    free(v);

    /* HTML: the failure's card comes first, then the warning's; its images exist. */
    char *hp = rep_path_join(run, "replay/report.html");
    char *html = read_text(hp);
    const char *card = strstr(html, "<article class=\"entry ");
    ck_assert_ptr_nonnull(card);
    v = attr_of(card, "<article ", "data-buffer");
    ck_assert_str_eq(v, "direct.radiance");
    free(v);
    v = attr_of(card, "<article ", "data-frame");
    ck_assert_str_eq(v, "1");
    free(v);
    v = attr_of(card, "<article ", "class");
    ck_assert_str_eq(v, "entry fail");
    free(v);
    v = attr_of(card + 1, "<article ", "data-buffer");
    ck_assert_str_eq(v, "gbuffer.position");
    free(v);
    ck_assert_int_eq(count_of(html, "<article "), 2);
    ck_assert_ptr_null(strstr(html, "http://"));
    ck_assert_ptr_null(strstr(html, "https://"));
    int imgs = 0;
    for (const char *p = strstr(html, "<img "); p; p = strstr(p + 1, "<img ")) {
        char *src = attr_of(p, "<img ", "src");
        char *dir = rep_path_join(run, "replay");
        char *file = rep_path_join(dir, src);
        ck_assert_msg(rep_is_file(file), "%s missing", file);
        free(file);
        free(dir);
        free(src);
        imgs++;
    }
    ck_assert_int_ge(imgs, 6);
    /* golden, new, diff for each of two cards, the ꟻLIP heat map of the colour buffer
     * (direct.radiance), golden and new of frame 0 and frame 2's final image */
    ck_assert_int_eq(img_files(run), 11);
    ck_assert_ptr_nonnull(strstr(html, "-f000001-direct.radiance-flip.png"));

    free(html);
    free(hp);
    free(xml);
    free(xp);
    fx_free(&r);
    free(run);
    free(golden);
}
END_TEST

START_TEST(report_green_run_stays_small)
{
    char *golden = make_golden();
    eng_error err;
    ck_assert_int_eq(replay(golden, golden, &err), REP_OK);
    /* Only the final image of the first and the last frame, golden and new. */
    ck_assert_int_eq(img_files(golden), 4);
    char *xp = rep_path_join(golden, "replay/report.junit.xml");
    char *xml = read_text(xp);
    ck_assert_int_eq(count_of(xml, "<testcase "), 11); /* 9 buffers, provenance and timing */
    ck_assert_int_eq(count_of(xml, "<failure"), 0);
    free(xml);
    free(xp);
    char *hp = rep_path_join(golden, "replay/report.html");
    char *html = read_text(hp);
    ck_assert_int_eq(count_of(html, "<article "), 0);
    free(html);
    free(hp);
    free(golden);
}
END_TEST

START_TEST(report_unreadable_run_is_a_junit_error)
{
    char *golden = make_golden();
    char *run = tpath("run");
    fx_run r;
    fx_make(&r);
    fx_write_ex(&r, run, 1, 1); /* no manifest */
    eng_error err;
    ck_assert_int_eq(replay(run, golden, &err), REP_UNREADABLE);
    char *xp = rep_path_join(run, "replay/report.junit.xml");
    char *xml = read_text(xp);
    char *v = attr_of(strstr(xml, "<testsuite "), "<testsuite ", "errors");
    ck_assert_str_eq(v, "1");
    free(v);
    ck_assert_int_eq(count_of(xml, "<error "), 1);
    free(xml);
    free(xp);
    char *hp = rep_path_join(run, "replay/report.html");
    ck_assert(rep_is_file(hp));
    free(hp);
    fx_free(&r);
    free(run);
    free(golden);
}
END_TEST

START_TEST(report_xml_escapes_everything)
{
    rep_sb sb = {0};
    rep_sb_xml(&sb, "a<b>&\"c'\x01\tz\xff\xc3\xa9\xed\xa0\x80\xef\xbf\xbe");
    /* é (U+00E9) is kept; a control byte, a stray 0xFF, a UTF-16 surrogate and U+FFFE are not. */
    ck_assert_str_eq(sb.s, "a&lt;b&gt;&amp;&quot;c&#39;\xEF\xBF\xBD\tz\xEF\xBF\xBD\xC3\xA9"
                           "\xEF\xBF\xBD\xEF\xBF\xBD");
    free(sb.s);

    rep_report r;
    memset(&r, 0, sizeof r);
    r.run_dir = "runs/<x>";
    r.golden_dir = "g&g";
    r.frames = 1;
    r.digest_frame = -1;
    rep_entry *e = rep_report_add(&r, 0, "evil<\"buffer\">&");
    e->verdict = REP_V_FAIL;
    e->problem = REP_PROB_EXTRA;
    r.exit = rep_report_exit(&r);
    char *xml = rep_report_junit(&r, "s<q>");
    ck_assert_ptr_null(strstr(xml, "evil<"));
    ck_assert_ptr_null(strstr(xml, "<x>"));
    ck_assert_ptr_nonnull(strstr(xml, "name=\"evil&lt;&quot;buffer&quot;&gt;&amp;\""));
    ck_assert_ptr_nonnull(strstr(xml, "classname=\"ispm.s&lt;q&gt;.frame000000\""));
    ck_assert_ptr_nonnull(strstr(xml, "type=\"extra\""));
    free(xml);
    rep_report_free(&r);
}
END_TEST

START_TEST(report_thumbnails_map_and_mark)
{
    static const char *const RGB[] = {"R", "G", "B"};
    float a[4 * 2 * 3], b[4 * 2 * 3];
    for (int i = 0; i < 24; i++)
        a[i] = b[i] = 0.5f;
    a[(1 * 4 + 2) * 3 + 0] = 0.75f; /* (2,1).R differs */
    a[(0 * 4 + 3) * 3 + 1] = NAN;   /* (3,0).G NaN in run only */
    eng_buffer run = {"composite.radiance", 4, 2, 3, RGB, a}, gold = {"composite.radiance", 4, 2, 3, RGB, b};
    rep_thumb_map m;
    rep_thumb_map_make(run.name, &run, &gold, &m);
    ck_assert_int_eq(m.kind, REP_THUMB_RADIANCE);
    ck_assert_int_eq(m.n, 3);
    int w, h;
    unsigned char *px = rep_thumb_render(&run, &m, &w, &h);
    ck_assert_int_eq(w, 4);
    ck_assert_int_eq(h, 2);
    ck_assert_int_eq(px[0], 188); /* sRGB(0.5) */
    ck_assert(px[3 * 3 + 0] == 255 && px[3 * 3 + 1] == 0 && px[3 * 3 + 2] == 255); /* NaN: magenta */
    free(px);
    double scale;
    px = rep_thumb_diff(&run, &gold, &scale, &w, &h);
    ck_assert_double_eq_tol(scale, 0.25, 1e-9);
    ck_assert(px[0] == 0 && px[1] == 0 && px[2] == 0);                       /* equal: black */
    ck_assert(px[(4 + 2) * 3] == 255 && px[(4 + 2) * 3 + 2] == 255);         /* the maximum: white */
    ck_assert(px[3 * 3] == 255 && px[3 * 3 + 1] == 0 && px[3 * 3 + 2] == 255); /* class change: magenta */
    free(px);

    /* Data buffers share one ramp over golden and run. */
    static const char *const Z[] = {"Z"};
    float za[2] = {1, 2}, zb[2] = {0, 4};
    eng_buffer ra = {"shadow.light0", 2, 1, 1, Z, za}, rb = {"shadow.light0", 2, 1, 1, Z, zb};
    rep_thumb_map_make(ra.name, &ra, &rb, &m);
    ck_assert_int_eq(m.kind, REP_THUMB_DATA);
    ck_assert_double_eq(m.lo, 0);
    ck_assert_double_eq(m.hi, 4);
    int tw, th;
    rep_thumb_size(1000, 500, &tw, &th);
    ck_assert_int_eq(tw, REP_THUMB_MAX_SIDE);
    ck_assert_int_eq(th, REP_THUMB_MAX_SIDE / 2);
}
END_TEST

/* A display buffer's bytes are lround(v * 255) of its values, ties away from zero, at and beside
 * every tie (k + 0.5) / 255 (thumb.c rounds without libm); a scaled thumbnail averages the same
 * source boxes in every row (the column boxes are computed once). */
/* rep_median (provenance's timing, ispm info and bench): the middle value, the mean of the
 * middle two, NAN for none; v comes back sorted. */
START_TEST(median_of_doubles)
{
    double odd[] = {5, 1, 4, 2, 3};
    ck_assert(rep_median(odd, 5) == 3.0);
    ck_assert(odd[0] == 1.0 && odd[4] == 5.0);
    double even[] = {10, -2, 7, 1};
    ck_assert(rep_median(even, 4) == 4.0);
    double one[] = {0.25};
    ck_assert(rep_median(one, 1) == 0.25);
    ck_assert(isnan(rep_median(one, 0)));
}
END_TEST

START_TEST(report_thumbnail_bytes_round_as_lround)
{
    static const char *const RGB[] = {"R", "G", "B"};
    enum { W = 255 * 7 };
    float *a = malloc((size_t)W * 3 * sizeof *a);
    ck_assert_ptr_nonnull(a);
    for (int k = 0; k < 255; k++) {
        float t = (float)(((double)k + 0.5) / 255.0);
        float near[7] = {t, nextafterf(t, 0), nextafterf(t, 1), nextafterf(nextafterf(t, 0), 0),
                         nextafterf(nextafterf(t, 1), 1), (float)((double)k / 255.0), (float)(((double)k + 0.25) / 255.0)};
        for (int j = 0; j < 7; j++)
            for (int c = 0; c < 3; c++)
                a[((size_t)k * 7 + (size_t)j) * 3 + (size_t)c] = near[j];
    }
    eng_buffer run = {"final.display", W, 1, 3, RGB, a};
    rep_thumb_map m;
    rep_thumb_map_make(run.name, &run, NULL, &m);
    ck_assert_int_eq(m.kind, REP_THUMB_DISPLAY);
    int w, h;
    unsigned char *px = rep_image_render(&run, &m, 0, &w, &h);
    ck_assert_int_eq(w, W);
    for (int i = 0; i < W; i++) {
        double v = a[(size_t)i * 3];
        long want = v > 0 ? (v >= 1 ? 255 : lround(v * 255.0)) : 0;
        ck_assert_msg(px[(size_t)i * 3] == want, "value %.9g: byte %d, lround %ld", v, px[(size_t)i * 3], want);
    }
    free(px);
    /* 5 x 3 source, 2 x 1 thumbnail: columns [0,2) and [2,5), rows [0,3) */
    float s[5 * 3 * 3];
    for (int y = 0; y < 3; y++)
        for (int x = 0; x < 5; x++)
            for (int c = 0; c < 3; c++)
                s[(y * 5 + x) * 3 + c] = (float)(x + 5 * y) / 20.0f;
    eng_buffer src = {"final.display", 5, 3, 3, RGB, s};
    px = rep_image_render(&src, &m, 2, &w, &h);
    ck_assert_int_eq(w, 2);
    ck_assert_int_eq(h, 1);
    ck_assert_int_eq(px[0], lround((0 + 1 + 5 + 6 + 10 + 11) / 20.0 / 6.0 * 255.0));
    ck_assert_int_eq(px[3], lround((2 + 3 + 4 + 7 + 8 + 9 + 12 + 13 + 14) / 20.0 / 9.0 * 255.0));
    free(px);
    free(a);
}
END_TEST

/* ---------------------------------------------------------------- suite */

static Suite *replay_suite(void)
{
    Suite *s = suite_create("replay");
    TCase *unit = tcase_create("logic");
    tcase_add_checked_fixture(unit, tmp_setup, tmp_teardown);
    tcase_add_test(unit, tol_first_match_wins_and_defaults_fill);
    tcase_add_test(unit, tol_builtin_defaults);
    tcase_add_test(unit, tol_rejects_bad_files);
    tcase_add_test(unit, tol_missing_file);
    tcase_add_test(unit, tol_flags_override_default_and_inherited_keys);
    tcase_add_test(unit, progress_plain_lines_with_time_left);
    tcase_add_test(unit, photon_map_compared_as_paths);
    tcase_add_test(unit, cmp_identical_is_bitexact);
    tcase_add_test(unit, cmp_negative_thresholds_fail_equal_values);
    tcase_add_test(unit, cmp_tiny_diff_within_or_warn);
    tcase_add_test(unit, cmp_failpercent);
    tcase_add_test(unit, cmp_hardfail);
    tcase_add_test(unit, cmp_relative_threshold);
    tcase_add_test(unit, cmp_rmse_threshold);
    tcase_add_test(unit, cmp_exact_mode);
    tcase_add_test(unit, cmp_nan_in_run_fails_whatever_the_tolerance);
    tcase_add_test(unit, cmp_nan_in_both_is_not_a_failure);
    tcase_add_test(unit, cmp_pinf_vs_ninf_fails);
    tcase_add_test(unit, cmp_size_and_channels);
    tcase_add_test(unit, report_xml_escapes_everything);
    tcase_add_test(unit, report_thumbnails_map_and_mark);
    tcase_add_test(unit, report_thumbnail_bytes_round_as_lround);
    tcase_add_test(unit, median_of_doubles);
    suite_add_tcase(s, unit);

    TCase *files = tcase_create("files");
    tcase_add_checked_fixture(files, tmp_setup, tmp_teardown);
    tcase_set_timeout(files, 120);
    tcase_add_test(files, shim_round_trip);
    tcase_add_test(files, shim_rejects_garbage);
    tcase_add_test(files, shim_rejects_lying_header_sizes);
    tcase_add_test(files, exr_reader_matches_oiio);
    tcase_add_test(files, exr_reader_truncated_file);
    tcase_add_test(files, exr_reader_leaves_other_files_to_oiio);
    tcase_add_test(files, png_writer_matches_oiio);
    tcase_add_test(files, e2e_identical_is_bitexact);
    tcase_add_test(files, e2e_one_pixel_changed);
    tcase_add_test(files, e2e_nan_fails);
    tcase_add_test(files, e2e_missing_and_extra_buffer);
    tcase_add_test(files, e2e_missing_frame);
    tcase_add_test(files, e2e_size_mismatch);
    tcase_add_test(files, e2e_truncated_exr_is_unreadable);
    tcase_add_test(files, e2e_tampered_exr_is_unreadable);
    tcase_add_test(files, e2e_pixels_disagree_with_manifest_digest);
    tcase_add_test(files, e2e_manifest_missing_or_incomplete);
    tcase_add_test(files, e2e_lying_manifests_are_unreadable);
    tcase_add_test(files, e2e_bad_tolerances_are_unreadable);
    tcase_add_test(files, e2e_no_golden_integrity_only);
    tcase_add_test(files, e2e_bless_then_replay_passes);
    tcase_add_test(files, e2e_bless_recompresses_to_zip);
    tcase_add_test(files, e2e_bless_keeps_tolerances);
    tcase_add_test(files, e2e_bless_reviewed_refuses_without_accept);
    tcase_add_test(files, prov_settings_warn_git_and_threads_inform);
    tcase_add_test(files, e2e_bless_refuses_incomplete);
    tcase_add_test(files, e2e_text_report_lists_worst_first);
    tcase_add_test(files, report_junit_and_html_name_the_failure);
    tcase_add_test(files, report_kept_parts_give_the_same_images);
    tcase_add_test(files, report_green_run_stays_small);
    tcase_add_test(files, report_unreadable_run_is_a_junit_error);
    suite_add_tcase(s, files);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(replay_suite());
    /* Not forking by default: OpenImageIO pulls in log4cplus 2.0 (through OpenVDB), whose thread
     * pool, started when the library loads, deadlocks exit() in a forked child, so every forked
     * test would hang until its timeout. CK_FORK=yes still forces forking. */
    if (!getenv("CK_FORK"))
        srunner_set_fork_status(sr, CK_NOFORK);
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
