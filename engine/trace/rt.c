/* rt.c — the scene as Embree 3 sees it (ISPM §3: bounces after the first are traced on the
 * CPU). One triangle geometry per drawn primitive instance, in world space. Geometry whose
 * world matrix did not change since the last frame is left alone; geometry that moved is
 * re-transformed in place and refit (RTC_BUILD_QUALITY_REFIT), so a static scene costs one
 * build for the whole run. Skinned and morphed draws (deform_gl.c) bring their own vertices,
 * deformed on the CPU each frame: they are re-posed every frame and refit the same way.
 *
 * Each geometry also keeps its world-space vertex normals (object normals through the
 * inverse transpose, m4_normal_matrix), re-posed with the positions, so rt_intersect can
 * return the interpolated shading normal the photon tracer scatters about, and its world
 * tangents where the primitive has them, for the normal texture (scn_normal_at).
 *
 * Lamps: the emitter of a point or spot light with a size is an opaque sphere that
 * reflects nothing, tested analytically (rt_lamp_hit): a ray that meets one before any
 * surface hits nothing (rt_intersect returns 0: the photon or path is absorbed), except a ray
 * that starts inside it (light vertices and photons leaving their own light's centre).
 *
 * alphaMode BLEND (pass_translucent.c): BLEND geometry is not in the scene that
 * rt_intersect and rt_occluded see (photons, shadow rays and the specular eye paths pass
 * through translucent surfaces as if they were not there); it is in a second Embree scene that
 * only rt_intersect_blend sees.
 *
 * Determinism: the device is made with a pinned ISA (isa=sse2) and thread count, recorded in
 * the manifest, so ray results do not follow the host's SIMD width. Embree finds which
 * triangle a ray hits; the hit's distance and barycentrics are then computed again here
 * (exact_hit), because Embree's divide by the triangle's determinant through the processor's
 * approximate reciprocal (RCPPS, refined by one Newton step), whose bits differ between
 * processor models: the same binary on two hosts gave a third of cornell-box-ci's photons
 * positions 1-2 ulps apart. IEEE division and products (no FMA:
 * -ffp-contract=off) give the same bits on every x86-64. */
#include "trace.h"

#include <embree3/rtcore.h>
#include <emmintrin.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RT_MAX_LAMPS 8

typedef struct rt_geom {
    RTCGeometry geom;
    const scn_scene *scene;
    uint32_t primitive;
    int32_t material;
    float *normals; /* world space, 3 per vertex, unit (zero where the authored normal is) */
    float *tangents; /* world space xyz (not renormalised, as the G-buffers interpolate them) + w; NULL without */
    float *tris; /* per triangle, world space: first vertex, e1 = v1 - v0, e2 = v2 - v0 (xyz each; pose), their
                  * fourth floats the normalised geometric normal (x, y, z) */
    float world[16];
    int posed;
    /* What a hit on this draw looks up (rt_geom_lookups): fixed by the material and the
     * primitive's attributes, so a hit skips the texture and COLOR_0 calls it does not need. */
    const scn_material *mat; /* NULL: the glTF default material */
    uint8_t base_lookup, mr_lookup, emissive_lookup;
    uint8_t textured; /* the material names a texture (photon_trace.c looks those up itself) */
} rt_geom;

struct eng_rt {
    const scn_scene *scene;
    RTCDevice device;
    RTCScene rtscene;
    RTCScene blend_scene; /* alphaMode BLEND geometry only (pass_translucent.c); NULL without any */
    uint32_t geom_count;
    rt_geom *geoms;
    uint32_t lamp_count;
    float lamp[RT_MAX_LAMPS][4]; /* centre, radius */
    int lamp_light[RT_MAX_LAMPS];
};

eng_result rt_create(const scn_scene *scene, int threads, eng_rt **out, eng_error *err)
{
    *out = NULL;
    char cfg[64];
    snprintf(cfg, sizeof cfg, "isa=sse2,threads=%d", threads < 1 ? 1 : threads);
    eng_rt *rt = calloc(1, sizeof *rt);
    if (!rt)
        return eng_fail(err, ENG_ERR_NOMEM, "embree: out of memory");
    rt->scene = scene;
    rt->device = rtcNewDevice(cfg);
    if (!rt->device) {
        free(rt);
        return eng_fail(err, ENG_ERR_UNSUPPORTED, "embree: cannot create a device with \"%s\" (error %d)", cfg,
                        (int)rtcGetDeviceError(NULL));
    }
    rt->rtscene = rtcNewScene(rt->device);
    rtcSetSceneBuildQuality(rt->rtscene, RTC_BUILD_QUALITY_MEDIUM);
    *out = rt;
    return ENG_OK;
}

