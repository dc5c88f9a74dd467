/* cmd_lineage.c — `ispm lineage RUN --frame F --pixel X,Y [--json]`: everything that made one
 * pixel of one recorded frame (replay/compare/lineage.h), as text or JSON, and the check that the
 * photons listed add up to the indirect method's own buffer at the pixel: Σ contribution =
 * <prefix>.indirect (or .irradiance) within LIN_PRECISION relative (the sum's order differs
 * from the GPU's blending order and the k-d tree's traversal order), and the number of photons
 * listed equals <prefix>.count exactly. */
#define _POSIX_C_SOURCE 200809L
#include "eng.h"
#include "lineage.h"
#include "rep_run.h"
#include "rep_util.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { LIN_OK = 0, LIN_MISMATCH = 1, LIN_INPUT = 2 };

/* Relative precision of Σ contributions against the buffer: |Σ − buffer| ≤ LIN_PRECISION ·
 * max(|buffer|, Σ|c|) per channel, plus LIN_ABS for values that are 0 in one float order. */
#define LIN_PRECISION 1e-5
#define LIN_ABS 1e-7

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ispm lineage RUN --frame F (--pixel X,Y [--json] [--chain N] | --check-all)\n"
            "\n"
            "Everything that made pixel (X, Y) (row 0 at the top) of frame F: the G-buffer sample; per light\n"
            "the shadow-map texel it was tested against (through the light's matrices in the manifest) and\n"
            "the verdict; every photon whose kernel covers the pixel's surface point, with its power,\n"
            "bounce, path density, origin (light, face, bounce-map texel) and its contribution by the\n"
            "engine's kernel; the indirect buffer's value and the sum of the contributions; the value at\n"
            "the pixel's coordinate in every other buffer (subsampled levels scaled, light-space buffers at\n"
            "the light's texel); and the same surface point in the other frames, followed by the motion\n"
            "vectors. The photons need photons.origin (ispm record --lineage).\n"
            "\n"
            "  -f, --frame F     frame index\n"
            "  -p, --pixel X,Y   eye pixel\n"
            "  -J, --json        JSON on stdout instead of text\n"
            "      --chain N     follow the surface point N frames each way (default: every frame)\n"
            "      --check-all   instead: the sum check at every surface pixel of the frame (pixels checked,\n"
            "                    largest relative difference, pixels whose photon count differs)\n"
            "\n"
            "exit: 0 printed (and the contributions add up to the indirect buffer within %g relative,\n"
            "      with as many photons as its count); 1 they do not; 2 bad arguments, unreadable run,\n"
            "      no such frame or pixel\n",
            LIN_PRECISION);
}

static cJSON *jarr(const float *v, int n)
{
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; i < n; i++)
        cJSON_AddItemToArray(a, cJSON_CreateNumber((double)v[i]));
    return a;
}

static cJSON *jint2(int a, int b)
{
    cJSON *o = cJSON_CreateArray();
    cJSON_AddItemToArray(o, cJSON_CreateNumber(a));
    cJSON_AddItemToArray(o, cJSON_CreateNumber(b));
    return o;
}

/* Whether Σ contributions match the buffer (see LIN_PRECISION); *rel gets the largest
 * relative difference. */
static int sum_matches(const lin_result *r, double *rel)
{
    *rel = 0.0;
    int ok = 1;
    for (int c = 0; c < 3; c++) {
        double mag = 0.0;
        for (int i = 0; i < r->photon_count; i++)
            mag += fabs((double)r->photons[i].contribution[c]);
        double scale = fmax(fabs((double)r->splat[c]), mag);
        double d = fabs(r->sum[c] - (double)r->splat[c]);
        double e = scale > 0.0 ? d / scale : 0.0;
        *rel = fmax(*rel, e);
        ok &= d <= LIN_PRECISION * scale + LIN_ABS;
    }
    return ok && (float)r->photon_count == r->splat_count;
}

typedef struct chain_step {
    int frame, x, y;
    float position[3], composite[3];
} chain_step;

