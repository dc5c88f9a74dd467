/* test_skin.c — Check suite for skins and morph targets (issue 17): deformed vertex positions
 * and normals at known times against the analytic pose (scn_deform), the loader's checks, and
 * the engine's eye G-buffer of an animated skinned model: its positions follow the pose and
 * its motion vectors reproject onto the previous frame's deformed surface.
 *
 * The glTF files are tests/data/skin_gltf.py's output (see there for what they hold). */
#define _POSIX_C_SOURCE 200809L
#include "eng.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define WORK ISPM_BINARY_DIR "/test_skin.work"

static const char SKIN_GLTF[] =
    "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0,1]}],\"nodes\":[{\"name\":\"body\",\"mesh"
    "\":0,\"skin\":0,\"translation\":[5,5,5]},{\"name\":\"root\",\"children\":[2]},{\"name\":\"tip\",\"tr"
    "anslation\":[0,1,0]}],\"skins\":[{\"joints\":[1,2],\"inverseBindMatrices\":5}],\"meshes\":[{\"primit"
    "ives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":1,\"JOINTS_0\":2,\"WEIGHTS_0\":3},\"indices\":4,\""
    "material\":0}]}],\"materials\":[{\"doubleSided\":true,\"pbrMetallicRoughness\":{\"metallicFactor\":0"
    "}}],\"animations\":[{\"channels\":[{\"sampler\":0,\"target\":{\"node\":1,\"path\":\"translation\"}},"
    "{\"sampler\":1,\"target\":{\"node\":2,\"path\":\"rotation\"}}],\"samplers\":[{\"input\":6,\"output\""
    ":7},{\"input\":6,\"output\":8}]}],\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":"
    "8,\"type\":\"VEC3\"},{\"bufferView\":1,\"componentType\":5126,\"count\":8,\"type\":\"VEC3\"},{\"buff"
    "erView\":2,\"componentType\":5121,\"count\":8,\"type\":\"VEC4\"},{\"bufferView\":3,\"componentType\""
    ":5126,\"count\":8,\"type\":\"VEC4\"},{\"bufferView\":4,\"componentType\":5123,\"count\":12,\"type\":"
    "\"SCALAR\"},{\"bufferView\":5,\"componentType\":5126,\"count\":2,\"type\":\"MAT4\"},{\"bufferView\":"
    "6,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\",\"min\":[0],\"max\":[1]},{\"bufferView\":7,"
    "\"componentType\":5126,\"count\":2,\"type\":\"VEC3\"},{\"bufferView\":8,\"componentType\":5126,\"cou"
    "nt\":2,\"type\":\"VEC4\"}],\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":96},{\"buf"
    "fer\":0,\"byteOffset\":96,\"byteLength\":96},{\"buffer\":0,\"byteOffset\":192,\"byteLength\":32},{\""
    "buffer\":0,\"byteOffset\":224,\"byteLength\":128},{\"buffer\":0,\"byteOffset\":352,\"byteLength\":24"
    "},{\"buffer\":0,\"byteOffset\":376,\"byteLength\":128},{\"buffer\":0,\"byteOffset\":504,\"byteLength"
    "\":8},{\"buffer\":0,\"byteOffset\":512,\"byteLength\":24},{\"buffer\":0,\"byteOffset\":536,\"byteLen"
    "gth\":32}],\"buffers\":[{\"byteLength\":568,\"uri\":\"data:application/octet-stream;base64,AAAAvwAAA"
    "AAAAAAAAAAAPwAAAAAAAAAAAAAAPwAAgD8AAAAAAAAAvwAAgD8AAAAAAAAAvwAAgD8K1yM8AAAAPwAAgD8K1yM8AAAAPwAAAEAK1"
    "yM8AAAAvwAAAEAK1yM8AAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/A"
    "AAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAAAAAAAAAAABAAAAAQAAAQAAAAEAAAAAAIA/AAAAA"
    "AAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAAAAAAAAPwAAAD8AAAAAAAAAAAAAA"
    "D8AAAA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAQACAAAAAgADAAQABQAGAAQABgAHAAAAgD8AA"
    "AAAAAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAAAAAAAAAAAAgD8AAIA/AAAAAAAAAAAAAAAAA"
    "AAAAAAAgD8AAAAAAAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAACAvwAAAAAAAIA/AAAAAAAAgD8AAAAAAAAAAAAAAAAAAAA/AAAAA"
    "AAAAAAAAAAAAAAAAAAAAAAAAIA/AAAAAAAAAADzBDU/8wQ1Pw==\"}]}";

static const char MORPH_GLTF[] =
    "{\"asset\":{\"version\":\"2.0\"},\"scenes\":[{\"nodes\":[0,1,2]}],\"nodes\":[{\"name\":\"animated\","
    "\"mesh\":0},{\"name\":\"fixed\",\"mesh\":0,\"weights\":[0.75],\"translation\":[2,0,0]},{\"name\":\"d"
    "efault\",\"mesh\":0,\"translation\":[4,0,0]}],\"meshes\":[{\"weights\":[0.25],\"primitives\":[{\"att"
    "ributes\":{\"POSITION\":0,\"NORMAL\":1},\"targets\":[{\"POSITION\":2,\"NORMAL\":3}]}]}],\"animations"
    "\":[{\"channels\":[{\"sampler\":0,\"target\":{\"node\":0,\"path\":\"weights\"}}],\"samplers\":[{\"in"
    "put\":4,\"output\":5}]}],\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\""
    ":\"VEC3\"},{\"bufferView\":1,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},{\"bufferView\":2"
    ",\"componentType\":5126,\"count\":3,\"type\":\"VEC3\"},{\"bufferView\":3,\"componentType\":5126,\"co"
    "unt\":3,\"type\":\"VEC3\"},{\"bufferView\":4,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\","
    "\"min\":[0],\"max\":[1]},{\"bufferView\":5,\"componentType\":5126,\"count\":2,\"type\":\"SCALAR\"}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":36,\""
    "byteLength\":36},{\"buffer\":0,\"byteOffset\":72,\"byteLength\":36},{\"buffer\":0,\"byteOffset\":108"
    ",\"byteLength\":36},{\"buffer\":0,\"byteOffset\":144,\"byteLength\":8},{\"buffer\":0,\"byteOffset\":"
    "152,\"byteLength\":8}],\"buffers\":[{\"byteLength\":160,\"uri\":\"data:application/octet-stream;base"
    "64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/A"
    "AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAA"
    "AAAgD8AAAAAAACAPw==\"}]}";

static scn_scene *load(const char *json)
{
    scn_scene *s = NULL;
    eng_error err;
    ck_assert_msg(scn_load_gltf_memory("test.gltf", json, strlen(json), &s, &err) == ENG_OK, "%s", err.msg);
    return s;
}

/* Replaces the first `from` in src by `to` (the test's bad variants of a good file). */
static char *replaced(const char *src, const char *from, const char *to)
{
    const char *at = strstr(src, from);
    ck_assert_ptr_nonnull(at);
    size_t n = strlen(src) + strlen(to) + 1;
    char *out = malloc(n);
    snprintf(out, n, "%.*s%s%s", (int)(at - src), src, to, at + strlen(from));
    return out;
}

/* The skin's analytic pose at t: root at (rx, 0, 0), rx = 0.5·clamp(t), the tip joint at
 * root + (0, 1, 0) turned θ = 90°·clamp(t) about z; inverse bind of the tip T(0, -1, 0). */
static void skin_expected(double t, const double rest[3], double w_root, double out[3])
{
    double u = t < 0 ? 0 : t > 1 ? 1 : t;
    double rx = 0.5 * u, th = u * 3.14159265358979323846 / 2, c = cos(th), s = sin(th);
    double root[3] = {rest[0] + rx, rest[1], rest[2]};
    double y = rest[1] - 1.0; /* the rest point relative to the tip joint */
    double tip[3] = {rx + c * rest[0] - s * y, 1.0 + s * rest[0] + c * y, rest[2]};
    for (int k = 0; k < 3; k++)
        out[k] = w_root * root[k] + (1.0 - w_root) * tip[k];
}

/* Bound on |deformed − analytic|: float world matrices (one rounding per level) and float
 * quaternions, coordinates below 3: a few ulp of 2, far below 2e-6. */
#define SKIN_TOL 2e-6

START_TEST(skin_poses)
{
    scn_scene *s = load(SKIN_GLTF);
    int32_t body = scn_find_node(s, "body");
    ck_assert_int_ge(body, 0);
    ck_assert_int_eq(s->nodes[body].skin, 0);
    ck_assert(scn_node_deforms(s, (uint32_t)body));
    ck_assert_int_eq(s->skins[0].joint_count, 2);
    const scn_primitive *p = &s->primitives[0];
    float *world = malloc((size_t)s->node_count * 16 * sizeof *world);
    float pos[8 * 3], nrm[8 * 3];
    /* vertex, rest position, weight of the root joint */
    const struct {
        int v;
        double rest[3], w_root;
    } probes[] = {{0, {-0.5, 0, 0}, 1.0}, {2, {0.5, 1, 0}, 1.0}, {4, {-0.5, 1, 0.01}, 0.5},
                  {5, {0.5, 1, 0.01}, 0.5},  {6, {0.5, 2, 0.01}, 0.0}, {7, {-0.5, 2, 0.01}, 0.0}};
    const double times[] = {0.0, 0.5, 1.0, 2.0}; /* start, mid-key, end, held after the end */
    for (size_t ti = 0; ti < sizeof times / sizeof times[0]; ti++) {
        scn_evaluate(s, times[ti], world);
        float none = 0.0f;
        ck_assert_int_eq(scn_deform(s, (uint32_t)body, 0, world, s->weight_count ? s->weights : &none, pos, nrm), 1);
        for (size_t k = 0; k < sizeof probes / sizeof probes[0]; k++) {
            double want[3];
            skin_expected(times[ti], probes[k].rest, probes[k].w_root, want);
            for (int c = 0; c < 3; c++)
                ck_assert_msg(fabs(pos[probes[k].v * 3 + c] - want[c]) <= SKIN_TOL,
                              "t %g vertex %d axis %d: %.9g, want %.9g", times[ti], probes[k].v, c,
                              pos[probes[k].v * 3 + c], want[c]);
        }
        for (uint32_t v = 0; v < p->vertex_count; v++) /* turned about z: normals stay +z */
            ck_assert_msg(fabsf(nrm[v * 3]) < 1e-6f && fabsf(nrm[v * 3 + 1]) < 1e-6f &&
                              fabsf(nrm[v * 3 + 2] - 1.0f) < 1e-6f,
                          "t %g normal %u: %g %g %g", times[ti], v, nrm[v * 3], nrm[v * 3 + 1], nrm[v * 3 + 2]);
    }
    free(world);
    scn_destroy(s);
}
END_TEST

START_TEST(morph_weights)
{
    scn_scene *s = load(MORPH_GLTF);
    ck_assert_uint_eq(s->weight_count, 3);
    float *world = malloc((size_t)s->node_count * 16 * sizeof *world);
    float w[3], pos[9], nrm[9];
    const char *names[3] = {"animated", "fixed", "default"};
    const double times[] = {0.0, 0.25, 0.5, 1.0, 3.0};
    for (size_t ti = 0; ti < sizeof times / sizeof times[0]; ti++) {
        double t = times[ti];
        scn_evaluate(s, t, world);
        scn_evaluate_weights(s, t, w);
        for (int k = 0; k < 3; k++) {
            int32_t n = scn_find_node(s, names[k]);
            ck_assert_int_ge(n, 0);
            /* LINEAR 0 → 1 over [0, 1], held after; node.weights 0.75; mesh.weights 0.25 */
            double want = k == 0 ? (t > 1 ? 1.0 : t) : k == 1 ? 0.75 : 0.25;
            ck_assert_float_eq(w[s->nodes[n].weight_first], (float)want);
            ck_assert_int_eq(scn_deform(s, (uint32_t)n, 0, world, w, pos, nrm), 0);
            /* v2 = (0, 1, 0) + w·(0, 0, 1), exactly; v0, v1 unmoved */
            ck_assert_float_eq(pos[6], 0.0f);
            ck_assert_float_eq(pos[7], 1.0f);
            ck_assert_float_eq(pos[8], (float)want);
            ck_assert_float_eq(pos[3], 1.0f);
            ck_assert_float_eq(pos[5], 0.0f);
            /* its normal (0, 0, 1) + w·(1, 0, 0), renormalised */
            double len = sqrt(want * want + 1.0);
            ck_assert_float_eq_tol(nrm[6], (float)(want / len), 1e-7f);
            ck_assert_float_eq_tol(nrm[8], (float)(1.0 / len), 1e-7f);
            ck_assert_float_eq(nrm[2], 1.0f);
        }
    }
    free(world);
    scn_destroy(s);
}
END_TEST

static void expect_invalid(const char *json, const char *needle)
{
    scn_scene *s = NULL;
    eng_error err;
    ck_assert_int_eq(scn_load_gltf_memory("bad.gltf", json, strlen(json), &s, &err), ENG_ERR_INVALID);
    ck_assert_ptr_null(s);
    ck_assert_msg(strstr(err.msg, needle) != NULL, "\"%s\" lacks \"%s\"", err.msg, needle);
    ck_assert_ptr_null(strchr(err.msg, '\n'));
}

START_TEST(bad_skins_and_weights)
{
    char *j = replaced(MORPH_GLTF, "\"weights\":[0.75]", "\"weights\":[0.75,1]");
    expect_invalid(j, "node 1: 2 weights for 1 morph targets");
    free(j);
    j = replaced(MORPH_GLTF, "\"weights\":[0.25]", "\"weights\":[]");
    scn_scene *s = load(j); /* an empty mesh.weights is absent: zeros */
    ck_assert_float_eq(s->weights[s->nodes[scn_find_node(s, "default")].weight_first], 0.0f);
    scn_destroy(s);
    free(j);
    j = replaced(SKIN_GLTF, "\"joints\":[1,2]", "\"joints\":[1]");
    expect_invalid(j, "uses joint 1, skin 0 has 1 joints");
    free(j);
    j = replaced(SKIN_GLTF, "\"joints\":[1,2]", "\"joints\":[1,9]");
    expect_invalid(j, "skins[0]: joint 9 out of range");
    free(j);
}
END_TEST

/* ---------------------------------------------------------------- engine */

typedef struct grab {
    const char *name;
    float *data;
    int channels;
} grab;

static int grab_buffer(void *user, int frame, const eng_buffer *b)
{
    (void)frame;
    for (grab *g = user; g->name; g++)
        if (!strcmp(b->name, g->name)) {
            size_t n = (size_t)b->width * b->height * b->channel_count;
            free(g->data);
            g->data = malloc(n * sizeof *g->data);
            memcpy(g->data, b->data, n * sizeof *g->data);
            g->channels = b->channel_count;
        }
    return 0;
}

#define RES 64

/* Bilinear value of channel c of a RES×RES image of `ch` channels at continuous pixel-centre
 * coordinates (x, y); 0 where a tap is outside or not on the same part (part(): 0 none). */
static int bilinear(const float *img, int ch, const float *depth, const float *pos, double x, double y, int part,
                    double out[3])
{
    int x0 = (int)floor(x), y0 = (int)floor(y);
    double ax = x - x0, ay = y - y0;
    if (x0 < 0 || y0 < 0 || x0 + 1 >= RES || y0 + 1 >= RES)
        return 0;
    for (int k = 0; k < 3; k++)
        out[k] = 0.0;
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            size_t at = (size_t)(y0 + j) * RES + (size_t)(x0 + i);
            if (!(depth[at] > 0.0f) || (pos[at * 3 + 2] > 0.005f) != (part == 2))
                return 0;
            double wgt = (i ? ax : 1 - ax) * (j ? ay : 1 - ay);
            for (int k = 0; k < 3; k++)
                out[k] += wgt * img[at * ch + k];
        }
    return 1;
}

