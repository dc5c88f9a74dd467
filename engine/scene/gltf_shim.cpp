/* gltf_shim.cpp — the engine's only C++: tinygltf behind the C ABI of gltf_shim.h.
 *
 * Debian ships tinygltf's implementation in libtinygltf.so (built with nlohmann-json and
 * stb_image, no Draco), so this file includes <tiny_gltf.h> without TINYGLTF_IMPLEMENTATION.
 * Nothing we could define changes the class layout: TINYGLTF_USE_CPP14 and the JSON backend
 * only affect the implementation half of the header, and the image-loader members are
 * function pointers either way. We define none of them.
 *
 * What the shim does beyond copying fields out:
 *   - images are decoded by tinygltf's own loader (stb_image, as Debian builds it) to RGBA of
 *     8 or 16 bits; an image it cannot decode fails the load with its message;
 *   - external files are looked up only in the glTF's own folder (tinygltf would also try the
 *     process's working directory, which makes a load depend on where it ran), and a URI may
 *     not leave it (exists_in_folder);
 *   - tinygltf's failure is sorted into I/O, syntax and structure by the text it reports
 *     (it has no error codes); the texts are those of tinygltf 2.7 and nlohmann-json 3.
 *     Only nlohmann's parse_error is syntax: its out_of_range (a number such as 1e999 that
 *     no double holds) is well-formed JSON with a wrong value, so structure;
 *   - KHR_draco_mesh_compression: tinygltf 2.7 (Debian, no Draco) refuses a Draco primitive's
 *     indices accessor, which has no bufferView. prepare points that accessor at the
 *     Draco bufferView in a copy of the JSON (GLB re-packed around it) so that tinygltf parses
 *     the rest; draco_decode then undoes it, decodes each Draco primitive with draco::Decoder
 *     and appends the decoded arrays as a new buffer, with one buffer view per accessor, in the
 *     accessor's own componentType and type. gltf_load.c then reads them like any accessor;
 *   - an indices accessor without a bufferView (all zeros, glTF §3.6.2.1), which tinygltf 2.7
 *     refuses: after that refusal the file is parsed again with such accessors pointed at a
 *     placeholder view (patch_zero_indices), which unzero_indices removes again;
 *   - EXT_meshopt_compression / KHR_meshopt_compression (meshoptimizer, Debian's
 *     libmeshoptimizer): meshopt_patch points each compressed bufferView at its compressed
 *     bytes in a copy of the JSON (and gives a data-less fallback buffer one byte), so that
 *     tinygltf parses the file; meshopt_decode then decodes each view (vertex or index codec,
 *     then its filter) into a buffer of its own and points the view back there;
 *   - every exception stops here.
 * The gls_impl owns the tinygltf::Model and the C arrays that point into it. */
#include "gltf_shim.h"
#include "gltf_precheck.h"

#include <tiny_gltf.h>
#include <draco/compression/decode.h>
#include <meshoptimizer.h>
#include <nlohmann/json.hpp>
#include <webp/decode.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <deque>
#include <algorithm>
#include <climits>
#include <iterator>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <new>
#include <string>
#include <vector>

static_assert(GLS_COMPONENT_BYTE == TINYGLTF_COMPONENT_TYPE_BYTE, "component");
static_assert(GLS_COMPONENT_UNSIGNED_BYTE == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, "component");
static_assert(GLS_COMPONENT_SHORT == TINYGLTF_COMPONENT_TYPE_SHORT, "component");
static_assert(GLS_COMPONENT_UNSIGNED_SHORT == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT, "component");
static_assert(GLS_COMPONENT_UNSIGNED_INT == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, "component");
static_assert(GLS_COMPONENT_FLOAT == TINYGLTF_COMPONENT_TYPE_FLOAT, "component");
static_assert(GLS_TYPE_VEC2 == TINYGLTF_TYPE_VEC2 && GLS_TYPE_VEC3 == TINYGLTF_TYPE_VEC3 &&
                  GLS_TYPE_VEC4 == TINYGLTF_TYPE_VEC4 && GLS_TYPE_MAT2 == TINYGLTF_TYPE_MAT2 &&
                  GLS_TYPE_MAT3 == TINYGLTF_TYPE_MAT3 && GLS_TYPE_MAT4 == TINYGLTF_TYPE_MAT4 &&
                  GLS_TYPE_SCALAR == TINYGLTF_TYPE_SCALAR,
              "type");

struct gls_impl {
    tinygltf::Model model;
    std::vector<gls_buffer> buffers;
    std::vector<gls_buffer_view> views;
    std::vector<gls_accessor> accessors;
    std::vector<std::vector<gls_attribute>> attributes; /* one per primitive */
    std::vector<std::vector<gls_primitive>> primitives; /* one per mesh */
    std::vector<std::vector<gls_attribute>> target_attributes; /* one per morph target */
    std::vector<std::vector<gls_target>> targets;              /* one per primitive */
    std::vector<gls_skin> skins;
    std::vector<gls_mesh> meshes;
    std::vector<gls_node> nodes;
    std::vector<gls_camera> cameras;
    std::vector<gls_light> lights;
    std::vector<gls_material> materials;
    std::vector<gls_image> images;
    std::vector<std::vector<unsigned char>> image_bytes; /* encoded, as the file stores them */
    std::vector<int> image_state;                        /* 0 not tried, 1 decoded, -1 failed */
    std::vector<tinygltf::Image> decoded;                /* pixels of the decoded images */
    std::vector<std::string> image_error;                /* why an image failed */
    std::vector<gls_texture> textures;
    std::vector<gls_tex_sampler> tex_samplers;
    std::deque<std::vector<double>> numbers; /* extension arrays (a deque: never moves them) */
    std::vector<std::vector<gls_channel>> channels;
    std::vector<std::vector<gls_sampler>> samplers;
    std::vector<gls_animation> animations;
    std::vector<gls_scene> scenes;
    std::vector<const char *> ext_required, ext_used;
    gls_model view;
};

namespace {

struct fs_scope {
    std::string prefix;      /* "<folder>/" as the glTF's path names it */
    std::string real_prefix; /* realpath(folder) + "/" ("" if it cannot be resolved) */
    std::string error;       /* the first URI refused, in one line */
    gls_status status;
    uint64_t max_external;   /* the largest external file read (gltf_precheck.h) */
};

bool starts_with_data(const std::string &uri)
{
    return uri.compare(0, 5, "data:") == 0;
}

void refuse(fs_scope *scope, gls_status status, const std::string &text)
{
    if (scope->error.empty()) {
        scope->error = text;
        scope->status = status;
    }
}

/* tinygltf asks for <search path>/<uri> (URI already %-decoded), first with the glTF's
 * folder, then with ".". Only the first is ours; a URI must name a regular file inside the
 * folder: not absolute, no ".." segment, no symbolic link that resolves outside. Each
 * refusal is remembered with its reason, since tinygltf only says "File not found". */
bool exists_in_folder(const std::string &abs, void *user)
{
    fs_scope *scope = static_cast<fs_scope *>(user);
    if (abs.compare(0, scope->prefix.size(), scope->prefix) != 0)
        return false;
    const std::string uri = abs.substr(scope->prefix.size());
    if (starts_with_data(uri))
        return true; /* a data URI tinygltf does not know (read_whole decodes it) */
    const std::string shown = "URI \"" + (uri.size() > 120 ? uri.substr(0, 120) + "..." : uri) + "\"";
    if (uri.empty()) {
        refuse(scope, GLS_ERR_GLTF, "an empty URI (a buffer without uri outside a GLB has no data)");
        return false;
    }
    if (uri[0] == '/') {
        refuse(scope, GLS_ERR_GLTF, shown + " is an absolute path; files must lie in the glTF's folder");
        return false;
    }
    for (size_t at = 0; at <= uri.size();) {
        size_t end = uri.find_first_of("/\\", at);
        if (end == std::string::npos)
            end = uri.size();
        if (uri.compare(at, end - at, "..") == 0 && end - at == 2) {
            refuse(scope, GLS_ERR_GLTF, shown + " leaves the glTF's folder (\"..\")");
            return false;
        }
        at = end + 1;
    }
    struct stat st;
    if (stat(abs.c_str(), &st) != 0) {
        if (errno == ENOENT || errno == ENOTDIR)
            refuse(scope, GLS_ERR_IO, shown + ": no such file beside the glTF");
        else
            refuse(scope, GLS_ERR_IO, shown + ": " + std::strerror(errno));
        return false;
    }
    if (S_ISDIR(st.st_mode)) {
        refuse(scope, GLS_ERR_GLTF, shown + " is a directory, not a file");
        return false;
    }
    if (!S_ISREG(st.st_mode)) {
        refuse(scope, GLS_ERR_GLTF, shown + " is not a regular file");
        return false;
    }
    char *real = realpath(abs.c_str(), nullptr);
    bool inside = real && !scope->real_prefix.empty() &&
                  std::strncmp(real, scope->real_prefix.c_str(), scope->real_prefix.size()) == 0;
    std::free(real);
    if (!inside) {
        refuse(scope, GLS_ERR_GLTF, shown + " is a symbolic link that leads out of the glTF's folder");
        return false;
    }
    return true;
}

std::string expand(const std::string &p, void *) { return tinygltf::ExpandFilePath(p, nullptr); }

/* An external file, opened as every input is (eng_open_input) and refused over the largest
 * size the glTF's buffers can need before a byte is read. */
bool read_bounded(std::vector<unsigned char> *out, std::string *err, const std::string &p, void *user)
{
    fs_scope *scope = static_cast<fs_scope *>(user);
    eng_error e;
    int fd;
    uint64_t size;
    if (eng_open_input(p.c_str(), 0, scope->max_external, &fd, &size, &e) != ENG_OK) {
        refuse(scope, GLS_ERR_GLTF, e.msg);
        if (err)
            *err = e.msg;
        return false;
    }
    out->resize(static_cast<size_t>(size));
    size_t got = 0;
    while (got < size) {
        ssize_t n = ::read(fd, out->data() + got, static_cast<size_t>(size) - got);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            break;
        got += static_cast<size_t>(n);
    }
    ::close(fd);
    if (got != size) {
        refuse(scope, GLS_ERR_IO, p + ": short read");
        if (err)
            *err = p + ": short read";
        return false;
    }
    return true;
}

/* A base64 data URI of a media type tinygltf does not list (data:image/webp, ...) reaches the
 * file callbacks as "<folder>/data:...", %-decoded, its '+' turned into ' '. Decodes its
 * payload; false where it is not base64. */
bool decode_data_uri(const std::string &uri, std::vector<unsigned char> *out)
{
    const size_t comma = uri.find(',');
    if (comma == std::string::npos || comma < 7 || uri.compare(comma - 7, 7, ";base64") != 0)
        return false;
    uint32_t acc = 0;
    int bits = 0;
    size_t k = comma + 1;
    for (; k < uri.size() && uri[k] != '='; k++) {
        const char c = uri[k] == ' ' ? '+' : uri[k];
        int v = c >= 'A' && c <= 'Z' ? c - 'A' : c >= 'a' && c <= 'z' ? c - 'a' + 26 : c >= '0' && c <= '9' ? c - '0' + 52
              : c == '+' ? 62 : c == '/' ? 63 : -1;
        if (v < 0)
            return false;
        acc = (acc << 6) | static_cast<uint32_t>(v);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out->push_back(static_cast<unsigned char>(acc >> bits));
        }
    }
    for (; k < uri.size(); k++)
        if (uri[k] != '=')
            return false;
    return true;
}

