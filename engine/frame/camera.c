/* camera.c — camera rays that see what the rasteriser sees, for the CPU renderers (the
 * reference renderer, translucency). */
#include "frame.h"

#include <math.h>

void frame_camera_ray(const double inv_view_proj[16], const float eye[3], int width, int height, double px, double py,
                    float org[3], float dir[3], float *tnear, float *tfar)
{
    double ndc[2] = {2.0 * px / width - 1.0, 1.0 - 2.0 * py / height};
    double pts[2][3];
    for (int k = 0; k < 2; k++) {
        double v[4] = {ndc[0], ndc[1], k ? 1.0 : -1.0, 1.0}, o[4];
        for (int r = 0; r < 4; r++)
            o[r] = inv_view_proj[r] * v[0] + inv_view_proj[4 + r] * v[1] + inv_view_proj[8 + r] * v[2] +
                   inv_view_proj[12 + r] * v[3];
        for (int i = 0; i < 3; i++)
            pts[k][i] = o[i] / o[3];
    }
    double d[3], dn = 0.0, tn = 0.0, tf = 0.0;
    for (int i = 0; i < 3; i++) {
        d[i] = pts[1][i] - pts[0][i];
        dn += d[i] * d[i];
    }
    dn = sqrt(dn);
    for (int i = 0; i < 3; i++) {
        org[i] = eye[i];
        dir[i] = (float)(d[i] / dn);
        tn += (pts[0][i] - eye[i]) * d[i] / dn;
        tf += (pts[1][i] - eye[i]) * d[i] / dn;
    }
    *tnear = (float)tn;
    *tfar = (float)tf;
}
