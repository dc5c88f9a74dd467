/* files.c — the one way a tool opens a file it reads (docs/inputs.md).
 *
 * Every input may come from a pull request: a sequence, a scene and its buffers and images, a
 * run's or golden's manifest, frames and tolerances, a bench config, a shard. So an input is
 * opened without blocking (a FIFO would otherwise wait for a writer forever), and fstat decides on
 * the open descriptor, not on the name: only a regular file is read; a FIFO, device, socket or
 * folder is refused by name. Its size is checked against the caller's bound before a byte is
 * read, so a sparse file of gigabytes costs nothing. Inside a run or a golden a symlink is
 * refused (ENG_IN_NOFOLLOW: O_NOFOLLOW on the last component), so that no tool reads, copies or
 * blesses a file outside the folder it was handed.
 *
 * A folder that a tool writes (a run during record, a golden during bless) is locked through a
 * file beside it, <folder>.lock (flock: released when the process ends, however it ends), which
 * names its holder; the folder itself may be swapped by rename while it is held.
 *
 * JSON text is checked before any parser sees it (eng_json_precheck): its nesting depth, which
 * recursive parsers (cJSON, tinygltf's nlohmann::json) pay for with stack, and text after the
 * value, which both would otherwise ignore.
 */
#define _GNU_SOURCE /* O_NOFOLLOW, O_CLOEXEC */
#include "eng_core.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *kind_of(mode_t m)
{
    if (S_ISDIR(m)) return "a folder";
    if (S_ISFIFO(m)) return "a FIFO";
    if (S_ISCHR(m)) return "a character device";
    if (S_ISBLK(m)) return "a block device";
    if (S_ISSOCK(m)) return "a socket";
    if (S_ISLNK(m)) return "a symbolic link";
    return "not a regular file";
}

eng_result eng_open_input(const char *path, unsigned flags, uint64_t max_bytes, int *fd_out, uint64_t *size_out,
                          eng_error *err)
{
    *fd_out = -1;
    if (size_out)
        *size_out = 0;
    int oflags = O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY;
    if (flags & ENG_IN_NOFOLLOW)
        oflags |= O_NOFOLLOW;
    int fd = open(path, oflags);
    if (fd < 0) {
        int e = errno;
        if ((flags & ENG_IN_NOFOLLOW) && e == ELOOP)
            return eng_fail(err, ENG_ERR_INVALID, "%s: is a symbolic link, refused inside a run or golden", path);
        struct stat ls;
        if (e == ENOENT && lstat(path, &ls) == 0 && S_ISLNK(ls.st_mode))
            return eng_fail(err, ENG_ERR_IO, "%s: dangling symbolic link", path);
        return eng_fail(err, ENG_ERR_IO, "%s: cannot open: %s", path, strerror(e));
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        return eng_fail(err, ENG_ERR_IO, "%s: cannot stat: %s", path, strerror(e));
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        return eng_fail(err, ENG_ERR_INVALID, "%s: is %s, not a regular file", path, kind_of(st.st_mode));
    }
    if (st.st_size < 0 || (uint64_t)st.st_size > max_bytes) {
        close(fd);
        return eng_fail(err, ENG_ERR_INVALID, "%s: file is %lld bytes, more than the %llu allowed", path,
                        (long long)st.st_size, (unsigned long long)max_bytes);
    }
    /* Reads block again from here on: a regular file never waits for a writer. */
    int fl = fcntl(fd, F_GETFL);
    if (fl >= 0)
        (void)fcntl(fd, F_SETFL, fl & ~O_NONBLOCK);
    *fd_out = fd;
    if (size_out)
        *size_out = (uint64_t)st.st_size;
    return ENG_OK;
}

eng_result eng_check_input(const char *path, unsigned flags, uint64_t max_bytes, uint64_t *size, eng_error *err)
{
    int fd;
    eng_result r = eng_open_input(path, flags, max_bytes, &fd, size, err);
    if (r == ENG_OK)
        close(fd);
    return r;
}

eng_result eng_read_input(const char *path, unsigned flags, size_t max_bytes, char **data, size_t *len, eng_error *err)
{
    *data = NULL;
    if (len)
        *len = 0;
    int fd;
    uint64_t size;
    eng_result r = eng_open_input(path, flags, max_bytes, &fd, &size, err);
    if (r != ENG_OK)
        return r;
    char *buf = malloc((size_t)size + 1);
    if (!buf) {
        close(fd);
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory reading %llu bytes", path, (unsigned long long)size);
    }
    /* At most size + 1 bytes: a file that grows while it is read is refused, never read past
     * the bound. */
    size_t got = 0;
    for (;;) {
        ssize_t n = read(fd, buf + got, (size_t)size + 1 - got);
        if (n < 0 && errno == EINTR)
            continue;
        if (n < 0) {
            int e = errno;
            free(buf);
            close(fd);
            return eng_fail(err, ENG_ERR_IO, "%s: cannot read: %s", path, strerror(e));
        }
        if (n == 0)
            break;
        got += (size_t)n;
        if (got > size)
            break;
    }
    close(fd);
    if (got != size) {
        free(buf);
        return eng_fail(err, ENG_ERR_IO, "%s: changed while read (%zu bytes, %llu expected)", path, got,
                        (unsigned long long)size);
    }
    buf[size] = 0;
    *data = buf;
    if (len)
        *len = (size_t)size;
    return ENG_OK;
}

