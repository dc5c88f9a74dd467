/* test_multiimage.c — Check suite of the photon-trace methods (trace_method.h) and the
 * multi-image trace (trace_multiimage.c, 004 §4–5): cube-map texel addressing, Eq. 1's texel
 * area, the greedy centre selection on a hand-made coverage table, false-position
 * intersection against a synthetic cube G-buffer of a room with an occluder (types A, B, D),
 * Eq. 2's angular error, the C/D classification across maps, and on the Cornell box: the
 * Embree method through the interface gives photon_trace's map bit for bit, the multi-image
 * trace agrees with Embree on most rays and is bit-identical for 1 and 3 threads. */
#include "multiimage.h"
#include "trace_method.h"

#include <check.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define CORNELL_GLTF ISPM_SOURCE_DIR "/scenes/cornell-box/cornell-box.gltf"

/* ---------------------------------------------------------------- cube addressing, Eq. 1 */

START_TEST(texel_round_trip)
{
    const int size = 7;
    for (size_t t = 0; t < 6u * size * size; t++) {
        float d[3];
        mi_texel_dir(size, t, d);
        ck_assert_uint_eq(mi_cube_texel(size, d), t);
        float axis[3];
        mi_face_axis((int)(t / (size * size)), axis);
        /* the texel's direction points out of its own face */
        ck_assert_float_eq_tol(d[0] * axis[0] + d[1] * axis[1] + d[2] * axis[2], 1.0f, 1e-6f);
    }
}
END_TEST

START_TEST(texel_area_eq1)
{
    /* A wall facing the centre at distance D: the central texel covers (2D/size)². */
    const float v[3] = {0, 0, 0}, fwd[3] = {1, 0, 0}, n[3] = {-1, 0, 0};
    const float x[3] = {2.0f, 0.0f, 0.0f};
    ck_assert_double_eq_tol(mi_texel_area(v, x, n, fwd, 16), (2.0 * 2.0 / 16) * (2.0 * 2.0 / 16), 1e-9);
    /* Tilted by 60°: twice the area (1/cos α). */
    const float nt[3] = {-0.5f, 0.8660254f, 0.0f};
    ck_assert_double_eq_tol(mi_texel_area(v, x, nt, fwd, 16), 2.0 * 0.0625, 1e-6);
    /* Summed over a whole face on the plane x = 1: the face's 2×2 square. */
    const int size = 32;
    double sum = 0.0;
    for (size_t t = 0; t < (size_t)size * size; t++) {
        float d[3];
        mi_texel_dir(size, t, d);
        float p[3] = {1.0f, d[1] / d[0], d[2] / d[0]};
        sum += mi_texel_area(v, p, n, fwd, size);
    }
    ck_assert_double_eq_tol(sum, 4.0, 0.02);
}
END_TEST

/* ---------------------------------------------------------------- §4.1 greedy selection */

/* 4 candidates with 4 pixels each; seen[c][v] = bitmask of v's pixels candidate c sees. */
static const unsigned seen_table[4][4] = {
    {0xF, 0x3, 0x0, 0x0},
    {0x0, 0xF, 0x0, 0x0},
    {0xF, 0xF, 0xF, 0x1},
    {0x0, 0x0, 0x0, 0xF},
};

static int table_visible(void *user, int c, int v, int p)
{
    (void)user;
    return (seen_table[c][v] >> p) & 1u;
}

