/* tool_fake_reference.c — test helper: turns a recorded run into a stand-in reference run for
 * `ispm bench` by renaming its indirect.radiance part to reference.indirect and
 * composite.radiance to reference.full, in every frame's EXR and in manifest.json. A
 * buffer's digest covers its channel planes, not its name, so the run stays self-consistent
 * and replay's reader accepts it. (Real reference runs come from `ispm reference`.)
 *
 * usage: ispm_test_fake_reference RUN */
#include "cap.h"
#include "eng_core.h"
#include "oiio_shim.h"

#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int die(const char *msg)
{
    fprintf(stderr, "ispm_test_fake_reference: %s\n", msg);
    return 1;
}

static const char *renamed(const char *name)
{
    if (!strcmp(name, "indirect.radiance"))
        return "reference.indirect";
    if (!strcmp(name, "composite.radiance"))
        return "reference.full";
    return NULL;
}

int main(int argc, char **argv)
{
    if (argc != 2)
        return die("usage: RUN");
    const char *run = argv[1];
    char mpath[4096];
    snprintf(mpath, sizeof mpath, "%s/manifest.json", run);
    eng_error err;
    char *text;
    size_t len;
    if (eng_read_file(mpath, (size_t)1 << 30, &text, &len, &err) != ENG_OK)
        return die(err.msg);
    cJSON *root = cJSON_Parse(text);
    free(text);
    if (!root)
        return die("manifest.json is not JSON");
    const cJSON *f;
    int frame = 0, found = 0;
    cJSON_ArrayForEach(f, cJSON_GetObjectItem(root, "frames"))
    {
        cJSON *b;
        cJSON_ArrayForEach(b, cJSON_GetObjectItem(f, "buffers"))
        {
            const char *to = renamed(cJSON_GetStringValue(cJSON_GetObjectItem(b, "name")));
            if (to) {
                cJSON_ReplaceItemInObject(b, "name", cJSON_CreateString(to));
                found++;
            }
        }
        char path[4096];
        snprintf(path, sizeof path, "%s/frames/%06d.exr", run, frame++);
        rep_part *parts = NULL;
        int count = 0;
        if (rep_oiio_read_parts(path, (size_t)1 << 28, &parts, &count, &err) != ENG_OK)
            return die(err.msg);
        eng_buffer *bufs = calloc((size_t)count, sizeof *bufs);
        const eng_buffer **ptrs = calloc((size_t)count, sizeof *ptrs);
        for (int i = 0; i < count; i++) {
            bufs[i] = rep_part_buffer(&parts[i]);
            const char *to = renamed(parts[i].name);
            if (to)
                bufs[i].name = to;
            ptrs[i] = &bufs[i];
        }
        if (cap_write_exr(path, ptrs, count, &err) != ENG_OK)
            return die(err.msg);
        free(ptrs);
        free(bufs);
        rep_parts_free(parts, count);
    }
    if (found != 2 * frame)
        return die("every frame must hold indirect.radiance and composite.radiance");
    char *out = cJSON_Print(root);
    FILE *fo = fopen(mpath, "wb");
    if (!fo || fputs(out, fo) < 0 || fclose(fo) != 0)
        return die("cannot write the manifest");
    free(out);
    cJSON_Delete(root);
    return 0;
}
