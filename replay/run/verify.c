/* verify.c — a decoded part checked against its manifest record: what run.c does for each part
 * of a frame file and objects.c for each object. Size, channel set, the content digest
 * (eng_buffer_digest over the decoded floats) and the non-finite counts must all agree: a
 * mismatch is a corrupt or tampered file, named with the part. */
#include "rep_run.h"
#include "run_internal.h"

#include <string.h>

/* Does the decoded part have exactly the manifest's channel set? */
int rep_run_same_channels(const rep_part *p, const rep_buffer_info *b)
{
    if (p->channel_count != b->channel_count)
        return 0;
    for (int c = 0; c < b->channel_count; c++) {
        int found = 0;
        for (int k = 0; k < p->channel_count && !found; k++)
            found = strcmp(p->channels[k], b->channels[c]) == 0;
        if (!found)
            return 0;
    }
    return 1;
}

eng_result rep_run_verify_part(const char *path, const rep_part *p, const rep_buffer_info *b, eng_error *err)
{
    if (p->width != b->width || p->height != b->height)
        return eng_fail(err, ENG_ERR_INVALID, "%s: part %s: %dx%d in the file, %dx%d in the manifest", path,
                        p->name, p->width, p->height, b->width, b->height);
    if (!rep_run_same_channels(p, b))
        return eng_fail(err, ENG_ERR_INVALID, "%s: part %s: channels differ from the manifest's", path, p->name);
    eng_buffer view = rep_part_buffer(p);
    char dg[40];
    eng_buffer_digest(&view, dg);
    if (strcmp(dg, b->digest) != 0)
        return eng_fail(err, ENG_ERR_INVALID,
                        "%s: part %s: decoded digest %s does not match the manifest's %s (corrupt or tampered file)",
                        path, p->name, dg, b->digest);
    if (b->has_nonfinite_counts) {
        uint64_t nn, ni;
        eng_buffer_nonfinite(&view, &nn, &ni, NULL, NULL);
        if (nn != b->nan || ni != b->inf)
            return eng_fail(err, ENG_ERR_INVALID,
                            "%s: part %s: %llu NaN and %llu Inf decoded, the manifest says %llu and %llu", path,
                            p->name, (unsigned long long)nn, (unsigned long long)ni,
                            (unsigned long long)b->nan, (unsigned long long)b->inf);
    }
    return ENG_OK;
}

