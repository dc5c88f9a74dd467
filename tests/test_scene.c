/* test_scene.c — Check suite for the scene module (engine/scene/gltf_load.c, scene.c, sequence.c).
 *
 * Topics: the Cornell box glTF against its OBJ/README spec; evaluation of the animated scene
 * and of a hand-made hierarchy; channel sampling against hand-computed values; flat normals;
 * sequence files (valid, and one failure per rule); a corpus of malformed glTF files under
 * tests/data/gltf/, each with the eng_result it must produce; and a byte-mutation pass over a
 * small glTF that must never crash. Tests check result codes, never message text. */
#include "seq.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DATA ISPM_SOURCE_DIR "/tests/data/gltf/"
#define CORNELL ISPM_SOURCE_DIR "/scenes/cornell-box/"
#define PI 3.14159265358979323846

static scn_scene *load_ok(const char *path)
{
    scn_scene *s = NULL;
    eng_error err = {{0}};
    eng_result r = scn_load_gltf(path, &s, &err);
    ck_assert_msg(r == ENG_OK, "%s: %s (%s)", path, eng_result_name(r), err.msg);
    ck_assert_ptr_nonnull(s);
    return s;
}

static const scn_node *node_named(const scn_scene *s, const char *name)
{
    int32_t i = scn_find_node(s, name);
    ck_assert_msg(i >= 0, "node %s missing", name);
    return &s->nodes[i];
}

/* ---------------------------------------------------------------- Cornell box */

START_TEST(cornell_nodes)
{
    scn_scene *s = load_ok(CORNELL "cornell-box.gltf");
    static const char *const names[] = {"floor", "ceiling", "backWall", "rightWall", "leftWall",
                                        "shortBox", "tallBox", "Light", "Camera"};
    ck_assert_uint_eq(s->node_count, 9);
    for (int i = 0; i < 9; i++) {
        ck_assert_str_eq(s->nodes[i].name, names[i]);
        ck_assert_int_eq(s->nodes[i].parent, -1);
        ck_assert_int_eq(scn_find_node(s, names[i]), i);
    }
    ck_assert_int_eq(scn_find_node(s, "nope"), -1);
    ck_assert_uint_eq(s->mesh_count, 7);
    ck_assert_uint_eq(s->material_count, 7);
    ck_assert_str_eq(s->meshes[s->nodes[0].mesh].name, "floor");
    ck_assert_uint_eq(strlen(s->digest), 32);
    scn_destroy(s);
}
END_TEST

START_TEST(cornell_floor_exact)
{
    scn_scene *s = load_ok(CORNELL "cornell-box.gltf");
    const scn_node *n = node_named(s, "floor");
    const scn_mesh *m = &s->meshes[n->mesh];
    ck_assert_uint_eq(m->primitive_count, 1);
    const scn_primitive *p = &s->primitives[m->first_primitive];
    /* The OBJ quad q0..q3 split 0-1-2, 0-2-3, each triangle with its own vertices. */
    const float q[4][3] = {{-1.01f, 0.00f, 0.99f}, {1.00f, 0.00f, 0.99f}, {1.00f, 0.00f, -1.04f},
                           {-0.99f, 0.00f, -1.04f}};
    const int corner[6] = {0, 1, 2, 0, 2, 3};
    ck_assert_uint_eq(p->index_count, 6);
    for (int i = 0; i < 6; i++) {
        const float *v = p->positions + (size_t)p->indices[i] * 3;
        const float *nv = p->normals + (size_t)p->indices[i] * 3;
        for (int k = 0; k < 3; k++)
            ck_assert_msg(v[k] == q[corner[i]][k], "floor corner %d axis %d: %.9g != %.9g", i, k, v[k],
                          q[corner[i]][k]);
        ck_assert(nv[0] == 0.0f && nv[1] == 1.0f && nv[2] == 0.0f);
    }
    const scn_material *mat = &s->materials[p->material];
    ck_assert_str_eq(mat->name, "floor");
    ck_assert(mat->base_color[0] == 0.725f && mat->base_color[1] == 0.71f && mat->base_color[2] == 0.68f);
    ck_assert(mat->base_color[3] == 1.0f);
    ck_assert(mat->metallic == 0.0f && mat->roughness == 1.0f);
    ck_assert(mat->transmission == 0.0f && mat->ior == 1.5f);
    ck_assert_int_eq(mat->double_sided, 1);
    scn_destroy(s);
}
END_TEST

