/* stability.c — temporal stability of a run: how much each image pass changes from one frame to
 * the next where the scene did not change (static pixels) or where the change is explained by
 * motion (reprojected pixels), and, given a reference run, how much the error against the
 * reference varies over time.
 *
 * ISPM's frame coherence (003 §4.1: random numbers seeded by scene quantities, so photons that
 * did not move are the same every frame) is what the static-pixel measure tests: where the
 * G-buffer is bit-identical and nothing in the light paths changed, indirect light must be
 * bit-identical too. The reprojected measure follows the surface under camera motion using the
 * G-buffer's motion vectors and masks disocclusions from the G-buffers alone (no scene is
 * loaded): the history of a pixel is accepted only when the previous frame's G-buffer at the
 * reprojected pixel shows the same surface point (rep_stab.h states the test).
 * Surfaces that moved in the world (animated objects) are not followed: their pixels are
 * counted as "moving" and left out, so the reprojected measure never mistakes a real change
 * of a moving object's lighting for flicker of a static one. The definitions of the flicker
 * and its statistics are in rep_stab.h and docs/stability.md.
 *
 * The run's frames are fed in order (rep_stab_frame); the previous frame's G-buffer and images
 * are kept, so memory holds two frames' worth of eye-sized images per measured pass. Every
 * rep_stab_run owns its buffers and is freed whole by rep_stab_free.
 */
#include "rep_run.h"
#include "rep_stab.h"
#include "rep_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *rep_repro_class_name(rep_repro_class c)
{
    switch (c) {
    case REP_REPRO_VALID: return "valid";
    case REP_REPRO_BACKGROUND: return "background";
    case REP_REPRO_OFFSCREEN: return "offscreen";
    case REP_REPRO_MOVING: return "moving";
    case REP_REPRO_DISOCCLUDED: return "disoccluded";
    case REP_REPRO_COUNT: break;
    }
    return "?";
}

/* Copies the named channels of part p, in the order given, into a new array; NULL if p lacks
 * one of them. */
static float *pick(const rep_part *p, const char *const *names, int n)
{
    int idx[ENG_MAX_CHANNELS];
    for (int k = 0; k < n; k++) {
        idx[k] = -1;
        for (int c = 0; c < p->channel_count; c++)
            if (strcmp(p->channels[c], names[k]) == 0)
                idx[k] = c;
        if (idx[k] < 0)
            return NULL;
    }
    size_t np = (size_t)p->width * (size_t)p->height;
    float *out = rep_xmalloc(np * (size_t)n * sizeof *out);
    for (size_t i = 0; i < np; i++)
        for (int k = 0; k < n; k++)
            out[i * (size_t)n + (size_t)k] = p->data[i * (size_t)p->channel_count + (size_t)idx[k]];
    return out;
}

static const rep_part *part_named(const rep_part *parts, int n, const char *name)
{
    for (int i = 0; i < n; i++)
        if (strcmp(parts[i].name, name) == 0)
            return &parts[i];
    return NULL;
}

void rep_stab_gbuffer_free(rep_stab_gbuffer *g)
{
    free(g->position);
    free(g->normal);
    free(g->material);
    free(g->motion);
    memset(g, 0, sizeof *g);
}

int rep_stab_gbuffer_from_parts(const rep_part *parts, int n, const rep_frame_info *f, rep_stab_gbuffer *g)
{
    static const char *const XYZ[] = {"X", "Y", "Z"};
    static const char *const MAT[] = {"roughness", "metallic", "transmission", "ior", "id"};
    memset(g, 0, sizeof *g);
    const rep_part *pp = part_named(parts, n, "gbuffer.position"), *pn = part_named(parts, n, "gbuffer.normal");
    const rep_part *pm = part_named(parts, n, "gbuffer.material"), *pv = part_named(parts, n, "gbuffer.motion");
    if (!pp || !pn || !pm || !pv)
        return 0;
    for (const rep_part *const *q = (const rep_part *const[]){pn, pm, pv, NULL}; *q; q++)
        if ((*q)->width != pp->width || (*q)->height != pp->height)
            return 0;
    g->width = pp->width;
    g->height = pp->height;
    g->position = pick(pp, XYZ, 3);
    g->normal = pick(pn, XYZ, 3);
    g->material = pick(pm, MAT, 5);
    g->motion = pick(pv, XYZ, 2);
    if (!g->position || !g->normal || !g->material || !g->motion) {
        rep_stab_gbuffer_free(g);
        return 0;
    }
    if (f && f->has_camera) {
        g->has_camera = 1;
        memcpy(g->view_proj, f->view_proj, sizeof g->view_proj);
    }
    return 1;
}

