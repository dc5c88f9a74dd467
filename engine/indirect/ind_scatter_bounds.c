/* ind_scatter_bounds.c — where a photon volume can reach the eye G-buffer (ISPM 003_… §5, §5.1), on
 * the CPU, for ind_scatter_splat.c: which photons to draw and the screen rectangle each is drawn as.
 *
 * The kernel of Eq. 2–3 is nonzero only where t < 1, a region inside the ellipsoid of
 * semi-axes (r_xy, r_xy, r_z) about the photon (r_z ≤ r_xy; with t = |d|/r_xy + |d·n_p|
 * (1/r_z − 1/r_xy), the ellipsoid's value on t = 1 is 1 − 2(k−1)h(1−kh) ≤ 1, k = r_xy/r_z,
 * h = |d·n_p|/r_xy), and so inside the slab |d·n_p| < r_z and the sphere |d| < r_xy. A pixel
 * gets a photon exactly when its G-buffer point s lies in that region, so a rectangle that
 * holds every pixel centre whose ray meets the ellipsoid loses nothing:
 *
 *  - the ellipsoid's exact screen bounding box: its silhouette planes through the eye are the
 *    roots of one quadratic per axis (the plane x = X·w tangent to the ellipsoid), computed in
 *    double with the axes inflated by 1e-3 (float G-buffer points and the shader's float t
 *    lie within ~1e-6 relative of the true surface); the whole screen when the ellipsoid
 *    comes within ~0 of the eye plane (w ≤ 0 somewhere: no finite box; the rectangle is
 *    drawn at w = 1 and never clipped, so the near plane cuts nothing away, 003 §6.3);
 *  - then trimmed to the 8×8-pixel tiles (found through 32×32 ones) whose G-buffer points'
 *    bounding box reaches the sphere and the slab: a tile whose every point is farther than r_xy from the photon, or
 *    farther than r_z from its surface plane, has no pixel the photon reaches (occluded or
 *    off-surface photons draw nothing at all).
 *
 * The far depth of the ellipsoid (largest w, inflated) is returned as an NDC depth so that
 * the rasteriser's early depth test (GEQUAL against the G-buffer depth) still drops pixels
 * whose surface lies behind the whole volume, as the icosahedron's back faces did.
 * Owns nothing but the tile boxes. */
#include "indirect.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

void splat_tiles_build(splat_tiles *t, const float *position, int width, int height)
{
    int tx = (width + SPLAT_TILE - 1) / SPLAT_TILE, ty = (height + SPLAT_TILE - 1) / SPLAT_TILE;
    int cx = (tx + SPLAT_COARSE - 1) / SPLAT_COARSE, cy = (ty + SPLAT_COARSE - 1) / SPLAT_COARSE;
    if (t->tiles_x != tx || t->tiles_y != ty || !t->box) {
        free(t->box);
        free(t->coarse);
        t->box = malloc((size_t)tx * (size_t)ty * 6 * sizeof(float));
        t->coarse = malloc((size_t)cx * (size_t)cy * 6 * sizeof(float));
        if (!t->box || !t->coarse) {
            fprintf(stderr, "ispm: out of memory\n");
            abort();
        }
    }
    t->width = width;
    t->height = height;
    t->tiles_x = tx;
    t->tiles_y = ty;
    t->coarse_x = cx;
    t->coarse_y = cy;
    for (int j = 0; j < ty; j++)
        for (int i = 0; i < tx; i++) {
            float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
            int y1 = (j + 1) * SPLAT_TILE < height ? (j + 1) * SPLAT_TILE : height;
            int x1 = (i + 1) * SPLAT_TILE < width ? (i + 1) * SPLAT_TILE : width;
            for (int y = j * SPLAT_TILE; y < y1; y++)
                for (int x = i * SPLAT_TILE; x < x1; x++) {
                    const float *p = position + 4 * ((size_t)y * (size_t)width + (size_t)x);
                    if (p[3] == 0.0f) /* background: the shader discards it */
                        continue;
                    for (int c = 0; c < 3; c++) {
                        lo[c] = fminf(lo[c], p[c]);
                        hi[c] = fmaxf(hi[c], p[c]);
                    }
                }
            float *b = t->box + 6 * ((size_t)j * (size_t)tx + (size_t)i);
            for (int c = 0; c < 3; c++) {
                b[c] = lo[c];
                b[3 + c] = hi[c];
            }
        }
    for (int j = 0; j < cy; j++)
        for (int i = 0; i < cx; i++) {
            float *cb = t->coarse + 6 * ((size_t)j * (size_t)cx + (size_t)i);
            for (int c = 0; c < 3; c++) {
                cb[c] = INFINITY;
                cb[3 + c] = -INFINITY;
            }
            for (int y = j * SPLAT_COARSE; y < (j + 1) * SPLAT_COARSE && y < ty; y++)
                for (int x = i * SPLAT_COARSE; x < (i + 1) * SPLAT_COARSE && x < tx; x++) {
                    const float *b = t->box + 6 * ((size_t)y * (size_t)tx + (size_t)x);
                    for (int c = 0; c < 3; c++) {
                        cb[c] = fminf(cb[c], b[c]);
                        cb[3 + c] = fmaxf(cb[3 + c], b[3 + c]);
                    }
                }
        }
}

