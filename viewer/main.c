/* main.c — ispm-view, the SDL2 front end of the viewer: opens a recorded run (and optionally a
 * golden or second run), maps keys and mouse to view_action values, and draws what
 * view_model.c computes.
 *
 * The window has four fixed regions, which the end-to-end test relies on: a buffer list on
 * the left (LEFT_W pixels), the pixel probe on the right (RIGHT_W), a timeline bar and a
 * status line at the bottom (BOTTOM_H), and the image in what remains, scaled to fit and
 * zoomed about its centre (mouse wheel, z/x), panned by dragging with the right button. The
 * program only redraws after an event or a playback tick. Frames are decoded when first
 * shown (view_run.c caches a few). Text is SDL2_ttf with DejaVu Sans Mono (ISPM_VIEW_FONT in
 * the environment overrides the path found at build time).
 *
 * Exit codes: 0 closed normally, 1 no window could be opened (no display) or SDL failed,
 * 2 bad arguments or an unreadable run (one line on stderr naming the file).
 */
#include <SDL.h>
#include <SDL_ttf.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "oiio_shim.h"
#include "view_model.h"

enum { LEFT_W = 260, RIGHT_W = 360, BOTTOM_H = 48, TIMELINE_H = 16, FONT_PT = 12 };
enum { SERIES_MAX = 64 }; /* frames around the current one in the across-frames series */

static const char *const HELP[] = {
    "ispm-view keys",
    "",
    "Left/Right      previous/next frame",
    "Home/End        first/last frame",
    "Space           play/pause",
    "Up/Down, PgUp/PgDn  previous/next buffer",
    "0               RGB",
    "1 2 3 4         one channel",
    "5 or l          luminance",
    "+/-             exposure (half stops)",
    "] / [           offset up/down",
    "a               auto range (min..max to 0..1)",
    "r               reset exposure, offset, zoom",
    "s               sRGB display on/off",
    "f               false colour (turbo)",
    "n               NaN/Inf/negative overlay",
    "b or Tab        A/B flip (second run)",
    "d               compare: abs / rel / signed diff",
    "wheel, z/x      zoom in/out; right-drag pans",
    "click image     pin pixel for the series",
    "click timeline  go to frame",
    "p               photons as points over eye-sized buffers:",
    "                bounce 2 cyan, 3 yellow, 4+ magenta; again:",
    "                only the probed pixel's, red to white by share",
    "e               FLIP heat map vs the second run (colour)",
    "h or F1         this help; q or Esc quits",
};

typedef struct app {
    view_run *a, *b;
    const char *a_dir, *b_dir;
    view_state s;
    SDL_Window *win;
    SDL_Renderer *ren;
    TTF_Font *font;
    int line_h, char_w;
    SDL_Texture *tex;
    int tex_w, tex_h;
    uint8_t *pixels;
    size_t pixels_cap;
    int mouse_x, mouse_y;
    int hover, hover_x, hover_y;   /* pixel under the cursor */
    int pinned, pin_x, pin_y;      /* clicked pixel: the series follows it */
    int pan_x, pan_y, dragging;
    char buffer_name[256];         /* kept across frames: a frame change keeps the buffer */
    float series[SERIES_MAX];
    int series_first, series_count, series_valid;
    view_point *points;            /* photon points of the shown frame */
    SDL_Rect *rects;
    size_t points_cap;
    int flip_view;                 /* e: ꟻLIP heat map instead of the image (view_flip.c) */
    view_flip_cache flip;
    unsigned live_last;            /* live view (view_live.c): last look for new frames */
    char live_err[512];
    /* Pixel lineage (view_lineage.c): the run's manifest, the probed pixel's lineage this
     * redraw, the contributing photons' weights, and where --dump-probe writes it. */
    lin_manifest lm;
    int lm_ok;
    lin_result lr;
    int lr_ok, lr_frame, lr_x, lr_y, dumped_frame, dumped_x, dumped_y;
    float *weights;
    size_t weights_cap;
    const char *probe_dump;
} app;

static void usage(FILE *f)
{
    fprintf(f, "usage: ispm-view RUN [--golden DIR] [--frame N] [--buffer NAME] [--size WxH] [--list]\n"
               "                [--dump-probe FILE]\n"
               "Interactive viewer for a recorded run: every buffer of every frame, channels,\n"
               "exposure, false colour, NaN/Inf overlay, comparison with a golden or second run\n"
               "(A/B flip, absolute/relative/signed difference), pixel probe. Press h in the\n"
               "window for the keys. --list prints frame 0's buffers and exits. The probe shows the\n"
               "pixel's lineage (every buffer at its own coordinate, shadow texels through the light's\n"
               "matrices); --dump-probe FILE also writes it to FILE whenever the probed pixel changes.\n"
               "A run still being recorded opens on its newest frame (without --frame) and follows it.\n"
               "Exit: 0 ok, 1 no display, 2 bad arguments or unreadable run.\n");
}

/* ---------------------------------------------------------------- drawing helpers */

static void fill(app *ap, int x, int y, int w, int h, uint32_t rgb, uint8_t alpha)
{
    SDL_SetRenderDrawColor(ap->ren, (uint8_t)(rgb >> 16), (uint8_t)(rgb >> 8), (uint8_t)rgb, alpha);
    SDL_Rect r = {x, y, w, h};
    SDL_RenderFillRect(ap->ren, &r);
}

/* Draws one line of text, clipped to max_w pixels (0: no limit). */
static void text(app *ap, int x, int y, uint32_t rgb, int max_w, const char *s)
{
    if (!s || !*s)
        return;
    SDL_Color c = {(uint8_t)(rgb >> 16), (uint8_t)(rgb >> 8), (uint8_t)rgb, 255};
    SDL_Surface *surf = TTF_RenderUTF8_Blended(ap->font, s, c);
    if (!surf)
        return;
    SDL_Texture *t = SDL_CreateTextureFromSurface(ap->ren, surf);
    if (t) {
        int w = surf->w;
        if (max_w > 0 && w > max_w)
            w = max_w;
        SDL_Rect src = {0, 0, w, surf->h}, dst = {x, y, w, surf->h};
        SDL_RenderCopy(ap->ren, t, &src, &dst);
        SDL_DestroyTexture(t);
    }
    SDL_FreeSurface(surf);
}

