/* objects.c — goldens whose buffers are stored once, by content (manifest format_version 2).
 *
 * A golden of format 2 keeps no frame files. Each distinct buffer is one single-part EXR in an
 * object store, named by the buffer's digest (eng_buffer_digest, the manifest's XXH3-128):
 * <store>/<first two hex digits>/<digest>.exr. The manifest's "objects" names the store
 * relative to the golden: "objects" (its own) or "../objects" (shared by the goldens of one
 * folder; a renderer set, two levels further down, says "../../../objects"). Frames list their
 * buffers by digest, so a buffer repeated across frames, methods or goldens is one file, and a
 * rebless adds only the buffers that changed.
 *
 * Nothing is trusted: an "objects" path that leaves the golden other than by those parents, a
 * store, fan-out folder or object that is a symbolic link or not what it should be, an object
 * missing, holding more than one part, of another size or channel count, or whose pixels do
 * not hash to its name: each is one error naming the file (ENG_ERR_INVALID or ENG_ERR_IO; replay
 * exits 4 on either). The digest covers channel planes in name order, not the names, so one
 * object serves buffers whose channel names differ: channels are matched by their rank in name
 * order, and the part comes back with the manifest's names, in the order the frame-file reader
 * gives them (OpenImageIO's), so every tool sees what it would see in a frame file.
 *
 * Frames are mostly read in order, and a golden's buffers repeat from frame to frame (shadow
 * maps of static lights, G-buffers of a still camera): of the last frame read, the parts whose
 * digest the next frame lists again are kept, and a buffer of the next frame with the same
 * digest, size and channel names is copied from them instead of being read and decoded again
 * (they were verified when read). Keeping every part would cost more in copies than it saves.
 */
#define _POSIX_C_SOURCE 200809L

#include "oiio_shim.h"
#include "rep_run.h"
#include "rep_util.h"
#include "run_internal.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MAX_STORE_DEPTH 3

eng_result rep_objects_resolve(const char *dir, const char *mf, const char *rel, char **store, eng_error *err)
{
    *store = NULL;
    const char *p = rel;
    int up = 0;
    while (strncmp(p, "../", 3) == 0 && up <= MAX_STORE_DEPTH) {
        p += 3;
        up++;
    }
    if (up > MAX_STORE_DEPTH || strcmp(p, "objects") != 0)
        return eng_fail(err, ENG_ERR_INVALID,
                        "%s: \"objects\" is \"%s\": the store must be \"objects\" or up to %d parent folders' "
                        "\"objects\" (the path escapes the golden)",
                        mf, rel, MAX_STORE_DEPTH);
    char *path = rep_path_join(dir, rel);
    struct stat st;
    if (lstat(path, &st) != 0) {
        eng_result r = eng_fail(err, ENG_ERR_IO, "%s: object store missing (\"objects\" in %s)", path, mf);
        free(path);
        return r;
    }
    if (S_ISLNK(st.st_mode) || !S_ISDIR(st.st_mode)) {
        eng_result r = eng_fail(err, ENG_ERR_INVALID, "%s: object store is %s", path,
                                S_ISLNK(st.st_mode) ? "a symbolic link" : "not a folder");
        free(path);
        return r;
    }
    *store = path;
    return ENG_OK;
}

char *rep_object_path(const char *store, const char *digest)
{
    return rep_xprintf("%s/%.2s/%s.exr", store, digest, digest);
}

