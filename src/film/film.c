/* film.c - the float accumulation buffer. */
#include <stdlib.h>
#include <string.h>

#include "kernel/vec.h"
#include "trac0r/film.h"

int tr_film_init(tr_film *f, uint32_t width, uint32_t height, tr_error *err) {
    memset(f, 0, sizeof *f);
    if (width == 0 || height == 0) {
        return tr_error_set(err, "image size %ux%u must be at least 1x1", width, height);
    }
    if (width > TR_FILM_MAX_SIDE || height > TR_FILM_MAX_SIDE ||
        (uint64_t)width * height > TR_FILM_MAX_PIXELS) {
        return tr_error_set(err, "image size %ux%u exceeds the limit of %u per side and %u pixels",
                            width, height, TR_FILM_MAX_SIDE, TR_FILM_MAX_PIXELS);
    }
    size_t n = (size_t)width * height;
    f->sum = calloc(3 * n, sizeof *f->sum);
    f->count = calloc(n, sizeof *f->count);
    if (!f->sum || !f->count) {
        tr_film_free(f);
        return tr_error_set(err, "out of memory allocating a %ux%u film", width, height);
    }
    f->width = width;
    f->height = height;
    return TR_OK;
}

void tr_film_free(tr_film *f) {
    free(f->sum);
    free(f->count);
    memset(f, 0, sizeof *f);
}

void tr_film_clear(tr_film *f) {
    size_t n = (size_t)f->width * f->height;
    memset(f->sum, 0, 3 * n * sizeof *f->sum);
    memset(f->count, 0, n * sizeof *f->count);
}

tr_vec3 tr_film_pixel(const tr_film *f, uint32_t x, uint32_t y) {
    size_t i = (size_t)y * f->width + x;
    uint32_t c = f->count[i];
    if (c == 0) {
        return v3s(0.0f);
    }
    float inv = 1.0f / (float)c;
    return v3(f->sum[3 * i] * inv, f->sum[3 * i + 1] * inv, f->sum[3 * i + 2] * inv);
}
