/* test_sampler_z.c - the screen-space sampler `--sampler zsobol` (src/kernel/sampler_z.h).
 *
 * (a) In time: in every pixel and dimension pair, each aligned block of 2^m samples is a
 *     (0,m,2)-net, exactly as with the plain Sobol sampler.
 * (b) In space: at every sample index, the points of each aligned 2^k x 2^k block of
 *     pixels (k = 1..4) form a (0,2k,2)-net; the plain sampler's do not.
 * (c) The Z-order permutation is nested: it maps each aligned block of 4^k Morton codes
 *     one-to-one onto an aligned block of 4^k indices.
 * (d) The screen-space property on a smooth integrand, exp(x y), at one sample per pixel:
 *     the RMS error of 2x2 and 4x4 block means over 64 images x 16 blocks. With
 *     independently scrambled pixels (the plain sampler) a block mean of n pixels has the
 *     Monte Carlo error sigma / sqrt(n): checked within 15 % (1024 block means estimate
 *     the RMS to about 2.2 %, so 15 % is 7 standard errors). zsobol's must be below 0.7
 *     of that for 2x2 and 0.4 for 4x4 (a digitally shifted net; measured 0.49 and 0.23;
 *     the 16 blocks of an image share the shift, so the RMS is good to 9 % at worst, and
 *     the bounds are over 4 standard errors away).
 * (e) Unbiased and convergent: one pixel's first sample over 8192 seeds averages to the
 *     integral within 5 standard errors; over 128 pixels, the RMS error at 1024 samples is
 *     at least 4 times below sigma / sqrt(1024) and falls more than 16 times from 16
 *     samples (as test_sampler's (b)).
 * (f) Determinism and addressing: the same (seed, x, y, sample, dimension) gives the same
 *     bits whatever the pixel index (the image's width) says; values lie in [0,1); seeds,
 *     pixels, tiles beyond 65536 and dimensions change them; rendered images are the same
 *     for 1 and 2 threads, any tile size and a frame split into rectangles, and differ
 *     from the plain sampler's. */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "exp_xy.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

static uint32_t bits24(float u) {
    return (uint32_t)(u * 16777216.0f);
}

static void point(uint32_t kind, uint64_t seed, uint32_t x, uint32_t y, uint32_t i, uint32_t dim,
                  float *u1, float *u2) {
    const uint64_t index = (uint64_t)y * 1000u + x; /* an image 1000 pixels wide */
    tr_sampler s = tr_sampler_make_pixel(seed, index, x, y, i, kind);
    tr_sampler_2d(&s, dim, u1, u2);
}

/* Whether the n = 2^m points (u[j], v[j]) form a (0,m,2)-net. */
static int net(const float *u, const float *v, int m) {
    static unsigned char hit[1 << 12];
    const uint32_t n = 1u << m;
    for (int a = 0; a <= m; ++a) {
        memset(hit, 0, n);
        for (uint32_t j = 0; j < n; ++j) {
            uint32_t bx = a ? bits24(u[j]) >> (24 - a) : 0u;
            uint32_t by = m - a ? bits24(v[j]) >> (24 - (m - a)) : 0u;
            if (hit[(bx << (m - a)) | by]++) {
                return 0;
            }
        }
    }
    return 1;
}

/* (a) */
static void time_nets(void) {
    static float u[1 << 10], v[1 << 10];
    int bad = 0, tried = 0;
    for (int m = 0; m <= 10; ++m) {
        for (uint32_t p = 0; p < 5; ++p) {
            for (uint32_t dim = 0; dim < 12; dim += 3) {
                const uint32_t first = (p % 3u) << m, x = 17u * p + 3u, y = 5u * p;
                for (uint32_t j = 0; j < (1u << m); ++j) {
                    point(TR_SAMPLER_ZSOBOL, 11 + p, x, y, first + j, dim, &u[j], &v[j]);
                }
                bad += !net(u, v, m);
                ++tried;
            }
        }
    }
    CHECK(bad == 0, "%d of %d aligned sample blocks of a pixel are not nets", bad, tried);
}