/* Barycentrics of (x, y) in the xy-projection of triangle (a, b, c); 1 if inside (with slack). */
static int barycentric(const float *a, const float *b, const float *c, double x, double y, double w[3])
{
    double d = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    if (fabs(d) < 1e-12)
        return 0;
    w[1] = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / d;
    w[2] = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / d;
    w[0] = 1.0 - w[1] - w[2];
    return w[0] > -1e-4 && w[1] > -1e-4 && w[2] > -1e-4;
}

/* Bound on |pos_{f-1}(p + motion) − X_{f-1}|, metres: a pixel here spans ~0.07 m, the
 * bilinear tap of a perspective-projected plane is off by far less than 1e-3 of that;
 * a motion vector that ignored the deformation would be off by the 0.06–0.4 m the surface
 * moves between frames. */
#define REPROJ_TOL 1e-3

START_TEST(engine_skinned_motion)
{
    mkdir(WORK, 0777);
    FILE *f = fopen(WORK "/skin.gltf", "w");
    ck_assert_ptr_nonnull(f);
    fputs(SKIN_GLTF, f);
    ck_assert_int_eq(fclose(f), 0);
    const char *json =
        "{\"scene\": \"skin.gltf\", \"frames\": 3, \"fps\": 4, \"resolution\": [64, 64],"
        " \"camera\": {\"keys\": [{\"time\": 0, \"position\": [0, 1, 4], \"target\": [0, 1, 0]}], \"yfov_deg\": 60},"
        " \"lights\": [{\"type\": \"point\", \"position\": [0, 1, 3]}],"
        " \"settings\": {\"shadow_map_size\": 64, \"photon_count\": 64, \"threads\": 2},"
        " \"capture\": [\"gbuffer.position\", \"gbuffer.depth\", \"gbuffer.motion\"]}";
    seq_sequence q;
    scn_scene *s = NULL;
    eng_engine *e = NULL;
    eng_error err;
    ck_assert_msg(seq_parse(WORK "/seq.json", json, strlen(json), &q, &err) == ENG_OK, "%s", err.msg);
    ck_assert_msg(seq_load_scene(&q, &s, &err) == ENG_OK, "%s", err.msg);
    eng_desc d = {.scene = s, .sequence = &q};
    ck_assert_msg(eng_create(&d, &e, &err) == ENG_OK, "%s", err.msg);
    grab g[] = {{"gbuffer.position", NULL, 0}, {"gbuffer.depth", NULL, 0}, {"gbuffer.motion", NULL, 0}, {NULL, NULL, 0}};
    eng_listener l = {g, NULL, grab_buffer, NULL};
    ck_assert_int_eq(eng_add_listener(e, &l), ENG_OK);
    float *prev_pos = NULL, *prev_depth = NULL;
    int32_t body = scn_find_node(s, "body");
    float *world = malloc((size_t)s->node_count * 16 * sizeof *world);
    float vp[2][8 * 3], nrm[8 * 3];
    for (int frame = 0; frame < 3; frame++) {
        ck_assert_msg(eng_render_frame(e, frame, &err) == ENG_OK, "%s", err.msg);
        if (frame == 2) {
            /* deformed vertices at frames 1 and 2 (t = 0.25, 0.5), checked above against the pose */
            for (int k = 0; k < 2; k++) {
                scn_evaluate(s, 0.25 * (k + 1), world);
                scn_deform(s, (uint32_t)body, 0, world, s->weights, vp[k], nrm);
            }
            int checked = 0, moved = 0;
            double worst = 0.0;
            for (int y = 0; y < RES; y++)
                for (int x = 0; x < RES; x++) {
                    size_t at = (size_t)y * RES + x;
                    if (!(g[1].data[at] > 0.0f))
                        continue;
                    const float *X = g[0].data + at * 3;
                    int part = X[2] > 0.005f ? 2 : 1;
                    /* the triangle under the pixel this frame, and the same point last frame */
                    static const int tris[4][3] = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
                    double b[3], xp[3] = {0, 0, 0};
                    int found = 0;
                    for (int t = (part - 1) * 2; t < part * 2 && !found; t++)
                        if (barycentric(vp[1] + tris[t][0] * 3, vp[1] + tris[t][1] * 3, vp[1] + tris[t][2] * 3, X[0], X[1], b)) {
                            found = 1;
                            for (int k = 0; k < 3; k++)
                                for (int c = 0; c < 3; c++)
                                    xp[c] += b[k] * vp[0][tris[t][k] * 3 + c];
                        }
                    if (!found)
                        continue;
                    const float *mv = g[2].data + at * 2;
                    double got[3];
                    if (!bilinear(prev_pos, 3, prev_depth, prev_pos, x + mv[0], y + mv[1], part, got))
                        continue; /* the point was hidden or off the part's interior last frame */
                    double err2 = 0.0, move = 0.0;
                    for (int c = 0; c < 3; c++) {
                        err2 += (got[c] - xp[c]) * (got[c] - xp[c]);
                        move += ((double)X[c] - xp[c]) * ((double)X[c] - xp[c]);
                    }
                    worst = fmax(worst, sqrt(err2));
                    moved += sqrt(move) > 0.05;
                    checked++;
                }
            fprintf(stderr, "test_skin: %d pixels reprojected (%d moved > 5 cm), worst %.3g m (bound %g)\n", checked,
                    moved, worst, REPROJ_TOL);
            ck_assert_int_gt(checked, 200);
            ck_assert_int_gt(moved, 100);
            ck_assert_msg(worst <= REPROJ_TOL, "reprojection off by %g m", worst);
            /* the positions changed between the frames */
            ck_assert_int_ne(memcmp(prev_pos, g[0].data, RES * RES * 3 * sizeof(float)), 0);
        }
        free(prev_pos);
        free(prev_depth);
        prev_pos = g[0].data;
        prev_depth = g[1].data;
        g[0].data = g[1].data = NULL;
    }
    free(prev_pos);
    free(prev_depth);
    free(g[2].data);
    free(world);
    eng_destroy(e);
    scn_destroy(s);
}
END_TEST

