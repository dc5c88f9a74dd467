/* golden_store.c — writing goldens whose buffers are stored once (format 2, run/objects.c):
 * objects put into a store, the manifest of format 2, and the two commands that keep a store:
 * migrate (a golden of frame files becomes one of objects) and gc (objects no golden lists are
 * removed).
 *
 * An object is immutable and named by its content, so writing one is idempotent: a store that
 * already holds a digest is not written again (a rebless adds only the buffers that changed),
 * and an object is written before any manifest lists it, so an interrupted bless or migrate
 * leaves at most unlisted objects, which gc collects. What is already in the store is read
 * back and checked against the digest before it is relied on, and so is every new object
 * after writing: a store is never trusted blindly. Objects are single-part ZIP EXRs at zlib
 * level 9 (written once, read many times; the level does not slow decoding).
 */
#define _XOPEN_SOURCE 700

#include "rep.h"
#include "rep_run.h"
#include "rep_util.h"
#include "replay_internal.h"

#include "cap.h"

#include <cjson/cJSON.h>

#include <dirent.h>
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define OBJECT_ZIP_LEVEL 9

static int is_real_dir(const char *path)
{
    struct stat st;
    return lstat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

static uint64_t file_bytes(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (uint64_t)st.st_size : 0;
}

char *rep_store_find(const char *golden, char **rel)
{
    *rel = NULL;
    /* Lexically, from the golden's path: a golden being blessed for the first time does not
     * exist yet, so "<golden>/../objects" cannot be looked up through it. */
    char cwd[PATH_MAX];
    char *dir = golden[0] == '/' ? rep_xstrdup(golden) : getcwd(cwd, sizeof cwd) ? rep_path_join(cwd, golden) : NULL;
    if (!dir)
        return NULL;
    rep_sb r = {0};
    char *found = NULL;
    for (int up = 1; up <= 3 && !found; up++) {
        char *slash = strrchr(dir, '/');
        if (!slash || slash == dir)
            break;
        *slash = 0;
        rep_sb_printf(&r, "../");
        char *path = rep_path_join(dir, "objects");
        if (is_real_dir(path)) {
            found = path;
            *rel = rep_xprintf("%sobjects", r.s);
        } else {
            free(path);
        }
    }
    free(r.s);
    free(dir);
    return found;
}

eng_result rep_make_parent(const char *path, eng_error *err)
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

eng_result rep_swap_in(const char *golden, const char *tmp, eng_error *err)
{
    char *old = rep_xprintf("%s.old", golden);
    char *parent = rep_xstrdup(golden);
    char *slash = strrchr(parent, '/');
    if (slash)
        slash[slash == parent ? 1 : 0] = 0;
    int had_old = rep_is_dir(golden);
    eng_result r = had_old ? rep_remove_tree(old, err) : rep_make_parent(golden, err);
    if (r == ENG_OK && had_old && rename(golden, old) != 0)
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot move the old golden aside: %s", golden, strerror(errno));
    if (r == ENG_OK && rename(tmp, golden) != 0) {
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot rename %s into place: %s", golden, tmp, strerror(errno));
        if (had_old && rename(old, golden) != 0) /* put the old golden back; the message above stands */
            fprintf(stderr, "ispm: %s: the old golden is left at %s\n", golden, old);
    } else if (r == ENG_OK && (r = rep_sync_dir(slash ? parent : ".", err)) != ENG_OK) {
        if (rename(golden, tmp) != 0 || (had_old && rename(old, golden) != 0))
            fprintf(stderr, "ispm: %s: the swap could not be undone (the next bless rolls it back)\n", golden);
    }
    if (r == ENG_OK && had_old) { /* the renderer sets stay with the golden: they are blessed on their own */
        char *sets = rep_path_join(old, "renderers"), *dst = rep_path_join(golden, "renderers");
        if (rep_is_dir(sets) && !rep_is_dir(dst) && rename(sets, dst) != 0)
            r = eng_fail(err, ENG_ERR_IO, "%s: cannot keep the renderer sets: %s", sets, strerror(errno));
        free(sets);
        free(dst);
    }
    if (r == ENG_OK && had_old)
        rep_remove_tree(old, NULL); /* a leftover <golden>.old is removed by the next rep_golden_recover */
    free(parent);
    free(old);
    return r;
}

eng_result rep_golden_recover(const char *golden, eng_error *err)
{
    char *old = rep_xprintf("%s.old", golden);
    struct stat st;
    eng_result r = ENG_OK;
    if (lstat(old, &st) == 0 && S_ISDIR(st.st_mode)) {
        if (lstat(golden, &st) != 0) {
            if (rename(old, golden) != 0)
                r = eng_fail(err, ENG_ERR_IO, "%s: cannot restore the golden from %s: %s", golden, old,
                             strerror(errno));
            else
                fprintf(stderr, "ispm: %s: an interrupted bless was rolled back (%s restored)\n", golden, old);
        } else {
            /* a finished swap: keep the renderer sets if the move above did not happen yet */
            char *sets = rep_path_join(old, "renderers"), *dst = rep_path_join(golden, "renderers");
            if (rep_is_dir(sets) && !rep_is_dir(dst) && rename(sets, dst) != 0)
                r = eng_fail(err, ENG_ERR_IO, "%s: cannot keep the renderer sets: %s", sets, strerror(errno));
            free(sets);
            free(dst);
            if (r == ENG_OK)
                r = rep_remove_tree(old, err);
        }
    }
    char *tmp = rep_xprintf("%s.tmp", golden);
    if (r == ENG_OK)
        r = rep_remove_tree(tmp, err);
    free(tmp);
    free(old);
    return r;
}

eng_result rep_store_put(const char *store, const rep_buffer_info *b, const rep_part *p, rep_store_stats *st,
                         eng_error *err)
{
    char *path = rep_object_path(store, b->digest);
    struct stat sb;
    eng_result r = ENG_OK;
    rep_part back;
    memset(&back, 0, sizeof back);
    if (lstat(path, &sb) == 0) {
        r = rep_object_read(store, b, store, &back, err);
        if (r == ENG_OK)
            st->objects_had++;
    } else {
        char *fan = rep_xprintf("%s/%.2s", store, b->digest);
        r = rep_mkdirs(fan, err);
        free(fan);
        eng_buffer view = rep_part_buffer(p);
        view.name = b->name;
        if (r == ENG_OK)
            r = cap_write_exr_zip(path, &view, OBJECT_ZIP_LEVEL, err);
        if (r == ENG_OK && (r = rep_object_read(store, b, store, &back, err)) != ENG_OK)
            r = ENG_ERR_IO; /* what was just written does not read back: a writing failure */
        if (r == ENG_OK) {
            st->objects_new++;
            st->bytes_new += file_bytes(path);
        }
    }
    rep_part_clear(&back);
    free(path);
    return r;
}

eng_result rep_store_write_manifest(const rep_run *run, const char *dst, const char *objects_rel, eng_error *err)
{
    cJSON *root = NULL;
    eng_result r = rep_json_load(run->manifest_path, ENG_IN_NOFOLLOW, &root, err);
    if (r != ENG_OK)
        return r;
    if (!cJSON_IsObject(root)) {
        cJSON_Delete(root);
        return eng_fail(err, ENG_ERR_PARSE, "%s: not a JSON object", run->manifest_path);
    }
    cJSON *cap = cJSON_GetObjectItemCaseSensitive(root, "capture");
    if (!cJSON_IsObject(cap)) {
        cJSON_DeleteItemFromObjectCaseSensitive(root, "capture");
        cap = cJSON_AddObjectToObject(root, "capture");
    }
    cJSON_DeleteItemFromObjectCaseSensitive(cap, "compression");
    int ok = cJSON_AddStringToObject(cap, "compression", "zip") != NULL;
    if (objects_rel) {
        ok = ok && cJSON_ReplaceItemInObjectCaseSensitive(root, "format_version", cJSON_CreateNumber(2));
        cJSON_DeleteItemFromObjectCaseSensitive(root, "objects");
        ok = ok && cJSON_AddStringToObject(root, "objects", objects_rel) != NULL;
        cJSON *frames = cJSON_GetObjectItemCaseSensitive(root, "frames");
        /* Every buffer is its object: neither a frame's file nor a buffer's "stored_in" (the
         * earlier frame file of a run that holds it) means anything in a golden of objects. */
        for (cJSON *f = frames ? frames->child : NULL; f; f = f->next) {
            cJSON_DeleteItemFromObjectCaseSensitive(f, "file");
            cJSON *bufs = cJSON_GetObjectItemCaseSensitive(f, "buffers");
            for (cJSON *b = bufs ? bufs->child : NULL; b; b = b->next)
                if (cJSON_IsObject(b))
                    cJSON_DeleteItemFromObjectCaseSensitive(b, "stored_in");
        }
    }
    char *out = ok ? cJSON_Print(root) : NULL;
    cJSON_Delete(root);
    if (!out) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    char *doc = rep_xprintf("%s\n", out);
    cJSON_free(out);
    r = rep_write_atomic(dst, doc, strlen(doc), err);
    free(doc);
    return r;
}

eng_result rep_store_put_run(const rep_run *run, const char *store, rep_store_stats *st, eng_error *err)
{
    eng_result r = ENG_OK;
    for (int i = 0; i < run->frame_count && r == ENG_OK; i++) {
        rep_part *parts = NULL;
        const rep_frame_info *f = &run->frames[i];
        if ((r = rep_run_read_frame(run, i, &parts, err)) != ENG_OK)
            return r;
        for (int j = 0; j < f->buffer_count && r == ENG_OK; j++) {
            int seen = 0; /* the same digest earlier in this frame: already put */
            for (int k = 0; k < j && !seen; k++)
                seen = strcmp(f->buffers[k].digest, f->buffers[j].digest) == 0;
            st->buffers++;
            if (!seen)
                r = rep_store_put(store, &f->buffers[j], &parts[j], st, err);
        }
        rep_parts_free(parts, f->buffer_count);
    }
    return r;
}

/* Every buffer of every frame of a and b: the same names, sizes, channel names, digests and
 * float bits. *buffers gets how many were compared. */
static eng_result same_runs(const rep_run *a, const rep_run *b, size_t *buffers, eng_error *err)
{
    *buffers = 0;
    if (a->frame_count != b->frame_count)
        return eng_fail(err, ENG_ERR_IO, "%s: %d frames, %s has %d", b->manifest_path, b->frame_count,
                        a->manifest_path, a->frame_count);
    eng_result r = ENG_OK;
    for (int i = 0; i < a->frame_count && r == ENG_OK; i++) {
        const rep_frame_info *fa = &a->frames[i], *fb = &b->frames[i];
        rep_part *pa = NULL, *pb = NULL;
        if (fa->buffer_count != fb->buffer_count)
            return eng_fail(err, ENG_ERR_IO, "%s: frame %d: %d buffers, expected %d", b->manifest_path, i,
                            fb->buffer_count, fa->buffer_count);
        r = rep_run_read_frame(a, i, &pa, err);
        if (r == ENG_OK)
            r = rep_run_read_frame(b, i, &pb, err);
        for (int j = 0; j < fa->buffer_count && r == ENG_OK; j++) {
            const rep_part *x = &pa[j], *y = &pb[j];
            int same = strcmp(fa->buffers[j].name, fb->buffers[j].name) == 0 &&
                       strcmp(fa->buffers[j].digest, fb->buffers[j].digest) == 0 && strcmp(x->name, y->name) == 0 &&
                       x->width == y->width && x->height == y->height && x->channel_count == y->channel_count;
            for (int c = 0; same && c < x->channel_count; c++)
                same = strcmp(x->channels[c], y->channels[c]) == 0;
            size_t n = (size_t)x->width * (size_t)x->height * (size_t)x->channel_count;
            if (same)
                same = memcmp(x->data, y->data, n * sizeof(float)) == 0;
            if (!same)
                r = eng_fail(err, ENG_ERR_IO, "%s: frame %d, buffer %s: not bit-exact with %s", b->manifest_path, i,
                             fb->buffers[j].name, a->manifest_path);
            else
                ++*buffers;
        }
        if (pa)
            rep_parts_free(pa, fa->buffer_count);
        if (pb)
            rep_parts_free(pb, fb->buffer_count);
    }
    return r;
}

/* Copies the golden's files other than its manifest and frames (tolerances.json, BLESS.md, ...)
 * into tmp; any folder other than frames/ and renderers/ is refused (it would be lost). */
static eng_result copy_extras(const char *golden, const char *tmp, eng_error *err)
{
    DIR *d = opendir(golden);
    if (!d)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot list: %s", golden, strerror(errno));
    eng_result r = ENG_OK;
    for (struct dirent *e; r == ENG_OK && (e = readdir(d));) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..") || !strcmp(e->d_name, "manifest.json") ||
            !strcmp(e->d_name, "frames") || !strcmp(e->d_name, "renderers"))
            continue; /* renderers/: the sets, kept by rep_swap_in (each migrates on its own) */
        char *src = rep_path_join(golden, e->d_name), *dst = rep_path_join(tmp, e->d_name);
        struct stat st;
        if (lstat(src, &st) != 0 || !S_ISREG(st.st_mode))
            r = eng_fail(err, ENG_ERR_INVALID, "%s: not a regular file: migrate keeps only a golden's files", src);
        else
            r = rep_copy_file(src, ENG_IN_NOFOLLOW, dst, err);
        free(src);
        free(dst);
    }
    closedir(d);
    return r;
}

