/* kernel.c — the photon kernel on the CPU: the radius of a photon's volume from its path
 * density (ISPM §2.5, §4.3) and κ of §5.1 Eq. 2-3, as shaders/splat.frag.glsl evaluates it. */
#include "kernel.h"

#include <math.h>

float splat_radius(float kernel_radius, float rho)
{
    float s = rho > 0.0f ? powf(1000.0f * rho, -0.25f) : 2.0f;
    if (s < 0.25f)
        s = 0.25f;
    if (s > 2.0f)
        s = 2.0f;
    return kernel_radius * s;
}

float splat_kernel(const float d[3], const float n_p[3], float r_xy, float r_z)
{
    double len = sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]);
    double t = 0.0;
    if (len > 0.0) {
        double c = fabs((double)d[0] * n_p[0] + (double)d[1] * n_p[1] + (double)d[2] * n_p[2]) / len;
        t = len / r_xy * (1.0 + c * (r_xy - r_z) / r_z);
    }
    if (t >= 1.0)
        return 0.0f;
    return (float)(2.0 / (ENG_PI * (double)r_xy * r_xy) * (1.0 - t * t));
}