START_TEST(cornell_light_camera)
{
    scn_scene *s = load_ok(CORNELL "cornell-box.gltf");
    const scn_node *ln = node_named(s, "Light");
    ck_assert_int_ge(ln->light, 0);
    ck_assert(ln->translation[0] == 0.0f && ln->translation[1] == 1.8f && ln->translation[2] == 0.0f);
    const scn_light *l = &s->lights[ln->light];
    ck_assert_str_eq(l->name, "light0");
    ck_assert_int_eq(l->type, SCN_LIGHT_POINT);
    ck_assert(l->intensity == 3.0f);
    ck_assert(l->color[0] == 1.0f && l->color[1] == 1.0f && l->color[2] == 1.0f);
    ck_assert(l->range == 0.0f);

    const scn_node *cn = node_named(s, "Camera");
    ck_assert_int_ge(cn->camera, 0);
    ck_assert(cn->translation[0] == 0.0f && cn->translation[1] == 1.0f && cn->translation[2] == 3.9f);
    ck_assert(cn->rotation[0] == 0.0f && cn->rotation[1] == 0.0f && cn->rotation[2] == 0.0f &&
              cn->rotation[3] == 1.0f);
    const scn_camera *c = &s->cameras[cn->camera];
    ck_assert_float_eq_tol(c->yfov, (float)(40.0 * PI / 180.0), 1e-7f);
    ck_assert(c->aspect == 1.0f && c->znear == 0.05f && c->zfar == 100.0f);

    ck_assert_uint_eq(s->animation_count, 1);
    ck_assert_str_eq(s->animations[0].name, "slide_and_dolly");
    ck_assert_uint_eq(s->animations[0].channel_count, 2);
    scn_destroy(s);
}
END_TEST

START_TEST(cornell_digest_is_file_digest)
{
    scn_scene *s = load_ok(CORNELL "cornell-box.gltf");
    char *bytes;
    size_t len;
    char hex[40];
    ck_assert_int_eq(eng_read_file(CORNELL "cornell-box.gltf", 1 << 26, &bytes, &len, NULL), ENG_OK);
    eng_digest_hex(bytes, len, hex);
    ck_assert_str_eq(s->digest, hex);
    free(bytes);
    scn_destroy(s);

    /* An external buffer is part of the digest: it differs from the .gltf's alone. */
    s = load_ok(DATA "valid-external-buffer.gltf");
    ck_assert_int_eq(eng_read_file(DATA "valid-external-buffer.gltf", 1 << 20, &bytes, &len, NULL), ENG_OK);
    eng_digest_hex(bytes, len, hex);
    ck_assert_str_ne(s->digest, hex);
    ck_assert_uint_eq(s->primitives[0].vertex_count, 3);
    free(bytes);
    scn_destroy(s);

    /* A .glb is digested as the file it is. */
    s = load_ok(DATA "valid-triangle.glb");
    ck_assert_int_eq(eng_read_file(DATA "valid-triangle.glb", 1 << 20, &bytes, &len, NULL), ENG_OK);
    eng_digest_hex(bytes, len, hex);
    ck_assert_str_eq(s->digest, hex);
    ck_assert_uint_eq(s->primitives[0].index_count, 3);
    free(bytes);
    scn_destroy(s);
}
END_TEST

START_TEST(cornell_glass)
{
    scn_scene *s = load_ok(CORNELL "cornell-glass.gltf");
    const scn_node *n = node_named(s, "glassSphere");
    const scn_primitive *p = &s->primitives[s->meshes[n->mesh].first_primitive];
    ck_assert_uint_eq(p->index_count, 2208 * 3);
    const scn_material *m = &s->materials[p->material];
    ck_assert_str_eq(m->name, "glass");
    ck_assert(m->transmission == 1.0f && m->ior == 1.5f && m->roughness == 0.0f && m->metallic == 0.0f);
    ck_assert(m->base_color[0] == 1.0f && m->base_color[3] == 1.0f);
    /* Smooth normals: unit length and pointing away from the centre (0.35, 0.3, 0.35). */
    for (uint32_t v = 0; v < p->vertex_count; v++) {
        const float *x = p->positions + v * 3, *nv = p->normals + v * 3;
        double len = sqrt((double)nv[0] * nv[0] + (double)nv[1] * nv[1] + (double)nv[2] * nv[2]);
        ck_assert_double_eq_tol(len, 1.0, 1e-6);
        double d = (x[0] - 0.35) * nv[0] + (x[1] - 0.3) * nv[1] + (x[2] - 0.35) * nv[2];
        ck_assert_msg(d > 0.29, "vertex %u normal not outward", v);
    }
    ck_assert_uint_eq(s->animation_count, 0);
    ck_assert_int_ge(node_named(s, "Light")->light, 0);
    ck_assert_int_ge(node_named(s, "Camera")->camera, 0);
    scn_destroy(s);
}
END_TEST

/* ---------------------------------------------------------------- evaluation */

/* tol 0 asks for exact equality. */
static void check_translation(const float *world, int node, float x, float y, float z, float tol)
{
    const float *m = world + node * 16;
    const float want[3] = {x, y, z};
    for (int k = 0; k < 3; k++)
        ck_assert_msg(fabsf(m[12 + k] - want[k]) <= tol, "node %d axis %d: %.9g, want %.9g (tol %g)", node, k,
                      m[12 + k], want[k], tol);
    ck_assert(m[15] == 1.0f);
}

