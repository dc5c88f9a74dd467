/* progress.c — frames done, elapsed and estimated time left for the long commands (record,
 * reference, bench, replay): one line refreshed in place on a terminal, plain lines otherwise
 * (a CI log gets one line per step, never carriage returns). The estimate is the mean time per
 * step so far times the steps left. */
#define _POSIX_C_SOURCE 200809L

#include "rep.h"

#include <string.h>
#include <time.h>
#include <unistd.h>

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void rep_progress_begin(rep_progress *p, FILE *f, const char *label, const char *unit, int total)
{
    memset(p, 0, sizeof *p);
    p->f = f;
    p->label = label;
    p->unit = unit;
    p->total = total;
    p->start = now_s();
    p->tty = f && isatty(fileno(f));
}

/* "1 min 05 s", "12.3 s" */
static void duration(char *out, size_t n, double s)
{
    if (s >= 60)
        snprintf(out, n, "%d min %02d s", (int)(s / 60), (int)s % 60);
    else
        snprintf(out, n, "%.1f s", s);
}

void rep_progress_step(rep_progress *p, int done, const char *detail)
{
    if (!p || !p->f)
        return;
    double el = now_s() - p->start;
    char e[32], left[32] = "?";
    duration(e, sizeof e, el);
    if (done > 0 && p->total >= done)
        duration(left, sizeof left, el / done * (p->total - done));
    fprintf(p->f, "%s%s: %s %d/%d  elapsed %s  left %s%s%s%s", p->tty ? "\r" : "", p->label, p->unit, done, p->total, e,
            left, detail ? "  " : "", detail ? detail : "", p->tty ? "\033[K" : "\n");
    p->open = p->tty;
    fflush(p->f);
}

void rep_progress_end(rep_progress *p)
{
    if (p && p->f && p->open) {
        fputc('\n', p->f);
        p->open = 0;
    }
}