eng_result rep_golden_migrate(const char *golden_dir, FILE *out, eng_error *err)
{
    char *golden = rep_xstrdup(golden_dir);
    for (size_t n = strlen(golden); n > 1 && golden[n - 1] == '/'; n--)
        golden[n - 1] = 0;
    rep_run *old = NULL;
    eng_lock lock = {.fd = -1}, slock = {.fd = -1};
    eng_result r = eng_lock_take(golden, "ispm golden migrate", &lock, err);
    if (r == ENG_OK)
        r = rep_golden_recover(golden, err);
    if (r == ENG_OK)
        r = rep_run_open(golden, &old, err);
    if (r == ENG_OK && old->format_version == 2) {
        if (out)
            fprintf(out, "migrate: %s already stores its buffers as objects: nothing to do\n", golden);
        rep_run_close(old);
        eng_lock_drop(&lock);
        free(golden);
        return ENG_OK;
    }
    char *rel = NULL, *store = NULL, *tmp = rep_xprintf("%s.tmp", golden);
    if (r == ENG_OK) {
        store = rep_store_find(golden, &rel);
        if (!store) { /* the first golden of its folder to move: the store is made beside it */
            rel = rep_xstrdup("../objects");
            store = rep_path_join(golden, rel);
            r = rep_mkdirs(store, err);
        }
    }
    rep_store_stats st;
    memset(&st, 0, sizeof st);
    if (r == ENG_OK) /* against a concurrent gc, as bless */
        r = eng_lock_take(store, "ispm golden migrate", &slock, err);
    if (r == ENG_OK)
        r = rep_store_put_run(old, store, &st, err);
    if (r == ENG_OK && (r = rep_remove_tree(tmp, err)) == ENG_OK && (r = rep_mkdirs(tmp, err)) == ENG_OK)
        r = copy_extras(golden, tmp, err);
    char *mf = rep_path_join(tmp, "manifest.json");
    if (r == ENG_OK)
        r = rep_store_write_manifest(old, mf, rel, err);
    free(mf);
    size_t checked = 0;
    if (r == ENG_OK) {
        /* The migrated golden must be the old one, digest by digest and float by float. */
        rep_run *moved = NULL;
        r = rep_run_open(tmp, &moved, err);
        if (r == ENG_OK)
            r = same_runs(old, moved, &checked, err);
        rep_run_close(moved);
    }
    if (r == ENG_OK)
        r = rep_swap_in(golden, tmp, err);
    if (r != ENG_OK)
        rep_remove_tree(tmp, NULL);
    else if (out)
        fprintf(out,
                "migrate: %s: %d frames, %zu buffers bit-exact as objects in %s: %d new (%llu bytes), %d already "
                "stored\n",
                golden, old->frame_count, checked, store, st.objects_new, (unsigned long long)st.bytes_new,
                st.objects_had);
    rep_run_close(old);
    eng_lock_drop(&slock);
    eng_lock_drop(&lock);
    free(tmp);
    free(store);
    free(rel);
    free(golden);
    return r;
}

