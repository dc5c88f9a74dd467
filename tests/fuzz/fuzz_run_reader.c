/* fuzz_run_reader.c — libFuzzer target for replay's readers of files it did not write: the
 * run manifest (rep_run_open + rep_run_read_frame, replay/run/run.c), tolerance files
 * (rep_tol_parse, replay/compare/tolerance.c) and frame EXRs (rep_read_parts: the OpenEXR C reader,
 * exr_read.c, then the OpenImageIO shim for what it leaves). A golden is read by the same code
 * as a run, so this covers goldens too.
 *
 * The first input byte picks the reader (mod 3) and the rest is the file:
 *   0  manifest.json of a run folder made once per process in a temp folder, which also holds
 *      frames/000000.exr, a fixed two-part frame ("a.rgb" 4x3 R,G,B and "b.z" 2x2 Z), so a
 *      manifest that names it gets past the existence check into decoding and the per-part
 *      checks (names, sizes, channel sets, digests, non-finite counts); the same bytes first
 *      as a live recording's run.json and frame record (rep_run_open_live);
 *   1  tolerances.json, then a lookup for a few buffer names;
 *   2  an EXR file, decoded with the same float limit replay uses.
 * Every failure must leave a one-line, non-empty message. With FUZZ_RUN_READER_SEED=DIR set,
 * initialisation also writes DIR/manifest (a valid mode-0 input describing the fixed frame)
 * and DIR/exr (mode 2: the fixed frame's bytes); smoke.sh makes the seed corpus that way.
 *
 * OpenEXR and OpenImageIO are Debian's uninstrumented builds: libFuzzer gets no coverage
 * inside them, so mode 2 mostly tests the shim's guards around them; a long run is still
 * worth it, because ASan intercepts their allocations and memory accesses through ours. */
#define _POSIX_C_SOURCE 200809L
#include "rep_compare.h"
#include "rep_run.h"
#include "rep_util.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static char run_dir[64];
static char *manifest_path, *exr_path;

static void check_message(const eng_error *err)
{
    size_t n = strnlen(err->msg, sizeof err->msg);
    if (n == 0 || n == sizeof err->msg || memchr(err->msg, '\n', n))
        abort();
}

static void cleanup(void)
{
    if (run_dir[0]) {
        eng_error err;
        (void)rep_remove_tree(run_dir, &err);
    }
}

/* Writes path or ends the process: the target cannot run without its fixture. */
static void write_file(const char *path, const void *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    if (!f || (len && fwrite(data, 1, len, f) != len) || fclose(f) != 0) {
        fprintf(stderr, "fuzz_run_reader: cannot write %s\n", path);
        exit(1);
    }
}

/* A manifest that describes the fixed frame exactly. */
static char *seed_manifest(const eng_buffer *bufs, int count)
{
    rep_sb sb = {0};
    rep_sb_printf(&sb, "{\"format\": \"ispm-run\", \"format_version\": 1, \"resolution\": [4, 3], "
                       "\"frame_count\": 1, \"frames\": [{\"index\": 0, \"time\": 0, "
                       "\"file\": \"frames/000000.exr\", \"buffers\": [");
    for (int i = 0; i < count; i++) {
        char dg[40];
        eng_buffer_digest(&bufs[i], dg);
        rep_sb_printf(&sb, "%s{\"name\": \"%s\", \"width\": %d, \"height\": %d, \"channels\": [", i ? ", " : "",
                      bufs[i].name, bufs[i].width, bufs[i].height);
        for (int c = 0; c < bufs[i].channel_count; c++)
            rep_sb_printf(&sb, "%s\"%s\"", c ? ", " : "", bufs[i].channels[c]);
        rep_sb_printf(&sb, "], \"digest\": \"%s\", \"nan\": 0, \"inf\": 0}", dg);
    }
    rep_sb_printf(&sb, "]}], \"complete\": true}\n");
    return sb.s;
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc;
    (void)argv;
    snprintf(run_dir, sizeof run_dir, "/tmp/fuzz_run_reader.XXXXXX");
    if (!mkdtemp(run_dir)) {
        perror("fuzz_run_reader: mkdtemp");
        exit(1);
    }
    atexit(cleanup);
    manifest_path = rep_path_join(run_dir, "manifest.json");
    exr_path = rep_path_join(run_dir, "input.exr");
    char *frames = rep_path_join(run_dir, "frames");
    eng_error err = {{0}};
    if (rep_mkdirs(frames, &err) != ENG_OK) {
        fprintf(stderr, "fuzz_run_reader: %s\n", err.msg);
        exit(1);
    }
    static const char *const rgb[] = {"R", "G", "B"}, *const z[] = {"Z"};
    static float a[4 * 3 * 3], b[2 * 2];
    for (size_t i = 0; i < sizeof a / sizeof a[0]; i++)
        a[i] = (float)i * 0.25f - 1.0f;
    for (size_t i = 0; i < sizeof b / sizeof b[0]; i++)
        b[i] = (float)i + 0.5f;
    const eng_buffer bufs[2] = {{"a.rgb", 4, 3, 3, rgb, a}, {"b.z", 2, 2, 1, z, b}};
    char *frame = rep_path_join(frames, "000000.exr");
    if (rep_oiio_write_parts(frame, bufs, 2, &err) != ENG_OK) {
        fprintf(stderr, "fuzz_run_reader: %s\n", err.msg);
        exit(1);
    }
    const char *seed = getenv("FUZZ_RUN_READER_SEED");
    if (seed && seed[0]) {
        char *text = seed_manifest(bufs, 2);
        size_t n = strlen(text);
        char *doc = rep_xmalloc(n + 1);
        doc[0] = 0; /* mode 0 */
        memcpy(doc + 1, text, n);
        char *out = rep_path_join(seed, "manifest");
        write_file(out, doc, n + 1);
        free(out);
        free(doc);
        free(text);
        char *bytes = NULL;
        size_t len = 0;
        if (eng_read_file(frame, (size_t)1 << 24, &bytes, &len, &err) != ENG_OK) {
            fprintf(stderr, "fuzz_run_reader: %s\n", err.msg);
            exit(1);
        }
        doc = rep_xmalloc(len + 1);
        doc[0] = 2; /* mode 2 */
        memcpy(doc + 1, bytes, len);
        out = rep_path_join(seed, "exr");
        write_file(out, doc, len + 1);
        free(out);
        free(doc);
        free(bytes);
    }
    free(frame);
    free(frames);
    return 0;
}

