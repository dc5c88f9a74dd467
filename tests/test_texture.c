/* test_texture.c — Check suite for base colour textures (issue 17): the loader's decoding
 * (sRGB, samplers), scn_base_color_at on the CPU, the eye G-buffer's albedo of a textured
 * checkerboard (exact texel values, in the right place), and a texture seen only through
 * photons, whose colour must bleed onto a white floor. Every glTF is written by the test. */
#define _POSIX_C_SOURCE 200809L
#include "eng_frame.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define WORK ISPM_BINARY_DIR "/test_texture.work"

/* 2x2 RGBA PNGs: a checker (top row red, green; bottom row blue, grey 128) and plain red. */
#define CHECKER_PNG "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAFUlEQVR4nGP4z8DwHwyB9P+Ghob/AEVRCHp8uJy8AAAAAElFTkSuQmCC"
#define RED_PNG "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAEUlEQVR4nGP4z8DwH4QZYAwAR8oH+WdZbrcAAAAASUVORK5CYII="
/* A constant tangent-space normal map: every texel (204, 77, 230), linear, so
 * (x, y, z) = 2·texel/255 − 1 = (0.6, −0.396, 0.804). */
#define NORMAL_PNG "data:image/png;base64,%s"
/* Opaque white top row, transparent white bottom row. */
#define MASK_PNG "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAADklEQVR4nGP4DwUMMAwAiYgN82n6rJMAAAAASUVORK5CYII="
/* A 2 m quad at y = 0 facing up: positions (-1,0,-1) (1,0,-1) (1,0,1) (-1,0,1), normals up,
 * TEXCOORD_0 (0,0) (1,0) (1,1) (0,1), indices 0 2 1 0 3 2: 140 bytes. */
#define QUAD_BIN "data:application/octet-stream;base64,AACAvwAAAAAAAIC/AACAPwAAAAAAAIC/AACAPwAAAAAAAIA/AACAvwAAAAAAAIA/AAAAAAAAgD8AAAAAAAAAAAAAgD8AAAAAAAAAAAAAgD8AAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAgD8AAIA/AAAAAAAAgD8AAAIAAQAAAAMAAgA="

static const char *const QUAD_PARTS =
    "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1,\"TEXCOORD_0\":2},\"indices\":3,"
    "\"material\":0}]},{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1,\"TEXCOORD_0\":2},"
    "\"indices\":3,\"material\":1}]}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
    "{\"bufferView\":1,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
    "{\"bufferView\":2,\"componentType\":5126,\"count\":4,\"type\":\"VEC2\"},"
    "{\"bufferView\":3,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteLength\":48},{\"buffer\":0,\"byteOffset\":48,\"byteLength\":48},"
    "{\"buffer\":0,\"byteOffset\":96,\"byteLength\":32},{\"buffer\":0,\"byteOffset\":128,\"byteLength\":12}],"
    "\"buffers\":[{\"byteLength\":140,\"uri\":\"" QUAD_BIN "\"}],"
    "\"samplers\":[{\"magFilter\":9728,\"minFilter\":9728,\"wrapS\":33071,\"wrapT\":33071}],"
    "\"textures\":[{\"source\":0,\"sampler\":0}],";

/* The checkerboard floor alone (material 0 textured: base colour, and the same image as its
 * metallicRoughness texture, metallicFactor 0.5; material 1 white, unused). */
static void write_checker(const char *path)
{
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fprintf(f,
            "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],%s"
            "\"images\":[{\"uri\":\"%s\"}],"
            "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},"
            "\"metallicRoughnessTexture\":{\"index\":0},\"metallicFactor\":0.5}},"
            "{\"pbrMetallicRoughness\":{\"metallicFactor\":0}}]}",
            QUAD_PARTS, CHECKER_PNG);
    ck_assert_int_eq(fclose(f), 0);
}

static float srgb(int c)
{
    float x = (float)c / 255.0f;
    return x <= 0.04045f ? x / 12.92f : powf((x + 0.055f) / 1.055f, 2.4f);
}

/* The checker's texels, linear, in image order (top-left, top-right, bottom-left, bottom-right). */
static void checker_texels(float want[4][4])
{
    const int c[4][3] = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {128, 128, 128}};
    for (int i = 0; i < 4; i++) {
        for (int k = 0; k < 3; k++)
            want[i][k] = srgb(c[i][k]);
        want[i][3] = 1.0f;
    }
}

