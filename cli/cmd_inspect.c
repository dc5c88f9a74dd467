/* cmd_inspect.c — looking into a run without replaying it:
 *   `ispm info RUN`: frames, buffers, settings, provenance and the verdict of its last replay;
 *   `ispm export RUN --frame F --buffer NAME -o FILE.png|.exr`: one buffer of one frame as an
 *   image, with the display mapping of the replay report's thumbnails (PNG) or as float (EXR);
 *   without --buffer, the whole frame as one multi-part EXR (a frame file, also of a golden whose
 *   buffers are stored as objects, for oiiotool and tev). Every output is written beside its
 *   final name, read back and renamed into place. */
#define _POSIX_C_SOURCE 200809L
#include "eng.h"
#include "rep_compare.h"
#include "rep_run.h"
#include "rep_util.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <fcntl.h>
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

enum { INS_OK = 0, INS_RUNTIME = 1, INS_INPUT = 2 };

static void info_usage(FILE *f)
{
    fprintf(f, "usage: ispm info RUN\n"
               "\n"
               "Prints what a run holds: frames, buffers (of frame 0: size and channels), the passes'\n"
               "times as recorded (frame 0, median of the later frames, sum), settings,\n"
               "provenance (sequence, scene, tool, GL, Embree, determinism pins) and the verdict of its\n"
               "last replay (RUN/replay/report.json), without decoding any frame.\n"
               "\n"
               "exit: 0 printed; 2 bad arguments or RUN unreadable\n");
}

static void export_usage(FILE *f)
{
    fprintf(f, "usage: ispm export RUN --frame F --buffer NAME -o FILE.png|FILE.exr\n"
               "       ispm export RUN --frame F -o FILE.exr\n"
               "\n"
               "Writes one buffer of one frame: .exr as float (the buffer's channels), .png 8-bit with\n"
               "the replay report's display mapping (*.display clamped, *.radiance sRGB, other buffers\n"
               "their min..max range; NaN/Inf magenta), full size. Without --buffer: every buffer of the\n"
               "frame as one multi-part EXR, one part per buffer (what a frame file holds; RUN may be a\n"
               "golden whose buffers are stored as objects).\n"
               "\n"
               "  -f, --frame F     frame index\n"
               "  -b, --buffer NAME buffer name (ispm info lists them)\n"
               "  -o, --output FILE .png or .exr\n"
               "\n"
               "exit: 0 written; 1 writing failed; 2 bad arguments, unreadable run, no such frame or buffer\n");
}

static cJSON *load_json(const char *path)
{
    cJSON *j = NULL;
    eng_error err;
    if (rep_json_load(path, ENG_IN_NOFOLLOW, &j, &err) != ENG_OK)
        return NULL;
    return j;
}

/* Milliseconds of pass `name` in frame fr of a manifest; -1 when the frame has no such pass. */
static double pass_ms(const cJSON *fr, const char *name)
{
    const cJSON *passes = cJSON_GetObjectItemCaseSensitive(fr, "passes");
    for (const cJSON *ps = passes ? passes->child : NULL; ps; ps = ps->next) {
        const cJSON *pn = cJSON_GetObjectItemCaseSensitive(ps, "name");
        const cJSON *pm = cJSON_GetObjectItemCaseSensitive(ps, "ms");
        if (cJSON_IsString(pn) && strcmp(pn->valuestring, name) == 0 && cJSON_IsNumber(pm) &&
            isfinite(pm->valuedouble) && pm->valuedouble >= 0)
            return pm->valuedouble;
    }
    return -1.0;
}

/* The manifest's per-pass times (frames[].passes, what the engine measured on its clock while
 * recording): per pass in the order the passes first appear, frame 0's milliseconds (start-up
 * work such as first-use shader variants lands there), the median over the later frames and the
 * sum over all frames; a last line sums every pass. The passes of a frame may overlap (the
 * photon trace runs beside the eye passes on two or more threads), so the sum can exceed the
 * frame's wall time. */
