/* view_model.c — the viewer's window-free logic: display state, the actions keys map to, and
 * the mapping of float pixels to RGBA8.
 *
 * The display pipeline follows tev and RenderDoc's texture viewer: select components (RGB,
 * one channel, luminance), scale by 2^exposure, add the offset, then either map through a
 * false-colour ramp (turbo) or clamp and sRGB-encode. The overlay marks NaN, +-Inf and
 * negative values in loud colours instead. Comparison modes ignore the offset and show
 * |a-b|, |a-b|/max(|a|,|b|) (inferno, where zero is black) or a-b (red/blue on black), so a
 * run compared with an identical golden is black. Everything here is a pure function of its
 * arguments; main.c owns the window.
 */
#include "view_model.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static float clamp01(float v)
{
    if (!(v > 0.0f)) /* NaN too */
        return 0.0f;
    return v > 1.0f ? 1.0f : v;
}

static uint8_t to_byte(float v)
{
    return (uint8_t)(clamp01(v) * 255.0f + 0.5f);
}

static void put_hex(uint32_t rgb, uint8_t rgba[4])
{
    rgba[0] = (uint8_t)(rgb >> 16);
    rgba[1] = (uint8_t)(rgb >> 8);
    rgba[2] = (uint8_t)rgb;
    rgba[3] = 255;
}

void view_turbo(float t, float rgb[3])
{
    /* Anton Mikhailov's polynomial approximation of turbo (Google AI blog, 2019). */
    double x = clamp01(t), x2 = x * x, x3 = x2 * x, x4 = x2 * x2, x5 = x4 * x;
    rgb[0] = clamp01((float)(0.13572138 + 4.61539260 * x - 42.66032258 * x2 + 132.13108234 * x3 -
                             152.94239396 * x4 + 59.28637943 * x5));
    rgb[1] = clamp01((float)(0.09140261 + 2.19418839 * x + 4.84296658 * x2 - 14.18503333 * x3 +
                             4.27729857 * x4 + 2.82956604 * x5));
    rgb[2] = clamp01((float)(0.10667330 + 12.64194608 * x - 60.58204836 * x2 + 110.36276771 * x3 -
                             89.90310912 * x4 + 27.34824973 * x5));
}

void view_inferno(float t, float rgb[3])
{
    /* Matt Zucker's degree-6 least-squares fit of matplotlib's inferno. */
    static const double c[7][3] = {
        {0.0002189403691192265, 0.001651004631001012, -0.01948089843709184},
        {0.1065134194856116, 0.5639564367884091, 3.932712388889277},
        {11.60249308247187, -3.972853965665698, -15.9423941062914},
        {-41.70399613139459, 17.43639888205313, 44.35414519872813},
        {77.162935699427, -33.40235894210092, -81.80730925738993},
        {-71.31942824499214, 32.62606426397723, 73.20951985803202},
        {25.13112622477341, -12.24266895238567, -23.07032500287172},
    };
    double x = clamp01(t);
    for (int k = 0; k < 3; k++) {
        double v = c[6][k];
        for (int i = 5; i >= 0; i--)
            v = v * x + c[i][k];
        rgb[k] = clamp01((float)v);
    }
    if (!(t > 0.0f)) /* exact black at zero, so "no difference" reads as black */
        rgb[0] = rgb[1] = rgb[2] = 0.0f;
}

float view_srgb_encode(float v)
{
    v = clamp01(v);
    return v <= 0.0031308f ? 12.92f * v : 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
}

