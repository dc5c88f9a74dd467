/* keep.c — what the walk over a run keeps for report.html (rep_keep, rep_run.h): the
 * decoded buffers its thumbnails show and the ꟻLIP maps of its heat maps, so that the report
 * neither decodes a frame file a second time nor runs ꟻLIP again (the report's second
 * decoding of every frame with a card was a third of replay's CPU).
 *
 * The walk moves in, after each frame's comparisons, the run's and the golden's part of every
 * buffer the report lists (not bit-exact, or failing) and of the preview buffer of the first and
 * last frames, and the ꟻLIP map of each listed colour buffer. What the report would decode is
 * the same file through the same reader, and the map the same function of the same inputs, so
 * the images are the same bytes either way. Memory is bounded: past REP_KEEP_MAX_FLOATS floats or
 * REP_KEEP_MAX_ITEMS items nothing more is kept, and the report decodes (or computes) what it
 * does not find here. Lookups search the items' frame order.
 */
#include "oiio_shim.h"
#include "rep_run.h"
#include "rep_util.h"

#include <stdlib.h>
#include <string.h>

/* A new item for frame, or NULL when k is full. Items stay in frame order (the walk's), which
 * find's binary search relies on: an earlier frame than the last is refused. */
static rep_kept *slot(rep_keep *k, int frame, size_t floats)
{
    if (k->floats + floats > REP_KEEP_MAX_FLOATS || k->count >= REP_KEEP_MAX_ITEMS ||
        (k->count && k->items[k->count - 1].frame > frame))
        return NULL;
    if (k->count == k->cap) {
        k->cap = k->cap ? 2 * k->cap : 64;
        k->items = rep_xrealloc(k->items, k->cap * sizeof *k->items);
    }
    k->floats += floats;
    rep_kept *it = &k->items[k->count++];
    memset(it, 0, sizeof *it);
    return it;
}

static rep_kept *find(const rep_keep *k, int frame, int side, const char *name)
{
    if (!k)
        return NULL;
    size_t lo = 0, hi = k->count; /* the first item of frame */
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (k->items[mid].frame < frame)
            lo = mid + 1;
        else
            hi = mid;
    }
    for (size_t i = lo; i < k->count && k->items[i].frame == frame; i++)
        if (k->items[i].side == side && strcmp(k->items[i].name, name) == 0)
            return &k->items[i];
    return NULL;
}

/* The item of (frame, side, name), made if there is none, with room counted for floats more;
 * NULL when k is full. */
static rep_kept *claim(rep_keep *k, int frame, int side, const char *name, size_t floats)
{
    rep_kept *it = find(k, frame, side, name);
    if (it) { /* its other half (part or ꟻLIP map) came first */
        if (k->floats + floats > REP_KEEP_MAX_FLOATS)
            return NULL;
        k->floats += floats;
        return it;
    }
    if (!(it = slot(k, frame, floats)))
        return NULL;
    it->frame = frame;
    it->side = side;
    it->name = rep_xstrdup(name);
    return it;
}

void rep_keep_part(rep_keep *k, int frame, int side, rep_part *p)
{
    if (!p->data)
        return;
    const rep_kept *had = find(k, frame, side, p->name);
    rep_kept *it;
    if ((had && had->part.data) ||
        !(it = claim(k, frame, side, p->name, (size_t)p->width * (size_t)p->height * (size_t)p->channel_count)))
        return;
    it->part = *p;
    memset(p, 0, sizeof *p); /* moved: the walk's free skips it */
}

int rep_keep_flip(rep_keep *k, int frame, const char *name, float *map, size_t floats)
{
    const rep_kept *had = find(k, frame, REP_KEEP_RUN, name);
    rep_kept *it;
    if ((had && had->flip) || !(it = claim(k, frame, REP_KEEP_RUN, name, floats)))
        return 0;
    it->flip = map;
    return 1;
}

const rep_part *rep_keep_find_part(const rep_keep *k, int frame, int side, const char *name)
{
    const rep_kept *it = find(k, frame, side, name);
    return it && it->part.data ? &it->part : NULL;
}

const float *rep_keep_find_flip(const rep_keep *k, int frame, const char *name)
{
    const rep_kept *it = find(k, frame, REP_KEEP_RUN, name);
    return it ? it->flip : NULL;
}

void rep_keep_free(rep_keep *k)
{
    if (!k)
        return;
    for (size_t i = 0; i < k->count; i++) {
        free(k->items[i].name);
        free(k->items[i].flip);
        rep_part_clear(&k->items[i].part);
    }
    free(k->items);
    free(k);
}
