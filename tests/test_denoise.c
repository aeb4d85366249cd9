/* test_denoise.c - the offline denoiser (tr_denoise_film, src/post/denoise.c), on films
 * built sample by sample so that their sums of squares are those of a render:
 *
 * 1. A constant image and a gradient of light under a constant albedo come back unchanged
 *    (within 1 %), noiseless and noisy.
 * 2. Steps in depth, in the normal and in the albedo stay sharp: the columns on either side
 *    of the step keep their own side's value.
 * 3. A planted firefly (one sample of 60 among 16 of 0.5) is removed (its energy spread
 *    thin over the surface around it) and its neighbourhood is neither darkened nor
 *    brightened; a pixel that is bright in every sample is no firefly and keeps most of its
 *    value.
 * 4. Noise falls: the error of a noisy flat image drops several times; a converged image
 *    whose light no feature explains (stripes a pixel wide) keeps its values.
 * 5. One thread and two give the same bits; a film without the guides is refused.
 * 6. A lamp's edge: a row of pixels of which some samples met the lamp comes back near
 *    the share of the lamp its pixels see, the lamp's inside and the row beside the edge
 *    keep their values; a thin bar in front of a wall keeps its own light and the wall
 *    its own; pixels that met no surface keep their value beside a lit one.
 * 7. A sparse cluster of bright samples (an undersampled caustic: every third pixel of a
 *    disc along rows and columns has one sample of 40 among 16 of 0.4) keeps its energy
 *    within 5 % and comes out as a patch whose peak is a fraction of the planted pixels';
 *    the same with one thread and two. */
#include "check.h"
#include "trac0r/film.h"
#include "trac0r/post.h"
#include "trac0r/render.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 64
#define H 48
#define SPP 16u

static uint32_t rng_state = 1u;

/* Uniform in [-0.5, 0.5). */
static float noise(void) {
    rng_state = rng_state * 1664525u + 1013904223u;
    return (float)(rng_state >> 8) / 16777216.0f - 0.5f;
}

typedef struct px {
    float color[3], albedo[3], normal[3], depth;
} px;

typedef px (*scene_fn)(int x, int y);

/* A film of W x H with SPP samples per pixel: each sample is the pixel's colour times
 * (1 + amp * noise), summed with its square; the guides are summed noiselessly. */
static void make_film(tr_film *f, scene_fn fn, float amp, uint32_t seed) {
    rng_state = seed;
    const uint32_t passes = TR_PASS_ALBEDO | TR_PASS_NORMAL | TR_PASS_DEPTH | TR_PASS_VARIANCE;
    tr_error err;
    CHECK(tr_film_init_passes(f, W, H, passes, &err) == TR_OK, "film: %s", err.msg);
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            const size_t i = (size_t)y * W + x;
            const px p = fn(x, y);
            f->count[i] = SPP;
            for (uint32_t s = 0; s < SPP; ++s) {
                const float m = 1.0f + amp * noise();
                for (int c = 0; c < 3; ++c) {
                    const float v = p.color[c] * m;
                    f->sum[3 * i + c] += v;
                    f->sq[3 * i + c] += v * v;
                }
            }
            for (int c = 0; c < 3; ++c) {
                f->albedo[3 * i + c] = p.albedo[c] * SPP;
                f->normal[3 * i + c] = p.normal[c] * SPP;
            }
            f->depth[i] = p.depth * SPP;
        }
    }
}

static px flat(int x, int y) {
    (void)x;
    (void)y;
    const px p = {{0.4f, 0.3f, 0.2f}, {0.5f, 0.5f, 0.5f}, {0.0f, 0.0f, 1.0f}, 2.0f};
    return p;
}

static px gradient(int x, int y) {
    px p = flat(x, y);
    const float v = 0.1f + 0.8f * (float)x / (W - 1);
    p.color[0] = p.color[1] = p.color[2] = v;
    return p;
}

