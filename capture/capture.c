/* capture.c — the listener that records a run (DESIGN.md, "Run layout"): announced buffers
 * become parts of frames/NNNNNN.exr, and manifest.json, written last, says what the run is
 * (tool, sequence, scene, settings, pinned determinism settings) and, per frame, the time,
 * per-pass milliseconds and per-buffer digest and non-finite counts.
 *
 * Ordering is the whole point. Each file appears by rename of a fsynced temp file, so no
 * reader sees half a frame; the manifest is the last thing written, after the frames'
 * directory entries are fsynced, so a manifest always describes frames that exist; and when
 * an old run is overwritten its manifest is unlinked (durably) before anything else, so a
 * crash cannot leave an old manifest beside new frames; then its run.json, and its frames/ is
 * renamed aside and removed by a thread while the new run renders (set_aside_frames).
 *
 * Buffers are deep-copied when announced, because the engine may reuse its memory as soon as
 * the callback returns, and held until frame_end writes them as one file; digests
 * (eng_buffer_digest, the one replay recomputes) and non-finite counts are taken from the
 * copies. After a frame is written only its small record stays in memory.
 *
 * Resuming (ispm record --resume). cap_create writes run.json, what the run is of, before
 * any frame; each frame's manifest record is also written beside its EXR as frames/NNNNNN.json,
 * after the EXR's rename. So after a kill at any moment the folder holds no manifest (replay
 * refuses it) and every frame either has both files (captured: its record is read back, the
 * frame is not rendered again) or not (rendered again). The engine renders each frame from
 * scratch, so the resumed run's manifest equals an uninterrupted one's up to the command line
 * and the timings of the frames rendered after the restart.
 *
 * The capture owns every string it was given (copied); the sequence and scene are borrowed. */
#define _POSIX_C_SOURCE 200809L

#include "cap_internal.h"
#include "workq.h"

#include <cjson/cJSON.h>

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <fnmatch.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define MANIFEST_NAME "manifest.json"
#define MANIFEST_TMP_NAME "manifest.json.tmp"
#define RUNINFO_NAME "run.json"
#define RUNINFO_TMP_NAME "run.json.tmp"
/* The keys of the manifest that run.json repeats and --resume compares. */
static const char *const runinfo_keys[] = {"sequence", "scene", "resolution", "fps", "frame_count",
                                           "camera", "settings", "gl", "shard", NULL};
/* Keys of runinfo_keys a run may lack (then absent from run.json, not null). */
static int runinfo_optional(const char *key)
{
    return strcmp(key, "shard") == 0;
}

typedef struct cap_frame {
    int done;
    double time;
    int pass_count;
    eng_pass_time passes[ENG_MAX_PASSES];
    int buffer_count;
    cap_bufrec *buffers;
    /* The eye camera (world → clip) and photon attrition of the frame, from eng_frame_stats. */
    float view_proj[16];
    float eye[3];
    uint64_t photons_emitted;
    uint64_t photons_stored[ENG_PHOTON_BOUNCES];
    uint64_t photons_truncated;
    /* The image-space photon trace's centres and counts (trace_maps = 0: Embree trace). */
    int trace_maps;
    float trace_centres[ENG_MAX_TRACE_MAPS][3];
    eng_trace_counts trace;
    int history_from; /* eng_frame_stats.history_from (recorded in shards only) */
    /* The lights' shadow views (eng_frame_stats.lights), for ispm lineage. */
    int light_count;
    eng_light_record lights[ENG_MAX_LIGHT_RECORDS];
    char display_warning[CAP_DISPLAY_WARNING_MAX]; /* cap_display_warning's line, or "" */
    int exposure_auto; /* eng_frame_stats: the display's stops came from "exposure": "auto" */
    float exposure;
} cap_frame;

/* A buffer of the frame in progress: its record and its pixel copy. */
typedef struct cap_pending {
    cap_bufrec rec;
    float *data;
} cap_pending;

struct cap_capture {
    eng_lock run_lock; /* <run>.lock while the capture lives: one writer per run */
    char *final_dir;   /* build_aside: the run that run_dir replaces at cap_finish, else NULL */
    int swapped;       /* ... and has replaced */
    char *run_dir, *frames_dir;
    const seq_sequence *seq;
    const scn_scene *scene;
    char *gl_version, *gl_renderer, *gl_backend, *gl_where, *tool_version, *git_revision, *command_line;
    char *renderer;            /* NULL: the engine */
    cJSON *renderer_settings;  /* a JSON object, or NULL */
    int det_count;  /* pairs */
    char **det;     /* 2*det_count strings; a value may be NULL */
    int frame_count;
    cap_frame *frames;
    int shard;           /* a frame shard (cap_desc.shard) */
    cap_shard shard_info;
    int write_first, write_last; /* frames this run holds: 0..frame_count-1, or a shard's */
    int cur_frame;  /* -1 outside frame_begin .. frame_end */
    double cur_time;
    char cur_display_warning[CAP_DISPLAY_WARNING_MAX]; /* of the frame in progress */
    int pending_count, pending_cap;
    cap_pending *pending;
    cap_compression compression;
    int dedupe;        /* not capture_whole_frames: a buffer equal to the previous frame's is stored once */
    cap_wq *wq;        /* the writers, or NULL: frames are written in on_frame_end */
    pthread_t remover; /* removes set-aside frames folders (remover_on: started, not joined) */
    int remover_on;
    /* status, error, frames[] and queued[] are shared with the writers: under lock. */
    pthread_mutex_t lock;
    /* queued[i]: frame i is ended and on its way to disk. A writer deciding what frame i + 1
     * stores waits on `written` while frame i is queued and not done, so that the decision, and
     * the file, are the same whatever the number of writers. */
    char *queued;
    pthread_cond_t written;
    eng_result status; /* sticky: the first failure, of a callback or a writer */
    eng_error error;
    eng_error cb_error; /* where the callbacks format a failure (this thread only) */
};

static char *dup_or_null(const char *s)
{
    return s ? cap__xstrdup(s) : NULL;
}

/* A fixed-size char array from the engine's structs, which may lack its NUL. */
static char *dup_field(const char *s, size_t size)
{
    size_t n = strnlen(s, size);
    char *p = cap__xmalloc(n + 1);
    memcpy(p, s, n);
    p[n] = 0;
    return p;
}

static void free_rec(cap_bufrec *r)
{
    free(r->name);
    for (int i = 0; i < r->channel_count; i++)
        free(r->channels[i]);
    memset(r, 0, sizeof *r);
}

static void free_frame(cap_frame *f)
{
    for (int i = 0; i < f->buffer_count; i++)
        free_rec(&f->buffers[i]);
    free(f->buffers);
    memset(f, 0, sizeof *f);
}

static void drop_pending(cap_capture *c)
{
    for (int i = 0; i < c->pending_count; i++) {
        free_rec(&c->pending[i].rec);
        free(c->pending[i].data);
    }
    c->pending_count = 0;
}

/* The path of frame i's file, relative to the run folder (as the manifest records it). */
static void frame_rel(int i, char out[32])
{
    snprintf(out, 32, "frames/%06d.exr", i);
}

int cap__parse_frame_rel(const char *rel, int *frame)
{
    int n = 0, len = 0;
    if (sscanf(rel, "frames/%6d.exr%n", &n, &len) != 1 || len != (int)strlen(rel) || n < 0)
        return 0;
    char back[32];
    frame_rel(n, back);
    if (strcmp(back, rel) != 0)
        return 0;
    *frame = n;
    return 1;
}

static char *frame_path(const cap_capture *c, int i)
{
    char rel[32];
    frame_rel(i, rel);
    return cap__join(c->run_dir, rel);
}

/* seq_wants' contract (eng.h: fnmatch globs, none means "*"), evaluated here because
 * seq_wants lives in the scene loader's library, which capture does not link: capture
 * depends only on the engine's core types. */
static int capture_wanted(const seq_sequence *seq, const char *name)
{
    int n = seq->capture_count < SEQ_MAX_CAPTURE ? seq->capture_count : SEQ_MAX_CAPTURE;
    if (n <= 0)
        return 1;
    for (int i = 0; i < n; i++) {
        char pattern[SCN_NAME_MAX + 1];
        size_t len = strnlen(seq->capture[i], SCN_NAME_MAX);
        memcpy(pattern, seq->capture[i], len);
        pattern[len] = 0;
        if (fnmatch(pattern, name, 0) == 0)
            return 1;
    }
    return 0;
}

/* ---------------------------------------------------------------- run folder */

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
}

static int path_exists(const char *path)
{
    struct stat st;
    return lstat(path, &st) == 0;
}

/* mkdir -p; the last component must end up a folder. */
static eng_result make_dirs(const char *dir, eng_error *err)
{
    char *p = cap__xstrdup(dir);
    eng_result r = ENG_OK;
    for (char *s = p + 1; ; s++) {
        if (*s != '/' && *s != 0)
            continue;
        char saved = *s;
        *s = 0;
        if (mkdir(p, 0777) != 0 && errno != EEXIST) {
            r = eng_fail(err, ENG_ERR_IO, "%s: cannot create folder: %s", p, strerror(errno));
            break;
        }
        *s = saved;
        if (!saved)
            break;
    }
    free(p);
    if (r != ENG_OK)
        return r;
    struct stat st;
    if (stat(dir, &st) != 0)
        return eng_fail(err, ENG_ERR_IO, "%s: %s", dir, strerror(errno));
    if (!S_ISDIR(st.st_mode))
        return eng_fail(err, ENG_ERR_IO, "%s: exists and is not a folder", dir);
    return ENG_OK;
}

