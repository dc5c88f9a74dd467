/* exr_write.c — the multi-part EXR writer behind capture's frame files (DESIGN.md, "Run
 * layout": one file per frame, one part per announced buffer).
 *
 * It drives the OpenEXR 3.1 C API (openexr.h) with a custom write function over a file
 * descriptor it owns, rather than the library's own file stream, for three reasons: the
 * descriptor can be fsynced before the rename that publishes the file; the errno of a
 * failing write (ENOSPC, EFBIG, EIO) is kept, so the message says what went wrong instead
 * of the library's generic "write failed"; and the library's error callback is captured
 * instead of printed, so a failure is reported once, through eng_error. The library's many
 * small writes are coalesced in a write-behind buffer. Pixels are float32 in and
 * float32 out (FLOAT channels, the lossless compression capture_compression names: none by
 * default, ZIP for cap_write_exr), so what is written is bit-exact what was announced, NaN
 * payloads and -0.0 included, and replay's digests match capture's.
 *
 * Parts are scanline images with INCREASING_Y line order: file row 0 is the top row, which
 * is the announced layout, so rows are handed to the encoder as they are, interleaved
 * channels described by pixel and line strides.
 *
 * cap_recompress_exr (ispm bless: goldens in ZIP) reads a file through the same C API, each
 * part decoded into planes of its channels' own types, and writes it again with every
 * attribute copied and another compression, then decodes its result to compare. */
#define _POSIX_C_SOURCE 200809L

#include "cap_internal.h"
#include "exr_planes.h"

#include <openexr.h>

#include <errno.h>
#include <fcntl.h>
#include <fnmatch.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

/* Names longer than this need the EXR "long names" flag (older readers refuse those). */
#define EXR_SHORT_NAME_MAX 31

/* The library's writes coalesced into runs of this many bytes at most: it writes
 * the header attribute by attribute and each chunk as a few small pieces, over 11,000
 * pwrite calls for one 43-part frame with one-scanline chunks (none, rle, zips). */
#define SINK_BUFFER (256 * 1024)

/* The output stream: a file descriptor, a write-behind buffer, and the first failure seen on
 * it. The buffer holds bytes for offsets [buf_off, buf_off + buf_len); a write that does not
 * continue it flushes it first, so the file receives the library's writes in their order
 * (a later write over an earlier one, such as the chunk table, still wins). */
typedef struct exr_sink {
    int fd;
    int write_errno;        /* errno of the first failed pwrite, 0 if none */
    exr_result_t lib_code;  /* first error the library reported through the callback */
    char lib_msg[512];
    char *buf;              /* SINK_BUFFER bytes */
    size_t buf_len;
    uint64_t buf_off;
} exr_sink;

/* pwrite of all n bytes at offset; 0, or the errno (kept as the sink's first). */
static int sink_pwrite(exr_sink *s, const char *p, uint64_t sz, uint64_t offset)
{
    uint64_t done = 0;
    while (done < sz) {
        size_t n = sz - done > ((uint64_t)1 << 30) ? (size_t)1 << 30 : (size_t)(sz - done);
        ssize_t w = pwrite(s->fd, p + done, n, (off_t)(offset + done));
        if (w < 0 && errno == EINTR)
            continue;
        if (w <= 0) {
            /* pwrite returning 0 for a non-empty request makes no progress: treat it as the
             * device being full rather than looping. */
            int e = w < 0 ? errno : ENOSPC;
            if (!s->write_errno)
                s->write_errno = e;
            return e;
        }
        done += (uint64_t)w;
    }
    return 0;
}

/* Writes out what the buffer holds; 0 or the errno. */
static int sink_flush(exr_sink *s)
{
    int e = s->buf_len ? sink_pwrite(s, s->buf, s->buf_len, s->buf_off) : 0;
    s->buf_len = 0;
    return e;
}

static int64_t sink_write(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t sz,
                          uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    exr_sink *s = user;
    int e = 0;
    if (s->buf_len && (offset != s->buf_off + s->buf_len || sz > SINK_BUFFER - s->buf_len))
        e = sink_flush(s);
    if (!e && sz >= SINK_BUFFER)
        e = sink_pwrite(s, buffer, sz, offset);
    else if (!e && sz) {
        if (!s->buf_len)
            s->buf_off = offset;
        memcpy(s->buf + s->buf_len, buffer, (size_t)sz);
        s->buf_len += (size_t)sz;
    }
    if (e) {
        error_cb(ctxt, EXR_ERR_WRITE_IO, "%s", strerror(e));
        return -1;
    }
    return (int64_t)sz;
}