static px depth_step(int x, int y) {
    px p = flat(x, y);
    const int left = x < W / 2;
    p.depth = left ? 1.0f : 3.0f;
    p.color[0] = p.color[1] = p.color[2] = left ? 0.2f : 0.8f;
    return p;
}

static px normal_step(int x, int y) {
    px p = flat(x, y);
    const int left = x < W / 2;
    p.normal[0] = left ? 0.0f : 1.0f;
    p.normal[2] = left ? 1.0f : 0.0f;
    p.color[0] = p.color[1] = p.color[2] = left ? 0.7f : 0.15f;
    return p;
}

static px albedo_step(int x, int y) {
    px p = flat(x, y);
    const float a = x < W / 2 ? 0.2f : 0.8f;
    p.albedo[0] = p.albedo[1] = p.albedo[2] = a;
    p.color[0] = p.color[1] = p.color[2] = 0.5f * a; /* the same light on both */
    return p;
}

/* Light in stripes one pixel wide that no feature explains (a fine shadow pattern on a
 * flat wall). */
static px stripes(int x, int y) {
    px p = flat(x, y);
    const float v = (x & 1) ? 0.8f : 0.2f;
    p.color[0] = p.color[1] = p.color[2] = v;
    return p;
}

/* The largest relative difference of out from the noiseless scene. */
static double worst_rel(const float *out, scene_fn fn) {
    double worst = 0.0;
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            const px p = fn(x, y);
            for (int c = 0; c < 3; ++c) {
                const double d = fabs(out[3 * (y * W + x) + c] - p.color[c]) / (double)p.color[c];
                worst = d > worst ? d : worst;
            }
        }
    }
    return worst;
}

/* The mean of channel 0 of column x. */
static double column(const float *img, int x) {
    double s = 0.0;
    for (int y = 0; y < H; ++y) {
        s += img[3 * (y * W + x)];
    }
    return s / H;
}

static void denoise(const tr_film *f, float *out, int threads) {
    tr_error err;
    CHECK(tr_denoise_film(f, NULL, threads, out, &err) == TR_OK, "denoise: %s", err.msg);
}

static void test_unchanged(void) {
    static float out[3 * W * H];
    scene_fn fns[2] = {flat, gradient};
    const char *names[2] = {"constant", "gradient"};
    for (int k = 0; k < 2; ++k) {
        for (int noisy = 0; noisy < 2; ++noisy) {
            tr_film f;
            make_film(&f, fns[k], 0.0f, 7u);
            denoise(&f, out, 0);
            const double worst = worst_rel(out, fns[k]);
            CHECK(worst <= 0.01, "%s image (noiseless) changed by %.4f", names[k], worst);
            tr_film_free(&f);
            if (noisy) {
                /* Noisy: the mean of each column stays within 1 %. */
                make_film(&f, fns[k], 0.5f, 11u);
                denoise(&f, out, 0);
                for (int x = 0; x < W; ++x) {
                    const double want = fns[k](x, 0).color[0];
                    CHECK(fabs(column(out, x) - want) <= 0.01 * want,
                          "%s image (noisy): column %d mean %.4f, expected %.4f", names[k], x,
                          column(out, x), want);
                }
                tr_film_free(&f);
            }
        }
    }
}

static void test_edges(void) {
    static float out[3 * W * H];
    scene_fn fns[3] = {depth_step, normal_step, albedo_step};
    const char *names[3] = {"depth", "normal", "albedo"};
    for (int k = 0; k < 3; ++k) {
        tr_film f;
        make_film(&f, fns[k], 0.5f, 3u + (uint32_t)k);
        denoise(&f, out, 0);
        /* The last column of the left side and the first of the right keep their side's
         * value within 3 % (a blur across the step would move each half way). */
        for (int x = W / 2 - 2; x < W / 2 + 2; ++x) {
            const double want = fns[k](x, 0).color[0];
            CHECK(fabs(column(out, x) - want) <= 0.03 * want,
                  "%s step: column %d mean %.4f, expected %.4f", names[k], x, column(out, x), want);
        }
        tr_film_free(&f);
    }
}

