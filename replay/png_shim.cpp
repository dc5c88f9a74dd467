// png_shim.cpp — the report's thumbnails leave replay as PNG files through OpenImageIO, behind
// the C header oiio_shim.h (rep_oiio_write_png).
//
// The writer is asked for by format name ("png"), not by the file's extension, so the caller
// can write to a temporary name and rename it into place (readers never see half a PNG). No
// metadata that varies between runs (time, host, software version) is written, so the same
// pixels give the same bytes. Like oiio_shim.cpp, every exception and every OIIO error string
// becomes a one-line eng_error naming the file, and no OIIO error is left pending.
#include "oiio_shim.h"

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

} // namespace

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