/* Does frames/ hold any *.exr or *.json? */
static eng_result frames_present(const char *frames_dir, int *present, eng_error *err)
{
    *present = 0;
    DIR *d = opendir(frames_dir);
    if (!d) {
        if (errno == ENOENT)
            return ENG_OK;
        return eng_fail(err, ENG_ERR_IO, "%s: cannot list: %s", frames_dir, strerror(errno));
    }
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (ends_with(e->d_name, ".exr") || ends_with(e->d_name, ".json")) {
            *present = 1;
            break;
        }
    closedir(d);
    return ENG_OK;
}

/* A file a run's frames/ holds: NNNNNN.exr, NNNNNN.json or their temp files. */
static int frame_file(const char *name)
{
    return ends_with(name, ".exr") || ends_with(name, ".json") || ends_with(name, ".exr.tmp") ||
           ends_with(name, ".json.tmp");
}

/* An old run's frames/ that an overwrite set aside (set_aside_frames): ".frames-removed-XXXXXX"
 * in the run folder, removed by the capture's remover thread. */
#define SET_ASIDE_PREFIX ".frames-removed-"
/* Set aside only from this many files or bytes on (fewer are removed in place). */
#define SET_ASIDE_FILES 64
#define SET_ASIDE_BYTES ((off_t)16 << 20)

/* Overwriting a run, the old frames are set aside rather than removed one by one before the
 * first frame renders: frames/ is renamed to a fresh SET_ASIDE_PREFIX folder (one rename), and
 * a thread removes its files while the new run renders (remove_set_aside). Removing a recorded
 * run's 8 frames of 5 MB took 20-25 ms of `ispm record --force`'s start.
 * Only when frames/ holds nothing but frame files (anything else stays where it is, as with
 * clean_frames), at least SET_ASIDE_FILES of them or SET_ASIDE_BYTES, and only run_dir's
 * entries change; the run.json written next is fsynced with its folder, which makes the rename
 * durable with it, as the unlinks were. Returns 1 when frames/ was set aside, 0 when not (then
 * clean_frames removes the old frames as before). */
static int set_aside_frames(const char *run_dir, const char *frames_dir)
{
    struct stat fst;
    if (lstat(frames_dir, &fst) != 0 || !S_ISDIR(fst.st_mode))
        return 0; /* a link to a folder elsewhere stays, its frames are removed in place */
    DIR *d = opendir(frames_dir);
    if (!d)
        return 0;
    int only_frames = 1;
    size_t files = 0;
    off_t bytes = 0;
    struct dirent *e;
    while (only_frames && (e = readdir(d)) != NULL) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0)
            continue;
        only_frames = frame_file(e->d_name);
        struct stat st;
        files++;
        if (only_frames && fstatat(dirfd(d), e->d_name, &st, AT_SYMLINK_NOFOLLOW) == 0)
            bytes += st.st_size;
    }
    closedir(d);
    /* A few small files go faster in place (~0.4 ms each here) than a rename, a second
     * thread and its unlinks beside run.json's fsyncs. */
    if (!only_frames || (files < SET_ASIDE_FILES && bytes < SET_ASIDE_BYTES))
        return 0;
    char *aside = cap__join(run_dir, SET_ASIDE_PREFIX "XXXXXX");
    /* An empty folder of a unique name, which the rename then replaces. */
    int done = mkdtemp(aside) != NULL;
    if (done && rename(frames_dir, aside) != 0) {
        rmdir(aside);
        done = 0;
    }
    free(aside);
    return done;
}

/* Removes a set-aside folder's frame files, then the folder (which stays if anything else was
 * put in it since). Failures leave files behind for the next overwrite to remove. */
static void remove_set_aside(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (!frame_file(e->d_name))
            continue;
        char *p = cap__join(dir, e->d_name);
        unlink(p);
        free(p);
    }
    closedir(d);
    rmdir(dir);
}

/* The remover thread: every SET_ASIDE_PREFIX folder of the run folder (the one this overwrite
 * set aside, and any an earlier run left when it was killed before removing its own). */
static void *remover_main(void *arg)
{
    const char *run_dir = arg;
    DIR *d = opendir(run_dir);
    if (!d)
        return NULL;
    char **names = NULL;
    size_t n = 0, cap = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (strncmp(e->d_name, SET_ASIDE_PREFIX, sizeof SET_ASIDE_PREFIX - 1) != 0)
            continue;
        if (n == cap) {
            cap = cap ? 2 * cap : 4;
            char **more = cap__xmalloc(cap * sizeof *more);
            if (n)
                memcpy(more, names, n * sizeof *more);
            free(names);
            names = more;
        }
        names[n++] = cap__join(run_dir, e->d_name);
    }
    closedir(d);
    for (size_t i = 0; i < n; i++) {
        struct stat st;
        if (lstat(names[i], &st) == 0 && S_ISDIR(st.st_mode))
            remove_set_aside(names[i]);
        free(names[i]);
    }
    free(names);
    return NULL;
}

/* Whether run_dir holds a SET_ASIDE_PREFIX entry (then the remover has work). */
static int has_set_aside(const char *run_dir)
{
    DIR *d = opendir(run_dir);
    if (!d)
        return 0;
    int found = 0;
    struct dirent *e;
    while (!found && (e = readdir(d)) != NULL)
        found = strncmp(e->d_name, SET_ASIDE_PREFIX, sizeof SET_ASIDE_PREFIX - 1) == 0;
    closedir(d);
    return found;
}

/* Removes frames/ *.exr and *.json (when remove_frames) and frames/ *.tmp. */
static eng_result clean_frames(const char *frames_dir, int remove_frames, eng_error *err)
{
    DIR *d = opendir(frames_dir);
    if (!d)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot list: %s", frames_dir, strerror(errno));
    eng_result r = ENG_OK;
    struct dirent *e;
    while (r == ENG_OK && (errno = 0, e = readdir(d)) != NULL) {
        const int tmp = ends_with(e->d_name, ".exr.tmp") || ends_with(e->d_name, ".json.tmp");
        if (!frame_file(e->d_name) || !(tmp || remove_frames))
            continue;
        char *p = cap__join(frames_dir, e->d_name);
        if (unlink(p) != 0 && errno != ENOENT)
            r = eng_fail(err, ENG_ERR_IO, "%s: cannot remove: %s", p, strerror(errno));
        free(p);
    }
    closedir(d);
    return r;
}

/* unlink that tolerates a missing file. */
static eng_result remove_file(const char *path, eng_error *err)
{
    if (unlink(path) != 0 && errno != ENOENT)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot remove: %s", path, strerror(errno));
    return ENG_OK;
}

/* Prepares run_dir as cap_create documents (the resume checks of run.json's content and the
 * frames come later, in cap_create). */
static eng_result prepare_run_dir(const char *run_dir, const char *frames_dir, int overwrite, int *resume,
                                  int set_aside, eng_error *err)
{
    eng_result r = make_dirs(run_dir, err);
    if (r != ENG_OK)
        return r;
    char *manifest = cap__join(run_dir, MANIFEST_NAME);
    char *manifest_tmp = cap__join(run_dir, MANIFEST_TMP_NAME);
    char *runinfo = cap__join(run_dir, RUNINFO_NAME);
    char *runinfo_tmp = cap__join(run_dir, RUNINFO_TMP_NAME);
    int has_manifest = path_exists(manifest), has_runinfo = path_exists(runinfo), has_frames = 0;
    r = frames_present(frames_dir, &has_frames, err);
    /* Killed before run.json was written, the folder holds nothing to keep: start afresh. */
    if (r == ENG_OK && *resume && !has_manifest && !has_runinfo && !has_frames)
        *resume = 0;
    if (r == ENG_OK && *resume) {
        if (has_manifest)
            r = eng_fail(err, ENG_ERR_INVALID, "%s: the run is complete (it has %s): nothing to resume", run_dir,
                         MANIFEST_NAME);
        else if (!has_runinfo)
            r = eng_fail(err, ENG_ERR_INVALID, "%s: no %s: not a run that --resume can continue", run_dir,
                         RUNINFO_NAME);
    } else if (r == ENG_OK && (has_manifest || has_runinfo || has_frames) && !overwrite)
        r = eng_fail(err, ENG_ERR_IO, "%s: already holds a run (use --force, or --resume to continue it)",
                     run_dir);
    /* The manifest goes first, so that no crash leaves it beside frames it does not describe;
     * then run.json, so that no crash leaves a resumable run of the old sequence. */
    if (r == ENG_OK && !*resume && (has_manifest || has_runinfo)) {
        if ((r = remove_file(manifest, err)) == ENG_OK && (r = cap__fsync_dir(run_dir, err)) == ENG_OK &&
            (r = remove_file(runinfo, err)) == ENG_OK)
            r = cap__fsync_dir(run_dir, err);
    }
    if (r == ENG_OK)
        r = remove_file(manifest_tmp, err);
    if (r == ENG_OK)
        r = remove_file(runinfo_tmp, err);
    /* The old frames: set aside for the remover thread (set_aside_frames), or removed here. */
    if (r == ENG_OK && set_aside && overwrite && !*resume && has_frames)
        set_aside_frames(run_dir, frames_dir);
    if (r == ENG_OK)
        r = make_dirs(frames_dir, err);
    if (r == ENG_OK)
        r = clean_frames(frames_dir, overwrite && !*resume, err);
    free(manifest);
    free(manifest_tmp);
    free(runinfo);
    free(runinfo_tmp);
    return r;
}

