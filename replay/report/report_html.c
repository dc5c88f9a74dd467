/* report_html.c — report.html: the page a person opens after a CI run (Blender's render-test
 * report is the model: failures first, golden / new / difference side by side, hover to flip).
 *
 * The page is one self-contained file: inline CSS and a few lines of inline JavaScript, no
 * external assets, nothing fetched from a network. Its parts, top to bottom: a verdict banner
 * with the counts; what was compared (run, golden, tolerances) with the first frame and buffer
 * whose digest differs and the first that differs in pixels; one card per buffer that is not
 * bit-exact (without golden: not clean), worst first in report.txt's order, with thumbnails,
 * every metric, the tolerance applied and relative links to both EXR files; the final image of
 * the first and last frame (so even a green report shows what was rendered); a compact table
 * of every buffer, worst first; and how thumbnails map floats to bytes (thumb.c).
 *
 * Thumbnails are PNGs in img/ beside the page, written through the OIIO shim, each atomically
 * (temporary name, then rename); img/ is replaced whole on every write so no stale image
 * survives. Only cards and the two previews get images, at most REP_THUMB_MAX_IMAGES of them
 * (worst entries first), so the report of a green run stays small. A frame file is decoded
 * once for all thumbnails of that frame. Images that cannot be made are left out and the page
 * says why; that is not an error. Writing the page itself is, and the page goes last.
 */
#define _XOPEN_SOURCE 700

#include "flip.h"
#include "oiio_shim.h"
#include "rep_compare.h"
#include "rep_report.h"
#include "rep_run.h"
#include "rep_util.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The thumbnails of one card or preview: file names relative to the page, NULL where none. */
typedef struct tset {
    char *golden, *run, *diff;
    char *flip;          /* ꟻLIP heat map (colour buffers that differ), or NULL */
    int tw, th;          /* thumbnail size */
    double scale;        /* heatmap white */
    rep_thumb_map map;
    int mapped;
    const char *note;    /* why images are missing, or NULL */
} tset;

typedef struct job {
    int frame;
    const char *buffer;
    tset *t;
    int want_golden, want_run, want_diff;
    const rep_entry *e;  /* the card's entry (NULL: a preview): ꟻLIP heat map with the difference */
} job;

typedef struct page {
    const rep_report *r;
    const rep_run *run, *golden;
    const char *dir;
    char real_dir[PATH_MAX]; /* the report folder, resolved, for relative links; "" if unknown */
    int images;              /* written so far */
    int serial;
} page;

static void esc(rep_sb *sb, const char *s)
{
    rep_sb_xml(sb, s ? s : "");
}

/* ---------------------------------------------------------------- links */

/* Path of target relative to the folder from (both resolved), percent-encoded for an href;
 * NULL if target does not exist. Caller frees. */
static char *rel_href(const char *from, const char *target)
{
    char real[PATH_MAX];
    if (!from[0] || !realpath(target, real))
        return NULL;
    size_t common = 0, i = 0;
    while (from[i] && real[i] && from[i] == real[i]) {
        i++;
        if ((from[i] == '/' || from[i] == 0) && (real[i] == '/' || real[i] == 0))
            common = i;
    }
    if (strcmp(from, "/") == 0)
        common = 0;
    rep_sb rel = {0};
    rep_sb_printf(&rel, "%s", "");
    for (const char *p = from + common; *p; p++)
        if (*p == '/')
            rep_sb_printf(&rel, "../");
    const char *rest = real + common;
    while (*rest == '/')
        rest++;
    rep_sb out = {0};
    rep_sb_printf(&out, "%s", rel.s);
    free(rel.s);
    for (const unsigned char *p = (const unsigned char *)rest; *p; p++) {
        if ((*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') ||
            strchr("/._-~", *p))
            rep_sb_printf(&out, "%c", *p);
        else
            rep_sb_printf(&out, "%%%02X", *p);
    }
    return out.s;
}

/* ---------------------------------------------------------------- thumbnails */

static void sanitize(char *s)
{
    for (; *s; s++)
        if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') || (*s >= '0' && *s <= '9') || *s == '.' ||
              *s == '-' || *s == '_'))
            *s = '_';
}

/* One thumbnail of a job: its pixels (made on any thread), then its name (given in job order, so
 * the names do not depend on timing), then its PNG (written on any thread). */
typedef struct image {
    unsigned char *px;
    int w, h;
    const char *what; /* "golden", "new", "diff", "flip" */
    char **slot;      /* where the tset keeps its page-relative name */
    char *rel, *path; /* img/<serial>-f<frame>-<buffer>-<what>.png, and its path */
    int ok;
} image;

/* The images of one job, in the order the page names them. */
typedef struct job_images {
    image im[4];
    int n;
} job_images;

static void add_image(job_images *ji, unsigned char *px, int w, int h, const char *what, char **slot)
{
    ji->im[ji->n++] = (image){px, w, h, what, slot, NULL, NULL, 0};
}

/* Names image im of a job img/<serial>-f<frame>-<buffer>-<what>.png (serials in call order). */
static void name_image(page *pg, const job *jb, image *im)
{
    char *leaf = rep_xprintf("%04d-f%06d-%s-%s.png", pg->serial++, jb->frame, jb->buffer, im->what);
    sanitize(leaf);
    im->rel = rep_xprintf("img/%s", leaf);
    im->path = rep_path_join(pg->dir, im->rel);
    free(leaf);
}

/* Writes an image atomically (temporary name, then rename); im->ok says whether it is there. */
static void write_image(image *im)
{
    char *tmp = rep_xprintf("%s.tmp.%ld", im->path, (long)getpid());
    eng_error err;
    im->ok = rep_png_write(tmp, im->w, im->h, 3, im->px, &err) == ENG_OK && rename(tmp, im->path) == 0;
    if (!im->ok)
        unlink(tmp);
    free(tmp);
}

static const rep_part *find_part(const rep_part *parts, int n, const char *name)
{
    for (int i = 0; i < n; i++)
        if (strcmp(parts[i].name, name) == 0)
            return &parts[i];
    return NULL;
}

/* The ꟻLIP heat map of a colour buffer that differs (flip.h's ramp, box maximum): the map the
 * comparison made, when the walk kept it (keep.c), else the same map computed again. */
static void flip_thumb(const job *jb, const rep_keep *keep, const eng_buffer *a, const eng_buffer *b,
                       job_images *ji)
{
    const rep_entry *e = jb->e;
    if (!e || e->flip_kind == REP_FLIP_NONE || e->verdict == REP_V_BITEXACT)
        return;
    const float *kept = rep_keep_find_flip(keep, jb->frame, jb->buffer);
    float *own = kept ? NULL : rep_flip_buffers(a, b, &e->tol, e->flip_kind, NULL);
    const float *map = kept ? kept : own;
    if (!map)
        return;
    int w, h;
    unsigned char *px = rep_flip_heat(map, a->width, a->height, REP_THUMB_MAX_SIDE, &w, &h);
    add_image(ji, px, w, h, "flip", &jb->t->flip);
    free(own);
}

