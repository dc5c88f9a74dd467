/* rep_util.h — the replay rooms' shared helpers (util.c): allocation that cannot fail, sorting
 * and medians, paths, a growing string, files written atomically, folders made and removed.
 * The bottom of replay: it includes nothing of replay's, and every room may use it.
 */
#ifndef ISPM_REP_UTIL_H
#define ISPM_REP_UTIL_H

#include <stddef.h>

#include "eng_core.h"

/* Largest manifest or tolerances file read. */
#define REP_MAX_JSON_BYTES ((size_t)64 << 20)

/* Allocation that cannot fail: out of memory prints one line and aborts, as in ispm_core. */
void *rep_xmalloc(size_t n);
void *rep_xcalloc(size_t n, size_t size);
void *rep_xrealloc(void *p, size_t n);
char *rep_xstrdup(const char *s);
char *rep_xprintf(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
/* Sorts v ascending: the array qsort with a < / > comparison leaves (a radix sort where every
 * value is finite and non-negative, as ꟻLIP maps and flicker measures are; qsort otherwise). */
void rep_sort_floats(float *v, size_t n);
/* The median of v[0..n) (the mean of the middle two when n is even), sorting v in place; NAN
 * when n is 0. */
double rep_median(double *v, int n);
/* dir + "/" + name, without doubling a trailing slash. Caller frees. */
char *rep_path_join(const char *dir, const char *name);

/* A growing NUL-terminated string. Zero-initialise; free s when done. */
typedef struct rep_sb {
    char *s;
    size_t len, cap;
} rep_sb;
void rep_sb_printf(rep_sb *sb, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* A JSON input (eng_read_input with flags, ENG_IN_NOFOLLOW inside a run or golden, within
 * REP_MAX_JSON_BYTES) checked by eng_json_precheck and parsed: ENG_ERR_PARSE "not valid JSON"
 * naming the byte. Caller frees *root with cJSON_Delete. */
struct cJSON;
eng_result rep_json_load(const char *path, unsigned flags, struct cJSON **root, eng_error *err);

int rep_is_file(const char *path); /* regular file (following links) */
int rep_is_dir(const char *path);
/* mkdir -p. */
eng_result rep_mkdirs(const char *path, eng_error *err);
/* Writes path.tmp.<pid>, flushes it to disk, renames it over path and flushes the folder (where
 * it can: the new file is in place either way): readers see the old file or the new one, never
 * a part; on failure the old file stays. */
eng_result rep_write_atomic(const char *path, const char *data, size_t len, eng_error *err);
/* Copies a regular file's bytes to dst (created or truncated) and flushes them to disk; src is
 * opened as an input with flags (ENG_IN_NOFOLLOW: a symbolic link is refused, never followed). */
eng_result rep_copy_file(const char *src, unsigned flags, const char *dst, eng_error *err);
/* fsync of a folder (after a rename into it). */
eng_result rep_sync_dir(const char *dir, eng_error *err);
/* rm -rf without following symbolic links; a missing path is not an error. */
eng_result rep_remove_tree(const char *path, eng_error *err);

#endif