START_TEST(decode_and_sample_cpu)
{
    mkdir(WORK, 0777);
    write_checker(WORK "/checker.gltf");
    scn_scene *s = NULL;
    eng_error err;
    ck_assert_msg(scn_load_gltf(WORK "/checker.gltf", &s, &err) == ENG_OK, "%s", err.msg);
    ck_assert_uint_eq(s->texture_count, 2); /* the image decoded as sRGB and as linear */
    ck_assert(!s->textures[1].srgb);
    ck_assert_float_eq(s->textures[1].texels[4 * 3], 128.0f / 255.0f);
    const scn_texture *t = &s->textures[0];
    ck_assert_uint_eq(t->width, 2);
    ck_assert(t->srgb && !t->mag_linear && t->wrap_s == SCN_WRAP_CLAMP);
    float want[4][4];
    checker_texels(want);
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 4; k++)
            ck_assert_float_eq(t->texels[i * 4 + k], want[i][k]);
    ck_assert_float_eq_tol(want[3][0], 0.2158605f, 1e-6f); /* sRGB 128 */
    /* Triangle 0 is vertices 0 2 1: 0.2·v0 + 0.1·v2 + 0.7·v1 has uv (0.8, 0.1), the top-right texel. */
    float out[4];
    const scn_material *m = &s->materials[0];
    scn_base_color_at(s, m, &s->primitives[0], 0, 0.1f, 0.7f, out);
    for (int k = 0; k < 4; k++)
        ck_assert_float_eq(out[k], want[1][k]);
    /* Triangle 1 (0 3 2) near vertex 3, uv (0, 1): bottom-left. */
    scn_base_color_at(s, m, &s->primitives[0], 1, 0.9f, 0.05f, out);
    for (int k = 0; k < 4; k++)
        ck_assert_float_eq(out[k], want[2][k]);
    /* LINEAR at the centre of the image is the mean of the four texels. */
    scn_texture lin = *t;
    lin.mag_linear = 1;
    scn_texture_sample(&lin, 0.5f, 0.5f, out);
    ck_assert_float_eq_tol(out[0], (want[0][0] + want[3][0]) / 4.0f, 1e-6f);
    /* REPEAT wraps u 1.25 to 0.25; MIRROR reflects it to 0.75. */
    lin.mag_linear = 0;
    lin.wrap_s = SCN_WRAP_REPEAT;
    scn_texture_sample(&lin, 1.25f, 0.25f, out);
    ck_assert_float_eq(out[0], want[0][0]);
    lin.wrap_s = SCN_WRAP_MIRROR;
    scn_texture_sample(&lin, 1.25f, 0.25f, out);
    ck_assert_float_eq(out[1], want[1][1]);
    /* Below 0 (texel −2 of 2): REPEAT texel 0, MIRROR texel 1, CLAMP texel 0; past 1 CLAMP the
     * last texel. (Inside the level wrap_index takes a shortcut; these take the general path.) */
    lin.wrap_s = SCN_WRAP_REPEAT;
    scn_texture_sample(&lin, -0.75f, 0.25f, out);
    ck_assert_float_eq(out[0], want[0][0]);
    lin.wrap_s = SCN_WRAP_MIRROR;
    scn_texture_sample(&lin, -0.75f, 0.25f, out);
    ck_assert_float_eq(out[1], want[1][1]);
    lin.wrap_s = SCN_WRAP_CLAMP;
    scn_texture_sample(&lin, -0.75f, 0.25f, out);
    ck_assert_float_eq(out[0], want[0][0]);
    scn_texture_sample(&lin, 1.75f, 0.25f, out);
    ck_assert_float_eq(out[1], want[1][1]);
    scn_destroy(s);
}
END_TEST

/* ---------------------------------------------------------------- engine */

typedef struct grab {
    const char *name;
    float *data;
    int width, height, channels;
} grab;

static int grab_buffer(void *user, int frame, const eng_buffer *b)
{
    (void)frame;
    grab *g = user;
    for (; g->name; g++)
        if (!strcmp(b->name, g->name)) {
            size_t n = (size_t)b->width * b->height * b->channel_count;
            free(g->data);
            g->data = malloc(n * sizeof *g->data);
            memcpy(g->data, b->data, n * sizeof *g->data);
            g->width = b->width;
            g->height = b->height;
            g->channels = b->channel_count;
        }
    return 0;
}

/* Loads the sequence json's scene, renders frame 0 into g; returns the engine when keep
 * (the caller destroys it and *scene), else destroys both. */
static eng_engine *render_one(const char *json, grab *g, int keep, scn_scene **scene)
{
    seq_sequence q;
    scn_scene *s = NULL;
    eng_engine *e = NULL;
    eng_error err;
    ck_assert_msg(seq_parse(WORK "/seq.json", json, strlen(json), &q, &err) == ENG_OK, "%s", err.msg);
    ck_assert_msg(seq_load_scene(&q, &s, &err) == ENG_OK, "%s", err.msg);
    eng_desc d = {.scene = s, .sequence = &q};
    ck_assert_msg(eng_create(&d, &e, &err) == ENG_OK, "%s", err.msg);
    eng_listener l = {g, NULL, grab_buffer, NULL};
    ck_assert_int_eq(eng_add_listener(e, &l), ENG_OK);
    ck_assert_msg(eng_render_frame(e, 0, &err) == ENG_OK, "%s", err.msg);
    if (keep) {
        *scene = s;
        return e;
    }
    eng_destroy(e);
    scn_destroy(s);
    return NULL;
}

/* render_one of the 32×32 view straight down on a glTF (-Z up in the image) that the
 * texture tests share, capturing the comma-separated quoted names in capture. */
