/* cmd_bench.c — `ispm bench CONFIG.json -o OUTDIR`: speed versus accuracy. A config names a
 * sequence, a reference run (frames holding reference.indirect and reference.full), the frames
 * to render, repeats, a grid of engine settings to sweep and named methods (the chart's
 * series), each with fixed settings (bench_config.c). Every grid point of every method is
 * rendered in this process and measured against the reference (bench_run.c); the tables and
 * charts follow (bench_output.c). This file is the command: its arguments, the order of the
 * steps and the exit status. Old bench.csv/bench.json are removed before anything is rendered,
 * and bench.csv again if anything fails. Exit: 0 done, 1 rendering or writing failed, 2 bad
 * arguments, config, sequence or reference (one line naming the file). */
#define _POSIX_C_SOURCE 200809L
#include "bench_config.h"
#include "bench_output.h"
#include "bench_run.h"
#include "rep.h"
#include "rep_run.h"
#include "rep_util.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int cmd_bench(int argc, char **argv, const char *command_line);

enum { B_OK = 0, B_RUNTIME = 1, B_INPUT = 2 };

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ispm bench CONFIG.json -o OUTDIR [--quiet]\n"
            "       ispm bench --check CONFIG.json\n"
            "\n"
            "Renders every grid point of every method of CONFIG in-process, times each pass\n"
            "(median over frames x repeats), measures indirect.radiance and composite.radiance\n"
            "against the reference run's reference.indirect and reference.full, and writes\n"
            "OUTDIR/bench.csv, bench.json, error_vs_time.png/.svg, pass_times.png and\n"
            "compare_scatter_vs_gather.png/.exr. See docs/bench.md for the config format.\n"
            "\n"
            "  -o, --output OUTDIR  where the results go (created if needed)\n"
            "  -q, --quiet          no per-point progress\n"
            "      --check          validate CONFIG, its sequence and scene and every point's\n"
            "                       settings, render nothing, need no reference run\n"
            "  -h, --help           this text\n"
            "\n"
            "exit: 0 done; 1 rendering or writing failed; 2 bad arguments, config, sequence or\n"
            "      reference run\n");
}

int cmd_bench(int argc, char **argv, const char *command_line)
{
    static const struct option opts[] = {
        {"output", required_argument, NULL, 'o'}, {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'}, {"check", no_argument, NULL, 'c'}, {NULL, 0, NULL, 0},
    };
    const char *outdir = NULL;
    int quiet = 0, check = 0, opt;
    while ((opt = getopt_long(argc, argv, "o:qh", opts, NULL)) != -1) {
        switch (opt) {
        case 'o': outdir = optarg; break;
        case 'q': quiet = 1; break;
        case 'c': check = 1; break;
        case 'h': usage(stdout); return B_OK;
        default: usage(stderr); return B_INPUT;
        }
    }
    if (optind + 1 != argc || (!outdir && !check)) {
        usage(stderr);
        return B_INPUT;
    }
    eng_error err = {{0}};
    bench_config c;
    int rc = B_OK;
    bench_point *pts = NULL;
    int n = 0;
    scn_scene *scene = NULL;
    bench_reference ref = {NULL, NULL, "unknown"};
    bench_passes passes = {0};
    char *old_json = NULL, *old_csv = NULL;
    eng_result r = bench_config_load(argv[optind], &c, &err);
    if (r == ENG_OK)
        r = bench_points_make(&c, &pts, &n, &err);
    if (r == ENG_OK && check) { /* everything but the reference run and the rendering */
        r = seq_load_scene(pts[0].seq, &scene, &err);
        if (r == ENG_OK)
            printf("ispm bench: %s: %d points (%d methods) valid\n", c.path, n, c.method_count);
        else
            fprintf(stderr, "ispm bench: %s\n", err.msg);
        rc = r == ENG_OK ? B_OK : B_INPUT;
        goto done;
    }
    if (r == ENG_OK && (r = bench_reference_load(&c, pts[0].seq->width, pts[0].seq->height, &ref, &err)) != ENG_OK) {
        eng_error inner = err;
        eng_fail(&err, r, "%s: reference: %s", c.path, inner.msg);
    }
    if (r == ENG_OK && !strcmp(ref.pixel, "box"))
        fprintf(stderr, "ispm bench: note: %s is box-filtered: at silhouettes its pixels mix surfaces where the "
                        "engine shades the pixel centre (ispm reference --pixel-center)\n",
                c.reference);
    if (r == ENG_OK)
        r = seq_load_scene(pts[0].seq, &scene, &err);
    if (r != ENG_OK) { /* the config, sequence, scene or reference */
        fprintf(stderr, "ispm bench: %s\n", err.msg);
        rc = B_INPUT;
        goto done;
    }
    if ((r = rep_mkdirs(outdir, &err)) != ENG_OK) {
        fprintf(stderr, "ispm bench: %s\n", err.msg);
        rc = B_RUNTIME;
        goto done;
    }
    /* An old result must not pass for this one while it runs or if it fails. */
    old_json = rep_path_join(outdir, "bench.json");
    old_csv = rep_path_join(outdir, "bench.csv");
    unlink(old_json);
    unlink(old_csv);
    if (!quiet)
        fprintf(stderr, "ispm bench: %d points (%d methods), frames %d..., %d repeats, %dx%d\n", n, c.method_count,
                c.frames[0], c.repeats, pts[0].seq->width, pts[0].seq->height);
    r = bench_run_points(&c, scene, pts, n, &ref, quiet, &passes, &err);
    if (r == ENG_OK)
        r = bench_write_results(&c, outdir, command_line, pts, n, &passes, &ref, quiet, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm bench: %s\n", err.msg);
        unlink(old_csv);
        rc = r == ENG_ERR_INVALID || r == ENG_ERR_UNSUPPORTED ? B_INPUT : B_RUNTIME;
    } else {
        printf("bench: %s\n", old_csv);
    }
done:
    free(old_json);
    free(old_csv);
    bench_points_free(pts, n);
    bench_reference_free(&ref);
    scn_destroy(scene);
    bench_config_free(&c);
    return rc;
}
