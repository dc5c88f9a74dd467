/* run.c — the run reader: a run folder's manifest.json, parsed and checked, and its frame
 * files, decoded and checked against it.
 *
 * Replay must never compare a file it cannot trust, so everything a run claims is verified
 * before use: the manifest says the run is complete, lists as many frames as frame_count, in
 * order, each with a file name that stays inside the run folder, and buffers whose sizes are
 * bounded (a lying width × height × channels could otherwise ask for terabytes). A decoded
 * frame must hold exactly the listed parts, with the listed sizes and channel sets, and each
 * part's content digest (eng_buffer_digest over the decoded floats) must equal the manifest's:
 * a mismatch is a corrupt or tampered file. Before a frame file is decoded it must be a regular
 * file inside the run (not a symbolic link), OpenEXR by its magic number and no larger than its
 * buffers can take, and its parts' headers must match the manifest (check_heads): a hostile
 * frame costs its header walk, not its pixels. Keys the reader does not use (tool, settings, gl,
 * ...) are left alone so the capture module can grow the manifest. rep_run owns every string
 * it holds and is freed whole by rep_run_close.
 */
#define _POSIX_C_SOURCE 200809L

#include "oiio_shim.h"
#include "rep_run.h"
#include "rep_util.h"
#include "run_internal.h"

#include <cjson/cJSON.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_DIM 65536

/* Reads an integral number in [lo, hi] from obj[key]. */
static eng_result get_int(const char *file, const char *where, const cJSON *obj, const char *key,
                          double lo, double hi, int64_t *out, eng_error *err)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!v)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: missing \"%s\"", file, where, key);
    double d = v->valuedouble;
    if (!cJSON_IsNumber(v) || !isfinite(d) || d != floor(d) || d < lo || d > hi)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"%s\" must be an integer in [%.0f, %.0f]", file,
                        where, key, lo, hi);
    *out = (int64_t)d;
    return ENG_OK;
}

static const char *get_string(const cJSON *obj, const char *key)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    return cJSON_IsString(v) && v->valuestring ? v->valuestring : NULL;
}

static int is_digest(const char *s)
{
    if (strlen(s) != 32)
        return 0;
    for (; *s; s++)
        if (!((*s >= '0' && *s <= '9') || (*s >= 'a' && *s <= 'f')))
            return 0;
    return 1;
}

/* A frame file must name something inside the run folder. */
static int is_safe_relative(const char *f)
{
    if (!f[0] || f[0] == '/' || strchr(f, '\\'))
        return 0;
    for (const char *p = f; *p;) {
        const char *e = strchr(p, '/');
        size_t n = e ? (size_t)(e - p) : strlen(p);
        if (n == 0 || (n == 1 && p[0] == '.') || (n == 2 && p[0] == '.' && p[1] == '.'))
            return 0;
        p += n + (e ? 1 : 0);
        if (e && !*p)
            return 0;
    }
    return 1;
}

static void free_buffer(rep_buffer_info *b)
{
    free(b->name);
    for (int c = 0; c < ENG_MAX_CHANNELS; c++)
        free(b->channels[c]);
}

static void free_frame(rep_frame_info *f)
{
    for (int j = 0; j < f->buffer_count; j++)
        free_buffer(&f->buffers[j]);
    free(f->buffers);
    free(f->file);
    free(f->display_warning);
    free(f->path);
}

void rep_run_close(rep_run *run)
{
    if (!run)
        return;
    for (int i = 0; i < run->frame_count; i++)
        free_frame(&run->frames[i]);
    free(run->frames);
    free(run->sequence_name);
    free(run->gl_renderer);
    free(run->gl_vendor);
    free(run->objects_dir);
    rep_object_cache_free(run->object_cache);
    free(run->manifest_path);
    free(run->dir);
    free(run);
}

int rep_frame_find(const rep_frame_info *f, const char *name)
{
    for (int j = 0; j < f->buffer_count; j++)
        if (strcmp(f->buffers[j].name, name) == 0)
            return j;
    return -1;
}

