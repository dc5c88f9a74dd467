/* view_model.h — the viewer's one public header: everything ispm-view does that needs no window.
 *
 * The viewer (ispm-view) is split in two. This header and its two files hold the logic, so that
 * Check tests can drive it without a display:
 *   view_model.c  the state (frame, buffer, channel, exposure, offset, compare mode, zoom),
 *                 the actions keys map to, and pure functions mapping float pixels to RGBA8
 *                 for every display mode (channel selection, exposure/offset, sRGB, false
 *                 colour, NaN/Inf/negative overlay, error heatmaps), the image layout, the
 *                 pixel-probe text and the projection of photon maps into the eye image;
 *   view_run.c    a recorded run opened through replay's run reader (rep_run_open,
 *                 rep_run_read_frame: manifest validated, every frame verified against its
 *                 digests) with frames decoded lazily into a small LRU cache.
 * main.c is the SDL2 front end: it maps events to view_action values and draws what these
 * functions compute. Nothing here links the renderer's GL code.
 */
#ifndef ISPM_VIEW_MODEL_H
#define ISPM_VIEW_MODEL_H

#include <stddef.h>
#include <stdint.h>

#include "eng_core.h"
#include "lineage.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- display modes */

/* What of a buffer's channels is shown. VIEW_CH_1..VIEW_CH_4 pick one channel (manifest
 * order) as grey; RGB shows the first three (one channel: grey; two: R,G,0). */
typedef enum view_channel {
    VIEW_CH_RGB = 0,
    VIEW_CH_1,
    VIEW_CH_2,
    VIEW_CH_3,
    VIEW_CH_4,
    VIEW_CH_LUMA, /* Rec. 709 luminance of the RGB selection */
    VIEW_CH_COUNT
} view_channel;

/* Comparison with the second run (golden). OFF shows run A (or B when show_b is set). */
typedef enum view_compare {
    VIEW_CMP_OFF = 0,
    VIEW_CMP_ABS,    /* |a - b|, heatmap (inferno: 0 is black) */
    VIEW_CMP_REL,    /* |a - b| / max(|a|, |b|), heatmap */
    VIEW_CMP_SIGNED, /* a - b: red positive, blue negative, black zero */
    VIEW_CMP_COUNT
} view_compare;

/* How values become display colours. Zero-initialised means the defaults: RGB, exposure 0,
 * offset 0, sRGB encoding, no false colour, no overlay, no comparison, run A. */
typedef struct view_display {
    view_channel channel;
    float exposure;   /* stops: values are multiplied by 2^exposure */
    float offset;     /* added after exposure (not in comparison modes) */
    int linear;       /* 1: no sRGB encoding (for display-referred buffers) */
    int false_colour; /* 1: turbo map of the value (luminance in RGB mode) */
    int overlay;      /* 1: NaN magenta, +-Inf green, negative blue */
    view_compare compare;
    int show_b;       /* A/B flip: show the second run's buffer */
} view_display;

/* Loud overlay colours (RGBA8). Shown in comparison modes too where a value's class
 * (finite, NaN, +Inf, -Inf) differs between the runs, whatever `overlay` says. */
#define VIEW_COLOUR_NAN 0xff00ffu /* 0xRRGGBB */
#define VIEW_COLOUR_INF 0x00ff00u
#define VIEW_COLOUR_NEG 0x0040ffu

/* Colour maps: t clamped to [0,1] (NaN as 0) -> RGB in [0,1]. Polynomial fits of Google's
 * turbo and matplotlib's inferno. */
void view_turbo(float t, float rgb[3]);
void view_inferno(float t, float rgb[3]);

/* sRGB encoding of a linear value in [0,1] (clamped). */
float view_srgb_encode(float v);

/* The selected components of one pixel (px: nch interleaved floats): returns how many (3 for
 * RGB, 1 otherwise; 0 when the channel does not exist, out then zeros). */
int view_select(const float *px, int nch, view_channel ch, float out[3]);

/* One pixel, normal display: selected components -> RGBA8 (alpha 255). */
void view_map_pixel(const float *px, int nch, const view_display *d, uint8_t rgba[4]);

