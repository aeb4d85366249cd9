/* metrics.c - error metrics of an image against a reference: what `trac0r compare`
 * prints and what `trac0r bench convergence` plots. */
#include <math.h>

#include "trac0r/post.h"

/* The metrics compare displayable radiance: [0,1], with NaN as black. */
static double clamp01(double v) {
    return v != v ? 0.0 : v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v;
}

double tr_psnr(double mse) {
    return mse > 0.0 ? 10.0 * log10(1.0 / mse) : INFINITY;
}

double tr_pixel_error(const float *a_rgb, const float *ref_rgb) {
    double d = 0.0;
    for (int c = 0; c < 3; ++c) {
        d += fabs(clamp01(a_rgb[c]) - clamp01(ref_rgb[c]));
    }
    return d / 3.0;
}

tr_image_metrics tr_image_compare(const float *a, const float *ref, size_t pixels) {
    double se = 0.0, rel = 0.0, max = 0.0;
    /* One sequential pass in pixel and channel order: the sums' rounding, and with it
     * every printed digit, is the same on every run. */
    for (size_t p = 0; p < pixels; ++p) {
        for (size_t c = 0; c < 3; ++c) {
            const double x = clamp01(a[3 * p + c]), y = clamp01(ref[3 * p + c]);
            const double d = x - y;
            se += d * d;
            rel += d * d / (y * y + TR_RELMSE_EPSILON);
        }
        const double e = tr_pixel_error(a + 3 * p, ref + 3 * p);
        max = e > max ? e : max;
    }
    tr_image_metrics m;
    const double n = 3.0 * (double)pixels;
    m.mse = se / n;
    m.rmse = sqrt(m.mse);
    m.relmse = rel / n;
    m.psnr = tr_psnr(m.mse);
    m.max_error = max;
    return m;
}
