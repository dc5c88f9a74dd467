/* fsutil.c — capture's small shared helpers: allocation that ends the process on exhaustion
 * (the engine's core does the same; a harness that cannot allocate a frame copy has nothing
 * useful left to do), path joining, folder fsync (the step that makes a rename or an unlink
 * durable on POSIX file systems), rm -rf, and the swap of a run built beside another. */
#define _XOPEN_SOURCE 700

#include "cap_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void cap_oom(void)
{
    fprintf(stderr, "ispm: out of memory\n");
    abort();
}

void *cap__xmalloc(size_t n)
{
    void *p = malloc(n ? n : 1);
    if (!p)
        cap_oom();
    return p;
}

void *cap__xcalloc(size_t n, size_t size)
{
    void *p = calloc(n ? n : 1, size ? size : 1);
    if (!p)
        cap_oom();
    return p;
}

char *cap__xstrdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = cap__xmalloc(n);
    memcpy(p, s, n);
    return p;
}

char *cap__join(const char *a, const char *b)
{
    size_t na = strlen(a), nb = strlen(b);
    int slash = na > 0 && a[na - 1] != '/';
    char *p = cap__xmalloc(na + (size_t)slash + nb + 1);
    memcpy(p, a, na);
    if (slash)
        p[na] = '/';
    memcpy(p + na + (size_t)slash, b, nb + 1);
    return p;
}

eng_result cap__fsync_dir(const char *dir, eng_error *err)
{
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot open folder: %s", dir, strerror(errno));
    if (fsync(fd) != 0 && errno != EINVAL) {
        int e = errno;
        close(fd);
        return eng_fail(err, ENG_ERR_IO, "%s: cannot sync folder: %s", dir, strerror(e));
    }
    close(fd);
    return ENG_OK;
}

static int remove_one(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)ftw;
    int rc = flag == FTW_DP ? rmdir(path) : unlink(path);
    return rc != 0 && errno != ENOENT ? -1 : 0;
}

eng_result cap__remove_tree(const char *path, eng_error *err)
{
    struct stat st;
    if (lstat(path, &st) != 0)
        return errno == ENOENT ? ENG_OK : eng_fail(err, ENG_ERR_IO, "%s: %s", path, strerror(errno));
    if (nftw(path, remove_one, 32, FTW_DEPTH | FTW_PHYS) != 0)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot remove: %s", path, strerror(errno));
    return ENG_OK;
}

eng_result cap__swap_run(const char *tmp, const char *run_dir, eng_error *err)
{
    char *old = cap__xmalloc(strlen(run_dir) + 16);
    sprintf(old, "%s.replaced", run_dir);
    char *parent = cap__xstrdup(run_dir);
    char *slash = strrchr(parent, '/');
    if (slash)
        slash[slash == parent ? 1 : 0] = 0;
    eng_result r = cap__remove_tree(old, err);
    if (r == ENG_OK && rename(run_dir, old) != 0)
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot move the old run aside: %s", run_dir, strerror(errno));
    else if (r == ENG_OK && rename(tmp, run_dir) != 0) {
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot rename %s into place: %s", run_dir, tmp, strerror(errno));
        if (rename(old, run_dir) != 0)
            fprintf(stderr, "ispm: %s: the old run is left at %s\n", run_dir, old);
    } else if (r == ENG_OK && (r = cap__fsync_dir(slash ? parent : ".", err)) != ENG_OK) {
        /* not durable: undone, the old run back in place */
        if (rename(run_dir, tmp) != 0 || rename(old, run_dir) != 0)
            fprintf(stderr, "ispm: %s: the swap could not be undone (the old run is at %s)\n", run_dir, old);
    }
    if (r == ENG_OK)
        cap__remove_tree(old, NULL); /* the new run is in place; what is left of the old one is no run */
    free(parent);
    free(old);
    return r;
}

eng_result cap__recover_run(const char *run_dir, eng_error *err)
{
    char *old = cap__xmalloc(strlen(run_dir) + 16);
    sprintf(old, "%s.replaced", run_dir);
    struct stat st;
    eng_result r = ENG_OK;
    if (lstat(old, &st) == 0 && S_ISDIR(st.st_mode)) {
        if (lstat(run_dir, &st) != 0) {
            if (rename(old, run_dir) != 0)
                r = eng_fail(err, ENG_ERR_IO, "%s: cannot restore the run from %s: %s", run_dir, old, strerror(errno));
            else
                fprintf(stderr, "ispm: %s: an interrupted replacement was rolled back (%s restored)\n", run_dir, old);
        } else {
            r = cap__remove_tree(old, err);
        }
    }
    free(old);
    return r;
}
