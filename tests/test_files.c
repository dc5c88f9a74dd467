/* test_files.c — Check suite for the one way an input is opened (engine/core/files.c): regular
 * files only, FIFOs and devices and folders refused by name without blocking, the size bound
 * before reading, symbolic links refused with ENG_IN_NOFOLLOW, the JSON depth and trailing-text
 * checks, and the folder lock; and for the glTF precheck beside it (engine/scene/gltf_precheck.c):
 * a .gltf's and a .glb's JSON depth, the external-file bound, and image sizes from headers. */
#define _GNU_SOURCE
#include "eng_core.h"
#include "gltf_precheck.h"

#include <check.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static char dir[256];

static void setup(void)
{
    snprintf(dir, sizeof dir, "/tmp/ispm-test-files-XXXXXX");
    ck_assert_ptr_nonnull(mkdtemp(dir));
}

static void teardown(void)
{
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    ck_assert_int_eq(system(cmd), 0);
}

static char *path_of(const char *name)
{
    static char p[2][400];
    static int k;
    k ^= 1;
    snprintf(p[k], sizeof p[k], "%s/%s", dir, name);
    return p[k];
}

static void write_text(const char *name, const char *text)
{
    FILE *f = fopen(path_of(name), "wb");
    ck_assert_ptr_nonnull(f);
    fputs(text, f);
    ck_assert_int_eq(fclose(f), 0);
}

START_TEST(reads_regular_file)
{
    write_text("a.json", "{\"x\": 1}\n");
    char *data;
    size_t len;
    eng_error err;
    ck_assert_int_eq(eng_read_input(path_of("a.json"), 0, 100, &data, &len, &err), ENG_OK);
    ck_assert_uint_eq(len, 9);
    ck_assert_str_eq(data, "{\"x\": 1}\n");
    free(data);
    ck_assert_int_eq(eng_read_input(path_of("a.json"), 0, 8, &data, &len, &err), ENG_ERR_INVALID);
    ck_assert_ptr_null(data);
    ck_assert_ptr_nonnull(strstr(err.msg, "more than the 8 allowed"));
    ck_assert_int_eq(eng_read_input(path_of("missing"), 0, 8, &data, &len, &err), ENG_ERR_IO);
}
END_TEST

START_TEST(refuses_fifo_without_blocking)
{
    ck_assert_int_eq(mkfifo(path_of("pipe"), 0600), 0);
    char *data;
    size_t len;
    eng_error err;
    /* A blocking open would wait here forever: the alarm ends the test instead. */
    alarm(10);
    ck_assert_int_eq(eng_read_input(path_of("pipe"), 0, 100, &data, &len, &err), ENG_ERR_INVALID);
    alarm(0);
    ck_assert_ptr_nonnull(strstr(err.msg, "a FIFO"));
    ck_assert_ptr_nonnull(strstr(err.msg, path_of("pipe")));
}
END_TEST

START_TEST(refuses_device_and_folder)
{
    eng_error err;
    ck_assert_int_eq(eng_check_input("/dev/zero", 0, 100, NULL, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "character device"));
    ck_assert_int_eq(eng_check_input(dir, 0, 100, NULL, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "a folder"));
}
END_TEST

START_TEST(sparse_file_refused_from_its_size)
{
    int fd = open(path_of("sparse"), O_WRONLY | O_CREAT, 0600);
    ck_assert_int_ge(fd, 0);
    ck_assert_int_eq(ftruncate(fd, (off_t)8 << 30), 0); /* 8 GiB, no block written */
    close(fd);
    uint64_t size = 0;
    eng_error err;
    ck_assert_int_eq(eng_check_input(path_of("sparse"), 0, (uint64_t)1 << 30, &size, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "8589934592 bytes"));
}
END_TEST

START_TEST(nofollow_refuses_links)
{
    write_text("target", "{}");
    ck_assert_int_eq(symlink(path_of("target"), path_of("link")), 0);
    ck_assert_int_eq(symlink(path_of("nothing"), path_of("dangling")), 0);
    eng_error err;
    ck_assert_int_eq(eng_check_input(path_of("link"), 0, 100, NULL, &err), ENG_OK);
    ck_assert_int_eq(eng_check_input(path_of("link"), ENG_IN_NOFOLLOW, 100, NULL, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "symbolic link"));
    ck_assert_int_eq(eng_check_input(path_of("dangling"), 0, 100, NULL, &err), ENG_ERR_IO);
    ck_assert_ptr_nonnull(strstr(err.msg, "dangling"));
}
END_TEST