void splat_tiles_free(splat_tiles *t)
{
    if (t) {
        free(t->box);
        free(t->coarse);
        t->box = t->coarse = NULL;
    }
}

/* Whether a box (min xyz, max xyz) can hold a point within sqrt(r2) of x and within slab of
 * the plane through x normal to the unit n. */
static int box_reaches(const float *b, const float x[3], const double n[3], double r2, double slab)
{
    if (b[0] > b[3]) /* no surface */
        return 0;
    double d2 = 0.0, mid = 0.0, ext = 0.0;
    for (int c = 0; c < 3; c++) {
        double lo = (double)b[c] - x[c], hi = (double)b[3 + c] - x[c];
        double d = lo > 0.0 ? lo : hi < 0.0 ? -hi : 0.0;
        d2 += d * d;
        mid += 0.5 * (lo + hi) * n[c];
        ext += 0.5 * (hi - lo) * fabs(n[c]);
    }
    return d2 <= r2 && mid - ext <= slab && mid + ext >= -slab;
}

/* Row r of a column-major 4×4 matrix applied to the direction e (w = 0) and the point x. */
static double row_dir(const float m[16], int r, const double e[3])
{
    return m[r] * e[0] + m[4 + r] * e[1] + m[8 + r] * e[2];
}
static double row_point(const float m[16], int r, const float x[3])
{
    return (double)m[r] * x[0] + (double)m[4 + r] * x[1] + (double)m[8 + r] * x[2] + m[12 + r];
}

/* The range of X = row_r / row_w over the ellipsoid x + E u (|u| ≤ 1), given w > 0 on it: the
 * X at which the plane row_r − X row_w touches the ellipsoid, (C_r − X C_w)² = |a_r − X a_w|². */
static void ratio_range(double cr, const double ar[3], double cw, const double aw[3], double *lo, double *hi)
{
    double aa = cw * cw - (aw[0] * aw[0] + aw[1] * aw[1] + aw[2] * aw[2]);
    double bb = cr * cw - (ar[0] * aw[0] + ar[1] * aw[1] + ar[2] * aw[2]);
    double cc = cr * cr - (ar[0] * ar[0] + ar[1] * ar[1] + ar[2] * ar[2]);
    double disc = bb * bb - aa * cc;
    double sq = disc > 0.0 ? sqrt(disc) : 0.0;
    *lo = (bb - sq) / aa;
    *hi = (bb + sq) / aa;
}

