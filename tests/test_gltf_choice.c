/* test_gltf_choice.c — Check suite for issue 17's loader and sequence parts
 * (engine/scene/gltf_load.c, gltf_shim.cpp, scene_choice.c, sequence.c): files stay inside the
 * scene's folder (every hostile URI gets its own one-line error), what a sequence chooses
 * (lights, scene_index, animations, a camera node by index), the no-light warning, and the
 * tolerated parts of glTF (orthographic cameras, POINTS, primitives without POSITION,
 * unknown optional extensions, alphaMode BLEND, ior 0, KHR_mesh_quantization, sparse
 * accessors).
 * Every glTF is written by the test into its own folder under the build tree. */
#define _POSIX_C_SOURCE 200809L
#include "seq.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define WORK ISPM_BINARY_DIR "/test_gltf_choice.work"
#define SCENE WORK "/scene"
#define PI 3.14159265358979323846

/* A triangle (0,0,0) (1,0,0) (0,1,0), indices 0 1 2, then key times [0, 1] and two
 * translations (0,0,0) (2,0,0): 76 bytes. */
#define TRI_B64 "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAEAAAAAAAAAAAA=="
#define TRI_DATA "data:application/octet-stream;base64," TRI_B64

static void write_file(const char *path, const void *bytes, size_t len)
{
    FILE *f = fopen(path, "wb");
    ck_assert_msg(f != NULL, "%s", path);
    ck_assert_uint_eq(fwrite(bytes, 1, len, f), len);
    ck_assert_int_eq(fclose(f), 0);
}

static void write_text(const char *path, const char *text) { write_file(path, text, strlen(text)); }

static void decode_b64(const char *in, unsigned char *out, size_t *len)
{
    static const char *tab = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    unsigned acc = 0;
    int bits = 0;
    *len = 0;
    for (; *in && *in != '='; in++) {
        acc = (acc << 6) | (unsigned)(strchr(tab, *in) - tab);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out[(*len)++] = (unsigned char)(acc >> bits);
        }
    }
}

static void mkdirs(void)
{
    mkdir(WORK, 0777);
    mkdir(SCENE, 0777);
}

/* The 76 buffer bytes written to path. */
static void write_bin(const char *path)
{
    unsigned char bin[128];
    size_t n;
    mkdirs();
    decode_b64(TRI_B64, bin, &n);
    ck_assert_uint_eq(n, 76);
    write_file(path, bin, n);
}

/* A glTF with one triangle whose buffer is `uri` (76 bytes), plus optionally an image. */
static void write_gltf(const char *path, const char *buffer_uri, const char *image_uri)
{
    char text[4096];
    snprintf(text, sizeof text,
             "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
             "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
             "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
             "\"buffers\":[{\"byteLength\":76,\"uri\":\"%s\"}]%s%s%s}",
             buffer_uri, image_uri ? ",\"images\":[{\"uri\":\"" : "", image_uri ? image_uri : "",
             image_uri ? "\"}]" : "");
    write_text(path, text);
}

static eng_result load(const char *path, scn_scene **s, eng_error *err)
{
    *s = NULL;
    memset(err, 0, sizeof *err);
    return scn_load_gltf(path, s, err);
}

/* ---------------------------------------------------------------- URIs */

START_TEST(uri_inside_ok)
{
    write_bin(SCENE "/tri.bin");
    unlink(SCENE "/in-link.bin");
    ck_assert_int_eq(symlink("tri.bin", SCENE "/in-link.bin"), 0);
    mkdir(SCENE "/sub", 0777);
    write_bin(SCENE "/sub/tri.bin");
    static const char *const ok[] = {"tri.bin", "in-link.bin", "sub/tri.bin", "sub/../tri.bin" /* refused below */};
    for (int i = 0; i < 3; i++) {
        write_gltf(SCENE "/ok.gltf", ok[i], NULL);
        scn_scene *s;
        eng_error err;
        ck_assert_msg(load(SCENE "/ok.gltf", &s, &err) == ENG_OK, "%s: %s", ok[i], err.msg);
        ck_assert_float_eq(s->primitives[0].positions[3], 1.0f);
        scn_destroy(s);
    }
}
END_TEST

