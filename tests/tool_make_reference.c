/* tool_make_reference.c — test helper: fabricates a reference run (what the reference renderer
 * will write) from a recorded run, for tests/e2e_stability.sh. Every frame of OUT holds
 * reference.indirect and reference.full, the per-pixel mean over all frames of the run's
 * indirect.radiance and composite.radiance: a temporally stable reference whose temporal error
 * is the run's own flicker about its mean. usage: ispm_test_reference RUN OUT */
#define _POSIX_C_SOURCE 200809L
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rep_run.h"
#include "rep_util.h"

static const char *const FROM[] = {"indirect.radiance", "composite.radiance"};
static const char *const TO[] = {"reference.indirect", "reference.full"};
static const char *const RGB[] = {"R", "G", "B"};

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: %s RUN OUT\n", argv[0]);
        return 2;
    }
    rep_run *run = NULL;
    eng_error err;
    if (rep_run_open(argv[1], &run, &err) != ENG_OK) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    int w = 0, h = 0;
    double *sum[2] = {NULL, NULL};
    for (int i = 0; i < run->frame_count; i++) {
        rep_part *parts = NULL;
        if (rep_run_read_frame(run, i, &parts, &err) != ENG_OK) {
            fprintf(stderr, "%s\n", err.msg);
            return 1;
        }
        for (int k = 0; k < 2; k++) {
            int j = rep_frame_find(&run->frames[i], FROM[k]);
            if (j < 0 || parts[j].channel_count != 3) {
                fprintf(stderr, "%s: frame %d has no RGB %s\n", argv[1], i, FROM[k]);
                return 1;
            }
            const rep_part *p = &parts[j];
            if (!sum[k]) {
                w = p->width, h = p->height;
                sum[k] = rep_xcalloc((size_t)w * (size_t)h * 3, sizeof(double));
            }
            int ch[3];
            for (int c = 0; c < 3; c++)
                for (int q = 0; q < 3; q++)
                    if (strcmp(p->channels[q], RGB[c]) == 0)
                        ch[c] = q;
            for (size_t x = 0; x < (size_t)w * (size_t)h; x++)
                for (int c = 0; c < 3; c++)
                    sum[k][x * 3 + (size_t)c] += p->data[x * 3 + (size_t)ch[c]];
        }
        rep_parts_free(parts, run->frames[i].buffer_count);
    }
    size_t nv = (size_t)w * (size_t)h * 3;
    float *mean[2];
    eng_buffer bufs[2];
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "format", "ispm-run");
    cJSON_AddNumberToObject(root, "format_version", 1);
    /* The keys docs/schema/manifest.schema.json requires of every run (e2e_manifest_schema
     * validates the runs the tests leave), named after this tool rather than ispm. */
    cJSON *tool = cJSON_AddObjectToObject(root, "tool");
    cJSON_AddStringToObject(tool, "name", "ispm_test_reference");
    cJSON *seq = cJSON_AddObjectToObject(root, "sequence");
    char *name = rep_xprintf("%s.reference", run->sequence_name ? run->sequence_name : "run");
    cJSON_AddStringToObject(seq, "name", name);
    free(name);
    cJSON *res = cJSON_AddArrayToObject(root, "resolution");
    cJSON_AddItemToArray(res, cJSON_CreateNumber(w));
    cJSON_AddItemToArray(res, cJSON_CreateNumber(h));
    cJSON_AddNumberToObject(root, "frame_count", run->frame_count);
    cJSON *frames = cJSON_AddArrayToObject(root, "frames");
    cJSON *jb = cJSON_CreateArray();
    for (int k = 0; k < 2; k++) {
        mean[k] = rep_xmalloc(nv * sizeof(float));
        for (size_t x = 0; x < nv; x++)
            mean[k][x] = (float)(sum[k][x] / run->frame_count);
        bufs[k] = (eng_buffer){TO[k], w, h, 3, RGB, mean[k]};
        char dg[40];
        eng_buffer_digest(&bufs[k], dg);
        cJSON *b = cJSON_CreateObject();
        cJSON_AddStringToObject(b, "name", TO[k]);
        cJSON_AddNumberToObject(b, "width", w);
        cJSON_AddNumberToObject(b, "height", h);
        cJSON_AddItemToObject(b, "channels", cJSON_CreateStringArray(RGB, 3));
        cJSON_AddStringToObject(b, "digest", dg);
        int nan = 0, inf = 0;
        for (size_t x = 0; x < nv; x++)
            nan += isnan(mean[k][x]) != 0, inf += isinf(mean[k][x]) != 0;
        cJSON_AddNumberToObject(b, "nan", nan);
        cJSON_AddNumberToObject(b, "inf", inf);
        cJSON_AddItemToArray(jb, b);
    }
    char *fdir = rep_path_join(argv[2], "frames");
    if (rep_mkdirs(fdir, &err) != ENG_OK) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    for (int i = 0; i < run->frame_count; i++) {
        char *file = rep_xprintf("frames/%06d.exr", i);
        char *path = rep_path_join(argv[2], file);
        if (rep_oiio_write_parts(path, bufs, 2, &err) != ENG_OK) {
            fprintf(stderr, "%s\n", err.msg);
            return 1;
        }
        cJSON *f = cJSON_CreateObject();
        cJSON_AddNumberToObject(f, "index", i);
        cJSON_AddNumberToObject(f, "time", run->frames[i].time);
        cJSON_AddStringToObject(f, "file", file);
        cJSON_AddItemToObject(f, "buffers", cJSON_Duplicate(jb, 1));
        cJSON_AddItemToArray(frames, f);
        free(file);
        free(path);
    }
    cJSON_AddBoolToObject(root, "complete", 1);
    char *text = cJSON_Print(root);
    char *mp = rep_path_join(argv[2], "manifest.json");
    if (rep_write_atomic(mp, text, strlen(text), &err) != ENG_OK) {
        fprintf(stderr, "%s\n", err.msg);
        return 1;
    }
    cJSON_free(text);
    cJSON_Delete(root);
    cJSON_Delete(jb);
    free(mp);
    free(fdir);
    for (int k = 0; k < 2; k++) {
        free(sum[k]);
        free(mean[k]);
    }
    rep_run_close(run);
    return 0;
}
