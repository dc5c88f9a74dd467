/* cmd_merge.c — `ispm merge SHARD... -o RUN`: frame shards recorded with `ispm record --frames`
 * (on one machine or many, e.g. a Slurm job array: scripts/slurm/) checked against each other
 * and written as one run, bit-identical to a one-machine recording (capture/merge.h). */
#define _POSIX_C_SOURCE 200809L
#include "merge.h"

#include <getopt.h>
#include <stdio.h>
#include <string.h>

static void merge_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm merge SHARD... -o RUN [--force]\n"
            "\n"
            "Merges frame shards (ispm record SEQUENCE -o SHARD --frames A-B [--warmup W] [--overlap O])\n"
            "into one run. Refuses, with one line, unless every shard is complete and all come from the\n"
            "same sequence, scene, settings, GL and binary; their frames cover the sequence without a\n"
            "gap; and every buffer of each shard's overlap frames (the last warm-up frames, written)\n"
            "has the digest of the shard that owns the frame: the warm-up rebuilt the temporal state\n"
            "bit for bit (else the line names the frame, the buffer and the warm-up the state needs).\n"
            "The run is written like a recording (manifest.json last): a merge that fails or is killed\n"
            "leaves no complete-looking run.\n"
            "\n"
            "  -o, --output RUN   the merged run's folder\n"
            "  -f, --force        replace a run already in RUN\n"
            "  -h, --help         this text\n"
            "\n"
            "exit: 0 merged; 1 writing failed or a shard is unreadable (no manifest is written);\n"
            "      2 bad arguments, or shards that cannot be merged\n");
}

int cmd_merge(int argc, char **argv, const char *command_line)
{
    static const struct option opts[] = {{"output", required_argument, NULL, 'o'}, {"force", no_argument, NULL, 'f'},
                                         {"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0}};
    cap_merge_desc d;
    memset(&d, 0, sizeof d);
    int c;
    while ((c = getopt_long(argc, argv, "o:fh", opts, NULL)) != -1) {
        switch (c) {
        case 'o': d.run_dir = optarg; break;
        case 'f': d.overwrite = 1; break;
        case 'h': merge_usage(stdout); return 0;
        default: merge_usage(stderr); return 2;
        }
    }
    if (optind >= argc || !d.run_dir) {
        merge_usage(stderr);
        return 2;
    }
    d.shards = (const char *const *)(argv + optind);
    d.shard_count = argc - optind;
    d.command_line = command_line;
    eng_error err = {{0}};
    eng_result r = cap_merge(&d, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm merge: %s\n", err.msg);
        if (r != ENG_ERR_INVALID)
            fprintf(stderr, "ispm merge: run %s is incomplete (no manifest written)\n", d.run_dir);
        return r == ENG_ERR_INVALID ? 2 : 1;
    }
    printf("run: %s (%d shards merged)\n", d.run_dir, d.shard_count);
    return 0;
}