static const struct {
    const char *uri;
    eng_result want;
    const char *says; /* a word of its one-line message, different for each kind of refusal */
} HOSTILE[] = {
    {"../outside.bin", ENG_ERR_INVALID, "leaves"},
    {"sub/../../outside.bin", ENG_ERR_INVALID, "leaves"},
    {"%2E%2E/outside.bin", ENG_ERR_INVALID, "leaves"},
    {"sub/../tri.bin", ENG_ERR_INVALID, "leaves"},
    {WORK "/outside.bin", ENG_ERR_INVALID, "absolute"},
    {"out-link.bin", ENG_ERR_INVALID, "symbolic link"},
    {"a-dir", ENG_ERR_INVALID, "directory"},
    {"missing.bin", ENG_ERR_IO, "no such file"},
    {"data:application/octet-stream;base64,@@@@", ENG_ERR_INVALID, "data URI"},
    {"data:application/octet-stream;base64,AAAA", ENG_ERR_INVALID, "data URI"},
};

START_TEST(uri_hostile)
{
    write_bin(WORK "/outside.bin");
    write_bin(SCENE "/tri.bin");
    mkdir(SCENE "/sub", 0777);
    mkdir(SCENE "/a-dir", 0777);
    unlink(SCENE "/out-link.bin");
    ck_assert_int_eq(symlink("../outside.bin", SCENE "/out-link.bin"), 0);
    write_gltf(SCENE "/hostile.gltf", HOSTILE[_i].uri, NULL);
    scn_scene *s;
    eng_error err;
    eng_result r = load(SCENE "/hostile.gltf", &s, &err);
    ck_assert_msg(r == HOSTILE[_i].want, "%s: got %s (%s)", HOSTILE[_i].uri, eng_result_name(r), err.msg);
    ck_assert_ptr_null(s);
    ck_assert_msg(strstr(err.msg, HOSTILE[_i].says) != NULL, "%s: message \"%s\" lacks \"%s\"", HOSTILE[_i].uri,
                  err.msg, HOSTILE[_i].says);
    ck_assert_msg(strstr(err.msg, "hostile.gltf") != NULL && !strchr(err.msg, '\n'), "%s", err.msg);
}
END_TEST

/* An image is a file the glTF names too: the same rules, although images are not decoded. */
START_TEST(uri_hostile_image)
{
    write_bin(WORK "/outside.png");
    write_gltf(SCENE "/image.gltf", TRI_DATA, "../outside.png");
    scn_scene *s;
    eng_error err;
    ck_assert_int_eq(load(SCENE "/image.gltf", &s, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "leaves"));
    write_gltf(SCENE "/image.gltf", TRI_DATA, "missing.png");
    ck_assert_int_eq(load(SCENE "/image.gltf", &s, &err), ENG_ERR_IO);
}
END_TEST

/* ---------------------------------------------------------------- what the sequence chooses */

/* Two scenes (0: the triangle; 1: the triangle and an unnamed camera node), two animations
 * ("slide" moves node 0 from x 0 to 2 over a second, "still" from 0 to 1), no light. */
static const char *const TWO_SCENES =
    "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]},{\"nodes\":[0,1]}],"
    "\"nodes\":[{\"name\":\"tri\",\"mesh\":0},{\"camera\":0,\"translation\":[0.3,0.3,2]}],"
    "\"cameras\":[{\"type\":\"perspective\",\"perspective\":{\"yfov\":0.8,\"znear\":0.1}}],"
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
    "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"},"
    "{\"bufferView\":2,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\",\"min\":[0],\"max\":[1]},"
    "{\"bufferView\":3,\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"},"
    "{\"bufferView\":0,\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6},"
    "{\"buffer\":0,\"byteOffset\":44,\"byteLength\":8},{\"buffer\":0,\"byteOffset\":52,\"byteLength\":24}],"
    "\"animations\":[{\"name\":\"slide\",\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"translation\"}}],"
    "\"samplers\":[{\"input\":2,\"output\":3}]},"
    "{\"name\":\"still\",\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"translation\"}}],"
    "\"samplers\":[{\"input\":2,\"output\":4}]}],"
    "\"buffers\":[{\"byteLength\":76,\"uri\":\"" TRI_DATA "\"}]}";

