/* film.c - the float accumulation buffer and its passes. */
#include <stdlib.h>
#include <string.h>

#include "kernel/types.h"
#include "trac0r/film.h"

int tr_film_check_size(uint32_t width, uint32_t height, tr_error *err) {
    if (width == 0 || height == 0) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "image size %ux%u must be at least 1x1", width, height);
    }
    if (width > TR_FILM_MAX_SIDE || height > TR_FILM_MAX_SIDE ||
        (uint64_t)width * height > TR_FILM_MAX_PIXELS) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "image size %ux%u exceeds the limit of %u per side and %u pixels",
                            width, height, TR_FILM_MAX_SIDE, TR_FILM_MAX_PIXELS);
    }
    return TR_OK;
}

int tr_film_init(tr_film *f, uint32_t width, uint32_t height, tr_error *err) {
    return tr_film_init_passes(f, width, height, 0u, err);
}

/* The layout (film.h): per array, the pass that keeps it and its bytes per pixel. */
static const uint32_t array_pass[TR_FILM_ARRAYS] = {0u,
                                                    0u,
                                                    TR_PASS_ALBEDO,
                                                    TR_PASS_NORMAL,
                                                    TR_PASS_DEPTH,
                                                    TR_PASS_PRIM,
                                                    TR_PASS_VARIANCE,
                                                    TR_PASS_DIRECT,
                                                    TR_PASS_EMISSION,
                                                    TR_PASS_SPECULAR};
static const size_t array_bytes[TR_FILM_ARRAYS] = {
    3 * sizeof(float), sizeof(uint32_t),  3 * sizeof(float), 3 * sizeof(float), sizeof(float),
    sizeof(uint32_t),  3 * sizeof(float), 3 * sizeof(float), 3 * sizeof(float), 8 * sizeof(float)};

uint32_t tr_film_array_pass(int i) {
    return i >= 0 && i < TR_FILM_ARRAYS ? array_pass[i] : 0u;
}

size_t tr_film_array_pixel_bytes(int i) {
    return i >= 0 && i < TR_FILM_ARRAYS ? array_bytes[i] : 0u;
}

void *tr_film_array_data(const tr_film *f, int i) {
    switch (i) {
    case 0:
        return f->sum;
    case 1:
        return f->count;
    case 2:
        return f->albedo;
    case 3:
        return f->normal;
    case 4:
        return f->depth;
    case 5:
        return f->prim;
    case 6:
        return f->sq;
    case 7:
        return f->direct;
    case 8:
        return f->emission;
    case 9:
        return f->specular;
    default:
        return NULL;
    }
}

/* Sets array i of f to p (the film's members are typed; the layout is not). */
static void set_array(tr_film *f, int i, void *p) {
    switch (i) {
    case 0:
        f->sum = p;
        break;
    case 1:
        f->count = p;
        break;
    case 2:
        f->albedo = p;
        break;
    case 3:
        f->normal = p;
        break;
    case 4:
        f->depth = p;
        break;
    case 5:
        f->prim = p;
        break;
    case 6:
        f->sq = p;
        break;
    case 7:
        f->direct = p;
        break;
    case 9:
        f->specular = p;
        break;
    default:
        f->emission = p;
        break;
    }
}

size_t tr_film_pixel_bytes(uint32_t passes) {
    size_t b = 0;
    for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
        b += array_pass[i] == 0u || (passes & array_pass[i]) != 0u ? array_bytes[i] : 0u;
    }
    return b;
}

int tr_film_init_passes(tr_film *f, uint32_t width, uint32_t height, uint32_t passes,
                        tr_error *err) {
    memset(f, 0, sizeof *f);
    if (tr_film_check_size(width, height, err) != TR_OK) {
        return TR_ERR;
    }
    if ((passes & ~TR_PASS_MASK) != 0u) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "unknown pass bits 0x%x",
                            passes & ~TR_PASS_MASK);
    }
    const size_t n = (size_t)width * height;
    int ok = 1;
    for (int i = 0; i < TR_FILM_ARRAYS && ok; ++i) {
        if (array_pass[i] == 0u || (passes & array_pass[i]) != 0u) {
            void *p = calloc(n, array_bytes[i]);
            set_array(f, i, p);
            ok = p != NULL;
        }
    }
    if (!ok) {
        tr_film_free(f);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory allocating a %ux%u film",
                            width, height);
    }
    f->width = width;
    f->height = height;
    f->passes = passes;
    return TR_OK;
}

