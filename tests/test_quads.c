/* test_quads.c — Check suite of the photon quads (engine/indirect/ind_quads.c, 001_… §3.3): on the
 * Cornell box, the GPU quads against a CPU evaluation of the same flat kernel
 * (shaders/quad_kernel.glsl) at every pixel — in particular with the camera 1.5 cm from a wall
 * and the near plane at 5 mm, where photon volumes may be clipped (003_… §6.3) and quads must
 * lose nothing; against the tile gather (002 §6.3, equal to the k-d gather and the photon
 * volumes) on pixels where every photon that reaches the pixel lies on the pixel's own plane
 * (there the two kernels are the same function); darker than the gather where the gather's
 * ellipsoid reaches across a corner; the irradiance mode of the filters likewise; no NaN; and
 * bit-identical buffers for 1 and 2 llvmpipe/Embree threads (each count in a process of its
 * own: llvmpipe reads LP_NUM_THREADS once per process). */
#include "eng.h"
#include "indirect.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CORNELL_GLTF ISPM_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define SIZE 48

static const char *g_self; /* this executable, for the per-thread-count child processes */
static int g_child;        /* running as such a child: no Check test is running */

/* ck_assert_msg, or in a child (outside any Check test, where even a passing ck_assert would try
 * to report progress to the runner) a message and exit status 1. */
#define REQUIRE(cond, ...)                                                                                          \
    do {                                                                                                           \
        if (!g_child) {                                                                                            \
            ck_assert_msg(cond, __VA_ARGS__);                                                                      \
        } else if (!(cond)) {                                                                                      \
            fprintf(stderr, "test_quads child: " __VA_ARGS__);                                                      \
            fprintf(stderr, "\n");                                                                                  \
            exit(1);                                                                                               \
        }                                                                                                          \
    } while (0)

/* ---------------------------------------------------------------- rendering */

typedef struct kept {
    char name[64];
    int w, h, n;
    float *data;
} kept;

typedef struct keeper {
    float eye[3];         /* the frame's camera position */
    eng_settings settings; /* the sequence's, as parsed */
    int count;
    kept bufs[160];
} keeper;

static int keep_buffer(void *user, int frame, const eng_buffer *b)
{
    (void)frame;
    keeper *k = user;
    REQUIRE(k->count < 160, "more than 160 buffers");
    kept *d = &k->bufs[k->count++];
    snprintf(d->name, sizeof d->name, "%s", b->name);
    d->w = b->width;
    d->h = b->height;
    d->n = b->channel_count;
    size_t sz = (size_t)b->width * b->height * b->channel_count * sizeof(float);
    d->data = malloc(sz);
    memcpy(d->data, b->data, sz);
    return 0;
}

static int keep_eye(void *user, const eng_frame_stats *st)
{
    keeper *k = user;
    memcpy(k->eye, st->camera_eye, sizeof k->eye);
    return 0;
}

static const kept *find(const keeper *k, const char *name)
{
    for (int i = 0; i < k->count; i++)
        if (!strcmp(k->bufs[i].name, name))
            return &k->bufs[i];
    return NULL;
}

static const kept *need(const keeper *k, const char *name)
{
    const kept *b = find(k, name);
    REQUIRE(b != NULL, "buffer %s was not announced", name);
    return b;
}

static void keeper_clear(keeper *k)
{
    for (int i = 0; i < k->count; i++)
        free(k->bufs[i].data);
    memset(k, 0, sizeof *k);
}

/* The camera of a view: the Cornell box's own, or 1.5 cm from its back wall (the near-plane
 * stress sequence's last key) with znear 5 mm. */
enum { VIEW_CAMERA, VIEW_CLOSE };

/* Renders `frame` of the Cornell box at SIZE² with the given indirect method into k. extra is
 * spliced into the settings (",\"key\":value…" or ""). */
