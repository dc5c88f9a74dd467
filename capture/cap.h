/* cap.h — capture: the listener that turns announced buffers into a run folder.
 *
 * A run (see shared/DESIGN.md, "Run layout") is
 *     RUN/manifest.json       written last, atomically; a run without it is incomplete
 *     RUN/frames/NNNNNN.exr   one multi-part EXR per frame, one part per captured buffer
 * Every file is written to "<name>.tmp", fsynced and renamed, so a reader never sees a
 * half-written frame or manifest, and a crash never leaves a manifest beside frames it does
 * not describe.
 *
 * Use: cap_create; eng_listener l = cap_listener(c); eng_add_listener(engine, &l); render
 * every frame; cap_finish; cap_destroy. The callbacks, cap_finish and cap_destroy are called
 * from one thread (the engine's, which renders); with writers (cap_desc.writers) frames are
 * encoded and written on threads of the capture's own.
 */
#ifndef ISPM_CAP_H
#define ISPM_CAP_H

#include "seq.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cap_desc {
    const char *run_dir;          /* RUN folder to create/fill */
    const seq_sequence *sequence; /* borrowed */
    const scn_scene *scene;       /* borrowed */
    const char *gl_version;       /* may be NULL */
    const char *gl_renderer;      /* may be NULL */
    /* The GL context's backend ("osmesa", "egl") and what it ran on ("surfaceless", "device 0
     * (…)"): "gl": {"backend", "device"} in the manifest. NULL: not recorded (older runs, whose
     * backend was OSMesa). */
    const char *gl_backend;
    const char *gl_where;
    const char *tool_version;     /* e.g. "0.1.0" */
    const char *git_revision;     /* e.g. "abc123" or "unknown" */
    const char *command_line;     /* recorded verbatim, may be NULL */
    int overwrite;                /* allow an existing non-empty run_dir (its manifest is removed first) */
    /* With overwrite, onto a complete run (one with manifest.json): the new run is recorded in
     * <run_dir>.recording and renamed over run_dir by cap_finish (the old run at
     * <run_dir>.replaced until the rename is synced), so that a recording that fails or is
     * killed leaves the old run as it was. A live view of run_dir sees the old run meanwhile. */
    int build_aside;
    /* NULL-terminated key, value, key, value, ... list recorded as "determinism" in the
     * manifest (pass eng_determinism_info()); may be NULL. Copied by cap_create. */
    const char *const *determinism;
    /* Continue an interrupted run instead of starting one (ispm record --resume): run_dir
     * must hold run.json written by a cap_create for the same sequence, scene and settings
     * (else ENG_ERR_INVALID) and no manifest.json (a complete run; ENG_ERR_INVALID). Every
     * frame whose frames/NNNNNN.exr and frames/NNNNNN.json both exist counts as captured
     * (cap_frame_done), its record read back from the .json; a frame with only one of the
     * two is removed, to be rendered again. A folder that holds no part of a run (killed
     * before run.json was written, or never recorded) gets a new run. Ignores overwrite. */
    int resume;
    /* A run made by another renderer than the engine (ispm reference): its name and the text
     * of a JSON object of its settings, recorded as "renderer": {"name", "settings"} in the
     * manifest. NULL (the default) records nothing, so engine runs are unchanged. A settings
     * text that is not a JSON object is ENG_ERR_INVALID. Copied by cap_create. */
    const char *renderer;
    const char *renderer_settings;
    /* Writer threads: 0 (the default) writes each frame in frame_end, on the
     * caller's thread; N > 0 hands ended frames to N threads through a queue of queue_depth
     * frames (0: 2), so that encoding and writing overlap rendering the next frame. At most
     * queue_depth + writers + 1 frames of buffers are held. A writer's failure is sticky as a
     * callback's: it makes the next callback, and cap_finish, fail. The files are the same
     * bytes either way. */
    int writers;
    int queue_depth;
    /* A frame shard (ispm record --frames A-B; NULL: the whole sequence). The run holds frames
     * first - overlap .. last (the last `overlap` frames of the warm-up are written too, for
     * ispm merge to compare with the previous shard's), each file and frames/NNNNNN.json named
     * by its sequence frame. Its manifest lists those frames in order ("index" 0, 1, ...,
     * "sequence_frame" the frame of the sequence, "history_from" the engine's
     * eng_frame_stats.history_from), "frame_count" their number, and "shard": {"frames": [A, B],
     * "warmup", "overlap", "sequence_frame_count"}; run.json repeats "shard" (--resume checks
     * it). Needs 0 <= overlap <= warmup <= first <= last < the sequence's frame count. */
    const struct cap_shard *shard;
} cap_desc;

