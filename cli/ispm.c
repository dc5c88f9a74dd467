/* ispm.c — the one command-line tool: `record` a sequence into a run (engine + capture),
 * `replay` a run against a golden (replay), `bless` a run as the new golden. Options are
 * parsed with getopt_long; every subcommand has --help. Exit codes are what CI scripts rely
 * on and are listed in usage() and the README. */
#define _POSIX_C_SOURCE 200809L
#include "cap.h"
#include "eng.h"
#include "rep.h"

#include <getopt.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { EXIT_OK = 0, EXIT_RUNTIME = 1, EXIT_INPUT = 2 };

int cmd_reference(int argc, char **argv, const char *command_line); /* cmd_reference.c */

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ispm <command> [options]\n"
            "\n"
            "Deterministic frame recorder and replay debugger for an Image Space Photon Mapping engine.\n"
            "\n"
            "commands:\n"
            "  record SEQUENCE -o RUN     render every frame of a sequence, capture every pass to RUN\n"
            "  replay RUN [--golden DIR]  compare a run buffer by buffer against a golden\n"
            "  bless RUN DIR              make a complete run the golden in DIR\n"
            "  reference SEQUENCE -o RUN  render ground truth (path tracing + photon mapping) to RUN\n"
            "  bench CONFIG -o OUTDIR     speed vs accuracy of engine settings against a reference run\n"
            "\n"
            "Run 'ispm <command> --help' for a command's options and exit codes.\n");
}

static void record_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm record SEQUENCE -o RUN [--force | --resume] [--threads N] [--gl osmesa|egl [--gl-device N]] [--quiet]\n"
            "\n"
            "Renders frame i of SEQUENCE at t = i / fps and writes every announced buffer to\n"
            "RUN/frames/NNNNNN.exr (one multi-part EXR per frame), then RUN/manifest.json last.\n"
            "\n"
            "  -o, --output RUN   run folder to create\n"
            "  -f, --force        replace an existing run in RUN\n"
            "  -r, --resume       continue an interrupted recording of the same sequence into RUN:\n"
            "                     frames already written are kept, the rest rendered (same\n"
            "                     options as the interrupted run; the result is bit-identical)\n"
            "  -j, --threads N    CPU threads (llvmpipe, Embree); overrides the sequence's settings\n"
            "      --gl BACKEND   how the GL 4.5 context is made: osmesa (default; Mesa's llvmpipe, the\n"
            "                     goldens' reference) or egl (no window: Mesa's surfaceless platform,\n"
            "                     or with --gl-device an EGL device such as a GPU); in the manifest\n"
            "      --gl-device N  with --gl egl: EGL device N (EGL_EXT_platform_device, from 0)\n"
            "  -q, --quiet        no per-frame progress\n"
            "  -h, --help         this text\n"
            "\n"
            "exit: 0 run complete; 1 rendering or writing failed (no manifest is written);\n"
            "      2 bad arguments or unreadable/invalid sequence or scene\n");
}

static void replay_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm replay RUN [--golden DIR] [--tolerances FILE] [--report DIR] [--reference REFRUN] [--quiet]\n"
            "\n"
            "Decodes every buffer of every frame of RUN, verifies it against the run's manifest,\n"
            "counts NaN/Inf, and compares it with the golden's buffer of the same name using the\n"
            "golden's tolerances.json. Writes report.txt and report.json to the report folder\n"
            "(default RUN/replay) and prints the summary. Where the run has an eye G-buffer it also\n"
            "measures temporal stability (flicker of every image pass between frames, static and\n"
            "reprojected; docs/stability.md), checked against the \"stability\" limits of the\n"
            "tolerances, with the per-pixel flicker written as a run in REPORT/stability.\n"
            "\n"
            "  -g, --golden DIR        golden run (without it: integrity and NaN/Inf checks only)\n"
            "  -t, --tolerances FILE   tolerance file (default DIR/tolerances.json)\n"
            "  -r, --report DIR        where to write report.txt and report.json\n"
            "  -R, --reference REFRUN  a run whose frames hold reference.full/.indirect/.direct: the\n"
            "                          temporal error of composite/indirect/direct against them\n"
            "  -q, --quiet             print only failures and the verdict\n"
            "  -h, --help              this text\n"
            "\n"
            "exit (idiff's convention): 0 ok, 1 warnings, 2 failures (incl. any NaN/Inf not in the\n"
            "golden, missing or extra buffers), 3 size mismatch, 4 unreadable run, golden or file\n");
}