static eng_engine *render_top(const char *gltf, const char *capture, grab *g, scn_scene **scene)
{
    char json[1024];
    snprintf(json, sizeof json,
             "{\"scene\": \"%s\", \"frames\": 1, \"fps\": 1, \"resolution\": [32, 32],"
             " \"camera\": {\"keys\": [{\"time\": 0, \"position\": [0, 3, 0], \"target\": [0, 0, 0]}],"
             " \"up\": [0, 0, -1], \"yfov_deg\": 30}, \"lights\": [{\"type\": \"point\", \"position\": [0, 2, 0]}],"
             " \"settings\": {\"shadow_map_size\": 64, \"photon_count\": 64, \"threads\": 2},"
             " \"capture\": [%s]}",
             gltf, capture);
    return render_one(json, g, scene != NULL, scene);
}

/* Looking straight down with -Z up in the image: the image's top-left quadrant is the
 * texture's top-left texel, and every pixel's albedo is exactly one of the four texels. */
START_TEST(gbuffer_albedo_checker)
{
    mkdir(WORK, 0777);
    write_checker(WORK "/checker.gltf");
    grab g[] = {{"gbuffer.albedo", NULL, 0, 0, 0}, {"gbuffer.material", NULL, 0, 0, 0}, {NULL, NULL, 0, 0, 0}};
    render_one("{\"scene\": \"checker.gltf\", \"frames\": 1, \"fps\": 1, \"resolution\": [32, 32],"
               " \"camera\": {\"keys\": [{\"time\": 0, \"position\": [0, 3, 0], \"target\": [0, 0, 0]}],"
               " \"up\": [0, 0, -1], \"yfov_deg\": 30}, \"lights\": [{\"type\": \"point\", \"position\": [0, 2, 0]}],"
               " \"settings\": {\"shadow_map_size\": 64, \"photon_count\": 64, \"threads\": 2},"
               " \"capture\": [\"gbuffer.albedo\", \"gbuffer.material\"]}",
               g, 0, NULL);
    ck_assert_ptr_nonnull(g[0].data);
    float want[4][4];
    checker_texels(want);
    int seen[4] = {0};
    for (int y = 0; y < 32; y++)
        for (int x = 0; x < 32; x++) {
            const float *p = g[0].data + ((size_t)y * 32 + x) * g[0].channels;
            int q = (y >= 16) * 2 + (x >= 16);
            for (int k = 0; k < 3; k++)
                ck_assert_msg(p[k] == want[q][k], "pixel (%d,%d) channel %d: %.9g, want %.9g", x, y, k, p[k], want[q][k]);
            /* roughness = 1 × G, metallic = 0.5 × B of the linear texel */
            static const int green[4] = {0, 255, 0, 128}, blue[4] = {0, 0, 255, 128};
            const float *mat = g[1].data + ((size_t)y * 32 + x) * g[1].channels;
            ck_assert_float_eq(mat[0], (float)green[q] / 255.0f);
            ck_assert_float_eq(mat[1], 0.5f * ((float)blue[q] / 255.0f));
            seen[q]++;
        }
    for (int q = 0; q < 4; q++)
        ck_assert_int_eq(seen[q], 256);
    free(g[0].data);
    free(g[1].data);
}
END_TEST

/* The checker as an emissive texture (emissiveFactor (1, 0.5, 2), exact multipliers): every
 * pixel's gbuffer.emission is the factor times exactly one sRGB-decoded texel, in the
 * quadrant the albedo test finds it; the CPU lookup a photon or reference path makes at a
 * hit (scn_texref_at, rt_hit.emissive_tex) gives the same texel. */
START_TEST(gbuffer_emission_texture)
{
    mkdir(WORK, 0777);
    FILE *f = fopen(WORK "/emissive.gltf", "w");
    ck_assert_ptr_nonnull(f);
    fprintf(f,
            "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],%s"
            "\"images\":[{\"uri\":\"%s\"}],"
            "\"materials\":[{\"emissiveTexture\":{\"index\":0},\"emissiveFactor\":[1,0.5,2],"
            "\"pbrMetallicRoughness\":{\"metallicFactor\":0}},{}]}",
            QUAD_PARTS, CHECKER_PNG);
    ck_assert_int_eq(fclose(f), 0);
    grab g[] = {{"gbuffer.emission", NULL, 0, 0, 0}, {NULL, NULL, 0, 0, 0}};
    scn_scene *s = NULL;
    eng_engine *e = render_top("emissive.gltf", "\"gbuffer.emission\"", g, &s);
    ck_assert_ptr_nonnull(g[0].data);
    float want[4][4];
    checker_texels(want);
    const float factor[3] = {1.0f, 0.5f, 2.0f};
    for (int y = 0; y < 32; y++)
        for (int x = 0; x < 32; x++) {
            const float *p = g[0].data + ((size_t)y * 32 + x) * g[0].channels;
            int q = (y >= 16) * 2 + (x >= 16);
            for (int k = 0; k < 3; k++)
                ck_assert_msg(p[k] == factor[k] * want[q][k], "pixel (%d,%d) channel %d: %.9g, want %.9g", x, y, k,
                              p[k], factor[k] * want[q][k]);
        }
    /* On the CPU: triangle 0 (vertices 0 2 1, uv (0,0) (1,1) (1,0)) at barycentrics
     * (0.1, 0.1) of vertices 2 and 1 is uv (0.2, 0.1): the top-left texel. */
    float c[4];
    ck_assert(scn_texref_at(s, &s->materials[0].emissive_tex, &s->primitives[0], 0, 0.1f, 0.1f, c));
    for (int k = 0; k < 3; k++)
        ck_assert_float_eq(c[k], want[0][k]);
    eng_destroy(e);
    scn_destroy(s);
    free(g[0].data);
}
END_TEST

