/* test_kdgather.c — Check suite of the k-d gather baseline (engine/indirect/ind_kdgather.c, 003_… Appendix
 * A): the balanced k-d tree's range query against brute force, the gather against the GPU's
 * photon-volume scatter on the Cornell box (ISPM §5: "mathematically identical"; here equal up
 * to float rounding), and bit-identical results for any thread count. */
#include "eng.h"
#include "indirect.h"
#include "kdtree.h"

#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CORNELL_GLTF ISPM_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"
#define SIZE 48

static uint64_t test_rng(uint64_t *state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static float test_uniform(uint64_t *state)
{
    return (float)(test_rng(state) >> 40) * (1.0f / 16777216.0f);
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* ---------------------------------------------------------------- the tree */

/* Random points, some on a coarse lattice so that many share coordinates (ties in the median
 * split) and some duplicated exactly; the range query must return exactly the brute-force set,
 * points at distance exactly r included. */
START_TEST(range_query_equals_brute_force)
{
    uint64_t st = 12345;
    const size_t sizes[] = {0, 1, 2, 3, 7, 100, 5000};
    for (size_t si = 0; si < sizeof sizes / sizeof sizes[0]; si++) {
        size_t n = sizes[si];
        float *pts = malloc((n ? n : 1) * 4 * sizeof(float)); /* stride 4: the 4th float is ignored */
        for (size_t i = 0; i < n; i++) {
            for (int c = 0; c < 3; c++) {
                float u = test_uniform(&st);
                pts[4 * i + c] = (i % 3 == 0) ? floorf(u * 8.0f) * 0.125f : u;
            }
            pts[4 * i + 3] = NAN;
            if (i % 17 == 5)
                memcpy(pts + 4 * i, pts + 4 * (i - 1), 3 * sizeof(float));
        }
        kd_tree t;
        eng_error err;
        ck_assert_msg(kd_tree_build(pts, n, 4, &t, &err) == ENG_OK, "%s", err.msg);
        ck_assert_uint_eq(t.count, n);
        uint32_t *got = NULL, *want = malloc((n ? n : 1) * sizeof *want);
        size_t cap = 0;
        for (int q = 0; q < 300; q++) {
            float c[3], r;
            if (q % 4 == 0 && n > 0) /* centred on a lattice point: many points at exactly r */
                memcpy(c, pts + 4 * ((size_t)q % n), sizeof c);
            else
                for (int k = 0; k < 3; k++)
                    c[k] = test_uniform(&st) * 1.2f - 0.1f;
            r = q % 4 == 0 ? 0.125f : test_uniform(&st) * 0.3f;
            size_t ng = 0, nw = 0;
            kd_tree_range(&t, c, r, &got, &ng, &cap);
            for (size_t i = 0; i < n; i++) {
                float dx = pts[4 * i] - c[0], dy = pts[4 * i + 1] - c[1], dz = pts[4 * i + 2] - c[2];
                if (dx * dx + dy * dy + dz * dz <= r * r)
                    want[nw++] = (uint32_t)i;
            }
            if (ng > 1)
                qsort(got, ng, sizeof *got, cmp_u32);
            ck_assert_msg(ng == nw, "n=%zu query %d: %zu found, %zu expected", n, q, ng, nw);
            ck_assert_msg(ng == 0 || memcmp(got, want, ng * sizeof *got) == 0, "n=%zu query %d: sets differ", n, q);
        }
        /* The tree is a permutation of the input and a valid k-d tree. */
        for (size_t i = 0; i < n; i++)
            ck_assert_int_eq(memcmp(t.point + 3 * i, pts + 4 * (size_t)t.index[i], 3 * sizeof(float)), 0);
        free(got);
        free(want);
        kd_tree_free(&t);
        free(pts);
    }
}
END_TEST

/* ---------------------------------------------------------------- against the scatter */

typedef struct kept {
    char name[64];
    int w, h, n;
    float *data;
} kept;

typedef struct keeper {
    int count;
    kept bufs[64];
} keeper;

static int keep_buffer(void *user, int frame, const eng_buffer *b)
{
    (void)frame;
    keeper *k = user;
    ck_assert_int_lt(k->count, 64);
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

static const kept *find(const keeper *k, const char *name)
{
    for (int i = 0; i < k->count; i++)
        if (!strcmp(k->bufs[i].name, name))
            return &k->bufs[i];
    return NULL;
}

static void keeper_clear(keeper *k)
{
    for (int i = 0; i < k->count; i++)
        free(k->bufs[i].data);
    memset(k, 0, sizeof *k);
}

/* Renders frame 1 of the Cornell box at SIZE² with the given indirect method into k. */
static void render_cornell(const char *indirect, keeper *k, seq_sequence *seq)
{
    char json[1024];
    snprintf(json, sizeof json,
             "{\"name\":\"kd\",\"scene\":\"%s\",\"frames\":2,\"fps\":8,\"resolution\":[%d,%d],"
             "\"camera\":{\"node\":\"Camera\"},\"settings\":{\"shadow_map_size\":128,\"threads\":2,"
             "\"photon_count\":4096,\"kernel_radius\":0.15,\"boundary\":\"renormalize\",\"indirect\":\"%s\"}}",
             CORNELL_GLTF, SIZE, SIZE, indirect);
    eng_error err;
    ck_assert_msg(seq_parse("inline.json", json, strlen(json), seq, &err) == ENG_OK, "%s", err.msg);
    scn_scene *scene = NULL;
    ck_assert_msg(scn_load_gltf(seq->scene_path, &scene, &err) == ENG_OK, "%s", err.msg);
    eng_engine *eng = NULL;
    eng_desc d = {.scene = scene, .sequence = seq};
    ck_assert_msg(eng_create(&d, &eng, &err) == ENG_OK, "%s", err.msg);
    eng_listener l = {k, NULL, keep_buffer, NULL};
    ck_assert_int_eq(eng_add_listener(eng, &l), ENG_OK);
    ck_assert_msg(eng_render_frame(eng, 1, &err) == ENG_OK, "%s", err.msg);
    eng_destroy(eng);
    scn_destroy(scene);
}

/* The eye G-buffer in kd_gather's input layout, from the announced buffers (coverage = the
 * material id is not −1). */
typedef struct gbuf {
    float pos[SIZE * SIZE * 4], mat[SIZE * SIZE * 4];
    const float *nrm, *alb;
} gbuf;

static void gbuf_of(const keeper *k, gbuf *g)
{
    const kept *pos = find(k, "gbuffer.position"), *mat = find(k, "gbuffer.material");
    const kept *nrm = find(k, "gbuffer.normal"), *alb = find(k, "gbuffer.albedo");
    ck_assert(pos && mat && nrm && alb);
    for (int i = 0; i < SIZE * SIZE; i++) {
        memcpy(g->pos + 4 * i, pos->data + 3 * i, 3 * sizeof(float));
        g->pos[4 * i + 3] = mat->data[5 * i + 4] >= 0.0f ? 1.0f : 0.0f;
        memcpy(g->mat + 4 * i, mat->data + 5 * i, 4 * sizeof(float));
    }
    g->nrm = nrm->data;
    g->alb = alb->data;
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

/* Tolerance of gather vs scatter. Both evaluate the same float expression per photon and sum
 * in photon-index order; what differs is llvmpipe's rounding of sqrt/division/normalize and
 * its blending. Where a pixel's value is not tiny (> 1e-3 of the image's largest), the
 * relative difference must stay under 1e-4 per channel; elsewhere the absolute difference
 * under 1e-5 of the largest value (measured: here worst relative 7.4e-7 with 74% of values
 * bit-identical; 1.6e-5 at 160² with 2048 photons and kernel_radius 0.05). Kernel counts may differ by a photon that lies within
 * rounding of the kernel's edge (t = 1), in a few pixels only. */
#define REL_TOL 1e-4
#define ABS_TOL_OF_MAX 1e-5

START_TEST(gather_equals_scatter_on_the_cornell_box)
{
    static keeper ks, kg;
    seq_sequence *seq = calloc(1, sizeof *seq);
    render_cornell("ispm", &ks, seq);
    render_cornell("kd-gather", &kg, seq);
    const kept *pm_s = find(&ks, "photons.map"), *pm_g = find(&kg, "photons.map");
    ck_assert(pm_s && pm_g);
    ck_assert_msg(pm_s->w == pm_g->w && pm_s->h == pm_g->h &&
                      !memcmp(pm_s->data, pm_g->data, (size_t)pm_s->w * pm_s->h * 14 * sizeof(float)),
                  "the two methods must gather/scatter the same photon map");
    const kept *sp = find(&ks, "splat.indirect"), *sc = find(&ks, "splat.count");
    const kept *ga = find(&kg, "gather.indirect"), *gc = find(&kg, "gather.count");
    const kept *ir = find(&kg, "indirect.radiance");
    ck_assert(sp && sc && ga && gc && ir);
    ck_assert(!find(&kg, "splat.indirect"));
    /* indirect.radiance = the method's estimate over the boundary correction's W (boundary.h,
     * switched on in this sequence), which is below 1 near the box's edges and corners. */
    const kept *bw = find(&kg, "boundary.weight");
    ck_assert(bw && bw->w == SIZE && bw->h == SIZE);
    int edge_px = 0;
    for (int i = 0; i < SIZE * SIZE; i++) {
        edge_px += bw->data[i] < 1.0f;
        for (int c = 0; c < 3; c++)
            ck_assert(ir->data[3 * i + c] == ga->data[3 * i + c] / bw->data[i]);
    }
    ck_assert_msg(edge_px > SIZE && edge_px < SIZE * SIZE * 3 / 4, "%d pixels with W < 1", edge_px);
    const kept *bws = find(&ks, "boundary.weight"); /* the same W behind the scatter */
    ck_assert(bws && !memcmp(bws->data, bw->data, SIZE * SIZE * sizeof(float)));
    double peak = 0.0;
    for (int i = 0; i < SIZE * SIZE * 3; i++)
        peak = fmax(peak, sp->data[i]);
    ck_assert(peak > 0.0);
    double worst_rel = 0.0, worst_abs = 0.0;
    int lit = 0, count_diff = 0, bitexact = 0;
    for (int i = 0; i < SIZE * SIZE; i++) {
        if (sc->data[i] != gc->data[i])
            count_diff++;
        for (int c = 0; c < 3; c++) {
            double a = sp->data[3 * i + c], b = ga->data[3 * i + c];
            ck_assert_msg(isfinite(b), "pixel %d: gather %g", i, b);
            bitexact += a == b;
            double d = fabs(a - b);
            if (fabs(a) > 1e-3 * peak) {
                lit++;
                worst_rel = fmax(worst_rel, d / fabs(a));
                ck_assert_msg(d <= REL_TOL * fabs(a), "pixel (%d,%d) ch %d: scatter %.9g, gather %.9g", i % SIZE,
                              i / SIZE, c, a, b);
            } else {
                worst_abs = fmax(worst_abs, d);
                ck_assert_msg(d <= ABS_TOL_OF_MAX * peak, "pixel (%d,%d) ch %d: scatter %.9g, gather %.9g",
                              i % SIZE, i / SIZE, c, a, b);
            }
        }
    }
    fprintf(stderr,
            "kd-gather vs scatter at %d²: %d lit values, worst relative %.3g, worst absolute (dim) %.3g "
            "(peak %.4g), %d/%d values bit-identical, kernel counts differ in %d pixels\n",
            SIZE, lit, worst_rel, worst_abs, peak, bitexact, SIZE * SIZE * 3, count_diff);
    ck_assert_int_gt(lit, SIZE * SIZE); /* most of the image is lit indirectly */
    ck_assert_int_le(count_diff, SIZE * SIZE / 100);
    /* The composite is direct + indirect for both. */
    const kept *cs = find(&ks, "composite.radiance"), *cg = find(&kg, "composite.radiance");
    const kept *ds = find(&ks, "direct.radiance"), *dg = find(&kg, "direct.radiance");
    ck_assert(cs && cg && ds && dg);
    ck_assert_int_eq(memcmp(ds->data, dg->data, SIZE * SIZE * 3 * sizeof(float)), 0);
    for (int i = 0; i < SIZE * SIZE * 3; i++)
        ck_assert_msg(fabs(cg->data[i] - (dg->data[i] + ir->data[i])) <= 1e-6 * fabs(cg->data[i]) + 1e-9,
                      "composite value %d: %g != %g + %g", i, cg->data[i], dg->data[i], ir->data[i]);
    keeper_clear(&ks);
    keeper_clear(&kg);
    free(seq);
}
END_TEST

/* kd_gather on the same inputs gives the same bits with 1, 2, 3 and 5 threads, and the same
 * bits the engine announced (its G-buffer read-back equals the announced buffers). */
START_TEST(gather_is_bit_identical_for_any_thread_count)
{
    static keeper kg;
    static gbuf g;
    seq_sequence *seq = calloc(1, sizeof *seq);
    render_cornell("kd-gather", &kg, seq);
    gbuf_of(&kg, &g);
    eng_photon_map map;
    ck_assert_uint_gt(photons_of(find(&kg, "photons.map"), &map), 500);
    eng_settings s = seq->settings;
    const float *eye = NULL;
    /* The eye is not announced; the camera node's position is what the engine used. */
    static float eye_buf[3];
    {
        eng_error err;
        scn_scene *scene = NULL;
        ck_assert_msg(scn_load_gltf(seq->scene_path, &scene, &err) == ENG_OK, "%s", err.msg);
        float *world = malloc(scene->node_count * 16 * sizeof(float));
        scn_evaluate(scene, 1.0 / seq->fps, world);
        int32_t cam = scn_find_node(scene, "Camera");
        ck_assert_int_ge(cam, 0);
        memcpy(eye_buf, world + 16 * cam + 12, sizeof eye_buf);
        eye = eye_buf;
        free(world);
        scn_destroy(scene);
    }
    static float out[5][SIZE * SIZE * 4];
    const int threads[5] = {1, 2, 3, 5, 8};
    for (int k = 0; k < 5; k++) {
        eng_error err;
        s.threads = threads[k];
        ck_assert_msg(kd_gather(&map, SIZE, SIZE, g.pos, g.nrm, g.alb, g.mat, eye, &s, out[k], &err) == ENG_OK, "%s",
                      err.msg);
        if (k > 0)
            ck_assert_msg(!memcmp(out[0], out[k], sizeof out[0]), "%d threads differ from 1 thread", threads[k]);
    }
    const kept *ga = find(&kg, "gather.indirect"), *gc = find(&kg, "gather.count");
    for (int i = 0; i < SIZE * SIZE; i++) {
        ck_assert_msg(!memcmp(out[0] + 4 * i, ga->data + 3 * i, 3 * sizeof(float)), "pixel %d differs from the engine's",
                      i);
        ck_assert(out[0][4 * i + 3] == gc->data[i]);
    }
    /* An empty map gathers nothing. */
    eng_photon_map empty = {0};
    eng_error err;
    ck_assert(kd_gather(&empty, SIZE, SIZE, g.pos, g.nrm, g.alb, g.mat, eye, &s, out[1], &err) == ENG_OK);
    for (int i = 0; i < SIZE * SIZE * 4; i++)
        ck_assert(out[1][i] == 0.0f);
    free(map.photons);
    keeper_clear(&kg);
    free(seq);
}
END_TEST

static Suite *kdgather_suite(void)
{
    Suite *s = suite_create("kdgather");
    TCase *tc = tcase_create("core");
    tcase_set_timeout(tc, 600);
    tcase_add_test(tc, range_query_equals_brute_force);
    tcase_add_test(tc, gather_equals_scatter_on_the_cornell_box);
    tcase_add_test(tc, gather_is_bit_identical_for_any_thread_count);
    suite_add_tcase(s, tc);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(kdgather_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
