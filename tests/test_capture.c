/* test_capture.c — Check suite for capture/: the multi-part EXR writer (read back through
 * the OpenEXR C decode path, bit-exact), the listener's run folder and manifest, the
 * atomicity rules (no manifest before cap_finish, refusal to overwrite, old manifest removed
 * first) and failure paths (file-size limit standing in for a full disk, bad buffers).
 * Sequences, scenes and buffers are built by hand: no GL engine is involved. */
#define _XOPEN_SOURCE 700

#include "cap.h"
#include "cap_internal.h"
#include "eng.h"

#include <check.h>
#include <cjson/cJSON.h>
#include <openexr.h>

#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <ftw.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

/* ---------------------------------------------------------------- helpers */

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

static char *make_tmpdir(char buf[256])
{
    snprintf(buf, 256, "/tmp/test_capture.XXXXXX");
    ck_assert_ptr_nonnull(mkdtemp(buf));
    return buf;
}

static int exists(const char *dir, const char *name)
{
    char p[512];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    struct stat st;
    return stat(p, &st) == 0;
}

/* Number of entries in dir whose name starts with prefix and ends with suffix. */
static int count_named(const char *dir, const char *prefix, const char *suffix)
{
    DIR *d = opendir(dir);
    if (!d)
        return 0;
    int n = 0;
    struct dirent *e;
    size_t m = strlen(suffix);
    while ((e = readdir(d)) != NULL) {
        size_t k = strlen(e->d_name);
        if (k >= m && strcmp(e->d_name + k - m, suffix) == 0 && strncmp(e->d_name, prefix, strlen(prefix)) == 0)
            n++;
    }
    closedir(d);
    return n;
}

static int count_suffix(const char *dir, const char *suffix)
{
    return count_named(dir, "", suffix);
}

static uint32_t bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static float from_bits(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* One part as decoded from a file. Channels in file order (the EXR sorts them by name);
 * data interleaved in that order, top row first. */
typedef struct rd_part {
    char name[128];
    int width, height, channel_count;
    char channels[ENG_MAX_CHANNELS][64];
    exr_storage_t storage;
    exr_compression_t compression;
    exr_lineorder_t lineorder;
    exr_attr_box2i_t display;
    int32_t frame;   /* "ispm:frame", -1 if absent */
    double time;     /* "ispm:time" */
    float *data;
} rd_part;

static void quiet_exr(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    (void)code;
    (void)msg;
}

/* Reads every part of an EXR through the C decode pipeline. Fails the test on any error. */
static int read_exr(const char *path, rd_part **out)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = quiet_exr;
    exr_context_t ctxt = NULL;
    ck_assert_int_eq(exr_start_read(&ctxt, path, &init), EXR_ERR_SUCCESS);
    int count = 0;
    ck_assert_int_eq(exr_get_count(ctxt, &count), EXR_ERR_SUCCESS);
    rd_part *parts = calloc((size_t)count, sizeof *parts);
    ck_assert_ptr_nonnull(parts);
    for (int p = 0; p < count; p++) {
        rd_part *rp = &parts[p];
        const char *name = NULL;
        ck_assert_int_eq(exr_get_name(ctxt, p, &name), EXR_ERR_SUCCESS);
        snprintf(rp->name, sizeof rp->name, "%s", name ? name : "");
        ck_assert_int_eq(exr_get_storage(ctxt, p, &rp->storage), EXR_ERR_SUCCESS);
        ck_assert_int_eq(exr_get_compression(ctxt, p, &rp->compression), EXR_ERR_SUCCESS);
        ck_assert_int_eq(exr_get_lineorder(ctxt, p, &rp->lineorder), EXR_ERR_SUCCESS);
        if (exr_attr_get_int(ctxt, p, "ispm:frame", &rp->frame) != EXR_ERR_SUCCESS)
            rp->frame = -1;
        if (exr_attr_get_double(ctxt, p, "ispm:time", &rp->time) != EXR_ERR_SUCCESS)
            rp->time = -1.0;
        ck_assert_int_eq(exr_get_display_window(ctxt, p, &rp->display), EXR_ERR_SUCCESS);
        exr_attr_box2i_t dw;
        ck_assert_int_eq(exr_get_data_window(ctxt, p, &dw), EXR_ERR_SUCCESS);
        ck_assert_int_eq(dw.min.x, 0);
        ck_assert_int_eq(dw.min.y, 0);
        rp->width = dw.max.x - dw.min.x + 1;
        rp->height = dw.max.y - dw.min.y + 1;
        const exr_attr_chlist_t *cl = NULL;
        ck_assert_int_eq(exr_get_channels(ctxt, p, &cl), EXR_ERR_SUCCESS);
        ck_assert_int_le(cl->num_channels, ENG_MAX_CHANNELS);
        rp->channel_count = cl->num_channels;
        for (int c = 0; c < cl->num_channels; c++) {
            ck_assert_int_eq(cl->entries[c].pixel_type, EXR_PIXEL_FLOAT);
            snprintf(rp->channels[c], sizeof rp->channels[c], "%s", cl->entries[c].name.str);
        }
        size_t nc = (size_t)rp->channel_count, row = (size_t)rp->width * nc;
        rp->data = calloc(row * (size_t)rp->height, sizeof(float));
        ck_assert_ptr_nonnull(rp->data);
        int32_t lines = 0;
        ck_assert_int_eq(exr_get_scanlines_per_chunk(ctxt, p, &lines), EXR_ERR_SUCCESS);
        exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
        int inited = 0;
        for (int y = 0; y < rp->height; y += lines) {
            exr_chunk_info_t ci;
            ck_assert_int_eq(exr_read_scanline_chunk_info(ctxt, p, y, &ci), EXR_ERR_SUCCESS);
            if (inited)
                ck_assert_int_eq(exr_decoding_update(ctxt, p, &ci, &dec), EXR_ERR_SUCCESS);
            else
                ck_assert_int_eq(exr_decoding_initialize(ctxt, p, &ci, &dec), EXR_ERR_SUCCESS);
            inited = 1;
            for (int k = 0; k < dec.channel_count; k++) {
                exr_coding_channel_info_t *ch = &dec.channels[k];
                int idx = -1;
                for (int c = 0; c < rp->channel_count; c++)
                    if (strcmp(rp->channels[c], ch->channel_name) == 0)
                        idx = c;
                ck_assert_int_ge(idx, 0);
                ch->user_bytes_per_element = 4;
                ch->user_data_type = EXR_PIXEL_FLOAT;
                ch->user_pixel_stride = (int32_t)(nc * 4);
                ch->user_line_stride = (int32_t)(row * 4);
                ch->decode_to_ptr = (uint8_t *)(rp->data + (size_t)ci.start_y * row + (size_t)idx);
            }
            ck_assert_int_eq(exr_decoding_choose_default_routines(ctxt, p, &dec), EXR_ERR_SUCCESS);
            ck_assert_int_eq(exr_decoding_run(ctxt, p, &dec), EXR_ERR_SUCCESS);
        }
        if (inited)
            exr_decoding_destroy(ctxt, &dec);
    }
    exr_finish(&ctxt);
    *out = parts;
    return count;
}

static void free_parts(rd_part *parts, int count)
{
    for (int i = 0; i < count; i++)
        free(parts[i].data);
    free(parts);
}

/* Asserts that a decoded part holds exactly buffer b (name, size, channel set, every value
 * bit for bit, same row order). */
static void assert_part_equals(const rd_part *rp, const eng_buffer *b)
{
    ck_assert_str_eq(rp->name, b->name);
    ck_assert_int_eq(rp->width, b->width);
    ck_assert_int_eq(rp->height, b->height);
    ck_assert_int_eq(rp->channel_count, b->channel_count);
    for (int c = 0; c < b->channel_count; c++) {
        int idx = -1;
        for (int k = 0; k < rp->channel_count; k++)
            if (strcmp(rp->channels[k], b->channels[c]) == 0)
                idx = k;
        ck_assert_msg(idx >= 0, "channel %s missing in part %s", b->channels[c], b->name);
        for (int y = 0; y < b->height; y++)
            for (int x = 0; x < b->width; x++) {
                size_t pix = (size_t)y * (size_t)b->width + (size_t)x;
                uint32_t want = bits(b->data[pix * (size_t)b->channel_count + (size_t)c]);
                uint32_t got = bits(rp->data[pix * (size_t)rp->channel_count + (size_t)idx]);
                ck_assert_msg(want == got, "%s.%s (%d,%d): wrote %08x, read %08x", b->name,
                              b->channels[c], x, y, (unsigned)want, (unsigned)got);
            }
    }
    /* Replay recomputes digests from decoded files: they must match capture's. */
    const char *names[ENG_MAX_CHANNELS];
    for (int k = 0; k < rp->channel_count; k++)
        names[k] = rp->channels[k];
    eng_buffer decoded = {rp->name, rp->width, rp->height, rp->channel_count, names, rp->data};
    char d1[40], d2[40];
    eng_buffer_digest(b, d1);
    eng_buffer_digest(&decoded, d2);
    ck_assert_str_eq(d1, d2);
}

/* No Check macros here or in what the disk-full child calls: Check reports through a file,
 * which the child's file-size limit would break. */
static float *pattern(int w, int h, int nc, float base)
{
    float *d = malloc((size_t)w * (size_t)h * (size_t)nc * sizeof(float));
    if (!d)
        abort();
    for (int i = 0; i < w * h * nc; i++)
        d[i] = base + (float)i * 0.25f;
    return d;
}

/* ---------------------------------------------------------------- EXR writer */