/* The pixels of a job's thumbnails (touches only the job's own tset and ji). */
static void make_thumbs(const job *jb, const rep_keep *keep, const rep_part *rp, int rn, const rep_part *gp, int gn,
                        job_images *ji)
{
    tset *t = jb->t;
    const rep_part *a = rp ? find_part(rp, rn, jb->buffer) : NULL;
    const rep_part *b = gp ? find_part(gp, gn, jb->buffer) : NULL;
    eng_buffer av, bv;
    if (a)
        av = rep_part_buffer(a);
    if (b)
        bv = rep_part_buffer(b);
    if (!a && !b) {
        if (!t->note)
            t->note = "no frame file could be decoded for this buffer";
        return;
    }
    rep_thumb_map_make(jb->buffer, a ? &av : NULL, b ? &bv : NULL, &t->map);
    t->mapped = 1;
    int w, h;
    if (b && jb->want_golden) {
        unsigned char *px = rep_thumb_render(&bv, &t->map, &w, &h);
        add_image(ji, px, w, h, "golden", &t->golden);
        t->tw = w, t->th = h;
    }
    if (a && jb->want_run) {
        unsigned char *px = rep_thumb_render(&av, &t->map, &w, &h);
        add_image(ji, px, w, h, "new", &t->run);
        t->tw = w, t->th = h;
    }
    if (a && b && jb->want_diff) {
        unsigned char *px = rep_thumb_diff(&av, &bv, &t->scale, &w, &h);
        if (px)
            add_image(ji, px, w, h, "diff", &t->diff);
        flip_thumb(jb, keep, &av, &bv, ji);
    }
}

static int by_frame(const void *pa, const void *pb)
{
    const job *a = pa, *b = pb;
    if (a->frame != b->frame)
        return a->frame < b->frame ? -1 : 1;
    return a->t < b->t ? -1 : a->t > b->t;
}

/* The parts of one side of frame f that the m jobs show, as the walk kept them (keep.c): a
 * borrowed array (free the array only), or NULL when one is missing (*n = -1) or the side has
 * no frame f (*n = 0). */
static rep_part *kept_parts(const page *pg, const rep_run *side, int which, int f, const job *jobs, size_t m, int *n)
{
    *n = 0;
    if (!side || f >= side->frame_count)
        return NULL;
    rep_part *a = rep_xcalloc(m + 1, sizeof *a);
    for (size_t k = 0; k < m; k++) {
        if (which == REP_KEEP_RUN ? !jobs[k].want_run : !jobs[k].want_golden)
            continue;
        const rep_part *p = rep_keep_find_part(pg->r->keep, f, which, jobs[k].buffer);
        if (!p) {
            free(a);
            *n = -1;
            return NULL;
        }
        a[(*n)++] = *p;
    }
    return a;
}

/* Frame f of one side decoded for its thumbnails (the walk did not keep all of them); *bad when
 * the side has frame f and it cannot be decoded. */
static void decode_side(const rep_run *side, int f, rep_part **parts, int *n, int *bad)
{
    eng_error err;
    *bad = 0;
    if (!side || f >= side->frame_count)
        return;
    /* Through the run reader: a frame's buffers may be objects (a golden of format 2) or parts of
     * an earlier frame's file (stored_in). */
    *bad = rep_run_read_frame(side, f, parts, &err) != ENG_OK;
    *n = *bad ? 0 : side->frames[f].buffer_count;
}

/* Makes the thumbnails of each frame that has jobs from the parts the walk kept, or else from
 * the frame decoded again (both sides side by side): pixels on OpenMP threads, names in job
 * order, PNGs on OpenMP threads. Either way the same parts, so the same images. */
static void run_jobs(page *pg, job *jobs, size_t n)
{
    qsort(jobs, n, sizeof *jobs, by_frame);
    job_images *ji = rep_xcalloc(n + 1, sizeof *ji);
    for (size_t i = 0; i < n;) {
        int f = jobs[i].frame;
        size_t j = i;
        while (j < n && jobs[j].frame == f)
            j++;
        rep_part *rp = NULL, *gp = NULL;
        int rn = 0, gn = 0, rbad = 0, gbad = 0;
        rp = kept_parts(pg, pg->run, REP_KEEP_RUN, f, jobs + i, j - i, &rn);
        gp = kept_parts(pg, pg->golden, REP_KEEP_GOLDEN, f, jobs + i, j - i, &gn);
        int kept = rn >= 0 && gn >= 0;
        if (!kept) {
            free(rp);
            free(gp);
            rp = gp = NULL;
            rn = gn = 0;
#pragma omp parallel sections
            {
#pragma omp section
                decode_side(pg->run, f, &rp, &rn, &rbad);
#pragma omp section
                decode_side(pg->golden, f, &gp, &gn, &gbad);
            }
        }
        const char *note = gbad ? "the golden's frame file could not be decoded"
                           : rbad ? "the run's frame file could not be decoded" : NULL;
        long m = (long)(j - i);
#pragma omp parallel for schedule(dynamic, 1)
        for (long k = 0; k < m; k++) {
            if (note)
                jobs[i + (size_t)k].t->note = note;
            make_thumbs(&jobs[i + (size_t)k], pg->r->keep, rp, rn, gp, gn, &ji[i + (size_t)k]);
        }
        if (kept) {
            free(rp);
            free(gp);
        } else {
            rep_parts_free(rp, rn);
            rep_parts_free(gp, gn);
        }
        i = j;
    }
    /* names in job order, then every PNG of the page at once */
    long total = 0;
    for (size_t k = 0; k < n; k++)
        for (int q = 0; q < ji[k].n; q++, total++)
            name_image(pg, &jobs[k], &ji[k].im[q]);
    image **all = rep_xcalloc((size_t)total + 1, sizeof *all);
    total = 0;
    for (size_t k = 0; k < n; k++)
        for (int q = 0; q < ji[k].n; q++)
            all[total++] = &ji[k].im[q];
#pragma omp parallel for schedule(dynamic, 1)
    for (long k = 0; k < total; k++)
        write_image(all[k]);
    for (size_t k = 0; k < n; k++)
        for (int q = 0; q < ji[k].n; q++) {
            image *im = &ji[k].im[q];
            if (im->ok) {
                *im->slot = im->rel;
                pg->images++;
            } else {
                free(im->rel);
                jobs[k].t->note = "a thumbnail could not be written";
            }
            free(im->path);
            free(im->px);
        }
    free(all);
    free(ji);
}

/* ---------------------------------------------------------------- page pieces */

static const char *css_class(const rep_entry *e)
{
    if (e->expected)
        return "xfail";
    switch (e->verdict) {
    case REP_V_SIZE: return "size";
    case REP_V_FAIL: return "fail";
    case REP_V_WARN: return "warn";
    case REP_V_WITHIN: return "within";
    case REP_V_BITEXACT: return "exact";
    default: return "checked";
    }
}

static const char *exit_class(rep_exit x)
{
    switch (x) {
    case REP_OK: return "ok";
    case REP_WARN: return "warn";
    case REP_FAIL: return "fail";
    case REP_SIZE: return "size";
    case REP_UNREADABLE: return "unreadable";
    case REP_UNWRITABLE: return "unwritable";
    }
    return "unreadable";
}