static void render_cornell(const char *indirect, int view, int threads, const char *extra, int frame, keeper *k)
{
    static const char *cams[] = {
        "{\"node\":\"Camera\"}",
        "{\"keys\":[{\"time\":0,\"position\":[0,1,-0.985],\"target\":[0,1,-2]}],\"yfov_deg\":50,\"znear\":0.005}"};
    char json[2048];
    snprintf(json, sizeof json,
             "{\"name\":\"quads\",\"scene\":\"%s\",\"frames\":2,\"fps\":8,\"resolution\":[%d,%d],"
             "\"camera\":%s,\"settings\":{\"shadow_map_size\":128,\"threads\":%d,"
             "\"photon_count\":4096,\"kernel_radius\":0.15,\"boundary\":\"renormalize\",\"indirect\":\"%s\"%s}}",
             CORNELL_GLTF, SIZE, SIZE, cams[view], threads, indirect, extra);
    eng_error err;
    seq_sequence *seq = calloc(1, sizeof *seq);
    REQUIRE(seq_parse("inline.json", json, strlen(json), seq, &err) == ENG_OK, "%s", err.msg);
    scn_scene *scene = NULL;
    REQUIRE(scn_load_gltf(seq->scene_path, &scene, &err) == ENG_OK, "%s", err.msg);
    k->settings = seq->settings;
    eng_engine *eng = NULL;
    eng_desc d = {.scene = scene, .sequence = seq};
    REQUIRE(eng_create(&d, &eng, &err) == ENG_OK, "%s", err.msg);
    eng_listener l = {k, NULL, keep_buffer, keep_eye};
    REQUIRE(eng_add_listener(eng, &l) == ENG_OK, "listener");
    REQUIRE(eng_render_frame(eng, frame, &err) == ENG_OK, "%s", err.msg);
    eng_destroy(eng);
    scn_destroy(scene);
    free(seq);
}

/* photons.map back into photons (one per pixel, bounce 0 = unused). */
static size_t photons_of(const kept *pm, eng_photon_map *m)
{
    size_t all = (size_t)pm->w * pm->h;
    m->photons = calloc(all, sizeof *m->photons);
    m->count = 0;
    for (size_t i = 0; i < all; i++) {
        const float *d = pm->data + 14 * i;
        if (d[13] == 0.0f)
            continue;
        eng_photon *p = &m->photons[m->count++];
        memcpy(p->position, d, 12);
        memcpy(p->direction, d + 3, 12);
        memcpy(p->power, d + 6, 12);
        memcpy(p->normal, d + 9, 12);
        p->path_density = d[12];
        p->bounce = (uint32_t)d[13];
    }
    m->capacity = all;
    return m->count;
}

/* ---------------------------------------------------------------- the kernels on the CPU */

static double dot3(const float a[3], const float b[3])
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

/* The tangent frame of shaders/quads.vert.glsl. */
static void tangent_frame(const float n[3], double t[3], double b[3])
{
    double a[3] = {fabsf(n[0]) > 0.9f ? 0.0 : 1.0, fabsf(n[0]) > 0.9f ? 1.0 : 0.0, 0.0};
    double c[3] = {a[1] * n[2] - a[2] * n[1], a[2] * n[0] - a[0] * n[2], a[0] * n[1] - a[1] * n[0]};
    double l = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    for (int k = 0; k < 3; k++)
        t[k] = c[k] / l;
    b[0] = n[1] * t[2] - n[2] * t[1];
    b[1] = n[2] * t[0] - n[0] * t[2];
    b[2] = n[0] * t[1] - n[1] * t[0];
}

/* Where a test is within rounding of its boundary the GPU and the CPU may decide it
 * differently: such a pixel is left out of the comparisons. */
#define EDGE 1e-4

/* One photon at one pixel (surface point s, normal n, seen from eye), shaders/quad_kernel.glsl
 * in double plus the rasteriser's coverage: the pixel's view ray (eye → s) must cross the
 * quad's plane inside the square of half-size 1.01 r_xy (quads.vert.glsl) in front of the eye.
 * The near plane is deliberately not modelled: quads must lose nothing to it. Returns κ, or −1
 * where the pixel does not receive the photon; *undecided is set where one test is within
 * rounding of its boundary and every other test passes. */
