/* deform.c — skinned and morphed meshes on the CPU: scn_deform.
 *
 * glTF 2.0 §3.7.2.2 (morph targets): the morphed attribute is the base plus the weighted sum
 * of the targets' deltas, pos = base + Σ_i w_i · Δpos_i, the same for normals.
 * glTF 2.0 §3.7.3 (skins): the joint matrix of joint j is world(joint_j) · inverseBind_j; a
 * vertex is moved by the skin matrix Σ_k WEIGHTS_n[k] · joint matrix(JOINTS_n[k]) over the
 * sets it has (JOINTS_0/WEIGHTS_0, and _1 for 8 influences), which maps the (morphed) bind-pose position straight to world space: the skinned node's own transform
 * is ignored, as the specification says. Normals are moved by the inverse transpose of the
 * skin matrix's upper 3×3 (its cofactor matrix with the sign of its determinant) and
 * renormalised; tangents (normal maps) by the upper 3×3 itself, renormalised, their
 * handedness w kept. Morphing comes first, then skinning (the spec's order).
 *
 * A primitive whose normals the loader computed flat gets its face normals recomputed from
 * the deformed positions (as flat_normals in gltf_load.c does), so they follow the surface.
 *
 * Everything is in double and rounded to float once per output component; each vertex is
 * independent of every other, so the result does not depend on any thread count (the
 * caller runs it on one thread anyway). */
#include "scn.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* out = a · b for column-major 4×4 matrices, a in float, b in float, out in double. */
static void mul_ff(const float *a, const float *b, double out[16])
{
    for (int c = 0; c < 4; c++)
        for (int r = 0; r < 4; r++) {
            double acc = 0.0;
            for (int k = 0; k < 4; k++)
                acc += (double)a[k * 4 + r] * (double)b[c * 4 + k];
            out[c * 4 + r] = acc;
        }
}

static void normalise_into(const double v[3], const float *fallback, float *out)
{
    double len = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(len > 0.0) || !isfinite(len)) {
        memcpy(out, fallback, 3 * sizeof *out);
        return;
    }
    for (int k = 0; k < 3; k++)
        out[k] = (float)(v[k] / len) + 0.0f; /* no -0.0: buffer digests */
}

int scn_deform(const scn_scene *scene, uint32_t node, uint32_t prim, const float *world, const float *weights,
               float *positions, float *normals)
{
    return scn_deform_tangents(scene, node, prim, world, weights, positions, normals, NULL);
}

/* Tangents are surface directions: they move with the skin matrix's upper 3×3 itself (not its
 * inverse transpose), after their morph deltas; w (handedness) is kept. */
