// png_shim.cpp — the report's thumbnails leave replay as PNG files through OpenImageIO, behind
// the C header oiio_shim.h (rep_oiio_write_png).
//
// The writer is asked for by format name ("png"), not by the file's extension, so the caller
// can write to a temporary name and rename it into place (readers never see half a PNG). No
// metadata that varies between runs (time, host, software version) is written, so the same
// pixels give the same bytes. Like oiio_shim.cpp, every exception and every OIIO error string
// becomes a one-line eng_error naming the file, and no OIIO error is left pending.
#include "oiio_shim.h"

#include <cstdlib>
#include <memory>
#include <new>
#include <string>

#include <OpenImageIO/imageio.h>

namespace {

eng_result write_png(const char *path, int w, int h, int nch, const unsigned char *pixels, eng_error *err)
{
    if (w < 1 || h < 1 || (nch != 1 && nch != 3 && nch != 4) || !pixels)
        return eng_fail(err, ENG_ERR_INVALID, "%s: bad thumbnail shape %dx%d, %d channels", path, w, h, nch);
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create("png");
    if (!out) {
        std::string e = OIIO::geterror();
        return eng_fail(err, ENG_ERR_IO, "%s: no PNG writer: %s", path, e.c_str());
    }
    OIIO::ImageSpec spec(w, h, nch, OIIO::TypeDesc::UINT8);
    spec.alpha_channel = nch == 4 ? 3 : -1;
    // Already display-encoded bytes: tag them sRGB so that viewers do not re-encode them.
    spec.attribute("oiio:ColorSpace", "sRGB");
    if (!out->open(path, spec))
        return eng_fail(err, ENG_ERR_IO, "%s: cannot create: %s", path, out->geterror().c_str());
    if (!out->write_image(OIIO::TypeDesc::UINT8, pixels))
        return eng_fail(err, ENG_ERR_IO, "%s: cannot write: %s", path, out->geterror().c_str());
    if (!out->close())
        return eng_fail(err, ENG_ERR_IO, "%s: cannot finish: %s", path, out->geterror().c_str());
    return ENG_OK;
}

eng_result read_image8(const char *path, int *w, int *h, int *nch, unsigned char **pixels, eng_error *err)
{
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in) {
        std::string e = OIIO::geterror();
        return eng_fail(err, ENG_ERR_IO, "%s: cannot open: %s", path, e.c_str());
    }
    const OIIO::ImageSpec &spec = in->spec();
    if (spec.width < 1 || spec.height < 1 || spec.nchannels < 1 || spec.nchannels > 4 ||
        (long long)spec.width * spec.height > (1LL << 26))
        return eng_fail(err, ENG_ERR_INVALID, "%s: unexpected image shape %dx%d, %d channels", path, spec.width,
                        spec.height, spec.nchannels);
    size_t n = (size_t)spec.width * (size_t)spec.height * (size_t)spec.nchannels;
    unsigned char *px = (unsigned char *)malloc(n);
    if (!px)
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory", path);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, px)) {
        free(px);
        return eng_fail(err, ENG_ERR_IO, "%s: cannot read: %s", path, in->geterror().c_str());
    }
    *w = spec.width;
    *h = spec.height;
    *nch = spec.nchannels;
    *pixels = px;
    return ENG_OK;
}

} // namespace

extern "C" eng_result rep_oiio_read_image8(const char *path, int *width, int *height, int *channel_count,
                                           unsigned char **pixels, eng_error *err)
{
    *pixels = NULL;
    try {
        return read_image8(path, width, height, channel_count, pixels, err);
    } catch (const std::bad_alloc &) {
        OIIO::geterror();
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory while reading", path);
    } catch (const std::exception &e) {
        OIIO::geterror();
        return eng_fail(err, ENG_ERR_IO, "%s: %s", path, e.what());
    } catch (...) {
        OIIO::geterror();
        return eng_fail(err, ENG_ERR_IO, "%s: unknown error while reading", path);
    }
}

extern "C" eng_result rep_oiio_write_png(const char *path, int width, int height, int channel_count,
                                         const unsigned char *pixels, eng_error *err)
{
    try {
        return write_png(path, width, height, channel_count, pixels, err);
    } catch (const std::bad_alloc &) {
        OIIO::geterror();
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory while writing", path);
    } catch (const std::exception &e) {
        OIIO::geterror();
        return eng_fail(err, ENG_ERR_IO, "%s: %s", path, e.what());
    } catch (...) {
        OIIO::geterror();
        return eng_fail(err, ENG_ERR_IO, "%s: unknown error while writing", path);
    }
}