/* The surface point of (x, y) in frame f followed through the other frames. */
static int follow(const rep_run *run, const lin_manifest *m, int frame, int x, int y, int chain, chain_step *steps,
                  eng_error *err)
{
    int n = run->frame_count, count = 0;
    int lo = chain < 0 || frame - chain < 0 ? 0 : frame - chain;
    int hi = chain < 0 || frame + chain >= n ? n - 1 : frame + chain;
    rep_part **parts = rep_xcalloc((size_t)n, sizeof *parts);
    eng_buffer **bufs = rep_xcalloc((size_t)n, sizeof *bufs);
    eng_result r = ENG_OK;
    for (int f = lo; f <= hi && r == ENG_OK; f++) {
        r = rep_run_read_frame(run, f, &parts[f], err);
        if (r != ENG_OK)
            break;
        bufs[f] = rep_xcalloc((size_t)run->frames[f].buffer_count + 1, sizeof **bufs);
        for (int j = 0; j < run->frames[f].buffer_count; j++)
            bufs[f][j] = rep_part_buffer(&parts[f][j]);
    }
    if (r == ENG_OK) {
        int px[2] = {x, y};
        int *at = rep_xcalloc((size_t)n * 3, sizeof *at); /* frame's pixel and whether reached */
        at[frame * 3] = x;
        at[frame * 3 + 1] = y;
        at[frame * 3 + 2] = 1;
        for (int f = frame; f > lo; f--) {
            lin_frame fr = {bufs[f], run->frames[f].buffer_count, m, &m->frames[f]};
            if (!lin_follow_back(&fr, px[0], px[1], &px[0], &px[1]))
                break;
            at[(f - 1) * 3] = px[0];
            at[(f - 1) * 3 + 1] = px[1];
            at[(f - 1) * 3 + 2] = 1;
        }
        px[0] = x;
        px[1] = y;
        for (int f = frame + 1; f <= hi; f++) {
            lin_frame fr = {bufs[f], run->frames[f].buffer_count, m, &m->frames[f]};
            if (!lin_follow_forward(&fr, px[0], px[1], 4, &px[0], &px[1]))
                break;
            at[f * 3] = px[0];
            at[f * 3 + 1] = px[1];
            at[f * 3 + 2] = 1;
        }
        for (int f = 0; f < n; f++) {
            if (!at[f * 3 + 2])
                continue;
            lin_frame fr = {bufs[f], run->frames[f].buffer_count, m, &m->frames[f]};
            chain_step *s = &steps[count++];
            s->frame = f;
            s->x = at[f * 3];
            s->y = at[f * 3 + 1];
            const eng_buffer *pos = lin_find(&fr, "gbuffer.position"), *comp = lin_find(&fr, "composite.radiance");
            memset(s->position, 0, sizeof s->position);
            memset(s->composite, 0, sizeof s->composite);
            lin_read_named(pos, s->x, s->y, "X,Y,Z", s->position);
            lin_read_named(comp, s->x, s->y, "R,G,B", s->composite);
        }
        free(at);
    }
    for (int f = 0; f < n; f++) {
        if (parts[f])
            rep_parts_free(parts[f], run->frames[f].buffer_count);
        free(bufs[f]);
    }
    free(parts);
    free(bufs);
    return r == ENG_OK ? count : -1;
}

