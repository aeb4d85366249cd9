/* test_sampler.c - the pt integrator's Owen-scrambled Sobol sampler (sampler.h).
 *
 * (a) Stratification: in every pixel and dimension pair, each aligned block of 2^m
 *     samples (the first 2^m, and later ones) is a (0,m,2)-net in base 2: every
 *     elementary interval of area 2^-m holds exactly one point; a one-dimensional use
 *     puts one point in each interval of length 2^-m. Exact, on the 24-bit values.
 * (b) Convergence: the mean of the smooth integrand exp(x y) over N samples approaches
 *     its integral faster than N^-1/2 (Owen scrambling gives N^-3/2 for smooth
 *     integrands): over 128 independently scrambled pixels, the RMS error at N = 1024
 *     must be at least 4 times below the Monte Carlo error sigma / sqrt(N) and fall by
 *     more than twice the Monte Carlo factor 8 from N = 16. The RMS estimates are good to
 *     about 10 % with 128 pixels; the theory's factors are 30 and 512.
 * (c) Independence: pairs of dimensions and neighbouring pixels are uncorrelated (sample
 *     correlation within 5 standard errors of 0) and every coordinate's mean is 1/2
 *     within 5 standard errors of a uniform variable (the sampler's error is smaller).
 * (d) Determinism and range: the same address gives the same bits; values lie in [0,1).
 * (e) The sampler's bit operations against their definitions: reversal, Sobol's second
 *     dimension from its generator matrix built column by column, the Owen scramble
 *     changing each bit only as a function of the bits above it.
 * (f) The random kind (tr_sampler_make_kind with TR_SAMPLER_RANDOM, `--sampler random`):
 *     values in [0,1), the same bits for the same address, and Monte Carlo's error, not
 *     the Sobol points': the RMS error of the exp(x y) integral at N = 1024 over 128
 *     pixels lies within 0.75 and 1.33 times sigma / sqrt(N) (the RMS over 128 pixels is
 *     good to about 6 %), and the first 256 points of a pixel are no (0,8,2)-net. */
#include "check.h"
#include "exp_xy.h"
#include "kernel/sampler.h"
#include "trac0r/render.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

static uint32_t bits24(float u) {
    return (uint32_t)(u * 16777216.0f);
}

/* (a) Whether samples first .. first + 2^m - 1 of (seed, pixel, dim) form a (0,m,2)-net. */
static int is_net(uint64_t seed, uint64_t pixel, uint32_t dim, uint32_t first, int m) {
    static unsigned char hit[1 << 12];
    const uint32_t n = 1u << m;
    for (int a = 0; a <= m; ++a) {
        memset(hit, 0, n);
        for (uint32_t i = 0; i < n; ++i) {
            tr_sampler s = tr_sampler_make(seed, pixel, first + i);
            float u1, u2;
            tr_sampler_2d(&s, dim, &u1, &u2);
            uint32_t bx = a ? bits24(u1) >> (24 - a) : 0u;
            uint32_t by = m - a ? bits24(u2) >> (24 - (m - a)) : 0u;
            uint32_t box = (bx << (m - a)) | by;
            if (hit[box]++) {
                return 0;
            }
        }
    }
    return 1;
}

static int is_stratified_1d(uint64_t seed, uint64_t pixel, uint32_t dim, uint32_t first, int m) {
    static unsigned char hit[1 << 12];
    const uint32_t n = 1u << m;
    memset(hit, 0, n);
    for (uint32_t i = 0; i < n; ++i) {
        tr_sampler s = tr_sampler_make(seed, pixel, first + i);
        uint32_t box = m ? bits24(tr_sampler_1d(&s, dim)) >> (24 - m) : 0u;
        if (hit[box]++) {
            return 0;
        }
    }
    return 1;
}

static void stratification(void) {
    int bad2 = 0, bad1 = 0, tried = 0;
    for (int m = 0; m <= 12; ++m) {
        for (uint64_t pixel = 0; pixel < 6; ++pixel) {
            for (uint32_t dim = 0; dim < 7; ++dim) {
                uint32_t first = (pixel % 3) * (1u << m); /* the first block and later ones */
                ++tried;
                bad2 += !is_net(7 + pixel, pixel * 977u, dim, first, m);
                bad1 += !is_stratified_1d(7 + pixel, pixel * 977u, dim, first, m);
            }
        }
    }
    CHECK(bad2 == 0, "%d of %d blocks are not (0,m,2)-nets", bad2, tried);
    CHECK(bad1 == 0, "%d of %d one-dimensional blocks are not stratified", bad1, tried);
    /* A block that is not aligned is not a net in general: the test can fail. */
    int unaligned_nets = 0;
    for (uint64_t pixel = 0; pixel < 8; ++pixel) {
        unaligned_nets += is_net(3, pixel, 1, 5, 8);
    }
    CHECK(unaligned_nets < 8, "every unaligned block of 256 was a net (%d of 8)", unaligned_nets);
}

