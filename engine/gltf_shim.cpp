/* gltf_shim.cpp — the engine's only C++: tinygltf behind the C ABI of gltf_shim.h.
 *
 * Debian ships tinygltf's implementation in libtinygltf.so (built with nlohmann-json and
 * stb_image, no Draco), so this file includes <tiny_gltf.h> without TINYGLTF_IMPLEMENTATION.
 * Nothing we could define changes the class layout: TINYGLTF_USE_CPP14 and the JSON backend
 * only affect the implementation half of the header, and the image-loader members are
 * function pointers either way. We define none of them.
 *
 * What the shim does beyond copying fields out:
 *   - images are never decoded: a loader callback accepts and drops them (textures are not
 *     supported, and stb_image on untrusted bytes is attack surface we do not need);
 *   - external files are looked up only in the glTF's own folder (tinygltf would also try the
 *     process's working directory, which makes a load depend on where it ran);
 *   - tinygltf's failure is sorted into I/O, syntax and structure by the text it reports
 *     (it has no error codes); the texts are those of tinygltf 2.7 and nlohmann-json 3.
 *     Only nlohmann's parse_error is syntax: its out_of_range (a number such as 1e999 that
 *     no double holds) is well-formed JSON with a wrong value, so structure;
 *   - every exception stops here.
 * The gls_impl owns the tinygltf::Model and the C arrays that point into it. */
#include "gltf_shim.h"

#include <tiny_gltf.h>

#include <climits>
#include <cstdio>
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
    std::vector<std::vector<gls_channel>> channels;
    std::vector<std::vector<gls_sampler>> samplers;
    std::vector<gls_animation> animations;
    std::vector<gls_scene> scenes;
    std::vector<const char *> ext_required;
    gls_model view;
};

namespace {

struct fs_scope {
    std::string prefix; /* "<folder>/" */
};

bool exists_in_folder(const std::string &abs, void *user)
{
    const fs_scope *scope = static_cast<const fs_scope *>(user);
    if (abs.compare(0, scope->prefix.size(), scope->prefix) != 0)
        return false;
    return tinygltf::FileExists(abs, nullptr);
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

bool ignore_image(tinygltf::Image *, const int, std::string *, std::string *, int, int,
                  const unsigned char *, int, void *)
{
    return true;
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
    for (const tinygltf::Accessor &a : m.accessors)
        g.accessors.push_back({a.bufferView, a.byteOffset, a.componentType, a.type, a.count,
                               a.normalized ? 1 : 0, a.sparse.isSparse ? 1 : 0});

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
    for (const tinygltf::Material &mat : m.materials) {
        gls_material c;
        c.name = mat.name.c_str();
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
    v.animation_count = static_cast<uint32_t>(g.animations.size());
    v.animations = g.animations.data();
    v.scene_count = static_cast<uint32_t>(g.scenes.size());
    v.scenes = g.scenes.data();
    v.default_scene = m.defaultScene;
    v.extensions_required_count = static_cast<uint32_t>(g.ext_required.size());
    v.extensions_required = g.ext_required.data();
    v.impl = &g;
}

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

    std::unique_ptr<gls_impl> g(new gls_impl());
    tinygltf::TinyGLTF loader;
    tinygltf::FsCallbacks fs = {&exists_in_folder, &expand, &read_whole, &write_whole, &scope};
    loader.SetFsCallbacks(fs);
    loader.SetImageLoader(&ignore_image, nullptr);

    std::string err, warn;
    const unsigned char *b = static_cast<const unsigned char *>(bytes);
    bool ok;
    if (len >= 4 && std::memcmp(b, "glTF", 4) == 0)
        ok = loader.LoadBinaryFromMemory(&g->model, &err, &warn, b, static_cast<unsigned>(len), folder);
    else
        ok = loader.LoadASCIIFromString(&g->model, &err, &warn, static_cast<const char *>(bytes),
                                        static_cast<unsigned>(len), folder);
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