static eng_result parse_buffer(const char *mf, const char *where, const cJSON *jb, rep_buffer_info *b,
                               eng_error *err)
{
    if (!cJSON_IsObject(jb))
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: not an object", mf, where);
    const char *name = get_string(jb, "name");
    if (!name || !name[0])
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"name\" must be a non-empty string", mf, where);
    b->name = rep_xstrdup(name);
    int64_t w, h;
    eng_result r;
    if ((r = get_int(mf, where, jb, "width", 1, MAX_DIM, &w, err)) != ENG_OK ||
        (r = get_int(mf, where, jb, "height", 1, MAX_DIM, &h, err)) != ENG_OK)
        return r;
    b->width = (int)w;
    b->height = (int)h;
    const cJSON *ch = cJSON_GetObjectItemCaseSensitive(jb, "channels");
    int n = cJSON_IsArray(ch) ? cJSON_GetArraySize(ch) : 0;
    if (n < 1 || n > ENG_MAX_CHANNELS)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s (%s): \"channels\" must list 1 to %d names", mf, where,
                        name, ENG_MAX_CHANNELS);
    for (int c = 0; c < n; c++) {
        const cJSON *cn = cJSON_GetArrayItem(ch, c);
        if (!cJSON_IsString(cn) || !cn->valuestring[0])
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s (%s): channel %d is not a non-empty string", mf,
                            where, name, c);
        for (int k = 0; k < c; k++)
            if (strcmp(b->channels[k], cn->valuestring) == 0)
                return eng_fail(err, ENG_ERR_INVALID, "%s: %s (%s): channel \"%s\" listed twice", mf, where,
                                name, cn->valuestring);
        b->channels[c] = rep_xstrdup(cn->valuestring);
        b->channel_count = c + 1;
    }
    if ((size_t)w * (size_t)h * (size_t)n > REP_MAX_FLOATS)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s (%s): %lldx%lldx%d floats, more than the %zu allowed", mf,
                        where, name, (long long)w, (long long)h, n, REP_MAX_FLOATS);
    const char *dg = get_string(jb, "digest");
    if (!dg || !is_digest(dg))
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s (%s): \"digest\" must be 32 lowercase hex digits", mf,
                        where, name);
    memcpy(b->digest, dg, 33);
    if (cJSON_GetObjectItemCaseSensitive(jb, "nan") || cJSON_GetObjectItemCaseSensitive(jb, "inf")) {
        int64_t nn, ni;
        double cap = (double)w * (double)h * (double)n;
        if ((r = get_int(mf, where, jb, "nan", 0, cap, &nn, err)) != ENG_OK ||
            (r = get_int(mf, where, jb, "inf", 0, cap, &ni, err)) != ENG_OK)
            return r;
        b->nan = (uint64_t)nn;
        b->inf = (uint64_t)ni;
        b->has_nonfinite_counts = 1;
    }
    return ENG_OK;
}

/* Buffer b of frame i: "stored_in" (absent: its frame's own file) must name the file of an
 * earlier frame k whose same-name buffer is in k's own file with b's digest, size and channels. */
