/* merge.c — ispm merge: frame shards checked against each other and written as one run
 * (merge.h has the contract).
 *
 * Everything is decided from the shards' manifests before anything is written: provenance,
 * coverage and the overlap digests. Only then is the run folder prepared (as cap_create does:
 * an old manifest unlinked first) and filled in the order capture uses — run.json, then per
 * frame the EXR and its record, each by rename of a complete file, and manifest.json last
 * after the frames' directory entries are fsynced — so a merge killed at any moment leaves a
 * folder that replay refuses (no manifest), never a complete-looking run. Frame files are
 * hard-linked from the shards (a run's files are never rewritten in place: each appears by
 * rename), copied where the shards lie on another file system; a shard's frame that is not a
 * regular file inside it (a symbolic link) is refused. A complete run in the way (--force) is
 * replaced only once the merged one is complete beside it (write_merged), and the output may
 * not be a shard. */
#define _XOPEN_SOURCE 700

#include "cap_internal.h"
#include "merge.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define MAX_MANIFEST_BYTES ((size_t)256 << 20)
#define MAX_FRAME 10000000

int cap_parse_range(const char *s, int *first, int *last)
{
    long v[2] = {0, 0};
    int n = 0;
    const char *p = s;
    if (!s)
        return 0;
    for (;;) {
        if (*p < '0' || *p > '9')
            return 0;
        long x = 0;
        while (*p >= '0' && *p <= '9') {
            x = x * 10 + (*p++ - '0');
            if (x > MAX_FRAME)
                return 0;
        }
        v[n++] = x;
        if (*p == 0)
            break;
        if (*p != '-' || n == 2)
            return 0;
        p++;
    }
    if (n == 1)
        v[1] = v[0];
    if (v[1] < v[0])
        return 0;
    *first = (int)v[0];
    *last = (int)v[1];
    return 1;
}

eng_result cap_merge_coverage(const int *first, const int *last, const char *const *names, int count,
                              int frame_count, eng_error *err)
{
    if (count < 1)
        return eng_fail(err, ENG_ERR_INVALID, "no shard to merge");
    if (first[0] > 0)
        return eng_fail(err, ENG_ERR_INVALID, "frames 0-%d are in no shard (the first, %s, begins at %d)",
                        first[0] - 1, names[0], first[0]);
    for (int k = 1; k < count; k++) {
        if (first[k] <= last[k - 1])
            return eng_fail(err, ENG_ERR_INVALID, "frames %d-%d are in two shards, %s and %s", first[k],
                            last[k - 1] < last[k] ? last[k - 1] : last[k], names[k - 1], names[k]);
        if (first[k] > last[k - 1] + 1)
            return eng_fail(err, ENG_ERR_INVALID, "frames %d-%d are in no shard (a gap between %s and %s)",
                            last[k - 1] + 1, first[k] - 1, names[k - 1], names[k]);
    }
    if (last[count - 1] < frame_count - 1)
        return eng_fail(err, ENG_ERR_INVALID, "frames %d-%d are in no shard (the last, %s, ends at %d)",
                        last[count - 1] + 1, frame_count - 1, names[count - 1], last[count - 1]);
    if (last[count - 1] > frame_count - 1)
        return eng_fail(err, ENG_ERR_INVALID, "%s: frames up to %d, but the sequence has %d", names[count - 1],
                        last[count - 1], frame_count);
    return ENG_OK;
}

/* ---------------------------------------------------------------- shards */

typedef struct shard {
    const char *dir;
    cJSON *manifest;
    int first, last, warmup, overlap, seq_frames;
    int write_first; /* first - overlap: the shard's first frame */
    const cJSON *frames;
} shard;

static const char *str_at(const cJSON *o, const char *key)
{
    const cJSON *j = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsString(j) ? j->valuestring : NULL;
}

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