/* ---------------------------------------------------------------- unpack */

eng_result rep_golden_unpack(const char *golden, const char *dst, FILE *out, eng_error *err)
{
    struct stat st;
    if (lstat(dst, &st) == 0)
        return eng_fail(err, ENG_ERR_INVALID, "%s: exists: unpack writes a new folder", dst);
    rep_run *g = NULL;
    eng_result r = rep_run_open(golden, &g, err);
    if (r != ENG_OK)
        return r;
    char *frames = rep_path_join(dst, "frames");
    r = rep_mkdirs(frames, err);
    free(frames);
    cJSON *root = NULL;
    if (r == ENG_OK && (r = rep_json_load(g->manifest_path, ENG_IN_NOFOLLOW, &root, err)) == ENG_OK &&
        !cJSON_IsObject(root))
        r = eng_fail(err, ENG_ERR_PARSE, "%s: not a JSON object", g->manifest_path);
    cJSON *jf = root ? cJSON_GetObjectItemCaseSensitive(root, "frames") : NULL;
    jf = jf ? jf->child : NULL;
    for (int i = 0; r == ENG_OK && i < g->frame_count; i++, jf = jf->next) {
        const rep_frame_info *f = &g->frames[i];
        rep_part *parts = NULL;
        if ((r = rep_run_read_frame(g, i, &parts, err)) != ENG_OK)
            break;
        eng_buffer *bufs = rep_xcalloc((size_t)f->buffer_count, sizeof *bufs);
        const eng_buffer **bp = rep_xcalloc((size_t)f->buffer_count, sizeof *bp);
        for (int j = 0; j < f->buffer_count; j++) {
            bufs[j] = rep_part_buffer(&parts[j]);
            bp[j] = &bufs[j];
        }
        char *rel = rep_xprintf("frames/%06d.exr", i), *path = rep_path_join(dst, rel);
        r = cap_write_exr(path, bp, f->buffer_count, err);
        cJSON_DeleteItemFromObjectCaseSensitive(jf, "file");
        if (!cJSON_AddStringToObject(jf, "file", rel)) {
            fprintf(stderr, "ispm: out of memory\n");
            abort();
        }
        free(rel);
        free(path);
        free(bufs);
        free(bp);
        rep_parts_free(parts, f->buffer_count);
    }
    if (r == ENG_OK) {
        cJSON_ReplaceItemInObjectCaseSensitive(root, "format_version", cJSON_CreateNumber(1));
        cJSON_DeleteItemFromObjectCaseSensitive(root, "objects");
        char *doc = cJSON_Print(root), *mf = rep_path_join(dst, "manifest.json");
        char *withnl = rep_xprintf("%s\n", doc);
        r = rep_write_atomic(mf, withnl, strlen(withnl), err);
        cJSON_free(doc);
        free(withnl);
        free(mf);
    }
    char *tol = rep_path_join(golden, "tolerances.json"), *tol_dst = rep_path_join(dst, "tolerances.json");
    if (r == ENG_OK && rep_is_file(tol))
        r = rep_copy_file(tol, ENG_IN_NOFOLLOW, tol_dst, err);
    free(tol);
    free(tol_dst);
    if (r == ENG_OK) { /* read back: the frame files decode to the digests */
        rep_run *u = NULL;
        size_t checked = 0;
        r = rep_run_open(dst, &u, err);
        if (r == ENG_OK)
            r = same_runs(g, u, &checked, err);
        rep_run_close(u);
        if (r == ENG_OK && out)
            fprintf(out, "unpack: %s: %d frames, %zu buffers bit-exact in %s/frames\n", golden, g->frame_count, checked,
                    dst);
    }
    cJSON_Delete(root);
    rep_run_close(g);
    return r;
}