static float luma(const float c[3])
{
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

int view_select(const float *px, int nch, view_channel ch, float out[3])
{
    out[0] = out[1] = out[2] = 0.0f;
    if (nch < 1)
        return 0;
    if (ch >= VIEW_CH_1 && ch <= VIEW_CH_4) {
        int k = (int)ch - (int)VIEW_CH_1;
        if (k >= nch)
            return 0;
        out[0] = px[k];
        return 1;
    }
    float rgb[3];
    if (nch == 1) {
        rgb[0] = rgb[1] = rgb[2] = px[0];
    } else {
        rgb[0] = px[0];
        rgb[1] = px[1];
        rgb[2] = nch >= 3 ? px[2] : 0.0f;
    }
    if (ch == VIEW_CH_LUMA) {
        /* A non-finite component must stay visible through the weighted sum. */
        out[0] = nch == 1 ? px[0] : luma(rgb);
        return 1;
    }
    memcpy(out, rgb, sizeof rgb);
    return 3;
}

/* The overlay colour for components v[0..n), or 0 if none applies. NaN wins over Inf over
 * negative, the order of how surprising each is. */
static uint32_t overlay_colour(const float *v, int n, int want_negative)
{
    uint32_t c = 0;
    for (int i = 0; i < n; i++) {
        if (isnan(v[i]))
            return VIEW_COLOUR_NAN;
        if (isinf(v[i]))
            c = VIEW_COLOUR_INF;
        else if (want_negative && v[i] < 0.0f && c == 0)
            c = VIEW_COLOUR_NEG;
    }
    return c;
}

void view_map_pixel(const float *px, int nch, const view_display *d, uint8_t rgba[4])
{
    float v[3];
    int n = view_select(px, nch, d->channel, v);
    if (d->overlay) {
        uint32_t c = overlay_colour(v, n, 1);
        if (c) {
            put_hex(c, rgba);
            return;
        }
    }
    float scale = exp2f(d->exposure);
    for (int i = 0; i < 3; i++)
        v[i] = v[i] * scale + d->offset;
    float out[3];
    if (d->false_colour) {
        view_turbo(n == 3 ? luma(v) : v[0], out);
    } else if (n == 3) {
        for (int i = 0; i < 3; i++)
            out[i] = d->linear ? clamp01(v[i]) : view_srgb_encode(v[i]);
    } else {
        out[0] = out[1] = out[2] = d->linear ? clamp01(v[0]) : view_srgb_encode(v[0]);
    }
    for (int i = 0; i < 3; i++)
        rgba[i] = to_byte(out[i]);
    rgba[3] = 255;
}

/* Class of a value: 0 finite, 1 NaN, 2 +Inf, 3 -Inf (replay's rule: a change of class is a
 * failure, the same class is no difference). */
static int value_class(float v)
{
    if (isnan(v))
        return 1;
    if (isinf(v))
        return v > 0 ? 2 : 3;
    return 0;
}

void view_map_diff(const float *a, const float *b, int nch, const view_display *d, uint8_t rgba[4])
{
    float va[3], vb[3];
    int n = view_select(a, nch, d->channel, va);
    view_select(b, nch, d->channel, vb);
    float best = 0.0f; /* the difference of largest magnitude, sign kept */
    for (int i = 0; i < n; i++) {
        int ca = value_class(va[i]), cb = value_class(vb[i]);
        if (ca != cb) {
            put_hex(VIEW_COLOUR_NAN, rgba);
            return;
        }
        if (ca != 0)
            continue;
        float diff = va[i] - vb[i];
        if (d->compare == VIEW_CMP_REL) {
            float m = fmaxf(fabsf(va[i]), fabsf(vb[i]));
            diff = m > 0.0f ? diff / m : 0.0f;
        }
        if (fabsf(diff) > fabsf(best))
            best = diff;
    }
    float t = fabsf(best) * exp2f(d->exposure), out[3];
    if (d->compare == VIEW_CMP_SIGNED) {
        t = clamp01(t);
        out[0] = best > 0.0f ? t : 0.0f;
        out[1] = 0.25f * t;
        out[2] = best < 0.0f ? t : 0.0f;
        if (best == 0.0f)
            out[1] = 0.0f;
    } else {
        view_inferno(t, out);
    }
    for (int i = 0; i < 3; i++)
        rgba[i] = to_byte(out[i]);
    rgba[3] = 255;
}

/* map[i]: the channel of b with a's channel i's name, or -1. */
static int match_channels(const eng_buffer *a, const eng_buffer *b, int map[ENG_MAX_CHANNELS])
{
    if (!b || b->width != a->width || b->height != a->height || b->channel_count != a->channel_count)
        return 0;
    for (int i = 0; i < a->channel_count; i++) {
        map[i] = -1;
        for (int j = 0; j < b->channel_count; j++)
            if (!strcmp(a->channels[i], b->channels[j]))
                map[i] = j;
        if (map[i] < 0)
            return 0;
    }
    return 1;
}

view_render_status view_render(const eng_buffer *a, const eng_buffer *b, const view_display *d,
                               uint8_t *out)
{
    int map[ENG_MAX_CHANNELS];
    int want_b = d->show_b || d->compare != VIEW_CMP_OFF;
    view_render_status st = VIEW_RENDER_OK;
    int use_b = 0;
    if (want_b) {
        if (!b)
            st = VIEW_RENDER_NO_B;
        else if (!match_channels(a, b, map))
            st = VIEW_RENDER_MISMATCH;
        else
            use_b = 1;
    }
    size_t pixels = (size_t)a->width * (size_t)a->height;
    int nch = a->channel_count;
    float pb[ENG_MAX_CHANNELS];
    for (size_t p = 0; p < pixels; p++) {
        const float *pa = a->data + p * (size_t)nch;
        uint8_t *o = out + p * 4;
        if (!use_b) {
            view_map_pixel(pa, nch, d, o);
            continue;
        }
        const float *src = b->data + p * (size_t)nch;
        for (int i = 0; i < nch; i++)
            pb[i] = src[map[i]];
        if (d->compare == VIEW_CMP_OFF)
            view_map_pixel(pb, nch, d, o);
        else
            view_map_diff(pa, pb, nch, d, o);
    }
    return st;
}

int view_auto_range(const eng_buffer *a, view_channel ch, float *exposure, float *offset)
{
    size_t pixels = (size_t)a->width * (size_t)a->height;
    float lo = INFINITY, hi = -INFINITY, v[3];
    for (size_t p = 0; p < pixels; p++) {
        int n = view_select(a->data + p * (size_t)a->channel_count, a->channel_count, ch, v);
        for (int i = 0; i < n; i++)
            if (isfinite(v[i])) {
                lo = fminf(lo, v[i]);
                hi = fmaxf(hi, v[i]);
            }
    }
    if (!(lo <= hi))
        return 0;
    float span = hi - lo;
    *exposure = span > 0.0f ? -log2f(span) : 0.0f;
    *offset = -lo * exp2f(*exposure);
    return 1;
}

/* ---------------------------------------------------------------- state */

void view_state_init(view_state *s, int frame_count, int buffer_count, int has_b)
{
    memset(s, 0, sizeof *s);
    s->frame_count = frame_count;
    s->buffer_count = buffer_count;
    s->has_b = has_b;
    s->zoom = 1.0f;
}

void view_state_set_frame(view_state *s, int frame)
{
    if (frame >= s->frame_count)
        frame = s->frame_count - 1;
    s->frame = frame < 0 ? 0 : frame;
}

void view_state_set_buffer(view_state *s, int buffer, int channel_count)
{
    if (buffer >= s->buffer_count)
        buffer = s->buffer_count - 1;
    s->buffer = buffer < 0 ? 0 : buffer;
    s->channel_count = channel_count;
    if (s->d.channel >= VIEW_CH_1 && s->d.channel <= VIEW_CH_4 &&
        (int)s->d.channel - (int)VIEW_CH_1 >= channel_count)
        s->d.channel = VIEW_CH_RGB;
}

static int set_channel(view_state *s, view_channel ch)
{
    if (ch >= VIEW_CH_1 && ch <= VIEW_CH_4 && (int)ch - (int)VIEW_CH_1 >= s->channel_count)
        return 0;
    if (s->d.channel == ch)
        return 0;
    s->d.channel = ch;
    return 1;
}

static int move_frame(view_state *s, int frame)
{
    int old = s->frame;
    view_state_set_frame(s, frame);
    return s->frame != old;
}

int view_state_apply(view_state *s, view_action a)
{
    int old_buffer = s->buffer;
    switch (a) {
    case VIEW_ACT_NONE: return 0;
    case VIEW_ACT_FRAME_NEXT: return move_frame(s, s->frame + 1);
    case VIEW_ACT_FRAME_PREV: return move_frame(s, s->frame - 1);
    case VIEW_ACT_FRAME_FIRST: return move_frame(s, 0);
    case VIEW_ACT_FRAME_LAST: return move_frame(s, s->frame_count - 1);
    case VIEW_ACT_PLAY: s->playing = !s->playing; return 1;
    case VIEW_ACT_BUFFER_NEXT:
        view_state_set_buffer(s, s->buffer + 1, s->channel_count);
        return s->buffer != old_buffer;
    case VIEW_ACT_BUFFER_PREV:
        view_state_set_buffer(s, s->buffer - 1, s->channel_count);
        return s->buffer != old_buffer;
    case VIEW_ACT_CH_RGB: return set_channel(s, VIEW_CH_RGB);
    case VIEW_ACT_CH_1: return set_channel(s, VIEW_CH_1);
    case VIEW_ACT_CH_2: return set_channel(s, VIEW_CH_2);
    case VIEW_ACT_CH_3: return set_channel(s, VIEW_CH_3);
    case VIEW_ACT_CH_4: return set_channel(s, VIEW_CH_4);
    case VIEW_ACT_CH_LUMA: return set_channel(s, VIEW_CH_LUMA);
    case VIEW_ACT_EXPOSURE_UP: s->d.exposure += 0.5f; return 1;
    case VIEW_ACT_EXPOSURE_DOWN: s->d.exposure -= 0.5f; return 1;
    case VIEW_ACT_OFFSET_UP: s->d.offset += 1.0f / 16.0f; return 1;
    case VIEW_ACT_OFFSET_DOWN: s->d.offset -= 1.0f / 16.0f; return 1;
    case VIEW_ACT_RESET:
        s->d.exposure = 0.0f;
        s->d.offset = 0.0f;
        s->zoom = 1.0f;
        return 1;
    case VIEW_ACT_TOGGLE_SRGB: s->d.linear = !s->d.linear; return 1;
    case VIEW_ACT_TOGGLE_FALSE: s->d.false_colour = !s->d.false_colour; return 1;
    case VIEW_ACT_TOGGLE_OVERLAY: s->d.overlay = !s->d.overlay; return 1;
    case VIEW_ACT_FLIP_AB:
        if (!s->has_b)
            return 0;
        s->d.show_b = !s->d.show_b;
        return 1;
    case VIEW_ACT_CYCLE_COMPARE:
        if (!s->has_b)
            return 0;
        s->d.compare = (view_compare)(((int)s->d.compare + 1) % (int)VIEW_CMP_COUNT);
        return 1;
    case VIEW_ACT_ZOOM_IN:
        if (s->zoom >= 64.0f)
            return 0;
        s->zoom *= 1.25f;
        return 1;
    case VIEW_ACT_ZOOM_OUT:
        if (s->zoom <= 1.0f / 16.0f)
            return 0;
        s->zoom /= 1.25f;
        return 1;
    case VIEW_ACT_HELP: s->help = !s->help; return 1;
    case VIEW_ACT_TOGGLE_PHOTONS: s->photons = (s->photons + 1) % 3; return 1;
    case VIEW_ACT_QUIT: s->quit = 1; return 0;
    }
    return 0;
}

int view_state_tick(view_state *s)
{
    if (!s->playing || s->frame_count < 1)
        return 0;
    s->frame = (s->frame + 1) % s->frame_count;
    return 1;
}

/* ---------------------------------------------------------------- photon points */

uint32_t view_bounce_colour(int bounce)
{
    return bounce <= 2 ? 0x00ffffu : bounce == 3 ? 0xffff00u : 0xff00ffu;
}

static int channel_index(const eng_buffer *b, const char *name)
{
    for (int c = 0; c < b->channel_count; c++)
        if (b->channels[c] && !strcmp(b->channels[c], name))
            return c;
    return -1;
}

int view_project_photons(const eng_buffer *map, const float view_proj[16], int img_w, int img_h,
                         view_point *out, int cap, int *total)
{
    if (total)
        *total = 0;
    int cx = channel_index(map, "position.X"), cy = channel_index(map, "position.Y");
    int cz = channel_index(map, "position.Z"), cb = channel_index(map, "bounce");
    if (cx < 0 || cy < 0 || cz < 0 || cb < 0)
        return -1;
    const float *m = view_proj;
    size_t n = (size_t)map->width * (size_t)map->height, nch = (size_t)map->channel_count;
    int count = 0, photons = 0;
    for (size_t i = 0; i < n; i++) {
        const float *px = map->data + i * nch;
        if (!(px[cb] != 0.0f))
            continue;
        photons++;
        if (count >= cap)
            continue;
        float p[3] = {px[cx], px[cy], px[cz]}, clip[4];
        for (int r = 0; r < 4; r++)
            clip[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
        if (!(clip[3] > 0.0f))
            continue;
        float nx = clip[0] / clip[3], ny = clip[1] / clip[3];
        if (!(nx >= -1.0f && nx <= 1.0f && ny >= -1.0f && ny <= 1.0f))
            continue;
        out[count].x = (nx * 0.5f + 0.5f) * (float)img_w;
        out[count].y = (0.5f - ny * 0.5f) * (float)img_h;
        out[count].bounce = (int)lroundf(px[cb]);
        count++;
    }
    if (total)
        *total = photons;
    return count;
}

/* ---------------------------------------------------------------- layout and probe */

view_rect view_fit(view_rect area, int img_w, int img_h, float zoom)
{
    view_rect r = {area.x, area.y, 0, 0};
    if (img_w < 1 || img_h < 1 || area.w < 1 || area.h < 1)
        return r;
    double s = fmin((double)area.w / img_w, (double)area.h / img_h) * zoom;
    r.w = (int)lround(img_w * s);
    r.h = (int)lround(img_h * s);
    if (r.w < 1)
        r.w = 1;
    if (r.h < 1)
        r.h = 1;
    r.x = area.x + (area.w - r.w) / 2;
    r.y = area.y + (area.h - r.h) / 2;
    return r;
}

int view_screen_to_pixel(view_rect dst, int img_w, int img_h, int sx, int sy, int *px, int *py)
{
    if (dst.w < 1 || dst.h < 1 || sx < dst.x || sy < dst.y || sx >= dst.x + dst.w ||
        sy >= dst.y + dst.h)
        return 0;
    int x = (int)((long long)(sx - dst.x) * img_w / dst.w);
    int y = (int)((long long)(sy - dst.y) * img_h / dst.h);
    *px = x < img_w ? x : img_w - 1;
    *py = y < img_h ? y : img_h - 1;
    return 1;
}

int view_timeline_frame(view_rect bar, int frame_count, int sx)
{
    if (frame_count < 1 || bar.w < 1)
        return 0;
    long long f = (long long)(sx - bar.x) * frame_count / bar.w;
    if (f < 0)
        f = 0;
    if (f >= frame_count)
        f = frame_count - 1;
    return (int)f;
}

static void format_value(float v, char *out, size_t n)
{
    if (isnan(v))
        snprintf(out, n, "nan");
    else if (isinf(v))
        snprintf(out, n, v > 0 ? "inf" : "-inf");
    else
        snprintf(out, n, "%.5g", (double)v);
}

char *view_probe_line(const eng_buffer *b, int x, int y, char *out, size_t n)
{
    if (n == 0)
        return out;
    size_t len = (size_t)snprintf(out, n, "%s ", b->name);
    if (x < 0 || y < 0 || x >= b->width || y >= b->height) {
        if (len < n)
            snprintf(out + len, n - len, " -");
        return out;
    }
    const float *px = b->data + ((size_t)y * (size_t)b->width + (size_t)x) * (size_t)b->channel_count;
    for (int c = 0; c < b->channel_count && len < n; c++) {
        char v[32];
        format_value(px[c], v, sizeof v);
        len += (size_t)snprintf(out + len, n - len, " %s=%s", b->channels[c], v);
    }
    return out;
}

float view_probe_value(const eng_buffer *b, view_channel ch, int x, int y)
{
    if (x < 0 || y < 0 || x >= b->width || y >= b->height)
        return NAN;
    const float *px = b->data + ((size_t)y * (size_t)b->width + (size_t)x) * (size_t)b->channel_count;
    float v[3];
    int n = view_select(px, b->channel_count, ch == VIEW_CH_RGB ? VIEW_CH_LUMA : ch, v);
    return n ? v[0] : NAN;
}
