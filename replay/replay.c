/* replay.c — rep_replay: a run, checked against itself and (usually) against a golden.
 *
 * The walk is frame by frame so that memory holds two frames of each run at a time (the one
 * compared and the next, decoded meanwhile). Both manifests are validated first, and from them
 * alone the first frame and buffer whose recorded digest differs is named (redis DEBUG DIGEST):
 * it points at the first divergence before any pixel is decoded. Then every frame file is decoded and verified against its
 * manifest (an unverifiable file is UNREADABLE: comparing it would compare noise), and each
 * run buffer is compared with the golden buffer of the same name under the tolerance that
 * matches it. Buffers or frames present on one side only fail. Without a golden only
 * integrity and non-finite values are checked. The report (report.json, report.txt) is
 * written even when an input is unreadable, if there is a place to put it.
 *
 * The same walk measures temporal stability (stability.c) of the run, and of the golden for its
 * own values, whenever the run has an eye G-buffer: each frame is fed after its comparison, the
 * per-pixel flicker goes to <report>/stability.tmp.<pid>/ frame by frame and that folder becomes
 * <report>/stability/ only once its manifest is written, so no reader sees a partial one.
 */
#define _POSIX_C_SOURCE 200809L

#include "rep.h"
#include "rep_compare.h"
#include "rep_report.h"
#include "rep_run.h"
#include "rep_stab.h"
#include "rep_util.h"
#include "replay_internal.h"

#include <fnmatch.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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

/* --buffers GLOB: whether a buffer is compared. */
static int wanted(const char *glob, const char *name)
{
    return !glob || fnmatch(glob, name, 0) == 0;
}

