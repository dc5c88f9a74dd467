/* exr_write.c — the multi-part EXR writer behind capture's frame files (DESIGN.md, "Run
 * layout": one file per frame, one part per announced buffer).
 *
 * It drives the OpenEXR 3.1 C API (openexr.h) with a custom write function over a file
 * descriptor it owns, rather than the library's own file stream, for three reasons: the
 * descriptor can be fsynced before the rename that publishes the file; the errno of a
 * failing write (ENOSPC, EFBIG, EIO) is kept, so the message says what went wrong instead
 * of the library's generic "write failed"; and the library's error callback is captured
 * instead of printed, so a failure is reported once, through eng_error. Pixels are float32
 * in and float32 out (FLOAT channels, ZIP or the lossless compression the meta names), so what is written is bit-exact what was
 * announced, NaN payloads and -0.0 included, and replay's digests match capture's.
 *
 * Parts are scanline images with INCREASING_Y line order: file row 0 is the top row, which
 * is the announced layout, so rows are handed to the encoder as they are, interleaved
 * channels described by pixel and line strides. */
#define _POSIX_C_SOURCE 200809L

#include "cap_internal.h"

#include <openexr.h>

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

/* Names longer than this need the EXR "long names" flag (older readers refuse those). */
#define EXR_SHORT_NAME_MAX 31

/* The output stream: a file descriptor plus the first failure seen on it. */
typedef struct exr_sink {
    int fd;
    int write_errno;        /* errno of the first failed pwrite, 0 if none */
    exr_result_t lib_code;  /* first error the library reported through the callback */
    char lib_msg[512];
} exr_sink;

static int64_t sink_write(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t sz,
                          uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    exr_sink *s = user;
    const char *p = buffer;
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
            error_cb(ctxt, EXR_ERR_WRITE_IO, "%s", strerror(e));
            return -1;
        }
        done += (uint64_t)w;
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

static int channel_index(const eng_buffer *b, const char *name)
{
    for (int i = 0; i < b->channel_count; i++)
        if (strcmp(b->channels[i], name) == 0)
            return i;
    return -1;
}

/* The library's compressor for the chunk being encoded on this thread (see zip_safe_compress). */
static _Thread_local exr_result_t (*library_compress)(exr_encode_pipeline_t *);

