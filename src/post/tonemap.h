/* tonemap.h - the display transform, per value and per film pixel: exposure, clamp to
 * [0,1], the sRGB transfer function, 8 bits.
 *
 * Single source like src/kernel/: C99 that also compiles as OpenCL C 1.2 (compat.h), so
 * that a device can tonemap its own film before the read-back. The host's
 * tr_tonemap_srgb8 and tr_tonemap_film (src/post/tonemap.c) wrap these functions; the PNG
 * writer and the viewer both go through them, so a PNG and the viewer's window show the
 * same bytes.
 *
 * The exposure arrives as its scale 2^exposure, computed once per image by the caller:
 * a device then has no exp2 per pixel, and the host's result stays bit-identical to
 * `linear * exp2f(exposure)`. A device's pow may differ from glibc's powf by an ulp
 * (OpenCL does not require correct rounding), so a device-tonemapped byte can differ by
 * one where a value sits on a rounding boundary; includers on a device set
 * FP_CONTRACT OFF as entry.cl does. */
#ifndef TR_POST_TONEMAP_H
#define TR_POST_TONEMAP_H

#include "../kernel/compat.h"

/* Linear [0,1] to the sRGB-encoded [0,1]: IEC 61966-2-1's transfer function. */
TR_FN float tr_srgb_encode(float v) {
    return v <= 0.0031308f ? 12.92f * v : 1.055f * tr_powf(v, 1.0f / 2.4f) - 0.055f;
}

/* The inverse: sRGB-encoded [0,1] back to linear (IEC 61966-2-1). */
TR_FN float tr_srgb_decode(float c) {
    return c <= 0.04045f ? c / 12.92f : tr_powf((c + 0.055f) / 1.055f, 2.4f);
}

/* One linear value, scaled by `scale` (2^exposure), to an 8-bit sRGB code 0..255.
 * Everything not above 0 (negatives, -0, NaN) is black; 1 and above (+inf) is white. */
TR_FN uint32_t tr_tonemap_srgb8_scaled(float linear, float scale) {
    const float v = linear * scale;
    if (!(v > 0.0f)) { /* also catches NaN */
        return 0u;
    }
    if (v >= 1.0f) {
        return 255u;
    }
    /* s lies in (0, 1]: s * 255 + 0.5 rounds to nearest and stays below 256. */
    return (uint32_t)(tr_srgb_encode(v) * 255.0f + 0.5f);
}

/* Display curves (post.h's tr_tonemap_curve): 0 clamps, 1 is the filmic curve. */
#define TR_CURVE_CLAMP 0
#define TR_CURVE_FILMIC 1

/* A filmic curve: Krzysztof Narkowicz's rational fit of the ACES reference rendering
 * transform with the output transform for an sRGB display ("ACES Filmic Tone Mapping
 * Curve", 2016), applied per channel. It rolls highlights off towards 1 instead of
 * clipping them (the lamp and its glow keep their shape) and darkens the toe slightly;
 * Narkowicz's fit expects the input pre-scaled by 0.6, which is folded in here so that
 * exposure 0 keeps mid-grey near where the clamp puts it. The fit rises past 1 near
 * x = 11 (its asymptote is 2.51 / 2.43); tr_tonemap_curve clips it there. */
TR_FN float tr_filmic_aces(float x) {
    const float v = 0.6f * x;
    return (v * (2.51f * v + 0.03f)) / (v * (2.43f * v + 0.59f) + 0.14f);
}

/* The display-referred linear value of `linear` scaled by `scale` through `curve`:
 * what the sRGB transfer then encodes. NaN and everything not above 0 are 0; the clamp's
 * values above 1 stay (the encoder clips them). */
TR_FN float tr_tonemap_curve(float linear, float scale, int curve) {
    const float v = linear * scale;
    if (!(v > 0.0f)) { /* also catches NaN */
        return 0.0f;
    }
    if (curve == TR_CURVE_FILMIC) {
        return v < 1e30f ? tr_fminf(tr_filmic_aces(v), 1.0f) : 1.0f;
    }
    return v;
}

/* One film pixel (the sum of its samples' radiance and their count) to 0x00RRGGBB:
 * its mean radiance sum * (1 / count), tonemapped per channel; black where no sample
 * landed. The mean is taken as tr_film_pixel takes it (a reciprocal, then products),
 * so that the bytes match a tonemap of tr_film_pixel's value. */
TR_FN uint32_t tr_tonemap_film_pixel(float sum_r, float sum_g, float sum_b, uint32_t count,
                                     float scale) {
    if (count == 0u) {
        return 0u;
    }
    const float inv = 1.0f / (float)count;
    const uint32_t r = tr_tonemap_srgb8_scaled(sum_r * inv, scale);
    const uint32_t g = tr_tonemap_srgb8_scaled(sum_g * inv, scale);
    const uint32_t b = tr_tonemap_srgb8_scaled(sum_b * inv, scale);
    return (r << 16) | (g << 8) | b;
}

/* The same through `curve`; TR_CURVE_CLAMP gives tr_tonemap_film_pixel's bytes. */
TR_FN uint32_t tr_tonemap_film_pixel_curve(float sum_r, float sum_g, float sum_b, uint32_t count,
                                           float scale, int curve) {
    if (curve == TR_CURVE_CLAMP) {
        return tr_tonemap_film_pixel(sum_r, sum_g, sum_b, count, scale);
    }
    if (count == 0u) {
        return 0u;
    }
    const float inv = 1.0f / (float)count;
    const uint32_t r = tr_tonemap_srgb8_scaled(tr_tonemap_curve(sum_r * inv, scale, curve), 1.0f);
    const uint32_t g = tr_tonemap_srgb8_scaled(tr_tonemap_curve(sum_g * inv, scale, curve), 1.0f);
    const uint32_t b = tr_tonemap_srgb8_scaled(tr_tonemap_curve(sum_b * inv, scale, curve), 1.0f);
    return (r << 16) | (g << 8) | b;
}

#endif