/* Draws s word-wrapped into width w starting at *y (advanced); stops at y_max. */
static void text_wrapped(app *ap, int x, int *y, int w, int y_max, uint32_t rgb, const char *s)
{
    int max_chars = w / (ap->char_w > 0 ? ap->char_w : 7);
    if (max_chars < 8)
        max_chars = 8;
    char line[512];
    size_t len = strlen(s), pos = 0;
    while (pos < len && *y + ap->line_h <= y_max) {
        size_t n = len - pos;
        if (n > (size_t)max_chars) {
            n = (size_t)max_chars;
            while (n > 1 && s[pos + n] != ' ')
                n--;
            if (n <= 1)
                n = (size_t)max_chars;
        }
        if (n >= sizeof line)
            n = sizeof line - 1;
        memcpy(line, s + pos, n);
        line[n] = 0;
        text(ap, x, *y, rgb, w, line);
        *y += ap->line_h;
        pos += n;
        while (pos < len && s[pos] == ' ')
            pos++;
    }
}

static view_rect image_area(app *ap)
{
    int w, h;
    SDL_GetRendererOutputSize(ap->ren, &w, &h);
    view_rect r = {LEFT_W, 0, w - LEFT_W - RIGHT_W, h - BOTTOM_H};
    if (r.w < 16)
        r.w = 16;
    if (r.h < 16)
        r.h = 16;
    return r;
}

static view_rect timeline_bar(app *ap)
{
    int w, h;
    SDL_GetRendererOutputSize(ap->ren, &w, &h);
    view_rect r = {8, h - BOTTOM_H + 4, w - 16, TIMELINE_H};
    return r;
}

/* ---------------------------------------------------------------- state helpers */

/* Points the state at this frame's buffer list, keeping the buffer by name. */
static void sync_buffer(app *ap)
{
    int f = ap->s.frame;
    ap->s.buffer_count = view_run_buffer_count(ap->a, f);
    int idx = view_run_find(ap->a, f, ap->buffer_name);
    if (idx < 0)
        idx = ap->s.buffer < ap->s.buffer_count ? ap->s.buffer : 0;
    view_state_set_buffer(&ap->s, idx, view_run_buffer_channels(ap->a, f, idx));
    const char *name = view_run_buffer_name(ap->a, f, ap->s.buffer);
    snprintf(ap->buffer_name, sizeof ap->buffer_name, "%s", name ? name : "");
}

/* The second run's buffer called name in frame f, or NULL. Valid until the next call. */
static const eng_buffer *b_buffer(app *ap, int f, const char *name, const char **why)
{
    *why = NULL;
    if (!ap->b)
        return NULL;
    if (f >= view_run_frame_count(ap->b)) {
        *why = "second run has no such frame";
        return NULL;
    }
    int j = view_run_find(ap->b, f, name);
    if (j < 0) {
        *why = "second run lacks this buffer";
        return NULL;
    }
    const eng_buffer *bufs;
    int count;
    eng_error err;
    if (view_run_frame(ap->b, f, &bufs, &count, &err) != ENG_OK) {
        *why = "second run's frame is unreadable";
        return NULL;
    }
    return j < count ? &bufs[j] : NULL;
}

static void compute_series(app *ap)
{
    ap->series_valid = 1;
    ap->series_count = 0;
    if (!ap->pinned)
        return;
    int n = ap->s.frame_count, first = ap->s.frame - SERIES_MAX / 2;
    if (first + SERIES_MAX > n)
        first = n - SERIES_MAX;
    if (first < 0)
        first = 0;
    ap->series_first = first;
    for (int f = first; f < n && f < first + SERIES_MAX; f++) {
        const eng_buffer *bufs;
        int count;
        eng_error err;
        float v = NAN;
        int j = view_run_find(ap->a, f, ap->buffer_name);
        if (j >= 0 && view_run_frame(ap->a, f, &bufs, &count, &err) == ENG_OK && j < count)
            v = view_probe_value(&bufs[j], ap->s.d.channel, ap->pin_x, ap->pin_y);
        ap->series[ap->series_count++] = v;
    }
}

/* ---------------------------------------------------------------- drawing */

static const char *channel_label(const view_state *s, const eng_buffer *a, char *buf, size_t n)
{
    switch (s->d.channel) {
    case VIEW_CH_RGB: return "RGB";
    case VIEW_CH_LUMA: return "luminance";
    default: {
        int k = (int)s->d.channel - (int)VIEW_CH_1;
        snprintf(buf, n, "channel %d (%s)", k + 1, a && k < a->channel_count ? a->channels[k] : "?");
        return buf;
    }
    }
}

static void draw_left(app *ap, int h)
{
    fill(ap, 0, 0, LEFT_W, h - BOTTOM_H, 0x202020, 255);
    int y = 4;
    char line[512];
    snprintf(line, sizeof line, "A: %s", ap->a_dir);
    text(ap, 6, y, 0xffffff, LEFT_W - 10, line);
    y += ap->line_h;
    if (ap->b_dir) {
        snprintf(line, sizeof line, "B: %s", ap->b_dir);
        text(ap, 6, y, 0xc0c0ff, LEFT_W - 10, line);
        y += ap->line_h;
    }
    snprintf(line, sizeof line, "frame %d of 0..%d", ap->s.frame, ap->s.frame_count - 1);
    text(ap, 6, y, 0xffffff, LEFT_W - 10, line);
    y += ap->line_h + 4;
    int rows = (h - BOTTOM_H - y) / ap->line_h;
    int first = 0;
    if (rows > 0 && ap->s.buffer >= rows)
        first = ap->s.buffer - rows + 1;
    for (int i = first; i < ap->s.buffer_count && y + ap->line_h <= h - BOTTOM_H; i++) {
        const char *name = view_run_buffer_name(ap->a, ap->s.frame, i);
        if (i == ap->s.buffer)
            fill(ap, 2, y, LEFT_W - 4, ap->line_h, 0x3060a0, 255);
        text(ap, 10, y, i == ap->s.buffer ? 0xffffff : 0xb0b0b0, LEFT_W - 14, name);
        y += ap->line_h;
    }
}