START_TEST(evaluate_cornell)
{
    scn_scene *s = load_ok(CORNELL "cornell-box.gltf");
    float *w = malloc(s->node_count * 16 * sizeof *w);
    int box = scn_find_node(s, "shortBox"), cam = scn_find_node(s, "Camera"), light = scn_find_node(s, "Light");

    scn_evaluate(s, 0.0, w);
    for (int k = 0; k < 16; k++)
        ck_assert(w[box * 16 + k] == ((k % 5 == 0) ? 1.0f : 0.0f));
    check_translation(w, cam, 0.0f, 1.0f, 3.9f, 0.0f);
    check_translation(w, light, 0.0f, 1.8f, 0.0f, 0.0f);

    scn_evaluate(s, 0.5, w);
    check_translation(w, box, -0.075f, 0.0f, 0.05f, 1e-7f);
    check_translation(w, cam, 0.0f, 1.0f, 3.75f, 1e-6f);
    for (int k = 0; k < 12; k++) /* the camera only moves */
        ck_assert(w[cam * 16 + k] == ((k % 5 == 0) ? 1.0f : 0.0f));

    scn_evaluate(s, 0.875, w); /* the CI sequence's last frame */
    check_translation(w, cam, 0.0f, 1.0f, 3.9f - 0.3f * 0.875f, 1e-6f);

    scn_evaluate(s, 7.0, w); /* clamped after the last key */
    check_translation(w, box, -0.15f, 0.0f, 0.10f, 0.0f);
    check_translation(w, cam, 0.0f, 1.0f, 3.6f, 0.0f);
    scn_evaluate(s, -1.0, w); /* and before the first */
    check_translation(w, box, 0.0f, 0.0f, 0.0f, 0.0f);
    free(w);
    scn_destroy(s);
}
END_TEST

START_TEST(evaluate_hierarchy)
{
    /* File order: leaf (child of root), orphan (in no scene), root, scene1only (in the other
     * scene). Default scene 1 keeps root and leaf, parents first. */
    scn_scene *s = load_ok(DATA "valid-hierarchy.gltf");
    ck_assert_uint_eq(s->node_count, 2);
    ck_assert_str_eq(s->nodes[0].name, "root");
    ck_assert_str_eq(s->nodes[1].name, "leaf");
    ck_assert_int_eq(s->nodes[0].parent, -1);
    ck_assert_int_eq(s->nodes[1].parent, 0);
    ck_assert_int_eq(scn_find_node(s, "orphan"), -1);
    ck_assert_int_eq(scn_find_node(s, "scene1only"), -1);
    /* The channel on the orphan is dropped; the one on the leaf follows it to index 1. */
    ck_assert_uint_eq(s->animations[0].channel_count, 1);
    ck_assert_int_eq(s->animations[0].channels[0].node, 1);
    ck_assert_int_eq(s->animations[0].channels[0].path, SCN_PATH_SCALE);

    float w[32];
    scn_evaluate(s, 0.5, w);
    /* root: 90° about +Y then (10,0,0); leaf at (0,0,1) in root space -> (11,0,0). */
    check_translation(w, 0, 10.0f, 0.0f, 0.0f, 1e-6f);
    check_translation(w, 1, 11.0f, 0.0f, 0.0f, 1e-6f);
    /* Leaf scale (0.5, 1, 1.5) at t = 0.5: its local X axis (scaled 0.5) becomes world -Z. */
    ck_assert_float_eq_tol(w[16 + 0], 0.0f, 1e-6f);
    ck_assert_float_eq_tol(w[16 + 2], -0.5f, 1e-6f);
    ck_assert_float_eq_tol(w[16 + 5], 1.0f, 1e-6f);
    ck_assert_float_eq_tol(w[16 + 8], 1.5f, 1e-6f);
    scn_destroy(s);
}
END_TEST

/* ---------------------------------------------------------------- sampling */

static scn_channel channel(scn_anim_path path, scn_interp interp, uint32_t n, float *times, float *values)
{
    scn_channel c = {0, path, interp, n, times, values, 0};
    return c;
}

START_TEST(sample_step)
{
    float t[3] = {0.0f, 1.0f, 2.0f};
    float v[9] = {0, 0, 0, 10, 0, 0, 20, 0, 0};
    scn_channel c = channel(SCN_PATH_TRANSLATION, SCN_INTERP_STEP, 3, t, v);
    float o[3];
    static const double at[] = {-1.0, 0.0, 0.5, 0.999, 1.0, 1.999, 2.0, 3.0};
    static const float want[] = {0, 0, 0, 0, 10, 10, 20, 20};
    for (size_t i = 0; i < sizeof at / sizeof at[0]; i++) {
        scn_sample_channel(&c, at[i], o);
        ck_assert_msg(o[0] == want[i], "STEP at %g: %g != %g", at[i], o[0], want[i]);
    }
}
END_TEST

