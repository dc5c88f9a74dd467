/* test_viewer.c — Check suite for the viewer's window-free logic (viewer/view_model.h).
 *
 * Unit tests of the pure parts: channel selection, the display transform (exposure, offset,
 * sRGB, false colour), the loud NaN/Inf/negative overlay, the comparison heatmaps (zero
 * difference is black, a class change is loud), the state machine the keys drive, layout and
 * probe text. Then the lazy run reader against the committed golden: the manifest opens
 * without decoding, frames decode once and stay cached, the LRU evicts the least recently
 * used, and a missing or incomplete run fails with ENG_ERR_IO / ENG_ERR_INVALID.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "view_model.h"

#define GOLDEN ISPM_SOURCE_DIR "/golden/cornell-box-ci"

static const char *const RGB_NAMES[] = {"R", "G", "B"};

static eng_buffer make_buffer(int w, int h, int nch, const char *const *names, float *data)
{
    eng_buffer b;
    b.name = "test.buffer";
    b.width = w;
    b.height = h;
    b.channel_count = nch;
    b.channels = names;
    b.data = data;
    return b;
}

START_TEST(select_channels)
{
    float px[5] = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f}, out[3];
    ck_assert_int_eq(view_select(px, 5, VIEW_CH_RGB, out), 3);
    ck_assert_float_eq(out[2], 0.3f);
    ck_assert_int_eq(view_select(px, 5, VIEW_CH_4, out), 1);
    ck_assert_float_eq(out[0], 0.4f);
    ck_assert_int_eq(view_select(px, 2, VIEW_CH_3, out), 0); /* absent channel */
    ck_assert_int_eq(view_select(px, 2, VIEW_CH_RGB, out), 3);
    ck_assert_float_eq(out[2], 0.0f);
    ck_assert_int_eq(view_select(px, 1, VIEW_CH_RGB, out), 3); /* grey */
    ck_assert_float_eq(out[1], 0.1f);
    ck_assert_int_eq(view_select(px, 3, VIEW_CH_LUMA, out), 1);
    ck_assert_float_eq_tol(out[0], 0.2126f * 0.1f + 0.7152f * 0.2f + 0.0722f * 0.3f, 1e-6f);
}
END_TEST

START_TEST(display_transform)
{
    view_display d;
    memset(&d, 0, sizeof d);
    uint8_t c[4];
    float half[3] = {0.5f, 0.5f, 0.5f};
    view_map_pixel(half, 3, &d, c); /* sRGB(0.5) = 0.7354 */
    ck_assert_int_eq(c[0], 188);
    ck_assert_int_eq(c[3], 255);
    d.linear = 1;
    view_map_pixel(half, 3, &d, c);
    ck_assert_int_eq(c[0], 128);
    d.exposure = 1.0f; /* 0.5 * 2 = 1 */
    view_map_pixel(half, 3, &d, c);
    ck_assert_int_eq(c[1], 255);
    d.exposure = 0.0f;
    d.offset = -0.5f;
    view_map_pixel(half, 3, &d, c);
    ck_assert_int_eq(c[2], 0);
    /* Single channel is grey. */
    memset(&d, 0, sizeof d);
    d.linear = 1;
    d.channel = VIEW_CH_2;
    float px[3] = {0.0f, 1.0f, 0.0f};
    view_map_pixel(px, 3, &d, c);
    ck_assert(c[0] == 255 && c[1] == 255 && c[2] == 255);
    /* Without the overlay, NaN shows as black rather than garbage. */
    float nan3[3] = {NAN, NAN, NAN};
    view_map_pixel(nan3, 3, &d, c);
    ck_assert(c[0] == 0 && c[1] == 0 && c[2] == 0);
}
END_TEST

