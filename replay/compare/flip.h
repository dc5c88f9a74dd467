/* flip.h — the perceptual difference metric ꟻLIP: how visible the difference
 * between a test image and a reference image is to a person who flips between them.
 *
 *   LDR-ꟻLIP  Andersson, Nilsson, Akenine-Möller, Oskarsson, Åström, Fairchild, "FLIP: A
 *             Difference Evaluator for Alternating Images", HPG 2020 (§4 colour pipeline,
 *             §5 feature pipeline, §6 the combination). Input: sRGB-encoded values in [0,1].
 *   HDR-ꟻLIP  Andersson, Nilsson, Shirley, Akenine-Möller, "Visualizing Errors in Rendered High
 *             Dynamic Range Images", Eurographics 2021 short paper (§3): LDR-ꟻLIP of the two
 *             images exposure-compensated and tone-mapped (ACES fit) at a range of exposures,
 *             the per-pixel maximum. Input: linear radiance.
 *
 * Per pixel the result lies in [0,1]: 0 no visible difference, 1 the largest (the colour term is
 * normalised by the distance of green to blue, §4.2). Identical images give exactly 0. The
 * metric is symmetric in its two images (every step treats them alike; with a pinned exposure
 * range HDR-ꟻLIP is too). Values depend on the observer's pixels per degree (ppd): the default,
 * 67.02, is the papers' (a 0.7 m wide 3840-pixel monitor seen from 0.7 m).
 *
 * The HDR exposure range is pinned, never taken from the images (the reference code's automatic
 * range follows the reference image's maximum and median luminance, so a changed golden would
 * move the yardstick): start and stop exposures come from the caller (tolerances.json
 * flip_exposure_start/flip_exposure_stop), default REP_FLIP_EXPOSURE_START..STOP; the exposures
 * are max(2, ceil(stop − start)) evenly spaced values from start to stop (HDR-ꟻLIP §3).
 *
 * Deterministic: one thread, a fixed order of operations, double arithmetic; the same inputs give
 * the same bits on any machine running the same binary. Non-finite inputs: NaN counts as 0, +Inf
 * as the clamp's top (LDR 1, HDR 65536, as the reference code clamps), −Inf as 0 (replay fails a
 * buffer with non-finite values on its own account; ꟻLIP only needs to stay defined).
 */
#ifndef ISPM_REP_FLIP_H
#define ISPM_REP_FLIP_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* 0.7 m × 3840 px / 0.7 m × π / 180 (ꟻLIP §3, the papers' default observer). */
#define REP_FLIP_PPD_DEFAULT 67.02064327658225
#define REP_FLIP_EXPOSURE_START -4.0
#define REP_FLIP_EXPOSURE_STOP 4.0

typedef enum rep_flip_kind {
    REP_FLIP_NONE = 0, /* not a colour image: no ꟻLIP */
    REP_FLIP_LDR,      /* display-referred sRGB in [0,1] */
    REP_FLIP_HDR       /* linear radiance */
} rep_flip_kind;

/* A zeroed desc is LDR at the default ppd; HDR with start = stop = 0 takes the default range. */
typedef struct rep_flip_desc {
    rep_flip_kind kind;
    double ppd;                          /* <= 0: REP_FLIP_PPD_DEFAULT */
    double exposure_start, exposure_stop; /* HDR only */
} rep_flip_desc;

typedef struct rep_flip_stats {
    double mean, p50, p95, p99, max; /* percentiles by nearest rank over all pixels */
    int exposures;                   /* HDR: how many exposures were evaluated; LDR: 1 */
} rep_flip_stats;

/* Which ꟻLIP a buffer gets, from its name: "*.display" LDR, "*.radiance" HDR, others none. */
rep_flip_kind rep_flip_kind_of(const char *buffer);

/* The per-pixel ꟻLIP of test against ref into map (w×h floats). test and ref: w×h pixels of
 * three floats R,G,B (stride floats apart, stride >= 3), top row first. */
void rep_flip_map(const float *test, const float *ref, int w, int h, int stride, const rep_flip_desc *d, float *map);

/* How many exposures d evaluates (LDR: 1). */
int rep_flip_exposures(const rep_flip_desc *d);

/* Mean, percentiles and maximum of a map of n values (n >= 1). */
void rep_flip_stats_of(const float *map, size_t n, rep_flip_stats *s);

/* Both in one: the map is computed, summarised and freed. */
void rep_flip_compute(const float *test, const float *ref, int w, int h, int stride, const rep_flip_desc *d,
                      rep_flip_stats *s);

/* The colour term alone (§4) of two uniform LDR colours (sRGB in [0,1]): on a uniform image the
 * CSF filters (normalised) leave every value as it is and the feature detectors (zero-sum) see
 * nothing, so this is the ꟻLIP of two uniform images. Exposed for the tests' hand computations. */
double rep_flip_uniform_ldr(const double a[3], const double b[3]);

/* One 1-D pass of ꟻLIP's filters: out = in convolved with the 2r+1 taps along x (dir 0) or y
 * (dir 1), edge pixels repeated; each output is 0.0 + taps[0]·p0, then + taps[i]·pi in increasing
 * i, bit for bit whatever the vector width. Exposed for the tests. */
void rep_flip_convolve(const double *in, double *out, int w, int h, const double *taps, int r, int dir);

/* The heat map of a ꟻLIP map (0 black through purple and orange to pale yellow at 1, a magma-like
 * ramp as in the paper's figures), RGB bytes, box-maximum reduced so the longest side is at most
 * max_side (0: full size). Caller frees. */
unsigned char *rep_flip_heat(const float *map, int w, int h, int max_side, int *tw, int *th);
/* One heat-map colour (t in [0,1]) as bytes. */
void rep_flip_heat_rgb(double t, unsigned char rgb[3]);

#ifdef __cplusplus
}
#endif

#endif