START_TEST(sample_linear)
{
    float t[3] = {1.0f, 2.0f, 4.0f};
    float v[9] = {0, 0, 0, 10, -2, 4, 20, 0, 0};
    scn_channel c = channel(SCN_PATH_TRANSLATION, SCN_INTERP_LINEAR, 3, t, v);
    float o[3];
    scn_sample_channel(&c, 1.25, o);
    ck_assert_float_eq_tol(o[0], 2.5f, 1e-6f);
    ck_assert_float_eq_tol(o[1], -0.5f, 1e-6f);
    ck_assert_float_eq_tol(o[2], 1.0f, 1e-6f);
    scn_sample_channel(&c, 3.0, o);
    ck_assert_float_eq_tol(o[0], 15.0f, 1e-6f);
    ck_assert_float_eq_tol(o[1], -1.0f, 1e-6f);
    scn_sample_channel(&c, 0.0, o); /* before the range: first key */
    ck_assert(o[0] == 0.0f && o[1] == 0.0f && o[2] == 0.0f);
    scn_sample_channel(&c, 100.0, o); /* after: last key */
    ck_assert(o[0] == 20.0f && o[1] == 0.0f && o[2] == 0.0f);
    scn_sample_channel(&c, NAN, o); /* a NaN time holds the first key rather than spreading */
    ck_assert(o[0] == 0.0f);
}
END_TEST

START_TEST(sample_cubicspline)
{
    /* Keys at t = 0 and 2 (dt = 2); per key (in-tangent, value, out-tangent).
     * x: p0 0, out0 1 -> m0 = 2; p1 1, in1 0 -> m1 = 0. At u = 0.5 the Hermite weights are
     * h00 = 0.5, h10 = 0.125, h01 = 0.5, h11 = -0.125: x = 0.25 + 0.5 = 0.75.
     * y: p0 2, out0 0; p1 4, in1 3 -> m1 = 6: y = 1 + 2 - 0.75 = 2.25.
     * z: constant 5 with zero tangents. */
    float t[2] = {0.0f, 2.0f};
    float v[18] = {9, 9, 9, 0, 2, 5, 1, 0, 0, /* key 0 */
                   0, 3, 0, 1, 4, 5, 9, 9, 9}; /* key 1 */
    scn_channel c = channel(SCN_PATH_TRANSLATION, SCN_INTERP_CUBICSPLINE, 2, t, v);
    float o[3];
    scn_sample_channel(&c, 1.0, o);
    ck_assert_float_eq_tol(o[0], 0.75f, 1e-6f);
    ck_assert_float_eq_tol(o[1], 2.25f, 1e-6f);
    ck_assert_float_eq_tol(o[2], 5.0f, 1e-6f);
    /* u = 0.25: h00 = 0.84375, h10 = 0.140625, h01 = 0.15625, h11 = -0.046875. */
    scn_sample_channel(&c, 0.5, o);
    ck_assert_float_eq_tol(o[0], 0.140625f * 2.0f + 0.15625f, 1e-6f);
    ck_assert_float_eq_tol(o[1], 0.84375f * 2.0f + 0.15625f * 4.0f - 0.046875f * 6.0f, 1e-6f);
    scn_sample_channel(&c, -3.0, o); /* clamped: values, never tangents */
    ck_assert(o[0] == 0.0f && o[1] == 2.0f && o[2] == 5.0f);
    scn_sample_channel(&c, 2.0, o);
    ck_assert(o[0] == 1.0f && o[1] == 4.0f && o[2] == 5.0f);
    scn_sample_channel(&c, 9.0, o);
    ck_assert(o[0] == 1.0f && o[1] == 4.0f && o[2] == 5.0f);
}
END_TEST

START_TEST(sample_slerp)
{
    const float s45 = (float)sin(PI / 4.0), c45 = (float)cos(PI / 4.0);
    float t[2] = {0.0f, 1.0f};
    float v[8] = {0, 0, 0, 1, 0, 0, s45, c45}; /* identity -> 90° about Z */
    scn_channel c = channel(SCN_PATH_ROTATION, SCN_INTERP_LINEAR, 2, t, v);
    float o[4];
    scn_sample_channel(&c, 0.5, o);
    ck_assert_float_eq_tol(o[0], 0.0f, 1e-7f);
    ck_assert_float_eq_tol(o[1], 0.0f, 1e-7f);
    ck_assert_float_eq_tol(o[2], (float)sin(PI / 8.0), 1e-6f);
    ck_assert_float_eq_tol(o[3], (float)cos(PI / 8.0), 1e-6f);
    scn_sample_channel(&c, 0.25, o); /* constant angular speed: 22.5° */
    ck_assert_float_eq_tol(o[2], (float)sin(PI / 16.0), 1e-6f);
    ck_assert_float_eq_tol(o[3], (float)cos(PI / 16.0), 1e-6f);

    /* The same rotation given as -q: shortest arc, same result. */
    v[6] = -s45;
    v[7] = -c45;
    scn_sample_channel(&c, 0.5, o);
    ck_assert_float_eq_tol(o[2], (float)sin(PI / 8.0), 1e-6f);
    ck_assert_float_eq_tol(o[3], (float)cos(PI / 8.0), 1e-6f);

    /* Results are normalised whatever the keys' length and the interpolation. */
    float vs[8] = {0, 0, 0, 2, 0, 0, 0, 2};
    scn_channel st = channel(SCN_PATH_ROTATION, SCN_INTERP_STEP, 2, t, vs);
    scn_sample_channel(&st, 0.5, o);
    ck_assert(o[0] == 0.0f && o[1] == 0.0f && o[2] == 0.0f && o[3] == 1.0f);
    float vc[24] = {0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0.3f, 0, /* key 0: in, value, out */
                    0, 0, 0.3f, 0, 0, 0, s45, c45, 0, 0, 0, 0};
    scn_channel cu = channel(SCN_PATH_ROTATION, SCN_INTERP_CUBICSPLINE, 2, t, vc);
    scn_sample_channel(&cu, 0.4, o);
    double len = sqrt((double)o[0] * o[0] + (double)o[1] * o[1] + (double)o[2] * o[2] + (double)o[3] * o[3]);
    ck_assert_double_eq_tol(len, 1.0, 1e-6);
}
END_TEST