void rep_stab_static_mask(const rep_stab_gbuffer *prev, const rep_stab_gbuffer *cur, uint8_t *mask)
{
    size_t np = (size_t)cur->width * (size_t)cur->height;
    for (size_t i = 0; i < np; i++)
        mask[i] = cur->material[5 * i + 4] >= 0 && memcmp(prev->position + 3 * i, cur->position + 3 * i, 3 * sizeof(float)) == 0 &&
                  memcmp(prev->normal + 3 * i, cur->normal + 3 * i, 3 * sizeof(float)) == 0 &&
                  memcmp(prev->material + 5 * i, cur->material + 5 * i, 5 * sizeof(float)) == 0;
}

static double dist3(const float *a, const float *b)
{
    double dx = (double)a[0] - b[0], dy = (double)a[1] - b[1], dz = (double)a[2] - b[2];
    return sqrt(dx * dx + dy * dy + dz * dz);
}

/* World distance from pixel (x, y) of g to its nearer neighbour of the same id along one
 * axis (dx, dy) = (1, 0) or (0, 1); 0 when neither neighbour is of the same id. */
static double footprint_axis(const rep_stab_gbuffer *g, int x, int y, int dx, int dy)
{
    size_t i = (size_t)y * (size_t)g->width + (size_t)x;
    float id = g->material[5 * i + 4];
    double best = INFINITY;
    for (int s = -1; s <= 1; s += 2) {
        int nx = x + s * dx, ny = y + s * dy;
        if (nx < 0 || ny < 0 || nx >= g->width || ny >= g->height)
            continue;
        size_t j = (size_t)ny * (size_t)g->width + (size_t)nx;
        if (g->material[5 * j + 4] != id)
            continue;
        double d = dist3(g->position + 3 * i, g->position + 3 * j);
        if (d < best)
            best = d;
    }
    return isfinite(best) ? best : 0.0;
}

/* Where the camera of g puts world point P, in continuous pixel coordinates (y down); 0 if
 * behind the camera. */
static int project(const rep_stab_gbuffer *g, const float *P, double *px, double *py)
{
    const float *m = g->view_proj;
    double c[4];
    for (int r = 0; r < 4; r++)
        c[r] = (double)m[r] * P[0] + (double)m[4 + r] * P[1] + (double)m[8 + r] * P[2] + (double)m[12 + r];
    if (!(c[3] > 0))
        return 0;
    *px = (c[0] / c[3] + 1.0) * 0.5 * g->width;
    *py = (1.0 - c[1] / c[3]) * 0.5 * g->height;
    return 1;
}

void rep_stab_reproject(const rep_stab_gbuffer *prev, const rep_stab_gbuffer *cur, int32_t *src, uint8_t *cls)
{
    int w = cur->width, h = cur->height;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * (size_t)w + (size_t)x;
            src[i] = -1;
            const float *P = cur->position + 3 * i, *N = cur->normal + 3 * i;
            float id = cur->material[5 * i + 4];
            if (id < 0) {
                cls[i] = REP_REPRO_BACKGROUND;
                continue;
            }
            double mx = cur->motion[2 * i], my = cur->motion[2 * i + 1];
            double sx = x + 0.5 + mx, sy = y + 0.5 + my;
            if (!(sx >= 0 && sy >= 0 && sx < prev->width && sy < prev->height)) {
                cls[i] = REP_REPRO_OFFSCREEN;
                continue;
            }
            int still;
            if (cur->has_camera && prev->has_camera) {
                double px, py;
                still = project(prev, P, &px, &py) && fabs(px - sx) <= REP_STAB_MOTION_TOL &&
                        fabs(py - sy) <= REP_STAB_MOTION_TOL;
            } else {
                still = mx == 0 && my == 0;
            }
            if (!still) {
                cls[i] = REP_REPRO_MOVING;
                continue;
            }
            int qx = (int)floor(sx), qy = (int)floor(sy);
            size_t j = (size_t)qy * (size_t)prev->width + (size_t)qx;
            const float *X = prev->position + 3 * j, *NQ = prev->normal + 3 * j;
            double dot = (double)N[0] * NQ[0] + (double)N[1] * NQ[1] + (double)N[2] * NQ[2];
            double tol = REP_STAB_FOOTPRINTS *
                         (footprint_axis(prev, qx, qy, 1, 0) + footprint_axis(prev, qx, qy, 0, 1));
            if (prev->material[5 * j + 4] != id || !(dot >= REP_STAB_NORMAL_DOT) || !(dist3(X, P) <= tol)) {
                cls[i] = REP_REPRO_DISOCCLUDED;
                continue;
            }
            cls[i] = REP_REPRO_VALID;
            src[i] = (int32_t)j;
        }
}

