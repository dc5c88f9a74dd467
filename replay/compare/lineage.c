/* lineage.c — pixel lineage (lineage.h).
 *
 * Shadow tests repeat shaders/shadow_pcf.glsl's shadow_lookup on the CPU with the light's
 * matrices the manifest records per frame (eng_light_record): normal offset of bias + 1.5
 * texels, the cube face of the offset point, its map coordinates, the centre tap compared as
 * `compared <= stored + texel`. Photons are evaluated with eng_photon_contribution, i.e. the
 * kernel the CPU methods share and the photon-volume shader mirrors (gather_kernel.h, ISPM
 * 003_… §5 Eq. 1–3), with the radius the engine used that frame (photons.origin), so their sum
 * is the method's own value at the pixel up to the order of the float sum (the GPU's blending
 * order, the k-d tree's traversal order). The quads' kernel is another one (001 §3.3,
 * quad_kernel.glsl): for "quads" the photons are not listed.
 *
 * Buffers other than the light-space ones are read at the pixel's coordinate in their own
 * size (lin_scale: subsampled levels scaled); the light-space ones (shadow, lightgbuffer,
 * bounce) at the texel the pixel projects to through its light's matrices. */
#define _POSIX_C_SOURCE 200809L
#include "lineage.h"
#include "rep_util.h"
#include "kernel.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- manifest */

static float num_or(const cJSON *o, const char *key, float dflt)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(v) ? (float)v->valuedouble : dflt;
}

eng_result lin_manifest_read(const char *run_dir, lin_manifest *m, eng_error *err)
{
    memset(m, 0, sizeof *m);
    char *path = rep_path_join(run_dir, "manifest.json");
    cJSON *j = NULL;
    eng_result r = rep_json_load(path, ENG_IN_NOFOLLOW, &j, err);
    if (r != ENG_OK) {
        free(path);
        return r;
    }
    const cJSON *res = cJSON_GetObjectItemCaseSensitive(j, "resolution");
    const cJSON *frames = cJSON_GetObjectItemCaseSensitive(j, "frames");
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(j, "settings");
    if (cJSON_GetArraySize(res) != 2 || !cJSON_IsArray(frames) || !cJSON_IsObject(s)) {
        r = eng_fail(err, ENG_ERR_INVALID, "%s: no \"resolution\", \"settings\" or \"frames\"", path);
        goto done;
    }
    m->width = cJSON_GetArrayItem(res, 0)->valueint;
    m->height = cJSON_GetArrayItem(res, 1)->valueint;
    const cJSON *ind = cJSON_GetObjectItemCaseSensitive(s, "indirect");
    snprintf(m->indirect, sizeof m->indirect, "%s", cJSON_IsString(ind) ? ind->valuestring : "ispm");
    m->compression = num_or(s, "normal_compression", 0.25f);
    m->shadow_bias = num_or(s, "shadow_bias", 0.002f);
    m->pcf_radius = (int)num_or(s, "pcf_radius", 1.0f);
    m->frame_count = cJSON_GetArraySize(frames);
    m->frames = rep_xcalloc(m->frame_count ? (size_t)m->frame_count : 1, sizeof *m->frames);
    for (int i = 0; i < m->frame_count; i++) {
        const cJSON *f = cJSON_GetArrayItem(frames, i);
        lin_frame_meta *fm = &m->frames[i];
        const cJSON *cam = cJSON_GetObjectItemCaseSensitive(f, "camera");
        const cJSON *vp = cJSON_GetObjectItemCaseSensitive(cam, "view_proj");
        const cJSON *eye = cJSON_GetObjectItemCaseSensitive(cam, "eye");
        if (cJSON_GetArraySize(vp) == 16 && cJSON_GetArraySize(eye) == 3) {
            fm->has_camera = 1;
            for (int k = 0; k < 16; k++)
                fm->view_proj[k] = (float)cJSON_GetArrayItem(vp, k)->valuedouble;
            for (int k = 0; k < 3; k++)
                fm->eye[k] = (float)cJSON_GetArrayItem(eye, k)->valuedouble;
        }
        r = eng_light_records_parse(path, cJSON_GetObjectItemCaseSensitive(f, "lights"), &fm->light_count,
                                    fm->lights, err);
        if (r != ENG_OK)
            goto done;
    }
    r = ENG_OK;
done:
    cJSON_Delete(j);
    free(path);
    if (r != ENG_OK)
        lin_manifest_free(m);
    return r;
}

