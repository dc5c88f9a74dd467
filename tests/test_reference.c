/* test_reference.c — Check suite of the reference renderer (engine/reference/reference.c) against
 * closed forms:
 *   - Cornell box: the direct radiance of lit floor pixels is (Kd/π)·I·cosθ/d² (the scene
 *     README's analytic check, with the camera ray built here from the spec's camera, not the
 *     engine's matrices), and the engine's rasterised direct.radiance agrees on those pixels
 *     (same pixel centres, row 0 on top);
 *   - a closed sphere of albedo ρ with a point light at its centre (scenes/furnace): direct
 *     (ρ/π)·I·cosθ/d² per pixel, and the area mean of the indirect radiance equals the energy
 *     balance of any closed enclosure, ρ²Φ/((1−ρ)πA);
 *   - the caustic estimator: a delta mirror under a point light (scenes/furnace/mirror-caustic)
 *     lights the ceiling like the light's mirror image scaled by the Schlick reflectance; on
 *     the glass sphere the caustic estimate at N and 4N samples agrees (the shrinking radius
 *     keeps it consistent);
 *   - pixel centres (ref_desc.pixel_center): on the floor's front edge, where a box-filtered pixel
 *     is part background, the reference takes the closed form at the pixel centre's floor point,
 *     as the engine's G-buffers do;
 *   - determinism: 1 and 2 threads give bit-identical buffers; full = direct + indirect. */
#include "cap.h"
#include "eng_frame.h"
#include "ref.h"
#include "furnace_test_util.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CORNELL_DIR ISPM_SOURCE_DIR "/scenes/cornell-box/"
#define FURNACE_DIR ISPM_SOURCE_DIR "/scenes/furnace/"

/* ---------------------------------------------------------------- harness */

typedef struct images {
    int width, height;
    float *direct, *indirect, *full; /* reference buffers */
    float *engine_direct;            /* direct.radiance, when the engine rendered */
    int announced;
} images;

static int grab(void *user, int frame, const eng_buffer *b)
{
    (void)frame;
    images *im = user;
    float **slot = !strcmp(b->name, "reference.direct")     ? &im->direct
                 : !strcmp(b->name, "reference.indirect")   ? &im->indirect
                 : !strcmp(b->name, "reference.full")       ? &im->full
                 : !strcmp(b->name, "direct.radiance")      ? &im->engine_direct
                                                            : NULL;
    if (!slot)
        return 0;
    ck_assert_int_eq(b->channel_count, 3);
    size_t n = (size_t)b->width * (size_t)b->height * 3;
    free(*slot);
    *slot = malloc(n * sizeof(float));
    ck_assert_ptr_nonnull(*slot);
    memcpy(*slot, b->data, n * sizeof(float));
    im->width = b->width;
    im->height = b->height;
    im->announced++;
    return 0;
}

static void images_free(images *im)
{
    free(im->direct);
    free(im->indirect);
    free(im->full);
    free(im->engine_direct);
    memset(im, 0, sizeof *im);
}

/* A loaded sequence, scene and engine (indirect none), for one test. */
typedef struct setup {
    seq_sequence seq;
    scn_scene *scene;
    eng_engine *engine;
} setup;

static void setup_open(setup *s, const char *seq_path, const char *json, int size, int threads)
{
    eng_error err = {{0}};
    memset(s, 0, sizeof *s);
    eng_result r = json ? seq_parse(seq_path, json, strlen(json), &s->seq, &err) : seq_load(seq_path, &s->seq, &err);
    ck_assert_msg(r == ENG_OK, "%s", err.msg);
    if (size) {
        s->seq.width = size;
        s->seq.height = size;
    }
    s->seq.settings.indirect = ENG_INDIRECT_NONE;
    s->seq.settings.threads = threads;
    r = scn_load_gltf(s->seq.scene_path, &s->scene, &err);
    ck_assert_msg(r == ENG_OK, "%s", err.msg);
    eng_desc ed = {.scene = s->scene, .sequence = &s->seq};
    r = eng_create(&ed, &s->engine, &err);
    ck_assert_msg(r == ENG_OK, "%s", err.msg);
}

