/* image_codec.c - image decoders for textures and environment maps.
 *
 * PNG goes through libpng's simplified API and JPEG through libjpeg (Debian's is
 * libjpeg-turbo): both are fuzzed upstream, refuse truncated data and check every table
 * they read. Debian 12's stb_image (a 2022-09 snapshot) predates the fixes stb 2.28 made
 * for fuzzers' findings, and fuzz_texture found one of them here (a JPEG Huffman table of
 * more than 256 codes written past its array). Radiance HDR is read here, to Greg Ward's
 * description ("Real Pixels", Graphics Gems II, 1991, and Radiance's color.c format):
 * stb's reader loops forever on a zero-length run. stb_image keeps the formats that have no
 * library in Debian worth the dependency: TGA and BMP (uncompressed and run-length data,
 * bounded by the caller's texels-per-byte check). */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jpeglib.h>
#include <png.h>

#include "scene/image_codec.h"
#include "scene/texture.h"

/* stb_image for TGA and BMP only, static, so that libtrac0r exports no stbi_ names. The
 * header declares a function its static build never defines, which gcc reports at the end
 * of the file: the warning is off for this file (the pragma cannot be popped before that). */
#define STBI_MAX_DIMENSIONS TR_TEXTURE_MAX_SIDE
#define STBI_NO_STDIO
#define STBI_NO_LINEAR
#define STBI_NO_HDR
#define STBI_FAILURE_USERMSG
#define STBI_ONLY_TGA
#define STBI_ONLY_BMP
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#pragma GCC diagnostic ignored "-Wunused-function"
#include <stb/stb_image.h>

static const unsigned char png_signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

tr_codec tr_codec_of(const unsigned char *data, size_t len) {
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

/* ---- PNG: libpng's simplified API (png_image). */

static int png_decode(const unsigned char *data, size_t len, const char *name, unsigned char **out,
                      int *w, int *h, tr_error *err) {
    png_image img;
    memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_memory(&img, data, len)) {
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': not a PNG libpng reads (%s)", name,
                            img.message);
    }
    if (img.width > INT32_MAX || img.height > INT32_MAX) {
        png_image_free(&img);
        return tr_error_set(err, TR_STATUS_LIMIT, "'%.200s': %ux%u texels", name,
                            (unsigned)img.width, (unsigned)img.height);
    }
    *w = (int)img.width;
    *h = (int)img.height;
    if (!out) {
        png_image_free(&img);
        return TR_OK;
    }
    /* 8-bit sRGB RGBA, not premultiplied; libpng converts palettes, grey, 16-bit channels
     * and a gAMA chunk's encoding to it. */
    img.format = PNG_FORMAT_RGBA;
    unsigned char *px = malloc(PNG_IMAGE_SIZE(img));
    if (!px) {
        png_image_free(&img);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory decoding '%.200s'", name);
    }
    if (!png_image_finish_read(&img, NULL, px, 0, NULL)) {
        free(px);
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': cannot decode (%s)", name,
                            img.message);
    }
    *out = px;
    return TR_OK;
}

/* ---- JPEG: libjpeg, its errors and warnings turned into a longjmp back here. */

/* A progressive JPEG may have any number of scans, each a pass over the whole image: a
 * small file of many empty scans takes minutes. Real encoders write about ten. */
#define JPEG_MAX_SCANS 256

typedef struct {
    struct jpeg_error_mgr pub;
    struct jpeg_progress_mgr progress;
    jmp_buf back;
    char msg[JMSG_LENGTH_MAX];
} jpeg_catch;

static void jpeg_fail(j_common_ptr c) {
    jpeg_catch *jc = (jpeg_catch *)(void *)c->err;
    c->err->format_message(c, jc->msg);
    longjmp(jc->back, 1);
}

/* Warnings (level -1) are corrupt or missing data, which libjpeg would decode as grey: a
 * refusal here, as a truncated PNG is. Trace messages (level >= 0) are ignored. */
static void jpeg_note(j_common_ptr c, int level) {
    if (level < 0) {
        jpeg_fail(c);
    }
}

static void jpeg_quiet(j_common_ptr c) {
    (void)c;
}

