/* texture.c - images for textures (RGBA8) and environment maps (float RGB), decoded by
 * src/scene/image_codec.c once the header's size has passed the limits here; files are
 * read here, so that size limits, special files and read errors are ours to report. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "util/infile.h"
#include "scene/image_codec.h"
#include "scene/scene_internal.h"
#include "scene/texture.h"

int tr_read_image_file(const char *path, unsigned char **data, size_t *len, tr_error *err) {
    *data = NULL;
    *len = 0;
    /* Regular files only, opened without blocking (a FIFO would hang the load). */
    uint64_t size = 0;
    FILE *fp = tr_infile_open(path, &size, err);
    if (!fp) {
        return TR_ERR;
    }
    if (size > TR_IMAGE_MAX_FILE_BYTES) {
        fclose(fp);
        return tr_error_set(err, TR_STATUS_LIMIT, "'%.200s' is larger than %u MiB", path,
                            TR_IMAGE_MAX_FILE_BYTES >> 20);
    }
    size_t n = (size_t)size;
    unsigned char *buf = malloc(n ? n : 1);
    if (!buf) {
        fclose(fp);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory reading '%.200s'", path);
    }
    size_t got = fread(buf, 1, n, fp);
    int bad = ferror(fp);
    fclose(fp);
    if (bad || got != n) {
        free(buf);
        return tr_error_set(err, TR_STATUS_IO, "cannot read '%.200s'", path);
    }
    *data = buf;
    *len = n;
    return TR_OK;
}

uint32_t tr_image_max_texels_per_byte(const unsigned char *data, size_t len) {
    /* The densest each format read here can encode, rounded up:
     * - PNG: deflate expands one byte to at most 1032 (RFC 1951: a 258-byte match in a
     *   code of at least two bits), at 1 bit a texel: 8256;
     * - JPEG: an 8x8 block needs at least one bit (its DC difference; progressive scans
     *   run their ends of block together): 512;
     * - the rest (TGA run-length packets of 128 texels in 2 bytes, Radiance HDR runs of
     *   127 in 2 bytes a channel, BMP at 1 bit a texel): 64. */
    switch (tr_codec_of(data, len)) {
    case TR_CODEC_PNG:
        return 8256;
    case TR_CODEC_JPEG:
        return 512;
    case TR_CODEC_HDR:
    case TR_CODEC_STB:
        break;
    }
    return 64;
}

int tr_png_chunks_fit(const unsigned char *data, size_t len) {
    if (tr_codec_of(data, len) != TR_CODEC_PNG) {
        return 1;
    }
    /* Each chunk: 4-byte big-endian length, 4-byte type, the data, 4-byte CRC. */
    for (size_t pos = 8; len - pos >= 8;) {
        const uint32_t n = (uint32_t)data[pos] << 24 | (uint32_t)data[pos + 1] << 16 |
                           (uint32_t)data[pos + 2] << 8 | (uint32_t)data[pos + 3];
        if (len - pos < 12 || n > len - pos - 12) {
            return 0;
        }
        if (memcmp(data + pos + 4, "IEND", 4) == 0) {
            break;
        }
        pos += 12 + (size_t)n;
    }
    return 1;
}

