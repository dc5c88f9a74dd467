/* bless.c — rep_bless: a run becomes the golden that later runs are compared against.
 *
 * Only a run that replay itself would accept is blessed: complete manifest, every frame file
 * present and decoding to its manifest digests; anything less is refused with ENG_ERR_INVALID
 * (a golden that cannot be read would fail every later replay as UNREADABLE, or worse, pass).
 * The copy is built beside the target in <golden>.tmp, with the golden's tolerances.json kept
 * if it had one (tolerances are tuned by people and outlive any one blessing) or the default
 * one written, and then swapped in with renames, so an interrupted bless leaves the old golden
 * or the new one, never a mixture (killed between the two renames, the next bless puts the old
 * one back: rep_golden_recover), and one bless at a time holds <golden>.lock. Files inside the
 * run and the golden are read as inputs that may not be symbolic links. Only manifest.json and
 * the frame files are copied: a replay/ report folder inside the run is not part of a golden.
 *
 * Goldens are committed, so their frame files are ZIP whatever the run was recorded with
 * (record writes none by default: no encoding, 70 % larger than zip): a frame file
 * that is not ZIP throughout is recompressed part by part through OpenEXR (cap_recompress_exr:
 * every attribute and every bit kept), the golden's manifest then says "capture":
 * {"compression": "zip"} (nothing else in it changes), and the new golden is verified before
 * it is swapped in: each file decodes to the run's pixels bit for bit (checked by
 * cap_recompress_exr before its rename) and, read back as replay reads it, to its manifest
 * digests. A run already in ZIP is copied byte for byte, as before.
 *
 * Where a folder above the golden holds an object store (golden/objects), or the golden has its
 * own objects/, the golden is written as format 2 instead (golden_store.c, run/objects.c): each
 * distinct buffer once, by digest, only the objects the store lacks written, the manifest listing
 * buffers by digest; the new golden is read back from the store before it is swapped in. A run
 * whose GL renderer is not the golden's goes into the golden's set for that renderer,
 * <golden>/renderers/<slug>/, and reblessing the canonical set keeps those sets.
 *
 * A golden moves only with a written review: the run is first replayed against the golden it
 * would replace (provenance, pixels, timing; the HTML review with thumbnails goes to the run's
 * bless/ folder, outside the committed golden). A bit-exact run made from the same inputs
 * changes nothing; a run that differs replaces the golden only when accepted, and then the
 * golden carries BLESS.md, the review in text: what moved, by how much, and why.
 */
#define _XOPEN_SOURCE 700

#include "rep.h"
#include "rep_compare.h"
#include "rep_report.h"
#include "rep_run.h"
#include "rep_util.h"
#include "replay_internal.h"

#include "cap.h"

#include <cjson/cJSON.h>

#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* The run must be one replay would accept; any reason it is not becomes ENG_ERR_INVALID with
 * the reader's message. */
static eng_result verify_run(const char *run_dir, rep_run **out, eng_error *err)
{
    eng_error why;
    eng_result r = rep_run_open(run_dir, out, &why);
    for (int i = 0; r == ENG_OK && i < (*out)->frame_count; i++) {
        rep_part *parts = NULL;
        r = rep_run_read_frame(*out, i, &parts, &why);
        if (r == ENG_OK)
            rep_parts_free(parts, (*out)->frames[i].buffer_count);
    }
    if (r == ENG_OK)
        return ENG_OK;
    rep_run_close(*out);
    *out = NULL;
    return eng_fail(err, ENG_ERR_INVALID, "%s", why.msg);
}

/* The golden's frames into tmp: as objects (format 2) in the shared store above the golden
 * (rep_store_find) or in the golden's own objects/ when it has one, else as ZIP frame files. */