int splat_photon_bounds(const float view_proj[16], const float proj[16], const splat_tiles *t, const float x[3],
                        const float n[3], float r_xy, float r_z, splat_bounds *out)
{
    const double grow = 1.0 + 1e-3;
    const int w = t->width, h = t->height;
    /* The ellipsoid's axes (any tangent frame: it is symmetric about n). */
    double nn[3] = {n[0], n[1], n[2]};
    double nl = sqrt(nn[0] * nn[0] + nn[1] * nn[1] + nn[2] * nn[2]);
    double e[3][3];
    double rxy = r_xy, rz = r_z;
    if (!(nl > 0.0) || rz > rxy) { /* a sphere (not reached with normal_compression ≤ 1) */
        double r = rxy > rz ? rxy : rz;
        rxy = rz = r;
        nn[0] = 0.0, nn[1] = 0.0, nn[2] = 1.0;
    } else
        for (int c = 0; c < 3; c++)
            nn[c] /= nl;
    double a[3] = {fabs(nn[0]) > 0.9 ? 0.0 : 1.0, fabs(nn[0]) > 0.9 ? 1.0 : 0.0, 0.0};
    double tt[3] = {a[1] * nn[2] - a[2] * nn[1], a[2] * nn[0] - a[0] * nn[2], a[0] * nn[1] - a[1] * nn[0]};
    double tl = sqrt(tt[0] * tt[0] + tt[1] * tt[1] + tt[2] * tt[2]);
    for (int c = 0; c < 3; c++)
        tt[c] /= tl;
    double bb[3] = {nn[1] * tt[2] - nn[2] * tt[1], nn[2] * tt[0] - nn[0] * tt[2], nn[0] * tt[1] - nn[1] * tt[0]};
    for (int c = 0; c < 3; c++) {
        e[0][c] = tt[c] * rxy * grow;
        e[1][c] = bb[c] * rxy * grow;
        e[2][c] = nn[c] * rz * grow;
    }
    /* Clip rows x (0), y (1), w (3) as C + A u. */
    double cx = row_point(view_proj, 0, x), cy = row_point(view_proj, 1, x), cw = row_point(view_proj, 3, x);
    double ax[3], ay[3], aw[3];
    for (int k = 0; k < 3; k++) {
        ax[k] = row_dir(view_proj, 0, e[k]);
        ay[k] = row_dir(view_proj, 1, e[k]);
        aw[k] = row_dir(view_proj, 3, e[k]);
    }
    double awl = sqrt(aw[0] * aw[0] + aw[1] * aw[1] + aw[2] * aw[2]);
    double w_max = cw + awl, w_min = cw - awl;
    if (!(w_max > 0.0)) /* wholly behind the eye */
        return 0;
    int x0 = 0, x1 = w - 1, y0 = 0, y1 = h - 1;
    if (w_min > 1e-5 * w_max) {
        double lo, hi;
        ratio_range(cx, ax, cw, aw, &lo, &hi);
        /* Pixel i is drawn when its centre i + 0.5 lies in [(lo+1)/2·w, (hi+1)/2·w]. */
        double fx0 = ceil((lo + 1.0) * 0.5 * w - 0.5 - 1e-3), fx1 = floor((hi + 1.0) * 0.5 * w - 0.5 + 1e-3);
        ratio_range(cy, ay, cw, aw, &lo, &hi);
        double fy0 = ceil((lo + 1.0) * 0.5 * h - 0.5 - 1e-3), fy1 = floor((hi + 1.0) * 0.5 * h - 0.5 + 1e-3);
        if (fx1 < 0.0 || fy1 < 0.0 || fx0 > w - 1 || fy0 > h - 1 || fx0 > fx1 || fy0 > fy1)
            return 0;
        x0 = fx0 < 0.0 ? 0 : (int)fx0;
        y0 = fy0 < 0.0 ? 0 : (int)fy0;
        x1 = fx1 > w - 1 ? w - 1 : (int)fx1;
        y1 = fy1 > h - 1 ? h - 1 : (int)fy1;
    }
    /* Trim to the tiles whose points can lie in the kernel's sphere and slab. */
    const double r2 = (rxy * grow) * (rxy * grow), slab = rz * grow;
    int bx0 = w, bx1 = -1, by0 = h, by1 = -1;
    const int tx0 = x0 / SPLAT_TILE, tx1 = x1 / SPLAT_TILE, ty0 = y0 / SPLAT_TILE, ty1 = y1 / SPLAT_TILE;
    const int cs = SPLAT_COARSE;
    for (int cj = ty0 / cs; cj <= ty1 / cs; cj++)
        for (int ci = tx0 / cs; ci <= tx1 / cs; ci++) {
            if (!box_reaches(t->coarse + 6 * ((size_t)cj * (size_t)t->coarse_x + (size_t)ci), x, nn, r2, slab))
                continue;
            int j0 = cj * cs > ty0 ? cj * cs : ty0, j1 = cj * cs + cs - 1 < ty1 ? cj * cs + cs - 1 : ty1;
            int i0 = ci * cs > tx0 ? ci * cs : tx0, i1 = ci * cs + cs - 1 < tx1 ? ci * cs + cs - 1 : tx1;
            for (int j = j0; j <= j1; j++)
                for (int i = i0; i <= i1; i++) {
                    if (!box_reaches(t->box + 6 * ((size_t)j * (size_t)t->tiles_x + (size_t)i), x, nn, r2, slab))
                        continue;
                    int px0 = i * SPLAT_TILE, py0 = j * SPLAT_TILE;
                    int px1 = px0 + SPLAT_TILE - 1, py1 = py0 + SPLAT_TILE - 1;
                    if (px0 < bx0)
                        bx0 = px0;
                    if (px1 > bx1)
                        bx1 = px1;
                    if (py0 < by0)
                        by0 = py0;
                    if (py1 > by1)
                        by1 = py1;
                }
        }
    if (bx1 < 0)
        return 0;
    out->x0 = x0 > bx0 ? x0 : bx0;
    out->x1 = x1 < bx1 ? x1 : bx1;
    out->y0 = y0 > by0 ? y0 : by0;
    out->y1 = y1 < by1 ? y1 : by1;
    /* Far depth: for a perspective projection z_ndc = −P₁₀ + P₁₄ / w grows with w. */
    double z = 1.0;
    if (proj[11] == -1.0f && proj[15] == 0.0f) {
        z = -(double)proj[10] + (double)proj[14] / (w_max * grow);
        if (z > 1.0)
            z = 1.0;
        if (z < -1.0)
            z = -1.0;
    }
    out->z = (float)z;
    return 1;
}