/* Reads and checks dir/manifest.json as a complete shard's. */
static eng_result load_shard(const char *dir, shard *s, eng_error *err)
{
    memset(s, 0, sizeof *s);
    s->dir = dir;
    char *path = cap__join(dir, "manifest.json");
    char *text = NULL;
    size_t len = 0;
    eng_result r = ENG_OK;
    if (!file_exists(path)) {
        r = eng_fail(err, ENG_ERR_INVALID, "%s: no manifest.json: the shard is incomplete (failed, killed or "
                     "still recording) or not a run", dir);
        goto out;
    }
    if ((r = eng_read_input(path, ENG_IN_NOFOLLOW, MAX_MANIFEST_BYTES, &text, &len, err)) != ENG_OK ||
        (r = eng_json_precheck(path, text, len, ENG_JSON_MAX_DEPTH, err)) != ENG_OK)
        goto out;
    s->manifest = cJSON_ParseWithLength(text, len);
    const cJSON *m = s->manifest, *sh = cJSON_GetObjectItemCaseSensitive(m, "shard");
    const cJSON *fr = cJSON_GetObjectItemCaseSensitive(sh, "frames");
    const char *format = str_at(m, "format");
    if (!m || !format || strcmp(format, "ispm-run") != 0) {
        r = eng_fail(err, ENG_ERR_INVALID, "%s: not an ispm run manifest", path);
        goto out;
    }
    if (!cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(m, "complete"))) {
        r = eng_fail(err, ENG_ERR_INVALID, "%s: the shard is incomplete (\"complete\" is not true)", path);
        goto out;
    }
    if (!cJSON_IsObject(sh)) {
        r = eng_fail(err, ENG_ERR_INVALID, "%s: not a shard (no \"shard\": record it with ispm record --frames A-B)",
                     path);
        goto out;
    }
    if (cJSON_GetArraySize(fr) != 2 || !cJSON_IsNumber(cJSON_GetArrayItem(fr, 0)) ||
        !cJSON_IsNumber(cJSON_GetArrayItem(fr, 1)) || !cap__json_int(sh, "warmup", 0, MAX_FRAME, &s->warmup) ||
        !cap__json_int(sh, "overlap", 0, MAX_FRAME, &s->overlap) ||
        !cap__json_int(sh, "sequence_frame_count", 1, MAX_FRAME, &s->seq_frames)) {
        r = eng_fail(err, ENG_ERR_INVALID, "%s: \"shard\" is not {\"frames\": [A, B], \"warmup\", \"overlap\", "
                     "\"sequence_frame_count\"}", path);
        goto out;
    }
    s->first = (int)cJSON_GetArrayItem(fr, 0)->valuedouble;
    s->last = (int)cJSON_GetArrayItem(fr, 1)->valuedouble;
    s->write_first = s->first - s->overlap;
    if (!(s->overlap <= s->warmup && s->warmup <= s->first && s->first <= s->last && s->last < s->seq_frames)) {
        r = eng_fail(err, ENG_ERR_INVALID, "%s: shard frames %d-%d, warm-up %d, overlap %d do not fit 0..%d", path,
                     s->first, s->last, s->warmup, s->overlap, s->seq_frames - 1);
        goto out;
    }
    s->frames = cJSON_GetObjectItemCaseSensitive(m, "frames");
    int n = s->last - s->write_first + 1;
    if (!cJSON_IsArray(s->frames) || cJSON_GetArraySize(s->frames) != n) {
        r = eng_fail(err, ENG_ERR_INVALID, "%s: \"frames\" does not list the shard's %d frames %d-%d", path, n,
                     s->write_first, s->last);
        goto out;
    }
    int i = 0;
    const cJSON *f;
    cJSON_ArrayForEach(f, s->frames) {
        int g = s->write_first + i++, sf, hf;
        char want[32];
        snprintf(want, sizeof want, "frames/%06d.exr", g);
        const char *file = str_at(f, "file");
        const cJSON *bufs = cJSON_GetObjectItemCaseSensitive(f, "buffers");
        if (!cap__json_int(f, "sequence_frame", 0, MAX_FRAME, &sf) || sf != g || !file || strcmp(file, want) != 0 ||
            !cap__json_int(f, "history_from", -1, MAX_FRAME, &hf) || !cJSON_IsArray(bufs)) {
            r = eng_fail(err, ENG_ERR_INVALID, "%s: frames[%d] is not the record of sequence frame %d (%s)", path,
                         i - 1, g, want);
            goto out;
        }
        const cJSON *b;
        cJSON_ArrayForEach(b, bufs) {
            if (!str_at(b, "name") || !str_at(b, "digest")) {
                r = eng_fail(err, ENG_ERR_INVALID, "%s: frame %d: a buffer without \"name\" and \"digest\"", path, g);
                goto out;
            }
        }
        char *exr = cap__join(dir, want);
        int ok = file_exists(exr);
        free(exr);
        if (!ok) {
            r = eng_fail(err, ENG_ERR_INVALID, "%s/%s: missing (listed in %s)", dir, want, path);
            goto out;
        }
    }
