/* ispm.c — the one command-line tool: `record` a sequence into a run (engine + capture),
 * `replay` a run against a golden (replay), `bless` a run as the new golden. Options are
 * parsed with getopt_long; every subcommand has --help. Exit codes are what CI scripts rely
 * on and are listed in each command's usage(), from which docs/man/ispm.1 is generated
 * (scripts/man_pages.py). */
#define _POSIX_C_SOURCE 200809L
#include "cap.h"
#include "eng.h"
#include "ispm_git_rev.h" /* ISPM_GIT_REV, made at build time */
#include "merge.h"
#include "rep.h"

#include <getopt.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { EXIT_OK = 0, EXIT_RUNTIME = 1, EXIT_INPUT = 2 };

int cmd_reference(int argc, char **argv, const char *command_line); /* cmd_reference.c */
int cmd_merge(int argc, char **argv, const char *command_line);     /* cmd_merge.c */
int cmd_settings(int argc, char **argv);                            /* cmd_settings.c */

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
            "  bless RUN DIR [--accept]   review a run against the golden in DIR, then make it the golden\n"
            "  check SEQUENCE             record to a temporary run and replay it (for git bisect run)\n"
            "  info RUN                   frames, buffers, settings, provenance, last replay's verdict\n"
            "  export RUN --frame F [--buffer NAME] -o FILE.png|.exr   one buffer as an image, or a frame\n"
            "  golden migrate GOLDEN... | gc ROOT   goldens' buffers stored once, by digest\n"
            "  lineage RUN --frame F --pixel X,Y [--json]   everything that made one pixel\n"
            "  reference SEQUENCE -o RUN  render ground truth (path tracing + photon mapping) to RUN\n"
            "  bench CONFIG -o OUTDIR     speed vs accuracy of engine settings against a reference run\n"
            "  merge SHARD... -o RUN      frame shards (record --frames) checked and merged into one run\n"
            "  tracebench SEQUENCE        photon-trace rays/s against raw Embree rtcIntersect1 on the same rays\n"
            "  settings [--markdown]      every key of a sequence's \"settings\": type, default, range, meaning\n"
            "  trend RUN... -o DIR        how replayed runs' metrics moved from run to run (charts)\n"
            "  tolerances suggest RUN... --golden DIR -o FILE   tolerances from runs that should pass\n"
            "\n"
            "Run 'ispm <command> --help' for a command's options and exit codes.\n");
}

static void record_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm record SEQUENCE -o RUN [--force | --resume] [--threads N] [--gl osmesa|egl [--gl-device N]] [--capture GLOBS] [--lineage] [--quiet]\n"
            "                   [--frames A-B | --shard K/N] [--warmup W] [--overlap O]\n"
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
            "      --capture GLOBS buffers to capture, comma-separated globs (e.g. final.display);\n"
            "                     replaces the sequence's \"capture\" list\n"
            "      --gl BACKEND   how the GL 4.5 context is made: osmesa (default; Mesa's llvmpipe, the\n"
            "                     goldens' reference) or egl (no window: Mesa's surfaceless platform,\n"
            "                     or with --gl-device an EGL device such as a GPU); in the manifest\n"
            "      --gl-device N  with --gl egl: EGL device N (EGL_EXT_platform_device, from 0)\n"
            "      --lineage      also capture photons.origin (each photon's light, bounce-map texel and\n"
            "                     kernel radius), which ispm lineage needs for the photons of a pixel\n"
            "  -q, --quiet        no per-frame progress\n"
            "      --frames A-B   a shard: frames A..B only (ispm merge joins shards into one run)\n"
            "      --shard K/N    a shard: the K-th (from 0) of N equal parts of the sequence's frames\n"
            "      --warmup W     render the W frames before A first, unwritten, so that temporal state\n"
            "                     (temporal and progressive accumulation) is rebuilt as in a whole run\n"
            "                     (default: as far back as the settings need: 0 without temporal\n"
            "                     state, to the temporal_window's start, else from frame 0)\n"
            "      --overlap O    write the last O warm-up frames too, for merge to compare with the\n"
            "                     previous shard (default 1; both clamped to A)\n"
            "  -h, --help         this text\n"
            "\n"
            "exit: 0 run complete; 1 rendering or writing failed (no manifest is written);\n"
            "      2 bad arguments or unreadable/invalid sequence or scene\n");
}