eng_result cap__make_parent_dirs(const char *run_dir, eng_error *err)
{
    char *parent = cap__xstrdup(run_dir);
    size_t n = strlen(parent);
    while (n > 1 && parent[n - 1] == '/')
        parent[--n] = 0;
    char *slash = strrchr(parent, '/');
    eng_result r = ENG_OK;
    if (slash && slash != parent) {
        *slash = 0;
        r = make_dirs(parent, err);
    }
    free(parent);
    return r;
}

static eng_result write_runinfo(cap_capture *c, eng_error *err);
static eng_result write_frame_record(cap_capture *c, int frame, eng_error *err);
static int write_job(void *ctx, void *job);
static void free_job(void *ctx, void *job);
static eng_result resume_run(cap_capture *c, eng_error *err);

/* ---------------------------------------------------------------- create / destroy */

eng_result cap_create(const cap_desc *desc, cap_capture **out, eng_error *err)
{
    if (!out)
        return eng_fail(err, ENG_ERR_INVALID, "cap_create: no output pointer");
    *out = NULL;
    if (!desc || !desc->run_dir || !desc->run_dir[0])
        return eng_fail(err, ENG_ERR_INVALID, "cap_create: no run folder given");
    if (!desc->sequence || !desc->scene)
        return eng_fail(err, ENG_ERR_INVALID, "%s: cap_create needs the sequence and the scene",
                        desc->run_dir);
    if (desc->sequence->frame_count < 1)
        return eng_fail(err, ENG_ERR_INVALID, "%s: the sequence has %d frames", desc->run_dir,
                        desc->sequence->frame_count);
    const cap_shard *sh = desc->shard;
    if (sh && !(sh->overlap >= 0 && sh->overlap <= sh->warmup && sh->warmup <= sh->first && sh->first <= sh->last &&
                sh->last < desc->sequence->frame_count))
        return eng_fail(err, ENG_ERR_INVALID, "%s: shard frames %d-%d, warm-up %d, overlap %d do not fit the "
                        "sequence's 0..%d", desc->run_dir, sh->first, sh->last, sh->warmup, sh->overlap,
                        desc->sequence->frame_count - 1);
    cJSON *renderer_settings = NULL;
    if (desc->renderer && desc->renderer_settings) {
        renderer_settings = cJSON_Parse(desc->renderer_settings);
        if (!cJSON_IsObject(renderer_settings)) {
            cJSON_Delete(renderer_settings);
            return eng_fail(err, ENG_ERR_INVALID, "%s: the renderer's settings are not a JSON object",
                            desc->run_dir);
        }
    }

    cap_capture *c = cap__xcalloc(1, sizeof *c);
    c->run_lock.fd = -1;
    pthread_mutex_init(&c->lock, NULL);
    pthread_cond_init(&c->written, NULL);
    c->renderer = dup_or_null(desc->renderer);
    c->renderer_settings = renderer_settings;
    c->run_dir = cap__xstrdup(desc->run_dir);
    c->frames_dir = cap__join(desc->run_dir, "frames");
    int resume = desc->resume;
    eng_result r = cap__make_parent_dirs(c->run_dir, err);
    if (r == ENG_OK)
        r = eng_lock_take(c->run_dir, "ispm record", &c->run_lock, err);
    if (r == ENG_OK)
        r = cap__recover_run(c->run_dir, err);
    char *old_manifest = cap__join(c->run_dir, MANIFEST_NAME);
    if (r == ENG_OK && desc->build_aside && desc->overwrite && !resume && path_exists(old_manifest)) {
        c->final_dir = c->run_dir;
        c->run_dir = cap__xmalloc(strlen(c->final_dir) + 16);
        sprintf(c->run_dir, "%s.recording", c->final_dir);
        free(c->frames_dir);
        c->frames_dir = cap__join(c->run_dir, "frames");
        r = cap__remove_tree(c->run_dir, err);
    }
    free(old_manifest);
    if (r == ENG_OK)
        r = prepare_run_dir(c->run_dir, c->frames_dir, desc->overwrite, &resume, 1, err);
    if (r != ENG_OK) {
        cap_destroy(c);
        return r;
    }
    if (has_set_aside(c->run_dir))
        c->remover_on = pthread_create(&c->remover, NULL, remover_main, c->run_dir) == 0;
    c->seq = desc->sequence;
    c->scene = desc->scene;
    c->gl_version = dup_or_null(desc->gl_version);
    c->gl_renderer = dup_or_null(desc->gl_renderer);
    c->gl_backend = dup_or_null(desc->gl_backend);
    c->gl_where = dup_or_null(desc->gl_where);
    c->tool_version = dup_or_null(desc->tool_version);
    c->git_revision = dup_or_null(desc->git_revision);
    c->command_line = dup_or_null(desc->command_line);
    if (desc->determinism) {
        int n = 0;
        while (desc->determinism[2 * n])
            n++;
        c->det_count = n;
        c->det = cap__xcalloc((size_t)(2 * n), sizeof *c->det);
        for (int i = 0; i < 2 * n; i++)
            c->det[i] = dup_or_null(desc->determinism[i]);
    }
    c->frame_count = desc->sequence->frame_count;
    c->frames = cap__xcalloc((size_t)c->frame_count, sizeof *c->frames);
    c->queued = cap__xcalloc((size_t)c->frame_count, 1);
    c->write_first = 0;
    c->write_last = c->frame_count - 1;
    if (desc->shard) {
        c->shard = 1;
        c->shard_info = *desc->shard;
        c->write_first = desc->shard->first - desc->shard->overlap;
        c->write_last = desc->shard->last;
    }
    c->cur_frame = -1;
    c->status = ENG_OK;
    eng_settings st = desc->sequence->settings;
    eng_settings_defaults(&st);
    if (!cap_compression_parse(st.capture_compression, &c->compression)) { /* seq_parse checked it */
        cap_destroy(c);
        return eng_fail(err, ENG_ERR_INVALID, "%s: capture_compression \"%.*s\" is not a compression capture knows",
                        desc->sequence->path, (int)sizeof st.capture_compression, st.capture_compression);
    }
    c->dedupe = !st.capture_whole_frames;
    r = resume ? resume_run(c, err) : write_runinfo(c, err);
    if (r != ENG_OK) {
        cap_destroy(c);
        return r;
    }
    if (desc->writers > 0)
        c->wq = cap_wq_create(desc->writers, desc->queue_depth > 0 ? desc->queue_depth : 2, write_job, free_job, c);
    *out = c;
    return ENG_OK;
}

/* Waits for the remover thread, if one runs. */
static void join_remover(cap_capture *c)
{
    if (c->remover_on)
        pthread_join(c->remover, NULL);
    c->remover_on = 0;
}

void cap_destroy(cap_capture *c)
{
    if (!c)
        return;
    join_remover(c);
    cap_wq_destroy(c->wq); /* frames already ended are still written (unless a write failed) */
    drop_pending(c);
    free(c->pending);
    if (c->frames)
        for (int i = 0; i < c->frame_count; i++)
            free_frame(&c->frames[i]);
    free(c->frames);
    for (int i = 0; i < 2 * c->det_count; i++)
        free(c->det[i]);
    free(c->det);
    free(c->gl_version);
    free(c->gl_renderer);
    free(c->gl_backend);
    free(c->gl_where);
    free(c->tool_version);
    free(c->git_revision);
    free(c->command_line);
    free(c->renderer);
    cJSON_Delete(c->renderer_settings);
    if (c->final_dir && !c->swapped)
        cap__remove_tree(c->run_dir, NULL); /* a recording that did not finish: the old run stays */
    eng_lock_drop(&c->run_lock);
    free(c->final_dir);
    free(c->run_dir);
    free(c->frames_dir);
    pthread_mutex_destroy(&c->lock);
    pthread_cond_destroy(&c->written);
    free(c->queued);
    free(c);
}

int cap_builds_aside(const cap_capture *c)
{
    return c && c->final_dir && !c->swapped;
}

/* The stops the first captured frame with an "auto" exposure recorded (the caller holds the
 * lock or is the only thread); 0 when none has. */
static int recorded_exposure(const cap_capture *c, float *stops)
{
    for (int i = c->write_first; i <= c->write_last; i++)
        if (c->frames[i].done && c->frames[i].exposure_auto) {
            *stops = c->frames[i].exposure;
            return 1;
        }
    return 0;
}

int cap_recorded_exposure(const cap_capture *c, float *stops)
{
    if (!c)
        return 0;
    cap_capture *m = (cap_capture *)c; /* the lock only */
    pthread_mutex_lock(&m->lock);
    int found = recorded_exposure(c, stops);
    pthread_mutex_unlock(&m->lock);
    return found;
}

int cap_frame_done(const cap_capture *c, int frame)
{
    if (!c || frame < c->write_first || frame > c->write_last)
        return 0;
    cap_capture *m = (cap_capture *)c; /* the lock only */
    pthread_mutex_lock(&m->lock);
    int done = c->frames[frame].done;
    pthread_mutex_unlock(&m->lock);
    return done;
}

eng_result cap_status(const cap_capture *c, eng_error *err)
{
    if (!c)
        return eng_fail(err, ENG_ERR_INVALID, "cap_status: no capture");
    cap_capture *m = (cap_capture *)c; /* the lock only */
    pthread_mutex_lock(&m->lock);
    eng_result r = c->status;
    if (r != ENG_OK && err)
        *err = c->error;
    pthread_mutex_unlock(&m->lock);
    return r;
}

/* ---------------------------------------------------------------- listener */

/* The first failure wins (callbacks on this thread, writers on theirs). */
static void set_error(cap_capture *c, eng_result r, const eng_error *err)
{
    pthread_mutex_lock(&c->lock);
    if (c->status == ENG_OK) {
        c->status = r;
        c->error = *err;
    }
    pthread_mutex_unlock(&c->lock);
}

