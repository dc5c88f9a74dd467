/* png_write.c — the report's PNG images written with libpng directly (rep_png_write,
 * rep_run.h), so that replay's HTML report does not load OpenImageIO (its ~260
 * shared libraries cost ~0.8 s of CPU, more than the images). The file holds what OpenImageIO
 * 2.4's PNG writer made from the same bytes before (png_shim.cpp; test_replay compares): 8-bit,
 * libpng's adaptive filters (so the same filtered rows), the sRGB chunk with its gAMA and cHRM
 * (absolute intent), a zero oFFs and the text "oiio:ColorSpace" = "sRGB", and no time or
 * software name, so the same pixels give the same bytes. Only the zlib level differs: 1, not
 * OpenImageIO's 6 (half the deflate time of a report's images, which are 12% larger). Grey or
 * RGB only (OpenImageIO would un-premultiply an alpha channel; the report has none). Written to
 * a temporary name and renamed by the caller.
 */
#include "rep_run.h"

#include <png.h>
#include <zlib.h>

#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>

/* libpng's error callback: keeps the message and unwinds to the setjmp in write_png. */
typedef struct png_err {
    char msg[200];
} png_err;

static void on_error(png_structp png, png_const_charp msg)
{
    png_err *e = png_get_error_ptr(png);
    snprintf(e->msg, sizeof e->msg, "%s", msg ? msg : "libpng error");
    png_longjmp(png, 1);
}

static void on_warning(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg;
}

/* The part of rep_png_write after fopen; 0 on success. Locals that live across setjmp are
 * volatile or unchanged after it. */
static int write_png(FILE *f, int w, int h, int nch, const unsigned char *pixels, png_err *e)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, e, on_error, on_warning);
    if (!png) {
        snprintf(e->msg, sizeof e->msg, "out of memory");
        return -1;
    }
    png_infop info = png_create_info_struct(png);
    if (!info || setjmp(png_jmpbuf(png))) {
        if (!info)
            snprintf(e->msg, sizeof e->msg, "out of memory");
        png_destroy_write_struct(&png, info ? &info : NULL);
        return -1;
    }
    png_init_io(png, f);
    png_set_compression_level(png, 1); /* see above */
    png_set_compression_strategy(png, Z_DEFAULT_STRATEGY);
    int type = nch == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB;
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, 8, type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_ABSOLUTE);
    png_set_oFFs(png, info, 0, 0, PNG_OFFSET_PIXEL);
    char key[] = "oiio:ColorSpace", value[] = "sRGB";
    png_text text = {.compression = PNG_TEXT_COMPRESSION_NONE, .key = key, .text = value};
    png_set_text(png, info, &text, 1);
    png_write_info(png, info);
    for (int y = 0; y < h; y++)
        png_write_row(png, pixels + (size_t)y * (size_t)w * (size_t)nch);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return 0;
}

eng_result rep_png_write(const char *path, int w, int h, int nch, const unsigned char *pixels, eng_error *err)
{
    if (w < 1 || h < 1 || (nch != 1 && nch != 3) || !pixels)
        return eng_fail(err, ENG_ERR_INVALID, "%s: bad thumbnail shape %dx%d, %d channels", path, w, h, nch);
    FILE *f = fopen(path, "wb");
    if (!f)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot create", path);
    png_err e = {{0}};
    int bad = write_png(f, w, h, nch, pixels, &e);
    if (fclose(f) != 0 && !bad) {
        bad = 1;
        snprintf(e.msg, sizeof e.msg, "cannot finish writing");
    }
    if (bad)
        return eng_fail(err, ENG_ERR_IO, "%s: %s", path, e.msg);
    return ENG_OK;
}