/* ---------------------------------------------------------------- gc */

typedef struct digest_set {
    char (*d)[40];
    size_t n, cap;
} digest_set;

static void set_add(digest_set *s, const char *d)
{
    if (s->n == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 1024;
        s->d = rep_xrealloc(s->d, s->cap * sizeof *s->d);
    }
    memcpy(s->d[s->n++], d, 40);
}

static int cmp_digest(const void *a, const void *b)
{
    return strcmp(a, b);
}

/* The digests listed by every golden under dir (depth levels) whose store is store_real. */
static eng_result collect(const char *dir, const char *store_real, int depth, digest_set *s, int *goldens,
                          eng_error *err)
{
    char *mf = rep_path_join(dir, "manifest.json");
    int is_golden = rep_is_file(mf);
    free(mf);
    if (is_golden) {
        rep_run *g = NULL;
        eng_result r = rep_run_open(dir, &g, err);
        if (r != ENG_OK)
            return r; /* an unreadable golden might list any object: collect nothing */
        ++*goldens;
        char real[PATH_MAX];
        if (g->format_version == 2 && realpath(g->objects_dir, real) && strcmp(real, store_real) == 0)
            for (int i = 0; i < g->frame_count; i++)
                for (int j = 0; j < g->frames[i].buffer_count; j++)
                    set_add(s, g->frames[i].buffers[j].digest);
        rep_run_close(g);
    }
    if (depth == 0)
        return ENG_OK;
    DIR *d = opendir(dir);
    if (!d)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot list: %s", dir, strerror(errno));
    eng_result r = ENG_OK;
    for (struct dirent *e; r == ENG_OK && (e = readdir(d));) {
        if (e->d_name[0] == '.' || !strcmp(e->d_name, "objects") || !strcmp(e->d_name, "frames"))
            continue;
        char *sub = rep_path_join(dir, e->d_name);
        if (is_real_dir(sub))
            r = collect(sub, store_real, depth - 1, s, goldens, err);
        free(sub);
    }
    closedir(d);
    return r;
}