static eng_result current_status(cap_capture *c)
{
    pthread_mutex_lock(&c->lock);
    eng_result r = c->status;
    pthread_mutex_unlock(&c->lock);
    return r;
}

/* Makes the failure already formatted into c->cb_error sticky; returns the callback's non-zero. */
static int fail_cb(cap_capture *c, eng_result r)
{
    set_error(c, r, &c->cb_error);
    drop_pending(c);
    c->cur_frame = -1;
    return 1;
}

static int on_frame_begin(void *user, int frame, double time)
{
    cap_capture *c = user;
    if (current_status(c) != ENG_OK)
        return 1;
    if (frame < c->write_first || frame > c->write_last)
        return fail_cb(c, eng_fail(&c->cb_error, ENG_ERR_INVALID, "%s: frame %d is outside the run's %d..%d",
                                   c->run_dir, frame, c->write_first, c->write_last));
    /* A frame begun and never ended was aborted (by another listener or the engine): its
     * buffers are not a frame, drop them. */
    drop_pending(c);
    c->cur_frame = frame;
    c->cur_time = time;
    c->cur_display_warning[0] = 0;
    return 0;
}

static int on_buffer(void *user, int frame, const eng_buffer *buf)
{
    cap_capture *c = user;
    if (current_status(c) != ENG_OK)
        return 1;
    if (c->cur_frame < 0 || frame != c->cur_frame)
        return fail_cb(c, eng_fail(&c->cb_error, ENG_ERR_INVALID,
                                   "%s: buffer announced for frame %d outside that frame's begin/end",
                                   c->run_dir, frame));
    /* Checked whether or not it is captured: a black or white frame is never silent. */
    if (buf && buf->name && buf->data && strcmp(buf->name, "final.display") == 0)
        cap_display_warning(buf, c->cur_display_warning, sizeof c->cur_display_warning);
    char *where = frame_path(c, frame);
    eng_result r = ENG_OK;
    if (!buf || !buf->name)
        r = cap__check_buffer(where, buf, &c->cb_error);
    else if (!capture_wanted(c->seq, buf->name)) {
        free(where);
        return 0;
    } else
        r = cap__check_buffer(where, buf, &c->cb_error);
    for (int i = 0; r == ENG_OK && i < c->pending_count; i++)
        if (strcmp(c->pending[i].rec.name, buf->name) == 0)
            r = eng_fail(&c->cb_error, ENG_ERR_INVALID, "%s: buffer \"%s\" announced twice", where, buf->name);
    free(where);
    if (r != ENG_OK)
        return fail_cb(c, r);

    if (c->pending_count == c->pending_cap) {
        int cap = c->pending_cap ? 2 * c->pending_cap : 16;
        cap_pending *p = cap__xcalloc((size_t)cap, sizeof *p);
        if (c->pending_count)
            memcpy(p, c->pending, (size_t)c->pending_count * sizeof *p);
        free(c->pending);
        c->pending = p;
        c->pending_cap = cap;
    }
    /* Only the copy is made here, on the thread that renders; digests and encoding are the
     * writer's (write_job). */
    cap_pending *p = &c->pending[c->pending_count++];
    memset(p, 0, sizeof *p);
    size_t n = (size_t)buf->width * (size_t)buf->height * (size_t)buf->channel_count;
    p->data = cap__xmalloc(n * sizeof(float));
    memcpy(p->data, buf->data, n * sizeof(float));
    p->rec.name = cap__xstrdup(buf->name);
    p->rec.width = buf->width;
    p->rec.height = buf->height;
    p->rec.channel_count = buf->channel_count;
    p->rec.stored_in = -1;
    for (int i = 0; i < buf->channel_count; i++)
        p->rec.channels[i] = cap__xstrdup(buf->channels[i]);
    return 0;
}

/* One ended frame on its way to disk: its buffers (copies and records) and its record. */
typedef struct cap_job {
    int frame;
    cap_frame rec;  /* everything but buffers, taken from the frame's stats */
    int count;
    cap_pending *bufs;
} cap_job;

static void free_job(void *ctx, void *job)
{
    cap_capture *c = ctx;
    cap_job *j = job;
    /* Written or dropped, the frame is no longer on its way: a writer waiting on it goes on. */
    pthread_mutex_lock(&c->lock);
    c->queued[j->frame] = 0;
    pthread_cond_broadcast(&c->written);
    pthread_mutex_unlock(&c->lock);
    for (int i = 0; i < j->count; i++) {
        free_rec(&j->bufs[i].rec);
        free(j->bufs[i].data);
    }
    free(j->bufs);
    free_frame(&j->rec);
    free(j);
}

/* Digests, frames/NNNNNN.exr, then the frame's record and frames/NNNNNN.json: on the writer
 * thread (or in on_frame_end when the capture has none). Returns non-zero on failure, the
 * error then sticky in c. Whatever the thread, a frame's file is written by one thread from
 * the same bytes, so it is byte-identical whatever the number of writers and their timing. */
static int write_job(void *ctx, void *job)
{
    cap_capture *c = ctx;
    cap_job *j = job;
    eng_error err = {{0}};
    const eng_buffer **bufs = cap__xcalloc((size_t)j->count, sizeof *bufs);
    eng_buffer *views = cap__xcalloc((size_t)j->count, sizeof *views);
    const char *(*chans)[ENG_MAX_CHANNELS] = cap__xcalloc((size_t)j->count, sizeof *chans);
    cap_bufrec *recs = cap__xcalloc((size_t)j->count, sizeof *recs);
    for (int i = 0; i < j->count; i++) {
        cap_bufrec *rec = &j->bufs[i].rec;
        for (int k = 0; k < rec->channel_count; k++)
            chans[i][k] = rec->channels[k];
        views[i] = (eng_buffer){rec->name, rec->width, rec->height, rec->channel_count, chans[i], j->bufs[i].data};
        eng_buffer_digest(&views[i], rec->digest);
        eng_buffer_nonfinite(&views[i], &rec->nan_count, &rec->inf_count, &rec->first_x, &rec->first_y);
        recs[i] = *rec; /* shallow: the strings stay j's */
    }
    /* The previous frame's records, once its writer is done with them (it was queued first). */
    int prev = j->frame - 1;
    if (c->dedupe && prev >= c->write_first) {
        pthread_mutex_lock(&c->lock);
        while (!c->frames[prev].done && c->queued[prev] && c->status == ENG_OK)
            pthread_cond_wait(&c->written, &c->lock);
        if (c->frames[prev].done)
            cap__dedupe_frame(c->frames[prev].buffers, c->frames[prev].buffer_count, prev, recs, j->count);
        pthread_mutex_unlock(&c->lock);
    }
    int stored = 0;
    for (int i = 0; i < j->count; i++) {
        j->bufs[i].rec.stored_in = recs[i].stored_in;
        if (recs[i].stored_in < 0)
            bufs[stored++] = &views[i];
    }
    free(recs);
    char *path = frame_path(c, j->frame);
    cap_exr_meta meta = {j->frame, j->rec.time, c->compression, 0};
    eng_result r = cap__write_exr(path, bufs, stored, &meta, &err);
    free(bufs);
    free(views);
    free(chans);
    free(path);
    if (r == ENG_OK) {
        /* A frame rendered again replaces its earlier record (the file was replaced too). */
        pthread_mutex_lock(&c->lock);
        cap_frame *f = &c->frames[j->frame];
        free_frame(f);
        *f = j->rec;
        memset(&j->rec, 0, sizeof j->rec); /* moved */
        f->buffer_count = j->count;
        f->buffers = cap__xcalloc((size_t)j->count, sizeof *f->buffers);
        for (int i = 0; i < j->count; i++) {
            f->buffers[i] = j->bufs[i].rec;
            memset(&j->bufs[i].rec, 0, sizeof j->bufs[i].rec); /* moved */
        }
        f->done = 1;
        pthread_cond_broadcast(&c->written);
        pthread_mutex_unlock(&c->lock);
        r = write_frame_record(c, j->frame, &err);
        if (r != ENG_OK) {
            pthread_mutex_lock(&c->lock);
            c->frames[j->frame].done = 0;
            pthread_mutex_unlock(&c->lock);
        }
    }
    if (r != ENG_OK)
        set_error(c, r, &err);
    free_job(c, j);
    return r != ENG_OK;
}

int cap__dedupe_frame(const cap_bufrec *prev, int np, int prev_frame, cap_bufrec *cur, int n)
{
    int stored = 0;
    for (int i = 0; i < n; i++) {
        cur[i].stored_in = -1;
        for (int k = 0; k < np; k++) {
            const cap_bufrec *p = &prev[k];
            if (strcmp(p->name, cur[i].name) != 0)
                continue;
            int same = strcmp(p->digest, cur[i].digest) == 0 && p->width == cur[i].width &&
                       p->height == cur[i].height && p->channel_count == cur[i].channel_count;
            for (int ch = 0; same && ch < p->channel_count; ch++)
                same = strcmp(p->channels[ch], cur[i].channels[ch]) == 0;
            if (same)
                cur[i].stored_in = p->stored_in >= 0 ? p->stored_in : prev_frame;
            break;
        }
        stored += cur[i].stored_in < 0;
    }
    if (stored == 0 && n > 0) {
        cur[0].stored_in = -1;
        stored = 1;
    }
    return stored;
}