static void test_firefly(void) {
    static float out[3 * W * H];
    tr_film f;
    make_film(&f, flat, 0.2f, 5u);
    /* Pixel (20, 20): one of its 16 samples was 60 in every channel. */
    const size_t spike = 20 * W + 20;
    for (int c = 0; c < 3; ++c) {
        const float v = f.sum[3 * spike + c] / SPP;
        f.sum[3 * spike + c] += 60.0f - v;
        f.sq[3 * spike + c] += 3600.0f - v * v;
    }
    /* Pixel (40, 30): every sample 8 times brighter than its neighbours'. */
    const size_t bright = 30 * W + 40;
    for (int c = 0; c < 3; ++c) {
        f.sum[3 * bright + c] *= 8.0f;
        f.sq[3 * bright + c] *= 64.0f;
    }
    denoise(&f, out, 0);
    const px p = flat(0, 0);
    CHECK(fabs(out[3 * spike] - p.color[0]) <= 0.05 * p.color[0],
          "the firefly is %.4f, its surroundings %.4f", out[3 * spike], p.color[0]);
    /* Its 9x9 neighbourhood, the firefly included, keeps the surroundings' mean. */
    double s = 0.0;
    for (int y = 16; y <= 24; ++y) {
        for (int x = 16; x <= 24; ++x) {
            s += out[3 * (y * W + x)];
        }
    }
    s /= 81.0;
    CHECK(fabs(s - p.color[0]) <= 0.01 * p.color[0],
          "the firefly's neighbourhood is %.4f, expected %.4f", s, p.color[0]);
    /* The steady bright pixel is not clamped to its neighbourhood before the filter: the
     * filter spreads it, but its energy (the sum over its neighbourhood above the
     * surroundings) stays more than half of what it was. */
    double excess = 0.0;
    for (int y = 25; y <= 35; ++y) {
        for (int x = 35; x <= 45; ++x) {
            excess += out[3 * (y * W + x)] - p.color[0];
        }
    }
    const double had = 7.0 * p.color[0];
    CHECK(excess > 0.5 * had, "the steady bright pixel kept %.3f of %.3f", excess, had);
    tr_film_free(&f);
}

static void test_noise_falls(void) {
    static float out[3 * W * H];
    tr_film f;
    make_film(&f, flat, 1.0f, 9u);
    denoise(&f, out, 0);
    double before = 0.0, after = 0.0;
    const float want = flat(0, 0).color[0];
    for (size_t i = 0; i < (size_t)W * H; ++i) {
        const double raw = f.sum[3 * i] / SPP - want;
        before += raw * raw;
        after += (out[3 * i] - want) * (out[3 * i] - want);
    }
    CHECK(after * 10.0 < before, "mean squared error %.3g after, %.3g before", after / (W * H),
          before / (W * H));
    tr_film_free(&f);
}

/* A converged image is not made worse: light no feature explains, rendered with little
 * noise (its samples within 1 % of the mean), comes back within 2 % everywhere, where any
 * window fit would blur the stripes into each other. */
static void test_converged_kept(void) {
    static float out[3 * W * H];
    tr_film f;
    make_film(&f, stripes, 0.02f, 17u);
    denoise(&f, out, 0);
    const double worst = worst_rel(out, stripes);
    CHECK(worst <= 0.02, "converged stripes changed by %.4f", worst);
    tr_film_free(&f);
}