static const char *tag(const rep_entry *e)
{
    if (e->verdict == REP_V_SIZE)
        return "SIZE";
    if (e->problem == REP_PROB_MISSING || e->problem == REP_PROB_FRAME_MISSING)
        return "MISSING";
    if (e->problem == REP_PROB_EXTRA || e->problem == REP_PROB_FRAME_EXTRA)
        return "EXTRA";
    if (e->m.fail_why & REP_WHY_NONFINITE)
        return "NaN/Inf";
    if (e->expected)
        return "XFAIL";
    switch (e->verdict) {
    case REP_V_FAIL: return "FAIL";
    case REP_V_WARN: return "WARN";
    case REP_V_WITHIN: return "WITHIN";
    case REP_V_BITEXACT: return "EXACT";
    default: return "OK";
    }
}

static void num(rep_sb *sb, double v)
{
    if (isnan(v))
        rep_sb_printf(sb, "—");
    else if (isinf(v))
        rep_sb_printf(sb, v > 0 ? "∞" : "−∞");
    else
        rep_sb_printf(sb, "%.4g", v);
}

static void row(rep_sb *sb, const char *k)
{
    rep_sb_printf(sb, "<tr><th>%s</th><td>", k);
}

static void why(rep_sb *sb, unsigned w)
{
    static const struct { unsigned bit; const char *name; } names[] = {
        {REP_WHY_PERCENT, "too many pixels over threshold"}, {REP_WHY_HARD, "hard limit"}, {REP_WHY_RMSE, "RMSE"},
        {REP_WHY_NONFINITE, "NaN/Inf"}, {REP_WHY_EXACT, "exact: bits differ"}, {REP_WHY_FLIP, "ꟻLIP"},
        {REP_WHY_BLOCK, "worst block"}};
    int any = 0;
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (w & names[i].bit)
            rep_sb_printf(sb, "%s%s", any++ ? ", " : "", names[i].name);
    if (!any)
        rep_sb_printf(sb, "—");
}

static void metrics_table(rep_sb *sb, const rep_report *r, const rep_entry *e)
{
    const rep_metrics *m = &e->m;
    rep_sb_printf(sb, "<table class=\"kv\"><caption>metrics</caption>");
    if (r->golden_dir) {
        row(sb, "max |Δ|");
        num(sb, m->max_abs);
        if (m->max_x >= 0) {
            rep_sb_printf(sb, " at (%d,%d).", m->max_x, m->max_y);
            esc(sb, m->max_channel);
        }
        rep_sb_printf(sb, "</td></tr>");
        row(sb, "mean |Δ|");
        num(sb, m->mean_abs);
        rep_sb_printf(sb, "</td></tr>");
        row(sb, "RMSE");
        num(sb, m->rmse);
        rep_sb_printf(sb, "</td></tr>");
        row(sb, "PSNR");
        num(sb, m->psnr);
        rep_sb_printf(sb, " dB</td></tr>");
        row(sb, "values differing");
        rep_sb_printf(sb, "%llu of %llu</td></tr>", (unsigned long long)m->values_differing,
                      (unsigned long long)m->values);
        row(sb, "pixels over fail");
        rep_sb_printf(sb, "%llu of %llu (%.4g%%)", (unsigned long long)m->fail_pixels, (unsigned long long)m->pixels,
                      m->fail_percent);
        if (m->first_fail_x >= 0)
            rep_sb_printf(sb, ", first at (%d,%d)", m->first_fail_x, m->first_fail_y);
        rep_sb_printf(sb, "</td></tr>");
        row(sb, "pixels over warn");
        rep_sb_printf(sb, "%llu (%.4g%%)</td></tr>", (unsigned long long)m->warn_pixels, m->warn_percent);
        if (m->block_size > 0 && m->block_abs.x >= 0) {
            row(sb, "worst block");
            rep_sb_printf(sb, "<span class=\"blkkey\"></span>mean |Δ| ");
            num(sb, m->block_abs.value);
            rep_sb_printf(sb, " at (%d,%d), %d×%d; relative ", m->block_abs.x, m->block_abs.y, m->block_abs.w,
                          m->block_abs.h);
            num(sb, m->block_rel.value);
            rep_sb_printf(sb, " at (%d,%d)</td></tr>", m->block_rel.x, m->block_rel.y);
        }
    }
    if (e->flip_kind != REP_FLIP_NONE) {
        row(sb, e->flip_kind == REP_FLIP_HDR ? "ꟻLIP (HDR)" : "ꟻLIP (LDR)");
        rep_sb_printf(sb, "mean %.4f · p50 %.4f · p95 %.4f · p99 %.4f · max %.4f", e->flip.mean, e->flip.p50,
                      e->flip.p95, e->flip.p99, e->flip.max);
        if (e->flip_kind == REP_FLIP_HDR && e->flip.exposures)
            rep_sb_printf(sb, " (%d exposures, %g to %g)", e->flip.exposures, e->tol.flip_exposure[0],
                          e->tol.flip_exposure[1]);
        rep_sb_printf(sb, "</td></tr>");
    }
    row(sb, "NaN / Inf");
    rep_sb_printf(sb, "run %llu / %llu", (unsigned long long)m->run_nan, (unsigned long long)m->run_inf);
    if (r->golden_dir)
        rep_sb_printf(sb, " · golden %llu / %llu", (unsigned long long)m->golden_nan, (unsigned long long)m->golden_inf);
    rep_sb_printf(sb, "</td></tr>");
    if (m->nf_x >= 0) {
        row(sb, r->golden_dir ? "first NaN/Inf change" : "first NaN/Inf");
        rep_sb_printf(sb, "(%d,%d)", m->nf_x, m->nf_y);
        if (r->golden_dir && m->nf_channel[0]) {
            rep_sb_printf(sb, ".");
            esc(sb, m->nf_channel);
            rep_sb_printf(sb, ": run ");
            num(sb, m->nf_run);
            rep_sb_printf(sb, ", golden ");
            num(sb, m->nf_golden);
        }
        rep_sb_printf(sb, "</td></tr>");
    }
    row(sb, "fails because");
    why(sb, m->fail_why);
    rep_sb_printf(sb, "</td></tr>");
    row(sb, "warns because");
    why(sb, m->warn_why);
    rep_sb_printf(sb, "</td></tr></table>\n");
}

static void tol_table(rep_sb *sb, const rep_entry *e)
{
    const rep_tol *t = &e->tol;
    rep_sb_printf(sb, "<table class=\"kv\"><caption>tolerance (rule <code>");
    esc(sb, e->tol_match ? e->tol_match : "default");
    rep_sb_printf(sb, "</code>)</caption>");
    row(sb, "exact");
    rep_sb_printf(sb, "%s</td></tr>", t->exact ? "yes: any bit difference fails" : "no");
    struct { const char *k; double v; } v[] = {
        {"fail", t->fail}, {"failrelative", t->failrelative}, {"failpercent", t->failpercent},
        {"hardfail", t->hardfail}, {"rmse_fail", t->rmse_fail}, {"warn", t->warn},
        {"warnrelative", t->warnrelative}, {"warnpercent", t->warnpercent}, {"hardwarn", t->hardwarn},
        {"rmse_warn", t->rmse_warn}, {"flip_mean_fail", t->flip_mean_fail}, {"flip_p99_fail", t->flip_p99_fail},
        {"block_fail", t->block_fail}, {"block_failrelative", t->block_failrelative}, {"block_warn", t->block_warn},
        {"block_warnrelative", t->block_warnrelative}};
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++) {
        row(sb, v[i].k);
        if (isinf(v[i].v))
            rep_sb_printf(sb, "off");
        else
            num(sb, v[i].v);
        rep_sb_printf(sb, "</td></tr>");
    }
    row(sb, "block_size");
    rep_sb_printf(sb, "%d</td></tr></table>\n", t->block_size > 0 ? t->block_size : REP_BLOCK_SIZE);
}