static double quad_kappa(const float s[3], const float n[3], const float eye[3], const eng_photon *ph, double rxy,
                         double rz, int *undecided)
{
    float d[3] = {s[0] - ph->position[0], s[1] - ph->position[1], s[2] - ph->position[2]};
    double h = dot3(d, ph->normal), w = dot3(n, ph->normal);
    double dt[3] = {d[0] - h * ph->normal[0], d[1] - h * ph->normal[1], d[2] - h * ph->normal[2]};
    double t2 = (dt[0] * dt[0] + dt[1] * dt[1] + dt[2] * dt[2]) / (rxy * rxy);
    /* Coverage. */
    double v[3] = {(double)s[0] - eye[0], (double)s[1] - eye[1], (double)s[2] - eye[2]};
    double xe[3] = {(double)ph->position[0] - eye[0], (double)ph->position[1] - eye[1],
                    (double)ph->position[2] - eye[2]};
    double den = v[0] * ph->normal[0] + v[1] * ph->normal[1] + v[2] * ph->normal[2];
    double cov = -1.0; /* margin: > 0 inside the square */
    if (fabs(den) > 1e-12) {
        double tau = (xe[0] * ph->normal[0] + xe[1] * ph->normal[1] + xe[2] * ph->normal[2]) / den;
        if (tau > 0.0) {
            double tt[3], bb[3], q[3];
            tangent_frame(ph->normal, tt, bb);
            for (int k = 0; k < 3; k++)
                q[k] = tau * v[k] - xe[k];
            double u = fabs(q[0] * tt[0] + q[1] * tt[1] + q[2] * tt[2]);
            double vv = fabs(q[0] * bb[0] + q[1] * bb[1] + q[2] * bb[2]);
            cov = (1.01 * rxy - fmax(u, vv)) / rxy;
        }
    }
    const double margin[4] = {(rz - fabs(h)) / rz, w, 1.0 - t2, cov};
    /* n·n_p is exactly 0 on the GPU too where every product is 0 (axis-aligned walls). */
    const int w_exact = n[0] * ph->normal[0] == 0.0f && n[1] * ph->normal[1] == 0.0f && n[2] * ph->normal[2] == 0.0f;
    int fail_far = 0, near = 0;
    for (int k = 0; k < 4; k++) {
        if (fabs(margin[k]) <= EDGE && !(k == 1 && w_exact))
            near = 1;
        else if (margin[k] < 0.0 || (k == 1 && margin[k] == 0.0))
            fail_far = 1;
    }
    if (near && !fail_far)
        *undecided = 1;
    if (fail_far || margin[0] < 0.0 || margin[1] <= 0.0 || margin[2] <= 0.0 || margin[3] <= 0.0)
        return -1.0;
    return 2.0 / (ENG_PI * rxy * rxy) * (1.0 - t2) * w;
}

/* The ellipsoid of the photon volumes and gathers (003 §5.1, photon_kernel.glsl): does it
 * reach s? */
static int ellipsoid_reaches(const float s[3], const eng_photon *ph, double rxy, double rz)
{
    float d[3] = {s[0] - ph->position[0], s[1] - ph->position[1], s[2] - ph->position[2]};
    double len = sqrt(dot3(d, d));
    double t = len > 0.0 ? len / rxy * (1.0 + fabs(dot3(d, ph->normal)) / len * (rxy - rz) / rz) : 0.0;
    return t < 1.0;
}

/* Per pixel of a rendered frame: the CPU quad estimate (radiance RGB, irradiance RGB, count),
 * and the pixel's class: PLANAR where every photon that reaches it (by the ellipsoid or the
 * quad) lies in its plane (|h| < 1e-5 m, n·n_p > 1 − 1e-6), CORNER where the ellipsoid of a
 * photon on a surface at more than 60° to the pixel's reaches it. */
enum { PX_BACKGROUND, PX_PLANAR, PX_CORNER, PX_OTHER };
typedef struct cpu_quads {
    double radiance[SIZE * SIZE][3], irradiance[SIZE * SIZE][3];
    int count[SIZE * SIZE];
    int cls[SIZE * SIZE];
    int undecidable[SIZE * SIZE];
} cpu_quads;