static void test_threads_and_errors(void) {
    static float a[3 * W * H], b[3 * W * H];
    tr_film f;
    make_film(&f, depth_step, 0.5f, 13u);
    denoise(&f, a, 1);
    denoise(&f, b, 2);
    CHECK(memcmp(a, b, sizeof a) == 0, "1 and 2 threads differ");
    tr_film_free(&f);

    tr_film bare;
    tr_error err;
    CHECK(tr_film_init(&bare, W, H, &err) == TR_OK, "film: %s", err.msg);
    CHECK_STATUS(tr_denoise_film(&bare, NULL, 0, a, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "a film without the guides");
    tr_denoise_params p = tr_denoise_params_default();
    p.radius = 65;
    make_film(&f, flat, 0.0f, 1u);
    CHECK_STATUS(tr_denoise_film(&f, &p, 0, a, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "a window of radius 65");
    tr_film_free(&f);
    tr_film_free(&bare);
}

/* A ceiling (rows above LAMP_ROW, light 0.1) meets a lamp (rows below, emission 16 in every
 * sample) along row LAMP_ROW, which covers 1/32 of each pixel of that row: with 16 samples
 * every other pixel has one sample on the lamp and the rest none, the way a render's row
 * of pixels under a lamp's edge sees it. The lamp and the ceiling lie in one plane. */
#define LAMP_ROW 20
static void make_lamp_film(tr_film *f) {
    rng_state = 23u;
    const uint32_t passes =
        TR_PASS_ALBEDO | TR_PASS_NORMAL | TR_PASS_DEPTH | TR_PASS_VARIANCE | TR_PASS_EMISSION;
    tr_error err;
    CHECK(tr_film_init_passes(f, W, H, passes, &err) == TR_OK, "film: %s", err.msg);
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            const size_t i = (size_t)y * W + x;
            f->count[i] = SPP;
            for (uint32_t s = 0; s < SPP; ++s) {
                const int on_lamp = y > LAMP_ROW || (y == LAMP_ROW && (x & 1) == 0 && s == 0);
                const float e = on_lamp ? 16.0f : 0.0f;
                const float v = on_lamp ? e : 0.1f * (1.0f + 0.2f * noise());
                for (int c = 0; c < 3; ++c) {
                    f->sum[3 * i + c] += v;
                    f->sq[3 * i + c] += v * v;
                    f->emission[3 * i + c] += e;
                    f->albedo[3 * i + c] += 0.5f;
                }
                f->normal[3 * i + 1] += -1.0f;
                f->depth[i] += 2.0f;
            }
        }
    }
}

static void test_lamp_edge(void) {
    static float out[3 * W * H];
    tr_film f;
    make_lamp_film(&f);
    denoise(&f, out, 0);
    /* The edge row: every pixel near the row's mean (0.5 of emission, 0.1 * 15/16 of
     * ceiling on the others), where the raw pixels are 1.0 or 0.1. */
    const double want = 0.5 + 0.1 * 15.0 / 16.0;
    for (int x = 4; x < W - 4; ++x) {
        const double v = out[3 * (LAMP_ROW * W + x)];
        CHECK(fabs(v - want) <= 0.25 * want, "lamp edge pixel %d is %.3f, expected %.3f", x, v,
              want);
    }
    /* The lamp's inside and the ceiling row beside the edge keep their values: no emission
     * is spread across the edge. */
    for (int x = 0; x < W; ++x) {
        const double in = out[3 * ((LAMP_ROW + 2) * W + x)];
        const double ceiling = out[3 * ((LAMP_ROW - 1) * W + x)];
        CHECK(fabs(in - 16.0) <= 0.01 * 16.0, "lamp pixel %d is %.3f", x, in);
        CHECK(fabs(ceiling - 0.1) <= 0.03, "ceiling pixel %d beside the edge is %.3f", x, ceiling);
    }
    tr_film_free(&f);
}

/* A bar 3 pixels wide at depth 1 in front of a wall at depth 3, lit differently. */
static px thin_bar(int x, int y) {
    px p = flat(x, y);
    const int bar = x >= W / 2 && x < W / 2 + 3;
    p.depth = bar ? 1.0f : 3.0f;
    p.color[0] = p.color[1] = p.color[2] = bar ? 0.8f : 0.2f;
    return p;
}

/* The left half met no surface (no albedo, normal or depth, black); the right is a lit
 * wall. */