START_TEST(json_depth_and_trailing_text)
{
    eng_error err;
    const char *ok[] = {"{}", " [1, {\"a\": [2]}] \n", "{\"s\": \"}]]\\\"{\"}", "3", "\"x\"", "{} \0", ""};
    for (size_t i = 0; i < sizeof ok / sizeof *ok; i++) {
        size_t len = i == 5 ? 4 : strlen(ok[i]); /* case 5 counts its NUL, as a C string's caller may */
        ck_assert_msg(eng_json_precheck("t.json", ok[i], len, 8, &err) == ENG_OK, "case %zu: %s", i, err.msg);
    }
    ck_assert_int_eq(eng_json_precheck("t.json", "{} SECRET", 9, 8, &err), ENG_ERR_PARSE);
    ck_assert_ptr_nonnull(strstr(err.msg, "t.json: byte 3: text after the JSON value"));
    ck_assert_int_eq(eng_json_precheck("t.json", "1 2", 3, 8, &err), ENG_ERR_PARSE);
    ck_assert_int_eq(eng_json_precheck("t.json", "{}{}", 4, 8, &err), ENG_ERR_PARSE);
    /* Exactly the limit passes, one more level does not; brackets inside strings do not count. */
    ck_assert_int_eq(eng_json_precheck("t.json", "[[[[[[[[]]]]]]]]", 16, 8, &err), ENG_OK);
    ck_assert_int_eq(eng_json_precheck("t.json", "[[[[[[[[[]]]]]]]]]", 18, 8, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "nested deeper than 8 levels"));
    ck_assert_int_eq(eng_json_precheck("t.json", "[\"[[[[[[[[[[[[\"]", 16, 8, &err), ENG_OK);
    /* 20,000 levels (the file that overflowed tinygltf's parser) end at the limit. */
    size_t n = 20000;
    char *deep = malloc(2 * n);
    memset(deep, '[', n);
    memset(deep + n, ']', n);
    ck_assert_int_eq(eng_json_precheck("deep.json", deep, 2 * n, ENG_JSON_MAX_DEPTH, &err), ENG_ERR_INVALID);
    free(deep);
}
END_TEST