static void replay_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm replay RUN [--golden DIR] [--tolerances FILE] [-fail X ...] [--provenance-fail]\n"
            "                       [--timing-fail RATIO] [--frames A-B] [--buffers GLOB] [--report DIR]\n"
            "                       [--reference REFRUN] [--expectations FILE [--today YYYY-MM-DD]] [--quiet]\n"
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
            "  -fail X, -failrelative X, -failpercent P, -hardfail X, -warn X, -warnrelative X,\n"
            "  -warnpercent P, -hardwarn X   (also --fail ...) idiff's thresholds: each replaces the\n"
            "                          tolerance file's default entry (and rules that inherit it)\n"
            "      --provenance-fail   a different sequence, scene or setting fails (default: warns);\n"
            "                          tool version, git revision, GL, Embree and pins are information\n"
            "      --timing-fail RATIO fail when a pass's share of the frame time (median over frames)\n"
            "                          is over RATIO times the golden's (default: timing is reported only)\n"
            "      --frames A-B        compare frames A to B only (no stability measurement then)\n"
            "      --buffers GLOB      compare the buffers whose names match GLOB only\n"
            "      --no-flip           skip the perceptual metric FLIP of the colour buffers\n"
            "      --expectations FILE known failures (default DIR/expectations.json, if present): a\n"
            "                          failing buffer a rule names is an expected failure and does not\n"
            "                          fail the run; one that now passes, or an expired rule, warns\n"
            "      --today YYYY-MM-DD  the date expectations' \"until\" is judged on (default: today, UTC)\n"
            "  -q, --quiet             print only failures and the verdict\n"
            "  -h, --help              this text\n"
            "\n"
            "Before the pixels it compares the two manifests: every difference in provenance is\n"
            "listed (info, warn or fail) and per-pass timing is reported as run/golden ratios.\n"
            "\n"
            "exit (idiff's convention): 0 ok, 1 warnings (incl. a different sequence, scene or\n"
            "settings), 2 failures (incl. any NaN/Inf not in the golden, missing or extra buffers)\n"
            "or bad arguments, 3 size mismatch, 4 unreadable run, golden or file, 5 the report\n"
            "could not be written (read-only or full disk)\n");
}

static void bless_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm bless RUN DIR [--accept] [--review REVIEWDIR]\n"
            "\n"
            "Makes the complete run RUN the golden in DIR, after a review. When DIR already holds a\n"
            "golden, RUN is first replayed against it: provenance changes (settings, scene, tool, GL,\n"
            "Embree), every buffer that is not bit-exact and by how much, and per-pass timing are\n"
            "printed and written as an HTML review with thumbnails to REVIEWDIR (default RUN/bless).\n"
            "  - bit-exact and made from the same inputs: nothing to do, the golden is left unchanged;\n"
            "  - different: nothing changes unless --accept is given; with it the golden is replaced\n"
            "    (atomically, keeping its tolerances.json) and DIR/BLESS.md records the review, so the\n"
            "    commit that moves a golden carries its own evidence.\n"
            "A new golden (DIR absent, empty, or holding only tolerances.json) needs no --accept.\n"
            "Where a folder above DIR holds an object store (../objects, up to three levels up), or DIR\n"
            "its own objects/, the golden stores each distinct buffer once there, by digest (format 2):\n"
            "only buffers the store lacks are written. A run whose GL renderer is not the golden's goes\n"
            "into DIR/renderers/<slug of the renderer>/, the golden's set for that renderer.\n"
            "\n"
            "  -a, --accept            replace a golden that differs from RUN (an intended change)\n"
            "  -r, --review DIR        where the HTML review goes (default RUN/bless)\n"
            "  -h, --help              this text\n"
            "\n"
            "exit: 0 blessed, or unchanged (bit-exact); 1 RUN differs from the golden and --accept was\n"
            "      not given (nothing changed); 2 bad arguments, RUN incomplete or invalid, DIR not a\n"
            "      golden; 3 writing failed\n");
}

/* Progress listener: one line per frame (refreshed in place on a terminal) with elapsed time,
 * time left and the per-pass times. */
typedef struct record_progress {
    rep_progress p;
    int done;
} record_progress;