double rep_stab_flicker(const float *a, const float *b, int n)
{
    double f = 0;
    for (int c = 0; c < n; c++) {
        if (!isfinite(a[c]) || !isfinite(b[c])) {
            if (memcmp(&a[c], &b[c], sizeof(float)) != 0)
                return 1.0;
            continue;
        }
        double d = fabs((double)a[c] - (double)b[c]);
        double l = fmax(fabs((double)a[c]), fabs((double)b[c]));
        double r = d / (l + REP_STAB_EPS);
        if (r > f)
            f = r;
    }
    return f;
}

void rep_stab_summarise(float *v, size_t n, rep_stab_stats *s)
{
    uint64_t changed = s->changed;
    memset(s, 0, sizeof *s);
    s->changed = changed;
    s->pixels = n;
    if (n == 0)
        return;
    rep_sort_floats(v, n);
    double sum = 0;
    for (size_t i = 0; i < n; i++)
        sum += v[i];
    s->mean = sum / (double)n;
    size_t rank = (size_t)ceil(0.99 * (double)n);
    s->p99 = v[rank ? rank - 1 : 0];
    s->max = v[n - 1];
}

int rep_stab_is_image(const rep_part *p, int width, int height)
{
    static const char *const SKIP[] = {"gbuffer.", "shadow.", "lightgbuffer.", "bounce.", "photons.", "stability."};
    for (size_t k = 0; k < sizeof SKIP / sizeof SKIP[0]; k++)
        if (strncmp(p->name, SKIP[k], strlen(SKIP[k])) == 0)
            return 0;
    if (p->width != width || p->height != height)
        return 0;
    int r = 0, g = 0, b = 0, y = 0;
    for (int c = 0; c < p->channel_count; c++) {
        r += strcmp(p->channels[c], "R") == 0;
        g += strcmp(p->channels[c], "G") == 0;
        b += strcmp(p->channels[c], "B") == 0;
        y += strcmp(p->channels[c], "Y") == 0;
    }
    return (p->channel_count == 3 && r && g && b) || (p->channel_count == 1 && y);
}

const char *rep_stab_reference_for(const char *buffer)
{
    if (strcmp(buffer, "indirect.radiance") == 0)
        return "reference.indirect";
    if (strcmp(buffer, "composite.radiance") == 0)
        return "reference.full";
    if (strcmp(buffer, "direct.radiance") == 0)
        return "reference.direct";
    return NULL;
}

rep_stab_buffer *rep_stab_find(const rep_stab_run *st, const char *name)
{
    for (int i = 0; i < st->buffer_count; i++)
        if (strcmp(st->buffers[i].name, name) == 0)
            return &st->buffers[i];
    return NULL;
}

static void push(float **v, size_t *n, size_t *cap, float x)
{
    if (*n == *cap) {
        *cap = *cap ? *cap * 2 : 4096;
        *v = rep_xrealloc(*v, *cap * sizeof **v);
    }
    (*v)[(*n)++] = x;
}

static rep_stab_buffer *add_buffer(rep_stab_run *st, const rep_part *p)
{
    st->buffers = rep_xrealloc(st->buffers, (size_t)(st->buffer_count + 1) * sizeof *st->buffers);
    rep_stab_buffer *b = &st->buffers[st->buffer_count++];
    memset(b, 0, sizeof *b);
    b->name = rep_xstrdup(p->name);
    b->channel_count = p->channel_count;
    b->static_mean = rep_xmalloc((size_t)st->frame_count * sizeof(double));
    b->static_p99 = rep_xmalloc((size_t)st->frame_count * sizeof(double));
    b->repro_mean = rep_xmalloc((size_t)st->frame_count * sizeof(double));
    b->repro_p99 = rep_xmalloc((size_t)st->frame_count * sizeof(double));
    for (int i = 0; i < st->frame_count; i++)
        b->static_mean[i] = b->static_p99[i] = b->repro_mean[i] = b->repro_p99[i] = NAN;
    b->reference = rep_stab_reference_for(p->name);
    return b;
}

