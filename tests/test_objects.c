/* test_objects.c — goldens whose buffers are stored once (replay/run/objects.c,
 * replay/golden_store.c): a golden of frame files migrated to objects reads back bit for bit,
 * a second golden sharing buffers adds only what is new, channel names differing from the
 * object's are matched by rank, gc removes only unlisted objects, renderer sets are found by
 * the run's renderer, and every kind of bad store is refused with its own error. */
#define _XOPEN_SOURCE 700
#include "cap.h"
#include "rep.h"
#include "rep_report.h"
#include "rep_run.h"
#include "rep_util.h"
#include "replay_internal.h"

#include <check.h>
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char g_tmp[] = "/tmp/ispm_test_objects_XXXXXX";
static char *g_old, *g_gold, *g_store;

/* The fixture is built from this golden, whatever its format: its first two frames. */
#define SOURCE ISPM_SOURCE_DIR "/golden/stress-corner"
#define FIXTURE_FRAMES 2

static void sh(char *cmd)
{
    ck_assert_msg(system(cmd) == 0, "%s", cmd);
    free(cmd);
}

static cJSON *load(const char *dir);
static void save(const char *dir, cJSON *j);

/* dir becomes a golden of frame files (format 1): SOURCE's first frames as capture writes them. */
static void make_format1(const char *dir)
{
    rep_run *src = NULL;
    eng_error err;
    ck_assert_msg(rep_run_open(SOURCE, &src, &err) == ENG_OK, "%s", err.msg);
    sh(rep_xprintf("mkdir -p '%s/frames' && cp '" SOURCE "/tolerances.json' '%s/'", dir, dir));
    cJSON *m = load(SOURCE);
    cJSON_ReplaceItemInObject(m, "format_version", cJSON_CreateNumber(1));
    cJSON_DeleteItemFromObject(m, "objects");
    cJSON_ReplaceItemInObject(m, "frame_count", cJSON_CreateNumber(FIXTURE_FRAMES));
    cJSON *frames = cJSON_GetObjectItem(m, "frames");
    while (cJSON_GetArraySize(frames) > FIXTURE_FRAMES)
        cJSON_DeleteItemFromArray(frames, FIXTURE_FRAMES);
    for (int i = 0; i < FIXTURE_FRAMES; i++) {
        rep_part *p = NULL;
        ck_assert_msg(rep_run_read_frame(src, i, &p, &err) == ENG_OK, "%s", err.msg);
        int n = src->frames[i].buffer_count;
        eng_buffer *b = rep_xcalloc((size_t)n, sizeof *b);
        const eng_buffer **bp = rep_xcalloc((size_t)n, sizeof *bp);
        for (int j = 0; j < n; j++) {
            b[j] = rep_part_buffer(&p[j]);
            bp[j] = &b[j];
        }
        char rel[32];
        snprintf(rel, sizeof rel, "frames/%06d.exr", i);
        char *path = rep_path_join(dir, rel);
        ck_assert_int_eq(cap_write_exr(path, bp, n, &err), ENG_OK);
        cJSON *f = cJSON_GetArrayItem(frames, i);
        cJSON_DeleteItemFromObject(f, "file");
        cJSON_AddStringToObject(f, "file", rel);
        free(path);
        free(b);
        free(bp);
        rep_parts_free(p, n);
    }
    save(dir, m);
    rep_run_close(src);
}

