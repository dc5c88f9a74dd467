/* framing.c — seq_frame_scene: a look-at camera that frames the scene's bounds, for
 * sequences without a camera or with {"frame": "scene"}. */
#include "seq.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void seq_frame_scene(const seq_sequence *q, const scn_scene *s, seq_camera_key *key, float *znear, float *zfar)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    float *world = malloc((s->node_count ? s->node_count : 1) * 16 * sizeof *world);
    if (world)
        scn_evaluate(s, 0.0, world);
    for (int pass = 0; pass < 2 && world; pass++) {
        /* pass 0: the box; pass 1: the sphere around its centre (radius in hi[0] - lo[0]). */
        double c[3], r2 = 0.0;
        for (int k = 0; k < 3; k++)
            c[k] = 0.5 * (lo[k] + hi[k]);
        for (uint32_t i = 0; i < s->node_count; i++) {
            const scn_node *n = &s->nodes[i];
            if (n->mesh < 0)
                continue;
            const float *w = world + 16 * (size_t)i;
            const scn_mesh *m = &s->meshes[n->mesh];
            for (uint32_t p = 0; p < m->primitive_count; p++) {
                const scn_primitive *pr = &s->primitives[m->first_primitive + p];
                for (uint32_t v = 0; v < pr->vertex_count; v++) {
                    const float *x = pr->positions + 3 * (size_t)v;
                    double y[3];
                    for (int k = 0; k < 3; k++)
                        y[k] = (double)w[k] * x[0] + (double)w[4 + k] * x[1] + (double)w[8 + k] * x[2] + w[12 + k];
                    if (pass == 0) {
                        for (int k = 0; k < 3; k++)
                            lo[k] = fmin(lo[k], y[k]), hi[k] = fmax(hi[k], y[k]);
                    } else {
                        double d2 = 0.0;
                        for (int k = 0; k < 3; k++)
                            d2 += (y[k] - c[k]) * (y[k] - c[k]);
                        r2 = fmax(r2, d2);
                    }
                }
            }
        }
        if (pass == 1) {
            memcpy(lo, c, sizeof c);
            hi[0] = sqrt(r2);
        }
    }
    free(world);
    double c[3] = {0, 0, 0}, r = 1.0;
    if (world && isfinite(lo[0]) && isfinite(lo[1]) && isfinite(lo[2]) && isfinite(hi[0])) {
        memcpy(c, lo, sizeof c);
        r = hi[0];
    }
    double scale = fmax(fabs(c[0]), fmax(fabs(c[1]), fabs(c[2])));
    if (!(r > 1e-6 * scale) || !(r > 1e-30))
        r = fmax(1e-3 * scale, 1.0e-3); /* a point or a flat speck: a little room around it */
    /* The sphere fits the narrower of the vertical and horizontal fields of view. */
    double half_v = 0.5 * q->camera_yfov;
    double half_h = atan(tan(half_v) * (double)q->width / (double)q->height);
    double dist = r / sin(fmin(half_v, half_h));
    key->time = 0.0;
    for (int k = 0; k < 3; k++) {
        key->target[k] = (float)c[k];
        key->position[k] = (float)(c[k] - dist * q->camera_direction[k]);
    }
    *znear = (float)fmax(0.5 * (dist - r), 1e-4 * dist);
    *zfar = (float)(2.0 * (dist + r));
}
