/* gltf_precheck.c — a glTF's bytes checked before tinygltf parses them (docs/inputs.md).
 *
 * tinygltf parses JSON with nlohmann::json, which recurses once per nesting level: a 40 KB file
 * of 20,000 nested arrays overflows the stack. So the JSON (a .gltf's text, a .glb's JSON chunk)
 * is held to ENG_JSON_MAX_DEPTH and to nothing after its value before the parser sees it, and
 * its accessor counts to what tinygltf's int can hold (check_counts). The same pass gives the largest external file the glTF can need (its largest buffer byteLength),
 * which the shim's file reads are held to, so that a huge or sparse .bin is refused from its
 * size, not read whole first. An image's size is read from its PNG or JPEG header, so that the
 * shim can refuse one over SCN_IMAGE_MAX_SIDE before stb_image allocates its pixels.
 */
#include "gltf_precheck.h"

#include <cjson/cJSON.h>

#include <string.h>

static uint32_t le32(const unsigned char *b)
{
    return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static uint32_t be32(const unsigned char *b)
{
    return (uint32_t)b[0] << 24 | (uint32_t)b[1] << 16 | (uint32_t)b[2] << 8 | (uint32_t)b[3];
}

/* Every accessors[i].count an integer in 1..2^31-1 and every sparse.count one in 1..count:
 * tinygltf 2.7 stores both in an int, so 2^31 would wrap (to a sparse count of 0) unnoticed. */
static eng_result check_counts(const char *path, const cJSON *root, eng_error *err)
{
    const cJSON *accessors = cJSON_GetObjectItemCaseSensitive(root, "accessors");
    int i = 0;
    const cJSON *a;
    cJSON_ArrayForEach(a, accessors)
    {
        const cJSON *c = cJSON_GetObjectItemCaseSensitive(a, "count");
        double count = cJSON_IsNumber(c) ? c->valuedouble : 0;
        /* the range first: converting a double outside int64_t's range is undefined */
        if (c && (!cJSON_IsNumber(c) || !(count >= 1 && count <= 2147483647.0) || count != (double)(int64_t)count))
            return eng_fail(err, ENG_ERR_INVALID, "%s: accessors[%d].count %.17g is not an integer in 1..2147483647",
                            path, i, count);
        const cJSON *sp = cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(a, "sparse"), "count");
        if (sp && (!cJSON_IsNumber(sp) || !(sp->valuedouble >= 1 && sp->valuedouble <= count) ||
                   sp->valuedouble != (double)(int64_t)sp->valuedouble))
            return eng_fail(err, ENG_ERR_INVALID, "%s: accessors[%d].sparse.count %.17g is not an integer in 1..%.17g "
                            "(the accessor's count)", path, i, cJSON_IsNumber(sp) ? sp->valuedouble : 0, count);
        i++;
    }
    return ENG_OK;
}

/* The largest buffers[i].byteLength (0 when none is readable). */
static uint64_t largest_buffer(const cJSON *root)
{
    uint64_t most = 0;
    const cJSON *buffers = cJSON_GetObjectItemCaseSensitive(root, "buffers");
    const cJSON *b;
    cJSON_ArrayForEach(b, buffers)
    {
        const cJSON *bl = cJSON_GetObjectItemCaseSensitive(b, "byteLength");
        if (cJSON_IsNumber(bl) && bl->valuedouble > (double)most && bl->valuedouble < 1e18)
            most = (uint64_t)bl->valuedouble;
    }
    return most;
}

eng_result scn_gltf_precheck(const char *path, const char *bytes, size_t len, uint64_t *max_external,
                             eng_error *err)
{
    const char *json = bytes;
    size_t json_len = len;
    if (len >= 4 && memcmp(bytes, "glTF", 4) == 0) {
        const unsigned char *b = (const unsigned char *)bytes;
        if (len < 20 || memcmp(b + 16, "JSON", 4) != 0)
            return ENG_OK; /* tinygltf names what is wrong with the header */
        uint64_t chunk = le32(b + 12);
        if (chunk > len - 20)
            return ENG_OK;
        json = bytes + 20;
        json_len = (size_t)chunk;
    }
    eng_result r = eng_json_precheck(path, json, json_len, ENG_JSON_MAX_DEPTH, err);
    if (r != ENG_OK)
        return r;
    cJSON *root = cJSON_ParseWithLength(json, json_len); /* NULL: tinygltf names the syntax error */
    r = check_counts(path, root, err);
    uint64_t most = largest_buffer(root) + 3;
    cJSON_Delete(root);
    if (max_external)
        *max_external = most < SCN_EXTERNAL_MIN ? SCN_EXTERNAL_MIN : most > SCN_EXTERNAL_MAX ? SCN_EXTERNAL_MAX : most;
    return r;
}

int scn_image_header_size(const unsigned char *b, size_t len, uint32_t *w, uint32_t *h)
{
    static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (len >= 24 && memcmp(b, png, 8) == 0 && memcmp(b + 12, "IHDR", 4) == 0) {
        *w = be32(b + 16);
        *h = be32(b + 20);
        return 1;
    }
    if (len < 4 || b[0] != 0xff || b[1] != 0xd8)
        return 0;
    /* JPEG: markers up to the first start-of-frame (SOF0..SOF15 but DHT C4, JPG C8, DAC CC). */
    size_t i = 2;
    while (i + 4 <= len) {
        if (b[i] != 0xff)
            return 0;
        unsigned m = b[i + 1];
        if (m == 0xff) {
            i++;
            continue;
        }
        if (m == 0xd8 || m == 0x01 || (m >= 0xd0 && m <= 0xd7)) {
            i += 2;
            continue;
        }
        size_t seg = (size_t)b[i + 2] << 8 | b[i + 3];
        if (m >= 0xc0 && m <= 0xcf && m != 0xc4 && m != 0xc8 && m != 0xcc) {
            if (i + 9 > len)
                return 0;
            *h = (uint32_t)b[i + 5] << 8 | b[i + 6];
            *w = (uint32_t)b[i + 7] << 8 | b[i + 8];
            return 1;
        }
        if (m == 0xda || seg < 2)
            return 0;
        i += 2 + seg;
    }
    return 0;
}