static eng_result build_tmp(const rep_run *run, const char *golden, const char *tol_from, const char *tmp,
                            rep_store_stats *st, eng_error *err)
{
    eng_result r = rep_remove_tree(tmp, err);
    if (r == ENG_OK)
        r = rep_mkdirs(tmp, err);
    if (r != ENG_OK)
        return r;
    char *rel = NULL, *store = rep_store_find(golden, &rel);
    char *own = rep_path_join(golden, "objects");
    if (!store && rep_is_dir(own)) {
        rel = rep_xstrdup("objects");
        store = rep_path_join(tmp, rel);
        r = rep_mkdirs(store, err);
    }
    free(own);
    if (store) {
        if (r == ENG_OK)
            r = rep_store_put_run(run, store, st, err);
        char *dst = rep_path_join(tmp, "manifest.json");
        if (r == ENG_OK)
            r = rep_store_write_manifest(run, dst, rel, err);
        free(dst);
        if (r == ENG_OK) { /* read back as replay reads it: every object checked */
            rep_run *g = NULL;
            if (verify_run(tmp, &g, err) != ENG_OK)
                r = ENG_ERR_IO;
            rep_run_close(g);
        }
        free(store);
        free(rel);
    } else {
        int recompressed = 0;
        for (int i = 0; i < run->frame_count && r == ENG_OK; i++) {
            char *dst = rep_path_join(tmp, run->frames[i].file);
            int rewritten = 0;
            r = rep_make_parent(dst, err);
            if (r == ENG_OK)
                r = cap_recompress_exr(run->frames[i].path, dst, CAP_COMPRESSION_ZIP, &rewritten, err);
            if (r == ENG_OK && !rewritten)
                r = rep_copy_file(run->frames[i].path, ENG_IN_NOFOLLOW, dst, err);
            recompressed |= rewritten;
            free(dst);
        }
        char *dst = rep_path_join(tmp, "manifest.json");
        if (r == ENG_OK)
            r = recompressed ? rep_store_write_manifest(run, dst, NULL, err) : rep_copy_file(run->manifest_path, ENG_IN_NOFOLLOW, dst, err);
        free(dst);
        if (r == ENG_OK && recompressed) {
            /* Read back as replay reads it: every frame decodes to its manifest's digests
             * (cap_recompress_exr has compared each file with the run's bit for bit). A failure here
             * is one of writing. */
            rep_run *g = NULL;
            if (verify_run(tmp, &g, err) != ENG_OK)
                r = ENG_ERR_IO;
            rep_run_close(g);
        }
    }
    if (r != ENG_OK)
        return r;
    /* The golden's own tolerance file when anything is there (a renderer set's may be absent:
     * then the canonical set's, tol_from). */
    char *golden_tol = rep_path_join(golden, "tolerances.json");
    struct stat lst;
    char *old_tol = rep_path_join(lstat(golden_tol, &lst) == 0 ? golden : tol_from, "tolerances.json");
    free(golden_tol);
    char *new_tol = rep_path_join(tmp, "tolerances.json");
    if (lstat(old_tol, &lst) == 0) {
        /* Whatever is there is the golden's tolerance file: a link, FIFO or device is refused
         * (never its target's bytes copied into the golden), and so is one that does not parse. */
        cJSON *check = NULL;
        r = rep_json_load(old_tol, ENG_IN_NOFOLLOW, &check, err);
        cJSON_Delete(check);
        if (r == ENG_OK)
            r = rep_copy_file(old_tol, ENG_IN_NOFOLLOW, new_tol, err);
    } else {
        char *text = rep_tol_default_json();
        r = rep_write_atomic(new_tol, text, strlen(text), err);
        free(text);
    }
    free(old_tol);
    free(new_tol);
    char *old_x = rep_path_join(golden, "expectations.json"), *new_x = rep_path_join(tmp, "expectations.json");
    if (r == ENG_OK && lstat(old_x, &lst) == 0) /* the known failures stay with the golden, as its tolerances do */
        r = rep_copy_file(old_x, ENG_IN_NOFOLLOW, new_x, err);
    free(old_x);
    free(new_x);
    return r;
}

