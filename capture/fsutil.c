/* fsutil.c — capture's small shared helpers: allocation that ends the process on exhaustion
 * (the engine's core does the same; a harness that cannot allocate a frame copy has nothing
 * useful left to do), path joining, and folder fsync, the step that makes a rename or an
 * unlink durable on POSIX file systems. */
#define _POSIX_C_SOURCE 200809L

#include "cap_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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