static void draw_series(app *ap, int x, int y, int w, int h)
{
    fill(ap, x, y, w, h, 0x101010, 255);
    float lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < ap->series_count; i++)
        if (isfinite(ap->series[i])) {
            lo = fminf(lo, ap->series[i]);
            hi = fmaxf(hi, ap->series[i]);
        }
    if (!(lo <= hi))
        return;
    float span = hi > lo ? hi - lo : 1.0f;
    int n = ap->series_count, prev_x = -1, prev_y = -1;
    for (int i = 0; i < n; i++) {
        float v = ap->series[i];
        int px = x + (n > 1 ? i * (w - 1) / (n - 1) : w / 2);
        if (!isfinite(v)) {
            fill(ap, px - 1, y, 3, h, 0xff00ff, 255);
            prev_x = -1;
            continue;
        }
        int py = y + h - 1 - (int)((v - lo) / span * (float)(h - 1));
        SDL_SetRenderDrawColor(ap->ren, 0x60, 0xd0, 0xff, 255);
        if (prev_x >= 0)
            SDL_RenderDrawLine(ap->ren, prev_x, prev_y, px, py);
        if (ap->series_first + i == ap->s.frame)
            fill(ap, px - 2, py - 2, 5, 5, 0xffff00, 255);
        prev_x = px;
        prev_y = py;
    }
    char line[128];
    snprintf(line, sizeof line, "min %.5g  max %.5g", (double)lo, (double)hi);
    text(ap, x, y + h + 2, 0x909090, w, line);
}

/* The probed pixel's lineage in the probe panel from y; returns the next line's y. */
static int draw_lineage_lines(app *ap, int x0, int y, int y_max)
{
    static char lines[512][VIEW_LINEAGE_LINE];
    int n = view_lineage_lines(&ap->lr, lines, 512);
    for (int i = 0; i < n && y + ap->line_h <= y_max; i++)
        text_wrapped(ap, x0 + 6, &y, RIGHT_W - 12, y_max, i < ap->lr.shadow_count + 1 ? 0x80ffc0 : 0xd0d0d0,
                     lines[i]);
    return y;
}

/* Computes ap->lr, the lineage of the eye pixel the probe (hover, else pin) stands for on the
 * shown buffer a, and writes it to --dump-probe's file when the pixel changed. */
static void update_lineage(app *ap, const eng_buffer *bufs, int count, const eng_buffer *a)
{
    lin_result_free(&ap->lr);
    ap->lr_ok = 0;
    int px = ap->hover ? ap->hover_x : ap->pin_x, py = ap->hover ? ap->hover_y : ap->pin_y;
    int eye_w, eye_h;
    view_run_resolution(ap->a, &eye_w, &eye_h);
    if (!ap->lm_ok || !a || !(ap->hover || ap->pinned) || ap->s.frame >= ap->lm.frame_count ||
        !view_lineage_eye_pixel(a, eye_w, eye_h, px, py, &ap->lr_x, &ap->lr_y))
        return;
    lin_frame fr = {bufs, count, &ap->lm, &ap->lm.frames[ap->s.frame]};
    eng_error err;
    if (lin_pixel(&fr, ap->lr_x, ap->lr_y, &ap->lr, &err) != ENG_OK)
        return;
    ap->lr_ok = 1;
    ap->lr_frame = ap->s.frame;
    if (!ap->probe_dump || (ap->dumped_frame == ap->lr_frame && ap->dumped_x == ap->lr_x && ap->dumped_y == ap->lr_y))
        return;
    static char lines[512][VIEW_LINEAGE_LINE];
    int n = view_lineage_lines(&ap->lr, lines, 512);
    FILE *f = fopen(ap->probe_dump, "w");
    if (!f)
        return;
    fprintf(f, "frame %d eye %d %d\n", ap->lr_frame, ap->lr_x, ap->lr_y);
    for (int i = 0; i < ap->lr.shadow_count; i++) {
        const lin_shadow *sh = &ap->lr.shadows[i];
        fprintf(f, "shadow %d texel %d %d stored %.9g compared %.9g distance %.9g tolerance %.9g lit %d\n", sh->light,
                sh->texel[0], sh->texel[1], (double)sh->stored, (double)sh->compared, (double)sh->distance,
                (double)sh->tolerance, sh->lit);
    }
    fprintf(f, "photons %d of %d\n", ap->lr.photon_count, ap->lr.map_photons);
    for (int i = 0; i < n; i++)
        fprintf(f, "%s\n", lines[i]);
    fclose(f);
    ap->dumped_frame = ap->lr_frame;
    ap->dumped_x = ap->lr_x;
    ap->dumped_y = ap->lr_y;
}