/* A data URI of a media type tinygltf does not list is decoded here; any other file goes to
 * read_bounded. */
bool read_whole(std::vector<unsigned char> *out, std::string *err, const std::string &p, void *user)
{
    const fs_scope *scope = static_cast<const fs_scope *>(user);
    if (p.compare(0, scope->prefix.size(), scope->prefix) == 0 && starts_with_data(p.substr(scope->prefix.size()))) {
        out->clear();
        if (decode_data_uri(p.substr(scope->prefix.size()), out))
            return true;
        if (err)
            *err += "a data URI that is not base64\n";
        return false;
    }
    return read_bounded(out, err, p, user);
}

bool write_whole(std::string *err, const std::string &p, const std::vector<unsigned char> &c, void *)
{
    return tinygltf::WriteWholeFile(err, p, c, nullptr);
}

gls_doubles doubles(const std::vector<double> &v)
{
    gls_doubles d;
    d.len = static_cast<uint32_t>(v.size());
    d.v = v.data();
    return d;
}

/* obj.member as a number: absent, present, or NOT_A_NUMBER (also when obj is no object). */
gls_number member_number(const tinygltf::Value &obj, const char *member)
{
    gls_number n = {GLS_NUM_ABSENT, 0.0};
    if (!obj.IsObject()) {
        n.state = GLS_NUM_NOT_A_NUMBER;
        return n;
    }
    if (!obj.Has(member))
        return n;
    const tinygltf::Value &v = obj.Get(member);
    if (!v.IsNumber()) {
        n.state = GLS_NUM_NOT_A_NUMBER;
        return n;
    }
    n.state = GLS_NUM_PRESENT;
    n.value = v.GetNumberAsDouble();
    return n;
}

/* ext_name.member of an extension map; *has tells whether ext_name was there at all. */
gls_number ext_number(const tinygltf::ExtensionMap &ext, const char *ext_name, const char *member,
                      int *has)
{
    auto it = ext.find(ext_name);
    if (has)
        *has = it != ext.end();
    if (it == ext.end())
        return gls_number{GLS_NUM_ABSENT, 0.0};
    return member_number(it->second, member);
}

/* extras.<group>.<member> of a glTF object's extras, in the states of ext_number. */
gls_number extras_number(const tinygltf::Value &extras, const char *group, const char *member)
{
    if (!extras.IsObject() || !extras.Has(group))
        return gls_number{GLS_NUM_ABSENT, 0.0};
    return member_number(extras.Get(group), member);
}

bool starts_with(const std::string &s, const char *prefix)
{
    return std::strncmp(s.c_str(), prefix, std::strlen(prefix)) == 0;
}

/* KHR_texture_transform's vec2 member as doubles kept in g.numbers (len 0: absent or not
 * an array of numbers, which the loader then refuses by length). */
gls_doubles ext_vec(gls_impl &g, const tinygltf::Value &obj, const char *member)
{
    gls_doubles d = {0, nullptr};
    if (!obj.IsObject() || !obj.Has(member))
        return d;
    const tinygltf::Value &v = obj.Get(member);
    std::vector<double> out;
    if (v.IsArray())
        for (size_t i = 0; i < v.ArrayLen(); i++)
            out.push_back(v.Get(static_cast<int>(i)).IsNumber() ? v.Get(static_cast<int>(i)).GetNumberAsDouble()
                                                                 : NAN);
    else
        out.push_back(NAN);
    g.numbers.push_back(std::move(out));
    d.len = static_cast<uint32_t>(g.numbers.back().size());
    d.v = g.numbers.back().data();
    return d;
}

gls_texinfo texinfo(gls_impl &g, int index, int texcoord, const tinygltf::ExtensionMap &ext)
{
    gls_texinfo t;
    std::memset(&t, 0, sizeof t);
    t.index = index;
    t.texcoord = texcoord;
    t.strength = 1.0;
    t.rotation = ext_number(ext, "KHR_texture_transform", "rotation", &t.has_transform);
    t.transform_texcoord = ext_number(ext, "KHR_texture_transform", "texCoord", nullptr);
    auto it = ext.find("KHR_texture_transform");
    if (it != ext.end()) {
        t.offset = ext_vec(g, it->second, "offset");
        t.scale = ext_vec(g, it->second, "scale");
    }
    return t;
}

/* The ExtensionMap form of a textureInfo's "extensions" member kept as a Value. */
tinygltf::ExtensionMap extension_map(const tinygltf::Value &obj)
{
    tinygltf::ExtensionMap map;
    if (obj.IsObject() && obj.Has("extensions") && obj.Get("extensions").IsObject()) {
        const tinygltf::Value &e = obj.Get("extensions");
        for (const std::string &k : e.Keys())
            map[k] = e.Get(k);
    }
    return map;
}

/* The extension object ext_name of an extension map, or nullptr. */
const tinygltf::Value *ext_object(const tinygltf::ExtensionMap &ext, const char *ext_name)
{
    auto it = ext.find(ext_name);
    return it == ext.end() ? nullptr : &it->second;
}

/* obj.member as a textureInfo (index, texCoord, KHR_texture_transform): index -1 where
 * absent, -2 where the member is not an object with an integer index. */
gls_texinfo ext_texinfo(gls_impl &g, const tinygltf::Value *obj, const char *member)
{
    gls_texinfo t;
    std::memset(&t, 0, sizeof t);
    t.index = -1;
    t.strength = 1.0;
    if (!obj || !obj->IsObject() || !obj->Has(member))
        return t;
    const tinygltf::Value &v = obj->Get(member);
    if (!v.IsObject() || !v.Has("index") || !v.Get("index").IsInt() || v.Get("index").GetNumberAsInt() < 0) {
        t.index = -2;
        return t;
    }
    int texcoord = 0;
    if (v.Has("texCoord") && v.Get("texCoord").IsInt())
        texcoord = v.Get("texCoord").GetNumberAsInt();
    else if (v.Has("texCoord"))
        texcoord = -1;
    return texinfo(g, v.Get("index").GetNumberAsInt(), texcoord, extension_map(v));
}

