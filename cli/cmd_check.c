/* cmd_check.c — `ispm check SEQUENCE [--golden DIR]`: record into a temporary run and replay it
 * against the golden in one command, with the exit codes `git bisect run` wants: 0 good, 1 bad,
 * 125 cannot judge (the sequence or golden cannot be read, no temporary folder).
 *
 * The recording is a child process (this same executable, `record ... --quiet`), so that a
 * commit whose renderer crashes is judged bad instead of ending the bisection. */
#define _POSIX_C_SOURCE 200809L
#include "eng.h"
#include "rep.h"
#include "rep_util.h"

#include <errno.h>
#include <getopt.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

enum { CHECK_GOOD = 0, CHECK_BAD = 1, CHECK_SKIP = 125 };

static void check_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm check SEQUENCE [--golden DIR] [--provenance-fail] [--keep] [--quiet]\n"
            "\n"
            "Records SEQUENCE into a temporary run and replays it against the golden (default\n"
            "golden/<sequence name>), for `git bisect run` and scripts/bisect.sh. Warnings (a different\n"
            "setting, pixels over -warn only) count as good unless --provenance-fail.\n"
            "\n"
            "  -g, --golden DIR      the golden to compare with\n"
            "  -p, --provenance-fail a different sequence, scene or setting is bad\n"
            "  -k, --keep            keep the temporary run (its path is printed)\n"
            "  -q, --quiet           print only the verdict\n"
            "  -h, --help            this text\n"
            "\n"
            "exit: 0 good (ok or warnings); 1 bad (failures, size mismatch, the renderer failed or\n"
            "      crashed); 125 cannot judge (unreadable sequence or golden, bad arguments, no\n"
            "      temporary folder)\n");
}

/* Runs `self record SEQUENCE -o RUN --quiet`; returns the child's exit status, or 128 + signal. */
static int record_child(const char *seq, const char *run)
{
    char self[4096];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0)
        return -1;
    self[n] = 0;
    char *argv[] = {self, "record", (char *)seq, "-o", (char *)run, "--quiet", NULL};
    pid_t pid;
    if (posix_spawn(&pid, self, NULL, NULL, argv, environ) != 0)
        return -1;
    int st;
    while (waitpid(pid, &st, 0) < 0)
        if (errno != EINTR)
            return -1;
    return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + (WIFSIGNALED(st) ? WTERMSIG(st) : 0);
}

int cmd_check(int argc, char **argv)
{
    static const struct option opts[] = {
        {"golden", required_argument, NULL, 'g'}, {"provenance-fail", no_argument, NULL, 'p'},
        {"keep", no_argument, NULL, 'k'}, {"quiet", no_argument, NULL, 'q'},
        {"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0},
    };
    const char *golden = NULL;
    int keep = 0, quiet = 0, prov_fail = 0, c;
    while ((c = getopt_long(argc, argv, "g:pkqh", opts, NULL)) != -1) {
        switch (c) {
        case 'g': golden = optarg; break;
        case 'p': prov_fail = 1; break;
        case 'k': keep = 1; break;
        case 'q': quiet = 1; break;
        case 'h': check_usage(stdout); return CHECK_GOOD;
        default: check_usage(stderr); return CHECK_SKIP;
        }
    }
    if (optind + 1 != argc) {
        check_usage(stderr);
        return CHECK_SKIP;
    }
    const char *seq_path = argv[optind];
    char golden_buf[4096];
    if (!golden) {
        seq_sequence *seq = calloc(1, sizeof *seq);
        eng_error err = {{0}};
        if (!seq || seq_load(seq_path, seq, &err) != ENG_OK) {
            fprintf(stderr, "ispm check: %s\n", seq ? err.msg : "out of memory");
            free(seq);
            return CHECK_SKIP;
        }
        snprintf(golden_buf, sizeof golden_buf, "golden/%s", seq->name);
        golden = golden_buf;
        free(seq);
    }
    char gm[4200];
    snprintf(gm, sizeof gm, "%s/manifest.json", golden);
    struct stat st;
    if (stat(gm, &st) != 0) {
        fprintf(stderr, "ispm check: %s: no golden there (no manifest.json): cannot judge\n", golden);
        return CHECK_SKIP;
    }
    const char *tmpdir = getenv("TMPDIR");
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s/ispm-check-XXXXXX", tmpdir && *tmpdir ? tmpdir : "/tmp");
    if (!mkdtemp(tmp)) {
        fprintf(stderr, "ispm check: %s: cannot create: %s\n", tmp, strerror(errno));
        return CHECK_SKIP;
    }
    char run[4200];
    snprintf(run, sizeof run, "%s/run", tmp);
    int rc = record_child(seq_path, run);
    int verdict;
    if (rc == 2 || rc < 0) {
        fprintf(stderr, "ispm check: recording %s could not start (exit %d): cannot judge\n", seq_path, rc);
        verdict = CHECK_SKIP;
    } else if (rc != 0) {
        fprintf(stderr, "ispm check: recording %s failed (exit %d): bad\n", seq_path, rc);
        verdict = CHECK_BAD;
    } else {
        rep_options o;
        memset(&o, 0, sizeof o);
        o.run_dir = run;
        o.golden_dir = golden;
        o.quiet = quiet;
        o.provenance_fail = prov_fail;
        eng_error err = {{0}};
        rep_exit x = rep_replay(&o, stdout, &err);
        if (x == REP_UNREADABLE || x == REP_UNWRITABLE)
            fprintf(stderr, "ispm check: %s\n", err.msg);
        verdict = x == REP_OK || x == REP_WARN ? CHECK_GOOD
                  : x == REP_UNREADABLE || x == REP_UNWRITABLE ? CHECK_SKIP : CHECK_BAD;
    }
    printf("check: %s — %s against %s\n", verdict == CHECK_GOOD ? "GOOD" : verdict == CHECK_BAD ? "BAD" : "CANNOT JUDGE",
           seq_path, golden);
    if (keep) {
        printf("run: %s\n", run);
    } else {
        eng_error ignored;
        rep_remove_tree(tmp, &ignored);
    }
    return verdict;
}