static void draw_right(app *ap, int w, int h, const eng_buffer *bufs, int count,
                       const eng_buffer *bcur)
{
    int x0 = w - RIGHT_W, y = 4, y_max = h - BOTTOM_H;
    fill(ap, x0, 0, RIGHT_W, y_max, 0x202020, 255);
    char line[1024];
    int px = ap->hover ? ap->hover_x : ap->pin_x, py = ap->hover ? ap->hover_y : ap->pin_y;
    int have = ap->hover || ap->pinned;
    int series_h = 70, list_max = y_max - series_h - 4 * ap->line_h;
    if (!have) {
        text_wrapped(ap, x0 + 6, &y, RIGHT_W - 12, list_max, 0xb0b0b0,
                     "probe: move the cursor over the image");
    } else {
        snprintf(line, sizeof line, "probe (%d, %d)%s", px, py, ap->hover ? "" : " pinned");
        if (ap->lr_ok)
            snprintf(line + strlen(line), sizeof line - strlen(line), "  eye (%d, %d)", ap->lr_x, ap->lr_y);
        text(ap, x0 + 6, y, 0xffffff, RIGHT_W - 12, line);
        y += ap->line_h;
        if (ap->lr_ok)
            y = draw_lineage_lines(ap, x0, y, list_max);
        for (int i = 0; i < count && !ap->lr_ok && y + ap->line_h <= list_max; i++) {
            view_probe_line(&bufs[i], px, py, line, sizeof line);
            text_wrapped(ap, x0 + 6, &y, RIGHT_W - 12, list_max,
                         i == ap->s.buffer ? 0xffff80 : 0xd0d0d0, line);
        }
        if (bcur && y + ap->line_h <= list_max) {
            char bl[1024] = "B: ";
            view_probe_line(bcur, px, py, bl + 3, sizeof bl - 3);
            text_wrapped(ap, x0 + 6, &y, RIGHT_W - 12, list_max, 0xc0c0ff, bl);
        }
    }
    y = y_max - series_h - 3 * ap->line_h;
    if (ap->pinned) {
        snprintf(line, sizeof line, "%s at (%d, %d), frames %d..%d", ap->buffer_name, ap->pin_x,
                 ap->pin_y, ap->series_first, ap->series_first + ap->series_count - 1);
        text(ap, x0 + 6, y, 0xffffff, RIGHT_W - 12, line);
        draw_series(ap, x0 + 6, y + ap->line_h + 2, RIGHT_W - 12, series_h);
    } else {
        text(ap, x0 + 6, y, 0x909090, RIGHT_W - 12, "click the image: value across frames");
    }
}

static void draw_bottom(app *ap, int w, int h, const eng_buffer *a, const char *note)
{
    fill(ap, 0, h - BOTTOM_H, w, BOTTOM_H, 0x181818, 255);
    view_rect bar = timeline_bar(ap);
    fill(ap, bar.x, bar.y, bar.w, bar.h, 0x404040, 255);
    int n = ap->s.frame_count;
    if (n > 0) {
        int x0 = bar.x + (int)((long long)ap->s.frame * bar.w / n);
        int x1 = bar.x + (int)((long long)(ap->s.frame + 1) * bar.w / n);
        fill(ap, x0, bar.y, x1 - x0 > 2 ? x1 - x0 : 2, bar.h, 0x40a0ff, 255);
        if (bar.w / n >= 4)
            for (int f = 1; f < n; f++)
                fill(ap, bar.x + (int)((long long)f * bar.w / n), bar.y, 1, bar.h, 0x202020, 255);
    }
    char line[1024], ch[64];
    static const char *const cmp[] = {"", "  | abs error", "  | rel error", "  | signed diff"};
    snprintf(line, sizeof line, "frame %d/%d  %s %dx%d  %s  exp %+.1f off %+.3f%s%s%s%s%s%s%s",
             ap->s.frame, n - 1, ap->buffer_name, a ? a->width : 0, a ? a->height : 0,
             channel_label(&ap->s, a, ch, sizeof ch), (double)ap->s.d.exposure,
             (double)ap->s.d.offset, ap->s.d.linear ? "  linear" : "  sRGB",
             ap->s.d.false_colour ? "  false-colour" : "", ap->s.d.overlay ? "  overlay" : "",
             cmp[ap->s.d.compare], ap->s.d.show_b && !ap->s.d.compare ? "  | showing B" : "",
             ap->s.playing ? "  | playing" : "", note ? note : "");
    text(ap, 8, bar.y + bar.h + 4, 0xe0e0e0, w - 16, line);
}

static void draw_help(app *ap, int w, int h)
{
    int n = (int)(sizeof HELP / sizeof HELP[0]);
    int longest = 0;
    for (int i = 0; i < n; i++)
        if ((int)strlen(HELP[i]) > longest)
            longest = (int)strlen(HELP[i]);
    int bw = longest * ap->char_w + 24, bh = n * ap->line_h + 20;
    int x = (w - bw) / 2, y = (h - bh) / 2;
    SDL_SetRenderDrawBlendMode(ap->ren, SDL_BLENDMODE_BLEND);
    fill(ap, x, y, bw, bh, 0x000000, 235);
    SDL_SetRenderDrawBlendMode(ap->ren, SDL_BLENDMODE_NONE);
    for (int i = 0; i < n; i++)
        text(ap, x + 12, y + 10 + i * ap->line_h, i == 0 ? 0xffff80 : 0xffffff, bw - 24, HELP[i]);
}

/* p pressed twice: only the photons that contribute to the probed pixel (ap->lr), 5x5 points
 * coloured by their share, largest drawn last; the count goes to note. ap->points holds at
 * least the map's photons. */
static void draw_contributors(app *ap, const float vp[16], int eye_w, int eye_h, const eng_buffer *a,
                              view_rect dst, char *note, size_t n)
{
    if (!ap->lr_ok || !ap->lr.has_photons) {
        snprintf(note, n, "  | photons of a pixel: %s",
                 !ap->lr_ok ? "probe a surface pixel (hover or click)"
                            : ap->lr.why ? ap->lr.why : "none");
        return;
    }
    if (ap->weights_cap < ap->points_cap) {
        free(ap->weights);
        ap->weights = malloc(ap->points_cap * sizeof *ap->weights);
        ap->weights_cap = ap->weights ? ap->points_cap : 0;
    }
    int cap = (int)(ap->weights_cap < ap->points_cap ? ap->weights_cap : ap->points_cap);
    int shown = view_lineage_points(&ap->lr, vp, eye_w, eye_h, ap->points, ap->weights, cap);
    for (int i = 0; i < shown; i++) {
        int sx = dst.x + (int)floorf(ap->points[i].x * (float)dst.w / (float)a->width);
        int sy = dst.y + (int)floorf(ap->points[i].y * (float)dst.h / (float)a->height);
        uint32_t c = view_contribution_colour(ap->weights[i]);
        fill(ap, sx - 2, sy - 2, 5, 5, c, 255);
    }
    snprintf(note, n, "  | photons of (%d, %d): %d of %d contribute (%d in view)", ap->lr_x, ap->lr_y,
             ap->lr.photon_count, ap->lr.map_photons, shown);
}

/* Draws the frame's photon map as points over the image a drawn at dst (clip already set),
 * and appends the photon count, or why there are no points, to note. */
