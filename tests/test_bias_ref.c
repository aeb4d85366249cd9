/* test_bias_ref.c - pt must be unbiased: every 8x8 block mean of pt's default render
 * within 3 % of a 16384-spp reference, at low resolution, with a bound from the variance.
 *
 * The classic Cornell box (scenes/cornell-classic.json) at 16 x 16 pixels: 4 blocks.
 *  - Reference: 16384 samples per pixel (1 048 576 per block), by another estimator than
 *    the one tested: independent random numbers (--sampler random) and max depth 1024 (no
 *    path of this scene gets that far), in 8 chunks of 2048 with their own seeds. 16 x 16
 *    rather than the 24 x 24 of the 2048-spp reference this test had: 4.2 M reference
 *    samples, 5 s of CPU time in a release build (9.4 M at 24 x 24 would take about 20 s
 *    on two cores). Each render is one device call (tr_device_render with a sample count):
 *    a frame per sample spends more on starting threads than on 256 pixels' paths.
 *  - Tested: the defaults (Sobol sampler, max depth 64), 8 seeds of 64 spp.
 * Standard errors come from the spread over the chunks and seeds (Student's t, 7 degrees of
 * freedom each). Every block must be within 3 % of the reference AND within 6 combined
 * standard errors of it (two-sided p < 1e-3 per block). The same check on max depth 4
 * (14 % dark in every block) must fail in some block: the test sees a bias of that kind. Max
 * depth 8, the former default, is 0.9 % dark in the worst block at this size (its dark
 * corners are a small part of a quarter of the image), which neither bound catches.
 * Sanitizer builds (ASan's slowdown) take half the samples: an 8192-spp reference. */
#include "check.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#if defined(__SANITIZE_ADDRESS__)
#define SAMPLE_SHIFT 1
#else
#define SAMPLE_SHIFT 0
#endif

enum { W = 16, H = 16, B = 8, NB = (W / B) * (H / B), R = 8 };

/* Block means (luminance) of R renders of spp samples each, seeds seed0 .. seed0 + R - 1. */
static void block_means(const tr_scene *s, int depth, int sampler, uint32_t spp, uint64_t seed0,
                        double m[R][NB]) {
    tr_error err;
    tr_film f;
    CHECK(tr_film_init(&f, W, H, &err) == TR_OK, "%s", err.msg);
    /* One device call per render: a frame per sample would spend more on starting the
     * threads of a 256-pixel frame than on its paths. */
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev != NULL && tr_device_upload(dev, s, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.max_depth = depth;
    cfg.sampler = sampler;
    for (int r = 0; r < R; ++r) {
        cfg.seed = seed0 + (uint64_t)r;
        CHECK(tr_device_clear(dev, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_device_render(dev, tr_scene_camera(s), &cfg, 0, spp, NULL, NULL, &err) == TR_OK,
              "%s", err.msg);
        CHECK(tr_device_read_film(dev, &f, &err) == TR_OK, "%s", err.msg);
        memset(m[r], 0, sizeof m[r]);
        for (uint32_t y = 0; y < H; ++y) {
            for (uint32_t x = 0; x < W; ++x) {
                tr_vec3 c = tr_film_pixel(&f, x, y);
                m[r][(y / B) * (W / B) + x / B] += (c.x + c.y + c.z) / (3.0 * B * B);
            }
        }
    }
    tr_device_destroy(dev);
    tr_film_free(&f);
}

static void stats(const double a[R][NB], int blk, double *mean, double *se) {
    double s1 = 0.0, s2 = 0.0;
    for (int r = 0; r < R; ++r) {
        s1 += a[r][blk];
        s2 += a[r][blk] * a[r][blk];
    }
    *mean = s1 / R;
    *se = sqrt(fmax(0.0, s2 / R - *mean * *mean) / (R - 1));
}

/* Blocks of a beyond 3 % or 6 standard errors of ref; *worst the largest relative gap. */
static int failures(const double a[R][NB], const double ref[R][NB], double *worst, int verbose) {
    int bad = 0;
    *worst = 0.0;
    for (int blk = 0; blk < NB; ++blk) {
        double ma, sa, mr, sr;
        stats(a, blk, &ma, &sa);
        stats(ref, blk, &mr, &sr);
        double gap = fabs(ma - mr), rel = gap / mr;
        *worst = fmax(*worst, rel);
        int ok = rel <= 0.03 && gap <= 6.0 * sqrt(sa * sa + sr * sr);
        if (!ok && verbose) {
            fprintf(stderr, "block %d: %.5f +- %.5f vs reference %.5f +- %.5f (%.2f %%)\n", blk, ma,
                    sa, mr, sr, 100.0 * rel);
        }
        bad += !ok;
    }
    return bad;
}

int main(void) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s != NULL, "%s", err.msg);
    CHECK(tr_scene_file_load(s, TR_SOURCE_DIR "/scenes/cornell-classic.json", NULL, NULL, &err) ==
              TR_OK,
          "%s", err.msg);
    tr_camera cam = *tr_scene_camera(s);
    CHECK(tr_camera_resize(&cam, W, H, &err) == TR_OK, "%s", err.msg);
    tr_scene_set_camera(s, &cam);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    static double ref[R][NB], def[R][NB], shallow[R][NB];
    const uint32_t ref_spp = 2048u >> SAMPLE_SHIFT, spp = 64u >> SAMPLE_SHIFT;
    block_means(s, 1024, TR_SAMPLER_RANDOM, ref_spp, 5000, ref);
    block_means(s, 0, TR_SAMPLER_SOBOL, spp, 6000, def);
    block_means(s, 4, TR_SAMPLER_SOBOL, spp, 6000, shallow);
    double worst_def, worst_shallow;
    int bad_def = failures(def, ref, &worst_def, 1);
    int bad_shallow = failures(shallow, ref, &worst_shallow, 0);
    printf("reference %u spp, tested %u spp: defaults %d of %d blocks off (worst %.2f %%), max "
           "depth 4 %d (worst %.2f %%)\n",
           R * ref_spp, R * spp, bad_def, NB, 100.0 * worst_def, bad_shallow,
           100.0 * worst_shallow);
    CHECK(bad_def == 0,
          "defaults: %d of %d blocks beyond 3 %% or 6 se of the reference (worst %.2f %%)", bad_def,
          NB, 100.0 * worst_def);
    CHECK(bad_shallow > 0, "max depth 4 is not told apart from the reference (worst %.2f %%)",
          100.0 * worst_shallow);
    tr_scene_destroy(s);
    return check_finish("test_bias_ref");
}