/* tinygltf's image callback: keeps the encoded bytes; gls_decode_image decodes on demand, so
 * an image no drawn material uses is never decoded and cannot fail the load. */
bool keep_image(tinygltf::Image *image, const int index, std::string *, std::string *, int, int,
                const unsigned char *bytes, int size, void *user)
{
    gls_impl *g = static_cast<gls_impl *>(user);
    if (index < 0)
        return false;
    const size_t i = static_cast<size_t>(index);
    if (g->image_bytes.size() <= i)
        g->image_bytes.resize(i + 1);
    g->image_bytes[i].assign(bytes, bytes + (size > 0 ? size : 0));
    image->image.clear();
    return true;
}

gls_status classify(const std::string &err)
{
    static const char *const io[] = {"File not found", "File read error", "File is empty"};
    static const char *const syntax[] = {
        "[json.exception.parse_error", "JSON string too short", "Root element is not a JSON object",
        "\"asset\" object not found", "Too short data size for glTF Binary", "Invalid magic",
        "Invalid glTF binary", "JSON Chunk end", "Insufficient storage space for Chunk1",
        "Insufficient Chunk1", "BIN Chunk", "Invalid type for chunk1"};
    for (size_t i = 0; i < sizeof io / sizeof io[0]; i++)
        if (std::strstr(err.c_str(), io[i]))
            return GLS_ERR_IO;
    for (size_t i = 0; i < sizeof syntax / sizeof syntax[0]; i++)
        if (starts_with(err, syntax[i]))
            return GLS_ERR_SYNTAX;
    return GLS_ERR_GLTF;
}

void set_msg(char *msg, size_t size, const std::string &text)
{
    if (!msg || size == 0)
        return;
    std::string one;
    for (char c : text)
        one += (c == '\n' || c == '\r') ? ' ' : c;
    while (!one.empty() && one.back() == ' ')
        one.pop_back();
    std::snprintf(msg, size, "%s", one.empty() ? "tinygltf failed without a message" : one.c_str());
}

void build_view(gls_impl &g)
{
    const tinygltf::Model &m = g.model;

    for (const tinygltf::Buffer &b : m.buffers) {
        gls_buffer c;
        c.data = b.data.data();
        c.size = b.data.size();
        c.external = !b.uri.empty() && !starts_with(b.uri, "data:");
        g.buffers.push_back(c);
    }
    for (const tinygltf::BufferView &v : m.bufferViews)
        g.views.push_back({v.buffer, v.byteOffset, v.byteLength, v.byteStride});
    for (const tinygltf::Accessor &a : m.accessors) {
        gls_accessor c = {a.bufferView, a.byteOffset, a.componentType, a.type, a.count,
                          a.normalized ? 1 : 0, a.sparse.isSparse ? 1 : 0, 0, -1, 0, -1, 0, 0};
        if (a.sparse.isSparse) {
            c.sparse_count = a.sparse.count < 0 ? 0 : static_cast<uint64_t>(a.sparse.count);
            c.sparse_index_view = a.sparse.indices.bufferView;
            c.sparse_index_type = a.sparse.indices.componentType;
            c.sparse_index_offset = a.sparse.indices.byteOffset < 0 ? UINT64_MAX
                                                                    : static_cast<uint64_t>(a.sparse.indices.byteOffset);
            c.sparse_value_view = a.sparse.values.bufferView;
            c.sparse_value_offset = a.sparse.values.byteOffset < 0 ? UINT64_MAX
                                                                   : static_cast<uint64_t>(a.sparse.values.byteOffset);
        }
        g.accessors.push_back(c);
    }

    /* Inner arrays first, so the outer ones never reallocate under a pointer. */
    g.attributes.reserve(m.meshes.size() * 4);
    for (const tinygltf::Mesh &mesh : m.meshes)
        for (const tinygltf::Primitive &p : mesh.primitives) {
            std::vector<gls_attribute> attrs;
            for (const auto &kv : p.attributes)
                attrs.push_back({kv.first.c_str(), kv.second});
            g.attributes.push_back(std::move(attrs));
            for (const auto &t : p.targets) {
                std::vector<gls_attribute> ta;
                for (const auto &kv : t)
                    ta.push_back({kv.first.c_str(), kv.second});
                g.target_attributes.push_back(std::move(ta));
            }
        }
    size_t tk = 0;
    for (const tinygltf::Mesh &mesh : m.meshes)
        for (const tinygltf::Primitive &p : mesh.primitives) {
            std::vector<gls_target> ts;
            for (size_t t = 0; t < p.targets.size(); t++, tk++)
                ts.push_back({static_cast<uint32_t>(g.target_attributes[tk].size()), g.target_attributes[tk].data()});
            g.targets.push_back(std::move(ts));
        }
    size_t k = 0;
    for (const tinygltf::Mesh &mesh : m.meshes) {
        std::vector<gls_primitive> prims;
        for (const tinygltf::Primitive &p : mesh.primitives) {
            const std::vector<gls_target> &ts = g.targets[k];
            const std::vector<gls_attribute> &attrs = g.attributes[k++];
            prims.push_back({p.mode, p.indices, p.material, static_cast<uint32_t>(attrs.size()),
                             attrs.data(), static_cast<uint32_t>(ts.size()), ts.data()});
        }
        g.primitives.push_back(std::move(prims));
    }
    for (size_t i = 0; i < m.meshes.size(); i++)
        g.meshes.push_back({m.meshes[i].name.c_str(), static_cast<uint32_t>(g.primitives[i].size()),
                            g.primitives[i].data(), doubles(m.meshes[i].weights)});
    for (const tinygltf::Skin &sk : m.skins)
        g.skins.push_back({sk.name.c_str(), sk.inverseBindMatrices, sk.skeleton,
                           static_cast<uint32_t>(sk.joints.size()), sk.joints.data()});

    for (const tinygltf::Node &n : m.nodes) {
        gls_node c;
        c.name = n.name.c_str();
        c.mesh = n.mesh;
        c.camera = n.camera;
        c.skin = n.skin;
        c.light = ext_number(n.extensions, "KHR_lights_punctual", "light", &c.has_light);
        c.child_count = static_cast<uint32_t>(n.children.size());
        c.children = n.children.data();
        c.translation = doubles(n.translation);
        c.rotation = doubles(n.rotation);
        c.scale = doubles(n.scale);
        c.matrix = doubles(n.matrix);
        c.weights = doubles(n.weights);
        g.nodes.push_back(c);
    }
    for (const tinygltf::Camera &c : m.cameras)
        g.cameras.push_back({c.name.c_str(), c.type.c_str(), c.perspective.yfov,
                             c.perspective.aspectRatio, c.perspective.znear, c.perspective.zfar});
    for (const tinygltf::Light &l : m.lights)
        g.lights.push_back({l.name.c_str(), l.type.c_str(), doubles(l.color), l.intensity, l.range,
                            l.spot.innerConeAngle, l.spot.outerConeAngle,
                            extras_number(l.extras, "ispm", "radius"),
                            extras_number(l.extras, "ispm", "angular_radius")});
    for (const tinygltf::Material &mat : m.materials) {
        gls_material c;
        c.name = mat.name.c_str();
        const tinygltf::PbrMetallicRoughness &pbr = mat.pbrMetallicRoughness;
        c.base_color_texture = texinfo(g, pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord,
                                       pbr.baseColorTexture.extensions);
        c.metallic_roughness_texture = texinfo(g, pbr.metallicRoughnessTexture.index,
                                               pbr.metallicRoughnessTexture.texCoord,
                                               pbr.metallicRoughnessTexture.extensions);
        c.normal_texture = texinfo(g, mat.normalTexture.index, mat.normalTexture.texCoord, mat.normalTexture.extensions);
        c.normal_texture.strength = mat.normalTexture.scale;
        c.occlusion_texture = texinfo(g, mat.occlusionTexture.index, mat.occlusionTexture.texCoord,
                                      mat.occlusionTexture.extensions);
        c.occlusion_texture.strength = mat.occlusionTexture.strength;
        c.emissive_texture = texinfo(g, mat.emissiveTexture.index, mat.emissiveTexture.texCoord,
                                     mat.emissiveTexture.extensions);
        c.alpha_mode = mat.alphaMode.c_str();
        c.alpha_cutoff = mat.alphaCutoff;
        c.base_color = doubles(mat.pbrMetallicRoughness.baseColorFactor);
        c.metallic = mat.pbrMetallicRoughness.metallicFactor;
        c.roughness = mat.pbrMetallicRoughness.roughnessFactor;
        c.emissive = doubles(mat.emissiveFactor);
        c.double_sided = mat.doubleSided ? 1 : 0;
        c.transmission = ext_number(mat.extensions, "KHR_materials_transmission",
                                    "transmissionFactor", nullptr);
        c.ior = ext_number(mat.extensions, "KHR_materials_ior", "ior", nullptr);
        c.emissive_strength = ext_number(mat.extensions, "KHR_materials_emissive_strength", "emissiveStrength",
                                         nullptr);
        c.transmission_texture =
            ext_texinfo(g, ext_object(mat.extensions, "KHR_materials_transmission"), "transmissionTexture");
        c.unlit = ext_object(mat.extensions, "KHR_materials_unlit") != nullptr;
        const tinygltf::Value *sg = ext_object(mat.extensions, "KHR_materials_pbrSpecularGlossiness");
        c.spec_gloss = sg != nullptr;
        c.diffuse_factor = sg ? ext_vec(g, *sg, "diffuseFactor") : gls_doubles{0, nullptr};
        c.specular_factor = sg ? ext_vec(g, *sg, "specularFactor") : gls_doubles{0, nullptr};
        c.glossiness = sg ? member_number(*sg, "glossinessFactor") : gls_number{GLS_NUM_ABSENT, 0.0};
        c.diffuse_texture = ext_texinfo(g, sg, "diffuseTexture");
        c.spec_gloss_texture = ext_texinfo(g, sg, "specularGlossinessTexture");
        g.materials.push_back(c);
    }

    g.image_bytes.resize(m.images.size());
    g.image_state.assign(m.images.size(), 0);
    g.decoded.resize(m.images.size());
    g.image_error.resize(m.images.size());
    for (size_t i = 0; i < m.images.size(); i++)
        g.images.push_back({m.images[i].uri.c_str(), m.images[i].mimeType.c_str(), !g.image_bytes[i].empty()});
    for (const tinygltf::Texture &t : m.textures) {
        int webp = -1;
        if (const tinygltf::Value *w = ext_object(t.extensions, "EXT_texture_webp"))
            webp = w->IsObject() && w->Has("source") && w->Get("source").IsInt() && w->Get("source").GetNumberAsInt() >= 0
                       ? w->Get("source").GetNumberAsInt()
                       : -2;
        g.textures.push_back({t.source, t.sampler, webp});
    }
    for (const tinygltf::Sampler &t : m.samplers)
        g.tex_samplers.push_back({t.magFilter, t.minFilter, t.wrapS, t.wrapT});

    for (const tinygltf::Animation &a : m.animations) {
        std::vector<gls_channel> chans;
        for (const tinygltf::AnimationChannel &ch : a.channels)
            chans.push_back({ch.sampler, ch.target_node, ch.target_path.c_str()});
        g.channels.push_back(std::move(chans));
        std::vector<gls_sampler> samps;
        for (const tinygltf::AnimationSampler &s : a.samplers)
            samps.push_back({s.input, s.output, s.interpolation.c_str()});
        g.samplers.push_back(std::move(samps));
    }
    for (size_t i = 0; i < m.animations.size(); i++)
        g.animations.push_back({m.animations[i].name.c_str(),
                                static_cast<uint32_t>(g.channels[i].size()), g.channels[i].data(),
                                static_cast<uint32_t>(g.samplers[i].size()), g.samplers[i].data()});

    for (const tinygltf::Scene &s : m.scenes)
        g.scenes.push_back({s.name.c_str(), static_cast<uint32_t>(s.nodes.size()), s.nodes.data()});
    for (const std::string &e : m.extensionsRequired)
        g.ext_required.push_back(e.c_str());
    for (const std::string &e : m.extensionsUsed)
        g.ext_used.push_back(e.c_str());

    gls_model &v = g.view;
    v.buffer_count = static_cast<uint32_t>(g.buffers.size());
    v.buffers = g.buffers.data();
    v.buffer_view_count = static_cast<uint32_t>(g.views.size());
    v.buffer_views = g.views.data();
    v.accessor_count = static_cast<uint32_t>(g.accessors.size());
    v.accessors = g.accessors.data();
    v.mesh_count = static_cast<uint32_t>(g.meshes.size());
    v.meshes = g.meshes.data();
    v.node_count = static_cast<uint32_t>(g.nodes.size());
    v.nodes = g.nodes.data();
    v.camera_count = static_cast<uint32_t>(g.cameras.size());
    v.cameras = g.cameras.data();
    v.light_count = static_cast<uint32_t>(g.lights.size());
    v.lights = g.lights.data();
    v.material_count = static_cast<uint32_t>(g.materials.size());
    v.materials = g.materials.data();
    v.image_count = static_cast<uint32_t>(g.images.size());
    v.images = g.images.data();
    v.texture_count = static_cast<uint32_t>(g.textures.size());
    v.textures = g.textures.data();
    v.tex_sampler_count = static_cast<uint32_t>(g.tex_samplers.size());
    v.tex_samplers = g.tex_samplers.data();
    v.animation_count = static_cast<uint32_t>(g.animations.size());
    v.animations = g.animations.data();
    v.scene_count = static_cast<uint32_t>(g.scenes.size());
    v.scenes = g.scenes.data();
    v.skin_count = static_cast<uint32_t>(g.skins.size());
    v.skins = g.skins.data();
    v.default_scene = m.defaultScene;
    v.extensions_required_count = static_cast<uint32_t>(g.ext_required.size());
    v.extensions_required = g.ext_required.data();
    v.extensions_used_count = static_cast<uint32_t>(g.ext_used.size());
    v.extensions_used = g.ext_used.data();
    v.impl = &g;
}