START_TEST(test_exr_roundtrip)
{
    char dir[256], path[512];
    make_tmpdir(dir);
    snprintf(path, sizeof path, "%s/two.exr", dir);

    /* 7x5 RGB, every value distinct, rows distinguishable so a flip would show. */
    enum { W = 7, H = 5 };
    float rgb[W * H * 3];
    for (int i = 0; i < W * H * 3; i++)
        rgb[i] = (float)(i + 1) * 1.5f;
    rgb[0] = -3.25f;                       /* negative, top-left R */
    rgb[4] = FLT_TRUE_MIN * 7.0f;          /* denormal */
    rgb[8] = 3.0e38f;                      /* large */
    rgb[10] = -0.0f;
    rgb[W * 3 * (H - 1)] = 1.0e-30f;       /* bottom-left R */
    rgb[20] = from_bits(0x7fc01234u);      /* NaN with a payload */
    rgb[21] = -INFINITY;
    const char *rgb_names[] = {"R", "G", "B"};
    eng_buffer b0 = {"direct.radiance", W, H, 3, rgb_names, rgb};

    float *xyz = pattern(4, 3, 3, -10.0f);
    const char *xyz_names[] = {"X", "Y", "Z"};
    eng_buffer b1 = {"gbuffer.position", 4, 3, 3, xyz_names, xyz};

    const eng_buffer *bufs[] = {&b0, &b1};
    eng_error err = {{0}};
    ck_assert_int_eq(cap_write_exr(path, bufs, 2, &err), ENG_OK);
    ck_assert_int_eq(count_suffix(dir, ".tmp"), 0);

    rd_part *parts = NULL;
    int n = read_exr(path, &parts);
    ck_assert_int_eq(n, 2);
    for (int i = 0; i < 2; i++) {
        ck_assert_int_eq(parts[i].storage, EXR_STORAGE_SCANLINE);
        ck_assert_int_eq(parts[i].compression, EXR_COMPRESSION_ZIP);
        ck_assert_int_eq(parts[i].lineorder, EXR_LINEORDER_INCREASING_Y);
        ck_assert_int_eq(parts[i].frame, -1);
        /* A shared attribute: equal in every part (the C++ library refuses the file
         * otherwise), holding every part's data window. */
        ck_assert_int_eq(parts[i].display.min.x, 0);
        ck_assert_int_eq(parts[i].display.min.y, 0);
        ck_assert_int_eq(parts[i].display.max.x, W - 1);
        ck_assert_int_eq(parts[i].display.max.y, H - 1);
    }
    assert_part_equals(&parts[0], &b0);
    assert_part_equals(&parts[1], &b1);
    /* Row 0 is the top row: the first value of the file is the announced top-left pixel. */
    int r_idx = -1;
    for (int c = 0; c < 3; c++)
        if (strcmp(parts[0].channels[c], "R") == 0)
            r_idx = c;
    ck_assert_int_ge(r_idx, 0);
    ck_assert_uint_eq(bits(parts[0].data[r_idx]), bits(-3.25f));
    ck_assert_uint_eq(bits(parts[0].data[(size_t)W * 3 * (H - 1) + (size_t)r_idx]), bits(1.0e-30f));
    free_parts(parts, n);

    /* Rewriting replaces the file atomically. */
    rgb[1] = 42.0f;
    ck_assert_int_eq(cap_write_exr(path, bufs, 2, &err), ENG_OK);
    n = read_exr(path, &parts);
    assert_part_equals(&parts[0], &b0);
    free_parts(parts, n);

    free(xyz);
    rm_rf(dir);
}
END_TEST

/* OpenEXR <= 3.4.7 stored a ZIP chunk's zlib bytes when they were exactly as long as the raw
 * pixels, which readers then decode as raw pixels (upstream issue #2306). These 64x16 RGB
 * floats (rows 48..63 of a recorded composite.radiance) compress to exactly their own size
 * with Debian 12's zlib; the writer must store them so they read back bit-exact. */
START_TEST(test_exr_zip_same_size_chunk)
{
    char dir[256], path[512];
    make_tmpdir(dir);
    snprintf(path, sizeof path, "%s/chunk.exr", dir);
    char *bytes = NULL;
    size_t len = 0;
    eng_error err = {{0}};
    ck_assert_int_eq(eng_read_file(ISPM_SOURCE_DIR "/tests/data/exr/zip-same-size-64x16-rgb.f32", 1 << 20, &bytes,
                                   &len, &err), ENG_OK);
    ck_assert_uint_eq(len, 64 * 16 * 3 * sizeof(float));
    float *rgb = malloc(len);
    ck_assert_ptr_nonnull(rgb);
    memcpy(rgb, bytes, len);
    free(bytes);
    static const char *const names[] = {"R", "G", "B"};
    eng_buffer b = {"composite.radiance", 64, 16, 3, names, rgb};
    const eng_buffer *bufs[] = {&b};
    ck_assert_int_eq(cap_write_exr(path, bufs, 1, &err), ENG_OK);
    rd_part *parts = NULL;
    int n = read_exr(path, &parts);
    ck_assert_int_eq(n, 1);
    assert_part_equals(&parts[0], &b);
    free_parts(parts, n);
    free(rgb);
    rm_rf(dir);
}
END_TEST

/* cap_write_exr_unsynced (replay's stability run) writes the very bytes cap_write_exr writes. */
START_TEST(test_exr_unsynced_same_bytes)
{
    char dir[256], a[512], b[512];
    make_tmpdir(dir);
    snprintf(a, sizeof a, "%s/a.exr", dir);
    snprintf(b, sizeof b, "%s/b.exr", dir);
    float *d = pattern(7, 5, 1, 0.5f);
    static const char *const y[] = {"Y"};
    eng_buffer buf = {"stability.final.display", 7, 5, 1, y, d};
    const eng_buffer *bufs[] = {&buf};
    eng_error err = {{0}};
    ck_assert_int_eq(cap_write_exr(a, bufs, 1, &err), ENG_OK);
    ck_assert_int_eq(cap_write_exr_unsynced(b, bufs, 1, &err), ENG_OK);
    char *x = NULL, *z = NULL;
    size_t lx = 0, lz = 0;
    ck_assert_int_eq(eng_read_file(a, 1 << 20, &x, &lx, &err), ENG_OK);
    ck_assert_int_eq(eng_read_file(b, 1 << 20, &z, &lz, &err), ENG_OK);
    ck_assert_uint_eq(lx, lz);
    ck_assert_int_eq(memcmp(x, z, lx), 0);
    ck_assert(!exists(dir, "b.exr.tmp"));
    free(x);
    free(z);
    free(d);
    rm_rf(dir);
}
END_TEST

START_TEST(test_exr_single_part_keeps_name)
{
    char dir[256], path[512];
    make_tmpdir(dir);
    snprintf(path, sizeof path, "%s/one.exr", dir);
    float *z = pattern(3, 17, 1, 0.5f); /* more rows than one ZIP chunk (16) */
    const char *zn[] = {"Z"};
    eng_buffer b = {"gbuffer.depth", 3, 17, 1, zn, z};
    const eng_buffer *bufs[] = {&b};
    eng_error err = {{0}};
    ck_assert_int_eq(cap_write_exr(path, bufs, 1, &err), ENG_OK);
    rd_part *parts = NULL;
    int n = read_exr(path, &parts);
    ck_assert_int_eq(n, 1);
    assert_part_equals(&parts[0], &b);
    free_parts(parts, n);
    free(z);
    rm_rf(dir);
}
END_TEST

START_TEST(test_exr_rejects_bad_input)
{
    char dir[256], path[512];
    make_tmpdir(dir);
    snprintf(path, sizeof path, "%s/bad.exr", dir);
    float v[12] = {0};
    const char *rgb[] = {"R", "G", "B"};
    const char *dup[] = {"R", "R", "B"};
    eng_buffer a = {"a", 2, 2, 3, rgb, v};
    eng_buffer a2 = {"a", 2, 2, 3, rgb, v};
    eng_buffer d = {"d", 2, 2, 3, dup, v};
    eng_buffer z = {"z", 0, 2, 3, rgb, v};
    eng_buffer nc0 = {"c", 2, 2, 0, rgb, v};
    eng_buffer nc17 = {"c", 1, 1, ENG_MAX_CHANNELS + 1, rgb, v};
    eng_error err = {{0}};
    const eng_buffer *twice[] = {&a, &a2};
    ck_assert_int_eq(cap_write_exr(path, twice, 2, &err), ENG_ERR_INVALID);
    ck_assert_int_ne(err.msg[0], 0);
    const eng_buffer *one[1] = {&d};
    ck_assert_int_eq(cap_write_exr(path, one, 1, &err), ENG_ERR_INVALID);
    one[0] = &z;
    ck_assert_int_eq(cap_write_exr(path, one, 1, &err), ENG_ERR_INVALID);
    one[0] = &nc0;
    ck_assert_int_eq(cap_write_exr(path, one, 1, &err), ENG_ERR_INVALID);
    one[0] = &nc17;
    ck_assert_int_eq(cap_write_exr(path, one, 1, &err), ENG_ERR_INVALID);
    ck_assert_int_eq(cap_write_exr(path, one, 0, &err), ENG_ERR_INVALID);
    ck_assert_int_eq(count_suffix(dir, ".exr"), 0);
    ck_assert_int_eq(count_suffix(dir, ".tmp"), 0);
    rm_rf(dir);
}
END_TEST

/* ---------------------------------------------------------------- listener */

static void make_seq(seq_sequence *s, int frames, int w, int h)
{
    memset(s, 0, sizeof *s);
    snprintf(s->path, sizeof s->path, "/seq/test.json");
    snprintf(s->scene_path, sizeof s->scene_path, "/seq/box.gltf");
    snprintf(s->name, sizeof s->name, "capture-test");
    s->frame_count = frames;
    s->fps = 8.0;
    s->width = w;
    s->height = h;
    snprintf(s->camera_node, sizeof s->camera_node, "Camera");
    s->settings.shadow_map_size = 256; /* the rest zero: defaults */
    snprintf(s->digest, sizeof s->digest, "0123456789abcdef0123456789abcdef");
}

static void make_scene(scn_scene *sc)
{
    memset(sc, 0, sizeof *sc);
    snprintf(sc->path, sizeof sc->path, "/seq/box.gltf");
    snprintf(sc->digest, sizeof sc->digest, "fedcba9876543210fedcba9876543210");
}

static cap_capture *make_capture(const char *run, const seq_sequence *s, const scn_scene *sc, int overwrite)
{
    static const char *const det[] = {"LP_NATIVE_VECTOR_WIDTH", "128", "LP_NUM_THREADS", "2", NULL};
    cap_desc d = {0};
    d.run_dir = run;
    d.sequence = s;
    d.scene = sc;
    d.gl_version = "4.5 (Core Profile) Mesa 22.3.6";
    d.gl_renderer = "llvmpipe (LLVM 15.0.6, 128 bits)";
    d.tool_version = "0.1.0";
    d.git_revision = "abc123";
    d.command_line = "ispm record seq.json --out run";
    d.overwrite = overwrite;
    d.determinism = det;
    cap_capture *c = NULL;
    eng_error err = {{0}};
    eng_result r = cap_create(&d, &c, &err);
    ck_assert_msg(r == ENG_OK, "cap_create: %s", err.msg);
    ck_assert_ptr_nonnull(c);
    return c;
}

