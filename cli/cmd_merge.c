/* cmd_merge.c — `ispm merge SHARD... -o RUN`: frame shards recorded with `ispm record --frames`
 * (on one machine or many, e.g. a Slurm job array: scripts/slurm/) checked against each other
 * and written as one run, bit-identical to a one-machine recording (capture/merge.h). Every
 * shard's frames are first checked against their manifest's digests. */
#define _POSIX_C_SOURCE 200809L
#include "merge.h"
#include "rep_run.h"
#include "rep_util.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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
            "leaves no complete-looking run; with --force onto a complete run, the new one is built\n"
            "beside it (RUN.merging) and swapped in, so a failure leaves the old run as it was.\n"
            "\n"
            "  -o, --output RUN   the merged run's folder\n"
            "  -f, --force        replace a run already in RUN\n"
            "  -h, --help         this text\n"
            "\n"
            "exit: 0 merged; 1 writing failed or a shard is unreadable (no manifest is written);\n"
            "      2 bad arguments, or shards that cannot be merged\n");
}

/* Every frame of a shard decodes to its manifest's digests (rep_run_read_frame), as replay
 * would find later: a tampered or corrupt shard is refused before anything is written. A shard
 * without a manifest is left to cap_merge, which names what it lacks. */
static eng_result verify_shard(const char *dir, eng_error *err)
{
    char *m = rep_path_join(dir, "manifest.json");
    int has = access(m, F_OK) == 0;
    free(m);
    if (!has)
        return ENG_OK;
    rep_run *run = NULL;
    eng_result r = rep_run_open(dir, &run, err);
    for (int i = 0; r == ENG_OK && i < run->frame_count; i++) {
        rep_part *parts = NULL;
        r = rep_run_read_frame(run, i, &parts, err);
        if (r == ENG_OK)
            rep_parts_free(parts, run->frames[i].buffer_count);
    }
    rep_run_close(run);
    return r == ENG_OK || r == ENG_ERR_NOMEM ? r : ENG_ERR_INVALID;
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
    eng_result r = ENG_OK;
    for (int i = 0; i < d.shard_count && r == ENG_OK; i++)
        r = verify_shard(d.shards[i], &err);
    if (r == ENG_OK)
        r = cap_merge(&d, &err);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm merge: %s\n", err.msg);
        return r == ENG_ERR_INVALID ? 2 : 1;
    }
    printf("run: %s (%d shards merged)\n", d.run_dir, d.shard_count);
    return 0;
}