static eng_result load_seq(const char *extra, seq_sequence *q, scn_scene **s, eng_error *err)
{
    mkdirs();
    write_text(SCENE "/two.gltf", TWO_SCENES);
    char json[2048];
    snprintf(json, sizeof json,
             "{\"scene\": \"two.gltf\", \"frames\": 2, \"fps\": 1, \"resolution\": [8, 8]%s%s}",
             strstr(extra ? extra : "", "\"camera\"") ? "" : ", \"camera\": {\"keys\": [{\"time\": 0, "
                                                             "\"position\": [0, 0, 3], \"target\": [0, 0, 0]}]}",
             extra ? extra : "");
    *s = NULL;
    memset(err, 0, sizeof *err);
    eng_result r = seq_parse(SCENE "/two.json", json, strlen(json), q, err);
    if (r)
        return r;
    return seq_load_scene(q, s, err);
}

START_TEST(seq_no_light_warns)
{
    seq_sequence q;
    scn_scene *s;
    eng_error err;
    ck_assert_msg(load_seq(NULL, &q, &s, &err) == ENG_OK, "%s", err.msg);
    ck_assert_uint_eq(s->warning_count, 1);
    ck_assert_ptr_nonnull(strstr(s->warnings[0], "no light"));
    ck_assert_uint_eq(s->animation_count, 2);
    ck_assert_uint_eq(s->node_count, 1); /* the default scene 0 */
    scn_destroy(s);
    /* A light of zero intensity lights nothing either. */
    ck_assert_msg(load_seq(", \"lights\": [{\"type\": \"point\", \"intensity\": 0}]", &q, &s, &err) == ENG_OK, "%s",
                  err.msg);
    ck_assert_uint_eq(s->warning_count, 1);
    scn_destroy(s);
}
END_TEST

START_TEST(seq_lights_added)
{
    seq_sequence q;
    scn_scene *s;
    eng_error err;
    ck_assert_msg(load_seq(", \"lights\": [{\"type\": \"spot\", \"position\": [1, 2, 3], \"direction\": [0, -2, 0], "
                           "\"color\": [1, 0.5, 0.25], \"intensity\": 7, \"outer_cone_deg\": 30, "
                           "\"inner_cone_deg\": 10, \"name\": \"key\"}, {\"type\": \"directional\", "
                           "\"direction\": [0, 0, 1]}, {\"type\": \"point\"}]",
                           &q, &s, &err) == ENG_OK,
                  "%s", err.msg);
    ck_assert_uint_eq(s->warning_count, 0);
    ck_assert_uint_eq(s->light_count, 3);
    ck_assert_uint_eq(s->node_count, 4);
    const scn_node *n = &s->nodes[1];
    ck_assert_str_eq(n->name, "key");
    ck_assert_int_eq(n->parent, -1);
    ck_assert_int_eq(n->source, -1);
    const scn_light *l = &s->lights[n->light];
    ck_assert_int_eq(l->type, SCN_LIGHT_SPOT);
    ck_assert_float_eq(l->intensity, 7.0f);
    ck_assert_float_eq(l->color[1], 0.5f);
    ck_assert_float_eq_tol(l->outer_cone, 30.0 * PI / 180.0, 1e-6);
    ck_assert_float_eq_tol(l->inner_cone, 10.0 * PI / 180.0, 1e-6);
    float w[4 * 16];
    scn_evaluate(s, 0.0, w);
    /* Position, and the node's -Z axis along the given direction (normalised). */
    ck_assert_float_eq(w[16 + 12], 1.0f);
    ck_assert_float_eq(w[16 + 13], 2.0f);
    ck_assert_float_eq(w[16 + 14], 3.0f);
    ck_assert_float_eq_tol(-w[16 + 8], 0.0f, 1e-6);
    ck_assert_float_eq_tol(-w[16 + 9], -1.0f, 1e-6);
    ck_assert_float_eq_tol(-w[16 + 10], 0.0f, 1e-6);
    /* +Z, the direction opposite to a light's own -Z. */
    ck_assert_float_eq_tol(-w[32 + 10], 1.0f, 1e-6);
    ck_assert_int_eq(s->lights[s->nodes[3].light].type, SCN_LIGHT_POINT);
    ck_assert_float_eq(s->lights[s->nodes[3].light].intensity, 1.0f);
    scn_destroy(s);
}
END_TEST