static cJSON *to_json(const char *dir, const lin_manifest *m, int frame, const lin_result *r, const chain_step *steps,
                      int nsteps, int checked, int ok, double rel)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "run", dir);
    cJSON_AddNumberToObject(o, "frame", frame);
    cJSON_AddItemToObject(o, "pixel", jint2(r->x, r->y));
    cJSON_AddStringToObject(o, "indirect", m->indirect);
    cJSON_AddBoolToObject(o, "covered", r->covered);
    cJSON *g = cJSON_AddObjectToObject(o, "gbuffer");
    cJSON_AddItemToObject(g, "position", jarr(r->position, 3));
    cJSON_AddItemToObject(g, "normal", jarr(r->normal, 3));
    cJSON_AddItemToObject(g, "albedo", jarr(r->albedo, 3));
    cJSON_AddItemToObject(g, "material", jarr(r->material, 4));
    cJSON_AddNumberToObject(g, "depth", r->depth);
    cJSON_AddItemToObject(g, "motion", jarr(r->motion, 2));
    cJSON *ls = cJSON_AddArrayToObject(o, "lights");
    for (int i = 0; i < r->shadow_count; i++) {
        const lin_shadow *s = &r->shadows[i];
        cJSON *l = cJSON_CreateObject();
        cJSON_AddNumberToObject(l, "light", s->light);
        cJSON_AddStringToObject(l, "map", s->map);
        cJSON_AddNumberToObject(l, "face", s->face);
        cJSON_AddItemToObject(l, "uv", jarr(s->uv, 2));
        cJSON_AddItemToObject(l, "texel", jint2(s->texel[0], s->texel[1]));
        cJSON_AddNumberToObject(l, "distance", s->distance);
        cJSON_AddNumberToObject(l, "compared", s->compared);
        cJSON_AddNumberToObject(l, "stored", s->stored);
        cJSON_AddNumberToObject(l, "tolerance", s->tolerance);
        cJSON_AddStringToObject(l, "verdict", s->outside ? (s->lit ? "outside, lit" : "outside, unlit")
                                              : s->lit  ? "lit"
                                                        : "shadowed");
        cJSON_AddNumberToObject(l, "visibility", s->visibility);
        cJSON_AddItemToArray(ls, l);
    }
    if (!r->has_photons) {
        cJSON_AddNullToObject(o, "photons");
        cJSON_AddStringToObject(o, "photons_why", r->why ? r->why : "");
    } else {
        cJSON_AddNumberToObject(o, "photons_in_map", r->map_photons);
        cJSON *ps = cJSON_AddArrayToObject(o, "photons");
        for (int i = 0; i < r->photon_count; i++) {
            const lin_photon *p = &r->photons[i];
            cJSON *j = cJSON_CreateObject();
            cJSON_AddNumberToObject(j, "index", p->index);
            cJSON_AddItemToObject(j, "position", jarr(p->position, 3));
            cJSON_AddItemToObject(j, "power", jarr(p->power, 3));
            cJSON_AddNumberToObject(j, "bounce", p->bounce);
            cJSON_AddNumberToObject(j, "density", p->density);
            cJSON_AddNumberToObject(j, "light", p->light);
            cJSON_AddNumberToObject(j, "face", p->face);
            cJSON_AddItemToObject(j, "bounce_texel", jint2(p->texel[0], p->texel[1]));
            cJSON_AddNumberToObject(j, "radius", p->radius);
            cJSON_AddItemToObject(j, "contribution", jarr(p->contribution, 3));
            if (r->irradiance)
                cJSON_AddItemToObject(j, "glossy", jarr(p->glossy, 3));
            cJSON_AddItemToArray(ps, j);
        }
        float sum[3] = {(float)r->sum[0], (float)r->sum[1], (float)r->sum[2]};
        cJSON_AddItemToObject(o, "sum", jarr(sum, 3));
    }
    if (r->splat_name)
        cJSON_AddStringToObject(o, "splat_buffer", r->splat_name);
    if (r->has_splat) {
        cJSON_AddItemToObject(o, "splat_pixel", jint2(r->splat_x, r->splat_y));
        cJSON_AddNumberToObject(o, "splat_level", r->splat_level);
        cJSON_AddItemToObject(o, "splat", jarr(r->splat, 3));
        cJSON_AddNumberToObject(o, "splat_count", r->splat_count);
    }
    if (checked) {
        cJSON *c = cJSON_AddObjectToObject(o, "check");
        cJSON_AddNumberToObject(c, "precision", LIN_PRECISION);
        cJSON_AddNumberToObject(c, "relative_difference", rel);
        cJSON_AddBoolToObject(c, "count_equal", (float)r->photon_count == r->splat_count);
        cJSON_AddBoolToObject(c, "ok", ok);
    }
    cJSON *bs = cJSON_AddArrayToObject(o, "buffers");
    for (int i = 0; i < r->value_count; i++) {
        const lin_value *v = &r->values[i];
        cJSON *b = cJSON_CreateObject();
        cJSON_AddStringToObject(b, "name", v->name);
        cJSON_AddItemToObject(b, "pixel", jint2(v->x, v->y));
        cJSON *vals = cJSON_AddObjectToObject(b, "values");
        for (int k = 0; k < v->channel_count && k < 8; k++)
            cJSON_AddNumberToObject(vals, v->channels[k], v->v[k]);
        cJSON_AddItemToArray(bs, b);
    }
    cJSON *ch = cJSON_AddArrayToObject(o, "motion_chain");
    for (int i = 0; i < nsteps; i++) {
        const chain_step *s = &steps[i];
        cJSON *j = cJSON_CreateObject();
        cJSON_AddNumberToObject(j, "frame", s->frame);
        cJSON_AddItemToObject(j, "pixel", jint2(s->x, s->y));
        cJSON_AddItemToObject(j, "position", jarr(s->position, 3));
        float d[3] = {s->position[0] - r->position[0], s->position[1] - r->position[1],
                      s->position[2] - r->position[2]};
        cJSON_AddNumberToObject(j, "distance", sqrt((double)(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])));
        cJSON_AddItemToObject(j, "composite", jarr(s->composite, 3));
        cJSON_AddItemToArray(ch, j);
    }
    return o;
}