/* alphaMode MASK (glTF §3.9.4) for rays: a hit where the base colour's alpha (factor times
 * texture and COLOR_0, scn_base_color_at, the value the G-buffers cut at) is below the
 * cutoff is not a hit. Installed as intersection and occlusion filter on MASK geometry. */
/* RTCHitN's SOA fields (Ng_x, Ng_y, Ng_z, u, v, primID, ...; rtcore_ray.h's accessors are
 * C++ only). */
static float hitn_float(const struct RTCHitN *h, unsigned n, unsigned field, unsigned i)
{
    float f;
    memcpy(&f, (const char *)h + ((size_t)field * n + i) * 4, 4);
    return f;
}

/* RTCRayN's SOA fields (org_x, org_y, org_z, tnear, dir_x, dir_y, dir_z, ...). */
static float rayn_float(const struct RTCRayN *r, unsigned n, unsigned field, unsigned i)
{
    float f;
    memcpy(&f, (const char *)r + ((size_t)field * n + i) * 4, 4);
    return f;
}

static unsigned hitn_uint(const struct RTCHitN *h, unsigned n, unsigned field, unsigned i)
{
    unsigned u;
    memcpy(&u, (const char *)h + ((size_t)field * n + i) * 4, 4);
    return u;
}

/* The distance and barycentrics (Embree's u, v: the weights of the triangle's second and third
 * vertex) of the ray org + t·dir on triangle prim of draw g, by Möller and Trumbore's
 * algorithm in IEEE single precision. Leaves *t, *u, *v as they were (Embree's) where the
 * determinant is 0 or a result is not finite: a ray Embree reports as a hit is never parallel
 * to its triangle, so that is only a safeguard. */
static void exact_hit(const rt_geom *g, unsigned prim, const float org[3], const float dir[3], float *t, float *u,
                      float *v)
{
    const float *a = g->tris + 12 * (size_t)prim, *e1 = a + 4, *e2 = a + 8; /* pose's */
    const float pv[3] = {dir[1] * e2[2] - dir[2] * e2[1], dir[2] * e2[0] - dir[0] * e2[2],
                         dir[0] * e2[1] - dir[1] * e2[0]};
    const float det = e1[0] * pv[0] + e1[1] * pv[1] + e1[2] * pv[2];
    if (det == 0.0f)
        return;
    const float inv = 1.0f / det;
    const float tv[3] = {org[0] - a[0], org[1] - a[1], org[2] - a[2]};
    const float qv[3] = {tv[1] * e1[2] - tv[2] * e1[1], tv[2] * e1[0] - tv[0] * e1[2], tv[0] * e1[1] - tv[1] * e1[0]};
    const float eu = (tv[0] * pv[0] + tv[1] * pv[1] + tv[2] * pv[2]) * inv;
    const float ev = (dir[0] * qv[0] + dir[1] * qv[1] + dir[2] * qv[2]) * inv;
    const float et = (e2[0] * qv[0] + e2[1] * qv[1] + e2[2] * qv[2]) * inv;
    if (isfinite(eu) && isfinite(ev) && isfinite(et))
        *t = et, *u = eu, *v = ev;
}

/* exact_hit for the four lanes of a packet Embree answered (rh; its rays SOA as cast), with
 * SSE: each lane computes exact_hit's products, sums and division in its order (IEEE single
 * precision, like the scalar code), so a hit gets the same bits either way. Lanes with hit[j]
 * set get t[j], u[j], v[j] (keeping Embree's where exact_hit would); the others compute on
 * lane `any`'s triangle (a hit lane) and are ignored. */