static void setup_close(setup *s)
{
    eng_destroy(s->engine);
    scn_destroy(s->scene);
}

/* Renders frame 0 with the reference renderer into im. */
static void render_ref(setup *s, ref_desc d, images *im)
{
    eng_error err = {{0}};
    d.engine = s->engine;
    d.sequence = &s->seq;
    d.quiet = 1;
    ref_renderer *r = NULL;
    eng_result res = ref_create(&d, &r, &err);
    ck_assert_msg(res == ENG_OK, "%s", err.msg);
    eng_listener l = {im, NULL, grab, NULL};
    ck_assert_int_eq(ref_add_listener(r, &l), ENG_OK);
    res = ref_render_frame(r, 0, &err);
    ck_assert_msg(res == ENG_OK, "%s", err.msg);
    ref_destroy(r);
    ck_assert_ptr_nonnull(im->direct);
    ck_assert_ptr_nonnull(im->indirect);
    ck_assert_ptr_nonnull(im->full);
}

static double dot3_f(const float a[3], const float b[3])
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

/* Unit ray through the centre of pixel (x, y) (row 0 on top) of a pinhole at a camera with
 * the given right/up/forward axes and tan of half the vertical field of view (square image). */
static void pixel_ray(int x, int y, int size, const float right[3], const float up[3], const float fwd[3],
                      double tan_half, double dir[3])
{
    double sx = (2.0 * (x + 0.5) / size - 1.0) * tan_half, sy = (1.0 - 2.0 * (y + 0.5) / size) * tan_half;
    double l = 0.0;
    for (int i = 0; i < 3; i++) {
        dir[i] = sx * right[i] + sy * up[i] + fwd[i];
        l += dir[i] * dir[i];
    }
    for (int i = 0; i < 3; i++)
        dir[i] /= sqrt(l);
}

static void full_is_sum(const images *im)
{
    size_t n = (size_t)im->width * (size_t)im->height * 3;
    for (size_t i = 0; i < n; i++)
        if (im->full[i] != im->direct[i] + im->indirect[i])
            ck_abort_msg("reference.full[%zu] = %g is not direct + indirect = %g", i, (double)im->full[i],
                         (double)(im->direct[i] + im->indirect[i]));
}

/* ---------------------------------------------------------------- Cornell box */

static const char CORNELL_SEQ[] =
    "{\"name\": \"cornell-box-ref\", \"scene\": \"cornell-box.gltf\", \"frames\": 1, \"fps\": 8,"
    " \"resolution\": [256, 256], \"camera\": {\"node\": \"Camera\"},"
    " \"settings\": {\"shadow_map_size\": 1024, \"pcf_radius\": 1, \"indirect\": \"none\"}}";

/* The floor point under pixel (x, y) of the spec camera: (0, 1, 3.9) looking at (0, 1, 0), 40°. */
static int floor_point(int x, int y, float p[3])
{
    static const float right[3] = {1, 0, 0}, up[3] = {0, 1, 0}, fwd[3] = {0, 0, -1};
    static const double eye[3] = {0.0, 1.0, 3.9};
    double d[3];
    pixel_ray(x, y, 256, right, up, fwd, tan(20.0 * ENG_PI / 180.0), d);
    if (d[1] >= 0.0)
        return 0;
    double t = -eye[1] / d[1];
    for (int i = 0; i < 3; i++)
        p[i] = (float)(eye[i] + t * d[i]);
    p[1] = 0.0f;
    return p[0] > -0.95f && p[0] < 0.95f && p[2] > -0.98f && p[2] < 0.94f;
}

/* The spec light's irradiance at floor point p: I cosθ / d², I = 3 W/sr at (0, 1.8, 0). */
static double floor_irradiance(const float p[3])
{
    double d2 = (double)p[0] * p[0] + 1.8 * 1.8 + (double)p[2] * p[2];
    return 3.0 * 1.8 / (d2 * sqrt(d2)); /* cosθ = 1.8/d */
}