/* The sink of the write in progress on this thread. The library delivers errors on the
 * thread that caused them, often while it holds the context's lock, so the handler cannot
 * ask the context for its user data (exr_get_user_data takes that lock: deadlock). */
static _Thread_local exr_sink *current_sink;

static void on_exr_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    exr_sink *s = current_sink;
    if (!s || s->lib_code != EXR_ERR_SUCCESS)
        return; /* the first error is the cause; later ones are its consequences */
    s->lib_code = code;
    snprintf(s->lib_msg, sizeof s->lib_msg, "%s", msg ? msg : exr_get_default_error_message(code));
}

eng_result cap__check_buffer(const char *where, const eng_buffer *b, eng_error *err)
{
    if (!b)
        return eng_fail(err, ENG_ERR_INVALID, "%s: NULL buffer", where);
    if (!b->name || !b->name[0])
        return eng_fail(err, ENG_ERR_INVALID, "%s: buffer without a name", where);
    if (b->width <= 0 || b->height <= 0)
        return eng_fail(err, ENG_ERR_INVALID, "%s: buffer \"%s\": size %dx%d is not positive",
                        where, b->name, b->width, b->height);
    if (b->channel_count < 1 || b->channel_count > ENG_MAX_CHANNELS)
        return eng_fail(err, ENG_ERR_INVALID, "%s: buffer \"%s\": %d channels, expected 1..%d",
                        where, b->name, b->channel_count, ENG_MAX_CHANNELS);
    /* The encoder takes a row's byte stride as int32. */
    if ((size_t)b->width * (size_t)b->channel_count > (size_t)INT32_MAX / sizeof(float) ||
        (size_t)b->height > SIZE_MAX / ((size_t)b->width * (size_t)b->channel_count * sizeof(float)))
        return eng_fail(err, ENG_ERR_INVALID, "%s: buffer \"%s\": %dx%d with %d channels is too large",
                        where, b->name, b->width, b->height, b->channel_count);
    if (!b->channels)
        return eng_fail(err, ENG_ERR_INVALID, "%s: buffer \"%s\": no channel names", where, b->name);
    for (int i = 0; i < b->channel_count; i++) {
        const char *ci = b->channels[i];
        if (!ci || !ci[0])
            return eng_fail(err, ENG_ERR_INVALID, "%s: buffer \"%s\": channel %d has no name",
                            where, b->name, i);
        if (strlen(ci) > 255)
            return eng_fail(err, ENG_ERR_INVALID, "%s: buffer \"%s\": channel name longer than 255 bytes",
                            where, b->name);
        for (int j = 0; j < i; j++)
            if (strcmp(b->channels[j], ci) == 0)
                return eng_fail(err, ENG_ERR_INVALID, "%s: buffer \"%s\": channel \"%s\" appears twice",
                                where, b->name, ci);
    }
    if (!b->data)
        return eng_fail(err, ENG_ERR_INVALID, "%s: buffer \"%s\": no pixel data", where, b->name);
    return ENG_OK;
}

/* The library's compressor for the chunk being encoded on this thread (see zip_safe_compress). */
static _Thread_local exr_result_t (*library_compress)(exr_encode_pipeline_t *);

/* OpenEXR up to 3.4.7 (Debian 12 ships 3.1.5) keeps the zlib output of a ZIP/ZIPS chunk when
 * it is exactly as long as the raw packed pixels, but a reader takes a chunk of that length for
 * uncompressed data and decodes the zlib bytes as pixels: silently wrong values, which replay
 * then reports as a tampered frame (OpenEXR report 2306 upstream, fixed by storing the raw bytes when
 * compression does not shrink them). This wrapper applies that fix: same size, raw bytes. */
static exr_result_t zip_safe_compress(exr_encode_pipeline_t *enc)
{
    exr_result_t rv = library_compress(enc);
    if (rv == EXR_ERR_SUCCESS && enc->compressed_buffer && enc->packed_buffer &&
        enc->compressed_buffer != enc->packed_buffer && enc->compressed_bytes == enc->packed_bytes &&
        enc->compressed_alloc_size >= enc->packed_bytes)
        memcpy(enc->compressed_buffer, enc->packed_buffer, enc->packed_bytes);
    return rv;
}