START_TEST(select_greedy)
{
    /* Candidate 2 owns the most area (pixels of 2), then 3 adds what 2 does not see. */
    double area[16];
    for (int i = 0; i < 16; i++)
        area[i] = 1.0;
    for (int p = 0; p < 4; p++)
        area[2 * 4 + p] = 3.0;
    int chosen[2];
    mi_select(4, 4, area, table_visible, NULL, 2, 0, chosen);
    ck_assert_int_eq(chosen[0], 2);
    /* A(0|{2}) = 0, A(1|{2}) = 0, A(3|{2}) = 3 pixels. */
    ck_assert_int_eq(chosen[1], 3);
    /* k = 1 then update steps: 2 is the best single centre and stays. */
    int one[1];
    mi_select(4, 4, area, table_visible, NULL, 1, 5, one);
    ck_assert_int_eq(one[0], 2);
    /* Equal areas everywhere: ties go to the lower index. */
    double flat[16];
    for (int i = 0; i < 16; i++)
        flat[i] = 1.0;
    mi_select(4, 4, flat, table_visible, NULL, 1, 0, one);
    ck_assert_int_eq(one[0], 0);
    /* Update steps from {0}: add 2 (A(2|{0}) = 4), remove 0 (2 sees all of it: A(0|{2}) = 0);
     * then adding 3 would remove 3 again: {2} is stable. */
    mi_select(4, 4, flat, table_visible, NULL, 1, 5, one);
    ck_assert_int_eq(one[0], 2);
}
END_TEST

/* ---------------------------------------------------------------- §5 intersection */

/* A synthetic cube G-buffer: centre at the origin of the room [−1, 1]³ (walls facing in),
 * with an occluder on the +X face: the texels below the horizon (y < 0) see a plane x = 0.5
 * facing −X. */
static void synthetic_map(mi_map *m, int size, int occluder)
{
    size_t n = 6u * (size_t)size * (size_t)size;
    m->size = size;
    m->centre[0] = m->centre[1] = m->centre[2] = 0.0f;
    m->position = malloc(n * 3 * sizeof(float));
    m->normal = malloc(n * 3 * sizeof(float));
    m->draw = malloc(n * sizeof(int32_t));
    m->material = malloc(n * sizeof(int32_t));
    m->tex = NULL; /* texture factors: only the tracer reads them, not the intersection */
    for (size_t t = 0; t < n; t++) {
        int face = (int)(t / ((size_t)size * size));
        float d[3], axis[3];
        mi_texel_dir(size, t, d);
        mi_face_axis(face, axis);
        float wall = 1.0f;
        m->draw[t] = face;
        if (occluder && face == 0 && d[1] < 0.0f) {
            wall = 0.5f;
            m->draw[t] = 6;
        }
        /* d has |major| = 1: the wall at |major| = wall is d·wall */
        for (int c = 0; c < 3; c++) {
            m->position[3 * t + c] = d[c] * wall;
            m->normal[3 * t + c] = -axis[c];
        }
        m->material[t] = 0;
    }
}

static void free_map(mi_map *m)
{
    free(m->position);
    free(m->normal);
    free(m->draw);
    free(m->material);
}

START_TEST(false_position_room)
{
    mi_map m;
    synthetic_map(&m, 32, 0);
    /* Rays from points on the floor to the walls: exact hits on the planes. */
    const float org[3] = {0.3f, -1.0f + 1e-4f, -0.2f};
    float dir[3] = {0.4f, 0.8f, 0.3f};
    float l = sqrtf(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int c = 0; c < 3; c++)
        dir[c] /= l;
    mi_candidate c;
    ck_assert_int_eq(mi_intersect_map(&m, org, dir, 1e-4f, 4.0f, 32, 8, MI_EPSILON, &c), MI_TYPE_D);
    /* the ray meets x = 1 at d = 0.7/dir.x (y, z still inside the room) */
    float d = 0.7f / dir[0];
    ck_assert_float_eq_tol(c.d, d, 1e-4f);
    for (int k = 0; k < 3; k++)
        ck_assert_float_eq_tol(c.p[k], org[k] + d * dir[k], 1e-4f);
    ck_assert_float_le(c.error, 1e-6f);
    /* Leaving through a missing wall: the map sees nothing (draw −1) there: type A up to
     * just outside the room (as the trace's scene-box limit does). */
    for (size_t t = 0; t < 6u * 32 * 32; t++)
        if (t / (32 * 32) == 0)
            m.draw[t] = -1;
    ck_assert_int_eq(mi_intersect_map(&m, org, dir, 1e-4f, d + 0.02f, 32, 8, MI_EPSILON, &c), MI_TYPE_A);
    /* Farther out the ray passes behind the ceiling as the centre sees it (y > 1 where the
     * ceiling's texels are looked up): a crossing whose point is off the ray, type B. */
    ck_assert_int_eq(mi_intersect_map(&m, org, dir, 1e-4f, 4.0f, 32, 8, MI_EPSILON, &c), MI_TYPE_B);
    ck_assert_float_gt(c.error, MI_EPSILON);
    free_map(&m);
}
END_TEST