START_TEST(seq_scene_animations_camera)
{
    seq_sequence q;
    scn_scene *s;
    eng_error err;
    ck_assert_msg(load_seq(", \"scene_index\": 1, \"animations\": [\"still\"], \"camera\": {\"node\": 1}, "
                           "\"lights\": [{\"type\": \"point\"}]",
                           &q, &s, &err) == ENG_OK,
                  "%s", err.msg);
    ck_assert_uint_eq(s->node_count, 3);
    ck_assert_int_eq(s->nodes[1].source, 1);
    ck_assert_int_eq(s->nodes[1].camera, 0);
    ck_assert(q.camera_by_index && q.camera_node_index == 1);
    ck_assert_uint_eq(s->animation_count, 1);
    ck_assert_str_eq(s->animations[0].name, "still");
    float w[3 * 16];
    scn_evaluate(s, 1.0, w);
    ck_assert_float_eq(w[12], 1.0f); /* "still" ends at x 1, "slide" at 2 */
    scn_destroy(s);
    ck_assert_msg(load_seq(", \"animations\": [0], \"lights\": [{\"type\": \"point\"}]", &q, &s, &err) == ENG_OK, "%s",
                  err.msg);
    scn_evaluate(s, 1.0, w);
    ck_assert_float_eq(w[12], 2.0f);
    scn_destroy(s);
    ck_assert_msg(load_seq(", \"animations\": []", &q, &s, &err) == ENG_OK, "%s", err.msg);
    ck_assert_uint_eq(s->animation_count, 0);
    scn_destroy(s);
}
END_TEST

static const struct {
    const char *extra;
    eng_result want;
} SEQ_BAD[] = {
    {", \"scene_index\": 2", ENG_ERR_INVALID},
    {", \"scene_index\": -1", ENG_ERR_INVALID},
    {", \"animations\": [\"nope\"]", ENG_ERR_INVALID},
    {", \"animations\": [2]", ENG_ERR_INVALID},
    {", \"animations\": \"slide\"", ENG_ERR_INVALID},
    {", \"lights\": []", ENG_ERR_INVALID},
    {", \"lights\": [{\"type\": \"area\"}]", ENG_ERR_INVALID},
    {", \"lights\": [{\"type\": \"spot\"}]", ENG_ERR_INVALID},
    {", \"lights\": [{\"type\": \"point\", \"colour\": [1, 1, 1]}]", ENG_ERR_INVALID},
    {", \"lights\": [{\"type\": \"point\", \"color\": [1, -1, 1]}]", ENG_ERR_INVALID},
    {", \"lights\": [{\"type\": \"point\", \"intensity\": -1}]", ENG_ERR_INVALID},
    {", \"lights\": [{\"type\": \"directional\", \"direction\": [0, 0, 0]}]", ENG_ERR_INVALID},
    {", \"lights\": [{\"type\": \"spot\", \"direction\": [0, -1, 0], \"inner_cone_deg\": 50}]", ENG_ERR_INVALID},
    {", \"camera\": {\"node\": -1}", ENG_ERR_INVALID},
    {", \"camera\": {\"node\": 1.5}", ENG_ERR_INVALID},
};

