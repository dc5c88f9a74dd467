/* plot.c — charts through PLplot's cairo drivers (pngcairo, svgcairo): see plot.h.
 *
 * Each chart is drawn on a stream of its own (plmkstrm … plend1), so charts can be made one
 * after another in one process. PLplot ends the process on some driver errors (plexit), so
 * everything that can fail on our side is checked before plinit: the extension, at least one
 * plottable point, and that the output can be created (the chart is drawn into a temporary
 * file beside it and renamed into place, so a chart file is either complete or absent).
 * Log axes are drawn the PLplot way: log10 of the data with the "l" axis option. */
#define _POSIX_C_SOURCE 200809L
#include "plot.h"

#include <plplot.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* Index 0 is the background, 1 black (axes, text), 9 grey (grid); the series colours are the
 * colour-blind-safe Okabe & Ito palette, then darker/lighter companions so that up to 14
 * series (a per-pass breakdown) stay distinct. */
static const int PALETTE[][3] = {
    {255, 255, 255}, {0, 0, 0}, {0, 114, 178}, {213, 94, 0}, {0, 158, 115}, {204, 121, 167},
    {230, 159, 0}, {86, 180, 233}, {240, 228, 66}, {120, 120, 120}, {0, 60, 110}, {140, 50, 0},
    {0, 95, 70}, {120, 60, 110}, {160, 110, 0}, {40, 40, 40},
};
#define PALETTE_N ((int)(sizeof PALETTE / sizeof PALETTE[0]))

static int series_colour(int s)
{
    static const int order[] = {2, 3, 4, 5, 6, 7, 8, 10, 11, 12, 13, 14, 15, 9};
    return order[s % (int)(sizeof order / sizeof order[0])];
}

/* The driver for a file name, or NULL. */
static const char *device_for(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot)
        return NULL;
    if (!strcmp(dot, ".png"))
        return "pngcairo";
    if (!strcmp(dot, ".svg"))
        return "svgcairo";
    return NULL;
}

/* Checks that path can be written and makes the temporary name beside it. */
static eng_result prepare(const char *path, char *tmp, size_t size, const char **dev, eng_error *err)
{
    *dev = device_for(path);
    if (!*dev)
        return eng_fail(err, ENG_ERR_INVALID, "%s: chart files must end in .png or .svg", path);
    const char *dot = strrchr(path, '.');
    /* keep the extension last: the cairo drivers do not care, people opening a leftover do */
    int n = snprintf(tmp, size, "%.*s.tmp%ld%s", (int)(dot - path), path, (long)getpid(), dot);
    if (n < 0 || (size_t)n >= size)
        return eng_fail(err, ENG_ERR_INVALID, "%s: path too long", path);
    FILE *f = fopen(tmp, "wb");
    if (!f)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot create the chart file", path);
    fclose(f);
    return ENG_OK;
}

static eng_result finish(const char *path, const char *tmp, eng_error *err)
{
    FILE *f = fopen(tmp, "rb");
    long len = -1;
    if (f) {
        if (fseek(f, 0, SEEK_END) == 0)
            len = ftell(f);
        fclose(f);
    }
    if (len <= 0) {
        remove(tmp);
        return eng_fail(err, ENG_ERR_IO, "%s: PLplot wrote nothing (disk full?)", path);
    }
    if (rename(tmp, path) != 0) {
        remove(tmp);
        return eng_fail(err, ENG_ERR_IO, "%s: cannot move the chart into place", path);
    }
    return ENG_OK;
}

static void begin(const char *dev, const char *tmp, int width, int height)
{
    PLINT strm;
    plmkstrm(&strm);
    plsdev(dev);
    plsfnam(tmp);
    plspage(0.0, 0.0, width > 0 ? width : 900, height > 0 ? height : 600, 0, 0);
    for (int i = 0; i < PALETTE_N; i++)
        plscol0(i, PALETTE[i][0], PALETTE[i][1], PALETTE[i][2]);
    plscolbg(255, 255, 255);
    plinit();
    pladv(0);
    plschr(0.0, 0.9);
}

static int usable(double v, int log_axis) { return isfinite(v) && (!log_axis || v > 0.0); }

static double axis_value(double v, int log_axis) { return log_axis ? log10(v) : v; }

/* Data range on one axis with a margin; log axes get whole decades around the data. */
static void axis_range(double lo, double hi, int log_axis, double *a, double *b)
{
    if (log_axis) {
        *a = floor(lo);
        *b = ceil(hi);
        if (*b - *a < 1.0)
            *b = *a + 1.0;
        return;
    }
    if (hi - lo <= 0.0) {
        double pad = fabs(lo) > 0.0 ? fabs(lo) * 0.1 : 1.0;
        *a = lo - pad;
        *b = hi + pad;
        return;
    }
    double pad = 0.05 * (hi - lo);
    *a = lo - pad;
    *b = hi + pad;
    if (lo >= 0.0 && *a < 0.0)
        *a = 0.0;
}