static void print_text(const lin_manifest *m, int frame, const lin_result *r, const chain_step *steps, int nsteps,
                       int checked, int ok, double rel)
{
    printf("frame %d pixel (%d, %d)  indirect method %s\n", frame, r->x, r->y, m->indirect);
    printf("gbuffer: %s position (%g, %g, %g) normal (%g, %g, %g) albedo (%g, %g, %g)\n",
           r->covered ? "surface" : "background", r->position[0], r->position[1], r->position[2], r->normal[0],
           r->normal[1], r->normal[2], r->albedo[0], r->albedo[1], r->albedo[2]);
    printf("         roughness %g metallic %g transmission %g ior %g depth %g motion (%g, %g)\n", r->material[0],
           r->material[1], r->material[2], r->material[3], r->depth, r->motion[0], r->motion[1]);
    for (int i = 0; i < r->shadow_count; i++) {
        const lin_shadow *s = &r->shadows[i];
        printf("light %d: %s texel (%d, %d) uv (%.5f, %.5f): stored %g vs compared %g (+%g), distance %g: %s, "
               "PCF visibility %g\n",
               s->light, s->map, s->texel[0], s->texel[1], s->uv[0], s->uv[1], s->stored, s->compared, s->tolerance,
               s->distance, s->outside ? "outside the map" : s->lit ? "lit" : "shadowed", s->visibility);
    }
    if (!r->has_photons) {
        printf("photons: not listed (%s)\n", r->why ? r->why : "");
    } else {
        printf("photons: %d of %d cover the surface point\n", r->photon_count, r->map_photons);
        for (int i = 0; i < r->photon_count; i++) {
            const lin_photon *p = &r->photons[i];
            printf("  #%d bounce %d light %d face %d texel (%d, %d) power (%g, %g, %g) density %g radius %g -> "
                   "(%g, %g, %g)\n",
                   p->index, p->bounce, p->light, p->face, p->texel[0], p->texel[1], p->power[0], p->power[1],
                   p->power[2], p->density, p->radius, p->contribution[0], p->contribution[1], p->contribution[2]);
        }
        printf("sum: (%g, %g, %g)\n", r->sum[0], r->sum[1], r->sum[2]);
    }
    if (r->has_splat)
        printf("%s at (%d, %d)%s: (%g, %g, %g), count %g\n", r->splat_name, r->splat_x, r->splat_y,
               r->splat_level ? " (a subsampled level: photons evaluated at its surface point)" : "", r->splat[0],
               r->splat[1], r->splat[2], r->splat_count);
    if (checked)
        printf("check: %s (relative difference %.3g, precision %g; count %s)\n", ok ? "ok" : "MISMATCH", rel,
               LIN_PRECISION, (float)r->photon_count == r->splat_count ? "equal" : "differs");
    printf("buffers:\n");
    for (int i = 0; i < r->value_count; i++) {
        const lin_value *v = &r->values[i];
        printf("  %-40s (%d, %d)", v->name, v->x, v->y);
        for (int k = 0; k < v->channel_count && k < 8; k++)
            printf(" %s=%g", v->channels[k], v->v[k]);
        printf("\n");
    }
    printf("the surface point across frames (motion vectors):\n");
    for (int i = 0; i < nsteps; i++)
        printf("  frame %d pixel (%d, %d) position (%g, %g, %g) composite (%g, %g, %g)\n", steps[i].frame, steps[i].x,
               steps[i].y, steps[i].position[0], steps[i].position[1], steps[i].position[2], steps[i].composite[0],
               steps[i].composite[1], steps[i].composite[2]);
}