/* The worst block's outline over a thumbnail of e (in a positioned box): placed in percent of
 * the buffer's size, so it lands on the block at any thumbnail scale. */
static void outline(rep_sb *sb, const rep_entry *e)
{
    if (!e || !e->compared || e->m.block_size <= 0 || e->m.block_abs.x < 0 || e->m.width <= 0 || e->m.height <= 0)
        return;
    const rep_block *b = &e->m.block_abs;
    rep_sb_printf(sb, "<div class=\"blk\" title=\"worst block: (%d,%d) %d×%d, mean |Δ| %.3g\" "
                      "style=\"left:%.4f%%;top:%.4f%%;width:%.4f%%;height:%.4f%%\"></div>",
                  b->x, b->y, b->w, b->h, b->value, 100.0 * b->x / e->m.width, 100.0 * b->y / e->m.height,
                  100.0 * b->w / e->m.width, 100.0 * b->h / e->m.height);
}

/* An <img> at an integer magnification that brings the longest side near 256 px. */
static void img(rep_sb *sb, const char *src, int w, int h, const char *cls, const char *alt)
{
    int longest = w > h ? w : h;
    int k = longest > 0 && longest < REP_THUMB_MAX_SIDE ? REP_THUMB_MAX_SIDE / longest : 1;
    rep_sb_printf(sb, "<img class=\"%s\" src=\"", cls);
    esc(sb, src);
    rep_sb_printf(sb, "\" width=\"%d\" height=\"%d\" alt=\"", w * k, h * k);
    esc(sb, alt);
    rep_sb_printf(sb, "\">");
}

static void placeholder(rep_sb *sb, const char *why_text)
{
    rep_sb_printf(sb, "<figure><div class=\"none\">");
    esc(sb, why_text);
    rep_sb_printf(sb, "</div></figure>");
}

static void map_caption(rep_sb *sb, const tset *t)
{
    if (!t->mapped)
        return;
    switch (t->map.kind) {
    case REP_THUMB_DISPLAY: rep_sb_printf(sb, "display values ×255"); break;
    case REP_THUMB_RADIANCE: rep_sb_printf(sb, "linear → sRGB, clamped to [0,1]"); break;
    case REP_THUMB_DATA:
        rep_sb_printf(sb, "data: ");
        num(sb, t->map.lo);
        rep_sb_printf(sb, " → black, ");
        num(sb, t->map.hi);
        rep_sb_printf(sb, " → white");
        break;
    }
    if (t->map.n > 0) {
        rep_sb_printf(sb, " (");
        for (int i = 0; i < t->map.n; i++) {
            rep_sb_printf(sb, "%s", i ? "," : "");
            esc(sb, t->map.ch[i]);
        }
        rep_sb_printf(sb, ")");
    }
}

/* golden | new (hover or click: golden) | difference | ꟻLIP; e (NULL: a preview) outlines its
 * worst block on each. */
static void thumbs(rep_sb *sb, const tset *t, const char *missing_golden, const char *missing_run, int with_diff,
                   const rep_entry *e)
{
    rep_sb_printf(sb, "<div class=\"thumbs\">");
    if (t->golden) {
        rep_sb_printf(sb, "<figure><div class=\"stack\">");
        img(sb, t->golden, t->tw, t->th, "t", "golden");
        outline(sb, e);
        rep_sb_printf(sb, "</div><figcaption>golden</figcaption></figure>");
    } else if (missing_golden) {
        placeholder(sb, missing_golden);
    }
    if (t->run) {
        rep_sb_printf(sb, "<figure class=\"%s\" tabindex=\"0\" title=\"hover or click to flip\"><div class=\"stack\">",
                      t->golden ? "flip" : "");
        img(sb, t->run, t->tw, t->th, "t new", "new");
        if (t->golden)
            img(sb, t->golden, t->tw, t->th, "t old", "golden");
        outline(sb, e);
        rep_sb_printf(sb, "</div><figcaption>");
        if (t->golden)
            rep_sb_printf(sb, "<span class=\"ln\">new — hover to flip to golden</span><span class=\"lo\">golden "
                              "(flipped)</span>");
        else
            rep_sb_printf(sb, "new");
        rep_sb_printf(sb, "</figcaption></figure>");
    } else if (missing_run) {
        placeholder(sb, missing_run);
    }
    if (t->diff) {
        rep_sb_printf(sb, "<figure><div class=\"stack\">");
        img(sb, t->diff, t->tw, t->th, "t", "difference heatmap");
        outline(sb, e);
        rep_sb_printf(sb, "</div><figcaption>|new − golden|: black 0, white ");
        num(sb, t->scale);
        rep_sb_printf(sb, "</figcaption></figure>");
    } else if (with_diff && t->golden && t->run) {
        placeholder(sb, "no difference image: sizes or channels differ");
    }
    if (t->flip) {
        rep_sb_printf(sb, "<figure><div class=\"stack\">");
        img(sb, t->flip, t->tw, t->th, "t", "FLIP heat map");
        outline(sb, e);
        rep_sb_printf(sb, "</div><figcaption>ꟻLIP: black 0 (invisible), pale yellow 1</figcaption></figure>");
    }
    rep_sb_printf(sb, "</div>\n<p class=\"map\">");
    map_caption(sb, t);
    if (t->note) {
        rep_sb_printf(sb, "%s<span class=\"note\">", t->mapped ? " · " : "");
        esc(sb, t->note);
        rep_sb_printf(sb, "</span>");
    }
    rep_sb_printf(sb, "</p>\n");
}

static void exr_links(rep_sb *sb, const page *pg, int frame, const char *buffer)
{
    rep_sb_printf(sb, "<p class=\"links\">EXR, part <code>");
    esc(sb, buffer);
    rep_sb_printf(sb, "</code>: ");
    const rep_run *sides[2] = {pg->run, pg->golden};
    const char *names[2] = {"run", "golden"};
    int any = 0;
    for (int s = 0; s < 2; s++) {
        if (!sides[s] || frame >= sides[s]->frame_count || !sides[s]->frames[frame].path)
            continue;
        char *href = rel_href(pg->real_dir, sides[s]->frames[frame].path);
        if (!href)
            continue;
        rep_sb_printf(sb, "%s<a href=\"", any++ ? " · " : "");
        esc(sb, href);
        rep_sb_printf(sb, "\">%s frame %d (", names[s], frame);
        esc(sb, sides[s]->frames[frame].file);
        rep_sb_printf(sb, ")</a>");
        free(href);
    }
    if (!any)
        rep_sb_printf(sb, "none readable");
    rep_sb_printf(sb, "</p>\n");
}

