/* test_post.c - the post layer (post.h): the one tonemapper and the image metrics.
 *
 * The tonemapper must give exactly the bytes the PNG writer and the viewer gave before
 * it replaced their code: the old formulas are kept here as oracles and compared bit
 * for bit over every class of float (zeros, denormals, the sRGB toe and knee, just
 * below and above 1, huge, infinities, NaNs of either sign and any payload) and over a
 * sweep of the whole 32-bit pattern space. The metrics are checked against values
 * worked out by hand, and against the old `trac0r compare` code as an oracle. */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

/* ---- Oracles: the code the post layer replaced, verbatim ------------------------ */

/* src/io/image.c's tr_tonemap_srgb8 before the post layer. */
static uint8_t old_tonemap_srgb8(float linear, float exposure) {
    float v = linear * exp2f(exposure);
    if (!(v > 0.0f)) {
        return 0;
    }
    if (v >= 1.0f) {
        return 255;
    }
    float s = v <= 0.0031308f ? 12.92f * v : 1.055f * powf(v, 1.0f / 2.4f) - 0.055f;
    return (uint8_t)(s * 255.0f + 0.5f);
}

/* apps/trac0r/view_render.c's view_tonemap, one pixel. */
static uint32_t old_view_pixel(const tr_film *film, size_t i, float exposure) {
    uint32_t c = film->count[i];
    uint32_t rgb = 0;
    if (c > 0) {
        float inv = 1.0f / (float)c;
        uint32_t r = old_tonemap_srgb8(film->sum[3 * i] * inv, exposure);
        uint32_t g = old_tonemap_srgb8(film->sum[3 * i + 1] * inv, exposure);
        uint32_t b = old_tonemap_srgb8(film->sum[3 * i + 2] * inv, exposure);
        rgb = (r << 16) | (g << 8) | b;
    }
    return 0xff000000u | rgb;
}