/* One pixel, comparison mode d->compare != OFF: a and b have nch channels in the same
 * order. */
void view_map_diff(const float *a, const float *b, int nch, const view_display *d, uint8_t rgba[4]);

typedef enum view_render_status {
    VIEW_RENDER_OK = 0,
    VIEW_RENDER_NO_B,      /* compare/flip asked, no second buffer: showing A */
    VIEW_RENDER_MISMATCH   /* second buffer differs in size or channel names: showing A */
} view_render_status;

/* Renders buffer a (or b, or their difference, as d says) into out: a->width*a->height*4
 * bytes, RGBA, top row first. b may be NULL; its channels are matched to a's by name. With
 * show_b and a matching b, b is shown through the normal display. */
view_render_status view_render(const eng_buffer *a, const eng_buffer *b, const view_display *d,
                               uint8_t *out);

/* The range of the selected components over the buffer's finite values, and the exposure and
 * offset that map it to [0,1] (min == max: exposure 0, offset -min). Returns 0 if there is no
 * finite value. */
int view_auto_range(const eng_buffer *a, view_channel ch, float *exposure, float *offset);

/* ---------------------------------------------------------------- state and actions */

typedef enum view_action {
    VIEW_ACT_NONE = 0,
    VIEW_ACT_FRAME_NEXT,
    VIEW_ACT_FRAME_PREV,
    VIEW_ACT_FRAME_FIRST,
    VIEW_ACT_FRAME_LAST,
    VIEW_ACT_PLAY,          /* toggle playback */
    VIEW_ACT_BUFFER_NEXT,
    VIEW_ACT_BUFFER_PREV,
    VIEW_ACT_CH_RGB,
    VIEW_ACT_CH_1,
    VIEW_ACT_CH_2,
    VIEW_ACT_CH_3,
    VIEW_ACT_CH_4,
    VIEW_ACT_CH_LUMA,
    VIEW_ACT_EXPOSURE_UP,   /* +0.5 stop */
    VIEW_ACT_EXPOSURE_DOWN,
    VIEW_ACT_OFFSET_UP,     /* +1/16 */
    VIEW_ACT_OFFSET_DOWN,
    VIEW_ACT_RESET,         /* exposure 0, offset 0, zoom to fit */
    VIEW_ACT_TOGGLE_SRGB,
    VIEW_ACT_TOGGLE_FALSE,
    VIEW_ACT_TOGGLE_OVERLAY,
    VIEW_ACT_FLIP_AB,
    VIEW_ACT_CYCLE_COMPARE, /* off -> abs -> rel -> signed -> off */
    VIEW_ACT_ZOOM_IN,
    VIEW_ACT_ZOOM_OUT,
    VIEW_ACT_HELP,
    VIEW_ACT_TOGGLE_PHOTONS,
    VIEW_ACT_QUIT
} view_action;

typedef struct view_state {
    int frame, frame_count;
    int buffer, buffer_count;
    int channel_count; /* of the current buffer: limits channel selection */
    int has_b;         /* a second run is open: compare and flip allowed */
    view_display d;
    int playing, help, quit;
    int photons;       /* p cycles: 0 none, 1 the frame's photon map as points over eye-sized
                        * buffers, 2 only the photons that contribute to the probed pixel */
    float zoom;        /* 1 = fit to the image area */
} view_state;

/* A state for a run with these counts: frame 0, buffer 0, defaults, zoom 1. */
void view_state_init(view_state *s, int frame_count, int buffer_count, int has_b);

/* Applies one action. Returns 1 if anything visible changed. Frame and buffer moves clamp at
 * the ends (playback wraps: see view_state_tick); selecting a channel the buffer lacks does
 * nothing; compare and flip do nothing without a second run. */
int view_state_apply(view_state *s, view_action a);

/* Playback: advances one frame, wrapping to 0 after the last. Returns 1 if playing. */
int view_state_tick(view_state *s);

/* Sets the current buffer (clamped) and its channel count; a single-channel selection the
 * new buffer lacks falls back to RGB. */
void view_state_set_buffer(view_state *s, int buffer, int channel_count);

/* Sets the frame, clamped to [0, frame_count). */
void view_state_set_frame(view_state *s, int frame);

