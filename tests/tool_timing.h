/* tool_timing.h — what the measuring tools share: a clock in milliseconds and the median of a
 * few samples (sorts them in place). */
#ifndef ISPM_TOOL_TIMING_H
#define ISPM_TOOL_TIMING_H

#include <stdlib.h>
#include <time.h>

static inline double tool_ms(clockid_t id)
{
    struct timespec t;
    clock_gettime(id, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec / 1e6;
}

static inline int tool_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static inline double tool_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, tool_cmp_double);
    return v[n / 2];
}

#endif