static int on_frame_end(void *user, const eng_frame_stats *stats)
{
    cap_capture *c = user;
    if (current_status(c) != ENG_OK)
        return 1;
    if (!stats || c->cur_frame < 0 || stats->frame != c->cur_frame)
        return fail_cb(c, eng_fail(&c->cb_error, ENG_ERR_INVALID, "%s: frame %d ended without being begun",
                                   c->run_dir, stats ? stats->frame : -1));
    int frame = c->cur_frame;
    if (c->pending_count == 0) {
        char *path = frame_path(c, frame);
        eng_fail(&c->cb_error, ENG_ERR_INVALID,
                 "%s: no announced buffer matches the sequence's capture patterns", path);
        free(path);
        return fail_cb(c, ENG_ERR_INVALID);
    }

    cap_job *j = cap__xcalloc(1, sizeof *j);
    j->frame = frame;
    cap_frame *f = &j->rec;
    f->time = c->cur_time;
    f->pass_count = stats->pass_count < 0 ? 0
                  : stats->pass_count > ENG_MAX_PASSES ? ENG_MAX_PASSES : stats->pass_count;
    for (int i = 0; i < f->pass_count; i++) {
        f->passes[i] = stats->passes[i];
        f->passes[i].name[SCN_NAME_MAX - 1] = 0;
    }
    memcpy(f->view_proj, stats->camera_view_proj, sizeof f->view_proj);
    memcpy(f->eye, stats->camera_eye, sizeof f->eye);
    f->photons_emitted = stats->photons_emitted;
    memcpy(f->photons_stored, stats->photons_stored, sizeof f->photons_stored);
    f->photons_truncated = stats->photons_truncated;
    f->trace_maps = stats->trace_maps < 0 ? 0
                  : stats->trace_maps > ENG_MAX_TRACE_MAPS ? ENG_MAX_TRACE_MAPS : stats->trace_maps;
    memcpy(f->trace_centres, stats->trace_centres, sizeof f->trace_centres);
    f->trace = stats->trace;
    f->history_from = stats->history_from;
    f->light_count = stats->light_count < 0 ? 0
                   : stats->light_count > ENG_MAX_LIGHT_RECORDS ? ENG_MAX_LIGHT_RECORDS : stats->light_count;
    memcpy(f->lights, stats->lights, sizeof f->lights);
    memcpy(f->display_warning, c->cur_display_warning, sizeof f->display_warning);
    f->exposure_auto = stats->exposure_auto != 0;
    f->exposure = stats->exposure;
    if (f->display_warning[0])
        fprintf(stderr, "ispm: warning: frame %d: %s\n", frame, f->display_warning);
    /* The pending list moves into the job; the next frame starts a new one. */
    j->count = c->pending_count;
    j->bufs = c->pending;
    c->pending = NULL;
    c->pending_count = c->pending_cap = 0;
    c->cur_frame = -1;
    pthread_mutex_lock(&c->lock);
    c->queued[frame] = 1;
    pthread_mutex_unlock(&c->lock);
    if (!c->wq)
        return write_job(c, j);
    /* Blocks while the queue is full (the memory bound); a writer's failure makes it fail. */
    return cap_wq_push(c->wq, j) != 0;
}

eng_listener cap_listener(cap_capture *c)
{
    eng_listener l = {c, on_frame_begin, on_buffer, on_frame_end};
    return l;
}

/* ---------------------------------------------------------------- compression names */

static const char *const COMPRESSION_NAMES[] = {"by-kind", "none", "rle", "zips", "zip", "piz", "by-kind"};

const char *cap_compression_name(cap_compression m)
{
    return (unsigned)m < sizeof COMPRESSION_NAMES / sizeof COMPRESSION_NAMES[0] ? COMPRESSION_NAMES[m] : "unknown";
}

int cap_compression_parse(const char *name, cap_compression *out)
{
    for (int m = CAP_COMPRESSION_NONE; name && m <= CAP_COMPRESSION_BY_KIND; m++)
        if (strcmp(name, COMPRESSION_NAMES[m]) == 0) {
            *out = (cap_compression)m;
            return 1;
        }
    return 0;
}

/* ---------------------------------------------------------------- manifest */

/* cJSON reports allocation failure as NULL; like every other allocation here, it ends the
 * process. */
static cJSON *jok(cJSON *j)
{
    if (!j) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    return j;
}

static void jadd(cJSON *obj, const char *key, cJSON *item)
{
    jok(item);
    if (!cJSON_AddItemToObject(obj, key, item))
        jok(NULL);
}

static void jpush(cJSON *arr, cJSON *item)
{
    jok(item);
    if (!cJSON_AddItemToArray(arr, item))
        jok(NULL);
}

static cJSON *jstr(const char *s)
{
    return s ? cJSON_CreateString(s) : cJSON_CreateNull();
}

static cJSON *jfield(const char *s, size_t size)
{
    char *t = dup_field(s, size);
    cJSON *j = cJSON_CreateString(t);
    free(t);
    return j;
}

/* The shortest decimal that reads back as the same float, as a double: 0.002f is recorded
 * as 0.002, not 0.0020000000949949026. */
static cJSON *jfloat(float f)
{
    char buf[32];
    for (int p = 1; p <= 9; p++) {
        snprintf(buf, sizeof buf, "%.*g", p, (double)f);
        if (strtof(buf, NULL) == f)
            return cJSON_CreateNumber(strtod(buf, NULL));
    }
    return cJSON_CreateNumber((double)f);
}

static cJSON *jfloats(const float *v, int n)
{
    cJSON *a = jok(cJSON_CreateArray());
    for (int i = 0; i < n; i++)
        jpush(a, jfloat(v[i]));
    return a;
}

/* "lights": per light its shadow views (eng_light_record): type, position, direction, texel,
 * far, view_proj per face. */
static cJSON *lights_json(const cap_frame *f)
{
    static const char *const types[] = {"point", "spot", "directional"};
    cJSON *arr = jok(cJSON_CreateArray());
    for (int l = 0; l < f->light_count; l++) {
        const eng_light_record *r = &f->lights[l];
        cJSON *o = jok(cJSON_CreateObject());
        jadd(o, "type", cJSON_CreateString(types[r->type >= 0 && r->type <= 2 ? r->type : 0]));
        jadd(o, "position", jfloats(r->position, 3));
        jadd(o, "direction", jfloats(r->direction, 3));
        jadd(o, "texel", jfloat(r->texel));
        jadd(o, "far", jfloat(r->far_value));
        cJSON *vps = jok(cJSON_CreateArray());
        for (int k = 0; k < r->faces && k < 6; k++)
            jpush(vps, jfloats(r->view_proj[k], 16));
        jadd(o, "view_proj", vps);
        jpush(arr, o);
    }
    return arr;
}

static cJSON *jpair(double a, double b)
{
    cJSON *arr = jok(cJSON_CreateArray());
    jpush(arr, cJSON_CreateNumber(a));
    jpush(arr, cJSON_CreateNumber(b));
    return arr;
}

static cJSON *frame_json(const cap_frame *f, int index)
{
    char rel[32];
    frame_rel(index, rel);
    cJSON *o = jok(cJSON_CreateObject());
    jadd(o, "index", cJSON_CreateNumber(index));
    jadd(o, "time", cJSON_CreateNumber(f->time));
    jadd(o, "file", cJSON_CreateString(rel));
    cJSON *passes = jok(cJSON_CreateArray());
    for (int i = 0; i < f->pass_count; i++) {
        cJSON *p = jok(cJSON_CreateObject());
        jadd(p, "name", jfield(f->passes[i].name, sizeof f->passes[i].name));
        jadd(p, "ms", cJSON_CreateNumber(f->passes[i].ms));
        jpush(passes, p);
    }
    jadd(o, "passes", passes);
    cJSON *cam = jok(cJSON_CreateObject());
    cJSON *vp = jok(cJSON_CreateArray());
    for (int i = 0; i < 16; i++)
        jpush(vp, jfloat(f->view_proj[i]));
    jadd(cam, "view_proj", vp);
    cJSON *eye = jok(cJSON_CreateArray());
    for (int i = 0; i < 3; i++)
        jpush(eye, jfloat(f->eye[i]));
    jadd(cam, "eye", eye);
    jadd(o, "camera", cam);
    if (f->display_warning[0])
        jadd(o, "display_warning", jfield(f->display_warning, sizeof f->display_warning));
    if (f->exposure_auto) /* the float's exact double: record --resume reads it back bit for bit */
        jadd(o, "exposure", cJSON_CreateNumber((double)f->exposure));
    if (f->light_count > 0)
        jadd(o, "lights", lights_json(f));
    if (f->photons_emitted) {
        /* Photon attrition (ISPM Fig. 10): stored[k] counts photons at bounce index k + 2. */
        cJSON *ph = jok(cJSON_CreateObject());
        jadd(ph, "emitted", cJSON_CreateNumber((double)f->photons_emitted));
        int last = ENG_PHOTON_BOUNCES - 1;
        while (last > 2 && f->photons_stored[last] == 0)
            last--;
        cJSON *st = jok(cJSON_CreateArray());
        for (int b = 2; b <= last; b++)
            jpush(st, cJSON_CreateNumber((double)f->photons_stored[b]));
        jadd(ph, "stored", st);
        /* Paths cut by the trace's safety limit (ENG_PHOTON_MAX_HITS) while alive. */
        jadd(ph, "truncated", cJSON_CreateNumber((double)f->photons_truncated));
        jadd(o, "photons", ph);
    }
    if (f->trace_maps > 0) {
        /* Multi-image photon trace (004 §4–5): map centres, and what became of its rays. */
        cJSON *tr = jok(cJSON_CreateObject());
        cJSON *cs = jok(cJSON_CreateArray());
        for (int k = 0; k < f->trace_maps; k++) {
            cJSON *c3 = jok(cJSON_CreateArray());
            for (int i = 0; i < 3; i++)
                jpush(c3, jfloat(f->trace_centres[k][i]));
            jpush(cs, c3);
        }
        jadd(tr, "centres", cs);
        const eng_trace_counts *t = &f->trace;
        const char *const names[] = {"rays", "resolved", "fallback", "dropped", "compared", "agree"};
        const uint64_t vals[] = {t->rays, t->resolved, t->fallback, t->dropped, t->compared, t->agree};
        for (int i = 0; i < 6; i++)
            jadd(tr, names[i], cJSON_CreateNumber((double)vals[i]));
        cJSON *ty = jok(cJSON_CreateArray());
        for (int i = 0; i < 4; i++)
            jpush(ty, cJSON_CreateNumber((double)t->types[i]));
        jadd(tr, "types", ty);
        jadd(o, "photon_trace", tr);
    }
    cJSON *bufs = jok(cJSON_CreateArray());
    for (int i = 0; i < f->buffer_count; i++) {
        const cap_bufrec *r = &f->buffers[i];
        cJSON *b = jok(cJSON_CreateObject());
        jadd(b, "name", cJSON_CreateString(r->name));
        jadd(b, "width", cJSON_CreateNumber(r->width));
        jadd(b, "height", cJSON_CreateNumber(r->height));
        cJSON *ch = jok(cJSON_CreateArray());
        for (int k = 0; k < r->channel_count; k++)
            jpush(ch, cJSON_CreateString(r->channels[k]));
        jadd(b, "channels", ch);
        jadd(b, "digest", cJSON_CreateString(r->digest));
        jadd(b, "nan", cJSON_CreateNumber((double)r->nan_count));
        jadd(b, "inf", cJSON_CreateNumber((double)r->inf_count));
        jadd(b, "first_nonfinite", r->first_x < 0 ? cJSON_CreateNull() : jpair(r->first_x, r->first_y));
        if (r->stored_in >= 0) {
            char rel[32];
            frame_rel(r->stored_in, rel);
            jadd(b, "stored_in", cJSON_CreateString(rel));
        }
        jpush(bufs, b);
    }
    jadd(o, "buffers", bufs);
    return o;
}

