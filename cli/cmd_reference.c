/* cmd_reference.c — `ispm reference`: renders a sequence's frames with the reference renderer
 * (engine/reference/ref.h) into a normal run folder (capture module: frames/NNNNNN.exr, manifest.json
 * last), so `ispm replay`, `bless` and the viewer read it like any run. The manifest records
 * the renderer and its settings under "renderer". With --frames A-B the run holds B − A + 1
 * frames: run frame i is sequence frame A + i, rendered at t = (A + i) / fps, and the time
 * recorded per frame is that t. Exit codes follow `record`: 0 ok, 1 rendering or writing
 * failed (no manifest), 2 bad arguments or unreadable/invalid sequence or scene. */
#define _POSIX_C_SOURCE 200809L
#include "cap.h"
#include "eng.h"
#include "ispm_git_rev.h" /* ISPM_GIT_REV, made at build time */
#include "ref.h"
#include "rep.h" /* rep_progress */

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cmd_reference(int argc, char **argv, const char *command_line);

enum { REF_EXIT_OK = 0, REF_EXIT_RUNTIME = 1, REF_EXIT_INPUT = 2 };

static void reference_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm reference SEQUENCE -o RUN [--spp N] [--frames A-B] [--threads N] [--seed S]\n"
            "                      [--max-depth N] [--photons N] [--pixel-center] [--force] [--quiet]\n"
            "\n"
            "Renders ground truth for SEQUENCE's frames on the CPU (Embree): path tracing with\n"
            "next-event estimation to the lights plus progressive photon mapping for caustics,\n"
            "with the engine's scene, camera, lights and BSDFs at the same frame times. Writes a\n"
            "run (RUN/frames/NNNNNN.exr, RUN/manifest.json last) with the buffers\n"
            "reference.direct, reference.indirect and reference.full (linear W/m^2/sr).\n"
            "\n"
            "  -o, --output RUN     run folder to create\n"
            "  -s, --spp N          samples per pixel (= caustic photon passes); default 64\n"
            "  -F, --frames A-B     sequence frames A..B (or one frame A); run frame i is\n"
            "                       sequence frame A+i; default all\n"
            "  -j, --threads N      CPU threads; default the sequence's settings\n"
            "  -S, --seed S         random seed (0..4294967295); default 0\n"
            "  -d, --max-depth N    surfaces per eye path; default 64\n"
            "  -p, --photons N      caustic photons per pass; default 16384\n"
            "  -c, --pixel-center   every camera ray through its pixel's centre, where the\n"
            "                       engine's G-buffers sample the scene (no antialiasing: the\n"
            "                       truth an image-space method is compared with at edges);\n"
            "                       default: jittered over the pixel (box-filtered)\n"
            "  -f, --force          replace an existing run in RUN\n"
            "  -q, --quiet          no progress on stderr\n"
            "  -h, --help           this text\n"
            "\n"
            "exit: 0 run complete; 1 rendering or writing failed (no manifest is written);\n"
            "      2 bad arguments or unreadable/invalid sequence or scene\n");
}

/* A whole number in lo..hi, or -1 on error (hi < 2^62). */
static long long parse_count(const char *s, long long lo, long long hi)
{
    char *end;
    if (!s[0] || s[0] == '-' || s[0] == '+')
        return -1;
    long long v = strtoll(s, &end, 10);
    if (*end || v < lo || v > hi)
        return -1;
    return v;
}

/* Forwards the reference renderer's callbacks to the capture with the frame index shifted by
 * `first`, so that sequence frames A..B become run frames 0..B−A. */
typedef struct shift_listener {
    eng_listener inner;
    int first;
} shift_listener;

static int shift_begin(void *user, int frame, double time)
{
    shift_listener *s = user;
    return s->inner.frame_begin(s->inner.user, frame - s->first, time);
}

static int shift_buffer(void *user, int frame, const eng_buffer *buf)
{
    shift_listener *s = user;
    return s->inner.buffer(s->inner.user, frame - s->first, buf);
}

static int shift_end(void *user, const eng_frame_stats *stats)
{
    shift_listener *s = user;
    eng_frame_stats st = *stats;
    st.frame -= s->first;
    return s->inner.frame_end(s->inner.user, &st);
}

