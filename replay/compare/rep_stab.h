/* rep_stab.h — temporal stability (compare room): the metrics (stability.c), their verdicts
 * against tolerances.json's "stability" limits and the per-pixel flicker written as a run
 * (stab_report.c). Used by replay.c, the report's stability sections and tests/test_stability.c.
 *
 * The definitions (docs/stability.md says the same for people):
 *   flicker of one pixel between two images a, b of the same pass:
 *       f = max over channels c of |a_c − b_c| / (max(|a_c|, |b_c|) + REP_STAB_EPS)
 *   (per-channel maximum rather than luminance: a change of hue at equal luminance is
 *   flicker too; f lies in [0, 1); a non-finite value on either side gives f = 1).
 *   static pixels: surface pixels (material id >= 0) whose gbuffer.position, gbuffer.normal and gbuffer.material bit-identical at the
 *   same pixel in both frames; f compares the same pixel.
 *   reprojected pixels: the pixel's history is the previous frame's pixel nearest to
 *   p + 0.5 + motion; it is valid when the reprojection test (rep_stab_reproject) accepts it.
 *   statistics: mean and 99th percentile (nearest rank) of f over the pixels, and the count
 *   of pixels where some channel differs in bits.
 */
#ifndef ISPM_REP_STAB_H
#define ISPM_REP_STAB_H

#include <stdint.h>

#include "rep_compare.h"
#include "rep_run.h"

/* ε of the relative change, in the buffer's units (radiance: W/m²/sr). Radiance below ε
 * changes count as absolute: the black parts of an image do not make flicker out of noise. */
#define REP_STAB_EPS 1e-3
/* A surface whose recorded motion differs from the camera-only reprojection of its world
 * position by more than this many pixels moved in the world (an animated object). */
#define REP_STAB_MOTION_TOL 0.05
/* The previous surface point must lie within this many pixel footprints of the current
 * one (the nearest previous pixel is at most half a pixel away in x and in y). */
#define REP_STAB_FOOTPRINTS 1.0
/* ... and face the same way: dot of the normals at least this (thin walls: the two sides are
 * closer than a footprint but face away from each other). */
#define REP_STAB_NORMAL_DOT 0.9

/* One eye G-buffer, channels picked by name, in a fixed order. */
typedef struct rep_stab_gbuffer {
    int width, height;
    float *position; /* X,Y,Z */
    float *normal;   /* X,Y,Z */
    float *material; /* roughness, metallic, transmission, ior, id */
    float *motion;   /* X,Y: pixels to the previous frame, y down */
    int has_camera;
    float view_proj[16]; /* this frame's world → clip (manifest "camera") */
} rep_stab_gbuffer;

/* Fills g from a frame's parts (copies). 0 if the frame lacks one of the four parts or they
 * differ in size or channels: no stability for that run. */
int rep_stab_gbuffer_from_parts(const rep_part *parts, int n, const rep_frame_info *f, rep_stab_gbuffer *g);
void rep_stab_gbuffer_free(rep_stab_gbuffer *g);

/* Why a pixel has no valid history (REP_REPRO_VALID: it has one). */
typedef enum rep_repro_class {
    REP_REPRO_VALID = 0,
    REP_REPRO_BACKGROUND,  /* no surface in the current frame */
    REP_REPRO_OFFSCREEN,   /* the motion leads outside the previous image */
    REP_REPRO_MOVING,      /* moved in the world: no camera, or motion not the camera's */
    REP_REPRO_DISOCCLUDED, /* the previous pixel shows another surface (id, position, normal) */
    REP_REPRO_COUNT
} rep_repro_class;

const char *rep_repro_class_name(rep_repro_class c);

/* static_mask[p] = 1 where a surface is (id >= 0: background is no surface to flicker) and position, normal and material are bit-identical in prev and cur. */
void rep_stab_static_mask(const rep_stab_gbuffer *prev, const rep_stab_gbuffer *cur, uint8_t *static_mask);

/* For each pixel p of cur: src[p] = index of its history pixel in prev, or -1; cls[p] why.
 * The test, for a surface pixel p with world position P, normal N, material id m and motion
 * v: q = floor(p + 0.5 + v) must lie in the image; the surface must be static in the world,
 * i.e. cur has a camera and the previous camera projects P to p + 0.5 + v within
 * REP_STAB_MOTION_TOL pixels (without cameras: v = 0 exactly), so the current point moved
 * back is P itself; then prev at q must show material id m, a normal N_q with N·N_q ≥
 * REP_STAB_NORMAL_DOT, and a position X_q with |X_q − P| ≤ REP_STAB_FOOTPRINTS × (fx + fy),
 * fx and fy the smaller world distances from X_q to its left/right and up/down neighbours of
 * the same id (the previous frame's pixel footprint at q). */
void rep_stab_reproject(const rep_stab_gbuffer *prev, const rep_stab_gbuffer *cur, int32_t *src, uint8_t *cls);