/* A shard's frame record: frame_json with the sequence's frame and the engine's history_from
 * (ispm merge reads them), listed at position pos of the shard's frames. */
static cJSON *shard_frame_json(const cap_frame *f, int frame, int pos)
{
    cJSON *o = frame_json(f, frame);
    cJSON_ReplaceItemInObjectCaseSensitive(o, "index", jok(cJSON_CreateNumber(pos)));
    jadd(o, "sequence_frame", cJSON_CreateNumber(frame));
    jadd(o, "history_from", cJSON_CreateNumber(f->history_from));
    return o;
}

static cJSON *manifest_json(const cap_capture *c)
{
    const seq_sequence *seq = c->seq;
    cJSON *root = jok(cJSON_CreateObject());
    jadd(root, "format", cJSON_CreateString("ispm-run"));
    jadd(root, "format_version", cJSON_CreateNumber(1));

    cJSON *tool = jok(cJSON_CreateObject());
    jadd(tool, "name", cJSON_CreateString("ispm"));
    jadd(tool, "version", jstr(c->tool_version));
    jadd(tool, "git", jstr(c->git_revision));
    jadd(root, "tool", tool);
    jadd(root, "command", jstr(c->command_line));

    cJSON *sq = jok(cJSON_CreateObject());
    jadd(sq, "path", jfield(seq->path, sizeof seq->path));
    jadd(sq, "name", jfield(seq->name, sizeof seq->name));
    jadd(sq, "digest", jfield(seq->digest, sizeof seq->digest));
    jadd(root, "sequence", sq);

    cJSON *sc = jok(cJSON_CreateObject());
    jadd(sc, "path", jfield(c->scene->path, sizeof c->scene->path));
    jadd(sc, "digest", jfield(c->scene->digest, sizeof c->scene->digest));
    jadd(root, "scene", sc);

    jadd(root, "resolution", jpair(seq->width, seq->height));
    jadd(root, "fps", cJSON_CreateNumber(seq->fps));
    jadd(root, "frame_count", cJSON_CreateNumber(c->write_last - c->write_first + 1));
    /* A look-at camera (keys in the sequence) has no node name: null; the keys are covered
     * by the sequence digest. */
    jadd(root, "camera", seq->camera_node[0]   ? jfield(seq->camera_node, sizeof seq->camera_node)
                         : seq->camera_by_index ? cJSON_CreateNumber(seq->camera_node_index)
                                                : cJSON_CreateNull());
    /* The scene's warnings (scn_warn), only when there are any, so runs without keep their
     * manifests as before. */
    if (c->scene->warning_count) {
        cJSON *wa = jok(cJSON_CreateArray());
        for (uint32_t w = 0; w < c->scene->warning_count && w < SCN_MAX_WARNINGS; w++)
            jpush(wa, jfield(c->scene->warnings[w], SCN_WARNING_MAX));
        if (c->scene->warning_count > SCN_MAX_WARNINGS)
            jpush(wa, jok(cJSON_CreateString("(more warnings not kept)")));
        jadd(root, "warnings", wa);
    }

    eng_settings s = seq->settings;
    eng_settings_defaults(&s);
    cJSON *st = jok(cJSON_CreateObject());
    int count = 0;
    const eng_setting *table = eng_settings_table(&count);
    for (int i = 0; i < count; i++) {
        const eng_setting *d = &table[i];
        if (!d->recorded(&s))
            continue;
        switch (d->type) {
        case ENG_SETTING_INT: jadd(st, d->key, cJSON_CreateNumber(d->get(&s))); break;
        case ENG_SETTING_FLOAT:
            if (d->word && d->word_get(&s)) {
                /* The engine's number once a frame recorded it ("<key>_<word>": true beside
                 * it), the word before (run.json, written before any frame). */
                float v;
                if (!recorded_exposure(c, &v)) {
                    jadd(st, d->key, jstr(d->word));
                    break;
                }
                d->set(&s, v);
                char flag[96];
                snprintf(flag, sizeof flag, "%s_%s", d->key, d->word);
                jadd(st, d->key, d->exact ? cJSON_CreateNumber(d->get(&s)) : jfloat((float)d->get(&s)));
                jadd(st, flag, cJSON_CreateBool(1));
                break;
            }
            jadd(st, d->key, d->exact ? cJSON_CreateNumber(d->get(&s)) : jfloat((float)d->get(&s)));
            break;
        case ENG_SETTING_BOOL: jadd(st, d->key, cJSON_CreateBool(d->get(&s) != 0.0)); break;
        case ENG_SETTING_ENUM: jadd(st, d->key, jstr(eng_setting_value_name(d, (int)d->get(&s)))); break;
        case ENG_SETTING_NAME: {
            char text[64];
            eng_setting_format(d, &s, text, sizeof text);
            jadd(st, d->key, jstr(text));
            break;
        }
        }
    }
    jadd(root, "settings", st);
    /* How the frame files are encoded: not a setting of the pictures (provenance does not
     * compare it), since every lossless choice decodes to the same bits. */
    cJSON *cp = jok(cJSON_CreateObject());
    jadd(cp, "compression", jstr(cap_compression_name(c->compression)));
    jadd(cp, "dedupe", cJSON_CreateBool(c->dedupe));
    jadd(root, "capture", cp);

    cJSON *det = jok(cJSON_CreateObject());
    for (int i = 0; i < c->det_count; i++)
        jadd(det, c->det[2 * i], jstr(c->det[2 * i + 1]));
    jadd(root, "determinism", det);

    cJSON *gl = jok(cJSON_CreateObject());
    jadd(gl, "version", jstr(c->gl_version));
    jadd(gl, "renderer", jstr(c->gl_renderer));
    if (c->gl_backend)
        jadd(gl, "backend", jstr(c->gl_backend));
    if (c->gl_where)
        jadd(gl, "device", jstr(c->gl_where));
    jadd(root, "gl", gl);

    if (c->renderer) {
        cJSON *rd = jok(cJSON_CreateObject());
        jadd(rd, "name", jstr(c->renderer));
        jadd(rd, "settings", c->renderer_settings ? jok(cJSON_Duplicate(c->renderer_settings, 1))
                                                  : cJSON_CreateNull());
        jadd(root, "renderer", rd);
    }

    if (c->shard) {
        cJSON *sh = jok(cJSON_CreateObject());
        jadd(sh, "frames", jpair(c->shard_info.first, c->shard_info.last));
        jadd(sh, "warmup", cJSON_CreateNumber(c->shard_info.warmup));
        jadd(sh, "overlap", cJSON_CreateNumber(c->shard_info.overlap));
        jadd(sh, "sequence_frame_count", cJSON_CreateNumber(seq->frame_count));
        jadd(root, "shard", sh);
    }

    cJSON *frames = jok(cJSON_CreateArray());
    for (int i = c->write_first; i <= c->write_last; i++)
        jpush(frames, c->shard ? shard_frame_json(&c->frames[i], i, i - c->write_first) : frame_json(&c->frames[i], i));
    jadd(root, "frames", frames);
    jadd(root, "complete", cJSON_CreateTrue());
    return root;
}

/* Writes text to dir/name atomically: name.tmp, fsync, rename, fsync dir. On failure name.tmp is
 * removed, and so is dir/name when it was renamed into place but its folder could not be synced. */