static void card(rep_sb *sb, const page *pg, const rep_entry *e, const tset *t)
{
    const rep_report *r = pg->r;
    rep_sb_printf(sb, "<article class=\"entry %s\" id=\"e%zu\" data-frame=\"%d\" data-buffer=\"", css_class(e),
                  (size_t)(e - r->entries), e->frame);
    esc(sb, e->buffer);
    rep_sb_printf(sb, "\" data-verdict=\"%s\">\n<h3><span class=\"tag %s\">%s</span> frame %d · <span class=\"buf\">",
                  rep_verdict_name(e->verdict), css_class(e), tag(e), e->frame);
    esc(sb, e->buffer);
    rep_sb_printf(sb, "</span></h3>\n");
    const char *reason = rep_entry_expect_reason(r, e);
    if (reason) {
        rep_sb_printf(sb, "<p class=\"xreason\">expected failure: ");
        esc(sb, reason);
        rep_sb_printf(sb, "</p>\n");
    }
    rep_sb_printf(sb, "<p class=\"line\">");
    rep_sb line = {0};
    rep_report_line(&line, r, e);
    esc(sb, line.s);
    free(line.s);
    rep_sb_printf(sb, "</p>\n");
    const char *mg = e->problem == REP_PROB_EXTRA || e->problem == REP_PROB_FRAME_EXTRA ? "not in golden" : NULL;
    const char *mr = e->problem == REP_PROB_MISSING || e->problem == REP_PROB_FRAME_MISSING ? "missing from run" : NULL;
    if (t->golden || t->run || t->note || mg || mr)
        thumbs(sb, t, mg, mr, 1, e);
    else if (r->golden_dir || e->verdict != REP_V_CHECKED)
        rep_sb_printf(sb, "<p class=\"map\"><span class=\"note\">no thumbnails: the report holds at most %d images</span></p>\n",
                      REP_THUMB_MAX_IMAGES);
    if (e->verdict == REP_V_SIZE)
    {
        rep_sb_printf(sb, "<p>run <code>");
        esc(sb, e->run_shape ? e->run_shape : "?");
        rep_sb_printf(sb, "</code>, golden <code>");
        esc(sb, e->golden_shape ? e->golden_shape : "?");
        rep_sb_printf(sb, "</code></p>\n");
    }
    if (e->compared) {
        rep_sb_printf(sb, "<div class=\"tables\">");
        metrics_table(sb, r, e);
        if (r->golden_dir)
            tol_table(sb, e);
        rep_sb_printf(sb, "</div>\n");
    }
    exr_links(sb, pg, e->frame, e->buffer);
    rep_sb_printf(sb, "</article>\n");
}

static const char CSS[] =
    "body{font:14px/1.45 system-ui,-apple-system,'Segoe UI',sans-serif;margin:0;background:#f3f4f6;color:#1f2328}"
    "header{padding:14px 24px;color:#fff}header h1{margin:0;font-size:22px}header p{margin:4px 0 0}"
    "header.ok{background:#1a7f37}header.warn{background:#9a6700}header.fail,header.size{background:#b42318}"
    "header.unreadable{background:#6e2fa0}"
    "main{padding:4px 24px 24px;max-width:1200px}h2{font-size:17px;margin:22px 0 8px}"
    "dl.sum{display:grid;grid-template-columns:max-content auto;gap:2px 14px;margin:10px 0}dl.sum dt{color:#57606a}"
    "dl.sum dd{margin:0;word-break:break-all}code,.line,.buf{font-family:ui-monospace,'DejaVu Sans Mono',monospace}"
    ".entry{background:#fff;border-left:6px solid #8c959f;border-radius:4px;padding:10px 16px;margin:12px 0;"
    "box-shadow:0 1px 2px #0002}.entry.fail,.entry.size{border-color:#b42318}.entry.warn{border-color:#bf8700}"
    ".entry.within{border-color:#0969da}.entry h3{margin:0 0 4px;font-size:15px}"
    ".tag{display:inline-block;min-width:56px;text-align:center;border-radius:3px;padding:0 6px;color:#fff;"
    "font-size:12px;font-weight:600;background:#8c959f}.tag.fail,.tag.size{background:#b42318}"
    ".tag.warn{background:#bf8700}.tag.within{background:#0969da}.tag.exact,.tag.checked{background:#1a7f37}"
    ".line{font-size:12px;color:#57606a;margin:0 0 8px;white-space:pre-wrap}"
    ".thumbs{display:flex;flex-wrap:wrap;gap:14px}figure{margin:0}figcaption{font-size:12px;color:#57606a}"
    "img.t{display:block;image-rendering:pixelated;background:repeating-conic-gradient(#ccc 0 25%,#eee 0 50%) 0 0/16px 16px}"
    ".stack{position:relative;width:max-content}.stack .old{position:absolute;left:0;top:0;visibility:hidden}"
    ".flip{cursor:pointer}.flip:hover .old,.flip.pinned .old{visibility:visible}"
    ".flip .lo{display:none}.flip:hover .lo,.flip.pinned .lo{display:inline;color:#b42318;font-weight:600}"
    ".flip:hover .ln,.flip.pinned .ln{display:none}"
    ".none{width:160px;height:120px;display:flex;align-items:center;justify-content:center;text-align:center;"
    "background:#eaeef2;color:#57606a;font-size:12px;padding:4px}"
    ".map{font-size:12px;color:#57606a;margin:4px 0}.note{color:#b42318}"
    ".tables{display:flex;flex-wrap:wrap;gap:18px;margin-top:6px}"
    "table.kv{border-collapse:collapse;font-size:12px}table.kv caption{text-align:left;font-weight:600;color:#57606a}"
    "table.kv th{text-align:left;font-weight:normal;color:#57606a;padding:1px 10px 1px 0}table.kv td{padding:1px 0}"
    "table.all{border-collapse:collapse;font-size:12px;background:#fff;width:100%}"
    "table.all th,table.all td{padding:2px 8px;border-bottom:1px solid #eaeef2;text-align:left}"
    "table.all td.n{text-align:right;font-variant-numeric:tabular-nums}"
    ".entry.xfail{border-color:#8c959f;opacity:.85}.tag.xfail{background:#6e7781}.xreason{font-size:13px;margin:0 0 4px}"
    ".blk{position:absolute;box-sizing:border-box;border:2px solid #f0f;outline:1px solid #000;pointer-events:none}"
    ".blkkey{display:inline-block;width:10px;height:10px;border:2px solid #f0f;margin-right:4px;vertical-align:-2px}"
    ".links{font-size:12px;margin:6px 0 0}.previews{display:flex;flex-wrap:wrap;gap:28px}"
    "footer{font-size:12px;color:#57606a;padding:0 24px 24px;max-width:1200px}";

/* Click (or Enter on a focused thumbnail) pins the flip for touch screens and keyboards. */
static const char JS[] =
    "document.querySelectorAll('.flip').forEach(function(f){"
    "function t(){f.classList.toggle('pinned');}"
    "f.addEventListener('click',t);"
    "f.addEventListener('keydown',function(e){if(e.key==='Enter'||e.key===' '){e.preventDefault();t();}});});";

/* Provenance (every manifest difference, worst level first) and per-pass timing: before the
 * pixels, so that a reader sees why before how. */
