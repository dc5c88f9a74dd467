/* outputs.c — the output tables' names (passes.h "outputs"): filling a table entry's
 * placeholders for the place in the frame loop where it is announced. The tables themselves
 * live beside their passes; the frame loop walks them (engine.c) and test_outputs checks every
 * name against DESIGN.md's buffer-name table. */
#include "passes.h"

#include <stdio.h>
#include <string.h>

int pass_output_channels(const pass_output *o)
{
    int n = 0;
    while (n < PASS_OUT_MAX_CHANNELS && o->channels[n])
        n++;
    return n;
}

int pass_output_name(const pass_output *o, const pass_output_at *at, char *out, size_t size)
{
    static const pass_output_at none = {0, 1, 0, 0, NULL};
    if (!at)
        at = &none;
    size_t n = 0;
    int skip = 0; /* inside a [...] group that is not written */
    for (const char *p = o->name; *p; p++) {
        char piece[32];
        int len;
        if (*p == '[') {
            skip = at->faces <= 1;
            continue;
        }
        if (*p == ']') {
            skip = 0;
            continue;
        }
        if (*p == '<') {
            const char *close = strchr(p, '>');
            if (!close || close - p != 2)
                return -1;
            switch (p[1]) {
            case 'i': len = snprintf(piece, sizeof piece, "%u", at->light); break;
            case 'f': len = snprintf(piece, sizeof piece, "%d", at->face); break;
            case 'k': len = snprintf(piece, sizeof piece, "%d", at->level + o->level_offset); break;
            case 'm': len = snprintf(piece, sizeof piece, "%s", at->prefix ? at->prefix : ""); break;
            default: return -1;
            }
            p = close;
        } else {
            piece[0] = *p;
            piece[1] = '\0';
            len = 1;
        }
        if (skip)
            continue;
        if (len < 0 || n + (size_t)len >= size)
            return -1;
        memcpy(out + n, piece, (size_t)len + 1);
        n += (size_t)len;
    }
    if (n >= size)
        return -1;
    out[n] = '\0';
    return 0;
}
