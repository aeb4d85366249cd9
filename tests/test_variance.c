/* test_variance.c - the variance pass (TR_PASS_VARIANCE): per pixel, the variance of the
 * mean radiance, from the film's sums of squares.
 *
 * 1. Constant radiance: a camera that sees nothing but a two-sided emitter gets the
 *    emitter's radiance from every sample, so every pixel's variance is 0 (and its mean
 *    the emitter's radiance: the camera does see it).
 * 2. Noisy radiance: K renders of a lit floor with independent seeds. With independent
 *    samples (naive's random numbers), at every pixel the layer (averaged over the K
 *    renders) and the empirical variance of the K pixel means are both unbiased estimates
 *    of the same number, sigma^2 / n; their difference, averaged over the pixels, must be
 *    within 4 of its own standard errors of 0, and that standard error must be small
 *    against the variance itself (so a layer off by a factor, e.g. the variance of one
 *    sample instead of the mean's, cannot pass). pt's stratified samples converge faster
 *    than independent ones: there the layer must not be below the empirical variance.
 * 3. The sums of squares are bit-identical whatever the thread count, and the layer is
 *    what tr_film_pass_pixel, tr_film_extract_pass and tr_film_variance agree on. */
#include "check.h"
#include "scene_util.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 24
#define H 16

static void render(const tr_scene *s, const tr_camera *cam, int integrator, uint64_t seed,
                   uint32_t spp, int threads, tr_film *film) {
    tr_error err;
    CHECK(tr_film_init_passes(film, cam->screen_width, cam->screen_height, TR_PASS_VARIANCE,
                              &err) == TR_OK,
          "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_VARIANCE;
    cfg.integrator = integrator;
    cfg.seed = seed;
    cfg.threads = threads;
    for (uint32_t k = 0; k < spp; ++k) {
        CHECK(tr_render_frame(s, cam, &cfg, film, k, NULL, &err) == TR_OK, "%s", err.msg);
    }
}

static void test_constant(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    /* Radiance (1, 0.5, 2): exact in binary, as are its multiples and squares. */
    tr_material m = tr_material_emitter(v3(0.5f, 0.25f, 1.0f), 2.0f);
    m.flags |= TR_MATERIAL_TWO_SIDED;
    const uint32_t lamp = add_mat(&s, m);
    add_shape(&s, TR_SHAPE_PLANE, lamp, v3s(0.0f), v3s(0.0f), v3(1000.0f, 1.0f, 1000.0f));
    tr_error err;
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.0f, 5.0f, 0.0f), v3(0.0f, -1.0f, 0.0f), v3(0.0f, 0.0f, 1.0f),
                         60.0f, 1e-3f, 1e4f, W, H, &err) == TR_OK,
          "camera: %s", err.msg);
    tr_film f;
    render(&s, &cam, TR_INTEGRATOR_PT, 3, 16, 0, &f);
    int bad_mean = 0, bad_var = 0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            const tr_vec3 c = tr_film_pixel(&f, x, y);
            bad_mean += c.x != 1.0f || c.y != 0.5f || c.z != 2.0f;
            float v[3];
            CHECK(tr_film_pass_pixel(&f, TR_PASS_VARIANCE, x, y, v, &err) == TR_OK, "%s", err.msg);
            bad_var += v[0] != 0.0f || v[1] != 0.0f || v[2] != 0.0f;
        }
    }
    CHECK(bad_mean == 0, "%d pixels do not see the emitter's radiance", bad_mean);
    CHECK(bad_var == 0, "%d pixels of constant radiance have a variance", bad_var);
    tr_film_free(&f);
    tr_scene_clear(&s);
}

