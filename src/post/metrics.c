/* metrics.c - error metrics of an image against a reference: what `trac0r compare`
 * prints and what `trac0r bench convergence` plots. */
#include <math.h>
#include <stdlib.h>

#include "trac0r/film.h"
#include "trac0r/image.h"
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

/* Luminance of a clamped pixel: SSIM is taken on one channel, as usual for colour. */
static double clamped_luma(const float *rgb) {
    return 0.2126 * clamp01(rgb[0]) + 0.7152 * clamp01(rgb[1]) + 0.0722 * clamp01(rgb[2]);
}

/* Wang, Bovik, Sheikh and Simoncelli, "Image Quality Assessment: From Error Visibility to
 * Structural Similarity", IEEE TIP 13(4), 2004: local means, variances and covariance
 * under an 11x11 Gaussian window (sigma 1.5, cut at the border and renormalised), the
 * SSIM index per pixel with C1 = (0.01 L)^2, C2 = (0.03 L)^2 for L = 1, averaged. */
double tr_ssim(const float *a, const float *ref, uint32_t width, uint32_t height) {
    const size_t n = (size_t)width * height;
    double *buf = malloc(7 * n * sizeof *buf);
    if (!buf || n == 0) {
        free(buf);
        return NAN;
    }
    double *x = buf, *y = buf + n, *mom[5];
    for (int k = 0; k < 5; ++k) {
        mom[k] = buf + (2 + k) * n;
    }
    for (size_t i = 0; i < n; ++i) {
        x[i] = clamped_luma(a + 3 * i);
        y[i] = clamped_luma(ref + 3 * i);
    }
    double g[11];
    for (int k = -5; k <= 5; ++k) {
        g[k + 5] = exp(-(double)(k * k) / (2.0 * 1.5 * 1.5));
    }
    /* mom: E[x], E[y], E[x^2], E[y^2], E[xy], blurred separably: rows into `row`, then
     * columns into mom[k]. */
    double *row = malloc(n * sizeof *row);
    if (!row) {
        free(buf);
        return NAN;
    }
    for (int k = 0; k < 5; ++k) {
        for (uint32_t r = 0; r < height; ++r) {
            for (uint32_t c = 0; c < width; ++c) {
                double s = 0.0, w = 0.0;
                for (int d = -5; d <= 5; ++d) {
                    const long cc = (long)c + d;
                    if (cc < 0 || cc >= (long)width) {
                        continue;
                    }
                    const size_t i = (size_t)r * width + (size_t)cc;
                    const double v = k == 0   ? x[i]
                                     : k == 1 ? y[i]
                                     : k == 2 ? x[i] * x[i]
                                     : k == 3 ? y[i] * y[i]
                                              : x[i] * y[i];
                    s += g[d + 5] * v;
                    w += g[d + 5];
                }
                row[(size_t)r * width + c] = s / w;
            }
        }
        for (uint32_t r = 0; r < height; ++r) {
            for (uint32_t c = 0; c < width; ++c) {
                double s = 0.0, w = 0.0;
                for (int d = -5; d <= 5; ++d) {
                    const long rr = (long)r + d;
                    if (rr < 0 || rr >= (long)height) {
                        continue;
                    }
                    s += g[d + 5] * row[(size_t)rr * width + c];
                    w += g[d + 5];
                }
                mom[k][(size_t)r * width + c] = s / w;
            }
        }
    }
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
    double sum = 0.0;
    for (size_t i = 0; i < n; ++i) {
        const double mx = mom[0][i], my = mom[1][i];
        const double vx = mom[2][i] - mx * mx, vy = mom[3][i] - my * my;
        const double cxy = mom[4][i] - mx * my;
        sum +=
            ((2.0 * mx * my + c1) * (2.0 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
    }
    free(row);
    free(buf);
    return sum / (double)n;
}

/* A perceptually ordered false-colour ramp (black, blue, magenta, orange, yellow, white)
 * for t in [0, 1], as linear RGB for the writers to encode. */
static void false_colour(double t, float *out) {
    static const float ramp[6][3] = {{0.0f, 0.0f, 0.0f},  {0.1f, 0.1f, 0.6f}, {0.7f, 0.1f, 0.6f},
                                     {1.0f, 0.5f, 0.05f}, {1.0f, 0.9f, 0.2f}, {1.0f, 1.0f, 1.0f}};
    t = (t > 0.0 ? (t < 1.0 ? t : 1.0) : 0.0) * 5.0;
    const int i = t >= 5.0 ? 4 : (int)t;
    const float f = (float)(t - i);
    for (int k = 0; k < 3; ++k) {
        out[k] = tr_srgb_to_linear(ramp[i][k] + f * (ramp[i + 1][k] - ramp[i][k]));
    }
}

int tr_error_map_write(const float *a, const float *ref, uint32_t width, uint32_t height,
                       double max, const char *path, tr_error *err) {
    tr_film f;
    if (tr_film_init(&f, width, height, err) != TR_OK) {
        return TR_ERR;
    }
    const size_t pixels = (size_t)width * height;
    for (size_t i = 0; i < pixels; ++i) {
        const double d = tr_pixel_error(a + 3 * i, ref + 3 * i);
        false_colour(max > 0.0 ? d / max : 0.0, f.sum + 3 * i);
        f.count[i] = 1;
    }
    const int rc = tr_film_write(&f, path, 0.0f, err);
    tr_film_free(&f);
    return rc;
}