void tr_film_free(tr_film *f) {
    for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
        free(tr_film_array_data(f, i));
    }
    memset(f, 0, sizeof *f);
}

void tr_film_clear(tr_film *f) {
    const size_t n = (size_t)f->width * f->height;
    for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
        void *p = tr_film_array_data(f, i);
        if (p) {
            memset(p, 0, n * array_bytes[i]);
        }
    }
}

/* Copies rectangle r of f's arrays to `out` (packing) or from `in` (unpacking), `size`
 * bytes there. */
static int copy_rect(const tr_film *f, const tr_rect *r, unsigned char *out,
                     const unsigned char *in, size_t size, tr_error *err) {
    if (!r || r->width == 0 || r->height == 0 || r->x >= f->width || r->y >= f->height ||
        r->width > f->width - r->x || r->height > f->height - r->y) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the rectangle is not inside the %ux%u film", f->width, f->height);
    }
    const size_t need = tr_film_pixel_bytes(f->passes) * r->width * r->height;
    if ((!out && !in) || size < need) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "a %ux%u rectangle of the film takes %zu bytes, the buffer has %zu",
                            r->width, r->height, need, size);
    }
    size_t at = 0;
    for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
        unsigned char *a = tr_film_array_data(f, i);
        if (!a) {
            continue;
        }
        const size_t row = (size_t)r->width * array_bytes[i];
        for (uint32_t y = r->y; y < r->y + r->height; ++y) {
            unsigned char *film_row = a + ((size_t)y * f->width + r->x) * array_bytes[i];
            if (out) {
                memcpy(out + at, film_row, row);
            } else {
                memcpy(film_row, in + at, row);
            }
            at += row;
        }
    }
    return TR_OK;
}

int tr_film_pack_rect(const tr_film *f, const tr_rect *r, void *buf, size_t size, tr_error *err) {
    return copy_rect(f, r, buf, NULL, buf ? size : 0u, err);
}

int tr_film_unpack_rect(tr_film *f, const tr_rect *r, const void *buf, size_t size, tr_error *err) {
    return copy_rect(f, r, NULL, buf, buf ? size : 0u, err);
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

/* Whether `pass` is one pass bit that f keeps. */
static int keeps_pass(const tr_film *f, uint32_t pass) {
    return tr_pass_name(pass) != NULL && (f->passes & pass) != 0u;
}

float tr_film_variance(const tr_film *f, size_t i, int c) {
    const uint32_t n = f->count[i];
    if (n < 2u) {
        return 0.0f;
    }
    const double s = f->sum[3 * i + (size_t)c], q = f->sq[3 * i + (size_t)c];
    const double var = (q - s * s / n) / (double)(n - 1u) / (double)n;
    return var > 0.0 ? (float)var : 0.0f;
}

int tr_film_pass_pixel(const tr_film *f, uint32_t pass, uint32_t x, uint32_t y, float out[3],
                       tr_error *err) {
    out[0] = out[1] = out[2] = 0.0f;
    if (!keeps_pass(f, pass)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "the film does not keep pass 0x%x",
                            pass);
    }
    if (x >= f->width || y >= f->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "pixel (%u, %u) is outside the %ux%u film", x, y, f->width, f->height);
    }
    size_t i = (size_t)y * f->width + x;
    uint32_t c = f->count[i];
    if (pass == TR_PASS_PRIM) {
        out[0] = (float)f->prim[i];
        return TR_OK;
    }
    if (pass == TR_PASS_VARIANCE) {
        for (int k = 0; k < 3; ++k) {
            out[k] = tr_film_variance(f, i, k);
        }
        return TR_OK;
    }
    if (c == 0) {
        return TR_OK;
    }
    float inv = 1.0f / (float)c;
    if (pass == TR_PASS_DEPTH) {
        out[0] = f->depth[i] * inv;
        return TR_OK;
    }
    if (pass == TR_PASS_SPECULAR) { /* its specular radiance, the first 3 of 8 */
        for (int k = 0; k < 3; ++k) {
            out[k] = f->specular[8 * i + (size_t)k] * inv;
        }
        return TR_OK;
    }
    const float *src = pass == TR_PASS_ALBEDO     ? f->albedo
                       : pass == TR_PASS_DIRECT   ? f->direct
                       : pass == TR_PASS_EMISSION ? f->emission
                                                  : f->normal;
    for (int k = 0; k < 3; ++k) {
        out[k] = src[3 * i + (size_t)k] * inv;
    }
    return TR_OK;
}