static void print_passes(const cJSON *frames)
{
    int nf = cJSON_GetArraySize(frames);
    if (nf < 1)
        return;
    const char *names[ENG_MAX_PASSES * 2];
    int count = 0;
    for (const cJSON *fr = frames->child; fr; fr = fr->next) {
        const cJSON *passes = cJSON_GetObjectItemCaseSensitive(fr, "passes");
        for (const cJSON *ps = passes ? passes->child : NULL; ps; ps = ps->next) {
            const cJSON *pn = cJSON_GetObjectItemCaseSensitive(ps, "name");
            if (!cJSON_IsString(pn))
                continue;
            int seen = 0;
            for (int i = 0; i < count && !seen; i++)
                seen = strcmp(names[i], pn->valuestring) == 0;
            if (!seen && count < (int)(sizeof names / sizeof names[0]))
                names[count++] = pn->valuestring;
        }
    }
    if (!count)
        return;
    printf("passes (ms): %-14s %10s %10s %12s\n", "", "frame 0", nf > 1 ? "median 1+" : "", "all frames");
    double *later = malloc((size_t)nf * sizeof *later);
    if (!later)
        return;
    double all0 = 0, all = 0;
    for (int i = 0; i < count; i++) {
        double f0 = -1, sum = 0;
        int k = 0, j = 0;
        for (const cJSON *fr = frames->child; fr; fr = fr->next, j++) {
            double ms = pass_ms(fr, names[i]);
            if (ms < 0)
                continue;
            sum += ms;
            if (j == 0)
                f0 = ms;
            else
                later[k++] = ms;
        }
        char med[32] = "";
        if (k > 0)
            snprintf(med, sizeof med, "%.1f", rep_median(later, k));
        printf("  %-25s %10.1f %10s %12.1f\n", names[i], f0 < 0 ? 0.0 : f0, med, sum);
        all0 += f0 < 0 ? 0.0 : f0;
        all += sum;
    }
    printf("  %-25s %10.1f %10s %12.1f\n", "(every pass)", all0, "", all);
    free(later);
}

static void print_object(const char *title, const cJSON *o)
{
    if (!cJSON_IsObject(o))
        return;
    printf("%s:\n", title);
    for (const cJSON *c = o->child; c; c = c->next) {
        char *v = cJSON_PrintUnformatted(c);
        printf("  %-22s %s\n", c->string, v ? v : "?");
        cJSON_free(v);
    }
}

int cmd_info(int argc, char **argv)
{
    static const struct option opts[] = {{"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0}};
    int c;
    while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        if (c == 'h') {
            info_usage(stdout);
            return INS_OK;
        }
        info_usage(stderr);
        return INS_INPUT;
    }
    if (optind + 1 != argc) {
        info_usage(stderr);
        return INS_INPUT;
    }
    const char *dir = argv[optind];
    rep_run *run = NULL;
    eng_error err = {{0}};
    if (rep_run_open(dir, &run, &err) != ENG_OK) {
        fprintf(stderr, "ispm info: %s\n", err.msg);
        return INS_INPUT;
    }
    char *origin = rep_manifest_origin(dir);
    printf("run: %s\n  %s\n", dir, origin);
    free(origin);
    printf("frames: %d at %dx%d\n", run->frame_count, run->width, run->height);
    const rep_frame_info *f0 = &run->frames[0];
    printf("buffers (frame 0): %d\n", f0->buffer_count);
    for (int j = 0; j < f0->buffer_count; j++) {
        const rep_buffer_info *b = &f0->buffers[j];
        printf("  %-36s %5dx%-5d ", b->name, b->width, b->height);
        for (int k = 0; k < b->channel_count; k++)
            printf("%s%s", k ? "," : "", b->channels[k]);
        printf("\n");
    }
    cJSON *m = load_json(run->manifest_path);
    print_passes(cJSON_GetObjectItemCaseSensitive(m, "frames"));
    print_object("settings", cJSON_GetObjectItemCaseSensitive(m, "settings"));
    print_object("tool", cJSON_GetObjectItemCaseSensitive(m, "tool"));
    print_object("gl", cJSON_GetObjectItemCaseSensitive(m, "gl"));
    print_object("determinism", cJSON_GetObjectItemCaseSensitive(m, "determinism"));
    cJSON_Delete(m);
    char *rp = rep_path_join(dir, "replay/report.json");
    cJSON *rep = load_json(rp);
    const cJSON *verdict = cJSON_GetObjectItemCaseSensitive(rep, "verdict");
    const cJSON *golden = cJSON_GetObjectItemCaseSensitive(rep, "golden");
    if (cJSON_IsString(verdict))
        printf("last replay: %s against %s (%s)\n", verdict->valuestring,
               cJSON_IsString(golden) ? golden->valuestring : "no golden", rp);
    else
        printf("last replay: none (%s absent)\n", rp);
    cJSON_Delete(rep);
    free(rp);
    rep_run_close(run);
    return INS_OK;
}

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix);
    return n >= k && strcmp(s + n - k, suffix) == 0;
}