/* The buffers one fake frame announces; values depend on the frame. */
typedef struct fake_frame {
    float *pos, *alb, *rad, *shadow;
    eng_buffer bpos, balb, brad, bshadow;
} fake_frame;

static const char *const XYZ[] = {"X", "Y", "Z"};
static const char *const RGB[] = {"R", "G", "B"};
static const char *const ZN[] = {"Z"};

static void fake_init(fake_frame *f, int frame, int w, int h)
{
    f->pos = pattern(w, h, 3, (float)frame * 100.0f);
    f->alb = pattern(w, h, 3, 0.125f + (float)frame);
    f->rad = pattern(w, h, 3, -1.0f - (float)frame);
    f->shadow = pattern(w, h, 1, 7.0f);
    /* 2 NaN and 1 Inf, the first non-finite pixel at (3, 1). */
    f->rad[((size_t)1 * (size_t)w + 3) * 3 + 1] = NAN;
    f->rad[((size_t)2 * (size_t)w + 0) * 3 + 2] = -NAN;
    f->rad[((size_t)2 * (size_t)w + 5) * 3 + 0] = INFINITY;
    f->bpos = (eng_buffer){"gbuffer.position", w, h, 3, XYZ, f->pos};
    f->balb = (eng_buffer){"gbuffer.albedo", w, h, 3, RGB, f->alb};
    f->brad = (eng_buffer){"direct.radiance", w, h, 3, RGB, f->rad};
    f->bshadow = (eng_buffer){"shadow.light0", w, h, 1, ZN, f->shadow};
}

static void fake_free(fake_frame *f)
{
    free(f->pos);
    free(f->alb);
    free(f->rad);
    free(f->shadow);
}

static eng_frame_stats fake_stats(int frame)
{
    eng_frame_stats st;
    memset(&st, 0, sizeof st);
    st.frame = frame;
    st.time = frame / 8.0;
    st.pass_count = 2;
    snprintf(st.passes[0].name, sizeof st.passes[0].name, "gbuffer");
    st.passes[0].ms = 1.234 + frame;
    snprintf(st.passes[1].name, sizeof st.passes[1].name, "direct");
    st.passes[1].ms = 0.5;
    return st;
}

/* Announces one fake frame in full; returns the first non-zero callback result. */
static int run_frame(const eng_listener *l, int frame, int w, int h)
{
    fake_frame f;
    fake_init(&f, frame, w, h);
    int rc = l->frame_begin(l->user, frame, frame / 8.0);
    const eng_buffer *order[] = {&f.bpos, &f.bshadow, &f.balb, &f.brad};
    for (int i = 0; i < 4 && !rc; i++)
        rc = l->buffer(l->user, frame, order[i]);
    eng_frame_stats st = fake_stats(frame);
    if (!rc)
        rc = l->frame_end(l->user, &st);
    fake_free(&f);
    return rc;
}

static cJSON *load_manifest(const char *run)
{
    char p[512];
    snprintf(p, sizeof p, "%s/manifest.json", run);
    char *text = NULL;
    size_t len = 0;
    eng_error err = {{0}};
    ck_assert_int_eq(eng_read_file(p, 1 << 24, &text, &len, &err), ENG_OK);
    cJSON *j = cJSON_ParseWithLength(text, len);
    free(text);
    ck_assert_ptr_nonnull(j);
    return j;
}

static cJSON *get(const cJSON *o, const char *key)
{
    cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    ck_assert_msg(v != NULL, "manifest lacks \"%s\"", key);
    return v;
}

static const char *gets(const cJSON *o, const char *key)
{
    cJSON *v = get(o, key);
    ck_assert_msg(cJSON_IsString(v), "\"%s\" is not a string", key);
    return v->valuestring;
}

static double getn(const cJSON *o, const char *key)
{
    cJSON *v = get(o, key);
    ck_assert_msg(cJSON_IsNumber(v), "\"%s\" is not a number", key);
    return v->valuedouble;
}

START_TEST(test_listener_full_flow)
{
    char dir[256], run[300];
    make_tmpdir(dir);
    snprintf(run, sizeof run, "%s/a/run", dir); /* nested: mkdir -p */
    enum { W = 6, H = 4 };
    seq_sequence seq;
    make_seq(&seq, 2, W, H);
    seq.capture_count = 2;
    snprintf(seq.capture[0], sizeof seq.capture[0], "gbuffer.*");
    snprintf(seq.capture[1], sizeof seq.capture[1], "direct.radiance");
    scn_scene scene;
    make_scene(&scene);
    cap_capture *c = make_capture(run, &seq, &scene, 0);
    ck_assert(exists(run, "frames"));
    ck_assert(!exists(run, "manifest.json"));
    eng_listener l = cap_listener(c);

    /* Frame 1 first: frames may be rendered in any order. The source memory is scribbled
     * on after each announcement, as an engine reusing its buffers would. */
    for (int k = 0; k < 2; k++) {
        int frame = 1 - k;
        fake_frame f;
        fake_init(&f, frame, W, H);
        ck_assert_int_eq(l.frame_begin(l.user, frame, frame / 8.0), 0);
        const eng_buffer *order[] = {&f.bpos, &f.bshadow, &f.balb, &f.brad};
        fake_frame keep;
        fake_init(&keep, frame, W, H);
        for (int i = 0; i < 4; i++) {
            ck_assert_int_eq(l.buffer(l.user, frame, order[i]), 0);
            float *d = (float *)order[i]->data;
            for (int v = 0; v < W * H * order[i]->channel_count; v++)
                d[v] = 999.0f;
        }
        eng_frame_stats st = fake_stats(frame);
        ck_assert_int_eq(l.frame_end(l.user, &st), 0);
        eng_error err = {{0}};
        ck_assert_int_eq(cap_status(c, &err), ENG_OK);
        ck_assert(!exists(run, "manifest.json"));

        char path[512];
        snprintf(path, sizeof path, "%s/frames/%06d.exr", run, frame);
        rd_part *parts = NULL;
        int n = read_exr(path, &parts);
        ck_assert_int_eq(n, 3); /* shadow.light0 filtered out */
        assert_part_equals(&parts[0], &keep.bpos);
        assert_part_equals(&parts[1], &keep.balb);
        assert_part_equals(&parts[2], &keep.brad);
        for (int i = 0; i < n; i++) {
            ck_assert_int_eq(parts[i].frame, frame);
            ck_assert(parts[i].time == frame / 8.0);
        }
        free_parts(parts, n);
        fake_free(&f);
        fake_free(&keep);
    }
    ck_assert_int_eq(count_suffix(run, ".tmp"), 0);
    ck_assert(!exists(run, "manifest.json"));

    eng_error err = {{0}};
    ck_assert_msg(cap_finish(c, &err) == ENG_OK, "cap_finish: %s", err.msg);
    cap_destroy(c);
    ck_assert(exists(run, "manifest.json"));
    ck_assert(!exists(run, "manifest.json.tmp"));

    cJSON *m = load_manifest(run);
    ck_assert_str_eq(gets(m, "format"), "ispm-run");
    ck_assert(getn(m, "format_version") == 1);
    const cJSON *tool = get(m, "tool");
    ck_assert_str_eq(gets(tool, "name"), "ispm");
    ck_assert_str_eq(gets(tool, "version"), "0.1.0");
    ck_assert_str_eq(gets(tool, "git"), "abc123");
    ck_assert_str_eq(gets(m, "command"), "ispm record seq.json --out run");
    const cJSON *sq = get(m, "sequence");
    ck_assert_str_eq(gets(sq, "path"), "/seq/test.json");
    ck_assert_str_eq(gets(sq, "name"), "capture-test");
    ck_assert_str_eq(gets(sq, "digest"), seq.digest);
    ck_assert_str_eq(gets(get(m, "scene"), "digest"), scene.digest);
    ck_assert_str_eq(gets(get(m, "scene"), "path"), "/seq/box.gltf");
    const cJSON *res = get(m, "resolution");
    ck_assert_int_eq(cJSON_GetArraySize(res), 2);
    ck_assert(cJSON_GetArrayItem(res, 0)->valuedouble == W);
    ck_assert(cJSON_GetArrayItem(res, 1)->valuedouble == H);
    ck_assert(getn(m, "fps") == 8.0);
    ck_assert(getn(m, "frame_count") == 2);
    ck_assert_str_eq(gets(m, "camera"), "Camera");
    const cJSON *st = get(m, "settings");
    ck_assert(getn(st, "shadow_map_size") == 256);
    ck_assert(getn(st, "pcf_radius") == 1);
    ck_assert(getn(st, "shadow_bias") == 0.002); /* shortest form of 0.002f */
    ck_assert(getn(st, "exposure") == 0);
    ck_assert(getn(st, "threads") == 2);
    const cJSON *det = get(m, "determinism");
    ck_assert_str_eq(gets(det, "LP_NATIVE_VECTOR_WIDTH"), "128");
    ck_assert_str_eq(gets(det, "LP_NUM_THREADS"), "2");
    ck_assert_int_eq(cJSON_GetArraySize(det), 2);
    ck_assert_str_eq(gets(get(m, "gl"), "renderer"), "llvmpipe (LLVM 15.0.6, 128 bits)");
    ck_assert(cJSON_IsTrue(get(m, "complete")));

    const cJSON *frames = get(m, "frames");
    ck_assert_int_eq(cJSON_GetArraySize(frames), 2);
    for (int i = 0; i < 2; i++) {
        const cJSON *f = cJSON_GetArrayItem(frames, i);
        ck_assert(getn(f, "index") == i);
        ck_assert(getn(f, "time") == i / 8.0);
        char rel[64];
        snprintf(rel, sizeof rel, "frames/%06d.exr", i);
        ck_assert_str_eq(gets(f, "file"), rel);
        const cJSON *passes = get(f, "passes");
        ck_assert_int_eq(cJSON_GetArraySize(passes), 2);
        ck_assert_str_eq(gets(cJSON_GetArrayItem(passes, 0), "name"), "gbuffer");
        ck_assert(getn(cJSON_GetArrayItem(passes, 0), "ms") == 1.234 + i);
        ck_assert_str_eq(gets(cJSON_GetArrayItem(passes, 1), "name"), "direct");

        fake_frame ff;
        fake_init(&ff, i, W, H);
        const eng_buffer *want[] = {&ff.bpos, &ff.balb, &ff.brad};
        const cJSON *bufs = get(f, "buffers");
        ck_assert_int_eq(cJSON_GetArraySize(bufs), 3);
        for (int b = 0; b < 3; b++) {
            const cJSON *jb = cJSON_GetArrayItem(bufs, b);
            ck_assert_str_eq(gets(jb, "name"), want[b]->name);
            ck_assert(getn(jb, "width") == W);
            ck_assert(getn(jb, "height") == H);
            const cJSON *ch = get(jb, "channels");
            ck_assert_int_eq(cJSON_GetArraySize(ch), 3);
            for (int k = 0; k < 3; k++)
                ck_assert_str_eq(cJSON_GetArrayItem(ch, k)->valuestring, want[b]->channels[k]);
            char dg[40];
            eng_buffer_digest(want[b], dg);
            ck_assert_str_eq(gets(jb, "digest"), dg);
            const cJSON *fn = get(jb, "first_nonfinite");
            if (want[b] == &ff.brad) {
                ck_assert(getn(jb, "nan") == 2);
                ck_assert(getn(jb, "inf") == 1);
                ck_assert(cJSON_IsArray(fn));
                ck_assert(cJSON_GetArrayItem(fn, 0)->valuedouble == 3);
                ck_assert(cJSON_GetArrayItem(fn, 1)->valuedouble == 1);
            } else {
                ck_assert(getn(jb, "nan") == 0);
                ck_assert(getn(jb, "inf") == 0);
                ck_assert(cJSON_IsNull(fn));
            }
        }
        fake_free(&ff);
    }
    cJSON_Delete(m);
    rm_rf(dir);
}
END_TEST

