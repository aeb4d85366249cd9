/* film.h - the float accumulation buffer: a sum of radiance and a sample count per
 * pixel. Tonemapping happens only when the film is written out (image.h). */
#ifndef TRAC0R_FILM_H
#define TRAC0R_FILM_H

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
} tr_film;

/* Allocates a cleared film. Fails (without allocating) on a zero size or one beyond
 * TR_FILM_MAX_SIDE / TR_FILM_MAX_PIXELS, or when memory runs out. */
int tr_film_init(tr_film *f, uint32_t width, uint32_t height, tr_error *err);
void tr_film_free(tr_film *f);
/* Forgets every sample (keeps the allocation). */
void tr_film_clear(tr_film *f);
/* The mean radiance of pixel (x, y): black where no sample has landed. */
tr_vec3 tr_film_pixel(const tr_film *f, uint32_t x, uint32_t y);

#endif