/* Whether the EXR at tmp holds what was written: its one part decodes to b's floats bit for bit
 * (OpenImageIO's writer may leave a file short on a full disk without a word). */
static eng_result read_back(const char *tmp, const eng_buffer *b, eng_error *err)
{
    rep_part *parts = NULL;
    int n = 0;
    eng_error why;
    if (rep_read_parts(tmp, REP_MAX_FLOATS, &parts, &n, &why) != ENG_OK)
        return eng_fail(err, ENG_ERR_IO, "%s: the written file does not read back: %s", tmp, why.msg);
    eng_buffer back = n == 1 ? rep_part_buffer(&parts[0]) : (eng_buffer){0};
    char d0[40], d1[40] = "";
    eng_buffer_digest(b, d0);
    if (n == 1 && back.width == b->width && back.height == b->height && back.channel_count == b->channel_count)
        eng_buffer_digest(&back, d1);
    rep_parts_free(parts, n);
    return strcmp(d0, d1) == 0 ? ENG_OK : eng_fail(err, ENG_ERR_IO, "%s: the written file reads back different", tmp);
}

/* fsync of a file by name. */
static eng_result sync_file(const char *path, eng_error *err)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return eng_fail(err, ENG_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    int rc = fsync(fd), e = errno;
    close(fd);
    return rc == 0 ? ENG_OK : eng_fail(err, ENG_ERR_IO, "%s: cannot sync: %s", path, strerror(e));
}

/* Writes buffer b to out (.png mapped for display, .exr float); returns an exit code. The image
 * goes to a temporary name beside out, is checked (an EXR read back) and flushed, and only then renamed over
 * out: a failure (a full disk) leaves out as it was. */
static int export_buffer(const eng_buffer *b, const char *out)
{
    eng_error err = {{0}};
    eng_result r;
    int exr = ends_with(out, ".exr");
    char *tmp = rep_xprintf("%s.tmp.%ld%s", out, (long)getpid(), exr ? ".exr" : ".png");
    unsigned char *rgb = NULL;
    int w, h;
    if (exr) {
        r = rep_oiio_write_parts(tmp, b, 1, &err);
        if (r == ENG_OK)
            r = read_back(tmp, b, &err);
    } else { /* libpng directly: every short write and the close are checked */
        rep_thumb_map map;
        rep_thumb_map_make(b->name, b, NULL, &map);
        rgb = rep_image_render(b, &map, 0, &w, &h);
        r = rep_png_write(tmp, w, h, 3, rgb, &err);
    }
    if (r == ENG_OK)
        r = sync_file(tmp, &err);
    if (r == ENG_OK && rename(tmp, out) != 0)
        r = eng_fail(&err, ENG_ERR_IO, "%s: cannot rename %s into place: %s", out, tmp, strerror(errno));
    if (r == ENG_OK) { /* durable where the folder can be synced; the new image is in place either way */
        char *dir = rep_xstrdup(out);
        char *slash = strrchr(dir, '/');
        if (slash)
            slash[slash == dir ? 1 : 0] = 0;
        rep_sync_dir(slash ? dir : ".", NULL);
        free(dir);
    } else {
        unlink(tmp);
    }
    free(rgb);
    free(tmp);
    if (r != ENG_OK) {
        fprintf(stderr, "ispm export: %s\n", err.msg);
        return INS_RUNTIME;
    }
    printf("%s: %s %dx%d\n", out, b->name, b->width, b->height);
    return INS_OK;
}