/* The image's size from its header, checked before anything is decoded. */
static int check_header(const unsigned char *data, size_t len, const char *name, int *w, int *h,
                        tr_error *err) {
    if (len == 0 || len > (size_t)TR_IMAGE_MAX_FILE_BYTES) {
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': %s", name,
                            len ? "too large" : "empty");
    }
    /* stb_image grows its buffer to a chunk's declared length before it reads the chunk:
     * a 90-byte file declaring a 1 GiB chunk made it allocate 2 GiB (found by
     * fuzz_texture). */
    if (!tr_png_chunks_fit(data, len)) {
        return tr_error_set(err, TR_STATUS_PARSE,
                            "'%.200s': a PNG chunk runs past the end of the file", name);
    }
    if (tr_codec_info(data, len, name, w, h, err) != TR_OK) {
        return TR_ERR;
    }
    if (*w <= 0 || *h <= 0) {
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': an image of %dx%d texels", name, *w,
                            *h);
    }
    if (*w > TR_TEXTURE_MAX_SIDE || *h > TR_TEXTURE_MAX_SIDE ||
        (uint64_t)*w * (uint64_t)*h > TR_TEXTURE_MAX_TEXELS) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "'%.200s': %dx%d texels exceed the limit (sides up to %d, %u texels)",
                            name, *w, *h, TR_TEXTURE_MAX_SIDE, TR_TEXTURE_MAX_TEXELS);
    }
    /* stb_image's TGA and BMP readers take bytes past the end as zeros: a
     * 17-byte TGA declaring 9799x4096 texels decoded to 40 million of them, 12 s under
     * the sanitizers (found by fuzz_texture). A header may not declare more texels than
     * its format could encode in the file's bytes. */
    const uint64_t texels = (uint64_t)*w * (uint64_t)*h;
    if (texels / tr_image_max_texels_per_byte(data, len) > (uint64_t)len) {
        return tr_error_set(err, TR_STATUS_PARSE,
                            "'%.200s': declares %dx%d texels, more than its %zu bytes can hold",
                            name, *w, *h, len);
    }
    return TR_OK;
}

/* Decodes to 8-bit RGBA after the header's checks; the decoded size must be the one
 * checked. */
static int decode_rgba8(const unsigned char *data, size_t len, const char *name,
                        unsigned char **out, int *w, int *h, tr_error *err) {
    int cw = 0, ch = 0;
    *out = NULL;
    if (check_header(data, len, name, &cw, &ch, err) != TR_OK ||
        tr_codec_rgba8(data, len, name, out, w, h, err) != TR_OK) {
        return TR_ERR;
    }
    if (*w != cw || *h != ch) {
        free(*out);
        *out = NULL;
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': decoded %dx%d texels, header %dx%d",
                            name, *w, *h, cw, ch);
    }
    return TR_OK;
}

int tr_image_decode_rgba8(const unsigned char *data, size_t len, const char *name, uint32_t **out,
                          uint32_t *width, uint32_t *height, tr_error *err) {
    int w = 0, h = 0;
    unsigned char *px = NULL;
    *out = NULL;
    if (decode_rgba8(data, len, name, &px, &w, &h, err) != TR_OK) {
        return TR_ERR;
    }
    size_t n = (size_t)w * (size_t)h;
    uint32_t *rgba = malloc(n * sizeof *rgba);
    if (!rgba) {
        free(px);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory decoding '%.200s'", name);
    }
    for (size_t i = 0; i < n; ++i) {
        const unsigned char *p = px + 4 * i;
        rgba[i] = (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) |
                  ((uint32_t)p[3] << 24);
    }
    free(px);
    *out = rgba;
    *width = (uint32_t)w;
    *height = (uint32_t)h;
    return TR_OK;
}

int tr_image_decode_rgbf(const unsigned char *data, size_t len, const char *name, float **out,
                         uint32_t *width, uint32_t *height, tr_error *err) {
    int w = 0, h = 0;
    float *px = NULL;
    *out = NULL;
    /* Radiance .hdr comes linear; 8-bit formats are taken as sRGB through a gamma of 2.2
     * (stb_image's mapping, close to it; environment maps are HDR in practice), a table of
     * the 256 values. */
    if (tr_codec_of(data, len) == TR_CODEC_HDR) {
        if (check_header(data, len, name, &w, &h, err) != TR_OK ||
            tr_codec_hdr_rgbf(data, len, name, &px, &w, &h, err) != TR_OK) {
            return TR_ERR;
        }
        /* RGBE reaches 255 * 2^119; sums of such texels would overflow to infinity. */
        for (size_t i = 0, n = (size_t)w * (size_t)h * 3; i < n; ++i) {
            px[i] = px[i] > 1e30f ? 1e30f : px[i];
        }
    } else {
        unsigned char *ldr;
        if (decode_rgba8(data, len, name, &ldr, &w, &h, err) != TR_OK) {
            return TR_ERR;
        }
        const size_t n = (size_t)w * (size_t)h;
        px = malloc(n * 3 * sizeof *px);
        if (!px) {
            free(ldr);
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory decoding '%.200s'",
                                name);
        }
        float lut[256];
        for (int i = 0; i < 256; ++i) {
            /* In double, as stb_image computed it. */
            /* NOLINTNEXTLINE(performance-type-promotion-in-math-fn) */
            lut[i] = (float)pow((float)i / 255.0f, 2.2f);
        }
        for (size_t i = 0; i < n; ++i) {
            for (int c = 0; c < 3; ++c) {
                px[3 * i + c] = lut[ldr[4 * i + c]];
            }
        }
        free(ldr);
    }
    *out = px;
    *width = (uint32_t)w;
    *height = (uint32_t)h;
    return TR_OK;
}

