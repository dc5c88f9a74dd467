/* spec_envmap.c — the "envmap" specular method (specular.h): the cheap approximation of
 * 003_d0bf8e920b03f4e1.txt §3 step 5, option 3 (its Fig. 7): per specular object a dynamic
 * cube map of the radiance arriving at the object's centre (the centre of its world bounding
 * box), made every frame, and looked up by the reflected and refracted directions at the
 * surface the eye sees.
 *
 * Cube map: ENVMAP_SIZE² texels per face, each the radiance along the ray from the centre
 * through the texel's centre, found by eye_tracer_ray (the traced method's shading: direct
 * light by shadow rays + the photon gather at the first non-specular surface, continued
 * through other mirrors and glass) with the object itself passed through. Made on the CPU
 * with Embree rather than by rasterising six views: the same radiance the traced method sees,
 * so the difference between the two methods is the approximation alone.
 * Lookup: the delta branches at the pixel's surface (eye_split, both weighted), each read
 * from the map of the object the pixel's G-buffer point lies in by its direction, nearest
 * texel. The approximations (what its error measures): every point of the object sees the
 * environment from the centre (parallax), and a refracted ray is looked up as it enters, not
 * as it leaves the object (no second refraction, no internal reflection).
 *
 * Determinism: texels and pixels are independent, each one thread's fixed work. */
#include "specular.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define ENVMAP_SIZE 32

typedef struct envmap_object {
    uint32_t draw;
    float lo[3], hi[3], centre[3];
} envmap_object;

typedef struct envmap_state {
    spec_buffers b;
    uint32_t count;
    envmap_object *objects;
    float *maps; /* count × 6 faces × ENVMAP_SIZE² × 3 */
} envmap_state;

/* Face and texel of direction d (the major axis picks the face, as GL cube maps do). */
static size_t texel_of(const float d[3])
{
    float a[3] = {fabsf(d[0]), fabsf(d[1]), fabsf(d[2])};
    int axis = a[0] >= a[1] && a[0] >= a[2] ? 0 : (a[1] >= a[2] ? 1 : 2);
    int face = 2 * axis + (d[axis] < 0.0f);
    float u = d[(axis + 1) % 3] / a[axis], v = d[(axis + 2) % 3] / a[axis];
    int x = (int)((u * 0.5f + 0.5f) * ENVMAP_SIZE), y = (int)((v * 0.5f + 0.5f) * ENVMAP_SIZE);
    x = x < 0 ? 0 : (x >= ENVMAP_SIZE ? ENVMAP_SIZE - 1 : x);
    y = y < 0 ? 0 : (y >= ENVMAP_SIZE ? ENVMAP_SIZE - 1 : y);
    return ((size_t)face * ENVMAP_SIZE + (size_t)y) * ENVMAP_SIZE + (size_t)x;
}

/* The unit direction through the centre of texel (face, x, y): texel_of's inverse. */
static void direction_of(int face, int x, int y, float d[3])
{
    int axis = face / 2;
    d[axis] = face % 2 ? -1.0f : 1.0f;
    d[(axis + 1) % 3] = ((float)x + 0.5f) / ENVMAP_SIZE * 2.0f - 1.0f;
    d[(axis + 2) % 3] = ((float)y + 0.5f) / ENVMAP_SIZE * 2.0f - 1.0f;
    float l = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int c = 0; c < 3; c++)
        d[c] /= l;
}

static void envmap_destroy(void *state)
{
    envmap_state *st = state;
    if (!st)
        return;
    spec_buffers_destroy(&st->b);
    free(st->objects);
    free(st->maps);
    free(st);
}

static eng_result envmap_create(int width, int height, void **state, eng_error *err)
{
    envmap_state *st = calloc(1, sizeof *st);
    if (!st)
        return eng_fail(err, ENG_ERR_NOMEM, "specular: out of memory");
    eng_result r = spec_buffers_create(&st->b, width, height, err);
    if (r != ENG_OK) {
        free(st);
        return r;
    }
    *state = st;
    return ENG_OK;
}

/* The specular draws of this frame and their world boxes. */
static void find_objects(envmap_state *st, const eng_frame_scene *fs)
{
    free(st->objects);
    st->objects = eng_xmalloc((fs->draw_count ? fs->draw_count : 1) * sizeof *st->objects);
    st->count = 0;
    for (uint32_t i = 0; i < fs->draw_count; i++) {
        scn_material m = eng_material_of(fs->scene, fs->draws[i].material);
        if (!eye_is_specular(&m))
            continue;
        envmap_object *o = &st->objects[st->count++];
        o->draw = i;
        for (int c = 0; c < 3; c++) {
            o->lo[c] = INFINITY;
            o->hi[c] = -INFINITY;
        }
        const scn_primitive *p = &fs->scene->primitives[fs->draws[i].primitive];
        const float *pos = eng_draw_positions(fs->scene, &fs->draws[i]);
        for (uint32_t v = 0; v < p->vertex_count; v++) {
            float q[3];
            m4_transform_point(fs->draws[i].world, pos + 3 * v, q);
            for (int c = 0; c < 3; c++) {
                o->lo[c] = fminf(o->lo[c], q[c]);
                o->hi[c] = fmaxf(o->hi[c], q[c]);
            }
        }
        for (int c = 0; c < 3; c++)
            o->centre[c] = p->vertex_count ? 0.5f * (o->lo[c] + o->hi[c]) : 0.0f;
    }
}

