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
 *   - every exception stops here.
 * The gls_impl owns the tinygltf::Model and the C arrays that point into it. */
#include "gltf_shim.h"

#include <tiny_gltf.h>

#include <sys/stat.h>

#include <cerrno>
#include <algorithm>
#include <climits>
#include <iterator>
#include <cstdio>
#include <cstdlib>
#include <cstring>
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
    std::vector<gls_mesh> meshes;
    std::vector<gls_node> nodes;
    std::vector<gls_camera> cameras;
    std::vector<gls_light> lights;
    std::vector<gls_material> materials;
    std::vector<gls_image> images;
    std::vector<gls_texture> textures;
    std::vector<gls_tex_sampler> tex_samplers;
    std::vector<std::vector<double>> numbers; /* KHR_texture_transform arrays */
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
};

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
    const std::string shown = "URI \"" + (uri.size() > 120 ? uri.substr(0, 120) + "..." : uri) + "\"";
    if (uri.empty()) {
        refuse(scope, GLS_ERR_GLTF, "an empty URI");
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

bool read_whole(std::vector<unsigned char> *out, std::string *err, const std::string &p, void *)
{
    return tinygltf::ReadWholeFile(out, err, p, nullptr);
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
    t.rotation = ext_number(ext, "KHR_texture_transform", "rotation", &t.has_transform);
    t.transform_texcoord = ext_number(ext, "KHR_texture_transform", "texCoord", nullptr);
    auto it = ext.find("KHR_texture_transform");
    if (it != ext.end()) {
        t.offset = ext_vec(g, it->second, "offset");
        t.scale = ext_vec(g, it->second, "scale");
    }
    return t;
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
        }
    size_t k = 0;
    for (const tinygltf::Mesh &mesh : m.meshes) {
        std::vector<gls_primitive> prims;
        for (const tinygltf::Primitive &p : mesh.primitives) {
            const std::vector<gls_attribute> &attrs = g.attributes[k++];
            prims.push_back({p.mode, p.indices, p.material, static_cast<uint32_t>(attrs.size()),
                             attrs.data(), static_cast<uint32_t>(p.targets.size())});
        }
        g.primitives.push_back(std::move(prims));
    }
    for (size_t i = 0; i < m.meshes.size(); i++)
        g.meshes.push_back({m.meshes[i].name.c_str(), static_cast<uint32_t>(g.primitives[i].size()),
                            g.primitives[i].data()});

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
    g.numbers.reserve(m.materials.size() * 10); /* no reallocation under a pointer */
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
        c.occlusion_texture = texinfo(g, mat.occlusionTexture.index, mat.occlusionTexture.texCoord,
                                      mat.occlusionTexture.extensions);
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
        g.materials.push_back(c);
    }

    for (const tinygltf::Image &im : m.images) {
        gls_image c = {0, 0, 0, nullptr};
        if (im.width > 0 && im.height > 0 && im.component == 4 && (im.bits == 8 || im.bits == 16) &&
            im.image.size() == static_cast<size_t>(im.width) * static_cast<size_t>(im.height) * 4 * (im.bits / 8)) {
            c.width = im.width;
            c.height = im.height;
            c.bits = im.bits;
            c.rgba = im.image.data();
        }
        g.images.push_back(c);
    }
    for (const tinygltf::Texture &t : m.textures)
        g.textures.push_back({t.source, t.sampler});
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
    v.default_scene = m.defaultScene;
    v.extensions_required_count = static_cast<uint32_t>(g.ext_required.size());
    v.extensions_required = g.ext_required.data();
    v.extensions_used_count = static_cast<uint32_t>(g.ext_used.size());
    v.extensions_used = g.ext_used.data();
    v.impl = &g;
}

const char DRACO[] = "KHR_draco_mesh_compression";

gls_status load(const char *path, const void *bytes, size_t len, gls_model **out, char *msg,
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
    loader.SetImageLoader(&tinygltf::LoadImageData, nullptr); /* stb_image, RGBA 8 or 16 bits */

    std::string err, warn;
    const unsigned char *b = static_cast<const unsigned char *>(bytes);
    bool ok;
    if (len >= 4 && std::memcmp(b, "glTF", 4) == 0)
        ok = loader.LoadBinaryFromMemory(&g->model, &err, &warn, b, static_cast<unsigned>(len), folder);
    else
        ok = loader.LoadASCIIFromString(&g->model, &err, &warn, static_cast<const char *>(bytes),
                                        static_cast<unsigned>(len), folder);
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
    /* tinygltf has no Draco decoder: it stumbles over the accessors a Draco primitive leaves
     * without data, with a message about buffer views. Name the extension instead. */
    if (!ok && std::search(b, b + len, std::begin(DRACO), std::end(DRACO) - 1) != b + len) {
        set_msg(msg, msg_size, "KHR_draco_mesh_compression is not supported (" + err + ")");
        return GLS_ERR_UNSUPPORTED;
    }
    if (!ok) {
        set_msg(msg, msg_size, err);
        return classify(err);
    }
    build_view(*g);
    *out = &g.release()->view;
    return GLS_OK;
}

} // namespace

extern "C" gls_status gls_load(const char *path, const void *bytes, size_t len, gls_model **out,
                               char *msg, size_t msg_size)
{
    *out = nullptr;
    if (msg && msg_size)
        msg[0] = 0;
    try {
        return load(path, bytes, len, out, msg, msg_size);
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

extern "C" void gls_free(gls_model *model)
{
    if (model)
        delete model->impl;
}