static void add_floats(float *dst, const float *src, size_t n) {
    if (dst && src) {
        for (size_t i = 0; i < n; ++i) {
            dst[i] += src[i];
        }
    }
}

int tr_film_accumulate(tr_film *dst, const tr_film *src, tr_error *err) {
    if (dst->width != src->width || dst->height != src->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "cannot add a %ux%u film to a %ux%u one", src->width, src->height,
                            dst->width, dst->height);
    }
    if ((dst->passes & ~src->passes) != 0u) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "the film added lacks passes 0x%x",
                            dst->passes & ~src->passes);
    }
    const size_t n = (size_t)dst->width * dst->height;
    if (dst->prim) {
        for (size_t i = 0; i < n; ++i) {
            if (dst->count[i] == 0u && src->count[i] != 0u) {
                dst->prim[i] = src->prim[i];
            }
        }
    }
    add_floats(dst->sum, src->sum, 3 * n);
    add_floats(dst->albedo, src->albedo, 3 * n);
    add_floats(dst->normal, src->normal, 3 * n);
    add_floats(dst->depth, src->depth, n);
    add_floats(dst->sq, src->sq, 3 * n);
    add_floats(dst->direct, src->direct, 3 * n);
    add_floats(dst->emission, src->emission, 3 * n);
    add_floats(dst->specular, src->specular, 8 * n);
    for (size_t i = 0; i < n; ++i) {
        dst->count[i] += src->count[i];
    }
    return TR_OK;
}

int tr_film_extract_pass(const tr_film *f, uint32_t pass, tr_film *out, tr_error *err) {
    if (!keeps_pass(f, pass)) {
        memset(out, 0, sizeof *out);
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "the film does not keep pass 0x%x",
                            pass);
    }
    if (tr_film_init(out, f->width, f->height, err) != TR_OK) {
        return TR_ERR;
    }
    const size_t n = (size_t)f->width * f->height;
    for (size_t i = 0; i < n; ++i) {
        if (pass == TR_PASS_PRIM) {
            /* One sample of the id itself: exact up to 2^24. */
            out->count[i] = 1u;
            out->sum[3 * i] = out->sum[3 * i + 1] = out->sum[3 * i + 2] = (float)f->prim[i];
            continue;
        }
        if (pass == TR_PASS_VARIANCE) {
            /* One sample of the variance itself (a mean of the sums would not be one). */
            out->count[i] = 1u;
            for (int c = 0; c < 3; ++c) {
                out->sum[3 * i + (size_t)c] = tr_film_variance(f, i, c);
            }
            continue;
        }
        out->count[i] = f->count[i];
        for (int c = 0; c < 3; ++c) {
            const size_t k = 3 * i + (size_t)c;
            out->sum[k] = pass == TR_PASS_ALBEDO     ? f->albedo[k]
                          : pass == TR_PASS_NORMAL   ? f->normal[k]
                          : pass == TR_PASS_DIRECT   ? f->direct[k]
                          : pass == TR_PASS_EMISSION ? f->emission[k]
                          : pass == TR_PASS_SPECULAR ? f->specular[8 * i + (size_t)c]
                                                     : f->depth[i];
        }
    }
    return TR_OK;
}

const char *tr_pass_name(uint32_t pass) {
    switch (pass) {
    case TR_PASS_ALBEDO:
        return "albedo";
    case TR_PASS_NORMAL:
        return "normal";
    case TR_PASS_DEPTH:
        return "depth";
    case TR_PASS_PRIM:
        return "id";
    case TR_PASS_VARIANCE:
        return "variance";
    case TR_PASS_DIRECT:
        return "direct";
    case TR_PASS_EMISSION:
        return "emission";
    case TR_PASS_SPECULAR:
        return "specular";
    default:
        return NULL;
    }
}

void tr_film_mean(const tr_film *f, float *rgb) {
    const size_t n = (size_t)f->width * f->height;
    for (size_t i = 0; i < n; ++i) {
        const float inv = f->count[i] ? 1.0f / (float)f->count[i] : 0.0f;
        for (int c = 0; c < 3; ++c) {
            rgb[3 * i + c] = f->sum[3 * i + c] * inv;
        }
    }
}