START_TEST(seq_choice_bad)
{
    seq_sequence q;
    scn_scene *s;
    eng_error err;
    eng_result r = load_seq(SEQ_BAD[_i].extra, &q, &s, &err);
    ck_assert_msg(r == SEQ_BAD[_i].want, "%s: got %s (%s)", SEQ_BAD[_i].extra, eng_result_name(r), err.msg);
    ck_assert_ptr_null(s);
    ck_assert(err.msg[0] && !strchr(err.msg, '\n'));
}
END_TEST

/* ---------------------------------------------------------------- tolerated glTF */

static scn_scene *load_text_ok(const char *name, const char *text)
{
    char path[512];
    mkdirs();
    snprintf(path, sizeof path, SCENE "/%s", name);
    write_text(path, text);
    scn_scene *s;
    eng_error err;
    eng_result r = load(path, &s, &err);
    ck_assert_msg(r == ENG_OK, "%s: %s (%s)", name, eng_result_name(r), err.msg);
    return s;
}

START_TEST(tolerated_parts)
{
    /* An orthographic camera beside a perspective one, a POINTS and a POSITION-less
     * primitive beside a triangle, an unknown optional extension, ior 0. */
    scn_scene *s = load_text_ok(
        "tolerant.gltf",
        "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"EXT_made_up\",\"KHR_materials_ior\"],"
        "\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"mesh\":0},{\"camera\":0}],"
        "\"cameras\":[{\"type\":\"orthographic\",\"orthographic\":{\"xmag\":1,\"ymag\":1,\"znear\":0.1,\"zfar\":9}}],"
        "\"materials\":[{\"extensions\":{\"KHR_materials_ior\":{\"ior\":0}},\"alphaMode\":\"BLEND\"}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"mode\":0},"
        "{\"attributes\":{\"NORMAL\":0},\"indices\":1},"
        "{\"attributes\":{\"POSITION\":0},\"mode\":1,\"indices\":2},"
        "{\"attributes\":{\"POSITION\":0},\"indices\":1,\"material\":0}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":2,\"type\":\"SCALAR\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6}],"
        "\"buffers\":[{\"byteLength\":76,\"uri\":\"" TRI_DATA "\"}]}");
    ck_assert_uint_eq(s->warning_count, 5); /* camera, POINTS, no POSITION, LINES, EXT_made_up (BLEND is drawn) */
    int seen[5] = {0};
    static const char *const says[5] = {"orthographic", "POINTS", "POSITION", "LINES", "EXT_made_up"};
    for (uint32_t w = 0; w < s->warning_count; w++) {
        ck_assert_msg(strstr(s->warnings[w], "BLEND") == NULL, "a warning about BLEND: %s", s->warnings[w]);
        for (int k = 0; k < 5; k++)
            seen[k] |= strstr(s->warnings[w], says[k]) != NULL;
    }
    for (int k = 0; k < 5; k++)
        ck_assert_msg(seen[k], "no warning about %s", says[k]);
    ck_assert_uint_eq(s->primitive_count, 1);
    ck_assert_uint_eq(s->meshes[0].primitive_count, 1);
    ck_assert_int_eq(s->primitives[s->meshes[0].first_primitive].material, 0);
    ck_assert_int_eq(s->nodes[1].camera, -1); /* an orthographic camera cannot be chosen */
    ck_assert_float_ge(s->materials[0].ior, 1000.0f);
    ck_assert_int_eq(s->materials[0].alpha_mode, SCN_ALPHA_BLEND); /* pass_translucent.c draws it */
    scn_destroy(s);
}
END_TEST

START_TEST(required_extension_named)
{
    mkdirs();
    write_text(SCENE "/draco.gltf",
               "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"EXT_made_up\"],"
               "\"extensionsRequired\":[\"EXT_made_up\"],\"scenes\":[{\"nodes\":[]}]}");
    scn_scene *s;
    eng_error err;
    ck_assert_int_eq(load(SCENE "/draco.gltf", &s, &err), ENG_ERR_UNSUPPORTED);
    ck_assert_ptr_nonnull(strstr(err.msg, "EXT_made_up"));
}
END_TEST

