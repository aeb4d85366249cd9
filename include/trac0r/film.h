/* film.h - the float accumulation buffer: per pixel a sum of radiance and a sample count,
 * and, for the passes asked for (TR_PASS_*), sums of albedo, normal and depth, the
 * primitive id of the pixel's first sample, sums of squared radiance (the variance), of
 * direct radiance (TR_PASS_DIRECT) and of the first hit's emission (TR_PASS_EMISSION).
 * Tonemapping
 * happens only when the film is written out (image.h). Two films of one size merge exactly: sums
 * and counts add. */
#ifndef TRAC0R_FILM_H
#define TRAC0R_FILM_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/types.h"
#include "trac0r/error.h"

/* The largest image libtrac0r allocates: each side and the total pixel count. */
#define TR_FILM_MAX_SIDE 16384u
#define TR_FILM_MAX_PIXELS (64u * 1024u * 1024u)

typedef struct tr_film {
    uint32_t width, height;
    float *sum;      /* 3 floats (linear RGB) per pixel, row-major, top row first */
    uint32_t *count; /* samples accumulated per pixel */
    uint32_t passes; /* TR_PASS_* this film keeps; the arrays of the others are NULL */
    float *albedo;   /* TR_PASS_ALBEDO: 3 floats per pixel, summed like radiance */
    float *normal;   /* TR_PASS_NORMAL: 3 floats per pixel, summed */
    float *depth;    /* TR_PASS_DEPTH: 1 float per pixel, summed */
    uint32_t *prim;  /* TR_PASS_PRIM: triangle index + 1 of the pixel's first sample, 0: none */
    float *sq;       /* TR_PASS_VARIANCE: 3 floats per pixel, sums of squared radiance */
    float *direct;   /* TR_PASS_DIRECT: 3 floats per pixel, sums of direct radiance */
    float *emission; /* TR_PASS_EMISSION: 3 floats per pixel, sums of the first hit's emission */
    float *specular; /* TR_PASS_SPECULAR: 8 floats per pixel (types.h), summed */
} tr_film;

/* A rectangle of pixels: columns x .. x+width-1, rows y .. y+height-1. */
typedef struct tr_rect {
    uint32_t x, y, width, height;
} tr_rect;

/* The film's layout, described once: its arrays in a fixed order - the radiance sums, the
 * counts, then one array per pass in TR_PASS_* bit order (albedo, normal, depth, id,
 * variance, direct, emission, specular) - each kept always (pass 0) or when the film keeps its
 * pass. Everything that copies a film whole or in part (a device's read-back, checkpoints, the
 * tiles of a distributed render) walks this list, so a pass added to the film travels with
 * it everywhere. */
#define TR_FILM_ARRAYS 10
/* The pass bit that keeps array i (0: always kept), and its bytes per pixel; 0 for both
 * when i is not in 0..TR_FILM_ARRAYS-1. */
uint32_t tr_film_array_pass(int i);
size_t tr_film_array_pixel_bytes(int i);
/* Array i of f, or NULL when f does not keep it. */
void *tr_film_array_data(const tr_film *f, int i);
/* The bytes one pixel takes in all the arrays a film keeping `passes` has. */
size_t tr_film_pixel_bytes(uint32_t passes);

/* Copies rectangle r of every array f keeps, in layout order and row by row, to buf (at
 * least tr_film_pixel_bytes(f->passes) * r->width * r->height bytes: `size`), or back from
 * buf into f. Fails on a rectangle outside the film or a buffer too small. */
int tr_film_pack_rect(const tr_film *f, const tr_rect *r, void *buf, size_t size, tr_error *err);
int tr_film_unpack_rect(tr_film *f, const tr_rect *r, const void *buf, size_t size, tr_error *err);

/* Checks, allocating nothing, that a film of width x height may be made: at least 1x1
 * (TR_STATUS_INVALID_ARGUMENT), within TR_FILM_MAX_SIDE / TR_FILM_MAX_PIXELS
 * (TR_STATUS_LIMIT). */
int tr_film_check_size(uint32_t width, uint32_t height, tr_error *err);
/* Allocates a cleared film keeping radiance only. Fails (without allocating) on a zero
 * size or one beyond TR_FILM_MAX_SIDE / TR_FILM_MAX_PIXELS, or when memory runs out. */
int tr_film_init(tr_film *f, uint32_t width, uint32_t height, tr_error *err);
/* The same, also keeping the passes in the TR_PASS_* mask `passes`. */
int tr_film_init_passes(tr_film *f, uint32_t width, uint32_t height, uint32_t passes,
                        tr_error *err);
void tr_film_free(tr_film *f);
/* Forgets every sample (keeps the allocation). */
void tr_film_clear(tr_film *f);
/* The mean radiance of pixel (x, y): black where no sample has landed. */
tr_vec3 tr_film_pixel(const tr_film *f, uint32_t x, uint32_t y);
/* The mean of pass `pass` (one TR_PASS_* bit the film keeps) at pixel (x, y) in out[0..2]
 * (depth and the primitive id in out[0], the others zero); zeros where no sample landed.
 * For TR_PASS_VARIANCE it is the variance of the pixel's mean radiance, per channel
 * (tr_film_variance); zeros below two samples. */
int tr_film_pass_pixel(const tr_film *f, uint32_t pass, uint32_t x, uint32_t y, float out[3],
                       tr_error *err);
/* The mean radiance of every pixel, 3 floats per pixel, into rgb (zeros where no sample
 * landed). */
void tr_film_mean(const tr_film *f, float *rgb);
/* Adds src's samples to dst: sums and counts add, a primitive id is taken from src where
 * dst has none. The films must have one size, and src must keep every pass dst keeps.
 * Pixel by pixel this is exact where at most one of the two has samples (a render split
 * into rectangles comes back bit for bit); where both have, it is one float addition per
 * sum, as when the two sample ranges had been accumulated apart and then added. */
int tr_film_accumulate(tr_film *dst, const tr_film *src, tr_error *err);
/* A new radiance-only film (free it with tr_film_free) whose pixels' means are pass
 * `pass` of f: albedo, normal, the variance, direct radiance and emission as RGB, depth and the
 * primitive id in all three channels (the id as a float, exact up to 2^24); for writing a pass as
 * an image. */
int tr_film_extract_pass(const tr_film *f, uint32_t pass, tr_film *out, tr_error *err);
/* The variance of the mean radiance of pixel i (row-major index), channel c, from a film
 * keeping TR_PASS_VARIANCE: with n samples, sum S and sum of squares Q, the unbiased
 * sample variance (Q - S^2/n) / (n - 1) over n, in double precision from the float sums
 * and clamped at 0 (rounding can make a constant pixel's difference slightly negative);
 * 0 below two samples. */
float tr_film_variance(const tr_film *f, size_t i, int c);
/* "albedo", "normal", "depth", "id", "variance", "direct", "emission" for one TR_PASS_* bit; NULL
 * for anything else. */
const char *tr_pass_name(uint32_t pass);

#endif