/* old/ a golden of frame files; golden/g the same migrated to objects in golden/objects. */
static void setup(void)
{
    ck_assert_ptr_nonnull(mkdtemp(g_tmp));
    g_old = rep_xprintf("%s/old", g_tmp);
    g_gold = rep_xprintf("%s/golden/g", g_tmp);
    g_store = rep_xprintf("%s/golden/objects", g_tmp);
    make_format1(g_old);
    rep_run *probe = NULL;
    eng_error err;
    ck_assert_msg(rep_run_open(g_old, &probe, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(probe->format_version, 1);
    rep_run_close(probe);
    sh(rep_xprintf("mkdir -p '%s' && cp -r '%s/.' '%s'", g_gold, g_old, g_gold));
    ck_assert_msg(rep_golden_migrate(g_gold, NULL, &err) == ENG_OK, "%s", err.msg);
}

static void teardown(void)
{
    rep_remove_tree(g_tmp, NULL);
    free(g_old);
    free(g_gold);
    free(g_store);
    strcpy(g_tmp, "/tmp/ispm_test_objects_XXXXXX");
}

static cJSON *load(const char *dir)
{
    char *p = rep_path_join(dir, "manifest.json"), *text = NULL;
    size_t len = 0;
    eng_error err;
    ck_assert_int_eq(eng_read_file(p, REP_MAX_JSON_BYTES, &text, &len, &err), ENG_OK);
    cJSON *j = cJSON_ParseWithLength(text, len);
    ck_assert_ptr_nonnull(j);
    free(text);
    free(p);
    return j;
}

static void save(const char *dir, cJSON *j)
{
    char *p = rep_path_join(dir, "manifest.json"), *text = cJSON_Print(j);
    eng_error err;
    ck_assert_int_eq(rep_write_atomic(p, text, strlen(text), &err), ENG_OK);
    cJSON_free(text);
    cJSON_Delete(j);
    free(p);
}

static cJSON *buffer_of(cJSON *m, int frame, int j)
{
    return cJSON_GetArrayItem(cJSON_GetObjectItem(cJSON_GetArrayItem(cJSON_GetObjectItem(m, "frames"), frame),
                                                  "buffers"), j);
}

/* Every frame of both, every buffer: same name, size, channels and float bits. */
static void assert_same_frames(const rep_run *a, const rep_run *b)
{
    eng_error err;
    ck_assert_int_eq(a->frame_count, b->frame_count);
    for (int i = 0; i < a->frame_count; i++) {
        rep_part *pa = NULL, *pb = NULL;
        ck_assert_msg(rep_run_read_frame(a, i, &pa, &err) == ENG_OK, "%s", err.msg);
        ck_assert_msg(rep_run_read_frame(b, i, &pb, &err) == ENG_OK, "%s", err.msg);
        for (int j = 0; j < a->frames[i].buffer_count; j++) {
            ck_assert_str_eq(pa[j].name, pb[j].name);
            ck_assert_int_eq(pa[j].channel_count, pb[j].channel_count);
            for (int c = 0; c < pa[j].channel_count; c++)
                ck_assert_str_eq(pa[j].channels[c], pb[j].channels[c]);
            size_t n = (size_t)pa[j].width * (size_t)pa[j].height * (size_t)pa[j].channel_count;
            ck_assert(memcmp(pa[j].data, pb[j].data, n * sizeof(float)) == 0);
        }
        rep_parts_free(pa, a->frames[i].buffer_count);
        rep_parts_free(pb, b->frames[i].buffer_count);
    }
}

START_TEST(migrated_golden_reads_as_before)
{
    rep_run *a = NULL, *b = NULL;
    eng_error err;
    ck_assert_int_eq(rep_run_open(g_old, &a, &err), ENG_OK);
    ck_assert_msg(rep_run_open(g_gold, &b, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(b->format_version, 2);
    ck_assert_ptr_null(b->frames[0].path);
    char *frames = rep_path_join(g_gold, "frames"), *tol = rep_path_join(g_gold, "tolerances.json");
    ck_assert(!rep_is_dir(frames)); /* no frame files left */
    ck_assert(rep_is_file(tol));    /* the golden's other files kept */
    free(frames);
    free(tol);
    assert_same_frames(a, b);
    rep_run_close(a);
    rep_run_close(b);
    /* migrating again changes nothing */
    ck_assert_int_eq(rep_golden_migrate(g_gold, NULL, &err), ENG_OK);
}
END_TEST

START_TEST(second_golden_adds_only_new_objects)
{
    char *second = rep_xprintf("%s/golden/h", g_tmp);
    sh(rep_xprintf("cp -r '%s' '%s'", g_old, second));
    rep_run *old = NULL;
    eng_error err;
    ck_assert_int_eq(rep_run_open(g_old, &old, &err), ENG_OK);
    rep_store_stats st;
    memset(&st, 0, sizeof st);
    ck_assert_int_eq(rep_store_put_run(old, g_store, &st, &err), ENG_OK);
    ck_assert_int_eq(st.objects_new, 0); /* the same buffers: all stored already */
    ck_assert_int_gt(st.objects_had, 0);
    rep_run_close(old);
    ck_assert_int_eq(rep_golden_migrate(second, NULL, &err), ENG_OK);
    rep_gc_stats gs;
    char *root = rep_xprintf("%s/golden", g_tmp);
    ck_assert_msg(rep_golden_gc(root, 0, &gs, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(gs.goldens, 2);
    ck_assert_uint_eq(gs.removed, 0);
    free(root);
    free(second);
}
END_TEST

START_TEST(gc_removes_only_unlisted_objects)
{
    static const char *const y[] = {"Y"};
    float px[4] = {1, 2, 3, 4};
    eng_buffer b = {"stray", 2, 2, 1, y, px};
    char dg[40];
    eng_buffer_digest(&b, dg);
    char *fan = rep_xprintf("%s/%.2s", g_store, dg), *obj = rep_object_path(g_store, dg);
    eng_error err;
    ck_assert_int_eq(rep_mkdirs(fan, &err), ENG_OK);
    ck_assert_msg(cap_write_exr_zip(obj, &b, 9, &err) == ENG_OK, "%s", err.msg);
    char *root = rep_xprintf("%s/golden", g_tmp);
    rep_gc_stats st;
    ck_assert_int_eq(rep_golden_gc(root, 1, &st, &err), ENG_OK);
    ck_assert_uint_eq(st.removed, 1);
    ck_assert(rep_is_file(obj)); /* dry run */
    size_t kept = st.kept;
    ck_assert_int_eq(rep_golden_gc(root, 0, &st, &err), ENG_OK);
    ck_assert_uint_eq(st.removed, 1);
    ck_assert_uint_eq(st.kept, kept);
    ck_assert(!rep_is_file(obj));
    rep_run *g = NULL;
    ck_assert_int_eq(rep_run_open(g_gold, &g, &err), ENG_OK); /* everything listed is still there */
    rep_run_close(g);
    /* a golden that cannot be read stops gc before anything is removed */
    ck_assert_int_eq(rep_mkdirs(fan, &err), ENG_OK);
    ck_assert_msg(cap_write_exr_zip(obj, &b, 9, &err) == ENG_OK, "%s", err.msg);
    cJSON *m = load(g_gold);
    cJSON_ReplaceItemInObject(m, "objects", cJSON_CreateString("/etc"));
    save(g_gold, m);
    ck_assert_int_ne(rep_golden_gc(root, 0, &st, &err), ENG_OK);
    ck_assert(rep_is_file(obj));
    free(root);
    free(fan);
    free(obj);
}
END_TEST

START_TEST(channels_matched_by_rank)
{
    /* gbuffer.normal X,Y,Z listed as B,G,R: the same planes in name order, so the same digest
     * and object; the part comes back with the listed names, B holding X's values. */
    cJSON *m = load(g_gold);
    int j = -1;
    for (int k = 0; k < 64 && j < 0; k++) {
        cJSON *b = buffer_of(m, 0, k);
        ck_assert_ptr_nonnull(b);
        if (!strcmp(cJSON_GetObjectItem(b, "name")->valuestring, "gbuffer.normal"))
            j = k;
    }
    cJSON *ch = cJSON_CreateArray();
    cJSON_AddItemToArray(ch, cJSON_CreateString("B"));
    cJSON_AddItemToArray(ch, cJSON_CreateString("G"));
    cJSON_AddItemToArray(ch, cJSON_CreateString("R"));
    cJSON_ReplaceItemInObject(buffer_of(m, 0, j), "channels", ch);
    save(g_gold, m);
    rep_run *a = NULL, *b = NULL;
    eng_error err;
    ck_assert_int_eq(rep_run_open(g_old, &a, &err), ENG_OK);
    ck_assert_int_eq(rep_run_open(g_gold, &b, &err), ENG_OK);
    rep_part *pa = NULL, *pb = NULL;
    ck_assert_int_eq(rep_run_read_frame(a, 0, &pa, &err), ENG_OK);
    ck_assert_msg(rep_run_read_frame(b, 0, &pb, &err) == ENG_OK, "%s", err.msg);
    const rep_part *x = &pa[j], *y = &pb[j];
    ck_assert_str_eq(y->channels[0], "R"); /* the readers' order: R, G, B */
    ck_assert_str_eq(y->channels[1], "G");
    ck_assert_str_eq(y->channels[2], "B");
    ck_assert_str_eq(x->channels[0], "X");
    ck_assert_str_eq(x->channels[2], "Z");
    size_t px = (size_t)x->width * (size_t)x->height;
    for (size_t i = 0; i < px; i++) {
        ck_assert(memcmp(&y->data[i * 3 + 2], &x->data[i * 3 + 0], sizeof(float)) == 0); /* B = X */
        ck_assert(memcmp(&y->data[i * 3 + 0], &x->data[i * 3 + 2], sizeof(float)) == 0); /* R = Z */
    }
    rep_parts_free(pa, a->frames[0].buffer_count);
    rep_parts_free(pb, b->frames[0].buffer_count);
    rep_run_close(a);
    rep_run_close(b);
}
END_TEST

/* The first object golden g lists (frame 0, buffer 0). */
static char *first_object(char digest[40])
{
    cJSON *m = load(g_gold);
    snprintf(digest, 40, "%s", cJSON_GetObjectItem(buffer_of(m, 0, 0), "digest")->valuestring);
    cJSON_Delete(m);
    return rep_object_path(g_store, digest);
}

static eng_result open_and_read(eng_error *err)
{
    rep_run *g = NULL;
    eng_result r = rep_run_open(g_gold, &g, err);
    for (int i = 0; r == ENG_OK && i < g->frame_count; i++) {
        rep_part *p = NULL;
        r = rep_run_read_frame(g, i, &p, err);
        if (r == ENG_OK)
            rep_parts_free(p, g->frames[i].buffer_count);
    }
    rep_run_close(g);
    return r;
}

START_TEST(tampered_object_is_refused)
{
    char dg[40];
    char *obj = first_object(dg);
    static const char *const y[] = {"Y"};
    float px[64 * 64];
    for (int i = 0; i < 64 * 64; i++)
        px[i] = (float)i;
    rep_run *g = NULL;
    eng_error err;
    ck_assert_int_eq(rep_run_open(g_gold, &g, &err), ENG_OK);
    const rep_buffer_info *bi = &g->frames[0].buffers[0];
    /* same size and channel names as the buffer, other pixels */
    float *data = rep_xcalloc((size_t)bi->width * (size_t)bi->height * (size_t)bi->channel_count, sizeof(float));
    eng_buffer b = {bi->name, bi->width, bi->height, bi->channel_count, (const char *const *)bi->channels, data};
    ck_assert_msg(cap_write_exr_zip(obj, &b, 9, &err) == ENG_OK, "%s", err.msg);
    rep_run_close(g);
    free(data);
    ck_assert_int_eq(open_and_read(&err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, dg) && strstr(err.msg, "does not match"), "%s", err.msg);
    /* an object of another shape */
    eng_buffer small = {"x", 64, 64, 1, y, px};
    ck_assert_int_eq(cap_write_exr_zip(obj, &small, 9, &err), ENG_OK);
    ck_assert_int_eq(open_and_read(&err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, dg) && strstr(err.msg, "channels"), "%s", err.msg);
    free(obj);
}
END_TEST

START_TEST(missing_and_linked_objects_are_refused)
{
    char dg[40];
    char *obj = first_object(dg), *moved = rep_xprintf("%s/moved.exr", g_tmp);
    eng_error err;
    ck_assert_int_eq(rename(obj, moved), 0);
    ck_assert_int_eq(open_and_read(&err), ENG_ERR_IO);
    ck_assert_ptr_nonnull(strstr(err.msg, "object missing"));
    ck_assert_int_eq(symlink(moved, obj), 0);
    ck_assert_int_eq(open_and_read(&err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "symbolic link"));
    ck_assert_int_eq(unlink(obj), 0);
    ck_assert_int_eq(rename(moved, obj), 0);
    ck_assert_msg(open_and_read(&err) == ENG_OK, "%s", err.msg);
    /* a store that is a link */
    char *real = rep_xprintf("%s/elsewhere", g_tmp);
    ck_assert_int_eq(rename(g_store, real), 0);
    ck_assert_int_eq(symlink(real, g_store), 0);
    ck_assert_int_eq(open_and_read(&err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "symbolic link"));
    free(real);
    free(obj);
    free(moved);
}
END_TEST

START_TEST(bad_manifest_fields_are_refused)
{
    static const char *const escapes[] = {"/tmp/objects", "../../../../objects", "../other", "objects/..", ""};
    eng_error err;
    for (size_t i = 0; i < sizeof escapes / sizeof escapes[0]; i++) {
        cJSON *m = load(g_gold);
        cJSON_ReplaceItemInObject(m, "objects", cJSON_CreateString(escapes[i]));
        save(g_gold, m);
        ck_assert_int_eq(open_and_read(&err), ENG_ERR_INVALID);
        ck_assert_msg(strstr(err.msg, "escapes the golden"), "%s", err.msg);
    }
    cJSON *m = load(g_gold);
    cJSON_ReplaceItemInObject(m, "objects", cJSON_CreateString("../objects"));
    cJSON_ReplaceItemInObject(buffer_of(m, 1, 0), "digest", cJSON_CreateString("0123456789abcdef0123456789abcdeg"));
    save(g_gold, m);
    ck_assert_int_eq(open_and_read(&err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "hex"));
    m = load(g_gold);
    cJSON_ReplaceItemInObject(buffer_of(m, 1, 0), "digest", cJSON_CreateString("0123456789abcdef0123456789abcdef"));
    save(g_gold, m);
    ck_assert_int_eq(open_and_read(&err), ENG_ERR_IO);
    ck_assert_ptr_nonnull(strstr(err.msg, "object missing"));
    m = load(g_gold);
    cJSON_DeleteItemFromObject(m, "objects");
    save(g_gold, m);
    ck_assert_int_eq(open_and_read(&err), ENG_ERR_INVALID);
}
END_TEST

START_TEST(renderer_slug_and_set)
{
    char *s = rep_renderer_slug(NULL, "llvmpipe (LLVM 15.0.6, 128 bits)");
    ck_assert_str_eq(s, "llvmpipe-llvm-15-0-6-128-bits");
    free(s);
    s = rep_renderer_slug("NVIDIA Corporation", "NVIDIA H100 80GB HBM3/PCIe/SSE2");
    ck_assert_str_eq(s, "nvidia-corporation-nvidia-h100-80gb-hbm3-pcie-sse2");
    free(s);
    s = rep_renderer_slug("", "");
    ck_assert_str_eq(s, "unknown");
    free(s);
    rep_run run, gold;
    memset(&run, 0, sizeof run);
    memset(&gold, 0, sizeof gold);
    run.gl_renderer = "NVIDIA H100/PCIe/SSE2";
    gold.gl_renderer = "llvmpipe (LLVM 15.0.6, 128 bits)";
    char *slug = NULL;
    ck_assert_ptr_null(rep_renderer_set_dir(g_gold, &run, &gold, &slug)); /* no such set */
    char *set = rep_xprintf("%s/renderers/nvidia-h100-pcie-sse2", g_gold);
    sh(rep_xprintf("mkdir -p '%s' && cp '%s/manifest.json' '%s/'", set, g_gold, set));
    char *dir = rep_renderer_set_dir(g_gold, &run, &gold, &slug);
    ck_assert_ptr_nonnull(dir);
    ck_assert_str_eq(dir, set);
    ck_assert_str_eq(slug, "nvidia-h100-pcie-sse2");
    free(dir);
    free(slug);
    run.gl_renderer = gold.gl_renderer; /* the same renderer: the canonical set */
    ck_assert_ptr_null(rep_renderer_set_dir(g_gold, &run, &gold, &slug));
    free(set);
}
END_TEST

static Suite *objects_suite(void)
{
    Suite *s = suite_create("objects");
    TCase *t = tcase_create("store");
    tcase_set_timeout(t, 120);
    tcase_add_checked_fixture(t, setup, teardown);
    tcase_add_test(t, migrated_golden_reads_as_before);
    tcase_add_test(t, second_golden_adds_only_new_objects);
    tcase_add_test(t, gc_removes_only_unlisted_objects);
    tcase_add_test(t, channels_matched_by_rank);
    tcase_add_test(t, tampered_object_is_refused);
    tcase_add_test(t, missing_and_linked_objects_are_refused);
    tcase_add_test(t, bad_manifest_fields_are_refused);
    tcase_add_test(t, renderer_slug_and_set);
    suite_add_tcase(s, t);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(objects_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