out:
    free(text);
    free(path);
    return r;
}

static const cJSON *shard_frame(const shard *s, int g)
{
    return g >= s->write_first && g <= s->last ? cJSON_GetArrayItem(s->frames, g - s->write_first) : NULL;
}

/* The first dotted key under which a and b differ (a, b equal: 0). */
static int first_diff(const cJSON *a, const cJSON *b, const char *key, char *out, size_t size)
{
    if (cJSON_IsObject(a) && cJSON_IsObject(b)) {
        for (int pass = 0; pass < 2; pass++)
            for (const cJSON *c = (pass ? b : a)->child; c; c = c->next) {
                char sub[256];
                snprintf(sub, sizeof sub, "%s.%s", key, c->string);
                const cJSON *other = cJSON_GetObjectItemCaseSensitive(pass ? a : b, c->string);
                if (pass && other)
                    continue;
                if (first_diff(pass ? other : c, pass ? c : other, sub, out, size))
                    return 1;
            }
        return 0;
    }
    if ((!a && !b) || (a && b && cJSON_Compare(a, b, 1)))
        return 0;
    snprintf(out, size, "%s", key);
    return 1;
}

/* What must be equal for frames of two shards to belong to one run: the sequence, scene and
 * settings, and everything that can change a bit for the same inputs (GL, pinned determinism
 * settings, the binary). Paths and the command line may differ. */
static const char *const SAME[] = {"sequence.name", "sequence.digest", "scene.digest", "resolution", "fps",
                                   "camera", "settings", "determinism", "gl", "tool", NULL};

static const cJSON *at_path(const cJSON *m, const char *dotted)
{
    char key[64];
    const char *dot = strchr(dotted, '.');
    if (!dot)
        return cJSON_GetObjectItemCaseSensitive(m, dotted);
    snprintf(key, sizeof key, "%.*s", (int)(dot - dotted), dotted);
    return cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(m, key), dot + 1);
}

static eng_result same_provenance(const shard *a, const shard *b, eng_error *err)
{
    for (int i = 0; SAME[i]; i++) {
        char where[256];
        if (first_diff(at_path(b->manifest, SAME[i]), at_path(a->manifest, SAME[i]), SAME[i], where, sizeof where))
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s differs from %s's: the shards are not of one sequence, "
                            "scene, settings and binary", b->dir, where, a->dir);
    }
    if (a->seq_frames != b->seq_frames)
        return eng_fail(err, ENG_ERR_INVALID, "%s: a sequence of %d frames, %s's has %d", b->dir, b->seq_frames,
                        a->dir, a->seq_frames);
    return ENG_OK;
}

static const char *buffer_digest(const cJSON *frame, const char *name)
{
    const cJSON *b;
    cJSON_ArrayForEach(b, cJSON_GetObjectItemCaseSensitive(frame, "buffers")) {
        const char *n = str_at(b, "name");
        if (n && strcmp(n, name) == 0)
            return str_at(b, "digest");
    }
    return NULL;
}

/* Shard s (after sorted[0..k-1], which own its overlap frames) wrote the frames before its
 * first as the owners did? */