START_TEST(cornell_floor_direct)
{
    setup s;
    setup_open(&s, CORNELL_DIR "reference-test.json", CORNELL_SEQ, 0, 2);
    images im;
    memset(&im, 0, sizeof im);
    ref_desc d;
    memset(&d, 0, sizeof d);
    d.spp = 64;     /* the pixel's jittered samples must average its gradient to its centre */
    d.max_depth = 1; /* direct light only: the check is about the first surface */
    d.no_caustics = 1;
    render_ref(&s, d, &im);
    full_is_sum(&im);
    /* The engine's rasterised direct light of the same frame, for the pixel convention. */
    eng_listener el = {&im, NULL, grab, NULL};
    eng_add_listener(s.engine, &el);
    eng_error err = {{0}};
    ck_assert_msg(eng_render_frame(s.engine, 0, &err) == ENG_OK, "%s", err.msg);
    ck_assert_ptr_nonnull(im.engine_direct);

    static const float kd[3] = {0.725f, 0.71f, 0.68f}, light[3] = {0.0f, 1.8f, 0.0f}, eye[3] = {0.0f, 1.0f, 3.9f};
    int checked = 0;
    double worst = 0.0, worst_engine = 0.0;
    for (int y = 128; y < 256; y++)
        for (int x = 0; x < 256; x++) {
            /* This pixel and its 8 neighbours must all be visible, lit floor (no shadow edge). */
            int ok = 1;
            float p[3] = {0.0f, 0.0f, 0.0f};
            for (int dy = -1; dy <= 1 && ok; dy++)
                for (int dx = -1; dx <= 1 && ok; dx++) {
                    float q[3];
                    ok = floor_point(x + dx, y + dy, q);
                    float lifted[3] = {q[0], 1e-3f, q[2]};
                    ok = ok && !eng_occluded(s.engine, eye, lifted) && !eng_occluded(s.engine, lifted, light);
                    if (dx == 0 && dy == 0)
                        memcpy(p, q, sizeof p);
                }
            if (!ok)
                continue;
            double e = floor_irradiance(p);
            for (int c = 0; c < 3; c++) {
                double want = kd[c] / ENG_PI * e;
                size_t i = 3 * ((size_t)y * 256 + (size_t)x) + (size_t)c;
                double rel = fabs(im.direct[i] - want) / want;
                double rel_engine = fabs(im.engine_direct[i] - want) / want;
                worst = rel > worst ? rel : worst;
                worst_engine = rel_engine > worst_engine ? rel_engine : worst_engine;
                ck_assert_msg(rel < 0.005, "pixel (%d, %d) channel %d: reference %.6g, analytic %.6g", x, y, c,
                              (double)im.direct[i], want);
                ck_assert_msg(im.indirect[i] == 0.0f, "max depth 1 must give no indirect light");
            }
            checked++;
        }
    printf("cornell floor: %d pixels, worst reference error %.4f%%, engine %.4f%%\n", checked, 100 * worst,
           100 * worst_engine);
    ck_assert_int_gt(checked, 2000);
    /* The engine's rasteriser sees the same points (shadow maps aside, the same formula). */
    ck_assert_msg(worst_engine < 0.01, "engine direct.radiance differs by %.3f%% on lit floor pixels",
                  100 * worst_engine);
    /* The README's worked example: floor point (−0.2, 0, 0.6) near pixel (106, 234), R ≈ 0.17944. */
    float p[3];
    ck_assert(floor_point(106, 234, p));
    ck_assert_msg(fabsf(p[0] + 0.2f) < 0.01f && fabsf(p[2] - 0.6f) < 0.01f, "pixel (106, 234) sees (%g, 0, %g)",
                  (double)p[0], (double)p[2]);
    double want = 0.725 / ENG_PI * floor_irradiance(p);
    ck_assert_msg(fabs(im.direct[3 * (234 * 256 + 106)] - want) < 0.005 * want, "pixel (106, 234): %g, want %g",
                  (double)im.direct[3 * (234 * 256 + 106)], want);
    images_free(&im);
    setup_close(&s);
}
END_TEST

/* The floor's front edge (z = 1, the box's open side) runs across a row of pixels: there a box-
 * filtered pixel is part floor, part background, while the engine's G-buffers take the floor at
 * the pixel's centre. With pixel_center the reference takes the same point: its direct radiance
 * on those pixels is the closed form at the centre's floor point (and the engine's), and the
 * box-filtered image is darker there by the part of the pixel that sees the background. */