int cmd_export(int argc, char **argv)
{
    static const struct option opts[] = {{"frame", required_argument, NULL, 'f'}, {"buffer", required_argument, NULL, 'b'},
                                         {"output", required_argument, NULL, 'o'}, {"help", no_argument, NULL, 'h'},
                                         {NULL, 0, NULL, 0}};
    const char *buffer = NULL, *out = NULL;
    long frame = -1;
    int c;
    while ((c = getopt_long(argc, argv, "f:b:o:h", opts, NULL)) != -1) {
        switch (c) {
        case 'f': {
            char *end;
            frame = strtol(optarg, &end, 10);
            if (*end || end == optarg || frame < 0) {
                fprintf(stderr, "ispm export: --frame: '%s' is not a frame index\n", optarg);
                return INS_INPUT;
            }
            break;
        }
        case 'b': buffer = optarg; break;
        case 'o': out = optarg; break;
        case 'h': export_usage(stdout); return INS_OK;
        default: export_usage(stderr); return INS_INPUT;
        }
    }
    if (optind + 1 != argc || frame < 0 || !out) {
        export_usage(stderr);
        return INS_INPUT;
    }
    if (!buffer && !ends_with(out, ".exr")) {
        fprintf(stderr, "ispm export: %s: a whole frame is written as .exr (or name one --buffer)\n", out);
        return INS_INPUT;
    }
    if (!ends_with(out, ".png") && !ends_with(out, ".exr")) {
        fprintf(stderr, "ispm export: %s: the output must end in .png or .exr\n", out);
        return INS_INPUT;
    }
    rep_run *run = NULL;
    eng_error err = {{0}};
    if (rep_run_open(argv[optind], &run, &err) != ENG_OK) {
        fprintf(stderr, "ispm export: %s\n", err.msg);
        return INS_INPUT;
    }
    int rc = INS_INPUT;
    int j = frame >= run->frame_count ? -1 : buffer ? rep_frame_find(&run->frames[frame], buffer) : 0;
    rep_part *parts = NULL;
    if (frame >= run->frame_count)
        fprintf(stderr, "ispm export: %s: no frame %ld (the run has %d)\n", run->manifest_path, frame, run->frame_count);
    else if (j < 0)
        fprintf(stderr, "ispm export: %s: frame %ld has no buffer '%s' (ispm info lists them)\n", run->manifest_path,
                frame, buffer);
    else if (rep_run_read_frame(run, (int)frame, &parts, &err) != ENG_OK)
        fprintf(stderr, "ispm export: %s\n", err.msg);
    else if (buffer) {
        eng_buffer b = rep_part_buffer(&parts[j]);
        rc = export_buffer(&b, out);
        rep_parts_free(parts, run->frames[frame].buffer_count);
    } else {
        int n = run->frames[frame].buffer_count;
        eng_buffer *bufs = rep_xcalloc((size_t)n, sizeof *bufs);
        for (int k = 0; k < n; k++)
            bufs[k] = rep_part_buffer(&parts[k]);
        rc = INS_OK;
        if (rep_oiio_write_parts(out, bufs, n, &err) != ENG_OK) {
            fprintf(stderr, "ispm export: %s\n", err.msg);
            rc = INS_RUNTIME;
        } else {
            printf("%s: frame %ld, %d parts\n", out, frame, n);
        }
        free(bufs);
        rep_parts_free(parts, n);
    }
    rep_run_close(run);
    return rc;
}
