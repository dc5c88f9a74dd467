/* normal_map.c — tangent frames and normal textures on the CPU: the loader's
 * generated tangents (scn_generate_tangents) and the shading normal at a CPU hit
 * (scn_normal_at), with the same arithmetic normal_map.glsl does for the G-buffers.
 *
 * glTF 2.0 §3.9.3 (normalTexture): a tangent-space normal map, (x, y, z) = 2·texel − 1, X and
 * Y scaled by normalTexture.scale, n' = normalize(T·x + B·y + N·z); §3.7.2.1 (TANGENT): the
 * bitangent is (N × T)·w. The glTF's texture v runs down the image while its normal maps'
 * +Y is up, so B points toward decreasing v: a generated tangent's w is the sign of
 * (N × T) · (−dP/dv).
 *
 * Generation: Debian packages no MikkTSpace, so this is the per-triangle accumulation of
 * E. Lengyel, "Computing Tangent Space Basis Vectors for an Arbitrary Mesh" (2001): each
 * triangle's dP/du and dP/dv from its edges and UV differences, summed over the triangles a
 * vertex belongs to, then T = dP/du Gram-Schmidt orthogonalised against the vertex normal.
 * MikkTSpace refines exactly this (angle weights, split vertices at UV seams); both agree on
 * meshes whose triangles share their UV orientation. Double arithmetic, one rounding per
 * output. */
#include "scn.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

float *scn_generate_tangents(const scn_primitive *p, int set)
{
    const float *uv = p->texcoords[set];
    if (!uv)
        return NULL;
    size_t nv = p->vertex_count;
    double *su = calloc(nv ? nv * 3 : 1, sizeof *su), *sv = calloc(nv ? nv * 3 : 1, sizeof *sv);
    float *out = malloc((nv ? nv : 1) * 4 * sizeof *out);
    if (!su || !sv || !out) {
        free(su);
        free(sv);
        free(out);
        return NULL;
    }
    for (uint32_t t = 0; t + 2 < p->index_count; t += 3) {
        const uint32_t i0 = p->indices[t], i1 = p->indices[t + 1], i2 = p->indices[t + 2];
        const float *p0 = p->positions + (size_t)i0 * 3, *p1 = p->positions + (size_t)i1 * 3,
                    *p2 = p->positions + (size_t)i2 * 3;
        double du1 = (double)uv[i1 * 2] - uv[i0 * 2], dv1 = (double)uv[i1 * 2 + 1] - uv[i0 * 2 + 1];
        double du2 = (double)uv[i2 * 2] - uv[i0 * 2], dv2 = (double)uv[i2 * 2 + 1] - uv[i0 * 2 + 1];
        double r = du1 * dv2 - du2 * dv1;
        if (!(fabs(r) > 0.0) || !isfinite(r))
            continue; /* degenerate in UV: no direction to give */
        for (int k = 0; k < 3; k++) {
            double e1 = (double)p1[k] - p0[k], e2 = (double)p2[k] - p0[k];
            double dpdu = (e1 * dv2 - e2 * dv1) / r, dpdv = (e2 * du1 - e1 * du2) / r;
            const uint32_t vi[3] = {i0, i1, i2};
            for (int j = 0; j < 3; j++) {
                su[(size_t)vi[j] * 3 + k] += dpdu;
                sv[(size_t)vi[j] * 3 + k] += dpdv;
            }
        }
    }
    for (size_t v = 0; v < nv; v++) {
        const float *nf = p->normals + v * 3;
        double n[3] = {nf[0], nf[1], nf[2]}, *u = su + v * 3, *w = sv + v * 3;
        double d = n[0] * u[0] + n[1] * u[1] + n[2] * u[2];
        double t[3] = {u[0] - d * n[0], u[1] - d * n[1], u[2] - d * n[2]};
        double len = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
        if (!(len > 1e-20) || !isfinite(len)) {
            /* No UV gradient here: any unit vector perpendicular to N. */
            double a[3] = {fabs(n[0]) < 0.9 ? 1.0 : 0.0, fabs(n[0]) < 0.9 ? 0.0 : 1.0, 0.0};
            d = n[0] * a[0] + n[1] * a[1] + n[2] * a[2];
            for (int k = 0; k < 3; k++)
                t[k] = a[k] - d * n[k];
            len = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
        }
        double b[3] = {n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]};
        double h = -(b[0] * w[0] + b[1] * w[1] + b[2] * w[2]);
        for (int k = 0; k < 3; k++)
            out[v * 4 + k] = (float)(t[k] / len) + 0.0f; /* no -0.0: buffer digests */
        out[v * 4 + 3] = h < 0.0 ? -1.0f : 1.0f;
    }
    free(su);
    free(sv);
    return out;
}

int scn_normal_at(const scn_scene *scene, const scn_material *m, const scn_primitive *p, uint32_t tri, float b1,
                  float b2, const float *t0, const float *t1, const float *t2, float n[3])
{
    float tex[4];
    if (!t0 || !scn_texref_at(scene, &m->normal_tex, p, tri, b1, b2, tex))
        return 0;
    const float b0 = 1.0f - b1 - b2;
    float t[3], w = b0 * t0[3] + b1 * t1[3] + b2 * t2[3];
    for (int k = 0; k < 3; k++)
        t[k] = b0 * t0[k] + b1 * t1[k] + b2 * t2[k];
    float d = n[0] * t[0] + n[1] * t[1] + n[2] * t[2];
    for (int k = 0; k < 3; k++)
        t[k] -= d * n[k];
    float len = sqrtf(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    if (!(len > 0.0f) || !isfinite(len))
        return 0; /* tangent parallel to the normal: no frame, the normal stays */
    for (int k = 0; k < 3; k++)
        t[k] /= len;
    const float s = w < 0.0f ? -1.0f : 1.0f;
    const float b[3] = {s * (n[1] * t[2] - n[2] * t[1]), s * (n[2] * t[0] - n[0] * t[2]),
                        s * (n[0] * t[1] - n[1] * t[0])};
    const float x = (2.0f * tex[0] - 1.0f) * m->normal_scale, y = (2.0f * tex[1] - 1.0f) * m->normal_scale,
                z = 2.0f * tex[2] - 1.0f;
    float r[3];
    for (int k = 0; k < 3; k++)
        r[k] = t[k] * x + b[k] * y + n[k] * z;
    len = sqrtf(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (!(len > 0.0f) || !isfinite(len))
        return 0;
    for (int k = 0; k < 3; k++)
        n[k] = r[k] / len;
    return 1;
}