START_TEST(type_b_behind_occluder)
{
    mi_map m;
    synthetic_map(&m, 64, 1);
    /* From (0.8, 0.5, 0) straight down: the map sees the far wall x = 1 above the horizon and
     * the occluder x = 0.5 below it, so f jumps from − to + at y = 0 though the ray (x = 0.8)
     * never meets the occluder: the crossing's surface point lies off the ray (type B). */
    const float org[3] = {0.8f, 0.5f, 0.0f}, dir[3] = {0.0f, -1.0f, 0.0f};
    mi_candidate c;
    ck_assert_int_eq(mi_intersect_map(&m, org, dir, 1e-4f, 1.2f, 32, 8, MI_EPSILON, &c), MI_TYPE_B);
    ck_assert_float_gt(c.error, MI_EPSILON);
    /* Farther on the scan passes the rejected crossing and finds the floor (type D). */
    ck_assert_int_eq(mi_intersect_map(&m, org, dir, 1e-4f, 2.0f, 32, 8, MI_EPSILON, &c), MI_TYPE_D);
    ck_assert_float_eq_tol(c.p[1], -1.0f, 1e-4f);
    ck_assert_float_eq_tol(c.p[0], 0.8f, 1e-4f);
    ck_assert_float_eq_tol(c.d, 1.5f, 1e-4f);
    free_map(&m);
}
END_TEST

START_TEST(angular_error_eq2)
{
    const float x[3] = {1, 2, 3}, r[3] = {0, 0, 1};
    const float on[3] = {1, 2, 5};
    ck_assert_float_eq_tol(mi_angular_error(x, r, on), 0.0f, 1e-7f);
    /* θ = 0.02 rad off the ray: e ≈ θ²/2 = 2e-4, accepted; θ = 0.05: 1.25e-3, rejected. */
    float th = 0.02f;
    const float p1[3] = {1 + 2 * sinf(th), 2, 3 + 2 * cosf(th)};
    ck_assert_float_eq_tol(mi_angular_error(x, r, p1), th * th / 2, 1e-6f);
    ck_assert_float_le(mi_angular_error(x, r, p1), MI_EPSILON);
    th = 0.05f;
    const float p2[3] = {1, 2 + 3 * sinf(th), 3 + 3 * cosf(th)};
    ck_assert_float_gt(mi_angular_error(x, r, p2), MI_EPSILON);
    /* Behind the origin: e = 2. */
    const float back[3] = {1, 2, 1};
    ck_assert_float_eq_tol(mi_angular_error(x, r, back), 2.0f, 1e-6f);
    ck_assert_float_eq(mi_angular_error(x, r, x), 2.0f);
}
END_TEST