static void prov_section(rep_sb *sb, const rep_prov *p)
{
    rep_sb_printf(sb, "<section id=\"provenance\"><h2>Provenance (%zu difference%s)</h2>\n", p->count,
                  p->count == 1 ? "" : "s");
    if (!p->count)
        rep_sb_printf(sb, "<p>Same sequence, scene, settings, tool, GL and pins as the golden.</p>\n");
    else
        rep_sb_printf(sb, "<table class=\"all\"><thead><tr><th>level</th><th>key</th><th>golden</th><th>run</th>"
                          "</tr></thead><tbody>\n");
    for (int level = REP_PROV_FAIL; level >= REP_PROV_INFO; level--)
        for (size_t i = 0; i < p->count; i++) {
            const rep_prov_item *it = &p->items[i];
            if (it->level != level)
                continue;
            rep_sb_printf(sb, "<tr class=\"%s\"><td>%s</td><td><code>", level == REP_PROV_FAIL ? "fail" : level == REP_PROV_WARN ? "warn" : "",
                          rep_prov_level_name(level));
            esc(sb, it->key);
            rep_sb_printf(sb, "</code></td><td><code>");
            esc(sb, it->golden ? it->golden : "(absent)");
            rep_sb_printf(sb, "</code></td><td><code>");
            esc(sb, it->run ? it->run : "(absent)");
            rep_sb_printf(sb, "</code></td></tr>\n");
        }
    if (p->count)
        rep_sb_printf(sb, "</tbody></table>\n");
    rep_sb_printf(sb, "</section>\n");
    if (!p->timing_count)
        return;
    rep_sb_printf(sb, "<section id=\"timing\"><h2>Timing: pass share of the frame (median), run vs golden</h2>\n"
                      "<p>median frame %.1f ms, golden %.1f ms; %s</p>\n<table class=\"all\"><thead><tr><th>pass</th>"
                      "<th>run</th><th>golden</th><th>ratio</th><th>run ms</th><th>golden ms</th></tr></thead><tbody>\n",
                  p->run_frame_ms, p->golden_frame_ms,
                  p->timing_fail > 0 ? "a ratio over --timing-fail fails" : "reported only (--timing-fail RATIO judges it)");
    for (int i = 0; i < p->timing_count; i++) {
        const rep_timing_pass *t = &p->timing[i];
        rep_sb_printf(sb, "<tr class=\"%s\"><td>", t->failed ? "fail" : "");
        esc(sb, t->name);
        const double v[5] = {100 * t->run_share, 100 * t->golden_share, t->ratio, t->run_ms, t->golden_ms};
        rep_sb_printf(sb, "</td>");
        for (int k = 0; k < 5; k++) {
            rep_sb_printf(sb, "<td class=\"n\">");
            if (isfinite(v[k]) && k < 2)
                rep_sb_printf(sb, "%.2f%%", v[k]);
            else if (isfinite(v[k]) && k == 2)
                rep_sb_printf(sb, "×%.2f", v[k]);
            else if (isfinite(v[k]))
                rep_sb_printf(sb, "%.1f", v[k]);
            else
                rep_sb_printf(sb, "—"); /* the pass is absent on one side */
            rep_sb_printf(sb, "</td>");
        }
        rep_sb_printf(sb, "</tr>\n");
    }
    rep_sb_printf(sb, "</tbody></table></section>\n");
}

/* The expectations in force: expired rules, unexpected passes, expected failures with reasons. */
static void expect_section(rep_sb *sb, const rep_report *r)
{
    const rep_expect_outcome *x = r->expect;
    if (!x)
        return;
    rep_sb_printf(sb, "<section id=\"expectations\"><h2>Expectations (");
    esc(sb, x->set->path);
    rep_sb_printf(sb, ", judged on %s)</h2>\n<table class=\"all\"><thead><tr><th>rule</th><th>match</th><th>renderer</th>"
                      "<th>until</th><th>reason</th><th>outcome</th></tr></thead><tbody>\n", x->today);
    for (int k = 0; k < x->set->count; k++) {
        const rep_expect_rule *q = &x->set->rules[k];
        int expired = rep_expect_expired(q, x->today), applies = rep_expect_applies(q, r->run_renderer);
        size_t failed = 0;
        for (size_t i = 0; i < r->count; i++)
            failed += r->entries[i].expected && r->entries[i].expect_rule == k;
        rep_sb up = {0};
        for (int i = 0; i < x->unexpected_count; i++)
            if (x->unexpected[i].rule == k)
                rep_sb_printf(&up, "%s%s", up.len ? ", " : "", x->unexpected[i].buffer);
        rep_sb_printf(sb, "<tr class=\"%s\"><td class=\"n\">%d</td><td><code>", expired || up.len ? "warn" : "", k);
        esc(sb, q->match);
        rep_sb_printf(sb, "</code></td><td>");
        esc(sb, q->renderer ? q->renderer : "any");
        rep_sb_printf(sb, "</td><td>%s</td><td>", q->until[0] ? q->until : "—");
        esc(sb, q->reason);
        rep_sb_printf(sb, "</td><td>");
        if (expired)
            rep_sb_printf(sb, "<b>expired</b>: excuses nothing");
        else if (!applies)
            rep_sb_printf(sb, "not this renderer");
        else {
            rep_sb_printf(sb, "%zu expected failure%s", failed, failed == 1 ? "" : "s");
            if (up.len) {
                rep_sb_printf(sb, "; <b>unexpected pass</b>: ");
                esc(sb, up.s);
            }
        }
        free(up.s);
        rep_sb_printf(sb, "</td></tr>\n");
    }
    rep_sb_printf(sb, "</tbody></table></section>\n");
}