static eng_result parse_stored_in(rep_run *run, const char *mf, const char *where, int i, const cJSON *jb,
                                  rep_buffer_info *b, eng_error *err)
{
    const cJSON *in = cJSON_GetObjectItemCaseSensitive(jb, "stored_in");
    b->stored_in = -1;
    if (!in)
        return ENG_OK;
    if (!cJSON_IsString(in) || !in->valuestring)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s (%s): \"stored_in\" must be an earlier frame's \"file\"", mf,
                        where, b->name);
    int k = -1;
    for (int q = 0; q < run->frame_count && k < 0; q++)
        if (run->frames[q].file && strcmp(run->frames[q].file, in->valuestring) == 0)
            k = q;
    /* Frames after i are not parsed yet: a name of capture's form tells a forward reference. */
    int later = 0, len = 0;
    if (k < 0 && sscanf(in->valuestring, "frames/%d.exr%n", &later, &len) == 1 && len == (int)strlen(in->valuestring) &&
        later > i && later < run->planned_frames)
        k = later;
    if (k < 0 || k >= i)
        return eng_fail(err, ENG_ERR_INVALID,
                        "%s: %s (%s): \"stored_in\" %s is not the file of an earlier frame (a reference %s)", mf,
                        where, b->name, in->valuestring,
                        k == i ? "to its own frame" : k > i ? "forward in time" : "to no frame of the run");
    const rep_frame_info *src = &run->frames[k];
    int j = rep_frame_find(src, b->name);
    if (j < 0)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s (%s): \"stored_in\" %s, whose frame lists no buffer %s", mf,
                        where, b->name, in->valuestring, b->name);
    const rep_buffer_info *o = &src->buffers[j];
    if (o->stored_in >= 0)
        return eng_fail(err, ENG_ERR_INVALID,
                        "%s: %s (%s): \"stored_in\" %s, which stores %s elsewhere itself (a chain of references)", mf,
                        where, b->name, in->valuestring, b->name);
    int same = strcmp(o->digest, b->digest) == 0 && o->width == b->width && o->height == b->height &&
               o->channel_count == b->channel_count;
    for (int c = 0; same && c < b->channel_count; c++)
        same = strcmp(o->channels[c], b->channels[c]) == 0;
    if (!same)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s (%s): \"stored_in\" %s, whose %s differs (digest, size or channels)",
                        mf, where, b->name, in->valuestring, b->name);
    b->stored_in = k;
    return ENG_OK;
}

/* Frame i of run from its manifest record jf; mf is the file the record came from (messages). */
static eng_result parse_frame(rep_run *run, const char *mf, int i, const cJSON *jf, eng_error *err)
{
    rep_frame_info *f = &run->frames[i];
    char where[96];
    snprintf(where, sizeof where, "frames[%d]", i);
    if (!cJSON_IsObject(jf))
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: not an object", mf, where);
    int64_t idx;
    eng_result r = get_int(mf, where, jf, "index", 0, 1e9, &idx, err);
    if (r != ENG_OK)
        return r;
    if (idx != i)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"index\" is %lld, expected %d (frames out of order)",
                        mf, where, (long long)idx, i);
    f->index = i;
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(jf, "time");
    if (t && (!cJSON_IsNumber(t) || !isfinite(t->valuedouble)))
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"time\" must be a finite number", mf, where);
    f->time = t ? t->valuedouble : 0.0;
    const char *file = get_string(jf, "file");
    if (run->format_version == 2) {
        if (cJSON_GetObjectItemCaseSensitive(jf, "file"))
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: a frame of format 2 lists objects, not a \"file\"", mf,
                            where);
    } else if (!file || !is_safe_relative(file)) {
        return eng_fail(err, ENG_ERR_INVALID,
                        "%s: %s: \"file\" must be a relative path inside the run folder", mf, where);
    } else {
        f->file = rep_xstrdup(file);
        f->path = rep_path_join(run->dir, file);
    }
    const cJSON *cam = cJSON_GetObjectItemCaseSensitive(jf, "camera");
    if (cam) {
        const cJSON *vp = cJSON_GetObjectItemCaseSensitive(cam, "view_proj");
        const cJSON *eye = cJSON_GetObjectItemCaseSensitive(cam, "eye");
        if (!cJSON_IsArray(vp) || cJSON_GetArraySize(vp) != 16 || !cJSON_IsArray(eye) || cJSON_GetArraySize(eye) != 3)
            return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"camera\" must be {\"view_proj\": [16 numbers], \"eye\": [3]}",
                            mf, where);
        for (int k = 0; k < 19; k++) {
            const cJSON *v = k < 16 ? cJSON_GetArrayItem(vp, k) : cJSON_GetArrayItem(eye, k - 16);
            if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble) || fabs(v->valuedouble) > 3.0e38)
                return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"camera\" holds a value that is not a finite float",
                                mf, where);
            if (k < 16)
                f->view_proj[k] = (float)v->valuedouble;
            else
                f->eye[k - 16] = (float)v->valuedouble;
        }
        f->has_camera = 1;
    }
    const cJSON *dw = cJSON_GetObjectItemCaseSensitive(jf, "display_warning");
    if (dw && !cJSON_IsString(dw))
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"display_warning\" must be a string", mf, where);
    if (dw)
        f->display_warning = rep_xstrdup(dw->valuestring);
    const cJSON *jbs = cJSON_GetObjectItemCaseSensitive(jf, "buffers");
    if (!cJSON_IsArray(jbs))
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: \"buffers\" must be an array", mf, where);
    int n = cJSON_GetArraySize(jbs);
    if (n < 1 || n > REP_MAX_PARTS)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: %d buffers, expected 1 to %d", mf, where, n,
                        REP_MAX_PARTS);
    f->buffers = rep_xcalloc((size_t)n, sizeof *f->buffers);
    for (int j = 0; j < n; j++) {
        char bw[128];
        snprintf(bw, sizeof bw, "%s.buffers[%d]", where, j);
        f->buffer_count = j + 1;
        if ((r = parse_buffer(mf, bw, cJSON_GetArrayItem(jbs, j), &f->buffers[j], err)) != ENG_OK)
            return r;
        for (int k = 0; k < j; k++)
            if (strcmp(f->buffers[k].name, f->buffers[j].name) == 0)
                return eng_fail(err, ENG_ERR_INVALID, "%s: %s: buffer \"%s\" listed twice", mf, where,
                                f->buffers[j].name);
    }
    for (int j = 0; j < n; j++)
        f->buffers[j].stored_in = -1;
    if (run->format_version == 2) {
        /* Every buffer is its object: a "stored_in" the run had says nothing here. */
        for (int j = 0; j < n; j++)
            if ((r = rep_object_check(run->objects_dir, f->buffers[j].digest, mf, err)) != ENG_OK)
                return r;
        return ENG_OK;
    }
    int own = 0;
    for (int j = 0; j < n; j++) {
        char bw[128];
        snprintf(bw, sizeof bw, "%s.buffers[%d]", where, j);
        if ((r = parse_stored_in(run, mf, bw, i, cJSON_GetArrayItem(jbs, j), &f->buffers[j], err)) != ENG_OK)
            return r;
        own += f->buffers[j].stored_in < 0;
    }
    if (own == 0)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s: every buffer is stored in an earlier frame's file, none in %s",
                        mf, where, f->file);
    if (!rep_is_file(f->path))
        return eng_fail(err, ENG_ERR_IO, "%s: frame %d's file is missing (listed in %s)", f->path, i, mf);
    return ENG_OK;
}

