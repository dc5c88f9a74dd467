/* gltf_load.c — scn_load_gltf: from what tinygltf parsed (gltf_shim.h) to a validated
 * scn_scene, and scn_destroy.
 *
 * tinygltf checks JSON syntax and the rough shape of the glTF objects; it does not check
 * meaning. Everything that can make a renderer read out of bounds, loop forever or produce
 * NaN is checked here, before anything is copied: buffer views and accessors against the
 * bytes that exist (64-bit, overflow-checked), accessor types against their use, every
 * index against the array it indexes, the node graph (one parent per node, no cycles), and
 * finiteness of every number that reaches a transform, a vertex, a key, a light or a
 * material. Each failure is one line naming the file, the place (as the glTF names it:
 * "accessor 3", "node 5", "animations[0].channels[2]") and the problem.
 *
 * What the loader decides for the engine:
 *   - meshes are TRIANGLES only: other modes, primitives without POSITION, orthographic
 *     cameras and unknown optional extensions are left out with a warning (scn_warn), a
 *     required extension other than lights, transmission, ior, emissive strength, texture
 *     transform, mesh quantization and Draco is ENG_ERR_UNSUPPORTED (Draco primitives arrive
 *     decoded from the shim, as ordinary accessors); sparse accessors and KHR_mesh_quantization's
 *     integer attributes are read (read_floats_as), sparse index accessors are not;
 *   - textures are decoded to linear RGBA floats (make_texture; base colour and emissive
 *     sRGB-decoded; occlusionTexture.strength checked to [0, 1]), TEXCOORD_0/1 and COLOR_0 read; skins (JOINTS_0/WEIGHTS_0 and _1, inverse
 *     bind matrices) and morph targets (POSITION/NORMAL/TANGENT deltas, mesh/node weights, "weights"
 *     channels) are read for deform.c; TANGENT is read, or generated (scn_generate_tangents)
 *     for a primitive whose material has a normal texture;
 *   - primitives without NORMAL get flat normals, their vertices un-shared; normals are
 *     normalised;
 *   - only nodes reachable from the default scene (else scene 0, else every root) are kept,
 *     in depth-first pre-order so parents precede children; animation channels are remapped
 *     to that order and dropped where their node is not kept;
 *   - the digest covers the file and each external buffer, in buffer order.
 * The scene owns every array it points to; scn_destroy frees it whole. */
#include "scn.h"
#include "gltf_features.h"
#include "gltf_precheck.h"
#include "gltf_shim.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "glTF buffers are little-endian; this loader reads them in place"
#endif

#define GLTF_MAX_FILE ((size_t)1 << 30)
#define MAX_PRIMITIVE_VERTICES ((uint64_t)1 << 26) /* also the cap on indices per primitive */
#define MAX_SCENE_VERTICES ((uint64_t)1 << 28)
#define MAX_KEYS ((uint64_t)1 << 24)
#define PI 3.14159265358979323846
#define IOR_ZERO 1.0e4f /* what ior 0 is stored as: F0 = 0.9996 */

typedef struct loader {
    const char *path;
    const gls_model *m;
    scn_scene *s;
    eng_error *err;
    uint64_t total_vertices;
    int scene_index; /* -1: the default scene */
    int32_t *texture_source; /* per scene texture, its glTF texture (make_texture) */
    unsigned char *drawn;    /* per glTF material: a node's mesh uses it (its textures are made) */
    /* What an extension defines that the engine reads only in part: one warning per file. */
    int averaged_transmission_texture, ignored_spec_gloss_texture;
} loader;