void lin_manifest_free(lin_manifest *m)
{
    if (!m)
        return;
    free(m->frames);
    memset(m, 0, sizeof *m);
}

/* ---------------------------------------------------------------- buffers */

const eng_buffer *lin_find(const lin_frame *fr, const char *name)
{
    for (int i = 0; i < fr->count; i++)
        if (fr->bufs[i].name && strcmp(fr->bufs[i].name, name) == 0)
            return &fr->bufs[i];
    return NULL;
}

static int channel(const eng_buffer *b, const char *name)
{
    for (int c = 0; c < b->channel_count; c++)
        if (strcmp(b->channels[c], name) == 0)
            return c;
    return -1;
}

/* n channels of b at (x, y) into out (0 where b is NULL or lacks them). */
static int read_px(const eng_buffer *b, int x, int y, int n, float *out)
{
    for (int c = 0; c < n; c++)
        out[c] = 0.0f;
    if (!b || x < 0 || y < 0 || x >= b->width || y >= b->height || b->channel_count < n)
        return 0;
    const float *p = b->data + ((size_t)y * (size_t)b->width + (size_t)x) * (size_t)b->channel_count;
    memcpy(out, p, (size_t)n * sizeof *out);
    return 1;
}

/* The channels called names[0..n) of b at (x, y) into out (EXR files keep channels sorted by
 * name, so they are found by name, never by position). 0 where b lacks one. */
static int read_named(const eng_buffer *b, int x, int y, const char *const *names, int n, float *out)
{
    float all[64];
    if (!b || b->channel_count > 64 || !read_px(b, x, y, b->channel_count, all))
        return 0;
    for (int k = 0; k < n; k++) {
        int c = channel(b, names[k]);
        if (c < 0)
            return 0;
        out[k] = all[c];
    }
    return 1;
}

int lin_read_named(const eng_buffer *b, int x, int y, const char *csv, float *out)
{
    char copy[128], *names[8], *save = NULL;
    int n = 0;
    snprintf(copy, sizeof copy, "%s", csv);
    for (char *t = strtok_r(copy, ",", &save); t && n < 8; t = strtok_r(NULL, ",", &save))
        names[n++] = t;
    return read_named(b, x, y, (const char *const *)names, n, out);
}

static const char *const XYZ[] = {"X", "Y", "Z"};
static const char *const RGB[] = {"R", "G", "B"};

void lin_scale(int x, int y, int w, int h, int bw, int bh, int *bx, int *by)
{
    *bx = (int)floor(((double)x + 0.5) * bw / w);
    *by = (int)floor(((double)y + 0.5) * bh / h);
    *bx = *bx < 0 ? 0 : *bx >= bw ? bw - 1 : *bx;
    *by = *by < 0 ? 0 : *by >= bh ? bh - 1 : *by;
}

static int is_light_space(const char *name)
{
    return strncmp(name, "shadow.light", 12) == 0 || strncmp(name, "lightgbuffer.light", 18) == 0 ||
           strncmp(name, "bounce.light", 12) == 0 || strncmp(name, "multiimage.", 11) == 0;
}

static void add_value(lin_result *r, const eng_buffer *b, int x, int y)
{
    lin_value *v = &r->values[r->value_count++];
    memset(v, 0, sizeof *v);
    v->name = b->name;
    v->x = x;
    v->y = y;
    v->channel_count = b->channel_count;
    v->channels = b->channels;
    int n = b->channel_count < 8 ? b->channel_count : 8;
    const float *p = b->data + ((size_t)y * (size_t)b->width + (size_t)x) * (size_t)b->channel_count;
    memcpy(v->v, p, (size_t)n * sizeof *p);
}

/* ---------------------------------------------------------------- shadows */

static float dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static float dist3(const float a[3], const float b[3])
{
    float d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrtf(dot3(d, d));
}

