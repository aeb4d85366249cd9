/* compare.h - image error metrics shared by `trac0r compare` and
 * `trac0r bench convergence`. */
#ifndef TRAC0R_COMPARE_H
#define TRAC0R_COMPARE_H

#include <stddef.h>

#include "trac0r/trac0r.h"

/* The epsilon of the relative MSE's denominator, B^2 + epsilon. */
#define COMPARE_REL_EPSILON 0.01

typedef struct image_error {
    double mse, rmse, relmse;
    double psnr; /* dB, peak 1; +inf for identical images */
} image_error;

/* Errors of `a` against the reference `ref` (3 floats per pixel, linear RGB), each
 * value clamped to [0,1] (NaN counts as 0). */
image_error compare_images(const float *a, const float *ref, size_t pixels);

/* Reads a .pfm (linear) or .png (sRGB, decoded to linear) image. */
int compare_load(const char *path, tr_image *img, tr_error *err);

#endif