START_TEST(lock_names_its_holder)
{
    char *run = path_of("run");
    eng_lock a, b;
    eng_error err;
    ck_assert_int_eq(eng_lock_take(run, "ispm record", &a, &err), ENG_OK);
    pid_t child = fork();
    ck_assert_int_ge(child, 0);
    if (child == 0) {
        /* another process: flock conflicts across open files */
        eng_result r = eng_lock_take(run, "ispm record", &b, &err);
        int named = strstr(err.msg, "in use by ispm record, process") != NULL;
        _exit(r == ENG_ERR_INVALID && named ? 0 : 1);
    }
    int st;
    ck_assert_int_eq(waitpid(child, &st, 0), child);
    ck_assert(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    eng_lock_drop(&a);
    ck_assert_int_ne(access(path_of("run.lock"), F_OK), 0);
    ck_assert_int_eq(eng_lock_take(run, "ispm record", &b, &err), ENG_OK);
    eng_lock_drop(&b);
    eng_lock_drop(NULL);
}
END_TEST

START_TEST(gltf_precheck)
{
    eng_error err;
    uint64_t most = 0;
    const char *small = "{\"asset\": {\"version\": \"2.0\"}, \"buffers\": [{\"byteLength\": 12, \"uri\": \"a.bin\"}]}";
    ck_assert_int_eq(scn_gltf_precheck("s.gltf", small, strlen(small), &most, &err), ENG_OK);
    ck_assert_uint_eq(most, SCN_EXTERNAL_MIN);
    const char *big = "{\"buffers\": [{\"byteLength\": 400000000}, {\"byteLength\": 5}]}";
    ck_assert_int_eq(scn_gltf_precheck("b.gltf", big, strlen(big), &most, &err), ENG_OK);
    ck_assert_uint_eq(most, 400000003u);
    const char *huge = "{\"buffers\": [{\"byteLength\": 1e15}]}";
    ck_assert_int_eq(scn_gltf_precheck("h.gltf", huge, strlen(huge), &most, &err), ENG_OK);
    ck_assert_uint_eq(most, SCN_EXTERNAL_MAX);
    ck_assert_int_eq(scn_gltf_precheck("t.gltf", "{} x", 4, &most, &err), ENG_ERR_PARSE);
    /* Accessor counts tinygltf's int would wrap. */
    const char *counts[] = {
        "{\"accessors\": [{\"count\": 24}, {\"count\": 24, \"sparse\": {\"count\": 2147483648}}]}",
        "{\"accessors\": [{\"count\": 4294967296}]}",
        "{\"accessors\": [{\"count\": 0}]}",
        "{\"accessors\": [{\"count\": 2.5}]}",
        "{\"accessors\": [{\"count\": 3, \"sparse\": {\"count\": 4}}]}",
    };
    for (size_t i = 0; i < sizeof counts / sizeof *counts; i++)
        ck_assert_msg(scn_gltf_precheck("c.gltf", counts[i], strlen(counts[i]), &most, &err) == ENG_ERR_INVALID,
                      "case %zu", i);
    ck_assert_ptr_nonnull(strstr(err.msg, "accessors[0].sparse.count 4"));
    const char *fine = "{\"accessors\": [{\"count\": 2147483647, \"sparse\": {\"count\": 1}}, {}]}";
    ck_assert_int_eq(scn_gltf_precheck("c.gltf", fine, strlen(fine), &most, &err), ENG_OK);
    /* A .glb whose JSON chunk nests 300 levels. */
    size_t n = 300, json_len = 2 * n, len = 20 + json_len;
    unsigned char *glb = calloc(1, len);
    memcpy(glb, "glTF", 4);
    glb[4] = 2;
    glb[8] = (unsigned char)len, glb[9] = (unsigned char)(len >> 8);
    glb[12] = (unsigned char)json_len, glb[13] = (unsigned char)(json_len >> 8);
    memcpy(glb + 16, "JSON", 4);
    memset(glb + 20, '[', n);
    memset(glb + 20 + n, ']', n);
    ck_assert_int_eq(scn_gltf_precheck("d.glb", (const char *)glb, len, &most, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "d.glb: byte"));
    free(glb);
}
END_TEST

START_TEST(image_header_sizes)
{
    unsigned char png[24] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                             0, 0, 0x75, 0x30, 0, 0, 0x40, 0x00}; /* 30000 x 16384 */
    uint32_t w = 0, h = 0;
    ck_assert_int_eq(scn_image_header_size(png, sizeof png, &w, &h), 1);
    ck_assert_uint_eq(w, 30000);
    ck_assert_uint_eq(h, 16384);
    ck_assert_int_eq(scn_image_header_size(png, 20, &w, &h), 0);
    /* JPEG: SOI, an APP0 segment, then SOF0 with height 600, width 800. */
    unsigned char jpg[] = {0xff, 0xd8, 0xff, 0xe0, 0, 4, 'J', 'F', 0xff, 0xc0, 0, 11, 8, 0x02, 0x58, 0x03, 0x20, 3};
    ck_assert_int_eq(scn_image_header_size(jpg, sizeof jpg, &w, &h), 1);
    ck_assert_uint_eq(w, 800);
    ck_assert_uint_eq(h, 600);
    unsigned char other[8] = "GIF89a!";
    ck_assert_int_eq(scn_image_header_size(other, sizeof other, &w, &h), 0);
}
END_TEST

static Suite *suite(void)
{
    Suite *s = suite_create("files");
    TCase *tc = tcase_create("inputs");
    tcase_add_checked_fixture(tc, setup, teardown);
    tcase_add_test(tc, reads_regular_file);
    tcase_add_test(tc, refuses_fifo_without_blocking);
    tcase_add_test(tc, refuses_device_and_folder);
    tcase_add_test(tc, sparse_file_refused_from_its_size);
    tcase_add_test(tc, nofollow_refuses_links);
    tcase_add_test(tc, json_depth_and_trailing_text);
    tcase_add_test(tc, lock_names_its_holder);
    tcase_add_test(tc, gltf_precheck);
    tcase_add_test(tc, image_header_sizes);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