/* What a manifest and run.json share: resolution, sequence name, GL renderer (all optional). */
static eng_result parse_head(rep_run *run, const char *mf, const cJSON *root, eng_error *err)
{
    const cJSON *res = cJSON_GetObjectItemCaseSensitive(root, "resolution");
    if (res) {
        const cJSON *w = cJSON_GetArrayItem(res, 0), *h = cJSON_GetArrayItem(res, 1);
        if (!cJSON_IsArray(res) || cJSON_GetArraySize(res) != 2 || !cJSON_IsNumber(w) || !cJSON_IsNumber(h) ||
            w->valuedouble < 1 || w->valuedouble > MAX_DIM || h->valuedouble < 1 || h->valuedouble > MAX_DIM)
            return eng_fail(err, ENG_ERR_INVALID, "%s: \"resolution\" must be [width, height]", mf);
        run->width = (int)w->valuedouble;
        run->height = (int)h->valuedouble;
    }
    const cJSON *seq = cJSON_GetObjectItemCaseSensitive(root, "sequence");
    const char *sname = cJSON_IsObject(seq) ? get_string(seq, "name") : NULL;
    if (sname)
        run->sequence_name = rep_xstrdup(sname);
    const cJSON *gl = cJSON_GetObjectItemCaseSensitive(root, "gl");
    const char *renderer = cJSON_IsObject(gl) ? get_string(gl, "renderer") : NULL;
    if (renderer)
        run->gl_renderer = rep_xstrdup(renderer);
    const char *vendor = cJSON_IsObject(gl) ? get_string(gl, "vendor") : NULL;
    if (vendor)
        run->gl_vendor = rep_xstrdup(vendor);
    return ENG_OK;
}