/* The part's pixels in R,G,B (or Y) order, as a new array. */
static float *image_of(const rep_part *p)
{
    static const char *const RGB[] = {"R", "G", "B"}, *const Y[] = {"Y"};
    return p->channel_count == 3 ? pick(p, RGB, 3) : pick(p, Y, 1);
}

/* Accumulates the error against the reference for one frame. */
static void accumulate_reference(rep_stab_run *st, rep_stab_buffer *b, const float *img, const rep_part *ref, int ref_n)
{
    const rep_part *rp = b->reference && ref ? part_named(ref, ref_n, b->reference) : NULL;
    if (!rp || !rep_stab_is_image(rp, st->width, st->height) || rp->channel_count != b->channel_count) {
        if (b->reference && ref)
            b->reference = NULL; /* absent or unlike in one frame: not measured at all */
        return;
    }
    float *r = image_of(rp);
    size_t nv = (size_t)st->width * (size_t)st->height * (size_t)b->channel_count;
    if (!b->sum) {
        b->sum = rep_xcalloc(nv, sizeof *b->sum);
        b->sumsq = rep_xcalloc(nv, sizeof *b->sumsq);
    }
    for (size_t k = 0; k < nv; k++) {
        double e = (double)img[k] - (double)r[k];
        b->sum[k] += e;
        b->sumsq[k] += e * e;
    }
    b->ref_frames++;
    free(r);
}

int rep_stab_frame(rep_stab_run *st, const rep_frame_info *f, const rep_part *parts, int n, const rep_part *ref,
                   int ref_n, float ***flicker, int *flicker_count)
{
    if (flicker) {
        *flicker = NULL;
        *flicker_count = 0;
    }
    rep_stab_gbuffer g;
    if (!rep_stab_gbuffer_from_parts(parts, n, f, &g) ||
        (st->has_prev && (g.width != st->width || g.height != st->height))) {
        rep_stab_gbuffer_free(&g);
        st->enabled = 0;
        return 0;
    }
    if (!st->has_prev && st->frames == 0) {
        st->enabled = 1;
        st->width = g.width;
        st->height = g.height;
    }
    size_t np = (size_t)g.width * (size_t)g.height;
    uint8_t *smask = NULL, *cls = NULL;
    int32_t *src = NULL;
    if (st->has_prev) {
        smask = rep_xmalloc(np);
        cls = rep_xmalloc(np);
        src = rep_xmalloc(np * sizeof *src);
        rep_stab_static_mask(&st->prev, &g, smask);
        rep_stab_reproject(&st->prev, &g, src, cls);
        for (size_t i = 0; i < np; i++) {
            st->classes[cls[i]]++;
            st->static_pixels += smask[i];
        }
    }
    float **out = NULL;
    int out_n = 0;
    for (int k = 0; k < n; k++) {
        const rep_part *p = &parts[k];
        if (!rep_stab_is_image(p, st->width, st->height))
            continue;
        rep_stab_buffer *b = rep_stab_find(st, p->name);
        if (!b) {
            if (st->frames > 0)
                continue; /* not in frame 0: its history is unknown; replay reports the extra buffer */
            b = add_buffer(st, p);
        }
        if (b->channel_count != p->channel_count)
            continue;
        int nc = b->channel_count;
        float *img = image_of(p);
        float *fl = NULL;
        if (flicker)
            fl = rep_xmalloc(np * sizeof *fl);
        if (st->has_prev && b->prev) {
            float *sv = rep_xmalloc(np * sizeof *sv), *rv = rep_xmalloc(np * sizeof *rv);
            size_t sn = 0, rn = 0;
            for (size_t i = 0; i < np; i++) {
                const float *a = img + i * (size_t)nc;
                if (smask[i]) {
                    const float *o = b->prev + i * (size_t)nc;
                    float v = (float)rep_stab_flicker(a, o, nc);
                    sv[sn++] = v;
                    push(&b->sv, &b->sn, &b->scap, v);
                    b->static_changed += memcmp(a, o, (size_t)nc * sizeof(float)) != 0;
                }
                if (src[i] >= 0) {
                    const float *o = b->prev + (size_t)src[i] * (size_t)nc;
                    float v = (float)rep_stab_flicker(a, o, nc);
                    rv[rn++] = v;
                    push(&b->rv, &b->rn, &b->rcap, v);
                    b->repro_changed += memcmp(a, o, (size_t)nc * sizeof(float)) != 0;
                    if (fl)
                        fl[i] = v;
                } else if (fl) {
                    fl[i] = -1.0f;
                }
            }
            rep_stab_stats s = {0}, r = {0};
            rep_stab_summarise(sv, sn, &s);
            rep_stab_summarise(rv, rn, &r);
            if (sn) {
                b->static_mean[f->index] = s.mean;
                b->static_p99[f->index] = s.p99;
            }
            if (rn) {
                b->repro_mean[f->index] = r.mean;
                b->repro_p99[f->index] = r.p99;
            }
            b->pairs++;
            free(sv);
            free(rv);
        } else if (fl) {
            for (size_t i = 0; i < np; i++)
                fl[i] = -1.0f;
        }
        accumulate_reference(st, b, img, ref, ref_n);
        free(b->prev);
        b->prev = img;
        if (fl) {
            out = rep_xrealloc(out, (size_t)(out_n + 1) * sizeof *out);
            out[out_n++] = fl;
        }
    }
    /* A buffer of frame 0 absent from this frame has no history for the next one. */
    for (int k = 0; k < st->buffer_count; k++)
        if (!part_named(parts, n, st->buffers[k].name)) {
            free(st->buffers[k].prev);
            st->buffers[k].prev = NULL;
        }
    free(smask);
    free(cls);
    free(src);
    rep_stab_gbuffer_free(&st->prev);
    st->prev = g;
    st->has_prev = 1;
    st->frames++;
    if (flicker) {
        *flicker = out;
        *flicker_count = out_n;
    } else {
        free(out);
    }
    return 1;
}