static void exact_hit4(const eng_rt *rt, const struct RTCRayHit4 *rh, const int hit[4], int any, float t[4],
                       float u[4], float v[4])
{
    __m128 va[4], e1[4], e2[4]; /* the triangles' first vertex and edges (pose's), one per lane, xyz_ */
    for (int j = 0; j < 4; j++) {
        const int k = hit[j] ? j : any;
        const float *r = rt->geoms[rh->hit.geomID[k]].tris + 12 * (size_t)rh->hit.primID[k];
        va[j] = _mm_load_ps(r);
        e1[j] = _mm_load_ps(r + 4);
        e2[j] = _mm_load_ps(r + 8);
    }
    _MM_TRANSPOSE4_PS(va[0], va[1], va[2], va[3]); /* va[0] = the lanes' x, ... */
    _MM_TRANSPOSE4_PS(e1[0], e1[1], e1[2], e1[3]);
    _MM_TRANSPOSE4_PS(e2[0], e2[1], e2[2], e2[3]);
    const __m128 dx = _mm_load_ps(rh->ray.dir_x), dy = _mm_load_ps(rh->ray.dir_y), dz = _mm_load_ps(rh->ray.dir_z);
    const __m128 e1x = e1[0], e1y = e1[1], e1z = e1[2], e2x = e2[0], e2y = e2[1], e2z = e2[2];
    const __m128 pvx = _mm_sub_ps(_mm_mul_ps(dy, e2z), _mm_mul_ps(dz, e2y));
    const __m128 pvy = _mm_sub_ps(_mm_mul_ps(dz, e2x), _mm_mul_ps(dx, e2z));
    const __m128 pvz = _mm_sub_ps(_mm_mul_ps(dx, e2y), _mm_mul_ps(dy, e2x));
    const __m128 det = _mm_add_ps(_mm_add_ps(_mm_mul_ps(e1x, pvx), _mm_mul_ps(e1y, pvy)), _mm_mul_ps(e1z, pvz));
    const __m128 inv = _mm_div_ps(_mm_set1_ps(1.0f), det);
    const __m128 tx = _mm_sub_ps(_mm_load_ps(rh->ray.org_x), va[0]), ty = _mm_sub_ps(_mm_load_ps(rh->ray.org_y), va[1]),
                 tz = _mm_sub_ps(_mm_load_ps(rh->ray.org_z), va[2]);
    const __m128 qx = _mm_sub_ps(_mm_mul_ps(ty, e1z), _mm_mul_ps(tz, e1y));
    const __m128 qy = _mm_sub_ps(_mm_mul_ps(tz, e1x), _mm_mul_ps(tx, e1z));
    const __m128 qz = _mm_sub_ps(_mm_mul_ps(tx, e1y), _mm_mul_ps(ty, e1x));
    const __m128 eu = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(tx, pvx), _mm_mul_ps(ty, pvy)), _mm_mul_ps(tz, pvz)), inv);
    const __m128 ev = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, qx), _mm_mul_ps(dy, qy)), _mm_mul_ps(dz, qz)), inv);
    const __m128 et = _mm_mul_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(e2x, qx), _mm_mul_ps(e2y, qy)), _mm_mul_ps(e2z, qz)), inv);
    float fd[4], fu[4], fv[4], ft[4];
    _mm_storeu_ps(fd, det);
    _mm_storeu_ps(fu, eu);
    _mm_storeu_ps(fv, ev);
    _mm_storeu_ps(ft, et);
    for (int j = 0; j < 4; j++)
        if (hit[j] && fd[j] != 0.0f && isfinite(fu[j]) && isfinite(fv[j]) && isfinite(ft[j]))
            t[j] = ft[j], u[j] = fu[j], v[j] = fv[j];
}

static void mask_filter(const struct RTCFilterFunctionNArguments *args)
{
    const rt_geom *g = args->geometryUserPtr;
    const scn_material *m = &g->scene->materials[g->material];
    const scn_primitive *p = &g->scene->primitives[g->primitive];
    for (unsigned i = 0; i < args->N; i++) {
        if (args->valid[i] != -1)
            continue;
        const unsigned prim = hitn_uint(args->hit, args->N, 5, i);
        const float org[3] = {rayn_float(args->ray, args->N, 0, i), rayn_float(args->ray, args->N, 1, i),
                              rayn_float(args->ray, args->N, 2, i)};
        const float dir[3] = {rayn_float(args->ray, args->N, 4, i), rayn_float(args->ray, args->N, 5, i),
                              rayn_float(args->ray, args->N, 6, i)};
        float t, u = hitn_float(args->hit, args->N, 3, i), v = hitn_float(args->hit, args->N, 4, i);
        exact_hit(g, prim, org, dir, &t, &u, &v);
        float c[4];
        scn_base_color_at(g->scene, m, p, prim, u, v, c);
        if (m->base_color[3] * c[3] < m->alpha_cutoff)
            args->valid[i] = 0;
    }
}

static int same_matrix(const float a[16], const float b[16])
{
    return memcmp(a, b, 16 * sizeof(float)) == 0;
}

/* Does texture reference r sample anything on p? (scn_texref_at's own test: without a
 * texture or the texcoords it names, scn_texref_at leaves 1 and returns 0.) */
static int texref_used(const scn_scene *scene, const scn_texref *r, const scn_primitive *p)
{
    return r->texture >= 0 && (uint32_t)r->texture < scene->texture_count && p->texcoords[r->texcoord];
}

