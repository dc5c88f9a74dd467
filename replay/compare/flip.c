/* flip.c — ꟻLIP and HDR-ꟻLIP (flip.h), written from the papers:
 *   [F]  Andersson et al., "FLIP: A Difference Evaluator for Alternating Images", HPG 2020;
 *   [H]  Andersson et al., "Visualizing Errors in Rendered High Dynamic Range Images", EG 2021.
 *
 * Per image pair: both go to the opponent space YyCxCz ([F] §4.1, a linearised CIELab), each
 * channel is filtered with its contrast sensitivity function ([F] §4.1, Eq. 2–4: a sum of two
 * Gaussians in degrees of visual angle), the result goes back to linear RGB, clamped to the
 * unit cube, to CIELab with the Hunt adjustment (a, b scaled by 0.01 L, [F] §4.2), and the
 * colour difference is HyAB (|ΔL| + ‖Δab‖, [F] Eq. 5) raised to q_c = 0.7 and re-mapped into
 * [0,1] against c_max, the distance of Hunt-adjusted green to blue ([F] §4.2, Eq. 6). Features
 * ([F] §5): on the achromatic channel normalised to [0,1], edges (first derivative of a Gaussian,
 * σ = 0.5 · 0.082° · ppd) and points (second derivative), kernels normalised to +1 and −1 per
 * sign; ΔE_f = (max(|‖edge_r‖ − ‖edge_t‖|, |‖point_r‖ − ‖point_t‖|) / √2)^q_f, q_f = 0.5
 * ([F] Eq. 8). The combination is ΔE = ΔE_c^(1 − ΔE_f) ([F] Eq. 9).
 *
 * All filters are Gaussians or Gaussian derivatives, so each 2-D convolution is done as two 1-D
 * passes (exact, the kernels are products); image borders repeat the edge pixel. HDR ([H] §3):
 * each exposure c scales by 2^c, tone-maps with the ACES fit of [H] Eq. 2 per channel, clamps
 * to [0,1] and runs LDR-ꟻLIP from linear RGB; the per-pixel maximum over the exposures is the
 * result. Double arithmetic, fixed loop order within an exposure, exposures as OpenMP tasks whose
 * per-pixel results are combined in exposure order: bit-identical everywhere, whatever the threads.
 */
#include "flip.h"

#include "rep_run.h"
#include "rep_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846
#define QC 0.7  /* [F] §4.2 */
#define PC 0.4
#define PT 0.95
#define QF 0.5  /* [F] §5 */
#define FEATURE_W 0.082 /* degrees, [F] §5 */

/* [F] Table 1: a1, b1, a2, b2 of the achromatic, red-green and blue-yellow CSFs (b in deg²). */
static const double CSF[3][4] = {{1.0, 0.0047, 0.0, 1e-5}, {1.0, 0.0053, 0.0, 1e-5}, {34.1, 0.04, 13.5, 0.025}};
#define CSF_B_MAX 0.04

/* Hot loops are cloned for AVX2 (four doubles a vector instead of SSE2's two) and picked at run
 * time; without FMA (ispm_fp: -ffp-contract=off) every clone computes the same operations in
 * the same order, so the bits do not depend on the clone. */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__)
#define FLIP_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FLIP_CLONES
#endif

/* D65 white of linear sRGB in XYZ (the normalisation of YyCxCz and Lab). */
static const double WHITE[3] = {0.950428545, 1.0, 1.088900371};

rep_flip_kind rep_flip_kind_of(const char *buffer)
{
    switch (rep_thumb_kind_of(buffer)) {
    case REP_THUMB_DISPLAY: return REP_FLIP_LDR;
    case REP_THUMB_RADIANCE: return REP_FLIP_HDR;
    case REP_THUMB_DATA: break;
    }
    return REP_FLIP_NONE;
}