START_TEST(test_finish_needs_every_frame)
{
    char dir[256];
    make_tmpdir(dir);
    seq_sequence seq;
    make_seq(&seq, 2, 8, 8);
    scn_scene scene;
    make_scene(&scene);
    cap_capture *c = make_capture(dir, &seq, &scene, 0);
    eng_listener l = cap_listener(c);
    ck_assert_int_eq(run_frame(&l, 0, 8, 8), 0);
    ck_assert(exists(dir, "frames/000000.exr"));
    eng_error err = {{0}};
    ck_assert_int_eq(cap_finish(c, &err), ENG_ERR_INVALID);
    ck_assert(!exists(dir, "manifest.json"));

    /* A frame outside the sequence is refused. */
    ck_assert_int_ne(l.frame_begin(l.user, 2, 0.25), 0);
    ck_assert_int_eq(cap_status(c, &err), ENG_ERR_INVALID);
    cap_destroy(c);
    rm_rf(dir);
}
END_TEST

START_TEST(test_existing_run)
{
    char dir[256];
    make_tmpdir(dir);
    seq_sequence seq;
    make_seq(&seq, 1, 8, 8);
    scn_scene scene;
    make_scene(&scene);

    /* Unrelated files do not make a run. */
    char p[512];
    snprintf(p, sizeof p, "%s/notes.txt", dir);
    FILE *f = fopen(p, "w");
    ck_assert_ptr_nonnull(f);
    fputs("hello\n", f);
    fclose(f);

    cap_capture *c = make_capture(dir, &seq, &scene, 0);
    eng_listener l = cap_listener(c);
    ck_assert_int_eq(run_frame(&l, 0, 8, 8), 0);
    eng_error err = {{0}};
    ck_assert_int_eq(cap_finish(c, &err), ENG_OK);
    cap_destroy(c);
    ck_assert(exists(dir, "manifest.json"));

    cap_desc d = {0};
    d.run_dir = dir;
    d.sequence = &seq;
    d.scene = &scene;
    c = (cap_capture *)&d; /* must be reset to NULL on failure */
    ck_assert_int_eq(cap_create(&d, &c, &err), ENG_ERR_IO);
    ck_assert_ptr_null(c);
    ck_assert(exists(dir, "manifest.json"));
    ck_assert(exists(dir, "frames/000000.exr"));

    /* Frames alone (a crashed run) are a run too. */
    snprintf(p, sizeof p, "%s/manifest.json", dir);
    ck_assert_int_eq(unlink(p), 0);
    ck_assert(!exists(dir, "manifest.json"));
    ck_assert_int_eq(cap_create(&d, &c, &err), ENG_ERR_IO);
    ck_assert_ptr_null(c);

    /* Overwrite: the old manifest is gone right after create, before any frame. */
    c = make_capture(dir, &seq, &scene, 1);
    ck_assert(!exists(dir, "manifest.json"));
    ck_assert_int_eq(count_suffix(dir, ".tmp"), 0);
    char frames[300];
    snprintf(frames, sizeof frames, "%s/frames", dir);
    ck_assert_int_eq(count_suffix(frames, ".exr"), 0);
    ck_assert(exists(dir, "notes.txt"));
    cap_destroy(c);
    rm_rf(dir);
}
END_TEST

static cap_capture *resume_capture(const char *run, const seq_sequence *s, const scn_scene *sc, eng_result *r,
                                   eng_error *err)
{
    static const char *const det[] = {"LP_NATIVE_VECTOR_WIDTH", "128", "LP_NUM_THREADS", "2", NULL};
    cap_desc d = {0};
    d.run_dir = run;
    d.sequence = s;
    d.scene = sc;
    d.gl_version = "4.5 (Core Profile) Mesa 22.3.6";
    d.gl_renderer = "llvmpipe (LLVM 15.0.6, 128 bits)";
    d.tool_version = "0.1.0";
    d.git_revision = "abc123";
    d.command_line = "ispm record seq.json --out run";
    d.determinism = det;
    d.resume = 1;
    cap_capture *c = (cap_capture *)&d; /* must be reset to NULL on failure */
    *r = cap_create(&d, &c, err);
    if (*r != ENG_OK)
        ck_assert_ptr_null(c);
    return c;
}

/* --resume: frames whose EXR and record both exist are kept and not rendered again; the
 * finished manifest equals an uninterrupted run's; a frame with only one of its two files is
 * rendered again; another sequence, and a complete run, are refused. */
START_TEST(test_resume)
{
    char ref[256], dir[256], frames[300], p[512];
    make_tmpdir(ref);
    make_tmpdir(dir);
    snprintf(frames, sizeof frames, "%s/frames", dir);
    seq_sequence seq;
    make_seq(&seq, 4, 8, 6);
    scn_scene scene;
    make_scene(&scene);
    eng_error err = {{0}};
    eng_result r;

    cap_capture *c = make_capture(ref, &seq, &scene, 0);
    eng_listener l = cap_listener(c);
    for (int i = 0; i < 4; i++)
        ck_assert_int_eq(run_frame(&l, i, 8, 6), 0);
    ck_assert_int_eq(cap_finish(c, &err), ENG_OK);
    cap_destroy(c);

    /* Interrupted after frame 2: no manifest; frame 1 lost its record (killed between the
     * renames) and a temp file of frame 3 lies around. */
    c = make_capture(dir, &seq, &scene, 0);
    ck_assert(exists(dir, "run.json"));
    l = cap_listener(c);
    for (int i = 0; i < 3; i++)
        ck_assert_int_eq(run_frame(&l, i, 8, 6), 0);
    cap_destroy(c);
    ck_assert(!exists(dir, "manifest.json"));
    ck_assert(exists(dir, "frames/000002.json"));
    snprintf(p, sizeof p, "%s/frames/000001.json", dir);
    ck_assert_int_eq(unlink(p), 0);
    snprintf(p, sizeof p, "%s/frames/000003.exr.tmp", dir);
    FILE *f = fopen(p, "w");
    ck_assert_ptr_nonnull(f);
    fclose(f);

    /* Not resumable with another sequence: nothing is touched. */
    seq_sequence other = seq;
    snprintf(other.digest, sizeof other.digest, "ffffffffffffffffffffffffffffffff");
    c = resume_capture(dir, &other, &scene, &r, &err);
    ck_assert_int_eq(r, ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "run.json"));
    ck_assert(exists(dir, "frames/000001.exr"));

    c = resume_capture(dir, &seq, &scene, &r, &err);
    ck_assert_msg(r == ENG_OK, "resume: %s", err.msg);
    ck_assert(cap_frame_done(c, 0));
    ck_assert(!cap_frame_done(c, 1));
    ck_assert(cap_frame_done(c, 2));
    ck_assert(!cap_frame_done(c, 3));
    ck_assert(!exists(dir, "frames/000001.exr"));
    ck_assert_int_eq(count_suffix(frames, ".tmp"), 0);
    ck_assert_int_eq(cap_finish(c, &err), ENG_ERR_INVALID); /* frames 1 and 3 missing */
    l = cap_listener(c);
    ck_assert_int_eq(run_frame(&l, 1, 8, 6), 0);
    ck_assert_int_eq(run_frame(&l, 3, 8, 6), 0);
    ck_assert_int_eq(cap_finish(c, &err), ENG_OK);
    cap_destroy(c);

    /* The resumed run's manifest is the uninterrupted one's (fake timings are fixed). */
    cJSON *a = load_manifest(ref), *b = load_manifest(dir);
    ck_assert(cJSON_Compare(a, b, 1));
    cJSON_Delete(a);
    cJSON_Delete(b);

    /* A complete run is not resumed. */
    c = resume_capture(dir, &seq, &scene, &r, &err);
    ck_assert_int_eq(r, ENG_ERR_INVALID);
    /* Frames without run.json are not a run --resume can continue. */
    snprintf(p, sizeof p, "%s/run.json", ref);
    ck_assert_int_eq(unlink(p), 0);
    snprintf(p, sizeof p, "%s/manifest.json", ref);
    ck_assert_int_eq(unlink(p), 0);
    c = resume_capture(ref, &seq, &scene, &r, &err);
    ck_assert_int_eq(r, ENG_ERR_INVALID);
    /* A folder that holds nothing of a run (killed before run.json) starts a new one. */
    rm_rf(ref);
    c = resume_capture(ref, &seq, &scene, &r, &err);
    ck_assert_msg(r == ENG_OK, "resume of nothing: %s", err.msg);
    ck_assert(exists(ref, "run.json"));
    ck_assert(!cap_frame_done(c, 0));
    cap_destroy(c);
    rm_rf(ref);
    rm_rf(dir);
}
END_TEST