eng_result plot_xy(const char *path, const plot_chart *c, eng_error *err)
{
    if (c->series_count < 1 || c->series_count > PLOT_MAX_SERIES)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %d series (1..%d)", path, c->series_count, PLOT_MAX_SERIES);
    double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
    int total = 0;
    for (int s = 0; s < c->series_count; s++) {
        const plot_series *ps = &c->series[s];
        for (int i = 0; i < ps->count; i++) {
            if (!usable(ps->x[i], c->log_x) || !usable(ps->y[i], c->log_y))
                continue;
            double x = axis_value(ps->x[i], c->log_x), y = axis_value(ps->y[i], c->log_y);
            xlo = fmin(xlo, x);
            xhi = fmax(xhi, x);
            ylo = fmin(ylo, y);
            yhi = fmax(yhi, y);
            total++;
        }
    }
    if (!total)
        return eng_fail(err, ENG_ERR_INVALID, "%s: no finite point to plot%s", path,
                        c->log_x || c->log_y ? " (log axes skip values <= 0)" : "");
    char tmp[4096];
    const char *dev;
    eng_result r = prepare(path, tmp, sizeof tmp, &dev, err);
    if (r != ENG_OK)
        return r;

    double x0, x1, y0, y1;
    axis_range(xlo, xhi, c->log_x, &x0, &x1);
    axis_range(ylo, yhi, c->log_y, &y0, &y1);
    begin(dev, tmp, c->width, c->height);
    plvpor(0.1, 0.72, 0.12, 0.9);
    plwind(x0, x1, y0, y1);
    plcol0(9);
    plwidth(0.5);
    plbox(c->log_x ? "ghl" : "g", 0.0, 0, c->log_y ? "ghl" : "g", 0.0, 0); /* grid first */
    plcol0(1);
    plwidth(1.0);
    plbox(c->log_x ? "bcnstl" : "bcnst", 0.0, 0, c->log_y ? "bcnstvl" : "bcnstv", 0.0, 0);
    pllab(c->x_label ? c->x_label : "", c->y_label ? c->y_label : "", c->title ? c->title : "");

    PLINT opts[PLOT_MAX_SERIES], colours[PLOT_MAX_SERIES], styles[PLOT_MAX_SERIES], numbers[PLOT_MAX_SERIES];
    PLFLT widths[PLOT_MAX_SERIES], scales[PLOT_MAX_SERIES];
    const char *texts[PLOT_MAX_SERIES], *symbols[PLOT_MAX_SERIES];
    for (int s = 0; s < c->series_count; s++) {
        const plot_series *ps = &c->series[s];
        PLFLT *x = malloc(sizeof(PLFLT) * (size_t)(ps->count ? ps->count : 1));
        PLFLT *y = malloc(sizeof(PLFLT) * (size_t)(ps->count ? ps->count : 1));
        if (!x || !y) {
            fprintf(stderr, "ispm: out of memory\n");
            abort();
        }
        int colour = series_colour(s);
        plcol0(colour);
        /* A line breaks at unusable points rather than bridging them. */
        int n = 0;
        for (int i = 0; i <= ps->count; i++) {
            int ok = i < ps->count && usable(ps->x[i], c->log_x) && usable(ps->y[i], c->log_y);
            if (ok) {
                x[n] = axis_value(ps->x[i], c->log_x);
                y[n] = axis_value(ps->y[i], c->log_y);
                n++;
                continue;
            }
            if (n > 0) {
                if (ps->style != PLOT_POINTS && n > 1) {
                    plwidth(2.0);
                    plline(n, x, y);
                    plwidth(1.0);
                }
                if (ps->style != PLOT_LINES) {
                    plschr(0.0, 2.0); /* plstring symbols follow the character height */
                    plstring(n, x, y, "#(850)"); /* filled circle */
                    plschr(0.0, 0.9);
                }
            }
            n = 0;
        }
        if (ps->marked) {
            plschr(0.0, 1.6);
            plwidth(2.0);
            for (int i = 0; i < ps->count; i++)
                if (ps->marked[i] && usable(ps->x[i], c->log_x) && usable(ps->y[i], c->log_y)) {
                    PLFLT mx = axis_value(ps->x[i], c->log_x), my = axis_value(ps->y[i], c->log_y);
                    plcol0(1);
                    plstring(1, &mx, &my, "#(840)"); /* ring */
                }
            plschr(0.0, 0.9);
            plwidth(1.0);
        }
        free(x);
        free(y);
        opts[s] = (ps->style != PLOT_POINTS ? PL_LEGEND_LINE : 0) | (ps->style != PLOT_LINES ? PL_LEGEND_SYMBOL : 0);
        colours[s] = colour;
        styles[s] = 1;
        widths[s] = 2.0;
        scales[s] = 2.5;
        numbers[s] = 1;
        texts[s] = ps->label ? ps->label : "";
        symbols[s] = "#(850)";
    }
    int any_marked = 0;
    for (int s = 0; s < c->series_count; s++)
        any_marked |= c->series[s].marked != NULL;
    int nleg = c->series_count;
    if (any_marked && nleg < PLOT_MAX_SERIES) {
        opts[nleg] = PL_LEGEND_SYMBOL;
        colours[nleg] = 1;
        styles[nleg] = 1;
        widths[nleg] = 1.0;
        scales[nleg] = 1.8;
        numbers[nleg] = 1;
        texts[nleg] = c->marked_label ? c->marked_label : "Pareto front";
        symbols[nleg] = "#(840)";
        nleg++;
    }
    PLFLT lw, lh;
    plcol0(1);
    pllegend(&lw, &lh, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX, PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT,
             0.02, 0.0, 0.05, 0, 1, 1, nleg, 1, nleg, opts, 0.8, 0.8, 2.0, 0.0, colours, texts, NULL, NULL, NULL,
             NULL, colours, styles, widths, colours, scales, numbers, symbols);
    plend1();
    return finish(path, tmp, err);
}