static eng_result fail(loader *L, eng_result code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static eng_result fail(loader *L, eng_result code, const char *fmt, ...)
{
    char what[900];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return eng_fail(L->err, code, "%s: %s", L->path, what);
}

static eng_result nomem(loader *L, const char *what)
{
    return fail(L, ENG_ERR_NOMEM, "out of memory (%s)", what);
}

/* Copies a name, truncated to SCN_NAME_MAX-1 bytes without splitting a UTF-8 sequence. */
static void copy_name(char dst[SCN_NAME_MAX], const char *src)
{
    size_t n = src ? strlen(src) : 0;
    if (n > SCN_NAME_MAX - 1) {
        n = SCN_NAME_MAX - 1;
        while (n > 0 && ((unsigned char)src[n] & 0xC0) == 0x80)
            n--;
    }
    if (n)
        memcpy(dst, src, n);
    dst[n] = 0;
}

/* *out = a*b + c; returns 0 on overflow. */
static int mul_add_u64(uint64_t a, uint64_t b, uint64_t c, uint64_t *out)
{
    if (b != 0 && a > UINT64_MAX / b)
        return 0;
    uint64_t p = a * b;
    if (p > UINT64_MAX - c)
        return 0;
    *out = p + c;
    return 1;
}

static int all_finite(const double *v, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return 0;
    return 1;
}

/* ---------------------------------------------------------------- accessors */

static uint32_t type_components(int type)
{
    switch (type) {
    case GLS_TYPE_SCALAR: return 1;
    case GLS_TYPE_VEC2: return 2;
    case GLS_TYPE_VEC3: return 3;
    case GLS_TYPE_VEC4: return 4;
    case GLS_TYPE_MAT2: return 4;
    case GLS_TYPE_MAT3: return 9;
    case GLS_TYPE_MAT4: return 16;
    }
    return 0;
}

static const char *type_name(int type)
{
    switch (type) {
    case GLS_TYPE_SCALAR: return "SCALAR";
    case GLS_TYPE_VEC2: return "VEC2";
    case GLS_TYPE_VEC3: return "VEC3";
    case GLS_TYPE_VEC4: return "VEC4";
    case GLS_TYPE_MAT2: return "MAT2";
    case GLS_TYPE_MAT3: return "MAT3";
    case GLS_TYPE_MAT4: return "MAT4";
    }
    return "?";
}

static uint32_t component_size(int ct)
{
    switch (ct) {
    case GLS_COMPONENT_BYTE:
    case GLS_COMPONENT_UNSIGNED_BYTE: return 1;
    case GLS_COMPONENT_SHORT:
    case GLS_COMPONENT_UNSIGNED_SHORT: return 2;
    case GLS_COMPONENT_UNSIGNED_INT:
    case GLS_COMPONENT_FLOAT: return 4;
    }
    return 0;
}

static const char *component_name(int ct)
{
    switch (ct) {
    case GLS_COMPONENT_BYTE: return "BYTE";
    case GLS_COMPONENT_UNSIGNED_BYTE: return "UNSIGNED_BYTE";
    case GLS_COMPONENT_SHORT: return "SHORT";
    case GLS_COMPONENT_UNSIGNED_SHORT: return "UNSIGNED_SHORT";
    case GLS_COMPONENT_UNSIGNED_INT: return "UNSIGNED_INT";
    case GLS_COMPONENT_FLOAT: return "FLOAT";
    }
    return "?";
}

/* Bytes of one element; matrix columns start on 4-byte boundaries (glTF §3.6.2.4). */
static uint64_t element_size(int ct, int type)
{
    uint64_t cs = component_size(ct);
    int rows = type == GLS_TYPE_MAT2 ? 2 : type == GLS_TYPE_MAT3 ? 3 : type == GLS_TYPE_MAT4 ? 4 : 0;
    if (rows == 0)
        return cs * type_components(type);
    uint64_t col = (cs * (uint64_t)rows + 3) & ~(uint64_t)3;
    return col * (uint64_t)rows;
}

static eng_result check_buffer_views(loader *L)
{
    const gls_model *m = L->m;
    for (uint32_t i = 0; i < m->buffer_view_count; i++) {
        const gls_buffer_view *v = &m->buffer_views[i];
        uint64_t end;
        if (v->buffer < 0 || (uint32_t)v->buffer >= m->buffer_count)
            return fail(L, ENG_ERR_INVALID, "buffer view %u: buffer %d out of range (%u buffers)", i,
                        v->buffer, m->buffer_count);
        if (v->byte_length == 0)
            return fail(L, ENG_ERR_INVALID, "buffer view %u: byteLength is 0", i);
        const gls_buffer *b = &m->buffers[v->buffer];
        if (!mul_add_u64(1, v->byte_offset, v->byte_length, &end) || end > b->size)
            return fail(L, ENG_ERR_INVALID,
                        "buffer view %u: bytes [%llu, %llu+%llu) lie outside buffer %d (%llu bytes)", i,
                        (unsigned long long)v->byte_offset, (unsigned long long)v->byte_offset,
                        (unsigned long long)v->byte_length, v->buffer, (unsigned long long)b->size);
        if (v->byte_stride != 0 && v->byte_stride < 4)
            return fail(L, ENG_ERR_INVALID, "buffer view %u: byteStride %llu is below 4", i,
                        (unsigned long long)v->byte_stride);
    }
    return ENG_OK;
}

static eng_result check_accessors(loader *L)
{
    const gls_model *m = L->m;
    for (uint32_t i = 0; i < m->accessor_count; i++) {
        const gls_accessor *a = &m->accessors[i];
        if (component_size(a->component_type) == 0)
            return fail(L, ENG_ERR_INVALID, "accessor %u: componentType %d is not a glTF 2.0 type", i,
                        a->component_type);
        if (type_components(a->type) == 0)
            return fail(L, ENG_ERR_INVALID, "accessor %u: unknown type %d", i, a->type);
        if (a->count == 0)
            return fail(L, ENG_ERR_INVALID, "accessor %u: count is 0 (glTF requires at least 1)", i);
        if (a->buffer_view == -1)
            continue; /* all zeros, or sparse: nothing to bound */
        if (a->buffer_view < 0 || (uint32_t)a->buffer_view >= m->buffer_view_count)
            return fail(L, ENG_ERR_INVALID, "accessor %u: buffer view %d out of range (%u buffer views)",
                        i, a->buffer_view, m->buffer_view_count);
        const gls_buffer_view *v = &m->buffer_views[a->buffer_view];
        uint64_t esize = element_size(a->component_type, a->type);
        uint64_t stride = v->byte_stride ? v->byte_stride : esize;
        if (stride < esize)
            return fail(L, ENG_ERR_INVALID,
                        "accessor %u: byteStride %llu of buffer view %d is smaller than its %llu-byte elements",
                        i, (unsigned long long)stride, a->buffer_view, (unsigned long long)esize);
        uint64_t end;
        if (!mul_add_u64(stride, a->count - 1, esize, &end) || !mul_add_u64(1, end, a->byte_offset, &end) ||
            end > v->byte_length)
            return fail(L, ENG_ERR_INVALID,
                        "accessor %u: %llu elements of %llu bytes (stride %llu) from offset %llu overrun "
                        "buffer view %d (%llu bytes)",
                        i, (unsigned long long)a->count, (unsigned long long)esize,
                        (unsigned long long)stride, (unsigned long long)a->byte_offset, a->buffer_view,
                        (unsigned long long)v->byte_length);
    }
    return ENG_OK;
}

/* The accessor `index` as used at `where`, which must be of the given type and
 * componentType (ct 0: any of the index types; ct -1: FLOAT, or with KHR_mesh_quantization
 * BYTE, UNSIGNED_BYTE, SHORT or UNSIGNED_SHORT) and, unless sparse_ok, not sparse. Returns
 * its first byte, or NULL in *base for an accessor without a buffer view (all zeros). */
static eng_result use_accessor(loader *L, int index, const char *where, int type, int ct, int sparse_ok,
                               const gls_accessor **acc, const unsigned char **base, uint64_t *stride)
{
    const gls_model *m = L->m;
    if (index < 0 || (uint32_t)index >= m->accessor_count)
        return fail(L, ENG_ERR_INVALID, "%s: accessor %d out of range (%u accessors)", where, index,
                    m->accessor_count);
    const gls_accessor *a = &m->accessors[index];
    if (a->sparse && !sparse_ok)
        return fail(L, ENG_ERR_UNSUPPORTED, "%s: accessor %d is sparse (not supported here)", where, index);
    int ict = a->component_type;
    int ct_ok = ct > 0  ? ict == ct
                : ct < 0 ? (ict == GLS_COMPONENT_FLOAT || ict == GLS_COMPONENT_BYTE ||
                            ict == GLS_COMPONENT_UNSIGNED_BYTE || ict == GLS_COMPONENT_SHORT ||
                            ict == GLS_COMPONENT_UNSIGNED_SHORT)
                         : (ict == GLS_COMPONENT_UNSIGNED_BYTE || ict == GLS_COMPONENT_UNSIGNED_SHORT ||
                            ict == GLS_COMPONENT_UNSIGNED_INT);
    if (a->type != type || !ct_ok || (ict == GLS_COMPONENT_FLOAT && a->normalized))
        return fail(L, ENG_ERR_INVALID, "%s: accessor %d is %s of %s%s, must be %s of %s", where, index,
                    type_name(a->type), component_name(a->component_type),
                    a->normalized ? " (normalized)" : "", type_name(type),
                    ct > 0 ? component_name(ct)
                    : ct < 0 ? "FLOAT (or BYTE/UNSIGNED_BYTE/SHORT/UNSIGNED_SHORT, KHR_mesh_quantization)"
                             : "UNSIGNED_BYTE/SHORT/INT");
    *acc = a;
    *base = NULL;
    *stride = 0;
    if (a->buffer_view >= 0) {
        const gls_buffer_view *v = &m->buffer_views[a->buffer_view];
        *base = m->buffers[v->buffer].data + v->byte_offset + a->byte_offset;
        *stride = v->byte_stride ? v->byte_stride : element_size(a->component_type, a->type);
    }
    return ENG_OK;
}

/* comps components of component type ct at p as floats: normalized integers map to [0, 1]
 * or [-1, 1] as glTF §3.11 (Animation, "normalized integers") writes, plain ones keep their
 * value (KHR_mesh_quantization). */
static void convert(const unsigned char *p, int ct, int normalized, uint32_t comps, float *out)
{
    for (uint32_t c = 0; c < comps; c++) {
        float f;
        switch (ct) {
        case GLS_COMPONENT_BYTE: {
            int8_t x = (int8_t)p[c];
            f = normalized ? fmaxf((float)x / 127.0f, -1.0f) : (float)x;
            break;
        }
        case GLS_COMPONENT_UNSIGNED_BYTE: f = normalized ? (float)p[c] / 255.0f : (float)p[c]; break;
        case GLS_COMPONENT_SHORT: {
            int16_t x;
            memcpy(&x, p + 2 * c, 2);
            f = normalized ? fmaxf((float)x / 32767.0f, -1.0f) : (float)x;
            break;
        }
        case GLS_COMPONENT_UNSIGNED_SHORT: {
            uint16_t x;
            memcpy(&x, p + 2 * c, 2);
            f = normalized ? (float)x / 65535.0f : (float)x;
            break;
        }
        default: memcpy(&f, p + 4 * c, 4); break;
        }
        out[c] = f;
    }
}

/* A sparse accessor's substitutions (glTF §3.6.2.3) applied to v (count × comps floats):
 * indices and values bounds-checked against their buffer views, each index below count
 * and strictly increasing. */
static eng_result apply_sparse(loader *L, const gls_accessor *a, int index, const char *where, uint32_t comps,
                               float *v)
{
    const gls_model *m = L->m;
    uint32_t isize = component_size(a->sparse_index_type);
    if (a->sparse_index_type != GLS_COMPONENT_UNSIGNED_BYTE && a->sparse_index_type != GLS_COMPONENT_UNSIGNED_SHORT &&
        a->sparse_index_type != GLS_COMPONENT_UNSIGNED_INT)
        return fail(L, ENG_ERR_INVALID, "%s: accessor %d: sparse indices are %s, not UNSIGNED_BYTE/SHORT/INT", where,
                    index, component_name(a->sparse_index_type));
    if (a->sparse_count == 0 || a->sparse_count > a->count)
        return fail(L, ENG_ERR_INVALID, "%s: accessor %d: sparse count %llu is not in 1..%llu", where, index,
                    (unsigned long long)a->sparse_count, (unsigned long long)a->count);
    const int views[2] = {a->sparse_index_view, a->sparse_value_view};
    const uint64_t offsets[2] = {a->sparse_index_offset, a->sparse_value_offset};
    const uint64_t sizes[2] = {isize, element_size(a->component_type, a->type)};
    const unsigned char *at[2];
    for (int k = 0; k < 2; k++) {
        uint64_t end;
        if (views[k] < 0 || (uint32_t)views[k] >= m->buffer_view_count)
            return fail(L, ENG_ERR_INVALID, "%s: accessor %d: sparse %s buffer view %d out of range", where, index,
                        k ? "values" : "indices", views[k]);
        const gls_buffer_view *bv = &m->buffer_views[views[k]];
        if (!mul_add_u64(sizes[k], a->sparse_count, offsets[k], &end) || end > bv->byte_length)
            return fail(L, ENG_ERR_INVALID, "%s: accessor %d: sparse %s overrun buffer view %d", where, index,
                        k ? "values" : "indices", views[k]);
        at[k] = m->buffers[bv->buffer].data + bv->byte_offset + offsets[k];
    }
    uint64_t prev = 0;
    for (uint64_t i = 0; i < a->sparse_count; i++) {
        uint32_t e = 0;
        if (isize == 1) {
            e = at[0][i];
        } else if (isize == 2) {
            uint16_t x;
            memcpy(&x, at[0] + 2 * i, 2);
            e = x;
        } else {
            memcpy(&e, at[0] + 4 * i, 4);
        }
        if (e >= a->count || (i > 0 && e <= prev))
            return fail(L, ENG_ERR_INVALID, "%s: accessor %d: sparse index %llu is %u (not increasing or not below %llu)",
                        where, index, (unsigned long long)i, e, (unsigned long long)a->count);
        prev = e;
        convert(at[1] + i * sizes[1], a->component_type, a->normalized, comps, v + (size_t)e * comps);
    }
    return ENG_OK;
}

/* Reads an accessor of `comps` components (3: VEC3, 4: VEC4, 1: SCALAR) into a new float
 * array, sparse substitutions applied, refusing more than max_count elements and any
 * non-finite value. quantized: integer component types are accepted too (convert). */
static eng_result read_floats_as(loader *L, int index, const char *where, uint32_t comps, int quantized,
                                 uint64_t max_count, float **out, uint64_t *count)
{
    int type = comps == 1 ? GLS_TYPE_SCALAR : comps == 2 ? GLS_TYPE_VEC2 : comps == 3 ? GLS_TYPE_VEC3 : GLS_TYPE_VEC4;
    const gls_accessor *a = NULL;
    const unsigned char *base = NULL;
    uint64_t stride = 0;
    eng_result r = use_accessor(L, index, where, type, quantized ? -1 : GLS_COMPONENT_FLOAT, 1, &a, &base, &stride);
    if (r)
        return r;
    if (a->count > max_count)
        return fail(L, ENG_ERR_UNSUPPORTED, "%s: accessor %d has %llu elements, more than the %llu supported",
                    where, index, (unsigned long long)a->count, (unsigned long long)max_count);
    float *v = calloc((size_t)a->count * comps, sizeof *v);
    if (!v)
        return nomem(L, where);
    if (base)
        for (uint64_t i = 0; i < a->count; i++)
            convert(base + i * stride, a->component_type, a->normalized, comps, v + i * comps);
    if (a->sparse && (r = apply_sparse(L, a, index, where, comps, v))) {
        free(v);
        return r;
    }
    for (uint64_t i = 0; i < a->count * comps; i++)
        if (!isfinite(v[i])) {
            free(v);
            return fail(L, ENG_ERR_INVALID, "%s: accessor %d element %llu is not finite", where, index,
                        (unsigned long long)(i / comps));
        }
    *out = v;
    *count = a->count;
    return ENG_OK;
}

static eng_result read_floats(loader *L, int index, const char *where, uint32_t comps, uint64_t max_count,
                              float **out, uint64_t *count)
{
    return read_floats_as(L, index, where, comps, 0, max_count, out, count);
}

static eng_result read_indices(loader *L, int index, const char *where, uint32_t vertex_count,
                               uint32_t **out, uint64_t *count)
{
    const gls_accessor *a = NULL;
    const unsigned char *base = NULL;
    uint64_t stride = 0;
    eng_result r = use_accessor(L, index, where, GLS_TYPE_SCALAR, 0, 0, &a, &base, &stride);
    if (r)
        return r;
    if (a->count > MAX_PRIMITIVE_VERTICES)
        return fail(L, ENG_ERR_UNSUPPORTED, "%s: accessor %d has %llu indices, more than the %llu supported",
                    where, index, (unsigned long long)a->count, (unsigned long long)MAX_PRIMITIVE_VERTICES);
    if (a->count % 3 != 0)
        return fail(L, ENG_ERR_INVALID, "%s: accessor %d has %llu indices, not a multiple of 3", where, index,
                    (unsigned long long)a->count);
    uint32_t *v = calloc((size_t)a->count, sizeof *v);
    if (!v)
        return nomem(L, where);
    for (uint64_t i = 0; base && i < a->count; i++) {
        const unsigned char *p = base + i * stride;
        if (a->component_type == GLS_COMPONENT_UNSIGNED_BYTE) {
            v[i] = p[0];
        } else if (a->component_type == GLS_COMPONENT_UNSIGNED_SHORT) {
            uint16_t x;
            memcpy(&x, p, 2);
            v[i] = x;
        } else {
            memcpy(&v[i], p, 4);
        }
    }
    for (uint64_t i = 0; i < a->count; i++)
        if (v[i] >= vertex_count) {
            uint32_t bad = v[i];
            free(v);
            return fail(L, ENG_ERR_INVALID, "%s: index %llu is %u, but there are only %u vertices", where,
                        (unsigned long long)i, bad, vertex_count);
        }
    *out = v;
    *count = a->count;
    return ENG_OK;
}

/* ---------------------------------------------------------------- materials, cameras, lights */

static eng_result check_unit_range(loader *L, const char *where, const char *what, double v)
{
    if (!isfinite(v) || v < 0.0 || v > 1.0)
        return fail(L, ENG_ERR_INVALID, "%s: %s %g is outside [0, 1]", where, what, v);
    return ENG_OK;
}

/* glTF §3.9.2 / KHR_texture_transform: the sRGB transfer function, inverted. */
static float srgb_to_linear(float c)
{
    return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

/* The scene texture for glTF texture `index` decoded as srgb says, made on first use. */
static eng_result make_texture(loader *L, int index, int srgb, const char *where, int32_t *out)
{
    const gls_model *m = L->m;
    scn_scene *s = L->s;
    for (uint32_t i = 0; i < s->texture_count; i++)
        if (L->texture_source[i] == index && s->textures[i].srgb == srgb) {
            *out = (int32_t)i;
            return ENG_OK;
        }
    const gls_texture *t = &m->textures[index];
    gls_pixels px;
    char msg[700];
    gls_status st;
    int source = t->source;
    if (t->webp_source == -2)
        return fail(L, ENG_ERR_INVALID, "texture %d: EXT_texture_webp.source is not a non-negative integer", index);
    if (t->webp_source >= 0) {
        /* EXT_texture_webp: the WebP image where it decodes, else the fallback source. */
        if ((uint32_t)t->webp_source >= m->image_count)
            return fail(L, ENG_ERR_INVALID, "texture %d: EXT_texture_webp.source %d out of range (%u images)", index,
                        t->webp_source, m->image_count);
        st = gls_decode_image(m, t->webp_source, &px, msg, sizeof msg);
        if (st == GLS_ERR_NOMEM)
            return nomem(L, "images");
        if (st == GLS_OK)
            source = t->webp_source;
        else if (t->source >= 0)
            scn_warn(s, "texture %d: EXT_texture_webp %s; its fallback source, image %d, is used", index, msg,
                     t->source);
        else
            return fail(L, ENG_ERR_INVALID, "texture %d: EXT_texture_webp %s, and the texture has no fallback source",
                        index, msg);
    }
    if (source < 0) {
        scn_warn(s, "%s: texture %d has no image (an extension's source?), ignored", where, index);
        *out = -1;
        return ENG_OK;
    }
    if (source == t->source) {
        if ((uint32_t)t->source >= m->image_count)
            return fail(L, ENG_ERR_INVALID, "texture %d: source %d out of range (%u images)", index, t->source,
                        m->image_count);
        st = gls_decode_image(m, t->source, &px, msg, sizeof msg);
        if (st == GLS_ERR_NOMEM)
            return nomem(L, "images");
        if (st != GLS_OK)
            return fail(L, st == GLS_ERR_UNSUPPORTED ? ENG_ERR_UNSUPPORTED : ENG_ERR_INVALID, "texture %d: %s", index,
                        msg);
    }
    const gls_pixels *im = &px;
    scn_texture d;
    memset(&d, 0, sizeof d);
    d.mag_linear = 1;
    d.min_filter = 9987; /* LINEAR_MIPMAP_LINEAR */
    if (t->sampler >= 0) {
        if ((uint32_t)t->sampler >= m->tex_sampler_count)
            return fail(L, ENG_ERR_INVALID, "texture %d: sampler %d out of range (%u samplers)", index, t->sampler,
                        m->tex_sampler_count);
        const gls_tex_sampler *sp = &m->tex_samplers[t->sampler];
        const int wraps[2] = {sp->wrap_s, sp->wrap_t};
        scn_wrap *dst[2] = {&d.wrap_s, &d.wrap_t};
        for (int k = 0; k < 2; k++) {
            if (wraps[k] == 10497 || wraps[k] == -1)
                *dst[k] = SCN_WRAP_REPEAT;
            else if (wraps[k] == 33071)
                *dst[k] = SCN_WRAP_CLAMP;
            else if (wraps[k] == 33648)
                *dst[k] = SCN_WRAP_MIRROR;
            else
                return fail(L, ENG_ERR_INVALID, "samplers[%d]: wrap mode %d is not a glTF wrap mode", t->sampler,
                            wraps[k]);
        }
        if (sp->mag_filter != -1 && sp->mag_filter != 9728 && sp->mag_filter != 9729)
            return fail(L, ENG_ERR_INVALID, "samplers[%d]: magFilter %d is not NEAREST or LINEAR", t->sampler,
                        sp->mag_filter);
        d.mag_linear = sp->mag_filter != 9728;
        if (sp->min_filter != -1 && sp->min_filter != 9728 && sp->min_filter != 9729 &&
            (sp->min_filter < 9984 || sp->min_filter > 9987))
            return fail(L, ENG_ERR_INVALID, "samplers[%d]: minFilter %d is not a glTF filter", t->sampler,
                        sp->min_filter);
        if (sp->min_filter != -1)
            d.min_filter = sp->min_filter;
    }
    d.width = (uint32_t)im->width;
    d.height = (uint32_t)im->height;
    d.srgb = srgb;
    size_t n = (size_t)d.width * d.height;
    d.texels = malloc(n * 4 * sizeof *d.texels);
    scn_texture *grown = realloc(s->textures, (s->texture_count + 1) * sizeof *grown);
    int32_t *src = realloc(L->texture_source, (s->texture_count + 1) * sizeof *src);
    if (grown)
        s->textures = grown;
    if (src)
        L->texture_source = src;
    if (!d.texels || !grown || !src) {
        free(d.texels);
        return nomem(L, "textures");
    }
    for (size_t i = 0; i < n * 4; i++) {
        float c;
        if (im->bits == 16) {
            uint16_t x;
            memcpy(&x, im->rgba + 2 * i, 2);
            c = (float)x / 65535.0f;
        } else {
            c = (float)im->rgba[i] / 255.0f;
        }
        d.texels[i] = srgb && i % 4 != 3 ? srgb_to_linear(c) : c;
    }
    d.mips[0] = d.texels;
    d.levels = 1;
    if (d.min_filter >= 9984 && d.min_filter <= 9987 && !scn_texture_build_mips(&d)) {
        for (uint32_t l = 1; l < d.levels; l++)
            free(d.mips[l]);
        free(d.texels);
        return nomem(L, "texture mip levels");
    }
    L->texture_source[s->texture_count] = index;
    s->textures[s->texture_count] = d;
    *out = (int32_t)s->texture_count++;
    return ENG_OK;
}

/* A material's textureInfo: the texture (made by make_texture), its TEXCOORD set (0 or 1;
 * another set is ignored with a warning) and its KHR_texture_transform as a 2x3 matrix
 * T · R · S (the extension's order). */
static eng_result load_texref(loader *L, const gls_texinfo *g, int srgb, const char *where, scn_texref *d)
{
    d->texture = -1;
    d->texcoord = 0;
    const float id[6] = {1, 0, 0, 1, 0, 0};
    memcpy(d->transform, id, sizeof id);
    if (g->index == -1)
        return ENG_OK;
    if (g->index == -2)
        return fail(L, ENG_ERR_INVALID, "%s: not a textureInfo (an object with an integer index)", where);
    if (g->index < 0 || (uint32_t)g->index >= L->m->texture_count)
        return fail(L, ENG_ERR_INVALID, "%s: texture %d out of range (%u textures)", where, g->index,
                    L->m->texture_count);
    double off[2] = {0, 0}, sc[2] = {1, 1}, rot = 0;
    int set = g->texcoord;
    if (g->has_transform) {
        if ((g->offset.len && g->offset.len != 2) || (g->scale.len && g->scale.len != 2) ||
            !all_finite(g->offset.v, g->offset.len) || !all_finite(g->scale.v, g->scale.len) ||
            g->rotation.state == GLS_NUM_NOT_A_NUMBER || !isfinite(g->rotation.value) ||
            g->transform_texcoord.state == GLS_NUM_NOT_A_NUMBER)
            return fail(L, ENG_ERR_INVALID, "%s: KHR_texture_transform is not offset[2], rotation, scale[2], texCoord",
                        where);
        for (int k = 0; k < 2; k++) {
            if (g->offset.len)
                off[k] = g->offset.v[k];
            if (g->scale.len)
                sc[k] = g->scale.v[k];
        }
        rot = g->rotation.value;
        if (g->transform_texcoord.state == GLS_NUM_PRESENT)
            set = (int)g->transform_texcoord.value;
    }
    if (set != 0 && set != 1) {
        scn_warn(L->s, "%s: TEXCOORD_%d is not supported (only 0 and 1); texture ignored", where, set);
        return ENG_OK;
    }
    eng_result r = make_texture(L, g->index, srgb, where, &d->texture);
    if (r)
        return r;
    /* KHR_texture_transform: uv' = T(offset) · R · S(scale) · uv, R with columns
     * (cos, -sin) and (sin, cos) as the extension's GLSL writes it. */
    double c = cos(rot), sn = sin(rot);
    d->transform[0] = (float)(c * sc[0]);
    d->transform[1] = (float)(-sn * sc[0]);
    d->transform[2] = (float)(sn * sc[1]);
    d->transform[3] = (float)(c * sc[1]);
    d->transform[4] = (float)off[0];
    d->transform[5] = (float)off[1];
    d->texcoord = set;
    return ENG_OK;
}

/* Khronos' conversion of specular-glossiness to metal-roughness (glTF-Sample-Viewer's
 * convert-between-workflows): the metallic value that explains the specular colour over the
 * dielectric F0 of 0.04, and a base colour blended from the diffuse and specular colours. */
static double perceived_brightness(const double c[3])
{
    return sqrt(0.299 * c[0] * c[0] + 0.587 * c[1] * c[1] + 0.114 * c[2] * c[2]);
}

static double solve_metallic(double diffuse, double specular, double one_minus_specular_strength)
{
    const double a = 0.04;
    if (specular < a)
        return 0.0;
    double b = diffuse * one_minus_specular_strength / (1.0 - a) + specular - 2.0 * a;
    double c = a - specular;
    double d = b * b - 4.0 * a * c;
    double m = (-b + sqrt(d > 0.0 ? d : 0.0)) / (2.0 * a);
    return m < 0.0 ? 0.0 : m > 1.0 ? 1.0 : m;
}

void scn_spec_gloss_to_metal_rough(const double diffuse[4], const double specular[3], double glossiness,
                                   float base_color[4], float *metallic, float *roughness)
{
    const double eps = 1e-6;
    double smax = fmax(specular[0], fmax(specular[1], specular[2]));
    double one_minus = 1.0 - smax;
    double m = solve_metallic(perceived_brightness(diffuse), perceived_brightness(specular), one_minus);
    for (int c = 0; c < 3; c++) {
        double from_diffuse = diffuse[c] * one_minus / (1.0 - 0.04) / fmax(1.0 - m, eps);
        double from_specular = (specular[c] - 0.04 * (1.0 - m)) / fmax(m, eps);
        double v = from_diffuse + (from_specular - from_diffuse) * m * m;
        base_color[c] = (float)(v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v);
    }
    base_color[3] = (float)diffuse[3];
    *metallic = (float)m;
    *roughness = (float)(1.0 - glossiness);
}

/* The material extensions that replace or scale what pbrMetallicRoughness gave: the
 * transmission texture (its mean red channel scales transmissionFactor: the engine has one
 * transmission per material), specular-glossiness (converted), unlit (docs/gltf.md). */
static eng_result load_material_extensions(loader *L, const gls_material *g, scn_material *d, const char *where)
{
    eng_result r;
    char what[96];
    if (g->transmission_texture.index != -1) {
        scn_texref t;
        snprintf(what, sizeof what, "%s transmissionTexture", where);
        if ((r = load_texref(L, &g->transmission_texture, 0, what, &t)))
            return r;
        if (t.texture >= 0) {
            const scn_texture *tx = &L->s->textures[t.texture];
            size_t n = (size_t)tx->width * tx->height;
            double sum = 0.0;
            for (size_t i = 0; i < n; i++)
                sum += tx->texels[4 * i];
            d->transmission = (float)(d->transmission * (n ? sum / (double)n : 1.0));
            L->averaged_transmission_texture = 1;
        }
    }
    if (g->spec_gloss) {
        double diffuse[4] = {1, 1, 1, 1}, specular[3] = {1, 1, 1}, gloss = 1.0;
        if (g->diffuse_factor.len && g->diffuse_factor.len != 4)
            return fail(L, ENG_ERR_INVALID, "%s: KHR_materials_pbrSpecularGlossiness.diffuseFactor has %u values, not 4",
                        where, g->diffuse_factor.len);
        if (g->specular_factor.len && g->specular_factor.len != 3)
            return fail(L, ENG_ERR_INVALID, "%s: KHR_materials_pbrSpecularGlossiness.specularFactor has %u values, not 3",
                        where, g->specular_factor.len);
        for (uint32_t c = 0; c < g->diffuse_factor.len; c++)
            if ((r = check_unit_range(L, where, "diffuseFactor component", diffuse[c] = g->diffuse_factor.v[c])))
                return r;
        for (uint32_t c = 0; c < g->specular_factor.len; c++)
            if ((r = check_unit_range(L, where, "specularFactor component", specular[c] = g->specular_factor.v[c])))
                return r;
        if (g->glossiness.state == GLS_NUM_NOT_A_NUMBER)
            return fail(L, ENG_ERR_INVALID, "%s: glossinessFactor is not a number", where);
        if (g->glossiness.state == GLS_NUM_PRESENT && (r = check_unit_range(L, where, "glossinessFactor",
                                                                            gloss = g->glossiness.value)))
            return r;
        scn_spec_gloss_to_metal_rough(diffuse, specular, gloss, d->base_color, &d->metallic, &d->roughness);
        snprintf(what, sizeof what, "%s diffuseTexture", where);
        if ((r = load_texref(L, &g->diffuse_texture, 1, what, &d->base_color_tex)))
            return r;
        d->metallic_roughness_tex.texture = -1;
        if (g->spec_gloss_texture.index != -1)
            L->ignored_spec_gloss_texture = 1;
    }
    if (g->unlit) {
        /* Unlit: the base colour is shown as it is, as emission; the surface reflects and
         * transmits nothing, so lights neither shade it nor bounce off it. Alpha stays. */
        for (int c = 0; c < 3; c++) {
            d->emissive[c] = d->base_color[c];
            d->base_color[c] = 0.0f;
        }
        d->emissive_tex = d->base_color_tex;
        d->metallic = 0.0f;
        d->roughness = 1.0f;
        d->transmission = 0.0f;
        d->metallic_roughness_tex.texture = -1;
        d->normal_tex.texture = -1;
        d->occlusion_tex.texture = -1;
    }
    return ENG_OK;
}

/* Which materials a node's mesh draws: only their textures are made (decoded). */
static eng_result mark_drawn_materials(loader *L)
{
    const gls_model *m = L->m;
    L->drawn = calloc(m->material_count ? m->material_count : 1, 1);
    if (!L->drawn)
        return nomem(L, "materials");
    for (uint32_t n = 0; n < m->node_count; n++) {
        int mi = m->nodes[n].mesh;
        if (mi < 0 || (uint32_t)mi >= m->mesh_count)
            continue;
        for (uint32_t p = 0; p < m->meshes[mi].primitive_count; p++) {
            int mat = m->meshes[mi].primitives[p].material;
            if (mat >= 0 && (uint32_t)mat < m->material_count)
                L->drawn[mat] = 1;
        }
    }
    return ENG_OK;
}

static eng_result load_materials(loader *L)
{
    const gls_model *m = L->m;
    scn_scene *s = L->s;
    s->materials = calloc(m->material_count ? m->material_count : 1, sizeof *s->materials);
    if (!s->materials)
        return nomem(L, "materials");
    s->material_count = m->material_count;
    for (uint32_t i = 0; i < m->material_count; i++) {
        const gls_material *g = &m->materials[i];
        scn_material *d = &s->materials[i];
        char where[48];
        eng_result r;
        snprintf(where, sizeof where, "material %u", i);
        copy_name(d->name, g->name);
        if (g->base_color.len != 4)
            return fail(L, ENG_ERR_INVALID, "%s: baseColorFactor has %u values, not 4", where, g->base_color.len);
        for (int c = 0; c < 4; c++) {
            if ((r = check_unit_range(L, where, "baseColorFactor component", g->base_color.v[c])))
                return r;
            d->base_color[c] = (float)g->base_color.v[c];
        }
        if ((r = check_unit_range(L, where, "metallicFactor", g->metallic)) ||
            (r = check_unit_range(L, where, "roughnessFactor", g->roughness)))
            return r;
        d->metallic = (float)g->metallic;
        d->roughness = (float)g->roughness;
        if (g->emissive.len != 3)
            return fail(L, ENG_ERR_INVALID, "%s: emissiveFactor has %u values, not 3", where, g->emissive.len);
        for (int c = 0; c < 3; c++) {
            double e = g->emissive.v[c];
            if (!isfinite(e) || e < 0.0)
                return fail(L, ENG_ERR_INVALID, "%s: emissiveFactor component %g is negative or not finite",
                            where, e);
            d->emissive[c] = (float)e;
        }
        if (g->emissive_strength.state == GLS_NUM_NOT_A_NUMBER)
            return fail(L, ENG_ERR_INVALID, "%s: KHR_materials_emissive_strength.emissiveStrength is not a number",
                        where);
        if (g->emissive_strength.state == GLS_NUM_PRESENT) {
            double k = g->emissive_strength.value;
            if (!isfinite(k) || k < 0.0 || k > 1e30)
                return fail(L, ENG_ERR_INVALID, "%s: emissiveStrength %g is negative, too large or not finite", where,
                            k);
            for (int c = 0; c < 3; c++) {
                d->emissive[c] = (float)(d->emissive[c] * k);
                if (!isfinite(d->emissive[c]))
                    return fail(L, ENG_ERR_INVALID, "%s: emissiveFactor × emissiveStrength overflows a float", where);
            }
        }
        d->double_sided = g->double_sided;
        if (!L->drawn[i]) {
            scn_texref none = {-1, 0, {1, 0, 0, 1, 0, 0}};
            d->base_color_tex = d->metallic_roughness_tex = d->normal_tex = d->occlusion_tex = d->emissive_tex = none;
        } else if ((r = load_texref(L, &g->base_color_texture, 1, where, &d->base_color_tex)) ||
            (r = load_texref(L, &g->metallic_roughness_texture, 0, where, &d->metallic_roughness_tex)) ||
            (r = load_texref(L, &g->normal_texture, 0, where, &d->normal_tex)) ||
            (r = load_texref(L, &g->occlusion_texture, 0, where, &d->occlusion_tex)) ||
            (r = load_texref(L, &g->emissive_texture, 1, where, &d->emissive_tex)))
            return r;
        if ((r = check_unit_range(L, where, "occlusionTexture.strength", g->occlusion_texture.strength)))
            return r;
        d->occlusion_strength = (float)g->occlusion_texture.strength;
        if (!isfinite(g->normal_texture.strength))
            return fail(L, ENG_ERR_INVALID, "%s: normalTexture.scale is not finite", where);
        d->normal_scale = (float)g->normal_texture.strength;
        d->alpha_mode = SCN_ALPHA_OPAQUE;
        if (g->alpha_mode && strcmp(g->alpha_mode, "MASK") == 0)
            d->alpha_mode = SCN_ALPHA_MASK;
        else if (g->alpha_mode && strcmp(g->alpha_mode, "BLEND") == 0)
            d->alpha_mode = SCN_ALPHA_BLEND;
        else if (g->alpha_mode && g->alpha_mode[0] && strcmp(g->alpha_mode, "OPAQUE") != 0)
            return fail(L, ENG_ERR_INVALID, "%s: alphaMode \"%s\" is not OPAQUE, MASK or BLEND", where, g->alpha_mode);
        if (!isfinite(g->alpha_cutoff) || g->alpha_cutoff < 0.0)
            return fail(L, ENG_ERR_INVALID, "%s: alphaCutoff %g is negative or not finite", where, g->alpha_cutoff);
        d->alpha_cutoff = (float)g->alpha_cutoff;
        d->transmission = 0.0f;
        if (g->transmission.state == GLS_NUM_NOT_A_NUMBER)
            return fail(L, ENG_ERR_INVALID, "%s: KHR_materials_transmission.transmissionFactor is not a number",
                        where);
        if (g->transmission.state == GLS_NUM_PRESENT) {
            if ((r = check_unit_range(L, where, "transmissionFactor", g->transmission.value)))
                return r;
            d->transmission = (float)g->transmission.value;
        }
        d->ior = 1.5f;
        if (g->ior.state == GLS_NUM_NOT_A_NUMBER)
            return fail(L, ENG_ERR_INVALID, "%s: KHR_materials_ior.ior is not a number", where);
        if (g->ior.state == GLS_NUM_PRESENT) {
            if (!isfinite(g->ior.value) || (g->ior.value < 1.0 && g->ior.value != 0.0))
                return fail(L, ENG_ERR_INVALID, "%s: ior %g is neither 0 nor at least 1, or not finite", where,
                            g->ior.value);
            /* KHR_materials_ior allows 0, whose Fresnel F0 = ((ior-1)/(ior+1))^2 is 1 (a
             * perfect mirror); a large finite ior has the same limit and no division by 0. */
            d->ior = g->ior.value == 0.0 ? IOR_ZERO : (float)g->ior.value;
        }
        if (L->drawn[i] && (r = load_material_extensions(L, g, d, where)))
            return r;
    }
    if (L->averaged_transmission_texture)
        scn_warn(s, "KHR_materials_transmission.transmissionTexture: its mean red channel scales "
                    "transmissionFactor (one transmission per material)");
    if (L->ignored_spec_gloss_texture)
        scn_warn(s, "KHR_materials_pbrSpecularGlossiness.specularGlossinessTexture ignored (its factors are "
                    "converted, the texture is not)");
    return ENG_OK;
}

static eng_result load_cameras(loader *L)
{
    const gls_model *m = L->m;
    scn_scene *s = L->s;
    s->cameras = calloc(m->camera_count ? m->camera_count : 1, sizeof *s->cameras);
    if (!s->cameras)
        return nomem(L, "cameras");
    s->camera_count = m->camera_count;
    for (uint32_t i = 0; i < m->camera_count; i++) {
        const gls_camera *g = &m->cameras[i];
        scn_camera *d = &s->cameras[i];
        copy_name(d->name, g->name);
        if (strcmp(g->type, "perspective") != 0) {
            /* yfov 0 marks it unusable: load_nodes detaches it from its nodes, so choosing
             * it in a sequence is an error, while a file that merely contains it loads. */
            scn_warn(L->s, "camera %u: type \"%s\" skipped (only perspective cameras are supported)", i, g->type);
            continue;
        }
        if (!isfinite(g->yfov) || g->yfov <= 0.0 || g->yfov >= PI)
            return fail(L, ENG_ERR_INVALID, "camera %u: yfov %g is outside (0, pi)", i, g->yfov);
        if (!isfinite(g->znear) || g->znear <= 0.0)
            return fail(L, ENG_ERR_INVALID, "camera %u: znear %g is not positive", i, g->znear);
        if (!isfinite(g->aspect_ratio) || g->aspect_ratio < 0.0)
            return fail(L, ENG_ERR_INVALID, "camera %u: aspectRatio %g is negative or not finite", i,
                        g->aspect_ratio);
        double zfar = g->zfar == 0.0 ? 1000.0 * g->znear : g->zfar;
        if (!isfinite(zfar) || zfar <= g->znear)
            return fail(L, ENG_ERR_INVALID, "camera %u: zfar %g is not beyond znear %g", i, zfar, g->znear);
        d->yfov = (float)g->yfov;
        d->aspect = (float)g->aspect_ratio;
        d->znear = (float)g->znear;
        d->zfar = (float)zfar;
    }
    return ENG_OK;
}

/* extras.ispm.radius (point, spot: metres, below 10) or extras.ispm.angular_radius
 * (directional: radians, below π/4); absent or 0 keeps the punctual light. */
static eng_result light_size(loader *L, uint32_t i, const gls_light *g, scn_light *d)
{
    int directional = d->type == SCN_LIGHT_DIRECTIONAL;
    const gls_number *n = directional ? &g->angular_radius : &g->radius;
    const gls_number *other = directional ? &g->radius : &g->angular_radius;
    const char *key = directional ? "angular_radius" : "radius";
    if (other->state != GLS_NUM_ABSENT)
        return fail(L, ENG_ERR_INVALID, "light %u: extras.ispm.%s is for %s lights, use extras.ispm.%s", i,
                    directional ? "radius" : "angular_radius", directional ? "point and spot" : "directional",
                    key);
    d->radius = 0.0f;
    if (n->state == GLS_NUM_NOT_A_NUMBER)
        return fail(L, ENG_ERR_INVALID, "light %u: extras.ispm.%s is not a number (or extras.ispm not an object)",
                    i, key);
    if (n->state == GLS_NUM_ABSENT)
        return ENG_OK;
    double limit = directional ? PI / 4.0 : 10.0;
    if (!isfinite(n->value) || n->value < 0.0 || n->value >= limit)
        return fail(L, ENG_ERR_INVALID, "light %u: extras.ispm.%s %g is not in [0, %g)", i, key, n->value, limit);
    d->radius = (float)n->value;
    return ENG_OK;
}

static eng_result load_lights(loader *L)
{
    const gls_model *m = L->m;
    scn_scene *s = L->s;
    s->lights = calloc(m->light_count ? m->light_count : 1, sizeof *s->lights);
    if (!s->lights)
        return nomem(L, "lights");
    s->light_count = m->light_count;
    for (uint32_t i = 0; i < m->light_count; i++) {
        const gls_light *g = &m->lights[i];
        scn_light *d = &s->lights[i];
        copy_name(d->name, g->name);
        if (strcmp(g->type, "point") == 0)
            d->type = SCN_LIGHT_POINT;
        else if (strcmp(g->type, "spot") == 0)
            d->type = SCN_LIGHT_SPOT;
        else if (strcmp(g->type, "directional") == 0)
            d->type = SCN_LIGHT_DIRECTIONAL;
        else
            return fail(L, ENG_ERR_INVALID, "light %u: type \"%s\" is not point, spot or directional", i, g->type);
        if (g->color.len == 0) {
            d->color[0] = d->color[1] = d->color[2] = 1.0f;
        } else if (g->color.len != 3) {
            return fail(L, ENG_ERR_INVALID, "light %u: color has %u values, not 3", i, g->color.len);
        } else {
            for (int c = 0; c < 3; c++) {
                if (!isfinite(g->color.v[c]) || g->color.v[c] < 0.0)
                    return fail(L, ENG_ERR_INVALID, "light %u: color component %g is negative or not finite", i,
                                g->color.v[c]);
                d->color[c] = (float)g->color.v[c];
            }
        }
        if (!isfinite(g->intensity) || g->intensity < 0.0)
            return fail(L, ENG_ERR_INVALID, "light %u: intensity %g is negative or not finite", i, g->intensity);
        if (!isfinite(g->range) || g->range < 0.0)
            return fail(L, ENG_ERR_INVALID, "light %u: range %g is negative or not finite", i, g->range);
        d->intensity = (float)g->intensity;
        d->range = (float)g->range;
        d->inner_cone = 0.0f;
        d->outer_cone = (float)(PI / 4.0);
        if (d->type == SCN_LIGHT_SPOT) {
            if (!isfinite(g->inner_cone) || !isfinite(g->outer_cone) || g->inner_cone < 0.0 ||
                g->inner_cone >= g->outer_cone || g->outer_cone > PI / 2.0)
                return fail(L, ENG_ERR_INVALID,
                            "light %u: spot cone angles inner %g, outer %g violate 0 <= inner < outer <= pi/2", i,
                            g->inner_cone, g->outer_cone);
            d->inner_cone = (float)g->inner_cone;
            d->outer_cone = (float)g->outer_cone;
        }
        eng_result r = light_size(L, i, g, d);
        if (r != ENG_OK)
            return r;
    }
    return ENG_OK;
}

/* ---------------------------------------------------------------- meshes */

/* Replaces an indexed triangle list without normals by one where each triangle has its own
 * three vertices and its face normal (normalised cross product of its edges in winding
 * order; (0, 1, 0) for a triangle of zero area, which covers no pixel anyway). */
/* The normals of zero length (count of them) in p: glTF asks for unit normals, but the
 * validator lets zero ones through (an accessor without bufferView is all zeros). Each
 * becomes the normalised sum of the area-weighted normals of the triangles that use its
 * vertex, or +Y where those are all degenerate (as flat_normals does); one warning. */
static void fill_zero_normals(loader *L, scn_primitive *p, const char *where, uint32_t count)
{
    double *sum = calloc((size_t)p->vertex_count * 3, sizeof *sum);
    if (!sum)
        eng_oom(where);
    for (uint32_t t = 0; t + 2 < p->index_count; t += 3) {
        const uint32_t *ix = p->indices + t;
        const float *v[3];
        for (int k = 0; k < 3; k++)
            v[k] = p->positions + (size_t)ix[k] * 3;
        double e1[3], e2[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = (double)v[1][k] - v[0][k];
            e2[k] = (double)v[2][k] - v[0][k];
        }
        const double c[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                             e1[0] * e2[1] - e1[1] * e2[0]};
        for (int k = 0; k < 3; k++)
            for (int a = 0; a < 3; a++)
                sum[(size_t)ix[k] * 3 + a] += c[a];
    }
    for (uint32_t v = 0; v < p->vertex_count; v++) {
        float *n = p->normals + (size_t)v * 3;
        if (n[0] != 0.0f || n[1] != 0.0f || n[2] != 0.0f)
            continue;
        const double *s = sum + (size_t)v * 3;
        double len = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
        if (len > 0.0 && isfinite(len)) {
            for (int k = 0; k < 3; k++)
                n[k] = (float)(s[k] / len) + 0.0f; /* -0.0 would change buffer digests */
        } else {
            n[0] = 0.0f;
            n[1] = 1.0f;
            n[2] = 0.0f;
        }
    }
    free(sum);
    scn_warn(L->s, "%s NORMAL: %u of %u normals have zero length; each is replaced by the normal of the triangles "
                   "at its vertex", where, count, p->vertex_count);
}

static eng_result flat_normals(loader *L, scn_primitive *p, const char *where)
{
    uint32_t n = p->index_count;
    float *pos = malloc((size_t)n * 3 * sizeof *pos);
    float *nrm = malloc((size_t)n * 3 * sizeof *nrm);
    if (!pos || !nrm) {
        free(pos);
        free(nrm);
        return nomem(L, where);
    }
    for (uint32_t t = 0; t < n / 3; t++) {
        const float *v[3];
        for (int k = 0; k < 3; k++) {
            v[k] = p->positions + (size_t)p->indices[3 * t + k] * 3;
            memcpy(pos + ((size_t)3 * t + k) * 3, v[k], 3 * sizeof *pos);
        }
        double e1[3], e2[3], c[3];
        for (int k = 0; k < 3; k++) {
            e1[k] = (double)v[1][k] - v[0][k];
            e2[k] = (double)v[2][k] - v[0][k];
        }
        c[0] = e1[1] * e2[2] - e1[2] * e2[1];
        c[1] = e1[2] * e2[0] - e1[0] * e2[2];
        c[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        float f[3] = {0.0f, 1.0f, 0.0f};
        if (len > 0.0 && isfinite(len))
            for (int k = 0; k < 3; k++)
                f[k] = (float)(c[k] / len) + 0.0f; /* -0.0 would change buffer digests */
        for (int k = 0; k < 3; k++)
            memcpy(nrm + ((size_t)3 * t + k) * 3, f, sizeof f);
    }
    /* The other attributes follow the vertices they belonged to. */
    float **attr[4] = {&p->texcoords[0], &p->texcoords[1], &p->colors, &p->tangents};
    const size_t comps[4] = {2, 2, 4, 4};
    for (int a = 0; a < 4; a++) {
        if (!*attr[a])
            continue;
        float *un = malloc((size_t)n * comps[a] * sizeof *un);
        if (!un) {
            free(pos);
            free(nrm);
            return nomem(L, where);
        }
        for (uint32_t i = 0; i < n; i++)
            memcpy(un + i * comps[a], *attr[a] + (size_t)p->indices[i] * comps[a], comps[a] * sizeof *un);
        free(*attr[a]);
        *attr[a] = un;
    }
    const size_t inf = p->influences ? p->influences : 4;
    if (p->joints) {
        uint32_t *un = malloc((size_t)n * inf * sizeof *un);
        if (!un) {
            free(pos);
            free(nrm);
            return nomem(L, where);
        }
        for (uint32_t i = 0; i < n; i++)
            memcpy(un + (size_t)i * inf, p->joints + (size_t)p->indices[i] * inf, inf * sizeof *un);
        free(p->joints);
        p->joints = un;
    }
    float **per_target[4] = {&p->weights, &p->target_positions, &p->target_normals, &p->target_tangents};
    const size_t tcomps[4] = {inf, 3, 3, 3};
    for (int a = 0; a < 4; a++) {
        if (!*per_target[a])
            continue;
        size_t sets = a == 0 ? 1 : p->target_count;
        float *un = malloc(sets * n * tcomps[a] * sizeof *un);
        if (!un) {
            free(pos);
            free(nrm);
            return nomem(L, where);
        }
        for (size_t t = 0; t < sets; t++)
            for (uint32_t i = 0; i < n; i++)
                memcpy(un + (t * n + i) * tcomps[a],
                       *per_target[a] + (t * p->vertex_count + p->indices[i]) * tcomps[a], tcomps[a] * sizeof *un);
        free(*per_target[a]);
        *per_target[a] = un;
    }
    p->flat = 1;
    for (uint32_t i = 0; i < n; i++)
        p->indices[i] = i;
    free(p->positions);
    free(p->normals);
    p->positions = pos;
    p->normals = nrm;
    p->vertex_count = n;
    return ENG_OK;
}

static int find_attribute(const gls_primitive *g, const char *semantic)
{
    for (uint32_t a = 0; a < g->attribute_count; a++)
        if (strcmp(g->attributes[a].semantic, semantic) == 0)
            return g->attributes[a].accessor;
    return -2;
}

/* One skinning set n: JOINTS_n (UNSIGNED_BYTE/SHORT VEC4) and WEIGHTS_n (FLOAT or normalized
 * UNSIGNED_BYTE/SHORT VEC4), both present (*j, *w: 4 per vertex, malloc'd), both absent
 * (ENG_OK, *j = *w = NULL), or an error. */
static eng_result load_skin_set(loader *L, const gls_primitive *g, scn_primitive *d, const char *where, int n,
                                uint32_t **jout, float **wout)
{
    const gls_model *m = L->m;
    char jn[16], wn[16];
    snprintf(jn, sizeof jn, "JOINTS_%d", n);
    snprintf(wn, sizeof wn, "WEIGHTS_%d", n);
    *jout = NULL;
    *wout = NULL;
    int ja = find_attribute(g, jn), wa = find_attribute(g, wn);
    if (ja == -2 && wa == -2)
        return ENG_OK;
    if (ja == -2 || wa == -2)
        return fail(L, ENG_ERR_INVALID, "%s: %s without %s", where, ja == -2 ? wn : jn, ja == -2 ? jn : wn);
    const gls_accessor *aj = &m->accessors[ja], *aw = &m->accessors[wa];
    if ((aj->component_type != GLS_COMPONENT_UNSIGNED_BYTE && aj->component_type != GLS_COMPONENT_UNSIGNED_SHORT) ||
        aj->normalized)
        return fail(L, ENG_ERR_INVALID, "%s %s: accessor %d is %s, must be UNSIGNED_BYTE or UNSIGNED_SHORT", where, jn,
                    ja, component_name(aj->component_type));
    if (aw->component_type != GLS_COMPONENT_FLOAT &&
        !((aw->component_type == GLS_COMPONENT_UNSIGNED_BYTE || aw->component_type == GLS_COMPONENT_UNSIGNED_SHORT) &&
          aw->normalized))
        return fail(L, ENG_ERR_INVALID, "%s %s: accessor %d must be FLOAT or normalized UNSIGNED_BYTE/SHORT", where,
                    wn, wa);
    char what[160];
    uint64_t count;
    float *j = NULL, *w = NULL;
    eng_result r;
    snprintf(what, sizeof what, "%s %s", where, jn);
    if ((r = read_floats_as(L, ja, what, 4, 1, MAX_PRIMITIVE_VERTICES, &j, &count)))
        return r;
    if (count != d->vertex_count) {
        free(j);
        return fail(L, ENG_ERR_INVALID, "%s: %llu joints for %u positions", what, (unsigned long long)count,
                    d->vertex_count);
    }
    uint32_t *ji = malloc((size_t)count * 4 * sizeof *ji);
    if (!ji) {
        free(j);
        return nomem(L, what);
    }
    for (size_t i = 0; i < count * 4; i++)
        ji[i] = (uint32_t)j[i];
    free(j);
    snprintf(what, sizeof what, "%s %s", where, wn);
    if ((r = read_floats_as(L, wa, what, 4, 1, MAX_PRIMITIVE_VERTICES, &w, &count))) {
        free(ji);
        return r;
    }
    if (count != d->vertex_count)
        r = fail(L, ENG_ERR_INVALID, "%s: %llu weights for %u positions", what, (unsigned long long)count,
                 d->vertex_count);
    for (size_t i = 0; !r && i < count * 4; i++)
        if (w[i] < 0.0f)
            r = fail(L, ENG_ERR_INVALID, "%s: weight %g of vertex %zu is negative", what, w[i], i / 4);
    if (r) {
        free(ji);
        free(w);
        return r;
    }
    *jout = ji;
    *wout = w;
    return ENG_OK;
}

/* Skinning attributes (glTF §3.7.3.1): JOINTS_0/WEIGHTS_0 and, for more than 4 influences,
 * JOINTS_1/WEIGHTS_1, interleaved into d->joints/d->weights with d->influences (4 or 8) per
 * vertex; a set 1 without set 0 is an error, sets 2 and up are ignored with a warning. Joint
 * indices are checked against the skin of each node that draws the mesh (load_skins). */
static eng_result load_skin_attributes(loader *L, const gls_primitive *g, scn_primitive *d, const char *where)
{
    uint32_t *j[2] = {NULL, NULL};
    float *w[2] = {NULL, NULL};
    eng_result r = ENG_OK;
    for (int n = 0; n < 2 && !r; n++)
        r = load_skin_set(L, g, d, where, n, &j[n], &w[n]);
    if (!r && !j[0] && j[1])
        r = fail(L, ENG_ERR_INVALID, "%s: JOINTS_1 without JOINTS_0", where);
    if (!r && find_attribute(g, "JOINTS_2") != -2)
        scn_warn(L->s, "%s: JOINTS_2 and later sets ignored (8 influences per vertex are used)", where);
    if (!r && j[1]) {
        size_t nv = d->vertex_count;
        d->joints = malloc(nv * 8 * sizeof *d->joints);
        d->weights = malloc(nv * 8 * sizeof *d->weights);
        if (!d->joints || !d->weights)
            r = nomem(L, where);
        for (size_t v = 0; !r && v < nv; v++)
            for (int n = 0; n < 2; n++) {
                memcpy(d->joints + v * 8 + 4 * n, j[n] + v * 4, 4 * sizeof *d->joints);
                memcpy(d->weights + v * 8 + 4 * n, w[n] + v * 4, 4 * sizeof *d->weights);
            }
        d->influences = 8;
        for (int n = 0; n < 2; n++) {
            free(j[n]);
            free(w[n]);
        }
        return r;
    }
    free(j[1]);
    free(w[1]);
    if (r) {
        free(j[0]);
        free(w[0]);
        return r;
    }
    d->joints = j[0];
    d->weights = w[0];
    d->influences = j[0] ? 4 : 0;
    return ENG_OK;
}

/* Morph targets' POSITION, NORMAL and TANGENT deltas (other target attributes, TEXCOORD or
 * COLOR, are ignored), one array of target_count × vertex_count × 3 each. */
static eng_result load_targets(loader *L, const gls_primitive *g, scn_primitive *d, const char *where)
{
    if (g->target_count == 0)
        return ENG_OK;
    if (g->target_count > 1024)
        return fail(L, ENG_ERR_UNSUPPORTED, "%s: %u morph targets, more than the 1024 supported", where,
                    g->target_count);
    size_t n = (size_t)d->vertex_count * 3;
    d->target_count = g->target_count;
    static const char *const sem[3] = {"POSITION", "NORMAL", "TANGENT"};
    float **dst[3] = {&d->target_positions, &d->target_normals, &d->target_tangents};
    for (uint32_t t = 0; t < g->target_count; t++) {
        const gls_target *gt = &g->targets[t];
        for (int a = 0; a < 3; a++) {
            int acc = -2;
            for (uint32_t k = 0; k < gt->attribute_count; k++)
                if (strcmp(gt->attributes[k].semantic, sem[a]) == 0)
                    acc = gt->attributes[k].accessor;
            if (acc == -2)
                continue;
            char what[160];
            uint64_t count;
            float *v = NULL;
            snprintf(what, sizeof what, "%s targets[%u] %s", where, t, sem[a]);
            if (acc < 0 || (uint32_t)acc >= L->m->accessor_count)
                return fail(L, ENG_ERR_INVALID, "%s: accessor %d out of range (%u accessors)", what, acc,
                            L->m->accessor_count);
            /* Quantized deltas may be normalized or not (KHR_mesh_quantization); read as written. */
            eng_result r = read_floats_as(L, acc, what, 3, 1, MAX_PRIMITIVE_VERTICES, &v, &count);
            if (r)
                return r;
            if (count != d->vertex_count) {
                free(v);
                return fail(L, ENG_ERR_INVALID, "%s: %llu deltas for %u positions", what, (unsigned long long)count,
                            d->vertex_count);
            }
            if (!*dst[a] && !(*dst[a] = calloc(n * g->target_count, sizeof(float)))) {
                free(v);
                return nomem(L, what);
            }
            memcpy(*dst[a] + t * n, v, n * sizeof(float));
            free(v);
        }
    }
    return ENG_OK;
}

/* A per-vertex attribute (accessor acc, semantic name) of comps floats per vertex into *out,
 * which must have vertex_count elements. */
static eng_result read_vertex_attribute(loader *L, int acc, const char *where, const char *name, uint32_t comps,
                                        uint32_t vertex_count, float **out)
{
    char what[160];
    uint64_t count;
    snprintf(what, sizeof what, "%s %s", where, name);
    eng_result r = read_floats_as(L, acc, what, comps, 1, MAX_PRIMITIVE_VERTICES, out, &count);
    if (r)
        return r;
    if (count != vertex_count)
        return fail(L, ENG_ERR_INVALID, "%s: %llu values for %u positions", what, (unsigned long long)count,
                    vertex_count);
    return ENG_OK;
}

/* *skip: the primitive is valid glTF that draws nothing here (points, lines, strips, fans,
 * no POSITION): left out with a warning, as glTF lets a client do (§3.7.2.1). */
static eng_result load_primitive(loader *L, const gls_primitive *g, scn_primitive *d, const char *where, int *skip)
{
    static const char *const modes[] = {"POINTS", "LINES", "LINE_LOOP", "LINE_STRIP", "TRIANGLES",
                                        "TRIANGLE_STRIP", "TRIANGLE_FAN"};
    const gls_model *m = L->m;
    eng_result r;
    *skip = 0;
    if (g->mode < 0 || g->mode > 6)
        return fail(L, ENG_ERR_INVALID, "%s: mode %d is not a glTF primitive mode", where, g->mode);
    if (g->mode != 4) {
        scn_warn(L->s, "%s: mode %s skipped (only TRIANGLES are rendered)", where, modes[g->mode]);
        *skip = 1;
        return ENG_OK;
    }
    if (g->material < -1 || g->material >= (int)m->material_count)
        return fail(L, ENG_ERR_INVALID, "%s: material %d out of range (%u materials)", where, g->material,
                    m->material_count);
    d->material = g->material;
    for (uint32_t a = 0; a < g->attribute_count; a++)
        if (g->attributes[a].accessor < 0 || (uint32_t)g->attributes[a].accessor >= m->accessor_count)
            return fail(L, ENG_ERR_INVALID, "%s: attribute %s: accessor %d out of range (%u accessors)", where,
                        g->attributes[a].semantic, g->attributes[a].accessor, m->accessor_count);

    char what[160];
    uint64_t count;
    uint32_t zero_normals = 0;
    int pos_acc = find_attribute(g, "POSITION");
    if (pos_acc == -2) {
        scn_warn(L->s, "%s: no POSITION attribute, skipped", where);
        *skip = 1;
        return ENG_OK;
    }
    snprintf(what, sizeof what, "%s POSITION", where);
    if ((r = read_floats_as(L, pos_acc, what, 3, 1, MAX_PRIMITIVE_VERTICES, &d->positions, &count)))
        return r;
    d->vertex_count = (uint32_t)count;

    int nrm_acc = find_attribute(g, "NORMAL");
    if (nrm_acc != -2) {
        if ((r = read_vertex_attribute(L, nrm_acc, where, "NORMAL", 3, d->vertex_count, &d->normals)))
            return r;
        for (uint32_t v = 0; v < d->vertex_count; v++) {
            float *n = d->normals + (size_t)v * 3;
            double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
            if (len == 0.0) { /* data, not an error (finite: read_vertex_attribute checked) */
                zero_normals++;
                continue;
            }
            for (int k = 0; k < 3; k++)
                n[k] = (float)(n[k] / len);
        }
    }

    for (int set = 0; set < 2; set++) {
        int acc = find_attribute(g, set ? "TEXCOORD_1" : "TEXCOORD_0");
        if (acc == -2)
            continue;
        if ((r = read_vertex_attribute(L, acc, where, set ? "TEXCOORD_1" : "TEXCOORD_0", 2, d->vertex_count,
                                       &d->texcoords[set])))
            return r;
    }
    int tan_acc = find_attribute(g, "TANGENT");
    if (tan_acc != -2) {
        /* glTF §3.7.2.1: VEC4, FLOAT or normalized BYTE/SHORT; xyz unit, w ±1. */
        if ((r = read_vertex_attribute(L, tan_acc, where, "TANGENT", 4, d->vertex_count, &d->tangents)))
            return r;
        for (uint32_t v = 0; v < d->vertex_count; v++)
            d->tangents[(size_t)v * 4 + 3] = d->tangents[(size_t)v * 4 + 3] < 0.0f ? -1.0f : 1.0f;
    }
    int col_acc = find_attribute(g, "COLOR_0");
    if (col_acc != -2) {
        snprintf(what, sizeof what, "%s COLOR_0", where);
        int vec3 = m->accessors[col_acc].type == GLS_TYPE_VEC3;
        float *c = NULL;
        if ((r = read_floats_as(L, col_acc, what, vec3 ? 3 : 4, 1, MAX_PRIMITIVE_VERTICES, &c, &count)))
            return r;
        d->colors = malloc((size_t)count * 4 * sizeof *d->colors);
        if (!d->colors) {
            free(c);
            return nomem(L, what);
        }
        for (uint64_t v = 0; v < count; v++)
            for (int k = 0; k < 4; k++)
                d->colors[v * 4 + k] = k < 3 || !vec3 ? c[v * (vec3 ? 3 : 4) + k] : 1.0f;
        free(c);
        if (count != d->vertex_count)
            return fail(L, ENG_ERR_INVALID, "%s: %llu colours for %u positions", what, (unsigned long long)count,
                        d->vertex_count);
    }

    if ((r = load_skin_attributes(L, g, d, where)) || (r = load_targets(L, g, d, where)))
        return r;

    if (g->indices >= 0) {
        snprintf(what, sizeof what, "%s indices", where);
        if ((r = read_indices(L, g->indices, what, d->vertex_count, &d->indices, &count)))
            return r;
        d->index_count = (uint32_t)count;
    } else {
        if (g->indices != -1)
            return fail(L, ENG_ERR_INVALID, "%s: indices accessor %d out of range", where, g->indices);
        if (d->vertex_count % 3 != 0)
            return fail(L, ENG_ERR_INVALID, "%s: %u vertices without indices, not a multiple of 3", where,
                        d->vertex_count);
        d->indices = malloc((size_t)d->vertex_count * sizeof *d->indices);
        if (!d->indices)
            return nomem(L, where);
        for (uint32_t i = 0; i < d->vertex_count; i++)
            d->indices[i] = i;
        d->index_count = d->vertex_count;
    }

    if (zero_normals)
        fill_zero_normals(L, d, where, zero_normals);
    if (!d->normals && (r = flat_normals(L, d, where)))
        return r;
    /* A normal texture needs tangents: the glTF's, or generated from its texcoord set. */
    const scn_material *mat = d->material >= 0 ? &L->s->materials[d->material] : NULL;
    if (mat && mat->normal_tex.texture >= 0 && !d->tangents && d->texcoords[mat->normal_tex.texcoord] &&
        !(d->tangents = scn_generate_tangents(d, mat->normal_tex.texcoord)))
        return nomem(L, where);
    L->total_vertices += d->vertex_count;
    if (L->total_vertices > MAX_SCENE_VERTICES)
        return fail(L, ENG_ERR_UNSUPPORTED, "%s: the scene exceeds %llu vertices", where,
                    (unsigned long long)MAX_SCENE_VERTICES);
    return ENG_OK;
}

static eng_result load_meshes(loader *L)
{
    const gls_model *m = L->m;
    scn_scene *s = L->s;
    uint64_t total = 0;
    for (uint32_t i = 0; i < m->mesh_count; i++)
        total += m->meshes[i].primitive_count;
    if (total > UINT32_MAX / 2)
        return fail(L, ENG_ERR_UNSUPPORTED, "%llu primitives", (unsigned long long)total);
    s->meshes = calloc(m->mesh_count ? m->mesh_count : 1, sizeof *s->meshes);
    s->primitives = calloc(total ? (size_t)total : 1, sizeof *s->primitives);
    if (!s->meshes || !s->primitives)
        return nomem(L, "meshes");
    s->mesh_count = m->mesh_count;
    for (uint32_t i = 0; i < m->mesh_count; i++) {
        const gls_mesh *g = &m->meshes[i];
        scn_mesh *d = &s->meshes[i];
        copy_name(d->name, g->name);
        d->first_primitive = s->primitive_count;
        for (uint32_t p = 0; p < g->primitive_count; p++) {
            char where[64];
            int skip;
            snprintf(where, sizeof where, "meshes[%u].primitives[%u]", i, p);
            /* Counted before loading so scn_destroy frees a half-built primitive. */
            scn_primitive *dp = &s->primitives[s->primitive_count++];
            eng_result r = load_primitive(L, &g->primitives[p], dp, where, &skip);
            if (r)
                return r;
            if (skip) {
                s->primitive_count--; /* nothing was allocated */
                continue;
            }
            if (d->primitive_count > 0 && dp->target_count != d->weight_count)
                return fail(L, ENG_ERR_INVALID, "%s: %u morph targets, but the mesh's primitive 0 has %u", where,
                            dp->target_count, d->weight_count);
            d->weight_count = dp->target_count;
            d->primitive_count++;
        }
        if (g->weights.len && g->weights.len != d->weight_count)
            return fail(L, ENG_ERR_INVALID, "meshes[%u]: %u weights for %u morph targets", i, g->weights.len,
                        d->weight_count);
        if (!all_finite(g->weights.v, g->weights.len))
            return fail(L, ENG_ERR_INVALID, "meshes[%u]: a weight is not finite", i);
        if (d->weight_count) {
            if (!(d->weights = calloc(d->weight_count, sizeof *d->weights)))
                return nomem(L, "mesh weights");
            for (uint32_t k = 0; k < g->weights.len; k++)
                d->weights[k] = (float)g->weights.v[k];
        }
    }
    return ENG_OK;
}

/* ---------------------------------------------------------------- nodes */

static eng_result check_node(loader *L, uint32_t i)
{
    const gls_model *m = L->m;
    const gls_node *g = &m->nodes[i];
    if (g->mesh < -1 || g->mesh >= (int)m->mesh_count)
        return fail(L, ENG_ERR_INVALID, "node %u: mesh %d out of range (%u meshes)", i, g->mesh, m->mesh_count);
    if (g->skin < -1 || g->skin >= (int)m->skin_count)
        return fail(L, ENG_ERR_INVALID, "node %u: skin %d out of range (%u skins)", i, g->skin, m->skin_count);
    if (g->weights.len) {
        uint32_t want = g->mesh >= 0 ? L->s->meshes[g->mesh].weight_count : 0;
        if (g->weights.len != want)
            return fail(L, ENG_ERR_INVALID, "node %u: %u weights for %u morph targets", i, g->weights.len, want);
        if (!all_finite(g->weights.v, g->weights.len))
            return fail(L, ENG_ERR_INVALID, "node %u: a weight is not finite", i);
    }
    if (g->camera < -1 || g->camera >= (int)m->camera_count)
        return fail(L, ENG_ERR_INVALID, "node %u: camera %d out of range (%u cameras)", i, g->camera,
                    m->camera_count);
    if (g->has_light) {
        double l = g->light.value;
        if (g->light.state != GLS_NUM_PRESENT)
            return fail(L, ENG_ERR_INVALID, "node %u: KHR_lights_punctual has no numeric \"light\"", i);
        if (l != floor(l) || l < 0.0 || l >= (double)m->light_count)
            return fail(L, ENG_ERR_INVALID, "node %u: light %g out of range (%u lights)", i, l, m->light_count);
    }
    struct {
        const char *name;
        gls_doubles d;
        uint32_t len;
    } vec[4] = {{"translation", g->translation, 3}, {"rotation", g->rotation, 4}, {"scale", g->scale, 3},
                {"matrix", g->matrix, 16}};
    for (int k = 0; k < 4; k++) {
        if (vec[k].d.len != 0 && vec[k].d.len != vec[k].len)
            return fail(L, ENG_ERR_INVALID, "node %u: %s has %u values, not %u", i, vec[k].name, vec[k].d.len,
                        vec[k].len);
        if (!all_finite(vec[k].d.v, vec[k].d.len))
            return fail(L, ENG_ERR_INVALID, "node %u: %s is not finite", i, vec[k].name);
    }
    if (g->rotation.len == 4) {
        const double *q = g->rotation.v;
        if (!(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3] > 0.0))
            return fail(L, ENG_ERR_INVALID, "node %u: rotation is the zero quaternion", i);
    }
    return ENG_OK;
}

static void fill_node(const gls_node *g, scn_node *d)
{
    copy_name(d->name, g->name);
    d->mesh = g->mesh;
    d->camera = g->camera;
    d->light = g->has_light ? (int32_t)g->light.value : -1;
    d->skin = g->mesh >= 0 ? g->skin : -1;
    for (int k = 0; k < 16; k++)
        d->matrix[k] = (k % 5 == 0) ? 1.0f : 0.0f;
    d->translation[0] = d->translation[1] = d->translation[2] = 0.0f;
    d->rotation[0] = d->rotation[1] = d->rotation[2] = 0.0f;
    d->rotation[3] = 1.0f;
    d->scale[0] = d->scale[1] = d->scale[2] = 1.0f;
    d->has_matrix = g->matrix.len == 16;
    if (d->has_matrix) {
        for (int k = 0; k < 16; k++)
            d->matrix[k] = (float)g->matrix.v[k];
        return;
    }
    for (int k = 0; k < 3 && g->translation.len; k++)
        d->translation[k] = (float)g->translation.v[k];
    for (int k = 0; k < 3 && g->scale.len; k++)
        d->scale[k] = (float)g->scale.v[k];
    if (g->rotation.len) {
        const double *q = g->rotation.v;
        double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        for (int k = 0; k < 4; k++)
            d->rotation[k] = (float)(q[k] / len);
    }
}

/* Validates every node and the hierarchy, then keeps the nodes reachable from the chosen
 * scene in pre-order. remap[old] is the kept index or -1. */
static eng_result load_nodes(loader *L, int32_t *remap)
{
    const gls_model *m = L->m;
    scn_scene *s = L->s;
    uint32_t n = m->node_count;
    eng_result r = ENG_OK;
    int32_t *parent = malloc((n ? n : 1) * sizeof *parent);
    unsigned char *state = calloc(n ? n : 1, 1);
    uint32_t *stack = malloc((n ? n : 1) * sizeof *stack);
    uint32_t *order = malloc((n ? n : 1) * sizeof *order);
    if (!parent || !state || !stack || !order) {
        r = nomem(L, "nodes");
        goto done;
    }
    for (uint32_t i = 0; i < n; i++) {
        parent[i] = -1;
        remap[i] = -1;
    }
    for (uint32_t i = 0; i < n; i++) {
        const gls_node *g = &m->nodes[i];
        if ((r = check_node(L, i)))
            goto done;
        for (uint32_t c = 0; c < g->child_count; c++) {
            int ch = g->children[c];
            if (ch < 0 || (uint32_t)ch >= n) {
                r = fail(L, ENG_ERR_INVALID, "node %u: child %d out of range (%u nodes)", i, ch, n);
                goto done;
            }
            if ((uint32_t)ch == i) {
                r = fail(L, ENG_ERR_INVALID, "node %u: is its own child (cycle)", i);
                goto done;
            }
            if (parent[ch] != -1) {
                r = fail(L, ENG_ERR_INVALID, "node %d: has two parents (nodes %d and %u)", ch, parent[ch], i);
                goto done;
            }
            parent[ch] = (int32_t)i;
        }
    }
    /* With one parent each, a cycle is a walk up that meets itself: 0 new, 1 on the
     * current walk, 2 known to end at a root. */
    for (uint32_t i = 0; i < n; i++) {
        int32_t j = (int32_t)i;
        while (j != -1 && state[j] == 0) {
            state[j] = 1;
            j = parent[j];
        }
        if (j != -1 && state[j] == 1) {
            r = fail(L, ENG_ERR_INVALID, "node %d: is part of a cycle of children", j);
            goto done;
        }
        for (j = (int32_t)i; j != -1 && state[j] == 1; j = parent[j])
            state[j] = 2;
    }

    const int *roots = NULL;
    uint32_t root_count = 0;
    int sc = m->default_scene;
    if (sc < -1 || sc >= (int)m->scene_count) {
        r = fail(L, ENG_ERR_INVALID, "scene %d out of range (%u scenes)", sc, m->scene_count);
        goto done;
    }
    if (L->scene_index >= 0) {
        if ((uint32_t)L->scene_index >= m->scene_count) {
            r = fail(L, ENG_ERR_INVALID, "scene_index %d out of range (the file has %u scenes)", L->scene_index,
                     m->scene_count);
            goto done;
        }
        sc = L->scene_index;
    }
    for (uint32_t k = 0; k < m->scene_count; k++)
        for (uint32_t j = 0; j < m->scenes[k].node_count; j++)
            if (m->scenes[k].nodes[j] < 0 || (uint32_t)m->scenes[k].nodes[j] >= n) {
                r = fail(L, ENG_ERR_INVALID, "scenes[%u]: node %d out of range (%u nodes)", k,
                         m->scenes[k].nodes[j], n);
                goto done;
            }
    if (sc == -1 && m->scene_count > 0)
        sc = 0;
    if (sc >= 0) {
        roots = m->scenes[sc].nodes;
        root_count = m->scenes[sc].node_count;
    }

    uint32_t kept = 0;
    for (uint32_t k = 0; k < (sc >= 0 ? root_count : n); k++) {
        uint32_t root = sc >= 0 ? (uint32_t)roots[k] : k;
        if (sc < 0 && parent[root] != -1)
            continue;
        if (parent[root] != -1) {
            r = fail(L, ENG_ERR_INVALID, "scenes[%d]: node %u is not a root (its parent is node %d)", sc, root,
                     parent[root]);
            goto done;
        }
        if (remap[root] != -1) {
            r = fail(L, ENG_ERR_INVALID, "scenes[%d]: node %u is listed twice", sc, root);
            goto done;
        }
        uint32_t top = 0;
        stack[top++] = root;
        while (top) {
            uint32_t i = stack[--top];
            remap[i] = (int32_t)kept;
            order[kept++] = i;
            const gls_node *g = &m->nodes[i];
            for (uint32_t c = g->child_count; c-- > 0;)
                stack[top++] = (uint32_t)g->children[c];
        }
    }

    s->nodes = calloc(kept ? kept : 1, sizeof *s->nodes);
    if (!s->nodes) {
        r = nomem(L, "nodes");
        goto done;
    }
    s->node_count = kept;
    for (uint32_t k = 0; k < kept; k++) {
        fill_node(&m->nodes[order[k]], &s->nodes[k]);
        s->nodes[k].source = (int32_t)order[k];
        if (s->nodes[k].camera >= 0 && s->cameras[s->nodes[k].camera].yfov == 0.0f)
            s->nodes[k].camera = -1; /* an orthographic camera (load_cameras) */
        s->nodes[k].parent = parent[order[k]] == -1 ? -1 : remap[parent[order[k]]];
    }
done:
    free(parent);
    free(state);
    free(stack);
    free(order);
    return r;
}

/* ---------------------------------------------------------------- skins, morph weights */

/* Skins (glTF §3.7.3): joints remapped to the kept nodes, inverse bind matrices (MAT4 FLOAT,
 * at least one per joint) or identities. A skin whose joints are not all in the scene played
 * is dropped with a warning (its meshes stay at rest); a JOINTS_0 index past a skin's joints
 * in a mesh a node draws with it is invalid. */
static eng_result load_skins(loader *L, const int32_t *remap)
{
    const gls_model *m = L->m;
    scn_scene *s = L->s;
    s->skins = calloc(m->skin_count ? m->skin_count : 1, sizeof *s->skins);
    if (!s->skins)
        return nomem(L, "skins");
    s->skin_count = m->skin_count;
    unsigned char *usable = calloc(m->skin_count ? m->skin_count : 1, 1);
    if (!usable)
        return nomem(L, "skins");
    eng_result r = ENG_OK;
    for (uint32_t i = 0; i < m->skin_count && !r; i++) {
        const gls_skin *g = &m->skins[i];
        scn_skin *d = &s->skins[i];
        char where[48];
        snprintf(where, sizeof where, "skins[%u]", i);
        if (g->joint_count == 0 || g->joint_count > 65536) {
            r = fail(L, ENG_ERR_INVALID, "%s: %u joints (must be 1..65536)", where, g->joint_count);
            break;
        }
        d->joints = malloc(g->joint_count * sizeof *d->joints);
        d->inverse_bind = malloc((size_t)g->joint_count * 16 * sizeof *d->inverse_bind);
        if (!d->joints || !d->inverse_bind) {
            r = nomem(L, where);
            break;
        }
        d->joint_count = g->joint_count;
        usable[i] = 1;
        for (uint32_t j = 0; j < g->joint_count; j++) {
            int n = g->joints[j];
            if (n < 0 || (uint32_t)n >= m->node_count) {
                r = fail(L, ENG_ERR_INVALID, "%s: joint %d out of range (%u nodes)", where, n, m->node_count);
                break;
            }
            d->joints[j] = remap[n];
            if (remap[n] < 0 && usable[i]) {
                scn_warn(s, "%s: joint node %d is not in the scene played; the skin is ignored", where, n);
                usable[i] = 0;
            }
        }
        for (uint32_t j = 0; j < g->joint_count * 16u; j++)
            d->inverse_bind[j] = j % 16 % 5 == 0 ? 1.0f : 0.0f;
        if (r || g->inverse_bind_matrices == -1)
            continue;
        const gls_accessor *a = NULL;
        const unsigned char *base = NULL;
        uint64_t stride = 0;
        char what[96];
        snprintf(what, sizeof what, "%s inverseBindMatrices", where);
        if ((r = use_accessor(L, g->inverse_bind_matrices, what, GLS_TYPE_MAT4, GLS_COMPONENT_FLOAT, 0, &a, &base,
                              &stride)))
            break;
        if (a->count < g->joint_count) {
            r = fail(L, ENG_ERR_INVALID, "%s: %llu matrices for %u joints", what, (unsigned long long)a->count,
                     g->joint_count);
            break;
        }
        for (uint32_t j = 0; base && j < g->joint_count; j++)
            memcpy(d->inverse_bind + (size_t)j * 16, base + j * stride, 16 * sizeof(float));
        for (uint32_t j = 0; j < g->joint_count * 16u && !r; j++)
            if (!isfinite(d->inverse_bind[j]))
                r = fail(L, ENG_ERR_INVALID, "%s: matrix %u is not finite", what, j / 16);
    }
    for (uint32_t k = 0; k < s->node_count && !r; k++) {
        scn_node *n = &s->nodes[k];
        if (n->skin < 0)
            continue;
        if (!usable[n->skin]) {
            n->skin = -1;
            continue;
        }
        const scn_mesh *me = &s->meshes[n->mesh];
        for (uint32_t p = 0; p < me->primitive_count && !r; p++) {
            const scn_primitive *pr = &s->primitives[me->first_primitive + p];
            const size_t inf = pr->influences;
            for (size_t v = 0; pr->joints && v < (size_t)pr->vertex_count * inf; v++)
                if (pr->joints[v] >= s->skins[n->skin].joint_count) {
                    r = fail(L, ENG_ERR_INVALID, "node %d: mesh %d vertex %zu uses joint %u, skin %d has %u joints",
                             n->source, n->mesh, v / inf, pr->joints[v], n->skin, s->skins[n->skin].joint_count);
                    break;
                }
        }
    }
    free(usable);
    return r;
}

/* Each kept node with a morphed mesh gets its slots in s->weights: node.weights, else
 * mesh.weights, else zeros (glTF §3.7.2.2). */
static eng_result load_node_weights(loader *L)
{
    scn_scene *s = L->s;
    uint64_t total = 0;
    for (uint32_t k = 0; k < s->node_count; k++)
        if (s->nodes[k].mesh >= 0)
            total += s->meshes[s->nodes[k].mesh].weight_count;
    if (total > UINT32_MAX / 4)
        return fail(L, ENG_ERR_UNSUPPORTED, "%llu morph weights", (unsigned long long)total);
    s->weights = calloc(total ? (size_t)total : 1, sizeof *s->weights);
    if (!s->weights)
        return nomem(L, "morph weights");
    uint32_t at = 0;
    for (uint32_t k = 0; k < s->node_count; k++) {
        scn_node *n = &s->nodes[k];
        n->weight_first = at;
        if (n->mesh < 0)
            continue;
        const scn_mesh *me = &s->meshes[n->mesh];
        const gls_node *g = &L->m->nodes[n->source];
        for (uint32_t w = 0; w < me->weight_count; w++)
            s->weights[at + w] = g->weights.len ? (float)g->weights.v[w] : me->weights[w];
        at += me->weight_count;
    }
    s->weight_count = at;
    return ENG_OK;
}

/* ---------------------------------------------------------------- animations */

static eng_result load_channel(loader *L, const gls_animation *ga, uint32_t a, uint32_t c, const int32_t *remap,
                               scn_channel *d, int *keep)
{
    const gls_model *m = L->m;
    const gls_channel *g = &ga->channels[c];
    char where[96];
    eng_result r;
    *keep = 0;
    snprintf(where, sizeof where, "animations[%u].channels[%u]", a, c);
    if (g->sampler < 0 || (uint32_t)g->sampler >= ga->sampler_count)
        return fail(L, ENG_ERR_INVALID, "%s: sampler %d out of range (%u samplers)", where, g->sampler,
                    ga->sampler_count);
    if (g->target_node < 0 || (uint32_t)g->target_node >= m->node_count)
        return fail(L, ENG_ERR_INVALID, "%s: target node %d out of range (%u nodes)", where, g->target_node,
                    m->node_count);
    if (strcmp(g->path, "translation") == 0)
        d->path = SCN_PATH_TRANSLATION;
    else if (strcmp(g->path, "rotation") == 0)
        d->path = SCN_PATH_ROTATION;
    else if (strcmp(g->path, "scale") == 0)
        d->path = SCN_PATH_SCALE;
    else if (strcmp(g->path, "weights") == 0)
        d->path = SCN_PATH_WEIGHTS;
    else
        return fail(L, ENG_ERR_INVALID, "%s: target path \"%s\" is not translation, rotation, scale or weights",
                    where, g->path);
    d->comps = d->path == SCN_PATH_ROTATION ? 4 : 3;
    if (d->path == SCN_PATH_WEIGHTS) {
        int mesh = m->nodes[g->target_node].mesh;
        d->comps = mesh >= 0 ? L->s->meshes[mesh].weight_count : 0;
        if (d->comps == 0) {
            scn_warn(L->s, "%s: \"weights\" of node %d, which has no morph targets; ignored", where, g->target_node);
            return ENG_OK;
        }
    } else if (m->nodes[g->target_node].matrix.len == 16)
        return fail(L, ENG_ERR_INVALID, "%s: node %d has a matrix, which glTF forbids animating", where,
                    g->target_node);

    const gls_sampler *gs = &ga->samplers[g->sampler];
    char swhere[96];
    snprintf(swhere, sizeof swhere, "animations[%u].samplers[%d]", a, g->sampler);
    if (strcmp(gs->interpolation, "LINEAR") == 0)
        d->interp = SCN_INTERP_LINEAR;
    else if (strcmp(gs->interpolation, "STEP") == 0)
        d->interp = SCN_INTERP_STEP;
    else if (strcmp(gs->interpolation, "CUBICSPLINE") == 0)
        d->interp = SCN_INTERP_CUBICSPLINE;
    else
        return fail(L, ENG_ERR_INVALID, "%s: interpolation \"%s\" is not LINEAR, STEP or CUBICSPLINE", swhere,
                    gs->interpolation);

    char what[128];
    uint64_t n, nout;
    snprintf(what, sizeof what, "%s input", swhere);
    if ((r = read_floats(L, gs->input, what, 1, MAX_KEYS, &d->times, &n)))
        return r;
    d->key_count = (uint32_t)n;
    if (d->times[0] < 0.0f)
        return fail(L, ENG_ERR_INVALID, "%s: first key time %g is negative", what, d->times[0]);
    for (uint32_t k = 1; k < d->key_count; k++)
        if (!(d->times[k] > d->times[k - 1]))
            return fail(L, ENG_ERR_INVALID, "%s: key times not strictly increasing at key %u (%g after %g)", what, k,
                        d->times[k], d->times[k - 1]);
    if (d->interp == SCN_INTERP_CUBICSPLINE && d->key_count < 2)
        return fail(L, ENG_ERR_INVALID, "%s: CUBICSPLINE needs at least 2 keys", swhere);

    uint32_t weights = d->path == SCN_PATH_WEIGHTS;
    uint32_t comps = weights ? 1 : d->comps; /* weights: SCALAR, comps per key */
    uint64_t per_key = (d->interp == SCN_INTERP_CUBICSPLINE ? 3 : 1) * (weights ? d->comps : 1);
    snprintf(what, sizeof what, "%s output", swhere);
    /* Rotation and weight keys may be normalized integers (glTF §3.11), other keys only with
     * KHR_mesh_quantization; all read through convert. */
    if ((r = read_floats_as(L, gs->output, what, comps, 1, MAX_KEYS * 3, &d->values, &nout)))
        return r;
    if (nout != n * per_key)
        return fail(L, ENG_ERR_INVALID, "%s: %llu values for %llu keys (needs %llu)", what,
                    (unsigned long long)nout, (unsigned long long)n, (unsigned long long)(n * per_key));

    d->node = remap[g->target_node];
    *keep = d->node >= 0;
    return ENG_OK;
}

static void free_channel(scn_channel *c)
{
    free(c->times);
    free(c->values);
    c->times = NULL;
    c->values = NULL;
}

static eng_result load_animations(loader *L, const int32_t *remap)
{
    const gls_model *m = L->m;
    scn_scene *s = L->s;
    s->animations = calloc(m->animation_count ? m->animation_count : 1, sizeof *s->animations);
    if (!s->animations)
        return nomem(L, "animations");
    s->animation_count = m->animation_count;
    for (uint32_t a = 0; a < m->animation_count; a++) {
        const gls_animation *g = &m->animations[a];
        scn_animation *d = &s->animations[a];
        copy_name(d->name, g->name);
        d->channels = calloc(g->channel_count ? g->channel_count : 1, sizeof *d->channels);
        if (!d->channels)
            return nomem(L, "animation channels");
        for (uint32_t c = 0; c < g->channel_count; c++) {
            scn_channel *dc = &d->channels[d->channel_count];
            int keep;
            eng_result r = load_channel(L, g, a, c, remap, dc, &keep);
            if (r || !keep) {
                free_channel(dc);
                if (r)
                    return r;
                continue;
            }
            d->channel_count++;
        }
    }
    return ENG_OK;
}

/* ---------------------------------------------------------------- top level */

/* A required extension the loader lacks is an error naming it; an optional one is ignored
 * with a warning (glTF §3.12: a client may then render without it). */
static eng_result check_extensions(loader *L)
{
    for (uint32_t i = 0; i < L->m->extensions_required_count; i++)
        if (!gltf_extension_supported(L->m->extensions_required[i]))
            return fail(L, ENG_ERR_UNSUPPORTED, "extensionsRequired: %s is not supported",
                        L->m->extensions_required[i]);
    for (uint32_t i = 0; i < L->m->extensions_used_count; i++)
        if (!gltf_extension_supported(L->m->extensions_used[i]))
            scn_warn(L->s, "extensionsUsed: %s is not supported; ignored", L->m->extensions_used[i]);
    return ENG_OK;
}

static eng_result compute_digest(loader *L, const char *bytes, size_t len)
{
    const gls_model *m = L->m;
    size_t total = len;
    for (uint32_t i = 0; i < m->buffer_count; i++)
        if (m->buffers[i].external)
            total += (size_t)m->buffers[i].size;
    if (total == len) {
        eng_digest_hex(bytes, len, L->s->digest);
        return ENG_OK;
    }
    char *all = malloc(total);
    if (!all)
        return nomem(L, "digest");
    memcpy(all, bytes, len);
    size_t at = len;
    for (uint32_t i = 0; i < m->buffer_count; i++)
        if (m->buffers[i].external) {
            memcpy(all + at, m->buffers[i].data, (size_t)m->buffers[i].size);
            at += (size_t)m->buffers[i].size;
        }
    eng_digest_hex(all, total, L->s->digest);
    free(all);
    return ENG_OK;
}

/* A scene none of whose nodes draws a triangle would render only the background: an error
 * naming the file rather than a black run. */
static eng_result check_geometry(loader *L)
{
    const scn_scene *s = L->s;
    for (uint32_t i = 0; i < s->node_count; i++)
        if (s->nodes[i].mesh >= 0 && s->meshes[s->nodes[i].mesh].primitive_count > 0)
            return ENG_OK;
    return fail(L, ENG_ERR_INVALID, "no geometry: no node of the scene draws a triangle");
}

static eng_result build(loader *L, const char *bytes, size_t len)
{
    eng_result r;
    if ((r = check_extensions(L)) || (r = check_buffer_views(L)) || (r = check_accessors(L)) ||
        (r = mark_drawn_materials(L)) || (r = load_materials(L)) || (r = load_cameras(L)) || (r = load_lights(L)) || (r = load_meshes(L)))
        return r;
    uint32_t n = L->m->node_count;
    int32_t *remap = malloc((n ? n : 1) * sizeof *remap);
    if (!remap)
        return nomem(L, "nodes");
    if (!(r = load_nodes(L, remap)) && !(r = check_geometry(L)) && !(r = load_skins(L, remap)) &&
        !(r = load_node_weights(L)))
        r = load_animations(L, remap);
    free(remap);
    if (r)
        return r;
    return compute_digest(L, bytes, len);
}

/* A file that names no mesh and fails to load for another reason: what matters first is that
 * nothing would be drawn, what else is wrong follows. Rewrites the reason (NUL-terminated, in
 * size bytes) in place, cut where it no longer fits; a reason that is "no geometry" stays. */
static void no_geometry_first(char *reason, size_t size)
{
    static const char first[] = "no geometry: no node of the scene draws a triangle; the file also fails to load: ";
    if (size < sizeof first || strncmp(reason, "no geometry", 11) == 0)
        return;
    size_t n = strlen(reason), room = size - sizeof first;
    memmove(reason + sizeof first - 1, reason, n < room ? n : room);
    reason[sizeof first - 1 + (n < room ? n : room)] = 0;
    memcpy(reason, first, sizeof first - 1);
}

/* Parses and validates bytes that came from path (named in messages; external buffers are
 * looked up beside it). Borrows bytes; frees nothing of the caller's. */
static eng_result load_bytes(const char *path, const char *bytes, size_t len, int scene_index, scn_scene **out,
                             eng_error *err)
{
    eng_result r;
    gls_model *m;
    char msg[800];
    uint64_t max_external;
    /* Depth, trailing text and counts first (bounded parsing), then the features by name. */
    if ((r = scn_gltf_precheck(path, bytes, len, &max_external, err)) != ENG_OK)
        return r;
    int no_mesh = 0;
    if ((r = gltf_features_check(path, bytes, len, &no_mesh, err)) != ENG_OK)
        return r;
    gls_status st = gls_load(path, bytes, len, max_external, &m, msg, sizeof msg);
    if (st != GLS_OK && no_mesh)
        no_geometry_first(msg, sizeof msg);
    if (st != GLS_OK) {
        switch (st) {
        case GLS_ERR_IO: return eng_fail(err, ENG_ERR_IO, "%s: %s", path, msg);
        case GLS_ERR_SYNTAX: return eng_fail(err, ENG_ERR_PARSE, "%s: %s", path, msg);
        case GLS_ERR_NOMEM: return eng_fail(err, ENG_ERR_NOMEM, "%s: %s", path, msg);
        case GLS_ERR_UNSUPPORTED: return eng_fail(err, ENG_ERR_UNSUPPORTED, "%s: %s", path, msg);
        default: return eng_fail(err, ENG_ERR_INVALID, "%s: %s", path, msg);
        }
    }

    scn_scene *s = calloc(1, sizeof *s);
    if (!s) {
        gls_free(m);
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory", path);
    }
    snprintf(s->path, sizeof s->path, "%s", path);
    loader L = {path, m, s, err, 0, scene_index, NULL, NULL, 0, 0};
    r = build(&L, bytes, len);
    free(L.texture_source);
    free(L.drawn);
    gls_free(m);
    if (r) {
        size_t at = strlen(path) + 2; /* err->msg is "<path>: <reason>" */
        if (no_mesh && err && strncmp(err->msg, path, at - 2) == 0 && strncmp(err->msg + at - 2, ": ", 2) == 0)
            no_geometry_first(err->msg + at, sizeof err->msg - at);
        scn_destroy(s);
        return r;
    }
    *out = s;
    return ENG_OK;
}

eng_result scn_load_gltf(const char *path, scn_scene **out, eng_error *err)
{
    return scn_load_gltf_scene(path, -1, out, err);
}

eng_result scn_load_gltf_scene(const char *path, int scene_index, scn_scene **out, eng_error *err)
{
    *out = NULL;
    char *bytes;
    size_t len;
    eng_result r = eng_read_file(path, GLTF_MAX_FILE, &bytes, &len, err);
    if (r)
        return r;
    r = load_bytes(path, bytes, len, scene_index, out, err);
    free(bytes);
    return r;
}

eng_result scn_load_gltf_memory(const char *name, const void *bytes, size_t len, scn_scene **out, eng_error *err)
{
    *out = NULL;
    if (len > GLTF_MAX_FILE)
        return eng_fail(err, ENG_ERR_INVALID, "%s: %zu bytes is over the %zu-byte limit", name, len,
                        (size_t)GLTF_MAX_FILE);
    /* The shim's JSON path reads up to len, but a NUL-terminated copy costs little and keeps
     * the same contract as bytes from eng_read_file. */
    char *copy = malloc(len + 1);
    if (!copy)
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory", name);
    if (len)
        memcpy(copy, bytes, len);
    copy[len] = 0;
    eng_result r = load_bytes(name, copy, len, -1, out, err);
    free(copy);
    return r;
}

void scn_destroy(scn_scene *s)
{
    if (!s)
        return;
    for (uint32_t i = 0; i < s->primitive_count; i++) {
        free(s->primitives[i].positions);
        free(s->primitives[i].normals);
        free(s->primitives[i].indices);
        free(s->primitives[i].texcoords[0]);
        free(s->primitives[i].texcoords[1]);
        free(s->primitives[i].colors);
        free(s->primitives[i].joints);
        free(s->primitives[i].weights);
        free(s->primitives[i].target_positions);
        free(s->primitives[i].target_normals);
        free(s->primitives[i].tangents);
        free(s->primitives[i].target_tangents);
    }
    for (uint32_t i = 0; i < s->mesh_count; i++)
        free(s->meshes[i].weights);
    for (uint32_t i = 0; i < s->skin_count; i++) {
        free(s->skins[i].joints);
        free(s->skins[i].inverse_bind);
    }
    free(s->skins);
    free(s->weights);
    for (uint32_t i = 0; i < s->texture_count; i++) {
        for (uint32_t l = 1; l < s->textures[i].levels; l++)
            free(s->textures[i].mips[l]);
        free(s->textures[i].texels);
    }
    free(s->textures);
    for (uint32_t a = 0; a < s->animation_count; a++) {
        for (uint32_t c = 0; c < s->animations[a].channel_count; c++)
            free_channel(&s->animations[a].channels[c]);
        free(s->animations[a].channels);
    }
    free(s->nodes);
    free(s->meshes);
    free(s->primitives);
    free(s->materials);
    free(s->cameras);
    free(s->lights);
    free(s->animations);
    free(s);
}
