/* replay.c — rep_replay: a run, checked against itself and (usually) against a golden.
 *
 * The walk is frame by frame so that memory holds one frame of each run at a time. Both
 * manifests are validated first, and from them alone the first frame and buffer whose
 * recorded digest differs is named (redis DEBUG DIGEST): it points at the first divergence
 * before any pixel is decoded. Then every frame file is decoded and verified against its
 * manifest (an unverifiable file is UNREADABLE: comparing it would compare noise), and each
 * run buffer is compared with the golden buffer of the same name under the tolerance that
 * matches it. Buffers or frames present on one side only fail. Without a golden only
 * integrity and non-finite values are checked. The report (report.json, report.txt) is
 * written even when an input is unreadable, if there is a place to put it.
 */
#include "rep_internal.h"

#include <stdlib.h>
#include <string.h>

static char *shape(int w, int h, int n, const char *const *channels)
{
    rep_sb sb = {0};
    rep_sb_printf(&sb, "%dx%d ", w, h);
    for (int c = 0; c < n; c++)
        rep_sb_printf(&sb, "%s%s", c ? "," : "", channels[c]);
    return sb.s;
}

/* First frame/buffer whose manifest digest differs, walking frames in order and, inside a
 * frame, the run's buffers then the golden's extra ones. */
static void digest_difference(rep_report *r, const rep_run *run, const rep_run *gold)
{
    r->digest_frame = -1;
    int n = run->frame_count > gold->frame_count ? run->frame_count : gold->frame_count;
    for (int i = 0; i < n; i++) {
        const rep_frame_info *rf = i < run->frame_count ? &run->frames[i] : NULL;
        const rep_frame_info *gf = i < gold->frame_count ? &gold->frames[i] : NULL;
        const char *name = NULL, *why = NULL;
        if (!rf) {
            name = gf->buffers[0].name;
            why = "frame missing from run";
        } else if (!gf) {
            name = rf->buffers[0].name;
            why = "frame not in golden";
        }
        for (int j = 0; !name && j < rf->buffer_count; j++) {
            int k = rep_frame_find(gf, rf->buffers[j].name);
            if (k < 0) {
                name = rf->buffers[j].name;
                why = "not in golden";
            } else if (strcmp(rf->buffers[j].digest, gf->buffers[k].digest) != 0) {
                name = rf->buffers[j].name;
                why = "digest differs";
            }
        }
        for (int k = 0; !name && k < gf->buffer_count; k++)
            if (rep_frame_find(rf, gf->buffers[k].name) < 0) {
                name = gf->buffers[k].name;
                why = "missing from run";
            }
        if (name) {
            r->digest_frame = i;
            r->digest_buffer = rep_xstrdup(name);
            r->digest_why = why;
            return;
        }
    }
}

static void integrity_only(rep_report *r, const rep_frame_info *f, const rep_part *parts)
{
    for (int j = 0; j < f->buffer_count; j++) {
        rep_entry *e = rep_report_add(r, f->index, f->buffers[j].name);
        eng_buffer b = rep_part_buffer(&parts[j]);
        e->compared = 1;
        e->m.max_x = e->m.max_y = e->m.first_fail_x = e->m.first_fail_y = -1;
        e->m.pixels = (uint64_t)b.width * (uint64_t)b.height;
        e->m.values = e->m.pixels * (uint64_t)b.channel_count;
        eng_buffer_nonfinite(&b, &e->m.run_nan, &e->m.run_inf, &e->m.nf_x, &e->m.nf_y);
        if (e->m.run_nan || e->m.run_inf) {
            e->verdict = REP_V_FAIL;
            e->m.fail_why = REP_WHY_NONFINITE;
        } else {
            e->verdict = REP_V_CHECKED;
        }
    }
}

static void compare_frame(rep_report *r, const rep_tolerances *tols, const rep_frame_info *rf,
                          const rep_part *rp, const rep_frame_info *gf, const rep_part *gp)
{
    for (int j = 0; j < rf->buffer_count; j++) {
        const char *name = rf->buffers[j].name;
        rep_entry *e = rep_report_add(r, rf->index, name);
        int k = rep_frame_find(gf, name);
        if (k < 0) {
            e->verdict = REP_V_FAIL;
            e->problem = REP_PROB_EXTRA;
            continue;
        }
        eng_buffer a = rep_part_buffer(&rp[j]), b = rep_part_buffer(&gp[k]);
        e->tol_match = rep_xstrdup(rep_tol_lookup(tols, name, &e->tol));
        e->verdict = rep_compare(&a, &b, &e->tol, &e->m);
        if (e->verdict == REP_V_SIZE) {
            e->run_shape = shape(a.width, a.height, a.channel_count, a.channels);
            e->golden_shape = shape(b.width, b.height, b.channel_count, b.channels);
        } else {
            e->compared = 1;
        }
    }
    for (int k = 0; k < gf->buffer_count; k++)
        if (rep_frame_find(rf, gf->buffers[k].name) < 0) {
            rep_entry *e = rep_report_add(r, gf->index, gf->buffers[k].name);
            e->verdict = REP_V_FAIL;
            e->problem = REP_PROB_MISSING;
        }
}

