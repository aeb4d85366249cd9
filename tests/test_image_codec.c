/* test_image_codec.c - the decoders behind textures and environment maps
 * (src/scene/image_codec.c): JPEG written by libjpeg here and read back, Radiance HDR
 * scanlines of every kind built byte by byte, and the malformed files each decoder must
 * refuse with a parse error rather than loop, read past the end or decode from zeros. */
#include <stdio.h> /* before jpeglib.h, which uses FILE */
#include <stdlib.h>
#include <string.h>

#include <jpeglib.h>

#include "check.h"
#include "scene/image_codec.h"
#include "scene/texture.h"

#ifndef TR_SOURCE_DIR
#error "TR_SOURCE_DIR must name the source tree"
#endif
#define TEXDATA TR_SOURCE_DIR "/tests/data/texture"

/* A JPEG of w x h texels from libjpeg at the given quality (*out: free()). */
static size_t write_jpeg(const unsigned char *px, int w, int h, int grey, int progressive,
                         unsigned char **out) {
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr e;
    unsigned char *mem = NULL;
    unsigned long len = 0;
    c.err = jpeg_std_error(&e);
    jpeg_create_compress(&c);
    jpeg_mem_dest(&c, &mem, &len);
    c.image_width = (JDIMENSION)w;
    c.image_height = (JDIMENSION)h;
    c.input_components = grey ? 1 : 3;
    c.in_color_space = grey ? JCS_GRAYSCALE : JCS_RGB;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, 98, TRUE);
    if (progressive) {
        jpeg_simple_progression(&c);
    }
    jpeg_start_compress(&c, TRUE);
    const int comps = grey ? 1 : 3;
    while (c.next_scanline < c.image_height) {
        JSAMPROW row = (JSAMPROW)(px + (size_t)c.next_scanline * (size_t)w * (size_t)comps);
        jpeg_write_scanlines(&c, &row, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    *out = mem;
    return (size_t)len;
}

static void test_jpeg(void) {
    enum { W = 37, H = 21 };
    static unsigned char rgb[W * H * 3], grey[W * H];
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            unsigned char *p = rgb + 3 * (y * W + x);
            p[0] = (unsigned char)(40 + 4 * x);
            p[1] = (unsigned char)(60 + 6 * y);
            p[2] = (unsigned char)(200 - 2 * x - 3 * y);
            grey[y * W + x] = (unsigned char)(30 + 3 * x + 2 * y);
        }
    }
    for (int kind = 0; kind < 3; ++kind) {
        const int is_grey = kind == 2, progressive = kind == 1;
        unsigned char *jpg = NULL;
        const size_t len = write_jpeg(is_grey ? grey : rgb, W, H, is_grey, progressive, &jpg);
        CHECK(jpg && len > 100, "kind %d: libjpeg wrote %zu bytes", kind, len);
        if (!jpg) {
            continue;
        }
        CHECK(tr_codec_of(jpg, len) == TR_CODEC_JPEG, "kind %d: not taken for a JPEG", kind);
        tr_error err;
        uint32_t *tex = NULL, w = 0, h = 0;
        CHECK(tr_image_decode_rgba8(jpg, len, "jpg", &tex, &w, &h, &err) == TR_OK && w == W &&
                  h == H,
              "kind %d: %s", kind, err.msg);
        /* Quality 98 on smooth ramps: every channel within a few levels of the source
         * (chroma subsampling included), opaque. */
        int worst = 0;
        for (int i = 0; tex && i < W * H; ++i) {
            for (int c = 0; c < 3; ++c) {
                const int want = is_grey ? grey[i] : rgb[3 * i + c];
                const int got = (int)(tex[i] >> (8 * c) & 0xffu);
                worst = abs(got - want) > worst ? abs(got - want) : worst;
            }
            CHECK((tex[i] >> 24) == 255u, "kind %d, texel %d: alpha %u", kind, i, tex[i] >> 24);
        }
        CHECK(tex && worst <= 8, "kind %d: a channel %d levels off", kind, worst);
        free(tex);
        /* Cut anywhere after the header: libjpeg's "premature end" is a refusal, not a
         * picture finished in grey. */
        for (size_t cut = len / 2; cut < len - 2; cut += len / 7) {
            tex = NULL;
            CHECK_STATUS(tr_image_decode_rgba8(jpg, cut, "cut", &tex, &w, &h, &err), err,
                         TR_STATUS_PARSE, "a truncated JPEG");
            CHECK(tex == NULL, "a truncated JPEG left texels");
        }
        free(jpg);
    }
    /* fuzz_texture's find: a Huffman table declaring more than 256 codes (stb_image wrote
     * past its arrays). */
    unsigned char *bad = NULL;
    size_t len = 0;
    tr_error err;
    CHECK(tr_read_image_file(TEXDATA "/dht_overflow.jpg", &bad, &len, &err) == TR_OK, "%s",
          err.msg);
    uint32_t *tex = NULL, w, h;
    CHECK_STATUS(tr_image_decode_rgba8(bad, len, "dht", &tex, &w, &h, &err), err, TR_STATUS_PARSE,
                 "dht_overflow.jpg");
    free(bad);
}

