/* exr_read.c — frame files read through OpenEXR's C API (openexr.h, OpenEXRCore), so that a
 * replay whose images are all frame EXRs never loads OpenImageIO (its ~260 shared
 * libraries cost ~0.8 s of CPU on the first frame read, as much as a whole `idiff` run).
 *
 * The parts it returns are the ones oiio_shim.cpp returns for the same file, or it returns
 * ENG_ERR_UNSUPPORTED and rep_read_parts asks OpenImageIO: same part order (the file's), same
 * names, channel names in OpenImageIO 2.4's order (its OpenEXR reader's canonical sort, below),
 * and float32 values copied bit for bit (only FLOAT channels are taken, so no conversion is
 * involved; only lossless compressions, which both libraries decode to the same bytes). What it
 * takes: scanline parts, data window at the origin, unsubsampled FLOAT channels, NONE, RLE,
 * ZIPS, ZIP or PIZ compression, within the caller's float limit and OpenImageIO's size limits.
 * Anything else, and any failure of the library, is left to OpenImageIO, which then says what is
 * wrong exactly as before (a truncated file is its one-line error naming the file). The header
 * walk of exr_check.c runs first, as it does before OpenImageIO. test_replay checks both readers
 * give the same parts on every golden frame. Every chunk is decompressed and unpacked by
 * OpenEXR's own decoding pipeline (exr_decoding_run): the codec stays the library's.
 */
#include "oiio_shim.h"

#include "exr_planes.h"

#include <openexr.h>

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* OpenImageIO's ImageInput::check_open limits on an EXR part (exrinput.cpp, seek_subimage). */
#define OIIO_MAX_SIDE (1 << 20)

static char *str_dup(const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = malloc(n);
    if (p)
        memcpy(p, s, n);
    return p;
}

static void quiet(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    (void)code;
    (void)msg; /* the failure goes to OpenImageIO, which reports it */
}

/* One channel as OpenImageIO sorts it (exrinput.cpp, ChanNameHolder): layer is the name up to and
 * including its last '.', suffix the rest. */
typedef struct chan {
    const char *name;
    size_t layer_len;
    const char *suffix;
    int special;
} chan;

/* OpenImageIO's sort priority of reserved suffixes (case-insensitive); the second list is used in
 * a layer holding X and Y or Z (a position or normal). */
static const char *const SPECIAL[] = {"R",  "Red", "G",  "Green", "B",  "Blue", "Y",     "real",  "imag", "A",
                                      "Alpha", "AR", "RA", "AG", "GA", "AB",   "BA", "Z", "Depth", "Zback", NULL};
static const char *const SPECIAL_XYZ[] = {"R",  "Red",  "G",  "Green", "B",  "Blue", "X",  "Y",     "Z",     "real",
                                          "imag", "A", "Alpha", "AR", "RA", "AG", "GA", "AB", "BA", "Depth", "Zback",
                                          NULL};

static int special_index(const char *suffix, const char *const *list)
{
    for (int i = 0; list[i]; i++)
        if (strcasecmp(suffix, list[i]) == 0)
            return i;
    return 10000;
}

/* string_view's operator< on two byte ranges (unsigned bytes, a prefix first). */
static int cmp_range(const char *a, size_t na, const char *b, size_t nb)
{
    int c = memcmp(a, b, na < nb ? na : nb);
    return c ? c : (na > nb) - (na < nb);
}

static int chan_order(const void *pa, const void *pb)
{
    const chan *a = pa, *b = pb;
    int c = cmp_range(a->name, a->layer_len, b->name, b->layer_len);
    if (c)
        return c;
    if (a->special != b->special)
        return a->special < b->special ? -1 : 1;
    return strcmp(a->suffix, b->suffix);
}

static int layer_has(const chan *ch, int n, size_t layer_len, const char *layer, const char *suffix)
{
    for (int i = 0; i < n; i++)
        if (ch[i].layer_len == layer_len && memcmp(ch[i].name, layer, layer_len) == 0 &&
            strcasecmp(ch[i].suffix, suffix) == 0)
            return 1;
    return 0;
}

/* Sorts n channels into OpenImageIO's order: by layer, then reserved suffixes first in their
 * list's order, then by suffix (a total order: names are unique). */
static void oiio_channel_order(chan *ch, int n)
{
    for (int i = 0; i < n; i++) {
        const char *dot = strrchr(ch[i].name, '.');
        ch[i].layer_len = dot ? (size_t)(dot - ch[i].name) + 1 : 0;
        ch[i].suffix = ch[i].name + ch[i].layer_len;
    }
    for (int i = 0; i < n; i++) {
        size_t ll = ch[i].layer_len;
        const char *layer = ch[i].name;
        int xyz = layer_has(ch, n, ll, layer, "X") && (layer_has(ch, n, ll, layer, "Y") || layer_has(ch, n, ll, layer, "Z"));
        ch[i].special = special_index(ch[i].suffix, xyz ? SPECIAL_XYZ : SPECIAL);
    }
    qsort(ch, (size_t)n, sizeof *ch, chan_order);
}

