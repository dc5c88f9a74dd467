/* util.c — the replay module's plumbing: allocation that ends the process when memory runs out
 * (the one out-of-memory hook, as in ispm_core), path joining, a growing string, and the file
 * operations bless and the report writer need to be atomic: mkdir -p, write-then-rename, copy
 * with fsync, and rm -rf that never follows a symbolic link out of the tree it removes.
 */
#define _XOPEN_SOURCE 700

#include "rep_util.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <fcntl.h>
#include <ftw.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static void oom(void)
{
    fprintf(stderr, "ispm: out of memory\n");
    abort();
}

void *rep_xmalloc(size_t n)
{
    void *p = malloc(n ? n : 1);
    if (!p)
        oom();
    return p;
}

void *rep_xcalloc(size_t n, size_t size)
{
    void *p = calloc(n ? n : 1, size ? size : 1);
    if (!p)
        oom();
    return p;
}

void *rep_xrealloc(void *p, size_t n)
{
    void *q = realloc(p, n ? n : 1);
    if (!q)
        oom();
    return q;
}

char *rep_xstrdup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = rep_xmalloc(n);
    memcpy(p, s, n);
    return p;
}

static char *vxprintf(const char *fmt, va_list ap)
{
    va_list aq;
    va_copy(aq, ap);
    int n = vsnprintf(NULL, 0, fmt, aq);
    va_end(aq);
    if (n < 0)
        n = 0;
    char *p = rep_xmalloc((size_t)n + 1);
    vsnprintf(p, (size_t)n + 1, fmt, ap);
    return p;
}

char *rep_xprintf(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *p = vxprintf(fmt, ap);
    va_end(ap);
    return p;
}

static int cmp_float(const void *pa, const void *pb)
{
    float a = *(const float *)pa, b = *(const float *)pb;
    return a < b ? -1 : a > b;
}

/* An LSD radix sort on the bit patterns when every value is finite and non-negative (+0 up,
 * no -0: then the bits' order is the values' order and equal values have equal bits, so the
 * array is the one qsort leaves, in O(n)); returns 0 with v untouched otherwise. */
static int radix_sort_nonneg(float *v, size_t n)
{
    uint32_t *keys = rep_xcalloc(2 * n, sizeof *keys), *src = keys, *dst = keys + n;
    memcpy(keys, v, n * sizeof *keys);
    for (size_t i = 0; i < n; i++)
        if (keys[i] >= 0x7f800000u) { /* sign bit, Inf or NaN */
            free(keys);
            return 0;
        }
    for (int shift = 0; shift < 32; shift += 8) {
        size_t count[257] = {0};
        for (size_t i = 0; i < n; i++)
            count[((src[i] >> shift) & 0xffu) + 1]++;
        if (count[1 + ((src[0] >> shift) & 0xffu)] == n)
            continue; /* every key has this byte: the pass would not move anything */
        for (int b = 0; b < 256; b++)
            count[b + 1] += count[b];
        for (size_t i = 0; i < n; i++)
            dst[count[(src[i] >> shift) & 0xffu]++] = src[i];
        uint32_t *t = src;
        src = dst;
        dst = t;
    }
    memcpy(v, src, n * sizeof *src);
    free(keys);
    return 1;
}

static int cmp_double(const void *pa, const void *pb)
{
    double a = *(const double *)pa, b = *(const double *)pb;
    return a < b ? -1 : a > b;
}

