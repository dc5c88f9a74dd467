/* view_live.c — live view: watching a run while it is being recorded.
 *
 * The run reader decides which frames exist (rep_run_open_live / rep_run_refresh: a frame counts
 * once its EXR and its record have both landed, capture's own rule for --resume); this file only
 * decides when to look again and what the viewer shows when frames arrive: it follows the newest
 * frame as long as the person has not stepped back to an older one, so a long recording can be
 * watched hands-off, and stepping back to study a frame is never interrupted.
 */
#include "view_model.h"

#include <stdio.h>

int view_state_follow(view_state *s, int frame_count)
{
    if (frame_count <= s->frame_count)
        return 0;
    int following = s->frame_count < 1 || s->frame >= s->frame_count - 1;
    s->frame_count = frame_count;
    if (!following || s->playing)
        return 0;
    s->frame = frame_count - 1;
    return 1;
}

int view_live_start_frame(int asked, int live, int frame_count)
{
    if (asked >= 0)
        return asked;
    return live && frame_count > 0 ? frame_count - 1 : 0;
}

int view_live_poll(view_run *r, view_state *s, unsigned now_ms, unsigned *last_ms, unsigned interval_ms,
                   char *err_out, size_t err_n)
{
    if (!view_run_live(r) || now_ms - *last_ms < interval_ms)
        return 0;
    *last_ms = now_ms;
    eng_error err;
    int added = view_run_refresh(r, &err);
    if (added < 0) {
        if (err_out && err_n)
            snprintf(err_out, err_n, "%s", err.msg);
        return 0;
    }
    if (added == 0)
        return !view_run_live(r); /* the manifest landed: the status line changes */
    view_state_follow(s, view_run_frame_count(r));
    return 1;
}