int scn_deform_tangents(const scn_scene *scene, uint32_t node, uint32_t prim, const float *world,
                        const float *weights, float *positions, float *normals, float *tangents)
{
    const scn_node *n = &scene->nodes[node];
    const scn_primitive *p = &scene->primitives[prim];
    const uint32_t nv = p->vertex_count;
    const float *w = weights + n->weight_first;
    const uint32_t nt = n->mesh >= 0 ? scene->meshes[n->mesh].weight_count : 0;
    const int skinned = n->skin >= 0 && p->joints && p->weights;
    const scn_skin *sk = skinned ? &scene->skins[n->skin] : NULL;
    double *joint = NULL;
    if (skinned) {
        joint = malloc((size_t)sk->joint_count * 16 * sizeof *joint);
        if (!joint)
            abort(); /* a few KB; the engine's allocator also ends the process */
        for (uint32_t j = 0; j < sk->joint_count; j++)
            mul_ff(world + (size_t)sk->joints[j] * 16, sk->inverse_bind + (size_t)j * 16, joint + (size_t)j * 16);
    }
    if (!p->tangents)
        tangents = NULL;
    for (uint32_t v = 0; v < nv; v++) {
        double pos[3], nrm[3], tan[3] = {0, 0, 0};
        for (int c = 0; c < 3; c++) {
            pos[c] = p->positions[(size_t)v * 3 + c];
            nrm[c] = p->normals[(size_t)v * 3 + c];
            if (tangents)
                tan[c] = p->tangents[(size_t)v * 4 + c];
        }
        for (uint32_t t = 0; t < nt && t < p->target_count; t++) {
            if (w[t] == 0.0f)
                continue;
            size_t at = ((size_t)t * nv + v) * 3;
            for (int c = 0; c < 3; c++) {
                if (p->target_positions)
                    pos[c] += (double)w[t] * p->target_positions[at + c];
                if (p->target_normals)
                    nrm[c] += (double)w[t] * p->target_normals[at + c];
                if (tangents && p->target_tangents)
                    tan[c] += (double)w[t] * p->target_tangents[at + c];
            }
        }
        if (skinned) {
            double s[16] = {0};
            const size_t inf = p->influences ? p->influences : 4; /* JOINTS_0, and _1 when 8 */
            for (size_t k = 0; k < inf; k++) {
                double wk = p->weights[(size_t)v * inf + k];
                if (wk == 0.0)
                    continue;
                const double *j = joint + (size_t)p->joints[(size_t)v * inf + k] * 16;
                for (int e = 0; e < 16; e++)
                    s[e] += wk * j[e];
            }
            double q[3], m[3];
            for (int r = 0; r < 3; r++)
                q[r] = s[r] * pos[0] + s[4 + r] * pos[1] + s[8 + r] * pos[2] + s[12 + r];
            /* Cofactors of the upper 3×3 (a = s as rows r, columns c: a[r][c] = s[c*4+r]). */
#define A(r, c) s[(c) * 4 + (r)]
            double cof[3][3];
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 3; c++) {
                    int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
                    cof[r][c] = A(r1, c1) * A(r2, c2) - A(r1, c2) * A(r2, c1);
                }
            double det = A(0, 0) * cof[0][0] + A(0, 1) * cof[0][1] + A(0, 2) * cof[0][2];
#undef A
            double sign = det < 0.0 ? -1.0 : 1.0;
            /* inverse transpose = cof / det: the normal is cof · n, up to a positive scale. */
            for (int r = 0; r < 3; r++)
                m[r] = sign * (cof[r][0] * nrm[0] + cof[r][1] * nrm[1] + cof[r][2] * nrm[2]);
            double tq[3];
            for (int r = 0; r < 3; r++)
                tq[r] = s[r] * tan[0] + s[4 + r] * tan[1] + s[8 + r] * tan[2];
            memcpy(pos, q, sizeof pos);
            memcpy(nrm, m, sizeof nrm);
            memcpy(tan, tq, sizeof tan);
        }
        for (int c = 0; c < 3; c++)
            positions[(size_t)v * 3 + c] = (float)pos[c];
        normalise_into(nrm, p->normals + (size_t)v * 3, normals + (size_t)v * 3);
        if (tangents) {
            normalise_into(tan, p->tangents + (size_t)v * 4, tangents + (size_t)v * 4);
            tangents[(size_t)v * 4 + 3] = p->tangents[(size_t)v * 4 + 3];
        }
    }
    free(joint);
    if (p->flat)
        for (uint32_t t = 0; t + 2 < p->index_count; t += 3) {
            const float *a = positions + (size_t)p->indices[t] * 3, *b = positions + (size_t)p->indices[t + 1] * 3,
                        *c = positions + (size_t)p->indices[t + 2] * 3;
            double e1[3], e2[3], x[3];
            for (int k = 0; k < 3; k++) {
                e1[k] = (double)b[k] - a[k];
                e2[k] = (double)c[k] - a[k];
            }
            x[0] = e1[1] * e2[2] - e1[2] * e2[1];
            x[1] = e1[2] * e2[0] - e1[0] * e2[2];
            x[2] = e1[0] * e2[1] - e1[1] * e2[0];
            static const float up[3] = {0.0f, 1.0f, 0.0f};
            float f[3];
            normalise_into(x, up, f);
            for (int k = 0; k < 3; k++)
                memcpy(normals + (size_t)p->indices[t + k] * 3, f, sizeof f);
        }
    return skinned;
}
