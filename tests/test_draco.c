/* test_draco.c — Check suite for KHR_draco_mesh_compression (issue 17, item 4): the loader
 * decodes a Draco-compressed box (written at test time by ispm_test_draco_box through the
 * Draco encoder library) to the same triangles as the uncompressed box, from a .gltf with an
 * external .bin and from a .glb, and refuses corrupt Draco data, an attribute id the data
 * lacks, an accessor count that disagrees and a missing bufferView, each with one line
 * naming the file and the mesh. */
#include "seq.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define WORK ISPM_BINARY_DIR "/tests/test_draco.work"
#define TOOL ISPM_BINARY_DIR "/tests/ispm_test_draco_box"

/* Draco quantises each position component to 14 bits over the box's extent (1): the decoded
 * value lies within half a step, 0.5 / (2^14 - 1) = 3.05e-5, of the original. Normals go
 * through 10-bit octahedral quantisation; the box's axis-aligned normals land on the
 * octahedron's corners, which are exact (bound below: 1e-6 after normalisation). */
#define POS_BOUND (0.5 / 16383.0)
#define NRM_BOUND 1e-6

static void make_files(void)
{
    mkdir(ISPM_BINARY_DIR "/tests", 0777);
    mkdir(WORK, 0777);
    ck_assert_int_eq(system(TOOL " " WORK " > /dev/null"), 0);
}

static scn_scene *load_ok(const char *name)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", WORK, name);
    scn_scene *s = NULL;
    eng_error err = {{0}};
    eng_result r = scn_load_gltf(path, &s, &err);
    ck_assert_msg(r == ENG_OK, "%s: %s", name, err.msg);
    ck_assert_uint_eq(s->primitive_count, 1);
    return s;
}

static double dist3(const float *a, const float *b)
{
    double d = 0;
    for (int k = 0; k < 3; k++)
        d = fmax(d, fabs((double)a[k] - (double)b[k]));
    return d;
}

/* Every triangle of want has one in got with the same corners in the same turning order
 * (Draco's edgebreaker may reorder vertices, triangles and the first corner): positions and
 * normals within the bounds. Returns the largest position and normal differences seen. */
static void same_triangles(const scn_primitive *want, const scn_primitive *got, double *pos_err, double *nrm_err)
{
    ck_assert_uint_eq(got->index_count, want->index_count);
    ck_assert_uint_eq(got->vertex_count, want->vertex_count);
    *pos_err = *nrm_err = 0;
    for (uint32_t t = 0; t < want->index_count; t += 3) {
        int found = 0;
        for (uint32_t u = 0; u < got->index_count && !found; u += 3)
            for (int rot = 0; rot < 3 && !found; rot++) {
                double pe = 0, ne = 0;
                for (int k = 0; k < 3; k++) {
                    uint32_t a = want->indices[t + (uint32_t)k], b = got->indices[u + (uint32_t)((k + rot) % 3)];
                    ck_assert_uint_lt(b, got->vertex_count);
                    pe = fmax(pe, dist3(want->positions + 3 * a, got->positions + 3 * b));
                    ne = fmax(ne, dist3(want->normals + 3 * a, got->normals + 3 * b));
                }
                if (pe <= POS_BOUND && ne <= NRM_BOUND) {
                    found = 1;
                    *pos_err = fmax(*pos_err, pe);
                    *nrm_err = fmax(*nrm_err, ne);
                }
            }
        ck_assert_msg(found, "triangle %u of the plain box has no Draco counterpart", t / 3);
    }
}

static void check_against_plain(const char *name)
{
    make_files();
    scn_scene *plain = load_ok("plain-box.gltf"), *draco = load_ok(name);
    ck_assert_uint_eq(plain->primitives[0].index_count, 36);
    double pe, ne;
    same_triangles(&plain->primitives[0], &draco->primitives[0], &pe, &ne);
    printf("%s: max position error %.3g (bound %.3g), max normal error %.3g (bound %.3g)\n", name, pe, POS_BOUND,
           ne, NRM_BOUND);
    ck_assert_int_eq(draco->primitives[0].material, 0);
    ck_assert_uint_eq(draco->warning_count, 0); /* the required extension is supported */
    scn_destroy(plain);
    scn_destroy(draco);
}

START_TEST(draco_gltf_matches_plain) { check_against_plain("draco-box.gltf"); }
END_TEST

START_TEST(draco_glb_matches_plain) { check_against_plain("draco-box.glb"); }
END_TEST

static const struct {
    const char *file, *says;
} HOSTILE[] = {
    {"draco-corrupt.gltf", "does not decode"},
    {"draco-badid.gltf", "attribute NORMAL: id"},
    {"draco-count.gltf", "has count 23, the Draco data 24 points"},
    {"draco-noview.gltf", "bufferView 5 does not exist"},
};

START_TEST(draco_hostile)
{
    make_files();
    char path[512];
    snprintf(path, sizeof path, "%s/%s", WORK, HOSTILE[_i].file);
    scn_scene *s = NULL;
    eng_error err = {{0}};
    ck_assert_int_eq(scn_load_gltf(path, &s, &err), ENG_ERR_INVALID);
    ck_assert_ptr_null(s);
    ck_assert_msg(strncmp(err.msg, path, strlen(path)) == 0, "no file name: %s", err.msg);
    ck_assert_msg(strstr(err.msg, "mesh 0 (\"box\") primitive 0: KHR_draco_mesh_compression: "), "no mesh: %s",
                  err.msg);
    ck_assert_msg(strstr(err.msg, HOSTILE[_i].says), "want \"%s\": %s", HOSTILE[_i].says, err.msg);
    ck_assert_ptr_null(strchr(err.msg, '\n'));
}
END_TEST

static Suite *draco_suite(void)
{
    Suite *s = suite_create("draco");
    TCase *tc = tcase_create("decode");
    tcase_add_test(tc, draco_gltf_matches_plain);
    tcase_add_test(tc, draco_glb_matches_plain);
    tcase_add_loop_test(tc, draco_hostile, 0, (int)(sizeof HOSTILE / sizeof HOSTILE[0]));
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(draco_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