/* ---- Radiance HDR */

typedef struct {
    unsigned char b[4096];
    size_t n;
} buf;

static void put(buf *o, const void *p, size_t n) {
    if (o->n + n <= sizeof o->b) {
        memcpy(o->b + o->n, p, n);
    }
    o->n += n;
}

static void put_bytes(buf *o, int n, const int *v) {
    for (int i = 0; i < n; ++i) {
        const unsigned char c = (unsigned char)v[i];
        put(o, &c, 1);
    }
}

static float rgbe(int m, int e) {
    return e ? (float)m * ldexpf(1.0f, e - 136) : 0.0f;
}

static int decode_hdr(const buf *o, float **px, int *w, int *h, tr_error *err) {
    *px = NULL;
    uint32_t uw = 0, uh = 0;
    const int rc = tr_image_decode_rgbf(o->b, o->n, "hdr", px, &uw, &uh, err);
    *w = (int)uw;
    *h = (int)uh;
    return rc;
}

static void test_hdr(void) {
    static const char head[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y 3 +X 8\n";
    /* Row 0: new-style run-length, each channel as runs and literals. */
    buf o = {.n = 0};
    put(&o, head, sizeof head - 1);
    static const int row0[] = {
        2,       2,   0,  8,                           /* scanline header */
        128 + 8, 100,                                  /* R: a run of 8 */
        3,       10,  20, 30,  128 + 5, 40,            /* G: 3 literals, a run of 5 */
        8,       1,   2,  3,   4,       5,   6,  7, 8, /* B: 8 literals */
        128 + 4, 130, 4,  131, 132,     133, 134};     /* E: run of 4, 4 literals */
    put_bytes(&o, (int)(sizeof row0 / sizeof row0[0]), row0);
    /* Row 1: flat RGBE texels. */
    for (int x = 0; x < 8; ++x) {
        const int t[4] = {10 * x + 5, 7, 200 - x, 128 + x};
        put_bytes(&o, 4, t);
    }
    /* Row 2: flat, with an old-style run (1, 1, 1, 3) repeating the texel before it 3 times
     * and a second one right after it, shifted 8 bits (0 x 256 = no texels; then the
     * last 4 flat). */
    static const int row2[] = {50, 60,  70, 140, 1, 1,   1, 3, 1, 1,   1,  0,  1,  2,
                               3,  129, 4,  5,   6, 129, 7, 8, 9, 129, 10, 11, 12, 0};
    put_bytes(&o, (int)(sizeof row2 / sizeof row2[0]), row2);

    float *px;
    int w, h;
    tr_error err;
    CHECK(decode_hdr(&o, &px, &w, &h, &err) == TR_OK && w == 8 && h == 3, "%s", err.msg);
    if (px && w == 8 && h == 3) {
        static const int g0[8] = {10, 20, 30, 40, 40, 40, 40, 40};
        static const int e0[8] = {130, 130, 130, 130, 131, 132, 133, 134};
        for (int x = 0; x < 8; ++x) {
            const float *t = px + 3 * x;
            CHECK(t[0] == rgbe(100, e0[x]) && t[1] == rgbe(g0[x], e0[x]) &&
                      t[2] == rgbe(x + 1, e0[x]),
                  "row 0, x %d: %g %g %g", x, (double)t[0], (double)t[1], (double)t[2]);
            const float *u = px + 3 * (8 + x);
            CHECK(u[0] == rgbe(10 * x + 5, 128 + x) && u[1] == rgbe(7, 128 + x) &&
                      u[2] == rgbe(200 - x, 128 + x),
                  "row 1, x %d: %g %g %g", x, (double)u[0], (double)u[1], (double)u[2]);
        }
        const float *r2 = px + 3 * 16;
        for (int x = 0; x < 4; ++x) {
            CHECK(r2[3 * x] == rgbe(50, 140) && r2[3 * x + 2] == rgbe(70, 140),
                  "row 2, x %d: %g (the run repeats texel 0)", x, (double)r2[3 * x]);
        }
        CHECK(r2[12] == rgbe(1, 129) && r2[15] == rgbe(4, 129) && r2[18] == rgbe(7, 129) &&
                  r2[21] == 0.0f,
              "row 2, after the runs: %g %g %g %g", (double)r2[12], (double)r2[15], (double)r2[18],
              (double)r2[21]);
    }
    free(px);

    /* Every cut short of the end is refused. */
    for (size_t cut = sizeof head - 1; cut < o.n; ++cut) {
        buf c = o;
        c.n = cut;
        CHECK_STATUS(decode_hdr(&c, &px, &w, &h, &err), err, TR_STATUS_PARSE, "a cut HDR");
        CHECK(px == NULL, "a cut HDR left texels");
    }
    /* Malformed run-length data: a literal count of 0 (stb_image looped on it forever), a
     * run or literals past the width, a scanline header of the wrong width. */
    static const struct {
        size_t at; /* offset into row 0 */
        int value;
        const char *what;
    } bad[] = {{4, 0, "a literal count of 0"},
               {4, 128 + 9, "a run of 9 in a width of 8"},
               {6, 9, "9 literals in a width of 8"},
               {3, 9, "a scanline header of width 9"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        buf c = o;
        c.b[sizeof head - 1 + bad[i].at] = (unsigned char)bad[i].value;
        CHECK_STATUS(decode_hdr(&c, &px, &w, &h, &err), err, TR_STATUS_PARSE, bad[i].what);
    }
    /* Headers: no "#?", another pixel format, another orientation, a resolution that is
     * not a number, no empty line before it. */
    static const char *const heads[] = {
        "#!RADIANCE\n\n-Y 3 +X 8\n",          "#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 3 +X 8\n",
        "#?RADIANCE\n\n+Y 3 +X 8\n",          "#?RADIANCE\n\n-Y 3 +X 8x\n",
        "#?RADIANCE\n\n-Y 3 +X 9999999999\n", "#?RADIANCE\n-Y 3 +X 8\n"};
    for (size_t i = 0; i < sizeof heads / sizeof heads[0]; ++i) {
        buf c = {.n = 0};
        put(&c, heads[i], strlen(heads[i]));
        put(&c, o.b + sizeof head - 1, o.n - (sizeof head - 1));
        CHECK_STATUS(decode_hdr(&c, &px, &w, &h, &err), err, TR_STATUS_PARSE, heads[i]);
    }
    /* The shipped sky map through both paths: floats, and 8 bits for a texture. */
    unsigned char *sky = NULL;
    size_t len = 0;
    CHECK(tr_read_image_file(TEXDATA "/sky.hdr", &sky, &len, &err) == TR_OK, "%s", err.msg);
    uint32_t *tex = NULL, tw = 0, th = 0;
    CHECK(sky && tr_image_decode_rgba8(sky, len, "sky", &tex, &tw, &th, &err) == TR_OK &&
              tw == 32 && th == 16,
          "sky.hdr as a texture: %s", err.msg);
    free(tex);
    free(sky);
}

static int read_rgba8(const char *file, uint32_t **tex, uint32_t *w, uint32_t *h) {
    unsigned char *d = NULL;
    size_t len = 0;
    tr_error err;
    *tex = NULL;
    int rc = tr_read_image_file(file, &d, &len, &err);
    if (rc == TR_OK) {
        rc = tr_image_decode_rgba8(d, len, file, tex, w, h, &err);
    }
    CHECK(rc == TR_OK, "%s", err.msg);
    free(d);
    return rc;
}

/* The same pictures in other containers (tests/data/texture/generate.py writes them):
 * checker.png's colours as a 24-bit BMP and a run-length TGA, the sky in run-length
 * scanlines next to its flat ones. */
static void test_formats(void) {
    uint32_t *png, *bmp, *tga, w, h, bw, bh, tw, th;
    if (read_rgba8(TEXDATA "/checker.png", &png, &w, &h) != TR_OK) {
        return;
    }
    if (read_rgba8(TEXDATA "/checker.bmp", &bmp, &bw, &bh) == TR_OK) {
        CHECK(bw == w && bh == h, "checker.bmp: %ux%u", bw, bh);
        for (uint32_t i = 0; bw == w && bh == h && i < w * h; ++i) {
            CHECK(bmp[i] == (png[i] | 0xff000000u), "checker.bmp, texel %u: %08x vs %08x", i,
                  bmp[i], png[i]);
        }
        free(bmp);
    }
    if (read_rgba8(TEXDATA "/checker_rle.tga", &tga, &tw, &th) == TR_OK) {
        static const uint32_t from[8] = {0, 1, 2, 2, 4, 5, 6, 6}; /* the runs repeat texel 2 */
        CHECK(tw == w && th == h, "checker_rle.tga: %ux%u", tw, th);
        for (uint32_t i = 0; tw == w && th == h && i < w * h; ++i) {
            CHECK(tga[i] == png[from[i]], "checker_rle.tga, texel %u: %08x vs %08x", i, tga[i],
                  png[from[i]]);
        }
        free(tga);
    }
    free(png);

    float *sky[2] = {NULL, NULL};
    uint32_t sw[2] = {0, 0}, sh[2] = {0, 0};
    static const char *const skies[2] = {TEXDATA "/sky.hdr", TEXDATA "/sky_rle.hdr"};
    for (int k = 0; k < 2; ++k) {
        unsigned char *d = NULL;
        size_t len = 0;
        tr_error err;
        CHECK(tr_read_image_file(skies[k], &d, &len, &err) == TR_OK &&
                  tr_image_decode_rgbf(d, len, skies[k], &sky[k], &sw[k], &sh[k], &err) == TR_OK,
              "%s: %s", skies[k], err.msg);
        free(d);
    }
    const int same_size =
        sky[0] && sky[1] && sw[0] == 32 && sh[0] == 16 && sw[1] == 32 && sh[1] == 16;
    CHECK(same_size, "sky: %ux%u and %ux%u", sw[0], sh[0], sw[1], sh[1]);
    int differ = 0;
    for (int i = 0; same_size && i < 32 * 16 * 3; ++i) {
        differ += sky[0][i] != sky[1][i];
    }
    CHECK(differ == 0, "sky_rle.hdr differs from sky.hdr in %d values", differ);
    free(sky[0]);
    free(sky[1]);
}

/* A BMP stored top-down (negative height in its header, as Windows writes some): its
 * size is the height's magnitude and its first row is the top one. */
static void test_bmp_top_down(void) {
    unsigned char b[62] = {'B', 'M'};
    const uint32_t size = sizeof b, off = 54, hs = 40;
    const int32_t w = 1, h = -2;
    const uint16_t planes = 1, bpp = 24;
    memcpy(b + 2, &size, 4);
    memcpy(b + 10, &off, 4);
    memcpy(b + 14, &hs, 4);
    memcpy(b + 18, &w, 4);
    memcpy(b + 22, &h, 4);
    memcpy(b + 26, &planes, 2);
    memcpy(b + 28, &bpp, 2);
    b[54 + 2] = 255; /* row 0 (the top): red, stored B, G, R */
    b[58 + 0] = 255; /* row 1: blue (rows padded to 4 bytes) */
    tr_error err;
    int iw = 0, ih = 0;
    CHECK(tr_codec_info(b, sizeof b, "top-down.bmp", &iw, &ih, &err) == TR_OK && iw == 1 && ih == 2,
          "top-down BMP's size: %dx%d", iw, ih);
    unsigned char *px = NULL;
    CHECK(tr_codec_rgba8(b, sizeof b, "top-down.bmp", &px, &iw, &ih, &err) == TR_OK && px &&
              px[0] == 255 && px[2] == 0 && px[4] == 0 && px[6] == 255,
          "top-down BMP's rows");
    free(px);
}

int main(void) {
    test_bmp_top_down();
    test_formats();
    test_jpeg();
    test_hdr();
    return check_finish("test_image_codec");
}