const char DRACO[] = "KHR_draco_mesh_compression";

/* ---- KHR_draco_mesh_compression */

using json = nlohmann::json;

uint32_t le32(const unsigned char *p)
{
    return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 | static_cast<uint32_t>(p[2]) << 16 |
           static_cast<uint32_t>(p[3]) << 24;
}

void put_le32(std::vector<unsigned char> &out, uint32_t v)
{
    for (int k = 0; k < 4; k++)
        out.push_back(static_cast<unsigned char>(v >> (8 * k)));
}

/* What a compressed-geometry decoder throws: the one line naming the view or primitive. */
struct decode_error {
    std::string text;
};

struct draco_error : decode_error {
};

[[noreturn]] void draco_fail(const std::string &where, const std::string &what)
{
    throw draco_error{{where + ": " + DRACO + ": " + what}};
}

/* "mesh 2 ("name") primitive 0", as messages name a primitive. */
std::string primitive_where(size_t mi, size_t pi, const std::string &name)
{
    std::string where = "mesh " + std::to_string(mi);
    if (!name.empty())
        where += " (\"" + name.substr(0, 80) + "\")";
    return where + " primitive " + std::to_string(pi);
}

/* In the JSON j, every Draco primitive's indices accessor that lacks a bufferView gets the
 * primitive's Draco bufferView (tinygltf 2.7 refuses an indices accessor without one; the
 * accessor's own data is never read). Returns the accessors so patched. A Draco extension
 * without an existing bufferView throws draco_error here (tinygltf would only complain about
 * the accessor); anything else malformed is left for tinygltf and draco_decode to report. */
std::vector<int> patch_indices(json &j)
{
    std::vector<int> patched;
    if (!j.is_object() || !j.contains("meshes") || !j["meshes"].is_array() || !j.contains("accessors") ||
        !j["accessors"].is_array())
        return patched;
    json &acc = j["accessors"];
    const size_t views = j.contains("bufferViews") && j["bufferViews"].is_array() ? j["bufferViews"].size() : 0;
    for (size_t mi = 0; mi < j["meshes"].size(); mi++) {
        json &mesh = j["meshes"][mi];
        if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
            continue;
        for (size_t pi = 0; pi < mesh["primitives"].size(); pi++) {
            json &p = mesh["primitives"][pi];
            if (!p.is_object() || !p.contains("extensions") || !p["extensions"].is_object() ||
                !p["extensions"].contains(DRACO))
                continue;
            const json &ext = p["extensions"][DRACO];
            const std::string name = mesh.contains("name") && mesh["name"].is_string() ? mesh["name"].get<std::string>() : "";
            if (!ext.is_object() || !ext.contains("bufferView") || !ext["bufferView"].is_number_unsigned())
                draco_fail(primitive_where(mi, pi, name), "no bufferView (a non-negative integer)");
            if (ext["bufferView"].get<uint64_t>() >= views)
                draco_fail(primitive_where(mi, pi, name),
                           "bufferView " + std::to_string(ext["bufferView"].get<uint64_t>()) + " does not exist");
            if (!p.contains("indices") || !p["indices"].is_number_unsigned())
                continue;
            uint64_t i = p["indices"].get<uint64_t>();
            if (i >= acc.size() || !acc[i].is_object() || acc[i].contains("bufferView"))
                continue;
            acc[i]["bufferView"] = ext["bufferView"];
            patched.push_back(static_cast<int>(i));
        }
    }
    return patched;
}