/* ---------------------------------------------------------------- layout and probe */

typedef struct view_rect {
    int x, y, w, h;
} view_rect;

/* Where an img_w x img_h image goes in `area`: scaled to fit (aspect kept), times zoom,
 * centred on the area's centre. */
view_rect view_fit(view_rect area, int img_w, int img_h, float zoom);

/* The image pixel under screen point (sx, sy) for an image drawn at dst. Returns 0 if the
 * point is outside the image. */
int view_screen_to_pixel(view_rect dst, int img_w, int img_h, int sx, int sy, int *px, int *py);

/* The frame under screen x on a timeline bar spanning `bar` (frames laid out evenly). */
int view_timeline_frame(view_rect bar, int frame_count, int sx);

/* One probe line for buffer b at pixel (x, y): "name  C=value C=value ...", values as %.5g
 * (nan, inf, -inf spelled so), or "name  -" where (x, y) is outside the buffer. Returns out. */
char *view_probe_line(const eng_buffer *b, int x, int y, char *out, size_t n);

/* The selected component (channel ch; RGB and luma: luminance) of buffer b at (x, y), NaN
 * where outside. Used for the across-frames series. */
float view_probe_value(const eng_buffer *b, view_channel ch, int x, int y);

/* ---------------------------------------------------------------- photon points */

/* One photon of a photon map projected into the eye image: (x, y) in image pixels, x right,
 * y down (row 0 at the top), continuous (pixel (i, j) covers [i, i+1) x [j, j+1)). */
typedef struct view_point {
    float x, y;
    int bounce; /* the photon's bounce index: 2 = second surface of its path, 3, ... */
} view_point;

/* The point colour (0xRRGGBB) for a bounce index: 2 (and below) cyan, 3 yellow, 4+ magenta. */
uint32_t view_bounce_colour(int bounce);

/* Projects the photons of `map` (the "photons.map" buffer: one photon a pixel, channels found
 * by name: position.X/Y/Z and bounce; bounce 0 = no photon) into an img_w x img_h eye image
 * through view_proj (world -> clip, column-major GL: element (row r, col c) at [c*4+r]):
 * clip -> NDC, dropping photons with w <= 0 or NDC x or y outside [-1, 1], then
 * x = (ndc.x*0.5+0.5)*img_w, y = (0.5-ndc.y*0.5)*img_h. Writes at most cap points to out in map
 * order and returns how many were written; *total (may be NULL) gets the photons in the map,
 * projected or not. Returns -1 (and *total 0) if map lacks one of those channels. */
int view_project_photons(const eng_buffer *map, const float view_proj[16], int img_w, int img_h,
                         view_point *out, int cap, int *total);

/* ---------------------------------------------------------------- runs (view_run.c) */

typedef struct view_run view_run;

/* Opens a recorded run through replay's reader (manifest validated, frame files present).
 * cache_frames (< 1 means 4) decoded frames are kept, least recently used evicted. On failure
 * *out is NULL and err names the file and the problem. */
eng_result view_run_open(const char *dir, int cache_frames, view_run **out, eng_error *err);
void view_run_close(view_run *r);

int view_run_frame_count(const view_run *r);
/* Buffers of frame f according to the manifest (no decoding). 0 if f is out of range. */
int view_run_buffer_count(const view_run *r, int f);
const char *view_run_buffer_name(const view_run *r, int f, int buffer);
int view_run_buffer_channels(const view_run *r, int f, int buffer);
/* Index of the buffer called name in frame f, or -1. */
int view_run_find(const view_run *r, int f, const char *name);

/* Decodes frame f (or finds it in the cache): *bufs gets *count buffers in manifest order,
 * each with its channels in manifest order. The buffers stay valid until the next
 * view_run_frame call on this run. A frame that fails to decode or verify fails the same way
 * each time it is asked for (the failure is cached), err naming the file. */
eng_result view_run_frame(view_run *r, int f, const eng_buffer **bufs, int *count, eng_error *err);

/* The run's eye resolution (the manifest's "resolution"). */
void view_run_resolution(const view_run *r, int *w, int *h);

