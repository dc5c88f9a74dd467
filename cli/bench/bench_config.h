/* bench_config.h — an `ispm bench` config read and checked into a plain struct: the sequence
 * and reference run it names, the frames, repeats and warm-up, the grid of settings to sweep,
 * the named methods with their fixed settings, what the chart plots and the frames that get a
 * row of their own. The format is docs/bench.md's. */
#ifndef ISPM_BENCH_CONFIG_H
#define ISPM_BENCH_CONFIG_H

#include "eng.h"
#include "plot.h"

#include <cjson/cJSON.h>

#define BENCH_MAX_POINTS 1000
#define BENCH_MAX_FRAMES 256
#define BENCH_MAX_KEYS 24
#define BENCH_MAX_METHODS (PLOT_MAX_SERIES - 1) /* one series is left for the Pareto front */
#define BENCH_MAX_SERIES 16                     /* report_frames */

typedef struct bench_config {
    const char *path;
    cJSON *root;                     /* owns everything below that points into it */
    char sequence[4096], reference[4096];
    int frames[BENCH_MAX_FRAMES], frame_count;
    int repeats, warmup, threads;    /* threads 0 = the sequence's */
    const cJSON *grid;               /* object: key → array of values; may be NULL */
    int grid_key_count;
    const cJSON *methods;            /* array of {"name", "settings"} */
    int method_count;
    const char *chart_metric, *chart_buffer;
    int reference_frame;             /* −1: bench frame i against reference frame i; else this one */
    int report_frames[BENCH_MAX_SERIES], report_count; /* indices into frames[] with a per-frame row */
} bench_config;

/* Reads the config at `path` (paths in it resolved against its folder) into *c. Anything
 * malformed: ENG_ERR_PARSE or ENG_ERR_INVALID with a message that names the file. Whatever it
 * returns, *c is left for bench_config_free. The point settings themselves are checked by the
 * engine when the points are made (bench_points_make). */
eng_result bench_config_load(const char *path, bench_config *c, eng_error *err);

/* Frees what bench_config_load allocated; accepts a zeroed config. */
void bench_config_free(bench_config *c);

#endif