START_TEST(pixel_centre_edges)
{
    setup s;
    setup_open(&s, CORNELL_DIR "reference-test.json", CORNELL_SEQ, 0, 2);
    images im[2];
    for (int k = 0; k < 2; k++) {
        memset(&im[k], 0, sizeof im[k]);
        ref_desc d;
        memset(&d, 0, sizeof d);
        d.spp = 16;
        d.max_depth = 1;
        d.no_caustics = 1;
        d.pixel_center = k == 0;
        render_ref(&s, d, &im[k]);
    }
    eng_listener el = {&im[0], NULL, grab, NULL};
    eng_add_listener(s.engine, &el);
    eng_error err = {{0}};
    ck_assert_msg(eng_render_frame(s.engine, 0, &err) == ENG_OK, "%s", err.msg);
    ck_assert_ptr_nonnull(im[0].engine_direct);

    static const float light[3] = {0.0f, 1.8f, 0.0f}, eye[3] = {0.0f, 1.0f, 3.9f};
    double sum_want = 0.0, sum_box = 0.0, worst = 0.0, worst_engine = 0.0;
    int edge = 0;
    for (int y = 128; y < 256; y++)
        for (int x = 8; x < 248; x++) {
            /* A floor pixel whose lower neighbour's centre lies beyond the floor's front edge
             * (floor_point's own bounds stop short of the edge: its points are used, not them). */
            float here[3] = {0.0f, 0.0f, 2.0f}, below[3] = {0.0f, 0.0f, 2.0f};
            floor_point(x, y, here);
            floor_point(x, y + 1, below);
            if (!(here[2] < 1.0f && below[2] >= 1.0f && fabsf(here[0]) < 0.9f))
                continue;
            float lifted[3] = {here[0], 1e-3f, here[2]};
            if (eng_occluded(s.engine, eye, lifted) || eng_occluded(s.engine, lifted, light))
                continue;
            double want = 0.725 / ENG_PI * floor_irradiance(here);
            size_t i = 3 * ((size_t)y * 256 + (size_t)x);
            double rel = fabs(im[0].direct[i] - want) / want, rel_engine = fabs(im[0].engine_direct[i] - want) / want;
            worst = rel > worst ? rel : worst;
            worst_engine = rel_engine > worst_engine ? rel_engine : worst_engine;
            sum_want += want;
            sum_box += im[1].direct[i];
            edge++;
        }
    printf("floor front edge: %d pixels; pixel centres: worst %.4f%% (engine %.4f%%); box-filtered: %.3f of the "
           "centre's light\n",
           edge, 100 * worst, 100 * worst_engine, sum_box / sum_want);
    ck_assert_int_gt(edge, 100);
    ck_assert_msg(worst < 0.005, "pixel-centre reference %.3f%% off the closed form on the edge row", 100 * worst);
    ck_assert_msg(worst_engine < 0.01, "engine direct.radiance %.3f%% off on the edge row", 100 * worst_engine);
    ck_assert_msg(sum_box < 0.95 * sum_want, "box-filtered edge row holds %.3f of the centre's light",
                  sum_box / sum_want);
    images_free(&im[0]);
    images_free(&im[1]);
    setup_close(&s);
}
END_TEST

/* ---------------------------------------------------------------- furnace */