/* (b) Points of the 2^k x 2^k block at (bx, by) (in blocks), sample i, in Morton order. */
static int block_net(uint32_t kind, uint64_t seed, uint32_t bx, uint32_t by, int k, uint32_t i,
                     uint32_t dim) {
    static float u[256], v[256];
    const uint32_t side = 1u << k;
    for (uint32_t y = 0; y < side; ++y) {
        for (uint32_t x = 0; x < side; ++x) {
            point(kind, seed, bx * side + x, by * side + y, i, dim, &u[y * side + x],
                  &v[y * side + x]);
        }
    }
    return net(u, v, 2 * k);
}

static void space_nets(void) {
    int bad = 0, tried = 0, plain = 0;
    for (int k = 1; k <= 4; ++k) {
        for (uint32_t i = 0; i < 40; i += 3) {
            for (uint32_t dim = 0; dim < 12; dim += 5) {
                const uint32_t bx = (i * 7u) % 11u, by = (i * 3u + dim) % 5u;
                bad += !block_net(TR_SAMPLER_ZSOBOL, 5, bx, by, k, i, dim);
                plain += block_net(TR_SAMPLER_SOBOL, 5, bx, by, k, i, dim);
                ++tried;
            }
        }
    }
    CHECK(bad == 0, "%d of %d aligned pixel blocks are not nets at one sample index", bad, tried);
    /* The plain sampler's pixels are independent: 2x2 blocks are nets by chance (about 1
     * in 10), larger ones practically never. */
    CHECK(plain < tried / 4, "%d of %d blocks of the plain sampler are nets", plain, tried);
}

/* (c) */
static void permutation(void) {
    static unsigned char seen[1 << 10];
    int bad = 0;
    for (uint32_t t = 0; t < 400; ++t) {
        const int k = 1 + (int)(t % 5u);
        const uint32_t size = 1u << (2 * k);
        const uint32_t base = tr_hash32(t) & ~(size - 1u);
        const uint32_t s1 = tr_hash32(t + 77u), s2 = tr_hash32(t + 99u);
        const uint32_t high = tr_zorder_permute(base, s1, s2) & ~(size - 1u);
        memset(seen, 0, size);
        for (uint32_t j = 0; j < size; ++j) {
            const uint32_t g = tr_zorder_permute(base | j, s1, s2);
            bad += (g & ~(size - 1u)) != high || seen[g & (size - 1u)]++ != 0;
        }
    }
    CHECK(bad == 0, "%d codes leave their block's image or collide", bad);
    /* All pairings occur: over many blocks, the Sobol pair {0,1} of a 2x2 block falls on a
     * row (codes 0,1 or 2,3) and on a column (0,2 or 1,3). */
    int rows = 0, cols = 0;
    for (uint32_t t = 0; t < 256; ++t) {
        const uint32_t base = t << 2, s1 = tr_hash32(5u), s2 = tr_hash32(6u);
        uint32_t where[4];
        for (uint32_t j = 0; j < 4; ++j) {
            where[tr_zorder_permute(base | j, s1, s2) & 3u] = j;
        }
        const uint32_t a = where[0], b = where[1];
        rows += (a ^ b) == 1u;
        cols += (a ^ b) == 2u;
    }
    CHECK(rows > 64 && cols > 64, "pairs on rows %d, on columns %d of 256", rows, cols);
}

/* (d) RMS error of the mean of exp(x y) over side x side pixel blocks at one sample. */
static double block_rms(uint32_t kind, uint32_t side, double integral) {
    double se = 0.0;
    int n = 0;
    for (uint32_t image = 0; image < 64; ++image) {
        for (uint32_t b = 0; b < 16; ++b) {
            const uint32_t x0 = (b % 4u) * side, y0 = (b / 4u) * side;
            double sum = 0.0;
            for (uint32_t y = y0; y < y0 + side; ++y) {
                for (uint32_t x = x0; x < x0 + side; ++x) {
                    float u1, u2;
                    point(kind, 1000 + image, x, y, 0, 3, &u1, &u2);
                    sum += exp((double)u1 * u2);
                }
            }
            const double e = sum / (side * side) - integral;
            se += e * e;
            ++n;
        }
    }
    return sqrt(se / n);
}