/* The same bytes as a recording in progress's run.json and frame 0's record (rep_run_open_live,
 * rep_run_refresh: the viewer's live view reads them). */
static void fuzz_live(const uint8_t *data, size_t size)
{
    unlink(manifest_path);
    char *info = rep_path_join(run_dir, "run.json"), *rec = rep_path_join(run_dir, "frames/000000.json");
    write_file(info, data, size);
    write_file(rec, data, size);
    rep_run *run = NULL;
    eng_error err = {{0}};
    if (rep_run_open_live(run_dir, &run, &err) != ENG_OK) {
        if (run)
            abort();
        check_message(&err);
    } else {
        int added;
        if (rep_run_refresh(run, &added, &err) != ENG_OK)
            check_message(&err);
        rep_run_close(run);
    }
    unlink(info);
    unlink(rec);
    free(info);
    free(rec);
}

static void fuzz_manifest(const uint8_t *data, size_t size)
{
    fuzz_live(data, size);
    write_file(manifest_path, data, size);
    rep_run *run = NULL;
    eng_error err = {{0}};
    if (rep_run_open(run_dir, &run, &err) != ENG_OK) {
        if (run)
            abort();
        check_message(&err);
        return;
    }
    for (int i = 0; i < run->frame_count && i < 4; i++) {
        rep_part *parts = NULL;
        if (rep_run_read_frame(run, i, &parts, &err) != ENG_OK) {
            if (parts)
                abort();
            check_message(&err);
            continue;
        }
        rep_parts_free(parts, run->frames[i].buffer_count);
    }
    rep_run_close(run);
}

static void fuzz_tolerances(const uint8_t *data, size_t size)
{
    rep_tolerances *t = NULL;
    eng_error err = {{0}};
    if (rep_tol_parse("/nonexistent/tolerances.json", (const char *)data, size, &t, &err) != ENG_OK) {
        check_message(&err);
        return;
    }
    static const char *const names[] = {"gbuffer.depth", "shadow.light0.face3", "final.display", ""};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        rep_tol tol;
        if (!rep_tol_lookup(t, names[i], &tol))
            abort();
    }
    rep_tol_free(t);
}

static void fuzz_exr(const uint8_t *data, size_t size)
{
    write_file(exr_path, data, size);
    rep_part *parts = NULL;
    int count = 0;
    eng_error err = {{0}};
    if (rep_read_parts(exr_path, REP_MAX_FLOATS, &parts, &count, &err) != ENG_OK) {
        if (parts || count)
            abort();
        check_message(&err);
        return;
    }
    for (int i = 0; i < count; i++) {
        const rep_part *p = &parts[i];
        if (!p->name || p->width < 1 || p->height < 1 || p->channel_count < 1 ||
            p->channel_count > ENG_MAX_CHANNELS || !p->data)
            abort();
        eng_buffer b = rep_part_buffer(p);
        char dg[40];
        eng_buffer_digest(&b, dg);
    }
    rep_parts_free(parts, count);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    switch (data[0] % 3) {
    case 0: fuzz_manifest(data + 1, size - 1); break;
    case 1: fuzz_tolerances(data + 1, size - 1); break;
    default: fuzz_exr(data + 1, size - 1); break;
    }
    return 0;
}
