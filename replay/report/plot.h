/* plot.h — charts for reports and benchmarks, drawn with PLplot (cairo driver): line
 * charts over frames, log–log scatter charts with marked points, stacked bar charts. One
 * call writes one chart to a PNG (pngcairo) or SVG (svgcairo) file chosen by the file name's
 * extension. Nothing here draws by hand: axes, ticks, labels and legends are PLplot's.
 *
 * Non-finite values and, on log axes, values <= 0 are skipped (never plotted as 0). */
#ifndef ISPM_PLOT_H
#define ISPM_PLOT_H

#include "eng_core.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PLOT_MAX_SERIES 16

typedef enum plot_style {
    PLOT_LINES = 0,       /* polyline through the points */
    PLOT_POINTS,          /* markers only */
    PLOT_LINES_POINTS     /* both */
} plot_style;

typedef struct plot_series {
    const char *label;    /* legend entry */
    const double *x, *y;  /* count points */
    int count;
    plot_style style;
    const int *marked;    /* optional: count flags; points with a non-zero flag get a larger
                           * ring marker (e.g. the Pareto front); NULL = none */
} plot_series;

typedef struct plot_chart {
    const char *title;
    const char *x_label, *y_label;
    int log_x, log_y;     /* logarithmic axes (decades) */
    int series_count;
    plot_series series[PLOT_MAX_SERIES];
    int width, height;    /* pixels (PNG) or points (SVG); 0 = 900×600 */
    const char *marked_label; /* legend entry of the ring markers; NULL = "Pareto front" */
} plot_chart;

/* Writes the chart to path (.png or .svg). Errors (unwritable file, no finite point at all,
 * unknown extension) name the file and the problem. */
eng_result plot_xy(const char *path, const plot_chart *chart, eng_error *err);

/* A stacked bar chart: bar_count bars (labels[i] under each), series_count stacked segments
 * per bar; values[s * bar_count + i] is segment s of bar i (>= 0), series_labels[s] its
 * legend entry. For per-pass time breakdowns. */
eng_result plot_stacked_bars(const char *path, const char *title, const char *y_label, int bar_count,
                             const char *const *labels, int series_count, const char *const *series_labels,
                             const double *values, eng_error *err);

#ifdef __cplusplus
}
#endif

#endif
