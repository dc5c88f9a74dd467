/* cmd_tolerances.c — `ispm tolerances suggest RUN... --golden DIR -o FILE [--margin M]
 * [--tolerances FILE]`: a tolerance file from runs that should pass (replay/rep_regress.h). */
#define _POSIX_C_SOURCE 200809L
#include "rep_regress.h"

#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void tolerances_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm tolerances suggest RUN... --golden DIR -o FILE [--margin M] [--tolerances FILE]\n"
            "\n"
            "Replays every RUN against the golden in DIR (writing nothing beside the runs) and writes\n"
            "FILE: the tightest tolerances under which every run passes, times the margin. RUNs are\n"
            "runs that should pass: other seeds, another renderer, a change that was judged acceptable.\n"
            "Per buffer: hardfail, failpercent, warnpercent, rmse_fail, block_fail, block_failrelative,\n"
            "flip_mean_fail, flip_p99_fail = the largest value measured over runs and frames x M,\n"
            "rounded up to 3 digits, each named in the rule's note with the run and frame that set it;\n"
            "fail, failrelative, warn and warnrelative (what a failing pixel is) are kept from the\n"
            "tolerances compared under; a buffer bit-exact in every run gets \"exact\": true. Runs\n"
            "from another GL renderer than the golden's fill the \"cross_renderer\" section.\n"
            "\n"
            "  -g, --golden DIR        the golden the runs are compared with\n"
            "  -o, --output FILE       the tolerance file to write\n"
            "  -m, --margin M          factor over the measured values, >= 1 (default 1.25)\n"
            "  -t, --tolerances FILE   compare under FILE (default DIR/tolerances.json)\n"
            "  -h, --help              this text\n"
            "\n"
            "exit: 0 written; 1 a run fails in a way no tolerance passes (a missing, extra or\n"
            "      resized buffer, a NaN/Inf change); 2 bad arguments; 4 a run, the golden or a file\n"
            "      unreadable, or FILE unwritable\n");
}

int cmd_tolerances(int argc, char **argv)
{
    static const struct option opts[] = {{"golden", required_argument, NULL, 'g'},
                                         {"output", required_argument, NULL, 'o'},
                                         {"margin", required_argument, NULL, 'm'},
                                         {"tolerances", required_argument, NULL, 't'},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    if (argc >= 2 && (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help"))) {
        tolerances_usage(stdout);
        return 0;
    }
    if (argc < 2 || strcmp(argv[1], "suggest") != 0) {
        fprintf(stderr, "ispm tolerances: unknown subcommand '%s' (suggest)\n", argc >= 2 ? argv[1] : "");
        tolerances_usage(stderr);
        return 2;
    }
    argc--;
    argv++;
    optind = 1;
    rep_suggest_options o;
    memset(&o, 0, sizeof o);
    o.margin = 1.25;
    int c;
    while ((c = getopt_long(argc, argv, "g:o:m:t:h", opts, NULL)) != -1) {
        switch (c) {
        case 'g': o.golden_dir = optarg; break;
        case 'o': o.out_path = optarg; break;
        case 't': o.tolerances = optarg; break;
        case 'm': {
            char *end;
            o.margin = strtod(optarg, &end);
            if (*end || !isfinite(o.margin) || !(o.margin >= 1) || o.margin > 1e6) {
                fprintf(stderr, "ispm tolerances suggest: --margin: '%s' is not a number >= 1\n", optarg);
                return 2;
            }
            break;
        }
        case 'h': tolerances_usage(stdout); return 0;
        default: tolerances_usage(stderr); return 2;
        }
    }
    if (optind >= argc || !o.golden_dir || !o.out_path) {
        tolerances_usage(stderr);
        return 2;
    }
    o.runs = (const char *const *)(argv + optind);
    o.run_count = argc - optind;
    eng_error err = {{0}};
    eng_result r = rep_tol_suggest(&o, stdout, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm tolerances suggest: %s\n", err.msg);
        return r == ENG_ERR_UNSUPPORTED ? 1 : 4;
    }
    return 0;
}
