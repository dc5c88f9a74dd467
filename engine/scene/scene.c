/* scene.c — a loaded scene at time t: animation sampling and world matrices.
 *
 * Sampling follows glTF 2.0 §3.11 and Appendix C: STEP holds the key's value; LINEAR
 * interpolates, with spherical linear interpolation along the shorter arc for rotations;
 * CUBICSPLINE is the Hermite spline whose tangents are scaled by the key interval. Outside
 * the keys a channel holds its first or last value (no looping, no extrapolation). Rotation
 * results are renormalised, whatever the interpolation.
 *
 * World matrices are T·R·S (or the node's matrix) times the parent's world matrix, in one
 * forward pass: the loader sorted nodes so parents come first. Arithmetic is in double and
 * rounded to float once per stored matrix, so a chain of nodes accumulates one rounding per
 * level and the result does not depend on the compiler's choice of float evaluation.
 * Nothing here allocates or owns memory. */
#include "scn.h"

#include <assert.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static void normalise_quat(const double q[4], float out[4])
{
    double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    if (!(len > 0.0) || !isfinite(len)) {
        out[0] = out[1] = out[2] = 0.0f;
        out[3] = 1.0f;
        return;
    }
    for (int k = 0; k < 4; k++)
        out[k] = (float)(q[k] / len);
}

/* Slerp from a to b by u in [0, 1], along the shorter arc. Unnormalised inputs are fine:
 * both are normalised first. */
static void slerp(const float *af, const float *bf, double u, double out[4])
{
    double a[4], b[4], la = 0.0, lb = 0.0, dot = 0.0;
    for (int k = 0; k < 4; k++) {
        a[k] = af[k];
        b[k] = bf[k];
        la += a[k] * a[k];
        lb += b[k] * b[k];
    }
    la = sqrt(la);
    lb = sqrt(lb);
    if (!(la > 0.0) || !(lb > 0.0)) { /* degenerate keys: fall back to a plain lerp */
        for (int k = 0; k < 4; k++)
            out[k] = a[k] + (b[k] - a[k]) * u;
        return;
    }
    for (int k = 0; k < 4; k++) {
        a[k] /= la;
        b[k] /= lb;
        dot += a[k] * b[k];
    }
    if (dot < 0.0) {
        dot = -dot;
        for (int k = 0; k < 4; k++)
            b[k] = -b[k];
    }
    double wa, wb;
    if (dot > 0.9995) {
        /* Nearly parallel: sin(theta) is too small to divide by; lerp is exact enough. */
        wa = 1.0 - u;
        wb = u;
    } else {
        double theta = acos(dot), st = sin(theta);
        wa = sin((1.0 - u) * theta) / st;
        wb = sin(u * theta) / st;
    }
    for (int k = 0; k < 4; k++)
        out[k] = wa * a[k] + wb * b[k];
}

void scn_sample_channel(const scn_channel *ch, double t, float *out)
{
    assert(ch->key_count >= 1);
    const uint32_t comps = ch->path == SCN_PATH_ROTATION ? 4 : ch->path == SCN_PATH_WEIGHTS ? ch->comps : 3;
    const uint32_t n = ch->key_count;
    const int cubic = ch->interp == SCN_INTERP_CUBICSPLINE;
    const int rotation = ch->path == SCN_PATH_ROTATION;
    /* Value of key k: for CUBICSPLINE each key stores (in-tangent, value, out-tangent). */
#define VALUE(k) (ch->values + ((size_t)(k) * (cubic ? 3 : 1) + (cubic ? 1 : 0)) * comps)
    double r[4] = {0.0, 0.0, 0.0, 0.0};
    const float *hold = NULL;

    if (!(t > (double)ch->times[0]) || n == 1) {
        hold = VALUE(0); /* also catches a NaN t */
    } else if (t >= (double)ch->times[n - 1]) {
        hold = VALUE(n - 1);
    }
    if (hold) {
        if (!rotation) {
            memcpy(out, hold, comps * sizeof *out);
            return;
        }
        for (uint32_t c = 0; c < comps; c++)
            r[c] = hold[c];
    } else {
        /* Largest k with times[k] <= t; here times[0] < t < times[n-1]. */
        uint32_t lo = 0, hi = n - 1;
        while (hi - lo > 1) {
            uint32_t mid = lo + (hi - lo) / 2;
            if ((double)ch->times[mid] <= t)
                lo = mid;
            else
                hi = mid;
        }
        const double t0 = ch->times[lo], t1 = ch->times[lo + 1];
        const double dt = t1 - t0;
        const double u = (t - t0) / dt;
        const float *v0 = VALUE(lo), *v1 = VALUE(lo + 1);
        if (rotation && ch->interp == SCN_INTERP_LINEAR) {
            slerp(v0, v1, u, r);
        } else {
            /* Component by component (any count: morph weights), each rounded once. */
            const double u2 = u * u, u3 = u2 * u;
            const double h00 = 2.0 * u3 - 3.0 * u2 + 1.0, h10 = u3 - 2.0 * u2 + u;
            const double h01 = -2.0 * u3 + 3.0 * u2, h11 = u3 - u2;
            const float *out0 = v0 + comps; /* CUBICSPLINE: out-tangent of key lo */
            const float *in1 = v1 - comps;  /* in-tangent of key lo+1 */
            for (uint32_t c = 0; c < comps; c++) {
                double x;
                switch (ch->interp) {
                case SCN_INTERP_STEP: x = v0[c]; break;
                case SCN_INTERP_LINEAR: x = (double)v0[c] + ((double)v1[c] - (double)v0[c]) * u; break;
                default: x = h00 * v0[c] + h10 * dt * out0[c] + h01 * v1[c] + h11 * dt * in1[c]; break;
                }
                if (rotation)
                    r[c] = x;
                else
                    out[c] = (float)x;
            }
            if (!rotation)
                return;
        }
    }
#undef VALUE
    normalise_quat(r, out);
}