/* The red wall over the floor of photons_carry_texture_colour, the floor with the checker as
 * its occlusion texture (linear R: 1, 0, 0, 128/255 by quadrant) at strength 0.5: the
 * composite is direct + indirect × (1 + 0.5·(R − 1)) at every pixel (glTF §3.9.3: occlusion
 * darkens indirect light only), with indirect light in every quadrant. */
START_TEST(occlusion_darkens_indirect_only)
{
    mkdir(WORK, 0777);
    FILE *f = fopen(WORK "/occlusion.gltf", "w");
    ck_assert_ptr_nonnull(f);
    fprintf(f,
            "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0,1]}],"
            "\"nodes\":[{\"mesh\":1},{\"mesh\":0,\"translation\":[-1,1,0],"
            "\"rotation\":[0,0,-0.70710678,0.70710678]}],%s"
            "\"images\":[{\"uri\":\"%s\"}],"
            "\"materials\":[{\"pbrMetallicRoughness\":{\"metallicFactor\":0},\"doubleSided\":true},"
            "{\"occlusionTexture\":{\"index\":0,\"strength\":0.5},\"pbrMetallicRoughness\":{\"metallicFactor\":0}}]}",
            QUAD_PARTS, CHECKER_PNG);
    ck_assert_int_eq(fclose(f), 0);
    grab g[] = {{"direct.radiance", NULL, 0, 0, 0}, {"indirect.radiance", NULL, 0, 0, 0},
                {"composite.radiance", NULL, 0, 0, 0}, {NULL, NULL, 0, 0, 0}};
    render_one("{\"scene\": \"occlusion.gltf\", \"frames\": 1, \"fps\": 1, \"resolution\": [32, 32],"
               " \"camera\": {\"keys\": [{\"time\": 0, \"position\": [0, 3, 0], \"target\": [0, 0, 0]}],"
               " \"up\": [0, 0, -1], \"yfov_deg\": 30},"
               " \"lights\": [{\"type\": \"point\", \"position\": [0, 1.5, 0], \"intensity\": 5}],"
               " \"settings\": {\"shadow_map_size\": 128, \"photon_count\": 4096, \"threads\": 2,"
               " \"kernel_radius\": 0.3}, \"capture\": [\"direct.radiance\", \"indirect.radiance\", \"composite.radiance\"]}",
               g, 0, NULL);
    const float red[4] = {1.0f, 0.0f, 0.0f, 128.0f / 255.0f};
    double lit[4] = {0, 0, 0, 0};
    for (int y = 0; y < 32; y++)
        for (int x = 0; x < 32; x++) {
            int q = (y >= 16) * 2 + (x >= 16);
            float o = 1.0f + 0.5f * (red[q] - 1.0f);
            size_t at = ((size_t)y * 32 + x) * 3;
            for (int k = 0; k < 3; k++) {
                float d = g[0].data[at + k], i = g[1].data[at + k], c = g[2].data[at + k];
                float want = d + i * o;
                ck_assert_msg(fabsf(c - want) <= 1e-6f * fmaxf(1.0f, fabsf(want)),
                              "pixel (%d,%d) channel %d: composite %.9g, want %.9g + %.9g × %g", x, y, k, c, d, i, o);
                lit[q] += i;
            }
        }
    for (int q = 0; q < 4; q++)
        ck_assert_msg(lit[q] > 0.0, "no indirect light in quadrant %d", q);
    for (int k = 0; k < 3; k++)
        free(g[k].data);
}
END_TEST

/* A red-textured wall (white factor) beside a white floor, out of the camera's view: the
 * floor's indirect light is red, which it could only be through the texture. */