eng_result rep_object_check(const char *store, const char *digest, const char *mf, eng_error *err)
{
    char *fan = rep_xprintf("%s/%.2s", store, digest);
    char *obj = rep_object_path(store, digest);
    struct stat st;
    eng_result r = ENG_OK;
    if (lstat(fan, &st) == 0 && (S_ISLNK(st.st_mode) || !S_ISDIR(st.st_mode)))
        r = eng_fail(err, ENG_ERR_INVALID, "%s: object folder is %s", fan,
                     S_ISLNK(st.st_mode) ? "a symbolic link" : "not a folder");
    else if (lstat(obj, &st) != 0)
        r = eng_fail(err, ENG_ERR_IO, "%s: object missing (listed in %s)", obj, mf);
    else if (S_ISLNK(st.st_mode))
        r = eng_fail(err, ENG_ERR_INVALID, "%s: object is a symbolic link", obj);
    else if (!S_ISREG(st.st_mode))
        r = eng_fail(err, ENG_ERR_INVALID, "%s: object is not a regular file", obj);
    free(fan);
    free(obj);
    return r;
}

/* Index of s among names[0..n) in strcmp order (names are distinct). */
static int name_rank(char *const *names, int n, const char *s)
{
    int k = 0;
    for (int i = 0; i < n; i++)
        k += strcmp(names[i], s) < 0;
    return k;
}

/* p's channels renamed to b's by rank in name order and put in the frame reader's order. */
static void rename_channels(rep_part *p, const rep_buffer_info *b)
{
    const int n = b->channel_count;
    int src_of_rank[ENG_MAX_CHANNELS];
    for (int c = 0; c < n; c++)
        src_of_rank[name_rank(p->channels, n, p->channels[c])] = c;
    int order[ENG_MAX_CHANNELS];
    rep_exr_channel_order((const char *const *)b->channels, n, order);
    const size_t px = (size_t)p->width * (size_t)p->height;
    float *data = rep_xmalloc(px * (size_t)n * sizeof *data);
    int src[ENG_MAX_CHANNELS];
    for (int c = 0; c < n; c++)
        src[c] = src_of_rank[name_rank(b->channels, n, b->channels[order[c]])];
    for (size_t i = 0; i < px; i++)
        for (int c = 0; c < n; c++)
            data[i * (size_t)n + (size_t)c] = p->data[i * (size_t)n + (size_t)src[c]];
    free(p->data);
    p->data = data;
    for (int c = 0; c < n; c++) {
        free(p->channels[c]);
        p->channels[c] = rep_xstrdup(b->channels[order[c]]);
    }
}

/* rep_parts_check for an object: one part of the buffer's size and channel count. */
static eng_result check_head(void *user, const char *path, const rep_part *heads, int count, eng_error *err)
{
    const rep_buffer_info *b = user;
    if (count != 1)
        return eng_fail(err, ENG_ERR_INVALID, "%s: object holds %d parts, expected 1", path, count);
    if (heads[0].width != b->width || heads[0].height != b->height || heads[0].channel_count != b->channel_count)
        return eng_fail(err, ENG_ERR_INVALID, "%s: object is %dx%d with %d channels, buffer %s is %dx%d with %d", path,
                        heads[0].width, heads[0].height, heads[0].channel_count, b->name, b->width, b->height,
                        b->channel_count);
    return ENG_OK;
}

eng_result rep_object_read(const char *store, const rep_buffer_info *b, const char *mf, rep_part *out, eng_error *err)
{
    memset(out, 0, sizeof *out);
    eng_result r = rep_object_check(store, b->digest, mf, err);
    if (r != ENG_OK)
        return r;
    char *path = rep_object_path(store, b->digest);
    rep_part *parts = NULL;
    int count = 0;
    /* Bounded like a frame file: a regular file no larger than its buffer uncompressed (plus
     * headers and chunk tables), its one part's header matching the buffer before any pixel is
     * decoded, so a hostile object costs no more memory than the manifest promises. */
    const uint64_t floats = (uint64_t)b->width * (uint64_t)b->height * (uint64_t)b->channel_count;
    r = eng_check_input(path, ENG_IN_NOFOLLOW, floats * 4 + (uint64_t)b->height * 16 + 65536 + (1u << 20), NULL,
                        err);
    if (r == ENG_OK)
        r = rep_read_parts_checked(path, floats ? (size_t)floats : 1, check_head, (void *)b, &parts, &count, err);
    if (r == ENG_OK && count != 1)
        r = eng_fail(err, ENG_ERR_INVALID, "%s: object holds %d parts, expected 1", path, count);
    else if (r == ENG_OK && (parts[0].width != b->width || parts[0].height != b->height ||
                             parts[0].channel_count != b->channel_count))
        r = eng_fail(err, ENG_ERR_INVALID, "%s: object is %dx%d with %d channels, buffer %s is %dx%d with %d", path,
                     parts[0].width, parts[0].height, parts[0].channel_count, b->name, b->width, b->height,
                     b->channel_count);
    if (r == ENG_OK) {
        *out = parts[0];
        memset(&parts[0], 0, sizeof parts[0]);
        if (!rep_run_same_channels(out, b))
            rename_channels(out, b);
        free(out->name);
        out->name = rep_xstrdup(b->name);
        r = rep_run_verify_part(path, out, b, err);
        if (r != ENG_OK)
            rep_part_clear(out);
    }
    rep_parts_free(parts, count);
    free(path);
    return r;
}