eng_result plot_stacked_bars(const char *path, const char *title, const char *y_label, int bar_count,
                             const char *const *labels, int series_count, const char *const *series_labels,
                             const double *values, eng_error *err)
{
    if (bar_count < 1 || series_count < 1 || series_count > PLOT_MAX_SERIES)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %d bars of %d segments (need >= 1 bar, 1..%d segments)", path,
                        bar_count, series_count, PLOT_MAX_SERIES);
    double top = 0.0;
    for (int i = 0; i < bar_count; i++) {
        double sum = 0.0;
        for (int s = 0; s < series_count; s++) {
            double v = values[(size_t)s * (size_t)bar_count + (size_t)i];
            if (!isfinite(v) || v < 0.0)
                return eng_fail(err, ENG_ERR_INVALID, "%s: segment %d of bar %d is %g (must be finite, >= 0)", path,
                                s, i, v);
            sum += v;
        }
        top = fmax(top, sum);
    }
    if (top <= 0.0)
        top = 1.0;
    char tmp[4096];
    const char *dev;
    eng_result r = prepare(path, tmp, sizeof tmp, &dev, err);
    if (r != ENG_OK)
        return r;
    begin(dev, tmp, 0, 0);
    plvpor(0.1, 0.72, 0.22, 0.9);
    plwind(0.0, (double)bar_count, 0.0, top * 1.05);
    plcol0(9);
    plbox("", 0.0, 0, "g", 0.0, 0);
    for (int i = 0; i < bar_count; i++) {
        double base = 0.0;
        for (int s = 0; s < series_count; s++) {
            double v = values[(size_t)s * (size_t)bar_count + (size_t)i];
            PLFLT bx[4] = {i + 0.15, i + 0.85, i + 0.85, i + 0.15};
            PLFLT by[4] = {base, base, base + v, base + v};
            plcol0(series_colour(s));
            plfill(4, bx, by);
            base += v;
        }
        plcol0(1);
        plschr(0.0, 0.7);
        plmtex("b", 1.0, (i + 0.5) / bar_count, 1.0, labels && labels[i] ? labels[i] : "");
        plschr(0.0, 0.9);
    }
    plcol0(1);
    plbox("bc", 0.0, 0, "bcnstv", 0.0, 0);
    pllab("", y_label ? y_label : "", title ? title : "");
    PLINT opts[PLOT_MAX_SERIES], colours[PLOT_MAX_SERIES], patterns[PLOT_MAX_SERIES];
    PLFLT scales[PLOT_MAX_SERIES], widths[PLOT_MAX_SERIES];
    const char *texts[PLOT_MAX_SERIES];
    for (int s = 0; s < series_count; s++) {
        opts[s] = PL_LEGEND_COLOR_BOX;
        colours[s] = series_colour(s);
        patterns[s] = 0;
        scales[s] = 0.8;
        widths[s] = 1.0;
        texts[s] = series_labels && series_labels[s] ? series_labels[s] : "";
    }
    PLFLT lw, lh;
    pllegend(&lw, &lh, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX, PL_POSITION_RIGHT | PL_POSITION_OUTSIDE | PL_POSITION_VIEWPORT,
             0.02, 0.0, 0.05, 0, 1, 1, series_count, 1, series_count, opts, 0.8, 0.8, 2.0, 0.0, colours, texts,
             colours, patterns, scales, widths, NULL, NULL, NULL, NULL, NULL, NULL, NULL);
    plend1();
    return finish(path, tmp, err);
}
