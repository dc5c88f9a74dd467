/* exr_planes.h — decoding an EXR part through OpenEXR's C API into caller-laid-out planes,
 * shared by capture's recompression (cap_recompress_exr) and replay's frame reader
 * (replay/run/exr_read.c), so that one loop drives OpenEXR's decoding pipeline for both. */
#ifndef CAP_EXR_PLANES_H
#define CAP_EXR_PLANES_H

#include <openexr.h>
#include <stdint.h>

/* Where one channel's samples live: row y, column x is at base + (y - y0) * line_stride +
 * x * pixel_stride (x from the data window's left edge), in the channel's own type. */
typedef struct cap_exr_plane {
    const char *name;
    const uint8_t *base;
    int32_t pixel_stride, line_stride;
    int16_t bytes; /* 2 (HALF) or 4 */
    uint16_t type; /* exr_pixel_type_t */
} cap_exr_plane;

/* Decodes every scanline chunk of part `part` (rows y0 .. y0 + height - 1, width samples a
 * row) into planes[0..n-1], each coding channel found by name (the planes are the caller's to
 * write). A chunk outside those rows, a channel of another size or without a plane is
 * EXR_ERR_INVALID_ARGUMENT (the file disagrees with itself); else the library's result. */
exr_result_t cap_exr_decode_part(exr_context_t ctxt, int part, int y0, int height, int width,
                                 const cap_exr_plane *planes, int n);

#endif
