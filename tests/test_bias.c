/* test_bias.c - pt's default settings are unbiased on the classic Cornell box.
 *
 * The scene file (scenes/cornell-classic.json) at 48 x 48 pixels: the mean radiance of
 * each 8 x 8 block, rendered with the defaults (max depth 0: the integrator's, 64 for pt),
 * against a reference with max depth 1024 (no path of this scene gets that far: every
 * surface absorbs at least a fifth and roulette ends the paths). Each configuration is
 * rendered with R seeds; standard errors come from the spread over the seeds.
 *  (a) Paired (the same seeds, so the same paths up to the cut): the mean over the seeds
 *      of each block's difference, default minus reference, is within 6 standard errors
 *      of that difference and below 0.5 % - what the cut at 64 segments loses. The same
 *      comparison with max depth 8, the former default, must find at least one block
 *      beyond 6 standard errors and 2 % dim: the test sees the bias it guards against.
 *  (b) Independent seeds: every block of the default render within 6 standard errors of
 *      the reference (Student's t with 14 degrees of freedom: two-sided p < 1e-4).
 *  (c) The real-time roulette (TR_ROULETTE_START_REALTIME, view and bench realtime) is
 *      unbiased as (b) says, and traces at least a tenth fewer rays than the default. */
#include "check.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { W = 48, H = 48, B = 8, NB = (W / B) * (H / B), R = 8, SPP = 16 };

/* Each block's mean for each of the R seeds seed0 .. seed0 + R - 1. */
static void block_means(const tr_scene *s, int depth, int rr_start, uint64_t seed0, double m[R][NB],
                        uint64_t *rays) {
    tr_error err;
    tr_film f;
    CHECK(tr_film_init(&f, W, H, &err) == TR_OK, "%s", err.msg);
    *rays = 0;
    for (int r = 0; r < R; ++r) {
        tr_film_clear(&f);
        tr_render_config cfg = tr_render_config_default();
        cfg.max_depth = depth;
        cfg.roulette_start = rr_start;
        cfg.seed = seed0 + (uint64_t)r;
        for (uint32_t k = 0; k < SPP; ++k) {
            tr_render_stats st;
            CHECK(tr_render_frame(s, tr_scene_camera(s), &cfg, &f, k, &st, &err) == TR_OK, "%s",
                  err.msg);
            *rays += st.rays;
        }
        memset(m[r], 0, sizeof m[r]);
        for (uint32_t y = 0; y < H; ++y) {
            for (uint32_t x = 0; x < W; ++x) {
                tr_vec3 c = tr_film_pixel(&f, x, y);
                m[r][(y / B) * (W / B) + x / B] += (c.x + c.y + c.z) / (3.0 * B * B);
            }
        }
    }
    tr_film_free(&f);
}

/* Mean and standard error over the seeds of a[r][b] - (paired ? b : 0)[r][b]. */
static void stats(const double a[R][NB], const double (*b)[NB], int blk, double *mean, double *se) {
    double s1 = 0.0, s2 = 0.0;
    for (int r = 0; r < R; ++r) {
        double v = a[r][blk] - (b ? b[r][blk] : 0.0);
        s1 += v;
        s2 += v * v;
    }
    *mean = s1 / R;
    *se = sqrt(fmax(0.0, s2 / R - *mean * *mean) / (R - 1));
}

/* (a) Blocks whose paired difference lies beyond 6 standard errors; *worst the largest
 * relative difference. */
static int paired_failures(const double a[R][NB], const double ref[R][NB], double *worst) {
    int bad = 0;
    *worst = 0.0;
    for (int blk = 0; blk < NB; ++blk) {
        double d, se, m, sm;
        stats(a, ref, blk, &d, &se);
        stats(ref, NULL, blk, &m, &sm);
        *worst = fmax(*worst, fabs(d) / m);
        bad += !(fabs(d) <= 6.0 * se);
    }
    return bad;
}

/* (b) Blocks of independent renders whose means differ by more than 6 standard errors. */
static int independent_failures(const double a[R][NB], const double ref[R][NB]) {
    int bad = 0;
    for (int blk = 0; blk < NB; ++blk) {
        double ma, sa, mr, sr;
        stats(a, NULL, blk, &ma, &sa);
        stats(ref, NULL, blk, &mr, &sr);
        if (!(fabs(ma - mr) <= 6.0 * sqrt(sa * sa + sr * sr))) {
            ++bad;
            fprintf(stderr, "block %d: %.5f +- %.5f vs %.5f +- %.5f\n", blk, ma, sa, mr, sr);
        }
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
    static double ref[R][NB], def[R][NB], d8[R][NB], indep[R][NB], rt[R][NB];
    uint64_t rays_ref, rays_def, rays_8, rays_indep, rays_rt;
    block_means(s, 1024, 0, 1000, ref, &rays_ref);
    block_means(s, 0, 0, 1000, def, &rays_def);
    block_means(s, 8, 0, 1000, d8, &rays_8);
    block_means(s, 0, 0, 2000, indep, &rays_indep);
    block_means(s, 0, TR_ROULETTE_START_REALTIME, 3000, rt, &rays_rt);
    double worst_def, worst_8;
    int bad_def = paired_failures(def, ref, &worst_def);
    int bad_8 = paired_failures(d8, ref, &worst_8);
    int bad_indep = independent_failures(indep, ref);
    int bad_rt = independent_failures(rt, ref);
    printf("paired: default %d of %d blocks beyond 6 se (worst %.3f %%), max depth 8 %d (worst "
           "%.2f %%); independent seeds: %d blocks beyond 6 se\n",
           bad_def, NB, 100.0 * worst_def, bad_8, 100.0 * worst_8, bad_indep);
    CHECK(bad_def == 0 && worst_def < 0.005,
          "default depth: %d blocks differ from depth 1024, worst %.3f %%", bad_def,
          100.0 * worst_def);
    CHECK(bad_8 > 0 && worst_8 > 0.02,
          "max depth 8 is not told apart from depth 1024 (%d blocks, worst %.2f %%)", bad_8,
          100.0 * worst_8);
    CHECK(bad_indep == 0, "default settings: %d of %d blocks differ from the reference", bad_indep,
          NB);
    printf("real-time roulette: %d blocks beyond 6 se, %.3f of the default's rays\n", bad_rt,
           (double)rays_rt / (double)rays_indep);
    CHECK(bad_rt == 0, "real-time roulette: %d of %d blocks differ from the reference", bad_rt, NB);
    CHECK(rays_rt < 0.9 * (double)rays_indep, "real-time roulette: %llu rays, default %llu",
          (unsigned long long)rays_rt, (unsigned long long)rays_indep);
    for (int k = 0; k < 2; ++k) {
        tr_render_config cfg = tr_render_config_default();
        cfg.roulette_start = k ? TR_MAX_DEPTH_LIMIT + 1 : -1;
        CHECK_STATUS(tr_render_config_check(&cfg, &err), err, TR_STATUS_INVALID_ARGUMENT,
                     "roulette start out of range");
    }
    tr_scene_destroy(s);
    return check_finish("test_bias");
}