static void bless_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm bless RUN DIR\n"
            "\n"
            "Copies the complete run RUN to the golden folder DIR (atomically), keeping DIR's\n"
            "tolerances.json if it has one. Regenerate a golden only for an intended image change.\n"
            "\n"
            "exit: 0 blessed; 2 RUN incomplete or invalid; 1 writing failed\n");
}

/* Progress listener: one line per frame with the per-pass times. */
static int progress_frame_end(void *user, const eng_frame_stats *st)
{
    const seq_sequence *seq = user;
    char line[512];
    int n = snprintf(line, sizeof line, "  frame %d/%d  t=%.4f s ", st->frame + 1, seq->frame_count, st->time);
    for (int i = 0; i < st->pass_count && n > 0 && (size_t)n < sizeof line; i++)
        n += snprintf(line + n, sizeof line - (size_t)n, " %s %.1f", st->passes[i].name, st->passes[i].ms);
    if (st->photons_emitted) {
        n += snprintf(line + n, sizeof line - (size_t)n, " ms  photons: %llu bounced, stored",
                      (unsigned long long)st->photons_emitted);
        for (int b = 2; b < ENG_PHOTON_BOUNCES && n > 0 && (size_t)n < sizeof line; b++)
            if (st->photons_stored[b])
                n += snprintf(line + n, sizeof line - (size_t)n, " %llu", (unsigned long long)st->photons_stored[b]);
        if (st->photons_truncated && n > 0 && (size_t)n < sizeof line)
            snprintf(line + n, sizeof line - (size_t)n, ", %llu truncated", (unsigned long long)st->photons_truncated);
        fprintf(stderr, "%s\n", line);
        return 0;
    }
    fprintf(stderr, "%s ms\n", line);
    return 0;
}

static int exit_for(eng_result r)
{
    switch (r) {
    case ENG_OK: return EXIT_OK;
    case ENG_ERR_PARSE:
    case ENG_ERR_INVALID:
    case ENG_ERR_UNSUPPORTED: return EXIT_INPUT;
    default: return EXIT_RUNTIME;
    }
}