static int progress_frame_end(void *user, const eng_frame_stats *st)
{
    record_progress *rp = user;
    char line[512];
    int n = snprintf(line, sizeof line, "t=%.4f s ", st->time);
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
    } else if (n > 0 && (size_t)n < sizeof line) {
        snprintf(line + n, sizeof line - (size_t)n, " ms");
    }
    rep_progress_step(&rp->p, ++rp->done, line);
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

/* --capture GLOB[,GLOB...]: replaces the sequence's "capture" list. Non-zero if a pattern is
 * empty or too long, or there are too many. */
static int set_capture(seq_sequence *seq, const char *list)
{
    int n = 0;
    for (const char *p = list;; n++) {
        const char *e = strchr(p, ',');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        if (n >= SEQ_MAX_CAPTURE || len == 0 || len >= SCN_NAME_MAX)
            return 1;
        memcpy(seq->capture[n], p, len);
        seq->capture[n][len] = 0;
        if (!e)
            break;
        p = e + 1;
    }
    seq->capture_count = n + 1;
    return 0;
}

/* A shard's warm-up and overlap (-1: not given): the overlap defaults to 1, the warm-up to what
 * the settings need for the overlap frames' state — none without temporal state, back to the
 * temporal_window boundary, else to frame 0 — never less than the overlap; both clamped to
 * the frames before the shard. */
static void shard_warmup(const eng_engine *eng, const eng_settings *s, cap_shard *sh, int warmup, int overlap)
{
    if (overlap < 0)
        overlap = warmup >= 0 && warmup < 1 ? warmup : 1;
    if (overlap > sh->first)
        overlap = sh->first;
    if (warmup < 0) {
        int from = sh->first - overlap;
        if (eng_stateful(eng))
            from = s->temporal_window > 0 ? from / s->temporal_window * s->temporal_window : 0;
        warmup = sh->first - from;
    }
    if (warmup > sh->first)
        warmup = sh->first;
    if (warmup < overlap)
        warmup = overlap;
    sh->warmup = warmup;
    sh->overlap = overlap;
}

/* What `"exposure": "auto"` metered at frame 0 (nothing when the stops were recorded by an
 * interrupted run or the exposure is a number): one line, a warning when frame 0 had no lit
 * pixel and the stops fell back to 0. */
static void report_exposure(const eng_engine *eng, const char *seq_path, int quiet)
{
    float stops;
    eng_exposure_key_info in;
    if (eng_exposure(eng, &stops, &in) != 1)
        return;
    if (in.counted == 0) {
        fprintf(stderr, "ispm record: warning: %s: \"exposure\": \"auto\": frame 0 has no lit pixel to meter; "
                        "exposure 0 stops\n", seq_path);
    } else if (!quiet) {
        fprintf(stderr, "ispm record: \"exposure\": \"auto\": %g stops (frame 0's log-average luminance %g over %llu "
                        "pixels%s)\n", (double)stops, in.log_average, (unsigned long long)in.counted,
                in.nonfinite ? ", non-finite ones left out" : "");
    }
}