START_TEST(false_colour_maps)
{
    float lo[3], hi[3], mid[3];
    view_turbo(0.0f, lo);
    view_turbo(1.0f, hi);
    view_turbo(0.5f, mid);
    ck_assert(lo[0] < 0.3f && lo[1] < 0.3f && lo[2] < 0.3f); /* turbo starts dark */
    float blue[3];
    view_turbo(0.15f, blue);
    ck_assert(blue[2] > 0.8f && blue[0] < 0.4f);              /* then blue */
    ck_assert(hi[0] > hi[2] && hi[0] > 0.4f);   /* and ends dark red */
    ck_assert(mid[1] > 0.8f);                   /* green-yellow in the middle */
    view_inferno(0.0f, lo);
    view_inferno(1.0f, hi);
    ck_assert(lo[0] == 0.0f && lo[1] == 0.0f && lo[2] == 0.0f); /* zero error is black */
    ck_assert(hi[0] > 0.9f && hi[1] > 0.9f);                    /* pale yellow */
    view_turbo(NAN, lo);                                        /* clamped, not propagated */
    ck_assert(isfinite(lo[0]));
    /* False colour of a grey value gives a saturated colour. */
    view_display d;
    memset(&d, 0, sizeof d);
    d.false_colour = 1;
    float grey[3] = {0.5f, 0.5f, 0.5f};
    uint8_t c[4];
    view_map_pixel(grey, 3, &d, c);
    ck_assert(!(c[0] == c[1] && c[1] == c[2]));
}
END_TEST

START_TEST(overlay_colours)
{
    view_display d;
    memset(&d, 0, sizeof d);
    d.overlay = 1;
    uint8_t c[4];
    float nanpx[3] = {0.5f, NAN, INFINITY}, infpx[3] = {0.5f, -INFINITY, -1.0f},
          negpx[3] = {0.5f, -0.1f, 0.2f}, okpx[3] = {0.5f, 0.1f, 0.2f};
    view_map_pixel(nanpx, 3, &d, c);
    ck_assert(c[0] == 255 && c[1] == 0 && c[2] == 255);
    view_map_pixel(infpx, 3, &d, c);
    ck_assert(c[0] == 0 && c[1] == 255 && c[2] == 0);
    view_map_pixel(negpx, 3, &d, c);
    ck_assert(c[0] == 0 && c[1] == 0x40 && c[2] == 255);
    view_map_pixel(okpx, 3, &d, c);
    ck_assert(!(c[0] == 255 && c[1] == 0 && c[2] == 255));
    /* Selecting a channel that is fine hides the others' problems. */
    d.channel = VIEW_CH_1;
    view_map_pixel(nanpx, 3, &d, c);
    ck_assert(!(c[0] == 255 && c[1] == 0 && c[2] == 255));
}
END_TEST

START_TEST(difference_modes)
{
    view_display d;
    memset(&d, 0, sizeof d);
    uint8_t c[4];
    float a[3] = {0.5f, 0.25f, 1.0f}, b[3] = {0.5f, 0.25f, 1.0f}, lo[3] = {0.5f, 0.25f, 0.0f};
    for (int m = VIEW_CMP_ABS; m <= VIEW_CMP_SIGNED; m++) {
        d.compare = (view_compare)m;
        view_map_diff(a, b, 3, &d, c);
        ck_assert_msg(c[0] == 0 && c[1] == 0 && c[2] == 0, "mode %d: equal pixels not black", m);
    }
    d.compare = VIEW_CMP_ABS;
    view_map_diff(a, lo, 3, &d, c); /* |d| = 1: top of inferno */
    ck_assert(c[0] > 200 && c[1] > 200);
    d.compare = VIEW_CMP_SIGNED;
    view_map_diff(a, lo, 3, &d, c); /* a - b = +1: red */
    ck_assert(c[0] == 255 && c[2] == 0);
    view_map_diff(lo, a, 3, &d, c); /* -1: blue */
    ck_assert(c[0] == 0 && c[2] == 255);
    d.compare = VIEW_CMP_REL;
    float big[3] = {1000.0f, 0, 0}, big2[3] = {999.0f, 0, 0};
    view_map_diff(big, big2, 3, &d, c); /* relative 1e-3: nearly black */
    ck_assert(c[0] < 10);
    /* A class change (finite vs NaN) is loud; the same class is no difference. */
    float n1[3] = {NAN, 0, 0}, n2[3] = {NAN, 0, 0};
    view_map_diff(a, n1, 3, &d, c);
    ck_assert(c[0] == 255 && c[1] == 0 && c[2] == 255);
    view_map_diff(n1, n2, 3, &d, c);
    ck_assert(c[0] == 0 && c[1] == 0 && c[2] == 0);
}
END_TEST