START_TEST(classify_types)
{
    mi_candidate c[5];
    memset(c, 0, sizeof c);
    c[0].type = MI_TYPE_D;
    c[0].d = 2.0f;
    c[1].type = MI_TYPE_A;
    c[2].type = MI_TYPE_D;
    c[2].d = 1.0f;
    c[3].type = MI_TYPE_B;
    c[3].d = 0.5f; /* rejected: its distance does not count */
    c[4].type = MI_TYPE_D;
    c[4].d = 1.005f;
    ck_assert_int_eq(mi_classify(c, 5, 0.01f), 2);
    ck_assert_int_eq(c[0].type, MI_TYPE_C);
    ck_assert_int_eq(c[1].type, MI_TYPE_A);
    ck_assert_int_eq(c[2].type, MI_TYPE_D);
    ck_assert_int_eq(c[3].type, MI_TYPE_B);
    ck_assert_int_eq(c[4].type, MI_TYPE_D); /* the same point seen from another map */
    mi_candidate none[2] = {{.type = MI_TYPE_A}, {.type = MI_TYPE_B}};
    ck_assert_int_eq(mi_classify(none, 2, 0.01f), -1);
}
END_TEST

/* ---------------------------------------------------------------- the methods on the Cornell box */

typedef struct cornell {
    scn_scene *scene;
    float *world;
    eng_frame_scene fs;
    eng_rt *rt;
} cornell;

static void cornell_open(cornell *c)
{
    memset(c, 0, sizeof *c);
    eng_error err;
    ck_assert_msg(scn_load_gltf(CORNELL_GLTF, &c->scene, &err) == ENG_OK, "%s", err.msg);
    const scn_scene *sc = c->scene;
    c->world = malloc(sc->node_count * 16 * sizeof(float));
    scn_evaluate(sc, 0.0, c->world);
    c->fs.scene = sc;
    c->fs.draws = calloc(sc->primitive_count + 1, sizeof(eng_draw));
    for (int a = 0; a < 3; a++) {
        c->fs.bounds_min[a] = INFINITY;
        c->fs.bounds_max[a] = -INFINITY;
    }
    for (uint32_t i = 0; i < sc->node_count; i++) {
        if (sc->nodes[i].mesh < 0)
            continue;
        const scn_mesh *m = &sc->meshes[sc->nodes[i].mesh];
        for (uint32_t k = 0; k < m->primitive_count; k++) {
            eng_draw *d = &c->fs.draws[c->fs.draw_count++];
            d->primitive = m->first_primitive + k;
            d->material = sc->primitives[d->primitive].material;
            memcpy(d->world, c->world + 16 * i, sizeof d->world);
            const scn_primitive *p = &sc->primitives[d->primitive];
            for (uint32_t v = 0; v < p->vertex_count; v++) {
                float w[3];
                m4_transform_point(d->world, p->positions + 3 * v, w);
                for (int a = 0; a < 3; a++) {
                    c->fs.bounds_min[a] = fminf(c->fs.bounds_min[a], w[a]);
                    c->fs.bounds_max[a] = fmaxf(c->fs.bounds_max[a], w[a]);
                }
            }
        }
    }
    ck_assert_int_eq(rt_create(sc, 2, &c->rt, &err), ENG_OK);
    rt_update(c->rt, &c->fs);
}

static void cornell_close(cornell *c)
{
    rt_destroy(c->rt);
    free(c->fs.draws);
    free(c->world);
    scn_destroy(c->scene);
}

/* Photons leaving the ceiling light's surroundings downward: from points just under the
 * ceiling, directions from the cosine table about −Y. */
static size_t light_photons(const eng_random_maps *rm, size_t n, eng_bounce_photon *out)
{
    for (size_t i = 0; i < n; i++) {
        const float *u = rm->uniform + 4 * i, *cd = rm->cosine + 4 * ((i * 7919u) & (rm->size - 1));
        eng_bounce_photon *p = &out[i];
        p->position[0] = -0.9f + 1.8f * u[0];
        p->position[1] = 1.98f;
        p->position[2] = -0.9f + 1.8f * u[1];
        p->direction[0] = cd[0];
        p->direction[1] = -cd[2];
        p->direction[2] = cd[1];
        p->power[0] = p->power[1] = p->power[2] = 0.001f;
        p->path_density = 0.001f;
        p->ior = 1.0f;
    }
    return n;
}