START_TEST(photons_carry_texture_colour)
{
    mkdir(WORK, 0777);
    FILE *f = fopen(WORK "/bleed.gltf", "w");
    ck_assert_ptr_nonnull(f);
    fprintf(f,
            "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0,1]}],"
            "\"nodes\":[{\"mesh\":1},{\"mesh\":0,\"translation\":[-1,1,0],"
            "\"rotation\":[0,0,-0.70710678,0.70710678]}],%s"
            "\"images\":[{\"uri\":\"%s\"}],"
            "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicFactor\":0},"
            "\"doubleSided\":true},{\"pbrMetallicRoughness\":{\"metallicFactor\":0}}]}",
            QUAD_PARTS, RED_PNG);
    ck_assert_int_eq(fclose(f), 0);
    grab g[] = {{"indirect.radiance", NULL, 0, 0, 0}, {NULL, NULL, 0, 0, 0}};
    render_one("{\"scene\": \"bleed.gltf\", \"frames\": 1, \"fps\": 1, \"resolution\": [32, 32],"
               " \"camera\": {\"keys\": [{\"time\": 0, \"position\": [0, 3, 0], \"target\": [0, 0, 0]}],"
               " \"up\": [0, 0, -1], \"yfov_deg\": 30},"
               " \"lights\": [{\"type\": \"point\", \"position\": [0, 1.5, 0], \"intensity\": 5}],"
               " \"settings\": {\"shadow_map_size\": 128, \"photon_count\": 8192, \"threads\": 2,"
               " \"kernel_radius\": 0.3}, \"capture\": [\"indirect.radiance\"]}",
               g, 0, NULL);
    ck_assert_ptr_nonnull(g[0].data);
    double sum[3] = {0, 0, 0};
    for (int i = 0; i < 32 * 32; i++)
        for (int k = 0; k < 3; k++)
            sum[k] += g[0].data[(size_t)i * g[0].channels + k];
    ck_assert_msg(sum[0] > 0.0 && sum[0] > 20.0 * sum[1] && sum[0] > 20.0 * sum[2],
                  "indirect light on the floor: R %g G %g B %g, want red", sum[0], sum[1], sum[2]);
    free(g[0].data);
}
END_TEST

/* alphaMode MASK: a floor whose texture is opaque where z < 0 and transparent where z > 0
 * is cut in the G-buffer (background there) and for Embree's rays alike. */
START_TEST(alpha_mask_everywhere)
{
    mkdir(WORK, 0777);
    FILE *f = fopen(WORK "/mask.gltf", "w");
    ck_assert_ptr_nonnull(f);
    fprintf(f,
            "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],%s"
            "\"images\":[{\"uri\":\"%s\"}],"
            "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0},\"metallicFactor\":0},"
            "\"alphaMode\":\"MASK\",\"doubleSided\":true},{}]}",
            QUAD_PARTS, MASK_PNG);
    ck_assert_int_eq(fclose(f), 0);
    static const char json[] =
        "{\"scene\": \"mask.gltf\", \"frames\": 1, \"fps\": 1, \"resolution\": [32, 32],"
        " \"camera\": {\"keys\": [{\"time\": 0, \"position\": [0, 3, 0], \"target\": [0, 0, 0]}],"
        " \"up\": [0, 0, -1], \"yfov_deg\": 30}, \"lights\": [{\"type\": \"point\", \"position\": [0, 2, 0]}],"
        " \"settings\": {\"shadow_map_size\": 64, \"photon_count\": 64, \"threads\": 2},"
        " \"capture\": [\"gbuffer.material\"]}";
    grab g[] = {{"gbuffer.material", NULL, 0, 0, 0}, {NULL, NULL, 0, 0, 0}};
    scn_scene *s = NULL;
    eng_engine *e = render_one(json, g, 1, &s);
    ck_assert_int_eq(s->materials[0].alpha_mode, SCN_ALPHA_MASK);
    ck_assert_ptr_nonnull(g[0].data);
    for (int y = 0; y < 32; y++)
        for (int x = 0; x < 32; x++) {
            float id = g[0].data[((size_t)y * 32 + x) * g[0].channels + 4]; /* material id, -1: background */
            ck_assert_msg(id == (y < 16 ? 0.0f : -1.0f), "pixel (%d,%d): material id %g", x, y, id);
        }
    const float a0[3] = {0.3f, 1, -0.5f}, b0[3] = {0.3f, -1, -0.5f}, a1[3] = {0.3f, 1, 0.5f}, b1[3] = {0.3f, -1, 0.5f};
    ck_assert_int_eq(eng_occluded(e, a0, b0), 1);
    ck_assert_int_eq(eng_occluded(e, a1, b1), 0);
    free(g[0].data);
    eng_destroy(e);
    scn_destroy(s);
}
END_TEST

/* Embree's view of scene s's first primitive drawn at node 0's world matrix at t = 0, as the
 * engine's draw would pose it (rt_update copies what it needs). */
static eng_rt *rt_of_node0(const scn_scene *s)
{
    float *world = malloc((size_t)s->node_count * 16 * sizeof *world);
    scn_evaluate(s, 0.0, world);
    eng_draw dr = {.primitive = 0, .material = s->primitives[0].material};
    memcpy(dr.world, world, sizeof dr.world);
    memcpy(dr.prev_world, world, sizeof dr.prev_world);
    free(world);
    eng_frame_scene fs = {.scene = s, .draw_count = 1, .draws = &dr};
    eng_rt *rt = NULL;
    eng_error err;
    ck_assert_int_eq(rt_create(s, 2, &rt, &err), ENG_OK);
    rt_update(rt, &fs);
    return rt;
}