static int cmd_record(int argc, char **argv, const char *command_line)
{
    static const struct option opts[] = {
        {"output", required_argument, NULL, 'o'}, {"force", no_argument, NULL, 'f'},
        {"threads", required_argument, NULL, 'j'}, {"quiet", no_argument, NULL, 'q'},
        {"resume", no_argument, NULL, 'r'}, {"help", no_argument, NULL, 'h'},
        {"gl", required_argument, NULL, 'G'}, {"gl-device", required_argument, NULL, 'D'},
        {"capture", required_argument, NULL, 'C'},
        {"frames", required_argument, NULL, 'F'}, {"warmup", required_argument, NULL, 'W'},
        {"overlap", required_argument, NULL, 'O'}, {"shard", required_argument, NULL, 'S'}, {"lineage", no_argument, NULL, 'L'},
        {NULL, 0, NULL, 0},
    };
    const char *out = NULL, *gl = NULL, *capture = NULL;
    int force = 0, resume = 0, quiet = 0, threads = 0, gl_device = -1, lineage = 0, c;
    int shard = 0, first = 0, last = 0, warmup = -1, overlap = -1, shard_k = -1, shard_n = 0;
    while ((c = getopt_long(argc, argv, "o:fj:qrh", opts, NULL)) != -1) {
        switch (c) {
        case 'o': out = optarg; break;
        case 'f': force = 1; break;
        case 'r': resume = 1; break;
        case 'q': quiet = 1; break;
        case 'L': lineage = 1; break;
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
        case 'C': capture = optarg; break;
        case 'F':
            if (!cap_parse_range(optarg, &first, &last)) {
                fprintf(stderr, "ispm record: --frames: '%s' is not A-B (frame indices, A <= B)\n", optarg);
                return EXIT_INPUT;
            }
            shard = 1;
            break;
        case 'S': {
            char tail;
            if (sscanf(optarg, "%d/%d%c", &shard_k, &shard_n, &tail) != 2 || shard_n < 1 || shard_k < 0 ||
                shard_k >= shard_n) {
                fprintf(stderr, "ispm record: --shard: '%s' is not K/N (0 <= K < N)\n", optarg);
                return EXIT_INPUT;
            }
            shard = 1;
            break;
        }
        case 'W':
        case 'O': {
            int v, v2;
            if (!cap_parse_range(optarg, &v, &v2) || v != v2 || strchr(optarg, '-')) {
                fprintf(stderr, "ispm record: --%s: '%s' is not a number of frames\n", c == 'W' ? "warmup" : "overlap",
                        optarg);
                return EXIT_INPUT;
            }
            *(c == 'W' ? &warmup : &overlap) = v;
            break;
        }
        case 'h': record_usage(stdout); return EXIT_OK;
        default: record_usage(stderr); return EXIT_INPUT;
        }
    }
    if (!shard && (warmup >= 0 || overlap >= 0)) {
        fprintf(stderr, "ispm record: --warmup and --overlap need --frames or --shard\n");
        return EXIT_INPUT;
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
    eng_keep_freed_memory(); /* llvmpipe's binned scene, freed and allocated again every frame */
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
    if (r == ENG_OK && capture && set_capture(seq, capture) != 0) {
        fprintf(stderr, "ispm record: --capture: '%s' is not 1..%d comma-separated glob patterns of at most %d "
                "characters\n", capture, SEQ_MAX_CAPTURE, SCN_NAME_MAX - 1);
        free(seq);
        return EXIT_INPUT;
    }
    if (r == ENG_OK)
        r = seq_load_scene(seq, &scene, &err);
    if (r != ENG_OK) {
        /* Whatever went wrong reading the inputs (missing, unreadable, malformed) is bad input. */
        fprintf(stderr, "ispm record: %s\n", err.msg);
        rc = EXIT_INPUT;
        goto done;
    }
    if (shard_n > 0) { /* --shard K/N: the K-th of N equal parts of the sequence */
        if (shard_n > seq->frame_count) {
            fprintf(stderr, "ispm record: --shard %d/%d: %s has only %d frames\n", shard_k, shard_n, seq_path,
                    seq->frame_count);
            rc = EXIT_INPUT;
            goto done;
        }
        first = (int)((long)shard_k * seq->frame_count / shard_n);
        last = (int)((long)(shard_k + 1) * seq->frame_count / shard_n) - 1;
    }
    if (shard && last >= seq->frame_count) {
        fprintf(stderr, "ispm record: --frames %d-%d: %s has frames 0..%d\n", first, last, seq_path,
                seq->frame_count - 1);
        rc = EXIT_INPUT;
        goto done;
    }
    for (uint32_t w = 0; w < scene->warning_count && w < SCN_MAX_WARNINGS; w++)
        fprintf(stderr, "ispm record: warning: %s\n", scene->warnings[w]);
    eng_desc ed = {.scene = scene, .sequence = seq, .gl = gl, .gl_use_device = gl_device >= 0,
                   .gl_device = gl_device, .lineage = lineage};
    r = eng_create(&ed, &eng, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm record: %s\n", err.msg);
        rc = exit_for(r);
        goto done;
    }
    cap_shard sh = {first, last, 0, 0};
    if (shard) {
        shard_warmup(eng, &seq->settings, &sh, warmup, overlap);
        eng_set_history_start(eng, first - sh.warmup);
    }
    cap_desc cd = {
        .run_dir = out, .sequence = seq, .scene = scene,
        .gl_version = eng_gl_version(eng), .gl_renderer = eng_gl_renderer(eng),
        .gl_backend = eng_gl_backend(eng), .gl_where = eng_gl_where(eng),
        .tool_version = ISPM_VERSION, .git_revision = ISPM_GIT_REV,
        .command_line = command_line, .overwrite = force, .build_aside = force,
        .determinism = eng_determinism_info(), .resume = resume, .shard = shard ? &sh : NULL,
        .writers = 1, /* frame N is encoded and written while frame N+1 renders */
    };
    r = cap_create(&cd, &cap, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm record: %s\n", err.msg);
        /* A run --resume cannot continue (another sequence, already complete), a run another
         * process is writing (its lock) and shard frames that do not fit are bad arguments. */
        rc = r == ENG_ERR_INVALID ? EXIT_INPUT : EXIT_RUNTIME;
        goto done;
    }
    eng_listener l = cap_listener(cap);
    eng_add_listener(eng, &l);
    /* Resuming an "auto" exposure: the stops the interrupted run metered at frame 0. */
    float stops = 0.0f;
    if (cap_recorded_exposure(cap, &stops))
        eng_set_exposure(eng, stops);
    record_progress prog;
    int to_render = 0, write_first = shard ? sh.first - sh.overlap : 0, write_last = shard ? sh.last : seq->frame_count - 1;
    for (int i = write_first; i <= write_last; i++)
        to_render += !cap_frame_done(cap, i);
    rep_progress_begin(&prog.p, stderr, "ispm record", "frame", to_render);
    prog.done = 0;
    eng_listener progress = {&prog, NULL, NULL, progress_frame_end};
    if (!quiet)
        eng_add_listener(eng, &progress);
    if (!quiet)
        fprintf(stderr, "ispm record: %s (%s), %d frames at %g fps, %dx%d, %s\n", seq->name, scene->path,
                seq->frame_count, seq->fps, seq->width, seq->height, eng_gl_renderer(eng));
    if (!quiet && gl)
        fprintf(stderr, "ispm record: GL through %s, %s\n", eng_gl_backend(eng), eng_gl_where(eng));
    if (!quiet && shard)
        fprintf(stderr, "ispm record: shard: frames %d-%d, warm-up %d (from frame %d), of which %d written\n",
                sh.first, sh.last, sh.warmup, sh.first - sh.warmup, sh.overlap);
    for (int i = write_first; i <= write_last; i++) {
        /* Resuming: frames the interrupted run completed are kept (each is rendered from
         * scratch, so skipping some changes no other frame). */
        if (cap_frame_done(cap, i))
            continue;
        r = eng_render_frame(eng, i, &err);
        if (r != ENG_OK) {
            if (!quiet)
                rep_progress_end(&prog.p);
            eng_error cerr = {{0}};
            if (cap_status(cap, &cerr) != ENG_OK)
                fprintf(stderr, "ispm record: %s\n", cerr.msg);
            else
                fprintf(stderr, "ispm record: %s\n", err.msg);
            if (!cap_builds_aside(cap)) /* else the old run in out is kept as it was */
                fprintf(stderr, "ispm record: run %s is incomplete (no manifest written)\n", out);
            rc = EXIT_RUNTIME;
            goto done;
        }
    }
    if (!quiet)
        rep_progress_end(&prog.p);
    report_exposure(eng, seq_path, quiet);
    /* The renderer is torn down (GL objects, the context: 20-30 ms) while the writer still
     * encodes, writes and syncs the last frame, which cap_finish waits for. */
    eng_destroy(eng);
    eng = NULL;
    r = cap_finish(cap, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm record: %s\n", err.msg);
        if (!cap_builds_aside(cap))
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

/* idiff spells its thresholds with one dash (-fail 0.1); getopt_long wants two: the eight
 * names are rewritten in place before parsing (argv's pointers only). */
static void idiff_dashes(int argc, char **argv)
{
    static char spelled[8][16];
    static const char *const names[8] = {"warn", "warnrelative", "warnpercent", "hardwarn",
                                         "fail", "failrelative", "failpercent", "hardfail"};
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--") == 0)
            return;
        for (int k = 0; k < 8; k++)
            if (argv[i][0] == '-' && strcmp(argv[i] + 1, names[k]) == 0) {
                snprintf(spelled[k], sizeof spelled[k], "--%s", names[k]);
                argv[i] = spelled[k];
            }
    }
}

/* "A-B" or "A" (frame indices, A <= B) into o. */
static int parse_frames(const char *s, rep_options *o)
{
    char *end;
    long a = strtol(s, &end, 10), b = a;
    if (end == s || a < 0)
        return 0;
    if (*end == '-') {
        const char *t = end + 1;
        b = strtol(t, &end, 10);
        if (end == t)
            return 0;
    }
    if (*end || b < a || b > 1000000)
        return 0;
    o->frames_set = 1;
    o->frame_first = (int)a;
    o->frame_last = (int)b;
    return 1;
}

static int cmd_replay(int argc, char **argv)
{
    enum { OPT_TOL = 1000, OPT_TIMING_FAIL = 1100, OPT_PROV_FAIL, OPT_FRAMES, OPT_BUFFERS, OPT_NO_FLIP, OPT_EXPECT,
           OPT_TODAY };
    static const struct option opts[] = {
        {"golden", required_argument, NULL, 'g'}, {"tolerances", required_argument, NULL, 't'},
        {"report", required_argument, NULL, 'r'}, {"quiet", no_argument, NULL, 'q'},
        {"reference", required_argument, NULL, 'R'}, {"help", no_argument, NULL, 'h'},
        {"warn", required_argument, NULL, OPT_TOL}, {"warnrelative", required_argument, NULL, OPT_TOL},
        {"warnpercent", required_argument, NULL, OPT_TOL}, {"hardwarn", required_argument, NULL, OPT_TOL},
        {"fail", required_argument, NULL, OPT_TOL}, {"failrelative", required_argument, NULL, OPT_TOL},
        {"failpercent", required_argument, NULL, OPT_TOL}, {"hardfail", required_argument, NULL, OPT_TOL},
        {"timing-fail", required_argument, NULL, OPT_TIMING_FAIL},
        {"provenance-fail", no_argument, NULL, OPT_PROV_FAIL},
        {"frames", required_argument, NULL, OPT_FRAMES}, {"buffers", required_argument, NULL, OPT_BUFFERS},
        {"no-flip", no_argument, NULL, OPT_NO_FLIP},
        {"expectations", required_argument, NULL, OPT_EXPECT}, {"today", required_argument, NULL, OPT_TODAY},
        {NULL, 0, NULL, 0},
    };
    rep_options o;
    memset(&o, 0, sizeof o);
    int c, idx = 0;
    idiff_dashes(argc, argv);
    while ((c = getopt_long(argc, argv, "g:t:r:R:qh", opts, &idx)) != -1) {
        switch (c) {
        case 'g': o.golden_dir = optarg; break;
        case 'R': o.reference_dir = optarg; break;
        case 't': o.tolerances = optarg; break;
        case 'r': o.report_dir = optarg; break;
        case 'q': o.quiet = 1; break;
        case 'h': replay_usage(stdout); return EXIT_OK;
        case OPT_TOL:
            if (rep_tol_flag_parse(&o.flags, opts[idx].name, optarg) != 1) {
                fprintf(stderr, "ispm replay: -%s: '%s' is not a number >= 0\n", opts[idx].name, optarg);
                return EXIT_INPUT;
            }
            break;
        case OPT_TIMING_FAIL: {
            char *end;
            o.timing_fail = strtod(optarg, &end);
            if (*end || !(o.timing_fail > 0) || o.timing_fail > 1e9) {
                fprintf(stderr, "ispm replay: --timing-fail: '%s' is not a ratio > 0\n", optarg);
                return EXIT_INPUT;
            }
            break;
        }
        case OPT_PROV_FAIL: o.provenance_fail = 1; break;
        case OPT_FRAMES:
            if (!parse_frames(optarg, &o)) {
                fprintf(stderr, "ispm replay: --frames: '%s' is not A-B (frame indices, A <= B)\n", optarg);
                return EXIT_INPUT;
            }
            break;
        case OPT_BUFFERS: o.buffers = optarg; break;
        case OPT_NO_FLIP: o.no_flip = 1; break;
        case OPT_EXPECT: o.expectations = optarg; break;
        case OPT_TODAY:
            if (!rep_date_valid(optarg)) {
                fprintf(stderr, "ispm replay: --today: '%s' is not a date YYYY-MM-DD\n", optarg);
                return EXIT_INPUT;
            }
            o.today = optarg;
            break;
        default: replay_usage(stderr); return EXIT_INPUT;
        }
    }
    if (optind + 1 != argc) {
        replay_usage(stderr);
        return EXIT_INPUT;
    }
    if ((o.flags.set || o.timing_fail > 0 || o.provenance_fail || o.expectations || o.today) && !o.golden_dir) {
        fprintf(stderr, "ispm replay: thresholds, --timing-fail, --provenance-fail and --expectations need --golden\n");
        return EXIT_INPUT;
    }
    o.run_dir = argv[optind];
    rep_progress prog;
    /* on a terminal only: in a log, stderr keeps its one line per error */
    rep_progress_begin(&prog, !o.quiet && isatty(STDERR_FILENO) ? stderr : NULL, "ispm replay", "frame", 0);
    o.progress = &prog;
    eng_error err = {{0}};
    rep_exit rc = rep_replay(&o, stdout, &err);
    if (rc == REP_UNREADABLE || rc == REP_UNWRITABLE)
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
    static const struct option opts[] = {{"accept", no_argument, NULL, 'a'}, {"review", required_argument, NULL, 'r'},
                                         {"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0}};
    rep_bless_options o;
    memset(&o, 0, sizeof o);
    int c;
    while ((c = getopt_long(argc, argv, "ar:h", opts, NULL)) != -1) {
        switch (c) {
        case 'a': o.accept = 1; break;
        case 'r': o.review_dir = optarg; break;
        case 'h': bless_usage(stdout); return EXIT_OK;
        default: bless_usage(stderr); return EXIT_INPUT;
        }
    }
    if (optind + 2 != argc) {
        bless_usage(stderr);
        return EXIT_INPUT;
    }
    o.run_dir = argv[optind];
    o.golden_dir = argv[optind + 1];
    eng_error err = {{0}};
    rep_bless_outcome out;
    eng_result r = rep_bless_reviewed(&o, stdout, &out, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm bless: %s\n", err.msg);
        return r == ENG_ERR_INVALID || r == ENG_ERR_PARSE ? EXIT_INPUT : 3;
    }
    switch (out) {
    case REP_BLESS_REFUSED: return EXIT_RUNTIME;
    case REP_BLESS_SAME: printf("golden: %s (unchanged)\n", o.golden_dir); break;
    case REP_BLESS_NEW: printf("golden: %s (new; review in %s/BLESS.md)\n", o.golden_dir, o.golden_dir); break;
    case REP_BLESS_REPLACED: printf("golden: %s (replaced; review in %s/BLESS.md)\n", o.golden_dir, o.golden_dir); break;
    }
    return EXIT_OK;
}

int cmd_bench(int argc, char **argv, const char *command_line); /* cmd_bench.c */
int cmd_check(int argc, char **argv);                           /* cmd_check.c */
int cmd_info(int argc, char **argv);                            /* cmd_inspect.c */
int cmd_export(int argc, char **argv);                          /* cmd_inspect.c */
int cmd_lineage(int argc, char **argv);                         /* cmd_lineage.c */
int cmd_tracebench(int argc, char **argv);                      /* cmd_tracebench.c */
int cmd_golden(int argc, char **argv);                          /* cmd_golden.c */
int cmd_trend(int argc, char **argv);                           /* cmd_trend.c */
int cmd_tolerances(int argc, char **argv);                      /* cmd_tolerances.c */

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
    if (!strcmp(cmd, "check"))
        return cmd_check(argc, argv);
    if (!strcmp(cmd, "merge"))
        return cmd_merge(argc, argv, line);
    if (!strcmp(cmd, "info"))
        return cmd_info(argc, argv);
    if (!strcmp(cmd, "export"))
        return cmd_export(argc, argv);
    if (!strcmp(cmd, "golden"))
        return cmd_golden(argc, argv);
    if (!strcmp(cmd, "lineage"))
        return cmd_lineage(argc, argv);
    if (!strcmp(cmd, "tracebench"))
        return cmd_tracebench(argc, argv);
    if (!strcmp(cmd, "settings"))
        return cmd_settings(argc, argv);
    if (!strcmp(cmd, "trend"))
        return cmd_trend(argc, argv);
    if (!strcmp(cmd, "tolerances"))
        return cmd_tolerances(argc, argv);
    fprintf(stderr, "ispm: unknown command '%s'\n", cmd);
    usage(stderr);
    return EXIT_INPUT;
}