static eng_settings mi_settings(int threads, int maps, int compare)
{
    eng_settings s;
    memset(&s, 0, sizeof s);
    s.photon_trace = ENG_TRACE_MULTI_IMAGE;
    s.multi_image_maps = maps;
    s.threads = threads;
    s.multi_image_compare = compare;
    eng_settings_defaults(&s);
    return s;
}

/* The Cornell box, random maps and N photons leaving the ceiling. */
enum { N = 2000 };
typedef struct fixture {
    cornell c;
    eng_random_maps rm;
    eng_bounce_photon in[N];
} fixture;

static fixture *fixture_open(void)
{
    fixture *f = calloc(1, sizeof *f);
    eng_error err;
    cornell_open(&f->c);
    ck_assert_int_eq(rmap_create(1, 4096, &f->rm, &err), ENG_OK);
    light_photons(&f->rm, N, f->in);
    return f;
}

static void fixture_close(fixture *f)
{
    rmap_destroy(&f->rm);
    cornell_close(&f->c);
    free(f);
}

START_TEST(embree_method_bit_identical)
{
    fixture *f = fixture_open();
    cornell c = f->c;
    const eng_random_maps rm = f->rm;
    const eng_bounce_photon *in = f->in;
    eng_error err;
    eng_trace_settings ts = {0, 2, 0, 0, {0, 0, 0, 0}, 0.0f};
    eng_photon_map a = {0}, b = {0};
    ck_assert_int_eq(photon_trace(c.rt, &c.fs, &rm, in, N, &ts, &a, NULL, &err), ENG_OK);
    const pt_method *m = pt_method_find(eng_trace_name(ENG_TRACE_DEFAULT));
    ck_assert_str_eq(m->name, "embree");
    eng_settings s;
    memset(&s, 0, sizeof s);
    eng_settings_defaults(&s);
    void *state = NULL;
    pt_tracer tr;
    ck_assert_int_eq(m->create(&s, &state, &err), ENG_OK);
    ck_assert_int_eq(m->prepare(state, c.rt, &c.fs, &tr, &err), ENG_OK);
    eng_buffer buf;
    ck_assert_int_eq(m->buffer(state, 0, &buf), 0);
    eng_trace_stats st;
    ck_assert_int_eq(photon_trace_with(&tr, &c.fs, &rm, in, N, &ts, &b, &st, &err), ENG_OK);
    ck_assert_uint_gt(a.count, N);
    ck_assert_uint_eq(a.count, b.count);
    ck_assert_int_eq(memcmp(a.photons, b.photons, a.count * sizeof *a.photons), 0);
    ck_assert_uint_eq(st.counts.rays, 0); /* Embree counts nothing */
    m->destroy(state);
    photon_map_free(&a);
    photon_map_free(&b);
    fixture_close(f);
}
END_TEST

/* Runs the multi-image method with `maps` maps on `threads` threads. */
static void run_mi(cornell *c, const eng_random_maps *rm, const eng_bounce_photon *in, size_t n, int threads,
                   int maps, int compare, eng_photon_map *out, eng_trace_stats *st, float centres[][3])
{
    eng_error err;
    const pt_method *m = pt_method_find(eng_trace_name(ENG_TRACE_MULTI_IMAGE));
    ck_assert_str_eq(m->name, "multi-image");
    eng_settings s = mi_settings(threads, maps, compare);
    void *state = NULL;
    pt_tracer tr;
    ck_assert_int_eq(m->create(&s, &state, &err), ENG_OK);
    ck_assert_int_eq(m->prepare(state, c->rt, &c->fs, &tr, &err), ENG_OK);
    eng_frame_stats fst;
    memset(&fst, 0, sizeof fst);
    m->frame_info(state, &fst);
    ck_assert_int_eq(fst.trace_maps, maps);
    memcpy(centres, fst.trace_centres, (size_t)maps * sizeof centres[0]);
    eng_buffer b;
    int count = 0;
    while (m->buffer(state, count, &b))
        count++;
    ck_assert_int_eq(count, maps * 18);
    ck_assert(m->buffer(state, 2, &b));
    ck_assert_str_eq(b.name, "multiimage.map0.face0.material");
    ck_assert_int_eq(b.channel_count, 6);
    eng_trace_settings ts = {0, threads, 0, 0, {0, 0, 0, 0}, 0.0f};
    ck_assert_int_eq(photon_trace_with(&tr, &c->fs, rm, in, n, &ts, out, st, &err), ENG_OK);
    m->destroy(state);
}

