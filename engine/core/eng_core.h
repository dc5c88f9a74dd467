/* eng_core.h — the engine's bottom room, which every other room and module (capture, replay,
 * viewer) may include: errors, allocation and its one out-of-memory hook, column-major 4x4
 * maths, content digests, bounded file reads, the announced buffer and the listener that
 * receives it, a frame's statistics, and the settings (settings.h). No GL, no Embree, no glTF.
 *
 * Conventions shared by every module (tests rely on them):
 *   - Units: metres, right-handed, Y up (glTF). Matrices are column-major float[16] as in GL
 *     and glTF: element (row r, column c) is m[c*4 + r].
 *   - Announced pixel data is float32, channels interleaved, row-major, row 0 is the TOP
 *     row of the image (the EXR convention; the GL passes flip when they read back).
 *   - Errors: functions that can fail on input or environment return an eng_result and fill
 *     an eng_error whose message names the file and the problem in one line. */
#ifndef ISPM_ENG_CORE_H
#define ISPM_ENG_CORE_H

#include <stddef.h>
#include <stdint.h>

#include "settings.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- errors */

typedef enum eng_result {
    ENG_OK = 0,
    ENG_ERR_IO,          /* file missing, unreadable, unwritable, disk full */
    ENG_ERR_PARSE,       /* syntax: not JSON / not glTF */
    ENG_ERR_INVALID,     /* well-formed but wrong: bad index, accessor overrun, cycle, NaN... */
    ENG_ERR_UNSUPPORTED, /* valid glTF that this tool does not handle (e.g. orthographic) */
    ENG_ERR_GL,          /* GL context or shader failure */
    ENG_ERR_NOMEM,
    ENG_ERR_ABORTED      /* a listener asked to stop */
} eng_result;

typedef struct eng_error {
    char msg[1024]; /* one line: "<file>: <where>: <problem>" */
} eng_error;

