/* view_flip.c — the viewer's ꟻLIP heat map: how visible the difference of the
 * shown colour buffer against the second run is (replay/compare/flip.h, the same code and ramp as the
 * HTML report's). A map is computed once per frame and buffer and kept, since HDR-ꟻLIP filters
 * the image at several exposures; redraws (hover, zoom) reuse it.
 */
#include "view_model.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "rep_compare.h"

int view_flip_render(view_flip_cache *c, int frame, const eng_buffer *a, const eng_buffer *b, uint8_t *out)
{
    rep_flip_kind k = rep_flip_kind_of(a->name ? a->name : "");
    if (!b || k == REP_FLIP_NONE)
        return 0;
    if (!c->valid || c->frame != frame || strcmp(c->name, a->name) != 0 || c->w != a->width || c->h != a->height) {
        view_flip_cache_free(c);
        rep_tol t;
        rep_tol_builtin(&t); /* the default pinned exposure range and ppd */
        c->map = rep_flip_buffers(a, b, &t, k, NULL);
        if (!c->map)
            return 0;
        c->frame = frame;
        snprintf(c->name, sizeof c->name, "%s", a->name);
        c->w = a->width;
        c->h = a->height;
        rep_flip_stats st;
        rep_flip_stats_of(c->map, (size_t)c->w * (size_t)c->h, &st);
        c->mean = st.mean;
        c->p99 = st.p99;
        c->valid = 1;
    }
    size_t n = (size_t)c->w * (size_t)c->h;
    for (size_t p = 0; p < n; p++) {
        rep_flip_heat_rgb(c->map[p], out + 4 * p);
        out[4 * p + 3] = 255;
    }
    return 1;
}

void view_flip_cache_free(view_flip_cache *c)
{
    free(c->map);
    memset(c, 0, sizeof *c);
}