static void draw_photons(app *ap, const eng_buffer *bufs, int count, const eng_buffer *a,
                         view_rect dst, char *note, size_t n)
{
    size_t len = strlen(note);
    if (len >= n)
        return;
    int f = ap->s.frame, j = view_run_find(ap->a, f, "photons.map"), eye_w, eye_h;
    float vp[16];
    view_run_resolution(ap->a, &eye_w, &eye_h);
    if (j < 0 || j >= count) {
        snprintf(note + len, n - len, "  | photons: this frame has no photons.map");
        return;
    }
    if (!view_run_camera(ap->a, f, vp)) {
        snprintf(note + len, n - len, "  | photons: the manifest gives no camera for this frame");
        return;
    }
    if (a->width != eye_w || a->height != eye_h) {
        snprintf(note + len, n - len, "  | photons are drawn over eye-sized (%dx%d) buffers", eye_w,
                 eye_h);
        return;
    }
    const eng_buffer *map = &bufs[j];
    size_t need = (size_t)map->width * (size_t)map->height;
    if (need > ap->points_cap) {
        free(ap->points);
        free(ap->rects);
        ap->points = malloc(need * sizeof *ap->points);
        ap->rects = malloc(need * sizeof *ap->rects);
        ap->points_cap = ap->points && ap->rects ? need : 0;
    }
    if (ap->s.photons == 2) {
        draw_contributors(ap, vp, eye_w, eye_h, a, dst, note + len, n - len);
        return;
    }
    int total = 0;
    int shown = view_project_photons(map, vp, eye_w, eye_h, ap->points, (int)ap->points_cap, &total);
    if (shown < 0) {
        snprintf(note + len, n - len, "  | photons: photons.map lacks position or bounce channels");
        return;
    }
    /* One batch per colour: bounce 2, 3, 4+. Points are 3x3 screen pixels. */
    for (int cls = 2; cls <= 4; cls++) {
        int k = 0;
        for (int i = 0; i < shown; i++) {
            int b = ap->points[i].bounce;
            if ((b <= 2 ? 2 : b >= 4 ? 4 : 3) != cls)
                continue;
            int sx = dst.x + (int)floorf(ap->points[i].x * (float)dst.w / (float)a->width);
            int sy = dst.y + (int)floorf(ap->points[i].y * (float)dst.h / (float)a->height);
            ap->rects[k++] = (SDL_Rect){sx - 1, sy - 1, 3, 3};
        }
        uint32_t c = view_bounce_colour(cls);
        SDL_SetRenderDrawColor(ap->ren, (uint8_t)(c >> 16), (uint8_t)(c >> 8), (uint8_t)c, 255);
        if (k > 0)
            SDL_RenderFillRects(ap->ren, ap->rects, k);
    }
    snprintf(note + len, n - len, "  | photons %d (%d in view)", total, shown);
}

/* With e on: the ꟻLIP heat map replaces the image in ap->pixels; the status line says its mean. */
static void flip_note(app *ap, const eng_buffer *a, const eng_buffer *b, char *note, size_t n)
{
    if (!ap->flip_view)
        return;
    size_t len = strlen(note);
    if (view_flip_render(&ap->flip, ap->s.frame, a, b, ap->pixels))
        snprintf(note + len, n - len, "  | FLIP mean %.4f p99 %.4f", ap->flip.mean, ap->flip.p99);
    else
        snprintf(note + len, n - len, "  | FLIP: colour buffers against a second run only");
}

/* A run still being recorded: how far it has got, and a record that could not be read. */
static void live_note(app *ap, char *note, size_t n)
{
    size_t len = strlen(note);
    if (view_run_live(ap->a))
        snprintf(note + len, n - len, "  | live: %d of %d frames%s%s", view_run_frame_count(ap->a),
                 view_run_planned_frames(ap->a), ap->live_err[0] ? ": " : "", ap->live_err);
}

static void redraw(app *ap)
{
    int w, h;
    SDL_GetRendererOutputSize(ap->ren, &w, &h);
    SDL_SetRenderDrawColor(ap->ren, 0x30, 0x30, 0x30, 255);
    SDL_RenderClear(ap->ren);

    const eng_buffer *bufs = NULL, *a = NULL, *bcur = NULL;
    int count = 0;
    eng_error err;
    const char *why = NULL;
    char note[1200] = "";
    view_rect area = image_area(ap);
    lin_result_free(&ap->lr); /* it borrows the frame's buffers: recomputed below */
    ap->lr_ok = 0;
    if (!ap->series_valid)
        compute_series(ap);
    if (view_run_frame(ap->a, ap->s.frame, &bufs, &count, &err) != ENG_OK) {
        int y = area.y + 10;
        text_wrapped(ap, area.x + 10, &y, area.w - 20, area.y + area.h, 0xff6060, err.msg);
        bufs = NULL;
        count = 0;
    } else if (ap->s.buffer < count) {
        a = &bufs[ap->s.buffer];
        bcur = b_buffer(ap, ap->s.frame, a->name, &why);
        size_t need = (size_t)a->width * (size_t)a->height * 4;
        if (need > ap->pixels_cap) {
            free(ap->pixels);
            ap->pixels = malloc(need);
            ap->pixels_cap = ap->pixels ? need : 0;
        }
        if (ap->tex && (ap->tex_w != a->width || ap->tex_h != a->height)) {
            SDL_DestroyTexture(ap->tex);
            ap->tex = NULL;
        }
        if (!ap->tex) {
            ap->tex = SDL_CreateTexture(ap->ren, SDL_PIXELFORMAT_RGBA32, SDL_TEXTUREACCESS_STREAMING,
                                        a->width, a->height);
            ap->tex_w = a->width;
            ap->tex_h = a->height;
        }
        if (ap->pixels && ap->tex) {
            view_render_status st = view_render(a, bcur, &ap->s.d, ap->pixels);
            if (st == VIEW_RENDER_NO_B)
                snprintf(note, sizeof note, "  | %s: showing A", why ? why : "no second run");
            else if (st == VIEW_RENDER_MISMATCH)
                snprintf(note, sizeof note, "  | B differs in size or channels: showing A");
            flip_note(ap, a, bcur, note, sizeof note);
            SDL_UpdateTexture(ap->tex, NULL, ap->pixels, a->width * 4);
            view_rect dst = view_fit(area, a->width, a->height, ap->s.zoom);
            dst.x += ap->pan_x;
            dst.y += ap->pan_y;
            SDL_Rect clip = {area.x, area.y, area.w, area.h};
            SDL_Rect d = {dst.x, dst.y, dst.w, dst.h};
            SDL_RenderSetClipRect(ap->ren, &clip);
            SDL_RenderCopy(ap->ren, ap->tex, NULL, &d);
            if (ap->pinned) {
                int cx = dst.x + (int)((ap->pin_x + 0.5) * dst.w / a->width);
                int cy = dst.y + (int)((ap->pin_y + 0.5) * dst.h / a->height);
                fill(ap, cx - 6, cy, 13, 1, 0xffff00, 255);
                fill(ap, cx, cy - 6, 1, 13, 0xffff00, 255);
            }
            update_lineage(ap, bufs, count, a);
            if (ap->s.photons)
                draw_photons(ap, bufs, count, a, dst, note, sizeof note);
            SDL_RenderSetClipRect(ap->ren, NULL);
        }
    }
    live_note(ap, note, sizeof note);
    draw_left(ap, h);
    draw_right(ap, w, h, bufs, count, bcur);
    draw_bottom(ap, w, h, a, note);
    if (ap->s.help)
        draw_help(ap, w, h);
    SDL_RenderPresent(ap->ren);
}

