/* test_live.c — Check suite of live view: the run reader on a run still being
 * recorded (rep_run_open_live, rep_run_refresh in replay/run/run.c) and the viewer's follow logic
 * (viewer/view_live.c). A recording is imitated file by file from a small golden run, in the
 * order capture writes: run.json first, then per frame the EXR and then its record
 * (frames/NNNNNN.json, the manifest's entry for the frame), manifest.json last. */
#define _XOPEN_SOURCE 700

#include <check.h>
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "rep.h"
#include "rep_run.h"
#include "rep_util.h"
#include "view_model.h"

#define GOLDEN ISPM_SOURCE_DIR "/golden/stress-photons-1k"

static char g_tmp[4096], g_src[4096];
static cJSON *g_manifest;

static void setup(void)
{
    const char *base = getenv("TMPDIR");
    snprintf(g_tmp, sizeof g_tmp, "%s/ispm-test-live-XXXXXX", base && base[0] ? base : "/tmp");
    ck_assert_ptr_nonnull(mkdtemp(g_tmp));
    /* The golden written out as frame files (it may store its buffers as objects): the frames
     * a recording would land. */
    snprintf(g_src, sizeof g_src, "%s/ispm-test-live-src-XXXXXX", base && base[0] ? base : "/tmp");
    ck_assert_ptr_nonnull(mkdtemp(g_src));
    char *src = rep_path_join(g_src, "golden");
    FILE *out = tmpfile();
    ck_assert_ptr_nonnull(out);
    eng_error uerr;
    ck_assert_msg(rep_golden_unpack(GOLDEN, src, out, &uerr) == ENG_OK, "%s", uerr.msg);
    fclose(out);
    free(src);
    char *frames = rep_path_join(g_tmp, "frames");
    eng_error err;
    ck_assert_int_eq(rep_mkdirs(frames, &err), ENG_OK);
    free(frames);
    char *text = NULL;
    size_t len = 0;
    char *manifest = rep_path_join(g_src, "golden/manifest.json");
    ck_assert_int_eq(eng_read_file(manifest, 1 << 24, &text, &len, &err), ENG_OK);
    free(manifest);
    g_manifest = cJSON_ParseWithLength(text, len);
    free(text);
    ck_assert_ptr_nonnull(g_manifest);
}

static void teardown(void)
{
    cJSON_Delete(g_manifest);
    rep_remove_tree(g_tmp, NULL);
    rep_remove_tree(g_src, NULL);
}

static void put(const char *rel, const char *text)
{
    char *p = rep_path_join(g_tmp, rel);
    eng_error err;
    ck_assert_int_eq(rep_write_atomic(p, text, strlen(text), &err), ENG_OK);
    free(p);
}

/* run.json as capture writes it (the manifest's resolution, sequence, frame_count). */
static void put_runinfo(void)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "format", "ispm-run-info");
    const char *keys[] = {"sequence", "resolution", "frame_count"};
    for (int i = 0; i < 3; i++)
        cJSON_AddItemToObject(o, keys[i], cJSON_Duplicate(cJSON_GetObjectItem(g_manifest, keys[i]), 1));
    char *s = cJSON_Print(o);
    put("run.json", s);
    free(s);
    cJSON_Delete(o);
}

static void land_exr(int i)
{
    char rel[64];
    snprintf(rel, sizeof rel, "frames/%06d.exr", i);
    char *golden = rep_path_join(g_src, "golden");
    char *src = rep_path_join(golden, rel), *dst = rep_path_join(g_tmp, rel);
    eng_error err;
    ck_assert_int_eq(rep_copy_file(src, 0, dst, &err), ENG_OK);
    free(golden);
    free(src);
    free(dst);
}

static void land_record(int i)
{
    char rel[64];
    snprintf(rel, sizeof rel, "frames/%06d.json", i);
    char *s = cJSON_Print(cJSON_GetArrayItem(cJSON_GetObjectItem(g_manifest, "frames"), i));
    put(rel, s);
    free(s);
}

static void land(int i)
{
    land_exr(i);
    land_record(i);
}

