/* tool_mutate_run.c — test helper: changes one channel of one pixel of one buffer in a
 * recorded run, as if the engine had produced that value, i.e. it rewrites the frame's EXR
 * and updates the buffer's digest and NaN/Inf counts in manifest.json so the run stays
 * self-consistent. Replay must then report the change as a difference (or a non-finite
 * value), not as file corruption.
 *
 * usage: ispm_test_mutate RUN FRAME BUFFER X Y CHANNEL (set|add) VALUE   (VALUE may be nan/inf) */
#include "cap.h"
#include "eng_core.h"
#include "oiio_shim.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int die(const char *msg)
{
    fprintf(stderr, "ispm_test_mutate: %s\n", msg);
    return 1;
}

int main(int argc, char **argv)
{
    if (argc != 9)
        return die("usage: RUN FRAME BUFFER X Y CHANNEL (set|add) VALUE");
    const char *run = argv[1], *buffer = argv[3], *channel = argv[6], *op = argv[7];
    int frame = atoi(argv[2]), x = atoi(argv[4]), y = atoi(argv[5]);
    float value = strtof(argv[8], NULL);
    char path[4096];
    snprintf(path, sizeof path, "%s/frames/%06d.exr", run, frame);
    eng_error err;
    rep_part *parts = NULL;
    int count = 0;
    if (rep_oiio_read_parts(path, (size_t)1 << 28, &parts, &count, &err) != ENG_OK)
        return die(err.msg);
    int target = -1;
    for (int i = 0; i < count; i++)
        if (!strcmp(parts[i].name, buffer))
            target = i;
    if (target < 0)
        return die("no such buffer");
    rep_part *p = &parts[target];
    int ch = -1;
    for (int c = 0; c < p->channel_count; c++)
        if (!strcmp(p->channels[c], channel))
            ch = c;
    if (ch < 0 || x < 0 || y < 0 || x >= p->width || y >= p->height)
        return die("no such channel or pixel");
    float *v = &p->data[((size_t)y * p->width + x) * p->channel_count + ch];
    *v = !strcmp(op, "add") ? *v + value : value;

    eng_buffer *bufs = calloc((size_t)count, sizeof *bufs);
    const eng_buffer **ptrs = calloc((size_t)count, sizeof *ptrs);
    for (int i = 0; i < count; i++) {
        bufs[i] = rep_part_buffer(&parts[i]);
        ptrs[i] = &bufs[i];
    }
    if (cap_write_exr(path, ptrs, count, &err) != ENG_OK)
        return die(err.msg);
    char digest[40];
    uint64_t nan_count, inf_count;
    int fx, fy;
    eng_buffer_digest(&bufs[target], digest);
    eng_buffer_nonfinite(&bufs[target], &nan_count, &inf_count, &fx, &fy);

    char mpath[4096];
    snprintf(mpath, sizeof mpath, "%s/manifest.json", run);
    char *text;
    size_t len;
    if (eng_read_file(mpath, (size_t)1 << 30, &text, &len, &err) != ENG_OK)
        return die(err.msg);
    cJSON *root = cJSON_Parse(text);
    free(text);
    cJSON *frames = cJSON_GetObjectItem(root, "frames");
    cJSON *f = cJSON_GetArrayItem(frames, frame);
    cJSON *b;
    int done = 0;
    cJSON_ArrayForEach(b, cJSON_GetObjectItem(f, "buffers"))
    {
        if (strcmp(cJSON_GetStringValue(cJSON_GetObjectItem(b, "name")), buffer) != 0)
            continue;
        cJSON_ReplaceItemInObject(b, "digest", cJSON_CreateString(digest));
        cJSON_ReplaceItemInObject(b, "nan", cJSON_CreateNumber((double)nan_count));
        cJSON_ReplaceItemInObject(b, "inf", cJSON_CreateNumber((double)inf_count));
        if (fx >= 0) {
            int xy[2] = {fx, fy};
            cJSON_ReplaceItemInObject(b, "first_nonfinite", cJSON_CreateIntArray(xy, 2));
        }
        done = 1;
    }
    if (!done)
        return die("buffer not in the manifest");
    char *out = cJSON_Print(root);
    FILE *fo = fopen(mpath, "wb");
    if (!fo || fputs(out, fo) < 0 || fclose(fo) != 0)
        return die("cannot write the manifest");
    free(out);
    cJSON_Delete(root);
    free(ptrs);
    free(bufs);
    rep_parts_free(parts, count);
    return 0;
}
