/* codec_web.c - the image decoders behind textures and environment maps in the web build
 * (src/scene/image_codec.h): every format through stb_image, since libpng and libjpeg are
 * not there. The native build reads PNG and JPEG with those libraries and Radiance HDR
 * with its own reader (src/scene/image_codec.c), which refuse the malformed files stb's
 * 2022 readers mishandle; the page loads the scene files it ships, so the web build takes
 * stb's readers as they are. Decoded texels are the same for PNG, TGA, BMP and HDR; JPEG
 * may differ in the last bit where stb's IDCT rounds otherwise than libjpeg-turbo's. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "scene/image_codec.h"
#include "scene/texture.h"

#define STBI_MAX_DIMENSIONS TR_TEXTURE_MAX_SIDE
#define STBI_NO_STDIO
#define STBI_FAILURE_USERMSG
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wmissing-prototypes"
#include <stb_image.h>

tr_codec tr_codec_of(const unsigned char *data, size_t len) {
    static const unsigned char png_signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (len >= 8 && memcmp(data, png_signature, 8) == 0) {
        return TR_CODEC_PNG;
    }
    if (len >= 3 && data[0] == 0xff && data[1] == 0xd8 && data[2] == 0xff) {
        return TR_CODEC_JPEG;
    }
    if (len >= 2 && data[0] == '#' && data[1] == '?') {
        return TR_CODEC_HDR;
    }
    return TR_CODEC_STB;
}

static int not_decoded(const char *name, tr_error *err) {
    return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': cannot decode (%s)", name,
                        stbi_failure_reason() ? stbi_failure_reason() : "unknown");
}

int tr_codec_info(const unsigned char *data, size_t len, const char *name, int *width, int *height,
                  tr_error *err) {
    int comp;
    if (len > INT32_MAX || !stbi_info_from_memory(data, (int)len, width, height, &comp)) {
        return tr_error_set(err, TR_STATUS_PARSE,
                            "'%.200s': not an image in a format read here (PNG, JPEG, Radiance "
                            "HDR, TGA, BMP)",
                            name);
    }
    return TR_OK;
}

int tr_codec_rgba8(const unsigned char *data, size_t len, const char *name, unsigned char **out,
                   int *width, int *height, tr_error *err) {
    int comp;
    *out = len > INT32_MAX ? NULL : stbi_load_from_memory(data, (int)len, width, height, &comp, 4);
    return *out ? TR_OK : not_decoded(name, err);
}

int tr_codec_hdr_rgbf(const unsigned char *data, size_t len, const char *name, float **out,
                      int *width, int *height, tr_error *err) {
    int comp;
    if (tr_codec_of(data, len) != TR_CODEC_HDR) {
        *out = NULL;
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': not a Radiance HDR image", name);
    }
    *out = len > INT32_MAX ? NULL : stbi_loadf_from_memory(data, (int)len, width, height, &comp, 3);
    return *out ? TR_OK : not_decoded(name, err);
}