/* src with a zero VEC4 accessor of `count` elements (no bufferView: all zeros, glTF
 * §3.6.2.3) appended to its accessors, and attr_from replaced by attr_to. */
static char *with_zero_vec4(const char *src, const char *attr_from, const char *attr_to, int count)
{
    char to[128];
    snprintf(to, sizeof to, "},{\"componentType\":5126,\"count\":%d,\"type\":\"VEC4\"}],\"bufferViews\"", count);
    char *a = replaced(src, "}],\"bufferViews\"", to);
    char *b = replaced(a, attr_from, attr_to);
    free(a);
    return b;
}

/* JOINTS_1/WEIGHTS_1 (8 influences): a second set of zero weights leaves every vertex where
 * the first set alone puts it (bit for bit); the first set repeated as the second doubles
 * the skin matrix, so every deformed position is twice the 4-influence one. A JOINTS_1
 * without JOINTS_0 is an error. */
START_TEST(eight_influences)
{
    scn_scene *s4 = load(SKIN_GLTF);
    char *zero = with_zero_vec4(SKIN_GLTF, "\"WEIGHTS_0\":3}", "\"WEIGHTS_0\":3,\"JOINTS_1\":2,\"WEIGHTS_1\":9}", 8);
    char *twice = replaced(SKIN_GLTF, "\"WEIGHTS_0\":3}", "\"WEIGHTS_0\":3,\"JOINTS_1\":2,\"WEIGHTS_1\":3}");
    scn_scene *sz = load(zero), *s2 = load(twice);
    ck_assert_uint_eq(s4->primitives[0].influences, 4);
    ck_assert_uint_eq(sz->primitives[0].influences, 8);
    ck_assert_uint_eq(s2->primitives[0].influences, 8);
    int32_t body = scn_find_node(s4, "body");
    float *world = malloc((size_t)s4->node_count * 16 * sizeof *world);
    float p4[8 * 3], pz[8 * 3], p2[8 * 3], nrm[8 * 3];
    float none = 0.0f;
    scn_evaluate(s4, 0.75, world);
    ck_assert_int_eq(scn_deform(s4, (uint32_t)body, 0, world, &none, p4, nrm), 1);
    ck_assert_int_eq(scn_deform(sz, (uint32_t)body, 0, world, &none, pz, nrm), 1);
    ck_assert_int_eq(scn_deform(s2, (uint32_t)body, 0, world, &none, p2, nrm), 1);
    for (int i = 0; i < 8 * 3; i++) {
        ck_assert_float_eq(pz[i], p4[i]);
        ck_assert_msg(fabs(p2[i] - 2.0 * p4[i]) <= 1e-6, "component %d: %.9g, want %.9g", i, p2[i], 2.0 * p4[i]);
    }
    char *alone = replaced(SKIN_GLTF, "\"JOINTS_0\":2,\"WEIGHTS_0\":3}", "\"JOINTS_1\":2,\"WEIGHTS_1\":3}");
    scn_scene *bad = NULL;
    eng_error err;
    ck_assert_int_eq(scn_load_gltf_memory("test.gltf", alone, strlen(alone), &bad, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "JOINTS_1 without JOINTS_0"), "%s", err.msg);
    free(alone);
    free(world);
    free(zero);
    free(twice);
    scn_destroy(s4);
    scn_destroy(sz);
    scn_destroy(s2);
}
END_TEST

