/* rep_run.h — the run room's face: reading a recorded run (or golden) and verifying it, and the
 * images made of its buffers. What cli/, viewer/ and the rooms above (compare, report) use.
 *
 *   run.c        run reader: manifest.json parsed and validated, frame files decoded through
 *                oiio_shim.h (exr_read.c, else OpenImageIO) and verified against the digests
 *   keep.c       decoded parts and ꟻLIP maps held between replay's walk and report.html
 *   thumb.c      float buffers (and their differences) mapped to 8-bit images
 *   png_write.c  8-bit images written as PNG with libpng
 * File reading and writing helpers are rep_util.h's; image files, oiio_shim.h's.
 */
#ifndef ISPM_REP_RUN_H
#define ISPM_REP_RUN_H

#include <stddef.h>
#include <stdint.h>

#include "eng_core.h"
#include "oiio_shim.h"

/* A buffer larger than this many floats (1 GiB) is taken for a lying manifest or header. */
#define REP_MAX_FLOATS ((size_t)1 << 28)
/* Longest channel name kept in fixed-size records (metrics, thumbnail maps). */
#define REP_CHANNEL_NAME_MAX 64

/* ---------------------------------------------------------------- run.c */

typedef struct rep_buffer_info {
    char *name;
    int width, height;
    int channel_count;
    char *channels[ENG_MAX_CHANNELS]; /* as the manifest lists them */
    char digest[40];                  /* 32 lowercase hex */
    uint64_t nan, inf;
    int has_nonfinite_counts;         /* the manifest gave "nan" and "inf" */
    /* -1: a part of its frame's own file. Else the index of the earlier frame whose file holds
     * the part: the manifest's "stored_in" (that frame's "file"), where capture stored a
     * buffer identical to the previous frame's once. rep_run_open checks that the frame is
     * earlier and lists the same-name buffer, with the same digest, size and channels, in its own
     * file; format 2 (objects by digest) sets -1. */
    int stored_in;
} rep_buffer_info;

typedef struct rep_frame_info {
    int index;
    double time;
    char *file; /* as in the manifest, relative to the run folder; NULL in a format-2 golden */
    char *path; /* run folder + file; NULL in a format-2 golden (its buffers are objects) */
    int buffer_count;
    rep_buffer_info *buffers;
    int has_camera;        /* the manifest gave "camera" (runs recorded before it did not) */
    float view_proj[16];   /* eye camera world → clip, column-major (GL) */
    float eye[3];
    char *display_warning; /* the frame record's "display_warning" (black or clipped), or NULL */
} rep_frame_info;

/* A run's manifest, validated: one owner, freed whole by rep_run_close. */
typedef struct rep_run {
    char *dir;
    char *manifest_path;
    int width, height; /* "resolution" */
    char *sequence_name; /* may be NULL */
    char *gl_renderer;   /* the manifest's gl.renderer (GL_RENDERER); NULL if absent */
    char *gl_vendor;     /* the manifest's gl.vendor (GL_VENDOR); NULL if absent */
    int format_version;  /* 1: one frame file per frame; 2: buffers stored once (objects.c) */
    char *objects_dir;   /* format 2: the object store, run folder + the manifest's "objects" */
    struct rep_object_cache *object_cache; /* format 2: parts the next frame repeats (objects.c) */
    int frame_count;
    rep_frame_info *frames;
    int complete;        /* manifest.json read; 0: a run still being recorded (rep_run_open_live) */
    int planned_frames;  /* live: run.json's frame_count (0 if absent); complete: frame_count */
} rep_run;

/* Opens a run: parses and validates manifest.json (format, version, "complete": true, frame
 * count equal to the frames listed, indices in order, safe relative file names, buffer sizes
 * within REP_MAX_FLOATS, unique names, well-formed digests) and checks that every frame file
 * exists. Any failure means the run cannot be read: *out is NULL, err names the file and the
 * problem (ENG_ERR_IO missing, ENG_ERR_PARSE not JSON, ENG_ERR_INVALID otherwise). */
eng_result rep_run_open(const char *dir, rep_run **out, eng_error *err);
void rep_run_close(rep_run *run);

/* Opens a run that may still be recording (live view). With manifest.json it
 * is rep_run_open. Without it, a folder holding run.json (written by capture before any frame)
 * is a run in progress: its frames are those whose frames/NNNNNN.exr and frames/NNNNNN.json
 * (the frame's manifest record, written after the EXR) both exist, from frame 0 up to the first
 * one missing either: the rule by which capture's --resume counts a frame as captured. Zero
 * frames is a valid state. Without either file: rep_run_open's error. */
eng_result rep_run_open_live(const char *dir, rep_run **out, eng_error *err);
/* Appends the frames of a live run that have landed since (same rule); once manifest.json is
 * there, the manifest's frames replace the records and run->complete is set. *added gets the
 * number of new frames. Already listed frames keep their rep_frame_info (pointers stay valid;
 * the frames array itself may move). A complete run is left as it is. */
eng_result rep_run_refresh(rep_run *run, int *added, eng_error *err);

/* ---------------------------------------------------------------- objects.c */

/* A golden of format 2 ("format_version": 2, "objects": "../objects") has no frame files: each
 * distinct buffer is a single-part EXR <store>/<ab>/<digest>.exr, named by its digest, shared
 * across frames and goldens; frames list buffers by digest. rep_run_open checks that every
 * listed object exists, is a regular file (no symbolic link) and that the store stays within
 * the golden or its parents' "objects"; rep_run_read_frame decodes and verifies each one. */

