/* tool_fault.c — an LD_PRELOAD library for tests/e2e_faults.sh: fault injection in the style of
 * SQLite's test VFS. Every call that changes a regular file or a folder (open with O_CREAT,
 * write, pwrite, writev, fwrite, ftruncate, fsync, fdatasync, rename, link, mkdir) is counted,
 * in the order the process makes them; with ISPM_FAULT_AT=N the N-th fails (ENOSPC for data,
 * EIO for syncs and renames) and every later one succeeds again, as a disk that filled for a
 * moment. Writes to anything but a regular file (the terminal, pipes: the tool's own messages)
 * are not counted. At exit, ISPM_FAULT_LOG (if set) gets "<calls> <1 if the N-th was failed>".
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <unistd.h>

static atomic_long calls;
static atomic_int hit;

static long fault_at(void)
{
    static long at = -1;
    if (at < 0) {
        const char *s = getenv("ISPM_FAULT_AT");
        at = s ? atol(s) : 0;
    }
    return at;
}

/* Counts one call; 1 when it is the one to fail. */
static int fail_now(void)
{
    long n = atomic_fetch_add(&calls, 1) + 1;
    if (n == fault_at()) {
        atomic_store(&hit, 1);
        return 1;
    }
    return 0;
}

static int regular(int fd)
{
    struct stat st;
    return fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
}

#define REAL(name) ((__typeof__(&name))dlsym(RTLD_NEXT, #name))

ssize_t write(int fd, const void *buf, size_t n)
{
    if (regular(fd) && fail_now()) {
        errno = ENOSPC;
        return -1;
    }
    return REAL(write)(fd, buf, n);
}

ssize_t pwrite(int fd, const void *buf, size_t n, off_t off)
{
    if (regular(fd) && fail_now()) {
        errno = ENOSPC;
        return -1;
    }
    return REAL(pwrite)(fd, buf, n, off);
}

ssize_t pwrite64(int fd, const void *buf, size_t n, off64_t off)
{
    if (regular(fd) && fail_now()) {
        errno = ENOSPC;
        return -1;
    }
    return REAL(pwrite64)(fd, buf, n, off);
}

ssize_t writev(int fd, const struct iovec *iov, int cnt)
{
    if (regular(fd) && fail_now()) {
        errno = ENOSPC;
        return -1;
    }
    return REAL(writev)(fd, iov, cnt);
}

size_t fwrite(const void *p, size_t size, size_t n, FILE *f)
{
    if (regular(fileno(f)) && fail_now()) {
        errno = ENOSPC;
        return 0;
    }
    return REAL(fwrite)(p, size, n, f);
}

int ftruncate(int fd, off_t len)
{
    if (fail_now()) {
        errno = EIO;
        return -1;
    }
    return REAL(ftruncate)(fd, len);
}

int fsync(int fd)
{
    if (fail_now()) {
        errno = EIO;
        return -1;
    }
    return REAL(fsync)(fd);
}

int fdatasync(int fd)
{
    if (fail_now()) {
        errno = EIO;
        return -1;
    }
    return REAL(fdatasync)(fd);
}

int rename(const char *a, const char *b)
{
    if (fail_now()) {
        errno = EIO;
        return -1;
    }
    return REAL(rename)(a, b);
}

int link(const char *a, const char *b)
{
    if (fail_now()) {
        errno = ENOSPC;
        return -1;
    }
    return REAL(link)(a, b);
}

int mkdir(const char *p, mode_t m)
{
    if (fail_now()) {
        errno = ENOSPC;
        return -1;
    }
    return REAL(mkdir)(p, m);
}

static int open_common(const char *p, int flags, mode_t m, int (*real)(const char *, int, ...))
{
    if ((flags & O_CREAT) && fail_now()) {
        errno = ENOSPC;
        return -1;
    }
    return real(p, flags, m);
}

int open(const char *p, int flags, ...)
{
    mode_t m = 0;
    if (flags & O_CREAT) {
        va_list ap;
        va_start(ap, flags);
        m = (mode_t)va_arg(ap, int);
        va_end(ap);
    }
    return open_common(p, flags, m, REAL(open));
}

int open64(const char *p, int flags, ...)
{
    mode_t m = 0;
    if (flags & O_CREAT) {
        va_list ap;
        va_start(ap, flags);
        m = (mode_t)va_arg(ap, int);
        va_end(ap);
    }
    return open_common(p, flags, m, REAL(open64));
}

__attribute__((destructor)) static void report(void)
{
    const char *log = getenv("ISPM_FAULT_LOG");
    if (!log)
        return;
    int fd = REAL(open)(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0)
        return;
    char line[64];
    int len = snprintf(line, sizeof line, "%ld %d\n", (long)atomic_load(&calls), atomic_load(&hit));
    if (len > 0)
        (void)!REAL(write)(fd, line, (size_t)len);
    close(fd);
}
