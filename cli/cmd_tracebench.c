/* cmd_tracebench.c — `ispm tracebench SEQUENCE`: the photon trace's rays per second against
 * Embree's raw rtcIntersect1 on the same rays in the same process (the
 * measurement is cli/bench/trace_bench.c's). Prints both rates (medians over the repeats, which
 * alternate trace and raw cast), their ratio, and whether every repeat's photon map was
 * bit-identical to the ray-by-ray one-thread trace. Exit: 0 measured; 1 the trace failed or
 * its map differed; 2 bad arguments or an unreadable sequence or scene. */
#include "eng.h"
#include "rep_util.h"
#include "tracebench.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int cmd_tracebench(int argc, char **argv);

enum { TB_EXIT_OK = 0, TB_EXIT_RUNTIME = 1, TB_EXIT_INPUT = 2 };

static void tracebench_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm tracebench SEQUENCE [--frame F] [--repeats R] [--threads N] [--photons N]\n"
            "\n"
            "Traces frame F's bounce-map photons through the engine's photon trace (Embree) and casts\n"
            "exactly the same rays (recorded from a one-thread trace) with raw rtcIntersect1 on the\n"
            "same scene, alternating R times, and prints the rays per second of each (medians) and\n"
            "their ratio. Also checks that every repeat's photon map is bit-identical to the\n"
            "ray-by-ray trace's.\n"
            "\n"
            "  -F, --frame F      frame of the sequence (default 0)\n"
            "  -r, --repeats R    alternations, 1..%d (default 5)\n"
            "  -j, --threads N    CPU threads (default: the sequence's)\n"
            "  -p, --photons N    bounce-map photons (default: the sequence's photon_count)\n"
            "  -h, --help         this text\n"
            "\n"
            "exit: 0 measured; 1 tracing failed or a photon map differed; 2 bad arguments or an\n"
            "      unreadable/invalid sequence or scene\n",
            TB_MAX_REPEATS);
}

static long long tb_count(const char *s, long long lo, long long hi)
{
    char *end;
    if (!s[0] || s[0] == '-' || s[0] == '+')
        return -1;
    long long v = strtoll(s, &end, 10);
    return *end || v < lo || v > hi ? -1 : v;
}

static double median(const double *v, int n)
{
    double s[TB_MAX_REPEATS];
    memcpy(s, v, (size_t)n * sizeof *s);
    return rep_median(s, n);
}