/* The path of the object of digest in store (caller frees). */
char *rep_object_path(const char *store, const char *digest);
/* The object exists as a regular file in a real folder (no symbolic link on the way from the
 * store); mf names who listed it in the message. */
eng_result rep_object_check(const char *store, const char *digest, const char *mf, eng_error *err);
/* Decodes the object of buffer b into *out, as the buffer: b's name and channel names (matched
 * by rank in name order), checked against b's size, digest and non-finite counts. */
eng_result rep_object_read(const char *store, const rep_buffer_info *b, const char *mf, rep_part *out, eng_error *err);
/* A folder name for the renderer that made a run: vendor and renderer lowercased, every run of
 * other characters one '-' ("llvmpipe-llvm-15-0-6-128-bits"); "unknown" when both are empty.
 * Caller frees. */
char *rep_renderer_slug(const char *vendor, const char *renderer);

/* Index of the buffer called name in frame f, or -1. */
int rep_frame_find(const rep_frame_info *f, const char *name);

/* Decodes frame `frame` of the run and verifies it against the manifest: the file holds
 * exactly the listed parts stored in it (stored_in -1; the others are read from the earlier
 * frame files that hold them), each of the listed size and channel set, each decoding to the
 * listed digest (and non-finite counts). On success (*parts)[j] is the buffer
 * run->frames[frame].buffers[j]; free with rep_parts_free(*parts, buffer_count). Failure
 * (missing, truncated, tampered, disagreeing file) names the file and part. */
eng_result rep_run_read_frame(const rep_run *run, int frame, rep_part **parts, eng_error *err);

/* ---------------------------------------------------------------- keep.c */

/* What replay's walk keeps for report.html (keep.c): decoded parts and ꟻLIP maps by frame,
 * side and buffer name, in frame order, at most REP_KEEP_MAX_FLOATS floats in all (128 MiB)
 * and REP_KEEP_MAX_ITEMS items. */
#define REP_KEEP_MAX_FLOATS ((size_t)1 << 25)
#define REP_KEEP_MAX_ITEMS 4096
enum { REP_KEEP_RUN = 0, REP_KEEP_GOLDEN = 1 };

typedef struct rep_kept {
    int frame, side;
    char *name;
    rep_part part; /* data NULL: not kept */
    float *flip;   /* run side only: the ꟻLIP map against the golden, or NULL */
} rep_kept;

typedef struct rep_keep {
    rep_kept *items;
    size_t count, cap;
    size_t floats; /* held, parts and maps */
} rep_keep;

/* Moves *p (zeroed after) into k unless it is already there or k is full (then *p stays). */
void rep_keep_part(rep_keep *k, int frame, int side, rep_part *p);
/* Takes map (floats values) as the run's ꟻLIP map of a buffer: 1 if taken, 0 (caller frees). */
int rep_keep_flip(rep_keep *k, int frame, const char *name, float *map, size_t floats);
/* What k holds, or NULL (k may be NULL). */
const rep_part *rep_keep_find_part(const rep_keep *k, int frame, int side, const char *name);
const float *rep_keep_find_flip(const rep_keep *k, int frame, const char *name);
void rep_keep_free(rep_keep *k); /* accepts NULL */

/* ---------------------------------------------------------------- thumb.c, png_write.c */

#define REP_THUMB_MAX_SIDE 256

typedef enum rep_thumb_kind {
    REP_THUMB_DATA = 0, /* min/max ramp shared by golden and run */
    REP_THUMB_RADIANCE, /* linear: clamp, sRGB curve */
    REP_THUMB_DISPLAY   /* already display-encoded: clamp */
} rep_thumb_kind;

/* How a buffer's floats become bytes; one map serves a golden and a run alike. */
typedef struct rep_thumb_map {
    rep_thumb_kind kind;
    int n;                                   /* channels shown, 0..3 */
    char ch[3][REP_CHANNEL_NAME_MAX];        /* their names */
    double lo, hi;                           /* DATA: finite range over both buffers */
} rep_thumb_map;

/* Writes an 8-bit image (w*h*nch bytes, interleaved, top row first; nch 1 or 3) as a PNG at
 * path, whatever its extension, with libpng (png_write.c): the chunks and filtered rows
 * OpenImageIO's PNG writer (rep_oiio_write_png) makes from the same pixels, deflated at zlib
 * level 1. Overwrites path. */
eng_result rep_png_write(const char *path, int w, int h, int nch, const unsigned char *pixels, eng_error *err);

/* The kind from the buffer's name: "*.display", "*.radiance", anything else is data. */
rep_thumb_kind rep_thumb_kind_of(const char *buffer);
/* The mapping for a buffer from its run and golden versions; either (not both) may be NULL. */
void rep_thumb_map_make(const char *buffer, const eng_buffer *run, const eng_buffer *golden, rep_thumb_map *m);
/* Thumbnail size: the buffer's, scaled down so the longest side is at most REP_THUMB_MAX_SIDE. */
void rep_thumb_size(int w, int h, int *tw, int *th);
/* b as *tw × *th RGB bytes under m; NaN/Inf pixels magenta. Caller frees. */
unsigned char *rep_thumb_render(const eng_buffer *b, const rep_thumb_map *m, int *tw, int *th);
/* The same at any size: the longest side at most max_side (0: full size; ispm export). */
unsigned char *rep_image_render(const eng_buffer *b, const rep_thumb_map *m, int max_side, int *tw, int *th);
/* Heatmap of |run − golden| as *tw × *th RGB bytes; *scale gets the largest finite difference
 * (white). NULL when the two differ in size or share no channel. Caller frees. */
unsigned char *rep_thumb_diff(const eng_buffer *run, const eng_buffer *golden, double *scale, int *tw, int *th);


#endif
