/* eye_tracer.c — backward tracing of the eye
 * paths that the eye G-buffer ends at a mirror or at glass (003_d0bf8e920b03f4e1.txt §3 step
 * 5, option 1: "trace the specular eye paths on the CPU"), with Embree (rt.c).
 *
 * From every pixel whose surface has a delta lobe the path splits into both delta branches,
 * reflection and refraction, weighted by their Fresnel weights (eye_split) instead of one
 * random choice, so the image has no noise; total internal reflection leaves one branch.
 * Each branch continues through further specular surfaces until it has crossed
 * `specular_depth` of them (what is left beyond the cap is dropped: that light is missing,
 * never invented). At every non-specular surface a branch reaches, its throughput times
 *   direct light: Σ_l f(ω_l, ω_o)·E_l·cosθ_l·V_l, a shadow ray per light (rt_occluded) with
 *                 the light model of shaders/direct.frag.glsl (frame_light_at), and
 *   indirect light: the same photon map and kernel as the pixels the G-buffer sees, gathered
 *                 at that point (kd_gather_point: κ of 003 §5.1 Eq. 2–3, gk_add's BSDF),
 * where f is the engine's BSDF (gather_kernel.h: Lambert for the non-metallic, non-
 * transmissive part and the GGX lobe of metals rougher than the mirror threshold), is added
 * to the pixel, and so is the emission of every surface a branch meets (emitters are seen, not
 * light sources). A surface that is both (e.g. transmission 0.5) is shaded and split.
 * Refraction carries no η² factor, as in bsdf.c and the reference renderer: for a path that
 * enters and leaves a dielectric the factors cancel.
 *
 * Determinism: each pixel is computed by one thread with a fixed amount of work (its branch
 * tree, depth first, reflection before refraction) and the k-d gather sums in photon-index
 * order, so the result is bit-identical for any thread count. */
#include "eye_tracer.h"

#include "bsdf.h"
#include "gather_kernel.h"
#include "kdtree.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SPEC_MAX_DEPTH 16

struct eye_tracer {
    const eng_frame_scene *fs;
    const eng_rt *rt;
    const eng_photon_map *map; /* NULL: no indirect light at the surfaces reached */
    const float *r_xy;
    kd_tree tree;
    float radius, compression, far_dist;
    int depth;
};