static void summary(rep_sb *sb, const page *pg, size_t listed)
{
    const rep_report *r = pg->r;
    size_t cnt[REP_V_COUNT] = {0}, xf = 0;
    for (size_t i = 0; i < r->count; i++) {
        cnt[r->entries[i].verdict] += !r->entries[i].expected;
        xf += r->entries[i].expected != 0;
    }
    rep_sb_printf(sb, "<header class=\"%s\" id=\"verdict\" data-exit=\"%d\"><h1>replay: %s</h1><p>", exit_class(r->exit),
                  (int)r->exit, rep_exit_word(r->exit));
    if (r->exit == REP_UNREADABLE) {
        esc(sb, r->error.msg);
        rep_sb_printf(sb, "<br>");
    }
    if (cnt[REP_V_SIZE])
        rep_sb_printf(sb, "%zu size mismatch · ", cnt[REP_V_SIZE]);
    if (xf)
        rep_sb_printf(sb, "%zu expected failure%s · ", xf, xf == 1 ? "" : "s");
    if (r->expect && r->expect->unexpected_count)
        rep_sb_printf(sb, "%d unexpected pass%s · ", r->expect->unexpected_count,
                      r->expect->unexpected_count == 1 ? "" : "es");
    if (r->expect && r->expect->expired_count)
        rep_sb_printf(sb, "%d expired expectation%s · ", r->expect->expired_count,
                      r->expect->expired_count == 1 ? "" : "s");
    if (r->golden_dir)
        rep_sb_printf(sb, "%zu failed · %zu warned · %zu within tolerance · %zu bit-exact", cnt[REP_V_FAIL],
                      cnt[REP_V_WARN], cnt[REP_V_WITHIN], cnt[REP_V_BITEXACT]);
    else
        rep_sb_printf(sb, "%zu failed · %zu checked (no golden)", cnt[REP_V_FAIL], cnt[REP_V_CHECKED]);
    rep_sb_printf(sb, " — %zu buffers, %d frames</p></header>\n<main>\n<dl class=\"sum\">", r->count, r->frames);
    rep_sb_printf(sb, "<dt>run</dt><dd>");
    esc(sb, r->run_dir);
    rep_sb_printf(sb, "</dd><dt>golden</dt><dd>");
    esc(sb, r->golden_dir ? r->golden_dir : "none: integrity and non-finite values only");
    if (r->golden_dir) {
        rep_sb_printf(sb, "</dd><dt>tolerances</dt><dd>");
        esc(sb, r->tol_path ? r->tol_path : "built-in");
    }
    char *note = rep_renderer_note(r);
    if (note) {
        rep_sb_printf(sb, "</dd><dt>renderer</dt><dd>");
        esc(sb, note);
    }
    free(note);
    rep_sb_printf(sb, "</dd><dt>frames</dt><dd>%d, %d buffers per frame</dd>", r->frames, r->buffers_per_frame);
    for (int i = 0; i < r->display_warning_count; i++) {
        rep_sb_printf(sb, "<dt>display warning</dt><dd class=\"warn\">%s frame %d: ",
                      r->display_warnings[i].golden ? "golden" : "run", r->display_warnings[i].frame);
        esc(sb, r->display_warnings[i].text);
        rep_sb_printf(sb, "</dd>");
    }
    for (int i = 0; i < r->tol_warning_count; i++) {
        rep_sb_printf(sb, "<dt>tolerance warning</dt><dd class=\"warn\">");
        esc(sb, r->tol_warnings[i]);
        rep_sb_printf(sb, "</dd>");
    }
    if (r->golden_dir && r->exit != REP_UNREADABLE) {
        rep_sb_printf(sb, "<dt>first digest difference</dt><dd>");
        if (r->digest_frame >= 0) {
            rep_sb_printf(sb, "frame %d <code>", r->digest_frame);
            esc(sb, r->digest_buffer);
            rep_sb_printf(sb, "</code> (");
            esc(sb, r->digest_why);
            rep_sb_printf(sb, ")");
        } else {
            rep_sb_printf(sb, "none: every digest matches the golden's");
        }
        rep_sb_printf(sb, "</dd>");
    }
    const rep_entry *first = NULL;
    for (size_t i = 0; i < r->count && !first; i++)
        if (rep_entry_listed(&r->entries[i]))
            first = &r->entries[i];
    rep_sb_printf(sb, "<dt>first differing frame</dt><dd id=\"first-difference\">");
    if (first) {
        rep_sb_printf(sb, "<a href=\"#e%zu\">frame %d <code>", (size_t)(first - r->entries), first->frame);
        esc(sb, first->buffer);
        rep_sb_printf(sb, "</code></a> (%s)", rep_verdict_name(first->verdict));
    } else {
        rep_sb_printf(sb, "none");
    }
    rep_sb_printf(sb, "</dd>");
    const rep_entry *wb = r->golden_dir ? rep_report_worst_block(r) : NULL;
    if (wb) {
        rep_sb_printf(sb, "<dt>worst block</dt><dd id=\"worst-block\"><a href=\"#e%zu\">", (size_t)(wb - r->entries));
        rep_sb w = {0};
        rep_block_text(&w, wb);
        esc(sb, w.s);
        free(w.s);
        rep_sb_printf(sb, "</a></dd>");
    }
    rep_sb_printf(sb, "</dl>\n");
    if (r->prov)
        prov_section(sb, r->prov);
    expect_section(sb, r);
    rep_sb_printf(sb, "<section id=\"differences\"><h2>%s (%zu, worst first)</h2>\n",
                  r->golden_dir ? "Buffers that are not bit-exact" : "Buffers that are not clean", listed);
    if (!listed)
        rep_sb_printf(sb, "<p>None.</p>\n");
}

static void all_table(rep_sb *sb, const rep_report *r, const rep_entry *const *order, size_t n)
{
    rep_sb_printf(sb, "<section id=\"all\"><h2>All buffers (%zu, worst first)</h2>\n<table class=\"all\"><thead><tr>"
                      "<th>verdict</th><th>frame</th><th>buffer</th><th>max |Δ|</th><th>RMSE</th><th>over fail</th>"
                      "<th>ꟻLIP mean / p99</th><th>NaN/Inf (run)</th></tr></thead><tbody>\n", n);
    for (size_t i = 0; i < n; i++) {
        const rep_entry *e = order[i];
        rep_sb_printf(sb, "<tr class=\"%s\"><td><span class=\"tag %s\">%s</span></td><td class=\"n\">%d</td><td>",
                      css_class(e), css_class(e), tag(e), e->frame);
        if (rep_entry_listed(e))
            rep_sb_printf(sb, "<a href=\"#e%zu\">", (size_t)(e - r->entries));
        rep_sb_printf(sb, "<code>");
        esc(sb, e->buffer);
        rep_sb_printf(sb, "</code>%s</td><td class=\"n\">", rep_entry_listed(e) ? "</a>" : "");
        if (e->compared && r->golden_dir) {
            num(sb, e->m.max_abs);
            rep_sb_printf(sb, "</td><td class=\"n\">");
            num(sb, e->m.rmse);
            rep_sb_printf(sb, "</td><td class=\"n\">%.3g%%", e->m.fail_percent);
        } else {
            rep_sb_printf(sb, "</td><td class=\"n\"></td><td class=\"n\">");
        }
        rep_sb_printf(sb, "</td><td class=\"n\">");
        if (e->flip_kind != REP_FLIP_NONE)
            rep_sb_printf(sb, "%.4f / %.4f", e->flip.mean, e->flip.p99);
        rep_sb_printf(sb, "</td><td class=\"n\">");
        if (e->compared)
            rep_sb_printf(sb, "%llu / %llu", (unsigned long long)e->m.run_nan, (unsigned long long)e->m.run_inf);
        rep_sb_printf(sb, "</td></tr>\n");
    }
    rep_sb_printf(sb, "</tbody></table></section>\n");
}

/* The final image of a frame: "final.display" if the frame has it, else its last buffer. */
static const char *final_buffer(const page *pg, int frame)
{
    const rep_run *src = pg->run && frame < pg->run->frame_count ? pg->run
                       : pg->golden && frame < pg->golden->frame_count ? pg->golden : NULL;
    if (!src)
        return NULL;
    const rep_frame_info *f = &src->frames[frame];
    int k = rep_frame_find(f, "final.display");
    if (k < 0)
        k = f->buffer_count - 1;
    return k >= 0 ? f->buffers[k].name : NULL;
}

/* The stability charts of a report (rep_stab_charts), on the thread that runs charts_main. */
typedef struct chart_job {
    const rep_report *r;
    const char *dir;
    char *rel[2];
} chart_job;

static void *charts_main(void *arg)
{
    chart_job *cj = arg;
    rep_stab_charts(cj->r, cj->dir, cj->rel);
    return NULL;
}