typedef struct cap_shard {
    int first, last;  /* the shard's own frames, A..B */
    int warmup;       /* frames rendered before A (their state only), W */
    int overlap;      /* of which the last ones written, O <= W */
} cap_shard;

typedef struct cap_capture cap_capture;

/* Creates run_dir and run_dir/frames (mkdir -p). A folder that already holds a run
 * (manifest.json, run.json or frames/ *.exr) is refused with ENG_ERR_IO unless
 * desc->overwrite (or desc->resume, above); then its manifest.json and run.json are unlinked
 * first (and the unlinks made durable), then its frames/ *.exr and *.json. Stale temporary
 * files of an earlier crash (*.tmp) are removed either way. A new run then gets run.json
 * (atomically): what the run is of (sequence and scene digests, resolution, frame count,
 * fps, camera, settings), which --resume checks. desc->sequence and desc->scene must outlive
 * the capture; the strings are copied. On failure *out is NULL. */
eng_result cap_create(const cap_desc *desc, cap_capture **out, eng_error *err);

/* The listener to register with eng_add_listener; its callbacks return non-zero on failure.
 * Buffers that seq_wants-style matching of sequence->capture rejects are ignored; the others
 * are copied at announce time, so the engine may reuse its memory as soon as the callback
 * returns. frame_end writes frames/NNNNNN.exr, then frames/NNNNNN.json (the frame's manifest
 * record, for --resume), each atomically: a frame counts as captured only when both exist
 * (with writers, frame_end queues the frame and a writer does this). Errors are sticky: after
 * one callback or write failed, every later callback and cap_finish fail with the same error. */
eng_listener cap_listener(cap_capture *c);

/* Whether c records beside a complete run that it replaces only at cap_finish (build_aside):
 * then a failure leaves that run as it was. */
int cap_builds_aside(const cap_capture *c);
/* A frame whose final.display is all black (no channel of any pixel reaches
 * CAP_DISPLAY_BLACK, half of one 8-bit step) or has more than CAP_DISPLAY_CLIP_FRACTION of its
 * pixels clipped to white (every channel at CAP_DISPLAY_CLIPPED or above: 255 in 8 bits, what
 * the display transform's clamp to 1 gives after sRGB encoding's rounding; a saturated colour
 * is not white) gets a warning: printed on stderr, written as the frame record's
 * "display_warning", shown by replay and the report. The fraction leaves room for visible
 * emitters and their surroundings (the canonical Cornell box shows 2.7 % white at its default
 * exposure). cap_display_warning writes it (one line, no newline) and returns 1, or returns 0
 * with out "". */
#define CAP_DISPLAY_BLACK (0.5f / 255.0f)
#define CAP_DISPLAY_CLIPPED (1.0f - 0.5f / 255.0f)
#define CAP_DISPLAY_CLIP_FRACTION 0.05
#define CAP_DISPLAY_WARNING_MAX 200
int cap_display_warning(const eng_buffer *display, char *out, size_t size);

/* Was frame already captured (by this capture, or by the interrupted run it resumes)?
 * A resumed recording skips such frames. */
int cap_frame_done(const cap_capture *c, int frame);
/* The stops of `"exposure": "auto"` that a captured frame recorded (frames/NNNNNN.json
 * "exposure"; a resumed run's too): 1 and *stops, or 0 when no captured frame has them. The
 * manifest's "settings" gives this number for the exposure, with "exposure_auto": true. */
int cap_recorded_exposure(const cap_capture *c, float *stops);

/* The error that made a callback fail (ENG_OK if none); copies its message into err. */
eng_result cap_status(const cap_capture *c, eng_error *err);

/* After the last frame: waits for the writers to write every frame ended, then writes manifest.json atomically (temp + fsync + rename + fsync of
 * the folder), after making the frames' directory entries durable. Fails if any frame in
 * 0..frame_count-1 was not completed (ENG_ERR_INVALID) or a callback had failed. */
eng_result cap_finish(cap_capture *c, eng_error *err);

void cap_destroy(cap_capture *c); /* accepts NULL */

