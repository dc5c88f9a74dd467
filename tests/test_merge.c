/* test_merge.c — Check suite for capture/merge.c (ispm merge, issue 20): frame-range parsing,
 * coverage (gaps, frames twice, missing ends), the overlap digest check and its messages (the
 * frame, the buffer and the warm-up the state needs), provenance, incomplete shards, and a
 * merged run's layout (every frame hard-linked, records renumbered, "shards", manifest last).
 * Shards are written here as manifests with placeholder frame files: merge reads only those
 * (replay checks pixels against digests; the e2e tests merge real recordings). */
#define _XOPEN_SOURCE 700

#include "merge.h"

#include <check.h>
#include <cjson/cJSON.h>

#include <ftw.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static int rm_entry(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st;
    (void)flag;
    (void)ftw;
    return remove(path);
}

static void rm_rf(const char *dir)
{
    nftw(dir, rm_entry, 16, FTW_DEPTH | FTW_PHYS);
}

static int exists(const char *dir, const char *name)
{
    char p[512];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    struct stat st;
    return stat(p, &st) == 0;
}

/* What a synthetic shard's frames hold: buffer "final.display" and "temporal.history" with a
 * digest made of the frame and a variant (a shard whose variant differs at a frame "rendered"
 * it differently), and the engine's history_from. */
typedef struct spec {
    int first, last, warmup, overlap, frames;
    int bad_frame;     /* frame whose temporal.history differs (-1: none) */
    int history_from;  /* recorded for every frame (-1: stateless) */
    const char *temporal; /* settings.temporal ("true"/"false") */
} spec;

static void digest_of(int frame, const char *buffer, int variant, char out[33])
{
    snprintf(out, 33, "%08x%08x%016x", (unsigned)frame, (unsigned)strlen(buffer), (unsigned)variant);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    ck_assert_ptr_nonnull(f);
    fputs(text, f);
    fclose(f);
}

static void write_shard(const char *dir, const spec *s)
{
    char p[512];
    mkdir(dir, 0777);
    snprintf(p, sizeof p, "%s/frames", dir);
    mkdir(p, 0777);
    cJSON *m = cJSON_CreateObject();
    cJSON_AddStringToObject(m, "format", "ispm-run");
    cJSON_AddNumberToObject(m, "format_version", 1);
    cJSON *tool = cJSON_AddObjectToObject(m, "tool");
    cJSON_AddStringToObject(tool, "version", "0.1.0");
    cJSON_AddStringToObject(tool, "git", "abc");
    snprintf(p, sizeof p, "ispm record seq.json -o %s", dir);
    cJSON_AddStringToObject(m, "command", p);
    cJSON *sq = cJSON_AddObjectToObject(m, "sequence");
    cJSON_AddStringToObject(sq, "path", "seq.json");
    cJSON_AddStringToObject(sq, "name", "seq");
    cJSON_AddStringToObject(sq, "digest", "0123");
    cJSON_AddStringToObject(cJSON_AddObjectToObject(m, "scene"), "digest", "4567");
    cJSON *st = cJSON_AddObjectToObject(m, "settings");
    cJSON_AddItemToObject(st, "temporal", cJSON_Parse(s->temporal ? s->temporal : "true"));
    cJSON_AddNumberToObject(st, "threads", 2);
    cJSON_AddNumberToObject(m, "frame_count", s->last - (s->first - s->overlap) + 1);
    cJSON *sh = cJSON_AddObjectToObject(m, "shard");
    cJSON *fr = cJSON_AddArrayToObject(sh, "frames");
    cJSON_AddItemToArray(fr, cJSON_CreateNumber(s->first));
    cJSON_AddItemToArray(fr, cJSON_CreateNumber(s->last));
    cJSON_AddNumberToObject(sh, "warmup", s->warmup);
    cJSON_AddNumberToObject(sh, "overlap", s->overlap);
    cJSON_AddNumberToObject(sh, "sequence_frame_count", s->frames);
    cJSON *frames = cJSON_AddArrayToObject(m, "frames");
    for (int g = s->first - s->overlap; g <= s->last; g++) {
        cJSON *f = cJSON_CreateObject();
        cJSON_AddNumberToObject(f, "index", g - (s->first - s->overlap));
        char file[32];
        snprintf(file, sizeof file, "frames/%06d.exr", g);
        cJSON_AddStringToObject(f, "file", file);
        cJSON_AddNumberToObject(f, "time", g / 8.0);
        cJSON *bufs = cJSON_AddArrayToObject(f, "buffers");
        const char *names[] = {"final.display", "temporal.history"};
        for (int b = 0; b < 2; b++) {
            char d[33];
            digest_of(g, names[b], g == s->bad_frame && b == 1, d);
            cJSON *jb = cJSON_CreateObject();
            cJSON_AddStringToObject(jb, "name", names[b]);
            cJSON_AddStringToObject(jb, "digest", d);
            cJSON_AddItemToArray(bufs, jb);
        }
        cJSON_AddNumberToObject(f, "sequence_frame", g);
        cJSON_AddNumberToObject(f, "history_from", s->history_from);
        cJSON_AddItemToArray(frames, f);
        snprintf(p, sizeof p, "%s/%s", dir, file);
        write_text(p, "exr placeholder\n");
    }
    cJSON_AddTrueToObject(m, "complete");
    char *text = cJSON_Print(m);
    snprintf(p, sizeof p, "%s/manifest.json", dir);
    write_text(p, text);
    free(text);
    cJSON_Delete(m);
}

