/* boundary.c — boundary renormalisation of the photon kernel (boundary.h). */
#include "boundary.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

double bnd_mass(double x)
{
    if (x >= 1.0)
        return 1.0;
    if (x <= 0.0)
        return 0.0;
    double x2 = x * x;
    return 2.0 * x2 - x2 * x2;
}

/* Homogeneous clip coordinates of p (w = 1 for a point, 0 for a direction). */
static void clip_of(const float vp[16], const double p[3], double w, double out[4])
{
    for (int r = 0; r < 4; r++)
        out[r] = (double)vp[r] * p[0] + (double)vp[4 + r] * p[1] + (double)vp[8 + r] * p[2] + (double)vp[12 + r] * w;
}

/* Mean photon radius per BND_TILE² screen tile (tiles without photons: the map's mean). */
static double *tile_radii(const float vp[16], int w, int h, const eng_photon_map *map, const float *radius, int tx,
                          int ty)
{
    double *sum = calloc((size_t)tx * ty, sizeof *sum);
    unsigned *cnt = calloc((size_t)tx * ty, sizeof *cnt);
    if (!sum || !cnt) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    double all = 0.0;
    for (size_t i = 0; i < map->count; i++) {
        all += radius[i];
        const float *p = map->photons[i].position;
        double pd[3] = {p[0], p[1], p[2]}, c[4];
        clip_of(vp, pd, 1.0, c);
        if (!(c[3] > 1e-6))
            continue;
        double x = (c[0] / c[3] * 0.5 + 0.5) * w, y = (0.5 - c[1] / c[3] * 0.5) * h;
        if (!(x >= 0.0 && x < w && y >= 0.0 && y < h))
            continue;
        size_t t = (size_t)((int)y / BND_TILE) * tx + (size_t)((int)x / BND_TILE);
        sum[t] += radius[i];
        cnt[t]++;
    }
    double mean = map->count ? all / (double)map->count : 0.0;
    for (size_t t = 0; t < (size_t)tx * ty; t++)
        sum[t] = cnt[t] ? sum[t] / cnt[t] : mean;
    free(cnt);
    return sum;
}

/* One step of the walk (boundary.h): 1 if the surface seen at q = s + ρu continues s's surface,
 * 0 if it ends there (convex edge or background), 2 if it ends at a surface in front of q within
 * R of it (a concave edge: a wall rising from s's surface), −1 if the G-buffer cannot tell (off
 * screen, behind the camera or outside the near/far planes, hidden behind something more than R
 * from q). cs, cu: clip coordinates of s and of u (w = 0), so that
 * clip(q) = cs + ρ cu. */
static int step(const glu_gbuffer *gb, const double cs[4], const double cu[4], const double eye[3], const double s[3],
                const double n[3], const double u[3], double rho, double R, double rz)
{
    const int w = gb->width, h = gb->height;
    double cw = cs[3] + rho * cu[3], cz = cs[2] + rho * cu[2];
    if (!(cw > 1e-6) || !(cz >= -cw && cz <= cw))
        return -1; /* behind the camera, or clipped by the near or far plane: not in the G-buffer */
    double x = ((cs[0] + rho * cu[0]) / cw * 0.5 + 0.5) * w, y = (0.5 - (cs[1] + rho * cu[1]) / cw * 0.5) * h;
    if (!(x >= 0.0 && x < w && y >= 0.0 && y < h))
        return -1;
    size_t k = (size_t)(int)y * (size_t)w + (size_t)(int)x;
    const float *g = gb->position + 4 * k, *gn = gb->normal + 3 * k;
    if (!(g[3] > 0.0f))
        return 0; /* background */
    double q[3], along = 0.0, cosn = 0.0, gl = 0.0;
    for (int c = 0; c < 3; c++) {
        q[c] = s[c] + rho * u[c];
        along += (g[c] - q[c]) * n[c];
        cosn += gn[c] * n[c];
        gl += (double)gn[c] * gn[c];
    }
    if (cosn >= 0.0 && 2.0 * cosn * cosn >= gl && fabs(along) <= rz)
        return 1; /* within 45° of s's normal and within r_z of q along it */
    double de = 0.0, dg = 0.0, dist2 = 0.0;
    for (int c = 0; c < 3; c++) {
        de += (q[c] - eye[c]) * (q[c] - eye[c]);
        dg += (g[c] - eye[c]) * (g[c] - eye[c]);
        dist2 += (g[c] - q[c]) * (g[c] - q[c]);
    }
    if (sqrt(dg) < sqrt(de) - rz && dist2 > R * R)
        return -1;
    return sqrt(dg) < sqrt(de) ? 2 : 0;
}