static eng_result parse_manifest(rep_run *run, const cJSON *root, eng_error *err)
{
    const char *mf = run->manifest_path;
    if (!cJSON_IsObject(root))
        return eng_fail(err, ENG_ERR_INVALID, "%s: not a JSON object", mf);
    const char *format = get_string(root, "format");
    if (!format || strcmp(format, "ispm-run") != 0)
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"format\" is not \"ispm-run\"", mf);
    int64_t version;
    eng_result r = get_int(mf, "top level", root, "format_version", 0, 1e9, &version, err);
    if (r != ENG_OK)
        return r;
    if (version != 1 && version != 2)
        return eng_fail(err, ENG_ERR_UNSUPPORTED, "%s: format_version %lld, this replay reads 1 and 2", mf,
                        (long long)version);
    run->format_version = (int)version;
    if (version == 2) {
        const char *objects = get_string(root, "objects");
        if (!objects)
            return eng_fail(err, ENG_ERR_INVALID, "%s: format_version 2 without \"objects\" (the object store)", mf);
        if ((r = rep_objects_resolve(run->dir, mf, objects, &run->objects_dir, err)) != ENG_OK)
            return r;
        run->object_cache = rep_object_cache_create();
    }
    if (!cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(root, "complete")))
        return eng_fail(err, ENG_ERR_INVALID, "%s: run is incomplete (\"complete\" is not true)", mf);
    if ((r = parse_head(run, mf, root, err)) != ENG_OK)
        return r;
    run->complete = 1;
    int64_t fc;
    if ((r = get_int(mf, "top level", root, "frame_count", 1, 1e7, &fc, err)) != ENG_OK)
        return r;
    const cJSON *frames = cJSON_GetObjectItemCaseSensitive(root, "frames");
    if (!cJSON_IsArray(frames))
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"frames\" must be an array", mf);
    int n = cJSON_GetArraySize(frames);
    if (n != fc)
        return eng_fail(err, ENG_ERR_INVALID, "%s: frame_count is %lld but %d frames are listed", mf,
                        (long long)fc, n);
    run->planned_frames = n;
    run->frames = rep_xcalloc((size_t)n, sizeof *run->frames);
    const cJSON *jf = frames->child;
    for (int i = 0; i < n; i++, jf = jf->next) {
        run->frame_count = i + 1;
        if ((r = parse_frame(run, mf, i, jf, err)) != ENG_OK)
            return r;
    }
    return ENG_OK;
}

eng_result rep_run_open(const char *dir, rep_run **out, eng_error *err)
{
    *out = NULL;
    if (!rep_is_dir(dir)) {
        /* A bless that ended between its two renames leaves the golden at <dir>.old; a record or
         * merge --force, the run at <dir>.replaced. */
        char *old = rep_xprintf("%s.old", dir), *replaced = rep_xprintf("%s.replaced", dir);
        int bless = rep_is_dir(old), swap = rep_is_dir(replaced);
        free(old);
        free(replaced);
        if (bless)
            return eng_fail(err, ENG_ERR_IO, "%s: missing, an interrupted bless left %s.old (ispm bless puts it back)",
                            dir, dir);
        if (swap)
            return eng_fail(err, ENG_ERR_IO,
                            "%s: missing, an interrupted record or merge --force left %s.replaced (either puts it back)",
                            dir, dir);
        return eng_fail(err, ENG_ERR_IO, "%s: run folder does not exist", dir);
    }
    rep_run *run = rep_xcalloc(1, sizeof *run);
    run->dir = rep_xstrdup(dir);
    run->manifest_path = rep_path_join(dir, "manifest.json");
    cJSON *root = NULL;
    struct stat st;
    if (lstat(run->manifest_path, &st) != 0) {
        eng_result r = eng_fail(err, ENG_ERR_IO, "%s: missing: the run is incomplete or not a run", run->manifest_path);
        rep_run_close(run);
        return r;
    }
    eng_result r = rep_json_load(run->manifest_path, ENG_IN_NOFOLLOW, &root, err);
    if (r == ENG_OK)
        r = parse_manifest(run, root, err);
    cJSON_Delete(root);
    if (r != ENG_OK) {
        rep_run_close(run);
        return r;
    }
    *out = run;
    return ENG_OK;
}