/* ---------------------------------------------------------------- flat normals */

START_TEST(flat_normals)
{
    scn_scene *s = load_ok(DATA "valid-no-normals.gltf");
    ck_assert_uint_eq(s->primitive_count, 1);
    const scn_primitive *p = &s->primitives[0];
    /* Two triangles sharing an edge are un-shared: 6 vertices, indices 0..5. */
    ck_assert_uint_eq(p->vertex_count, 6);
    ck_assert_uint_eq(p->index_count, 6);
    for (uint32_t i = 0; i < 6; i++)
        ck_assert_uint_eq(p->indices[i], i);
    const float want_pos[6][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 1}};
    const float r3 = (float)(1.0 / sqrt(3.0));
    const float want_n[2][3] = {{0, 0, 1}, {r3, -r3, r3}};
    for (int v = 0; v < 6; v++)
        for (int k = 0; k < 3; k++) {
            ck_assert(p->positions[v * 3 + k] == want_pos[v][k]);
            ck_assert_float_eq_tol(p->normals[v * 3 + k], want_n[v / 3][k], 1e-7f);
        }
    ck_assert_int_eq(p->material, -1);
    scn_destroy(s);

    /* A triangle of a file that gives no normals either. */
    s = load_ok(DATA "valid-triangle.gltf");
    ck_assert_uint_eq(s->primitives[0].vertex_count, 3);
    ck_assert(s->primitives[0].normals[2] == 1.0f);
    scn_destroy(s);
}
END_TEST

/* ---------------------------------------------------------------- sequence files */

static const char *const SEQ_KEYS =
    "{\"name\": \"cornell-box-ci\", \"scene\": \"cornell-box.gltf\", \"frames\": 8, \"fps\": 24,\n"
    " \"resolution\": [160, 120],\n"
    " \"camera\": {\"keys\": [{\"time\": 0, \"position\": [0,1,3.9], \"target\": [0,1,0]},\n"
    "                       {\"time\": 1.5, \"position\": [0,1,3.6], \"target\": [0,1,0]}],\n"
    "            \"up\": [0,1,0], \"yfov_deg\": 30, \"znear\": 0.1, \"zfar\": 50},\n"
    " \"settings\": {\"shadow_map_size\": 256, \"pcf_radius\": 2, \"exposure\": -1, \"threads\": 4},\n"
    " \"capture\": [\"gbuffer.*\", \"direct.radiance\"]}\n";

static eng_result parse(const char *json, seq_sequence *out)
{
    eng_error err = {{0}};
    eng_result r = seq_parse("/some/dir/seq.json", json, strlen(json), out, &err);
    if (r != ENG_OK)
        ck_assert_msg(err.msg[0] != 0 && strchr(err.msg, '\n') == NULL, "message: %s", err.msg);
    return r;
}

