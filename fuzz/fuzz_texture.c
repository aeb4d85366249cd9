/* fuzz_texture.c - libFuzzer target for texture decoding (src/scene/texture.c, stb_image):
 * every input goes through both decoders; a decoded image must have the size its
 * header promised within the limits. Seeded by fuzz/run.sh with tests/data/texture/. */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdlib.h>

#include "scene/texture.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    tr_error err;
    uint32_t *rgba = NULL, w = 0, h = 0;
    if (tr_image_decode_rgba8(data, size, "fuzz", &rgba, &w, &h, &err) == TR_OK) {
        if (!rgba || w == 0 || h == 0 || w > TR_TEXTURE_MAX_SIDE || h > TR_TEXTURE_MAX_SIDE) {
            abort();
        }
        free(rgba);
    }
    float *rgb = NULL;
    if (tr_image_decode_rgbf(data, size, "fuzz", &rgb, &w, &h, &err) == TR_OK) {
        if (!rgb || w == 0 || h == 0) {
            abort();
        }
        free(rgb);
    }
    return 0;
}