/* Points a coding channel at its plane (found by name among planes[0..n-1]) for the chunk
 * starting at row start_y: sets the user layout and returns where the chunk's first sample is,
 * or NULL if no plane has that name (the library lists exactly the channels defined, so only a
 * file disagreeing with itself). */
static const uint8_t *bind_plane(exr_coding_channel_info_t *ch, const cap_exr_plane *planes, int n, int y0,
                                 int start_y)
{
    const cap_exr_plane *pl = NULL;
    for (int i = 0; i < n && !pl; i++)
        if (strcmp(planes[i].name, ch->channel_name) == 0)
            pl = &planes[i];
    if (!pl)
        return NULL;
    ch->user_bytes_per_element = pl->bytes;
    ch->user_data_type = pl->type;
    ch->user_pixel_stride = pl->pixel_stride;
    ch->user_line_stride = pl->line_stride;
    return pl->base + (size_t)(start_y - y0) * (size_t)pl->line_stride;
}

exr_result_t cap_exr_decode_part(exr_context_t ctxt, int part, int y0, int height, int width,
                                 const cap_exr_plane *planes, int n)
{
    int32_t lines = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctxt, part, &lines);
    if (rv == EXR_ERR_SUCCESS && lines < 1)
        rv = EXR_ERR_INVALID_ARGUMENT;
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int initialized = 0;
    for (int64_t y = y0; rv == EXR_ERR_SUCCESS && y < (int64_t)y0 + height; y += lines) {
        exr_chunk_info_t ci;
        rv = exr_read_scanline_chunk_info(ctxt, part, (int)y, &ci);
        if (rv == EXR_ERR_SUCCESS)
            rv = initialized ? exr_decoding_update(ctxt, part, &ci, &dec) : exr_decoding_initialize(ctxt, part, &ci, &dec);
        if (rv != EXR_ERR_SUCCESS)
            break;
        initialized = 1;
        if (ci.start_y < y0 || ci.height < 1 || (int64_t)ci.start_y + ci.height > (int64_t)y0 + height)
            rv = EXR_ERR_INVALID_ARGUMENT;
        for (int k = 0; k < dec.channel_count && rv == EXR_ERR_SUCCESS; k++) {
            exr_coding_channel_info_t *ch = &dec.channels[k];
            /* The planes are the caller's to write. */
            const uint8_t *to = ch->height == ci.height && ch->width == width
                                    ? bind_plane(ch, planes, n, y0, ci.start_y)
                                    : NULL;
            ch->decode_to_ptr = (uint8_t *)(uintptr_t)to;
            if (!to)
                rv = EXR_ERR_INVALID_ARGUMENT;
        }
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_decoding_choose_default_routines(ctxt, part, &dec);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_decoding_run(ctxt, part, &dec);
    }
    if (initialized)
        exr_decoding_destroy(ctxt, &dec);
    return rv;
}

/* Encodes every scanline chunk of one part, top (row y0) to bottom, from planes[0..n-1],
 * found by channel name. */
static exr_result_t write_part_pixels(exr_context_t ctxt, int part, int y0, int height, const cap_exr_plane *planes,
                                      int n)
{
    int32_t lines = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctxt, part, &lines);
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    if (lines < 1)
        return EXR_ERR_INVALID_ARGUMENT;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int initialized = 0, routines = 0;
    for (int y = y0; y - y0 < height && rv == EXR_ERR_SUCCESS; y += lines) {
        exr_chunk_info_t ci;
        rv = exr_write_scanline_chunk_info(ctxt, part, y, &ci);
        if (rv != EXR_ERR_SUCCESS)
            break;
        rv = initialized ? exr_encoding_update(ctxt, part, &ci, &enc)
                         : exr_encoding_initialize(ctxt, part, &ci, &enc);
        if (rv != EXR_ERR_SUCCESS)
            break;
        initialized = 1;
        for (int k = 0; k < enc.channel_count && rv == EXR_ERR_SUCCESS; k++) {
            enc.channels[k].encode_from_ptr = bind_plane(&enc.channels[k], planes, n, y0, ci.start_y);
            if (!enc.channels[k].encode_from_ptr)
                rv = EXR_ERR_INVALID_ARGUMENT;
        }
        if (rv != EXR_ERR_SUCCESS)
            break;
        if (!routines) {
            rv = exr_encoding_choose_default_routines(ctxt, part, &enc);
            if (rv != EXR_ERR_SUCCESS)
                break;
            routines = 1;
        }
        if (enc.compress_fn && enc.compress_fn != zip_safe_compress) {
            library_compress = enc.compress_fn;
            enc.compress_fn = zip_safe_compress;
        }
        rv = exr_encoding_run(ctxt, part, &enc);
    }
    if (initialized)
        exr_encoding_destroy(ctxt, &enc);
    return rv;
}