/* The Cornell box is Lambertian (no metal, no glass); the diffuse BSDF is then all there is. */
static void cpu_quads_eval(const keeper *k, const eng_settings *s, cpu_quads *q)
{
    const kept *pos = need(k, "gbuffer.position"), *nrm = need(k, "gbuffer.normal");
    const kept *alb = need(k, "gbuffer.albedo"), *mat = need(k, "gbuffer.material");
    eng_photon_map map;
    ck_assert_uint_gt(photons_of(need(k, "photons.map"), &map), 500);
    memset(q, 0, sizeof *q);
    for (int i = 0; i < SIZE * SIZE; i++) {
        const float *m = mat->data + 5 * i;
        if (m[4] < 0.0f) {
            q->cls[i] = PX_BACKGROUND;
            continue;
        }
        ck_assert_msg(m[1] == 0.0f && m[2] == 0.0f, "pixel %d: the CPU evaluation is diffuse only", i);
        const float *sp = pos->data + 3 * i, *n = nrm->data + 3 * i, *a = alb->data + 3 * i;
        int on_plane_only = 1, off_plane_ellipsoid = 0, any = 0;
        for (size_t j = 0; j < map.count; j++) {
            const eng_photon *ph = &map.photons[j];
            double rxy = splat_radius(s->kernel_radius, ph->path_density);
            double rz = rxy * s->normal_compression;
            float d[3] = {sp[0] - ph->position[0], sp[1] - ph->position[1], sp[2] - ph->position[2]};
            double h = dot3(d, ph->normal), w = dot3(n, ph->normal);
            int ell = ellipsoid_reaches(sp, ph, rxy, rz);
            double kq = quad_kappa(sp, n, k->eye, ph, rxy, rz, &q->undecidable[i]);
            if (ell || kq >= 0.0) {
                any = 1;
                if (!(fabs(h) < 1e-5 && w > 1.0 - 1e-6))
                    on_plane_only = 0;
                if (ell && w < 0.5)
                    off_plane_ellipsoid = 1;
            }
            if (kq < 0.0)
                continue;
            double cos_i = dot3(ph->direction, n);
            if (cos_i <= 0.0)
                continue;
            for (int c = 0; c < 3; c++) {
                double e = ph->power[c] * kq;
                q->irradiance[i][c] += e;
                q->radiance[i][c] += a[c] / ENG_PI * e;
            }
            q->count[i]++;
        }
        q->cls[i] = !any ? PX_OTHER : on_plane_only ? PX_PLANAR : off_plane_ellipsoid ? PX_CORNER : PX_OTHER;
    }
    free(map.photons);
}

/* GPU float sums against the CPU's double sums: relative `rel` where the value is not tiny,
 * else absolute 1e-5 of the image's peak. rel = 1e-4 for float rounding of up to a few hundred
 * terms (measured worst: see the tests' output). */
static int close_enough(double gpu, double cpu, double peak, double rel)
{
    double d = fabs(gpu - cpu);
    return fabs(cpu) > 1e-3 * peak ? d <= rel * fabs(cpu) : d <= 1e-5 * peak;
}

static double peak_of(const float *rgb, int n)
{
    double p = 0.0;
    for (int i = 0; i < n; i++)
        p = fmax(p, rgb[i]);
    return p;
}

/* Every pixel of a quads render (radiance mode) equals the CPU evaluation. Returns the number
 * of pixels compared. */
static int check_against_cpu(const keeper *k, const eng_settings *s, const char *what)
{
    static cpu_quads q;
    cpu_quads_eval(k, s, &q);
    const kept *qi = need(k, "splat.indirect"), *qc = need(k, "splat.count");
    const kept *ir = need(k, "indirect.radiance");
    const kept *bw = need(k, "boundary.weight"); /* the boundary correction (boundary.h) */
    for (int i = 0; i < SIZE * SIZE; i++)
        for (int c = 0; c < 3; c++)
            ck_assert(ir->data[3 * i + c] == qi->data[3 * i + c] / bw->data[i]);
    double peak = peak_of(qi->data, SIZE * SIZE * 3);
    ck_assert_msg(peak > 0.0, "%s: no indirect light", what);
    int compared = 0, lit = 0, skipped = 0;
    for (int i = 0; i < SIZE * SIZE; i++) {
        for (int c = 0; c < 3; c++)
            ck_assert_msg(isfinite(qi->data[3 * i + c]), "%s: pixel %d: %g", what, i, qi->data[3 * i + c]);
        if (q.cls[i] == PX_BACKGROUND) {
            for (int c = 0; c < 3; c++)
                ck_assert_msg(qi->data[3 * i + c] == 0.0f, "%s: background pixel %d lit", what, i);
            continue;
        }
        if (q.undecidable[i]) {
            skipped++;
            continue;
        }
        compared++;
        ck_assert_msg(qc->data[i] == (float)q.count[i], "%s: pixel (%d,%d): %g quads reach it, %d expected", what,
                      i % SIZE, i / SIZE, qc->data[i], q.count[i]);
        for (int c = 0; c < 3; c++) {
            lit += q.radiance[i][c] > 1e-3 * peak;
            ck_assert_msg(close_enough(qi->data[3 * i + c], q.radiance[i][c], peak, 1e-4),
                          "%s: pixel (%d,%d) ch %d: GPU %.9g, CPU %.9g", what, i % SIZE, i / SIZE, c,
                          qi->data[3 * i + c], q.radiance[i][c]);
        }
    }
    fprintf(stderr, "quads vs CPU (%s): %d pixels compared (%d lit values), %d within rounding of a kernel edge\n",
            what, compared, lit, skipped);
    ck_assert_int_gt(lit, SIZE * SIZE);
    ck_assert_int_le(skipped, SIZE * SIZE / 20);
    return compared;
}