/* apps/trac0r/compare.c's srgb_to_linear. */
static float old_srgb_to_linear(float c) {
    return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

static double old_clamp01(double v) {
    return v != v ? 0.0 : v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v;
}

/* apps/trac0r/compare.c's compare_images and its error image's maximum. */
static void old_compare(const float *a, const float *ref, size_t pixels, double out[5]) {
    double se = 0.0, rel = 0.0;
    for (size_t i = 0; i < 3 * pixels; ++i) {
        double x = old_clamp01(a[i]), y = old_clamp01(ref[i]);
        double d = x - y;
        se += d * d;
        rel += d * d / (y * y + 0.01);
    }
    double n = 3.0 * (double)pixels;
    out[0] = se / n;
    out[1] = sqrt(out[0]);
    out[2] = rel / n;
    out[3] = out[0] > 0.0 ? 10.0 * log10(1.0 / out[0]) : INFINITY;
    double max = 0.0;
    for (size_t i = 0; i < pixels; ++i) {
        double d = 0.0;
        for (int c = 0; c < 3; ++c) {
            d += fabs(old_clamp01(a[3 * i + c]) - old_clamp01(ref[3 * i + c]));
        }
        max = d / 3.0 > max ? d / 3.0 : max;
    }
    out[4] = max;
}

/* ---- Helpers -------------------------------------------------------------------- */

static float from_bits(uint32_t u) {
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static uint32_t to_bits(float f) {
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

/* Bitwise equal doubles (so that inf == inf and the sign of zero counts). */
static int same_double(double a, double b) {
    return memcmp(&a, &b, sizeof a) == 0;
}

/* The float classes that could trip a tonemapper up, with their neighbours. */
static size_t special_floats(float *out) {
    const float base[] = {
        0.0f,   FLT_TRUE_MIN, FLT_MIN, 1e-30f,   1e-7f,   0.0031308f, 0.0031308f / 255.0f,
        0.002f, 0.04045f,     0.2f,    0.5f,     0.7354f, 0.99f,      1.0f,
        1.5f,   2.0f,         255.0f,  65504.0f, 1e20f,   FLT_MAX,    INFINITY};
    size_t n = 0;
    for (size_t k = 0; k < sizeof base / sizeof base[0]; ++k) {
        for (int sign = 0; sign < 2; ++sign) {
            const float v = sign ? -base[k] : base[k];
            out[n++] = v;
            out[n++] = nextafterf(v, INFINITY);
            out[n++] = nextafterf(v, -INFINITY);
        }
    }
    /* NaNs: quiet and signalling, both signs, several payloads. */
    const uint32_t nans[] = {0x7fc00000u, 0xffc00000u, 0x7f800001u, 0xff800001u,
                             0x7fffffffu, 0xffffffffu, 0x7fa5a5a5u, 0x7fc00001u};
    for (size_t k = 0; k < sizeof nans / sizeof nans[0]; ++k) {
        out[n++] = from_bits(nans[k]);
    }
    return n;
}

#define MAX_SPECIAL 160

static const float exposures[] = {0.0f, -1.5f, 1.0f, 3.7f, -20.0f, 20.0f, -0.25f, 0.1f};
#define N_EXPOSURES (sizeof exposures / sizeof exposures[0])

/* ---- Tonemapping ---------------------------------------------------------------- */

static void test_tonemap_value_classes(void) {
    float v[MAX_SPECIAL];
    const size_t n = special_floats(v);
    CHECK(n <= MAX_SPECIAL, "special_floats wrote %zu values", n);
    int bad = 0;
    for (size_t e = 0; e < N_EXPOSURES; ++e) {
        for (size_t i = 0; i < n; ++i) {
            const uint8_t got = tr_tonemap_srgb8(v[i], exposures[e]);
            const uint8_t want = old_tonemap_srgb8(v[i], exposures[e]);
            if (got != want && bad++ < 5) {
                CHECK(got == want, "tonemap(0x%08x = %g, EV %g) = %u, the old formula %u",
                      to_bits(v[i]), (double)v[i], (double)exposures[e], got, want);
            }
        }
    }
    /* Exposures that are themselves odd: +-inf and NaN stops. */
    const float odd_ev[] = {INFINITY, -INFINITY, NAN, 128.0f, -150.0f};
    for (size_t e = 0; e < sizeof odd_ev / sizeof odd_ev[0]; ++e) {
        for (size_t i = 0; i < n; ++i) {
            const uint8_t got = tr_tonemap_srgb8(v[i], odd_ev[e]);
            const uint8_t want = old_tonemap_srgb8(v[i], odd_ev[e]);
            if (got != want && bad++ < 5) {
                CHECK(got == want, "tonemap(0x%08x, EV %g) = %u, the old formula %u", to_bits(v[i]),
                      (double)odd_ev[e], got, want);
            }
        }
    }
    CHECK(bad == 0, "%d special values tonemap differently from the old formula", bad);
    /* And the anchors the formula must keep (not only agree with itself). */
    CHECK(tr_tonemap_srgb8(0.0f, 0.0f) == 0 && tr_tonemap_srgb8(1.0f, 0.0f) == 255 &&
              tr_tonemap_srgb8(NAN, 0.0f) == 0 && tr_tonemap_srgb8(-INFINITY, 0.0f) == 0 &&
              tr_tonemap_srgb8(INFINITY, 0.0f) == 255,
          "black, white, NaN and infinities");
    /* sRGB(0.5) = 1.055 * 0.5^(1/2.4) - 0.055 = 0.7354 -> 187.5 + 0.5 -> 188 */
    CHECK(tr_tonemap_srgb8(0.25f, 1.0f) == 188, "one stop up on 0.25 is mid grey 188: %u",
          tr_tonemap_srgb8(0.25f, 1.0f));
}

/* Every 251st 32-bit pattern (all signs, exponents, NaN payloads; 17 million values) at
 * EV 0 and EV -1.5, and a dense sweep of (0, 1] where the transfer curve lives. */
static void test_tonemap_sweep(void) {
    int bad = 0;
    uint64_t tested = 0;
    for (uint64_t u = 0; u <= 0xffffffffu; u += 251) {
        const float v = from_bits((uint32_t)u);
        for (int e = 0; e < 2; ++e) {
            const float ev = e ? -1.5f : 0.0f;
            if (tr_tonemap_srgb8(v, ev) != old_tonemap_srgb8(v, ev) && bad++ < 5) {
                CHECK(0, "tonemap(0x%08x, EV %g) differs from the old formula", (uint32_t)u,
                      (double)ev);
            }
        }
        ++tested;
    }
    /* (0, 1]: bit patterns 1 .. 0x3f800000, every 61st. */
    for (uint32_t u = 1; u <= 0x3f800000u; u += 61) {
        const float v = from_bits(u);
        if (tr_tonemap_srgb8(v, 0.0f) != old_tonemap_srgb8(v, 0.0f) && bad++ < 10) {
            CHECK(0, "tonemap(0x%08x) differs from the old formula", u);
        }
        ++tested;
    }
    CHECK(bad == 0, "%d of %llu swept values tonemap differently", bad, (unsigned long long)tested);
}

/* The monotone staircase: each 8-bit code is reached, in order. */
static void test_tonemap_monotonic(void) {
    int prev = 0, seen = 0;
    int monotonic = 1;
    for (int i = 0; i <= 100000; ++i) {
        const int code = tr_tonemap_srgb8((float)i / 100000.0f, 0.0f);
        monotonic &= code >= prev;
        seen += code != prev;
        prev = code;
    }
    CHECK(monotonic, "the tonemap is not monotonic on [0,1]");
    CHECK(seen == 255 && prev == 255, "[0,1] reaches %d codes, ends at %d", seen, prev);
}

/* A film whose pixels run through the special classes, one channel each. */
static void fill_special_film(tr_film *f) {
    float v[MAX_SPECIAL];
    const size_t n = special_floats(v);
    const uint32_t counts[] = {0, 1, 2, 3, 7, 1000, 4294967295u};
    const size_t px = (size_t)f->width * f->height;
    for (size_t i = 0; i < px; ++i) {
        f->count[i] = counts[(i * 5) % (sizeof counts / sizeof counts[0])];
        for (int c = 0; c < 3; ++c) {
            f->sum[3 * i + (size_t)c] = v[(i * 3 + (size_t)c * 7 + i / 11) % n];
        }
    }
}

static void test_tonemap_film(void) {
    tr_error err;
    tr_film f;
    /* An odd size, so that no row or stride arithmetic hides behind a power of two. */
    CHECK(tr_film_init(&f, 37, 29, &err) == TR_OK, "%s", err.msg);
    fill_special_film(&f);
    const size_t px = (size_t)f.width * f.height;
    for (size_t e = 0; e < N_EXPOSURES; ++e) {
        const float ev = exposures[e];
        /* The viewer's case: the whole film to ARGB8888. */
        uint32_t *argb = malloc(px * sizeof *argb);
        CHECK(tr_tonemap_film(&f, 0, 0, f.width, f.height, ev, TR_PIXEL_ARGB8888, argb,
                              f.width * sizeof *argb, &err) == TR_OK,
              "%s", err.msg);
        int bad = 0;
        for (size_t i = 0; i < px; ++i) {
            bad += argb[i] != old_view_pixel(&f, i, ev);
        }
        CHECK(bad == 0, "EV %g: %d ARGB pixels differ from the old viewer", (double)ev, bad);
        free(argb);

        /* The PNG writer's case: RGB8, checked against the old writer's path
         * (tr_film_pixel, then the old formula per channel). */
        uint8_t *rgb = malloc(px * 3);
        CHECK(tr_tonemap_film(&f, 0, 0, f.width, f.height, ev, TR_PIXEL_RGB8, rgb, f.width * 3,
                              &err) == TR_OK,
              "%s", err.msg);
        bad = 0;
        for (uint32_t y = 0; y < f.height; ++y) {
            for (uint32_t x = 0; x < f.width; ++x) {
                const tr_vec3 c = tr_film_pixel(&f, x, y);
                const uint8_t *p = rgb + 3 * ((size_t)y * f.width + x);
                bad += p[0] != old_tonemap_srgb8(c.x, ev) || p[1] != old_tonemap_srgb8(c.y, ev) ||
                       p[2] != old_tonemap_srgb8(c.z, ev);
            }
        }
        CHECK(bad == 0, "EV %g: %d RGB8 pixels differ from the old PNG writer", (double)ev, bad);
        free(rgb);
    }

    /* A rectangle into a padded buffer: its pixels land where the stride says, and
     * the padding and the rows beyond are left alone. */
    const uint32_t rx = 5, ry = 3, rw = 11, rh = 20;
    const size_t stride = rw * 3 + 7;
    uint8_t *buf = malloc(stride * (rh + 1));
    memset(buf, 0xa5, stride * (rh + 1));
    CHECK(tr_tonemap_film(&f, rx, ry, rw, rh, 0.5f, TR_PIXEL_RGB8, buf, stride, &err) == TR_OK,
          "%s", err.msg);
    int bad = 0, touched = 0;
    for (uint32_t r = 0; r < rh; ++r) {
        for (uint32_t c = 0; c < rw; ++c) {
            const uint32_t want = old_view_pixel(&f, (size_t)(ry + r) * f.width + rx + c, 0.5f);
            const uint8_t *p = buf + r * stride + 3 * c;
            bad += p[0] != (uint8_t)(want >> 16) || p[1] != (uint8_t)(want >> 8) ||
                   p[2] != (uint8_t)want;
        }
        for (size_t k = rw * 3; k < stride; ++k) {
            touched += buf[r * stride + k] != 0xa5;
        }
    }
    for (size_t k = 0; k < stride; ++k) {
        touched += buf[rh * stride + k] != 0xa5;
    }
    CHECK(bad == 0, "%d pixels of the rectangle differ", bad);
    CHECK(touched == 0, "%d bytes outside the rectangle were written", touched);

    /* Refusals: nothing is written. */
    memset(buf, 0xa5, stride * (rh + 1));
    CHECK(tr_tonemap_film(&f, 30, 0, 8, 1, 0.0f, TR_PIXEL_RGB8, buf, stride, &err) == TR_ERR,
          "a rectangle past the right edge");
    CHECK(tr_tonemap_film(&f, 0, 29, 1, 1, 0.0f, TR_PIXEL_RGB8, buf, stride, &err) == TR_ERR,
          "a rectangle below the film");
    CHECK(tr_tonemap_film(&f, 0, 0, 0, 1, 0.0f, TR_PIXEL_RGB8, buf, stride, &err) == TR_ERR,
          "an empty rectangle");
    CHECK(tr_tonemap_film(&f, 4294967295u, 0, 2, 1, 0.0f, TR_PIXEL_RGB8, buf, stride, &err) ==
              TR_ERR,
          "x + width wrapping around");
    CHECK(tr_tonemap_film(&f, 0, 0, 4, 1, 0.0f, (tr_pixel_format)7, buf, stride, &err) == TR_ERR,
          "an unknown pixel format");
    CHECK(tr_tonemap_film(&f, 0, 0, 4, 2, 0.0f, TR_PIXEL_ARGB8888, buf, 15, &err) == TR_ERR,
          "a stride shorter than a row");
    CHECK(tr_tonemap_film(&f, 0, 0, 4, 2, 0.0f, TR_PIXEL_RGB8, buf, 12, NULL) == TR_OK,
          "a stride of exactly one row");
    touched = 0;
    for (size_t k = 24; k < stride * (rh + 1); ++k) {
        touched += buf[k] != 0xa5;
    }
    CHECK(touched == 0, "refused calls wrote %d bytes", touched);
    free(buf);
    tr_film_free(&f);
}

static void test_srgb_decode(void) {
    float v[MAX_SPECIAL];
    const size_t n = special_floats(v);
    int bad = 0;
    for (size_t i = 0; i < n; ++i) {
        bad += to_bits(tr_srgb_to_linear(v[i])) != to_bits(old_srgb_to_linear(v[i]));
    }
    /* Every 8-bit code as tr_image_read_png gives it. */
    int roundtrip = 0;
    for (int k = 0; k <= 255; ++k) {
        const float c = (float)k / 255.0f;
        bad += to_bits(tr_srgb_to_linear(c)) != to_bits(old_srgb_to_linear(c));
        /* Decoding then tonemapping gives the code back: the two are inverses. */
        roundtrip += tr_tonemap_srgb8(tr_srgb_to_linear(c), 0.0f) != k;
    }
    CHECK(bad == 0, "%d values decode differently from compare.c's old formula", bad);
    CHECK(roundtrip == 0, "%d codes do not survive decode + tonemap", roundtrip);
    CHECK_NEAR(tr_srgb_to_linear(0.5f), 0.21404114, 1e-6, "sRGB 0.5 is linear 0.214");
    CHECK(tr_srgb_to_linear(0.0f) == 0.0f && tr_srgb_to_linear(1.0f) == 1.0f, "ends");
}

/* ---- Metrics -------------------------------------------------------------------- */

static void fill(float *img, size_t pixels, float v) {
    for (size_t i = 0; i < 3 * pixels; ++i) {
        img[i] = v;
    }
}

static void test_metrics_analytic(void) {
    enum { N = 12 };
    float a[3 * N], ref[3 * N];

    /* Identical images: no error, PSNR +inf as `trac0r compare` prints it. */
    for (size_t i = 0; i < 3 * N; ++i) {
        a[i] = ref[i] = (float)i / (3.0f * N);
    }
    tr_image_metrics m = tr_image_compare(a, ref, N);
    CHECK(m.mse == 0.0 && m.rmse == 0.0 && m.relmse == 0.0 && m.max_error == 0.0,
          "identical: mse %g rmse %g relmse %g max %g", m.mse, m.rmse, m.relmse, m.max_error);
    CHECK(isinf(m.psnr) && m.psnr > 0.0, "identical: psnr %g, expected +inf", m.psnr);

    /* Uniform 0.5 against black: d = 0.5 everywhere. MSE 0.25, RMSE 0.5, relMSE
     * 0.25 / (0 + 0.01) = 25, PSNR 10 log10(4) = 6.0206 dB, max 0.5. */
    fill(a, N, 0.5f);
    fill(ref, N, 0.0f);
    m = tr_image_compare(a, ref, N);
    CHECK_NEAR(m.mse, 0.25, 1e-15, "grey vs black: mse");
    CHECK_NEAR(m.rmse, 0.5, 1e-15, "grey vs black: rmse");
    CHECK_NEAR(m.relmse, 25.0, 1e-12, "grey vs black: relmse");
    CHECK_NEAR(m.psnr, 6.020599913279624, 1e-12, "grey vs black: psnr");
    CHECK_NEAR(m.max_error, 0.5, 1e-15, "grey vs black: max error");

    /* White against black: MSE 1, PSNR 0 dB; relMSE 1 / 0.01 = 100. */
    fill(a, N, 1.0f);
    m = tr_image_compare(a, ref, N);
    CHECK(m.mse == 1.0 && m.psnr == 0.0 && m.max_error == 1.0, "white vs black: %g %g %g", m.mse,
          m.psnr, m.max_error);
    CHECK_NEAR(m.relmse, 100.0, 1e-12, "white vs black: relmse");

    /* Two pixels, by hand: a = (0.1 0.2 0.3 | 0.9 0.8 0.7), ref = (0 0 0 | 1 1 1).
     * Differences 0.1 0.2 0.3 in each pixel: squared sum 2 * 0.14 = 0.28, MSE 0.28 / 6;
     * relMSE (0.14 / 0.01 + 0.14 / 1.01) / 6; pixel errors 0.2 and 0.2. */
    const float a2[6] = {0.1f, 0.2f, 0.3f, 0.9f, 0.8f, 0.7f};
    const float r2[6] = {0.0f, 0.0f, 0.0f, 1.0f, 1.0f, 1.0f};
    m = tr_image_compare(a2, r2, 2);
    CHECK_NEAR(m.mse, 0.28 / 6.0, 1e-8, "two pixels: mse");
    CHECK_NEAR(m.rmse, sqrt(0.28 / 6.0), 1e-8, "two pixels: rmse");
    CHECK_NEAR(m.relmse, (0.14 / 0.01 + 0.14 / 1.01) / 6.0, 1e-6, "two pixels: relmse");
    CHECK_NEAR(m.psnr, 10.0 * log10(6.0 / 0.28), 1e-6, "two pixels: psnr");
    CHECK_NEAR(m.max_error, 0.2, 1e-7, "two pixels: max error");
    CHECK_NEAR(tr_pixel_error(a2, r2), 0.2, 1e-7, "pixel error, first pixel");

    /* Clamping: above 1, below 0, infinities and NaN (as black) are displayable
     * values first, so these pairs do not differ at all. */
    const float a3[6] = {2.0f, -1.0f, NAN, INFINITY, -INFINITY, 1e30f};
    const float r3[6] = {1.0f, 0.0f, 0.0f, 1.0f, 0.0f, 1.0f};
    m = tr_image_compare(a3, r3, 2);
    CHECK(m.mse == 0.0 && isinf(m.psnr) && m.max_error == 0.0, "clamped: mse %g psnr %g max %g",
          m.mse, m.psnr, m.max_error);

    /* The max is the worst pixel, not the mean: one pixel off by 0.3 in one channel. */
    fill(a, N, 0.25f);
    fill(ref, N, 0.25f);
    a[3 * 7 + 1] = 0.55f;
    m = tr_image_compare(a, ref, N);
    CHECK_NEAR(m.max_error, 0.1, 1e-7, "one pixel: max error 0.3 / 3");
    CHECK_NEAR(m.mse, 0.09 / (3.0 * N), 1e-8, "one pixel: mse");

    /* PSNR itself: 20 dB at 1e-2, 0 dB at 1, +inf where the MSE is not positive (bench
     * convergence subtracts the reference's own MSE and can reach 0 or below). */
    CHECK_NEAR(tr_psnr(1e-2), 20.0, 1e-12, "psnr(0.01)");
    CHECK_NEAR(tr_psnr(1e-4), 40.0, 1e-12, "psnr(1e-4)");
    CHECK(tr_psnr(1.0) == 0.0, "psnr(1)");
    CHECK(isinf(tr_psnr(0.0)) && isinf(tr_psnr(-1e-3)) && isinf(tr_psnr(NAN)),
          "psnr of 0, negative and NaN MSE");
}

/* A noisy image with every special class in it, against the old compare code: each
 * metric bit-identical, so `trac0r compare` and `bench convergence` print the same. */
static void test_metrics_oracle(void) {
    enum { W = 61, H = 47 };
    const size_t px = (size_t)W * H;
    float *a = malloc(3 * px * sizeof *a), *ref = malloc(3 * px * sizeof *ref);
    float v[MAX_SPECIAL];
    const size_t n = special_floats(v);
    uint64_t s = 0x9e3779b97f4a7c15ull;
    for (size_t i = 0; i < 3 * px; ++i) {
        /* xorshift64: a fixed pseudo-random image */
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        const float u = (float)(s >> 40) / 16777216.0f;
        ref[i] = u;
        a[i] = i % 17 == 0 ? v[(s >> 8) % n]
                           : u + 0.2f * ((float)((s >> 20) & 0xffff) / 65536.0f - 0.5f);
    }
    double want[5];
    old_compare(a, ref, px, want);
    const tr_image_metrics m = tr_image_compare(a, ref, px);
    CHECK(same_double(m.mse, want[0]) && same_double(m.rmse, want[1]) &&
              same_double(m.relmse, want[2]) && same_double(m.psnr, want[3]) &&
              same_double(m.max_error, want[4]),
          "metrics differ from the old compare code: mse %.17g/%.17g rmse %.17g/%.17g relmse "
          "%.17g/%.17g psnr %.17g/%.17g max %.17g/%.17g",
          m.mse, want[0], m.rmse, want[1], m.relmse, want[2], m.psnr, want[3], m.max_error,
          want[4]);
    CHECK(m.mse > 0.0 && m.max_error > 0.0, "the oracle image must differ from its reference");
    free(a);
    free(ref);
}

/* A black or white image is noted; one with shapes is not; nor is a film without
 * samples. 0.1 % of lit pixels in a black image (1 in 1000) still counts as black. */
static void test_exposure_note(void) {
    tr_error err;
    tr_film f;
    char note[400];
    CHECK(tr_film_init(&f, 50, 40, &err) == TR_OK, "%s", err.msg);
    const size_t px = (size_t)f.width * f.height;
    CHECK(tr_image_exposure_note(&f, 0.0f, note, sizeof note) == 0 && note[0] == '\0',
          "no samples: noted '%s'", note);
    for (size_t i = 0; i < px; ++i) {
        f.count[i] = 4;
        for (int c = 0; c < 3; ++c) {
            f.sum[3 * i + (size_t)c] = i < 2 ? 2.0f : 0.0f; /* two lit pixels of 2000 */
        }
    }
    CHECK(tr_image_exposure_note(&f, 0.0f, note, sizeof note) == 1 && note[0] != '\0',
          "black image not noted: '%s'", note);
    for (size_t i = 0; i < px; ++i) {
        for (int c = 0; c < 3; ++c) {
            f.sum[3 * i + (size_t)c] = i % 2 ? 4.0f * 0.3f : 4.0f * 0.01f; /* shapes */
        }
    }
    CHECK(tr_image_exposure_note(&f, 0.0f, note, sizeof note) == 0, "lit image noted: '%s'", note);
    CHECK(tr_image_exposure_note(&f, 12.0f, note, sizeof note) == 2 && note[0] != '\0',
          "overexposed image not noted: '%s'", note);
    CHECK(tr_image_exposure_note(&f, -30.0f, note, sizeof note) == 1,
          "underexposed image not noted: '%s'", note);
    tr_film_free(&f);
}

/* The error map: an exact pixel is black, the largest error white, half of it in
 * between (orange-magenta: neither black nor white), read back from the PFM written. */
static void test_error_map(void) {
    const float a[9] = {0.5f, 0.5f, 0.5f, 1.0f, 1.0f, 1.0f, 0.75f, 0.75f, 0.75f};
    const float ref[9] = {0.5f, 0.5f, 0.5f, 0.0f, 0.0f, 0.0f, 0.25f, 0.25f, 0.25f};
    char path[512];
    const char *tmp = getenv("TMPDIR");
    snprintf(path, sizeof path, "%s/trac0r-test-post-%ld.pfm", tmp && *tmp ? tmp : "/tmp",
             (long)getpid());
    tr_error err;
    const tr_image_metrics m = tr_image_compare(a, ref, 3);
    CHECK(m.max_error == 1.0, "max error %g", m.max_error);
    CHECK(tr_error_map_write(a, ref, 3, 1, m.max_error, path, &err) == TR_OK, "%s", err.msg);
    tr_image img;
    memset(&img, 0, sizeof img);
    CHECK(tr_image_read(&img, path, &err) == TR_OK && img.width == 3 && img.height == 1, "%s",
          err.msg);
    if (img.rgb) {
        CHECK(img.rgb[0] == 0.0f && img.rgb[1] == 0.0f && img.rgb[2] == 0.0f, "exact: not black");
        CHECK(img.rgb[3] == 1.0f && img.rgb[4] == 1.0f && img.rgb[5] == 1.0f, "largest: not white");
        const float *h = img.rgb + 6;
        CHECK(h[0] > 0.05f && h[0] < 1.0f && h[2] < 1.0f, "half: (%g, %g, %g)", (double)h[0],
              (double)h[1], (double)h[2]);
    }
    tr_image_free(&img);
    remove(path);
    CHECK(tr_error_map_write(a, ref, 3, 1, 1.0, "/nonexistent-dir/e.png", &err) == TR_ERR,
          "an unwritable error map accepted");
}

int main(void) {
    test_exposure_note();
    test_tonemap_value_classes();
    test_tonemap_sweep();
    test_tonemap_monotonic();
    test_tonemap_film();
    test_srgb_decode();
    test_metrics_analytic();
    test_metrics_oracle();
    test_error_map();
    return check_finish("test_post");
}