START_TEST(test_overwrite_removes_manifest_first)
{
    char dir[256];
    make_tmpdir(dir);
    seq_sequence seq;
    make_seq(&seq, 1, 8, 8);
    scn_scene scene;
    make_scene(&scene);
    cap_capture *c = make_capture(dir, &seq, &scene, 0);
    eng_listener l = cap_listener(c);
    ck_assert_int_eq(run_frame(&l, 0, 8, 8), 0);
    eng_error err = {{0}};
    ck_assert_int_eq(cap_finish(c, &err), ENG_OK);
    cap_destroy(c);

    /* Leftovers of a crash: temp files of ours are cleaned up too. */
    char p[512];
    snprintf(p, sizeof p, "%s/frames/000007.exr.tmp", dir);
    fclose(fopen(p, "w"));
    snprintf(p, sizeof p, "%s/manifest.json.tmp", dir);
    fclose(fopen(p, "w"));

    c = make_capture(dir, &seq, &scene, 1);
    ck_assert(!exists(dir, "manifest.json"));
    ck_assert(!exists(dir, "manifest.json.tmp"));
    ck_assert(!exists(dir, "frames/000000.exr"));
    ck_assert(!exists(dir, "frames/000007.exr.tmp"));
    l = cap_listener(c);
    ck_assert_int_eq(run_frame(&l, 0, 8, 8), 0);
    ck_assert(!exists(dir, "manifest.json"));
    ck_assert_int_eq(cap_finish(c, &err), ENG_OK);
    ck_assert(exists(dir, "manifest.json"));
    cap_destroy(c);
    rm_rf(dir);
}
END_TEST

static void touch(const char *dir, const char *name)
{
    char p[512];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    FILE *f = fopen(p, "w");
    ck_assert_ptr_nonnull(f);
    fputs("x\n", f);
    fclose(f);
}

static ino_t inode_of(const char *path)
{
    struct stat st;
    ck_assert_int_eq(stat(path, &st), 0);
    return st.st_ino;
}

/* Overwriting a run whose frames/ holds many frame files (or many bytes) sets that folder aside
 * and removes it on a thread (capture.c, set_aside_frames): right after cap_create frames/ is a
 * new, empty folder, and once the new run is finished no set-aside folder is left, also none an
 * earlier, killed run left behind. A frames/ holding anything but frame files, or a few small
 * ones, is cleaned in place as before; a set-aside folder that holds a foreign file keeps it
 * (and stays) while its frame files go. */
START_TEST(test_overwrite_sets_frames_aside)
{
    char dir[256], frames[300], p[512], name[32];
    make_tmpdir(dir);
    snprintf(frames, sizeof frames, "%s/frames", dir);
    seq_sequence seq;
    make_seq(&seq, 2, 8, 8);
    scn_scene scene;
    make_scene(&scene);
    eng_error err = {{0}};
    for (int pass = 0; pass < 4; pass++) {
        if (pass == 1) { /* an earlier run's leftovers: one removable, one with a foreign file */
            snprintf(p, sizeof p, "%s/.frames-removed-old", dir);
            ck_assert_int_eq(mkdir(p, 0777), 0);
            touch(p, "000009.exr");
            touch(p, "000009.json");
            snprintf(p, sizeof p, "%s/.frames-removed-mine", dir);
            ck_assert_int_eq(mkdir(p, 0777), 0);
            touch(p, "000003.exr");
            touch(p, "keep.txt");
        }
        if (pass == 1 || pass == 2) /* many frame files: worth setting aside */
            for (int i = 100; i < 164; i++) {
                snprintf(name, sizeof name, "%06d.%s", i, i % 2 ? "exr" : "json");
                touch(frames, name);
            }
        if (pass == 2)
            touch(frames, "notes.txt"); /* not a frame file: frames/ is cleaned in place */
        ino_t before = pass ? inode_of(frames) : 0;
        cap_capture *c = make_capture(dir, &seq, &scene, pass > 0);
        ck_assert_int_eq(count_suffix(frames, ".exr"), 0);
        ck_assert_int_eq(count_suffix(frames, ".json"), 0);
        if (pass) /* set aside: a new folder; in place: the same one */
            ck_assert_int_eq(inode_of(frames) != before, pass == 1);
        eng_listener l = cap_listener(c);
        ck_assert_int_eq(run_frame(&l, 0, 8, 8), 0);
        ck_assert_int_eq(run_frame(&l, 1, 8, 8), 0);
        ck_assert_int_eq(cap_finish(c, &err), ENG_OK);
        cap_destroy(c);
        ck_assert(exists(dir, "manifest.json"));
        ck_assert_int_eq(count_suffix(frames, ".exr"), 2);
        ck_assert_int_eq(count_suffix(frames, ".json"), 2);
        ck_assert(!exists(dir, ".frames-removed-old"));
        ck_assert_int_eq(count_named(dir, ".frames-removed-", ""), pass > 0 ? 1 : 0);
        if (pass > 0) {
            ck_assert(exists(dir, ".frames-removed-mine/keep.txt"));
            ck_assert(!exists(dir, ".frames-removed-mine/000003.exr"));
        }
        ck_assert_int_eq(exists(frames, "notes.txt"), pass >= 2);
    }
    /* frames/ a link to a folder elsewhere that holds only frame files, many: the link stays,
     * the frames there are removed in place (a link set aside would leave them behind). */
    char elsewhere[256], cmd[1400];
    make_tmpdir(elsewhere);
    char *fr = realpath(frames, NULL);
    ck_assert_ptr_nonnull(fr);
    snprintf(cmd, sizeof cmd, "mv '%s'/* '%s'/ && rmdir '%s' && rm '%s/notes.txt'", fr, elsewhere, fr, elsewhere);
    ck_assert_int_eq(system(cmd), 0);
    free(fr);
    ck_assert_int_eq(symlink(elsewhere, frames), 0);
    for (int i = 100; i < 164; i++) {
        snprintf(name, sizeof name, "%06d.exr", i);
        touch(elsewhere, name);
    }
    cap_capture *c = make_capture(dir, &seq, &scene, 1);
    struct stat st;
    ck_assert_int_eq(lstat(frames, &st), 0);
    ck_assert(S_ISLNK(st.st_mode));
    ck_assert_int_eq(count_suffix(elsewhere, ".exr"), 0);
    cap_destroy(c);
    rm_rf(dir);
    rm_rf(elsewhere);
}
END_TEST

/* Runs one frame in a child whose file-size limit is limit bytes (writes past it fail
 * with EFBIG, the stand-in for a full disk). Exit status 0 when every expectation held,
 * otherwise the number of the failed one. */
static int disk_full_child(const char *run, long limit, int writers)
{
    signal(SIGXFSZ, SIG_IGN);
    struct rlimit rl = {(rlim_t)limit, (rlim_t)limit};
    if (setrlimit(RLIMIT_FSIZE, &rl) != 0)
        return 1;
    seq_sequence seq;
    make_seq(&seq, 1, 64, 48);
    scn_scene scene;
    make_scene(&scene);
    cap_desc d = {0};
    d.run_dir = run;
    d.sequence = &seq;
    d.scene = &scene;
    d.overwrite = 1;
    d.writers = writers;
    cap_capture *c = NULL;
    eng_error err = {{0}};
    eng_result r = cap_create(&d, &c, &err);
    /* The smallest limits already stop run.json, written at create. */
    if (r == ENG_ERR_IO && !c && strstr(err.msg, "run.json") && strstr(err.msg, strerror(EFBIG)))
        return 0;
    if (r != ENG_OK)
        return 2;
    eng_listener l = cap_listener(c);
    /* Written in frame_end, the failure is the callback's; with a writer, it shows at the
     * latest in cap_finish, which must not write a manifest. */
    if (run_frame(&l, 0, 64, 48) == 0 && !writers)
        return 3;
    if (cap_finish(c, &err) == ENG_OK)
        return 6;
    memset(&err, 0, sizeof err);
    if (cap_status(c, &err) != ENG_ERR_IO)
        return 4;
    if (!strstr(err.msg, "frames/000000.exr") || !strstr(err.msg, strerror(EFBIG)))
        return 5;
    cap_destroy(c);
    return 0;
}

START_TEST(test_disk_full)
{
    char dir[256], run[300], frames[320];
    make_tmpdir(dir);
    snprintf(run, sizeof run, "%s/run", dir);
    snprintf(frames, sizeof frames, "%s/frames", run);

    /* The size of the complete frame file, to place limits inside it. Noise-like values
     * keep ZIP from shrinking it to nothing. */
    seq_sequence seq;
    make_seq(&seq, 1, 64, 48);
    scn_scene scene;
    make_scene(&scene);
    cap_capture *c = make_capture(run, &seq, &scene, 0);
    eng_listener l = cap_listener(c);
    ck_assert_int_eq(run_frame(&l, 0, 64, 48), 0);
    cap_destroy(c);
    struct stat st;
    char p[512];
    snprintf(p, sizeof p, "%s/000000.exr", frames);
    ck_assert_int_eq(stat(p, &st), 0);
    long size = (long)st.st_size;
    ck_assert_int_gt(size, 2000);

    const long limits[] = {0, 1, 300, size / 2, size - 1};
    for (size_t i = 0; i < 2 * sizeof limits / sizeof limits[0]; i++) {
        size_t li = i % (sizeof limits / sizeof limits[0]);
        int writers = (int)(i / (sizeof limits / sizeof limits[0])); /* 0, then 1 writer thread */
        fflush(NULL);
        pid_t pid = fork();
        ck_assert_int_ge(pid, 0);
        if (pid == 0)
            _exit(disk_full_child(run, limits[li], writers));
        int status = 0;
        ck_assert_int_eq(waitpid(pid, &status, 0), pid);
        ck_assert_msg(WIFEXITED(status) && WEXITSTATUS(status) == 0,
                      "limit %ld, %d writers: child failed expectation %d", limits[li], writers, WEXITSTATUS(status));
        ck_assert_int_eq(count_suffix(frames, ".exr"), 0);
        ck_assert_int_eq(count_suffix(frames, ".tmp"), 0);
        ck_assert_int_eq(count_suffix(frames, ".json"), 0);
        ck_assert(!exists(run, "manifest.json"));
        ck_assert(!exists(run, "manifest.json.tmp"));
        ck_assert(!exists(run, "run.json.tmp"));
    }
    rm_rf(dir);
}
END_TEST