int cmd_tracebench(int argc, char **argv)
{
    static const struct option opts[] = {{"frame", required_argument, NULL, 'F'},
                                         {"repeats", required_argument, NULL, 'r'},
                                         {"threads", required_argument, NULL, 'j'},
                                         {"photons", required_argument, NULL, 'p'},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    long long frame = 0, repeats = 5, threads = 0, photons = 0;
    int c;
    while ((c = getopt_long(argc, argv, "F:r:j:p:h", opts, NULL)) != -1) {
        long long *dst = c == 'F' ? &frame : c == 'r' ? &repeats : c == 'j' ? &threads : c == 'p' ? &photons : NULL;
        const char *name = c == 'F' ? "--frame" : c == 'r' ? "--repeats" : c == 'j' ? "--threads" : "--photons";
        long long lo = c == 'F' ? 0 : 1;
        long long hi = c == 'F' ? 1 << 20 : c == 'r' ? TB_MAX_REPEATS : c == 'j' ? 64 : 1 << 24;
        if (c == 'h') {
            tracebench_usage(stdout);
            return TB_EXIT_OK;
        }
        if (!dst) {
            tracebench_usage(stderr);
            return TB_EXIT_INPUT;
        }
        if ((*dst = tb_count(optarg, lo, hi)) < 0) {
            fprintf(stderr, "ispm tracebench: %s: '%s' is not a number in %lld..%lld\n", name, optarg, lo, hi);
            return TB_EXIT_INPUT;
        }
    }
    if (optind + 1 != argc) {
        tracebench_usage(stderr);
        return TB_EXIT_INPUT;
    }
    const char *path = argv[optind];
    eng_error err = {{0}};
    seq_sequence *seq = calloc(1, sizeof *seq);
    if (!seq) {
        fprintf(stderr, "ispm: out of memory\n");
        return TB_EXIT_RUNTIME;
    }
    scn_scene *scene = NULL;
    eng_engine *eng = NULL;
    int rc = TB_EXIT_OK;
    eng_result r = seq_load(path, seq, &err);
    if (r == ENG_OK)
        r = seq_load_scene(seq, &scene, &err);
    if (r == ENG_OK && seq->settings.indirect == ENG_INDIRECT_NONE)
        r = eng_fail(&err, ENG_ERR_INVALID, "%s: \"indirect\": \"none\" traces no photons", path);
    if (r == ENG_OK && frame >= seq->frame_count)
        r = eng_fail(&err, ENG_ERR_INVALID, "%s: frame %lld outside 0..%d", path, frame, seq->frame_count - 1);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm tracebench: %s\n", err.msg);
        rc = TB_EXIT_INPUT;
        goto done;
    }
    if (threads)
        seq->settings.threads = (int)threads;
    if (photons)
        seq->settings.photon_count = (int)photons;
    seq->settings.photon_trace = ENG_TRACE_EMBREE;
    seq->capture_count = 0; /* nothing is captured: no listener */
    eng_desc d = {.scene = scene, .sequence = seq};
    tb_result res;
    r = eng_create(&d, &eng, &err);
    if (r == ENG_OK)
        r = tb_run(eng, (int)frame, (int)repeats, &res, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm tracebench: %s\n", err.msg);
        rc = r == ENG_ERR_PARSE || r == ENG_ERR_INVALID || r == ENG_ERR_UNSUPPORTED ? TB_EXIT_INPUT : TB_EXIT_RUNTIME;
        goto done;
    }
    double tm = median(res.trace_ms, res.repeats), rm = median(res.raw_ms, res.repeats);
    double pm = median(res.packet_ms, res.repeats);
    double trace_rate = tm > 0.0 ? (double)res.rays / (tm * 1e-3) : 0.0;
    double raw_rate = rm > 0.0 ? (double)res.rays / (rm * 1e-3) : 0.0;
    printf("tracebench: %s frame %lld, %zu bounce-map photons, %zu rays (%llu hit), %zu photons stored, %d threads, "
           "%d repeats alternating\n",
           path, frame, res.photons, res.rays, (unsigned long long)res.hits, res.stored, res.threads, res.repeats);
    printf("  photon trace       %8.3f Mrays/s  (median %.2f ms; %d paths in flight a thread, rtcIntersect4 packets)\n",
           trace_rate * 1e-6, tm, res.lanes);
    printf("  raw rtcIntersect1  %8.3f Mrays/s  (median %.2f ms)\n", raw_rate * 1e-6, rm);
    printf("  raw rtcIntersect4  %8.3f Mrays/s  (median %.2f ms; packets of 4 consecutive rays, hits %s rtcIntersect1's)\n",
           pm > 0.0 ? (double)res.rays / (pm * 1e-3) * 1e-6 : 0.0, pm, res.packets_identical ? "bit-identical to" : "DIFFERENT from");
    printf("  ratio %.1f %% of raw   (goal >= 70 %%: %s)\n", raw_rate > 0.0 ? 100.0 * trace_rate / raw_rate : 0.0,
           trace_rate >= 0.7 * raw_rate ? "goal met" : "SHORT of the goal");
    printf("  photon maps bit-identical to the ray-by-ray trace: %s\n", res.maps_identical ? "yes" : "NO");
    if (!res.maps_identical) {
        fprintf(stderr, "ispm tracebench: %s: the photon trace's map differs from the ray-by-ray trace's\n", path);
        rc = TB_EXIT_RUNTIME;
    }
done:
    eng_destroy(eng);
    scn_destroy(scene);
    free(seq);
    return rc;
}