eng_result rep_report_html_write(const rep_report *r, const rep_run *run, const rep_run *golden, const char *dir,
                                 eng_error *err)
{
    page pg;
    memset(&pg, 0, sizeof pg);
    pg.r = r;
    pg.run = run;
    pg.golden = golden;
    pg.dir = dir;
    if (!realpath(dir, pg.real_dir))
        pg.real_dir[0] = 0;

    size_t n = 0;
    const rep_entry **order = rep_report_sorted(r, &n);
    size_t listed = 0;
    while (listed < n && rep_entry_listed(order[listed]))
        listed++;
    /* worst_first puts every listed entry before every unlisted one: listed verdicts rank
     * above bit-exact and checked. */

    tset *sets = rep_xcalloc(r->count, sizeof *sets);
    tset previews[2];
    memset(previews, 0, sizeof previews);
    job *jobs = rep_xcalloc(r->count + 2, sizeof *jobs);
    size_t nj = 0;
    int budget = REP_THUMB_MAX_IMAGES;
    int last = r->frames - 1;
    int preview_frames[2] = {0, last};
    int npreviews = r->exit == REP_UNREADABLE || r->frames < 1 ? 0 : last > 0 ? 2 : 1;
    for (int i = 0; i < npreviews; i++) {
        const char *b = final_buffer(&pg, preview_frames[i]);
        if (!b)
            continue;
        job *jb = &jobs[nj++];
        jb->frame = preview_frames[i];
        jb->buffer = b;
        jb->t = &previews[i];
        jb->want_run = run != NULL;
        jb->want_golden = golden != NULL;
        budget -= jb->want_run + jb->want_golden;
    }
    for (size_t i = 0; i < listed; i++) {
        const rep_entry *e = order[i];
        job jb = {e->frame, e->buffer, &sets[e - r->entries], 0, 0, 0, e};
        jb.want_run = run && e->frame < run->frame_count && rep_frame_find(&run->frames[e->frame], e->buffer) >= 0;
        jb.want_golden = golden && e->frame < golden->frame_count &&
                         rep_frame_find(&golden->frames[e->frame], e->buffer) >= 0;
        jb.want_diff = jb.want_run && jb.want_golden && e->verdict != REP_V_SIZE;
        int cost = jb.want_run + jb.want_golden + 2 * jb.want_diff; /* the diff and, maybe, ꟻLIP */
        if (cost == 0 || cost > budget)
            continue;
        budget -= cost;
        jobs[nj++] = jb;
    }
    char *imgdir = rep_path_join(dir, "img");
    eng_result res = rep_remove_tree(imgdir, err);
    if (res == ENG_OK && (nj > 0 || r->stab))
        res = rep_mkdirs(imgdir, err);
    /* The stability charts (PLplot, which loads its cairo driver and fontconfig on first use,
     * ~0.1 s of one core) are drawn on a thread of their own while the thumbnails are made: their
     * files are their own and the page names them the same whichever finishes first. */
    chart_job cj = {r, dir, {NULL, NULL}};
    pthread_t chart_thread;
    int charts = res == ENG_OK && r->stab != NULL;
    int charting = charts && pthread_create(&chart_thread, NULL, charts_main, &cj) == 0;
    if (charts && !charting)
        charts_main(&cj); /* no thread to be had: drawn here, as before */
    if (res == ENG_OK)
        run_jobs(&pg, jobs, nj);
    if (charting)
        pthread_join(chart_thread, NULL);

    rep_sb sb = {0};
    if (res == ENG_OK) {
        rep_sb_printf(&sb, "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                           "<meta name=\"viewport\" content=\"width=device-width,initial-scale=1\">\n<title>ispm replay: %s — ",
                      rep_exit_word(r->exit));
        esc(&sb, r->run_dir);
        rep_sb_printf(&sb, "</title>\n<style>%s</style>\n</head>\n<body>\n", CSS);
        summary(&sb, &pg, listed);
        for (size_t i = 0; i < listed; i++)
            card(&sb, &pg, order[i], &sets[order[i] - r->entries]);
        rep_sb_printf(&sb, "</section>\n");
        rep_stab_html(&sb, r, cj.rel);
        if (npreviews) {
            rep_sb_printf(&sb, "<section id=\"previews\"><h2>Final image, first and last frame</h2><div class=\"previews\">\n");
            for (int i = 0; i < npreviews; i++) {
                const char *b = final_buffer(&pg, preview_frames[i]);
                if (!b)
                    continue;
                rep_sb_printf(&sb, "<div class=\"preview\"><h3>frame %d · <code>", preview_frames[i]);
                esc(&sb, b);
                rep_sb_printf(&sb, "</code></h3>\n");
                thumbs(&sb, &previews[i], NULL, NULL, 0, NULL);
                rep_sb_printf(&sb, "</div>\n");
            }
            rep_sb_printf(&sb, "</div></section>\n");
        }
        all_table(&sb, r, order, n);
        rep_sb_printf(&sb,
                      "</main>\n<footer><h2>How thumbnails are made</h2><p>Thumbnails are box-filtered so the longest "
                      "side is at most %d pixels and shown at an integer magnification. <b>*.display</b> buffers are "
                      "already exposed and sRGB-encoded: values are clamped to [0,1] and scaled to 255. "
                      "<b>*.radiance</b> buffers are linear: clamped to [0,1], then the sRGB curve (no exposure). "
                      "Every other buffer is data: one linear ramp from the smallest to the largest finite value of "
                      "the shown channels over golden and run together (both thumbnails share it). Channels shown: "
                      "R,G,B if present, else the first three (two: red, green; one: grey). NaN or Inf is "
                      "<b style=\"color:#f0f\">magenta</b>. The difference is the largest |new − golden| over common "
                      "channels, maximum over each box: black where equal, then dark red (smallest non-zero) through "
                      "yellow to white at the buffer's largest difference; magenta where a value's class "
                      "(finite/NaN/+Inf/−Inf) changed; a <b style=\"color:#00c8ff\">cyan</b> square ring (over black only) "
                      "marks the largest difference. The ꟻLIP heat map (colour buffers: *.display as LDR-ꟻLIP, "
                      "*.radiance as HDR-ꟻLIP over the rule's pinned exposure range) shows per pixel how visible the "
                      "difference is when flipping between the images, black 0 through purple and orange to pale "
                      "yellow 1, maximum over each box. A <span class=\"blkkey\"></span>magenta frame over all four marks "
                      "the worst block: the block_size × block_size block (8 × 8 unless the rule says otherwise, aligned "
                      "to pixel (0,0)) with the largest mean |new − golden| (docs/regression.md). At most %d thumbnails, "
                      "worst buffers first.</p></footer>\n"
                      "<script>%s</script>\n</body>\n</html>\n",
                      REP_THUMB_MAX_SIDE, REP_THUMB_MAX_IMAGES, JS);
        char *path = rep_path_join(dir, "report.html");
        res = rep_write_atomic(path, sb.s, sb.len, err);
        free(path);
    }
    free(sb.s);
    free(imgdir);
    free(cj.rel[0]);
    free(cj.rel[1]);
    for (size_t i = 0; i < r->count; i++) {
        free(sets[i].golden);
        free(sets[i].run);
        free(sets[i].diff);
        free(sets[i].flip);
    }
    for (int i = 0; i < 2; i++) {
        free(previews[i].golden);
        free(previews[i].run);
        free(previews[i].diff);
    }
    free(sets);
    free(jobs);
    free(order);
    return res;
}
