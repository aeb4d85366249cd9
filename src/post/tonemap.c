/* tonemap.c - the host side of the display transform: wraps the single-source
 * operator of src/post/tonemap.h for one value and for a rectangle of a film. */
#include <math.h>
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

int tr_tonemap_film(const struct tr_film *film, uint32_t x, uint32_t y, uint32_t width,
                    uint32_t height, float exposure, tr_pixel_format format, void *dst,
                    size_t dst_stride, tr_error *err) {
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
            const uint32_t rgb =
                tr_tonemap_film_pixel(sum[3 * i], sum[3 * i + 1], sum[3 * i + 2], count[i], scale);
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
