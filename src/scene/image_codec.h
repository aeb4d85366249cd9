/* image_codec.h - the decoders behind textures and environment maps
 * (src/scene/image_codec.c): PNG through libpng, JPEG through libjpeg(-turbo), Radiance HDR
 * read here, TGA and BMP through stb_image. The callers (src/scene/texture.c) check the
 * declared size against the limits between tr_codec_info and the decode. */
#ifndef TR_SCENE_IMAGE_CODEC_H
#define TR_SCENE_IMAGE_CODEC_H

#include <stddef.h>

#include "trac0r/error.h"

typedef enum { TR_CODEC_PNG, TR_CODEC_JPEG, TR_CODEC_HDR, TR_CODEC_STB } tr_codec;

/* The decoder for data, by its signature; data without one (TGA) goes to stb_image. */
tr_codec tr_codec_of(const unsigned char *data, size_t len);
/* The size the header declares, without decoding the texels; a parse error naming `name`
 * when there is no header that decoder reads. */
int tr_codec_info(const unsigned char *data, size_t len, const char *name, int *width, int *height,
                  tr_error *err);
/* Decodes to 8-bit RGBA, 4 bytes a texel, top row first (*out: free()). HDR images come
 * through stb_image's mapping to 8 bits (gamma 1/2.2, clamped). */
int tr_codec_rgba8(const unsigned char *data, size_t len, const char *name, unsigned char **out,
                   int *width, int *height, tr_error *err);
/* Decodes a Radiance HDR image to linear float RGB, 3 floats a texel (*out: free()). */
int tr_codec_hdr_rgbf(const unsigned char *data, size_t len, const char *name, float **out,
                      int *width, int *height, tr_error *err);

#endif