/* Which of intersect_in's per-hit lookups can change its (1, ...) defaults on draw g. */
static void rt_geom_lookups(rt_geom *g, const scn_scene *scene, const scn_primitive *p)
{
    g->mat = g->material >= 0 && (uint32_t)g->material < scene->material_count ? &scene->materials[g->material] : NULL;
    g->base_lookup = p->colors || (g->mat && texref_used(scene, &g->mat->base_color_tex, p));
    g->mr_lookup = g->mat && texref_used(scene, &g->mat->metallic_roughness_tex, p);
    g->emissive_lookup = g->mat && texref_used(scene, &g->mat->emissive_tex, p);
    g->textured = g->mat && rt_material_textured(g->mat);
}

static inline void normalize_or(float v[3], const float fallback[3])
{
    float len = sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (len > 0.0f && isfinite(len)) {
        for (int i = 0; i < 3; i++)
            v[i] /= len;
    } else {
        for (int i = 0; i < 3; i++)
            v[i] = fallback[i];
    }
}

/* Draw d's vertices (the primitive's, or this frame's deformed ones) at its world matrix. */
static void pose(rt_geom *g, const scn_primitive *p, const eng_draw *d)
{
    const float *world = d->world;
    const float *positions = d->positions ? d->positions : p->positions;
    const float *normals = d->normals ? d->normals : p->normals;
    float *v = rtcGetGeometryBufferData(g->geom, RTC_BUFFER_TYPE_VERTEX, 0);
    for (uint32_t i = 0; i < p->vertex_count; i++)
        m4_transform_point(world, positions + 3 * i, v + 4 * i);
    for (uint32_t k = 0; k < p->index_count / 3; k++) { /* exact_hit's edges, once a pose */
        const float *a = v + 4 * p->indices[3 * k], *b = v + 4 * p->indices[3 * k + 1], *c = v + 4 * p->indices[3 * k + 2];
        float *r = g->tris + 12 * (size_t)k;
        for (int i = 0; i < 3; i++)
            r[i] = a[i], r[4 + i] = b[i] - a[i], r[8 + i] = c[i] - a[i];
        /* In the fourth floats: the geometric normal of every hit on the triangle
         * (hit_geometry), Embree's Ng normalised. Embree's Ng is cross(e2, e1) with its own
         * edges e1 = v0 − v1, e2 = v2 − v0 (Möller–Trumbore in its SSE2 kernels, no FMA): the same
         * products and differences, so the same bits, here once a pose instead of a square
         * root and three divisions a hit (test_photon packets_match_single_rays checks them
         * against Embree's Ng on every hit). */
        const float f1[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]}, *f2 = r + 8;
        float ng[3] = {f2[1] * f1[2] - f2[2] * f1[1], f2[2] * f1[0] - f2[0] * f1[2], f2[0] * f1[1] - f2[1] * f1[0]};
        normalize_or(ng, (const float[3]){0.0f, 1.0f, 0.0f});
        r[3] = ng[0], r[7] = ng[1], r[11] = ng[2];
    }
    float nm[9];
    m4_normal_matrix(nm, world);
    for (uint32_t i = 0; i < p->vertex_count; i++) {
        const float *o = normals + 3 * i;
        float *w = g->normals + 3 * i;
        for (int r = 0; r < 3; r++)
            w[r] = nm[r] * o[0] + nm[3 + r] * o[1] + nm[6 + r] * o[2];
        float len = sqrtf(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
        if (len > 0.0f)
            for (int r = 0; r < 3; r++)
                w[r] /= len;
    }
    if (g->tangents) { /* surface directions: the world matrix's upper 3×3, as gbuffer.vert.glsl */
        const float *tan = d->tangents ? d->tangents : p->tangents;
        for (uint32_t i = 0; i < p->vertex_count; i++) {
            const float *o = tan + 4 * i;
            float *w = g->tangents + 4 * i;
            for (int r = 0; r < 3; r++)
                w[r] = world[r] * o[0] + world[4 + r] * o[1] + world[8 + r] * o[2];
            w[3] = o[3];
        }
    }
    rtcUpdateGeometryBuffer(g->geom, RTC_BUFFER_TYPE_VERTEX, 0);
    memcpy(g->world, world, sizeof g->world);
    g->posed = 1;
    rtcCommitGeometry(g->geom);
}

