/* exposure.c — `"exposure": "auto"`: the exposure in stops that maps a frame's log-average
 * luminance to middle grey. The log average is Reinhard et al. 2002, "Photographic Tone
 * Reproduction for Digital Images" (SIGGRAPH), Eq. 1: L̄ = exp(1/N Σ log(δ + L(x, y))), the
 * scene's key; Eq. 2 scales luminance by a / L̄ with the "normal" key a = 0.18, which as an
 * exposure in stops is log2(0.18 / L̄). None of the project's papers meter exposure.
 *
 * Deterministic by construction: one thread, pixels in row-major order, every term and the sum
 * in double, so the number depends on the pixels only (never on thread count or scheduling). */
#include "eng_core.h"

#include <math.h>

void eng_exposure_key(const float *rgb, const float *coverage, size_t pixels, eng_exposure_key_info *out)
{
    double sum = 0.0;
    uint64_t counted = 0, nonfinite = 0;
    for (size_t i = 0; i < pixels; i++) {
        if (coverage && coverage[i] == 0.0f)
            continue;
        const float *p = rgb + 3 * i;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2])) {
            nonfinite++;
            continue;
        }
        /* Rec. 709 / sRGB primaries (ITU-R BT.709-6 item 3.2), linear radiance. */
        double y = 0.2126 * (double)p[0] + 0.7152 * (double)p[1] + 0.0722 * (double)p[2];
        if (!(y > 0.0))
            continue; /* black (and negative) pixels say nothing about the key */
        sum += log(ENG_EXPOSURE_DELTA + y);
        counted++;
    }
    out->counted = counted;
    out->nonfinite = nonfinite;
    out->log_average = 0.0;
    out->stops = 0.0f;
    if (!counted)
        return;
    out->log_average = exp(sum / (double)counted);
    double stops = log2(ENG_EXPOSURE_GREY / out->log_average);
    if (stops > ENG_EXPOSURE_MAX)
        stops = ENG_EXPOSURE_MAX;
    if (stops < -ENG_EXPOSURE_MAX)
        stops = -ENG_EXPOSURE_MAX;
    out->stops = (float)stops;
}
