/* image.h - writing films out, and reading float images back.
 *
 * Every writer writes to a temporary file next to the target and renames it into
 * place, so a failure never leaves a partial image behind. */
#ifndef TRAC0R_IMAGE_H
#define TRAC0R_IMAGE_H

#include <stdint.h>

#include "trac0r/error.h"
#include "trac0r/film.h"

typedef enum tr_image_format {
    TR_IMAGE_UNKNOWN = 0,
    TR_IMAGE_PNG = 1, /* 8-bit sRGB, tonemapped */
    TR_IMAGE_PFM = 2, /* 32-bit float linear RGB */
    TR_IMAGE_EXR = 3, /* OpenEXR, half or float linear RGB, passes as layers */
} tr_image_format;

/* The format named by a path's extension (case-insensitive), or TR_IMAGE_UNKNOWN. */
tr_image_format tr_image_format_from_path(const char *path);

/* Writes the film's mean radiance as PNG (tonemapped with `exposure` stops by
 * tr_tonemap_film, post.h) or PFM, chosen by the path's extension. */
int tr_film_write(const tr_film *f, const char *path, float exposure, tr_error *err);
/* The same, a PNG through display curve `curve` (TR_TONEMAP_*, post.h; TR_TONEMAP_CLAMP is
 * tr_film_write's own transform); PFM and EXR stay linear whatever the curve. */
int tr_film_write_curve(const tr_film *f, const char *path, float exposure, int curve,
                        tr_error *err);
int tr_film_write_png(const tr_film *f, const char *path, float exposure, tr_error *err);
int tr_film_write_pfm(const tr_film *f, const char *path, tr_error *err);

/* Writes the film as OpenEXR (src/io/exr.c): the mean radiance as R, G, B, and the
 * passes it keeps as layers albedo.{R,G,B}, normal.{X,Y,Z}, depth.Z, id (UINT) and
 * variance.{R,G,B} (the variance of the mean radiance, tr_film_variance); half or float
 * channels (`half` nonzero: half). ZIP-compressed scanlines. */
int tr_film_write_exr(const tr_film *f, const char *path, int half, tr_error *err);
/* The same with R, G, B from `rgb` (a film of f's size: a filtered image of f) and the
 * layers, the variance included, from f. */
int tr_film_write_exr_rgb(const tr_film *f, const tr_film *rgb, const char *path, int half,
                          tr_error *err);

/* Checks, without leaving anything behind, that a file can be created at path's
 * directory (so a long render is not wasted on an unwritable target). */
int tr_image_check_writable(const char *path, tr_error *err);

/* A float RGB image read back from disk (top row first). */
typedef struct tr_image {
    uint32_t width, height;
    float *rgb;
} tr_image;

int tr_image_read_pfm(tr_image *img, const char *path, tr_error *err);
/* Reads an 8-bit PNG as values in [0,1] (no inverse transfer applied). */
int tr_image_read_png(tr_image *img, const char *path, tr_error *err);
/* Reads layer `layer`'s channels of an OpenEXR image as floats (NULL: the unnamed layer,
 * R, G, B): LAYER.R/G/B, else LAYER.X/Y/Z, else LAYER.Z in all three. Scanline images. */
int tr_image_read_exr(tr_image *img, const char *path, const char *layer, tr_error *err);
/* Reads an image as linear RGB by its extension: .pfm and .exr (its R, G, B) as they are,
 * .png decoded from sRGB to linear. TR_STATUS_UNSUPPORTED for another extension. */
int tr_image_read(tr_image *img, const char *path, tr_error *err);
void tr_image_free(tr_image *img);

#endif