void rt_update(eng_rt *rt, const eng_frame_scene *fs)
{
    rt->lamp_count = 0;
    for (uint32_t l = 0; l < fs->light_count && rt->lamp_count < RT_MAX_LAMPS; l++) {
        const eng_light_pose *lp = &fs->lights[l];
        if (!(lp->radius > 0.0f) || lp->type == SCN_LIGHT_DIRECTIONAL)
            continue;
        memcpy(rt->lamp[rt->lamp_count], lp->position, 3 * sizeof(float));
        rt->lamp[rt->lamp_count][3] = lp->radius;
        rt->lamp_light[rt->lamp_count++] = (int)l;
    }
    if (!rt->geoms) {
        rt->geom_count = fs->draw_count;
        rt->geoms = calloc(fs->draw_count ? fs->draw_count : 1, sizeof *rt->geoms);
        if (!rt->geoms) {
            fprintf(stderr, "ispm: out of memory\n");
            abort();
        }
        for (uint32_t i = 0; i < fs->draw_count; i++) {
            const scn_primitive *p = &rt->scene->primitives[fs->draws[i].primitive];
            rt_geom *g = &rt->geoms[i];
            g->primitive = fs->draws[i].primitive;
            g->material = fs->draws[i].material;
            g->normals = malloc((p->vertex_count ? p->vertex_count : 1) * 3 * sizeof(float));
            g->tangents = p->tangents ? malloc((size_t)p->vertex_count * 4 * sizeof(float)) : NULL;
            g->tris = aligned_alloc(16, (p->index_count / 3 ? p->index_count / 3 : 1) * 12 * sizeof(float));
            if (!g->normals || (p->tangents && !g->tangents) || !g->tris) {
                fprintf(stderr, "ispm: out of memory\n");
                abort();
            }
            g->geom = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_TRIANGLE);
            /* 4 floats per vertex: Embree reads 16 bytes at the last vertex. */
            rtcSetNewGeometryBuffer(g->geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 4 * sizeof(float),
                                    p->vertex_count);
            unsigned *idx = rtcSetNewGeometryBuffer(g->geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                    3 * sizeof(unsigned), p->index_count / 3);
            memcpy(idx, p->indices, p->index_count * sizeof(unsigned));
            rtcSetGeometryBuildQuality(g->geom, RTC_BUILD_QUALITY_REFIT);
            g->scene = rt->scene;
            rt_geom_lookups(g, rt->scene, p);
            if (g->material >= 0 && (uint32_t)g->material < rt->scene->material_count &&
                rt->scene->materials[g->material].alpha_mode == SCN_ALPHA_MASK) {
                rtcSetGeometryUserData(g->geom, g);
                rtcSetGeometryIntersectFilterFunction(g->geom, mask_filter);
                rtcSetGeometryOccludedFilterFunction(g->geom, mask_filter);
            }
            pose(g, p, &fs->draws[i]);
            if (rt_is_blend(rt->scene, g->material)) {
                if (!rt->blend_scene) {
                    rt->blend_scene = rtcNewScene(rt->device);
                    rtcSetSceneBuildQuality(rt->blend_scene, RTC_BUILD_QUALITY_MEDIUM);
                }
                rtcAttachGeometryByID(rt->blend_scene, g->geom, i);
            } else {
                rtcAttachGeometryByID(rt->rtscene, g->geom, i);
            }
        }
        rtcCommitScene(rt->rtscene);
        if (rt->blend_scene)
            rtcCommitScene(rt->blend_scene);
        return;
    }
    int changed = 0;
    for (uint32_t i = 0; i < rt->geom_count && i < fs->draw_count; i++) {
        rt_geom *g = &rt->geoms[i];
        /* Deformed draws (skins, morph targets) change their vertices every frame. */
        if (!same_matrix(g->world, fs->draws[i].world) || fs->draws[i].positions) {
            pose(g, &rt->scene->primitives[g->primitive], &fs->draws[i]);
            changed = 1;
        }
    }
    if (changed) {
        rtcCommitScene(rt->rtscene);
        if (rt->blend_scene)
            rtcCommitScene(rt->blend_scene);
    }
}

int rt_is_blend(const scn_scene *scene, int32_t material)
{
    return material >= 0 && (uint32_t)material < scene->material_count &&
           scene->materials[material].alpha_mode == SCN_ALPHA_BLEND;
}

int rt_has_blend(const eng_rt *rt)
{
    return rt->blend_scene != NULL;
}