static void jpeg_scans(j_common_ptr c) {
    if (c->is_decompressor && ((j_decompress_ptr)c)->input_scan_number > JPEG_MAX_SCANS) {
        jpeg_catch *jc = (jpeg_catch *)(void *)c->err;
        snprintf(jc->msg, sizeof jc->msg, "more than %d scans", JPEG_MAX_SCANS);
        longjmp(jc->back, 1);
    }
}

static int jpeg_decode(const unsigned char *data, size_t len, const char *name, unsigned char **out,
                       int *w, int *h, tr_error *err) {
    struct jpeg_decompress_struct ci;
    jpeg_catch jc;
    unsigned char *volatile px = NULL;
    memset(&ci, 0, sizeof ci);
    memset(&jc, 0, sizeof jc);
    ci.err = jpeg_std_error(&jc.pub);
    jc.pub.error_exit = jpeg_fail;
    jc.pub.emit_message = jpeg_note;
    jc.pub.output_message = jpeg_quiet;
    jc.progress.progress_monitor = jpeg_scans;
    if (setjmp(jc.back)) {
        jpeg_destroy_decompress(&ci);
        free(px);
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': not a JPEG libjpeg reads (%s)", name,
                            jc.msg);
    }
    jpeg_create_decompress(&ci);
    ci.progress = &jc.progress;
    jpeg_mem_src(&ci, data, (unsigned long)len);
    jpeg_read_header(&ci, TRUE);
    if (ci.image_width > INT32_MAX || ci.image_height > INT32_MAX) {
        jpeg_destroy_decompress(&ci);
        return tr_error_set(err, TR_STATUS_LIMIT, "'%.200s': %ux%u texels", name,
                            (unsigned)ci.image_width, (unsigned)ci.image_height);
    }
    *w = (int)ci.image_width;
    *h = (int)ci.image_height;
    if (!out) {
        jpeg_destroy_decompress(&ci);
        return TR_OK;
    }
    ci.out_color_space = JCS_EXT_RGBA; /* libjpeg-turbo's; grey and YCbCr convert to it */
    jpeg_start_decompress(&ci);
    const size_t row = (size_t)ci.output_width * 4;
    px = malloc(row * ci.output_height);
    if (!px) {
        jpeg_destroy_decompress(&ci);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory decoding '%.200s'", name);
    }
    while (ci.output_scanline < ci.output_height) {
        JSAMPROW r = px + row * ci.output_scanline;
        jpeg_read_scanlines(&ci, &r, 1);
    }
    jpeg_finish_decompress(&ci);
    jpeg_destroy_decompress(&ci);
    *out = px;
    return TR_OK;
}

/* ---- Radiance HDR (RGBE). */

/* The next line (without its '\n') from *pos; 0 when the data ends first. */
static int hdr_line(const unsigned char *d, size_t len, size_t *pos, const char **line, size_t *n) {
    const size_t start = *pos;
    const unsigned char *nl = memchr(d + start, '\n', len - start);
    if (!nl) {
        return 0;
    }
    *line = (const char *)d + start;
    *n = (size_t)(nl - (d + start));
    *pos = start + *n + 1;
    return 1;
}

/* A positive decimal of at most 9 digits at *s, then *s past it; -1 when there is none. */
static int hdr_int(const char **s, const char *end) {
    int v = 0, digits = 0;
    while (*s < end && **s >= '0' && **s <= '9' && digits < 9) {
        v = v * 10 + (**s - '0');
        ++*s;
        ++digits;
    }
    if (digits == 0 || (*s < end && **s >= '0' && **s <= '9')) {
        return -1;
    }
    return v;
}

/* The header: "#?" and a program name, KEY=value lines, an empty line, then the resolution
 * "-Y height +X width" (rows top to bottom, columns left to right; the only orientation
 * written in practice and the only one read here). *pos: the first byte of the texels. */
