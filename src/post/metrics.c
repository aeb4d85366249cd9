/* metrics.c - error metrics of an image against a reference: what `trac0r compare`
 * prints and what `trac0r bench convergence` plots. */
#include <math.h>
#include <stdlib.h>

#include "trac0r/film.h"
#include "trac0r/image.h"
#include "trac0r/measure.h"
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

/* measure.h; kept beside tr_image_compare, whose clamp it shares. */
double tr_image_flicker(const float *a, const float *a_prev, const float *r, const float *r_prev,
                        size_t pixels) {
    static const double luma[3] = {0.2126, 0.7152, 0.0722};
    double s = 0.0;
    for (size_t i = 0; i < pixels; ++i) {
        double d = 0.0;
        for (int k = 0; k < 3; ++k) {
            const size_t j = 3 * i + (size_t)k;
            const double va = clamp01(a[j]) - clamp01(a_prev[j]);
            const double vr = clamp01(r[j]) - clamp01(r_prev[j]);
            d += luma[k] * (va - vr);
        }
        s += d * d;
    }
    return pixels ? sqrt(s / (double)pixels) : 0.0;
}

/* Luminance of a clamped pixel: SSIM is taken on one channel, as usual for colour. */
static double clamped_luma(const float *rgb) {
    return 0.2126 * clamp01(rgb[0]) + 0.7152 * clamp01(rgb[1]) + 0.0722 * clamp01(rgb[2]);
}

/* Wang, Bovik, Sheikh and Simoncelli, "Image Quality Assessment: From Error Visibility to
 * Structural Similarity", IEEE TIP 13(4), 2004: local means, variances and covariance
 * under an 11x11 Gaussian window (sigma 1.5, cut at the border and renormalised), the
 * SSIM index per pixel with C1 = (0.01 L)^2, C2 = (0.03 L)^2 for L = 1, averaged.
 *
 * The image is taken in bands of rows, each band by one thread: the five moments (x, y,
 * x^2, y^2, xy) of the band's rows and of the 5 rows either side are blurred along the
 * rows into the thread's buffer, then down the columns, and each row's SSIM sum is kept.
 * The rows' sums are added in row order, so the result does not depend on the number of
 * threads. At 3840x2160 this is what lets `bench realtime` score a 4K frame in a fraction
 * of a second; one pass per moment over the whole image took seconds. */
enum { SSIM_R = 5, SSIM_BAND = 32 };

/* The moments of row `r` blurred along the row into out (5 doubles per pixel). lx, ly:
 * width doubles each, the row's luminances; wc[c]: 1 / the window's weight at column c. */
static void ssim_row(const float *a, const float *ref, uint32_t width, uint32_t r, const double *g,
                     const double *wc, double *lx, double *ly, double *out) {
    const float *pa = a + (size_t)3 * width * r, *pr = ref + (size_t)3 * width * r;
    for (uint32_t c = 0; c < width; ++c) {
        lx[c] = clamped_luma(pa + 3 * c);
        ly[c] = clamped_luma(pr + 3 * c);
    }
    for (uint32_t c = 0; c < width; ++c) {
        const long lo = (long)c - SSIM_R < 0 ? -(long)c : -SSIM_R;
        const long hi = (long)c + SSIM_R >= (long)width ? (long)width - 1 - (long)c : SSIM_R;
        double m[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
        for (long d = lo; d <= hi; ++d) {
            const double w = g[d + SSIM_R], x = lx[(long)c + d], y = ly[(long)c + d];
            m[0] += w * x;
            m[1] += w * y;
            m[2] += w * x * x;
            m[3] += w * y * y;
            m[4] += w * x * y;
        }
        for (int k = 0; k < 5; ++k) {
            out[5 * (size_t)c + (size_t)k] = m[k] * wc[c];
        }
    }
}

double tr_ssim(const float *a, const float *ref, uint32_t width, uint32_t height) {
    const size_t n = (size_t)width * height;
    if (n == 0) {
        return NAN;
    }
    double g[2 * SSIM_R + 1];
    for (int k = -SSIM_R; k <= SSIM_R; ++k) {
        g[k + SSIM_R] = exp(-(double)(k * k) / (2.0 * 1.5 * 1.5));
    }
    /* wn[c]: 1 / the window's weight along a row at column c, cut at the border. */
    double *wn = malloc(width * sizeof *wn), *rowsum = malloc(height * sizeof *rowsum);
    if (!wn || !rowsum) {
        free(wn);
        free(rowsum);
        return NAN;
    }
    for (uint32_t c = 0; c < width; ++c) {
        double w = 0.0;
        for (int d = -SSIM_R; d <= SSIM_R; ++d) {
            w += (long)c + d >= 0 && (long)c + d < (long)width ? g[d + SSIM_R] : 0.0;
        }
        wn[c] = 1.0 / w;
    }
    int failed = 0;
    const uint32_t bands = (height + SSIM_BAND - 1) / SSIM_BAND;
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
#pragma omp parallel if (n >= 65536) reduction(| : failed)
    {
        const size_t rows = SSIM_BAND + 2 * SSIM_R;
        double *hm = malloc((rows * 5 + 2) * width * sizeof *hm);
        failed |= !hm;
#pragma omp for schedule(dynamic)
        for (uint32_t b = 0; b < bands; ++b) {
            if (!hm) {
                continue;
            }
            const uint32_t r0 = b * SSIM_BAND,
                           r1 = r0 + SSIM_BAND < height ? r0 + SSIM_BAND : height;
            const uint32_t h0 = r0 >= SSIM_R ? r0 - SSIM_R : 0;
            const uint32_t h1 = r1 + SSIM_R < height ? r1 + SSIM_R : height;
            double *lx = hm + rows * 5 * width, *ly = lx + width;
            for (uint32_t r = h0; r < h1; ++r) {
                ssim_row(a, ref, width, r, g, wn, lx, ly, hm + (size_t)(r - h0) * 5 * width);
            }
            for (uint32_t r = r0; r < r1; ++r) {
                /* The column window of row r, cut at the image's top and bottom, in
                 * rows of the band's buffer. The border weight is the row's own. */
                const uint32_t lo = r >= SSIM_R ? r - SSIM_R : 0;
                const uint32_t hi = r + SSIM_R < height ? r + SSIM_R : height - 1;
                double wr = 0.0;
                for (uint32_t q = lo; q <= hi; ++q) {
                    wr += g[(long)q - (long)r + SSIM_R];
                }
                wr = 1.0 / wr;
                double sum = 0.0;
                for (uint32_t c = 0; c < width; ++c) {
                    double m[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
                    for (uint32_t q = lo; q <= hi; ++q) {
                        const double w = g[(long)q - (long)r + SSIM_R];
                        const double *v = hm + (size_t)(q - h0) * 5 * width + 5 * (size_t)c;
                        for (int k = 0; k < 5; ++k) {
                            m[k] += w * v[k];
                        }
                    }
                    const double mx = m[0] * wr, my = m[1] * wr;
                    const double vx = m[2] * wr - mx * mx, vy = m[3] * wr - my * my;
                    const double cxy = m[4] * wr - mx * my;
                    sum += ((2.0 * mx * my + c1) * (2.0 * cxy + c2)) /
                           ((mx * mx + my * my + c1) * (vx + vy + c2));
                }
                rowsum[r] = sum;
            }
        }
        free(hm);
    }
    double sum = 0.0;
    for (uint32_t r = 0; !failed && r < height; ++r) {
        sum += rowsum[r];
    }
    free(wn);
    free(rowsum);
    return failed ? NAN : sum / (double)n;
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