static eng_result write_atomic(const char *dir, const char *name, const char *text, eng_error *err)
{
    char *path = cap__join(dir, name);
    char *tmp = cap__xmalloc(strlen(path) + 5);
    sprintf(tmp, "%s.tmp", path);
    eng_result r = ENG_OK;
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) {
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot create: %s", tmp, strerror(errno));
        goto out;
    }
    size_t len = strlen(text), done = 0;
    while (r == ENG_OK && done < len) {
        ssize_t w = write(fd, text + done, len - done);
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0)
            r = eng_fail(err, ENG_ERR_IO, "%s: %s", path, w < 0 ? strerror(errno) : strerror(ENOSPC));
        else
            done += (size_t)w;
    }
    if (r == ENG_OK && fsync(fd) != 0)
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot sync: %s", path, strerror(errno));
    if (close(fd) != 0 && r == ENG_OK)
        r = eng_fail(err, ENG_ERR_IO, "%s: %s", path, strerror(errno));
    if (r == ENG_OK && rename(tmp, path) != 0)
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot rename %s into place: %s", path, tmp, strerror(errno));
    if (r != ENG_OK) {
        unlink(tmp);
    } else if ((r = cap__fsync_dir(dir, err)) != ENG_OK) {
        /* Renamed but not durable: the file goes, so that no failed write leaves a manifest
         * that makes the run look complete. */
        unlink(path);
    }
out:
    free(tmp);
    free(path);
    return r;
}

eng_result cap_finish(cap_capture *c, eng_error *err)
{
    if (!c)
        return eng_fail(err, ENG_ERR_INVALID, "cap_finish: no capture");
    if (c->wq)
        cap_wq_finish(c->wq); /* every frame ended is on disk (or failed) before the manifest */
    join_remover(c); /* the old run's set-aside frames are gone when the new run is complete */
    if (c->status != ENG_OK) {
        if (err)
            *err = c->error;
        return c->status;
    }
    if (c->cur_frame >= 0)
        return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d was begun but never ended", c->run_dir,
                        c->cur_frame);
    for (int i = c->write_first; i <= c->write_last; i++)
        if (!c->frames[i].done)
            return eng_fail(err, ENG_ERR_INVALID, "%s: frame %d of %d..%d was not captured", c->run_dir,
                            i, c->write_first, c->write_last);
    eng_result r = cap__fsync_dir(c->frames_dir, err);
    if (r != ENG_OK)
        return r;
    cJSON *root = manifest_json(c);
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    if (!text)
        jok(NULL);
    size_t n = strlen(text);
    char *doc = cap__xmalloc(n + 2);
    memcpy(doc, text, n);
    memcpy(doc + n, "\n", 2);
    cJSON_free(text);
    r = write_atomic(c->run_dir, MANIFEST_NAME, doc, err);
    free(doc);
    if (r == ENG_OK && c->final_dir) {
        r = cap__swap_run(c->run_dir, c->final_dir, err);
        c->swapped = r == ENG_OK;
    }
    return r;
}

/* ---------------------------------------------------------------- resume */

/* Prints a cJSON tree with a trailing newline, as write_atomic wants it. */
static char *json_text(cJSON *root)
{
    char *text = cJSON_Print(root);
    if (!text)
        jok(NULL);
    size_t n = strlen(text);
    char *doc = cap__xmalloc(n + 2);
    memcpy(doc, text, n);
    memcpy(doc + n, "\n", 2);
    cJSON_free(text);
    return doc;
}

/* run.json: the manifest's runinfo_keys, taken from the manifest this capture would write. */
static cJSON *runinfo_json(const cap_capture *c)
{
    cJSON *m = manifest_json(c);
    cJSON *info = jok(cJSON_CreateObject());
    jadd(info, "format", cJSON_CreateString("ispm-run-info"));
    jadd(info, "format_version", cJSON_CreateNumber(1));
    for (int i = 0; runinfo_keys[i]; i++) {
        cJSON *item = cJSON_DetachItemFromObjectCaseSensitive(m, runinfo_keys[i]);
        if (item || !runinfo_optional(runinfo_keys[i]))
            jadd(info, runinfo_keys[i], item ? item : cJSON_CreateNull());
    }
    cJSON_Delete(m);
    return info;
}

static eng_result write_runinfo(cap_capture *c, eng_error *err)
{
    cJSON *info = runinfo_json(c);
    char *doc = json_text(info);
    cJSON_Delete(info);
    eng_result r = write_atomic(c->run_dir, RUNINFO_NAME, doc, err);
    free(doc);
    return r;
}

static eng_result write_frame_record(cap_capture *c, int frame, eng_error *err)
{
    char name[32];
    snprintf(name, sizeof name, "%06d.json", frame);
    pthread_mutex_lock(&c->lock);
    cJSON *o = frame_json(&c->frames[frame], frame);
    if (c->shard)
        jadd(o, "history_from", cJSON_CreateNumber(c->frames[frame].history_from));
    pthread_mutex_unlock(&c->lock);
    char *doc = json_text(o);
    cJSON_Delete(o);
    eng_result r = write_atomic(c->frames_dir, name, doc, err);
    free(doc);
    return r;
}

/* Reads a JSON file written by write_atomic; ENG_ERR_INVALID when it does not parse. */
static eng_result read_json(const char *path, cJSON **out, eng_error *err)
{
    *out = NULL;
    char *text = NULL;
    size_t len = 0;
    eng_result r = eng_read_input(path, ENG_IN_NOFOLLOW, (size_t)64 << 20, &text, &len, err);
    if (r == ENG_OK && (r = eng_json_precheck(path, text, len, ENG_JSON_MAX_DEPTH, err)) != ENG_OK)
        free(text);
    if (r != ENG_OK)
        return r;
    *out = cJSON_ParseWithLength(text, len);
    free(text);
    if (!*out)
        return eng_fail(err, ENG_ERR_INVALID, "%s: not valid JSON", path);
    return ENG_OK;
}

static int json_int(const cJSON *o, const char *key, double lo, double hi, int *out)
{
    const cJSON *j = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!cJSON_IsNumber(j) || !(j->valuedouble >= lo && j->valuedouble <= hi) ||
        j->valuedouble != (double)(int64_t)j->valuedouble)
        return 0;
    *out = (int)j->valuedouble;
    return 1;
}

/* Fills f from a frames/NNNNNN.json that frame_json wrote for frame index; anything else is
 * ENG_ERR_INVALID naming the file and the key. */