/* Frame f's eye camera (world -> clip, column-major) into view_proj. Returns 0 if the frame is
 * out of range or the manifest gave no camera (runs recorded before it did). */
int view_run_camera(const view_run *r, int f, float view_proj[16]);

/* How many frame decodes this run has done (cache misses); for tests. */
int view_run_decodes(const view_run *r);

/* ---------------------------------------------------------------- live view (view_live.c) */

/* A run opened while it is still being recorded (no manifest.json yet) is live: its frames are
 * those whose EXR and record have both landed (rep_run_open_live). 1 while live. */
int view_run_live(const view_run *r);
/* Frames the recording will have (run.json's frame_count; 0 if unknown), or the frame count. */
int view_run_planned_frames(const view_run *r);
/* Picks up the frames that landed since; a run whose manifest has appeared stops being live.
 * Returns the number of new frames, or -1 (err names the file) when a new record is unreadable. */
int view_run_refresh(view_run *r, eng_error *err);

/* The state after the run grew to frame_count frames: a viewer showing the newest frame (or
 * none yet) follows to the new newest one; one that was sent back to an older frame stays
 * there (End follows again). Returns 1 if the shown frame changed. */
int view_state_follow(view_state *s, int frame_count);

/* The frame a viewer opens at: the one asked for (--frame, clamped later), else the newest of a
 * run still being recorded (so that it follows the recording even when several frames landed
 * before the window opened), else 0. asked < 0: none asked for. */
int view_live_start_frame(int asked, int live, int frame_count);

/* Live polling: refreshes r at most every interval_ms (now_ms: a monotonic clock; *last_ms the
 * time of the last refresh, updated), then applies view_state_follow. Returns 1 if anything
 * visible changed (frames added); a refresh error is told once through err_out (may be NULL). */
int view_live_poll(view_run *r, view_state *s, unsigned now_ms, unsigned *last_ms, unsigned interval_ms,
                   char *err_out, size_t err_n);

/* ---------------------------------------------------------------- ꟻLIP heat map (view_flip.c) */

/* The last ꟻLIP map computed (per frame and buffer: recomputed only when either changes). */
typedef struct view_flip_cache {
    int frame;
    char name[256];
    float *map;
    int w, h;
    double mean, p99;
    int valid;
} view_flip_cache;

/* The ꟻLIP heat map (flip.h: *.display LDR, *.radiance HDR over the default pinned exposure
 * range) of a against b into out (a->width*a->height RGBA). Returns 1 when drawn, 0 when a is no
 * colour buffer or b is missing or of another size (out untouched). */
int view_flip_render(view_flip_cache *c, int frame, const eng_buffer *a, const eng_buffer *b, uint8_t *out);
void view_flip_cache_free(view_flip_cache *c);
/* ---------------------------------------------------------------- pixel lineage (view_lineage.c) */

/* The eye pixel a probe at (px, py) of the shown buffer stands for: the same pixel on eye-sized
 * buffers, the scaled one on subsampled levels. Returns 0 for light-space buffers (shadow,
 * lightgbuffer, bounce), photon maps and probes outside the buffer. */
int view_lineage_eye_pixel(const eng_buffer *shown, int eye_w, int eye_h, int px, int py, int *ex, int *ey);

/* The probe panel's lines for a pixel's lineage (replay/compare/lineage.h): the shadow test per light
 * (map, texel, stored against compared value, verdict), the photons that contribute and their
 * sum, then every buffer at its own coordinate. Writes at most max lines; returns how many. */
#define VIEW_LINEAGE_LINE 256
int view_lineage_lines(const lin_result *r, char (*out)[VIEW_LINEAGE_LINE], int max);

/* The photons that contribute to the pixel projected into the eye image as view_project_photons
 * does, with weight[i] = the luminance of point i's contribution over the largest one (0..1).
 * Returns the points written (at most cap). */
int view_lineage_points(const lin_result *r, const float view_proj[16], int img_w, int img_h, view_point *out,
                        float *weight, int cap);

/* The point colour (0xRRGGBB) for a contribution weight in 0..1: dark red to white. */
uint32_t view_contribution_colour(float t);

#ifdef __cplusplus
}
#endif

#endif