START_TEST(furnace_sphere)
{
    const int size = 96;
    setup s;
    setup_open(&s, FURNACE_DIR "furnace.json", NULL, size, 2);
    images im;
    memset(&im, 0, sizeof im);
    ref_desc d;
    memset(&d, 0, sizeof d);
    d.spp = 96;
    render_ref(&s, d, &im);
    full_is_sum(&im);

    const double rho = FURNACE_RHO, intensity = FURNACE_INTENSITY;
    const double area = furnace_area(s.scene);
    ck_assert(area > 12.0 && area < 4.0 * ENG_PI);
    const eng_frame_scene *fs;
    const eng_rt *rt;
    eng_pose(s.engine, 0, &fs, &rt);
    static const float right[3] = {1, 0, 0}, up[3] = {0, 1, 0}, fwd[3] = {0, 0, -1};
    const float origin[3] = {0, 0, 0};
    double sum_w = 0.0, sum_wl = 0.0, worst = 0.0;
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            double dd[3];
            pixel_ray(x, y, size, right, up, fwd, 1.0, dd);
            float dir[3] = {(float)dd[0], (float)dd[1], (float)dd[2]};
            rt_hit h;
            ck_assert(rt_intersect(rt, origin, dir, 0.0f, 100.0f, &h));
            double cos_s = fabs(dot3_f(h.geom_normal, dir));
            /* Direct: (ρ/π)·I·cosθ/d² with the light at the camera. */
            double want = rho / ENG_PI * intensity * cos_s / ((double)h.t * h.t);
            size_t i = 3 * ((size_t)y * (size_t)size + (size_t)x);
            double rel = fabs(im.direct[i] - want) / want;
            worst = rel > worst ? rel : worst;
            ck_assert_msg(rel < 0.005, "pixel (%d, %d): direct %.6g, analytic %.6g", x, y, (double)im.direct[i], want);
            /* Area weight of the pixel: dA = t²·dω/cos_s, dω ∝ cos³ of the pixel's angle (−dir.z). */
            double cz = -dd[2];
            double w = (double)h.t * h.t * cz * cz * cz / cos_s;
            sum_w += w;
            sum_wl += w * im.indirect[i];
        }
    double mean = sum_wl / sum_w;
    double want = furnace_indirect_mean(area);
    printf("furnace: A = %.6f m², direct worst %.4f%%, indirect area mean %.6f, energy balance %.6f (%+.3f%%)\n",
           area, 100 * worst, mean, want, 100 * (mean - want) / want);
    ck_assert_msg(fabs(mean - want) < 0.005 * want, "indirect area mean %.6g, energy balance %.6g", mean, want);
    images_free(&im);
    setup_close(&s);
}
END_TEST

/* ---------------------------------------------------------------- caustics */

START_TEST(mirror_caustic)
{
    const int size = 64;
    setup s;
    setup_open(&s, FURNACE_DIR "mirror-caustic.json", NULL, size, 2);
    images im;
    memset(&im, 0, sizeof im);
    ref_desc d;
    memset(&d, 0, sizeof d);
    d.spp = 32;
    d.photons = 1 << 16;
    d.max_depth = 1; /* eye paths end at the ceiling: indirect = the caustic gather alone */
    render_ref(&s, d, &im);
    full_is_sum(&im);
    /* The camera at (0, 0.2, 0) looks up (+Y) with +Z as its up axis. */
    static const float right[3] = {1, 0, 0}, up[3] = {0, 0, 1}, fwd[3] = {0, 1, 0};
    double sum = 0.0, sum_want = 0.0, block[2][2] = {{0}}, block_want[2][2] = {{0}};
    double sum_direct = 0.0, sum_direct_want = 0.0;
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            double dd[3];
            pixel_ray(x, y, size, right, up, fwd, 1.0, dd);
            double t = 0.8 / dd[1];
            double p[3] = {t * dd[0], 1.0, t * dd[2]};
            /* The mirror image of the light at (0, −0.5, 0); reflection point inside the mirror. */
            double dv = sqrt(p[0] * p[0] + 1.5 * 1.5 + p[2] * p[2]), cv = 1.5 / dv;
            ck_assert(fabs(p[0] / 3.0) < 0.45 && fabs(p[2] / 3.0) < 0.45);
            double k = 1.0 - cv, f = 0.9 + 0.1 * k * k * k * k * k;
            double want = 0.5 / ENG_PI * f * cv / (dv * dv);
            double dl = sqrt(p[0] * p[0] + 0.25 + p[2] * p[2]);
            double want_direct = 0.5 / ENG_PI * (0.5 / dl) / (dl * dl);
            size_t i = 3 * ((size_t)y * (size_t)size + (size_t)x);
            sum_direct += im.direct[i];
            sum_direct_want += want_direct;
            sum += im.indirect[i];
            sum_want += want;
            block[y / 32][x / 32] += im.indirect[i];
            block_want[y / 32][x / 32] += want;
        }
    /* Direct light per pixel varies by up to 7% across a pixel here; its mean is checked. */
    double direct_err = (sum_direct - sum_direct_want) / sum_direct_want;
    printf("mirror caustic: mean %.6f, analytic %.6f (%+.3f%%), direct mean %+.4f%%\n", sum / (size * size),
           sum_want / (size * size), 100 * (sum - sum_want) / sum_want, 100 * direct_err);
    ck_assert_msg(fabs(direct_err) < 0.005, "direct light mean off by %.3f%%", 100 * direct_err);
    ck_assert_msg(fabs(sum - sum_want) < 0.01 * sum_want, "caustic mean %.6g, analytic %.6g", sum / (size * size),
                  sum_want / (size * size));
    for (int by = 0; by < 2; by++)
        for (int bx = 0; bx < 2; bx++)
            ck_assert_msg(fabs(block[by][bx] - block_want[by][bx]) < 0.03 * block_want[by][bx],
                          "caustic quadrant (%d, %d): %.6g, analytic %.6g", bx, by, block[by][bx] / 1024,
                          block_want[by][bx] / 1024);
    images_free(&im);
    setup_close(&s);
}
END_TEST

