/* texture.h - decoding images for the scene (src/scene/texture.c, image_codec.c). */
#ifndef TR_SCENE_TEXTURE_H
#define TR_SCENE_TEXTURE_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/error.h"
#include "trac0r/scene.h"

/* Limits checked against an image's header before it is decoded. */
#define TR_TEXTURE_MAX_SIDE 16384
#define TR_TEXTURE_MAX_TEXELS (1u << 26)
#define TR_IMAGE_MAX_FILE_BYTES (512u << 20)

/* Reads a whole regular file (not a FIFO or device) of at most TR_IMAGE_MAX_FILE_BYTES. */
int tr_read_image_file(const char *path, unsigned char **data, size_t *len, tr_error *err);
/* 0 when data is a PNG (by its signature) one of whose chunks, up to IEND, declares more
 * bytes than the data holds; 1 otherwise (also for every other format). */
int tr_png_chunks_fit(const unsigned char *data, size_t len);
/* The most texels one byte of data can encode in its format (known by its signature; 64
 * for formats without one): a header that declares more than this times the file's
 * length is refused before decoding. */
uint32_t tr_image_max_texels_per_byte(const unsigned char *data, size_t len);
/* Decodes an image (PNG, JPEG, Radiance HDR, TGA or BMP: image_codec.h) to RGBA8
 * texels, R in the low byte, top row first (*out: caller frees). `name` is for messages. */
int tr_image_decode_rgba8(const unsigned char *data, size_t len, const char *name, uint32_t **out,
                          uint32_t *width, uint32_t *height, tr_error *err);
/* Decodes an image to linear float RGB, 3 floats a texel (*out: caller frees). */
int tr_image_decode_rgbf(const unsigned char *data, size_t len, const char *name, float **out,
                         uint32_t *width, uint32_t *height, tr_error *err);
/* Decodes an image and adds it to the scene as a texture (tr_scene_add_texture). */
int tr_scene_load_texture_memory(tr_scene *s, const unsigned char *data, size_t len,
                                 const char *name, uint32_t flags, uint32_t *index, tr_error *err);
int tr_scene_load_texture(tr_scene *s, const char *path, uint32_t flags, uint32_t *index,
                          tr_error *err);

#endif