/* 1 if the points at R/2 and R in direction u both lie on the surface (the quick path). */
static int reaches(const glu_gbuffer *gb, const float vp[16], const double eye[3], const double s[3],
                   const double n[3], const double u[3], double R, double rz)
{
    double cs[4], cu[4];
    clip_of(vp, s, 1.0, cs);
    clip_of(vp, u, 0.0, cu);
    return step(gb, cs, cu, eye, s, n, u, R, R, rz) == 1 && step(gb, cs, cu, eye, s, n, u, 0.5 * R, R, rz) == 1;
}

/* e/R of the surface of pixel (s, n) in direction u (boundary.h) by the walk of BND_STEPS steps;
 * *concave: it ends at a wall. */
static double extent(const glu_gbuffer *gb, const float vp[16], const double eye[3], const double s[3],
                     const double n[3], const double u[3], double R, double rz, int *concave)
{
    *concave = 0;
    double cs[4], cu[4];
    clip_of(vp, s, 1.0, cs);
    clip_of(vp, u, 0.0, cu);
    double last = 0.0;
    for (int m = 1; m <= BND_STEPS; m++) {
        double rho = R * m / BND_STEPS;
        int on = step(gb, cs, cu, eye, s, n, u, rho, R, rz);
        if (on < 0)
            return 1.0; /* unknown: the surface is taken to go on */
        if (on == 0 || on == 2) {
            /* Two bisections between the last step on the surface and the first off it. */
            double lo = last, hi = rho;
            for (int b = 0; b < 2; b++) {
                double mid = 0.5 * (lo + hi);
                int o = step(gb, cs, cu, eye, s, n, u, mid, R, rz);
                if (o < 0)
                    break;
                if (o == 1)
                    lo = mid;
                else {
                    hi = mid;
                    on = o;
                }
            }
            *concave = on == 2;
            return 0.5 * (lo + hi) / R;
        }
        last = rho;
    }
    return 1.0;
}

/* λ(d) of boundary.h for d = k/(BND_LEAK−1) · compression (units of R), k = 0 … BND_LEAK−1:
 * the kernel mass a wall perpendicular to the surface at distance d brings in (its photons,
 * normal along the wall's, reach the pixel through the ellipsoid of Eq. 2–3:
 * t = (|D| + d (1/c − 1)) / R) over the mass the surface loses beyond d. Midpoint sums. */
#define BND_LEAK 33
static void leak_table(double c, double *lambda)
{
    const int G = 64;
    for (int k = 0; k < BND_LEAK; k++) {
        double d = c * k / (BND_LEAK - 1), gain = 0.0, loss = 0.0;
        for (int a = 0; a < G; a++) {
            double z = (a + 0.5) / G; /* wall: height z ∈ (0, 1), across y ∈ (−1, 1) */
            for (int b = 0; b < 2 * G; b++) {
                double y = (b + 0.5) / G - 1.0;
                double tt = (sqrt(d * d + y * y + z * z) + d * (1.0 / c - 1.0));
                if (tt < 1.0)
                    gain += 2.0 / ENG_PI * (1.0 - tt * tt);
            }
        }
        gain /= (double)G * G;
        for (int a = 0; a < G; a++) { /* the surface beyond d: κ's marginal (8/3π)(1 − x²)^{3/2} */
            double x = d + (1.0 - d) * (a + 0.5) / G;
            loss += 8.0 / (3.0 * ENG_PI) * pow(1.0 - x * x, 1.5) * (1.0 - d) / G;
        }
        lambda[k] = loss > 1e-9 ? fmin(gain / loss, 1.0) : 0.0;
    }
}

