/* tonemap.c - the host side of the display transform: wraps the single-source
 * operator of src/post/tonemap.h for one value and for a rectangle of a film. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "post/tonemap.h"
#include "trac0r/film.h"
#include "trac0r/post.h"

uint8_t tr_tonemap_srgb8(float linear, float exposure) {
    return (uint8_t)tr_tonemap_srgb8_scaled(linear, exp2f(exposure));
}

float tr_srgb_to_linear(float encoded) {
    return tr_srgb_decode(encoded);
}

const char *tr_tonemap_curve_name(int curve) {
    return curve == TR_TONEMAP_CLAMP ? "clamp" : curve == TR_TONEMAP_FILMIC ? "filmic" : NULL;
}

int tr_tonemap_curve_parse(const char *name) {
    return strcmp(name, "clamp") == 0    ? TR_TONEMAP_CLAMP
           : strcmp(name, "filmic") == 0 ? TR_TONEMAP_FILMIC
                                         : -1;
}

int tr_tonemap_film(const struct tr_film *film, uint32_t x, uint32_t y, uint32_t width,
                    uint32_t height, float exposure, tr_pixel_format format, void *dst,
                    size_t dst_stride, tr_error *err) {
    return tr_tonemap_film_curve(film, x, y, width, height, exposure, TR_TONEMAP_CLAMP, format, dst,
                                 dst_stride, err);
}

int tr_tonemap_display_film(const struct tr_film *in, float exposure, int curve,
                            struct tr_film *out, tr_error *err) {
    if (!tr_tonemap_curve_name(curve)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tonemap: unknown curve %d", curve);
    }
    if (tr_film_init(out, in->width, in->height, err) != TR_OK) {
        return TR_ERR;
    }
    const float scale = exp2f(exposure);
    const size_t n = (size_t)in->width * in->height;
    for (size_t i = 0; i < n; ++i) {
        /* The mean as the tonemap takes it (a reciprocal, then products), so that this
         * film written at exposure 0 gives the bytes of the direct tonemap. */
        const float inv = in->count[i] ? 1.0f / (float)in->count[i] : 0.0f;
        for (int k = 0; k < 3; ++k) {
            out->sum[3 * i + k] =
                in->count[i] ? tr_tonemap_curve(in->sum[3 * i + k] * inv, scale, curve) : 0.0f;
        }
        out->count[i] = in->count[i] ? 1u : 0u;
    }
    return TR_OK;
}

int tr_tonemap_film_curve(const struct tr_film *film, uint32_t x, uint32_t y, uint32_t width,
                          uint32_t height, float exposure, int curve, tr_pixel_format format,
                          void *dst, size_t dst_stride, tr_error *err) {
    if (!tr_tonemap_curve_name(curve)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tonemap: unknown curve %d", curve);
    }
    if (width == 0 || height == 0 || x > film->width || width > film->width - x ||
        y > film->height || height > film->height - y) {
        return tr_error_set(
            err, TR_STATUS_INVALID_ARGUMENT,
            "tonemap: rectangle %ux%u at (%u, %u) is empty or outside the %ux%u film", width,
            height, x, y, film->width, film->height);
    }
    size_t bytes_per_pixel = format == TR_PIXEL_RGB8 ? 3 : format == TR_PIXEL_ARGB8888 ? 4 : 0;
    if (bytes_per_pixel == 0) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tonemap: unknown pixel format %d",
                            (int)format);
    }
    if (dst_stride < bytes_per_pixel * width) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tonemap: row stride %zu is less than a row of %zu bytes", dst_stride,
                            bytes_per_pixel * width);
    }
    const float scale = exp2f(exposure);
    const float *sum = film->sum;
    const uint32_t *count = film->count;
    const size_t fw = film->width;
    /* Serial on purpose: the PNG writer calls this per row, and the viewer from its
     * render thread, whose --threads limit a thread team here would ignore (and whose
     * idle OpenMP workers would spin against the render). A caller that wants threads
     * splits the film into rectangles; a device runs one work item per pixel. */
    for (uint32_t r = 0; r < height; ++r) {
        const size_t row = ((size_t)y + r) * fw + x;
        unsigned char *out = (unsigned char *)dst + (size_t)r * dst_stride;
        for (uint32_t c = 0; c < width; ++c) {
            const size_t i = row + c;
            const uint32_t rgb = tr_tonemap_film_pixel_curve(
                sum[3 * i], sum[3 * i + 1], sum[3 * i + 2], count[i], scale, curve);
            if (format == TR_PIXEL_RGB8) {
                out[3 * c] = (unsigned char)(rgb >> 16);
                out[3 * c + 1] = (unsigned char)(rgb >> 8);
                out[3 * c + 2] = (unsigned char)rgb;
            } else {
                const uint32_t argb = 0xff000000u | rgb;
                memcpy(out + 4 * (size_t)c, &argb, sizeof argb); /* any alignment of dst */
            }
        }
    }
    return TR_OK;
}

int tr_image_exposure_note(const struct tr_film *film, float exposure, char *buf, size_t n) {
    if (n > 0) {
        buf[0] = '\0';
    }
    const size_t px = (size_t)film->width * film->height;
    float *rgb = px ? malloc(3 * px * sizeof *rgb) : NULL;
    if (!rgb) {
        return 0;
    }
    tr_film_mean(film, rgb);
    /* Displayed black: below half an 8-bit sRGB step (1/510 encoded is about 1.2e-4
     * linear); clipped: every channel at or above 1. */
    const float scale = exp2f(exposure);
    size_t black = 0, white = 0, sampled = 0;
    double sum = 0.0;
    for (size_t i = 0; i < px; ++i) {
        if (film->count[i] == 0) {
            continue;
        }
        const float r = rgb[3 * i] * scale, g = rgb[3 * i + 1] * scale, b = rgb[3 * i + 2] * scale;
        ++sampled;
        black += r < 1.2e-4f && g < 1.2e-4f && b < 1.2e-4f;
        white += r >= 1.0f && g >= 1.0f && b >= 1.0f;
        sum += (r + g + b) / 3.0;
    }
    free(rgb);
    if (sampled == 0) {
        return 0;
    }
    if (black >= sampled - sampled / 1000) {
        snprintf(buf, n,
                 "the image is black (mean %.3g): no light reaches the camera; it may sit "
                 "inside geometry, or the lights may be hidden, pointed away or too weak "
                 "(a higher exposure shows what little there is)",
                 sum / (double)sampled);
        return 1;
    }
    if (white >= sampled - sampled / 100) {
        snprintf(buf, n,
                 "the image is white (mean %.3g): nearly every pixel is clipped; the lights or "
                 "the environment may be far too bright for this exposure, or the materials "
                 "white (a lower exposure or a darker environment shows the shapes)",
                 sum / (double)sampled);
        return 2;
    }
    return 0;
}