static int hdr_header(const unsigned char *d, size_t len, const char *name, int *w, int *h,
                      size_t *pos, tr_error *err) {
    const char *line;
    size_t n;
    *pos = 0;
    if (!hdr_line(d, len, pos, &line, &n) || n < 2 || memcmp(line, "#?", 2) != 0) {
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': no Radiance header line", name);
    }
    for (;;) {
        if (!hdr_line(d, len, pos, &line, &n)) {
            return tr_error_set(err, TR_STATUS_PARSE,
                                "'%.200s': the Radiance header has no end (an empty line)", name);
        }
        if (n == 0) {
            break;
        }
        static const char fmt[] = "FORMAT=";
        if (n >= sizeof fmt - 1 && memcmp(line, fmt, sizeof fmt - 1) == 0) {
            static const char rgbe[] = "FORMAT=32-bit_rle_rgbe";
            if (n != sizeof rgbe - 1 || memcmp(line, rgbe, n) != 0) {
                return tr_error_set(err, TR_STATUS_PARSE,
                                    "'%.200s': %.*s (only 32-bit_rle_rgbe is read)", name,
                                    (int)(n > 60 ? 60 : n), line);
            }
        }
    }
    if (!hdr_line(d, len, pos, &line, &n)) {
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': no resolution line", name);
    }
    const char *s = line, *end = line + n;
    int hh = -1, ww = -1;
    if (n > 3 && memcmp(s, "-Y ", 3) == 0) {
        s += 3;
        hh = hdr_int(&s, end);
        if (hh > 0 && end - s > 4 && memcmp(s, " +X ", 4) == 0) {
            s += 4;
            ww = hdr_int(&s, end);
        }
    }
    if (hh <= 0 || ww <= 0 || s != end) {
        return tr_error_set(err, TR_STATUS_PARSE,
                            "'%.200s': resolution line '%.*s' is not '-Y height +X width'", name,
                            (int)(n > 60 ? 60 : n), line);
    }
    *w = ww;
    *h = hh;
    return TR_OK;
}

/* One scanline of w RGBE texels at *pos into sc (4 bytes a texel). New-style run-length
 * scanlines start with 2, 2 and the width in 15 bits, then hold each channel in turn as runs
 * (a count above 128: count - 128 copies of the next byte) and literals (a count of 1 to
 * 128: that many bytes). Others are flat RGBE texels, where an old-style run (1, 1, 1, n)
 * repeats the previous texel n times, shifted 8 bits further for each run that follows. */
static int hdr_scanline(const unsigned char *d, size_t len, size_t *pos, int w, unsigned char *sc) {
    size_t p = *pos;
    if (w >= 8 && w < 0x8000 && len - p >= 4 && d[p] == 2 && d[p + 1] == 2 && !(d[p + 2] & 0x80)) {
        if ((d[p + 2] << 8 | d[p + 3]) != w) {
            return 0;
        }
        p += 4;
        for (int c = 0; c < 4; ++c) {
            for (int i = 0; i < w;) {
                if (p >= len) {
                    return 0;
                }
                int count = d[p++];
                if (count > 128) {
                    count -= 128;
                    if (count > w - i || p >= len) {
                        return 0;
                    }
                    const unsigned char v = d[p++];
                    for (; count > 0; --count, ++i) {
                        sc[4 * i + c] = v;
                    }
                } else {
                    if (count == 0 || count > w - i || len - p < (size_t)count) {
                        return 0;
                    }
                    for (; count > 0; --count, ++i) {
                        sc[4 * i + c] = d[p++];
                    }
                }
            }
        }
        *pos = p;
        return 1;
    }
    int shift = 0;
    for (int i = 0; i < w;) {
        if (len - p < 4) {
            return 0;
        }
        const unsigned char *t = d + p;
        p += 4;
        if (t[0] == 1 && t[1] == 1 && t[2] == 1) {
            const long count = shift < 24 ? (long)t[3] << shift : -1;
            if (i == 0 || count < 0 || count > w - i) {
                return 0;
            }
            for (long k = 0; k < count; ++k, ++i) {
                memcpy(sc + 4 * i, sc + 4 * (i - 1), 4);
            }
            shift += 8;
        } else {
            memcpy(sc + 4 * i, t, 4);
            ++i;
            shift = 0;
        }
    }
    *pos = p;
    return 1;
}

