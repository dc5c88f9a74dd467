/* oiio_shim.h — the C face of replay's one C++ file (oiio_shim.cpp), which hides OpenImageIO.
 *
 * A frame file is a multi-part EXR, one part per buffer, the part name being the buffer name.
 * The reader decodes every part into float32 (interleaved, top row first, the eng_buffer
 * layout) and owns nothing after returning: the caller owns the parts array and frees it with
 * rep_parts_free. The writer exists so that tests (and tools) can make fixture runs without
 * the capture module. No C++ exception crosses this header; every failure is an eng_result
 * with a one-line message naming the file. The C++ lives in the module libispm_oiio.so, which
 * oiio_lazy.c loads on the first call (so that programs and commands that never read or write
 * an image through OpenImageIO, `ispm record`, do not pay its ~240 libraries' start-up); a
 * module that cannot be loaded is an ENG_ERR_IO naming the file and the module.
 */
#ifndef ISPM_REP_OIIO_SHIM_H
#define ISPM_REP_OIIO_SHIM_H

#include <stddef.h>

#include "eng_core.h"

#ifdef __cplusplus
extern "C" {
#endif

/* At most this many parts in one frame file; more is taken for a corrupt or hostile file. */
#define REP_MAX_PARTS 4096

/* One decoded EXR part. Channel names are in the order OpenImageIO presents them, which need
 * not be the order they were written in: compare channels by name, never by position. */
typedef struct rep_part {
    char *name;
    int width, height;
    int channel_count; /* 1..ENG_MAX_CHANNELS */
    char *channels[ENG_MAX_CHANNELS];
    float *data;       /* width*height*channel_count floats, interleaved, top row first */
} rep_part;

/* Reads every part of the EXR at path. Refuses (ENG_ERR_INVALID) a file that is not
 * OpenEXR, a deep or volume part, a part without a name, more than ENG_MAX_CHANNELS channels
 * or more than max_floats floats in one part (checked before allocating, so a lying header
 * cannot exhaust memory). A missing, truncated or undecodable file is ENG_ERR_IO. On failure
 * *parts is NULL and *count 0. */
eng_result rep_oiio_read_parts(const char *path, size_t max_floats, rep_part **parts, int *count,
                               eng_error *err);

void rep_parts_free(rep_part *parts, int count);
/* Frees what one part owns and zeroes it (for a part that is not in an array of its own). */
void rep_part_clear(rep_part *p);

/* Reads every part of a frame file as rep_oiio_read_parts does, and gives the same parts (names,
 * channel names in OpenImageIO's order, bit-identical floats), but through OpenEXR's C API
 * (exr_read.c) when the file is one that reader takes (scanline float32 parts at the origin),
 * so that reading a run needs no OpenImageIO; any other file, and any file that reader fails
 * on, goes to rep_oiio_read_parts, which decides (so errors are OpenImageIO's, as before). The
 * reader every tool and replay use for frame files. */
eng_result rep_read_parts(const char *path, size_t max_floats, rep_part **parts, int *count, eng_error *err);

/* A check of a frame's parts from their headers alone (names, sizes, channels; data NULL),
 * before any pixel is decoded or its memory taken: non-OK stops the read with that result. */
typedef eng_result (*rep_parts_check)(void *user, const char *path, const rep_part *heads, int count,
                                      eng_error *err);
/* rep_read_parts with check run on the OpenEXR C API reader's headers (a file that reader leaves
 * goes to OpenImageIO unchecked, within max_floats a part). */
eng_result rep_read_parts_checked(const char *path, size_t max_floats, rep_parts_check check, void *user,
                                  rep_part **parts, int *count, eng_error *err);

/* rep_read_parts keeping only the parts named in only[0..only_n-1] (file order; the others' headers
 * are checked, their pixels not decoded): a frame's buffers stored in an earlier frame's file. */
eng_result rep_read_parts_only(const char *path, size_t max_floats, const char *const *only, int only_n,
                               rep_part **parts, int *count, eng_error *err);
/* The OpenEXR C API reader alone: ENG_OK with the parts as above; ENG_ERR_UNSUPPORTED (err says
 * why) for a file it leaves to OpenImageIO (tiled, deep, non-float, subsampled or offset parts,
 * limits exceeded, or an error while decoding); or rep_exr_check_header's refusal. */
eng_result rep_exr_read_parts(const char *path, size_t max_floats, rep_part **parts, int *count, eng_error *err);
/* The order in which the readers present n distinct channel names (OpenImageIO's): order[c] is
 * the index in names of the c-th channel presented. */
void rep_exr_channel_order(const char *const *names, int n, int *order);

/* Walks the header(s) of the EXR at path before any library parses them (exr_check.c): refuses
 * (ENG_ERR_INVALID, or ENG_ERR_IO when truncated) attributes, chunk counts, data windows or
 * channel pixel types the file cannot hold, which OpenEXR 3.1 would believe (allocating
 * gigabytes) or OpenImageIO 2.4 would abort on. Missing and non-EXR files pass (ENG_OK). */
eng_result rep_exr_check_header(const char *path, eng_error *err);

/* Loads the OpenImageIO module now (the other calls load it on first use). A program that opens
 * a window calls this first: some of the libraries OpenImageIO pulls in initialise Xlib's
 * threading when they load, which breaks an X connection opened before (ispm-view died with
 * "XIO: fatal IO error" when the module came after SDL's window). */
eng_result rep_oiio_load(eng_error *err);

/* Writes count buffers as a multi-part float32 ZIP-compressed EXR, part i named parts[i].name
 * with parts[i]'s channel names. Overwrites path. */
eng_result rep_oiio_write_parts(const char *path, const eng_buffer *parts, int count, eng_error *err);

/* Writes an 8-bit image (width*height*channel_count bytes, interleaved, top row first;
 * channel_count 1, 3 or 4) as a PNG at path, whatever path's extension (so that a temporary
 * name can be renamed into place). Implemented in png_shim.cpp. Overwrites path. */
eng_result rep_oiio_write_png(const char *path, int width, int height, int channel_count,
                              const unsigned char *pixels, eng_error *err);

/* Reads any 8-bit-representable image OpenImageIO can open (PNG charts and thumbnails, for
 * tests and tools) as width*height*channel_count bytes, top row first; caller frees. */
eng_result rep_oiio_read_image8(const char *path, int *width, int *height, int *channel_count,
                                unsigned char **pixels, eng_error *err);

/* A borrowed eng_buffer view of a part (valid while the part lives). */
static inline eng_buffer rep_part_buffer(const rep_part *p)
{
    eng_buffer b;
    b.name = p->name;
    b.width = p->width;
    b.height = p->height;
    b.channel_count = p->channel_count;
    b.channels = (const char *const *)p->channels;
    b.data = p->data;
    return b;
}

#ifdef __cplusplus
}
#endif

#endif