/* An announced buffer's pixels as planes (interleaved float32 channels, top row first). */
static exr_result_t write_buffer_pixels(exr_context_t ctxt, int part, const eng_buffer *b)
{
    cap_exr_plane planes[ENG_MAX_CHANNELS];
    size_t nc = (size_t)b->channel_count;
    for (size_t c = 0; c < nc; c++)
        planes[c] = (cap_exr_plane){b->channels[c], (const uint8_t *)(b->data + c), (int32_t)(nc * sizeof(float)),
                                (int32_t)((size_t)b->width * nc * sizeof(float)), (int16_t)sizeof(float),
                                EXR_PIXEL_FLOAT};
    return write_part_pixels(ctxt, part, 0, b->height, planes, (int)nc);
}

static exr_compression_t exr_type(cap_compression m)
{
    switch (m) {
    case CAP_COMPRESSION_NONE:
    case CAP_COMPRESSION_DEFAULT: return EXR_COMPRESSION_NONE;
    case CAP_COMPRESSION_ZIPS: return EXR_COMPRESSION_ZIPS;
    case CAP_COMPRESSION_ZIP: return EXR_COMPRESSION_ZIP;
    case CAP_COMPRESSION_PIZ: return EXR_COMPRESSION_PIZ;
    case CAP_COMPRESSION_BY_KIND: return EXR_COMPRESSION_ZIP; /* per part: exr_part_compression */
    case CAP_COMPRESSION_RLE: break;
    }
    return EXR_COMPRESSION_RLE;
}

/* Buffer names by kind, first match wins (fnmatch): what by-kind compresses with ZIP level 1. */
static const char *const ZIP1_KINDS[] = {
    "gbuffer.material", "gbuffer.motion", "gbuffer.normal", "gbuffer.depth", "*.count", "*_count",
    "lightgbuffer.*",   "bounce.*",       "photons.*",      NULL};

cap_compression cap_compression_for(const char *name, int *zip_level)
{
    for (int i = 0; name && ZIP1_KINDS[i]; i++)
        if (fnmatch(ZIP1_KINDS[i], name, 0) == 0) {
            *zip_level = 1;
            return CAP_COMPRESSION_ZIP;
        }
    *zip_level = 0;
    return CAP_COMPRESSION_NONE;
}

/* cap_write_exr (no meta) keeps its documented ZIP; frame files follow the setting, by-kind (the
 * default) part by part. *level: the part's zlib level (0: the library's default). */
static exr_compression_t exr_part_compression(const cap_exr_meta *meta, const char *name, int *level)
{
    *level = meta ? meta->zip_level : 0;
    if (!meta)
        return EXR_COMPRESSION_ZIP;
    if (meta->compression == CAP_COMPRESSION_BY_KIND || meta->compression == CAP_COMPRESSION_DEFAULT)
        return exr_type(cap_compression_for(name, level));
    return exr_type(meta->compression);
}

/* What one file holds: defines the parts in ctxt (a context started for writing), writes
 * the header and every part's pixels. */
typedef exr_result_t (*exr_fill_fn)(exr_context_t ctxt, void *arg);

/* A write context over the sink, filled by fill, then finished. */
static exr_result_t write_exr_stream(exr_sink *s, const char *path, exr_fill_fn fill, void *arg)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    init.user_data = s;
    init.write_fn = sink_write;
    exr_context_t ctxt = NULL;
    exr_result_t rv = exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS)
        rv = fill(ctxt, arg);
    /* exr_finish writes the chunk offset tables, so its result matters on success. */
    exr_result_t frv = ctxt ? exr_finish(&ctxt) : EXR_ERR_SUCCESS;
    return rv != EXR_ERR_SUCCESS ? rv : frv;
}

/* The buffers of cap__write_exr. */
typedef struct exr_frame {
    const eng_buffer *const *bufs;
    int count;
    const cap_exr_meta *meta;
} exr_frame;