/* The quad of QUAD_PARTS turned 30° about +Y, with material 0's normal texture at `scale`
 * (none when scale < 0). */
static void write_normal_quad(const char *path, double scale)
{
    char png[160];
    snprintf(png, sizeof png, NORMAL_PNG, "iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAEUlEQVR42mM44/vsPwgzwBgAaWYL+XSz8UEAAAAASUVORK5CYII=");
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    char mat[128] = "";
    if (scale >= 0.0)
        snprintf(mat, sizeof mat, "\"normalTexture\":{\"index\":0,\"scale\":%.17g},", scale);
    fprintf(f,
            "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0]}],"
            "\"nodes\":[{\"mesh\":0,\"rotation\":[0,0.25881904510252074,0,0.9659258262890683]}],%s"
            "\"images\":[{\"uri\":\"%s\"}],"
            "\"materials\":[{%s\"pbrMetallicRoughness\":{\"metallicFactor\":0}},{}]}",
            QUAD_PARTS, png, mat);
    ck_assert_int_eq(fclose(f), 0);
}

/* normalTexture (glTF §3.9.3) with generated tangents: the loader's tangent is the quad's +u
 * direction (1, 0, 0), w = +1 (u right, v down the image); every gbuffer.normal pixel is the
 * map's constant normal in that frame, n = R_y(30°)·normalize(0.6·T − 0.396·(N × T) + 0.804·N),
 * within 1e-6 (llvmpipe's normalize against the C one); the CPU hit shading normal
 * (rt_intersect → scn_normal_at) at each pixel's surface point equals the GPU one within
 * 1e-6; scale 0 gives exactly the unmapped normal (0, 1, 0) on both sides, as no map does. */
START_TEST(normal_map_gbuffer_and_hits)
{
    mkdir(WORK, 0777);
    for (int pass = 0; pass < 3; pass++) {
        const double scale = pass == 0 ? 1.0 : pass == 1 ? 0.0 : -1.0;
        write_normal_quad(WORK "/normal.gltf", scale);
        grab g[] = {{"gbuffer.normal", NULL, 0, 0, 0},
                    {"gbuffer.position", NULL, 0, 0, 0},
                    {"gbuffer.depth", NULL, 0, 0, 0},
                    {NULL, NULL, 0, 0, 0}};
        scn_scene *s = NULL;
        eng_engine *e = render_top("normal.gltf", "\"gbuffer.normal\", \"gbuffer.position\", \"gbuffer.depth\"", g, &s);
        ck_assert_ptr_nonnull(g[0].data);
        const scn_primitive *p = &s->primitives[0];
        if (pass == 2) {
            ck_assert_ptr_null(p->tangents);
        } else {
            ck_assert_ptr_nonnull(p->tangents);
            for (uint32_t v = 0; v < p->vertex_count; v++) {
                const float want[4] = {1, 0, 0, 1};
                for (int k = 0; k < 4; k++)
                    ck_assert_float_eq(p->tangents[v * 4 + k], want[k]);
            }
        }
        /* Tangent space (x, y, z) from the 8-bit texel, in the quad's frame T = +x, N = +y,
         * B = N × T = −z, then turned 30° about +Y (x' = c·x + s·z, z' = −s·x + c·z). */
        const double sc = scale > 0.0 ? scale : 0.0;
        double x = (2.0 * 204 / 255 - 1) * sc, y = (2.0 * 77 / 255 - 1) * sc, z = 2.0 * 230 / 255 - 1;
        double loc[3] = {x, z, -y}, len = sqrt(loc[0] * loc[0] + loc[1] * loc[1] + loc[2] * loc[2]);
        double c = cos(3.14159265358979323846 / 6), sn = sin(3.14159265358979323846 / 6);
        double want[3] = {(c * loc[0] + sn * loc[2]) / len, loc[1] / len, (-sn * loc[0] + c * loc[2]) / len};
        if (scale < 0.0)
            want[0] = 0.0, want[1] = 1.0, want[2] = 0.0;
        eng_rt *rt = rt_of_node0(s);
        int covered = 0;
        double worst_gpu = 0.0, worst_cpu = 0.0;
        for (int i = 0; i < 32 * 32; i++) {
            const float *n = g[0].data + (size_t)i * g[0].channels, *pos = g[1].data + (size_t)i * g[1].channels;
            if (!(g[2].data[i] > 0.0f))
                continue; /* background */
            covered++;
            for (int k = 0; k < 3; k++)
                worst_gpu = fmax(worst_gpu, fabs(n[k] - want[k]));
            const float org[3] = {pos[0], pos[1] + 1.0f, pos[2]}, dir[3] = {0, -1, 0};
            rt_hit h;
            ck_assert(rt_intersect(rt, org, dir, 0.0f, 2.0f, &h));
            for (int k = 0; k < 3; k++)
                worst_cpu = fmax(worst_cpu, fabs(h.normal[k] - n[k]));
        }
        ck_assert_int_gt(covered, 900); /* the turned quad leaves the image corners */
        /* Measured: 4.7e-8 and 6.0e-8 (one float ulp) at scale 1; exactly 0 at scale 0. */
        const double tol = scale > 0.0 ? 1e-6 : 0.0;
        ck_assert_msg(worst_gpu <= tol, "scale %g: gbuffer.normal off the expected normal by %g", scale, worst_gpu);
        ck_assert_msg(worst_cpu <= tol, "scale %g: CPU hit normal off the GPU one by %g", scale, worst_cpu);
        rt_destroy(rt);
        eng_destroy(e);
        scn_destroy(s);
        free(g[0].data);
        free(g[1].data);
        free(g[2].data);
    }
}
END_TEST