/* Tangents follow the deformation (normal maps on skinned and morphed meshes): skinned by the
 * skin matrix's upper 3×3 and renormalised, handedness kept; morphed by their TANGENT deltas. */
START_TEST(tangents_deform)
{
    /* The skin with WEIGHTS_0's accessor as TANGENT too (xyz = the weights, w = 0: +1). */
    char *tj = replaced(SKIN_GLTF, "\"WEIGHTS_0\":3}", "\"WEIGHTS_0\":3,\"TANGENT\":3}");
    scn_scene *s = load(tj);
    const scn_primitive *p = &s->primitives[0];
    ck_assert_ptr_nonnull(p->tangents);
    int32_t body = scn_find_node(s, "body");
    float *world = malloc((size_t)s->node_count * 16 * sizeof *world);
    float pos[8 * 3], nrm[8 * 3], tan[8 * 4];
    float none = 0.0f;
    scn_evaluate(s, 1.0, world); /* tip turned 90° about z */
    ck_assert_int_eq(scn_deform_tangents(s, (uint32_t)body, 0, world, &none, pos, nrm, tan), 1);
    for (uint32_t v = 0; v < p->vertex_count; v++) {
        const float *t = p->tangents + v * 4;
        double wr = 0.0; /* the root's (joint 0) weight; the tip has the rest */
        for (int k = 0; k < 4; k++)
            wr += p->joints[v * 4 + k] == 0 ? p->weights[v * 4 + k] : 0.0;
        /* (wr·I + (1 − wr)·Rz(90°)) t */
        double m[3] = {wr * t[0] - (1 - wr) * t[1], wr * t[1] + (1 - wr) * t[0], t[2]};
        double len = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        for (int k = 0; k < 3; k++)
            ck_assert_msg(fabs(tan[v * 4 + k] - m[k] / len) <= 1e-6, "vertex %u axis %d: %.9g, want %.9g", v, k,
                          tan[v * 4 + k], m[k] / len);
        ck_assert_float_eq(tan[v * 4 + 3], 1.0f);
    }
    free(tj);
    scn_destroy(s);
    /* The morph with a zero base TANGENT and the NORMAL deltas as TANGENT deltas: at weight
     * 0.75 (node "fixed") the tangent is the deltas' direction. */
    char *tm = with_zero_vec4(MORPH_GLTF, "\"NORMAL\":1},\"targets\":[{\"POSITION\":2,\"NORMAL\":3}]",
                              "\"NORMAL\":1,\"TANGENT\":6},\"targets\":[{\"POSITION\":2,\"NORMAL\":3,\"TANGENT\":3}]", 3);
    s = load(tm);
    p = &s->primitives[0];
    ck_assert_ptr_nonnull(p->target_tangents);
    int32_t fixed = scn_find_node(s, "fixed");
    float *w = malloc((size_t)s->weight_count * sizeof *w);
    free(world);
    world = malloc((size_t)s->node_count * 16 * sizeof *world);
    scn_evaluate(s, 0.0, world);
    scn_evaluate_weights(s, 0.0, w);
    ck_assert_int_eq(scn_deform_tangents(s, (uint32_t)fixed, 0, world, w, pos, nrm, tan), 0);
    for (uint32_t v = 0; v < p->vertex_count; v++) {
        const float *d = p->target_normals + v * 3;
        double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
        if (len == 0.0)
            continue;
        for (int k = 0; k < 3; k++)
            ck_assert_msg(fabs(tan[v * 4 + k] - d[k] / len) <= 1e-6, "vertex %u axis %d: %.9g", v, k, tan[v * 4 + k]);
    }
    free(w);
    free(world);
    free(tm);
    scn_destroy(s);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("skin");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 60);
    tcase_add_test(tc, skin_poses);
    tcase_add_test(tc, morph_weights);
    tcase_add_test(tc, eight_influences);
    tcase_add_test(tc, tangents_deform);
    tcase_add_test(tc, bad_skins_and_weights);
    tcase_add_test(tc, engine_skinned_motion);
    suite_add_tcase(s, tc);
    SRunner *r = srunner_create(s);
    srunner_run_all(r, CK_NORMAL);
    int failed = srunner_ntests_failed(r);
    srunner_free(r);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
