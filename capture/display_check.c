/* display_check.c — cap_display_warning: whether a frame's final.display is all black or has
 * too many clipped pixels, as one line for stderr and the manifest. */
#include "cap.h"

#include <stdio.h>
#include <string.h>

int cap_display_warning(const eng_buffer *b, char *out, size_t size)
{
    if (size)
        out[0] = 0;
    if (!b || !b->data || b->width <= 0 || b->height <= 0 || b->channel_count < 1)
        return 0;
    const int nc = b->channel_count < 3 ? b->channel_count : 3; /* alpha is not seen */
    const size_t n = (size_t)b->width * (size_t)b->height;
    size_t lit = 0, clipped = 0;
    for (size_t i = 0; i < n; i++) {
        const float *p = b->data + i * (size_t)b->channel_count;
        float hi = p[0], lo = p[0];
        for (int k = 1; k < nc; k++) {
            hi = p[k] > hi ? p[k] : hi;
            lo = p[k] < lo ? p[k] : lo;
        }
        if (hi >= CAP_DISPLAY_BLACK)
            lit++;
        if (lo >= CAP_DISPLAY_CLIPPED) /* white: every channel clipped (a saturated colour is not) */
            clipped++;
    }
    if (lit == 0) {
        snprintf(out, size, "final.display is all black (no pixel reaches %.4g): no light reaches what the camera "
                            "sees, or the exposure is far too low",
                 (double)CAP_DISPLAY_BLACK);
        return 1;
    }
    if ((double)clipped > CAP_DISPLAY_CLIP_FRACTION * (double)n) {
        snprintf(out, size, "final.display has %.1f%% of its pixels clipped to white (over %.0f%%): lower the "
                            "\"exposure\" setting (or make it \"auto\") or the light intensities",
                 100.0 * (double)clipped / (double)n, 100.0 * CAP_DISPLAY_CLIP_FRACTION);
        return 1;
    }
    return 0;
}