/* Formats msg into err (if err is non-NULL) and returns code. */
eng_result eng_fail(eng_error *err, eng_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

const char *eng_result_name(eng_result r);

#define ENG_NAME_MAX 64 /* names of passes, nodes, materials, with the NUL */

/* The GL backends (gl/glctx_*.c) by name: the default, the goldens' reference, and the list
 * for messages. */
#define ENG_GL_DEFAULT "osmesa"
#define ENG_GL_BACKENDS "osmesa, egl"

/* ---------------------------------------------------------------- allocation (alloc.c) */

/* malloc that ends the process through eng_oom when out of memory. */
void *eng_xmalloc(size_t size);
/* calloc likewise (n = 0 allocates one element). */
void *eng_xcalloc(size_t n, size_t size);
/* The one out-of-memory exit: prints what ran out and ends the process. */
void eng_oom(const char *what)
#if defined(__GNUC__)
    __attribute__((noreturn))
#endif
    ;

/* ---------------------------------------------------------------- math (maths.c) */

#define ENG_PI 3.14159265358979323846
void m4_identity(float m[16]);
void m4_mul(float out[16], const float a[16], const float b[16]); /* out = a·b; out may alias */
int m4_invert(float out[16], const float m[16]);                  /* 0 if singular */
void m4_perspective(float m[16], float yfov, float aspect, float znear, float zfar);
void m4_look_at(float m[16], const float eye[3], const float target[3], const float up[3]);
void m4_transform_point(const float m[16], const float p[3], float out[3]);
/* Upper 3×3 of the inverse transpose, as a column-major 3×3 (for normals). */
void m4_normal_matrix(float out9[9], const float m[16]);

/* ---------------------------------------------------------------- buffers & listeners */

#define ENG_MAX_CHANNELS 16

typedef struct eng_buffer {
    const char *name;              /* "<pass>.<buffer>[.light<i>][.face<f>]" */
    int width, height;
    int channel_count;
    const char *const *channels;   /* EXR channel names, e.g. {"R","G","B"} */
    const float *data;             /* width*height*channel_count, interleaved, top row first */
} eng_buffer;

typedef struct eng_pass_time {
    char name[ENG_NAME_MAX]; /* "gbuffer", "shadow", "direct", "composite", ... */
    double ms;
} eng_pass_time;

#define ENG_MAX_PASSES 32

/* Safety limit on the surface hits of one photon path after the bounce map (Russian roulette
 * ends paths; this only bounds pathological ones, e.g. between two perfect mirrors), and the
 * number of bounce indices a photon can be stored with (2 .. ENG_PHOTON_MAX_HITS + 1). */
#define ENG_PHOTON_MAX_HITS 64
#define ENG_PHOTON_BOUNCES (ENG_PHOTON_MAX_HITS + 2)

/* Cube maps of the multi-image trace at most (ENG_TRACE_MULTI_IMAGE). */
#define ENG_MAX_TRACE_MAPS 8

/* Per frame counts of an image-space photon trace (004 §5.2), summed over its bounce rays. */
typedef struct eng_trace_counts {
    uint64_t rays;      /* bounce rays asked of the method */
    uint64_t resolved;  /* found by some map (an accepted type C/D point) */
    uint64_t fallback;  /* resolved by none, traced with Embree (multi_image_miss = embree) */
    uint64_t dropped;   /* resolved by none, path ended (multi_image_miss = drop) */
    uint64_t types[4];  /* per ray and map: A (no hit), B (rejected by Eq. 2), C (accepted, not
                         * the nearest), D (the nearest accepted) */
    uint64_t compared;  /* with multi_image_compare: rays where Embree finds a hit */
    uint64_t agree;     /* ... and the multi-image hit is on the same draw within 1 cm */
} eng_trace_counts;

/* One light's shadow views as the direct pass used them: type (0 point, 1 spot, 2
 * directional, as shaders/shadow_pcf.glsl), position, direction, the world size of a shadow
 * texel (per metre of distance for point and spot lights: u_shadow_texel), the value of an
 * empty texel, and per face the view-projection (world → clip, column-major). */
#define ENG_MAX_LIGHT_RECORDS 8
typedef struct eng_light_record {
    int type, faces;
    float position[3], direction[3];
    float texel, far_value;
    float view_proj[6][16];
} eng_light_record;


/* A manifest frame's "lights" (a cJSON array, or NULL: none) into lights (count set); an
 * invalid entry is ENG_ERR_INVALID naming path (light_record.c, in ispm_core). */
eng_result eng_light_records_parse(const char *path, const void *json, int *count, eng_light_record *lights,
                                   eng_error *err);

typedef struct eng_frame_stats {
    int frame;
    double time;
    int pass_count;
    eng_pass_time passes[ENG_MAX_PASSES];
    /* Photon attrition (ISPM Fig. 10): bounce-map photons that survived the first bounce, and
     * photon-map photons stored at bounce index b (b = 2 is the second surface of a path). */
    uint64_t photons_emitted;
    uint64_t photons_stored[ENG_PHOTON_BOUNCES];
    /* Paths the trace cut at ENG_PHOTON_MAX_HITS surface hits while they still carried power
     * (the estimate's only bias besides the kernels; should be ~0). */
    uint64_t photons_truncated;
    /* Image-space photon trace (multi-image): its map centres this frame and its counts;
     * trace_maps = 0 for the Embree trace. */
    int trace_maps;
    float trace_centres[ENG_MAX_TRACE_MAPS][3];
    eng_trace_counts trace;
    /* The eye camera of this frame: world → clip (column-major, GL conventions) and its
     * position, so tools can project world-space data (e.g. photons) into the image. */
    float camera_view_proj[16];
    float camera_eye[3];
    /* The earliest frame this frame's temporal state (temporal accumulation, progressive
     * accumulation) depends on: the last reset of that state (frame 0, a temporal_window
     * boundary, a progressive global restart, or where the history of a shard was rebuilt
     * from). -1: nothing in the engine carries state from frame to frame at these settings. */
    int history_from;
    /* The lights' shadow views of this frame (pass_shadow.c light_views, pass_direct.c), so
     * tools can find the shadow-map texel an eye pixel was tested against (ispm lineage). */
    int light_count;
    eng_light_record lights[ENG_MAX_LIGHT_RECORDS];
    /* The stops of this frame's display transform, and whether they came from `"exposure":
     * "auto"` (eng_exposure): then capture records them with the frame. */
    float exposure;
    int exposure_auto;
} eng_frame_stats;

/* A listener sees every announced buffer. Any callback may be NULL. A non-zero return
 * aborts the frame: eng_render_frame then returns ENG_ERR_ABORTED. */
typedef struct eng_listener {
    void *user;
    int (*frame_begin)(void *user, int frame, double time);
    int (*buffer)(void *user, int frame, const eng_buffer *buf);
    int (*frame_end)(void *user, const eng_frame_stats *stats);
} eng_listener;


/* ---------------------------------------------------------------- small shared helpers */

/* Hex XXH3-128 of bytes (32 hex chars + NUL). */
void eng_digest_hex(const void *data, size_t len, char out[40]);

/* Content digest of a buffer, the one capture writes to the manifest and replay recomputes
 * from decoded files: XXH3-128 over each channel plane in strcmp order of channel names,
 * each plane width*height float32 (little-endian, top row first). The order of channels in
 * memory therefore does not matter; -0.0 and 0.0 differ, as do NaN payloads. */
void eng_buffer_digest(const eng_buffer *b, char out[40]);

/* Counts of NaN and ±Inf values in a buffer; first_x/first_y get the first non-finite pixel
 * in row-major order (-1 if none). */
void eng_buffer_nonfinite(const eng_buffer *b, uint64_t *nan_count, uint64_t *inf_count,
                          int *first_x, int *first_y);

/* ---------------------------------------------------------------- inputs (files.c)
 * The one way a tool opens a file it reads (docs/inputs.md): without blocking, regular files
 * only (a FIFO, device, socket or folder is ENG_ERR_INVALID naming what it is), the size
 * checked against max_bytes before any byte is read (ENG_ERR_INVALID). ENG_IN_NOFOLLOW: for
 * files inside a run or golden, a symbolic link as the last component is refused. */
#define ENG_IN_NOFOLLOW 1u
/* The deepest JSON nesting an input may have (manifests need ~6, glTF ~10). */
#define ENG_JSON_MAX_DEPTH 256

/* Opens path (the descriptor blocking again, close-on-exec) and gives its size. */
eng_result eng_open_input(const char *path, unsigned flags, uint64_t max_bytes, int *fd, uint64_t *size,
                          eng_error *err);
/* eng_open_input's checks alone (size may be NULL). */
eng_result eng_check_input(const char *path, unsigned flags, uint64_t max_bytes, uint64_t *size, eng_error *err);
/* Reads a whole input (NUL-terminated; *len excludes the NUL). Caller frees. */
eng_result eng_read_input(const char *path, unsigned flags, size_t max_bytes, char **data, size_t *len,
                          eng_error *err);
/* eng_read_input without flags. */
eng_result eng_read_file(const char *path, size_t max_bytes, char **data, size_t *len, eng_error *err);
/* An advisory lock on a folder a tool writes: <dir>.lock beside it, flock'd, holding the
 * holder's words ("ispm bless") and pid. Taken: ENG_OK; held elsewhere: ENG_ERR_INVALID
 * "<dir>: in use by <holder>, process <pid> (lock <dir>.lock)". Dropped (and the file
 * removed) by eng_lock_drop or the process's end (then the file stays, unlocked). */
typedef struct eng_lock {
    int fd;
    char path[4096];
} eng_lock;
eng_result eng_lock_take(const char *dir, const char *holder, eng_lock *lk, eng_error *err);
void eng_lock_drop(eng_lock *lk); /* accepts NULL and a lock not taken */

/* Before a JSON parser sees text: nesting deeper than max_depth is ENG_ERR_INVALID, anything
 * but whitespace after the first value ENG_ERR_PARSE, both naming path and the byte. Malformed
 * text passes (the parser names it). */
eng_result eng_json_precheck(const char *path, const char *text, size_t len, int max_depth, eng_error *err);

/* ---------------------------------------------------------------- exposure (exposure.c) */

#define ENG_EXPOSURE_GREY 0.18  /* the key value a frame's log-average luminance is mapped to */
#define ENG_EXPOSURE_DELTA 1e-6 /* δ of the log average (Reinhard et al. 2002, Eq. 1) */
#define ENG_EXPOSURE_MAX 100.0  /* |stops| at most: the "exposure" setting's range */

typedef struct eng_exposure_key_info {
    double log_average; /* L̄ over the pixels counted; 0 when none was */
    uint64_t counted;   /* pixels that entered the average */
    uint64_t nonfinite; /* pixels left out for a NaN or ±Inf channel */
    float stops;        /* log2(0.18 / L̄), clamped to ±ENG_EXPOSURE_MAX; 0 when counted is 0 */
} eng_exposure_key_info;

/* The exposure of `"exposure": "auto"` from pixels RGB triples of linear radiance: the
 * log-average Rec. 709 luminance of the pixels that coverage marks (non-zero; NULL: all) whose
 * luminance is finite and above 0. No pixel counted (an all-black frame): 0 stops. */
void eng_exposure_key(const float *rgb, const float *coverage, size_t pixels, eng_exposure_key_info *out);

/* Process-wide, once: freed memory stays in the heap for reuse, every thread allocates from
 * one heap, and a range of it is advised for transparent huge pages (fewer page faults; see
 * core.c). Returns the bytes advised, 0 where nothing was (not glibc, a replaced allocator). */
size_t eng_keep_freed_memory(void);

#ifdef __cplusplus
}
#endif

#endif
