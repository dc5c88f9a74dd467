/* stab_report.c — the stability part of a replay's result: each measured pass's verdict against
 * the "stability" limits of tolerances.json (a limit, or the golden's own value times a margin),
 * and the per-pixel flicker written as a run folder of its own (RUN/replay/stability:
 * frames/NNNNNN.exr with one Y part stability.<part> per measured pass, manifest.json last, so
 * ispm-view opens it like any run). The run is written into a temporary folder that replaces the
 * old one only once its manifest is complete (replay.c does the rename). rep_stab_report owns
 * both runs' measures and the verdicts, and is freed whole by rep_stab_report_free.
 */
#define _POSIX_C_SOURCE 200809L

#include "rep_compare.h"
#include "rep_run.h"
#include "rep_stab.h"

#include "cap.h"
#include "rep_util.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char *print_json(cJSON *o)
{
    char *t = cJSON_PrintUnformatted(o);
    if (!t) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    char *s = rep_xstrdup(t);
    cJSON_free(t);
    return s;
}

/* ---------------------------------------------------------------- verdicts */

static void over(rep_sb *why, const char *what, double v, double lim)
{
    if (isfinite(lim) && v > lim)
        rep_sb_printf(why, "%s%s %.3g over %.3g", why->len ? "; " : "", what, v, lim);
}

/* Only where the golden measured some pixels: a golden recorded without cameras has no
 * reprojected pixels, and 0 is then no value to hold a run to. */
static void over_golden(rep_sb *why, const char *what, double v, const rep_stab_stats *gs, double g, double margin)
{
    if (margin >= 0 && gs->pixels > 0 && isfinite(g) && isfinite(v) && v > g * (1.0 + margin))
        rep_sb_printf(why, "%s%s %.3g over golden %.3g × %.3g", why->len ? "; " : "", what, v, g, 1.0 + margin);
}

void rep_stab_judge(rep_stab_report *s, const rep_tolerances *tols)
{
    s->verdicts = rep_xcalloc((size_t)s->run.buffer_count ? (size_t)s->run.buffer_count : 1, sizeof *s->verdicts);
    s->failed = 0;
    for (int k = 0; k < s->run.buffer_count; k++) {
        const rep_stab_buffer *b = &s->run.buffers[k];
        rep_stab_verdict *v = &s->verdicts[k];
        if (!tols)
            continue;
        rep_tol t;
        v->tol_match = rep_xstrdup(rep_tol_lookup(tols, b->name, &t));
        v->tol = t.stab;
        v->checked = t.stab.set;
        if (!v->checked)
            continue;
        rep_sb why = {0};
        over(&why, "static mean", b->st.mean, t.stab.static_mean);
        over(&why, "static p99", b->st.p99, t.stab.static_p99);
        over(&why, "reprojected mean", b->rp.mean, t.stab.reprojected_mean);
        over(&why, "reprojected p99", b->rp.p99, t.stab.reprojected_p99);
        if (b->reference) {
            over(&why, "temporal std mean", b->tstd_mean, t.stab.temporal_std_mean);
            over(&why, "temporal std p99", b->tstd_p99, t.stab.temporal_std_p99);
        }
        const rep_stab_buffer *g = s->has_golden ? rep_stab_find(&s->golden, b->name) : NULL;
        if (g && t.stab.golden_margin >= 0) {
            over_golden(&why, "static mean", b->st.mean, &g->st, g->st.mean, t.stab.golden_margin);
            over_golden(&why, "static p99", b->st.p99, &g->st, g->st.p99, t.stab.golden_margin);
            over_golden(&why, "reprojected mean", b->rp.mean, &g->rp, g->rp.mean, t.stab.golden_margin);
            over_golden(&why, "reprojected p99", b->rp.p99, &g->rp, g->rp.p99, t.stab.golden_margin);
        } else if (!g && t.stab.golden_margin >= 0 && s->has_golden) {
            rep_sb_printf(&why, "%sgolden_margin: the golden has no %s to compare with", why.len ? "; " : "", b->name);
        }
        if (why.len) {
            v->failed = 1;
            v->why = why.s;
            s->failed++;
        }
    }
}

void rep_stab_report_free(rep_stab_report *s)
{
    if (!s)
        return;
    if (s->verdicts)
        for (int k = 0; k < s->run.buffer_count; k++) {
            free(s->verdicts[k].tol_match);
            free(s->verdicts[k].why);
        }
    free(s->verdicts);
    rep_stab_free(&s->run);
    rep_stab_free(&s->golden);
    free(s->reference_dir);
    free(s->out_dir);
    free(s);
}

/* ---------------------------------------------------------------- the stability run */