START_TEST(render_matches_b_by_channel_name)
{
    /* b stores the same pixel with channels in another order: no difference. */
    static const char *const BGR[] = {"B", "G", "R"};
    float da[6] = {0.1f, 0.2f, 0.3f, 1, 1, 1}, db[6] = {0.3f, 0.2f, 0.1f, 1, 1, 1};
    eng_buffer a = make_buffer(2, 1, 3, RGB_NAMES, da), b = make_buffer(2, 1, 3, BGR, db);
    view_display d;
    memset(&d, 0, sizeof d);
    d.compare = VIEW_CMP_ABS;
    uint8_t out[8];
    ck_assert_int_eq(view_render(&a, &b, &d, out), VIEW_RENDER_OK);
    for (int i = 0; i < 8; i++)
        ck_assert_int_eq(out[i], i % 4 == 3 ? 255 : 0);
    eng_buffer small = make_buffer(1, 1, 3, RGB_NAMES, db);
    ck_assert_int_eq(view_render(&a, &small, &d, out), VIEW_RENDER_MISMATCH);
    ck_assert_int_eq(view_render(&a, NULL, &d, out), VIEW_RENDER_NO_B);
    d.compare = VIEW_CMP_OFF;
    ck_assert_int_eq(view_render(&a, NULL, &d, out), VIEW_RENDER_OK);
    d.show_b = 1; /* flip: b's pixels through the normal display, channels matched */
    d.linear = 1;
    ck_assert_int_eq(view_render(&a, &b, &d, out), VIEW_RENDER_OK);
    ck_assert_int_eq(out[0], 26); /* R = 0.1 */
}
END_TEST

START_TEST(auto_range)
{
    static const char *const Z[] = {"Z"};
    float data[4] = {2.0f, 4.0f, NAN, 6.0f};
    eng_buffer b = make_buffer(4, 1, 1, Z, data);
    float e, o;
    ck_assert(view_auto_range(&b, VIEW_CH_RGB, &e, &o));
    ck_assert_float_eq_tol(e, -2.0f, 1e-6f); /* span 4 */
    ck_assert_float_eq_tol(2.0f * exp2f(e) + o, 0.0f, 1e-6f);
    ck_assert_float_eq_tol(6.0f * exp2f(e) + o, 1.0f, 1e-6f);
    float nans[1] = {NAN};
    eng_buffer n = make_buffer(1, 1, 1, Z, nans);
    ck_assert(!view_auto_range(&n, VIEW_CH_RGB, &e, &o));
}
END_TEST

START_TEST(state_actions)
{
    view_state s;
    view_state_init(&s, 3, 4, 0);
    view_state_set_buffer(&s, 0, 1);
    ck_assert(!view_state_apply(&s, VIEW_ACT_FRAME_PREV)); /* clamps */
    ck_assert(view_state_apply(&s, VIEW_ACT_FRAME_LAST));
    ck_assert_int_eq(s.frame, 2);
    ck_assert(!view_state_apply(&s, VIEW_ACT_FRAME_NEXT));
    ck_assert(view_state_apply(&s, VIEW_ACT_FRAME_FIRST));
    ck_assert_int_eq(s.frame, 0);
    ck_assert(!view_state_apply(&s, VIEW_ACT_CH_2));       /* one-channel buffer */
    ck_assert(view_state_apply(&s, VIEW_ACT_CH_1));
    view_state_set_buffer(&s, 3, 3);
    ck_assert(view_state_apply(&s, VIEW_ACT_CH_3));
    view_state_set_buffer(&s, 2, 1);                       /* channel 3 gone: back to RGB */
    ck_assert_int_eq(s.d.channel, VIEW_CH_RGB);
    ck_assert(!view_state_apply(&s, VIEW_ACT_CYCLE_COMPARE)); /* no second run */
    ck_assert(!view_state_apply(&s, VIEW_ACT_FLIP_AB));
    s.has_b = 1;
    for (int i = 0; i < VIEW_CMP_COUNT; i++)
        view_state_apply(&s, VIEW_ACT_CYCLE_COMPARE);
    ck_assert_int_eq(s.d.compare, VIEW_CMP_OFF);
    view_state_apply(&s, VIEW_ACT_EXPOSURE_UP);
    view_state_apply(&s, VIEW_ACT_OFFSET_DOWN);
    view_state_apply(&s, VIEW_ACT_RESET);
    ck_assert(s.d.exposure == 0.0f && s.d.offset == 0.0f && s.zoom == 1.0f);
    view_state_apply(&s, VIEW_ACT_PLAY);
    view_state_set_frame(&s, 2);
    ck_assert(view_state_tick(&s));
    ck_assert_int_eq(s.frame, 0); /* playback wraps */
    view_state_apply(&s, VIEW_ACT_QUIT);
    ck_assert(s.quit);
}
END_TEST