/* Bless replaces golden_dir wholesale, so it must be a golden already (or empty, or absent):
 * a mistyped path must not delete an unrelated folder. */
static eng_result check_target(const char *golden, eng_error *err)
{
    struct stat st;
    if (lstat(golden, &st) != 0)
        return ENG_OK;
    if (!S_ISDIR(st.st_mode))
        return eng_fail(err, ENG_ERR_INVALID, "%s: exists and is not a folder", golden);
    char *m = rep_path_join(golden, "manifest.json");
    char *t = rep_path_join(golden, "tolerances.json");
    int looks_golden = rep_is_file(m) || rep_is_file(t);
    free(m);
    free(t);
    if (looks_golden)
        return ENG_OK;
    DIR *d = opendir(golden);
    if (!d)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot list: %s", golden, strerror(errno));
    int empty = 1;
    for (struct dirent *e; empty && (e = readdir(d));)
        empty = strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0;
    closedir(d);
    if (!empty)
        return eng_fail(err, ENG_ERR_INVALID,
                        "%s: not a golden (no manifest.json or tolerances.json) and not empty: refusing to replace it",
                        golden);
    return ENG_OK;
}

/* Where a run is blessed: canonical itself, or canonical/renderers/<slug> when canonical is a
 * golden whose GL renderer is another than the run's (*slug set then; caller frees). */
static char *renderer_target(char *canonical, const rep_run *run, char **slug)
{
    *slug = NULL;
    char *mf = rep_path_join(canonical, "manifest.json");
    int has = rep_is_file(mf);
    free(mf);
    rep_run *g = NULL;
    eng_error ignored; /* an unreadable canonical golden is the review's to report */
    if (!has || !run->gl_renderer || rep_run_open(canonical, &g, &ignored) != ENG_OK)
        return canonical;
    char *mine = rep_renderer_slug(run->gl_vendor, run->gl_renderer);
    char *theirs = g->gl_renderer ? rep_renderer_slug(g->gl_vendor, g->gl_renderer) : NULL;
    rep_run_close(g);
    if (!theirs || strcmp(mine, theirs) == 0) {
        free(mine);
        free(theirs);
        return canonical;
    }
    free(theirs);
    *slug = mine;
    return rep_xprintf("%s/renderers/%s", canonical, mine);
}

/* At most this many buffer lines in BLESS.md: goldens are committed, the HTML review has all. */
#define BLESS_MAX_LINES 40