int cmd_reference(int argc, char **argv, const char *command_line)
{
    static const struct option opts[] = {
        {"output", required_argument, NULL, 'o'}, {"spp", required_argument, NULL, 's'},
        {"frames", required_argument, NULL, 'F'}, {"threads", required_argument, NULL, 'j'},
        {"seed", required_argument, NULL, 'S'},   {"max-depth", required_argument, NULL, 'd'},
        {"photons", required_argument, NULL, 'p'}, {"force", no_argument, NULL, 'f'},
        {"quiet", no_argument, NULL, 'q'},        {"help", no_argument, NULL, 'h'},
        {"pixel-center", no_argument, NULL, 'c'}, {NULL, 0, NULL, 0},
    };
    const char *out = NULL, *frames_arg = NULL;
    ref_desc rd;
    memset(&rd, 0, sizeof rd);
    int force = 0, c;
    long long v;
    while ((c = getopt_long(argc, argv, "o:s:F:j:S:d:p:fqhc", opts, NULL)) != -1) {
        switch (c) {
        case 'o': out = optarg; break;
        case 'F': frames_arg = optarg; break;
        case 'f': force = 1; break;
        case 'q': rd.quiet = 1; break;
        case 'c': rd.pixel_center = 1; break;
        case 's':
            if ((v = parse_count(optarg, 1, 1 << 20)) < 0) {
                fprintf(stderr, "ispm reference: --spp: '%s' is not a number in 1..%d\n", optarg, 1 << 20);
                return REF_EXIT_INPUT;
            }
            rd.spp = (int)v;
            break;
        case 'j':
            if ((v = parse_count(optarg, 1, 64)) < 0) {
                fprintf(stderr, "ispm reference: --threads: '%s' is not a number in 1..64\n", optarg);
                return REF_EXIT_INPUT;
            }
            rd.threads = (int)v;
            break;
        case 'S':
            if ((v = parse_count(optarg, 0, 4294967295ll)) < 0) {
                fprintf(stderr, "ispm reference: --seed: '%s' is not a number in 0..4294967295\n", optarg);
                return REF_EXIT_INPUT;
            }
            rd.seed = (uint32_t)v;
            break;
        case 'd':
            if ((v = parse_count(optarg, 1, 256)) < 0) {
                fprintf(stderr, "ispm reference: --max-depth: '%s' is not a number in 1..256\n", optarg);
                return REF_EXIT_INPUT;
            }
            rd.max_depth = (int)v;
            break;
        case 'p':
            if ((v = parse_count(optarg, 1, 1 << 24)) < 0) {
                fprintf(stderr, "ispm reference: --photons: '%s' is not a number in 1..%d\n", optarg, 1 << 24);
                return REF_EXIT_INPUT;
            }
            rd.photons = (int)v;
            break;
        case 'h': reference_usage(stdout); return REF_EXIT_OK;
        default: reference_usage(stderr); return REF_EXIT_INPUT;
        }
    }
    if (optind + 1 != argc || !out) {
        reference_usage(stderr);
        return REF_EXIT_INPUT;
    }
    const char *seq_path = argv[optind];
    eng_error err = {{0}};
    /* eseq: the sequence as the engine sees it (no photon passes); cseq: as the capture sees
     * it (the frames of this run, only the reference buffers). */
    seq_sequence *eseq = calloc(1, sizeof *eseq), *cseq = calloc(1, sizeof *cseq);
    if (!eseq || !cseq) {
        fprintf(stderr, "ispm: out of memory\n");
        free(eseq);
        free(cseq);
        return REF_EXIT_RUNTIME;
    }
    scn_scene *scene = NULL;
    eng_engine *eng = NULL;
    ref_renderer *ref = NULL;
    cap_capture *cap = NULL;
    int rc = REF_EXIT_OK;
    eng_result r = seq_load(seq_path, eseq, &err);
    if (r == ENG_OK)
        r = seq_load_scene(eseq, &scene, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm reference: %s\n", err.msg);
        rc = REF_EXIT_INPUT;
        goto done;
    }
    for (uint32_t w = 0; w < scene->warning_count && w < SCN_MAX_WARNINGS; w++)
        fprintf(stderr, "ispm reference: warning: %s\n", scene->warnings[w]);
    int first = 0, last = eseq->frame_count - 1;
    if (frames_arg) {
        char a[32], b[32];
        const char *dash = strchr(frames_arg, '-');
        size_t n = dash ? (size_t)(dash - frames_arg) : strlen(frames_arg);
        long long fa = -1, fb = -1;
        if (n < sizeof a && (!dash || strlen(dash + 1) < sizeof b)) {
            memcpy(a, frames_arg, n);
            a[n] = 0;
            snprintf(b, sizeof b, "%s", dash ? dash + 1 : a);
            fa = parse_count(a, 0, eseq->frame_count - 1);
            fb = parse_count(b, 0, eseq->frame_count - 1);
        }
        if (fa < 0 || fb < fa) {
            fprintf(stderr, "ispm reference: --frames: '%s' is not A-B with 0 <= A <= B <= %d (%s)\n", frames_arg,
                    eseq->frame_count - 1, seq_path);
            rc = REF_EXIT_INPUT;
            goto done;
        }
        first = (int)fa;
        last = (int)fb;
    }
    eseq->settings.indirect = ENG_INDIRECT_NONE;
    if (rd.threads)
        eseq->settings.threads = rd.threads;
    *cseq = *eseq;
    cseq->frame_count = last - first + 1;
    cseq->capture_count = 1;
    snprintf(cseq->capture[0], sizeof cseq->capture[0], "reference.*");

    eng_desc ed = {.scene = scene, .sequence = eseq};
    r = eng_create(&ed, &eng, &err);
    if (r == ENG_OK) {
        rd.engine = eng;
        rd.sequence = eseq;
        r = ref_create(&rd, &ref, &err);
    }
    if (r != ENG_OK) {
        fprintf(stderr, "ispm reference: %s\n", err.msg);
        rc = r == ENG_ERR_PARSE || r == ENG_ERR_INVALID || r == ENG_ERR_UNSUPPORTED ? REF_EXIT_INPUT : REF_EXIT_RUNTIME;
        goto done;
    }
    char settings[1024], inner[900];
    ref_settings_json(ref, inner, sizeof inner);
    snprintf(settings, sizeof settings, "{\"first_frame\": %d, \"last_frame\": %d, %s", first, last, inner + 1);
    cap_desc cd = {
        .run_dir = out, .sequence = cseq, .scene = scene,
        .gl_version = eng_gl_version(eng), .gl_renderer = eng_gl_renderer(eng),
        .tool_version = ISPM_VERSION, .git_revision = ISPM_GIT_REV,
        .command_line = command_line, .overwrite = force,
        .determinism = eng_determinism_info(),
        .renderer = "reference", .renderer_settings = settings,
    };
    r = cap_create(&cd, &cap, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm reference: %s\n", err.msg);
        rc = REF_EXIT_RUNTIME;
        goto done;
    }
    shift_listener shift = {cap_listener(cap), first};
    eng_listener l = {&shift, shift_begin, shift_buffer, shift_end};
    ref_add_listener(ref, &l);
    const ref_desc *s = ref_settings(ref);
    if (!rd.quiet)
        fprintf(stderr, "ispm reference: %s (%s), frames %d-%d, %dx%d, %d spp (%s), max depth %d, %s, %d threads\n",
                eseq->name, scene->path, first, last, eseq->width, eseq->height, s->spp,
                s->pixel_center ? "pixel centres" : "box-filtered", s->max_depth,
                s->no_caustics ? "no caustics" : "caustic photon passes", s->threads);
    rep_progress prog;
    rep_progress_begin(&prog, rd.quiet ? NULL : stderr, "ispm reference", "frame", last - first + 1);
    for (int f = first; f <= last; f++) {
        r = ref_render_frame(ref, f, &err);
        rep_progress_step(&prog, f - first + 1, NULL);
        if (r != ENG_OK) {
            eng_error cerr = {{0}};
            fprintf(stderr, "ispm reference: %s\n", cap_status(cap, &cerr) != ENG_OK ? cerr.msg : err.msg);
            fprintf(stderr, "ispm reference: run %s is incomplete (no manifest written)\n", out);
            rc = REF_EXIT_RUNTIME;
            goto done;
        }
    }
    rep_progress_end(&prog);
    r = cap_finish(cap, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm reference: %s\n", err.msg);
        fprintf(stderr, "ispm reference: run %s is incomplete (no manifest written)\n", out);
        rc = REF_EXIT_RUNTIME;
        goto done;
    }
    printf("run: %s\n", out);
done:
    cap_destroy(cap);
    ref_destroy(ref);
    eng_destroy(eng);
    scn_destroy(scene);
    free(eseq);
    free(cseq);
    return rc;
}