START_TEST(test_duplicate_buffer_rejected)
{
    char dir[256];
    make_tmpdir(dir);
    seq_sequence seq;
    make_seq(&seq, 1, 4, 4);
    scn_scene scene;
    make_scene(&scene);
    cap_capture *c = make_capture(dir, &seq, &scene, 0);
    eng_listener l = cap_listener(c);
    float *n1 = pattern(4, 4, 3, 0.0f);
    eng_buffer b = {"gbuffer.normal", 4, 4, 3, XYZ, n1};
    ck_assert_int_eq(l.frame_begin(l.user, 0, 0.0), 0);
    ck_assert_int_eq(l.buffer(l.user, 0, &b), 0);
    ck_assert_int_ne(l.buffer(l.user, 0, &b), 0);
    eng_error err = {{0}};
    ck_assert_int_eq(cap_status(c, &err), ENG_ERR_INVALID);
    ck_assert_ptr_nonnull(strstr(err.msg, "gbuffer.normal"));
    eng_frame_stats st = fake_stats(0);
    ck_assert_int_ne(l.frame_end(l.user, &st), 0); /* sticky */
    ck_assert(!exists(dir, "frames/000000.exr"));
    ck_assert_int_eq(cap_finish(c, &err), ENG_ERR_INVALID);
    ck_assert(!exists(dir, "manifest.json"));
    cap_destroy(c);
    free(n1);
    rm_rf(dir);
}
END_TEST

START_TEST(test_bad_buffers_rejected)
{
    char dir[256];
    make_tmpdir(dir);
    seq_sequence seq;
    make_seq(&seq, 1, 4, 4);
    scn_scene scene;
    make_scene(&scene);
    float v[4 * 4 * ENG_MAX_CHANNELS] = {0};
    const char *many[ENG_MAX_CHANNELS + 1];
    for (int i = 0; i <= ENG_MAX_CHANNELS; i++)
        many[i] = "C";
    const char *dup[] = {"X", "Y", "X"};
    eng_buffer bad[] = {
        {"a.zero_channels", 4, 4, 0, XYZ, v},
        {"a.too_many", 4, 4, ENG_MAX_CHANNELS + 1, many, v},
        {"a.dup_channels", 4, 4, 3, dup, v},
        {"a.zero_width", 0, 4, 3, XYZ, v},
        {"a.neg_height", 4, -1, 3, XYZ, v},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        cap_capture *c = make_capture(dir, &seq, &scene, 1);
        eng_listener l = cap_listener(c);
        ck_assert_int_eq(l.frame_begin(l.user, 0, 0.0), 0);
        ck_assert_msg(l.buffer(l.user, 0, &bad[i]) != 0, "%s accepted", bad[i].name);
        eng_error err = {{0}};
        ck_assert_int_eq(cap_status(c, &err), ENG_ERR_INVALID);
        cap_destroy(c);
    }

    /* A frame in which nothing matches the capture patterns has nothing to write. */
    seq.capture_count = 1;
    snprintf(seq.capture[0], sizeof seq.capture[0], "final.*");
    cap_capture *c = make_capture(dir, &seq, &scene, 1);
    eng_listener l = cap_listener(c);
    ck_assert_int_ne(run_frame(&l, 0, 4, 4), 0);
    eng_error err = {{0}};
    ck_assert_int_eq(cap_status(c, &err), ENG_ERR_INVALID);
    ck_assert(!exists(dir, "frames/000000.exr"));
    cap_destroy(c);
    cap_destroy(NULL);
    rm_rf(dir);
}
END_TEST

/* capture_whole_frames for record_fake's runs (0: the static shadow is stored once). */
static int fake_whole_frames;

/* Records `frames` fake frames into run with the given writers and compression. */
static void record_fake(const char *run, int frames, int writers, cap_compression comp)
{
    seq_sequence seq;
    make_seq(&seq, frames, 24, 20);
    seq.settings.capture_whole_frames = fake_whole_frames;
    if (comp != CAP_COMPRESSION_DEFAULT)
        snprintf(seq.settings.capture_compression, sizeof seq.settings.capture_compression, "%s",
                 cap_compression_name(comp));
    scn_scene scene;
    make_scene(&scene);
    static const char *const det[] = {"LP_NUM_THREADS", "2", NULL};
    cap_desc d = {0};
    d.run_dir = run;
    d.sequence = &seq;
    d.scene = &scene;
    d.tool_version = "0.1.0";
    d.git_revision = "abc123";
    d.determinism = det;
    d.overwrite = 1;
    d.writers = writers;
    d.queue_depth = 1;
    cap_capture *c = NULL;
    eng_error err = {{0}};
    ck_assert_msg(cap_create(&d, &c, &err) == ENG_OK, "cap_create: %s", err.msg);
    eng_listener l = cap_listener(c);
    for (int f = 0; f < frames; f++)
        ck_assert_int_eq(run_frame(&l, f, 24, 20), 0);
    ck_assert_msg(cap_finish(c, &err) == ENG_OK, "cap_finish: %s", err.msg);
    cap_destroy(c);
}

static char *slurp(const char *dir, const char *name, size_t *len)
{
    char p[600];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    char *text = NULL;
    eng_error err = {{0}};
    ck_assert_msg(eng_read_file(p, 1 << 26, &text, len, &err) == ENG_OK, "%s", err.msg);
    return text;
}

/* Every file of the run a is byte-identical in run b. */
static void assert_same_files(const char *a, const char *b, int frames)
{
    for (int f = -1; f < frames; f++) {
        for (int k = 0; k < 2; k++) {
            char name[64];
            if (f < 0)
                snprintf(name, sizeof name, k ? "run.json" : "manifest.json");
            else
                snprintf(name, sizeof name, "frames/%06d.%s", f, k ? "json" : "exr");
            size_t la = 0, lb = 0;
            char *x = slurp(a, name, &la), *y = slurp(b, name, &lb);
            ck_assert_msg(la == lb && memcmp(x, y, la) == 0, "%s differs between %s and %s", name, a, b);
            free(x);
            free(y);
        }
    }
}

/* Issue 22: frames written by writer threads are the same bytes as frames written in
 * frame_end, whatever the number of writers (and the frame EXR's pixels whatever the
 * lossless compression). */
START_TEST(test_writers_same_bytes)
{
    char dir[256], ref[300], run[300];
    make_tmpdir(dir);
    snprintf(ref, sizeof ref, "%s/sync", dir);
    record_fake(ref, 5, 0, CAP_COMPRESSION_DEFAULT);
    for (int writers = 1; writers <= 3; writers += 2) {
        snprintf(run, sizeof run, "%s/w%d", dir, writers);
        record_fake(run, 5, writers, CAP_COMPRESSION_DEFAULT);
        assert_same_files(ref, run, 5);
    }
    rm_rf(dir);
}
END_TEST

/* The dedupe decision: same name, digest, size and channels → where the previous frame has it;
 * a reference is never chained; a frame file is never empty. */
START_TEST(test_dedupe_decision)
{
    static char *ch_rgb[] = {"R", "G", "B"}, *ch_y[] = {"Y"};
    cap_bufrec prev[3] = {
        {.name = "shadow.light0", .width = 4, .height = 4, .channel_count = 1, .digest = "aa", .stored_in = -1},
        {.name = "gbuffer.normal", .width = 4, .height = 4, .channel_count = 3, .digest = "bb", .stored_in = 2},
        {.name = "final.display", .width = 4, .height = 4, .channel_count = 3, .digest = "cc", .stored_in = -1},
    };
    prev[0].channels[0] = ch_y[0];
    for (int k = 0; k < 3; k++)
        prev[1].channels[k] = prev[2].channels[k] = ch_rgb[k];
    cap_bufrec cur[4];
    memcpy(cur, prev, sizeof prev);
    cur[3] = (cap_bufrec){.name = "new.buffer", .width = 4, .height = 4, .channel_count = 1, .digest = "dd"};
    cur[3].channels[0] = ch_y[0];
    snprintf(cur[2].digest, sizeof cur[2].digest, "ce"); /* changed */
    ck_assert_int_eq(cap__dedupe_frame(prev, 3, 5, cur, 4), 2);
    ck_assert_int_eq(cur[0].stored_in, 5);  /* held by frame 5 itself */
    ck_assert_int_eq(cur[1].stored_in, 2);  /* frame 5 refers to 2: so does this one, no chain */
    ck_assert_int_eq(cur[2].stored_in, -1); /* changed */
    ck_assert_int_eq(cur[3].stored_in, -1); /* not in the previous frame */
    /* Same digest but other channel names or size: stored. */
    memcpy(cur, prev, sizeof prev);
    static char *ch_xyz[] = {"X", "Y", "Z"};
    for (int k = 0; k < 3; k++)
        cur[1].channels[k] = ch_xyz[k];
    cur[0].width = 8;
    ck_assert_int_eq(cap__dedupe_frame(prev, 3, 5, cur, 3), 2);
    ck_assert_int_eq(cur[0].stored_in, -1);
    ck_assert_int_eq(cur[1].stored_in, -1);
    ck_assert_int_eq(cur[2].stored_in, 5);
    /* Everything the same: the first buffer stays in the file; no previous frame: all stored. */
    memcpy(cur, prev, sizeof prev);
    ck_assert_int_eq(cap__dedupe_frame(prev, 3, 5, cur, 3), 1);
    ck_assert_int_eq(cur[0].stored_in, -1);
    ck_assert_int_eq(cur[1].stored_in, 2);
    ck_assert_int_eq(cur[2].stored_in, 5);
    ck_assert_int_eq(cap__dedupe_frame(NULL, 0, -1, cur, 3), 3);
    /* The manifest's names of frame files, and nothing else. */
    int f = -1;
    ck_assert(cap__parse_frame_rel("frames/000012.exr", &f) && f == 12);
    ck_assert(!cap__parse_frame_rel("frames/12.exr", &f));
    ck_assert(!cap__parse_frame_rel("frames/000012.exr.tmp", &f));
    ck_assert(!cap__parse_frame_rel("../frames/000012.exr", &f));
    ck_assert(!cap__parse_frame_rel("frames/-00001.exr", &f));
}
END_TEST