static eng_result check_overlap(const shard *const *sorted, int k, eng_error *err)
{
    const shard *s = sorted[k];
    if (s->overlap < 1)
        return eng_fail(err, ENG_ERR_INVALID, "%s: no overlap frame (it begins at frame %d): nothing shows that its "
                        "warm-up reproduced the temporal state; record it with --overlap 1 or more", s->dir, s->first);
    const shard *prev = sorted[k - 1];
    for (int g = s->write_first; g < s->first; g++) {
        const shard *owner = NULL;
        for (int j = 0; j < k && !owner; j++)
            if (g >= sorted[j]->first && g <= sorted[j]->last)
                owner = sorted[j];
        const cJSON *mine = shard_frame(s, g), *theirs = owner ? shard_frame(owner, g) : NULL;
        if (!theirs)
            continue; /* coverage is checked before: cannot happen */
        const char *bad = NULL, *d_theirs = NULL, *d_mine = NULL;
        const cJSON *b;
        cJSON_ArrayForEach(b, cJSON_GetObjectItemCaseSensitive(theirs, "buffers")) {
            d_theirs = str_at(b, "digest");
            d_mine = buffer_digest(mine, str_at(b, "name"));
            if (!d_mine || strcmp(d_mine, d_theirs) != 0) {
                bad = str_at(b, "name");
                break;
            }
        }
        if (!bad && cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(mine, "buffers")) !=
                        cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(theirs, "buffers")))
            return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d has other buffers than %s's", s->dir, g, owner->dir);
        if (!bad)
            continue;
        /* How far back the state of the frame before the shard reaches, in the shard that owns it. */
        int from = -1;
        cap__json_int(shard_frame(prev, s->first - 1), "history_from", -1, MAX_FRAME, &from);
        char need[256];
        if (from < 0)
            snprintf(need, sizeof need, "no warm-up changes it: the engine keeps no temporal state at these settings "
                     "(another machine or a nondeterminism)");
        else if (s->first - from <= s->warmup)
            snprintf(need, sizeof need, "its warm-up of %d frames already reached frame %d, where the state of "
                     "frame %d begins: not a warm-up problem", s->warmup, from, s->first - 1);
        else
            snprintf(need, sizeof need, "warm-up %d did not reproduce the temporal state, whose frame %d depends on "
                     "every frame since %d: it needs --warmup %d", s->warmup, s->first - 1, from, s->first - from);
        return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d buffer %s differs from %s's (digest %.8s, there %.8s): %s",
                        s->dir, g, bad, owner->dir, d_mine ? d_mine : "missing", d_theirs ? d_theirs : "-", need);
    }
    return ENG_OK;
}

/* ---------------------------------------------------------------- writing */

/* dst (a fresh name) gets src's content: a hard link, or a copy fsynced. */
static eng_result link_or_copy(const char *src, const char *dst, eng_error *err)
{
    if (link(src, dst) == 0)
        return ENG_OK;
    int in = open(src, O_RDONLY | O_CLOEXEC);
    if (in < 0)
        return eng_fail(err, ENG_ERR_IO, "%s: %s", src, strerror(errno));
    int out = open(dst, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (out < 0) {
        close(in);
        return eng_fail(err, ENG_ERR_IO, "%s: cannot create: %s", dst, strerror(errno));
    }
    eng_result r = ENG_OK;
    char buf[1 << 16];
    for (;;) {
        ssize_t n = read(in, buf, sizeof buf);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            r = eng_fail(err, ENG_ERR_IO, "%s: %s", src, strerror(errno));
            break;
        }
        if (n == 0)
            break;
        for (ssize_t done = 0; done < n && r == ENG_OK;) {
            ssize_t w = write(out, buf + done, (size_t)(n - done));
            if (w < 0 && errno == EINTR)
                continue;
            if (w <= 0)
                r = eng_fail(err, ENG_ERR_IO, "%s: %s", dst, w < 0 ? strerror(errno) : strerror(ENOSPC));
            else
                done += w;
        }
        if (r != ENG_OK)
            break;
    }
    if (r == ENG_OK && fsync(out) != 0)
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot sync: %s", dst, strerror(errno));
    if (close(out) != 0 && r == ENG_OK)
        r = eng_fail(err, ENG_ERR_IO, "%s: %s", dst, strerror(errno));
    close(in);
    return r;
}

static eng_result write_json(const char *dir, const char *name, cJSON *o, eng_error *err)
{
    char *doc = cap__json_text(o);
    eng_result r = cap__write_atomic(dir, name, doc, err);
    free(doc);
    return r;
}

