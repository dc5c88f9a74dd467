/* exr_check.c — the walk over an EXR's header(s) that runs before any library parses them
 * (rep_exr_check_header, oiio_shim.h).
 *
 * OpenEXR 3.1 (Debian 12) believes the size fields of a header: it allocates and clears a string
 * attribute as long as its size field says before noticing the file is shorter, and sizes a
 * part's chunk offset table from "chunkCount" or the data window. A few hundred hostile bytes
 * then cost gigabytes. So the header(s) are walked first, and any attribute, chunk count or data
 * window the file cannot possibly hold is refused before OpenImageIO or OpenEXR's C API sees the
 * file. A channel list whose pixel type is not UINT, HALF or FLOAT is refused too: it makes
 * OpenImageIO 2.4 abort on an assertion instead of failing. Files that are missing or not
 * OpenEXR pass (the reader then says what they are). Both readers (exr_read.c and the
 * OpenImageIO module, which compiles this file too) call it, so both refuse the same files with
 * the same message.
 */
#include "oiio_shim.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Longest attribute name or type: 255 with the "long names" flag. */
#define NAME_MAX_LONG 255

/* Reads a NUL-terminated header string of at most max characters into out[max + 1]; 0 at EOF
 * or when longer. */
static int read_cstr(FILE *f, size_t max, char *out)
{
    size_t n = 0;
    for (int c; (c = fgetc(f)) != EOF;) {
        if (c == 0) {
            out[n] = 0;
            return 1;
        }
        if (n >= max)
            return 0;
        out[n++] = (char)c;
    }
    return 0;
}

static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static int read_i32(FILE *f, int32_t *v)
{
    unsigned char b[4];
    if (fread(b, 1, 4, f) != 4)
        return 0;
    *v = (int32_t)le32(b);
    return 1;
}

static eng_result malformed(const char *path, int part, eng_error *err)
{
    return eng_fail(err, ENG_ERR_IO,
                    "%s: EXR header of part %d: truncated, or an attribute name or type over the length limit", path,
                    part);
}

/* A channel list (OpenEXR file layout: name, int pixel type, pLinear, 3 reserved bytes, x and y
 * sampling; an empty name ends it). Reads exactly len bytes. */
static eng_result check_chlist(FILE *f, int32_t len, const char *path, int part, const char *attr, eng_error *err)
{
    unsigned char *b = malloc(len > 0 ? (size_t)len : 1);
    if (!b)
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory while reading", path);
    eng_result r = ENG_OK;
    size_t size = (size_t)len;
    if (len > 0 && fread(b, 1, size, f) != size) {
        free(b);
        return malformed(path, part, err);
    }
    size_t at = 0;
    for (;;) {
        size_t nul = at;
        while (nul < size && b[nul] != 0)
            nul++;
        if (nul >= size)
            break; /* no terminator: the reader reports the truncated list */
        if (nul == at)
            goto out;
        const char *ch = (const char *)&b[at];
        at = nul + 1;
        if (size - at < 16)
            break;
        uint32_t type = le32(&b[at]);
        if (type > 2) {
            r = eng_fail(err, ENG_ERR_INVALID,
                         "%s: EXR header of part %d: \"%s\" channel \"%s\" has pixel type %u (not uint, half or float)",
                         path, part, attr, ch, (unsigned)type);
            goto out;
        }
        at += 16;
    }
    r = eng_fail(err, ENG_ERR_INVALID, "%s: EXR header of part %d: channel list \"%s\" is truncated", path, part,
                 attr);
out:
    free(b);
    return r;
}

/* The walk over an open file; see rep_exr_check_header. */
static eng_result walk(FILE *f, const char *path, eng_error *err)
{
    if (fseek(f, 0, SEEK_END) != 0)
        return ENG_OK;
    long end = ftell(f);
    rewind(f);
    int32_t magic = 0, version = 0;
    if (end < 8 || !read_i32(f, &magic) || !read_i32(f, &version) || magic != 20000630)
        return ENG_OK;
    const int multipart = (version & 0x1000) != 0;
    const size_t max_name = (version & 0x400) ? 255 : 31;
    const uint64_t size = (uint64_t)end;
    char name[NAME_MAX_LONG + 1], type[NAME_MAX_LONG + 1];
    for (int part = 0;; part++) {
        if (part >= REP_MAX_PARTS)
            return eng_fail(err, ENG_ERR_INVALID, "%s: EXR header: more than %d parts", path, REP_MAX_PARTS);
        if (multipart && part > 0) {
            int c = fgetc(f);
            if (c == 0 || c == EOF)
                return ENG_OK; /* the empty header that ends the list (or truncation: the reader reports it) */
            ungetc(c, f);
        }
        int tiled = (version & 0x200) != 0;
        int64_t rows = 0;
        for (;;) {
            /* A header this walk cannot follow is one the library would misread into arbitrary
             * sizes: refuse it here (a conforming writer's header always parses). */
            int32_t len = 0;
            if (!read_cstr(f, max_name, name))
                return malformed(path, part, err);
            if (!name[0])
                break;
            if (!read_cstr(f, max_name, type) || !read_i32(f, &len))
                return malformed(path, part, err);
            long at = ftell(f);
            if (len < 0 || at < 0 || (uint64_t)len > size - (uint64_t)at)
                return eng_fail(err, ENG_ERR_INVALID,
                                "%s: EXR header of part %d: attribute \"%s\" claims %d bytes, more than the file holds",
                                path, part, name, len);
            int32_t v[4] = {0, 0, 0, 0};
            if (strcmp(name, "chunkCount") == 0 && strcmp(type, "int") == 0 && len == 4) {
                if (!read_i32(f, &v[0]))
                    return malformed(path, part, err);
                if (v[0] < 0 || (uint64_t)v[0] * 8 > size)
                    return eng_fail(err, ENG_ERR_INVALID, "%s: EXR header of part %d: chunkCount %d needs a larger file",
                                    path, part, v[0]);
                continue;
            }
            if (strcmp(name, "dataWindow") == 0 && strcmp(type, "box2i") == 0 && len == 16) {
                for (int k = 0; k < 4; k++)
                    if (!read_i32(f, &v[k]))
                        return malformed(path, part, err);
                rows = (int64_t)v[3] - v[1] + 1;
                continue;
            }
            if (strcmp(type, "chlist") == 0) {
                eng_result cr = check_chlist(f, len, path, part, name, err);
                if (cr != ENG_OK)
                    return cr;
                continue;
            }
            if (strcmp(name, "tiles") == 0)
                tiled = 1;
            if (fseek(f, len, SEEK_CUR) != 0)
                return malformed(path, part, err);
        }
        /* A scanline part has at least one chunk, with an 8-byte offset, per 256 rows (DWAB, the
         * largest block); tiled parts are bounded by the pixel limit checked after opening. */
        if (!tiled && rows > 0 && (uint64_t)((rows + 255) / 256) * 8 > size)
            return eng_fail(err, ENG_ERR_INVALID, "%s: EXR header of part %d: %lld rows need a larger file", path, part,
                            (long long)rows);
        if (!multipart)
            return ENG_OK;
    }
}

eng_result rep_exr_check_header(const char *path, eng_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return ENG_OK; /* missing or unreadable: the reader says so */
    eng_result r = walk(f, path, err);
    fclose(f);
    return r;
}