/* In the JSON j, every primitive's indices accessor without a bufferView (all zeros, glTF
 * §3.6.2.1; tinygltf 2.7 refuses it) gets a placeholder bufferView of one byte, appended with
 * a one-byte data-URI buffer of its own, so that tinygltf parses the file. Returns the
 * accessors so patched; unzero_indices undoes it. */
std::vector<int> patch_zero_indices(json &j)
{
    std::vector<int> patched;
    if (!j.is_object() || !j.contains("meshes") || !j["meshes"].is_array() || !j.contains("accessors") ||
        !j["accessors"].is_array())
        return patched;
    if ((j.contains("bufferViews") && !j["bufferViews"].is_array()) || (j.contains("buffers") && !j["buffers"].is_array()))
        return patched;
    json &acc = j["accessors"];
    const size_t view = j.contains("bufferViews") ? j["bufferViews"].size() : 0;
    const size_t buffer = j.contains("buffers") ? j["buffers"].size() : 0;
    for (json &mesh : j["meshes"]) {
        if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
            continue;
        for (json &p : mesh["primitives"]) {
            if (!p.is_object() || !p.contains("indices") || !p["indices"].is_number_unsigned())
                continue;
            uint64_t i = p["indices"].get<uint64_t>();
            if (i >= acc.size() || !acc[i].is_object() || acc[i].contains("bufferView"))
                continue;
            acc[i]["bufferView"] = view;
            patched.push_back(static_cast<int>(i));
        }
    }
    if (!patched.empty()) {
        j["buffers"].push_back({{"byteLength", 1}, {"uri", "data:application/octet-stream;base64,AA=="}});
        j["bufferViews"].push_back({{"buffer", buffer}, {"byteLength", 1}});
    }
    return patched;
}

/* Undoes patch_zero_indices: the accessors lose their bufferView again (read as zeros) and the
 * placeholder view and buffer, the last of each, go. */
void unzero_indices(tinygltf::Model &m, const std::vector<int> &patched)
{
    if (patched.empty())
        return;
    for (int i : patched)
        if (static_cast<size_t>(i) < m.accessors.size())
            m.accessors[static_cast<size_t>(i)].bufferView = -1;
    if (!m.bufferViews.empty())
        m.bufferViews.pop_back();
    if (!m.buffers.empty())
        m.buffers.pop_back();
}

/* ---- EXT_meshopt_compression / KHR_meshopt_compression */

struct meshopt_error : decode_error {
};

/* A compressed bufferView as the file gave it: where its compressed bytes are (the
 * extension's buffer range) and what it decodes to (count elements of byteStride bytes). */
struct meshopt_view {
    int view;
    std::string ext; /* which of the two extensions */
    int buffer;
    uint64_t offset, length, stride, count;
    std::string mode, filter;
    bool has_view_stride;
    uint64_t view_stride, view_length;
};

[[noreturn]] void meshopt_fail(size_t view, const std::string &ext, const std::string &what)
{
    throw meshopt_error{{"bufferView " + std::to_string(view) + ": " + ext + ": " + what}};
}

uint64_t meshopt_uint(const json &o, const char *key, size_t view, const std::string &ext, bool required,
                      uint64_t fallback)
{
    if (!o.contains(key)) {
        if (required)
            meshopt_fail(view, ext, std::string("no ") + key);
        return fallback;
    }
    if (!o[key].is_number_unsigned())
        meshopt_fail(view, ext, std::string(key) + " is not a non-negative integer");
    return o[key].get<uint64_t>();
}

/* Points every compressed bufferView at its compressed bytes, so that tinygltf reads the
 * file (meshopt_decode puts the decoded bytes back), and gives each fallback buffer without
 * a URI (it holds no data) one byte of data URI, since tinygltf refuses a buffer without one. */
std::vector<meshopt_view> meshopt_patch(json &j)
{
    std::vector<meshopt_view> out;
    if (!j.contains("bufferViews") || !j["bufferViews"].is_array())
        return out;
    json &views = j["bufferViews"];
    for (size_t vi = 0; vi < views.size(); vi++) {
        json &v = views[vi];
        if (!v.is_object() || !v.contains("extensions") || !v["extensions"].is_object())
            continue;
        for (const char *name : {"EXT_meshopt_compression", "KHR_meshopt_compression"}) {
            if (!v["extensions"].contains(name))
                continue;
            const json &e = v["extensions"][name];
            if (!e.is_object())
                meshopt_fail(vi, name, "not an object");
            meshopt_view m;
            m.view = static_cast<int>(vi);
            m.ext = name;
            m.buffer = static_cast<int>(meshopt_uint(e, "buffer", vi, name, true, 0) & 0x7fffffff);
            m.offset = meshopt_uint(e, "byteOffset", vi, name, false, 0);
            m.length = meshopt_uint(e, "byteLength", vi, name, true, 0);
            m.stride = meshopt_uint(e, "byteStride", vi, name, true, 0);
            m.count = meshopt_uint(e, "count", vi, name, true, 0);
            if (!e.contains("mode") || !e["mode"].is_string())
                meshopt_fail(vi, name, "no mode");
            m.mode = e["mode"].get<std::string>();
            m.filter = e.contains("filter") && e["filter"].is_string() ? e["filter"].get<std::string>() : "NONE";
            m.has_view_stride = v.contains("byteStride");
            m.view_stride = m.has_view_stride && v["byteStride"].is_number_unsigned() ? v["byteStride"].get<uint64_t>() : 0;
            m.view_length = v.contains("byteLength") && v["byteLength"].is_number_unsigned() ? v["byteLength"].get<uint64_t>() : 0;
            v["buffer"] = m.buffer;
            v["byteOffset"] = m.offset;
            v["byteLength"] = m.length;
            v.erase("byteStride");
            out.push_back(m);
            break;
        }
    }
    if (out.empty() || !j.contains("buffers") || !j["buffers"].is_array())
        return out;
    for (json &b : j["buffers"]) {
        if (!b.is_object() || b.contains("uri") || !b.contains("extensions") || !b["extensions"].is_object())
            continue;
        for (const char *name : {"EXT_meshopt_compression", "KHR_meshopt_compression"})
            if (b["extensions"].contains(name) && b["extensions"][name].is_object() &&
                b["extensions"][name].contains("fallback") && b["extensions"][name]["fallback"] == true) {
                b["uri"] = "data:application/octet-stream;base64,AA==";
                b["byteLength"] = 1;
            }
    }
    return out;
}

/* Decodes every compressed bufferView (meshopt_patch) into a buffer of its own, filters
 * applied, and points the view there with its own byteStride back. Throws meshopt_error
 * naming the view. */
