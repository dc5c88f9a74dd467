/* cap_internal.h — what capture's files share and nobody else sees: the EXR writer with
 * per-file metadata, buffer validation, and small file-system helpers. */
#ifndef ISPM_CAP_INTERNAL_H
#define ISPM_CAP_INTERNAL_H

#include "cap.h"

/* Extra attributes stamped on every part of a frame file; frame < 0 means none. */
typedef struct cap_exr_meta {
    int frame;
    double time;
    cap_compression compression; /* 0 (default): none */
    int zip_level;               /* ZIP/ZIPS zlib level 1..9; 0: OpenEXR's default */
} cap_exr_meta;

/* What the manifest says about one captured buffer. */
typedef struct cap_bufrec {
    char *name;
    int width, height, channel_count;
    char *channels[ENG_MAX_CHANNELS];
    char digest[40];
    uint64_t nan_count, inf_count;
    int first_x, first_y; /* first non-finite pixel, -1 if none */
    /* -1: a part of its own frame's file; else the earlier frame whose file holds an identical
     * buffer of the same name (the manifest's "stored_in"), never one that refers on itself. */
    int stored_in;
} cap_bufrec;

/* Within-run storage of a buffer identical to the previous frame's (unless capture_whole_frames): sets
 * cur[i].stored_in, for each of the n buffers of a frame, to where the same-name buffer of the
 * previous frame prev_frame (its np records prev, or none: np 0) is stored when both have the
 * same digest, size and channel names in the same order: prev's stored_in, or prev_frame when
 * prev holds it itself; else -1. A frame file is never empty: when every buffer would refer, the
 * first stays stored. Returns how many buffers the frame's file holds. */
int cap__dedupe_frame(const cap_bufrec *prev, int np, int prev_frame, cap_bufrec *cur, int n);

/* "frames/NNNNNN.exr" (the manifest's name of frame NNNNNN's file, exactly as capture writes
 * it) → *frame; 0 if rel is not such a name. */
int cap__parse_frame_rel(const char *rel, int *frame);

/* cap_write_exr with metadata (meta may be NULL). */
eng_result cap__write_exr(const char *path, const eng_buffer *const *bufs, int count,
                          const cap_exr_meta *meta, eng_error *err);

/* Checks one buffer against what an EXR part can hold (see cap_write_exr); where names
 * the file the buffer is meant for, in the message. */
eng_result cap__check_buffer(const char *where, const eng_buffer *b, eng_error *err);

/* Out of memory ends the process (STYLE.md: one hook), as in the engine's core. */
void *cap__xmalloc(size_t n);
void *cap__xcalloc(size_t n, size_t size);
char *cap__xstrdup(const char *s);
/* "a/b" in fresh memory. */
char *cap__join(const char *a, const char *b);

/* fsync of a folder, so that renames and unlinks in it survive a crash. Filesystems that
 * cannot fsync a folder (EINVAL) count as success. */
eng_result cap__fsync_dir(const char *dir, eng_error *err);

/* What ispm merge (merge.c) shares with capture.c: the run folder prepared as cap_create
 * does (refused when it holds a run unless overwrite; the old manifest unlinked first), and
 * text written to dir/name atomically (name.tmp, fsync, rename, fsync of dir). */
eng_result cap__prepare_run(const char *run_dir, const char *frames_dir, int overwrite, eng_error *err);
/* rm -rf that never follows a symbolic link; a missing path is no error (err may be NULL). */
eng_result cap__remove_tree(const char *path, eng_error *err);
/* A complete run built beside run_dir (in tmp) takes its place: run_dir renamed to
 * <run_dir>.replaced, tmp to run_dir, the parent folder synced (else the swap is undone and
 * the old run is back), then the old one removed. On failure run_dir is the old run. */
eng_result cap__swap_run(const char *tmp, const char *run_dir, eng_error *err);
/* A swap that ended between its two renames leaves <run_dir>.replaced and no run_dir: the old
 * run is renamed back (one line on stderr); a <run_dir>.replaced beside a run is removed.
 * Under the run's lock. */
eng_result cap__recover_run(const char *run_dir, eng_error *err);
/* The folders above run_dir, made (the lock beside it, <run>.lock, needs them). */
eng_result cap__make_parent_dirs(const char *run_dir, eng_error *err);
eng_result cap__write_atomic(const char *dir, const char *name, const char *text, eng_error *err);
/* capture.c's JSON helpers: j itself, or the process ends (out of memory); obj[key] as an
 * integer in [lo, hi] (1) or not (0); a tree printed with a trailing newline (free it). */
struct cJSON;
struct cJSON *cap__jok(struct cJSON *j);
int cap__json_int(const struct cJSON *o, const char *key, double lo, double hi, int *out);
char *cap__json_text(struct cJSON *root);

#endif