/* BLESS.md: the written review that travels with the golden in the commit that moves it. */
static char *review_md(const char *run_dir, const char *golden, const char *review_dir, const rep_report *r)
{
    rep_sb sb = {0};
    char *origin = rep_manifest_origin(run_dir);
    time_t now = time(NULL);
    char when[32] = "?";
    struct tm tm;
    if (gmtime_r(&now, &tm))
        strftime(when, sizeof when, "%Y-%m-%d %H:%M UTC", &tm);
    rep_sb_printf(&sb, "# Bless review: %s\n\n- reviewed: %s\n- from run: `%s`\n- made by: %s\n", golden, when, run_dir, origin);
    free(origin);
    if (!r) {
        rep_sb_printf(&sb, "- replaces: nothing (new golden)\n");
        return sb.s;
    }
    char *old = rep_manifest_origin(golden);
    rep_sb_printf(&sb, "- replaces: %s\n- HTML review with thumbnails (not committed): `%s/report.html`\n\n", old,
                  review_dir);
    free(old);
    size_t cnt[REP_V_COUNT] = {0};
    for (size_t i = 0; i < r->count; i++)
        cnt[r->entries[i].verdict]++;
    rep_sb_printf(&sb, "The run against the golden it replaces: **%s** (exit %d) — %zu failed, %zu warned, %zu within "
                       "tolerance, %zu bit-exact, %zu size mismatch (%zu buffers, %d frames).\n",
                  rep_exit_word(r->exit), (int)r->exit, cnt[REP_V_FAIL], cnt[REP_V_WARN], cnt[REP_V_WITHIN],
                  cnt[REP_V_BITEXACT], cnt[REP_V_SIZE], r->count, r->frames);
    if (r->exit == REP_UNREADABLE)
        rep_sb_printf(&sb, "\nThe old golden could not be compared: %s\n", r->error.msg);
    if (r->prov) {
        rep_sb_printf(&sb, "\n## Provenance changes\n\n```\n");
        rep_prov_text(&sb, r->prov);
        rep_sb_printf(&sb, "```\n");
    }
    size_t n = 0, listed = 0;
    const rep_entry **order = rep_report_sorted(r, &n);
    for (size_t i = 0; i < n; i++)
        listed += rep_entry_listed(order[i]) ? 1 : 0;
    rep_sb_printf(&sb, "\n## What changes (%zu buffer%s not bit-exact, worst first", listed, listed == 1 ? "" : "s");
    if (listed > BLESS_MAX_LINES)
        rep_sb_printf(&sb, "; the first %d here, all in the HTML review", BLESS_MAX_LINES);
    rep_sb_printf(&sb, ")\n\n```\n");
    for (size_t i = 0, shown = 0; i < n && shown < BLESS_MAX_LINES; i++)
        if (rep_entry_listed(order[i])) {
            rep_report_line(&sb, r, order[i]);
            shown++;
        }
    free(order);
    rep_sb_printf(&sb, "```\n");
    if (r->prov && r->prov->timing_count) {
        rep_sb_printf(&sb, "\n## Timing\n\n```\n");
        rep_timing_text(&sb, r->prov);
        rep_sb_printf(&sb, "```\n");
    }
    return sb.s;
}

static eng_result write_review(const char *tmp, const char *md, eng_error *err)
{
    char *p = rep_path_join(tmp, "BLESS.md");
    eng_result r = rep_write_atomic(p, md, strlen(md), err);
    free(p);
    return r;
}

/* Bit-exact everywhere and no judged provenance difference: blessing would change nothing. */
static int unchanged(const rep_report *r)
{
    if (r->exit == REP_UNREADABLE || !r->prov || r->prov->warn || r->prov->fail || r->count == 0)
        return 0;
    for (size_t i = 0; i < r->count; i++)
        if (r->entries[i].verdict != REP_V_BITEXACT)
            return 0;
    return 1;
}