/* Frame g's record in the merged run: the shard's, as a whole run lists it. */
static cJSON *merged_record(const shard *s, int g)
{
    cJSON *o = cap__jok(cJSON_Duplicate(shard_frame(s, g), 1));
    cJSON_ReplaceItemInObjectCaseSensitive(o, "index", cap__jok(cJSON_CreateNumber(g)));
    cJSON_DeleteItemFromObjectCaseSensitive(o, "sequence_frame");
    cJSON_DeleteItemFromObjectCaseSensitive(o, "history_from");
    return o;
}

static cJSON *shards_json(const shard *const *sorted, int count)
{
    cJSON *arr = cap__jok(cJSON_CreateArray());
    for (int k = 0; k < count; k++) {
        const shard *s = sorted[k];
        cJSON *o = cap__jok(cJSON_CreateObject());
        cJSON_AddItemToObject(o, "run", cap__jok(cJSON_CreateString(s->dir)));
        cJSON *fr = cap__jok(cJSON_CreateArray());
        cJSON_AddItemToArray(fr, cap__jok(cJSON_CreateNumber(s->first)));
        cJSON_AddItemToArray(fr, cap__jok(cJSON_CreateNumber(s->last)));
        cJSON_AddItemToObject(o, "frames", fr);
        cJSON_AddItemToObject(o, "warmup", cap__jok(cJSON_CreateNumber(s->warmup)));
        cJSON_AddItemToObject(o, "overlap", cap__jok(cJSON_CreateNumber(s->overlap)));
        const cJSON *cmd = cJSON_GetObjectItemCaseSensitive(s->manifest, "command");
        cJSON_AddItemToObject(o, "command", cap__jok(cmd ? cJSON_Duplicate(cmd, 1) : cJSON_CreateNull()));
        cJSON_AddItemToArray(arr, o);
    }
    return arr;
}

static void replace(cJSON *o, const char *key, cJSON *item)
{
    if (cJSON_GetObjectItemCaseSensitive(o, key))
        cJSON_ReplaceItemInObjectCaseSensitive(o, key, cap__jok(item));
    else
        cJSON_AddItemToObject(o, key, cap__jok(item));
}

/* A buffer a shard stored once within the run ("stored_in": an earlier frame's file) may name
 * one of its overlap frames, whose file the merged run takes from the shard before, where that
 * buffer may itself be stored further back: each reference, frame by frame in order, is made
 * the one the merged frame it names holds (equal digests: the overlap was checked), so that
 * every reference names a file that holds the part. */
static eng_result resolve_stored_in(cJSON *frames, const char *run_dir, eng_error *err)
{
    int g = 0;
    for (cJSON *f = frames->child; f; f = f->next, g++) {
        cJSON *bufs = cJSON_GetObjectItemCaseSensitive(f, "buffers");
        for (cJSON *b = bufs ? bufs->child : NULL; b; b = b->next) {
            cJSON *in = cJSON_GetObjectItemCaseSensitive(b, "stored_in");
            if (!in)
                continue;
            const cJSON *name = cJSON_GetObjectItemCaseSensitive(b, "name");
            int h = -1;
            if (!cJSON_IsString(in) || !cap__parse_frame_rel(in->valuestring, &h) || h >= g || !cJSON_IsString(name))
                return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d: a buffer's \"stored_in\" names no earlier frame",
                                run_dir, g);
            const cJSON *hb = NULL, *hbufs = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(frames, h), "buffers");
            for (const cJSON *x = hbufs ? hbufs->child : NULL; x && !hb; x = x->next) {
                const cJSON *xn = cJSON_GetObjectItemCaseSensitive(x, "name");
                if (cJSON_IsString(xn) && strcmp(xn->valuestring, name->valuestring) == 0)
                    hb = x;
            }
            if (!hb)
                return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d: %s is stored in frame %d, which has no %s", run_dir,
                                g, name->valuestring, h, name->valuestring);
            const cJSON *further = cJSON_GetObjectItemCaseSensitive(hb, "stored_in");
            if (further)
                cJSON_ReplaceItemInObjectCaseSensitive(b, "stored_in", cap__jok(cJSON_Duplicate(further, 1)));
        }
    }
    return ENG_OK;
}