typedef struct frame_check {
    const rep_run *run;
    const rep_frame_info *f;
} frame_check;

/* The parts' headers against the manifest (rep_parts_check): the same count, every name listed
 * once, each part's size and channels the manifest's. */
static eng_result check_heads(void *user, const char *path, const rep_part *heads, int count, eng_error *err)
{
    const frame_check *fc = user;
    const rep_frame_info *f = fc->f;
    int own = 0;
    for (int j = 0; j < f->buffer_count; j++)
        own += f->buffers[j].stored_in < 0;
    if (count != own)
        return eng_fail(err, ENG_ERR_INVALID, "%s: holds %d parts, %s lists %d in it", path, count,
                        fc->run->manifest_path, own);
    eng_result r = ENG_OK;
    int *seen = rep_xcalloc((size_t)f->buffer_count, sizeof *seen);
    for (int k = 0; k < count && r == ENG_OK; k++) {
        int j = rep_frame_find(f, heads[k].name);
        if (j < 0 || f->buffers[j].stored_in >= 0)
            r = eng_fail(err, ENG_ERR_INVALID, "%s: part %s is not listed in %s%s", path, heads[k].name,
                         fc->run->manifest_path, j < 0 ? "" : " as stored in this file");
        else if (seen[j]++)
            r = eng_fail(err, ENG_ERR_INVALID, "%s: part %s appears twice", path, heads[k].name);
        else if (heads[k].width != f->buffers[j].width || heads[k].height != f->buffers[j].height)
            r = eng_fail(err, ENG_ERR_INVALID, "%s: part %s: %dx%d in the file, %dx%d in the manifest", path,
                         heads[k].name, heads[k].width, heads[k].height, f->buffers[j].width, f->buffers[j].height);
        else if (!rep_run_same_channels(&heads[k], &f->buffers[j]))
            r = eng_fail(err, ENG_ERR_INVALID, "%s: part %s: channels differ from the manifest's", path,
                         heads[k].name);
    }
    free(seen);
    return r;
}

/* The frame file before any library reads it: a regular file inside the run (not a link), an
 * OpenEXR file by its magic number, no larger than its buffers uncompressed with a generous
 * allowance for headers and chunk tables. *largest gets the floats of its largest buffer. */
static eng_result check_frame_file(const rep_frame_info *f, size_t *largest, eng_error *err)
{
    uint64_t bound = 1 << 20;
    *largest = 1;
    for (int j = 0; j < f->buffer_count; j++) {
        const rep_buffer_info *b = &f->buffers[j];
        uint64_t floats = (uint64_t)b->width * (uint64_t)b->height * (uint64_t)b->channel_count;
        bound += floats * 4 + (uint64_t)b->height * 16 + 65536;
        if (floats > *largest)
            *largest = (size_t)floats;
    }
    int fd;
    eng_result r = eng_open_input(f->path, ENG_IN_NOFOLLOW, bound, &fd, NULL, err);
    if (r != ENG_OK)
        return r;
    unsigned char magic[4] = {0};
    ssize_t got = read(fd, magic, sizeof magic);
    close(fd);
    if (got != 4 || magic[0] != 0x76 || magic[1] != 0x2f || magic[2] != 0x31 || magic[3] != 0x01)
        return eng_fail(err, ENG_ERR_INVALID, "%s: not an OpenEXR file (no EXR magic number)", f->path);
    return ENG_OK;
}

/* The buffers of f that earlier frames' files hold (stored_in), each file read once for the
 * parts it holds for f, verified as f's own parts are, into sorted[]; taken[] marks them. */