static void one_side(rep_report *r, const rep_frame_info *f, rep_problem problem)
{
    for (int j = 0; j < f->buffer_count; j++) {
        rep_entry *e = rep_report_add(r, f->index, f->buffers[j].name);
        e->verdict = REP_V_FAIL;
        e->problem = problem;
    }
}

/* Fills r; returns ENG_OK or the error that makes an input unreadable. */
static eng_result walk(const rep_options *o, rep_report *r, eng_error *err)
{
    rep_run *run = NULL, *gold = NULL;
    rep_tolerances *tols = NULL;
    char *tol_default = NULL;
    eng_result res = rep_run_open(o->run_dir, &run, err);
    if (res == ENG_OK && o->golden_dir)
        res = rep_run_open(o->golden_dir, &gold, err);
    if (res == ENG_OK && gold) {
        if (o->tolerances) {
            res = rep_tol_load(o->tolerances, 0, &tols, err);
        } else {
            tol_default = rep_path_join(o->golden_dir, "tolerances.json");
            res = rep_tol_load(tol_default, 1, &tols, err);
        }
        if (res == ENG_OK && tols->path)
            r->tol_path = rep_xstrdup(tols->path);
    }
    if (res != ENG_OK)
        goto done;

    r->frames = run->frame_count;
    r->buffers_per_frame = run->frames[0].buffer_count;
    if (gold) {
        if (gold->frame_count > r->frames)
            r->frames = gold->frame_count;
        digest_difference(r, run, gold);
    }
    for (int i = 0; i < r->frames && res == ENG_OK; i++) {
        rep_part *rp = NULL, *gp = NULL;
        const rep_frame_info *rf = i < run->frame_count ? &run->frames[i] : NULL;
        const rep_frame_info *gf = gold && i < gold->frame_count ? &gold->frames[i] : NULL;
        if (rf)
            res = rep_run_read_frame(run, i, &rp, err);
        if (res == ENG_OK && gf)
            res = rep_run_read_frame(gold, i, &gp, err);
        if (res == ENG_OK) {
            if (!gold)
                integrity_only(r, rf, rp);
            else if (!rf)
                one_side(r, gf, REP_PROB_FRAME_MISSING);
            else if (!gf)
                one_side(r, rf, REP_PROB_FRAME_EXTRA);
            else
                compare_frame(r, tols, rf, rp, gf, gp);
        }
        if (rf)
            rep_parts_free(rp, rf->buffer_count);
        if (gf)
            rep_parts_free(gp, gf->buffer_count);
    }
done:
    free(tol_default);
    rep_tol_free(tols);
    rep_run_close(gold);
    rep_run_close(run);
    return res;
}

rep_exit rep_replay(const rep_options *o, FILE *summary, eng_error *err)
{
    eng_error local;
    if (!err)
        err = &local;
    if (!o || !o->run_dir) {
        eng_fail(err, ENG_ERR_INVALID, "replay: no run folder given");
        if (summary)
            fprintf(summary, "replay: UNREADABLE — %s\n", err->msg);
        return REP_UNREADABLE;
    }
    rep_report r;
    memset(&r, 0, sizeof r);
    r.run_dir = o->run_dir;
    r.golden_dir = o->golden_dir;
    r.digest_frame = -1;
    eng_result res = walk(o, &r, err);
    if (res != ENG_OK) {
        r.exit = REP_UNREADABLE;
        r.error = *err;
    } else {
        r.exit = rep_report_exit(&r);
    }

    /* An unreadable run folder that does not exist gets no report folder created inside it. */
    char *dir = o->report_dir ? rep_xstrdup(o->report_dir) : rep_path_join(o->run_dir, "replay");
    if (o->report_dir || rep_is_dir(o->run_dir)) {
        eng_error werr;
        if (rep_report_write(&r, dir, &werr) != ENG_OK && r.exit != REP_UNREADABLE) {
            r.exit = REP_UNREADABLE;
            r.error = werr;
            *err = werr;
        }
    }
    free(dir);
    if (summary) {
        char *text = rep_report_text(&r, o->quiet);
        fputs(text, summary);
        fflush(summary);
        free(text);
    }
    rep_exit x = r.exit;
    rep_report_free(&r);
    return x;
}