static exr_result_t fill_frame(exr_context_t ctxt, void *arg)
{
    const exr_frame *f = arg;
    const eng_buffer *const *bufs = f->bufs;
    int count = f->count;
    const cap_exr_meta *meta = f->meta;
    exr_result_t rv = EXR_ERR_SUCCESS;
    int long_names = 0;
    for (int i = 0; i < count; i++)
        for (int c = 0; c < bufs[i]->channel_count; c++)
            if (strlen(bufs[i]->channels[c]) > EXR_SHORT_NAME_MAX)
                long_names = 1;
    if (long_names)
        rv = exr_set_longname_support(ctxt, 1);
    /* displayWindow is a shared attribute: every part of a multi-part file must carry the
     * same one (the C++ library, and so OpenImageIO, refuses the file otherwise), yet the
     * buffers of a frame differ in size (shadow maps vs. the camera's). So all parts get
     * the box that holds every part's data window. */
    exr_attr_box2i_t display;
    memset(&display, 0, sizeof display);
    for (int i = 0; i < count; i++) {
        if (bufs[i]->width - 1 > display.max.x)
            display.max.x = bufs[i]->width - 1;
        if (bufs[i]->height - 1 > display.max.y)
            display.max.y = bufs[i]->height - 1;
    }
    exr_attr_v2f_t center;
    memset(&center, 0, sizeof center);
    for (int i = 0; i < count && rv == EXR_ERR_SUCCESS; i++) {
        const eng_buffer *b = bufs[i];
        int part = -1;
        exr_attr_box2i_t data;
        memset(&data, 0, sizeof data);
        data.max.x = b->width - 1;
        data.max.y = b->height - 1;
        int level = 0;
        exr_compression_t comp = exr_part_compression(meta, b->name, &level);
        rv = exr_add_part(ctxt, b->name, EXR_STORAGE_SCANLINE, &part);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_initialize_required_attr(ctxt, part, &display, &data, 1.0f, &center, 1.0f,
                                              EXR_LINEORDER_INCREASING_Y, comp);
        if (rv == EXR_ERR_SUCCESS && level > 0 && (comp == EXR_COMPRESSION_ZIP || comp == EXR_COMPRESSION_ZIPS))
            rv = exr_set_zip_compression_level(ctxt, part, level);
        for (int c = 0; c < b->channel_count && rv == EXR_ERR_SUCCESS; c++)
            rv = exr_add_channel(ctxt, part, b->channels[c], EXR_PIXEL_FLOAT,
                                 EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
        if (meta && meta->frame >= 0) {
            if (rv == EXR_ERR_SUCCESS)
                rv = exr_attr_set_int(ctxt, part, "ispm:frame", meta->frame);
            if (rv == EXR_ERR_SUCCESS)
                rv = exr_attr_set_double(ctxt, part, "ispm:time", meta->time);
        }
    }
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctxt);
    for (int i = 0; i < count && rv == EXR_ERR_SUCCESS; i++)
        rv = write_buffer_pixels(ctxt, i, bufs[i]);
    return rv;
}

/* Checks the written temp file before it is renamed into place (NULL: none). */
typedef eng_result (*exr_check_fn)(const char *tmp, void *arg, eng_error *err);

/* Writes path atomically: "<path>.tmp" filled through the sink, flushed, fsynced, closed,
 * checked and renamed over path; on any failure the temp file is removed and path left as it
 * was. sync 0: no fsync (files that need not survive a crash). */