/* ---------------------------------------------------------------- tests */

START_TEST(quads_equal_the_cpu_kernel)
{
    static keeper k;
    render_cornell("quads", VIEW_CAMERA, 2, "", 1, &k);
    ck_assert(find(&k, "splat.indirect") && !find(&k, "gather.indirect")); /* a scatter's buffers */
    check_against_cpu(&k, &k.settings, "Cornell box camera");
    keeper_clear(&k);
}
END_TEST

/* 1.5 cm from the back wall, znear 5 mm: the quads still deliver every photon the CPU kernel
 * says reaches a visible pixel (no near-plane clipping loss, 001 §5 vs 003 §6.3). */
START_TEST(quads_lose_nothing_at_the_near_plane)
{
    static keeper k;
    render_cornell("quads", VIEW_CLOSE, 2, "", 1, &k);
    check_against_cpu(&k, &k.settings, "1.5 cm from the wall");
    keeper_clear(&k);
}
END_TEST

/* Quads against the gather on one plane: the two kernels are then the same function of
 * |s − x|, up to the photon's height h < 1e-5 m over the pixel's plane, which moves the
 * ellipsoid's t by |h|(1/r_z − 1/r_xy) ≤ 2.7e-4 at r_xy = 0.0375 m (the smallest radius) and
 * 1 − t² by twice that at most: 5e-4 relative (measured worst: 5.8e-5). */
#define PLANE_REL 5e-4

/* The tile gather (bit-identical to the k-d gather) and the quads, on the same photon map:
 * equal where every photon reaching a pixel lies in its plane; darker across corners. */
static void compare_with_gather(const char *extra, const char *qname, const char *gname, int irradiance)
{
    static keeper kq, kg;
    static cpu_quads q;
    render_cornell("quads", VIEW_CAMERA, 2, extra, 1, &kq);
    render_cornell("tile-gather", VIEW_CAMERA, 2, extra, 1, &kg);
    const kept *pq = need(&kq, "photons.map"), *pg = need(&kg, "photons.map");
    ck_assert_msg(pq->w == pg->w && pq->h == pg->h &&
                      !memcmp(pq->data, pg->data, (size_t)pq->w * pq->h * 14 * sizeof(float)),
                  "the two methods must use the same photon map");
    cpu_quads_eval(&kq, &kq.settings, &q);
    const kept *a = need(&kq, qname), *b = need(&kg, gname);
    double peak = peak_of(b->data, SIZE * SIZE * 3);
    ck_assert(peak > 0.0);
    int planar = 0, corner = 0;
    double worst_rel = 0.0, sum_q = 0.0, sum_g = 0.0, sum_q_all = 0.0, sum_g_all = 0.0;
    for (int i = 0; i < SIZE * SIZE; i++) {
        for (int c = 0; c < 3; c++) {
            ck_assert_msg(isfinite(a->data[3 * i + c]), "pixel %d: quads %g", i, a->data[3 * i + c]);
            sum_q_all += a->data[3 * i + c];
            sum_g_all += b->data[3 * i + c];
        }
        if (q.undecidable[i])
            continue;
        if (q.cls[i] == PX_PLANAR) {
            planar++;
            for (int c = 0; c < 3; c++) {
                double x = a->data[3 * i + c], y = b->data[3 * i + c];
                ck_assert_msg(close_enough(x, y, peak, PLANE_REL), "%s, pixel (%d,%d) ch %d on one plane: quads %.9g, gather %.9g",
                              qname, i % SIZE, i / SIZE, c, x, y);
                if (fabs(y) > 1e-3 * peak)
                    worst_rel = fmax(worst_rel, fabs(x - y) / fabs(y));
            }
        } else if (q.cls[i] == PX_CORNER) {
            corner++;
            for (int c = 0; c < 3; c++) {
                sum_q += a->data[3 * i + c];
                sum_g += b->data[3 * i + c];
            }
        }
    }
    fprintf(stderr,
            "quads vs tile gather (%s): %d pixels on one plane, worst relative %.3g; %d corner pixels, "
            "mean quads/gather %.4f there; whole image %.4f\n",
            qname, planar, worst_rel, corner, sum_q / sum_g, sum_q_all / sum_g_all);
    ck_assert_int_gt(planar, SIZE * SIZE / 4);
    ck_assert_int_gt(corner, SIZE);
    /* The corner pixels lose the photons of the other surface (measured at 48², frame 1: 0.913
     * radiance, 0.902 irradiance); over the whole image that is about 1 % (0.992). With the
     * ellipsoid's kernel both would be 1. */
    ck_assert_msg(sum_q < 0.95 * sum_g, "corners not darker: quads %g, gather %g", sum_q, sum_g);
    ck_assert_msg(sum_q > 0.7 * sum_g, "corners far too dark: quads %g, gather %g", sum_q, sum_g);
    ck_assert_msg(sum_q_all < sum_g_all && sum_q_all > 0.95 * sum_g_all, "whole image: quads %g, gather %g",
                  sum_q_all, sum_g_all);
    if (irradiance) { /* the glossy part: none on a Lambertian scene */
        const kept *gq = need(&kq, "splat.glossy");
        for (int i = 0; i < SIZE * SIZE * 3; i++)
            ck_assert(gq->data[i] == 0.0f);
    }
    keeper_clear(&kq);
    keeper_clear(&kg);
}

