/* gltf_features.c — refusals by name before tinygltf reads anything.
 *
 * tinygltf reads a glTF top-down and fails on the first thing it cannot read: a glTF 1.0
 * file may pass and render nothing, and a required extension that changes how buffers or
 * images are stored (KHR_texture_basisu, a compression) fails as some missing URI
 * or undecodable image. Looking at asset and extensionsRequired first makes the refusal name
 * the feature (glTF §3.12: a client that lacks a required extension must refuse the asset).
 * It also tells whether the file names no mesh at all, so that a file that then fails to load
 * is refused for having no geometry first. */
#include "gltf_features.h"

#include <cjson/cJSON.h>

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Every extension the loader reads; docs/gltf.md lists what each one covers. */
static const char *const supported[] = {
    "KHR_lights_punctual",          "KHR_materials_transmission", "KHR_materials_ior",
    "KHR_materials_emissive_strength", "KHR_materials_unlit",     "KHR_materials_pbrSpecularGlossiness",
    "KHR_mesh_quantization",        "KHR_texture_transform",      "KHR_draco_mesh_compression",
    "EXT_texture_webp",             "EXT_meshopt_compression",    "KHR_meshopt_compression",
};

int gltf_extension_supported(const char *name)
{
    for (size_t k = 0; k < sizeof supported / sizeof supported[0]; k++)
        if (strcmp(name, supported[k]) == 0)
            return 1;
    return 0;
}

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* "major.minor" -> major * 1000 + minor; -1 where it is not of that form. */
static long version_number(const char *v)
{
    char *end;
    long major = strtol(v, &end, 10);
    if (end == v || *end != '.' || major < 0 || major > 1000)
        return -1;
    const char *m = end + 1;
    long minor = strtol(m, &end, 10);
    if (end == m || *end != 0 || minor < 0 || minor > 999)
        return -1;
    return major * 1000 + minor;
}

/* glTF 1.0 kept meshes, nodes, accessors, ... in objects keyed by id; 2.0 in arrays. */
static int name_keyed(const cJSON *root)
{
    static const char *const keys[] = {"meshes", "nodes", "accessors", "bufferViews", "buffers", "materials"};
    for (size_t k = 0; k < sizeof keys / sizeof keys[0]; k++)
        if (cJSON_IsObject(cJSON_GetObjectItemCaseSensitive(root, keys[k])))
            return 1;
    return 0;
}

/* 0 when no node names a mesh, or there is no mesh with a primitive: the file cannot draw
 * anything, whatever its buffers hold (the glTF validator's test files often have buffers
 * without data and no mesh). Anything finer (a mesh of POINTS only, a scene without that
 * node) is gltf_load.c's check_geometry, after loading. */
static int draws_anything(const cJSON *root)
{
    const cJSON *meshes = cJSON_GetObjectItemCaseSensitive(root, "meshes");
    const cJSON *nodes = cJSON_GetObjectItemCaseSensitive(root, "nodes");
    int primitives = 0, named = 0;
    for (const cJSON *m = cJSON_IsArray(meshes) ? meshes->child : NULL; m && !primitives; m = m->next)
        primitives = cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(m, "primitives")) > 0;
    for (const cJSON *n = cJSON_IsArray(nodes) ? nodes->child : NULL; n && !named; n = n->next)
        named = cJSON_GetObjectItemCaseSensitive(n, "mesh") != NULL;
    return primitives && named;
}

static eng_result check_json(const char *path, const cJSON *root, eng_error *err)
{
    const cJSON *asset = cJSON_GetObjectItemCaseSensitive(root, "asset");
    const cJSON *version = cJSON_GetObjectItemCaseSensitive(asset, "version");
    const cJSON *min_version = cJSON_GetObjectItemCaseSensitive(asset, "minVersion");
    if (cJSON_IsString(version)) {
        long v = version_number(version->valuestring);
        if (v >= 0 && v < 2000)
            return eng_fail(err, ENG_ERR_UNSUPPORTED,
                            "%s: glTF %.16s (asset.version) is not supported; only glTF 2.0 is", path,
                            version->valuestring);
        if (v >= 3000)
            return eng_fail(err, ENG_ERR_UNSUPPORTED,
                            "%s: glTF %.16s (asset.version) is not supported; only glTF 2.0 is", path,
                            version->valuestring);
    } else if (name_keyed(root)) {
        return eng_fail(err, ENG_ERR_UNSUPPORTED,
                        "%s: glTF 1.0 (objects keyed by name, no asset.version \"2.0\") is not supported; "
                        "only glTF 2.0 is", path);
    }
    if (cJSON_IsString(min_version)) {
        long v = version_number(min_version->valuestring);
        if (v > 2000)
            return eng_fail(err, ENG_ERR_UNSUPPORTED,
                            "%s: asset.minVersion %.16s is above the glTF 2.0 this loader reads", path,
                            min_version->valuestring);
    }
    const cJSON *required = cJSON_GetObjectItemCaseSensitive(root, "extensionsRequired");
    const cJSON *e = cJSON_IsArray(required) ? required->child : NULL;
    for (; e; e = e->next)
        if (cJSON_IsString(e) && !gltf_extension_supported(e->valuestring))
            return eng_fail(err, ENG_ERR_UNSUPPORTED, "%s: extensionsRequired: %.120s is not supported", path,
                            e->valuestring);
    return ENG_OK;
}

eng_result gltf_features_check(const char *path, const char *bytes, size_t len, int *no_mesh, eng_error *err)
{
    *no_mesh = 0;
    const unsigned char *b = (const unsigned char *)bytes;
    const char *json = bytes;
    size_t json_len = len;
    if (len >= 4 && memcmp(b, "glTF", 4) == 0) {
        if (len >= 8 && le32(b + 4) == 1)
            return eng_fail(err, ENG_ERR_UNSUPPORTED,
                            "%s: a GLB container of version 1 (glTF 1.0) is not supported; only glTF 2.0 is", path);
        if (len < 20 || le32(b + 16) != 0x4E4F534Au || le32(b + 12) > len - 20)
            return ENG_OK;
        json = bytes + 20;
        json_len = le32(b + 12);
    }
    cJSON *root = cJSON_ParseWithLength(json, json_len);
    if (!root)
        return ENG_OK;
    eng_result r = cJSON_IsObject(root) ? check_json(path, root, err) : ENG_OK;
    /* without asset, not a glTF: tinygltf says so */
    *no_mesh = cJSON_IsObject(cJSON_GetObjectItemCaseSensitive(root, "asset")) && !draws_anything(root);
    cJSON_Delete(root);
    return r;
}