/* A temporary folder holding shards s0, s1, ... of specs, and the merged run's path. */
typedef struct fixture {
    char root[256];
    char shard[4][300];
    const char *shards[4];
    char run[300];
} fixture;

static void fixture_make(fixture *fx, const spec *specs, int n)
{
    snprintf(fx->root, sizeof fx->root, "/tmp/test_merge.XXXXXX");
    ck_assert_ptr_nonnull(mkdtemp(fx->root));
    for (int i = 0; i < n; i++) {
        snprintf(fx->shard[i], sizeof fx->shard[i], "%s/s%d", fx->root, i);
        write_shard(fx->shard[i], &specs[i]);
        fx->shards[i] = fx->shard[i];
    }
    snprintf(fx->run, sizeof fx->run, "%s/run", fx->root);
}

static eng_result merge(fixture *fx, int n, eng_error *err)
{
    cap_merge_desc d = {fx->shards, n, fx->run, 0, "ispm merge ..."};
    return cap_merge(&d, err);
}

/* ---------------------------------------------------------------- ranges */

START_TEST(test_parse_range)
{
    int a = -1, b = -1;
    ck_assert(cap_parse_range("3-7", &a, &b));
    ck_assert_int_eq(a, 3);
    ck_assert_int_eq(b, 7);
    ck_assert(cap_parse_range("5", &a, &b));
    ck_assert_int_eq(a, 5);
    ck_assert_int_eq(b, 5);
    ck_assert(cap_parse_range("0-0", &a, &b));
    ck_assert_int_eq(a + b, 0);
    const char *bad[] = {"", "-3", "7-3", "a-b", "3-", "3-4-5", "1e3", " 3", "3 ", "+3", "99999999", "3--4", NULL};
    for (int i = 0; bad[i]; i++) {
        a = b = 42;
        ck_assert_msg(!cap_parse_range(bad[i], &a, &b), "'%s' accepted", bad[i]);
        ck_assert_int_eq(a, 42);
    }
    ck_assert(!cap_parse_range(NULL, &a, &b));
}
END_TEST

START_TEST(test_coverage)
{
    const char *names[] = {"s0", "s1", "s2"};
    eng_error err = {{0}};
    int f_ok[] = {0, 3, 6}, l_ok[] = {2, 5, 7};
    ck_assert_int_eq(cap_merge_coverage(f_ok, l_ok, names, 3, 8, &err), ENG_OK);
    int f_gap[] = {0, 4, 6}, l_gap[] = {2, 5, 7};
    ck_assert_int_eq(cap_merge_coverage(f_gap, l_gap, names, 3, 8, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "frames 3-3 are in no shard") && strstr(err.msg, "s0 and s1"), "%s", err.msg);
    int f_twice[] = {0, 2, 6}, l_twice[] = {2, 5, 7};
    ck_assert_int_eq(cap_merge_coverage(f_twice, l_twice, names, 3, 8, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "frames 2-2 are in two shards"), "%s", err.msg);
    int f_start[] = {1, 3, 6};
    ck_assert_int_eq(cap_merge_coverage(f_start, l_ok, names, 3, 8, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "frames 0-0 are in no shard"), "%s", err.msg);
    int l_end[] = {2, 5, 6};
    ck_assert_int_eq(cap_merge_coverage(f_ok, l_end, names, 3, 8, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "frames 7-7 are in no shard"), "%s", err.msg);
    ck_assert_int_eq(cap_merge_coverage(f_ok, l_ok, names, 3, 7, &err), ENG_ERR_INVALID);
    ck_assert_int_eq(cap_merge_coverage(f_ok, l_ok, names, 0, 8, &err), ENG_ERR_INVALID);
}
END_TEST