/* f of one pixel (see the header comment); a and b hold n channels. */
double rep_stab_flicker(const float *a, const float *b, int n);

typedef struct rep_stab_stats {
    uint64_t pixels;  /* pixels measured */
    uint64_t changed; /* of which some channel differs in bits */
    double mean, p99, max;
} rep_stab_stats;

/* mean, p99 (nearest rank: the ceil(0.99 n)-th smallest) and max of v[0..n); sorts v. */
void rep_stab_summarise(float *v, size_t n, rep_stab_stats *s);

/* ---------------------------------------------------------------- a run's stability */

/* One image buffer of the eye view over a sequence. */
typedef struct rep_stab_buffer {
    char *name;
    int channel_count;           /* 3 (R,G,B) or 1 (Y) */
    int pairs;                   /* frame pairs measured */
    /* per frame (index = the later frame of the pair; NaN at frame 0 or where not measured) */
    double *static_mean, *static_p99, *repro_mean, *repro_p99;
    /* pooled over all pairs */
    float *sv, *rv;
    size_t sn, scap, rn, rcap;
    uint64_t static_changed, repro_changed;
    rep_stab_stats st, rp;       /* filled by rep_stab_finish */
    /* against a reference (when given) */
    const char *reference;       /* the reference part name, or NULL */
    double *sum, *sumsq;         /* per pixel and channel */
    int ref_frames;
    double tstd_mean, tstd_p99, bias_mean; /* per-pixel std over time (max over channels) */
    /* the previous frame's image */
    float *prev;
} rep_stab_buffer;

typedef struct rep_stab_run {
    int enabled;                 /* the run has an eye G-buffer */
    int width, height, frames;   /* frames seen */
    int buffer_count;
    rep_stab_buffer *buffers;
    rep_stab_gbuffer prev;
    int has_prev;
    uint64_t classes[REP_REPRO_COUNT]; /* over all pairs (surface and background pixels) */
    uint64_t static_pixels;            /* over all pairs */
    int frame_count;             /* of the run, for the per-frame arrays */
} rep_stab_run;

/* Is this part an image of the eye view the metrics apply to? R,G,B or Y channels, the
 * G-buffer's size, and not a G-buffer (the test's input), light-space (shadow, lightgbuffer,
 * bounce: not image-aligned), photons.map (a list, not an image) or a stability part. */
int rep_stab_is_image(const rep_part *p, int width, int height);

/* The reference part the temporal error of a buffer is measured against, or NULL. */
const char *rep_stab_reference_for(const char *buffer);

/* Feeds one frame. parts are the frame's parts; ref (may be NULL) the reference frame's.
 * flicker: if non-NULL, gets one malloc'd W×H float image per buffer (stability.<part>: the
 * reprojected flicker where the pixel has valid history, −1 where it has none) in
 * st->buffers order; *flicker_count their number. Returns 0 when the frame lacks the G-buffer
 * (stability is then off for the run). */
int rep_stab_frame(rep_stab_run *st, const rep_frame_info *f, const rep_part *parts, int n, const rep_part *ref,
                   int ref_n, float ***flicker, int *flicker_count);
void rep_stab_finish(rep_stab_run *st);
void rep_stab_free(rep_stab_run *st);
rep_stab_buffer *rep_stab_find(const rep_stab_run *st, const char *name);

/* ---------------------------------------------------------------- verdicts and output */

/* One measured buffer's verdict against the "stability" limits of its tolerance rule. */
typedef struct rep_stab_verdict {
    rep_tol_stab tol;
    char *tol_match; /* the rule's pattern, or "default" */
    int checked;     /* the rule had a stability object */
    int failed;
    char *why;       /* what exceeded which limit, or NULL */
} rep_stab_verdict;

typedef struct rep_stab_report {
    rep_stab_run run, golden;
    int has_golden;              /* golden measured too (its own values for golden_margin) */
    char *reference_dir;
    rep_stab_verdict *verdicts;  /* parallel to run.buffers */
    char *out_dir;               /* the stability run written (report folder/stability), or NULL */
    int failed;                  /* buffers over a limit */
} rep_stab_report;

/* Fills report->verdicts from the tolerances (NULL: nothing is checked). */
void rep_stab_judge(rep_stab_report *s, const rep_tolerances *tols);
void rep_stab_report_free(rep_stab_report *s);

/* The flicker images of one frame as frames/NNNNNN.exr of a run folder (parts stability.<part>, Y);
 * rec gets the frame's manifest record (cJSON object, as a string). */
eng_result rep_stab_write_frame(const char *run_dir, const rep_frame_info *f, const rep_stab_run *st, float **flicker,
                                int count, char **rec, eng_error *err);
/* The stability run's manifest.json, last: records are the frames' records in order. */
eng_result rep_stab_write_manifest(const char *run_dir, const char *sequence_name, const rep_stab_run *st,
                                   char **records, int count, eng_error *err);

#endif