/* KHR_mesh_quantization: POSITION as normalized SHORT (32767 → 1, -32767 → -1). */
START_TEST(mesh_quantization)
{
    scn_scene *s = load_text_ok(
        "quantized.gltf",
        "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_mesh_quantization\"],"
        "\"extensionsRequired\":[\"KHR_mesh_quantization\"],\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1}]}],"
        "\"accessors\":[{\"bufferView\":0,\"componentType\":5122,\"normalized\":true,\"count\":3,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":18},{\"buffer\":0,\"byteOffset\":20,\"byteLength\":6}],"
        "\"buffers\":[{\"byteLength\":26,\"uri\":\"data:application/octet-stream;base64,"
        "AAAAAAAA/38AAAAAAAABgAAAAAAAAAEAAgA=\"}]}");
    ck_assert_uint_eq(s->warning_count, 0);
    const float want[9] = {0, 0, 0, 1, 0, 0, 0, -1, 0};
    /* No NORMAL: flat normals un-share the vertices in index order 0 1 2. */
    for (int k = 0; k < 9; k++)
        ck_assert_float_eq(s->primitives[0].positions[k], want[k]);
    scn_destroy(s);
}
END_TEST

/* Sparse accessors (glTF §3.6.2.3): one without a buffer view (zeros, then indices 1 and 2
 * get (1,0,0) and (0,1,0): the triangle again), one over the positions whose index 2 gets
 * (2,0,0). */
START_TEST(sparse_accessor)
{
    scn_scene *s = load_text_ok(
        "sparse.gltf",
        "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0},\"indices\":1},"
        "{\"attributes\":{\"POSITION\":2},\"indices\":1}]}],"
        "\"accessors\":[{\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
        "\"sparse\":{\"count\":2,\"indices\":{\"bufferView\":1,\"byteOffset\":2,\"componentType\":5123},"
        "\"values\":{\"bufferView\":0,\"byteOffset\":12}}},"
        "{\"bufferView\":1,\"componentType\":5123,\"count\":3,\"type\":\"SCALAR\"},"
        "{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
        "\"sparse\":{\"count\":1,\"indices\":{\"bufferView\":1,\"byteOffset\":4,\"componentType\":5123},"
        "\"values\":{\"bufferView\":2,\"byteOffset\":12}}}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\"byteLength\":6},"
        "{\"buffer\":0,\"byteOffset\":52,\"byteLength\":24}],"
        "\"buffers\":[{\"byteLength\":76,\"uri\":\"" TRI_DATA "\"}]}");
    const float tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, moved[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
    for (int k = 0; k < 9; k++) {
        ck_assert_float_eq(s->primitives[0].positions[k], tri[k]);
        ck_assert_float_eq(s->primitives[1].positions[k], moved[k]);
    }
    ck_assert_float_eq(s->primitives[0].normals[2], 1.0f); /* flat normal of the sparse triangle */
    scn_destroy(s);
}
END_TEST

static Suite *gltf_choice_suite(void)
{
    Suite *s = suite_create("gltf_choice");
    TCase *tc = tcase_create("uri");
    tcase_add_test(tc, uri_inside_ok);
    tcase_add_loop_test(tc, uri_hostile, 0, (int)(sizeof HOSTILE / sizeof HOSTILE[0]));
    tcase_add_test(tc, uri_hostile_image);
    suite_add_tcase(s, tc);
    tc = tcase_create("sequence");
    tcase_add_test(tc, seq_no_light_warns);
    tcase_add_test(tc, seq_lights_added);
    tcase_add_test(tc, seq_scene_animations_camera);
    tcase_add_loop_test(tc, seq_choice_bad, 0, (int)(sizeof SEQ_BAD / sizeof SEQ_BAD[0]));
    suite_add_tcase(s, tc);
    tc = tcase_create("tolerant");
    tcase_add_test(tc, tolerated_parts);
    tcase_add_test(tc, required_extension_named);
    tcase_add_test(tc, mesh_quantization);
    tcase_add_test(tc, sparse_accessor);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(gltf_choice_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