static void block_error(void) {
    const double integral = series_exp_xy(1.0);
    const double sigma = sqrt(series_exp_xy(2.0) - integral * integral);
    for (uint32_t side = 2; side <= 4; side += 2) {
        const double mc = sigma / side;
        const double plain = block_rms(TR_SAMPLER_SOBOL, side, integral);
        const double z = block_rms(TR_SAMPLER_ZSOBOL, side, integral);
        printf("%ux%u block means at 1 spp: RMS error sobol %.4g, zsobol %.4g (Monte Carlo %.4g)\n",
               side, side, plain, z, mc);
        CHECK(plain > 0.85 * mc && plain < 1.15 * mc, "%ux%u: sobol RMS %.4g, Monte Carlo %.4g",
              side, side, plain, mc);
        CHECK(z < (side == 2 ? 0.7 : 0.4) * mc, "%ux%u: zsobol RMS %.4g, Monte Carlo %.4g", side,
              side, z, mc);
    }
}

/* (e) */
static void unbiased(void) {
    const double integral = series_exp_xy(1.0);
    const double sigma = sqrt(series_exp_xy(2.0) - integral * integral);
    double sum = 0.0;
    const int seeds = 8192;
    for (int s = 0; s < seeds; ++s) {
        float u1, u2;
        point(TR_SAMPLER_ZSOBOL, (uint64_t)s * 7919u, 12, 34, 5, 2, &u1, &u2);
        sum += exp((double)u1 * u2);
    }
    const double mean = sum / seeds, se = sigma / sqrt((double)seeds);
    CHECK(fabs(mean - integral) < 5.0 * se, "mean over seeds %.6f, integral %.6f (se %.2g)", mean,
          integral, se);
    for (uint32_t dim = 0; dim < 12; dim += 5) {
        double se16 = 0.0, se1024 = 0.0;
        for (uint32_t p = 0; p < 128; ++p) {
            double acc = 0.0;
            for (uint32_t i = 0; i < 1024; ++i) {
                float u1, u2;
                point(TR_SAMPLER_ZSOBOL, 2024, p % 16u, p / 16u, i, dim, &u1, &u2);
                acc += exp((double)u1 * u2);
                if (i == 15) {
                    se16 += (acc / 16 - integral) * (acc / 16 - integral);
                }
            }
            se1024 += (acc / 1024 - integral) * (acc / 1024 - integral);
        }
        const double e16 = sqrt(se16 / 128), e1024 = sqrt(se1024 / 128);
        printf("dim %u: RMS error %.3g at 16, %.3g at 1024 samples (Monte Carlo %.3g)\n", dim, e16,
               e1024, sigma / 32.0);
        CHECK(e1024 * 4.0 < sigma / 32.0, "dim %u: RMS %.3g at 1024 samples", dim, e1024);
        CHECK(e16 / e1024 > 16.0, "dim %u: error falls only %.1f times", dim, e16 / e1024);
    }
}

/* (f) Three samples of the whole image through the CPU device, the frame in two
 * rectangles where `split`. */
static int render(const tr_scene *s, tr_film *f, int threads, uint32_t tile, int sampler,
                  int split) {
    tr_error err;
    tr_device *dev = tr_device_create("cpu", &err);
    if (!dev || tr_device_upload(dev, s, &err) != TR_OK) {
        fprintf(stderr, "device: %s\n", err.msg);
        tr_device_destroy(dev);
        return 0;
    }
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = threads;
    cfg.tile = tile;
    cfg.seed = 42;
    cfg.sampler = sampler;
    const uint32_t w = s->camera.screen_width, h = s->camera.screen_height;
    const tr_rect top = {0, 0, w, h / 3}, bottom = {0, h / 3, w, h - h / 3};
    int ok = split ? tr_device_render(dev, &s->camera, &cfg, 0, 3, &top, NULL, &err) == TR_OK &&
                         tr_device_render(dev, &s->camera, &cfg, 0, 3, &bottom, NULL, &err) == TR_OK
                   : tr_device_render(dev, &s->camera, &cfg, 0, 3, NULL, NULL, &err) == TR_OK;
    ok = ok && tr_device_read_film(dev, f, &err) == TR_OK;
    if (!ok) {
        fprintf(stderr, "render failed: %s\n", err.msg);
    }
    tr_device_destroy(dev);
    return ok;
}