/* ---------------------------------------------------------------- merging */

static cJSON *read_json(const char *dir, const char *name)
{
    char p[512];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    char *text = NULL;
    size_t len = 0;
    eng_error err = {{0}};
    ck_assert_int_eq(eng_read_file(p, 1 << 24, &text, &len, &err), ENG_OK);
    cJSON *j = cJSON_ParseWithLength(text, len);
    free(text);
    ck_assert_ptr_nonnull(j);
    return j;
}

START_TEST(test_merge_ok)
{
    /* Given in another order than their frames: merge sorts them. */
    const spec specs[] = {{6, 7, 2, 1, 8, -1, 0, NULL}, {0, 2, 0, 0, 8, -1, 0, NULL}, {3, 5, 3, 2, 8, -1, 0, NULL}};
    fixture fx;
    fixture_make(&fx, specs, 3);
    eng_error err = {{0}};
    ck_assert_msg(merge(&fx, 3, &err) == ENG_OK, "%s", err.msg);
    cJSON *m = read_json(fx.run, "manifest.json");
    ck_assert_int_eq(cJSON_GetObjectItem(m, "frame_count")->valueint, 8);
    ck_assert(cJSON_IsTrue(cJSON_GetObjectItem(m, "complete")));
    ck_assert_ptr_null(cJSON_GetObjectItem(m, "shard"));
    ck_assert_str_eq(cJSON_GetObjectItem(m, "command")->valuestring, "ispm merge ...");
    const cJSON *frames = cJSON_GetObjectItem(m, "frames");
    ck_assert_int_eq(cJSON_GetArraySize(frames), 8);
    for (int g = 0; g < 8; g++) {
        const cJSON *f = cJSON_GetArrayItem(frames, g);
        ck_assert_int_eq(cJSON_GetObjectItem(f, "index")->valueint, g);
        ck_assert_ptr_null(cJSON_GetObjectItem(f, "sequence_frame"));
        ck_assert_ptr_null(cJSON_GetObjectItem(f, "history_from"));
        char name[64], d[33];
        digest_of(g, "final.display", 0, d);
        ck_assert_str_eq(cJSON_GetObjectItem(cJSON_GetArrayItem(cJSON_GetObjectItem(f, "buffers"), 0), "digest")->valuestring, d);
        snprintf(name, sizeof name, "frames/%06d.exr", g);
        ck_assert(exists(fx.run, name));
        snprintf(name, sizeof name, "frames/%06d.json", g);
        ck_assert(exists(fx.run, name));
    }
    const cJSON *sh = cJSON_GetObjectItem(m, "shards");
    ck_assert_int_eq(cJSON_GetArraySize(sh), 3);
    ck_assert_int_eq(cJSON_GetArrayItem(cJSON_GetObjectItem(cJSON_GetArrayItem(sh, 1), "frames"), 0)->valueint, 3);
    ck_assert_int_eq(cJSON_GetObjectItem(cJSON_GetArrayItem(sh, 1), "warmup")->valueint, 3);
    cJSON_Delete(m);
    cJSON *info = read_json(fx.run, "run.json");
    ck_assert_int_eq(cJSON_GetObjectItem(info, "frame_count")->valueint, 8);
    cJSON_Delete(info);
    /* A second merge into the same folder needs overwrite. */
    ck_assert_int_eq(merge(&fx, 3, &err), ENG_ERR_IO);
    rm_rf(fx.root);
}
END_TEST

START_TEST(test_digest_mismatch_names_warmup)
{
    /* Shard 1 begins at 3 with warm-up 1: its overlap frame 2's temporal.history differs; the
     * state of frame 2 reaches back to frame 0 (history_from): it needs --warmup 3. */
    const spec specs[] = {{0, 2, 0, 0, 8, -1, 0, NULL}, {3, 5, 1, 1, 8, 2, 2, NULL}, {6, 7, 6, 1, 8, -1, 0, NULL}};
    fixture fx;
    fixture_make(&fx, specs, 3);
    eng_error err = {{0}};
    ck_assert_int_eq(merge(&fx, 3, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "frame 2 buffer temporal.history differs") != NULL, "%s", err.msg);
    ck_assert_msg(strstr(err.msg, "s1:") != NULL && strstr(err.msg, "s0's") != NULL, "%s", err.msg);
    ck_assert_msg(strstr(err.msg, "needs --warmup 3") != NULL, "%s", err.msg);
    ck_assert_ptr_null(strchr(err.msg, '\n'));
    ck_assert(!exists(fx.run, "manifest.json"));
    ck_assert(!exists(fx.run, "frames"));
    rm_rf(fx.root);
}
END_TEST