/* shadow_pcf.glsl cube_face */
static int cube_face(const float d[3])
{
    float a[3] = {fabsf(d[0]), fabsf(d[1]), fabsf(d[2])};
    if (a[0] >= a[1] && a[0] >= a[2])
        return d[0] > 0.0f ? 0 : 1;
    if (a[1] >= a[2])
        return d[1] > 0.0f ? 2 : 3;
    return d[2] > 0.0f ? 4 : 5;
}

/* "<pass>.light<l>[.face<f>]" */
static void light_name(char *out, size_t n, const char *pass, int l, int faces, int f)
{
    if (faces > 1)
        snprintf(out, n, "%s.light%d.face%d", pass, l, f);
    else
        snprintf(out, n, "%s.light%d", pass, l);
}

/* Light l's shadow test for surface point p (normal n); the values of its light-space
 * buffers at the projected texel go to r->values. */
static void shadow_test(const lin_frame *fr, int l, const float p[3], const float n[3], lin_result *r)
{
    const eng_light_record *L = &fr->meta->lights[l];
    lin_shadow *s = &r->shadows[r->shadow_count++];
    memset(s, 0, sizeof *s);
    s->light = l;
    s->distance = L->type == 2 ? dot3((float[3]){p[0] - L->position[0], p[1] - L->position[1], p[2] - L->position[2]},
                                      L->direction)
                               : dist3(p, L->position);
    float dist = dist3(p, L->position);
    s->tolerance = L->type == 2 ? L->texel : L->texel * dist;
    float q[3], d[3];
    for (int c = 0; c < 3; c++) {
        q[c] = p[c] + n[c] * (fr->m->shadow_bias + 1.5f * s->tolerance);
        d[c] = q[c] - L->position[c];
    }
    s->compared = L->type == 2 ? dot3(d, L->direction) : sqrtf(dot3(d, d));
    s->face = L->type == 0 ? cube_face(d) : 0;
    if (s->face >= L->faces)
        s->face = 0;
    const float *vp = L->view_proj[s->face];
    float c[4];
    for (int i = 0; i < 4; i++)
        c[i] = vp[i] * q[0] + vp[4 + i] * q[1] + vp[8 + i] * q[2] + vp[12 + i];
    s->uv[0] = c[0] / c[3] * 0.5f + 0.5f;
    s->uv[1] = c[1] / c[3] * 0.5f + 0.5f;
    light_name(s->map, sizeof s->map, "shadow", l, L->faces, s->face);
    if (L->type != 0 && (s->uv[0] < 0.0f || s->uv[0] > 1.0f || s->uv[1] < 0.0f || s->uv[1] > 1.0f)) {
        s->outside = 1;
        s->lit = s->visibility = L->type == 2 ? 1.0f : 0.0f;
        return;
    }
    const eng_buffer *map = lin_find(fr, s->map);
    if (!map || map->channel_count < 1)
        return;
    int size = map->width;
    int bx = (int)floorf(s->uv[0] * (float)size), by = (int)floorf(s->uv[1] * (float)size);
    int lit = 0, taps = 0;
    for (int dy = -fr->m->pcf_radius; dy <= fr->m->pcf_radius; dy++)
        for (int dx = -fr->m->pcf_radius; dx <= fr->m->pcf_radius; dx++) {
            int tx = bx + dx, ty = by + dy;
            tx = tx < 0 ? 0 : tx > size - 1 ? size - 1 : tx;
            ty = ty < 0 ? 0 : ty > size - 1 ? size - 1 : ty;
            float stored;
            read_px(map, tx, map->height - 1 - ty, 1, &stored); /* GL rows bottom up, the buffer top down */
            int ok = s->compared <= stored + s->tolerance;
            lit += ok;
            taps++;
            if (dx == 0 && dy == 0) {
                s->texel[0] = tx;
                s->texel[1] = map->height - 1 - ty;
                s->stored = stored;
                s->lit = ok;
            }
        }
    s->visibility = (float)lit / (float)taps;
    /* The light's other maps of that face, at the same map coordinates in their own size. */
    static const char *const passes[] = {"shadow", "lightgbuffer", "bounce"};
    char prefix[64];
    for (int k = 0; k < 3; k++) {
        light_name(prefix, sizeof prefix, passes[k], l, L->faces, s->face);
        size_t pl = strlen(prefix);
        for (int i = 0; i < fr->count; i++) {
            const eng_buffer *b = &fr->bufs[i];
            if (!b->name || strncmp(b->name, prefix, pl) != 0 || (b->name[pl] != 0 && b->name[pl] != '.'))
                continue;
            if (b->name[pl] == '.' && strncmp(b->name + pl + 1, "face", 4) == 0)
                continue; /* shadow.light0 is a prefix of shadow.light0.face1 only when faces = 1 */
            int tx = (int)floorf(s->uv[0] * (float)b->width), ty = (int)floorf(s->uv[1] * (float)b->height);
            tx = tx < 0 ? 0 : tx >= b->width ? b->width - 1 : tx;
            ty = ty < 0 ? 0 : ty >= b->height ? b->height - 1 : ty;
            add_value(r, b, tx, b->height - 1 - ty);
        }
    }
}