START_TEST(quads_equal_the_gather_on_a_plane_and_are_darker_in_corners)
{
    compare_with_gather("", "splat.indirect", "gather.indirect", 0);
}
END_TEST

/* The filters' irradiance mode (one À-Trous iteration: full resolution, irradiance buffers). */
START_TEST(irradiance_mode_likewise)
{
    compare_with_gather(",\"atrous_iterations\":1", "splat.irradiance", "gather.irradiance", 1);
}
END_TEST

/* Child process: renders frame 1 with `threads` threads and writes splat.indirect and
 * splat.count to `path`. */
static int child_render(int threads, const char *path)
{
    static keeper k;
    render_cornell("quads", VIEW_CAMERA, threads, "", 1, &k);
    const kept *qi = need(&k, "splat.indirect"), *qc = need(&k, "splat.count");
    FILE *f = fopen(path, "wb");
    if (!f)
        return 1;
    int ok = fwrite(qi->data, sizeof(float), SIZE * SIZE * 3, f) == SIZE * SIZE * 3 &&
             fwrite(qc->data, sizeof(float), SIZE * SIZE, f) == SIZE * SIZE;
    ok = (fclose(f) == 0) && ok;
    keeper_clear(&k);
    return ok ? 0 : 1;
}

START_TEST(quads_are_bit_identical_for_1_and_2_threads)
{
    static float out[2][SIZE * SIZE * 4];
    const int threads[2] = {1, 2};
    for (int t = 0; t < 2; t++) {
        char path[512], cmd[1200];
        snprintf(path, sizeof path, "%s/tests/test_quads.threads%d.bin", ISPM_BINARY_DIR, threads[t]);
        remove(path);
        snprintf(cmd, sizeof cmd, "'%s' --child %d '%s'", g_self, threads[t], path);
        ck_assert_msg(system(cmd) == 0, "child with %d threads failed", threads[t]);
        FILE *f = fopen(path, "rb");
        ck_assert(f != NULL);
        ck_assert_int_eq(fread(out[t], sizeof(float), SIZE * SIZE * 4, f), SIZE * SIZE * 4);
        fclose(f);
        remove(path);
    }
    ck_assert_msg(peak_of(out[0], SIZE * SIZE * 3) > 0.0, "no indirect light");
    ck_assert_msg(!memcmp(out[0], out[1], sizeof out[0]), "1 and 2 threads differ");
}
END_TEST

static Suite *quads_suite(void)
{
    Suite *s = suite_create("quads");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 600);
    tcase_add_test(tc, quads_equal_the_cpu_kernel);
    tcase_add_test(tc, quads_lose_nothing_at_the_near_plane);
    tcase_add_test(tc, quads_equal_the_gather_on_a_plane_and_are_darker_in_corners);
    tcase_add_test(tc, irradiance_mode_likewise);
    tcase_add_test(tc, quads_are_bit_identical_for_1_and_2_threads);
    suite_add_tcase(s, tc);
    return s;
}

int main(int argc, char **argv)
{
    g_self = argv[0];
    if (argc == 4 && !strcmp(argv[1], "--child")) {
        g_child = 1;
        return child_render(atoi(argv[2]), argv[3]);
    }
    SRunner *sr = srunner_create(quads_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