/* A copy of src, an already verified part of the same digest, as buffer b. */
static void copy_part(const rep_part *src, const rep_buffer_info *b, rep_part *out)
{
    size_t n = (size_t)src->width * (size_t)src->height * (size_t)src->channel_count;
    out->name = rep_xstrdup(b->name);
    out->width = src->width;
    out->height = src->height;
    out->channel_count = src->channel_count;
    for (int c = 0; c < src->channel_count; c++)
        out->channels[c] = rep_xstrdup(src->channels[c]);
    out->data = rep_xmalloc(n * sizeof *out->data);
    memcpy(out->data, src->data, n * sizeof *out->data);
}

struct rep_object_cache {
    pthread_mutex_t lock;
    int count;
    rep_part *parts;
    char (*digests)[40];
};

struct rep_object_cache *rep_object_cache_create(void)
{
    struct rep_object_cache *c = rep_xcalloc(1, sizeof *c);
    pthread_mutex_init(&c->lock, NULL);
    return c;
}

static void cache_clear(struct rep_object_cache *c)
{
    rep_parts_free(c->parts, c->count);
    free(c->digests);
    c->parts = NULL;
    c->digests = NULL;
    c->count = 0;
}

void rep_object_cache_free(struct rep_object_cache *c)
{
    if (!c)
        return;
    cache_clear(c);
    pthread_mutex_destroy(&c->lock);
    free(c);
}

/* Whether the verified part p (of digest d) can stand for buffer b. */
static int serves(const rep_part *p, const char *d, const rep_buffer_info *b)
{
    return strcmp(d, b->digest) == 0 && p->width == b->width && p->height == b->height &&
           p->channel_count == b->channel_count && rep_run_same_channels(p, b);
}