int rt_occluded(const eng_rt *rt, const float a[3], const float b[3])
{
    float d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    float len = sqrtf(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if (len <= 0.0f)
        return 0;
    const float eps = 1e-4f;
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay ray;
    memset(&ray, 0, sizeof ray);
    ray.org_x = a[0];
    ray.org_y = a[1];
    ray.org_z = a[2];
    ray.dir_x = d[0] / len;
    ray.dir_y = d[1] / len;
    ray.dir_z = d[2] / len;
    ray.tnear = eps;
    ray.tfar = len - eps;
    ray.mask = 0xFFFFFFFFu;
    rtcOccluded1(rt->rtscene, &ctx, &ray);
    return ray.tfar < 0.0f; /* Embree sets tfar to -inf on a hit */
}

int rt_lamp_hit(const eng_rt *rt, const float org[3], const float dir[3], float tmin, float tmax, int skip,
                float *t)
{
    int best = -1;
    for (uint32_t k = 0; k < rt->lamp_count; k++) {
        if (rt->lamp_light[k] == skip)
            continue;
        const float *c = rt->lamp[k];
        float oc[3] = {org[0] - c[0], org[1] - c[1], org[2] - c[2]};
        float b = oc[0] * dir[0] + oc[1] * dir[1] + oc[2] * dir[2];
        float cc = oc[0] * oc[0] + oc[1] * oc[1] + oc[2] * oc[2] - c[3] * c[3];
        float disc = b * b - cc;
        if (cc < 0.0f || !(disc > 0.0f))
            continue; /* starts inside, or misses */
        float t0 = -b - sqrtf(disc);
        if (t0 > tmin && t0 < tmax) {
            tmax = t0;
            best = rt->lamp_light[k];
        }
    }
    if (best >= 0)
        *t = tmax;
    return best;
}

/* A single ray org + t·dir, t in [tnear, tfar], with no hit yet. */
static void ray_init(struct RTCRayHit *rh, const float org[3], const float dir[3], float tnear, float tfar)
{
    memset(rh, 0, sizeof *rh);
    rh->ray.org_x = org[0];
    rh->ray.org_y = org[1];
    rh->ray.org_z = org[2];
    rh->ray.dir_x = dir[0];
    rh->ray.dir_y = dir[1];
    rh->ray.dir_z = dir[2];
    rh->ray.tnear = tnear;
    rh->ray.tfar = tfar;
    rh->ray.mask = 0xFFFFFFFFu;
    rh->hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

/* What a ray's closest hit is in rt_hit terms, from Embree's answer (t = its tfar, u, v, the
 * unnormalised Ng, geomID, primID): the lamps, the shading normal and the texture factors.
 * Two steps, so that a packet's rays (rt_intersect4_untextured) go through each step together
 * (the steps of different rays do not wait on each other); a single ray goes through both at
 * once. The same code for both, so a hit Embree reports alike gives the same rt_hit. */
typedef struct rt_answer {
    float t, u, v, ng[3]; /* Embree's tfar and hit: ng unnormalised */
    unsigned geom_id, prim_id;
} rt_answer;

/* Step 1: lamps, the hit point and the geometric normal; 0 when there is no hit. a's t, u, v
 * are exact_hit's (the caller's). */
static int hit_geometry(const eng_rt *rt, int lamps, const float org[3], const float dir[3], float tnear, float tfar,
                        const rt_answer *a, rt_hit *hit)
{
    int found = a->geom_id != RTC_INVALID_GEOMETRY_ID && a->geom_id < rt->geom_count;
    float tl;
    if (lamps && rt->lamp_count && rt_lamp_hit(rt, org, dir, tnear, found ? a->t : tfar, -1, &tl) >= 0)
        return 0; /* absorbed by a lamp */
    if (!found)
        return 0;
    hit->t = a->t;
    for (int i = 0; i < 3; i++)
        hit->position[i] = org[i] + a->t * dir[i];
    const float *r = rt->geoms[a->geom_id].tris + 12 * (size_t)a->prim_id; /* pose's normalised Ng */
    hit->geom_normal[0] = r[3], hit->geom_normal[1] = r[7], hit->geom_normal[2] = r[11];
    return 1;
}

/* Step 2 of a hit: the shading normal, the material and the texture factors. */
static void hit_surface(const eng_rt *rt, int untextured, const rt_answer *a, rt_hit *hit)
{
    const rt_geom *g = &rt->geoms[a->geom_id];
    const scn_primitive *p = &rt->scene->primitives[g->primitive];
    const uint32_t *tri = p->indices + 3 * (size_t)a->prim_id;
    const float u = a->u, v = a->v, w = 1.0f - u - v;
    const float *n0 = g->normals + 3 * tri[0], *n1 = g->normals + 3 * tri[1], *n2 = g->normals + 3 * tri[2];
    float ns[3];
    for (int i = 0; i < 3; i++)
        ns[i] = w * n0[i] + u * n1[i] + v * n2[i];
    normalize_or(ns, hit->geom_normal);
    if (g->tangents && g->material >= 0 && (uint32_t)g->material < rt->scene->material_count)
        scn_normal_at(rt->scene, &rt->scene->materials[g->material], p, a->prim_id, u, v, g->tangents + 4 * tri[0],
                      g->tangents + 4 * tri[1], g->tangents + 4 * tri[2], ns);
    memcpy(hit->normal, ns, sizeof ns);
    hit->material = g->material;
    hit->draw = a->geom_id;
    hit->tri = a->prim_id;
    hit->bary[0] = u;
    hit->bary[1] = v;
    const int lookups = g->base_lookup || g->mr_lookup || g->emissive_lookup;
    /* The triangle's world area: half the length of Embree's unnormalised Ng (e1 × e2). */
    hit->world_area = lookups ? 0.5f * sqrtf(a->ng[0] * a->ng[0] + a->ng[1] * a->ng[1] + a->ng[2] * a->ng[2]) : 0.0f;
    if (lookups && !(untextured && g->textured)) {
        rt_hit_textures(rt->scene, p, hit, 0.0f);
    } else { /* no lookup would return anything but 1 (see rt_geom), or the caller looks them up */
        hit->base_tex[0] = hit->base_tex[1] = hit->base_tex[2] = hit->base_tex[3] = 1.0f;
        hit->roughness_tex = hit->metallic_tex = 1.0f;
        hit->emissive_tex[0] = hit->emissive_tex[1] = hit->emissive_tex[2] = 1.0f;
    }
}

static int intersect_in(const eng_rt *rt, RTCScene scene, int lamps, int untextured, const float org[3],
                        const float dir[3], float tnear, float tfar, rt_hit *hit)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    ray_init(&rh, org, dir, tnear, tfar);
    rtcIntersect1(scene, &ctx, &rh);
    rt_answer a = {rh.ray.tfar, rh.hit.u, rh.hit.v, {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z}, rh.hit.geomID,
                   rh.hit.primID};
    if (a.geom_id != RTC_INVALID_GEOMETRY_ID && a.geom_id < rt->geom_count)
        exact_hit(&rt->geoms[a.geom_id], a.prim_id, org, dir, &a.t, &a.u, &a.v);
    if (!hit_geometry(rt, lamps, org, dir, tnear, tfar, &a, hit))
        return 0;
    hit_surface(rt, untextured, &a, hit);
    return 1;
}

int rt_intersect(const eng_rt *rt, const float org[3], const float dir[3], float tnear, float tfar, rt_hit *hit)
{
    return intersect_in(rt, rt->rtscene, 1, 0, org, dir, tnear, tfar, hit);
}

int rt_intersect_untextured(const eng_rt *rt, const float org[3], const float dir[3], float tnear, float tfar,
                            rt_hit *hit)
{
    return intersect_in(rt, rt->rtscene, 1, 1, org, dir, tnear, tfar, hit);
}

void rt_intersect4_untextured(const eng_rt *rt, int n, const rt_ray *rays, rt_hit *hits, int *found)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTC_ALIGN(16) struct RTCRayHit4 rh;
    RTC_ALIGN(16) int valid[4];
    for (int j = 0; j < 4; j++) {
        const rt_ray *r = &rays[j < n ? j : 0];
        rh.ray.time[j] = 0.0f; /* ray_init's fields, without a memset of the whole packet */
        rh.ray.id[j] = rh.ray.flags[j] = 0;
        valid[j] = j < n ? -1 : 0;
        rh.ray.org_x[j] = r->org[0];
        rh.ray.org_y[j] = r->org[1];
        rh.ray.org_z[j] = r->org[2];
        rh.ray.dir_x[j] = r->dir[0];
        rh.ray.dir_y[j] = r->dir[1];
        rh.ray.dir_z[j] = r->dir[2];
        rh.ray.tnear[j] = r->tnear;
        rh.ray.tfar[j] = INFINITY;
        rh.ray.mask[j] = 0xFFFFFFFFu;
        rh.hit.Ng_x[j] = rh.hit.Ng_y[j] = rh.hit.Ng_z[j] = rh.hit.u[j] = rh.hit.v[j] = 0.0f;
        rh.hit.primID[j] = 0;
        rh.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
    }
    rtcIntersect4(valid, rt->rtscene, &ctx, &rh);
    /* Embree's answers, the hits' t, u, v then through exact_hit4. */
    rt_answer a[4];
    int hit[4] = {0}, any = -1;
    float t[4], u[4], v[4];
    for (int j = 0; j < n; j++) {
        a[j] = (rt_answer){rh.ray.tfar[j], rh.hit.u[j], rh.hit.v[j], {rh.hit.Ng_x[j], rh.hit.Ng_y[j], rh.hit.Ng_z[j]},
                           rh.hit.geomID[j], rh.hit.primID[j]};
        hit[j] = a[j].geom_id != RTC_INVALID_GEOMETRY_ID && a[j].geom_id < rt->geom_count;
        if (hit[j])
            any = j, t[j] = a[j].t, u[j] = a[j].u, v[j] = a[j].v;
    }
    if (any >= 0)
        exact_hit4(rt, &rh, hit, any, t, u, v);
    for (int j = 0; j < n; j++)
        if (hit[j])
            a[j].t = t[j], a[j].u = u[j], a[j].v = v[j];
    for (int j = 0; j < n; j++)
        found[j] = hit_geometry(rt, 1, rays[j].org, rays[j].dir, rays[j].tnear, INFINITY, &a[j], &hits[j]);
    for (int j = 0; j < n; j++)
        if (found[j])
            hit_surface(rt, 1, &a[j], &hits[j]);
}

