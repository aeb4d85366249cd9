/* post.h - what happens to a film after rendering: tonemapping for display and files,
 * and the error metrics of an image against a reference.
 *
 * Usage:
 *
 *     uint32_t *argb = malloc(w * h * 4);   (the viewer's texture)
 *     tr_tonemap_film(&film, 0, 0, w, h, exposure, TR_PIXEL_ARGB8888, argb, w * 4, &err);
 *
 *     tr_image_metrics m = tr_image_compare(a.rgb, ref.rgb, (size_t)w * h);
 *     printf("rmse %g psnr %g dB\n", m.rmse, m.psnr);
 *
 * The per-pixel tonemap is single-source (src/post/tonemap.h) so that a device can run
 * it too; these functions are its host side. Plain C99 / C++, no kernel headers. */
#ifndef TRAC0R_POST_H
#define TRAC0R_POST_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/error.h"

#ifdef __cplusplus
extern "C" {
#endif

struct tr_film;

/* ---- Tonemapping --------------------------------------------------------------- */

/* Tonemaps one linear value: scale by 2^exposure, clamp to [0,1] (NaN and negatives
 * are black), sRGB transfer, 8 bits. */
uint8_t tr_tonemap_srgb8(float linear, float exposure);

/* The sRGB transfer function's inverse: an sRGB-encoded value in [0,1] to linear. */
float tr_srgb_to_linear(float encoded);

typedef enum tr_pixel_format {
    TR_PIXEL_RGB8 = 1,     /* 3 bytes per pixel: R, G, B */
    TR_PIXEL_ARGB8888 = 2, /* one uint32_t per pixel, 0xAARRGGBB with alpha 255 */
} tr_pixel_format;

/* Tonemaps the film's mean radiance in the rectangle at (x, y) of size width x height
 * into dst (row r of the rectangle at dst + r * dst_stride bytes; pixels where no
 * sample landed are black), exactly as tr_tonemap_srgb8 maps each channel. Runs on the
 * calling thread only (split the film into rectangles for more). Fails on a rectangle
 * outside the film, an empty one, an unknown format or a stride smaller than a row. */
int tr_tonemap_film(const struct tr_film *film, uint32_t x, uint32_t y, uint32_t width,
                    uint32_t height, float exposure, tr_pixel_format format, void *dst,
                    size_t dst_stride, tr_error *err);

/* ---- Image metrics ------------------------------------------------------------- */

/* The epsilon of the relative MSE's denominator, ref^2 + epsilon. */
#define TR_RELMSE_EPSILON 0.01

/* Errors of an image against a reference, over every pixel and channel, on values
 * clamped to [0,1] (NaN counts as 0). */
typedef struct tr_image_metrics {
    double mse;       /* mean of (a - ref)^2 */
    double rmse;      /* sqrt(mse) */
    double relmse;    /* mean of (a - ref)^2 / (ref^2 + TR_RELMSE_EPSILON) */
    double psnr;      /* tr_psnr(mse): dB, peak 1; +inf for identical images */
    double max_error; /* the largest tr_pixel_error over the pixels */
} tr_image_metrics;

/* Metrics of `a` against the reference `ref` (3 floats per pixel, linear RGB). The
 * sums run in pixel order, so the result never depends on the thread count. */
tr_image_metrics tr_image_compare(const float *a, const float *ref, size_t pixels);

/* One pixel's error: the mean over R, G, B of |a - ref| on values clamped as above. */
double tr_pixel_error(const float *a_rgb, const float *ref_rgb);

/* Peak signal-to-noise ratio of an MSE, peak 1: 10 log10(1 / mse) dB; +inf where mse is
 * not above 0. */
double tr_psnr(double mse);

#ifdef __cplusplus
}
#endif

#endif
