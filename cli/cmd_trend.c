/* cmd_trend.c — `ispm trend RUN... -o DIR [--by-commit [--repo GITDIR]]`: the metrics of
 * replayed runs as series over the runs (replay/report/rep_trend.h). Ordering by commit asks git
 * (`git -C GITDIR rev-list --count COMMIT`: how many commits a run's tool.git has behind it, so
 * runs of later commits come later on one branch); everything else is the report room's. */
#define _POSIX_C_SOURCE 200809L
#include "rep_trend.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

static void trend_usage(FILE *f)
{
    fprintf(f,
            "usage: ispm trend RUN... -o DIR [--by-commit [--repo GITDIR]]\n"
            "\n"
            "Reads runs that have been replayed (RUN/replay/report.json and RUN/manifest.json), in\n"
            "the order given, and writes DIR/trend.json (per run: verdict, frame time, per-pass time\n"
            "and share; per buffer: max |delta|, RMSE, FLIP mean and p99, flicker; every series with\n"
            "the step where it moved most) and DIR/trend.html (PLplot charts, that step ringed).\n"
            "\n"
            "  -o, --output DIR   where trend.json, trend.html and img/ go\n"
            "      --by-commit    order the runs by their tool.git in the repository (the number of\n"
            "                     commits behind it; ties keep the order given)\n"
            "      --repo GITDIR  the repository for --by-commit (default: the current folder)\n"
            "  -h, --help         this text\n"
            "\n"
            "exit: 0 written; 2 bad arguments or a commit the repository does not have;\n"
            "      4 a run, report or manifest unreadable, or the output unwritable\n");
}

/* How many commits `sha` has behind it in repo (git rev-list --count), or -1. */
static long commit_depth(const char *repo, const char *sha)
{
    if (!sha || !sha[0] || strspn(sha, "0123456789abcdef") != strlen(sha))
        return -1; /* also keeps a hostile value from reading as an option */
    int fd[2];
    if (pipe(fd) != 0)
        return -1;
    pid_t pid = fork();
    if (pid < 0) {
        close(fd[0]);
        close(fd[1]);
        return -1;
    }
    if (pid == 0) {
        dup2(fd[1], STDOUT_FILENO);
        close(fd[0]);
        close(fd[1]);
        FILE *null = freopen("/dev/null", "w", stderr);
        (void)null;
        char spec[128];
        snprintf(spec, sizeof spec, "%s^{commit}", sha);
        execlp("git", "git", "-C", repo, "rev-list", "--count", spec, (char *)NULL);
        _exit(127);
    }
    close(fd[1]);
    char buf[64] = {0};
    size_t got = 0;
    ssize_t k;
    while (got < sizeof buf - 1 && (k = read(fd[0], buf + got, sizeof buf - 1 - got)) > 0)
        got += (size_t)k;
    close(fd[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    char *end;
    long n = strtol(buf, &end, 10);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || end == buf)
        return -1;
    return n;
}

typedef struct ordered {
    const char *run;
    long depth;
    int given;
} ordered;

static int by_depth(const void *pa, const void *pb)
{
    const ordered *a = pa, *b = pb;
    if (a->depth != b->depth)
        return a->depth < b->depth ? -1 : 1;
    return a->given - b->given;
}

int cmd_trend(int argc, char **argv)
{
    enum { OPT_BY_COMMIT = 1000, OPT_REPO };
    static const struct option opts[] = {{"output", required_argument, NULL, 'o'},
                                         {"by-commit", no_argument, NULL, OPT_BY_COMMIT},
                                         {"repo", required_argument, NULL, OPT_REPO},
                                         {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    const char *out = NULL, *repo = NULL;
    int by_commit = 0, c;
    while ((c = getopt_long(argc, argv, "o:h", opts, NULL)) != -1) {
        switch (c) {
        case 'o': out = optarg; break;
        case OPT_BY_COMMIT: by_commit = 1; break;
        case OPT_REPO: repo = optarg; break;
        case 'h': trend_usage(stdout); return 0;
        default: trend_usage(stderr); return 2;
        }
    }
    if (optind >= argc || !out || (repo && !by_commit)) {
        trend_usage(stderr);
        return 2;
    }
    int n = argc - optind;
    ordered *o = calloc((size_t)n, sizeof *o);
    const char **runs = calloc((size_t)n, sizeof *runs);
    if (!o || !runs) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    int rc = 0;
    for (int i = 0; i < n; i++) {
        o[i] = (ordered){argv[optind + i], 0, i};
        if (!by_commit)
            continue;
        char *git = rep_trend_run_git(o[i].run);
        o[i].depth = commit_depth(repo ? repo : ".", git);
        if (o[i].depth < 0 && !rc) {
            fprintf(stderr, "ispm trend: %s/manifest.json: tool.git %s is not a commit of %s\n", o[i].run,
                    git ? git : "(none)", repo ? repo : ".");
            rc = 2;
        }
        free(git);
    }
    if (!rc) {
        qsort(o, (size_t)n, sizeof *o, by_depth);
        for (int i = 0; i < n; i++)
            runs[i] = o[i].run;
        eng_error err = {{0}};
        if (rep_trend_write(runs, NULL, n, out, stdout, &err) != ENG_OK) {
            fprintf(stderr, "ispm trend: %s\n", err.msg);
            rc = 4;
        }
    }
    free(runs);
    free(o);
    return rc;
}