void meshopt_decode(tinygltf::Model &m, const std::vector<meshopt_view> &views)
{
    for (const meshopt_view &mv : views) {
        const size_t vi = static_cast<size_t>(mv.view);
        if (vi >= m.bufferViews.size())
            continue;
        if (mv.buffer < 0 || static_cast<size_t>(mv.buffer) >= m.buffers.size())
            meshopt_fail(vi, mv.ext, "buffer " + std::to_string(mv.buffer) + " does not exist");
        const std::vector<unsigned char> &src = m.buffers[static_cast<size_t>(mv.buffer)].data;
        if (mv.offset > src.size() || mv.length > src.size() - mv.offset)
            meshopt_fail(vi, mv.ext, "bytes " + std::to_string(mv.offset) + "+" + std::to_string(mv.length) +
                                         " lie outside buffer " + std::to_string(mv.buffer) + " (" +
                                         std::to_string(src.size()) + " bytes)");
        const bool attributes = mv.mode == "ATTRIBUTES";
        const bool triangles = mv.mode == "TRIANGLES";
        if (!attributes && !triangles && mv.mode != "INDICES")
            meshopt_fail(vi, mv.ext, "mode \"" + mv.mode.substr(0, 40) + "\" is not ATTRIBUTES, TRIANGLES or INDICES");
        if (attributes ? (mv.stride == 0 || mv.stride % 4 != 0 || mv.stride > 256) : (mv.stride != 2 && mv.stride != 4))
            meshopt_fail(vi, mv.ext, "byteStride " + std::to_string(mv.stride) + " does not fit mode " + mv.mode);
        if (triangles && mv.count % 3 != 0)
            meshopt_fail(vi, mv.ext, "count " + std::to_string(mv.count) + " of TRIANGLES is not a multiple of 3");
        if (mv.count > (uint64_t(1) << 30) / mv.stride)
            meshopt_fail(vi, mv.ext, "count " + std::to_string(mv.count) + " x byteStride is over 1 GiB");
        tinygltf::Buffer out;
        out.data.resize(mv.count * mv.stride);
        const unsigned char *in = src.data() + mv.offset;
        int rc = attributes ? meshopt_decodeVertexBuffer(out.data.data(), mv.count, mv.stride, in, mv.length)
                 : triangles ? meshopt_decodeIndexBuffer(out.data.data(), mv.count, mv.stride, in, mv.length)
                             : meshopt_decodeIndexSequence(out.data.data(), mv.count, mv.stride, in, mv.length);
        if (rc != 0)
            meshopt_fail(vi, mv.ext, "the compressed data does not decode (meshoptimizer " +
                                         std::to_string(MESHOPTIMIZER_VERSION / 100) + "." +
                                         std::to_string(MESHOPTIMIZER_VERSION % 100) + ": error " +
                                         std::to_string(rc) + ")");
        if (mv.filter == "OCTAHEDRAL") {
            if (!attributes || (mv.stride != 4 && mv.stride != 8))
                meshopt_fail(vi, mv.ext, "filter OCTAHEDRAL needs ATTRIBUTES of byteStride 4 or 8");
            meshopt_decodeFilterOct(out.data.data(), mv.count, mv.stride);
        } else if (mv.filter == "QUATERNION") {
            if (!attributes || mv.stride != 8)
                meshopt_fail(vi, mv.ext, "filter QUATERNION needs ATTRIBUTES of byteStride 8");
            meshopt_decodeFilterQuat(out.data.data(), mv.count, mv.stride);
        } else if (mv.filter == "EXPONENTIAL") {
            if (!attributes)
                meshopt_fail(vi, mv.ext, "filter EXPONENTIAL needs ATTRIBUTES");
            meshopt_decodeFilterExp(out.data.data(), mv.count, mv.stride);
        } else if (mv.filter != "NONE") {
            meshopt_fail(vi, mv.ext, "filter \"" + mv.filter.substr(0, 40) + "\" is not supported");
        }
        tinygltf::BufferView &v = m.bufferViews[vi];
        if (mv.view_length > out.data.size())
            meshopt_fail(vi, mv.ext, "the bufferView's byteLength " + std::to_string(mv.view_length) +
                                         " is more than the " + std::to_string(out.data.size()) + " bytes decoded");
        v.buffer = static_cast<int>(m.buffers.size());
        v.byteOffset = 0;
        v.byteLength = mv.view_length ? mv.view_length : out.data.size();
        v.byteStride = mv.has_view_stride ? mv.view_stride : 0;
        m.buffers.push_back(std::move(out));
    }
}

/* The JSON chunk of a GLB (or the whole of a JSON glTF): false where the GLB header is
 * malformed (tinygltf then says so). */
bool json_range(const unsigned char *b, size_t len, bool *glb, size_t *at, size_t *n)
{
    *glb = len >= 4 && std::memcmp(b, "glTF", 4) == 0;
    *at = 0;
    *n = len;
    if (*glb) {
        if (len < 20 || le32(b + 16) != 0x4E4F534Au || le32(b + 12) > len - 20)
            return false;
        *at = 20;
        *n = le32(b + 12);
    }
    return true;
}

/* The bytes tinygltf should parse: the JSON glTF, or the GLB with its JSON chunk, after
 * Draco's (patch_indices), meshopt's (meshopt_patch) and zero indices' (patch_zero_indices)
 * patches. Returns false (and leaves
 * *out empty) where nothing needed patching or the input is too malformed to patch; tinygltf
 * then reads the original bytes. */
bool prepare(const unsigned char *b, size_t len, bool draco, bool meshopt, bool zero_indices,
             std::vector<unsigned char> *out, std::vector<int> *patched, std::vector<meshopt_view> *views,
             std::vector<int> *zeroed)
{
    bool glb;
    size_t json_at, json_len;
    if (!json_range(b, len, &glb, &json_at, &json_len))
        return false;
    json j = json::parse(b + json_at, b + json_at + json_len, nullptr, false);
    if (j.is_discarded() || !j.is_object())
        return false;
    if (draco)
        *patched = patch_indices(j);
    if (meshopt)
        *views = meshopt_patch(j);
    if (zero_indices)
        *zeroed = patch_zero_indices(j);
    if (patched->empty() && views->empty() && zeroed->empty())
        return false;
    std::string text;
    try {
        text = j.dump();
    } catch (const json::exception &) { /* a string that is not UTF-8: leave it to tinygltf */
        patched->clear();
        views->clear();
        zeroed->clear();
        return false;
    }
    if (!glb) {
        out->assign(text.begin(), text.end());
        return true;
    }
    while (text.size() % 4)
        text += ' ';
    const size_t rest = json_at + json_len; /* the BIN chunk, if any, as it was */
    const size_t total = 20 + text.size() + (len - rest);
    if (total > UINT32_MAX) {
        patched->clear();
        views->clear();
        zeroed->clear();
        return false;
    }
    out->assign(b, b + 12);
    out->resize(8);
    put_le32(*out, static_cast<uint32_t>(total));
    put_le32(*out, static_cast<uint32_t>(text.size()));
    put_le32(*out, 0x4E4F534Au);
    out->insert(out->end(), text.begin(), text.end());
    out->insert(out->end(), b + rest, b + len);
    return true;
}

int component_count(int type)
{
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    default: return 0;
    }
}

template <typename T> void append_value(std::vector<unsigned char> &out, T v)
{
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, &v, sizeof v);
    out.insert(out.end(), raw, raw + sizeof raw);
}

template <typename T>
bool append_attribute(std::vector<unsigned char> &out, const draco::PointAttribute &a, uint32_t points, int n)
{
    T v[4];
    for (uint32_t i = 0; i < points; i++) {
        if (!a.ConvertValue<T>(a.mapped_index(draco::PointIndex(i)), static_cast<int8_t>(n), v))
            return false;
        for (int k = 0; k < n; k++)
            append_value(out, v[k]);
    }
    return true;
}


/* Writes accessor a's decoded values (attribute att, one per point) at the end of out. */
void decode_attribute(const std::string &where, const std::string &semantic, const tinygltf::Accessor &a,
                      int index, const draco::PointAttribute &att, uint32_t points, std::vector<unsigned char> &out)
{
    const std::string acc = "accessor " + std::to_string(index) + " (" + semantic + ")";
    const int n = component_count(a.type);
    if (n == 0 || n != att.num_components())
        draco_fail(where, acc + " has " + std::to_string(n) + " components per element, the Draco attribute " +
                              std::to_string(att.num_components()));
    if (a.count != points)
        draco_fail(where, acc + " has count " + std::to_string(a.count) + ", the Draco data " +
                              std::to_string(points) + " points");
    bool ok;
    switch (a.componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: ok = append_attribute<float>(out, att, points, n); break;
    case TINYGLTF_COMPONENT_TYPE_BYTE: ok = append_attribute<int8_t>(out, att, points, n); break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: ok = append_attribute<uint8_t>(out, att, points, n); break;
    case TINYGLTF_COMPONENT_TYPE_SHORT: ok = append_attribute<int16_t>(out, att, points, n); break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: ok = append_attribute<uint16_t>(out, att, points, n); break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: ok = append_attribute<uint32_t>(out, att, points, n); break;
    default: ok = false;
    }
    if (!ok)
        draco_fail(where, acc + ": the Draco attribute does not convert to componentType " +
                              std::to_string(a.componentType));
}

/* The faces as indices in the indices accessor's componentType. */
void decode_indices(const std::string &where, const tinygltf::Accessor &a, int index, const draco::Mesh &mesh,
                    std::vector<unsigned char> &out)
{
    const std::string acc = "accessor " + std::to_string(index) + " (indices)";
    const uint64_t want = 3 * static_cast<uint64_t>(mesh.num_faces());
    if (a.type != TINYGLTF_TYPE_SCALAR)
        draco_fail(where, acc + " is not SCALAR");
    if (a.count != want)
        draco_fail(where, acc + " has count " + std::to_string(a.count) + ", the Draco data " +
                              std::to_string(mesh.num_faces()) + " triangles (" + std::to_string(want) + " indices)");
    const uint32_t limit = a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE    ? 0xFFu
                           : a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 0xFFFFu
                           : a.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT   ? 0xFFFFFFFFu
                                                                                       : 0;
    if (limit == 0)
        draco_fail(where, acc + " is not UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT");
    for (draco::FaceIndex f(0); f < mesh.num_faces(); ++f)
        for (int k = 0; k < 3; k++) {
            const uint32_t v = mesh.face(f)[k].value();
            if (v >= mesh.num_points() || v > limit)
                draco_fail(where, "decoded index " + std::to_string(v) + " does not fit " + acc);
            if (limit == 0xFFu)
                append_value(out, static_cast<uint8_t>(v));
            else if (limit == 0xFFFFu)
                append_value(out, static_cast<uint16_t>(v));
            else
                append_value(out, v);
        }
}