/* ---------------------------------------------------------------- photons */

static const char *const PH_CH[14] = {"position.X", "position.Y", "position.Z", "direction.X", "direction.Y",
                                      "direction.Z", "power.R",    "power.G",    "power.B",     "normal.X",
                                      "normal.Y",   "normal.Z",   "density",    "bounce"};
static const char *const OR_CH[5] = {"light", "face", "texel.X", "texel.Y", "radius"};

static void photons(const lin_frame *fr, lin_result *r)
{
    const eng_buffer *map = lin_find(fr, "photons.map");
    const eng_buffer *org = lin_find(fr, "photons.origin");
    if (strcmp(fr->m->indirect, "quads") == 0) {
        r->why = "the quads' kernel (001 §3.3) is not the photon-volume kernel lineage evaluates";
        return;
    }
    if (strcmp(fr->m->indirect, "final-gather") == 0) {
        r->why = "the final gather's pixels come from rays traced from them (photons looked up one bounce away), "
                 "not from kernels at the pixel";
        return;
    }
    if (!map || !org) {
        r->why = map ? "no photons.origin in the run (record it with ispm record --lineage)"
                     : "no photons.map in the run";
        return;
    }
    int pi[14], oi[5];
    for (int k = 0; k < 14; k++)
        if ((pi[k] = channel(map, PH_CH[k])) < 0) {
            r->why = "photons.map lacks a photon channel";
            return;
        }
    for (int k = 0; k < 5; k++)
        if ((oi[k] = channel(org, OR_CH[k])) < 0) {
            r->why = "photons.origin lacks a channel";
            return;
        }
    if (org->width != map->width || org->height != map->height) {
        r->why = "photons.origin and photons.map differ in size";
        return;
    }
    r->has_photons = 1;
    /* Where the method evaluated the photons: the splat buffer's own pixel (a subsampled
     * level's surface point), else the eye pixel's. */
    const float *sp = r->has_splat ? r->splat_position : r->position;
    const float *sn = r->has_splat ? r->splat_normal : r->normal;
    if (!(r->has_splat ? r->splat_covered : r->covered))
        return;
    size_t n = (size_t)map->width * (size_t)map->height;
    size_t cap = 64;
    r->photons = rep_xcalloc(cap, sizeof *r->photons);
    for (size_t i = 0; i < n; i++) {
        const float *src = map->data + i * (size_t)map->channel_count;
        const float *o = org->data + i * (size_t)org->channel_count;
        float ph[14];
        for (int k = 0; k < 14; k++)
            ph[k] = src[pi[k]];
        if (!(ph[13] > 0.0f))
            continue; /* an unused pixel */
        r->map_photons++;
        float rgb[3], g[3];
        if (!eng_photon_contribution(ph, o[oi[4]], fr->m->compression, sp, sn, r->albedo,
                                     r->material, fr->meta->eye, r->irradiance, rgb, g))
            continue;
        if ((size_t)r->photon_count == cap) {
            cap *= 2;
            lin_photon *p = realloc(r->photons, cap * sizeof *p);
            if (!p) {
                fprintf(stderr, "ispm: out of memory\n");
                abort();
            }
            r->photons = p;
        }
        lin_photon *p = &r->photons[r->photon_count++];
        p->index = (int)i;
        memcpy(p->position, ph, 3 * sizeof(float));
        memcpy(p->power, ph + 6, 3 * sizeof(float));
        p->density = ph[12];
        p->bounce = (int)ph[13];
        p->light = (int)o[oi[0]];
        p->face = (int)o[oi[1]];
        p->texel[0] = (int)o[oi[2]];
        p->texel[1] = (int)o[oi[3]];
        p->radius = o[oi[4]];
        for (int c = 0; c < 3; c++) {
            p->contribution[c] = rgb[c];
            p->glossy[c] = g[c];
            r->sum[c] += rgb[c];
        }
    }
}