START_TEST(a_recording_grows_frame_by_frame)
{
    eng_error err;
    rep_run *run = NULL;
    /* neither manifest nor run.json: not a run, the complete reader's error */
    ck_assert_int_eq(rep_run_open_live(g_tmp, &run, &err), ENG_ERR_IO);
    ck_assert_ptr_null(run);
    put_runinfo();
    ck_assert_int_eq(rep_run_open_live(g_tmp, &run, &err), ENG_OK);
    ck_assert_int_eq(run->frame_count, 0);
    ck_assert_int_eq(run->complete, 0);
    ck_assert_int_eq(run->planned_frames, 4);
    ck_assert_int_eq(run->width, 48);
    int added = -1;
    land_exr(0); /* the EXR alone is not a frame yet */
    ck_assert_int_eq(rep_run_refresh(run, &added, &err), ENG_OK);
    ck_assert_int_eq(added, 0);
    land_record(0);
    ck_assert_int_eq(rep_run_refresh(run, &added, &err), ENG_OK);
    ck_assert_int_eq(added, 1);
    rep_part *parts = NULL;
    ck_assert_int_eq(rep_run_read_frame(run, 0, &parts, &err), ENG_OK); /* verified against the record */
    rep_parts_free(parts, run->frames[0].buffer_count);
    const char *name0 = run->frames[0].buffers[0].name;
    /* frame 2 lands before frame 1 (a gap): only frames up to the gap count */
    land(2);
    ck_assert_int_eq(rep_run_refresh(run, &added, &err), ENG_OK);
    ck_assert_int_eq(added, 0);
    land(1);
    ck_assert_int_eq(rep_run_refresh(run, &added, &err), ENG_OK);
    ck_assert_int_eq(added, 2);
    ck_assert_int_eq(run->frame_count, 3);
    ck_assert_ptr_eq(run->frames[0].buffers[0].name, name0); /* listed frames keep their info */
    /* a record that is not JSON is an error naming it; the run stays as it was */
    land_exr(3);
    put("frames/000003.json", "{ nope");
    ck_assert_int_eq(rep_run_refresh(run, &added, &err), ENG_ERR_PARSE);
    ck_assert(strstr(err.msg, "000003.json") != NULL);
    ck_assert_int_eq(run->frame_count, 3);
    land_record(3);
    /* the manifest lands: the run is complete, its frames are the manifest's */
    char *s = cJSON_Print(g_manifest);
    put("manifest.json", s);
    free(s);
    ck_assert_int_eq(rep_run_refresh(run, &added, &err), ENG_OK);
    ck_assert_int_eq(added, 1);
    ck_assert_int_eq(run->complete, 1);
    ck_assert_int_eq(run->frame_count, 4);
    ck_assert_ptr_eq(run->frames[0].buffers[0].name, name0);
    ck_assert_int_eq(rep_run_read_frame(run, 3, &parts, &err), ENG_OK);
    rep_parts_free(parts, run->frames[3].buffer_count);
    ck_assert_int_eq(rep_run_refresh(run, &added, &err), ENG_OK);
    ck_assert_int_eq(added, 0);
    rep_run_close(run);
    /* a complete run opens complete */
    ck_assert_int_eq(rep_run_open_live(g_tmp, &run, &err), ENG_OK);
    ck_assert_int_eq(run->complete, 1);
    ck_assert_int_eq(run->planned_frames, 4);
    rep_run_close(run);
}
END_TEST

START_TEST(the_viewer_follows_the_newest_frame)
{
    view_state s;
    view_state_init(&s, 3, 5, 0);
    view_state_set_frame(&s, 2);
    ck_assert_int_eq(view_state_follow(&s, 5), 1); /* on the newest: follows */
    ck_assert_int_eq(s.frame, 4);
    ck_assert_int_eq(s.frame_count, 5);
    ck_assert_int_eq(view_state_follow(&s, 5), 0); /* nothing new */
    view_state_apply(&s, VIEW_ACT_FRAME_PREV);
    ck_assert_int_eq(view_state_follow(&s, 7), 0); /* went back: stays */
    ck_assert_int_eq(s.frame, 3);
    ck_assert_int_eq(s.frame_count, 7);
    view_state_apply(&s, VIEW_ACT_FRAME_LAST); /* End follows again */
    ck_assert_int_eq(view_state_follow(&s, 8), 1);
    ck_assert_int_eq(s.frame, 7);
}
END_TEST

/* Two frames landed before the window opened: without --frame the viewer opens on the newest
 * and so follows the recording (opened on frame 0 it would count as sent back and stay). */
START_TEST(a_live_viewer_opens_on_the_newest_frame)
{
    ck_assert_int_eq(view_live_start_frame(-1, 1, 2), 1);
    ck_assert_int_eq(view_live_start_frame(-1, 0, 8), 0); /* a finished run opens at frame 0 */
    ck_assert_int_eq(view_live_start_frame(0, 1, 2), 0);  /* --frame 0 is kept */
    ck_assert_int_eq(view_live_start_frame(-1, 1, 0), 0);
    view_state s;
    view_state_init(&s, 2, 5, 0);
    view_state_set_frame(&s, view_live_start_frame(-1, 1, 2));
    ck_assert_int_eq(view_state_follow(&s, 6), 1);
    ck_assert_int_eq(s.frame, 5);
}
END_TEST

START_TEST(live_poll_through_a_view_run)
{
    put_runinfo();
    land(0);
    view_run *r = NULL;
    eng_error err;
    ck_assert_int_eq(view_run_open(g_tmp, 2, &r, &err), ENG_OK);
    ck_assert_int_eq(view_run_live(r), 1);
    ck_assert_int_eq(view_run_frame_count(r), 1);
    ck_assert_int_eq(view_run_planned_frames(r), 4);
    view_state s;
    view_state_init(&s, 1, view_run_buffer_count(r, 0), 0);
    unsigned last = 0;
    char msg[256] = "";
    land(1);
    ck_assert_int_eq(view_live_poll(r, &s, 100, &last, 250, msg, sizeof msg), 0); /* too soon */
    ck_assert_int_eq(view_live_poll(r, &s, 300, &last, 250, msg, sizeof msg), 1);
    ck_assert_int_eq(s.frame, 1);
    const eng_buffer *bufs;
    int count;
    ck_assert_int_eq(view_run_frame(r, 1, &bufs, &count, &err), ENG_OK);
    ck_assert_int_eq(count, view_run_buffer_count(r, 1));
    view_run_close(r);
}
END_TEST

static Suite *live_suite(void)
{
    Suite *s = suite_create("live");
    TCase *tc = tcase_create("core");
    tcase_add_checked_fixture(tc, setup, teardown);
    tcase_add_test(tc, a_recording_grows_frame_by_frame);
    tcase_add_test(tc, the_viewer_follows_the_newest_frame);
    tcase_add_test(tc, a_live_viewer_opens_on_the_newest_frame);
    tcase_add_test(tc, live_poll_through_a_view_run);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(live_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