/* scn_normal_at's frame on its own: T, B = (N × T)·w with w = −1 mirrors the map's y, a
 * tangent along N leaves the normal alone, and scale multiplies x and y only. */
START_TEST(normal_at_handedness)
{
    mkdir(WORK, 0777);
    write_normal_quad(WORK "/normal.gltf", 0.5);
    scn_scene *s = NULL;
    eng_error err;
    ck_assert_msg(scn_load_gltf(WORK "/normal.gltf", &s, &err) == ENG_OK, "%s", err.msg);
    const scn_material *m = &s->materials[0];
    ck_assert_float_eq(m->normal_scale, 0.5f);
    const float tp[4] = {1, 0, 0, 1}, tm[4] = {1, 0, 0, -1}, tn[4] = {0, 1, 0, 1};
    float a[3] = {0, 1, 0}, b[3] = {0, 1, 0}, c[3] = {0, 1, 0};
    ck_assert(scn_normal_at(s, m, &s->primitives[0], 0, 0.2f, 0.3f, tp, tp, tp, a));
    ck_assert(scn_normal_at(s, m, &s->primitives[0], 0, 0.2f, 0.3f, tm, tm, tm, b));
    ck_assert(!scn_normal_at(s, m, &s->primitives[0], 0, 0.2f, 0.3f, tn, tn, tn, c));
    double x = (2.0 * 204 / 255 - 1) * 0.5, y = (2.0 * 77 / 255 - 1) * 0.5, z = 2.0 * 230 / 255 - 1;
    double len = sqrt(x * x + y * y + z * z);
    ck_assert_double_eq_tol(a[0], x / len, 1e-6);
    ck_assert_double_eq_tol(a[1], z / len, 1e-6);
    ck_assert_double_eq_tol(a[2], -y / len, 1e-6); /* B = N × T = −z */
    ck_assert_double_eq_tol(b[2], y / len, 1e-6);  /* w = −1: B = +z */
    ck_assert_float_eq(c[0], 0.0f);
    ck_assert_float_eq(c[1], 1.0f);
    scn_destroy(s);
}
END_TEST

/* An 8×8 black-and-white checkerboard (sRGB 0 and 255: linear 0 and 1) with a mipmapping,
 * repeating sampler, tiled 16 times by KHR_texture_transform: every 2×2 block holds two of
 * each, so every level below the top is exactly grey 0.5. */
#define CHECKER8_PNG "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAgAAAAICAYAAADED76LAAAAGElEQVR42mNgYGD4DwI4abySQJphWJgAAAOGn2FVFEfMAAAAAElFTkSuQmCC"

static void write_checker8(const char *path)
{
    static const char nearest[] = "\"magFilter\":9728,\"minFilter\":9728,\"wrapS\":33071,\"wrapT\":33071";
    static const char mipmap[] = "\"magFilter\":9729,\"minFilter\":9987,\"wrapS\":10497,\"wrapT\":10497";
    const char *at = strstr(QUAD_PARTS, nearest);
    ck_assert_ptr_nonnull(at);
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fprintf(f,
            "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_texture_transform\"],"
            "\"scenes\":[{\"nodes\":[0]}],\"nodes\":[{\"mesh\":0}],%.*s%s%s"
            "\"images\":[{\"uri\":\"%s\"}],"
            "\"materials\":[{\"pbrMetallicRoughness\":{\"baseColorTexture\":{\"index\":0,"
            "\"extensions\":{\"KHR_texture_transform\":{\"scale\":[16,16]}}},\"metallicFactor\":0}},{}]}",
            (int)(at - QUAD_PARTS), QUAD_PARTS, mipmap, at + strlen(nearest), CHECKER8_PNG);
    ck_assert_int_eq(fclose(f), 0);
}

/* CPU mip levels (texture_mip.c): 4 levels, level 0 the checker, every texel of levels 1..3
 * exactly 0.5; scn_texture_sample_lod at λ ≤ 0 is the top level's texel, at λ = 1.5 and past
 * the last level grey; the G-buffer, which samples the same levels (engine.c uploads them),
 * sees the minified checker as exactly 0.5 at every pixel; a CPU hit's texture at a ray-cone
 * footprint (rt_hit_textures) is grey too, and the top level's texel without one. */