/* Updates the hovered pixel from the mouse position. */
static void update_hover(app *ap)
{
    ap->hover = 0;
    const eng_buffer *bufs;
    int count;
    if (view_run_frame(ap->a, ap->s.frame, &bufs, &count, NULL) != ENG_OK || ap->s.buffer >= count)
        return;
    const eng_buffer *a = &bufs[ap->s.buffer];
    view_rect area = image_area(ap);
    if (ap->mouse_x < area.x || ap->mouse_x >= area.x + area.w || ap->mouse_y < area.y ||
        ap->mouse_y >= area.y + area.h)
        return;
    view_rect dst = view_fit(area, a->width, a->height, ap->s.zoom);
    dst.x += ap->pan_x;
    dst.y += ap->pan_y;
    ap->hover = view_screen_to_pixel(dst, a->width, a->height, ap->mouse_x, ap->mouse_y,
                                     &ap->hover_x, &ap->hover_y);
}

/* ---------------------------------------------------------------- events */

static view_action key_action(const SDL_Keysym *k)
{
    switch (k->sym) {
    case SDLK_RIGHT: return VIEW_ACT_FRAME_NEXT;
    case SDLK_LEFT: return VIEW_ACT_FRAME_PREV;
    case SDLK_HOME: return VIEW_ACT_FRAME_FIRST;
    case SDLK_END: return VIEW_ACT_FRAME_LAST;
    case SDLK_SPACE: return VIEW_ACT_PLAY;
    case SDLK_DOWN: case SDLK_PAGEDOWN: return VIEW_ACT_BUFFER_NEXT;
    case SDLK_UP: case SDLK_PAGEUP: return VIEW_ACT_BUFFER_PREV;
    case SDLK_0: case SDLK_KP_0: return VIEW_ACT_CH_RGB;
    case SDLK_1: case SDLK_KP_1: return VIEW_ACT_CH_1;
    case SDLK_2: case SDLK_KP_2: return VIEW_ACT_CH_2;
    case SDLK_3: case SDLK_KP_3: return VIEW_ACT_CH_3;
    case SDLK_4: case SDLK_KP_4: return VIEW_ACT_CH_4;
    case SDLK_5: case SDLK_KP_5: case SDLK_l: return VIEW_ACT_CH_LUMA;
    case SDLK_PLUS: case SDLK_EQUALS: case SDLK_KP_PLUS: return VIEW_ACT_EXPOSURE_UP;
    case SDLK_MINUS: case SDLK_KP_MINUS: return VIEW_ACT_EXPOSURE_DOWN;
    case SDLK_RIGHTBRACKET: return VIEW_ACT_OFFSET_UP;
    case SDLK_LEFTBRACKET: return VIEW_ACT_OFFSET_DOWN;
    case SDLK_r: return VIEW_ACT_RESET;
    case SDLK_s: return VIEW_ACT_TOGGLE_SRGB;
    case SDLK_f: return VIEW_ACT_TOGGLE_FALSE;
    case SDLK_n: return VIEW_ACT_TOGGLE_OVERLAY;
    case SDLK_b: case SDLK_TAB: return VIEW_ACT_FLIP_AB;
    case SDLK_d: return VIEW_ACT_CYCLE_COMPARE;
    case SDLK_z: return VIEW_ACT_ZOOM_IN;
    case SDLK_x: return VIEW_ACT_ZOOM_OUT;
    case SDLK_h: case SDLK_F1: return VIEW_ACT_HELP;
    case SDLK_p: return VIEW_ACT_TOGGLE_PHOTONS;
    case SDLK_q: case SDLK_ESCAPE: return VIEW_ACT_QUIT;
    default: return VIEW_ACT_NONE;
    }
}