START_TEST(layout_and_probe)
{
    view_rect area = {260, 0, 660, 752};
    view_rect r = view_fit(area, 160, 160, 1.0f);
    ck_assert(r.x == 260 && r.y == 46 && r.w == 660 && r.h == 660);
    int px, py;
    ck_assert(view_screen_to_pixel(r, 160, 160, 260, 46, &px, &py));
    ck_assert(px == 0 && py == 0);
    ck_assert(view_screen_to_pixel(r, 160, 160, 919, 705, &px, &py));
    ck_assert(px == 159 && py == 159);
    ck_assert(!view_screen_to_pixel(r, 160, 160, 259, 100, &px, &py));
    view_rect wide = view_fit(area, 1920, 1080, 1.0f); /* any size fits */
    ck_assert(wide.w == 660 && wide.h <= 752);
    view_rect bar = {8, 0, 800, 16};
    ck_assert_int_eq(view_timeline_frame(bar, 8, 8), 0);
    ck_assert_int_eq(view_timeline_frame(bar, 8, 807), 7);
    ck_assert_int_eq(view_timeline_frame(bar, 8, 5000), 7);

    float data[6] = {1.0f, NAN, -INFINITY, 0.25f, 2.0f, 3.0f};
    eng_buffer b = make_buffer(2, 1, 3, RGB_NAMES, data);
    char line[256];
    ck_assert_str_eq(view_probe_line(&b, 0, 0, line, sizeof line), "test.buffer  R=1 G=nan B=-inf");
    ck_assert_str_eq(view_probe_line(&b, 5, 0, line, sizeof line), "test.buffer  -");
    char tiny[8];
    view_probe_line(&b, 1, 0, tiny, sizeof tiny); /* truncates, stays terminated */
    ck_assert_int_eq((int)strlen(tiny), 7);
    ck_assert_float_eq(view_probe_value(&b, VIEW_CH_1, 1, 0), 0.25f);
    ck_assert(isnan(view_probe_value(&b, VIEW_CH_1, 2, 0)));
}
END_TEST

START_TEST(run_lazy_cache)
{
    view_run *r = NULL;
    eng_error err;
    ck_assert_int_eq(view_run_open(GOLDEN, 2, &r, &err), ENG_OK);
    ck_assert_int_eq(view_run_decodes(r), 0); /* opening decodes nothing */
    ck_assert_int_ge(view_run_frame_count(r), 3);
    int rw = 0, rh = 0;
    float vp[16];
    view_run_resolution(r, &rw, &rh);
    ck_assert_int_eq(rw, 160);
    ck_assert_int_eq(rh, 160);
    ck_assert_int_eq(view_run_camera(r, 999, vp), 0);
    int fin = view_run_find(r, 0, "final.display");
    ck_assert_int_ge(fin, 0);
    ck_assert_int_eq(view_run_buffer_channels(r, 0, fin), 3);
    const eng_buffer *bufs;
    int count;
    ck_assert_int_eq(view_run_frame(r, 0, &bufs, &count, &err), ENG_OK);
    ck_assert_int_eq(count, view_run_buffer_count(r, 0));
    ck_assert_str_eq(bufs[fin].name, "final.display");
    ck_assert_str_eq(bufs[fin].channels[0], "R"); /* manifest order */
    ck_assert_int_gt(bufs[fin].width, 0);
    ck_assert_int_eq(view_run_frame(r, 0, &bufs, &count, &err), ENG_OK);
    ck_assert_int_eq(view_run_decodes(r), 1);    /* cached */
    view_run_frame(r, 1, &bufs, &count, &err);
    view_run_frame(r, 0, &bufs, &count, &err);   /* 0 most recent, 1 least */
    ck_assert_int_eq(view_run_decodes(r), 2);
    view_run_frame(r, 2, &bufs, &count, &err);   /* evicts 1 */
    view_run_frame(r, 0, &bufs, &count, &err);
    ck_assert_int_eq(view_run_decodes(r), 3);
    view_run_frame(r, 1, &bufs, &count, &err);
    ck_assert_int_eq(view_run_decodes(r), 4);
    ck_assert_int_eq(view_run_frame(r, 999, &bufs, &count, &err), ENG_ERR_INVALID);
    view_run_close(r);
    view_run_close(NULL);
}
END_TEST

static const char *const PHOTON_NAMES[14] = {
    "position.X", "position.Y", "position.Z", "direction.X", "direction.Y", "direction.Z", "power.R",
    "power.G", "power.B", "normal.X", "normal.Y", "normal.Z", "density", "bounce"};