int rt_intersect_blend(const eng_rt *rt, const float org[3], const float dir[3], float tnear, float tfar, rt_hit *hit)
{
    return rt->blend_scene ? intersect_in(rt, rt->blend_scene, 0, 0, org, dir, tnear, tfar, hit) : 0;
}

void rt_destroy(eng_rt *rt)
{
    if (!rt)
        return;
    for (uint32_t i = 0; i < rt->geom_count; i++) {
        if (rt->geoms[i].geom)
            rtcReleaseGeometry(rt->geoms[i].geom);
        free(rt->geoms[i].normals);
        free(rt->geoms[i].tangents);
        free(rt->geoms[i].tris);
    }
    free(rt->geoms);
    if (rt->rtscene)
        rtcReleaseScene(rt->rtscene);
    if (rt->blend_scene)
        rtcReleaseScene(rt->blend_scene);
    if (rt->device)
        rtcReleaseDevice(rt->device);
    free(rt);
}

static void raw_result(rt_raw_hit *out, float t, float u, float v, const float ng[3], unsigned geom, unsigned prim)
{
    if (!out)
        return;
    out->t = t;
    out->u = u;
    out->v = v;
    memcpy(out->ng, ng, sizeof out->ng);
    out->geom = geom;
    out->prim = prim;
}