/* Decodes one Draco primitive into a new buffer (one view per accessor) and points its
 * accessors there. Throws draco_error naming the mesh and primitive. */
void decode_primitive(tinygltf::Model &m, size_t mi, size_t pi)
{
    const tinygltf::Primitive &p = m.meshes[mi].primitives[pi];
    const std::string where = primitive_where(mi, pi, m.meshes[mi].name);
    const tinygltf::Value &ext = p.extensions.at(DRACO);
    if (!ext.IsObject() || !ext.Has("bufferView") || !ext.Get("bufferView").IsInt())
        draco_fail(where, "no integer bufferView");
    const int bv = ext.Get("bufferView").GetNumberAsInt();
    if (bv < 0 || static_cast<size_t>(bv) >= m.bufferViews.size())
        draco_fail(where, "bufferView " + std::to_string(bv) + " does not exist");
    const tinygltf::BufferView &view = m.bufferViews[static_cast<size_t>(bv)];
    if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= m.buffers.size() ||
        view.byteOffset > m.buffers[static_cast<size_t>(view.buffer)].data.size() ||
        view.byteLength > m.buffers[static_cast<size_t>(view.buffer)].data.size() - view.byteOffset)
        draco_fail(where, "bufferView " + std::to_string(bv) + " lies outside its buffer");
    if (!ext.Has("attributes") || !ext.Get("attributes").IsObject())
        draco_fail(where, "no attributes object");
    if (p.indices < 0 || static_cast<size_t>(p.indices) >= m.accessors.size())
        draco_fail(where, "the primitive has no indices accessor");

    draco::DecoderBuffer in;
    in.Init(reinterpret_cast<const char *>(m.buffers[static_cast<size_t>(view.buffer)].data.data() + view.byteOffset),
            view.byteLength);
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&in);
    if (!decoded.ok())
        draco_fail(where, "bufferView " + std::to_string(bv) + " does not decode (" +
                              decoded.status().error_msg_string() + ")");
    std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
    if (!mesh)
        draco_fail(where, "bufferView " + std::to_string(bv) + " decodes to no mesh");

    /* The accessors to fill: the indices, then each attribute the extension maps. */
    std::vector<std::pair<int, std::vector<unsigned char>>> data;
    data.emplace_back(p.indices, std::vector<unsigned char>());
    decode_indices(where, m.accessors[static_cast<size_t>(p.indices)], p.indices, *mesh, data.back().second);
    const tinygltf::Value &attrs = ext.Get("attributes");
    for (const std::string &semantic : attrs.Keys()) {
        auto it = p.attributes.find(semantic);
        if (it == p.attributes.end())
            continue; /* compressed but not used by the primitive */
        const tinygltf::Value &id = attrs.Get(semantic);
        if (!id.IsInt() || id.GetNumberAsInt() < 0)
            draco_fail(where, "attribute " + semantic + " has no non-negative integer id");
        const draco::PointAttribute *att = mesh->GetAttributeByUniqueId(static_cast<uint32_t>(id.GetNumberAsInt()));
        if (!att)
            draco_fail(where, "attribute " + semantic + ": id " + std::to_string(id.GetNumberAsInt()) +
                                  " does not exist in the Draco data (" + std::to_string(mesh->num_attributes()) +
                                  " attributes)");
        if (it->second < 0 || static_cast<size_t>(it->second) >= m.accessors.size())
            draco_fail(where, "attribute " + semantic + ": accessor " + std::to_string(it->second) + " does not exist");
        data.emplace_back(it->second, std::vector<unsigned char>());
        decode_attribute(where, semantic, m.accessors[static_cast<size_t>(it->second)], it->second, *att,
                         mesh->num_points(), data.back().second);
    }
    /* An attribute the extension does not compress keeps its own data, but must agree. */
    for (const auto &kv : p.attributes)
        if (!attrs.Has(kv.first) && kv.second >= 0 && static_cast<size_t>(kv.second) < m.accessors.size() &&
            m.accessors[static_cast<size_t>(kv.second)].count != mesh->num_points())
            draco_fail(where, "accessor " + std::to_string(kv.second) + " (" + kv.first + ", not compressed) has count " +
                                  std::to_string(m.accessors[static_cast<size_t>(kv.second)].count) +
                                  ", the Draco data " + std::to_string(mesh->num_points()) + " points");

    tinygltf::Buffer buffer;
    for (auto &d : data) {
        while (buffer.data.size() % 4)
            buffer.data.push_back(0);
        tinygltf::BufferView v;
        v.buffer = static_cast<int>(m.buffers.size());
        v.byteOffset = buffer.data.size();
        v.byteLength = d.second.size();
        buffer.data.insert(buffer.data.end(), d.second.begin(), d.second.end());
        tinygltf::Accessor &a = m.accessors[static_cast<size_t>(d.first)];
        a.bufferView = static_cast<int>(m.bufferViews.size());
        a.byteOffset = 0;
        m.bufferViews.push_back(v);
    }
    m.buffers.push_back(std::move(buffer));
}

/* Undoes prepare's Draco patch, then decodes every TRIANGLES primitive with the extension
 * (another mode is left to gltf_load.c, which skips it). */
void draco_decode(tinygltf::Model &m, const std::vector<int> &patched)
{
    for (int i : patched)
        if (static_cast<size_t>(i) < m.accessors.size())
            m.accessors[static_cast<size_t>(i)].bufferView = -1;
    for (size_t mi = 0; mi < m.meshes.size(); mi++)
        for (size_t pi = 0; pi < m.meshes[mi].primitives.size(); pi++) {
            const tinygltf::Primitive &p = m.meshes[mi].primitives[pi];
            if (p.extensions.count(DRACO) && (p.mode == TINYGLTF_MODE_TRIANGLES || p.mode == -1))
                decode_primitive(m, mi, pi);
        }
}
gls_status load(const char *path, const void *bytes, size_t len, uint64_t max_external, gls_model **out, char *msg,
                size_t msg_size)
{
    if (len > UINT_MAX) {
        set_msg(msg, msg_size, "file too large for tinygltf");
        return GLS_ERR_GLTF;
    }
    std::string p(path ? path : "");
    size_t slash = p.find_last_of('/');
    fs_scope scope;
    std::string folder = slash == std::string::npos ? std::string(".") : p.substr(0, slash);
    scope.prefix = folder + "/";
    if (slash == 0) /* a file in / */
        folder = "/", scope.prefix = "/";
    scope.status = GLS_OK;
    scope.max_external = max_external;
    if (char *real = realpath(folder.c_str(), nullptr)) {
        scope.real_prefix = real;
        if (scope.real_prefix.empty() || scope.real_prefix.back() != '/')
            scope.real_prefix += '/';
        std::free(real);
    }

    std::unique_ptr<gls_impl> g(new gls_impl());
    tinygltf::TinyGLTF loader;
    tinygltf::FsCallbacks fs = {&exists_in_folder, &expand, &read_whole, &write_whole, &scope};
    loader.SetFsCallbacks(fs);
    loader.SetImageLoader(&keep_image, g.get()); /* kept encoded; gls_decode_image decodes */

    std::string err, warn;
    const unsigned char *b = static_cast<const unsigned char *>(bytes);
    std::vector<unsigned char> patched_bytes;
    std::vector<int> patched;
    std::vector<meshopt_view> meshopt_views;
    std::vector<int> zeroed;
    static const char MESHOPT[] = "_meshopt_compression";
    const unsigned char *const original = b;
    const size_t original_len = len;
    /* Parses b (a second time: with indices accessors without bufferView patched, after
     * tinygltf refused them, so that other files pay nothing for it). */
    bool ok = false;
    for (int pass = 0; pass < 2; pass++) {
        try {
            const bool draco = std::search(original, original + original_len, std::begin(DRACO),
                                           std::end(DRACO) - 1) != original + original_len;
            const bool meshopt = std::search(original, original + original_len, std::begin(MESHOPT),
                                             std::end(MESHOPT) - 1) != original + original_len;
            const bool zero = pass == 1;
            b = original;
            len = original_len;
            patched_bytes.clear();
            patched.clear();
            meshopt_views.clear();
            zeroed.clear();
            if ((draco || meshopt || zero) &&
                prepare(b, len, draco, meshopt, zero, &patched_bytes, &patched, &meshopt_views, &zeroed)) {
                if (patched_bytes.size() > UINT_MAX) {
                    set_msg(msg, msg_size, "file too large for tinygltf");
                    return GLS_ERR_GLTF;
                }
                b = patched_bytes.data();
                len = patched_bytes.size();
            }
        } catch (const decode_error &e) {
            set_msg(msg, msg_size, e.text);
            return GLS_ERR_GLTF;
        }
        if (pass == 1 && zeroed.empty())
            break; /* nothing to patch: the first pass's error stands */
        std::string e1, w1;
        g->model = tinygltf::Model();
        g->image_bytes.clear();
        if (len >= 4 && std::memcmp(b, "glTF", 4) == 0)
            ok = loader.LoadBinaryFromMemory(&g->model, &e1, &w1, b, static_cast<unsigned>(len), folder);
        else
            ok = loader.LoadASCIIFromString(&g->model, &e1, &w1, reinterpret_cast<const char *>(b),
                                            static_cast<unsigned>(len), folder);
        if (pass == 0 || ok) {
            err = e1;
            warn = w1;
        }
        if (ok || !scope.error.empty() || e1.find("] invalid bufferView") == std::string::npos)
            break;
    }
    /* A refused URI is the error, also where tinygltf only warned (an image it could skip):
     * a file the glTF names must be there. */
    if (!scope.error.empty()) {
        set_msg(msg, msg_size, scope.error);
        return scope.status;
    }
    if (!ok && starts_with(err, "Failed to decode 'uri' : data:")) {
        set_msg(msg, msg_size, "a buffer's data URI does not decode (bad base64, or not byteLength bytes)");
        return GLS_ERR_GLTF;
    }
    if (!ok) {
        set_msg(msg, msg_size, err);
        return classify(err);
    }
    try {
        unzero_indices(g->model, zeroed);
        meshopt_decode(g->model, meshopt_views);
        draco_decode(g->model, patched);
    } catch (const decode_error &e) {
        set_msg(msg, msg_size, e.text);
        return GLS_ERR_GLTF;
    }
    build_view(*g);
    *out = &g.release()->view;
    return GLS_OK;
}

} // namespace