/* A static buffer is stored once within the run: frame files after the first leave it out and
 * their records say where it is; with capture_whole_frames every file holds every buffer. The
 * files are the same bytes whatever the number of writers (test_writers_same_bytes). */
START_TEST(test_dedupe_run)
{
    char dir[256], run[300], whole[300];
    make_tmpdir(dir);
    snprintf(run, sizeof run, "%s/run", dir);
    snprintf(whole, sizeof whole, "%s/whole", dir);
    record_fake(run, 3, 1, CAP_COMPRESSION_DEFAULT);
    fake_whole_frames = 1;
    record_fake(whole, 3, 1, CAP_COMPRESSION_DEFAULT);
    fake_whole_frames = 0;
    for (int f = 0; f < 3; f++) {
        char p[400];
        rd_part *a = NULL, *b = NULL;
        snprintf(p, sizeof p, "%s/frames/%06d.exr", run, f);
        int na = read_exr(p, &a);
        snprintf(p, sizeof p, "%s/frames/%06d.exr", whole, f);
        int nb = read_exr(p, &b);
        ck_assert_int_eq(na, f == 0 ? 4 : 3);
        ck_assert_int_eq(nb, 4);
        for (int i = 0; i < na; i++)
            ck_assert(f == 0 || strcmp(a[i].name, "shadow.light0") != 0);
        free_parts(a, na);
        free_parts(b, nb);
    }
    cJSON *man = load_manifest(run), *wm = load_manifest(whole);
    ck_assert(cJSON_IsTrue(get(get(man, "capture"), "dedupe")));
    ck_assert(cJSON_IsFalse(get(get(wm, "capture"), "dedupe")));
    cJSON *frames = get(man, "frames"), *wframes = get(wm, "frames");
    for (int f = 0; f < 3; f++) {
        cJSON *bufs = get(cJSON_GetArrayItem(frames, f), "buffers");
        cJSON *wbufs = get(cJSON_GetArrayItem(wframes, f), "buffers");
        for (int i = 0; i < cJSON_GetArraySize(bufs); i++) {
            cJSON *b = cJSON_GetArrayItem(bufs, i), *w = cJSON_GetArrayItem(wbufs, i);
            ck_assert_str_eq(gets(b, "digest"), gets(w, "digest"));
            ck_assert(!cJSON_GetObjectItemCaseSensitive(w, "stored_in"));
            cJSON *in = cJSON_GetObjectItemCaseSensitive(b, "stored_in");
            if (f > 0 && strcmp(gets(b, "name"), "shadow.light0") == 0)
                ck_assert_str_eq(in ? in->valuestring : "", "frames/000000.exr");
            else
                ck_assert_ptr_null(in);
        }
    }
    cJSON_Delete(man);
    cJSON_Delete(wm);
    rm_rf(dir);
}
END_TEST

START_TEST(test_compression)
{
    cap_compression m = CAP_COMPRESSION_DEFAULT;
    const char *names[] = {"none", "rle", "zips", "zip", "piz", "by-kind"};
    enum { NC = 6 };
    for (int i = 0; i < NC; i++) {
        ck_assert(cap_compression_parse(names[i], &m));
        ck_assert_int_eq(m, CAP_COMPRESSION_NONE + i);
        ck_assert_str_eq(cap_compression_name(m), names[i]);
    }
    ck_assert_str_eq(cap_compression_name(CAP_COMPRESSION_DEFAULT), "by-kind"); /* record's default */
    /* by-kind's table: ZIP level 1 for the kinds that shrink cheaply, none for the rest. */
    static const char *const zip1[] = {"gbuffer.material", "gbuffer.motion", "gbuffer.normal", "gbuffer.depth",
                                       "splat.count", "gather.tile_count", "lightgbuffer.light0.face2.normal",
                                       "bounce.light1", "photons.map"};
    static const char *const none[] = {"gbuffer.position", "gbuffer.albedo", "direct.radiance", "final.display",
                                       "shadow.light0", "composite.radiance", "splat.indirect"};
    for (size_t i = 0; i < sizeof zip1 / sizeof zip1[0]; i++) {
        int level = -1;
        ck_assert_msg(cap_compression_for(zip1[i], &level) == CAP_COMPRESSION_ZIP && level == 1, "%s", zip1[i]);
    }
    for (size_t i = 0; i < sizeof none / sizeof none[0]; i++) {
        int level = -1;
        ck_assert_msg(cap_compression_for(none[i], &level) == CAP_COMPRESSION_NONE && level == 0, "%s", none[i]);
    }
    m = CAP_COMPRESSION_RLE;
    ck_assert(!cap_compression_parse("b44", &m)); /* lossy for floats: refused */
    ck_assert(!cap_compression_parse("ZIP", &m));
    ck_assert(!cap_compression_parse("", &m));
    ck_assert(!cap_compression_parse(NULL, &m));
    ck_assert_int_eq(m, CAP_COMPRESSION_RLE);

    /* The sequence accepts exactly the names capture knows (settings.def lists them). */
    const eng_setting *d = eng_setting_find("capture_compression");
    ck_assert_ptr_nonnull(d);
    ck_assert_int_eq(d->name_count, NC);
    for (int i = 0; i < d->name_count; i++) {
        ck_assert(cap_compression_parse(d->names[i].name, &m));
        ck_assert_str_eq(d->names[i].name, names[i]);
    }
    ck_assert_str_eq(d->def_name, cap_compression_name(CAP_COMPRESSION_DEFAULT));

    const char *fmt = "{\"scene\": \"x.gltf\", \"frames\": 1, \"fps\": 1, \"resolution\": [4, 4], "
                      "\"camera\": {\"node\": \"C\"}, \"settings\": {\"capture_compression\": %s}}";
    const char *values[] = {"\"piz\"", "\"none\"", "\"dwaa\"", "\"pxr24\"", "3", "null"};
    const eng_result want[] = {ENG_OK, ENG_OK, ENG_ERR_INVALID, ENG_ERR_INVALID, ENG_ERR_INVALID, ENG_ERR_INVALID};
    for (int i = 0; i < 6; i++) {
        char json[512];
        snprintf(json, sizeof json, fmt, values[i]);
        seq_sequence q;
        eng_error err = {{0}};
        eng_result r = seq_parse("/d/s.json", json, strlen(json), &q, &err);
        ck_assert_msg(r == want[i], "%s: %s", values[i], err.msg);
        if (r != ENG_OK)
            ck_assert_msg(strstr(err.msg, "capture_compression") && strstr(err.msg, "/d/s.json"), "%s", err.msg);
    }

    /* Each compression decodes to the announced bits; the manifests' digests are the same. */
    char dir[256], run[300], path[400];
    make_tmpdir(dir);
    long size[NC];
    char *digests[NC];
    for (int i = 0; i < NC; i++) {
        snprintf(run, sizeof run, "%s/%s", dir, names[i]);
        record_fake(run, 1, 1, (cap_compression)(CAP_COMPRESSION_NONE + i));
        snprintf(path, sizeof path, "%s/frames/000000.exr", run);
        struct stat st;
        ck_assert_int_eq(stat(path, &st), 0);
        size[i] = (long)st.st_size;
        rd_part *parts = NULL;
        int n = read_exr(path, &parts);
        ck_assert_int_eq(n, 4);
        fake_frame f;
        fake_init(&f, 0, 24, 20);
        if (i == NC - 1) /* by-kind: none for every one of these kinds */
            for (int k = 0; k < n; k++)
                ck_assert_int_eq(parts[k].compression, EXR_COMPRESSION_NONE);
        assert_part_equals(&parts[0], &f.bpos);
        assert_part_equals(&parts[2], &f.balb);
        assert_part_equals(&parts[3], &f.brad);
        fake_free(&f);
        free_parts(parts, n);
        cJSON *man = load_manifest(run);
        ck_assert_str_eq(gets(get(man, "capture"), "compression"), names[i]);
        cJSON *frames = get(man, "frames");
        digests[i] = cJSON_PrintUnformatted(get(cJSON_GetArrayItem(frames, 0), "buffers"));
        cJSON_Delete(man);
        if (i)
            ck_assert_str_eq(digests[i], digests[0]);
    }
    ck_assert_int_lt(size[3], size[0]); /* zip < none */
    for (int i = 0; i < NC; i++)
        free(digests[i]);
    rm_rf(dir);
}
END_TEST

/* record writes frame files by kind of buffer by default (capture_compression "by-kind"); ispm bless
 * recompresses them to zip with cap_recompress_exr: same parts, order, attributes and bits, only the compression changes. */