static int is_object_name(const char *n, const char *fan)
{
    if (strlen(n) != 36 || strcmp(n + 32, ".exr") != 0 || strncmp(n, fan, 2) != 0)
        return 0;
    for (int i = 0; i < 32; i++)
        if (!((n[i] >= '0' && n[i] <= '9') || (n[i] >= 'a' && n[i] <= 'f')))
            return 0;
    return 1;
}

eng_result rep_golden_gc(const char *root, int dry_run, rep_gc_stats *st, eng_error *err)
{
    memset(st, 0, sizeof *st);
    char *store = rep_path_join(root, "objects");
    char real[PATH_MAX];
    if (!is_real_dir(store) || !realpath(store, real)) {
        eng_result r = eng_fail(err, ENG_ERR_INVALID, "%s: no object store (a folder, not a link)", store);
        free(store);
        return r;
    }
    /* One collection at a time, and none while a bless or migrate writes into the store. */
    eng_lock lock = {.fd = -1};
    eng_result r = dry_run ? ENG_OK : eng_lock_take(store, "ispm golden gc", &lock, err);
    digest_set s = {0};
    if (r == ENG_OK)
        r = collect(root, real, 4, &s, &st->goldens, err);
    if (r == ENG_OK)
        qsort(s.d, s.n, sizeof *s.d, cmp_digest);
    DIR *d = r == ENG_OK ? opendir(store) : NULL;
    if (r == ENG_OK && !d)
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot list: %s", store, strerror(errno));
    for (struct dirent *e; r == ENG_OK && (e = readdir(d));) {
        if (e->d_name[0] == '.')
            continue;
        char *fan = rep_path_join(store, e->d_name);
        DIR *fd = strlen(e->d_name) == 2 && is_real_dir(fan) ? opendir(fan) : NULL;
        int left = 0;
        for (struct dirent *o; fd && r == ENG_OK && (o = readdir(fd));) {
            if (!strcmp(o->d_name, ".") || !strcmp(o->d_name, ".."))
                continue;
            char *p = rep_path_join(fan, o->d_name);
            char key[40];
            if (is_object_name(o->d_name, e->d_name)) {
                memcpy(key, o->d_name, 32);
                key[32] = 0;
            } else {
                key[0] = 0; /* a stray file (a temporary of an interrupted write): not listed */
            }
            if (key[0] && bsearch(key, s.d, s.n, sizeof *s.d, cmp_digest)) {
                st->kept++;
                st->bytes_kept += file_bytes(p);
                left++;
            } else {
                st->removed++;
                st->bytes_removed += file_bytes(p);
                if (!dry_run && unlink(p) != 0)
                    r = eng_fail(err, ENG_ERR_IO, "%s: cannot remove: %s", p, strerror(errno));
                left += dry_run;
            }
            free(p);
        }
        if (fd)
            closedir(fd);
        if (fd && !left && !dry_run)
            rmdir(fan);
        free(fan);
    }
    if (d)
        closedir(d);
    free(s.d);
    free(store);
    eng_lock_drop(&lock);
    return r;
}