static double sum_indirect(const images *im)
{
    double s = 0.0;
    for (int i = 0; i < im->width * im->height * 3; i++)
        s += im->indirect[i];
    return s;
}

/* The caustic estimator's share of the indirect light: with and without it the eye paths use
 * the same random numbers, so the difference is what the photon gathers added. */
static void caustic_image(setup *s, ref_desc d, float *out, double *total)
{
    images on, off;
    memset(&on, 0, sizeof on);
    memset(&off, 0, sizeof off);
    d.no_caustics = 1;
    render_ref(s, d, &off);
    d.no_caustics = 0;
    render_ref(s, d, &on);
    *total = 0.0;
    for (int i = 0; i < on.width * on.height; i++) {
        out[i] = on.indirect[3 * i] - off.indirect[3 * i];
        *total += out[i];
    }
    images_free(&on);
    images_free(&off);
}

START_TEST(glass_caustic_converges)
{
    const int size = 64;
    setup s;
    setup_open(&s, CORNELL_DIR "cornell-glass-ci.json", NULL, size, 2);
    ref_desc d;
    memset(&d, 0, sizeof d);
    d.max_depth = 4; /* the floor under the sphere is seen through two glass surfaces */
    d.photons = 8192;
    float *a = malloc(sizeof(float) * size * size), *b = malloc(sizeof(float) * size * size);
    ck_assert(a && b);
    double ta, tb;
    d.spp = 16;
    caustic_image(&s, d, a, &ta);
    d.spp = 64;
    d.seed = 7;
    caustic_image(&s, d, b, &tb);
    /* Caustic pixels: the caustic adds more than half the README's floor example
     * (0.179 W/m²/sr) at 4N samples. */
    int bright = 0;
    double ra = 0.0, rb = 0.0;
    for (int i = 0; i < size * size; i++)
        if (b[i] > 0.09f) {
            bright++;
            ra += a[i];
            rb += b[i];
        }
    printf("glass caustic: total N = 16: %.6g, 4N = 64: %.6g (%+.2f%%); %d bright pixels: %.6g vs %.6g (%+.2f%%)\n",
           ta, tb, 100 * (ta - tb) / tb, bright, ra, rb, 100 * (ra - rb) / rb);
    ck_assert_msg(bright >= 10, "only %d pixels with a bright caustic", bright);
    ck_assert_msg(fabs(ta - tb) < 0.10 * tb, "caustic total at 16 spp %.6g, at 64 spp %.6g", ta, tb);
    ck_assert_msg(fabs(ra - rb) < 0.05 * rb, "caustic region at 16 spp %.6g, at 64 spp %.6g", ra, rb);
    free(a);
    free(b);
    setup_close(&s);
}
END_TEST

/* ---------------------------------------------------------------- determinism */