eng_result rep_stab_write_frame(const char *run_dir, const rep_frame_info *f, const rep_stab_run *st, float **flicker,
                                int count, char **rec, eng_error *err)
{
    static const char *const Y[] = {"Y"};
    *rec = NULL;
    char *file = rep_xprintf("frames/%06d.exr", f->index);
    char *path = rep_path_join(run_dir, file);
    eng_buffer *bufs = rep_xcalloc((size_t)(count ? count : 1), sizeof *bufs);
    char **names = rep_xcalloc((size_t)(count ? count : 1), sizeof *names);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "index", f->index);
    cJSON_AddNumberToObject(o, "time", f->time);
    cJSON_AddStringToObject(o, "file", file);
    if (f->has_camera) {
        cJSON *cam = cJSON_AddObjectToObject(o, "camera");
        cJSON *vp = cJSON_AddArrayToObject(cam, "view_proj"), *eye = cJSON_AddArrayToObject(cam, "eye");
        for (int k = 0; k < 16; k++)
            cJSON_AddItemToArray(vp, cJSON_CreateNumber(f->view_proj[k]));
        for (int k = 0; k < 3; k++)
            cJSON_AddItemToArray(eye, cJSON_CreateNumber(f->eye[k]));
    }
    cJSON *jb = cJSON_AddArrayToObject(o, "buffers");
    for (int k = 0; k < count; k++) {
        names[k] = rep_xprintf("stability.%s", st->buffers[k].name);
        bufs[k].name = names[k];
        bufs[k].width = st->width;
        bufs[k].height = st->height;
        bufs[k].channel_count = 1;
        bufs[k].channels = Y;
        bufs[k].data = flicker[k];
        char dg[40];
        eng_buffer_digest(&bufs[k], dg);
        cJSON *b = cJSON_CreateObject();
        cJSON_AddStringToObject(b, "name", names[k]);
        cJSON_AddNumberToObject(b, "width", st->width);
        cJSON_AddNumberToObject(b, "height", st->height);
        cJSON_AddItemToObject(b, "channels", cJSON_CreateStringArray(Y, 1));
        cJSON_AddStringToObject(b, "digest", dg);
        cJSON_AddNumberToObject(b, "nan", 0);
        cJSON_AddNumberToObject(b, "inf", 0);
        cJSON_AddItemToArray(jb, b);
    }
    /* Written like a recorded frame (capture's OpenEXR writer), so replay loads no OpenImageIO;
     * unsynced, as OpenImageIO wrote it (the folder is renamed into place whole). */
    const eng_buffer **ptrs = rep_xcalloc((size_t)(count ? count : 1), sizeof *ptrs);
    for (int k = 0; k < count; k++)
        ptrs[k] = &bufs[k];
    eng_result r = count > 0 ? cap_write_exr_unsynced(path, ptrs, count, err)
                             : eng_fail(err, ENG_ERR_INVALID, "%s: no image pass to measure", path);
    free(ptrs);
    if (r == ENG_OK)
        *rec = print_json(o);
    cJSON_Delete(o);
    for (int k = 0; k < count; k++)
        free(names[k]);
    free(names);
    free(bufs);
    free(path);
    free(file);
    return r;
}

eng_result rep_stab_write_manifest(const char *run_dir, const char *sequence_name, const rep_stab_run *st,
                                   char **records, int count, eng_error *err)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "format", "ispm-run");
    cJSON_AddNumberToObject(root, "format_version", 1);
    cJSON *tool = cJSON_AddObjectToObject(root, "tool");
    cJSON_AddStringToObject(tool, "name", "ispm replay (stability)");
    cJSON *seq = cJSON_AddObjectToObject(root, "sequence");
    char *name = rep_xprintf("%s.stability", sequence_name ? sequence_name : "run");
    cJSON_AddStringToObject(seq, "name", name);
    free(name);
    cJSON *res = cJSON_AddArrayToObject(root, "resolution");
    cJSON_AddItemToArray(res, cJSON_CreateNumber(st->width));
    cJSON_AddItemToArray(res, cJSON_CreateNumber(st->height));
    cJSON_AddStringToObject(root, "meaning",
                            "stability.<part>: per-pixel reprojected flicker max_c |a_c - b_c| / (max(|a_c|,|b_c|) + 1e-3) "
                            "against the previous frame; -1 where the pixel has no valid history (frame 0, "
                            "background, off-screen, moving, disoccluded)");
    cJSON_AddNumberToObject(root, "frame_count", count);
    cJSON *frames = cJSON_AddArrayToObject(root, "frames");
    for (int i = 0; i < count; i++)
        cJSON_AddItemToArray(frames, cJSON_Parse(records[i]));
    cJSON_AddBoolToObject(root, "complete", 1);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    char *path = rep_path_join(run_dir, "manifest.json");
    eng_result r = rep_write_atomic(path, text, strlen(text), err);
    free(path);
    cJSON_free(text);
    return r;
}