/* --check-all: the sum check at every surface pixel of the frame. */
static int check_all(const lin_frame *fr)
{
    int pixels = 0, bad = 0, count_bad = 0, photons = 0;
    double worst = 0.0;
    for (int y = 0; y < fr->m->height; y++)
        for (int x = 0; x < fr->m->width; x++) {
            lin_result r;
            eng_error err;
            if (lin_pixel(fr, x, y, &r, &err) != ENG_OK) {
                fprintf(stderr, "ispm lineage: %s\n", err.msg);
                return LIN_INPUT;
            }
            if (!r.has_photons || !r.has_splat) {
                fprintf(stderr, "ispm lineage: %s\n", r.why ? r.why : "no indirect buffer at the eye resolution");
                lin_result_free(&r);
                return LIN_INPUT;
            }
            if (r.splat_covered) {
                double rel;
                pixels++;
                photons += r.photon_count;
                int ok = sum_matches(&r, &rel);
                bad += !ok;
                count_bad += (float)r.photon_count != r.splat_count;
                worst = fmax(worst, rel);
            }
            lin_result_free(&r);
        }
    printf("%d surface pixels, %d photons listed: largest relative difference %.3g (precision %g), %d pixels "
           "over it, %d with another photon count\n",
           pixels, photons, worst, LIN_PRECISION, bad, count_bad);
    return bad ? LIN_MISMATCH : LIN_OK;
}