uint64_t rt_cast_raw(const eng_rt *rt, const float *rays, size_t n, int threads, int width, rt_raw_hit *out)
{
    uint64_t hits = 0;
    if (width == 4) {
        /* Packets of 4 consecutive rays (rtcIntersect4, SOA). */
        const ptrdiff_t packets = (ptrdiff_t)((n + 3) / 4);
#pragma omp parallel for schedule(static) num_threads(threads > 0 ? threads : 1) reduction(+ : hits)
        for (ptrdiff_t k = 0; k < packets; k++) {
            struct RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            RTC_ALIGN(16) struct RTCRayHit4 rh;
            memset(&rh, 0, sizeof rh);
            RTC_ALIGN(16) int valid[4];
            for (int j = 0; j < 4; j++) {
                size_t i = 4 * (size_t)k + (size_t)j;
                valid[j] = i < n ? -1 : 0;
                const float *r = rays + RT_RAW_FLOATS * (i < n ? i : n - 1);
                rh.ray.org_x[j] = r[0];
                rh.ray.org_y[j] = r[1];
                rh.ray.org_z[j] = r[2];
                rh.ray.dir_x[j] = r[3];
                rh.ray.dir_y[j] = r[4];
                rh.ray.dir_z[j] = r[5];
                rh.ray.tnear[j] = r[6];
                rh.ray.tfar[j] = INFINITY;
                rh.ray.mask[j] = 0xFFFFFFFFu;
                rh.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
                rh.hit.instID[0][j] = RTC_INVALID_GEOMETRY_ID;
            }
            rtcIntersect4(valid, rt->rtscene, &ctx, &rh);
            for (int j = 0; j < 4; j++) {
                size_t i = 4 * (size_t)k + (size_t)j;
                if (i >= n)
                    break;
                hits += rh.hit.geomID[j] != RTC_INVALID_GEOMETRY_ID;
                const float ng[3] = {rh.hit.Ng_x[j], rh.hit.Ng_y[j], rh.hit.Ng_z[j]};
                raw_result(out ? out + i : NULL, rh.ray.tfar[j], rh.hit.u[j], rh.hit.v[j], ng, rh.hit.geomID[j],
                           rh.hit.primID[j]);
            }
        }
        return hits;
    }
#pragma omp parallel for schedule(static) num_threads(threads > 0 ? threads : 1) reduction(+ : hits)
    for (ptrdiff_t i = 0; i < (ptrdiff_t)n; i++) {
        const float *r = rays + RT_RAW_FLOATS * (size_t)i;
        struct RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        struct RTCRayHit rh;
        ray_init(&rh, r, r + 3, r[6], INFINITY);
        rtcIntersect1(rt->rtscene, &ctx, &rh);
        hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
        const float ng[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
        raw_result(out ? out + i : NULL, rh.ray.tfar, rh.hit.u, rh.hit.v, ng, rh.hit.geomID, rh.hit.primID);
    }
    return hits;
}