START_TEST(seq_valid)
{
    seq_sequence q;
    ck_assert_int_eq(parse(SEQ_KEYS, &q), ENG_OK);
    ck_assert_str_eq(q.name, "cornell-box-ci");
    ck_assert_str_eq(q.path, "/some/dir/seq.json");
    ck_assert_str_eq(q.scene_path, "/some/dir/cornell-box.gltf");
    ck_assert_int_eq(q.frame_count, 8);
    ck_assert(q.fps == 24.0);
    ck_assert_int_eq(q.width, 160);
    ck_assert_int_eq(q.height, 120);
    ck_assert_str_eq(q.camera_node, "");
    ck_assert_int_eq(q.camera_key_count, 2);
    ck_assert(q.camera_keys[1].time == 1.5 && q.camera_keys[1].position[2] == 3.6f);
    ck_assert(q.camera_keys[0].target[1] == 1.0f);
    ck_assert_float_eq_tol(q.camera_yfov, (float)(30.0 * PI / 180.0), 1e-7f);
    ck_assert(q.camera_znear == 0.1f && q.camera_zfar == 50.0f && q.camera_up[1] == 1.0f);
    ck_assert_int_eq(q.settings.shadow_map_size, 256);
    ck_assert_int_eq(q.settings.pcf_radius, 2);
    ck_assert(q.settings.shadow_bias == 0.002f); /* default filled in */
    ck_assert(q.settings.exposure == -1.0f);
    ck_assert_int_eq(q.settings.threads, 4);
    ck_assert_int_eq(q.capture_count, 2);
    ck_assert(seq_wants(&q, "gbuffer.normal"));
    ck_assert(seq_wants(&q, "direct.radiance"));
    ck_assert(!seq_wants(&q, "shadow.light0"));
    char hex[40];
    eng_digest_hex(SEQ_KEYS, strlen(SEQ_KEYS), hex);
    ck_assert_str_eq(q.digest, hex);

    const char *minimal = "{\"scene\": \"/abs/x.gltf\", \"frames\": 1, \"fps\": 0.5, \"resolution\": [1, 16384],"
                          " \"camera\": {\"node\": \"Camera\"}}";
    ck_assert_int_eq(parse(minimal, &q), ENG_OK);
    ck_assert_str_eq(q.name, "seq"); /* from the file name */
    ck_assert_str_eq(q.scene_path, "/abs/x.gltf");
    ck_assert_str_eq(q.camera_node, "Camera");
    ck_assert_int_eq(q.camera_key_count, 0);
    ck_assert_int_eq(q.settings.shadow_map_size, 1024);
    ck_assert_int_eq(q.settings.pcf_radius, 1);
    ck_assert_int_eq(q.settings.threads, 2);
    ck_assert_int_eq(q.capture_count, 0);
    ck_assert(seq_wants(&q, "anything.at.all"));
}
END_TEST

/* Each shipped sequence file parses, its scene loads, and its camera node has a camera. */
START_TEST(seq_shipped)
{
    static const char *const files[] = {CORNELL "cornell-box-ci.json", CORNELL "cornell-box.json",
                                        CORNELL "cornell-glass-ci.json"};
    static const int size[] = {160, 256, 160}, frames[] = {8, 8, 1}, shadow[] = {256, 512, 256};
    for (int i = 0; i < 3; i++) {
        seq_sequence q;
        eng_error err = {{0}};
        ck_assert_msg(seq_load(files[i], &q, &err) == ENG_OK, "%s", err.msg);
        ck_assert_int_eq(q.width, size[i]);
        ck_assert_int_eq(q.height, size[i]);
        ck_assert_int_eq(q.frame_count, frames[i]);
        ck_assert_int_eq(q.settings.shadow_map_size, shadow[i]);
        ck_assert_int_eq(q.settings.pcf_radius, 1);
        ck_assert(q.fps == 8.0);
        scn_scene *s = load_ok(q.scene_path);
        ck_assert_int_ge(node_named(s, q.camera_node)->camera, 0);
        scn_destroy(s);
    }
    seq_sequence q;
    ck_assert_int_eq(seq_load(CORNELL "cornell-box-ci.json", &q, NULL), ENG_OK);
    ck_assert_str_eq(q.name, "cornell-box-ci");
    ck_assert_double_eq_tol((q.frame_count - 1) / q.fps, 0.875, 1e-12);
}
END_TEST