static eng_result write_atomic(const char *path, exr_fill_fn fill, exr_check_fn check, void *arg, int sync,
                               eng_error *err)
{
    char *tmp = cap__xmalloc(strlen(path) + 5);
    sprintf(tmp, "%s.tmp", path);
    eng_result res = ENG_OK;
    exr_sink s = {.fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666)};
    if (s.fd < 0) {
        res = eng_fail(err, ENG_ERR_IO, "%s: cannot create: %s", tmp, strerror(errno));
        free(tmp);
        return res;
    }

    s.buf = cap__xmalloc(SINK_BUFFER);
    exr_sink *outer = current_sink;
    current_sink = &s;
    exr_result_t rv = write_exr_stream(&s, path, fill, arg);
    current_sink = outer;
    if (rv == EXR_ERR_SUCCESS)
        sink_flush(&s); /* a failure is s.write_errno */
    free(s.buf);
    if (s.write_errno)
        res = eng_fail(err, ENG_ERR_IO, "%s: %s", path, strerror(s.write_errno));
    else if (rv == EXR_ERR_OUT_OF_MEMORY)
        res = eng_fail(err, ENG_ERR_NOMEM, "%s: OpenEXR: out of memory", path);
    else if (rv != EXR_ERR_SUCCESS)
        res = eng_fail(err, ENG_ERR_IO, "%s: OpenEXR: %s", path,
                       s.lib_code != EXR_ERR_SUCCESS ? s.lib_msg : exr_get_default_error_message(rv));
    else if (sync && fsync(s.fd) != 0)
        res = eng_fail(err, ENG_ERR_IO, "%s: cannot sync: %s", path, strerror(errno));

    /* close() can be where a deferred write error (NFS, quota) finally shows. */
    if (close(s.fd) != 0 && res == ENG_OK)
        res = eng_fail(err, ENG_ERR_IO, "%s: %s", path, strerror(errno));
    if (res == ENG_OK && check)
        res = check(tmp, arg, err);
    if (res == ENG_OK && rename(tmp, path) != 0)
        res = eng_fail(err, ENG_ERR_IO, "%s: cannot rename %s into place: %s", path, tmp, strerror(errno));
    if (res != ENG_OK)
        unlink(tmp);
    free(tmp);
    return res;
}

/* cap__write_exr, with the fsync before the rename or (sync 0) without. */
static eng_result write_exr_file(const char *path, const eng_buffer *const *bufs, int count,
                                 const cap_exr_meta *meta, int sync, eng_error *err)
{
    if (!path || !path[0])
        return eng_fail(err, ENG_ERR_INVALID, "cap_write_exr: no path");
    if (count < 1 || !bufs)
        return eng_fail(err, ENG_ERR_INVALID, "%s: no buffers to write", path);
    for (int i = 0; i < count; i++) {
        eng_result r = cap__check_buffer(path, bufs[i], err);
        if (r != ENG_OK)
            return r;
        for (int j = 0; j < i; j++)
            if (strcmp(bufs[j]->name, bufs[i]->name) == 0)
                return eng_fail(err, ENG_ERR_INVALID, "%s: two buffers are named \"%s\"", path,
                                bufs[i]->name);
    }

    exr_frame f = {bufs, count, meta};
    return write_atomic(path, fill_frame, NULL, &f, sync, err);
}

eng_result cap__write_exr(const char *path, const eng_buffer *const *bufs, int count,
                          const cap_exr_meta *meta, eng_error *err)
{
    return write_exr_file(path, bufs, count, meta, 1, err);
}

eng_result cap_write_exr(const char *path, const eng_buffer *const *bufs, int count, eng_error *err)
{
    return cap__write_exr(path, bufs, count, NULL, err);
}

/* ---------------------------------------------------------------- recompression */

/* One part of the file being recompressed, decoded: its channels as planes in their own type. */
typedef struct exr_part_pixels {
    int y0, height, count;
    cap_exr_plane planes[ENG_MAX_CHANNELS];
    uint8_t *data; /* every plane, one after the other */
} exr_part_pixels;

typedef struct exr_recode {
    exr_context_t in;
    int count;
    exr_part_pixels *parts;
    exr_compression_t comp;
    int long_names;
} exr_recode;

/* Largest part recompressed, in bytes (as replay's REP_MAX_FLOATS floats): a lying header must
 * not exhaust memory. */
#define RECODE_MAX_BYTES ((size_t)1 << 30)

static int16_t pixel_bytes(exr_pixel_type_t t)
{
    return t == EXR_PIXEL_HALF ? 2 : 4;
}

/* Decodes part p of r->in into r->parts[p]; why gets the reason a part cannot be recompressed
 * (EXR_ERR_INVALID_ARGUMENT with why set), else the library's error. */