/* λ at d (units of R) by linear interpolation; 0 beyond compression. */
static double leak_at(const double *lambda, double c, double d)
{
    double f = d / c * (BND_LEAK - 1);
    if (!(f < BND_LEAK - 1))
        return 0.0;
    int k = (int)f;
    return lambda[k] + (f - k) * (lambda[k + 1] - lambda[k]);
}

void bnd_weights(const glu_gbuffer *gb, const float view_proj[16], const float eye[3], const eng_photon_map *map,
                 const float *radius, float compression, int threads, float *weight)
{
    bnd_weights_scaled(gb, view_proj, eye, map, radius, NULL, compression, threads, weight);
}

void bnd_weights_scaled(const glu_gbuffer *gb, const float view_proj[16], const float eye[3],
                        const eng_photon_map *map, const float *radius, const float *pixel_scale, float compression,
                        int threads, float *weight)
{
    const int w = gb->width, h = gb->height;
    const int tx = (w + BND_TILE - 1) / BND_TILE, ty = (h + BND_TILE - 1) / BND_TILE;
    double *rt = tile_radii(view_proj, w, h, map, radius, tx, ty);
    const double e3[3] = {eye[0], eye[1], eye[2]};
    double lambda[BND_LEAK];
    leak_table(compression, lambda);
    double cosj[BND_DIRECTIONS], sinj[BND_DIRECTIONS];
    for (int j = 0; j < BND_DIRECTIONS; j++) {
        double phi = 2.0 * ENG_PI * (j + 0.5) / BND_DIRECTIONS;
        cosj[j] = cos(phi);
        sinj[j] = sin(phi);
    }
    /* Rows shared among OpenMP threads; each pixel is computed by one thread alone, in the
     * same operations whatever the thread count. */
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads > 0 ? threads : 1)
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            const float *p = gb->position + 4 * i, *pn = gb->normal + 3 * i;
            double R = rt[(size_t)(y / BND_TILE) * tx + (size_t)(x / BND_TILE)];
            if (pixel_scale)
                R *= pixel_scale[i];
            double nl = sqrt((double)pn[0] * pn[0] + (double)pn[1] * pn[1] + (double)pn[2] * pn[2]);
            if (!(p[3] > 0.0f) || !(R > 0.0) || !(nl > 0.0)) {
                weight[i] = 1.0f;
                continue;
            }
            double s[3] = {p[0], p[1], p[2]}, n[3] = {pn[0] / nl, pn[1] / nl, pn[2] / nl};
            /* Tangent frame: t1 ⟂ n from the axis least aligned with n. */
            double a[3] = {0.0, 0.0, 0.0};
            int ax = fabs(n[0]) <= fabs(n[1]) && fabs(n[0]) <= fabs(n[2]) ? 0 : fabs(n[1]) <= fabs(n[2]) ? 1 : 2;
            a[ax] = 1.0;
            double t1[3] = {a[1] * n[2] - a[2] * n[1], a[2] * n[0] - a[0] * n[2], a[0] * n[1] - a[1] * n[0]};
            double tl = sqrt(t1[0] * t1[0] + t1[1] * t1[1] + t1[2] * t1[2]);
            for (int c = 0; c < 3; c++)
                t1[c] /= tl;
            double t2[3] = {n[1] * t1[2] - n[2] * t1[1], n[2] * t1[0] - n[0] * t1[2], n[0] * t1[1] - n[1] * t1[0]};
            /* Quick path: where the points at R/2 and R lie on the surface in every other
             * direction, the pixel is taken to be away from edges (W = 1). */
            int inside = 1;
            for (int j = 0; j < BND_DIRECTIONS && inside; j += 2) {
                double u[3];
                for (int c = 0; c < 3; c++)
                    u[c] = cosj[j] * t1[c] + sinj[j] * t2[c];
                inside = reaches(gb, view_proj, e3, s, n, u, R, compression * R);
            }
            if (inside) {
                weight[i] = 1.0f;
                continue;
            }
            double e[BND_DIRECTIONS], dwall = 2.0, W = 0.0;
            int conc[BND_DIRECTIONS];
            for (int j = 0; j < BND_DIRECTIONS; j++) {
                double u[3];
                for (int c = 0; c < 3; c++)
                    u[c] = cosj[j] * t1[c] + sinj[j] * t2[c];
                e[j] = reaches(gb, view_proj, e3, s, n, u, R, compression * R)
                           ? (conc[j] = 0, 1.0)
                           : extent(gb, view_proj, e3, s, n, u, R, compression * R, &conc[j]);
                if (conc[j] && e[j] < dwall)
                    dwall = e[j];
            }
            /* A wall at distance dwall (the nearest concave end) gives back λ(dwall) of what the
             * surface loses in the directions that end at a wall. */
            double lam = leak_at(lambda, compression, dwall);
            for (int j = 0; j < BND_DIRECTIONS; j++) {
                double g = bnd_mass(e[j]);
                W += g + (conc[j] ? (1.0 - g) * lam : 0.0);
            }
            W /= BND_DIRECTIONS;
            weight[i] = (float)fmax(W, (double)BND_WMIN);
        }
    free(rt);
}