static eng_result read_stored_elsewhere(const rep_run *run, const rep_frame_info *f, rep_part *sorted, int *taken,
                                        eng_error *err)
{
    eng_result r = ENG_OK;
    const char **names = rep_xcalloc((size_t)f->buffer_count, sizeof *names);
    for (int j = 0; j < f->buffer_count && r == ENG_OK; j++) {
        int k = f->buffers[j].stored_in;
        if (k < 0 || taken[j])
            continue;
        const rep_frame_info *src = &run->frames[k];
        int n = 0;
        for (int q = j; q < f->buffer_count; q++)
            if (f->buffers[q].stored_in == k)
                names[n++] = f->buffers[q].name;
        size_t largest;
        r = check_frame_file(src, &largest, err);
        rep_part *parts = NULL;
        int count = 0;
        if (r == ENG_OK)
            r = rep_read_parts_only(src->path, largest < REP_MAX_FLOATS ? largest : REP_MAX_FLOATS, names, n, &parts,
                                    &count, err);
        for (int p = 0; p < count && r == ENG_OK; p++) {
            int q = rep_frame_find(f, parts[p].name);
            if (q < 0 || f->buffers[q].stored_in != k || taken[q])
                r = eng_fail(err, ENG_ERR_INVALID, "%s: part %s appears twice", src->path, parts[p].name);
            else if ((r = rep_run_verify_part(src->path, &parts[p], &f->buffers[q], err)) == ENG_OK) {
                taken[q] = 1;
                sorted[q] = parts[p];
                memset(&parts[p], 0, sizeof parts[p]);
            }
        }
        rep_parts_free(parts, count);
        for (int q = j; q < f->buffer_count && r == ENG_OK; q++)
            if (f->buffers[q].stored_in == k && !taken[q])
                r = eng_fail(err, ENG_ERR_INVALID, "%s: part %s, which %s stores in it for frame %d, is missing",
                             src->path, f->buffers[q].name, run->manifest_path, f->index);
    }
    free(names);
    return r;
}

eng_result rep_run_read_frame(const rep_run *run, int frame, rep_part **out, eng_error *err)
{
    *out = NULL;
    if (run->format_version == 2)
        return rep_objects_read_frame(run, frame, out, err);
    const rep_frame_info *f = &run->frames[frame];
    rep_part *parts = NULL;
    int count = 0;
    size_t largest;
    eng_result r = check_frame_file(f, &largest, err);
    if (r != ENG_OK)
        return r;
    frame_check fc = {run, f};
    r = rep_read_parts_checked(f->path, largest < REP_MAX_FLOATS ? largest : REP_MAX_FLOATS, check_heads, &fc,
                               &parts, &count, err);
    if (r != ENG_OK)
        return r;
    rep_part *sorted = rep_xcalloc((size_t)f->buffer_count, sizeof *sorted);
    int *taken = rep_xcalloc((size_t)f->buffer_count, sizeof *taken);
    for (int k = 0; k < count && r == ENG_OK; k++) {
        int j = rep_frame_find(f, parts[k].name);
        if (j < 0 || f->buffers[j].stored_in >= 0)
            r = eng_fail(err, ENG_ERR_INVALID, "%s: part %s is not listed in %s", f->path, parts[k].name,
                         run->manifest_path);
        else if (taken[j])
            r = eng_fail(err, ENG_ERR_INVALID, "%s: part %s appears twice", f->path, parts[k].name);
        else if ((r = rep_run_verify_part(f->path, &parts[k], &f->buffers[j], err)) == ENG_OK) {
            taken[j] = 1;
            sorted[j] = parts[k];
            memset(&parts[k], 0, sizeof parts[k]);
        }
    }
    for (int j = 0; j < f->buffer_count && r == ENG_OK; j++)
        if (!taken[j] && f->buffers[j].stored_in < 0)
            r = eng_fail(err, ENG_ERR_INVALID, "%s: part %s, listed in %s, is missing", f->path,
                         f->buffers[j].name, run->manifest_path);
    rep_parts_free(parts, count);
    if (r == ENG_OK)
        r = read_stored_elsewhere(run, f, sorted, taken, err);
    free(taken);
    if (r != ENG_OK) {
        rep_parts_free(sorted, f->buffer_count);
        return r;
    }
    *out = sorted;
    return ENG_OK;
}

/* ---------------------------------------------------------------- runs still being recorded */