START_TEST(test_digest_mismatch_stateless)
{
    /* Without temporal state (history_from -1) no warm-up helps: merge says so. */
    const spec specs[] = {{0, 3, 0, 0, 6, -1, -1, "false"}, {4, 5, 1, 1, 6, 3, -1, "false"}};
    fixture fx;
    fixture_make(&fx, specs, 2);
    eng_error err = {{0}};
    ck_assert_int_eq(merge(&fx, 2, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "frame 3 buffer temporal.history") && strstr(err.msg, "no warm-up changes it"), "%s",
                  err.msg);
    rm_rf(fx.root);
}
END_TEST

START_TEST(test_mismatch_with_enough_warmup)
{
    /* The warm-up reached the state's start and still differs: not a warm-up problem. */
    const spec specs[] = {{0, 3, 0, 0, 6, -1, 2, NULL}, {4, 5, 2, 1, 6, 3, 2, NULL}};
    fixture fx;
    fixture_make(&fx, specs, 2);
    eng_error err = {{0}};
    ck_assert_int_eq(merge(&fx, 2, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "not a warm-up problem"), "%s", err.msg);
    rm_rf(fx.root);
}
END_TEST

START_TEST(test_refusals)
{
    eng_error err = {{0}};
    fixture fx;
    /* No overlap frame: nothing proves the warm-up. */
    const spec no_overlap[] = {{0, 3, 0, 0, 6, -1, 0, NULL}, {4, 5, 4, 0, 6, -1, 0, NULL}};
    fixture_make(&fx, no_overlap, 2);
    ck_assert_int_eq(merge(&fx, 2, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "no overlap frame"), "%s", err.msg);
    rm_rf(fx.root);
    /* Other settings. */
    const spec other[] = {{0, 3, 0, 0, 6, -1, 0, NULL}, {4, 5, 1, 1, 6, -1, 0, "false"}};
    fixture_make(&fx, other, 2);
    ck_assert_int_eq(merge(&fx, 2, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "settings.temporal differs"), "%s", err.msg);
    rm_rf(fx.root);
    /* A gap. */
    const spec gap[] = {{0, 2, 0, 0, 6, -1, 0, NULL}, {4, 5, 1, 1, 6, -1, 0, NULL}};
    fixture_make(&fx, gap, 2);
    ck_assert_int_eq(merge(&fx, 2, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "frames 3-3 are in no shard"), "%s", err.msg);
    rm_rf(fx.root);
    /* An incomplete shard (killed: no manifest) and a run that is no shard. */
    const spec ok[] = {{0, 3, 0, 0, 6, -1, 0, NULL}, {4, 5, 1, 1, 6, -1, 0, NULL}};
    fixture_make(&fx, ok, 2);
    char p[512];
    snprintf(p, sizeof p, "%s/manifest.json", fx.shard[1]);
    unlink(p);
    ck_assert_int_eq(merge(&fx, 2, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "no manifest.json") && strstr(err.msg, "s1"), "%s", err.msg);
    ck_assert(!exists(fx.run, "manifest.json"));
    snprintf(p, sizeof p, "%s/manifest.json", fx.shard[1]);
    write_text(p, "{\"format\": \"ispm-run\", \"complete\": true, \"frames\": []}\n");
    ck_assert_int_eq(merge(&fx, 2, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "not a shard"), "%s", err.msg);
    /* A listed frame file that is missing. */
    write_shard(fx.shard[1], &ok[1]);
    snprintf(p, sizeof p, "%s/frames/000005.exr", fx.shard[1]);
    unlink(p);
    ck_assert_int_eq(merge(&fx, 2, &err), ENG_ERR_INVALID);
    ck_assert_msg(strstr(err.msg, "000005.exr: missing"), "%s", err.msg);
    rm_rf(fx.root);
}
END_TEST

int main(void)
{
    Suite *s = suite_create("merge");
    TCase *tc = tcase_create("checks");
    tcase_add_test(tc, test_parse_range);
    tcase_add_test(tc, test_coverage);
    tcase_add_test(tc, test_merge_ok);
    tcase_add_test(tc, test_digest_mismatch_names_warmup);
    tcase_add_test(tc, test_digest_mismatch_stateless);
    tcase_add_test(tc, test_mismatch_with_enough_warmup);
    tcase_add_test(tc, test_refusals);
    suite_add_tcase(s, tc);
    SRunner *sr = srunner_create(s);
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