void rep_exr_channel_order(const char *const *names, int n, int *order)
{
    chan ch[ENG_MAX_CHANNELS];
    for (int c = 0; c < n; c++)
        ch[c].name = names[c];
    oiio_channel_order(ch, n);
    for (int c = 0; c < n; c++)
        for (int k = 0; k < n; k++)
            if (ch[c].name == names[k])
                order[c] = k;
}

/* A luminance-chroma channel set (Y, RY, BY, maybe A), which OpenImageIO converts to RGB. */
static int luminance_chroma(const chan *ch, int n)
{
    if (n < 3 || n > 4)
        return 0;
    int y = 0, ry = 0, by = 0, a = 0;
    for (int i = 0; i < n; i++) {
        y |= strcasecmp(ch[i].suffix, "Y") == 0;
        ry |= strcasecmp(ch[i].suffix, "RY") == 0;
        by |= strcasecmp(ch[i].suffix, "BY") == 0;
        a |= strcasecmp(ch[i].suffix, "A") == 0 || strcasecmp(ch[i].suffix, "Alpha") == 0;
    }
    return y && ry && by && (n == 3 || a);
}

static eng_result leave(const char *path, int part, const char *why, eng_error *err)
{
    return eng_fail(err, ENG_ERR_UNSUPPORTED, "%s: part %d: %s (left to OpenImageIO)", path, part, why);
}

static eng_result lib_failed(const char *path, int part, exr_result_t rv, eng_error *err)
{
    return leave(path, part, exr_get_default_error_message(rv), err);
}

/* The header of part p into *out (name, size, channels in OpenImageIO's order; no pixels, data
 * NULL). */
static eng_result read_header(exr_context_t ctxt, const char *path, int p, size_t max_floats, rep_part *out,
                              eng_error *err)
{
    exr_storage_t storage;
    exr_compression_t comp;
    exr_attr_box2i_t dw;
    const char *name = NULL;
    const exr_attr_chlist_t *cl = NULL;
    exr_result_t rv;
    if ((rv = exr_get_storage(ctxt, p, &storage)) != EXR_ERR_SUCCESS ||
        (rv = exr_get_compression(ctxt, p, &comp)) != EXR_ERR_SUCCESS ||
        (rv = exr_get_data_window(ctxt, p, &dw)) != EXR_ERR_SUCCESS ||
        (rv = exr_get_channels(ctxt, p, &cl)) != EXR_ERR_SUCCESS)
        return lib_failed(path, p, rv, err);
    if (storage != EXR_STORAGE_SCANLINE)
        return leave(path, p, "not a scanline part", err);
    if (comp != EXR_COMPRESSION_NONE && comp != EXR_COMPRESSION_RLE && comp != EXR_COMPRESSION_ZIPS &&
        comp != EXR_COMPRESSION_ZIP && comp != EXR_COMPRESSION_PIZ)
        return leave(path, p, "lossy or unusual compression", err);
    if (exr_get_name(ctxt, p, &name) != EXR_ERR_SUCCESS || !name || !name[0])
        return leave(path, p, "no name", err);
    if (dw.min.x != 0 || dw.min.y != 0 || dw.max.x < 0 || dw.max.y < 0 || dw.max.x >= OIIO_MAX_SIDE ||
        dw.max.y >= OIIO_MAX_SIDE)
        return leave(path, p, "data window not at the origin, or too large", err);
    int n = cl ? cl->num_channels : 0;
    size_t w = (size_t)dw.max.x + 1, h = (size_t)dw.max.y + 1;
    if (n < 1 || n > ENG_MAX_CHANNELS)
        return leave(path, p, "channel count beyond the limits", err);
    /* Over the caller's limit: refused here as OpenImageIO refuses it (same result, same words),
     * without loading OpenImageIO to say so. */
    if (w > max_floats || h > max_floats || w * h > max_floats / (size_t)n)
        return eng_fail(err, ENG_ERR_INVALID, "%s: part %s: %zux%zux%d floats, more than the %zu allowed", path, name,
                        w, h, n, max_floats);
    chan ch[ENG_MAX_CHANNELS];
    for (int c = 0; c < n; c++) {
        const exr_attr_chlist_entry_t *e = &cl->entries[c];
        if (e->pixel_type != EXR_PIXEL_FLOAT || e->x_sampling != 1 || e->y_sampling != 1 || !e->name.str ||
            !e->name.str[0])
            return leave(path, p, "a channel that is not full-resolution float32", err);
        ch[c].name = e->name.str;
    }
    oiio_channel_order(ch, n);
    if (luminance_chroma(ch, n))
        return leave(path, p, "luminance-chroma channels", err);
    out->name = str_dup(name);
    out->width = (int)w;
    out->height = (int)h;
    out->channel_count = n;
    for (int c = 0; c < n; c++)
        out->channels[c] = str_dup(ch[c].name);
    if (!out->name)
        return eng_fail(err, ENG_ERR_NOMEM, "%s: part %s: out of memory", path, name);
    for (int c = 0; c < n; c++)
        if (!out->channels[c])
            return eng_fail(err, ENG_ERR_NOMEM, "%s: part %s: out of memory", path, name);
    return ENG_OK;
}

