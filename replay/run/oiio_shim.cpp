// oiio_shim.cpp — replay's only C++: multi-part EXR reading and writing through OpenImageIO,
// behind the C header oiio_shim.h.
//
// Every entry point catches all exceptions and turns them, like OpenImageIO's own error
// strings, into one-line eng_error messages that name the file (and the part, where one is
// known). Errors are always retrieved from OIIO (ImageInput::geterror / OIIO::geterror) so that
// none is left pending to be printed at exit. Decoded pixels are handed over in malloc'd
// storage owned by the caller; nothing here keeps state between calls.
#include "oiio_shim.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

namespace {

char *dup_string(const std::string &s)
{
    char *p = static_cast<char *>(std::malloc(s.size() + 1));
    if (!p)
        throw std::bad_alloc();
    std::memcpy(p, s.c_str(), s.size() + 1);
    return p;
}

void free_part(rep_part &p)
{
    std::free(p.name);
    for (int c = 0; c < ENG_MAX_CHANNELS; c++)
        std::free(p.channels[c]);
    std::free(p.data);
    std::memset(&p, 0, sizeof p);
}

// Owns parts until they are released to the caller, so every early return frees them.
struct PartList {
    std::vector<rep_part> parts;
    ~PartList()
    {
        for (rep_part &p : parts)
            free_part(p);
    }
};

std::string pending(OIIO::ImageInput *in)
{
    std::string m = in ? in->geterror() : std::string();
    std::string g = OIIO::geterror();
    if (m.empty())
        return g.empty() ? std::string("unknown OpenImageIO error") : g;
    return m;
}

// Frame files hold many small parts: decoding each on OpenImageIO's and OpenEXR's thread
// pools costs a thread start and join per part (slow, and very slow under ASan) for no gain.
// Replay decodes on the calling thread; the results do not depend on it.
// Replay's own threads may decode several files at once (each through its own ImageInput).
void single_threaded_decode()
{
    static std::once_flag once;
    std::call_once(once, [] {
        OIIO::attribute("threads", 1);
        OIIO::attribute("exr_threads", -1); // -1: no OpenEXR thread pool at all
    });
}

eng_result read_parts(const char *path, size_t max_floats, rep_part **out, int *count, eng_error *err)
{
    single_threaded_decode();
    eng_result hr = rep_exr_check_header(path, err); // exr_check.c
    if (hr != ENG_OK)
        return hr;
    std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(path);
    if (!in)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot open as an image: %s", path, pending(nullptr).c_str());
    if (std::strcmp(in->format_name(), "openexr") != 0) {
        std::string fmt = in->format_name();
        in->close();
        return eng_fail(err, ENG_ERR_INVALID, "%s: not an OpenEXR file (OpenImageIO reads it as %s)",
                        path, fmt.c_str());
    }
    PartList list;
    for (int s = 0; in->seek_subimage(s, 0); s++) {
        if (s >= REP_MAX_PARTS)
            return eng_fail(err, ENG_ERR_INVALID, "%s: more than %d parts", path, REP_MAX_PARTS);
        const OIIO::ImageSpec spec = in->spec();
        std::string name = spec.get_string_attribute("oiio:subimagename");
        if (name.empty())
            return eng_fail(err, ENG_ERR_INVALID, "%s: part %d has no name", path, s);
        const char *pn = name.c_str();
        if (spec.deep || spec.depth != 1)
            return eng_fail(err, ENG_ERR_INVALID, "%s: part %s: deep or volume images are not buffers", path, pn);
        if (spec.width < 1 || spec.height < 1 || spec.nchannels < 1)
            return eng_fail(err, ENG_ERR_INVALID, "%s: part %s: empty image (%dx%d, %d channels)", path, pn,
                            spec.width, spec.height, spec.nchannels);
        if (spec.nchannels > ENG_MAX_CHANNELS)
            return eng_fail(err, ENG_ERR_INVALID, "%s: part %s: %d channels, more than the %d allowed", path,
                            pn, spec.nchannels, ENG_MAX_CHANNELS);
        size_t floats = (size_t)spec.width * (size_t)spec.height * (size_t)spec.nchannels;
        if ((size_t)spec.width > max_floats || (size_t)spec.height > max_floats || floats > max_floats)
            return eng_fail(err, ENG_ERR_INVALID, "%s: part %s: %dx%dx%d floats, more than the %zu allowed",
                            path, pn, spec.width, spec.height, spec.nchannels, max_floats);
        list.parts.push_back(rep_part());
        rep_part &p = list.parts.back();
        std::memset(&p, 0, sizeof p);
        p.name = dup_string(name);
        p.width = spec.width;
        p.height = spec.height;
        p.channel_count = spec.nchannels;
        for (int c = 0; c < spec.nchannels; c++) {
            std::string cn = c < (int)spec.channelnames.size() ? spec.channelnames[(size_t)c] : std::string();
            if (cn.empty())
                return eng_fail(err, ENG_ERR_INVALID, "%s: part %s: channel %d has no name", path, pn, c);
            p.channels[c] = dup_string(cn);
        }
        p.data = static_cast<float *>(std::malloc(floats * sizeof(float)));
        if (!p.data)
            return eng_fail(err, ENG_ERR_NOMEM, "%s: part %s: out of memory for %zu floats", path, pn, floats);
        // All-float parts are read in their native format: OpenImageIO then decodes straight
        // into p.data instead of through a conversion buffer of up to 64 MB per call.
        bool all_float = spec.format == OIIO::TypeDesc::FLOAT &&
                         (spec.channelformats.empty() ||
                          std::all_of(spec.channelformats.begin(), spec.channelformats.end(),
                                      [](const OIIO::TypeDesc &t) { return t == OIIO::TypeDesc::FLOAT; }));
        if (!in->read_image(s, 0, 0, spec.nchannels, all_float ? OIIO::TypeDesc::UNKNOWN : OIIO::TypeDesc::FLOAT,
                            p.data))
            return eng_fail(err, ENG_ERR_IO, "%s: part %s: cannot decode pixels: %s", path, pn,
                            pending(in.get()).c_str());
    }
    // Running off the end of the subimages is how the loop stops; it is not an error, but a
    // failure to read a header on the way is.
    if (in->has_error())
        return eng_fail(err, ENG_ERR_IO, "%s: %s", path, pending(in.get()).c_str());
    OIIO::geterror();
    if (list.parts.empty())
        return eng_fail(err, ENG_ERR_INVALID, "%s: no parts", path);
    in->close();
    rep_part *arr = static_cast<rep_part *>(std::calloc(list.parts.size(), sizeof(rep_part)));
    if (!arr)
        throw std::bad_alloc();
    for (size_t i = 0; i < list.parts.size(); i++)
        arr[i] = list.parts[i];
    *count = (int)list.parts.size();
    list.parts.clear(); // ownership moved to arr
    *out = arr;
    return ENG_OK;
}

eng_result write_parts(const char *path, const eng_buffer *parts, int count, eng_error *err)
{
    if (count < 1)
        return eng_fail(err, ENG_ERR_INVALID, "%s: nothing to write (no parts)", path);
    std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
    if (!out)
        return eng_fail(err, ENG_ERR_IO, "%s: no EXR writer: %s", path, pending(nullptr).c_str());
    if (count > 1 && !out->supports("multiimage"))
        return eng_fail(err, ENG_ERR_UNSUPPORTED, "%s: writer cannot hold several parts", path);
    // OpenEXR requires every part of a multi-part file to share one display window; parts of
    // different sizes get the union as display window and their own size as data window.
    int full_w = 0, full_h = 0;
    for (int i = 0; i < count; i++) {
        full_w = parts[i].width > full_w ? parts[i].width : full_w;
        full_h = parts[i].height > full_h ? parts[i].height : full_h;
    }
    std::vector<OIIO::ImageSpec> specs((size_t)count);
    for (int i = 0; i < count; i++) {
        const eng_buffer &b = parts[i];
        if (b.channel_count < 1 || b.channel_count > ENG_MAX_CHANNELS || b.width < 1 || b.height < 1)
            return eng_fail(err, ENG_ERR_INVALID, "%s: part %s: bad shape %dx%d, %d channels", path, b.name,
                            b.width, b.height, b.channel_count);
        OIIO::ImageSpec &s = specs[(size_t)i];
        s = OIIO::ImageSpec(b.width, b.height, b.channel_count, OIIO::TypeDesc::FLOAT);
        s.full_x = s.full_y = 0;
        s.full_width = full_w;
        s.full_height = full_h;
        s.channelnames.clear();
        for (int c = 0; c < b.channel_count; c++)
            s.channelnames.push_back(b.channels[c]);
        // Buffers are data, not pictures: no channel is alpha or depth to OIIO.
        s.alpha_channel = -1;
        s.z_channel = -1;
        s.attribute("oiio:subimagename", b.name);
        s.attribute("compression", "zip");
    }
    if (!out->open(path, count, specs.data()))
        return eng_fail(err, ENG_ERR_IO, "%s: cannot create: %s", path, out->geterror().c_str());
    for (int i = 0; i < count; i++) {
        if (i > 0 && !out->open(path, specs[(size_t)i], OIIO::ImageOutput::AppendSubimage))
            return eng_fail(err, ENG_ERR_IO, "%s: part %s: %s", path, parts[i].name, out->geterror().c_str());
        if (!out->write_image(OIIO::TypeDesc::FLOAT, parts[i].data))
            return eng_fail(err, ENG_ERR_IO, "%s: part %s: %s", path, parts[i].name, out->geterror().c_str());
    }
    if (!out->close())
        return eng_fail(err, ENG_ERR_IO, "%s: cannot finish: %s", path, out->geterror().c_str());
    return ENG_OK;
}

} // namespace

extern "C" eng_result rep_oiio_read_parts(const char *path, size_t max_floats, rep_part **parts, int *count,
                                          eng_error *err)
{
    *parts = nullptr;
    *count = 0;
    try {
        return read_parts(path, max_floats, parts, count, err);
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

extern "C" eng_result rep_oiio_write_parts(const char *path, const eng_buffer *parts, int count, eng_error *err)
{
    try {
        return write_parts(path, parts, count, err);
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