static eng_result load_json(const char *path, cJSON **root, eng_error *err)
{
    return rep_json_load(path, ENG_IN_NOFOLLOW, root, err);
}

/* Adds the frames from run->frame_count on whose EXR and record both exist. */
static eng_result scan_records(rep_run *run, int *added, eng_error *err)
{
    eng_result r = ENG_OK;
    *added = 0;
    for (int i = run->frame_count; r == ENG_OK; i++) {
        char rel[40];
        snprintf(rel, sizeof rel, "frames/%06d.json", i);
        char *rec = rep_path_join(run->dir, rel);
        snprintf(rel, sizeof rel, "frames/%06d.exr", i);
        char *exr = rep_path_join(run->dir, rel);
        int both = rep_is_file(rec) && rep_is_file(exr);
        cJSON *jf = NULL;
        if (both)
            r = load_json(rec, &jf, err);
        if (both && r == ENG_OK) {
            run->frames = rep_xrealloc(run->frames, (size_t)(i + 1) * sizeof *run->frames);
            memset(&run->frames[i], 0, sizeof run->frames[i]);
            run->frame_count = i + 1;
            r = parse_frame(run, rec, i, jf, err);
            if (r == ENG_OK) {
                ++*added;
            } else { /* the run stays as it was: frames before i */
                free_frame(&run->frames[i]);
                run->frame_count = i;
            }
        }
        cJSON_Delete(jf);
        free(rec);
        free(exr);
        if (!both)
            break;
    }
    return r;
}

eng_result rep_run_open_live(const char *dir, rep_run **out, eng_error *err)
{
    *out = NULL;
    char *mf = rep_path_join(dir, "manifest.json"), *info = rep_path_join(dir, "run.json");
    int live = !rep_is_file(mf) && rep_is_file(info);
    free(mf);
    if (!live) {
        free(info);
        eng_result r = rep_run_open(dir, out, err);
        if (r == ENG_OK)
            (*out)->planned_frames = (*out)->frame_count;
        return r;
    }
    rep_run *run = rep_xcalloc(1, sizeof *run);
    run->dir = rep_xstrdup(dir);
    run->manifest_path = rep_path_join(dir, "manifest.json");
    cJSON *root = NULL;
    eng_result r = load_json(info, &root, err);
    if (r == ENG_OK && !cJSON_IsObject(root))
        r = eng_fail(err, ENG_ERR_INVALID, "%s: not a JSON object", info);
    if (r == ENG_OK)
        r = parse_head(run, info, root, err);
    if (r == ENG_OK) {
        const cJSON *fc = cJSON_GetObjectItemCaseSensitive(root, "frame_count");
        if (cJSON_IsNumber(fc) && fc->valuedouble >= 1 && fc->valuedouble <= 1e7)
            run->planned_frames = (int)fc->valuedouble;
    }
    cJSON_Delete(root);
    free(info);
    int added;
    if (r == ENG_OK)
        r = scan_records(run, &added, err);
    if (r != ENG_OK) {
        rep_run_close(run);
        return r;
    }
    *out = run;
    return ENG_OK;
}

eng_result rep_run_refresh(rep_run *run, int *added, eng_error *err)
{
    *added = 0;
    if (run->complete)
        return ENG_OK;
    if (rep_is_file(run->manifest_path)) {
        rep_run *full = NULL;
        eng_result r = rep_run_open(run->dir, &full, err);
        if (r != ENG_OK)
            return r;
        int have = run->frame_count < full->frame_count ? run->frame_count : full->frame_count;
        /* the records already listed are the manifest's own (capture writes both from one frame) */
        run->frames = rep_xrealloc(run->frames, (size_t)full->frame_count * sizeof *run->frames);
        memcpy(run->frames + have, full->frames + have, (size_t)(full->frame_count - have) * sizeof *run->frames);
        *added = full->frame_count - have;
        run->frame_count = full->frame_count;
        run->planned_frames = full->frame_count;
        run->complete = 1;
        full->frame_count = have; /* the moved frames are run's now */
        rep_run_close(full);
        return ENG_OK;
    }
    return scan_records(run, added, err);
}