/* Writes one multi-part scanline EXR: part i is bufs[i], named bufs[i]->name, with its
 * channels as FLOAT, ZIP-compressed (lossless; frame files follow capture_compression),
 * data window (0,0)-(w-1,h-1), row 0 = top
 * (INCREASING_Y). The display window, which the format requires to be the same in every
 * part, is (0,0)-(W-1,H-1) with W, H the largest width and height among the buffers. count >= 1, names unique, 1..ENG_MAX_CHANNELS distinct non-empty channel
 * names per buffer, width and height > 0; otherwise ENG_ERR_INVALID and nothing is written.
 * Atomic: writes "<path>.tmp", fsyncs it and renames it over path; on any failure the temp
 * file is removed and path is left as it was. The rename itself is not made durable: fsync
 * the folder for that. A one-part file is a plain single-part EXR that still carries the
 * part name. */
eng_result cap_write_exr(const char *path, const eng_buffer *const *bufs, int count, eng_error *err);
/* One buffer as a single-part cap_write_exr file, ZIP at zlib level `level` (1..9; 0: OpenEXR's
 * default), without frame attributes: a golden's stored object (the smallest lossless file
 * OpenEXR's ZIP makes, written once and read many times). */
eng_result cap_write_exr_zip(const char *path, const eng_buffer *b, int level, eng_error *err);
/* cap_write_exr without the fsync, for files whose durability nobody relies on (replay's
 * stability run, which is renamed into place whole): the same bytes, without waiting on the disk. */
eng_result cap_write_exr_unsynced(const char *path, const eng_buffer *const *bufs, int count, eng_error *err);

/* How capture compresses each EXR part (lossless only: what replay decodes is bit-exact what
 * was announced whatever the choice; only the file's bytes and size change). A sequence names
 * it in settings.capture_compression, which the engine passes on as text. */
typedef enum cap_compression {
    CAP_COMPRESSION_DEFAULT = 0, /* record's default: by-kind */
    CAP_COMPRESSION_NONE,
    CAP_COMPRESSION_RLE,
    CAP_COMPRESSION_ZIPS,        /* zlib, one scanline per block */
    CAP_COMPRESSION_ZIP,         /* zlib, 16 scanlines per block */
    CAP_COMPRESSION_PIZ,         /* wavelet + Huffman */
    CAP_COMPRESSION_BY_KIND      /* per part, cap_compression_for's table */
} cap_compression;
const char *cap_compression_name(cap_compression m);
/* "none", "rle", "zips", "zip", "piz", "by-kind" → *out; 0 if name is none of them. */
int cap_compression_parse(const char *name, cap_compression *out);

/* What "by-kind" gives the buffer called name, chosen by measurement (docs/runs.md, "How frames
 * are compressed": bytes and encode time of every buffer of the atrium at 1920×1080): ZIP at zlib
 * level 1 (*zip_level 1) for the kinds it shrinks to a tenth to a half for little time (material
 * ids, motion, normals, depth, counts, the lights' small G-buffers, bounce and photon maps);
 * none (*zip_level 0) for noisy float colour, positions and shadow depth, which no lossless codec
 * shrinks by more than a third and whose encode would cost more CPU than rendering spares. */
cap_compression cap_compression_for(const char *name, int *zip_level);

/* The EXR file src written again as dst with every part compressed with m (lossless: none,
 * rle, zips, zip, piz; DEFAULT is none): the same parts in the same order, every attribute
 * copied (ispm:frame, ispm:time, windows, channels and their types), the pixels decoded and
 * encoded again in their own type, so dst decodes to src's bits. Used by ispm bless, which
 * keeps goldens in zip whatever the run was recorded with. Atomic as cap_write_exr (dst.tmp,
 * fsync, rename; the rename not made durable), and verified before the rename: dst.tmp is
 * decoded again and must hold src's parts bit for bit in the new compression (else
 * ENG_ERR_IO). When every part of src already has that compression nothing is written and
 * *rewritten is 0 (copy the file instead); else *rewritten is 1 on success. Tiled, deep or subsampled parts are ENG_ERR_INVALID; an
 * unreadable src or a failed write ENG_ERR_IO; the message names the file. */
eng_result cap_recompress_exr(const char *src, const char *dst, cap_compression m, int *rewritten,
                              eng_error *err);

#ifdef __cplusplus
}
#endif

#endif