static int cmd_record(int argc, char **argv, const char *command_line)
{
    static const struct option opts[] = {
        {"output", required_argument, NULL, 'o'}, {"force", no_argument, NULL, 'f'},
        {"threads", required_argument, NULL, 'j'}, {"quiet", no_argument, NULL, 'q'},
        {"resume", no_argument, NULL, 'r'}, {"help", no_argument, NULL, 'h'},
        {"gl", required_argument, NULL, 'G'}, {"gl-device", required_argument, NULL, 'D'}, {NULL, 0, NULL, 0},
    };
    const char *out = NULL, *gl = NULL;
    int force = 0, resume = 0, quiet = 0, threads = 0, gl_device = -1, c;
    while ((c = getopt_long(argc, argv, "o:fj:qrh", opts, NULL)) != -1) {
        switch (c) {
        case 'o': out = optarg; break;
        case 'f': force = 1; break;
        case 'r': resume = 1; break;
        case 'q': quiet = 1; break;
        case 'j': {
            char *end;
            long v = strtol(optarg, &end, 10);
            if (*end || v < 1 || v > 64) {
                fprintf(stderr, "ispm record: --threads: '%s' is not a number in 1..64\n", optarg);
                return EXIT_INPUT;
            }
            threads = (int)v;
            break;
        }
        case 'G':
            if (!eng_gl_backend_known(optarg)) {
                fprintf(stderr, "ispm record: --gl: '%s' is not a GL backend (%s)\n", optarg, ENG_GL_BACKENDS);
                return EXIT_INPUT;
            }
            gl = optarg;
            break;
        case 'D': {
            char *end;
            long v = strtol(optarg, &end, 10);
            if (!*optarg || *end || v < 0 || v > 1023) {
                fprintf(stderr, "ispm record: --gl-device: '%s' is not a device number (0, 1, ...)\n", optarg);
                return EXIT_INPUT;
            }
            gl_device = (int)v;
            break;
        }
        case 'h': record_usage(stdout); return EXIT_OK;
        default: record_usage(stderr); return EXIT_INPUT;
        }
    }
    if (optind + 1 != argc || !out) {
        record_usage(stderr);
        return EXIT_INPUT;
    }
    if (force && resume) {
        fprintf(stderr, "ispm record: --force and --resume exclude each other\n");
        return EXIT_INPUT;
    }
    if (gl_device >= 0 && (!gl || strcmp(gl, "egl") != 0)) {
        fprintf(stderr, "ispm record: --gl-device needs --gl egl\n");
        return EXIT_INPUT;
    }
    const char *seq_path = argv[optind];
    eng_error err = {{0}};
    seq_sequence *seq = calloc(1, sizeof *seq);
    if (!seq) {
        fprintf(stderr, "ispm: out of memory\n");
        return EXIT_RUNTIME;
    }
    scn_scene *scene = NULL;
    eng_engine *eng = NULL;
    cap_capture *cap = NULL;
    int rc = EXIT_OK;
    eng_result r = seq_load(seq_path, seq, &err);
    if (r == ENG_OK && threads)
        seq->settings.threads = threads;
    if (r == ENG_OK)
        r = scn_load_gltf(seq->scene_path, &scene, &err);
    if (r != ENG_OK) {
        /* Whatever went wrong reading the inputs (missing, unreadable, malformed) is bad input. */
        fprintf(stderr, "ispm record: %s\n", err.msg);
        rc = EXIT_INPUT;
        goto done;
    }
    eng_desc ed = {.scene = scene, .sequence = seq, .gl = gl, .gl_use_device = gl_device >= 0,
                   .gl_device = gl_device};
    r = eng_create(&ed, &eng, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm record: %s\n", err.msg);
        rc = exit_for(r);
        goto done;
    }
    cap_desc cd = {
        .run_dir = out, .sequence = seq, .scene = scene,
        .gl_version = eng_gl_version(eng), .gl_renderer = eng_gl_renderer(eng),
        .gl_backend = eng_gl_backend(eng), .gl_where = eng_gl_where(eng),
        .tool_version = ISPM_VERSION, .git_revision = ISPM_GIT_REV,
        .command_line = command_line, .overwrite = force,
        .determinism = eng_determinism_info(), .resume = resume,
    };
    r = cap_create(&cd, &cap, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm record: %s\n", err.msg);
        /* A run --resume cannot continue (another sequence, already complete) is a bad argument. */
        rc = resume && r == ENG_ERR_INVALID ? EXIT_INPUT : EXIT_RUNTIME;
        goto done;
    }
    eng_listener l = cap_listener(cap);
    eng_add_listener(eng, &l);
    eng_listener progress = {seq, NULL, NULL, progress_frame_end};
    if (!quiet)
        eng_add_listener(eng, &progress);
    if (!quiet)
        fprintf(stderr, "ispm record: %s (%s), %d frames at %g fps, %dx%d, %s\n", seq->name, scene->path,
                seq->frame_count, seq->fps, seq->width, seq->height, eng_gl_renderer(eng));
    if (!quiet && gl)
        fprintf(stderr, "ispm record: GL through %s, %s\n", eng_gl_backend(eng), eng_gl_where(eng));
    for (int i = 0; i < seq->frame_count; i++) {
        /* Resuming: frames the interrupted run completed are kept (each is rendered from
         * scratch, so skipping some changes no other frame). */
        if (cap_frame_done(cap, i))
            continue;
        r = eng_render_frame(eng, i, &err);
        if (r != ENG_OK) {
            eng_error cerr = {{0}};
            if (cap_status(cap, &cerr) != ENG_OK)
                fprintf(stderr, "ispm record: %s\n", cerr.msg);
            else
                fprintf(stderr, "ispm record: %s\n", err.msg);
            fprintf(stderr, "ispm record: run %s is incomplete (no manifest written)\n", out);
            rc = EXIT_RUNTIME;
            goto done;
        }
    }
    r = cap_finish(cap, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm record: %s\n", err.msg);
        fprintf(stderr, "ispm record: run %s is incomplete (no manifest written)\n", out);
        rc = EXIT_RUNTIME;
        goto done;
    }
    printf("run: %s\n", out);
done:
    cap_destroy(cap);
    eng_destroy(eng);
    scn_destroy(scene);
    free(seq);
    return rc;
}