static eng_result write_run(const shard *const *sorted, int count, const cap_merge_desc *d, const char *run_dir,
                            eng_error *err)
{
    const int n = sorted[0]->seq_frames;
    char *frames_dir = cap__join(run_dir, "frames");
    eng_result r = cap__prepare_run(run_dir, frames_dir, d->overwrite, err);

    /* The merged manifest, built first: run.json is taken from it, as capture does. */
    cJSON *m = cap__jok(cJSON_Duplicate(sorted[0]->manifest, 1));
    cJSON_DeleteItemFromObjectCaseSensitive(m, "shard");
    cJSON_DeleteItemFromObjectCaseSensitive(m, "complete");
    cJSON_DeleteItemFromObjectCaseSensitive(m, "frames");
    replace(m, "frame_count", cJSON_CreateNumber(n));
    replace(m, "command", d->command_line ? cJSON_CreateString(d->command_line) : cJSON_CreateNull());
    cJSON_AddItemToObject(m, "shards", shards_json(sorted, count));
    cJSON *frames = cap__jok(cJSON_CreateArray());
    for (int k = 0; k < count; k++)
        for (int g = sorted[k]->first; g <= sorted[k]->last; g++)
            cJSON_AddItemToArray(frames, merged_record(sorted[k], g));
    cJSON_AddItemToObject(m, "frames", frames);
    cJSON_AddItemToObject(m, "complete", cap__jok(cJSON_CreateTrue()));
    if (r == ENG_OK)
        r = resolve_stored_in(frames, run_dir, err);

    if (r == ENG_OK) {
        static const char *const info_keys[] = {"sequence", "scene", "resolution", "fps", "frame_count",
                                                "camera", "settings", "gl", NULL};
        cJSON *info = cap__jok(cJSON_CreateObject());
        cJSON_AddItemToObject(info, "format", cap__jok(cJSON_CreateString("ispm-run-info")));
        cJSON_AddItemToObject(info, "format_version", cap__jok(cJSON_CreateNumber(1)));
        for (int i = 0; info_keys[i]; i++) {
            const cJSON *v = cJSON_GetObjectItemCaseSensitive(m, info_keys[i]);
            cJSON_AddItemToObject(info, info_keys[i], cap__jok(v ? cJSON_Duplicate(v, 1) : cJSON_CreateNull()));
        }
        r = write_json(run_dir, "run.json", info, err);
        cJSON_Delete(info);
    }
    for (int k = 0; r == ENG_OK && k < count; k++)
        for (int g = sorted[k]->first; r == ENG_OK && g <= sorted[k]->last; g++) {
            char name[32], rel[32];
            snprintf(name, sizeof name, "%06d.exr", g);
            snprintf(rel, sizeof rel, "frames/%06d.exr", g);
            char *src = cap__join(sorted[k]->dir, rel);
            char *dst = cap__join(frames_dir, name);
            char *tmp = cap__xmalloc(strlen(dst) + 5);
            sprintf(tmp, "%s.tmp", dst);
            unlink(tmp);
            /* A shard's frame is a regular file inside it: link() would link a symbolic link
             * itself, whatever it points to. */
            r = eng_check_input(src, ENG_IN_NOFOLLOW, UINT64_MAX, NULL, err);
            if (r == ENG_OK)
                r = link_or_copy(src, tmp, err);
            if (r == ENG_OK && rename(tmp, dst) != 0)
                r = eng_fail(err, ENG_ERR_IO, "%s: cannot rename %s into place: %s", dst, tmp, strerror(errno));
            if (r != ENG_OK)
                unlink(tmp);
            free(src);
            free(dst);
            free(tmp);
            if (r == ENG_OK) {
                cJSON *rec = cJSON_GetArrayItem(frames, g);
                snprintf(name, sizeof name, "%06d.json", g);
                r = write_json(frames_dir, name, rec, err);
            }
        }
    if (r == ENG_OK)
        r = cap__fsync_dir(frames_dir, err);
    if (r == ENG_OK)
        r = write_json(run_dir, "manifest.json", m, err);
    cJSON_Delete(m);
    free(frames_dir);
    return r;
}