/* OpenEXR up to 3.4.7 (Debian 12 ships 3.1.5) keeps the zlib output of a ZIP/ZIPS chunk when
 * it is exactly as long as the raw packed pixels, but a reader takes a chunk of that length for
 * uncompressed data and decodes the zlib bytes as pixels: silently wrong values, which replay
 * then reports as a tampered frame (upstream issue #2306, fixed by storing the raw bytes when
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

/* Encodes every scanline chunk of one part, top to bottom. */
static exr_result_t write_part_pixels(exr_context_t ctxt, int part, const eng_buffer *b)
{
    int32_t lines = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctxt, part, &lines);
    if (rv != EXR_ERR_SUCCESS)
        return rv;
    if (lines < 1)
        return EXR_ERR_INVALID_ARGUMENT;
    size_t nc = (size_t)b->channel_count;
    size_t row = (size_t)b->width * nc; /* floats per row */
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int initialized = 0, routines = 0;
    for (int y = 0; y < b->height && rv == EXR_ERR_SUCCESS; y += lines) {
        exr_chunk_info_t ci;
        rv = exr_write_scanline_chunk_info(ctxt, part, y, &ci);
        if (rv != EXR_ERR_SUCCESS)
            break;
        rv = initialized ? exr_encoding_update(ctxt, part, &ci, &enc)
                         : exr_encoding_initialize(ctxt, part, &ci, &enc);
        if (rv != EXR_ERR_SUCCESS)
            break;
        initialized = 1;
        for (int k = 0; k < enc.channel_count; k++) {
            exr_coding_channel_info_t *ch = &enc.channels[k];
            int src = channel_index(b, ch->channel_name);
            if (src < 0) { /* the library lists exactly the channels added: cannot happen */
                rv = EXR_ERR_INVALID_ARGUMENT;
                break;
            }
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_pixel_stride = (int32_t)(nc * sizeof(float));
            ch->user_line_stride = (int32_t)(row * sizeof(float));
            ch->encode_from_ptr = (const uint8_t *)(b->data + (size_t)ci.start_y * row + (size_t)src);
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

static exr_compression_t exr_compression(const cap_exr_meta *meta)
{
    switch (meta ? meta->compression : ENG_COMPRESSION_DEFAULT) {
    case ENG_COMPRESSION_NONE: return EXR_COMPRESSION_NONE;
    case ENG_COMPRESSION_RLE: return EXR_COMPRESSION_RLE;
    case ENG_COMPRESSION_ZIPS: return EXR_COMPRESSION_ZIPS;
    case ENG_COMPRESSION_PIZ: return EXR_COMPRESSION_PIZ;
    case ENG_COMPRESSION_ZIP:
    case ENG_COMPRESSION_DEFAULT: break;
    }
    return EXR_COMPRESSION_ZIP;
}

/* Defines the parts, writes the header and every part's pixels into the sink. */
static exr_result_t write_exr_stream(exr_sink *s, const char *path, const eng_buffer *const *bufs,
                                     int count, const cap_exr_meta *meta)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = on_exr_error;
    init.user_data = s;
    init.write_fn = sink_write;
    exr_context_t ctxt = NULL;
    exr_result_t rv = exr_start_write(&ctxt, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv != EXR_ERR_SUCCESS) {
        if (ctxt)
            exr_finish(&ctxt);
        return rv;
    }
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
        rv = exr_add_part(ctxt, b->name, EXR_STORAGE_SCANLINE, &part);
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_initialize_required_attr(ctxt, part, &display, &data, 1.0f, &center, 1.0f,
                                              EXR_LINEORDER_INCREASING_Y, exr_compression(meta));
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
        rv = write_part_pixels(ctxt, i, bufs[i]);
    /* exr_finish writes the chunk offset tables, so its result matters on success. */
    exr_result_t frv = exr_finish(&ctxt);
    return rv != EXR_ERR_SUCCESS ? rv : frv;
}

eng_result cap__write_exr(const char *path, const eng_buffer *const *bufs, int count,
                          const cap_exr_meta *meta, eng_error *err)
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

    char *tmp = cap__xmalloc(strlen(path) + 5);
    sprintf(tmp, "%s.tmp", path);
    eng_result res = ENG_OK;
    exr_sink s = {.fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666)};
    if (s.fd < 0) {
        res = eng_fail(err, ENG_ERR_IO, "%s: cannot create: %s", tmp, strerror(errno));
        free(tmp);
        return res;
    }

    current_sink = &s;
    exr_result_t rv = write_exr_stream(&s, path, bufs, count, meta);
    current_sink = NULL;
    if (s.write_errno)
        res = eng_fail(err, ENG_ERR_IO, "%s: %s", path, strerror(s.write_errno));
    else if (rv == EXR_ERR_OUT_OF_MEMORY)
        res = eng_fail(err, ENG_ERR_NOMEM, "%s: OpenEXR: out of memory", path);
    else if (rv != EXR_ERR_SUCCESS)
        res = eng_fail(err, ENG_ERR_IO, "%s: OpenEXR: %s", path,
                       s.lib_code != EXR_ERR_SUCCESS ? s.lib_msg : exr_get_default_error_message(rv));
    else if (fsync(s.fd) != 0)
        res = eng_fail(err, ENG_ERR_IO, "%s: cannot sync: %s", path, strerror(errno));

    /* close() can be where a deferred write error (NFS, quota) finally shows. */
    if (close(s.fd) != 0 && res == ENG_OK)
        res = eng_fail(err, ENG_ERR_IO, "%s: %s", path, strerror(errno));
    if (res == ENG_OK && rename(tmp, path) != 0)
        res = eng_fail(err, ENG_ERR_IO, "%s: cannot rename %s into place: %s", path, tmp, strerror(errno));
    if (res != ENG_OK)
        unlink(tmp);
    free(tmp);
    return res;
}

eng_result cap_write_exr(const char *path, const eng_buffer *const *bufs, int count, eng_error *err)
{
    return cap__write_exr(path, bufs, count, NULL, err);
}
