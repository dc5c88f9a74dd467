/* view_lineage.c — the viewer's side of pixel lineage (replay/compare/lineage.h): which eye
 * pixel a probe on the shown buffer stands for, the probe panel's lines with every buffer read at
 * its own coordinate (subsampled levels scaled, light-space buffers at the texel the pixel
 * projects to through the light's matrices) and the shadow verdicts, and the photons that
 * contribute to the pixel as points coloured by their contribution. Window-free, like
 * view_model.c, so that Check tests drive it. */
#include "view_model.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

int view_lineage_eye_pixel(const eng_buffer *shown, int eye_w, int eye_h, int px, int py, int *ex, int *ey)
{
    if (!shown || !shown->name || shown->width < 1 || shown->height < 1)
        return 0;
    const char *n = shown->name;
    if (!strncmp(n, "shadow.", 7) || !strncmp(n, "lightgbuffer.", 13) || !strncmp(n, "bounce.", 7) ||
        !strncmp(n, "photons.", 8) || !strncmp(n, "multiimage.", 11))
        return 0; /* not an image of the eye's view */
    if (px < 0 || py < 0 || px >= shown->width || py >= shown->height)
        return 0;
    *ex = (int)floor(((double)px + 0.5) * eye_w / shown->width);
    *ey = (int)floor(((double)py + 0.5) * eye_h / shown->height);
    *ex = *ex >= eye_w ? eye_w - 1 : *ex;
    *ey = *ey >= eye_h ? eye_h - 1 : *ey;
    return 1;
}

/* Appends one line (without newline) to out[*n] if there is room. */
static void line(char (*out)[VIEW_LINEAGE_LINE], int max, int *n, const char *fmt_done)
{
    if (*n < max)
        snprintf(out[(*n)++], VIEW_LINEAGE_LINE, "%s", fmt_done);
}

int view_lineage_lines(const lin_result *r, char (*out)[VIEW_LINEAGE_LINE], int max)
{
    int n = 0;
    char b[VIEW_LINEAGE_LINE];
    if (!r->covered) {
        line(out, max, &n, "background: no surface");
    }
    for (int i = 0; i < r->shadow_count; i++) {
        const lin_shadow *s = &r->shadows[i];
        if (s->outside)
            snprintf(b, sizeof b, "light %d: outside its map: %s", s->light, s->lit ? "lit" : "unlit");
        else
            snprintf(b, sizeof b, "light %d: %s (%d, %d) stored %.5g vs %.5g (+%.3g): %s, PCF %.3g", s->light, s->map,
                     s->texel[0], s->texel[1], (double)s->stored, (double)s->compared, (double)s->tolerance,
                     s->lit ? "lit" : "shadowed", (double)s->visibility);
        line(out, max, &n, b);
    }
    if (r->has_photons && r->covered) {
        snprintf(b, sizeof b, "photons: %d of %d contribute, sum (%.5g, %.5g, %.5g)", r->photon_count, r->map_photons,
                 r->sum[0], r->sum[1], r->sum[2]);
        line(out, max, &n, b);
    } else if (!r->has_photons) {
        snprintf(b, sizeof b, "photons: %s", r->why ? r->why : "-");
        line(out, max, &n, b);
    }
    for (int i = 0; i < r->value_count; i++) {
        const lin_value *v = &r->values[i];
        int k = snprintf(b, sizeof b, "%s (%d, %d)", v->name, v->x, v->y);
        for (int c = 0; c < v->channel_count && c < 8 && k > 0 && (size_t)k < sizeof b; c++)
            k += snprintf(b + k, sizeof b - (size_t)k, " %s=%.5g", v->channels[c], (double)v->v[c]);
        line(out, max, &n, b);
    }
    return n;
}

int view_lineage_points(const lin_result *r, const float view_proj[16], int img_w, int img_h, view_point *out,
                        float *weight, int cap)
{
    float top = 0.0f;
    for (int i = 0; i < r->photon_count; i++) {
        const float *c = r->photons[i].contribution;
        top = fmaxf(top, 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]);
    }
    int n = 0;
    const float *m = view_proj;
    for (int i = 0; i < r->photon_count && n < cap; i++) {
        const float *p = r->photons[i].position, *c = r->photons[i].contribution;
        float cx = m[0] * p[0] + m[4] * p[1] + m[8] * p[2] + m[12];
        float cy = m[1] * p[0] + m[5] * p[1] + m[9] * p[2] + m[13];
        float cw = m[3] * p[0] + m[7] * p[1] + m[11] * p[2] + m[15];
        if (!(cw > 0.0f))
            continue;
        float nx = cx / cw, ny = cy / cw;
        if (nx < -1.0f || nx > 1.0f || ny < -1.0f || ny > 1.0f)
            continue;
        out[n].x = (nx * 0.5f + 0.5f) * (float)img_w;
        out[n].y = (0.5f - ny * 0.5f) * (float)img_h;
        out[n].bounce = r->photons[i].bounce;
        float y = 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
        weight[n] = top > 0.0f ? y / top : 0.0f;
        n++;
    }
    return n;
}

uint32_t view_contribution_colour(float t)
{
    /* Dark red (a small share of the pixel's indirect light) through orange to white (the
     * largest): apart from the bounce colours (cyan, yellow, magenta) of the whole map. */
    t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
    float r = 0.45f + 0.55f * fminf(1.0f, 2.0f * t);
    float g = t < 0.5f ? 0.3f * t : 0.15f + 0.85f * (t - 0.5f) * 2.0f;
    float b = t < 0.7f ? 0.0f : (t - 0.7f) / 0.3f;
    return ((uint32_t)(r * 255.0f + 0.5f) << 16) | ((uint32_t)(g * 255.0f + 0.5f) << 8) | (uint32_t)(b * 255.0f + 0.5f);
}