static eng_result frame_from_json(const char *path, int index, const cJSON *o, cap_frame *f, eng_error *err)
{
    int idx;
    if (!cJSON_IsObject(o) || !json_int(o, "index", 0, 1e9, &idx) || idx != index)
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"index\" is not %d", path, index);
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(o, "time");
    if (!cJSON_IsNumber(t))
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"time\" is not a number", path);
    f->time = t->valuedouble;
    const cJSON *passes = cJSON_GetObjectItemCaseSensitive(o, "passes");
    if (!cJSON_IsArray(passes) || cJSON_GetArraySize(passes) > ENG_MAX_PASSES)
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"passes\" is not an array of at most %d", path, ENG_MAX_PASSES);
    const cJSON *p;
    cJSON_ArrayForEach(p, passes) {
        const cJSON *name = cJSON_GetObjectItemCaseSensitive(p, "name");
        const cJSON *ms = cJSON_GetObjectItemCaseSensitive(p, "ms");
        if (!cJSON_IsString(name) || strlen(name->valuestring) >= SCN_NAME_MAX || !cJSON_IsNumber(ms))
            return eng_fail(err, ENG_ERR_INVALID, "%s: passes[%d] is not {\"name\", \"ms\"}", path, f->pass_count);
        eng_pass_time *pt = &f->passes[f->pass_count++];
        snprintf(pt->name, sizeof pt->name, "%s", name->valuestring);
        pt->ms = ms->valuedouble;
    }
    const cJSON *cam = cJSON_GetObjectItemCaseSensitive(o, "camera");
    const cJSON *vp = cJSON_GetObjectItemCaseSensitive(cam, "view_proj");
    const cJSON *eye = cJSON_GetObjectItemCaseSensitive(cam, "eye");
    if (cJSON_GetArraySize(vp) != 16 || cJSON_GetArraySize(eye) != 3)
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"camera\" is not {\"view_proj\": [16], \"eye\": [3]}", path);
    for (int i = 0; i < 16; i++)
        f->view_proj[i] = (float)cJSON_GetArrayItem(vp, i)->valuedouble;
    for (int i = 0; i < 3; i++)
        f->eye[i] = (float)cJSON_GetArrayItem(eye, i)->valuedouble;
    const cJSON *ph = cJSON_GetObjectItemCaseSensitive(o, "photons");
    if (ph) {
        const cJSON *em = cJSON_GetObjectItemCaseSensitive(ph, "emitted");
        const cJSON *st = cJSON_GetObjectItemCaseSensitive(ph, "stored");
        const cJSON *tr = cJSON_GetObjectItemCaseSensitive(ph, "truncated");
        if (!cJSON_IsNumber(em) || !cJSON_IsArray(st) || cJSON_GetArraySize(st) > ENG_PHOTON_BOUNCES - 2 ||
            (tr && !cJSON_IsNumber(tr)))
            return eng_fail(err, ENG_ERR_INVALID, "%s: \"photons\" is not {\"emitted\", \"stored\"[, \"truncated\"]}",
                            path);
        f->photons_emitted = (uint64_t)em->valuedouble;
        f->photons_truncated = tr ? (uint64_t)tr->valuedouble : 0;
        for (int b = 0; b < cJSON_GetArraySize(st); b++)
            f->photons_stored[b + 2] = (uint64_t)cJSON_GetArrayItem(st, b)->valuedouble;
    }
    const cJSON *dw = cJSON_GetObjectItemCaseSensitive(o, "display_warning");
    if (dw && (!cJSON_IsString(dw) || strlen(dw->valuestring) >= sizeof f->display_warning))
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"display_warning\" is not a string of under %zu bytes", path,
                        sizeof f->display_warning);
    if (dw)
        snprintf(f->display_warning, sizeof f->display_warning, "%s", dw->valuestring);
    const cJSON *ex = cJSON_GetObjectItemCaseSensitive(o, "exposure");
    if (ex && (!cJSON_IsNumber(ex) || !(fabs(ex->valuedouble) <= ENG_EXPOSURE_MAX)))
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"exposure\" is not a number of stops within ±%g", path,
                        ENG_EXPOSURE_MAX);
    f->exposure_auto = ex != NULL;
    f->exposure = ex ? (float)ex->valuedouble : 0.0f;
    eng_result lr = eng_light_records_parse(path, cJSON_GetObjectItemCaseSensitive(o, "lights"), &f->light_count,
                                     f->lights, err);
    if (lr != ENG_OK)
        return lr;
    const cJSON *tr = cJSON_GetObjectItemCaseSensitive(o, "photon_trace");
    if (tr) {
        const cJSON *cs = cJSON_GetObjectItemCaseSensitive(tr, "centres");
        const cJSON *ty = cJSON_GetObjectItemCaseSensitive(tr, "types");
        int nc = cJSON_IsArray(cs) ? cJSON_GetArraySize(cs) : -1;
        if (nc < 1 || nc > ENG_MAX_TRACE_MAPS || cJSON_GetArraySize(ty) != 4)
            return eng_fail(err, ENG_ERR_INVALID, "%s: \"photon_trace\" is not {\"centres\": [1..%d × [3]], "
                            "\"types\": [4], ...}", path, ENG_MAX_TRACE_MAPS);
        f->trace_maps = nc;
        for (int k = 0; k < nc; k++) {
            const cJSON *c3 = cJSON_GetArrayItem(cs, k);
            if (cJSON_GetArraySize(c3) != 3)
                return eng_fail(err, ENG_ERR_INVALID, "%s: \"photon_trace\".centres[%d] is not [x, y, z]", path, k);
            for (int i = 0; i < 3; i++)
                f->trace_centres[k][i] = (float)cJSON_GetArrayItem(c3, i)->valuedouble;
        }
        const char *const names[] = {"rays", "resolved", "fallback", "dropped", "compared", "agree"};
        uint64_t *vals[] = {&f->trace.rays, &f->trace.resolved, &f->trace.fallback, &f->trace.dropped,
                            &f->trace.compared, &f->trace.agree};
        for (int i = 0; i < 6; i++) {
            const cJSON *v = cJSON_GetObjectItemCaseSensitive(tr, names[i]);
            if (!cJSON_IsNumber(v))
                return eng_fail(err, ENG_ERR_INVALID, "%s: \"photon_trace\".%s is not a number", path, names[i]);
            *vals[i] = (uint64_t)v->valuedouble;
        }
        for (int i = 0; i < 4; i++)
            f->trace.types[i] = (uint64_t)cJSON_GetArrayItem(ty, i)->valuedouble;
    }
    const cJSON *hf = cJSON_GetObjectItemCaseSensitive(o, "history_from");
    f->history_from = cJSON_IsNumber(hf) ? (int)hf->valuedouble : -1;
    const cJSON *bufs = cJSON_GetObjectItemCaseSensitive(o, "buffers");
    int n = cJSON_IsArray(bufs) ? cJSON_GetArraySize(bufs) : 0;
    if (n < 1)
        return eng_fail(err, ENG_ERR_INVALID, "%s: \"buffers\" is not a non-empty array", path);
    f->buffers = cap__xcalloc((size_t)n, sizeof *f->buffers);
    const cJSON *b;
    cJSON_ArrayForEach(b, bufs) {
        cap_bufrec *rec = &f->buffers[f->buffer_count];
        int i = f->buffer_count++;
        const cJSON *name = cJSON_GetObjectItemCaseSensitive(b, "name");
        const cJSON *dg = cJSON_GetObjectItemCaseSensitive(b, "digest");
        const cJSON *ch = cJSON_GetObjectItemCaseSensitive(b, "channels");
        const cJSON *first = cJSON_GetObjectItemCaseSensitive(b, "first_nonfinite");
        int nch = cJSON_IsArray(ch) ? cJSON_GetArraySize(ch) : 0, nan, inf;
        if (!cJSON_IsString(name) || !json_int(b, "width", 1, 1 << 30, &rec->width) ||
            !json_int(b, "height", 1, 1 << 30, &rec->height) || nch < 1 || nch > ENG_MAX_CHANNELS ||
            !cJSON_IsString(dg) || strlen(dg->valuestring) != 32 || !json_int(b, "nan", 0, 2e9, &nan) ||
            !json_int(b, "inf", 0, 2e9, &inf))
            return eng_fail(err, ENG_ERR_INVALID, "%s: buffers[%d] is not a buffer record", path, i);
        rec->name = cap__xstrdup(name->valuestring);
        memcpy(rec->digest, dg->valuestring, 33);
        rec->nan_count = (uint64_t)nan;
        rec->inf_count = (uint64_t)inf;
        const cJSON *cn;
        cJSON_ArrayForEach(cn, ch) {
            if (!cJSON_IsString(cn))
                return eng_fail(err, ENG_ERR_INVALID, "%s: buffers[%d].channels holds a non-string", path, i);
            rec->channels[rec->channel_count++] = cap__xstrdup(cn->valuestring);
        }
        rec->first_x = rec->first_y = -1;
        if (cJSON_IsArray(first) && cJSON_GetArraySize(first) == 2) {
            const cJSON *x = cJSON_GetArrayItem(first, 0), *y = cJSON_GetArrayItem(first, 1);
            if (!cJSON_IsNumber(x) || !cJSON_IsNumber(y))
                return eng_fail(err, ENG_ERR_INVALID, "%s: buffers[%d].first_nonfinite is not [x, y]", path, i);
            rec->first_x = (int)x->valuedouble;
            rec->first_y = (int)y->valuedouble;
        } else if (!cJSON_IsNull(first))
            return eng_fail(err, ENG_ERR_INVALID, "%s: buffers[%d].first_nonfinite is not null or [x, y]", path, i);
        rec->stored_in = -1;
        const cJSON *in = cJSON_GetObjectItemCaseSensitive(b, "stored_in");
        if (in && !cap__parse_frame_rel(cJSON_IsString(in) ? in->valuestring : "", &rec->stored_in))
            return eng_fail(err, ENG_ERR_INVALID, "%s: buffers[%d].stored_in is not frames/NNNNNN.exr", path, i);
        if (rec->stored_in >= index)
            return eng_fail(err, ENG_ERR_INVALID, "%s: buffers[%d].stored_in names frame %d, not an earlier one", path, i,
                            rec->stored_in);
    }
    f->done = 1;
    return ENG_OK;
}

static eng_result resume_run(cap_capture *c, eng_error *err)
{
    /* Same sequence, scene and settings as the interrupted run, or its frames are not ours. */
    char *path = cap__join(c->run_dir, RUNINFO_NAME);
    cJSON *old = NULL;
    eng_result r = read_json(path, &old, err);
    if (r == ENG_OK) {
        cJSON *now = runinfo_json(c);
        for (int i = 0; r == ENG_OK && runinfo_keys[i]; i++) {
            const cJSON *a = cJSON_GetObjectItemCaseSensitive(old, runinfo_keys[i]);
            const cJSON *b = cJSON_GetObjectItemCaseSensitive(now, runinfo_keys[i]);
            if (!a && !b && runinfo_optional(runinfo_keys[i]))
                continue;
            if (!cJSON_Compare(a, b, 1))
                r = eng_fail(err, ENG_ERR_INVALID,
                             "%s: \"%s\" differs from this recording's: the run was recorded from another "
                             "sequence, scene or settings (use --force to start again)",
                             path, runinfo_keys[i]);
        }
        cJSON_Delete(now);
    }
    cJSON_Delete(old);
    free(path);
    int removed = 0;
    for (int i = c->write_first; r == ENG_OK && i <= c->write_last; i++) {
        char name[32];
        snprintf(name, sizeof name, "%06d.json", i);
        char *json = cap__join(c->frames_dir, name);
        char *exr = frame_path(c, i);
        int has_json = path_exists(json), has_exr = path_exists(exr);
        if (has_json && has_exr) {
            cJSON *o = NULL;
            if ((r = read_json(json, &o, err)) == ENG_OK)
                r = frame_from_json(json, i, o, &c->frames[i], err);
            cJSON_Delete(o);
            if (r != ENG_OK)
                free_frame(&c->frames[i]);
        } else if (has_json || has_exr) {
            /* Killed between the two renames: the frame is rendered again. */
            if ((r = remove_file(has_json ? json : exr, err)) == ENG_OK)
                removed = 1;
        }
        free(json);
        free(exr);
    }
    if (r == ENG_OK && removed)
        r = cap__fsync_dir(c->frames_dir, err);
    return r;
}

/* ---------------------------------------------------------------- for merge.c */

eng_result cap__prepare_run(const char *run_dir, const char *frames_dir, int overwrite, eng_error *err)
{
    int resume = 0;
    return prepare_run_dir(run_dir, frames_dir, overwrite, &resume, 0, err);
}

eng_result cap__write_atomic(const char *dir, const char *name, const char *text, eng_error *err)
{
    return write_atomic(dir, name, text, err);
}

cJSON *cap__jok(cJSON *j)
{
    return jok(j);
}

int cap__json_int(const cJSON *o, const char *key, double lo, double hi, int *out)
{
    return json_int(o, key, lo, hi, out);
}

char *cap__json_text(cJSON *root)
{
    return json_text(root);
}