/* The pixels of part p into out->data (interleaved in out's channel order, top row first),
 * through capture's decoding loop (capture/exr_planes.h): one plane per channel. */
static exr_result_t read_pixels(exr_context_t ctxt, int p, rep_part *out)
{
    const size_t nc = (size_t)out->channel_count, row = (size_t)out->width * nc;
    cap_exr_plane planes[ENG_MAX_CHANNELS];
    for (size_t c = 0; c < nc; c++)
        planes[c] = (cap_exr_plane){out->channels[c], (const uint8_t *)(out->data + c), (int32_t)(nc * sizeof(float)),
                                    (int32_t)(row * sizeof(float)), (int16_t)sizeof(float), EXR_PIXEL_FLOAT};
    return cap_exr_decode_part(ctxt, p, 0, out->height, out->width, planes, (int)nc);
}

/* The whole file in memory, for OpenEXR's custom read (exr_context_initializer_t.read_fn): the
 * library reads a frame chunk by chunk, one pread each (a 160x160 frame of 43 one-scanline parts:
 * ~7,000 system calls; a replay of the CI run against a 43-part run ~71,000), and on a virtual
 * machine each costs microseconds of kernel entry. Read once, served by memcpy: the same bytes
 * at the same offsets, so the same parts. */
typedef struct mem_file {
    uint8_t *data;
    size_t size;
} mem_file;

#define MEM_FILE_MAX ((size_t)256 << 20) /* larger files are left to the library's own reads */

static int64_t mem_read(exr_const_context_t ctxt, void *user, void *buf, uint64_t sz, uint64_t off,
                        exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb; /* a short read is the library's to report, as with its pread */
    const mem_file *m = user;
    if (off >= m->size)
        return 0; /* end of file, as pread says it */
    uint64_t n = m->size - off < sz ? m->size - off : sz;
    memcpy(buf, m->data + off, (size_t)n);
    return (int64_t)n;
}

static int64_t mem_size(exr_const_context_t ctxt, void *user)
{
    (void)ctxt;
    return (int64_t)((const mem_file *)user)->size;
}

/* The file's bytes (eng_read_file), or 0 with m->data NULL when it cannot be read whole or is
 * empty: the library then opens it itself and reports what is wrong as before. */
static int mem_load(const char *path, mem_file *m)
{
    char *data;
    eng_error ignored;
    if (eng_read_file(path, MEM_FILE_MAX, &data, &m->size, &ignored) != ENG_OK || m->size == 0) {
        free(data); /* NULL when nothing was read */
        m->data = NULL;
        m->size = 0;
        return 0;
    }
    m->data = (uint8_t *)data;
    return 1;
}

/* Is name one of only[0..n-1]? (only NULL: every name is.) */
static int wanted(const char *const *only, int n, const char *name)
{
    if (!only)
        return 1;
    for (int i = 0; i < n; i++)
        if (strcmp(only[i], name) == 0)
            return 1;
    return 0;
}

/* Drops the parts whose name only does not list (freed), keeping the others in file order. */
static void keep_only(rep_part *arr, int *n, const char *const *only, int only_n)
{
    int k = 0;
    for (int p = 0; p < *n; p++) {
        if (wanted(only, only_n, arr[p].name))
            arr[k++] = arr[p];
        else
            rep_part_clear(&arr[p]);
    }
    *n = k;
}