START_TEST(mips_average_checker_to_grey)
{
    mkdir(WORK, 0777);
    write_checker8(WORK "/checker8.gltf");
    grab g[] = {{"gbuffer.albedo", NULL, 0, 0, 0}, {NULL, NULL, 0, 0, 0}};
    scn_scene *s = NULL;
    eng_engine *e = render_top("checker8.gltf", "\"gbuffer.albedo\"", g, &s);
    const scn_texture *t = &s->textures[0];
    ck_assert_uint_eq(t->levels, 4);
    for (uint32_t l = 1; l < t->levels; l++) {
        uint32_t n = (8u >> l) * (8u >> l);
        for (uint32_t i = 0; i < n * 4; i++)
            ck_assert_float_eq(t->mips[l][i], i % 4 == 3 ? 1.0f : 0.5f);
    }
    float c[4];
    scn_texture_sample_lod(t, 0.5f / 8, 0.5f / 8, 0.0f, c); /* texel (0, 0): black */
    ck_assert_float_eq(c[0], 0.0f);
    scn_texture_sample_lod(t, 1.5f / 8, 0.5f / 8, -1.0f, c); /* texel (1, 0): white */
    ck_assert_float_eq(c[0], 1.0f);
    scn_texture_sample_lod(t, 0.3f, 0.7f, 1.5f, c);
    ck_assert_float_eq(c[0], 0.5f);
    scn_texture_sample_lod(t, 0.3f, 0.7f, 9.0f, c);
    ck_assert_float_eq(c[0], 0.5f);
    ck_assert_ptr_nonnull(g[0].data);
    for (int i = 0; i < 32 * 32; i++)
        for (int k = 0; k < 3; k++)
            ck_assert_msg(g[0].data[(size_t)i * g[0].channels + k] == 0.5f, "pixel %d channel %d: %.9g, want 0.5", i,
                          k, g[0].data[(size_t)i * g[0].channels + k]);
    /* A photon's hit at a texel centre of the quad (64 texels per metre): a 3 cm cone is
     * 1.92 texels, λ = 0.94 (trilinear between the checker and grey); a 10 cm cone (the
     * default kernel's diameter is 20 cm) is λ = 2.68: grey. */
    eng_rt *rt = rt_of_node0(s);
    rt_hit h;
    const float org[3] = {0.0078125f, 1.0f, -0.4140625f}, dir[3] = {0, -1, 0};
    ck_assert(rt_intersect(rt, org, dir, 0.0f, 2.0f, &h));
    ck_assert_msg(fabsf(h.base_tex[0] - 0.5f) > 0.499f, "no footprint: %g, want one texel (0 or 1)", h.base_tex[0]);
    ck_assert_float_eq_tol(h.world_area, 2.0f, 1e-6f);
    rt_hit_textures(s, &s->primitives[0], &h, 0.1f);
    for (int k = 0; k < 3; k++)
        ck_assert_float_eq(h.base_tex[k], 0.5f);
    rt_hit_textures(s, &s->primitives[0], &h, 0.03f);
    ck_assert(h.base_tex[0] > 0.0f && h.base_tex[0] < 1.0f && h.base_tex[0] != 0.5f);
    /* The photon trace's hits (rt_intersect_untextured) leave a textured material's factors at
     * 1 for photon_trace.c to look up once: the same hit as rt_intersect's otherwise, and the
     * same bits after that lookup, with a footprint or without. */
    for (int k = 0; k < 3; k++) {
        const float width = k == 0 ? 0.0f : k == 1 ? 0.03f : 0.1f;
        rt_hit a, b;
        memset(&a, 0, sizeof a);
        memset(&b, 0, sizeof b);
        ck_assert(rt_intersect(rt, org, dir, 0.0f, 2.0f, &a));
        ck_assert(rt_intersect_untextured(rt, org, dir, 0.0f, 2.0f, &b));
        ck_assert_float_eq(b.base_tex[0], 1.0f);
        ck_assert_float_eq(b.world_area, a.world_area);
        rt_hit_textures(s, &s->primitives[0], &a, width);
        rt_hit_textures(s, &s->primitives[0], &b, width);
        ck_assert_msg(memcmp(&a, &b, sizeof a) == 0, "width %g: the hits differ", (double)width);
    }
    rt_destroy(rt);
    eng_destroy(e);
    scn_destroy(s);
    free(g[0].data);
}
END_TEST

static Suite *texture_suite(void)
{
    Suite *s = suite_create("texture");
    TCase *tc = tcase_create("texture");
    tcase_add_test(tc, decode_and_sample_cpu);
    tcase_add_test(tc, gbuffer_albedo_checker);
    tcase_add_test(tc, gbuffer_emission_texture);
    tcase_add_test(tc, occlusion_darkens_indirect_only);
    tcase_add_test(tc, photons_carry_texture_colour);
    tcase_add_test(tc, alpha_mask_everywhere);
    tcase_add_test(tc, normal_map_gbuffer_and_hits);
    tcase_add_test(tc, normal_at_handedness);
    tcase_add_test(tc, mips_average_checker_to_grey);
    tcase_set_timeout(tc, 120);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(texture_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