static void put_photon(float *map, int i, float x, float y, float z, float bounce)
{
    float *px = map + i * 14;
    px[0] = x;
    px[1] = y;
    px[2] = z;
    px[6] = 1.0f;
    px[13] = bounce;
}

START_TEST(photon_projection)
{
    /* Camera at the origin looking down -Z, 90 degrees, near 0.1, far 100: a point at depth d
     * in front maps x/d, y/d to NDC. Column-major: element (r, c) at [c*4+r]. */
    const float n = 0.1f, f = 100.0f;
    float vp[16] = {0};
    vp[0] = 1.0f;
    vp[5] = 1.0f;
    vp[10] = -(f + n) / (f - n);
    vp[11] = -1.0f;
    vp[14] = -2.0f * f * n / (f - n);
    float map[8 * 14] = {0};
    put_photon(map, 0, 0.0f, 0.0f, -5.0f, 2.0f);   /* centre */
    put_photon(map, 1, 0.0f, 0.0f, 5.0f, 2.0f);    /* behind the camera: w < 0 */
    put_photon(map, 2, 10.0f, 0.0f, -5.0f, 3.0f);  /* NDC x = 2: outside */
    put_photon(map, 3, 2.5f, 2.5f, -5.0f, 3.0f);   /* NDC (0.5, 0.5): upper right */
    put_photon(map, 4, -5.0f, -5.0f, -5.0f, 6.0f); /* NDC (-1, -1): the lower left corner */
    put_photon(map, 5, 1.0f, 1.0f, -5.0f, 0.0f);   /* bounce 0: no photon */
    eng_buffer b = make_buffer(8, 1, 14, PHOTON_NAMES, map);
    view_point pts[8];
    int total = -1;
    ck_assert_int_eq(view_project_photons(&b, vp, 160, 120, pts, 8, &total), 3);
    ck_assert_int_eq(total, 5);
    ck_assert_float_eq_tol(pts[0].x, 80.0f, 1e-4f); /* exact centre -> the image's centre */
    ck_assert_float_eq_tol(pts[0].y, 60.0f, 1e-4f);
    ck_assert_int_eq(pts[0].bounce, 2);
    ck_assert_float_eq_tol(pts[1].x, 120.0f, 1e-3f);
    ck_assert_float_eq_tol(pts[1].y, 30.0f, 1e-3f); /* rows top-first: +y is up */
    ck_assert_int_eq(pts[1].bounce, 3);
    ck_assert_float_eq_tol(pts[2].x, 0.0f, 1e-3f);
    ck_assert_float_eq_tol(pts[2].y, 120.0f, 1e-3f);
    ck_assert_int_eq(pts[2].bounce, 6);
    /* cap limits the points written, not the count */
    ck_assert_int_eq(view_project_photons(&b, vp, 160, 120, pts, 1, &total), 1);
    ck_assert_int_eq(total, 5);
    /* colours by bounce */
    ck_assert_uint_eq(view_bounce_colour(2), 0x00ffffu);
    ck_assert_uint_eq(view_bounce_colour(3), 0xffff00u);
    ck_assert_uint_eq(view_bounce_colour(4), 0xff00ffu);
    ck_assert_uint_eq(view_bounce_colour(9), 0xff00ffu);
    /* a buffer without the channels */
    eng_buffer rgb = make_buffer(8, 1, 3, RGB_NAMES, map);
    ck_assert_int_eq(view_project_photons(&rgb, vp, 160, 120, pts, 8, &total), -1);
    ck_assert_int_eq(total, 0);
    /* the toggle */
    view_state s;
    view_state_init(&s, 3, 2, 0);
    ck_assert_int_eq(s.photons, 0);
    ck_assert_int_eq(view_state_apply(&s, VIEW_ACT_TOGGLE_PHOTONS), 1);
    ck_assert_int_eq(s.photons, 1);
    view_state_apply(&s, VIEW_ACT_TOGGLE_PHOTONS); /* the probed pixel's photons only */
    ck_assert_int_eq(s.photons, 2);
    view_state_apply(&s, VIEW_ACT_TOGGLE_PHOTONS);
    ck_assert_int_eq(s.photons, 0);
}
END_TEST