START_TEST(test_recompress)
{
    char dir[256], run[300], src[400], zip[400], back[400], again[400];
    make_tmpdir(dir);
    snprintf(run, sizeof run, "%s/run", dir);
    fake_whole_frames = 1; /* frame 1's file holds every buffer */
    record_fake(run, 2, 1, CAP_COMPRESSION_RLE);
    fake_whole_frames = 0;
    snprintf(src, sizeof src, "%s/frames/000001.exr", run);
    snprintf(zip, sizeof zip, "%s/zip.exr", dir);
    snprintf(back, sizeof back, "%s/back.exr", dir);
    snprintf(again, sizeof again, "%s/again.exr", dir);
    cJSON *man = load_manifest(run);
    ck_assert_str_eq(gets(get(man, "capture"), "compression"), "rle");
    cJSON_Delete(man);

    eng_error err = {{0}};
    int rewritten = -1;
    ck_assert_msg(cap_recompress_exr(src, zip, CAP_COMPRESSION_ZIP, &rewritten, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(rewritten, 1);
    ck_assert_int_eq(count_suffix(dir, ".tmp"), 0);
    rd_part *a = NULL, *z = NULL;
    int na = read_exr(src, &a), nz = read_exr(zip, &z);
    ck_assert_int_eq(na, 4);
    ck_assert_int_eq(nz, 4);
    fake_frame f;
    fake_init(&f, 1, 24, 20);
    const eng_buffer *order[] = {&f.bpos, &f.bshadow, &f.balb, &f.brad};
    for (int i = 0; i < 4; i++) {
        ck_assert_int_eq(a[i].compression, EXR_COMPRESSION_RLE);
        ck_assert_int_eq(z[i].compression, EXR_COMPRESSION_ZIP);
        assert_part_equals(&z[i], order[i]); /* names, order, channels, bits, digest */
        ck_assert_int_eq(z[i].frame, 1);
        ck_assert(z[i].time == a[i].time);
        ck_assert_mem_eq(&z[i].display, &a[i].display, sizeof z[i].display);
        ck_assert_int_eq(z[i].lineorder, a[i].lineorder);
    }
    fake_free(&f);
    free_parts(a, na);
    free_parts(z, nz);
    struct stat sr, sz;
    ck_assert_int_eq(stat(src, &sr), 0);
    ck_assert_int_eq(stat(zip, &sz), 0);
    ck_assert_int_lt(sz.st_size, sr.st_size);

    /* Already zip: nothing written. */
    ck_assert_int_eq(cap_recompress_exr(zip, again, CAP_COMPRESSION_ZIP, &rewritten, &err), ENG_OK);
    ck_assert_int_eq(rewritten, 0);
    ck_assert_int_ne(stat(again, &sz), 0);
    /* Back to rle: the very bytes capture wrote (every attribute carried over as it was). */
    ck_assert_msg(cap_recompress_exr(zip, back, CAP_COMPRESSION_RLE, &rewritten, &err) == ENG_OK, "%s", err.msg);
    ck_assert_int_eq(rewritten, 1);
    size_t l1 = 0, l2 = 0;
    char *x = slurp(run, "frames/000001.exr", &l1), *y = slurp(dir, "back.exr", &l2);
    ck_assert_msg(l1 == l2 && memcmp(x, y, l1) == 0, "rle -> zip -> rle changed the file");
    free(x);
    free(y);

    /* A missing or non-EXR source: an I/O error naming it; the target left alone. */
    char missing[400];
    snprintf(missing, sizeof missing, "%s/missing.exr", dir);
    ck_assert_int_eq(cap_recompress_exr(missing, again, CAP_COMPRESSION_ZIP, &rewritten, &err), ENG_ERR_IO);
    ck_assert_msg(strstr(err.msg, missing), "%s", err.msg);
    char manifest[400];
    snprintf(manifest, sizeof manifest, "%s/manifest.json", run);
    ck_assert_int_eq(cap_recompress_exr(manifest, again, CAP_COMPRESSION_ZIP, &rewritten, &err), ENG_ERR_IO);
    ck_assert_msg(strstr(err.msg, manifest), "%s", err.msg);
    ck_assert_int_eq(rewritten, 0);
    ck_assert_int_ne(stat(again, &sz), 0);
    /* An unwritable target: the write's error, no temp file left. */
    char nodir[400];
    snprintf(nodir, sizeof nodir, "%s/no/such/dir.exr", dir);
    ck_assert_int_eq(cap_recompress_exr(src, nodir, CAP_COMPRESSION_ZIP, &rewritten, &err), ENG_ERR_IO);
    ck_assert_msg(strstr(err.msg, "no/such/dir.exr"), "%s", err.msg);
    ck_assert_int_eq(count_suffix(dir, ".tmp"), 0);
    rm_rf(dir);
}
END_TEST

/* eng_buffer_nonfinite (what the capture records per buffer, and replay per run buffer) gives
 * the per-value loop's counts and first pixel, whatever the length (blocks of 16 and a tail),
 * the channel count and the kind: quiet and signalling NaN of either sign and any payload,
 * either infinity, beside the largest finite values and subnormals, which are not counted. */
static void nonfinite_reference(const eng_buffer *b, uint64_t *nn, uint64_t *ni, int *fx, int *fy)
{
    *nn = *ni = 0;
    *fx = *fy = -1;
    for (int y = 0; y < b->height; y++)
        for (int x = 0; x < b->width; x++)
            for (int c = 0; c < b->channel_count; c++) {
                float v = b->data[((size_t)y * (size_t)b->width + (size_t)x) * (size_t)b->channel_count + (size_t)c];
                if (!isfinite(v)) {
                    if (isnan(v))
                        (*nn)++;
                    else
                        (*ni)++;
                    if (*fx < 0) {
                        *fx = x;
                        *fy = y;
                    }
                }
            }
}

START_TEST(test_nonfinite_counts)
{
    const uint32_t bad[] = {0x7f800000u, 0xff800000u, 0x7fc00000u, 0xffc00000u,
                            0x7f800001u, 0xffffffffu, 0x7fbfffffu, 0x7fffffffu};
    const uint32_t good[] = {0x7f7fffffu, 0xff7fffffu, 0x00000001u, 0x80000001u,
                             0x007fffffu, 0x00000000u, 0x80000000u, 0x3f800000u};
    static const char *names[] = {"R", "G", "B", "A"};
    uint32_t seed = 12345u;
    int checked = 0;
    for (int w = 1; w <= 41; w += 4)
        for (int h = 1; h <= 3; h++)
            for (int ch = 1; ch <= 4; ch++) {
                size_t n = (size_t)w * (size_t)h * (size_t)ch;
                float *data = malloc(n * sizeof *data);
                ck_assert_ptr_nonnull(data);
                eng_buffer b = {"t", w, h, ch, names, data};
                /* none, then one at each place (first, inside, the last value: the tail), then several */
                for (int trial = 0; trial < 6; trial++) {
                    for (size_t i = 0; i < n; i++) {
                        seed = seed * 1664525u + 1013904223u;
                        uint32_t u = good[seed >> 29];
                        memcpy(&data[i], &u, sizeof u);
                    }
                    size_t at[3] = {0, n / 2, n - 1};
                    int put = trial == 0 ? 0 : trial <= 3 ? 1 : 3;
                    for (int k = 0; k < put; k++) {
                        seed = seed * 1664525u + 1013904223u;
                        uint32_t u = bad[seed >> 29];
                        size_t i = put == 1 ? at[trial - 1] : at[k];
                        memcpy(&data[i], &u, sizeof u);
                    }
                    uint64_t nn, ni, rn, ri;
                    int fx, fy, rx, ry;
                    eng_buffer_nonfinite(&b, &nn, &ni, &fx, &fy);
                    nonfinite_reference(&b, &rn, &ri, &rx, &ry);
                    ck_assert_uint_eq(nn, rn);
                    ck_assert_uint_eq(ni, ri);
                    ck_assert_int_eq(fx, rx);
                    ck_assert_int_eq(fy, ry);
                    if (trial == 0)
                        ck_assert_uint_eq(nn + ni, 0);
                    else
                        ck_assert_uint_ge(nn + ni, 1);
                    checked++;
                }
                free(data);
            }
    ck_assert_int_eq(checked, 11 * 3 * 4 * 6);
}
END_TEST

/* cap_display_warning: all black (every channel under half an 8-bit step), clipped (over 5%
 * of the pixels at 8-bit white in every channel), and neither at the limits. */
START_TEST(test_display_warning)
{
    static const char *const ch[] = {"R", "G", "B"};
    enum { W = 10, H = 10 };
    static float px[W * H * 3];
    eng_buffer b = {"final.display", W, H, 3, ch, px};
    char msg[CAP_DISPLAY_WARNING_MAX];
    memset(px, 0, sizeof px);
    px[5] = 0.4f / 255.0f; /* under half a step: still black */
    ck_assert_int_eq(cap_display_warning(&b, msg, sizeof msg), 1);
    ck_assert_msg(strstr(msg, "all black") && !strchr(msg, '\n'), "%s", msg);
    px[5] = 1.0f / 255.0f; /* one pixel lit: not black */
    ck_assert_int_eq(cap_display_warning(&b, msg, sizeof msg), 0);
    ck_assert_str_eq(msg, "");
    for (int i = 10; i < 20; i++) /* 10 saturated red pixels: a colour, not white */
        px[3 * i] = 1.0f;
    ck_assert_int_eq(cap_display_warning(&b, msg, sizeof msg), 0);
    for (int i = 30; i < 35; i++) /* 5 of 100 pixels white: exactly 5%, no warning */
        px[3 * i] = px[3 * i + 1] = px[3 * i + 2] = i == 34 ? 0.99999994f : 1.0f;
    ck_assert_int_eq(cap_display_warning(&b, msg, sizeof msg), 0);
    px[3 * 40] = px[3 * 40 + 1] = px[3 * 40 + 2] = 1.0f; /* 6%: a warning that says how many */
    ck_assert_int_eq(cap_display_warning(&b, msg, sizeof msg), 1);
    ck_assert_msg(strstr(msg, "6.0% of its pixels clipped"), "%s", msg);
}
END_TEST

static Suite *capture_suite(void)
{
    Suite *s = suite_create("capture");
    TCase *exr = tcase_create("exr");
    tcase_add_test(exr, test_exr_roundtrip);
    tcase_add_test(exr, test_exr_single_part_keeps_name);
    tcase_add_test(exr, test_exr_unsynced_same_bytes);
    tcase_add_test(exr, test_exr_zip_same_size_chunk);
    tcase_add_test(exr, test_exr_rejects_bad_input);
    tcase_add_test(exr, test_nonfinite_counts);
    tcase_add_test(exr, test_display_warning);
    suite_add_tcase(s, exr);
    TCase *run = tcase_create("run");
    tcase_add_test(run, test_listener_full_flow);
    tcase_add_test(run, test_finish_needs_every_frame);
    tcase_add_test(run, test_existing_run);
    tcase_add_test(run, test_resume);
    tcase_add_test(run, test_overwrite_removes_manifest_first);
    tcase_add_test(run, test_overwrite_sets_frames_aside);
    tcase_add_test(run, test_disk_full);
    tcase_add_test(run, test_duplicate_buffer_rejected);
    tcase_add_test(run, test_bad_buffers_rejected);
    tcase_add_test(run, test_writers_same_bytes);
    tcase_add_test(run, test_dedupe_decision);
    tcase_add_test(run, test_dedupe_run);
    tcase_add_test(run, test_compression);
    tcase_add_test(run, test_recompress);
    suite_add_tcase(s, run);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(capture_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed == 0 ? EXIT_SUCCESS : EXIT_FAILURE;
}