static int films_equal(const tr_film *a, const tr_film *b) {
    const size_t n = (size_t)a->width * a->height;
    return memcmp(a->sum, b->sum, 3 * n * sizeof(float)) == 0;
}

static void determinism(void) {
    int bad = 0;
    for (uint32_t t = 0; t < 20000; ++t) {
        const uint64_t seed = (uint64_t)t * 0x9e3779b97f4a7c15ULL;
        const uint32_t x = t % 701u, y = t % 313u, dim = t % 40u;
        tr_sampler a = tr_sampler_make_pixel(seed, 1, x, y, t, TR_SAMPLER_ZSOBOL);
        tr_sampler b =
            tr_sampler_make_pixel(seed, (uint64_t)y * 5000u + x, x, y, t, TR_SAMPLER_ZSOBOL);
        float a1, a2, b1, b2;
        tr_sampler_2d(&a, dim, &a1, &a2);
        tr_sampler_2d(&b, dim, &b1, &b2);
        bad += memcmp(&a1, &b1, sizeof a1) != 0 || memcmp(&a2, &b2, sizeof a2) != 0;
        bad += !(a1 >= 0.0f && a1 < 1.0f && a2 >= 0.0f && a2 < 1.0f);
        bad += tr_sampler_1d(&a, dim) != a1;
    }
    CHECK(bad == 0, "%d samples not reproducible, outside [0,1) or 1D differs from 2D", bad);
    float u, w, dummy;
    point(TR_SAMPLER_ZSOBOL, 1, 2, 3, 4, 5, &u, &dummy);
    int same = 0;
    point(TR_SAMPLER_ZSOBOL, 2, 2, 3, 4, 5, &w, &dummy);
    same += u == w;
    point(TR_SAMPLER_ZSOBOL, 1, 3, 3, 4, 5, &w, &dummy);
    same += u == w;
    point(TR_SAMPLER_ZSOBOL, 1, 2, 3, 4, 6, &w, &dummy);
    same += u == w;
    point(TR_SAMPLER_ZSOBOL, 1, 2 + 65536, 3, 4, 5, &w, &dummy);
    same += u == w;
    CHECK(same == 0, "%d of seed, pixel, tile and dimension left the value unchanged", same);

    tr_error err;
    tr_scene s = {0};
    CHECK(tr_scene_builtin(&s, "cornell", 37, 29, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film a, b;
    CHECK(tr_film_init(&a, 37, 29, &err) == TR_OK && tr_film_init(&b, 37, 29, &err) == TR_OK, "%s",
          err.msg);
    CHECK(render(&s, &a, 1, 16, TR_SAMPLER_ZSOBOL, 0) && render(&s, &b, 2, 5, TR_SAMPLER_ZSOBOL, 0),
          "render");
    CHECK(films_equal(&a, &b), "1 thread, tile 16 and 2 threads, tile 5 differ");
    CHECK(render(&s, &b, 2, 16, TR_SAMPLER_ZSOBOL, 1), "render");
    CHECK(films_equal(&a, &b), "a frame split into two rectangles differs");
    CHECK(render(&s, &b, 2, 16, TR_SAMPLER_SOBOL, 0), "render");
    CHECK(!films_equal(&a, &b), "zsobol and sobol give the same image");
    tr_render_config cfg = tr_render_config_default();
    cfg.sampler = 3;
    CHECK_STATUS(tr_render_frame(&s, &s.camera, &cfg, &a, 0, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "sampler 3");
    tr_film_free(&a);
    tr_film_free(&b);
    tr_scene_clear(&s);
}

int main(void) {
    time_nets();
    space_nets();
    permutation();
    block_error();
    unbiased();
    determinism();
    return check_finish("test_sampler_z");
}