static void integrity_only(rep_report *r, const char *glob, const rep_frame_info *f, const rep_part *parts)
{
    for (int j = 0; j < f->buffer_count; j++) {
        if (!wanted(glob, f->buffers[j].name))
            continue;
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

/* One comparison of compare_frame: entry index, run part, golden part. */
typedef struct cmp_job {
    size_t entry;
    int j, k;
} cmp_job;

/* The entries of a frame are added in the report's order first (run buffers, then the golden's
 * extra ones) and the comparisons listed in jobs (returned, their count in *njobs); each
 * comparison then writes only its own entry (compare_one), on whichever thread runs it: the
 * report is the same whatever the thread count and timing. */
static cmp_job *compare_prepare(rep_report *r, const rep_tolerances *tols, const char *glob, const rep_frame_info *rf,
                                const rep_frame_info *gf, int *njobs)
{
    cmp_job *jobs = rep_xcalloc((size_t)rf->buffer_count + 1, sizeof *jobs);
    *njobs = 0;
    for (int j = 0; j < rf->buffer_count; j++) {
        const char *name = rf->buffers[j].name;
        if (!wanted(glob, name))
            continue;
        rep_entry *e = rep_report_add(r, rf->index, name);
        int k = rep_frame_find(gf, name);
        if (k < 0) {
            e->verdict = REP_V_FAIL;
            e->problem = REP_PROB_EXTRA;
            continue;
        }
        e->tol_match = rep_xstrdup(rep_tol_lookup(tols, name, &e->tol));
        jobs[(*njobs)++] = (cmp_job){r->count - 1, j, k};
    }
    for (int k = 0; k < gf->buffer_count; k++)
        if (wanted(glob, gf->buffers[k].name) && rep_frame_find(rf, gf->buffers[k].name) < 0) {
            rep_entry *e = rep_report_add(r, gf->index, gf->buffers[k].name);
            e->verdict = REP_V_FAIL;
            e->problem = REP_PROB_MISSING;
        }
    return jobs;
}

static void compare_one(rep_entry *e, const cmp_job *jb, const rep_part *rp, const rep_part *gp, int no_flip,
                        float **flip_map)
{
    eng_buffer a = rep_part_buffer(&rp[jb->j]), b = rep_part_buffer(&gp[jb->k]);
    if (rep_is_photon_map(&a) && rep_is_photon_map(&b)) {
        e->photon_set = 1;
        e->verdict = rep_photon_compare(&a, &b, &e->tol, &e->m, &e->pd);
    } else {
        e->verdict = rep_compare(&a, &b, &e->tol, &e->m);
        e->verdict = rep_compare_flip_map(&a, &b, &e->tol, e->verdict, no_flip, &e->m, &e->flip_kind, &e->flip,
                                          flip_map);
    }
    if (e->verdict == REP_V_SIZE) {
        e->run_shape = shape(a.width, a.height, a.channel_count, a.channels);
        e->golden_shape = shape(b.width, b.height, b.channel_count, b.channels);
    } else {
        e->compared = 1;
    }
}

static void one_side(rep_report *r, const char *glob, const rep_frame_info *f, rep_problem problem)
{
    for (int j = 0; j < f->buffer_count; j++) {
        if (!wanted(glob, f->buffers[j].name))
            continue;
        rep_entry *e = rep_report_add(r, f->index, f->buffers[j].name);
        e->verdict = REP_V_FAIL;
        e->problem = problem;
    }
}

/* Stability state of one walk: the measurements and the stability run being written. */
typedef struct stab_walk {
    rep_stab_report *s;
    int on, golden_on;
    char *tmp;     /* the stability run being written, or NULL (no report folder) */
    char **records;
    int record_count;
    rep_run *ref;
    rep_part *ref_parts; /* a one-frame reference, kept */
} stab_walk;

static void stab_walk_free(stab_walk *w)
{
    if (w->tmp) {
        eng_error ignored;
        rep_remove_tree(w->tmp, &ignored);
    }
    free(w->tmp);
    for (int i = 0; i < w->record_count; i++)
        free(w->records[i]);
    free(w->records);
    if (w->ref && w->ref_parts)
        rep_parts_free(w->ref_parts, w->ref->frames[0].buffer_count);
    rep_run_close(w->ref);
    rep_stab_report_free(w->s);
}

static eng_result stab_begin(stab_walk *w, const rep_options *o, const char *report_dir, const rep_run *run,
                             const rep_run *gold, eng_error *err)
{
    memset(w, 0, sizeof *w);
    w->s = rep_xcalloc(1, sizeof *w->s);
    w->on = 1;
    w->golden_on = gold != NULL;
    w->s->run.frame_count = run->frame_count;
    if (gold)
        w->s->golden.frame_count = gold->frame_count;
    eng_result res = ENG_OK;
    if (o->reference_dir) {
        w->s->reference_dir = rep_xstrdup(o->reference_dir);
        res = rep_run_open(o->reference_dir, &w->ref, err);
        if (res == ENG_OK && w->ref->frame_count != 1 && w->ref->frame_count != run->frame_count)
            res = eng_fail(err, ENG_ERR_INVALID, "%s: the reference has %d frames, the run %d (a reference has 1 or as many)",
                           w->ref->manifest_path, w->ref->frame_count, run->frame_count);
        if (res == ENG_OK && w->ref->frame_count == 1)
            res = rep_run_read_frame(w->ref, 0, &w->ref_parts, err);
    }
    if (res == ENG_OK && report_dir) {
        w->tmp = rep_xprintf("%s/stability.tmp.%ld", report_dir, (long)getpid());
        char *frames = rep_path_join(w->tmp, "frames");
        if ((res = rep_remove_tree(w->tmp, err)) == ENG_OK)
            res = rep_mkdirs(frames, err);
        free(frames);
    }
    return res;
}

/* stab_frame's part for the run (and its reference). */
static eng_result stab_run_frame(stab_walk *w, int i, const rep_frame_info *rf, const rep_part *rp, eng_error *err)
{
    eng_result res = ENG_OK;
    if (!w->on || !rf)
        return ENG_OK;
    rep_part *refp = w->ref_parts, *own = NULL;
    int refn = w->ref ? w->ref->frames[0].buffer_count : 0;
    if (w->ref && !refp) {
        if ((res = rep_run_read_frame(w->ref, i, &own, err)) != ENG_OK)
            return res;
        refp = own;
        refn = w->ref->frames[i].buffer_count;
    }
    float **fl = NULL;
    int fn = 0;
    if (!rep_stab_frame(&w->s->run, rf, rp, rf->buffer_count, refp, refn, w->tmp ? &fl : NULL, &fn)) {
        w->on = 0;
    } else if (w->tmp) {
        char *rec = NULL;
        res = rep_stab_write_frame(w->tmp, rf, &w->s->run, fl, fn, &rec, err);
        if (res == ENG_OK) {
            w->records = rep_xrealloc(w->records, (size_t)(w->record_count + 1) * sizeof *w->records);
            w->records[w->record_count++] = rec;
        }
    }
    for (int k = 0; k < fn; k++)
        free(fl[k]);
    free(fl);
    if (own)
        rep_parts_free(own, refn);
    return res;
}

/* Ends the measurement: verdicts, the stability run put in place; hands the result to r. */
static eng_result stab_end(stab_walk *w, rep_report *r, const rep_run *run, const rep_tolerances *tols,
                           const char *report_dir, eng_error *err)
{
    eng_result res = ENG_OK;
    if (!w->on || w->s->run.frames != run->frame_count)
        return ENG_OK; /* the run has no eye G-buffer (in some frame): no stability */
    rep_stab_finish(&w->s->run);
    if (w->golden_on) {
        rep_stab_finish(&w->s->golden);
        w->s->has_golden = 1;
    }
    rep_stab_judge(w->s, tols);
    if (w->tmp) {
        char *final = rep_path_join(report_dir, "stability");
        res = rep_stab_write_manifest(w->tmp, run->sequence_name, &w->s->run, w->records, w->record_count, err);
        if (res == ENG_OK)
            res = rep_remove_tree(final, err);
        if (res == ENG_OK && rename(w->tmp, final) != 0)
            res = eng_fail(err, ENG_ERR_IO, "%s: cannot rename to %s", w->tmp, final);
        if (res == ENG_OK) {
            free(w->tmp);
            w->tmp = NULL;
            w->s->out_dir = final;
        } else {
            free(final);
        }
    }
    if (res == ENG_OK) {
        r->stab = w->s;
        w->s = NULL;
    }
    return res;
}

/* The name of the buffer report.html previews in frame i (report_html.c's final_buffer): the
 * run's final.display, else its last buffer (the golden's when the run lacks the frame). */
static const char *preview_buffer(const rep_frame_info *rf, const rep_frame_info *gf)
{
    const rep_frame_info *f = rf ? rf : gf;
    if (!f)
        return NULL;
    int k = rep_frame_find(f, "final.display");
    if (k < 0)
        k = f->buffer_count - 1;
    return k >= 0 ? f->buffers[k].name : NULL;
}

/* Moves the part named name of each side into r->keep (keep.c), if the side has it. */
static void keep_both(rep_report *r, int i, const char *name, const rep_frame_info *rf, rep_part *rp,
                      const rep_frame_info *gf, rep_part *gp)
{
    int j = rf && rp ? rep_frame_find(rf, name) : -1;
    if (j >= 0)
        rep_keep_part(r->keep, i, REP_KEEP_RUN, &rp[j]);
    int k = gf && gp ? rep_frame_find(gf, name) : -1;
    if (k >= 0)
        rep_keep_part(r->keep, i, REP_KEEP_GOLDEN, &gp[k]);
}

/* After frame i's comparisons: what report.html will show of it (keep.c) moves into r->keep,
 * the listed entries' parts and ꟻLIP maps and, in the first and last frames, the preview
 * buffer; maps not kept are freed. first: the frame's first entry. */
static void keep_frame(rep_report *r, int i, size_t first, const rep_frame_info *rf, rep_part *rp,
                       const rep_frame_info *gf, rep_part *gp, const cmp_job *jobs, float **maps, int njobs)
{
    if (!r->keep)
        r->keep = rep_xcalloc(1, sizeof *r->keep);
    for (int k = 0; k < njobs; k++) {
        const rep_entry *e = &r->entries[jobs[k].entry];
        if (maps[k] && (!rep_entry_listed(e) ||
                        !rep_keep_flip(r->keep, i, e->buffer, maps[k], (size_t)rp[jobs[k].j].width * (size_t)rp[jobs[k].j].height)))
            free(maps[k]);
        maps[k] = NULL;
    }
    for (size_t x = first; x < r->count; x++)
        if (rep_entry_listed(&r->entries[x]))
            keep_both(r, i, r->entries[x].buffer, rf, rp, gf, gp);
    if (i == 0 || i == r->frames - 1) {
        const char *b = preview_buffer(rf, gf);
        if (b)
            keep_both(r, i, b, rf, rp, gf, gp);
    }
}

/* The decoded parts of one frame of the run and of the golden, with what decoding them gave. */
typedef struct frame_parts {
    rep_part *rp, *gp;
    eng_result res, gres;
    eng_error err, gerr;
} frame_parts;

/* Frame i of one side (none when the side has no frame i). */
static void frame_fetch_side(const rep_run *side, int i, rep_part **parts, eng_result *res, eng_error *err)
{
    *parts = NULL;
    *res = ENG_OK;
    if (side && i < side->frame_count)
        *res = rep_run_read_frame(side, i, parts, err);
}

/* Frame i of both sides, decoded and verified side by side. */
static void frame_fetch(const rep_run *run, const rep_run *gold, int i, frame_parts *f)
{
    memset(f, 0, sizeof *f);
#pragma omp parallel sections
    {
#pragma omp section
        frame_fetch_side(run, i, &f->rp, &f->res, &f->err);
#pragma omp section
        frame_fetch_side(gold, i, &f->gp, &f->gres, &f->gerr);
    }
}

static void frame_free(const rep_run *run, const rep_run *gold, int i, frame_parts *f)
{
    if (f->rp)
        rep_parts_free(f->rp, run->frames[i].buffer_count);
    if (f->gp)
        rep_parts_free(f->gp, gold->frames[i].buffer_count);
    f->rp = f->gp = NULL;
}

/* The first frame from i on that --frames selects (frames: none). */
static int next_frame(const rep_options *o, int i, int frames)
{
    while (i < frames && o->frames_set && (i < o->frame_first || i > o->frame_last))
        i++; /* stability needs every frame: it is then not measured */
    return i;
}

/* Fills r; returns ENG_OK or the error that makes an input unreadable. */
static eng_result walk(const rep_options *o, const char *report_dir, rep_report *r, eng_error *err)
{
    rep_run *run = NULL, *gold = NULL;
    stab_walk sw;
    memset(&sw, 0, sizeof sw);
    rep_tolerances *tols = NULL;
    char *tol_default = NULL;
    eng_result res = rep_run_open(o->run_dir, &run, err);
    const char *gdir = o->golden_dir;
    if (res == ENG_OK && gdir)
        res = rep_run_open(gdir, &gold, err);
    if (res == ENG_OK && gold) { /* the golden's set for the run's renderer, when it has one */
        char *slug = NULL, *set = rep_renderer_set_dir(gdir, run, gold, &slug);
        if (set) {
            rep_run_close(gold);
            gold = NULL;
            r->renderer_set = slug;
            r->renderer_set_dir = set;
            r->golden_dir = gdir = set;
            res = rep_run_open(gdir, &gold, err);
        }
    }
    if (res == ENG_OK && gold) {
        if (o->tolerances) {
            res = rep_tol_load(o->tolerances, 0, &tols, err);
        } else {
            tol_default = rep_path_join(gdir, "tolerances.json");
            res = rep_tol_load(tol_default, 1, &tols, err);
        }
    }
    const rep_tolerances *use = tols;
    if (res == ENG_OK && gold) {
        rep_tol_apply_flags(tols, &o->flags);
        if (tols->cross)
            rep_tol_apply_flags(tols->cross, &o->flags);
        use = rep_renderer_tolerances(r, run, gold, tols);
        if (use->path || use != tols)
            r->tol_path = rep_xstrdup(use->path ? use->path : "built-in cross-renderer defaults");
        /* what made each run, before any pixel */
        res = rep_prov_compare(o->run_dir, gdir, o->provenance_fail, o->timing_fail, &r->prov, err);
    }
    if (res == ENG_OK && gold) /* known failures, by rule */
        res = rep_report_expect_load(r, o->expectations, o->golden_dir, run, gold, o->today, err);
    if (res != ENG_OK)
        goto done;

    r->frames = run->frame_count;
    r->buffers_per_frame = run->frames[0].buffer_count;
    rep_report_display_warnings(r, run, gold);
    rep_report_tol_warnings(r, use, gold);
    if (gold) {
        if (gold->frame_count > r->frames)
            r->frames = gold->frame_count;
        digest_difference(r, run, gold);
    }
    if ((res = stab_begin(&sw, o, report_dir, run, gold, err)) != ENG_OK)
        goto done;
    if (o->frames_set && (o->frame_first < 0 || o->frame_first >= r->frames || o->frame_last < o->frame_first)) {
        res = eng_fail(err, ENG_ERR_INVALID, "%s: --frames %d-%d: the run has frames 0-%d", run->manifest_path,
                       o->frame_first, o->frame_last, r->frames - 1);
        goto done;
    }
    if (o->progress)
        o->progress->total = o->frames_set ? (o->frame_last < r->frames ? o->frame_last : r->frames - 1) - o->frame_first + 1
                                           : r->frames;
    /* A pipeline of two frames: while frame i is compared and measured, frame i+1 (the next one
     * in --frames) of both sides is decoded and verified, all as OpenMP tasks of one parallel
     * region (the decoding of a frame file is serial inside OpenImageIO, so alone it would
     * leave a core idle). Each task writes only its own results; a frame's decoding error is
     * looked at when that frame's turn comes, as if it had been decoded then (the run's error
     * is the one reported when both sides fail). */
    frame_parts cur, nxt;
    memset(&cur, 0, sizeof cur);
    memset(&nxt, 0, sizeof nxt);
    int i = next_frame(o, 0, r->frames);
    if (i < r->frames)
        frame_fetch(run, gold, i, &cur);
    for (int done = 0; i < r->frames && res == ENG_OK;) {
        const rep_frame_info *rf = i < run->frame_count ? &run->frames[i] : NULL;
        const rep_frame_info *gf = gold && i < gold->frame_count ? &gold->frames[i] : NULL;
        int ni = next_frame(o, i + 1, r->frames);
        int fetching = 0;
        res = cur.res;
        if (res != ENG_OK) {
            *err = cur.err;
        } else if (cur.gres != ENG_OK) {
            res = cur.gres;
            *err = cur.gerr;
        }
        if (res == ENG_OK) {
            cmp_job *jobs = NULL;
            int njobs = 0;
            size_t first = r->count;
            if (!gold)
                integrity_only(r, o->buffers, rf, cur.rp);
            else if (!rf)
                one_side(r, o->buffers, gf, REP_PROB_FRAME_MISSING);
            else if (!gf)
                one_side(r, o->buffers, rf, REP_PROB_FRAME_EXTRA);
            else
                jobs = compare_prepare(r, use, o->buffers, rf, gf, &njobs);
            rep_entry *entries = r->entries; /* no entry is added below: the array stays put */
            float **maps = rep_xcalloc((size_t)njobs + 1, sizeof *maps);
            int golden_ok = 1;
            eng_result sres = ENG_OK;
            fetching = ni < r->frames;
            rep_part *rp = cur.rp, *gp = cur.gp;
#pragma omp parallel
#pragma omp single
            {
                if (fetching) {
#pragma omp task shared(nxt)
                    frame_fetch_side(run, ni, &nxt.rp, &nxt.res, &nxt.err);
#pragma omp task shared(nxt)
                    frame_fetch_side(gold, ni, &nxt.gp, &nxt.gres, &nxt.gerr);
                }
                for (int k = 0; k < njobs; k++) {
#pragma omp task firstprivate(k) shared(jobs, entries, rp, gp, maps)
                    compare_one(&entries[jobs[k].entry], &jobs[k], rp, gp, o->no_flip, &maps[k]);
                }
                /* temporal stability: the golden's measure and the run's are independent */
#pragma omp task shared(sw, golden_ok)
                if (sw.golden_on && gf)
                    golden_ok = rep_stab_frame(&sw.s->golden, gf, gp, gf->buffer_count, NULL, 0, NULL, NULL);
#pragma omp task shared(sw, sres)
                sres = stab_run_frame(&sw, i, rf, rp, err);
            }
            keep_frame(r, i, first, rf, cur.rp, gf, cur.gp, jobs, maps, njobs);
            free(maps);
            free(jobs);
            if (!golden_ok)
                sw.golden_on = 0;
            res = sres;
        }
        frame_free(run, gold, i, &cur);
        if (res != ENG_OK) {
            if (fetching)
                frame_free(run, gold, ni, &nxt);
            break;
        }
        if (o->progress)
            rep_progress_step(o->progress, ++done, NULL);
        cur = nxt;
        i = ni;
    }
    if (o->progress)
        rep_progress_end(o->progress);
    if (res == ENG_OK)
        res = stab_end(&sw, r, run, use, report_dir, err);
    rep_report_expect_apply(r);
done:
    stab_walk_free(&sw);
    free(tol_default);
    rep_tol_free(tols);
    rep_run_close(gold);
    rep_run_close(run);
    return res;
}

rep_exit rep_replay_report(const rep_options *o, rep_report *r, eng_error *err)
{
    eng_keep_freed_memory(); /* a frame's buffers per frame and side: reused, not faulted anew */
    memset(r, 0, sizeof *r);
    r->digest_frame = -1;
    if (!o || !o->run_dir) {
        eng_fail(err, ENG_ERR_INVALID, "replay: no run folder given");
        r->exit = REP_UNREADABLE;
        r->error = *err;
        return REP_UNREADABLE;
    }
    r->run_dir = o->run_dir;
    r->golden_dir = o->golden_dir;
    if (o->golden_dir)
        r->flags_text = rep_tol_flags_text(&o->flags);
    if (o->frames_set || o->buffers) {
        rep_sb scope = {0};
        if (o->frames_set)
            rep_sb_printf(&scope, "frames %d-%d", o->frame_first, o->frame_last);
        if (o->buffers)
            rep_sb_printf(&scope, "%sbuffers %s", scope.len ? ", " : "", o->buffers);
        r->scope_text = scope.s;
    }
    /* An unreadable run folder that does not exist gets no report folder created inside it. */
    char *dir = o->report_dir ? rep_xstrdup(o->report_dir) : rep_path_join(o->run_dir, "replay");
    int writable = !o->no_files && (o->report_dir || rep_is_dir(o->run_dir));
    /* A report folder that cannot be made is said before anything is compared, as what it is. */
    if (writable && rep_mkdirs(dir, err) != ENG_OK) {
        r->exit = REP_UNWRITABLE;
        r->error = *err;
        free(dir);
        return r->exit;
    }
    eng_result res = walk(o, writable ? dir : NULL, r, err);
    if (res != ENG_OK) {
        r->exit = REP_UNREADABLE;
        r->error = *err;
    } else {
        r->exit = rep_report_exit(r);
    }

    if (writable) {
        eng_error werr;
        if (rep_report_write(r, dir, &werr) != ENG_OK && r->exit != REP_UNREADABLE) {
            r->exit = REP_UNWRITABLE;
            r->error = werr;
            *err = werr;
        }
    }
    free(dir);
    return r->exit;
}

rep_exit rep_replay(const rep_options *o, FILE *summary, eng_error *err)
{
    eng_error local;
    if (!err)
        err = &local;
    rep_report r;
    rep_replay_report(o, &r, err);
    if (summary) {
        char *text = rep_report_text(&r, o ? o->quiet : 0);
        fputs(text, summary);
        fflush(summary);
        free(text);
    }
    rep_exit x = r.exit;
    rep_report_free(&r);
    return x;
}