static double srgb_to_linear(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static void linear_to_xyz(const double c[3], double o[3])
{
    o[0] = (10135552.0 * c[0] + 8788810.0 * c[1] + 4435075.0 * c[2]) / 24577794.0;
    o[1] = (2613072.0 * c[0] + 8788810.0 * c[1] + 887015.0 * c[2]) / 12288897.0;
    o[2] = (1425312.0 * c[0] + 8788810.0 * c[1] + 70074185.0 * c[2]) / 73733382.0;
}

static void xyz_to_linear(const double x[3], double o[3])
{
    o[0] = 3.241003275 * x[0] - 1.537398934 * x[1] - 0.498615861 * x[2];
    o[1] = -0.969224334 * x[0] + 1.875930071 * x[1] + 0.041554224 * x[2];
    o[2] = 0.055639423 * x[0] - 0.204011202 * x[1] + 1.057148933 * x[2];
}

/* Linear RGB → YyCxCz ([F] §4.1: Lab without the cube root). */
static void linear_to_ycxcz(const double c[3], double o[3])
{
    double x[3];
    linear_to_xyz(c, x);
    for (int i = 0; i < 3; i++)
        x[i] /= WHITE[i];
    o[0] = 116.0 * x[1] - 16.0;
    o[1] = 500.0 * (x[0] - x[1]);
    o[2] = 200.0 * (x[1] - x[2]);
}

static void ycxcz_to_linear(const double v[3], double o[3])
{
    double y = (v[0] + 16.0) / 116.0;
    double x[3] = {(y + v[1] / 500.0) * WHITE[0], y * WHITE[1], (y - v[2] / 200.0) * WHITE[2]};
    xyz_to_linear(x, o);
}

static double lab_f(double t)
{
    const double d = 6.0 / 29.0;
    return t > d * d * d ? cbrt(t) : t / (3.0 * d * d) + 4.0 / 29.0;
}

/* Linear RGB → CIELab → Hunt-adjusted (a, b scaled by 0.01 L, [F] §4.2). */
static void linear_to_hunt_lab(const double c[3], double o[3])
{
    double x[3];
    linear_to_xyz(c, x);
    double f[3];
    for (int i = 0; i < 3; i++)
        f[i] = lab_f(x[i] / WHITE[i]);
    double L = 116.0 * f[1] - 16.0;
    o[0] = L;
    o[1] = 0.01 * L * 500.0 * (f[0] - f[1]);
    o[2] = 0.01 * L * 200.0 * (f[1] - f[2]);
}

/* HyAB ([F] Eq. 5). */
static double hyab(const double a[3], const double b[3])
{
    double da = a[1] - b[1], db = a[2] - b[2];
    return fabs(a[0] - b[0]) + sqrt(da * da + db * db);
}

static double cmax(void)
{
    static const double green[3] = {0, 1, 0}, blue[3] = {0, 0, 1};
    double g[3], b[3];
    linear_to_hunt_lab(green, g);
    linear_to_hunt_lab(blue, b);
    return pow(hyab(g, b), QC);
}

/* HyAB^q_c re-mapped into [0,1]: [0, p_c·c_max) onto [0, p_t), the rest onto [p_t, 1] ([F] Eq. 6). */
static double remap(double d, double cm)
{
    double e = pow(d, QC), pcm = PC * cm;
    return e < pcm ? e * PT / pcm : PT + (e - pcm) / (cm - pcm) * (1.0 - PT);
}

/* A 1-D kernel of 2r+1 taps. */
typedef struct kernel {
    int r;
    double *k;
} kernel;

/* o += k·p over n values; first: o = 0.0 + k·p, which is what zeroing o and adding gives (−0
 * included) without the zeroing pass. Vectorised: lane by lane the scalar operations. */
static inline void accumulate(double *restrict o, double k, const double *restrict p, size_t n, int first)
{
    if (first) {
#pragma omp simd
        for (size_t x = 0; x < n; x++)
            o[x] = 0.0 + k * p[x];
        return;
    }
#pragma omp simd
    for (size_t x = 0; x < n; x++)
        o[x] += k * p[x];
}

#define CONV_BLOCK 16
/* Four doubles; on the SSE2 clone two registers each. GCC's vector extension: element-wise IEEE
 * operations, so a lane computes what the scalar code does (no contraction: -ffp-contract=off). */
typedef double v4d __attribute__((vector_size(32)));
/* Outputs x0..x0+nb-1 of one row: src[i] is the row tap i reads (conv1). A full block keeps its
 * 16 sums in four named vectors: an array of them, or of 16 doubles, was kept on the stack and
 * loaded and stored per tap, slower than the old tap-by-tap loop (a replay of the CI run against
 * cornell-box-quads-ci: 1.36 vs 1.03 s, and 1.07 vs 0.98 s). */
static inline void conv_block(double *restrict o, const kernel *k, const double *const *src, size_t x0, int nb)
{
    const double *kk = k->k;
    if (nb == CONV_BLOCK) {
        const v4d zero = {0.0, 0.0, 0.0, 0.0};
        const double *p = src[0] + x0;
        double kv = kk[0]; /* scalar · vector: the scalar broadcast */
        v4d x0v, x1v, x2v, x3v;
        memcpy(&x0v, p, sizeof x0v);
        memcpy(&x1v, p + 4, sizeof x1v);
        memcpy(&x2v, p + 8, sizeof x2v);
        memcpy(&x3v, p + 12, sizeof x3v);
        v4d a0 = zero + kv * x0v, a1 = zero + kv * x1v, a2 = zero + kv * x2v, a3 = zero + kv * x3v;
        for (int i = 1; i <= 2 * k->r; i++) {
            p = src[i] + x0;
            kv = kk[i];
            memcpy(&x0v, p, sizeof x0v);
            memcpy(&x1v, p + 4, sizeof x1v);
            memcpy(&x2v, p + 8, sizeof x2v);
            memcpy(&x3v, p + 12, sizeof x3v);
            a0 = a0 + kv * x0v;
            a1 = a1 + kv * x1v;
            a2 = a2 + kv * x2v;
            a3 = a3 + kv * x3v;
        }
        memcpy(o + x0, &a0, sizeof a0);
        memcpy(o + x0 + 4, &a1, sizeof a1);
        memcpy(o + x0 + 8, &a2, sizeof a2);
        memcpy(o + x0 + 12, &a3, sizeof a3);
        return;
    }
    for (int j = 0; j < nb; j++) {
        double acc = 0.0 + kk[0] * src[0][x0 + (size_t)j];
        for (int i = 1; i <= 2 * k->r; i++)
            acc = acc + kk[i] * src[i][x0 + (size_t)j];
        o[x0 + (size_t)j] = acc;
    }
}

/* out = in convolved along x (dir 0) or y (dir 1) with k; edge pixels repeat. Each output is
 * the sum over the taps in increasing order, whatever the direction: 0.0 + k0·p0, then + ki·pi
 * tap by tap. A row is done CONV_BLOCK outputs at a time whose sums stay in registers through all
 * the taps (vectorised across x, each lane doing exactly the scalar sequence of multiplies and
 * adds, so the bits do not depend on the vector width or the block). pad: scratch of w + 2r
 * doubles. */
FLIP_CLONES static void conv1(const double *restrict in, double *restrict out, int w, int h, const kernel *k, int dir,
                              double *restrict pad, const double **src)
{
    int r = k->r;
    for (int y = 0; y < h; y++) {
        double *o = out + (size_t)y * (size_t)w;
        if (dir == 0) {
            const double *row = in + (size_t)y * (size_t)w;
            for (int x = -r; x < w + r; x++)
                pad[x + r] = row[x < 0 ? 0 : x >= w ? w - 1 : x];
        }
        for (int i = 0; i <= 2 * r; i++) {
            int yy = y + i - r < 0 ? 0 : y + i - r >= h ? h - 1 : y + i - r;
            src[i] = dir == 0 ? pad + i : in + (size_t)yy * (size_t)w;
        }
        for (int x0 = 0; x0 < w; x0 += CONV_BLOCK)
            conv_block(o, k, src, (size_t)x0, w - x0 < CONV_BLOCK ? w - x0 : CONV_BLOCK);
    }
}

void rep_flip_convolve(const double *in, double *out, int w, int h, const double *taps, int r, int dir)
{
    kernel k = {r, (double *)taps};
    double *pad = rep_xmalloc((size_t)(w + 2 * r + 1) * sizeof *pad);
    const double **src = rep_xmalloc((size_t)(2 * r + 1) * sizeof *src);
    conv1(in, out, w, h, &k, dir, pad, src);
    free(pad);
    free(src);
}

/* The filters for one ppd: per CSF channel up to two normalised 1-D Gaussians with the weight of
 * each in the normalised 2-D kernel ([F] Eq. 2–4); the feature kernels ([F] §5). */
typedef struct filters {
    kernel csf[3][2];
    double weight[3][2];
    kernel gauss, edge, point;
} filters;

static void filters_make(filters *f, double ppd)
{
    memset(f, 0, sizeof *f);
    int r = (int)ceil(3.0 * sqrt(CSF_B_MAX / (2.0 * PI * PI)) * ppd);
    double dx = 1.0 / ppd;
    for (int c = 0; c < 3; c++) {
        double total = 0, mass[2] = {0, 0};
        for (int t = 0; t < 2; t++) {
            double a = CSF[c][2 * t], b = CSF[c][2 * t + 1];
            if (a == 0)
                continue;
            kernel *k = &f->csf[c][t];
            k->r = r;
            k->k = rep_xmalloc((size_t)(2 * r + 1) * sizeof *k->k);
            double s = 0;
            for (int i = -r; i <= r; i++) {
                double xd = i * dx;
                k->k[i + r] = exp(-PI * PI * xd * xd / b);
                s += k->k[i + r];
            }
            for (int i = 0; i <= 2 * r; i++)
                k->k[i] /= s;
            mass[t] = a * sqrt(PI / b) * s * s; /* the 2-D kernel's sum, unnormalised */
            total += mass[t];
        }
        for (int t = 0; t < 2; t++)
            f->weight[c][t] = mass[t] / total;
    }
    double sd = 0.5 * FEATURE_W * ppd;
    int fr = (int)ceil(3.0 * sd);
    kernel *ks[3] = {&f->gauss, &f->edge, &f->point};
    for (int j = 0; j < 3; j++) {
        ks[j]->r = fr;
        ks[j]->k = rep_xmalloc((size_t)(2 * fr + 1) * sizeof(double));
    }
    double gs = 0, ep = 0, en = 0, pp = 0, pn = 0;
    for (int i = -fr; i <= fr; i++) {
        double g = exp(-(double)i * i / (2.0 * sd * sd));
        double e = -i * g, p = ((double)i * i / (sd * sd) - 1.0) * g;
        f->gauss.k[i + fr] = g;
        f->edge.k[i + fr] = e;
        f->point.k[i + fr] = p;
        gs += g;
        ep += e > 0 ? e : 0;
        en += e < 0 ? -e : 0;
        pp += p > 0 ? p : 0;
        pn += p < 0 ? -p : 0;
    }
    for (int i = 0; i <= 2 * fr; i++) {
        f->gauss.k[i] /= gs;
        f->edge.k[i] /= f->edge.k[i] > 0 ? ep : en;
        f->point.k[i] /= f->point.k[i] > 0 ? pp : pn;
    }
}

static void filters_free(filters *f)
{
    for (int c = 0; c < 3; c++)
        for (int t = 0; t < 2; t++)
            free(f->csf[c][t].k);
    free(f->gauss.k);
    free(f->edge.k);
    free(f->point.k);
}

/* Scratch of one image: its YyCxCz planes, the Hunt-Lab of the filtered image, feature norms. */
typedef struct side {
    double *opp[3];
    double *lab[3];
    double *edge, *point;
} side;

/* From the YyCxCz planes of one image: its filtered Hunt-Lab and its edge and point strengths.
 * t0..t3: scratch planes; pad: a scratch row, src: 2r + 1 row pointers (conv1). */
static void side_eval(side *s, const filters *f, int w, int h, double *t0, double *t1, double *t2, double *t3,
                      double *pad, const double **src)
{
    size_t n = (size_t)w * (size_t)h;
    double *filt[3];
    for (int c = 0; c < 3; c++) {
        filt[c] = s->lab[c]; /* filtered YyCxCz first, turned into Lab below */
        int first = 1;
        for (int t = 0; t < 2; t++) {
            if (!f->csf[c][t].k)
                continue;
            conv1(s->opp[c], t0, w, h, &f->csf[c][t], 0, pad, src);
            conv1(t0, t1, w, h, &f->csf[c][t], 1, pad, src);
            accumulate(filt[c], f->weight[c][t], t1, n, first);
            first = 0;
        }
    }
    for (size_t p = 0; p < n; p++) {
        double v[3] = {filt[0][p], filt[1][p], filt[2][p]}, rgb[3], lab[3];
        ycxcz_to_linear(v, rgb);
        for (int c = 0; c < 3; c++)
            rgb[c] = rgb[c] < 0 ? 0 : rgb[c] > 1 ? 1 : rgb[c];
        linear_to_hunt_lab(rgb, lab);
        for (int c = 0; c < 3; c++)
            s->lab[c][p] = lab[c];
    }
    /* features on the achromatic channel, normalised to [0,1] ([F] §5); the 2-D kernels are a
     * derivative along one axis times the Gaussian along the other */
    for (size_t p = 0; p < n; p++)
        t2[p] = (s->opp[0][p] + 16.0) / 116.0;
    conv1(t2, t3, w, h, &f->gauss, 0, pad, src); /* Gaussian along x, shared by both d/dy */
    const kernel *der[2] = {&f->edge, &f->point};
    double *out[2] = {s->edge, s->point};
    for (int j = 0; j < 2; j++) {
        conv1(t2, t0, w, h, der[j], 0, pad, src); /* d/dx */
        conv1(t0, t1, w, h, &f->gauss, 1, pad, src);
        for (size_t p = 0; p < n; p++)
            out[j][p] = t1[p] * t1[p];
        conv1(t3, t1, w, h, der[j], 1, pad, src); /* d/dy */
        for (size_t p = 0; p < n; p++)
            out[j][p] = sqrt(out[j][p] + t1[p] * t1[p]);
    }
}

static double clampv(float v, double hi)
{
    double c = v > 0 ? (double)v : 0.0; /* NaN, −Inf, negatives: 0 (selects, no branch: vectorisable) */
    return c > hi ? hi : c;
}

/* ACES fit of [H] Eq. 2 (Narkowicz's, with the 0.6 pre-scale folded in), clamped to [0,1]. */
static double aces(double x)
{
    const double k0 = 0.6 * 0.6 * 2.51, k1 = 0.6 * 0.03, k3 = 0.6 * 0.6 * 2.43, k4 = 0.6 * 0.59, k5 = 0.14;
    double y = (k0 * x * x + k1 * x) / (k3 * x * x + k4 * x + k5);
    return y < 0 ? 0 : y > 1 ? 1 : y;
}

/* The YyCxCz planes of an image: LDR from sRGB, HDR at exposure scale (2^c) through ACES. The HDR
 * loop has no library call and is vectorised (lane by lane the scalar operations). */
FLIP_CLONES static void to_opponent(const float *img, size_t n, int stride, rep_flip_kind kind, double scale, side *s)
{
    double *o0 = s->opp[0], *o1 = s->opp[1], *o2 = s->opp[2];
    if (kind == REP_FLIP_LDR) {
        for (size_t p = 0; p < n; p++) {
            double rgb[3], o[3];
            for (int c = 0; c < 3; c++)
                rgb[c] = srgb_to_linear(clampv(img[p * (size_t)stride + (size_t)c], 1.0));
            linear_to_ycxcz(rgb, o);
            o0[p] = o[0], o1[p] = o[1], o2[p] = o[2];
        }
        return;
    }
#pragma omp simd
    for (size_t p = 0; p < n; p++) {
        double rgb[3], o[3];
        for (int c = 0; c < 3; c++)
            rgb[c] = aces(scale * clampv(img[p * (size_t)stride + (size_t)c], 65536.0));
        linear_to_ycxcz(rgb, o);
        o0[p] = o[0], o1[p] = o[1], o2[p] = o[2];
    }
}

/* The exposures of d: their count, the first and the step ([H] §3: max(2, ⌈stop − start⌉)
 * exposures evenly spaced from start to stop); LDR: one, scale 2^0. */
static int exposure_range(const rep_flip_desc *d, double *start, double *step)
{
    *start = 0;
    *step = 0;
    if (!d || d->kind != REP_FLIP_HDR)
        return 1;
    double a = d->exposure_start, b = d->exposure_stop;
    if (a == 0 && b == 0)
        a = REP_FLIP_EXPOSURE_START, b = REP_FLIP_EXPOSURE_STOP;
    int n = (int)ceil(b - a);
    if (n < 2)
        n = 2;
    *start = a;
    *step = (b - a) / (n - 1);
    return n;
}

int rep_flip_exposures(const rep_flip_desc *d)
{
    double start, step;
    return exposure_range(d, &start, &step);
}

/* One exposure of rep_flip_map: the per-pixel ΔE of test against ref at exposure scale `scale`
 * (LDR: 1) into v[0..n-1], with scratch of its own (so exposures may run at once). */
static void flip_exposure(const float *test, const float *ref, int w, int h, int stride, rep_flip_kind kind,
                          const filters *f, double cm, double scale, double *v)
{
    size_t n = (size_t)w * (size_t)h;
    side s[2];
    for (int i = 0; i < 2; i++) {
        for (int c = 0; c < 3; c++) {
            s[i].opp[c] = rep_xmalloc(n * sizeof(double));
            s[i].lab[c] = rep_xmalloc(n * sizeof(double));
        }
        s[i].edge = rep_xmalloc(n * sizeof(double));
        s[i].point = rep_xmalloc(n * sizeof(double));
    }
    double *t0 = rep_xmalloc(n * sizeof(double)), *t1 = rep_xmalloc(n * sizeof(double)),
           *t2 = rep_xmalloc(n * sizeof(double)), *t3 = rep_xmalloc(n * sizeof(double));
    int rmax = f->csf[2][0].r > f->gauss.r ? f->csf[2][0].r : f->gauss.r;
    double *pad = rep_xmalloc((size_t)(w + 2 * rmax + 1) * sizeof(double));
    const double **src = rep_xmalloc((size_t)(2 * rmax + 1) * sizeof *src);

    to_opponent(test, n, stride, kind, scale, &s[0]);
    to_opponent(ref, n, stride, kind, scale, &s[1]);
    for (int i = 0; i < 2; i++)
        side_eval(&s[i], f, w, h, t0, t1, t2, t3, pad, src);
    for (size_t p = 0; p < n; p++) {
        double a[3] = {s[0].lab[0][p], s[0].lab[1][p], s[0].lab[2][p]};
        double b[3] = {s[1].lab[0][p], s[1].lab[1][p], s[1].lab[2][p]};
        double dc = remap(hyab(a, b), cm);
        double fe = fmax(fabs(s[0].edge[p] - s[1].edge[p]), fabs(s[0].point[p] - s[1].point[p]));
        double df = pow(fe / sqrt(2.0), QF);
        if (df > 1)
            df = 1;
        v[p] = pow(dc, 1.0 - df); /* [F] Eq. 9 */
    }
    for (int i = 0; i < 2; i++) {
        for (int c = 0; c < 3; c++) {
            free(s[i].opp[c]);
            free(s[i].lab[c]);
        }
        free(s[i].edge);
        free(s[i].point);
    }
    free(t0);
    free(t1);
    free(t2);
    free(t3);
    free(pad);
    free(src);
}

void rep_flip_map(const float *test, const float *ref, int w, int h, int stride, const rep_flip_desc *d, float *map)
{
    size_t n = (size_t)w * (size_t)h;
    rep_flip_desc def = {REP_FLIP_LDR, 0, 0, 0};
    if (!d || d->kind == REP_FLIP_NONE)
        d = &def;
    filters f;
    filters_make(&f, d->ppd > 0 ? d->ppd : REP_FLIP_PPD_DEFAULT);
    double cm = cmax();
    double start, step;
    int exposures = exposure_range(d, &start, &step);
    /* The exposures are independent: OpenMP tasks (inside replay's parallel region another thread
     * takes some, so an HDR buffer's 8 exposures no longer run on one thread at the end of a
     * frame); each keeps its ΔE per pixel, and the maximum is taken afterwards in exposure order
     * with the serial loop's comparison, so the map is the same bits. */
    double *v = rep_xmalloc((size_t)exposures * n * sizeof *v);
    rep_flip_kind kind = d->kind;
#pragma omp taskloop grainsize(1) default(none) shared(test, ref, w, h, stride, kind, f, cm, start, step, v, n, exposures)
    for (int e = 0; e < exposures; e++)
        flip_exposure(test, ref, w, h, stride, kind, &f, cm, exp2(start + e * step), v + (size_t)e * n);
    for (size_t p = 0; p < n; p++)
        map[p] = 0;
    for (int e = 0; e < exposures; e++) {
        const double *ve = v + (size_t)e * n;
        for (size_t p = 0; p < n; p++)
            if (ve[p] > map[p])
                map[p] = (float)ve[p];
    }
    free(v);
    filters_free(&f);
}

/* Nearest rank: the smallest value with at least q of the values at or below it. */
static double rank(const float *sorted, size_t n, double q)
{
    size_t k = (size_t)ceil(q * (double)n);
    return sorted[k > 0 ? k - 1 : 0];
}

void rep_flip_stats_of(const float *map, size_t n, rep_flip_stats *s)
{
    float *sorted = rep_xmalloc(n * sizeof *sorted);
    memcpy(sorted, map, n * sizeof *sorted);
    rep_sort_floats(sorted, n); /* was qsort: ~3 % of a differing replay's CPU */
    double sum = 0;
    for (size_t p = 0; p < n; p++)
        sum += map[p];
    s->mean = sum / (double)n;
    s->p50 = rank(sorted, n, 0.50);
    s->p95 = rank(sorted, n, 0.95);
    s->p99 = rank(sorted, n, 0.99);
    s->max = sorted[n - 1];
    s->exposures = 1;
    free(sorted);
}

void rep_flip_compute(const float *test, const float *ref, int w, int h, int stride, const rep_flip_desc *d,
                      rep_flip_stats *s)
{
    size_t n = (size_t)w * (size_t)h;
    float *map = rep_xmalloc(n * sizeof *map);
    rep_flip_map(test, ref, w, h, stride, d, map);
    rep_flip_stats_of(map, n, s);
    s->exposures = rep_flip_exposures(d);
    free(map);
}

double rep_flip_uniform_ldr(const double a[3], const double b[3])
{
    double la[3], lb[3], ha[3], hb[3];
    for (int c = 0; c < 3; c++) {
        la[c] = srgb_to_linear(a[c]);
        lb[c] = srgb_to_linear(b[c]);
    }
    linear_to_hunt_lab(la, ha);
    linear_to_hunt_lab(lb, hb);
    return remap(hyab(ha, hb), cmax());
}

/* Points of matplotlib's magma ramp (perceptually uniform, readable in grey) at t = 0, ¼, ½, ¾, 1;
 * linear in between. */
void rep_flip_heat_rgb(double t, unsigned char rgb[3])
{
    static const double P[5][3] = {{0.001462, 0.000466, 0.013866}, {0.316654, 0.071690, 0.485380},
                                   {0.716387, 0.214982, 0.474720}, {0.986700, 0.535582, 0.382210},
                                   {0.987053, 0.991438, 0.749504}};
    if (!(t > 0))
        t = 0;
    if (t > 1)
        t = 1;
    double u = t * 4.0;
    int i = u >= 4 ? 3 : (int)u;
    double f = u - i;
    for (int c = 0; c < 3; c++) {
        double v = P[i][c] + (P[i + 1][c] - P[i][c]) * f;
        rgb[c] = (unsigned char)lround(v * 255.0);
    }
}

unsigned char *rep_flip_heat(const float *map, int w, int h, int max_side, int *tw, int *th)
{
    int longest = w > h ? w : h;
    *tw = w, *th = h;
    if (max_side > 0 && longest > max_side) {
        *tw = (int)((long long)w * max_side / longest);
        *th = (int)((long long)h * max_side / longest);
        *tw = *tw < 1 ? 1 : *tw;
        *th = *th < 1 ? 1 : *th;
    }
    unsigned char *out = rep_xmalloc((size_t)*tw * (size_t)*th * 3);
    for (int ty = 0; ty < *th; ty++)
        for (int tx = 0; tx < *tw; tx++) {
            int x0 = (int)((long long)tx * w / *tw), x1 = (int)((long long)(tx + 1) * w / *tw);
            int y0 = (int)((long long)ty * h / *th), y1 = (int)((long long)(ty + 1) * h / *th);
            x1 = x1 > x0 ? x1 : x0 + 1;
            y1 = y1 > y0 ? y1 : y0 + 1;
            float m = 0; /* box maximum: one visible pixel survives the reduction */
            for (int y = y0; y < y1; y++)
                for (int x = x0; x < x1; x++)
                    m = map[(size_t)y * (size_t)w + (size_t)x] > m ? map[(size_t)y * (size_t)w + (size_t)x] : m;
            rep_flip_heat_rgb(m, out + ((size_t)ty * (size_t)*tw + (size_t)tx) * 3);
        }
    return out;
}