static exr_result_t read_part(exr_recode *r, int p, char *why, size_t why_size)
{
    exr_part_pixels *pp = &r->parts[p];
    exr_storage_t storage;
    const exr_attr_chlist_t *chl = NULL;
    exr_attr_box2i_t dw;
    int32_t lines = 0;
    exr_result_t rv = exr_get_storage(r->in, p, &storage);
    if (rv == EXR_ERR_SUCCESS && storage != EXR_STORAGE_SCANLINE) {
        snprintf(why, why_size, "part %d is not a scanline image (tiled or deep): not recompressed", p);
        return EXR_ERR_INVALID_ARGUMENT;
    }
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_channels(r->in, p, &chl);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_data_window(r->in, p, &dw);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_scanlines_per_chunk(r->in, p, &lines);
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (chl->num_channels < 1 || chl->num_channels > ENG_MAX_CHANNELS || w < 1 || h < 1 || lines < 1 ||
        (size_t)w * (size_t)h > RECODE_MAX_BYTES / 4 / (size_t)chl->num_channels) {
        snprintf(why, why_size, "part %d: %d channels over %lldx%lld pixels: not recompressed", p,
                 chl->num_channels, (long long)w, (long long)h);
        return EXR_ERR_INVALID_ARGUMENT;
    }
    for (int c = 0; c < chl->num_channels; c++) {
        const exr_attr_chlist_entry_t *e = &chl->entries[c];
        if (e->x_sampling != 1 || e->y_sampling != 1) {
            snprintf(why, why_size, "part %d: channel \"%s\" is subsampled: not recompressed", p, e->name.str);
            return EXR_ERR_INVALID_ARGUMENT;
        }
        if (e->name.length > EXR_SHORT_NAME_MAX)
            r->long_names = 1;
    }
    pp->y0 = dw.min.y;
    pp->height = (int)h;
    pp->count = chl->num_channels;
    pp->data = cap__xmalloc((size_t)w * (size_t)h * 4 * (size_t)pp->count);
    size_t offset = 0;
    for (int c = 0; c < pp->count; c++) {
        const exr_attr_chlist_entry_t *e = &chl->entries[c];
        int16_t bytes = pixel_bytes(e->pixel_type);
        pp->planes[c] = (cap_exr_plane){e->name.str, pp->data + offset, bytes, (int32_t)(w * bytes), bytes,
                                    (uint16_t)e->pixel_type};
        offset += (size_t)w * (size_t)h * (size_t)bytes;
    }

    return cap_exr_decode_part(r->in, p, pp->y0, pp->height, (int)w, pp->planes, pp->count);
}

/* The parts of r->in again, every attribute copied, compression r->comp, pixels from r->parts. */
static exr_result_t fill_recode(exr_context_t ctxt, void *arg)
{
    exr_recode *r = arg;
    exr_result_t rv = EXR_ERR_SUCCESS;
    for (int p = 0; p < r->count && rv == EXR_ERR_SUCCESS; p++) {
        int32_t n = 0;
        rv = exr_get_attribute_count(r->in, p, &n);
        for (int32_t i = 0; i < n && rv == EXR_ERR_SUCCESS; i++) {
            const exr_attribute_t *a = NULL;
            rv = exr_get_attribute_by_index(r->in, p, EXR_ATTR_LIST_FILE_ORDER, i, &a);
            if (rv == EXR_ERR_SUCCESS && (strlen(a->name) > EXR_SHORT_NAME_MAX || strlen(a->type_name) > EXR_SHORT_NAME_MAX))
                r->long_names = 1;
        }
    }
    if (rv == EXR_ERR_SUCCESS && r->long_names)
        rv = exr_set_longname_support(ctxt, 1);
    for (int p = 0; p < r->count && rv == EXR_ERR_SUCCESS; p++) {
        const char *name = NULL;
        int part = -1;
        rv = exr_get_name(r->in, p, &name);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_add_part(ctxt, name, EXR_STORAGE_SCANLINE, &part);
        /* Every attribute as it was (chunkCount, which depends on the compression, is set
         * again by exr_write_header), then the new compression over the copied one. */
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_copy_unset_attributes(ctxt, part, r->in, p);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_set_compression(ctxt, part, r->comp);
    }
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctxt);
    for (int p = 0; p < r->count && rv == EXR_ERR_SUCCESS; p++)
        rv = write_part_pixels(ctxt, p, r->parts[p].y0, r->parts[p].height, r->parts[p].planes, r->parts[p].count);
    return rv;
}

/* Opens path into r (r->in, r->count) and decodes every part into r->parts, unless skip_same
 * and every part already has r->comp (*same then 1, nothing decoded). */