eng_result rep_bless_reviewed(const rep_bless_options *o, FILE *summary, rep_bless_outcome *outcome, eng_error *err)
{
    if (!o || !o->run_dir || !o->golden_dir || !o->golden_dir[0])
        return eng_fail(err, ENG_ERR_INVALID, "bless: a run folder and a golden folder are needed");
    /* "golden/" + ".tmp" must not become "golden/.tmp". */
    char *golden = rep_xstrdup(o->golden_dir);
    for (size_t n = strlen(golden); n > 1 && golden[n - 1] == '/'; n--)
        golden[n - 1] = 0;
    char rp[PATH_MAX], gp[PATH_MAX];
    if (realpath(o->run_dir, rp) && realpath(golden, gp) && strcmp(rp, gp) == 0) {
        free(golden);
        return eng_fail(err, ENG_ERR_INVALID, "%s: cannot bless a run onto itself", o->run_dir);
    }
    rep_run *run = NULL;
    eng_lock lock;
    eng_result r = rep_make_parent(golden, err);
    if (r == ENG_OK)
        r = eng_lock_take(golden, "ispm bless", &lock, err);
    else
        lock.fd = -1;
    if (r == ENG_OK)
        r = rep_golden_recover(golden, err);
    if (r == ENG_OK)
        r = check_target(golden, err);
    if (r == ENG_OK)
        r = verify_run(o->run_dir, &run, err);
    if (r != ENG_OK) {
        eng_lock_drop(&lock);
        free(golden);
        return r;
    }
    /* A run from another renderer than the canonical golden's goes into its renderer's set. */
    char *canonical = golden, *slug = NULL;
    golden = renderer_target(canonical, run, &slug);
    /* The shared object store is locked too (ispm golden gc takes the same lock), so that no
     * collection removes an object between its write here and the swap that lists it. */
    eng_lock slock = {.fd = -1};
    char *srel = NULL, *store = rep_store_find(golden, &srel);
    free(srel);
    if (golden != canonical)
        r = check_target(golden, err);
    if (r == ENG_OK && store)
        r = eng_lock_take(store, "ispm bless", &slock, err);
    free(store);
    if (r != ENG_OK) {
        eng_lock_drop(&lock);
        if (golden != canonical)
            free(canonical);
        free(golden);
        free(slug);
        rep_run_close(run);
        return r;
    }
    if (summary && slug)
        fprintf(summary, "bless: the run's renderer \"%s\" is not the golden's: renderer set %s\n", run->gl_renderer,
                slug);
    char *review_dir = o->review_dir ? rep_xstrdup(o->review_dir) : rep_path_join(o->run_dir, "bless");
    char *old_manifest = rep_path_join(golden, "manifest.json");
    int has_old = rep_is_file(old_manifest);
    free(old_manifest);
    rep_report rev;
    memset(&rev, 0, sizeof rev);
    rep_bless_outcome out = REP_BLESS_NEW;
    if (has_old) {
        rep_options ro;
        memset(&ro, 0, sizeof ro);
        ro.run_dir = o->run_dir;
        ro.golden_dir = golden;
        ro.report_dir = review_dir;
        eng_error ignored; /* an unreadable old golden is a difference: rev says why */
        rep_replay_report(&ro, &rev, &ignored);
        out = unchanged(&rev) ? REP_BLESS_SAME : o->accept ? REP_BLESS_REPLACED : REP_BLESS_REFUSED;
    }
    char *md = review_md(o->run_dir, golden, review_dir, has_old ? &rev : NULL);
    if (summary && out != REP_BLESS_NEW) {
        if (out == REP_BLESS_SAME) {
            fprintf(summary, "bless: %s is bit-exact with the run (%zu buffers) and made from the same inputs: "
                             "nothing to bless, the golden is unchanged\n", golden, rev.count);
        } else {
            fputs(md, summary);
            if (out == REP_BLESS_REFUSED)
                fprintf(summary, "\nbless: NOT blessed — the run differs from %s (review above; thumbnails in %s/report.html).\n"
                                 "If the change is intended: ispm bless %s %s --accept\n",
                        golden, review_dir, o->run_dir, o->golden_dir);
        }
    }
    if (out == REP_BLESS_NEW || out == REP_BLESS_REPLACED) {
        char *tmp = rep_xprintf("%s.tmp", golden);
        rep_store_stats st;
        memset(&st, 0, sizeof st);
        r = build_tmp(run, golden, canonical, tmp, &st, err);
        if (r == ENG_OK && summary && st.buffers)
            fprintf(summary, "bless: %zu buffers stored as objects: %d new (%llu bytes), %d already stored\n",
                    st.buffers, st.objects_new, (unsigned long long)st.bytes_new, st.objects_had);
        if (r == ENG_OK)
            r = write_review(tmp, md, err);
        if (r == ENG_OK)
            r = rep_swap_in(golden, tmp, err);
        if (r != ENG_OK)
            rep_remove_tree(tmp, NULL);
        free(tmp);
    }
    if (outcome)
        *outcome = out;
    free(md);
    rep_report_free(&rev);
    free(review_dir);
    if (golden != canonical)
        free(canonical);
    free(slug);
    free(golden);
    rep_run_close(run);
    eng_lock_drop(&slock);
    eng_lock_drop(&lock);
    return r;
}

eng_result rep_bless(const char *run_dir, const char *golden_dir, eng_error *err)
{
    rep_bless_options o = {run_dir, golden_dir, 1, NULL};
    return rep_bless_reviewed(&o, NULL, NULL, err);
}