START_TEST(threads_bit_identical)
{
    images im[2];
    for (int k = 0; k < 2; k++) {
        setup s;
        setup_open(&s, CORNELL_DIR "cornell-glass-ci.json", NULL, 48, k + 1);
        memset(&im[k], 0, sizeof im[k]);
        ref_desc d;
        memset(&d, 0, sizeof d);
        d.spp = 3;
        d.photons = 4096;
        d.threads = k + 1;
        render_ref(&s, d, &im[k]);
        setup_close(&s);
    }
    size_t n = 48 * 48 * 3 * sizeof(float);
    ck_assert_msg(memcmp(im[0].direct, im[1].direct, n) == 0, "reference.direct differs between 1 and 2 threads");
    ck_assert_msg(memcmp(im[0].indirect, im[1].indirect, n) == 0, "reference.indirect differs between 1 and 2 threads");
    ck_assert_msg(memcmp(im[0].full, im[1].full, n) == 0, "reference.full differs between 1 and 2 threads");
    ck_assert_msg(sum_indirect(&im[0]) > 0.0, "no indirect light");
    images_free(&im[0]);
    images_free(&im[1]);
}
END_TEST

START_TEST(bad_settings)
{
    setup s;
    setup_open(&s, CORNELL_DIR "cornell-glass-ci.json", NULL, 16, 1);
    ref_desc d;
    memset(&d, 0, sizeof d);
    d.engine = s.engine;
    d.sequence = &s.seq;
    ref_renderer *r = (ref_renderer *)&d;
    eng_error err = {{0}};
    d.spp = -1;
    ck_assert_int_eq(ref_create(&d, &r, &err), ENG_ERR_INVALID);
    ck_assert_ptr_null(r);
    ck_assert_msg(strstr(err.msg, "cornell-glass-ci.json") != NULL, "%s", err.msg);
    d.spp = 1;
    d.alpha = 1.5f;
    ck_assert_int_eq(ref_create(&d, &r, &err), ENG_ERR_INVALID);
    d.alpha = 0.0f;
    ck_assert_int_eq(ref_create(&d, &r, &err), ENG_OK);
    ck_assert_float_gt(ref_settings(r)->radius, 0.0f);
    ck_assert_int_eq(ref_render_frame(r, 1, &err), ENG_ERR_INVALID);
    ref_destroy(r);
    setup_close(&s);
}
END_TEST

/* The capture's optional renderer record: settings must be a JSON object. */
START_TEST(capture_renderer_settings)
{
    setup s;
    setup_open(&s, CORNELL_DIR "cornell-glass-ci.json", NULL, 16, 1);
    eng_error err = {{0}};
    cap_desc cd;
    memset(&cd, 0, sizeof cd);
    cd.run_dir = ISPM_BINARY_DIR "/tests/test_reference.work/run";
    cd.sequence = &s.seq;
    cd.scene = s.scene;
    cd.overwrite = 1;
    cd.renderer = "reference";
    cd.renderer_settings = "[1, 2]";
    cap_capture *cap = NULL;
    ck_assert_int_eq(cap_create(&cd, &cap, &err), ENG_ERR_INVALID);
    ck_assert_ptr_null(cap);
    ck_assert_msg(strstr(err.msg, "test_reference.work/run") != NULL, "%s", err.msg);
    cd.renderer_settings = "{\"spp\": 4}";
    ck_assert_msg(cap_create(&cd, &cap, &err) == ENG_OK, "%s", err.msg);
    cap_destroy(cap);
    setup_close(&s);
}
END_TEST

static Suite *reference_suite(void)
{
    Suite *s = suite_create("reference");
    TCase *tc = tcase_create("reference");
    tcase_set_timeout(tc, 600);
    tcase_add_test(tc, bad_settings);
    tcase_add_test(tc, capture_renderer_settings);
    tcase_add_test(tc, threads_bit_identical);
    tcase_add_test(tc, cornell_floor_direct);
    tcase_add_test(tc, pixel_centre_edges);
    tcase_add_test(tc, furnace_sphere);
    tcase_add_test(tc, mirror_caustic);
    tcase_add_test(tc, glass_caustic_converges);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(reference_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