int cmd_lineage(int argc, char **argv)
{
    static const struct option opts[] = {{"frame", required_argument, NULL, 'f'},
                                         {"pixel", required_argument, NULL, 'p'},
                                         {"json", no_argument, NULL, 'J'},
                                         {"check-all", no_argument, NULL, 'A'},
                                         {"chain", required_argument, NULL, 'C'},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    long frame = -1;
    int x = -1, y = -1, json = 0, all = 0, chain = -1, c;
    while ((c = getopt_long(argc, argv, "f:p:Jh", opts, NULL)) != -1) {
        switch (c) {
        case 'f': {
            char *end;
            frame = strtol(optarg, &end, 10);
            if (!*optarg || *end || frame < 0) {
                fprintf(stderr, "ispm lineage: --frame: '%s' is not a frame index\n", optarg);
                return LIN_INPUT;
            }
            break;
        }
        case 'p': {
            /* Each coordinate in 0..65535 (strtol, not sscanf's %d, which wraps what it cannot
             * hold): the run then says whether the pixel is in the frame. */
            char *end, *end2 = NULL;
            errno = 0;
            long px = strtol(optarg, &end, 10), py = -1;
            if (end != optarg && *end == ',' && end[1] >= '0' && end[1] <= '9')
                py = strtol(end + 1, &end2, 10);
            if (errno || !end2 || *end2 || optarg[0] < '0' || optarg[0] > '9' || px > 65535 || py < 0 || py > 65535) {
                fprintf(stderr, "ispm lineage: --pixel: '%s' is not X,Y (each 0..65535)\n", optarg);
                return LIN_INPUT;
            }
            x = (int)px;
            y = (int)py;
            break;
        }
        case 'J': json = 1; break;
        case 'A': all = 1; break;
        case 'C': {
            char *end;
            long v = strtol(optarg, &end, 10);
            if (!*optarg || *end || v < 0 || v > 100000) {
                fprintf(stderr, "ispm lineage: --chain: '%s' is not a number of frames\n", optarg);
                return LIN_INPUT;
            }
            chain = (int)v;
            break;
        }
        case 'h': usage(stdout); return LIN_OK;
        default: usage(stderr); return LIN_INPUT;
        }
    }
    if (optind + 1 != argc || frame < 0 || (x < 0) == !all) {
        usage(stderr);
        return LIN_INPUT;
    }
    const char *dir = argv[optind];
    eng_error err = {{0}};
    rep_run *run = NULL;
    lin_manifest m;
    if (rep_run_open(dir, &run, &err) != ENG_OK || lin_manifest_read(dir, &m, &err) != ENG_OK) {
        fprintf(stderr, "ispm lineage: %s\n", err.msg);
        rep_run_close(run);
        return LIN_INPUT;
    }
    int rc = LIN_INPUT;
    rep_part *parts = NULL;
    eng_buffer *bufs = NULL;
    chain_step *steps = NULL;
    lin_result r;
    memset(&r, 0, sizeof r);
    if (frame >= run->frame_count || m.frame_count != run->frame_count) {
        fprintf(stderr, "ispm lineage: %s: no frame %ld (%d frames)\n", dir, frame, run->frame_count);
        goto done;
    }
    if (rep_run_read_frame(run, (int)frame, &parts, &err) != ENG_OK) {
        fprintf(stderr, "ispm lineage: %s\n", err.msg);
        goto done;
    }
    int nb = run->frames[frame].buffer_count;
    bufs = rep_xcalloc((size_t)nb + 1, sizeof *bufs);
    for (int j = 0; j < nb; j++)
        bufs[j] = rep_part_buffer(&parts[j]);
    lin_frame fr = {bufs, nb, &m, &m.frames[frame]};
    if (all) {
        rc = check_all(&fr);
        goto done;
    }
    if (lin_pixel(&fr, x, y, &r, &err) != ENG_OK) {
        fprintf(stderr, "ispm lineage: %s: frame %ld: %s\n", dir, frame, err.msg);
        goto done;
    }
    steps = rep_xcalloc((size_t)run->frame_count, sizeof *steps);
    int nsteps = r.covered ? follow(run, &m, (int)frame, x, y, chain, steps, &err) : 0;
    if (nsteps < 0) {
        fprintf(stderr, "ispm lineage: %s\n", err.msg);
        goto done;
    }
    double rel = 0.0;
    int checked = r.has_photons && r.has_splat && r.splat_covered;
    int ok = checked ? sum_matches(&r, &rel) : 1;
    if (json) {
        cJSON *o = to_json(dir, &m, (int)frame, &r, steps, nsteps, checked, ok, rel);
        char *text = cJSON_Print(o);
        if (!text) {
            fprintf(stderr, "ispm: out of memory\n");
            abort();
        }
        printf("%s\n", text);
        free(text);
        cJSON_Delete(o);
    } else {
        print_text(&m, (int)frame, &r, steps, nsteps, checked, ok, rel);
    }
    rc = ok ? LIN_OK : LIN_MISMATCH;
done:
    lin_result_free(&r);
    free(steps);
    free(bufs);
    if (parts)
        rep_parts_free(parts, run->frames[frame].buffer_count);
    lin_manifest_free(&m);
    rep_run_close(run);
    return rc;
}