/* (b) (series_exp_xy: exp_xy.h) */
static double rms_error(int n, uint32_t dim, double integral) {
    const int pixels = 128;
    double se = 0.0;
    for (int p = 0; p < pixels; ++p) {
        double sum = 0.0;
        for (int i = 0; i < n; ++i) {
            tr_sampler s = tr_sampler_make(2024, (uint64_t)p, (uint32_t)i);
            float u1, u2;
            tr_sampler_2d(&s, dim, &u1, &u2);
            sum += exp((double)u1 * u2);
        }
        double e = sum / n - integral;
        se += e * e;
    }
    return sqrt(se / pixels);
}

static void convergence(void) {
    const double integral = series_exp_xy(1.0);
    const double sigma = sqrt(series_exp_xy(2.0) - integral * integral);
    for (uint32_t dim = 0; dim < 12; dim += 5) {
        double e16 = rms_error(16, dim, integral), e1024 = rms_error(1024, dim, integral);
        double mc1024 = sigma / 32.0;
        CHECK(e1024 * 4.0 < mc1024, "dim %u: RMS error %.3g at 1024 samples, Monte Carlo %.3g", dim,
              e1024, mc1024);
        CHECK(e16 / e1024 > 16.0, "dim %u: error falls only %.1f times from 16 to 1024 samples",
              dim, e16 / e1024);
        printf("dim %u: RMS error %.3g at 16, %.3g at 1024 samples (Monte Carlo %.3g, %.3g)\n", dim,
               e16, e1024, sigma / 4.0, mc1024);
    }
}