eng_result eng_read_file(const char *path, size_t max_bytes, char **data, size_t *len, eng_error *err)
{
    return eng_read_input(path, 0, max_bytes, data, len, err);
}

static size_t skip_ws(const char *s, size_t i, size_t n)
{
    while (i < n && (s[i] == ' ' || s[i] == '\t' || s[i] == '\n' || s[i] == '\r'))
        i++;
    return i;
}

eng_result eng_json_precheck(const char *path, const char *text, size_t len, int max_depth, eng_error *err)
{
    size_t i = skip_ws(text, 0, len);
    if (i == len)
        return ENG_OK; /* empty: the parser says so */
    int depth = 0;
    int in_string = 0;
    /* The first value's extent: a container up to its matching close, a string up to its
     * closing quote, a scalar up to whitespace or a structural character. Syntax inside is the
     * parser's to judge; this only counts levels and finds where the value ends. */
    if (text[i] == '{' || text[i] == '[' || text[i] == '"') {
        for (; i < len; i++) {
            char c = text[i];
            if (in_string) {
                if (c == '\\')
                    i++;
                else if (c == '"') {
                    in_string = 0;
                    if (depth == 0) {
                        i++;
                        break;
                    }
                }
                continue;
            }
            if (c == '"') {
                in_string = 1;
            } else if (c == '{' || c == '[') {
                if (++depth > max_depth)
                    return eng_fail(err, ENG_ERR_INVALID,
                                    "%s: byte %zu: JSON nested deeper than %d levels (the limit for inputs)", path, i,
                                    max_depth);
            } else if (c == '}' || c == ']') {
                if (--depth == 0) {
                    i++;
                    break;
                }
                if (depth < 0)
                    return ENG_OK; /* malformed: the parser names it */
            }
        }
        if (depth != 0 || in_string)
            return ENG_OK; /* unterminated: the parser names it */
    } else {
        while (i < len && !strchr(" \t\r\n{}[],:\"", text[i]))
            i++;
    }
    /* Only whitespace may follow (a GLB's JSON chunk is padded with spaces), and NULs (callers
     * may count a C string's terminator). */
    for (size_t end = i; end < len; end++)
        if (!strchr(" \t\r\n", text[end])) /* strchr finds the NUL too */
            return eng_fail(err, ENG_ERR_PARSE, "%s: byte %zu: text after the JSON value", path, end);
    return ENG_OK;
}

/* ---------------------------------------------------------------- locks */

eng_result eng_lock_take(const char *dir, const char *holder, eng_lock *lk, eng_error *err)
{
    lk->fd = -1;
    size_t n = strlen(dir);
    while (n > 1 && dir[n - 1] == '/')
        n--;
    if (n + 6 > sizeof lk->path)
        return eng_fail(err, ENG_ERR_INVALID, "%s: path too long for its lock", dir);
    snprintf(lk->path, sizeof lk->path, "%.*s.lock", (int)n, dir);
    /* The file is removed by its holder when done: a lock taken on a file that was removed
     * meanwhile is no lock, so take it again on the file now at the path. */
    for (int tries = 0; tries < 100; tries++) {
        int fd = open(lk->path, O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW, 0666);
        if (fd < 0)
            return eng_fail(err, ENG_ERR_IO, "%s: cannot create the lock: %s", lk->path, strerror(errno));
        if (flock(fd, LOCK_EX | LOCK_NB) != 0) {
            int e = errno;
            char who[200] = "";
            ssize_t got = pread(fd, who, sizeof who - 1, 0);
            close(fd);
            if (e != EWOULDBLOCK)
                return eng_fail(err, ENG_ERR_IO, "%s: cannot lock: %s", lk->path, strerror(e));
            who[got > 0 ? got : 0] = 0;
            for (char *p = who; *p; p++)
                if (*p == '\n')
                    *p = 0;
            return eng_fail(err, ENG_ERR_INVALID, "%.*s: in use by %s (lock %s)", (int)n, dir,
                            who[0] ? who : "another process", lk->path);
        }
        struct stat a, b;
        if (fstat(fd, &a) == 0 && stat(lk->path, &b) == 0 && a.st_ino == b.st_ino && a.st_dev == b.st_dev) {
            /* The holder's name is for messages only: the flock is the lock, so a file that
             * cannot be written to (a full disk, a file-size limit) still locks. */
            char who[200];
            int len = snprintf(who, sizeof who, "%s, process %ld\n", holder, (long)getpid());
            if (ftruncate(fd, 0) == 0 && pwrite(fd, who, (size_t)len, 0) != len)
                (void)ftruncate(fd, 0);
            lk->fd = fd;
            return ENG_OK;
        }
        close(fd);
    }
    return eng_fail(err, ENG_ERR_IO, "%s: the lock keeps being replaced", lk->path);
}

void eng_lock_drop(eng_lock *lk)
{
    if (!lk || lk->fd < 0)
        return;
    unlink(lk->path);
    close(lk->fd);
    lk->fd = -1;
}