/* The run folder must not be one of the shards, nor inside one, nor hold one. */
static eng_result check_output(const cap_merge_desc *d, eng_error *err)
{
    char out[PATH_MAX];
    if (!realpath(d->run_dir, out))
        return ENG_OK; /* not there yet: no shard can be it */
    size_t no = strlen(out);
    for (int i = 0; i < d->shard_count; i++) {
        char in[PATH_MAX];
        if (!realpath(d->shards[i], in))
            continue;
        size_t ni = strlen(in);
        size_t k = no < ni ? no : ni;
        if (strncmp(out, in, k) == 0 && (no == ni || (no > ni ? out[ni] : in[no]) == '/'))
            return eng_fail(err, ENG_ERR_INVALID, "%s: the output is the shard %s or overlaps it: refusing to write "
                            "into an input", d->run_dir, d->shards[i]);
    }
    return ENG_OK;
}

/* Writes the merged run. Onto a complete run (--force), the new one is built beside it in
 * <run>.merging and swapped in by rename, so that a failure leaves the old run as it was. */
static eng_result write_merged(const shard *const *sorted, int count, const cap_merge_desc *d, eng_error *err)
{
    char *manifest = cap__join(d->run_dir, "manifest.json");
    struct stat st;
    int complete = lstat(manifest, &st) == 0;
    free(manifest);
    if (!complete)
        return write_run(sorted, count, d, d->run_dir, err);
    if (!d->overwrite)
        return eng_fail(err, ENG_ERR_IO, "%s: already holds a run (use --force)", d->run_dir);
    char *tmp = cap__xmalloc(strlen(d->run_dir) + 16);
    sprintf(tmp, "%s.merging", d->run_dir);
    eng_result r = cap__remove_tree(tmp, err);
    if (r == ENG_OK)
        r = write_run(sorted, count, d, tmp, err);
    if (r == ENG_OK)
        r = cap__swap_run(tmp, d->run_dir, err);
    else
        cap__remove_tree(tmp, NULL);
    free(tmp);
    return r;
}

eng_result cap_merge(const cap_merge_desc *d, eng_error *err)
{
    if (!d || !d->shards || d->shard_count < 1 || !d->run_dir || !d->run_dir[0])
        return eng_fail(err, ENG_ERR_INVALID, "cap_merge: no shards or no run folder given");
    int count = d->shard_count;
    shard *shards = cap__xcalloc((size_t)count, sizeof *shards);
    const shard **sorted = cap__xcalloc((size_t)count, sizeof *sorted);
    const char **names = cap__xcalloc((size_t)count, sizeof *names);
    int *first = cap__xcalloc((size_t)count, sizeof *first), *last = cap__xcalloc((size_t)count, sizeof *last);
    eng_result r = ENG_OK;
    for (int i = 0; r == ENG_OK && i < count; i++)
        r = load_shard(d->shards[i], &shards[i], err);
    for (int i = 1; r == ENG_OK && i < count; i++)
        r = same_provenance(&shards[0], &shards[i], err);
    if (r == ENG_OK) {
        for (int i = 0; i < count; i++) { /* insertion sort by first frame */
            int j = i;
            while (j > 0 && sorted[j - 1]->first > shards[i].first) {
                sorted[j] = sorted[j - 1];
                j--;
            }
            sorted[j] = &shards[i];
        }
        for (int i = 0; i < count; i++) {
            names[i] = sorted[i]->dir;
            first[i] = sorted[i]->first;
            last[i] = sorted[i]->last;
        }
        r = cap_merge_coverage(first, last, names, count, shards[0].seq_frames, err);
    }
    for (int k = 1; r == ENG_OK && k < count; k++)
        r = check_overlap(sorted, k, err);
    if (r == ENG_OK)
        r = check_output(d, err);
    eng_lock lock = {.fd = -1};
    if (r == ENG_OK)
        r = cap__make_parent_dirs(d->run_dir, err);
    if (r == ENG_OK)
        r = eng_lock_take(d->run_dir, "ispm merge", &lock, err);
    if (r == ENG_OK)
        r = cap__recover_run(d->run_dir, err);
    if (r == ENG_OK)
        r = write_merged(sorted, count, d, err);
    eng_lock_drop(&lock);
    for (int i = 0; i < count; i++)
        cJSON_Delete(shards[i].manifest);
    free(shards);
    free(sorted);
    free(names);
    free(first);
    free(last);
    return r;
}