START_TEST(multi_image_cornell)
{
    fixture *f = fixture_open();
    cornell c = f->c;
    const eng_random_maps rm = f->rm;
    const eng_bounce_photon *in = f->in;
    eng_photon_map a = {0}, b = {0};
    eng_trace_stats sa, sb;
    float ca[2][3], cb[2][3];
    run_mi(&c, &rm, in, N, 1, 2, 1, &a, &sa, ca);
    run_mi(&c, &rm, in, N, 3, 2, 1, &b, &sb, cb);
    /* Bit-identical for any thread count, centres included. */
    ck_assert_int_eq(memcmp(ca, cb, sizeof ca), 0);
    ck_assert_uint_eq(a.count, b.count);
    ck_assert_int_eq(memcmp(a.photons, b.photons, a.count * sizeof *a.photons), 0);
    ck_assert_int_eq(memcmp(&sa.counts, &sb.counts, sizeof sa.counts), 0);
    /* Centres inside the room, not inside the boxes (they see no back faces). */
    for (int k = 0; k < 2; k++)
        for (int i = 0; i < 3; i++) {
            ck_assert_float_gt(ca[k][i], c.fs.bounds_min[i]);
            ck_assert_float_lt(ca[k][i], c.fs.bounds_max[i]);
        }
    const eng_trace_counts *t = &sa.counts;
    ck_assert_uint_gt(t->rays, N);
    ck_assert_uint_eq(t->rays, t->resolved + t->fallback + t->dropped);
    ck_assert_uint_eq(t->dropped, 0);
    ck_assert_uint_eq(t->types[0] + t->types[1] + t->types[2] + t->types[3], 2 * t->rays);
    /* The box is open at the front: some rays leave it; most hits agree with Embree's. */
    ck_assert_uint_le(t->compared, t->rays);
    ck_assert_uint_gt(t->compared, t->rays / 2);
    ck_assert_msg((double)t->agree >= 0.9 * (double)t->compared, "agree %llu of %llu",
                  (unsigned long long)t->agree, (unsigned long long)t->compared);
    photon_map_free(&a);
    photon_map_free(&b);
    fixture_close(f);
}
END_TEST

static Suite *multiimage_suite(void)
{
    Suite *s = suite_create("multiimage");
    TCase *tc = tcase_create("unit");
    tcase_add_test(tc, texel_round_trip);
    tcase_add_test(tc, texel_area_eq1);
    tcase_add_test(tc, select_greedy);
    tcase_add_test(tc, false_position_room);
    tcase_add_test(tc, type_b_behind_occluder);
    tcase_add_test(tc, angular_error_eq2);
    tcase_add_test(tc, classify_types);
    suite_add_tcase(s, tc);
    TCase *tm = tcase_create("methods");
    tcase_set_timeout(tm, 120);
    tcase_add_test(tm, embree_method_bit_identical);
    tcase_add_test(tm, multi_image_cornell);
    suite_add_tcase(s, tm);
    return s;
}

int main(void)
{
    SRunner *sr = srunner_create(multiimage_suite());
    srunner_run_all(sr, CK_NORMAL);
    int failed = srunner_ntests_failed(sr);
    srunner_free(sr);
    return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
