/* view_run.c — a recorded run as the viewer sees it: the manifest, and frames decoded lazily.
 *
 * Opening reads only the manifest, through replay's run reader (rep_run_open validates it
 * and checks that every frame file exists), so a run of any length opens at once. A run still
 * being recorded (no manifest.json yet, run.json there) opens with the frames that have landed
 * (rep_run_open_live: EXR and record both written) and grows by view_run_refresh. A frame's
 * EXR is decoded the first time it is asked for, verified against the manifest's digests by
 * rep_run_read_frame, and kept in a small least-recently-used cache: scrubbing back and forth
 * costs one decode per frame, and memory stays bounded by the cache size whatever the run's
 * length. OpenImageIO may present a part's channels in another order than they were written
 * (EXR sorts them); the viewer shows them in manifest order, so each buffer is reordered once
 * on decode. A frame that fails to decode stays in the cache as a failure, so a broken file
 * is reported once per eviction rather than re-read on every redraw.
 */
#include "view_model.h"

#include <stdlib.h>
#include <string.h>

#include "rep_run.h"
#include "rep_util.h"

typedef struct view_entry {
    int frame;          /* -1: empty slot */
    unsigned long used; /* LRU clock */
    eng_result result;
    eng_error error;
    rep_part *parts;
    int count;
    eng_buffer *bufs;   /* count views, channels and data in manifest order */
    float **owned;      /* reordered copies (NULL where the part's order already matched) */
} view_entry;

struct view_run {
    rep_run *run;
    int capacity;
    view_entry *entries;
    unsigned long clock;
    int decodes;
};

static void entry_clear(view_entry *e)
{
    if (e->owned)
        for (int i = 0; i < e->count; i++)
            free(e->owned[i]);
    free(e->owned);
    free(e->bufs);
    rep_parts_free(e->parts, e->count);
    memset(e, 0, sizeof *e);
    e->frame = -1;
}

eng_result view_run_open(const char *dir, int cache_frames, view_run **out, eng_error *err)
{
    *out = NULL;
    rep_run *run = NULL;
    eng_result r = rep_run_open_live(dir, &run, err);
    if (r != ENG_OK)
        return r;
    view_run *v = rep_xcalloc(1, sizeof *v);
    v->run = run;
    v->capacity = cache_frames < 1 ? 4 : cache_frames;
    v->entries = rep_xcalloc((size_t)v->capacity, sizeof *v->entries);
    for (int i = 0; i < v->capacity; i++)
        v->entries[i].frame = -1;
    *out = v;
    return ENG_OK;
}

void view_run_close(view_run *r)
{
    if (!r)
        return;
    for (int i = 0; i < r->capacity; i++)
        entry_clear(&r->entries[i]);
    free(r->entries);
    rep_run_close(r->run);
    free(r);
}

int view_run_frame_count(const view_run *r)
{
    return r->run->frame_count;
}

int view_run_buffer_count(const view_run *r, int f)
{
    return f >= 0 && f < r->run->frame_count ? r->run->frames[f].buffer_count : 0;
}

const char *view_run_buffer_name(const view_run *r, int f, int buffer)
{
    if (buffer < 0 || buffer >= view_run_buffer_count(r, f))
        return NULL;
    return r->run->frames[f].buffers[buffer].name;
}

int view_run_buffer_channels(const view_run *r, int f, int buffer)
{
    if (buffer < 0 || buffer >= view_run_buffer_count(r, f))
        return 0;
    return r->run->frames[f].buffers[buffer].channel_count;
}

int view_run_find(const view_run *r, int f, const char *name)
{
    if (f < 0 || f >= r->run->frame_count || !name)
        return -1;
    return rep_frame_find(&r->run->frames[f], name);
}

int view_run_decodes(const view_run *r)
{
    return r->decodes;
}

/* Fills e->bufs from e->parts: manifest channel order, copying data only where the decoded
 * order differs. rep_run_read_frame has already checked that the channel sets agree. */
static void entry_views(view_entry *e, const rep_frame_info *fi)
{
    e->bufs = rep_xcalloc((size_t)e->count, sizeof *e->bufs);
    e->owned = rep_xcalloc((size_t)e->count, sizeof *e->owned);
    for (int j = 0; j < e->count; j++) {
        const rep_part *p = &e->parts[j];
        const rep_buffer_info *bi = &fi->buffers[j];
        int nch = p->channel_count, map[ENG_MAX_CHANNELS], same = 1;
        for (int c = 0; c < nch; c++) {
            map[c] = c;
            for (int k = 0; k < nch; k++)
                if (!strcmp(bi->channels[c], p->channels[k]))
                    map[c] = k;
            same &= map[c] == c;
        }
        eng_buffer *b = &e->bufs[j];
        b->name = bi->name;
        b->width = p->width;
        b->height = p->height;
        b->channel_count = nch;
        b->channels = (const char *const *)bi->channels;
        if (same) {
            b->data = p->data;
            continue;
        }
        size_t pixels = (size_t)p->width * (size_t)p->height;
        float *d = rep_xmalloc(pixels * (size_t)nch * sizeof *d);
        for (size_t i = 0; i < pixels; i++)
            for (int c = 0; c < nch; c++)
                d[i * (size_t)nch + (size_t)c] = p->data[i * (size_t)nch + (size_t)map[c]];
        e->owned[j] = d;
        b->data = d;
    }
}

eng_result view_run_frame(view_run *r, int f, const eng_buffer **bufs, int *count, eng_error *err)
{
    *bufs = NULL;
    *count = 0;
    if (f < 0 || f >= r->run->frame_count)
        return eng_fail(err, ENG_ERR_INVALID, "%s: no frame %d (the run has %d)", r->run->dir, f,
                        r->run->frame_count);
    view_entry *e = NULL, *victim = &r->entries[0];
    for (int i = 0; i < r->capacity && !e; i++) {
        view_entry *c = &r->entries[i];
        if (c->frame == f)
            e = c;
        else if (c->frame < 0 || (victim->frame >= 0 && c->used < victim->used))
            victim = c;
    }
    if (!e) {
        e = victim;
        entry_clear(e);
        e->frame = f;
        r->decodes++;
        e->result = rep_run_read_frame(r->run, f, &e->parts, &e->error);
        if (e->result == ENG_OK) {
            e->count = r->run->frames[f].buffer_count;
            entry_views(e, &r->run->frames[f]);
        }
    }
    e->used = ++r->clock;
    if (e->result != ENG_OK) {
        if (err)
            *err = e->error;
        return e->result;
    }
    *bufs = e->bufs;
    *count = e->count;
    return ENG_OK;
}

void view_run_resolution(const view_run *r, int *w, int *h)
{
    *w = r->run->width;
    *h = r->run->height;
}

int view_run_camera(const view_run *r, int f, float view_proj[16])
{
    if (f < 0 || f >= r->run->frame_count || !r->run->frames[f].has_camera)
        return 0;
    memcpy(view_proj, r->run->frames[f].view_proj, 16 * sizeof *view_proj);
    return 1;
}

int view_run_live(const view_run *r)
{
    return !r->run->complete;
}

int view_run_planned_frames(const view_run *r)
{
    return r->run->planned_frames;
}

int view_run_refresh(view_run *r, eng_error *err)
{
    int added = 0;
    if (rep_run_refresh(r->run, &added, err) != ENG_OK)
        return -1;
    return added;
}