static const struct {
    const char *json;
    eng_result want;
} SEQ_BAD[] = {
    /* unknown keys, at each level */
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"},\"frame\":8}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"},"
     "\"settings\":{\"shadowmap_size\":256}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\",\"up\":[0,1,0]}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],"
     "\"camera\":{\"keys\":[{\"time\":0,\"position\":[0,0,1],\"target\":[0,0,0],\"fov\":3}]}}",
     ENG_ERR_INVALID},
    /* missing required keys */
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}", ENG_ERR_INVALID},
    {"{\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}", ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{}}", ENG_ERR_INVALID},
    /* wrong types */
    {"{\"scene\":\"a.gltf\",\"frames\":\"8\",\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    {"{\"scene\":7,\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}", ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8.5,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":\"8x8\",\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":\"Camera\"}", ENG_ERR_INVALID},
    {"[1, 2]", ENG_ERR_INVALID},
    /* out of range */
    {"{\"scene\":\"a.gltf\",\"frames\":0,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":100001,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":0,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":1e999,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[0,8],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,16385],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"},"
     "\"settings\":{\"pcf_radius\":0}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"},"
     "\"settings\":{\"shadow_map_size\":8}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"},"
     "\"settings\":{\"shadow_bias\":0}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"},"
     "\"settings\":{\"threads\":65}}",
     ENG_ERR_INVALID},
    /* bounce_strata: a power of two, 1..64 */
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"},"
     "\"settings\":{\"bounce_strata\":3}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"},"
     "\"settings\":{\"bounce_strata\":128}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"},\"capture\":[]}",
     ENG_ERR_INVALID},
    {"{\"name\":\"../x\",\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    /* camera keys */
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"keys\":["
     "{\"time\":0,\"position\":[0,0,1],\"target\":[0,0,0]},{\"time\":0,\"position\":[0,0,2],\"target\":[0,0,0]}]}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"keys\":["
     "{\"time\":1,\"position\":[0,0,1],\"target\":[0,0,0]},{\"time\":0.5,\"position\":[0,0,2],\"target\":[0,0,0]}]}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"keys\":[]}}", ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"keys\":["
     "{\"time\":0,\"position\":[0,0,1]}]}}",
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"keys\":["
     "{\"time\":0,\"position\":[0,2,0],\"target\":[0,0,0]}]}}", /* looking along up */
     ENG_ERR_INVALID},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\","
     "\"keys\":[{\"time\":0,\"position\":[0,0,1],\"target\":[0,0,0]}]}}",
     ENG_ERR_INVALID},
    /* duplicate key */
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"frames\":9,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}}",
     ENG_ERR_INVALID},
    /* not JSON */
    {"{\"scene\":\"a.gltf\",\"frames\":8,", ENG_ERR_PARSE},
    {"{\"scene\":\"a.gltf\",\"frames\":8,\"fps\":24,\"resolution\":[8,8],\"camera\":{\"node\":\"C\"}} trailing",
     ENG_ERR_PARSE},
    {"", ENG_ERR_PARSE},
    {"// comment\n{}", ENG_ERR_PARSE},
};

START_TEST(seq_invalid)
{
    seq_sequence q;
    eng_result r = parse(SEQ_BAD[_i].json, &q);
    ck_assert_msg(r == SEQ_BAD[_i].want, "case %d: got %s, want %s: %s", _i, eng_result_name(r),
                  eng_result_name(SEQ_BAD[_i].want), SEQ_BAD[_i].json);
}
END_TEST

START_TEST(seq_missing_file)
{
    seq_sequence q;
    eng_error err = {{0}};
    ck_assert_int_eq(seq_load(ISPM_SOURCE_DIR "/tests/data/no-such-sequence.json", &q, &err), ENG_ERR_IO);
    ck_assert(err.msg[0] != 0);
}
END_TEST

/* ---------------------------------------------------------------- malformed glTF corpus */

static const struct {
    const char *file;
    eng_result want;
} GLTF_BAD[] = {
    {"bad-truncated.gltf", ENG_ERR_PARSE},
    {"bad-no-geometry-points.gltf", ENG_ERR_INVALID}, /* POINTS only: nothing a frame can draw */
    {"bad-truncated.glb", ENG_ERR_PARSE},
    {"bad-not-gltf.gltf", ENG_ERR_PARSE},
    {"bad-accessor-overrun.gltf", ENG_ERR_INVALID},
    {"bad-accessor-offset-overrun.gltf", ENG_ERR_INVALID},
    {"bad-view-overrun.gltf", ENG_ERR_INVALID},
    {"bad-index-out-of-range.gltf", ENG_ERR_INVALID},
    {"bad-index-type.gltf", ENG_ERR_INVALID},
    {"bad-cyclic-nodes.gltf", ENG_ERR_INVALID},
    {"bad-self-child.gltf", ENG_ERR_INVALID},
    {"bad-two-parents.gltf", ENG_ERR_INVALID},
    {"bad-child-index.gltf", ENG_ERR_INVALID},
    {"bad-scene-non-root.gltf", ENG_ERR_INVALID},
    {"bad-inf-translation.gltf", ENG_ERR_INVALID},
    {"bad-nan-animated-translation.gltf", ENG_ERR_INVALID},
    {"bad-nan-position.gltf", ENG_ERR_INVALID},
    {"bad-light-type.gltf", ENG_ERR_INVALID},
    {"bad-light-index.gltf", ENG_ERR_INVALID},
    {"bad-light-intensity.gltf", ENG_ERR_INVALID},
    {"bad-mesh-index.gltf", ENG_ERR_INVALID},
    {"bad-material-index.gltf", ENG_ERR_INVALID},
    {"bad-material-roughness.gltf", ENG_ERR_INVALID},
    {"bad-anim-input-not-increasing.gltf", ENG_ERR_INVALID},
    {"bad-anim-output-count.gltf", ENG_ERR_INVALID},
    {"bad-anim-node.gltf", ENG_ERR_INVALID},
    {"bad-anim-path.gltf", ENG_ERR_INVALID},
    {"bad-zero-count.gltf", ENG_ERR_INVALID},
    {"bad-huge-count.gltf", ENG_ERR_INVALID},
    {"bad-large-count.gltf", ENG_ERR_INVALID},
    {"unsupported-required-extension.gltf", ENG_ERR_UNSUPPORTED},
    {"io-missing-buffer.gltf", ENG_ERR_IO},
    {"no-such-file.gltf", ENG_ERR_IO},
};