static float dot3(const float a[3], const float b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

int eye_is_specular(const scn_material *m)
{
    float metallic = fminf(fmaxf(m->metallic, 0.0f), 1.0f), transmission = fminf(fmaxf(m->transmission, 0.0f), 1.0f);
    return (metallic > 0.0f && m->roughness < BSDF_MIRROR_ROUGHNESS) || (metallic < 1.0f && transmission > 0.0f);
}

int eye_scene_has_specular(const scn_scene *scene)
{
    for (uint32_t i = 0; i < scene->primitive_count; i++) {
        scn_material m = eng_material_of(scene, scene->primitives[i].material);
        if (eye_is_specular(&m))
            return 1;
    }
    return 0;
}

int eye_split(const scn_material *m, const float n[3], const float wi[3], float eta, eye_branch out[2])
{
    float metallic = fminf(fmaxf(m->metallic, 0.0f), 1.0f), transmission = fminf(fmaxf(m->transmission, 0.0f), 1.0f);
    float cos_n = dot3(wi, n);
    float s = cos_n >= 0.0f ? 1.0f : -1.0f;
    float ns[3] = {s * n[0], s * n[1], s * n[2]};
    float cos_i = fabsf(cos_n);
    if (!(cos_i > 0.0f))
        return 0;
    float mirror = metallic > 0.0f && m->roughness < BSDF_MIRROR_ROUGHNESS ? metallic : 0.0f;
    float glass = (1.0f - metallic) * transmission;
    int entering = cos_n > 0.0f;
    float n1 = entering ? eta : m->ior, n2 = entering ? m->ior : 1.0f;
    float r = glass > 0.0f ? bsdf_fresnel_dielectric(cos_i, n1, n2) : 0.0f;
    int count = 0;
    eye_branch *b = &out[count];
    float k = 1.0f - cos_i, k5 = k * k * k * k * k; /* Schlick, as bsdf.c's mirror */
    for (int c = 0; c < 3; c++) {
        b->dir[c] = 2.0f * cos_i * ns[c] - wi[c];
        b->weight[c] = mirror * (m->base_color[c] + (1.0f - m->base_color[c]) * k5) + glass * r;
    }
    b->eta = eta;
    if (b->weight[0] > 0.0f || b->weight[1] > 0.0f || b->weight[2] > 0.0f)
        count++;
    if (glass > 0.0f && r < 1.0f) {
        /* 002_… §4.5: ωr = −e·wi + (e·cosθi − cosθt)·ns, e = n1/n2 (no TIR: r < 1). */
        b = &out[count];
        float e = n1 / n2;
        float cos_t = sqrtf(fmaxf(0.0f, 1.0f - e * e * (1.0f - cos_i * cos_i)));
        float len = 0.0f;
        for (int c = 0; c < 3; c++) {
            b->dir[c] = -e * wi[c] + (e * cos_i - cos_t) * ns[c];
            len += b->dir[c] * b->dir[c];
        }
        len = sqrtf(len);
        for (int c = 0; c < 3; c++) {
            b->dir[c] /= len;
            b->weight[c] = glass * (1.0f - r) * m->base_color[c];
        }
        b->eta = n2;
        if (b->weight[0] > 0.0f || b->weight[1] > 0.0f || b->weight[2] > 0.0f)
            count++;
    }
    return count;
}

eye_tracer *eye_tracer_create(const eng_frame_scene *fs, const eng_rt *rt, const eng_photon_map *map,
                                const float *radius, const eng_settings *s, eng_error *err)
{
    eye_tracer *t = calloc(1, sizeof *t);
    if (!t) {
        eng_fail(err, ENG_ERR_NOMEM, "specular: out of memory");
        return NULL;
    }
    t->fs = fs;
    t->rt = rt;
    t->depth = s->specular_depth < 1 ? 1 : (s->specular_depth > SPEC_MAX_DEPTH ? SPEC_MAX_DEPTH : s->specular_depth);
    t->compression = s->normal_compression;
    float diag = 0.0f;
    for (int c = 0; c < 3; c++) {
        float e = fs->bounds_max[c] - fs->bounds_min[c];
        diag += e * e;
    }
    t->far_dist = 2.0f * sqrtf(diag) + 1.0f;
    if (map && map->count > 0 && radius) {
        if (kd_tree_build(map->photons[0].position, map->count, sizeof(eng_photon) / sizeof(float), &t->tree, err) !=
            ENG_OK) {
            free(t);
            return NULL;
        }
        t->map = map;
        t->r_xy = radius;
        for (size_t i = 0; i < map->count; i++)
            t->radius = fmaxf(t->radius, radius[i]);
    }
    return t;
}

void eye_tracer_destroy(eye_tracer *t)
{
    if (!t)
        return;
    kd_tree_free(&t->tree);
    free(t);
}

/* Light leaving the non-specular lobes of m at hit h toward `from` (the previous vertex):
 * direct light by shadow rays and the photon gather. ns: the shading normal turned toward wi. */
static void shade(const eye_tracer *t, const rt_hit *h, const scn_material *m, const float ns[3], const float wi[3],
                  const float from[3], int gather, eye_scratch *sc, float out[3])
{
    const float mat[4] = {m->roughness, m->metallic, m->transmission, m->ior};
    gk_pixel px;
    gk_pixel_init(&px, h->position, ns, m->base_color, mat, from);
    float kd = (1.0f - m->metallic) * (1.0f - m->transmission) / (float)ENG_PI;
    int glossy = m->metallic > 0.0f && m->roughness >= BSDF_MIRROR_ROUGHNESS;
    const float *ng = h->geom_normal;
    float gi = dot3(ng, wi);
    out[0] = out[1] = out[2] = 0.0f;
    for (uint32_t l = 0; l < t->fs->light_count; l++) {
        const eng_light_pose *lp = &t->fs->lights[l];
        float wl[3], dist, e[3];
        if (!frame_light_at(lp, h->position, wl, &dist, e))
            continue;
        float cosl = dot3(ns, wl), gl = dot3(ng, wl);
        if (!(cosl > 0.0f) || (gl >= 0.0f) != (gi >= 0.0f)) /* the light is behind the true surface */
            continue;
        float f[3], g[3] = {0.0f, 0.0f, 0.0f};
        if (glossy)
            gk_glossy(&px, wl, cosl, g);
        for (int c = 0; c < 3; c++)
            f[c] = kd * m->base_color[c] + g[c];
        float eps = gl >= 0.0f ? bsdf_offset_eps(h->position) : -bsdf_offset_eps(h->position);
        float a[3], b[3];
        for (int c = 0; c < 3; c++) {
            a[c] = h->position[c] + eps * ng[c];
            b[c] = isinf(dist) ? h->position[c] + t->far_dist * wl[c] : lp->position[c];
        }
        if (rt_occluded(t->rt, a, b))
            continue;
        for (int c = 0; c < 3; c++)
            out[c] += f[c] * e[c] * cosl;
    }
    if (gather && t->map) {
        float acc[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        kd_gather_point(&t->tree, t->map, t->r_xy, t->radius, t->compression, &px, &sc->list, &sc->cap, acc, NULL);
        for (int c = 0; c < 3; c++)
            out[c] += acc[c];
    }
}

typedef struct spec_ray {
    float org[3], dir[3], thr[3], eta;
    int bounce; /* specular surfaces crossed so far */
} spec_ray;

/* Pushes the branches of a split at point p (normal n used for the offset) onto the stack. */
static int push_branches(spec_ray *stack, int top, const eye_branch *b, int count, const float p[3],
                         const float n[3], const float thr[3], int bounce)
{
    float eps = bsdf_offset_eps(p);
    /* Reflection first on top of the stack's order: pushed last, popped first. */
    for (int k = count - 1; k >= 0; k--) {
        spec_ray *r = &stack[top++];
        float side = dot3(n, b[k].dir) >= 0.0f ? eps : -eps;
        for (int c = 0; c < 3; c++) {
            r->org[c] = p[c] + side * n[c];
            r->dir[c] = b[k].dir[c];
            r->thr[c] = thr[c] * b[k].weight[c];
        }
        r->eta = b[k].eta;
        r->bounce = bounce;
    }
    return top;
}

/* Follows the branch tree on the stack depth first, adding to radiance/throughput/depth as
 * eye_tracer_pixel documents. Hits on draw `skip` (UINT32_MAX: none) are passed through by
 * rays that have not yet met another surface (the envmap's rays leave their own object).
 * emit 0: the emitters met add nothing (the path has scattered diffusely before: emitters are
 * seen only after delta lobes, as in the reference renderer). */
static void trace_tree(const eye_tracer *t, spec_ray *stack, int top, uint32_t skip, int emit, eye_scratch *sc,
                       float radiance[3], float *depth, float throughput[3])
{
    eye_branch b[2];
    const scn_scene *scene = t->fs->scene;
    int passes = 0;
    while (top > 0) {
        spec_ray r = stack[--top];
        rt_hit h;
        if (!rt_intersect(t->rt, r.org, r.dir, 0.0f, INFINITY, &h))
            continue; /* nothing emits in the background */
        if (h.draw == skip && r.bounce == 1 && passes < 16) {
            float eps = bsdf_offset_eps(h.position);
            for (int c = 0; c < 3; c++)
                r.org[c] = h.position[c] + eps * r.dir[c];
            stack[top++] = r;
            passes++;
            continue;
        }
        if ((float)r.bounce > *depth)
            *depth = (float)r.bounce;
        scn_material hm = eng_material_at(scene, &h);
        const float hwi[3] = {-r.dir[0], -r.dir[1], -r.dir[2]};
        for (int c = 0; c < 3 && emit; c++) /* an emitter seen in the mirror (not a light source) */
            radiance[c] += r.thr[c] * (hm.emissive[c] * h.emissive_tex[c]);
        /* The scattering normal: the interpolated one unless it puts wi on the other side
         * than the true surface does (photon_trace.c's and reference.c's rule). */
        const float *hn = (dot3(h.geom_normal, hwi) >= 0.0f) == (dot3(h.normal, hwi) >= 0.0f) ? h.normal
                                                                                            : h.geom_normal;
        if (bsdf_stores_photons(&hm)) {
            float s = dot3(hn, hwi) >= 0.0f ? 1.0f : -1.0f;
            float ns[3] = {s * hn[0], s * hn[1], s * hn[2]}, l[3];
            shade(t, &h, &hm, ns, hwi, r.org, 1, sc, l);
            for (int c = 0; c < 3; c++) {
                radiance[c] += r.thr[c] * l[c];
                throughput[c] += r.thr[c];
            }
        }
        if (r.bounce < t->depth && eye_is_specular(&hm))
            top = push_branches(stack, top, b, eye_split(&hm, hn, hwi, r.eta, b), h.position, h.geom_normal, r.thr,
                                r.bounce + 1);
    }
}

void eye_tracer_pixel(const eye_tracer *t, const float p[3], const float n[3], const scn_material *m,
                       const float eye[3], eye_scratch *sc, float radiance[3], float *depth, float throughput[3])
{
    for (int c = 0; c < 3; c++)
        radiance[c] = throughput[c] = 0.0f;
    *depth = 0.0f;
    if (!eye_is_specular(m))
        return;
    float wi[3] = {eye[0] - p[0], eye[1] - p[1], eye[2] - p[2]};
    float len = sqrtf(dot3(wi, wi));
    if (!(len > 0.0f))
        return;
    for (int c = 0; c < 3; c++)
        wi[c] /= len;
    /* Depth first: at most one pending branch per level besides the one being followed. */
    spec_ray stack[2 * SPEC_MAX_DEPTH + 2];
    eye_branch b[2];
    const float one[3] = {1.0f, 1.0f, 1.0f};
    int top = push_branches(stack, 0, b, eye_split(m, n, wi, 1.0f, b), p, n, one, 1);
    trace_tree(t, stack, top, UINT32_MAX, 1, sc, radiance, depth, throughput);
}

void eye_tracer_translucent(const eye_tracer *t, const rt_hit *h, const scn_material *m, const float eye[3],
                             eye_scratch *sc, float radiance[3])
{
    float wi[3] = {eye[0] - h->position[0], eye[1] - h->position[1], eye[2] - h->position[2]};
    float len = sqrtf(dot3(wi, wi));
    radiance[0] = radiance[1] = radiance[2] = 0.0f;
    if (!(len > 0.0f))
        return;
    for (int c = 0; c < 3; c++)
        wi[c] /= len;
    const float *hn = (dot3(h->geom_normal, wi) >= 0.0f) == (dot3(h->normal, wi) >= 0.0f) ? h->normal : h->geom_normal;
    float s = dot3(hn, wi) >= 0.0f ? 1.0f : -1.0f;
    float ns[3] = {s * hn[0], s * hn[1], s * hn[2]};
    if (bsdf_stores_photons(m))
        shade(t, h, m, ns, wi, eye, 0, sc, radiance); /* direct light only: no photons on a translucent surface */
    for (int c = 0; c < 3; c++)
        radiance[c] += m->emissive[c];
    if (eye_is_specular(m)) {
        spec_ray stack[2 * SPEC_MAX_DEPTH + 2];
        eye_branch b[2];
        const float one[3] = {1.0f, 1.0f, 1.0f};
        float depth = 0.0f, thr[3] = {0.0f, 0.0f, 0.0f}, l[3] = {0.0f, 0.0f, 0.0f};
        int top = push_branches(stack, 0, b, eye_split(m, hn, wi, 1.0f, b), h->position, h->geom_normal, one, 1);
        trace_tree(t, stack, top, UINT32_MAX, 1, sc, l, &depth, thr);
        for (int c = 0; c < 3; c++)
            radiance[c] += l[c];
    }
}

/* One ray's branch tree from org along dir (eye_tracer_ray, eye_tracer_gather_ray). */
static void trace_ray(const eye_tracer *t, const float org[3], const float dir[3], uint32_t skip_draw, int emit,
                      eye_scratch *sc, float radiance[3])
{
    spec_ray stack[2 * SPEC_MAX_DEPTH + 2];
    float depth = 0.0f, throughput[3] = {0.0f, 0.0f, 0.0f};
    for (int c = 0; c < 3; c++) {
        stack[0].org[c] = org[c];
        stack[0].dir[c] = dir[c];
        stack[0].thr[c] = 1.0f;
        radiance[c] = 0.0f;
    }
    stack[0].eta = 1.0f;
    stack[0].bounce = 1;
    trace_tree(t, stack, 1, skip_draw, emit, sc, radiance, &depth, throughput);
}

void eye_tracer_ray(const eye_tracer *t, const float org[3], const float dir[3], uint32_t skip_draw,
                     eye_scratch *sc, float radiance[3])
{
    trace_ray(t, org, dir, skip_draw, 1, sc, radiance);
}

void eye_tracer_gather_ray(const eye_tracer *t, const float org[3], const float dir[3], eye_scratch *sc,
                            float radiance[3])
{
    trace_ray(t, org, dir, UINT32_MAX, 0, sc, radiance);
}

/* ---------------------------------------------------------------- the methods' buffers */