eng_result rep_objects_read_frame(const rep_run *run, int frame, rep_part **out, eng_error *err)
{
    *out = NULL;
    const rep_frame_info *f = &run->frames[frame];
    const int n = f->buffer_count;
    rep_part *parts = rep_xcalloc((size_t)n, sizeof *parts);
    eng_result *res = rep_xcalloc((size_t)n, sizeof *res);
    eng_error *errs = rep_xcalloc((size_t)n, sizeof *errs);
    int *have = rep_xcalloc((size_t)n, sizeof *have);
    struct rep_object_cache *cache = run->object_cache;
    if (cache) {
        pthread_mutex_lock(&cache->lock);
        for (int j = 0; j < n; j++)
            for (int k = 0; k < cache->count && !have[j]; k++)
                if (serves(&cache->parts[k], cache->digests[k], &f->buffers[j])) {
                    copy_part(&cache->parts[k], &f->buffers[j], &parts[j]);
                    have[j] = 1;
                }
        pthread_mutex_unlock(&cache->lock);
    }
    int *same_as = rep_xmalloc((size_t)n * sizeof *same_as);
    for (int j = 0; j < n; j++) {
        same_as[j] = -1;
        for (int k = 0; k < j && same_as[j] < 0 && !have[j]; k++)
            if (!have[k] && same_as[k] < 0 && strcmp(f->buffers[k].digest, f->buffers[j].digest) == 0 &&
                f->buffers[k].channel_count == f->buffers[j].channel_count &&
                f->buffers[k].width == f->buffers[j].width && f->buffers[k].height == f->buffers[j].height)
                same_as[j] = k;
    }
    /* Objects decode as tasks: on other threads inside replay's parallel region, on this one
     * outside it. Each task writes only its own slot. */
#pragma omp taskloop grainsize(1) default(none) shared(run, f, parts, res, errs, same_as, have, n)
    for (int j = 0; j < n; j++)
        if (!have[j] && same_as[j] < 0)
            res[j] = rep_object_read(run->objects_dir, &f->buffers[j], run->manifest_path, &parts[j], &errs[j]);
    eng_result r = ENG_OK;
    for (int j = 0; j < n && r == ENG_OK; j++)
        if (!have[j] && same_as[j] < 0 && res[j] != ENG_OK) {
            r = res[j];
            if (err)
                *err = errs[j];
        }
    for (int j = 0; j < n && r == ENG_OK; j++)
        if (same_as[j] >= 0) {
            if (rep_run_same_channels(&parts[same_as[j]], &f->buffers[j]))
                copy_part(&parts[same_as[j]], &f->buffers[j], &parts[j]);
            else
                r = rep_object_read(run->objects_dir, &f->buffers[j], run->manifest_path, &parts[j], err);
        }
    if (r == ENG_OK && cache) {
        /* The cache keeps only what the next frame lists again (the manifest says which): a copy
         * costs less than a decode, but copying every part would cost more than it saves. */
        const rep_frame_info *next = frame + 1 < run->frame_count ? &run->frames[frame + 1] : NULL;
        rep_part *keep = rep_xcalloc((size_t)n + 1, sizeof *keep);
        char(*digests)[40] = rep_xmalloc(((size_t)n + 1) * sizeof *digests);
        int kept = 0;
        for (int j = 0; j < n && next; j++) {
            int again = 0;
            for (int k = 0; k < next->buffer_count && !again; k++)
                again = strcmp(next->buffers[k].digest, f->buffers[j].digest) == 0;
            for (int k = 0; k < kept && again; k++)
                again = strcmp(digests[k], f->buffers[j].digest) != 0 || !rep_run_same_channels(&keep[k], &f->buffers[j]);
            if (again) {
                copy_part(&parts[j], &f->buffers[j], &keep[kept]);
                memcpy(digests[kept++], f->buffers[j].digest, 40);
            }
        }
        pthread_mutex_lock(&cache->lock);
        cache_clear(cache);
        cache->parts = keep;
        cache->digests = digests;
        cache->count = kept;
        pthread_mutex_unlock(&cache->lock);
    }
    free(res);
    free(errs);
    free(same_as);
    free(have);
    if (r != ENG_OK) {
        rep_parts_free(parts, n);
        return r;
    }
    *out = parts;
    return ENG_OK;
}

char *rep_renderer_slug(const char *vendor, const char *renderer)
{
    rep_sb sb = {0};
    const char *src[2] = {vendor, renderer};
    int dash = 0;
    for (int s = 0; s < 2; s++, dash = 1)
        for (const char *c = src[s] ? src[s] : ""; *c && sb.len < 80; c++) {
            char ch = *c;
            if (ch >= 'A' && ch <= 'Z')
                ch = (char)(ch - 'A' + 'a');
            if ((ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9')) {
                if (dash && sb.len)
                    rep_sb_printf(&sb, "-");
                rep_sb_printf(&sb, "%c", ch);
                dash = 0;
            } else {
                dash = 1;
            }
        }
    if (!sb.len)
        rep_sb_printf(&sb, "unknown");
    return sb.s;
}