void rep_stab_finish(rep_stab_run *st)
{
    size_t np = (size_t)st->width * (size_t)st->height;
    for (int k = 0; k < st->buffer_count; k++) {
        rep_stab_buffer *b = &st->buffers[k];
        b->st.changed = b->static_changed;
        b->rp.changed = b->repro_changed;
        rep_stab_summarise(b->sv, b->sn, &b->st);
        rep_stab_summarise(b->rv, b->rn, &b->rp);
        b->tstd_mean = b->tstd_p99 = b->bias_mean = NAN;
        if (b->reference && b->ref_frames > 0 && b->sum) {
            float *sd = rep_xmalloc(np * sizeof *sd);
            double bias = 0, nf = (double)b->ref_frames;
            for (size_t i = 0; i < np; i++) {
                double worst = 0, wb = 0;
                for (int c = 0; c < b->channel_count; c++) {
                    size_t k2 = i * (size_t)b->channel_count + (size_t)c;
                    double mean = b->sum[k2] / nf;
                    double var = b->sumsq[k2] / nf - mean * mean;
                    double s = var > 0 ? sqrt(var) : 0;
                    if (s > worst)
                        worst = s;
                    if (fabs(mean) > wb)
                        wb = fabs(mean);
                }
                sd[i] = (float)worst;
                bias += wb;
            }
            rep_stab_stats s = {0};
            rep_stab_summarise(sd, np, &s);
            b->tstd_mean = s.mean;
            b->tstd_p99 = s.p99;
            b->bias_mean = bias / (double)np;
            free(sd);
        } else {
            b->reference = NULL;
        }
    }
}

void rep_stab_free(rep_stab_run *st)
{
    if (!st)
        return;
    for (int k = 0; k < st->buffer_count; k++) {
        rep_stab_buffer *b = &st->buffers[k];
        free(b->name);
        free(b->static_mean);
        free(b->static_p99);
        free(b->repro_mean);
        free(b->repro_p99);
        free(b->sv);
        free(b->rv);
        free(b->sum);
        free(b->sumsq);
        free(b->prev);
    }
    free(st->buffers);
    rep_stab_gbuffer_free(&st->prev);
    memset(st, 0, sizeof *st);
}