static eng_result load_exr(const char *path, exr_recode *r, int skip_same, int *same, eng_error *err)
{
    exr_sink rs = {.fd = -1}; /* only for the reader's messages */
    exr_sink *outer = current_sink;
    current_sink = &rs;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    exr_result_t rv = exr_start_read(&r->in, path, &init);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_count(r->in, &r->count);
    *same = rv == EXR_ERR_SUCCESS;
    for (int p = 0; p < r->count && rv == EXR_ERR_SUCCESS; p++) {
        exr_compression_t c;
        rv = exr_get_compression(r->in, p, &c);
        *same = *same && rv == EXR_ERR_SUCCESS && c == r->comp;
    }
    char why[300] = "";
    if (rv == EXR_ERR_SUCCESS && !(skip_same && *same)) {
        r->parts = cap__xcalloc((size_t)r->count, sizeof *r->parts);
        for (int p = 0; p < r->count && rv == EXR_ERR_SUCCESS; p++)
            rv = read_part(r, p, why, sizeof why);
    }
    current_sink = outer;
    if (why[0])
        return eng_fail(err, ENG_ERR_INVALID, "%s: %s", path, why);
    if (rv == EXR_ERR_OUT_OF_MEMORY)
        return eng_fail(err, ENG_ERR_NOMEM, "%s: OpenEXR: out of memory", path);
    if (rv != EXR_ERR_SUCCESS)
        return eng_fail(err, ENG_ERR_IO, "%s: OpenEXR: %s", path,
                        rs.lib_code != EXR_ERR_SUCCESS ? rs.lib_msg : exr_get_default_error_message(rv));
    return ENG_OK;
}

static void free_recode(exr_recode *r)
{
    for (int p = 0; r->parts && p < r->count; p++)
        free(r->parts[p].data);
    free(r->parts);
    if (r->in)
        exr_finish(&r->in);
}

/* The recompressed file, before it is renamed into place: decoded again, it holds the source's
 * parts in the new compression, every channel the same type and bytes. */
static eng_result check_recode(const char *tmp, void *arg, eng_error *err)
{
    const exr_recode *r = arg;
    exr_recode back = {.comp = r->comp};
    int same = 0;
    eng_result res = load_exr(tmp, &back, 0, &same, err);
    int bad = res == ENG_OK && (!same || back.count != r->count) ? 0 : -1;
    for (int p = 0; res == ENG_OK && bad < 0 && p < r->count; p++) {
        const exr_part_pixels *a = &r->parts[p], *b = &back.parts[p];
        int ok = a->y0 == b->y0 && a->height == b->height && a->count == b->count;
        for (int c = 0; ok && c < a->count; c++) {
            const cap_exr_plane *x = &a->planes[c], *y = &b->planes[c];
            ok = strcmp(x->name, y->name) == 0 && x->type == y->type && x->line_stride == y->line_stride &&
                 memcmp(x->base, y->base, (size_t)x->line_stride * (size_t)a->height) == 0;
        }
        if (!ok)
            bad = p;
    }
    if (bad >= 0)
        res = eng_fail(err, ENG_ERR_IO, "%s: the file written does not decode to the source's pixels (part %d)", tmp, bad);
    free_recode(&back);
    return res;
}

eng_result cap_recompress_exr(const char *src, const char *dst, cap_compression m, int *rewritten,
                              eng_error *err)
{
    if (rewritten)
        *rewritten = 0;
    if (!src || !src[0] || !dst || !dst[0])
        return eng_fail(err, ENG_ERR_INVALID, "cap_recompress_exr: no path");
    if (m == CAP_COMPRESSION_BY_KIND)
        return eng_fail(err, ENG_ERR_INVALID, "%s: cap_recompress_exr takes one compression for every part", src);
    exr_recode r = {.comp = exr_type(m)};
    int same = 0;
    eng_result res = load_exr(src, &r, 1, &same, err);
    if (res == ENG_OK && !same) {
        res = write_atomic(dst, fill_recode, check_recode, &r, 1, err);
        if (res == ENG_OK && rewritten)
            *rewritten = 1;
    }
    free_recode(&r);
    return res;
}

eng_result cap_write_exr_zip(const char *path, const eng_buffer *b, int level, eng_error *err)
{
    cap_exr_meta meta = {-1, 0.0, CAP_COMPRESSION_ZIP, level};
    const eng_buffer *bufs[1] = {b};
    return write_exr_file(path, bufs, 1, &meta, 1, err);
}

eng_result cap_write_exr_unsynced(const char *path, const eng_buffer *const *bufs, int count, eng_error *err)
{
    return write_exr_file(path, bufs, count, NULL, 0, err);
}