/* ---------------------------------------------------------------- the pixel */

/* The indirect method's own buffer: <prefix>.indirect or .irradiance of splat/gather. */
static const eng_buffer *indirect_buffer(const lin_frame *fr, int *irradiance)
{
    static const char *const names[] = {"splat.indirect", "gather.indirect", "splat.irradiance",
                                        "gather.irradiance"};
    for (int k = 0; k < 4; k++) {
        const eng_buffer *b = lin_find(fr, names[k]);
        if (b) {
            *irradiance = k >= 2;
            return b;
        }
    }
    *irradiance = 0;
    return NULL;
}

/* The indirect buffer ib's value at its pixel for eye pixel (x, y), and the surface point the
 * method evaluated there (lineage.h: has_splat). */
static void splat_pixel(const lin_frame *fr, const eng_buffer *ib, int x, int y, lin_result *out)
{
    const int w = fr->m->width, h = fr->m->height;
    int sx = x, sy = y;
    if (ib->width == w && ib->height == h) {
        memcpy(out->splat_position, out->position, sizeof out->splat_position);
        memcpy(out->splat_normal, out->normal, sizeof out->splat_normal);
        out->splat_covered = out->covered;
    } else {
        lin_scale(x, y, w, h, ib->width, ib->height, &sx, &sy);
        int k = 1;
        const eng_buffer *pos = NULL, *nrm = NULL, *dep = NULL;
        for (; k < 16; k++) {
            char name[64];
            snprintf(name, sizeof name, "gbuffer.level%d.position", k);
            pos = lin_find(fr, name);
            if (pos && pos->width == ib->width && pos->height == ib->height)
                break;
        }
        if (k == 16)
            return; /* the level's G-buffer is not in the run */
        char name[64];
        snprintf(name, sizeof name, "gbuffer.level%d.normal", k);
        nrm = lin_find(fr, name);
        snprintf(name, sizeof name, "gbuffer.level%d.depth", k);
        dep = lin_find(fr, name);
        float d = 0.0f;
        if (!read_named(pos, sx, sy, XYZ, 3, out->splat_position) ||
            !read_named(nrm, sx, sy, XYZ, 3, out->splat_normal) || !read_px(dep, sx, sy, 1, &d))
            return;
        out->splat_level = k;
        out->splat_covered = d > 0.0f;
    }
    if (!read_named(ib, sx, sy, RGB, 3, out->splat))
        return;
    out->has_splat = 1;
    out->splat_x = sx;
    out->splat_y = sy;
    char cname[64];
    snprintf(cname, sizeof cname, "%.*s.count", (int)(strchr(ib->name, '.') - ib->name), ib->name);
    read_px(lin_find(fr, cname), sx, sy, 1, &out->splat_count);
}