extern "C" gls_status gls_load(const char *path, const void *bytes, size_t len, uint64_t max_external,
                               gls_model **out, char *msg, size_t msg_size)
{
    *out = nullptr;
    if (msg && msg_size)
        msg[0] = 0;
    try {
        return load(path, bytes, len, max_external, out, msg, msg_size);
    } catch (const std::bad_alloc &) {
        set_msg(msg, msg_size, "out of memory");
        return GLS_ERR_NOMEM;
    } catch (const std::exception &e) {
        set_msg(msg, msg_size, e.what());
        return classify(e.what());
    } catch (...) {
        set_msg(msg, msg_size, "unknown exception in tinygltf");
        return GLS_ERR_GLTF;
    }
}

namespace {

/* The format the bytes' signature shows: "png", "jpeg", "webp", ... or "unknown". */
const char *sniff(const std::vector<unsigned char> &b)
{
    const unsigned char *p = b.data();
    const size_t n = b.size();
    if (n >= 8 && std::memcmp(p, "\x89PNG\r\n\x1a\n", 8) == 0)
        return "png";
    if (n >= 3 && p[0] == 0xFF && p[1] == 0xD8 && p[2] == 0xFF)
        return "jpeg";
    if (n >= 12 && std::memcmp(p, "RIFF", 4) == 0 && std::memcmp(p + 8, "WEBP", 4) == 0)
        return "webp";
    if (n >= 12 && std::memcmp(p, "\xABKTX 20\xBB\r\n\x1a\n", 12) == 0)
        return "ktx2";
    if (n >= 4 && std::memcmp(p, "DDS ", 4) == 0)
        return "dds";
    if (n >= 6 && (std::memcmp(p, "GIF87a", 6) == 0 || std::memcmp(p, "GIF89a", 6) == 0))
        return "gif";
    if (n >= 2 && p[0] == 'B' && p[1] == 'M')
        return "bmp";
    return "unknown";
}

/* Decodes image i into g.decoded[i]; false with g.image_error[i] set. */
bool decode_image(gls_impl &g, size_t i)
{
    const std::vector<unsigned char> &b = g.image_bytes[i];
    const tinygltf::Image &src = g.model.images[i];
    const char *format = sniff(b);
    std::string name = "image " + std::to_string(i);
    if (!src.uri.empty())
        name += " (URI \"" + (src.uri.size() > 120 ? src.uri.substr(0, 120) + "..." : src.uri) + "\")";
    name += std::string(", format ") + format;
    if (!src.mimeType.empty())
        name += " (mimeType " + src.mimeType.substr(0, 40) + ")";
    if (b.empty()) {
        g.image_error[i] = name + ": no image data";
        return false;
    }
    if (b.size() > INT_MAX) {
        g.image_error[i] = name + ": too large to decode";
        return false;
    }
    /* The decoders allocate from the header's size: a side over SCN_IMAGE_MAX_SIDE
     * (docs/inputs.md) is refused from the header, before any pixel memory is taken. */
    uint32_t hw = 0, hh = 0;
    int wi = 0, hi = 0;
    if (std::strcmp(format, "webp") == 0 && WebPGetInfo(b.data(), b.size(), &wi, &hi) && wi > 0 && hi > 0) {
        hw = static_cast<uint32_t>(wi);
        hh = static_cast<uint32_t>(hi);
    } else if (!scn_image_header_size(b.data(), b.size(), &hw, &hh)) {
        hw = hh = 0;
    }
    if (hw > SCN_IMAGE_MAX_SIDE || hh > SCN_IMAGE_MAX_SIDE) {
        g.image_error[i] = name + ": " + std::to_string(hw) + "x" + std::to_string(hh) + ", over the limit of " +
                           std::to_string(SCN_IMAGE_MAX_SIDE) + " texels a side";
        return false;
    }
    tinygltf::Image &out = g.decoded[i];
    if (std::strcmp(format, "webp") == 0) {
        int w = 0, h = 0;
        if (!WebPGetInfo(b.data(), b.size(), &w, &h) || w <= 0 || h <= 0) {
            g.image_error[i] = name + ": not a WebP image libwebp reads";
            return false;
        }
        out.image.resize(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
        if (!WebPDecodeRGBAInto(b.data(), b.size(), out.image.data(), out.image.size(), w * 4)) {
            out.image.clear();
            g.image_error[i] = name + ": libwebp does not decode it";
            return false;
        }
        out.width = w;
        out.height = h;
        out.component = 4;
        out.bits = 8;
        return true;
    }
    if (std::strcmp(format, "ktx2") == 0 || std::strcmp(format, "dds") == 0) {
        g.image_error[i] = name + ": not supported (no decoder for this format here)";
        return false;
    }
    std::string err, warn;
    /* No user data: tinygltf's defaults, channels expanded to RGBA. */
    if (!tinygltf::LoadImageData(&out, static_cast<int>(i), &err, &warn, 0, 0, b.data(), static_cast<int>(b.size()),
                                 nullptr)) {
        std::string why;
        for (char c : err)
            why += (c == '\n' || c == '\r') ? ' ' : c;
        while (!why.empty() && why.back() == ' ')
            why.pop_back();
        g.image_error[i] = name + ": does not decode (" + (why.empty() ? "stb_image failed" : why) + ")";
        return false;
    }
    if (out.width <= 0 || out.height <= 0 || out.component != 4 || (out.bits != 8 && out.bits != 16) ||
        out.image.size() != static_cast<size_t>(out.width) * static_cast<size_t>(out.height) * 4 * (out.bits / 8)) {
        out.image.clear();
        g.image_error[i] = name + ": decodes to no RGBA image of 8 or 16 bits";
        return false;
    }
    return true;
}

} // namespace

extern "C" gls_status gls_decode_image(const gls_model *model, int index, gls_pixels *out, char *msg,
                                       size_t msg_size)
{
    std::memset(out, 0, sizeof *out);
    if (msg && msg_size)
        msg[0] = 0;
    gls_impl &g = *model->impl;
    if (index < 0 || static_cast<size_t>(index) >= g.image_state.size()) {
        set_msg(msg, msg_size, "image " + std::to_string(index) + " does not exist");
        return GLS_ERR_GLTF;
    }
    const size_t i = static_cast<size_t>(index);
    try {
        if (g.image_state[i] == 0)
            g.image_state[i] = decode_image(g, i) ? 1 : -1;
    } catch (const std::bad_alloc &) {
        g.decoded[i].image.clear();
        set_msg(msg, msg_size, "image " + std::to_string(index) + ": out of memory");
        return GLS_ERR_NOMEM;
    }
    if (g.image_state[i] < 0) {
        set_msg(msg, msg_size, g.image_error[i]);
        return g.image_error[i].find("not supported") != std::string::npos ? GLS_ERR_UNSUPPORTED : GLS_ERR_GLTF;
    }
    const tinygltf::Image &d = g.decoded[i];
    out->width = d.width;
    out->height = d.height;
    out->bits = d.bits;
    out->rgba = d.image.data();
    return GLS_OK;
}

extern "C" void gls_free(gls_model *model)
{
    if (model)
        delete model->impl;
}
