/* ind_common.c — what every indirect method shares: the photons' kernel radii under the
 * kernel scaling, the anisotropic kernel, each kernel's reach, and the state a CPU method keeps
 * between frames (its G-buffer read back and the target it uploads into). */
#include "indirect.h"
#include "gather_kernel.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Tile size of the tile-density scaling (002 §6.1.1 keeps a counter per screen tile). */
#define IND_DENSITY_TILE 16
/* n_tile of 002 Eq. 6.2: photons expected to overlap each point. */
#define IND_DENSITY_NTILE 16.0
/* Clamp of every scaling to the path-density scaling's range: [r/4, 2r] (002 Eq. 6.2's r_min,
 * r_max; 004 §6's [P_min, P_max] on p gives the same bounds on C = C0/√p). */
#define IND_RMIN 0.25
#define IND_RMAX 2.0

const pass_output ind_radiance_outputs[] = {
    {.name = "<m>.indirect", .attachment = 0, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {.name = "<m>.count", .attachment = 0, .pick = {3}, .channels = {"Y"}},
    {0},
};

const pass_output ind_irradiance_outputs[] = {
    {.name = "<m>.irradiance", .attachment = 0, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {.name = "<m>.count", .attachment = 0, .pick = {3}, .channels = {"Y"}},
    {.name = "<m>.glossy", .attachment = 1, .pick = {0, 1, 2}, .channels = {"R", "G", "B"}},
    {0},
};

static double clampd(double v, double lo, double hi) { return v < lo ? lo : v > hi ? hi : v; }


void ind_photon_radii(const eng_photon_map *map, const eng_settings *s, const eng_frame_scene *fs, int width,
                      int height, float scale, float *radius)
{
    const size_t n = map->count;
    const double kr = s->kernel_radius;
    switch (s->kernel_scaling) {
    case ENG_SCALING_RAY_LENGTH: {
        /* 002 Eq. 6.1: s_l = min(l / l_max, 1), the ray cone's growth with its length l; l_max
         * from the scene's bounding box (half its diagonal). r = 2 kr · max(s_l, 1/8): a photon
         * that travelled l_max/2 gets kr, the range is path-density's [kr/4, 2 kr]. */
        double diag2 = 0.0;
        for (int c = 0; c < 3; c++) {
            double e = (double)fs->bounds_max[c] - fs->bounds_min[c];
            diag2 += e * e;
        }
        double lmax = diag2 > 0.0 ? 0.5 * sqrt(diag2) : 1.0;
        for (size_t i = 0; i < n; i++) {
            double sl = fmin((double)map->photons[i].ray_length / lmax, 1.0);
            radius[i] = (float)(IND_RMAX * kr * fmax(sl, IND_RMIN / IND_RMAX));
        }
        break;
    }
    case ENG_SCALING_TILE_DENSITY: {
        /* 002 Eq. 6.2: count the photons landing in each 16×16-pixel screen tile; a photon's
         * circular kernel gets n_tile/n_p of its tile's view-space area at the photon's depth,
         * a_view = z² · 4 tan(α_x/2) tan(α_y/2) t_x t_y / (r_x r_y) (the thesis's c_tile drops
         * the 4 of the half-angles), r = √(n_tile a_view / (π n_p)), clamped to [kr/4, 2 kr].
         * (The thesis multiplies r by n_tile; scaling the area by n_tile keeps n_tile the number
         * of overlapping kernels.) Photons off screen count in the nearest edge tile; behind
         * the camera they keep kr. */
        const float *vp = fs->camera.view_proj;
        const int tx = (width + IND_DENSITY_TILE - 1) / IND_DENSITY_TILE;
        const int ty = (height + IND_DENSITY_TILE - 1) / IND_DENSITY_TILE;
        int *tile = eng_xmalloc((n ? n : 1) * sizeof *tile);
        uint32_t *count = calloc((size_t)tx * ty, sizeof *count);
        double *depth = eng_xmalloc((n ? n : 1) * sizeof *depth);
        if (!count) {
            fprintf(stderr, "ispm: out of memory\n");
            abort();
        }
        for (size_t i = 0; i < n; i++) {
            const float *p = map->photons[i].position;
            double cl[4];
            for (int r = 0; r < 4; r++)
                cl[r] = (double)vp[r] * p[0] + (double)vp[4 + r] * p[1] + (double)vp[8 + r] * p[2] + vp[12 + r];
            tile[i] = -1;
            depth[i] = cl[3];
            if (!(cl[3] > 1e-6))
                continue;
            double px = (cl[0] / cl[3] * 0.5 + 0.5) * width;
            double py = (0.5 - cl[1] / cl[3] * 0.5) * height;
            int x = (int)clampd(floor(px), 0.0, width - 1), y = (int)clampd(floor(py), 0.0, height - 1);
            tile[i] = (y / IND_DENSITY_TILE) * tx + x / IND_DENSITY_TILE;
            count[tile[i]]++;
        }
        /* tan(α/2) = 1 / proj[0] (x), 1 / proj[5] (y) for a perspective projection. */
        const double ctile = 4.0 * IND_DENSITY_TILE * IND_DENSITY_TILE /
                             ((double)fs->camera.proj[0] * fs->camera.proj[5] * width * height);
        for (size_t i = 0; i < n; i++) {
            double r = kr;
            if (tile[i] >= 0) {
                double aview = depth[i] * depth[i] * ctile;
                r = sqrt(IND_DENSITY_NTILE * aview / (ENG_PI * count[tile[i]]));
                r = clampd(r, IND_RMIN * kr, IND_RMAX * kr);
            }
            radius[i] = (float)r;
        }
        free(tile);
        free(count);
        free(depth);
        break;
    }
    case ENG_SCALING_BANDWIDTH: {
        /* 004 §6 (after Herzog et al. 2007): h = C·(A/N) with a variable bandwidth C = C0/√p,
         * p = cos θ / d² the photon's approximate density (θ its incident angle, d the length of
         * its last ray), p clamped. Here C0·(A/N) is chosen so that a photon of the map's
         * geometric-mean p gets kernel_radius: h = kr · √(p̄ / p), clamped to [kr/4, 2 kr]
         * (i.e. p to [p̄/4, 16 p̄]). */
        double logsum = 0.0;
        size_t used = 0;
        for (size_t i = 0; i < n; i++) {
            const eng_photon *ph = &map->photons[i];
            double c = (double)ph->direction[0] * ph->normal[0] + (double)ph->direction[1] * ph->normal[1] +
                       (double)ph->direction[2] * ph->normal[2];
            double d = ph->ray_length;
            double p = c > 1e-3 && d > 1e-6 ? c / (d * d) : 0.0;
            radius[i] = (float)p; /* scratch: p */
            if (p > 0.0) {
                logsum += log(p);
                used++;
            }
        }
        double pbar = used ? exp(logsum / (double)used) : 1.0;
        for (size_t i = 0; i < n; i++) {
            double p = radius[i];
            double f = p > 0.0 ? sqrt(pbar / p) : IND_RMAX;
            radius[i] = (float)(kr * clampd(f, IND_RMIN, IND_RMAX));
        }
        break;
    }
    case ENG_SCALING_ANISOTROPIC: /* path-density's size; the shape is ind_photon_aniso's */
    case ENG_SCALING_PATH_DENSITY:
    case ENG_SCALING_DEFAULT:
        for (size_t i = 0; i < n; i++)
            radius[i] = splat_radius(s->kernel_radius, map->photons[i].path_density);
        break;
    }
    /* Progressive photon mapping's shrinking radius (engine.c, progressive_begin). */
    if (scale != 1.0f)
        for (size_t i = 0; i < n; i++)
            radius[i] *= scale;
}

int ind_photon_aniso(const eng_photon_map *map, const eng_settings *s, float *aniso)
{
    if (s->kernel_scaling != ENG_SCALING_ANISOTROPIC)
        return 0;
    for (size_t i = 0; i < map->count; i++)
        gk_aniso_of(&map->photons[i], aniso + 4 * i);
    return 1;
}

const float *ind_reach(const ind_input *in, float **buf, size_t *cap)
{
    const size_t n = in->map->count;
    if (!in->aniso)
        return in->radius;
    if (n > *cap) {
        free(*buf);
        *buf = eng_xmalloc(n * sizeof **buf);
        *cap = n;
    }
    for (size_t i = 0; i < n; i++)
        (*buf)[i] = in->radius[i] * in->aniso[4 * i + 3];
    return *buf;
}

eng_result ind_cpu_state_init(ind_cpu_state *c, const char *method, int width, int height, int irradiance,
                              eng_error *err)
{
    memset(c, 0, sizeof *c);
    c->width = width;
    c->height = height;
    c->irradiance = irradiance;
    size_t n = (size_t)width * (size_t)height * 4;
    c->out = malloc(n * sizeof(float));
    c->glossy = irradiance ? malloc(n * sizeof(float)) : NULL;
    if (!c->out || (irradiance && !c->glossy)) {
        free(c->out);
        free(c->glossy);
        memset(c, 0, sizeof *c);
        return eng_fail(err, ENG_ERR_NOMEM, "%s: out of memory for a %dx%d image", method, width, height);
    }
    eng_result r = glu_cpu_target_create(&c->target, width, height, irradiance, err);
    if (r != ENG_OK) {
        free(c->out);
        free(c->glossy);
        memset(c, 0, sizeof *c);
    }
    return r;
}

void ind_cpu_state_free(ind_cpu_state *c)
{
    if (c->out)
        glu_cpu_target_destroy(&c->target);
    glu_gbuffer_free(&c->gb);
    free(c->out);
    free(c->glossy);
    memset(c, 0, sizeof *c);
}

void ind_cpu_state_output(ind_cpu_state *c, ind_output *o)
{
    glu_cpu_target_upload(&c->target, 0, c->out);
    if (c->irradiance)
        glu_cpu_target_upload(&c->target, 1, c->glossy);
    o->target = &c->target.target;
    o->extra_count = 0;
}
