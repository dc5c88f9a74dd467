/* tool_specular_compare.c — test and measurement helper for eye-specular surfaces: compares the pixels of
 * specular transmissive surfaces (gbuffer.material transmission > 0: the glass sphere) of a
 * recorded run's BUFFER (default composite.radiance) with a reference run's reference.full,
 * frame 0 of each. Prints one line:
 *   pixels N mean_ratio R block_p90 P black B
 * mean ratio = Σ test / Σ reference over those pixels; block p90 = the 90th percentile of the
 * relative error of 8×8-block means (rep_metric_bias with every other pixel zeroed); black =
 * those pixels where the run shows nothing (all channels 0) but the reference shows more than
 * 5% of the pixels' mean. With MASK_PART MASK_CHANNEL the pixels are those where that channel of
 * the run is > 0 instead (translucent.radiance A: the alphaMode BLEND pane).
 * usage: ispm_test_specular RUN REFERENCE_RUN [BUFFER [MASK_PART MASK_CHANNEL]] */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "metrics.h"
#include "rep_run.h"
#include "rep_util.h"

/* The RGB (or one named channel) of part `name` of frame 0, as w×h×n floats. */
static float *read_part(const char *dir, const char *name, const char *channel, int *w, int *h)
{
    rep_run *run = NULL;
    eng_error err;
    rep_part *parts = NULL;
    if (rep_run_open(dir, &run, &err) != ENG_OK || rep_run_read_frame(run, 0, &parts, &err) != ENG_OK) {
        fprintf(stderr, "%s\n", err.msg);
        exit(1);
    }
    int j = rep_frame_find(&run->frames[0], name);
    if (j < 0) {
        fprintf(stderr, "%s: frame 0 has no %s\n", dir, name);
        exit(1);
    }
    const rep_part *p = &parts[j];
    static const char *const RGB[] = {"R", "G", "B"};
    int n = channel ? 1 : 3, ch[3] = {-1, -1, -1};
    for (int c = 0; c < n; c++)
        for (int q = 0; q < p->channel_count; q++)
            if (!strcmp(p->channels[q], channel ? channel : RGB[c]))
                ch[c] = q;
    for (int c = 0; c < n; c++)
        if (ch[c] < 0) {
            fprintf(stderr, "%s: %s lacks a channel\n", dir, name);
            exit(1);
        }
    *w = p->width;
    *h = p->height;
    size_t npix = (size_t)p->width * (size_t)p->height;
    float *out = rep_xmalloc(npix * 3 * sizeof(float));
    for (size_t i = 0; i < npix; i++)
        for (int c = 0; c < n; c++)
            out[i * (size_t)n + (size_t)c] = p->data[i * (size_t)p->channel_count + (size_t)ch[c]];
    rep_parts_free(parts, run->frames[0].buffer_count);
    rep_run_close(run);
    return out;
}

int main(int argc, char **argv)
{
    if (argc != 3 && argc != 4 && argc != 6) {
        fprintf(stderr, "usage: %s RUN REFERENCE_RUN [BUFFER [MASK_PART MASK_CHANNEL]]\n", argv[0]);
        return 2;
    }
    int w, h, rw, rh, mw, mh;
    float *test = read_part(argv[1], argc >= 4 ? argv[3] : "composite.radiance", NULL, &w, &h);
    float *trans = read_part(argv[1], argc == 6 ? argv[4] : "gbuffer.material", argc == 6 ? argv[5] : "transmission",
                             &mw, &mh);
    float *ref = read_part(argv[2], "reference.full", NULL, &rw, &rh);
    if (rw != w || rh != h || mw != w || mh != h) {
        fprintf(stderr, "%s and %s differ in size\n", argv[1], argv[2]);
        return 1;
    }
    size_t npix = (size_t)w * (size_t)h, count = 0, black = 0;
    double sum_ref = 0.0;
    for (size_t i = 0; i < npix; i++) {
        if (trans[i] > 0.0f) {
            count++;
            sum_ref += (ref[3 * i] + ref[3 * i + 1] + ref[3 * i + 2]) / 3.0;
        } else {
            for (int c = 0; c < 3; c++)
                test[3 * i + (size_t)c] = ref[3 * i + (size_t)c] = 0.0f;
        }
    }
    double mean_ref = count ? sum_ref / (double)count : 0.0;
    for (size_t i = 0; i < npix; i++)
        if (trans[i] > 0.0f && test[3 * i] == 0.0f && test[3 * i + 1] == 0.0f && test[3 * i + 2] == 0.0f &&
            (ref[3 * i] + ref[3 * i + 1] + ref[3 * i + 2]) / 3.0 > 0.05 * mean_ref)
            black++;
    rep_metrics_bias m;
    rep_metric_bias(test, ref, w, h, NULL, &m);
    printf("pixels %zu mean_ratio %.4f block_p90 %.4f black %zu\n", count, m.mean_ratio, m.block_p90, black);
    free(test);
    free(trans);
    free(ref);
    return 0;
}
