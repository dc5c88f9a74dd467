/* bless.c — rep_bless: a run becomes the golden that later runs are compared against.
 *
 * Only a run that replay itself would accept is blessed: complete manifest, every frame file
 * present and decoding to its manifest digests; anything less is refused with ENG_ERR_INVALID
 * (a golden that cannot be read would fail every later replay as UNREADABLE, or worse, pass).
 * The copy is built beside the target in <golden>.tmp, with the golden's tolerances.json kept
 * if it had one (tolerances are tuned by people and outlive any one blessing) or the default
 * one written, and then swapped in with renames, so an interrupted bless leaves the old golden
 * or the new one, never a mixture. Only manifest.json and the frame files are copied: a
 * replay/ report folder inside the run is not part of a golden.
 */
#define _XOPEN_SOURCE 700

#include "rep_internal.h"

#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
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

/* Creates the parent folders of path (path names a file). */
static eng_result make_parent(const char *path, eng_error *err)
{
    char *dir = rep_xstrdup(path);
    char *slash = strrchr(dir, '/');
    eng_result r = ENG_OK;
    if (slash && slash != dir) {
        *slash = 0;
        r = rep_mkdirs(dir, err);
    }
    free(dir);
    return r;
}

static eng_result build_tmp(const rep_run *run, const char *golden, const char *tmp, eng_error *err)
{
    eng_result r = rep_remove_tree(tmp, err);
    if (r == ENG_OK)
        r = rep_mkdirs(tmp, err);
    if (r != ENG_OK)
        return r;
    char *dst = rep_path_join(tmp, "manifest.json");
    r = rep_copy_file(run->manifest_path, dst, err);
    free(dst);
    for (int i = 0; i < run->frame_count && r == ENG_OK; i++) {
        dst = rep_path_join(tmp, run->frames[i].file);
        r = make_parent(dst, err);
        if (r == ENG_OK)
            r = rep_copy_file(run->frames[i].path, dst, err);
        free(dst);
    }
    if (r != ENG_OK)
        return r;
    char *old_tol = rep_path_join(golden, "tolerances.json");
    char *new_tol = rep_path_join(tmp, "tolerances.json");
    if (rep_is_file(old_tol)) {
        r = rep_copy_file(old_tol, new_tol, err);
    } else {
        char *text = rep_tol_default_json();
        r = rep_write_atomic(new_tol, text, strlen(text), err);
        free(text);
    }
    free(old_tol);
    free(new_tol);
    return r;
}

static eng_result swap_in(const char *golden, const char *tmp, eng_error *err)
{
    if (!rep_is_dir(golden)) {
        eng_result r = make_parent(golden, err);
        if (r != ENG_OK)
            return r;
        if (rename(tmp, golden) != 0)
            return eng_fail(err, ENG_ERR_IO, "%s: cannot rename %s into place: %s", golden, tmp, strerror(errno));
        return ENG_OK;
    }
    char *old = rep_xprintf("%s.old", golden);
    eng_result r = rep_remove_tree(old, err);
    if (r == ENG_OK && rename(golden, old) != 0)
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot move the old golden aside: %s", golden, strerror(errno));
    if (r == ENG_OK && rename(tmp, golden) != 0) {
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot rename %s into place: %s", golden, tmp, strerror(errno));
        if (rename(old, golden) != 0) /* put the old golden back; the message above stands */
            fprintf(stderr, "ispm: %s: the old golden is left at %s\n", golden, old);
    }
    if (r == ENG_OK)
        r = rep_remove_tree(old, err);
    free(old);
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

eng_result rep_bless(const char *run_dir, const char *golden_dir, eng_error *err)
{
    if (!run_dir || !golden_dir || !golden_dir[0])
        return eng_fail(err, ENG_ERR_INVALID, "bless: a run folder and a golden folder are needed");
    /* "golden/" + ".tmp" must not become "golden/.tmp". */
    char *golden = rep_xstrdup(golden_dir);
    for (size_t n = strlen(golden); n > 1 && golden[n - 1] == '/'; n--)
        golden[n - 1] = 0;
    char rp[PATH_MAX], gp[PATH_MAX];
    if (realpath(run_dir, rp) && realpath(golden, gp) && strcmp(rp, gp) == 0) {
        free(golden);
        return eng_fail(err, ENG_ERR_INVALID, "%s: cannot bless a run onto itself", run_dir);
    }
    rep_run *run = NULL;
    eng_result r = check_target(golden, err);
    if (r == ENG_OK)
        r = verify_run(run_dir, &run, err);
    if (r != ENG_OK) {
        free(golden);
        return r;
    }
    char *tmp = rep_xprintf("%s.tmp", golden);
    r = build_tmp(run, golden, tmp, err);
    if (r == ENG_OK)
        r = swap_in(golden, tmp, err);
    if (r != ENG_OK)
        rep_remove_tree(tmp, NULL);
    free(tmp);
    free(golden);
    rep_run_close(run);
    return r;
}