/* Handles one event; returns 1 if the window needs a redraw. */
static int handle(app *ap, const SDL_Event *ev)
{
    int old_frame = ap->s.frame, old_buffer = ap->s.buffer;
    view_channel old_ch = ap->s.d.channel;
    int dirty = 0;
    switch (ev->type) {
    case SDL_QUIT: ap->s.quit = 1; return 0;
    case SDL_WINDOWEVENT: dirty = 1; break;
    case SDL_KEYDOWN: {
        if (ev->key.keysym.sym == SDLK_e) {
            ap->flip_view = !ap->flip_view;
            dirty = 1;
            break;
        }
        if (ev->key.keysym.sym == SDLK_a) {
            const eng_buffer *bufs;
            int count;
            if (view_run_frame(ap->a, ap->s.frame, &bufs, &count, NULL) == ENG_OK &&
                ap->s.buffer < count)
                dirty = view_auto_range(&bufs[ap->s.buffer], ap->s.d.channel, &ap->s.d.exposure,
                                        &ap->s.d.offset);
            break;
        }
        view_action act = key_action(&ev->key.keysym);
        if (act == VIEW_ACT_QUIT && ap->s.help)
            act = VIEW_ACT_HELP; /* Esc/q first closes the help */
        dirty = view_state_apply(&ap->s, act);
        if (act == VIEW_ACT_RESET)
            ap->pan_x = ap->pan_y = 0;
        break;
    }
    case SDL_MOUSEWHEEL:
        dirty = view_state_apply(&ap->s, ev->wheel.y > 0 ? VIEW_ACT_ZOOM_IN : VIEW_ACT_ZOOM_OUT);
        break;
    case SDL_MOUSEMOTION:
        if (ap->dragging) {
            ap->pan_x += ev->motion.xrel;
            ap->pan_y += ev->motion.yrel;
        }
        ap->mouse_x = ev->motion.x;
        ap->mouse_y = ev->motion.y;
        dirty = 1;
        break;
    case SDL_MOUSEBUTTONDOWN: {
        if (ev->button.button == SDL_BUTTON_RIGHT) {
            ap->dragging = 1;
            break;
        }
        if (ev->button.button != SDL_BUTTON_LEFT)
            break;
        ap->mouse_x = ev->button.x;
        ap->mouse_y = ev->button.y;
        view_rect bar = timeline_bar(ap);
        if (ev->button.y >= bar.y - 2 && ev->button.y < bar.y + bar.h + 2) {
            view_state_set_frame(&ap->s, view_timeline_frame(bar, ap->s.frame_count, ev->button.x));
            dirty = 1;
            break;
        }
        update_hover(ap);
        if (ap->hover) {
            ap->pinned = 1;
            ap->pin_x = ap->hover_x;
            ap->pin_y = ap->hover_y;
            ap->series_valid = 0;
            dirty = 1;
        }
        break;
    }
    case SDL_MOUSEBUTTONUP:
        if (ev->button.button == SDL_BUTTON_RIGHT)
            ap->dragging = 0;
        break;
    default: break;
    }
    if (ap->s.frame != old_frame)
        sync_buffer(ap);
    if (ap->s.buffer != old_buffer) {
        view_state_set_buffer(&ap->s, ap->s.buffer,
                              view_run_buffer_channels(ap->a, ap->s.frame, ap->s.buffer));
        const char *name = view_run_buffer_name(ap->a, ap->s.frame, ap->s.buffer);
        snprintf(ap->buffer_name, sizeof ap->buffer_name, "%s", name ? name : "");
        ap->series_valid = 0;
    }
    if (ap->s.d.channel != old_ch || ap->s.frame != old_frame)
        ap->series_valid = 0;
    if (dirty)
        update_hover(ap);
    return dirty;
}

/* ---------------------------------------------------------------- main */

static int fail_sdl(const char *what)
{
    fprintf(stderr, "ispm-view: %s: %s\n", what, SDL_GetError());
    return 1;
}

