/* texture_mip.c — texture sampling on the CPU with mip levels: the same levels the
 * GPU samples (engine.c uploads these, not glGenerateMipmap's), the same filters (OpenGL 4.5
 * §8.14), and a level of detail from a ray cone for CPU hits.
 *
 * Mip levels: each texel of level l+1 is the box average of the 2×2 texels of level l it
 * covers (a 3-wide box on the last row or column of an odd-sized level, so no texel is
 * dropped), in linear space (the loader already sRGB-decoded base colour and emissive, as the
 * GL texture holds them), in double and rounded once.
 *
 * Level of detail at a CPU hit: the ray-cone footprint of T. Akenine-Möller et al., "Texture
 * Level of Detail Strategies for Real-Time Ray Tracing" (Ray Tracing Gems, 2019, ch. 20,
 * §20.3.4): λ = Δ + log2(W / |n̂·d̂|), Δ = ½·log2(t_a / p_a) with t_a the triangle's area in
 * texels (uv area × width × height, × |det| of KHR_texture_transform) and p_a its world-space
 * area. The caller passes W / |n̂·d̂| (photon_trace.c: which cone it uses). */
#include "scn.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Texel coordinate i (may be outside 0..n-1) wrapped as glTF §3.8.4 (GL's wrap modes). A
 * coordinate inside the level is itself in every mode (the photon trace's texture lookups are
 * nearly all inside: no 64-bit division for them). */
static inline uint32_t wrap_index(long long i, uint32_t n, scn_wrap w)
{
    long long nn = (long long)n;
    if (i >= 0 && i < nn)
        return (uint32_t)i;
    switch (w) {
    case SCN_WRAP_CLAMP: return (uint32_t)(i < 0 ? 0 : i >= nn ? nn - 1 : i);
    case SCN_WRAP_MIRROR: {
        long long p = ((i % (2 * nn)) + 2 * nn) % (2 * nn);
        return (uint32_t)(p < nn ? p : 2 * nn - 1 - p);
    }
    default: return (uint32_t)(((i % nn) + nn) % nn);
    }
}

static uint32_t level_size(uint32_t n, uint32_t l)
{
    n >>= l;
    return n ? n : 1;
}

/* Level l of t at (u, v), NEAREST or LINEAR. */
static void sample_level(const scn_texture *t, uint32_t l, int linear, float u, float v, float out[4])
{
    const uint32_t w = level_size(t->width, l), h = level_size(t->height, l);
    const float *texels = l == 0 ? t->texels : t->mips[l];
    /* GL's texel space: texel i covers [i, i+1) of u·width; LINEAR weighs the four texels
     * around u·width − 0.5 (OpenGL 4.5 §8.14.2). Row 0 is the top of the image, v = 0. */
    double x = (double)u * w, y = (double)v * h;
    if (!isfinite(x) || !isfinite(y) || fabs(x) > 1e15 || fabs(y) > 1e15)
        x = y = 0.0;
    if (!linear) {
        const float *p = texels + ((size_t)wrap_index((long long)floor(y), h, t->wrap_t) * w +
                                   wrap_index((long long)floor(x), w, t->wrap_s)) * 4;
        memcpy(out, p, 4 * sizeof *out);
        return;
    }
    x -= 0.5;
    y -= 0.5;
    double fx = floor(x), fy = floor(y);
    double ax = x - fx, ay = y - fy;
    uint32_t x0 = wrap_index((long long)fx, w, t->wrap_s), x1 = wrap_index((long long)fx + 1, w, t->wrap_s);
    uint32_t y0 = wrap_index((long long)fy, h, t->wrap_t), y1 = wrap_index((long long)fy + 1, h, t->wrap_t);
    const float *p00 = texels + ((size_t)y0 * w + x0) * 4, *p01 = texels + ((size_t)y0 * w + x1) * 4;
    const float *p10 = texels + ((size_t)y1 * w + x0) * 4, *p11 = texels + ((size_t)y1 * w + x1) * 4;
    for (int c = 0; c < 4; c++)
        out[c] = (float)((1 - ay) * ((1 - ax) * p00[c] + ax * p01[c]) + ay * ((1 - ax) * p10[c] + ax * p11[c]));
}

void scn_texture_sample(const scn_texture *t, float u, float v, float out[4])
{
    sample_level(t, 0, t->mag_linear, u, v, out);
}