eng_result lin_pixel(const lin_frame *fr, int x, int y, lin_result *out, eng_error *err)
{
    memset(out, 0, sizeof *out);
    const int w = fr->m->width, h = fr->m->height;
    if (x < 0 || y < 0 || x >= w || y >= h)
        return eng_fail(err, ENG_ERR_INVALID, "pixel (%d, %d) outside the %dx%d image", x, y, w, h);
    const eng_buffer *pos = lin_find(fr, "gbuffer.position"), *nrm = lin_find(fr, "gbuffer.normal");
    const eng_buffer *alb = lin_find(fr, "gbuffer.albedo"), *mat = lin_find(fr, "gbuffer.material");
    const eng_buffer *dep = lin_find(fr, "gbuffer.depth"), *mot = lin_find(fr, "gbuffer.motion");
    if (!pos || !nrm || !alb || !dep)
        return eng_fail(err, ENG_ERR_INVALID, "frame lacks gbuffer.position, .normal, .albedo or .depth");
    out->x = x;
    out->y = y;
    static const char *const MAT[] = {"roughness", "metallic", "transmission", "ior"};
    read_named(pos, x, y, XYZ, 3, out->position);
    read_named(nrm, x, y, XYZ, 3, out->normal);
    read_named(alb, x, y, RGB, 3, out->albedo);
    read_px(dep, x, y, 1, &out->depth);
    read_named(mot, x, y, XYZ, 2, out->motion);
    float m4[4] = {0.5f, 0.0f, 0.0f, 1.5f}; /* the glTF default material where none is captured */
    if (mat && !read_named(mat, x, y, MAT, 4, m4))
        memcpy(m4, (float[4]){0.5f, 0.0f, 0.0f, 1.5f}, sizeof m4);
    memcpy(out->material, m4, sizeof out->material);
    out->covered = out->depth > 0.0f;
    out->values = rep_xcalloc((size_t)fr->count + 1, sizeof *out->values);
    if (out->covered)
        for (int l = 0; l < fr->meta->light_count; l++)
            shadow_test(fr, l, out->position, out->normal, out);
    const eng_buffer *ib = indirect_buffer(fr, &out->irradiance);
    if (ib) {
        out->splat_name = ib->name;
        splat_pixel(fr, ib, x, y, out);
    }
    photons(fr, out);
    for (int i = 0; i < fr->count; i++) {
        const eng_buffer *b = &fr->bufs[i];
        if (!b->name || is_light_space(b->name) || strncmp(b->name, "photons.", 8) == 0 || b->width < 1 ||
            b->height < 1)
            continue;
        int bx, by;
        lin_scale(x, y, w, h, b->width, b->height, &bx, &by);
        add_value(out, b, bx, by);
    }
    return ENG_OK;
}

void lin_result_free(lin_result *r)
{
    if (!r)
        return;
    free(r->photons);
    free(r->values);
    memset(r, 0, sizeof *r);
}

/* ---------------------------------------------------------------- across frames */

int lin_follow_back(const lin_frame *fr, int x, int y, int *px, int *py)
{
    const eng_buffer *mot = lin_find(fr, "gbuffer.motion"), *dep = lin_find(fr, "gbuffer.depth");
    float m[2], d;
    if (!read_named(mot, x, y, XYZ, 2, m) || !read_px(dep, x, y, 1, &d) || !(d > 0.0f))
        return 0;
    float fx = (float)x + 0.5f + m[0], fy = (float)y + 0.5f + m[1];
    if (!(fx >= 0.0f && fy >= 0.0f && fx < (float)mot->width && fy < (float)mot->height))
        return 0;
    *px = (int)floorf(fx);
    *py = (int)floorf(fy);
    return 1;
}

int lin_follow_forward(const lin_frame *next, int x, int y, int window, int *nx, int *ny)
{
    const eng_buffer *mot = lin_find(next, "gbuffer.motion"), *dep = lin_find(next, "gbuffer.depth");
    if (!mot || !dep)
        return 0;
    float best = 1.0f;
    int found = 0;
    for (int j = y - window; j <= y + window; j++)
        for (int i = x - window; i <= x + window; i++) {
            float m[2], d;
            if (!read_named(mot, i, j, XYZ, 2, m) || !read_px(dep, i, j, 1, &d) || !(d > 0.0f))
                continue;
            float dx = (float)i + m[0] - (float)x, dy = (float)j + m[1] - (float)y;
            float e = dx * dx + dy * dy;
            if (e < best) {
                best = e;
                *nx = i;
                *ny = j;
                found = 1;
            }
        }
    return found;
}