double rep_median(double *v, int n)
{
    if (n <= 0)
        return NAN;
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

void rep_sort_floats(float *v, size_t n)
{
    if (n > 1 && !radix_sort_nonneg(v, n))
        qsort(v, n, sizeof *v, cmp_float);
}

char *rep_path_join(const char *dir, const char *name)
{
    size_t n = strlen(dir);
    if (n > 0 && dir[n - 1] == '/')
        return rep_xprintf("%s%s", dir, name);
    return rep_xprintf("%s/%s", dir, name);
}

void rep_sb_printf(rep_sb *sb, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *p = vxprintf(fmt, ap);
    va_end(ap);
    size_t n = strlen(p);
    if (sb->len + n + 1 > sb->cap) {
        size_t cap = sb->cap ? sb->cap : 256;
        while (cap < sb->len + n + 1)
            cap *= 2;
        sb->s = rep_xrealloc(sb->s, cap);
        sb->cap = cap;
    }
    memcpy(sb->s + sb->len, p, n + 1);
    sb->len += n;
    free(p);
}

eng_result rep_json_load(const char *path, unsigned flags, cJSON **root, eng_error *err)
{
    char *text = NULL;
    size_t len = 0;
    *root = NULL;
    eng_result r = eng_read_input(path, flags, REP_MAX_JSON_BYTES, &text, &len, err);
    if (r == ENG_OK)
        r = eng_json_precheck(path, text, len, ENG_JSON_MAX_DEPTH, err);
    if (r == ENG_OK) {
        const char *end = NULL;
        *root = cJSON_ParseWithLengthOpts(text, len, &end, 0);
        if (!*root) {
            size_t at = end && end >= text ? (size_t)(end - text) : 0;
            r = eng_fail(err, ENG_ERR_PARSE, "%s: byte %zu: not valid JSON", path, at);
        }
    }
    free(text);
    return r;
}

int rep_is_file(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

int rep_is_dir(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

eng_result rep_mkdirs(const char *path, eng_error *err)
{
    if (!path[0])
        return eng_fail(err, ENG_ERR_IO, "cannot create a folder with an empty name");
    char *p = rep_xstrdup(path);
    for (char *s = p + 1; ; s++) {
        int end = *s == 0;
        if (*s == '/' || end) {
            *s = 0;
            if (p[0] && mkdir(p, 0777) != 0 && errno != EEXIST) {
                eng_result r = eng_fail(err, ENG_ERR_IO, "%s: cannot create folder: %s", p, strerror(errno));
                free(p);
                return r;
            }
            if (end)
                break;
            *s = '/';
        }
    }
    eng_result r = ENG_OK;
    if (!rep_is_dir(path))
        r = eng_fail(err, ENG_ERR_IO, "%s: not a folder", path);
    free(p);
    return r;
}

/* Writes len bytes to an already open descriptor and syncs it; closes fd in every case. */
static eng_result write_all(int fd, const char *path, const char *data, size_t len, eng_error *err)
{
    size_t done = 0;
    while (done < len) {
        ssize_t w = write(fd, data + done, len - done);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            int e = errno;
            close(fd);
            return eng_fail(err, ENG_ERR_IO, "%s: cannot write: %s", path, strerror(e));
        }
        done += (size_t)w;
    }
    if (fsync(fd) != 0) {
        int e = errno;
        close(fd);
        return eng_fail(err, ENG_ERR_IO, "%s: cannot sync: %s", path, strerror(e));
    }
    if (close(fd) != 0)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot close: %s", path, strerror(errno));
    return ENG_OK;
}

eng_result rep_write_atomic(const char *path, const char *data, size_t len, eng_error *err)
{
    char *tmp = rep_xprintf("%s.tmp.%ld", path, (long)getpid());
    int fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0666);
    if (fd < 0) {
        eng_result r = eng_fail(err, ENG_ERR_IO, "%s: cannot create: %s", tmp, strerror(errno));
        free(tmp);
        return r;
    }
    eng_result r = write_all(fd, tmp, data, len, err);
    if (r == ENG_OK && rename(tmp, path) != 0)
        r = eng_fail(err, ENG_ERR_IO, "%s: cannot rename into place: %s", path, strerror(errno));
    if (r != ENG_OK)
        unlink(tmp);
    free(tmp);
    if (r == ENG_OK) { /* the rename made durable where the folder can be synced: the new file is in place either way */
        char *dir = rep_xstrdup(path);
        char *slash = strrchr(dir, '/');
        if (slash)
            slash[slash == dir ? 1 : 0] = 0;
        rep_sync_dir(slash ? dir : ".", NULL);
        free(dir);
    }
    return r;
}

eng_result rep_sync_dir(const char *dir, eng_error *err)
{
    int fd = open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot open folder: %s", dir, strerror(errno));
    /* err may be NULL: eng_fail then only returns the code. */
    int rc = fsync(fd), e = errno;
    close(fd);
    if (rc != 0)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot sync folder: %s", dir, strerror(e));
    return ENG_OK;
}

eng_result rep_copy_file(const char *src, unsigned flags, const char *dst, eng_error *err)
{
    int in;
    eng_result r = eng_open_input(src, flags, UINT64_MAX, &in, NULL, err);
    if (r != ENG_OK)
        return r;
    int out = open(dst, O_WRONLY | O_CREAT | O_TRUNC, 0666);
    if (out < 0) {
        int e = errno;
        close(in);
        return eng_fail(err, ENG_ERR_IO, "%s: cannot create: %s", dst, strerror(e));
    }
    char buf[1 << 16];
    for (;;) {
        ssize_t n = read(in, buf, sizeof buf);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            int e = errno;
            close(in);
            close(out);
            return eng_fail(err, ENG_ERR_IO, "%s: cannot read: %s", src, strerror(e));
        }
        if (n == 0)
            break;
        size_t done = 0;
        while (done < (size_t)n) {
            ssize_t w = write(out, buf + done, (size_t)n - done);
            if (w < 0 && errno == EINTR)
                continue;
            if (w < 0) {
                int e = errno;
                close(in);
                close(out);
                return eng_fail(err, ENG_ERR_IO, "%s: cannot write: %s", dst, strerror(e));
            }
            done += (size_t)w;
        }
    }
    close(in);
    return write_all(out, dst, NULL, 0, err);
}

static int remove_one(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)ftw;
    int rc = (flag == FTW_DP) ? rmdir(path) : unlink(path);
    return rc != 0 && errno != ENOENT ? -1 : 0;
}

eng_result rep_remove_tree(const char *path, eng_error *err)
{
    struct stat st;
    if (lstat(path, &st) != 0)
        return errno == ENOENT ? ENG_OK : eng_fail(err, ENG_ERR_IO, "%s: %s", path, strerror(errno));
    if (!S_ISDIR(st.st_mode))
        return unlink(path) == 0 ? ENG_OK : eng_fail(err, ENG_ERR_IO, "%s: cannot remove: %s", path, strerror(errno));
    if (nftw(path, remove_one, 32, FTW_DEPTH | FTW_PHYS) != 0)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot remove: %s", path, strerror(errno));
    return ENG_OK;
}