static int cmd_replay(int argc, char **argv)
{
    static const struct option opts[] = {
        {"golden", required_argument, NULL, 'g'}, {"tolerances", required_argument, NULL, 't'},
        {"report", required_argument, NULL, 'r'}, {"quiet", no_argument, NULL, 'q'},
        {"reference", required_argument, NULL, 'R'}, {"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0},
    };
    rep_options o;
    memset(&o, 0, sizeof o);
    int c;
    while ((c = getopt_long(argc, argv, "g:t:r:R:qh", opts, NULL)) != -1) {
        switch (c) {
        case 'g': o.golden_dir = optarg; break;
        case 'R': o.reference_dir = optarg; break;
        case 't': o.tolerances = optarg; break;
        case 'r': o.report_dir = optarg; break;
        case 'q': o.quiet = 1; break;
        case 'h': replay_usage(stdout); return EXIT_OK;
        default: replay_usage(stderr); return REP_UNREADABLE;
        }
    }
    if (optind + 1 != argc) {
        replay_usage(stderr);
        return REP_UNREADABLE;
    }
    o.run_dir = argv[optind];
    eng_error err = {{0}};
    rep_exit rc = rep_replay(&o, stdout, &err);
    if (rc == REP_UNREADABLE)
        fprintf(stderr, "ispm replay: %s\n", err.msg);
    else {
        char dir[4096];
        snprintf(dir, sizeof dir, "%s", o.report_dir ? o.report_dir : o.run_dir);
        printf("report: %s%s/report.html (and report.txt, report.json, report.junit.xml)\n", dir, o.report_dir ? "" : "/replay");
    }
    return (int)rc;
}

static int cmd_bless(int argc, char **argv)
{
    static const struct option opts[] = {{"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        if (c == 'h') {
            bless_usage(stdout);
            return EXIT_OK;
        }
        bless_usage(stderr);
        return EXIT_INPUT;
    }
    if (optind + 2 != argc) {
        bless_usage(stderr);
        return EXIT_INPUT;
    }
    eng_error err = {{0}};
    eng_result r = rep_bless(argv[optind], argv[optind + 1], &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm bless: %s\n", err.msg);
        return exit_for(r);
    }
    printf("golden: %s\n", argv[optind + 1]);
    return EXIT_OK;
}

int cmd_bench(int argc, char **argv, const char *command_line); /* cmd_bench.c */

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return EXIT_INPUT;
    }
    const char *cmd = argv[1];
    /* Past a file-size limit, let writes fail with EFBIG (reported like a full disk) rather
     * than the process dying from SIGXFSZ with a half-written run. */
    signal(SIGXFSZ, SIG_IGN);
    if (!strcmp(cmd, "-h") || !strcmp(cmd, "--help") || !strcmp(cmd, "help")) {
        usage(stdout);
        return EXIT_OK;
    }
    if (!strcmp(cmd, "--version")) {
        printf("ispm %s (%s)\n", ISPM_VERSION, ISPM_GIT_REV);
        return EXIT_OK;
    }
    /* The command line as typed, for the manifest. */
    char line[2048] = "ispm";
    for (int i = 1; i < argc; i++) {
        size_t used = strlen(line);
        snprintf(line + used, sizeof line - used, " %s", argv[i]);
    }
    /* Subcommand options start after the subcommand name. */
    argc--;
    argv++;
    optind = 1;
    if (!strcmp(cmd, "record"))
        return cmd_record(argc, argv, line);
    if (!strcmp(cmd, "replay"))
        return cmd_replay(argc, argv);
    if (!strcmp(cmd, "bless"))
        return cmd_bless(argc, argv);
    if (!strcmp(cmd, "reference"))
        return cmd_reference(argc, argv, line);
    if (!strcmp(cmd, "bench"))
        return cmd_bench(argc, argv, line);
    fprintf(stderr, "ispm: unknown command '%s'\n", cmd);
    usage(stderr);
    return EXIT_INPUT;
}