int main(int argc, char **argv)
{
    const char *run_dir = NULL, *golden = NULL, *buffer = NULL;
    const char *probe_dump = NULL;
    int frame = -1, win_w = 1280, win_h = 800, list = 0;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (!strcmp(arg, "--help") || !strcmp(arg, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(arg, "--list")) {
            list = 1;
        } else if (!strcmp(arg, "--dump-probe") && i + 1 < argc) {
            probe_dump = argv[++i];
        } else if (!strcmp(arg, "--golden") && i + 1 < argc) {
            golden = argv[++i];
        } else if (!strcmp(arg, "--frame") && i + 1 < argc) {
            frame = atoi(argv[++i]);
            if (frame < 0)
                frame = 0;
        } else if (!strcmp(arg, "--buffer") && i + 1 < argc) {
            buffer = argv[++i];
        } else if (!strcmp(arg, "--size") && i + 1 < argc) {
            if (sscanf(argv[++i], "%dx%d", &win_w, &win_h) != 2 || win_w < 320 || win_h < 240) {
                fprintf(stderr, "ispm-view: --size %s: want WxH, at least 320x240\n", argv[i]);
                return 2;
            }
        } else if (arg[0] == '-' || run_dir) {
            fprintf(stderr, "ispm-view: unexpected argument '%s' (see ispm-view --help)\n", arg);
            return 2;
        } else {
            run_dir = arg;
        }
    }
    if (!run_dir) {
        usage(stderr);
        return 2;
    }

    app ap;
    memset(&ap, 0, sizeof ap);
    ap.a_dir = run_dir;
    ap.b_dir = golden;
    ap.probe_dump = probe_dump;
    ap.dumped_frame = -1;
    eng_error err;
    if (view_run_open(run_dir, 8, &ap.a, &err) != ENG_OK) {
        fprintf(stderr, "ispm-view: %s\n", err.msg);
        return 2;
    }
    if (golden && view_run_open(golden, 8, &ap.b, &err) != ENG_OK) {
        fprintf(stderr, "ispm-view: %s\n", err.msg);
        view_run_close(ap.a);
        return 2;
    }
    if (view_run_frame_count(ap.a) < 1 && view_run_live(ap.a)) {
        /* A recording that has not finished its first frame yet: wait for it. */
        fprintf(stderr, "ispm-view: %s: waiting for the recording's first frame\n", run_dir);
        while (view_run_frame_count(ap.a) < 1 && view_run_live(ap.a)) {
            if (view_run_refresh(ap.a, &err) < 0) {
                fprintf(stderr, "ispm-view: %s\n", err.msg);
                view_run_close(ap.a);
                view_run_close(ap.b);
                return 2;
            }
            SDL_Delay(200);
        }
    }
    if (view_run_frame_count(ap.a) < 1) {
        fprintf(stderr, "ispm-view: %s: the run has no frames\n", run_dir);
        view_run_close(ap.a);
        view_run_close(ap.b);
        return 2;
    }
    if (list) {
        /* The buffers of frame 0 in manifest (and panel) order, one a line; no window. */
        for (int i = 0; i < view_run_buffer_count(ap.a, 0); i++)
            printf("%s\n", view_run_buffer_name(ap.a, 0, i));
        view_run_close(ap.a);
        view_run_close(ap.b);
        return 0;
    }
    ap.lm_ok = lin_manifest_read(run_dir, &ap.lm, &err) == ENG_OK; /* without it, the plain probe */
    view_state_init(&ap.s, view_run_frame_count(ap.a), 0, ap.b != NULL);
    view_state_set_frame(&ap.s, view_live_start_frame(frame, view_run_live(ap.a), view_run_frame_count(ap.a)));
    snprintf(ap.buffer_name, sizeof ap.buffer_name, "%s", buffer ? buffer : "final.display");
    sync_buffer(&ap);
    if (buffer && strcmp(ap.buffer_name, buffer)) {
        fprintf(stderr, "ispm-view: %s: frame %d has no buffer '%s'\n", run_dir, ap.s.frame, buffer);
        view_run_close(ap.a);
        view_run_close(ap.b);
        return 2;
    }

    /* OpenImageIO's libraries before any X connection (oiio_shim.h: rep_oiio_load). */
    if (rep_oiio_load(&err) != ENG_OK) {
        fprintf(stderr, "ispm-view: %s\n", err.msg);
        view_run_close(ap.a);
        view_run_close(ap.b);
        return 1;
    }
    /* SDL falls back to its "offscreen" driver when there is no display, which would run
     * invisibly forever: without a display (or an explicit SDL_VIDEODRIVER) stop here. */
    int rc = 0;
    const char *driver_env = getenv("SDL_VIDEODRIVER");
    int explicit_driver = driver_env && *driver_env;
    const char *display = getenv("DISPLAY"), *wayland = getenv("WAYLAND_DISPLAY");
    if ((!explicit_driver && !(display && *display) && !(wayland && *wayland)) ||
        SDL_Init(SDL_INIT_VIDEO) != 0 ||
        (!explicit_driver && (!strcmp(SDL_GetCurrentVideoDriver(), "offscreen") ||
                              !strcmp(SDL_GetCurrentVideoDriver(), "dummy")))) {
        const char *why = SDL_GetError();
        fprintf(stderr, "ispm-view: cannot open a window: no display (set DISPLAY, or run under xvfb-run)%s%s\n",
                why && *why ? ": " : "", why && *why ? why : "");
        SDL_Quit();
        view_run_close(ap.a);
        view_run_close(ap.b);
        return 1;
    }
    SDL_SetHint(SDL_HINT_RENDER_SCALE_QUALITY, "0"); /* nearest: pixels stay pixels */
    const char *font_path = getenv("ISPM_VIEW_FONT");
    if (!font_path || !*font_path)
        font_path = ISPM_VIEW_FONT;
    char title[512];
    snprintf(title, sizeof title, "ispm-view %s%s%s", run_dir, golden ? " vs " : "", golden ? golden : "");
    if (TTF_Init() != 0) {
        rc = fail_sdl("SDL_ttf");
        goto out;
    }
    ap.font = TTF_OpenFont(font_path, FONT_PT);
    if (!ap.font) {
        fprintf(stderr, "ispm-view: %s: cannot open the font (Debian: fonts-dejavu-core; or set ISPM_VIEW_FONT)\n",
                font_path);
        rc = 1;
        goto out;
    }
    ap.line_h = TTF_FontLineSkip(ap.font);
    TTF_SizeUTF8(ap.font, "M", &ap.char_w, NULL);
    ap.win = SDL_CreateWindow(title, SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED, win_w, win_h,
                              SDL_WINDOW_RESIZABLE);
    if (!ap.win) {
        fprintf(stderr, "ispm-view: cannot open a window (no display? set DISPLAY or use xvfb-run): %s\n",
                SDL_GetError());
        rc = 1;
        goto out;
    }
    ap.ren = SDL_CreateRenderer(ap.win, -1, 0);
    if (!ap.ren)
        ap.ren = SDL_CreateRenderer(ap.win, -1, SDL_RENDERER_SOFTWARE);
    if (!ap.ren) {
        rc = fail_sdl("cannot create a renderer");
        goto out;
    }

    int dirty = 1;
    Uint32 last_tick = SDL_GetTicks();
    while (!ap.s.quit) {
        if (dirty) {
            redraw(&ap);
            dirty = 0;
        }
        SDL_Event ev;
        if (SDL_WaitEventTimeout(&ev, ap.s.playing ? 20 : 250)) {
            do
                dirty |= handle(&ap, &ev);
            while (!ap.s.quit && SDL_PollEvent(&ev));
        }
        if (view_live_poll(ap.a, &ap.s, SDL_GetTicks(), &ap.live_last, 250, ap.live_err, sizeof ap.live_err)) {
            sync_buffer(&ap);
            ap.series_valid = 0;
            update_hover(&ap);
            dirty = 1;
        }
        /* Playback at about 8 frames a second, whatever the decode time. */
        if (ap.s.playing && SDL_GetTicks() - last_tick >= 125) {
            last_tick = SDL_GetTicks();
            int old = ap.s.frame;
            view_state_tick(&ap.s);
            if (ap.s.frame != old) {
                sync_buffer(&ap);
                ap.series_valid = 0;
                update_hover(&ap);
                dirty = 1;
            }
        }
    }

out:
    if (ap.tex)
        SDL_DestroyTexture(ap.tex);
    if (ap.ren)
        SDL_DestroyRenderer(ap.ren);
    if (ap.win)
        SDL_DestroyWindow(ap.win);
    if (ap.font)
        TTF_CloseFont(ap.font);
    if (TTF_WasInit())
        TTF_Quit();
    SDL_Quit();
    view_flip_cache_free(&ap.flip);
    free(ap.pixels);
    free(ap.points);
    free(ap.weights);
    lin_result_free(&ap.lr);
    lin_manifest_free(&ap.lm);
    free(ap.rects);
    view_run_close(ap.a);
    view_run_close(ap.b);
    return rc;
}