int tr_scene_load_texture_memory(tr_scene *s, const unsigned char *data, size_t len,
                                 const char *name, uint32_t flags, uint32_t *index, tr_error *err) {
    uint32_t *rgba = NULL, w = 0, h = 0;
    if (tr_image_decode_rgba8(data, len, name, &rgba, &w, &h, err) != TR_OK) {
        return TR_ERR;
    }
    int rc = tr_scene_add_texture(s, rgba, w, h, flags, index, err);
    free(rgba);
    return rc;
}

/* Remembers that texture `index` was decoded from `path`. */
static int note_file(tr_scene *s, uint32_t index, const char *path, tr_error *err) {
    if (index >= s->texture_file_count) {
        char **grown = realloc(s->texture_files, ((size_t)index + 1) * sizeof *grown);
        if (!grown) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
        }
        for (uint32_t i = s->texture_file_count; i <= index; ++i) {
            grown[i] = NULL;
        }
        s->texture_files = grown;
        s->texture_file_count = index + 1;
    }
    const size_t n = strlen(path) + 1;
    s->texture_files[index] = malloc(n);
    if (!s->texture_files[index]) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
    }
    memcpy(s->texture_files[index], path, n);
    return TR_OK;
}

int tr_scene_load_texture(tr_scene *s, const char *path, uint32_t flags, uint32_t *index,
                          tr_error *err) {
    /* A file named again (by sixteen materials, say) is decoded once: the same texture,
     * or under another wrap mode a texture over the same texels. */
    for (uint32_t i = 0; i < s->texture_file_count; ++i) {
        if (!s->texture_files[i] || strcmp(s->texture_files[i], path) != 0) {
            continue;
        }
        if (s->textures[i].flags == flags) {
            if (index) {
                *index = i;
            }
            return TR_OK;
        }
        for (uint32_t j = i + 1; j < s->texture_file_count; ++j) {
            if (s->texture_files[j] && strcmp(s->texture_files[j], path) == 0 &&
                s->textures[j].flags == flags) {
                if (index) {
                    *index = j;
                }
                return TR_OK;
            }
        }
        tr_texture *grown = realloc(s->textures, ((size_t)s->texture_count + 1) * sizeof *grown);
        if (!grown) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
        }
        s->textures = grown;
        s->texture_capacity = s->texture_count + 1;
        const uint32_t k = s->texture_count;
        s->textures[k] = s->textures[i];
        s->textures[k].flags = flags;
        s->texture_count++;
        s->generation++;
        if (index) {
            *index = k;
        }
        return note_file(s, k, path, err);
    }
    unsigned char *data;
    size_t len;
    if (tr_read_image_file(path, &data, &len, err) != TR_OK) {
        return TR_ERR;
    }
    uint32_t k = 0;
    int rc = tr_scene_load_texture_memory(s, data, len, path, flags, &k, err);
    free(data);
    if (rc == TR_OK && index) {
        *index = k;
    }
    return rc == TR_OK ? note_file(s, k, path, err) : rc;
}