/* The object whose box holds p (the first such), else the one with the nearest centre. */
static uint32_t object_at(const envmap_state *st, const float p[3])
{
    uint32_t best = 0;
    float best_d = INFINITY;
    for (uint32_t k = 0; k < st->count; k++) {
        const envmap_object *o = &st->objects[k];
        float d = 0.0f;
        int inside = 1;
        for (int c = 0; c < 3; c++) {
            float m = 1e-3f * (1.0f + fabsf(o->centre[c]));
            inside &= p[c] >= o->lo[c] - m && p[c] <= o->hi[c] + m;
            d += (p[c] - o->centre[c]) * (p[c] - o->centre[c]);
        }
        if (inside)
            return k;
        if (d < best_d) {
            best_d = d;
            best = k;
        }
    }
    return best;
}

static eng_result envmap_run(void *state, const spec_input *in, spec_output *out, eng_error *err)
{
    envmap_state *st = state;
    spec_buffers *b = &st->b;
    glu_gbuffer_read(in->gbuf, &b->gb);
    eye_tracer *t = eye_tracer_create(in->fs, in->rt, in->map, in->radius, in->s, err);
    if (!t)
        return ENG_ERR_NOMEM;
    find_objects(st, in->fs);
    const size_t per_map = 6 * (size_t)ENVMAP_SIZE * ENVMAP_SIZE;
    free(st->maps);
    st->maps = eng_xmalloc((st->count ? st->count : 1) * per_map * 3 * sizeof(float));
    const int texels = (int)(st->count * per_map);
    const int w = b->width, h = b->height;
    const float *eye = in->fs->camera.eye;
    int threads = in->s->threads > 0 ? in->s->threads : 2;
#pragma omp parallel num_threads(threads)
    {
        eye_scratch sc = {NULL, 0};
#pragma omp for schedule(dynamic, 64)
        for (int i = 0; i < texels; i++) {
            uint32_t k = (uint32_t)((size_t)i / per_map);
            int rest = (int)((size_t)i % per_map), face = rest / (ENVMAP_SIZE * ENVMAP_SIZE);
            int y = rest / ENVMAP_SIZE % ENVMAP_SIZE, x = rest % ENVMAP_SIZE;
            float d[3];
            direction_of(face, x, y, d);
            eye_tracer_ray(t, st->objects[k].centre, d, st->objects[k].draw, &sc, st->maps + 3 * (size_t)i);
        }
#pragma omp for schedule(dynamic, 1)
        for (int y = 0; y < h; y++) {
            for (int x = 0; x < w; x++) {
                size_t i = (size_t)y * (size_t)w + (size_t)x;
                float *rad = b->radiance + 3 * i, *thr = b->throughput + 3 * i;
                const float *p = b->gb.position + 4 * i, *n = b->gb.normal + 3 * i;
                scn_material m;
                spec_buffers_material(b, i, &m);
                for (int c = 0; c < 3; c++)
                    rad[c] = thr[c] = 0.0f;
                b->depth[i] = 0.0f;
                float wi[3] = {eye[0] - p[0], eye[1] - p[1], eye[2] - p[2]};
                float len = sqrtf(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2]);
                if (st->count && len > 0.0f && eye_is_specular(&m)) {
                    for (int c = 0; c < 3; c++)
                        wi[c] /= len;
                    eye_branch br[2];
                    int nb = eye_split(&m, n, wi, 1.0f, br);
                    const float *map = st->maps + object_at(st, p) * per_map * 3;
                    for (int k = 0; k < nb; k++) {
                        const float *l = map + 3 * texel_of(br[k].dir);
                        for (int c = 0; c < 3; c++) {
                            rad[c] += br[k].weight[c] * l[c];
                            thr[c] += br[k].weight[c];
                        }
                    }
                    b->depth[i] = nb ? 1.0f : 0.0f;
                }
            }
        }
        free(sc.list);
    }
    eye_tracer_destroy(t);
    spec_buffers_finish(b, out);
    return ENG_OK;
}

const spec_method spec_envmap_method = {
    .name = "envmap",
    .create = envmap_create,
    .run = envmap_run,
    .destroy = envmap_destroy,
};