int scn_texture_build_mips(scn_texture *t)
{
    t->mips[0] = t->texels;
    t->levels = 1;
    while (t->levels < SCN_MAX_MIPS) {
        const uint32_t l = t->levels - 1;
        const uint32_t sw = level_size(t->width, l), sh = level_size(t->height, l);
        if (sw == 1 && sh == 1)
            break;
        const uint32_t dw = level_size(t->width, l + 1), dh = level_size(t->height, l + 1);
        float *d = malloc((size_t)dw * dh * 4 * sizeof *d);
        if (!d)
            return 0;
        const float *s = t->mips[l];
        for (uint32_t y = 0; y < dh; y++) {
            /* Source rows 2y, 2y+1 (and 2y+2 for the last row of an odd level); one row when
             * the level is one texel high. */
            uint32_t y0 = sh == 1 ? 0 : 2 * y, y1 = sh == 1 ? 0 : (y + 1 == dh && (sh & 1) ? 2 * y + 2 : 2 * y + 1);
            for (uint32_t x = 0; x < dw; x++) {
                uint32_t x0 = sw == 1 ? 0 : 2 * x, x1 = sw == 1 ? 0 : (x + 1 == dw && (sw & 1) ? 2 * x + 2 : 2 * x + 1);
                if (x1 == x0 + 1 && y1 == y0 + 1) {
                    /* 2×2: the bilinear mix at the block's centre, as GL's mipmap blit
                     * computes it (lerp(lerp(a, b, ½), lerp(c, d, ½), ½) in float). */
                    const float *a = s + ((size_t)y0 * sw + x0) * 4, *b = a + 4, *c0 = a + (size_t)sw * 4, *d0 = c0 + 4;
                    for (int c = 0; c < 4; c++) {
                        float ab = a[c] + 0.5f * (b[c] - a[c]), cd = c0[c] + 0.5f * (d0[c] - c0[c]);
                        d[((size_t)y * dw + x) * 4 + c] = ab + 0.5f * (cd - ab);
                    }
                    continue;
                }
                for (int c = 0; c < 4; c++) {
                    double acc = 0.0;
                    for (uint32_t yy = y0; yy <= y1; yy++)
                        for (uint32_t xx = x0; xx <= x1; xx++)
                            acc += s[((size_t)yy * sw + xx) * 4 + c];
                    d[((size_t)y * dw + x) * 4 + c] = (float)(acc / (double)((y1 - y0 + 1) * (x1 - x0 + 1)));
                }
            }
        }
        t->mips[t->levels++] = d;
    }
    return 1;
}

void scn_texture_sample_lod(const scn_texture *t, float u, float v, float lod, float out[4])
{
    const int f = t->min_filter;
    const int mipmapped = f >= 9984 && f <= 9987 && t->levels > 1;
    /* §8.14.2: magnification below c = 0.5 for LINEAR magnification with a NEAREST_MIPMAP_*
     * minification, 0 otherwise. */
    const float c = t->mag_linear && (f == 9984 || f == 9986) ? 0.5f : 0.0f;
    if (!(lod > c) || !isfinite(lod)) {
        sample_level(t, 0, t->mag_linear, u, v, out);
        return;
    }
    const int linear = f == 9729 || f == 9985 || f == 9987; /* LINEAR, LINEAR_MIPMAP_* */
    if (!mipmapped) {
        sample_level(t, 0, linear, u, v, out);
        return;
    }
    const float q = (float)(t->levels - 1);
    if (lod > q)
        lod = q;
    if (f == 9984 || f == 9985) { /* *_MIPMAP_NEAREST: d = ⌈λ + ½⌉ − 1 (§8.14.3) */
        uint32_t d = lod <= 0.5f ? 0 : (uint32_t)ceilf(lod + 0.5f) - 1;
        sample_level(t, d > (uint32_t)q ? (uint32_t)q : d, linear, u, v, out);
        return;
    }
    uint32_t d1 = (uint32_t)floorf(lod), d2 = d1 + 1 > (uint32_t)q ? (uint32_t)q : d1 + 1;
    float a = lod - (float)d1, t1[4], t2[4];
    sample_level(t, d1, linear, u, v, t1);
    sample_level(t, d2, linear, u, v, t2);
    for (int k = 0; k < 4; k++)
        out[k] = (1.0f - a) * t1[k] + a * t2[k];
}

int scn_texref_at_cone(const scn_scene *scene, const scn_texref *r, const scn_primitive *p, uint32_t tri, float b1,
                       float b2, float width, float world_area, float out[4])
{
    out[0] = out[1] = out[2] = out[3] = 1.0f;
    if (!(r->texture >= 0 && (uint32_t)r->texture < scene->texture_count && p->texcoords[r->texcoord]))
        return 0;
    const scn_texture *tex = &scene->textures[r->texture];
    const uint32_t *i = p->indices + 3 * (size_t)tri;
    const float *tc = p->texcoords[r->texcoord];
    double w[3] = {1.0 - (double)b1 - (double)b2, b1, b2};
    double uv[2] = {0, 0};
    for (int k = 0; k < 3; k++)
        for (int c = 0; c < 2; c++)
            uv[c] += w[k] * tc[(size_t)i[k] * 2 + c];
    const float *t = r->transform;
    float u = (float)(t[0] * uv[0] + t[2] * uv[1] + t[4]), v = (float)(t[1] * uv[0] + t[3] * uv[1] + t[5]);
    if (!(width > 0.0f) || !(world_area > 0.0f)) {
        scn_texture_sample(tex, u, v, out); /* no footprint: level 0, magFilter */
        return 1;
    }
    /* t_a: twice the uv triangle's area is |e1 × e2|; the halves cancel against p_a's. */
    const float *a = tc + (size_t)i[0] * 2, *b = tc + (size_t)i[1] * 2, *cc = tc + (size_t)i[2] * 2;
    double uv_area = 0.5 * fabs(((double)b[0] - a[0]) * ((double)cc[1] - a[1]) -
                                ((double)cc[0] - a[0]) * ((double)b[1] - a[1]));
    double det = fabs((double)t[0] * t[3] - (double)t[1] * t[2]);
    double ta = uv_area * det * tex->width * tex->height;
    float lod = ta > 0.0 ? (float)(0.5 * log2(ta / world_area) + log2(width)) : 0.0f;
    scn_texture_sample_lod(tex, u, v, lod, out);
    return 1;
}

int scn_texref_at(const scn_scene *scene, const scn_texref *r, const scn_primitive *p, uint32_t tri, float b1,
                  float b2, float out[4])
{
    return scn_texref_at_cone(scene, r, p, tri, b1, b2, 0.0f, 0.0f, out);
}