START_TEST(gltf_corpus)
{
    char path[1024];
    snprintf(path, sizeof path, DATA "%s", GLTF_BAD[_i].file);
    scn_scene *s = (scn_scene *)&path; /* must be reset to NULL */
    eng_error err = {{0}};
    eng_result r = scn_load_gltf(path, &s, &err);
    ck_assert_msg(r == GLTF_BAD[_i].want, "%s: got %s, want %s (%s)", GLTF_BAD[_i].file, eng_result_name(r),
                  eng_result_name(GLTF_BAD[_i].want), err.msg);
    ck_assert_ptr_null(s);
    ck_assert(err.msg[0] != 0 && strchr(err.msg, '\n') == NULL);
}
END_TEST

START_TEST(gltf_valid_corpus)
{
    static const char *const files[] = {"valid-triangle.gltf", "valid-no-normals.gltf", "valid-hierarchy.gltf",
                                        "valid-external-buffer.gltf", "valid-triangle.glb", "valid-sparse.gltf",
                                        "warn-orthographic.gltf"};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char path[1024];
        snprintf(path, sizeof path, DATA "%s", files[i]);
        scn_destroy(load_ok(path));
    }
    scn_destroy(NULL);
}
END_TEST

/* Every byte of a small glTF replaced by a few troublesome characters: whatever the result,
 * no crash, no leak (under valgrind/ASan), and *out is set exactly when the result is OK. */
START_TEST(gltf_mutations)
{
    char *orig;
    size_t len;
    ck_assert_int_eq(eng_read_file(DATA "valid-hierarchy.gltf", 1 << 20, &orig, &len, NULL), ENG_OK);
    char tmp[1024];
    snprintf(tmp, sizeof tmp, "%s/test_scene_mutant.gltf", ISPM_BINARY_DIR);
    static const char subst[] = {'0', '9', '-', '"', '}', ']', 'e'};
    int ok = 0, failed = 0;
    for (size_t i = 0; i < len; i++) {
        if (orig[i] == '\n' || orig[i] == ' ')
            continue;
        for (size_t k = 0; k < sizeof subst; k++) {
            if (orig[i] == subst[k])
                continue;
            char saved = orig[i];
            orig[i] = subst[k];
            FILE *f = fopen(tmp, "wb");
            ck_assert_ptr_nonnull(f);
            ck_assert_uint_eq(fwrite(orig, 1, len, f), len);
            fclose(f);
            orig[i] = saved;
            scn_scene *s = NULL;
            eng_error err;
            eng_result r = scn_load_gltf(tmp, &s, &err);
            if (r == ENG_OK) {
                ck_assert_ptr_nonnull(s);
                float *w = malloc((s->node_count + 1) * 16 * sizeof *w);
                scn_evaluate(s, 0.5, w);
                free(w);
                scn_destroy(s);
                ok++;
            } else {
                ck_assert_ptr_null(s);
                failed++;
            }
        }
    }
    remove(tmp);
    free(orig);
    ck_assert_int_gt(ok, 0);
    ck_assert_int_gt(failed, 0);
}
END_TEST

/* ---------------------------------------------------------------- suite */

static Suite *scene_suite(void)
{
    Suite *s = suite_create("scene");
    TCase *tc = tcase_create("gltf_cornell");
    tcase_add_test(tc, cornell_nodes);
    tcase_add_test(tc, cornell_floor_exact);
    tcase_add_test(tc, cornell_light_camera);
    tcase_add_test(tc, cornell_digest_is_file_digest);
    tcase_add_test(tc, cornell_glass);
    suite_add_tcase(s, tc);

    tc = tcase_create("evaluate");
    tcase_add_test(tc, evaluate_cornell);
    tcase_add_test(tc, evaluate_hierarchy);
    suite_add_tcase(s, tc);

    tc = tcase_create("sampling");
    tcase_add_test(tc, sample_step);
    tcase_add_test(tc, sample_linear);
    tcase_add_test(tc, sample_cubicspline);
    tcase_add_test(tc, sample_slerp);
    suite_add_tcase(s, tc);

    tc = tcase_create("flat_normals");
    tcase_add_test(tc, flat_normals);
    suite_add_tcase(s, tc);

    tc = tcase_create("sequence");
    tcase_add_test(tc, seq_valid);
    tcase_add_test(tc, seq_shipped);
    tcase_add_loop_test(tc, seq_invalid, 0, (int)(sizeof SEQ_BAD / sizeof SEQ_BAD[0]));
    tcase_add_test(tc, seq_missing_file);
    suite_add_tcase(s, tc);

    tc = tcase_create("malformed_gltf");
    tcase_add_loop_test(tc, gltf_corpus, 0, (int)(sizeof GLTF_BAD / sizeof GLTF_BAD[0]));
    tcase_add_test(tc, gltf_valid_corpus);
    tcase_add_test(tc, gltf_mutations);
    tcase_set_timeout(tc, 600);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(scene_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