static eng_result read_parts(const char *path, size_t max_floats, rep_parts_check check, void *user,
                             const char *const *only, int only_n, rep_part **parts, int *count, eng_error *err)
{
    *parts = NULL;
    *count = 0;
    eng_result r = rep_exr_check_header(path, err);
    if (r != ENG_OK)
        return r;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet;
    mem_file mf;
    if (mem_load(path, &mf)) {
        init.user_data = &mf;
        init.read_fn = mem_read;
        init.size_fn = mem_size;
    }
    exr_context_t ctxt = NULL;
    exr_result_t rv = exr_start_read(&ctxt, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(&ctxt);
        free(mf.data);
        return leave(path, -1, exr_get_default_error_message(rv), err);
    }
    int n = 0;
    if ((rv = exr_get_count(ctxt, &n)) != EXR_ERR_SUCCESS || n < 1 || n > REP_MAX_PARTS) {
        exr_finish(&ctxt);
        free(mf.data);
        return leave(path, -1, "no parts, or too many", err);
    }
    rep_part *arr = calloc((size_t)n, sizeof *arr);
    if (!arr) {
        exr_finish(&ctxt);
        free(mf.data);
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory while reading", path);
    }
    /* Headers in order up to the first that fails (h), then the pixels of parts 0..h-1 as tasks
     * (OpenEXR decodes chunks of one context on several threads; each part has its own pipeline
     * and planes): inside replay's parallel region another thread takes parts of a large frame,
     * outside one this thread decodes them all. The error is the one the serial order meets
     * first: a part's pixels before a later part's header. */
    int h = 0;
    eng_error herr;
    eng_result hres = ENG_OK;
    while (h < n && (hres = read_header(ctxt, path, h, max_floats, &arr[h], &herr)) == ENG_OK)
        h++;
    /* Every header before any pixel: the caller's check, then the pixels' memory. */
    if (check && h == n)
        r = check(user, path, arr, n, err);
    for (int p = 0; p < h && r == ENG_OK; p++) {
        if (!wanted(only, only_n, arr[p].name))
            continue; /* its header was checked; its pixels are not decoded */
        arr[p].data = malloc((size_t)arr[p].width * (size_t)arr[p].height * (size_t)arr[p].channel_count *
                             sizeof(float));
        if (!arr[p].data)
            r = eng_fail(err, ENG_ERR_NOMEM, "%s: part %s: out of memory", path, arr[p].name);
    }
    exr_result_t *prv = r == ENG_OK ? calloc((size_t)(h > 0 ? h : 1), sizeof *prv) : NULL;
    if (r != ENG_OK) {
        /* the check's refusal, or no memory: nothing decoded */
    } else if (!prv) {
        r = eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory while reading", path);
    } else {
#pragma omp taskloop grainsize(1) default(none) shared(ctxt, arr, prv, h)
        for (int p = 0; p < h; p++)
            prv[p] = arr[p].data ? read_pixels(ctxt, p, &arr[p]) : EXR_ERR_SUCCESS;
        for (int p = 0; p < h && r == ENG_OK; p++)
            if (prv[p] != EXR_ERR_SUCCESS)
                r = lib_failed(path, p, prv[p], err);
        if (r == ENG_OK && hres != ENG_OK) {
            r = hres;
            if (err)
                *err = herr;
        }
        free(prv);
    }
    exr_finish(&ctxt);
    free(mf.data);
    if (r != ENG_OK) {
        rep_parts_free(arr, n);
        return r;
    }
    keep_only(arr, &n, only, only_n);
    *parts = arr;
    *count = n;
    return ENG_OK;
}

eng_result rep_exr_read_parts(const char *path, size_t max_floats, rep_part **parts, int *count, eng_error *err)
{
    return read_parts(path, max_floats, NULL, NULL, NULL, 0, parts, count, err);
}

eng_result rep_read_parts(const char *path, size_t max_floats, rep_part **parts, int *count, eng_error *err)
{
    return rep_read_parts_checked(path, max_floats, NULL, NULL, parts, count, err);
}

eng_result rep_read_parts_checked(const char *path, size_t max_floats, rep_parts_check check, void *user,
                                  rep_part **parts, int *count, eng_error *err)
{
    eng_result r = read_parts(path, max_floats, check, user, NULL, 0, parts, count, err);
    if (r != ENG_ERR_UNSUPPORTED)
        return r; /* the parts, or the header walk's refusal (OpenImageIO's path refuses alike) */
    return rep_oiio_read_parts(path, max_floats, parts, count, err);
}

eng_result rep_read_parts_only(const char *path, size_t max_floats, const char *const *only, int only_n,
                               rep_part **parts, int *count, eng_error *err)
{
    eng_result r = read_parts(path, max_floats, NULL, NULL, only, only_n, parts, count, err);
    if (r != ENG_ERR_UNSUPPORTED)
        return r;
    r = rep_oiio_read_parts(path, max_floats, parts, count, err);
    if (r == ENG_OK)
        keep_only(*parts, count, only, only_n);
    return r;
}