/* local = T·R·S, column-major. */
static void trs_matrix(const float t[3], const float q[4], const float s[3], double m[16])
{
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const double r[3][3] = {
        {1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)},
        {2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)},
        {2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)},
    };
    for (int c = 0; c < 3; c++) {
        for (int row = 0; row < 3; row++)
            m[c * 4 + row] = r[row][c] * (double)s[c];
        m[c * 4 + 3] = 0.0;
    }
    m[12] = t[0];
    m[13] = t[1];
    m[14] = t[2];
    m[15] = 1.0;
}

void scn_evaluate(const scn_scene *scene, double t, float *world)
{
    /* world doubles as scratch: slot i first holds node i's animated T (0..2), R (3..6) and
     * S (7..9), then its world matrix. A parent's slot is final before its children read it
     * because parents come first. */
    for (uint32_t i = 0; i < scene->node_count; i++) {
        const scn_node *n = &scene->nodes[i];
        float *slot = world + (size_t)i * 16;
        memcpy(slot, n->translation, 3 * sizeof(float));
        memcpy(slot + 3, n->rotation, 4 * sizeof(float));
        memcpy(slot + 7, n->scale, 3 * sizeof(float));
    }
    for (uint32_t a = 0; a < scene->animation_count; a++) {
        const scn_animation *an = &scene->animations[a];
        for (uint32_t c = 0; c < an->channel_count; c++) {
            const scn_channel *ch = &an->channels[c];
            assert(ch->node >= 0 && (uint32_t)ch->node < scene->node_count);
            float *slot = world + (size_t)ch->node * 16;
            switch (ch->path) {
            case SCN_PATH_TRANSLATION: scn_sample_channel(ch, t, slot); break;
            case SCN_PATH_ROTATION: scn_sample_channel(ch, t, slot + 3); break;
            case SCN_PATH_SCALE: scn_sample_channel(ch, t, slot + 7); break;
            case SCN_PATH_WEIGHTS: break; /* scn_evaluate_weights */
            }
        }
    }
    for (uint32_t i = 0; i < scene->node_count; i++) {
        const scn_node *n = &scene->nodes[i];
        float *slot = world + (size_t)i * 16;
        double local[16];
        if (n->has_matrix) {
            for (int k = 0; k < 16; k++)
                local[k] = n->matrix[k];
        } else {
            float tr[3], q[4], s[3];
            memcpy(tr, slot, sizeof tr);
            memcpy(q, slot + 3, sizeof q);
            memcpy(s, slot + 7, sizeof s);
            trs_matrix(tr, q, s, local);
        }
        if (n->parent < 0) {
            for (int k = 0; k < 16; k++)
                slot[k] = (float)local[k];
            continue;
        }
        assert((uint32_t)n->parent < i);
        const float *p = world + (size_t)n->parent * 16;
        for (int c = 0; c < 4; c++)
            for (int r = 0; r < 4; r++) {
                double acc = 0.0;
                for (int k = 0; k < 4; k++)
                    acc += (double)p[k * 4 + r] * local[c * 4 + k];
                slot[c * 4 + r] = (float)acc;
            }
    }
}

void scn_evaluate_weights(const scn_scene *scene, double t, float *weights)
{
    if (scene->weight_count)
        memcpy(weights, scene->weights, scene->weight_count * sizeof *weights);
    for (uint32_t a = 0; a < scene->animation_count; a++) {
        const scn_animation *an = &scene->animations[a];
        for (uint32_t c = 0; c < an->channel_count; c++) {
            const scn_channel *ch = &an->channels[c];
            if (ch->path != SCN_PATH_WEIGHTS)
                continue;
            const scn_node *n = &scene->nodes[ch->node];
            assert(n->mesh >= 0 && scene->meshes[n->mesh].weight_count == ch->comps);
            scn_sample_channel(ch, t, weights + n->weight_first);
        }
    }
}

int scn_node_deforms(const scn_scene *scene, uint32_t node)
{
    const scn_node *n = &scene->nodes[node];
    return n->mesh >= 0 && (n->skin >= 0 || scene->meshes[n->mesh].weight_count > 0);
}

int32_t scn_find_node(const scn_scene *scene, const char *name)
{
    if (!scene || !name)
        return -1;
    for (uint32_t i = 0; i < scene->node_count; i++)
        if (strcmp(scene->nodes[i].name, name) == 0)
            return (int32_t)i;
    return -1;
}

/* ---------------------------------------------------------------- textures */

/* scn_texture_sample: texture_mip.c, beside the mip levels. */

/* scn_texref_at: texture_mip.c (scn_texref_at_cone without a footprint). */

void scn_base_color_at(const scn_scene *scene, const scn_material *m, const scn_primitive *p, uint32_t tri,
                       float b1, float b2, float out[4])
{
    scn_texref_at(scene, &m->base_color_tex, p, tri, b1, b2, out);
    const uint32_t *i = p->indices + 3 * (size_t)tri;
    double w[3] = {1.0 - (double)b1 - (double)b2, b1, b2};
    if (p->colors)
        for (int c = 0; c < 4; c++) {
            double acc = 0.0;
            for (int k = 0; k < 3; k++)
                acc += w[k] * p->colors[(size_t)i[k] * 4 + c];
            out[c] *= (float)acc;
        }
}

void scn_warn(scn_scene *s, const char *fmt, ...)
{
    if (s->warning_count < SCN_MAX_WARNINGS) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(s->warnings[s->warning_count], SCN_WARNING_MAX, fmt, ap);
        va_end(ap);
    }
    s->warning_count++;
}