static px silhouette(int x, int y) {
    px p = flat(x, y);
    if (x < W / 2) {
        memset(&p, 0, sizeof p);
    }
    return p;
}

static void test_thin_and_silhouette(void) {
    static float out[3 * W * H];
    tr_film f;
    make_film(&f, thin_bar, 0.5f, 29u);
    denoise(&f, out, 0);
    for (int x = W / 2 - 2; x < W / 2 + 5; ++x) {
        const double want = thin_bar(x, 0).color[0];
        CHECK(fabs(column(out, x) - want) <= 0.03 * want,
              "thin bar: column %d mean %.4f, expected %.4f", x, column(out, x), want);
    }
    tr_film_free(&f);
    make_film(&f, silhouette, 0.5f, 31u);
    denoise(&f, out, 0);
    for (int x = 0; x < W / 2; ++x) {
        CHECK(column(out, x) == 0.0, "no surface: column %d mean %.4f, expected 0", x,
              column(out, x));
    }
    tr_film_free(&f);
}

/* Pixels of the disc of radius CLUSTER_R around (CLUSTER_X, CLUSTER_Y) whose coordinates are
 * both multiples of 3 hold one sample of CLUSTER_V in every channel in place of one of their
 * own: each is brighter than all of its 5x5 neighbours, as the few pixels of an undersampled
 * caustic that have a sample of it. */
#define CLUSTER_X 32
#define CLUSTER_Y 24
#define CLUSTER_R 9
#define CLUSTER_V 40.0f

static int in_cluster(int x, int y) {
    const int dx = x - CLUSTER_X, dy = y - CLUSTER_Y;
    return dx * dx + dy * dy <= CLUSTER_R * CLUSTER_R && x % 3 == 0 && y % 3 == 0;
}

static void test_sparse_cluster(void) {
    static float out[3 * W * H], two[3 * W * H];
    tr_film f;
    make_film(&f, flat, 0.2f, 21u);
    const px p = flat(0, 0);
    double planted = 0.0, peak_in = 0.0;
    int count = 0;
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            if (!in_cluster(x, y)) {
                continue;
            }
            const size_t i = (size_t)y * W + x;
            for (int c = 0; c < 3; ++c) {
                const float v = f.sum[3 * i + c] / SPP;
                f.sum[3 * i + c] += CLUSTER_V - v;
                f.sq[3 * i + c] += CLUSTER_V * CLUSTER_V - v * v;
            }
            planted += f.sum[3 * i] / SPP - p.color[0];
            peak_in = fmax(peak_in, f.sum[3 * i] / SPP);
            ++count;
        }
    }
    CHECK(count > 20, "the cluster has %d pixels", count);
    denoise(&f, out, 1);
    /* The energy above the surroundings, over the image, against the cluster's pixels'. */
    double excess = 0.0, peak = 0.0;
    int lit = 0;
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            const float v = out[3 * (y * W + x)];
            excess += v - p.color[0];
            peak = fmax(peak, v);
            lit += v > p.color[0] + 0.1;
        }
    }
    CHECK(fabs(excess - planted) <= 0.05 * planted,
          "the cluster's energy after denoising is %.3f, planted %.3f", excess, planted);
    CHECK(peak < 0.5 * peak_in, "the cluster's peak is %.3f, the planted pixels %.3f", peak,
          peak_in);
    CHECK(lit > 2 * count, "%d pixels are lit by the cluster, planted %d", lit, count);
    denoise(&f, two, 2);
    CHECK(memcmp(out, two, sizeof out) == 0, "the cluster: 1 and 2 threads differ");
    tr_film_free(&f);
}

int main(void) {
    test_unchanged();
    test_edges();
    test_firefly();
    test_noise_falls();
    test_converged_kept();
    test_threads_and_errors();
    test_lamp_edge();
    test_thin_and_silhouette();
    test_sparse_cluster();
    return check_finish("test_denoise");
}
