/* furnace_test_util.h — the furnace scene's closed form (scenes/furnace: a closed sphere of
 * albedo ρ = 0.8 with a point light of intensity 1 W/sr at its centre, the camera there too),
 * shared by test_reference.c and test_finalgather.c: the area mean of the indirect radiance of
 * any closed enclosure is ρ²Φ/((1−ρ)πA). Test-only, static functions. */
#ifndef ISPM_FURNACE_TEST_UTIL_H
#define ISPM_FURNACE_TEST_UTIL_H

#include "eng.h"

#include <math.h>

#define FURNACE_RHO 0.8
#define FURNACE_INTENSITY 1.0

/* A: the area of the tessellated sphere (every draw at identity). */
static double furnace_area(const scn_scene *scene)
{
    double area = 0.0;
    for (uint32_t k = 0; k < scene->primitive_count; k++) {
        const scn_primitive *p = &scene->primitives[k];
        for (uint32_t t = 0; t < p->index_count; t += 3) {
            const float *a = p->positions + 3 * p->indices[t], *b = p->positions + 3 * p->indices[t + 1],
                        *c = p->positions + 3 * p->indices[t + 2];
            double u[3], v[3];
            for (int i = 0; i < 3; i++) {
                u[i] = (double)b[i] - a[i];
                v[i] = (double)c[i] - a[i];
            }
            double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
            area += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        }
    }
    return area;
}

/* The energy balance ρ²Φ/((1−ρ)πA), Φ = 4πI. */
static double furnace_indirect_mean(double area)
{
    const double phi = 4.0 * ENG_PI * FURNACE_INTENSITY;
    return FURNACE_RHO * FURNACE_RHO * phi / ((1.0 - FURNACE_RHO) * ENG_PI * area);
}

#endif