static void test_noisy(int integrator) {
    enum { K = 24, SPP = 8 };
    /* A diffuse floor under a large square lamp, seen from between them: one bounce, so
     * the radiance is bounded (no caustics, whose rare huge samples would need many more
     * renders for the same confidence) but varies with the light sample and the jitter. */
    tr_error err;
    tr_scene s = {0};
    tr_scene_init(&s);
    const uint32_t floor = add_mat(&s, tr_material_diffuse(v3(0.7f, 0.5f, 0.3f)));
    tr_material light = tr_material_emitter(v3s(1.0f), 4.0f);
    light.flags |= TR_MATERIAL_TWO_SIDED;
    const uint32_t lamp = add_mat(&s, light);
    add_shape(&s, TR_SHAPE_PLANE, floor, v3s(0.0f), v3s(0.0f), v3(100.0f, 1.0f, 100.0f));
    add_shape(&s, TR_SHAPE_PLANE, lamp, v3(1.0f, 3.0f, 0.0f), v3s(0.0f), v3(2.0f, 1.0f, 2.0f));
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.0f, 2.0f, 0.0f), v3(0.0f, -1.0f, 0.0f), v3(0.0f, 0.0f, 1.0f),
                         90.0f, 1e-3f, 1e4f, W, H, &err) == TR_OK,
          "camera: %s", err.msg);
    const size_t n = (size_t)W * H;
    double *layer = calloc(3 * n, sizeof *layer);     /* sum over renders of the layer */
    double *mean = calloc(3 * n, sizeof *mean);       /* sum over renders of the means */
    double *mean_sq = calloc(3 * n, sizeof *mean_sq); /* ... and of their squares */
    CHECK(layer && mean && mean_sq, "out of memory");
    if (!layer || !mean || !mean_sq) {
        return;
    }
    for (int k = 0; k < K; ++k) {
        tr_film f;
        render(&s, &cam, integrator, 1000u + (uint64_t)k, SPP, 0, &f);
        for (size_t i = 0; i < n; ++i) {
            CHECK(f.count[i] == SPP, "pixel %zu has %u samples", i, f.count[i]);
            for (int c = 0; c < 3; ++c) {
                const double m = f.sum[3 * i + (size_t)c] / SPP;
                layer[3 * i + (size_t)c] += tr_film_variance(&f, i, c);
                mean[3 * i + (size_t)c] += m;
                mean_sq[3 * i + (size_t)c] += m * m;
            }
        }
        tr_film_free(&f);
    }
    /* Per pixel d = (layer averaged over renders) - (empirical variance of the means),
     * summed over the channels; its mean over the pixels and that mean's standard error. */
    double sum_d = 0.0, sum_d2 = 0.0, sum_layer = 0.0;
    for (size_t i = 0; i < n; ++i) {
        double d = 0.0;
        for (size_t c = 3 * i; c < 3 * i + 3; ++c) {
            const double emp = (mean_sq[c] - mean[c] * mean[c] / K) / (K - 1);
            d += layer[c] / K - emp;
            sum_layer += layer[c] / K;
        }
        sum_d += d;
        sum_d2 += d * d;
    }
    const double dbar = sum_d / (double)n;
    const double se = sqrt((sum_d2 - sum_d * sum_d / (double)n) / (double)(n - 1) / (double)n);
    const double vbar = sum_layer / (double)n;
    const char *name = tr_integrator_name(integrator);
    printf("%s: mean layer %.4g, mean difference to the empirical variance %.3g, standard "
           "error %.3g\n",
           name, vbar, dbar, se);
    CHECK(vbar > 0.0 && se < 0.1 * vbar,
          "%s: the test has no power: mean variance %g, standard error %g", name, vbar, se);
    if (integrator == TR_INTEGRATOR_NAIVE) {
        CHECK(fabs(dbar) <= 4.0 * se,
              "%s: the variance layer (mean %g) differs from the empirical variance by %g, %.1f "
              "standard errors",
              name, vbar, dbar, se > 0.0 ? fabs(dbar) / se : INFINITY);
    } else {
        /* pt's samples are stratified (Owen-scrambled Sobol, sampler.h): the pixel's
         * actual error is below the independent-sample variance the layer reports. */
        CHECK(dbar >= -4.0 * se,
              "%s: the variance layer (mean %g) is below the empirical variance by %g, %.1f "
              "standard errors",
              name, vbar, -dbar, se > 0.0 ? -dbar / se : INFINITY);
    }
    free(layer);
    free(mean);
    free(mean_sq);
    tr_scene_clear(&s);
}

static void test_threads(void) {
    tr_error err;
    tr_scene s = {0};
    tr_scene_init(&s);
    CHECK(tr_scene_builtin(&s, "cornell", 37, 29, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film one, two;
    render(&s, &s.camera, TR_INTEGRATOR_PT, 5, 6, 1, &one);
    render(&s, &s.camera, TR_INTEGRATOR_PT, 5, 6, 2, &two);
    const size_t n = (size_t)37 * 29;
    CHECK(memcmp(one.sq, two.sq, 3 * n * sizeof(float)) == 0,
          "the sums of squares differ between 1 and 2 threads");
    /* The views of the layer agree; a film without the pass has none. */
    tr_film pass;
    CHECK(tr_film_extract_pass(&one, TR_PASS_VARIANCE, &pass, &err) == TR_OK, "%s", err.msg);
    int bad = 0, nonzero = 0;
    for (uint32_t y = 0; y < 29; ++y) {
        for (uint32_t x = 0; x < 37; ++x) {
            const size_t i = (size_t)y * 37 + x;
            float v[3];
            CHECK(tr_film_pass_pixel(&one, TR_PASS_VARIANCE, x, y, v, &err) == TR_OK, "%s",
                  err.msg);
            const tr_vec3 e = tr_film_pixel(&pass, x, y);
            bad +=
                v[0] != e.x || v[1] != e.y || v[2] != e.z || v[1] != tr_film_variance(&one, i, 1);
            nonzero += v[0] > 0.0f;
        }
    }
    CHECK(bad == 0, "%d pixels where the views of the variance disagree", bad);
    CHECK(nonzero > 0, "the Cornell box has no noise");
    tr_film plain;
    float v[3];
    CHECK(tr_film_init(&plain, 4, 4, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_film_pass_pixel(&plain, TR_PASS_VARIANCE, 0, 0, v, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "read a variance from a film without it");
    tr_film_free(&plain);
    tr_film_free(&pass);
    tr_film_free(&one);
    tr_film_free(&two);
    tr_scene_clear(&s);
}

int main(void) {
    test_constant();
    test_noisy(TR_INTEGRATOR_NAIVE);
    test_noisy(TR_INTEGRATOR_PT);
    test_threads();
    return check_finish("test_variance");
}