void bnd_apply(size_t n, const float *weight, float *rgba)
{
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            rgba[4 * i + c] /= weight[i];
}

struct bnd_pass {
    int attachments;
    glu_cpu_target target;
    glu_gbuffer gb;
    float *rgba, *weight;
};

eng_result bnd_pass_create(int width, int height, int attachments, bnd_pass **out, eng_error *err)
{
    bnd_pass *b = calloc(1, sizeof *b);
    if (!b) {
        fprintf(stderr, "ispm: out of memory\n");
        abort();
    }
    eng_result r = glu_cpu_target_create(&b->target, width, height, attachments > 1, err);
    if (r != ENG_OK) {
        free(b);
        return r;
    }
    b->attachments = attachments;
    b->rgba = eng_xmalloc((size_t)width * (size_t)height * 4 * sizeof(float));
    b->weight = eng_xmalloc((size_t)width * (size_t)height * sizeof(float));
    *out = b;
    return ENG_OK;
}

void bnd_pass_destroy(bnd_pass *b)
{
    if (!b)
        return;
    glu_cpu_target_destroy(&b->target);
    glu_gbuffer_free(&b->gb);
    free(b->rgba);
    free(b->weight);
    free(b);
}

const float *bnd_pass_run(bnd_pass *b, const glu_target *gb, const glu_target **sp, const ind_input *in)
{
    static const int p4[] = {0, 1, 2, 3};
    glu_gbuffer_read(gb, &b->gb);
    bnd_weights_scaled(&b->gb, in->fs->camera.view_proj, in->fs->camera.eye, in->map, in->radius, in->pixel_scale,
                       in->s->normal_compression, in->s->threads, b->weight);
    const size_t n = (size_t)gb->width * (size_t)gb->height;
    for (int a = 0; a < b->attachments; a++) {
        glu_read(*sp, a, 0, 4, p4, b->rgba);
        bnd_apply(n, b->weight, b->rgba);
        glu_cpu_target_upload(&b->target, a, b->rgba);
    }
    *sp = &b->target.target;
    return b->weight;
}