START_TEST(run_errors)
{
    view_run *r = (view_run *)1;
    eng_error err;
    ck_assert_int_eq(view_run_open(ISPM_BINARY_DIR "/no-such-run", 0, &r, &err), ENG_ERR_IO);
    ck_assert_ptr_null(r);
    /* A run without its manifest is incomplete. */
    char dir[512];
    snprintf(dir, sizeof dir, "%s/test_viewer_incomplete", ISPM_BINARY_DIR);
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s' && mkdir -p '%s/frames'", dir, dir);
    ck_assert_int_eq(system(cmd), 0);
    ck_assert_int_ne(view_run_open(dir, 0, &r, &err), ENG_OK);
    ck_assert_ptr_null(r);
}
END_TEST

/* The probe's lineage (view_lineage.c): which eye pixel a probe stands for, the contributing
 * photons' points and weights, the panel's lines. */
START_TEST(lineage_probe)
{
    float d[4 * 4 * 3] = {0};
    eng_buffer eye = make_buffer(4, 4, 3, RGB_NAMES, d), half = make_buffer(2, 2, 3, RGB_NAMES, d);
    eng_buffer light = make_buffer(4, 4, 3, RGB_NAMES, d);
    eye.name = "final.display";
    half.name = "upsample.level1";
    light.name = "shadow.light0.face2";
    int x, y;
    ck_assert(view_lineage_eye_pixel(&eye, 4, 4, 3, 1, &x, &y));
    ck_assert_int_eq(x, 3);
    ck_assert_int_eq(y, 1);
    ck_assert(view_lineage_eye_pixel(&half, 4, 4, 1, 0, &x, &y)); /* covers eye pixels 2..3 x 0..1 */
    ck_assert_int_eq(x, 3);
    ck_assert_int_eq(y, 1);
    ck_assert(!view_lineage_eye_pixel(&light, 4, 4, 1, 1, &x, &y));
    ck_assert(!view_lineage_eye_pixel(&eye, 4, 4, 4, 0, &x, &y));

    /* Two contributing photons, one twice the other's luminance; identity camera. */
    lin_photon ph[2];
    memset(ph, 0, sizeof ph);
    ph[0].position[0] = 0.5f; /* NDC (0.5, 0): image (75 %, 50 %) */
    ph[1].position[1] = -0.5f;
    for (int c = 0; c < 3; c++) {
        ph[0].contribution[c] = 1.0f;
        ph[1].contribution[c] = 2.0f;
    }
    lin_result r;
    memset(&r, 0, sizeof r);
    r.covered = r.has_photons = 1;
    r.photon_count = 2;
    r.map_photons = 10;
    r.photons = ph;
    float vp[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    view_point pts[2];
    float w[2];
    ck_assert_int_eq(view_lineage_points(&r, vp, 100, 100, pts, w, 2), 2);
    ck_assert_float_eq_tol(pts[0].x, 75.0f, 1e-4f);
    ck_assert_float_eq_tol(pts[0].y, 50.0f, 1e-4f);
    ck_assert_float_eq_tol(pts[1].y, 75.0f, 1e-4f);
    ck_assert_float_eq_tol(w[0], 0.5f, 1e-6f);
    ck_assert_float_eq_tol(w[1], 1.0f, 1e-6f);
    ck_assert_uint_eq(view_contribution_colour(1.0f), 0xffffffu);
    ck_assert_uint_ne(view_contribution_colour(0.0f), view_contribution_colour(1.0f));
    static char lines[8][VIEW_LINEAGE_LINE];
    int n = view_lineage_lines(&r, lines, 8);
    ck_assert_int_eq(n, 1);
    ck_assert_ptr_nonnull(strstr(lines[0], "2 of 10"));
}
END_TEST

int main(void)
{
    Suite *s = suite_create("viewer");
    TCase *model = tcase_create("model");
    tcase_add_test(model, select_channels);
    tcase_add_test(model, display_transform);
    tcase_add_test(model, false_colour_maps);
    tcase_add_test(model, overlay_colours);
    tcase_add_test(model, difference_modes);
    tcase_add_test(model, render_matches_b_by_channel_name);
    tcase_add_test(model, auto_range);
    tcase_add_test(model, state_actions);
    tcase_add_test(model, layout_and_probe);
    tcase_add_test(model, photon_projection);
    tcase_add_test(model, lineage_probe);
    suite_add_tcase(s, model);
    TCase *run = tcase_create("run");
    tcase_add_test(run, run_lazy_cache);
    tcase_add_test(run, run_errors);
    suite_add_tcase(s, run);
    SRunner *sr = srunner_create(s);
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