int tr_codec_hdr_rgbf(const unsigned char *data, size_t len, const char *name, float **out,
                      int *width, int *height, tr_error *err) {
    size_t pos = 0;
    int w = 0, h = 0;
    *out = NULL;
    if (hdr_header(data, len, name, &w, &h, &pos, err) != TR_OK) {
        return TR_ERR;
    }
    if (w > TR_TEXTURE_MAX_SIDE || h > TR_TEXTURE_MAX_SIDE) {
        return tr_error_set(err, TR_STATUS_LIMIT, "'%.200s': %dx%d texels", name, w, h);
    }
    float *px = malloc((size_t)w * (size_t)h * 3 * sizeof *px);
    unsigned char *sc = malloc((size_t)w * 4);
    if (!px || !sc) {
        free(px);
        free(sc);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory decoding '%.200s'", name);
    }
    for (int y = 0; y < h; ++y) {
        if (!hdr_scanline(data, len, &pos, w, sc)) {
            free(px);
            free(sc);
            return tr_error_set(err, TR_STATUS_PARSE,
                                "'%.200s': scanline %d of %d is truncated or malformed", name,
                                y + 1, h);
        }
        float *o = px + (size_t)y * (size_t)w * 3;
        for (int x = 0; x < w; ++x) {
            const unsigned char *t = sc + 4 * x;
            /* RGBE: a shared exponent, mantissas of 8 bits (Ward's colr_color, without
             * its half-unit offset, as stb_image and most readers do). */
            const float f = t[3] ? ldexpf(1.0f, (int)t[3] - (128 + 8)) : 0.0f;
            o[3 * x] = (float)t[0] * f;
            o[3 * x + 1] = (float)t[1] * f;
            o[3 * x + 2] = (float)t[2] * f;
        }
    }
    free(sc);
    *out = px;
    *width = w;
    *height = h;
    return TR_OK;
}

/* ---- dispatch */

int tr_codec_info(const unsigned char *data, size_t len, const char *name, int *width, int *height,
                  tr_error *err) {
    size_t pos;
    int comp;
    switch (tr_codec_of(data, len)) {
    case TR_CODEC_PNG:
        return png_decode(data, len, name, NULL, width, height, err);
    case TR_CODEC_JPEG:
        return jpeg_decode(data, len, name, NULL, width, height, err);
    case TR_CODEC_HDR:
        return hdr_header(data, len, name, width, height, &pos, err);
    case TR_CODEC_STB:
        break;
    }
    if (len > INT32_MAX || !stbi_info_from_memory(data, (int)len, width, height, &comp)) {
        return tr_error_set(err, TR_STATUS_PARSE,
                            "'%.200s': not an image in a format read here (PNG, JPEG, Radiance "
                            "HDR, TGA, BMP)",
                            name);
    }
    /* A BMP stored top-down has a negative height in its header, which stb_image's info
     * call passes on (its decoder takes the magnitude and reads the rows right). */
    if (*height < 0 && *height > INT32_MIN) {
        *height = -*height;
    }
    return TR_OK;
}

int tr_codec_rgba8(const unsigned char *data, size_t len, const char *name, unsigned char **out,
                   int *width, int *height, tr_error *err) {
    *out = NULL;
    switch (tr_codec_of(data, len)) {
    case TR_CODEC_PNG:
        return png_decode(data, len, name, out, width, height, err);
    case TR_CODEC_JPEG:
        return jpeg_decode(data, len, name, out, width, height, err);
    case TR_CODEC_HDR: {
        float *f = NULL;
        int w = 0, h = 0;
        if (tr_codec_hdr_rgbf(data, len, name, &f, &w, &h, err) != TR_OK) {
            return TR_ERR;
        }
        const size_t n = (size_t)w * (size_t)h;
        unsigned char *px = malloc(n * 4);
        if (!px) {
            free(f);
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory decoding '%.200s'",
                                name);
        }
        for (size_t i = 0; i < n; ++i) {
            for (int c = 0; c < 3; ++c) {
                /* stb_image's hdr_to_ldr: gamma 1/2.2, rounded, clamped. */
                float z = powf(f[3 * i + c], 1.0f / 2.2f) * 255.0f + 0.5f;
                z = z < 0.0f ? 0.0f : (z > 255.0f ? 255.0f : z);
                px[4 * i + c] = (unsigned char)(int)z;
            }
            px[4 * i + 3] = 255;
        }
        free(f);
        *out = px;
        *width = w;
        *height = h;
        return TR_OK;
    }
    case TR_CODEC_STB:
        break;
    }
    int comp;
    unsigned char *px =
        len > INT32_MAX ? NULL : stbi_load_from_memory(data, (int)len, width, height, &comp, 4);
    if (!px) {
        return tr_error_set(err, TR_STATUS_PARSE, "'%.200s': cannot decode (%s)", name,
                            stbi_failure_reason() ? stbi_failure_reason() : "unknown");
    }
    /* stb_image's allocation is malloc's (STBI_MALLOC's default): free() releases it. */
    *out = px;
    return TR_OK;
}