/* (c) */
static double correlation(const double *a, const double *b, int n) {
    double ma = 0, mb = 0;
    for (int i = 0; i < n; ++i) {
        ma += a[i];
        mb += b[i];
    }
    ma /= n;
    mb /= n;
    double sab = 0, saa = 0, sbb = 0;
    for (int i = 0; i < n; ++i) {
        sab += (a[i] - ma) * (b[i] - mb);
        saa += (a[i] - ma) * (a[i] - ma);
        sbb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / sqrt(saa * sbb);
}

static void independence(void) {
    enum { N = 4096 };
    static double x[4][N];
    int bad = 0;
    double worst = 0.0;
    for (uint32_t dim = 0; dim < 40; ++dim) {
        for (int i = 0; i < N; ++i) {
            /* Sample counts that are not powers of two too: N - 1 below. */
            tr_sampler s = tr_sampler_make(99, 1000, (uint32_t)i);
            tr_sampler t = tr_sampler_make(99, 1001, (uint32_t)i);
            float u1, u2, v1, v2;
            tr_sampler_2d(&s, dim, &u1, &u2);
            tr_sampler_2d(&s, dim + 1u, &v1, &v2);
            x[0][i] = u1;
            x[1][i] = v1;
            x[2][i] = v2;
            tr_sampler_2d(&t, dim, &v1, &v2);
            x[3][i] = v1;
        }
        const int n = N - 1;
        double r[4] = {correlation(x[0], x[1], n), correlation(x[0], x[2], n),
                       correlation(x[1], x[2], n), correlation(x[0], x[3], n)};
        for (int k = 0; k < 4; ++k) {
            worst = fmax(worst, fabs(r[k]));
            bad += fabs(r[k]) > 5.0 / sqrt((double)n);
        }
        double mean = 0.0;
        for (int i = 0; i < n; ++i) {
            mean += x[0][i];
        }
        mean /= n;
        bad += fabs(mean - 0.5) > 5.0 * sqrt(1.0 / 12.0 / n);
    }
    CHECK(bad == 0, "%d correlations or means beyond 5 standard errors (worst |r| %.4f)", bad,
          worst);
}

/* (d) */
static void determinism(void) {
    int bad = 0;
    for (uint32_t i = 0; i < 20000; ++i) {
        uint64_t seed = (uint64_t)i * 0x9e3779b97f4a7c15ULL, pixel = i * 31u;
        tr_sampler a = tr_sampler_make(seed, pixel, i), b = tr_sampler_make(seed, pixel, i);
        float a1, a2, b1, b2;
        tr_sampler_2d(&a, i % 50u, &a1, &a2);
        tr_sampler_1d(&b, (i + 7u) % 50u); /* another use in between changes nothing */
        tr_sampler_2d(&b, i % 50u, &b1, &b2);
        bad += memcmp(&a1, &b1, sizeof a1) != 0 || memcmp(&a2, &b2, sizeof a2) != 0;
        bad += !(a1 >= 0.0f && a1 < 1.0f && a2 >= 0.0f && a2 < 1.0f);
        bad += tr_sampler_1d(&a, i % 50u) != a1; /* the 1D use is the pair's first coordinate */
    }
    CHECK(bad == 0, "%d samples not reproducible, outside [0,1) or 1D differs from 2D", bad);
    /* Seeds, pixels and dimensions all change the values. */
    tr_sampler s = tr_sampler_make(1, 2, 3);
    tr_sampler s_seed = tr_sampler_make(2, 2, 3), s_pixel = tr_sampler_make(1, 3, 3);
    float u = tr_sampler_1d(&s, 4);
    CHECK(u != tr_sampler_1d(&s_seed, 4) && u != tr_sampler_1d(&s_pixel, 4) &&
              u != tr_sampler_1d(&s, 5),
          "seed, pixel and dimension must each change the value");
    /* Pixels whose 64-bit index differs only above bit 32. */
    tr_sampler hi = tr_sampler_make(1, 2 + ((uint64_t)1 << 40), 3);
    CHECK(u != tr_sampler_1d(&hi, 4), "the pixel index's high bits are ignored");
}

/* (e) */
static void bit_operations(void) {
    int bad = 0;
    uint32_t col[32];
    col[0] = 0x80000000u;
    for (int k = 1; k < 32; ++k) {
        col[k] = col[k - 1] ^ (col[k - 1] >> 1);
    }
    /* Column k of Sobol's second dimension holds binomial(k, j) mod 2 in bit 31 - j
     * (the Pascal matrix). */
    for (int k = 0; k < 32; ++k) {
        for (int j = 0; j < 32; ++j) {
            int pascal = j <= k && (k & j) == j; /* Lucas: C(k, j) odd iff j's bits are in k's */
            bad += pascal != (int)((col[k] >> (31 - j)) & 1u);
        }
    }
    for (uint32_t i = 0; i < 70000; i += 7) {
        uint32_t want = 0u;
        for (int k = 0; k < 32; ++k) {
            if ((i >> k) & 1u) {
                want ^= col[k];
            }
        }
        bad += tr_sobol1(i) != want;
        uint32_t r = 0;
        for (int k = 0; k < 32; ++k) {
            r |= ((i >> k) & 1u) << (31 - k);
        }
        bad += tr_reverse_bits32(i) != r;
    }
    CHECK(bad == 0, "%d Sobol or bit-reversal values wrong", bad);
    /* Owen: flipping bit k of the input leaves the output's bits above k unchanged and
     * (being a permutation) changes bit k. */
    int owen_bad = 0;
    for (uint32_t t = 0; t < 3000; ++t) {
        uint32_t x = tr_hash32(t), seed = tr_hash32(t + 12345u);
        int k = (int)(t % 32u);
        uint32_t a = tr_owen_scramble(x, seed), b = tr_owen_scramble(x ^ (1u << k), seed);
        uint32_t above = k == 31 ? 0u : ~0u << (k + 1);
        owen_bad += ((a ^ b) & above) != 0u || ((a ^ b) & (1u << k)) == 0u;
    }
    CHECK(owen_bad == 0, "%d Owen scrambles are not nested", owen_bad);
}

/* (f) */
static void random_kind(void) {
    const double integral = series_exp_xy(1.0);
    const double sigma = sqrt(series_exp_xy(2.0) - integral * integral);
    double se = 0.0;
    int bad = 0, nets = 0;
    for (int p = 0; p < 128; ++p) {
        double sum = 0.0;
        static unsigned char hit[256];
        memset(hit, 0, sizeof hit);
        for (int i = 0; i < 1024; ++i) {
            tr_sampler s = tr_sampler_make_kind(2024, (uint64_t)p, (uint32_t)i, TR_SAMPLER_RANDOM);
            tr_sampler t = tr_sampler_make_kind(2024, (uint64_t)p, (uint32_t)i, TR_SAMPLER_RANDOM);
            float u1, u2, v1, v2;
            tr_sampler_2d(&s, 3, &u1, &u2);
            tr_sampler_2d(&t, 3, &v1, &v2);
            bad += !(u1 >= 0.0f && u1 < 1.0f && u2 >= 0.0f && u2 < 1.0f) || u1 != v1 || u2 != v2 ||
                   tr_sampler_1d(&s, 3) != u1;
            sum += exp((double)u1 * u2);
            if (i < 256) { /* the 16 x 16 elementary intervals of the (0,8,2)-net */
                hit[(bits24(u1) >> 20) * 16u + (bits24(u2) >> 20)]++;
            }
        }
        int net = 1;
        for (int c = 0; c < 256; ++c) {
            net &= hit[c] == 1;
        }
        nets += net;
        double e = sum / 1024 - integral;
        se += e * e;
    }
    double rms = sqrt(se / 128), mc = sigma / 32.0;
    printf("random kind: RMS error %.3g at 1024 samples (Monte Carlo %.3g)\n", rms, mc);
    CHECK(bad == 0, "random kind: %d values out of range or not deterministic", bad);
    CHECK(rms > 0.75 * mc && rms < 1.33 * mc, "random kind: RMS error %.3g, Monte Carlo %.3g", rms,
          mc);
    CHECK(nets == 0, "random kind: %d of 128 pixels' first 256 points form a net", nets);
}

int main(void) {
    stratification();
    convergence();
    independence();
    determinism();
    bit_operations();
    random_kind();
    return check_finish("test_sampler");
}
