/* test_measure.c - measuring the renderer's error (measure.h).
 *
 * 1. tr_reference_render's own-error estimate: two references of independent seeds differ
 *    by about the sum of their own MSEs, for every sampler (the halves are independent
 *    scramblings); the reference is the film of both halves' samples.
 * 2. The scorer: the reference scored against itself has the floor's PSNR (10 dB above its
 *    own), the error left after the reference's own is what is scored, a noisy image
 *    a finite one that rises with its samples, flicker is 0 at a slot's first frame and
 *    for a still frame, a region counts its pixels.
 * 3. tr_image_flicker and tr_recovery_frames on made-up values.
 * 4. tr_convergence_measure under a sample budget (so the curves do not depend on the
 *    machine's load): every method's curve grows in samples and time, the PSNR
 *    rises, progress can cancel; tr_convergence_reach interpolates in log time.
 * 5. tr_camera_path: frame 0 without a cut is the start; a cut moves the camera; the demo
 *    animation's sway.
 * 6. Ray sets: one primary ray per pixel, a bounce per primary hit, a shadow ray per
 *    bounce at most; every structure finds the same hits on them.
 * 7. tr_ssim against the paper's definition summed directly over each pixel's 11x11
 *    window (no separation, no bands), on images narrower and shorter than the window
 *    and on one of several bands; 1 for an image against itself; the same bits for 1
 *    and 2 threads. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "classic_box.h"
#include "trac0r/trac0r.h"

#define W 32
#define H 24
#define PX ((size_t)W * H)

static tr_device *cpu_with(tr_scene *s) {
    tr_error err;
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev != NULL, "%s", err.msg);
    CHECK(tr_device_upload(dev, s, &err) == TR_OK, "%s", err.msg);
    return dev;
}

/* The ratio MSE(a, b) / (own_a + own_b) over `pairs` pairs of references of independent
 * seeds rendered with `sampler` (sums of each, so that one pair's spread counts less). */
static double own_ratio(tr_device *dev, const tr_scene *s, int sampler, int pairs, tr_film *film,
                        float *a, float *b, float *half) {
    tr_error err;
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = 1;
    cfg.sampler = sampler;
    double diff = 0.0, own = 0.0;
    for (int p = 0; p < pairs; ++p) {
        double own_a = 0.0, own_b = 0.0;
        cfg.seed = 1000u + 2u * (uint64_t)p;
        CHECK(tr_reference_render(dev, tr_scene_camera(s), &cfg, 64, film, a, half, &own_a, NULL,
                                  NULL, &err) == TR_OK,
              "%s", err.msg);
        cfg.seed += 1u;
        CHECK(tr_reference_render(dev, tr_scene_camera(s), &cfg, 64, film, b, half, &own_b, NULL,
                                  NULL, &err) == TR_OK,
              "%s", err.msg);
        CHECK(own_a > 0.0 && own_b > 0.0, "own %g %g", own_a, own_b);
        diff += tr_image_compare(a, b, PX).mse;
        own += own_a + own_b;
    }
    return diff / own;
}

static void test_reference(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    tr_device *dev = cpu_with(s);
    tr_film film;
    CHECK(tr_film_init(&film, W, H, &err) == TR_OK, "%s", err.msg);
    float *a = malloc(3 * PX * sizeof *a), *b = malloc(3 * PX * sizeof *b);
    float *half = malloc(3 * PX * sizeof *half);
    /* E[MSE(a, b)] = own_a + own_b for independent references when each own is unbiased.
     * On the diffuse box (no glossy fireflies, whose heavy tails make the ratio of 8 pairs
     * spread from 0.6 to 2 on the classic box) the ratio of 8 pairs of 32x24 references
     * spreads over 0.90-1.20 for other seeds and every sampler, so [0.85, 1.35] holds it,
     * while the estimate from consecutive halves of one Sobol sequence (the halves
     * stratified against each other, so their distance overstates the whole's error) gives
     * 0.65-0.79 with the Sobol and the screen-space Sobol samplers. */
    tr_scene *diffuse = tr_scene_create(&err);
    tr_scene_open_desc od;
    memset(&od, 0, sizeof od);
    od.request.width = W;
    od.request.height = H;
    tr_render_settings set;
    CHECK(diffuse &&
              tr_scene_open(diffuse, "builtin:cornell-diffuse", &od, NULL, &set, &err) == TR_OK,
          "%s", err.msg);
    tr_device *ddev = cpu_with(diffuse);
    static const int samplers[] = {TR_SAMPLER_SOBOL, TR_SAMPLER_RANDOM, TR_SAMPLER_ZSOBOL};
    for (int k = 0; k < 3; ++k) {
        const double r = own_ratio(ddev, diffuse, samplers[k], 8, &film, a, b, half);
        CHECK(r > 0.85 && r < 1.35, "sampler %d: MSE / own sum %.3f", samplers[k], r);
    }
    tr_device_destroy(ddev);
    tr_scene_destroy(diffuse);
    /* The reference is the whole film: samples 0..31 under the seed, then 0..31 under the
     * second half's seed, give its bits. */
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = 1;
    double own = 0.0;
    CHECK(tr_reference_render(dev, tr_scene_camera(s), &cfg, 64, &film, b, half, &own, NULL, NULL,
                              &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_device_clear(dev, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_render(dev, tr_scene_camera(s), &cfg, 0, 32, NULL, NULL, &err) == TR_OK, "%s",
          err.msg);
    tr_render_config second = cfg;
    second.seed = cfg.seed + 0x9e3779b97f4a7c15ull;
    CHECK(tr_device_render(dev, tr_scene_camera(s), &second, 0, 32, NULL, NULL, &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_device_read_film(dev, &film, &err) == TR_OK, "%s", err.msg);
    tr_film_mean(&film, half);
    CHECK(memcmp(half, b, 3 * PX * sizeof *b) == 0, "reference differs from its two halves");
    double own_a = 0.0;
    /* Too few samples and missing buffers are refused. */
    CHECK(tr_reference_render(dev, tr_scene_camera(s), &cfg, 1, &film, a, half, &own_a, NULL, NULL,
                              &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "spp 1 accepted");
    free(a);
    free(b);
    free(half);
    tr_film_free(&film);
    tr_device_destroy(dev);
    tr_scene_destroy(s);
}

static int cancel_at(void *user, uint64_t done, uint64_t total) {
    (void)total;
    return done >= *(uint64_t *)user;
}

static void test_scorer(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    tr_device *dev = cpu_with(s);
    CHECK(tr_scorer_create(W, H, 0, &err) == NULL && err.code == TR_STATUS_INVALID_ARGUMENT,
          "0 slots accepted");
    tr_scorer *sc = tr_scorer_create(W, H, 2, &err);
    CHECK(sc != NULL, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = 1;
    cfg.seed = 7;
    CHECK(tr_scorer_reference(sc, dev, tr_scene_camera(s), &cfg, 64, &err) == TR_OK, "%s", err.msg);
    double own = 0.0;
    const float *ref = tr_scorer_reference_rgb(sc, &own);
    float *copy = malloc(3 * PX * sizeof *copy);
    memcpy(copy, ref, 3 * PX * sizeof *copy);
    tr_frame_scores sr = tr_scorer_score(sc, 0, copy);
    /* The reference against itself is as good as it can tell: 10 dB above its own PSNR. */
    CHECK(own > 0.0 && fabs(sr.psnr - (tr_psnr(own) + 10.0)) < 1e-9 && sr.flicker == 0.0 &&
              isnan(sr.region_psnr),
          "self psnr %g, own %g", sr.psnr, own);
    /* The error left after the reference's own is scored; below a tenth of the reference's
     * own, the floor; with no own error known, the MSE as measured. */
    CHECK(fabs(tr_psnr_less_reference(3e-4, 1e-4) - tr_psnr(2e-4)) < 1e-12, "less own");
    CHECK(fabs(tr_psnr_less_reference(1.05e-4, 1e-4) - tr_psnr(1e-5)) < 1e-12, "floor");
    CHECK(fabs(tr_psnr_less_reference(1e-4, 0.0) - 40.0) < 1e-9 &&
              fabs(tr_psnr_less_reference(0.0, 0.0) - 120.0) < 1e-9,
          "no own");
    /* Noisy images of 1 and 16 samples: finite PSNR, rising with samples. */
    tr_film film;
    CHECK(tr_film_init(&film, W, H, &err) == TR_OK, "%s", err.msg);
    double psnr[2];
    for (int k = 0; k < 2; ++k) {
        cfg.seed = 1;
        CHECK(tr_device_clear(dev, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_device_render(dev, tr_scene_camera(s), &cfg, 0, k ? 16 : 1, NULL, NULL, &err) ==
                  TR_OK,
              "%s", err.msg);
        CHECK(tr_device_read_film(dev, &film, &err) == TR_OK, "%s", err.msg);
        tr_film_mean(&film, copy);
        psnr[k] = tr_scorer_score(sc, 1, copy).psnr;
    }
    CHECK(isfinite(psnr[0]) && psnr[1] > psnr[0] + 6.0, "psnr 1 spp %g, 16 spp %g", psnr[0],
          psnr[1]);
    /* The next frame, same camera and seed: the reference does not change, neither does
     * slot 0's output, so its flicker is 0. */
    cfg.seed = 7;
    CHECK(tr_scorer_reference(sc, dev, tr_scene_camera(s), &cfg, 64, &err) == TR_OK, "%s", err.msg);
    memcpy(copy, tr_scorer_reference_rgb(sc, NULL), 3 * PX * sizeof *copy);
    CHECK(tr_scorer_score(sc, 0, copy).flicker == 0.0, "still frame flickers");
    /* A region of the ids 1..2 of a made-up id pass: two pixels. */
    uint32_t *ids = calloc(PX, sizeof *ids);
    ids[5] = 1;
    ids[17] = 2;
    ids[40] = 3;
    CHECK(tr_scorer_region(sc, ids, 1, 3) == 2, "region count");
    CHECK(!isnan(tr_scorer_score(sc, 0, copy).region_psnr), "region psnr");
    CHECK(tr_scorer_region(sc, NULL, 1, 3) == 0, "no ids, no region");
    /* The same as a rectangle: its pixels, scored; one past the frame's edge is none. */
    const uint32_t rect[4] = {1, 2, 3, 2}, past[4] = {W - 2, 0, 3, 1};
    CHECK(tr_scorer_region_rect(sc, rect) == 6, "a 3x2 rectangle's pixels");
    CHECK(!isnan(tr_scorer_score(sc, 0, copy).region_psnr), "rectangle's psnr");
    CHECK(tr_scorer_region_rect(sc, past) == 0 && isnan(tr_scorer_score(sc, 0, copy).region_psnr),
          "a rectangle past the edge scored");
    /* A cancelled reference fails with its status. */
    uint64_t stop = 16;
    CHECK(tr_reference_render(dev, tr_scene_camera(s), &cfg, 64, &film, copy, copy, &own, cancel_at,
                              &stop, &err) == TR_ERR &&
              err.code == TR_STATUS_CANCELLED,
          "cancel");
    free(ids);
    free(copy);
    tr_film_free(&film);
    tr_scorer_destroy(sc);
    tr_device_destroy(dev);
    tr_scene_destroy(s);
}

static void test_flicker_recovery(void) {
    /* Two pixels: the output changes by +0.2 in every channel, the reference by +0.1:
     * flicker is the luminance of 0.1. */
    const float a0[6] = {0.1f, 0.1f, 0.1f, 0.5f, 0.5f, 0.5f};
    const float a1[6] = {0.3f, 0.3f, 0.3f, 0.7f, 0.7f, 0.7f};
    const float r0[6] = {0.1f, 0.1f, 0.1f, 0.5f, 0.5f, 0.5f};
    const float r1[6] = {0.2f, 0.2f, 0.2f, 0.6f, 0.6f, 0.6f};
    const double f = tr_image_flicker(a1, a0, r1, r0, 2);
    CHECK(fabs(f - 0.1) < 1e-6, "flicker %g", f);
    CHECK(tr_image_flicker(a1, a0, a1, a0, 2) == 0.0, "same change flickers");
    /* PSNR 30 for frames 0..9, a cut at 10 drops it to 20, back to 29.6 at 13. */
    tr_frame_scores fr[16];
    for (int i = 0; i < 16; ++i) {
        fr[i].psnr = i < 10 ? 30.0 : i < 13 ? 20.0 : 29.6;
        fr[i].region_psnr = i == 3 ? NAN : 10.0 + (i >= 12);
    }
    double steady = 0.0;
    CHECK(tr_recovery_frames(fr, 16, 10, 10, 0, 0.5, &steady) == 3 && steady == 30.0, "recovery %g",
          steady);
    CHECK(tr_recovery_frames(fr, 16, 10, 10, 0, 0.1, &steady) == -1, "never");
    /* The region's steady value skips the frame without one; from frame 11 on. */
    CHECK(tr_recovery_frames(fr, 16, 8, 11, 1, 0.0, &steady) == 0 && steady == 10.0, "region");
    CHECK(tr_recovery_frames(fr, 16, 0, 0, 0, 0.5, &steady) == -1 && isnan(steady), "no steady");
}

static int count_progress(void *user, uint64_t done, uint64_t total) {
    int *calls = user;
    ++*calls;
    return done > total; /* never: used is at most total */
}

static int cancel_progress(void *user, uint64_t done, uint64_t total) {
    (void)user;
    (void)total;
    return done > 0;
}

static void test_convergence(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    tr_device *devs[2] = {cpu_with(s), cpu_with(s)};
    tr_render_config cfgs[2] = {tr_render_config_default(), tr_render_config_default()};
    cfgs[0].integrator = TR_INTEGRATOR_NAIVE;
    cfgs[0].threads = cfgs[1].threads = 1;
    tr_film film;
    CHECK(tr_film_init(&film, W, H, &err) == TR_OK, "%s", err.msg);
    float *ref = malloc(3 * PX * sizeof *ref), *half = malloc(3 * PX * sizeof *half);
    double own = 0.0;
    tr_render_config rcfg = cfgs[1];
    rcfg.seed = 1234;
    CHECK(tr_reference_render(devs[1], tr_scene_camera(s), &rcfg, 256, &film, ref, half, &own, NULL,
                              NULL, &err) == TR_OK,
          "%s", err.msg);
    int calls = 0;
    tr_convergence_desc d = {.scene = s,
                             .methods = 2,
                             .devs = devs,
                             .configs = cfgs,
                             .ref = ref,
                             .ref_mse = own,
                             /* a sample budget, not a time one: the same curve under any
                              * load (the time budget is far beyond what 200 spp take) */
                             .budget = 600.0,
                             .max_spp = 200,
                             .progress = count_progress,
                             .user = &calls};
    tr_convergence_run *runs = calloc(2, sizeof *runs);
    CHECK(tr_convergence_measure(&d, runs, &err) == TR_OK, "%s", err.msg);
    CHECK(calls > 0, "no progress");
    for (int m = 0; m < 2; ++m) {
        const tr_convergence_run *r = &runs[m];
        CHECK(r->n >= 2 && r->integrator == cfgs[m].integrator && r->width == W,
              "run %d: %d points", m, r->n);
        /* the last point at the sample budget, or earlier past the stop PSNR (41 dB) */
        CHECK(r->pt[0].spp == 1 && r->pt[r->n - 1].spp <= 200 &&
                  (r->pt[r->n - 1].spp == 200 || r->pt[r->n - 1].psnr > 41.0),
              "points at %u .. %u spp", r->pt[0].spp, r->pt[r->n - 1].spp);
        for (int k = 1; k < r->n; ++k) {
            CHECK(r->pt[k].spp > r->pt[k - 1].spp && r->pt[k].seconds >= r->pt[k - 1].seconds,
                  "run %d point %d", m, k);
        }
        CHECK(r->pt[r->n - 1].psnr > r->pt[0].psnr + 3.0, "run %d: %g -> %g dB", m, r->pt[0].psnr,
              r->pt[r->n - 1].psnr);
    }
    d.progress = cancel_progress;
    CHECK(tr_convergence_measure(&d, runs, &err) == TR_ERR && err.code == TR_STATUS_CANCELLED,
          "cancel");
    d.methods = 0;
    CHECK(tr_convergence_measure(&d, runs, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "0 methods");
    /* reach: 20 dB at 1 s, 30 dB at 100 s: 25 dB halfway in log time, 10 s. */
    memset(&runs[0], 0, sizeof runs[0]);
    runs[0].n = 2;
    runs[0].pt[0].seconds = 1.0;
    runs[0].pt[0].psnr = 20.0;
    runs[0].pt[0].spp = 1;
    runs[0].pt[1].seconds = 100.0;
    runs[0].pt[1].psnr = 30.0;
    runs[0].pt[1].spp = 100;
    CHECK(fabs(tr_convergence_reach(&runs[0], 25.0, 0) - 10.0) < 1e-9, "reach time");
    CHECK(tr_convergence_reach(&runs[0], 15.0, 1) == 1.0, "reach at the first point");
    CHECK(tr_convergence_reach(&runs[0], 31.0, 0) < 0.0, "never reached");
    free(runs);
    free(ref);
    free(half);
    tr_film_free(&film);
    tr_device_destroy(devs[0]);
    tr_device_destroy(devs[1]);
    tr_scene_destroy(s);
}

static void test_camera_path(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    const tr_camera *c0 = tr_scene_camera(s);
    tr_camera c;
    CHECK(tr_camera_path(c0, 10.0f, 0, 8, 0, &c, &err) == TR_OK, "%s", err.msg);
    CHECK(fabsf(c.pos.x - c0->pos.x) < 1e-5f && fabsf(c.pos.z - c0->pos.z) < 1e-5f, "start");
    CHECK(c.right.x * c0->right.x + c.right.y * c0->right.y + c.right.z * c0->right.z > 0.9f,
          "handedness");
    tr_camera before, after;
    CHECK(tr_camera_path(c0, 10.0f, 3, 8, 4, &before, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_camera_path(c0, 10.0f, 4, 8, 4, &after, &err) == TR_OK, "%s", err.msg);
    const float dx = after.pos.x - before.pos.x, dy = after.pos.y - before.pos.y,
                dz = after.pos.z - before.pos.z;
    CHECK(sqrtf(dx * dx + dy * dy + dz * dz) > 1.5f, "the cut does not move the camera");
    /* The sway of the demo animation: frame 0 moves nothing, frame 15 a quarter of the
     * last shape's width along x (the sine's peak). */
    const uint32_t last = tr_scene_shape_count(s) - 1;
    const tr_aabb b0 = tr_scene_shape_box(s, last);
    CHECK(tr_scene_animate_sway(s, 0, &err) == TR_OK, "%s", err.msg);
    for (uint32_t f = 1; f <= 15; ++f) {
        CHECK(tr_scene_animate_sway(s, f, &err) == TR_OK, "%s", err.msg);
    }
    const tr_aabb b1 = tr_scene_shape_box(s, last);
    CHECK_NEAR(b1.min.x - b0.min.x, 0.25 * (b0.max.x - b0.min.x), 1e-3 * (b0.max.x - b0.min.x),
               "sway at frame 15");
    CHECK_NEAR(b1.min.y, b0.min.y, 0.0, "sway stays in x");
    tr_scene_destroy(s);
}

static void test_ray_sets(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_ray_sets *r = tr_ray_sets_create(s, 5, &err);
    CHECK(r != NULL, "%s", err.msg);
    const uint32_t np = tr_ray_sets_count(r, TR_RAY_PRIMARY);
    const uint32_t nd = tr_ray_sets_count(r, TR_RAY_DIFFUSE);
    const uint32_t ns = tr_ray_sets_count(r, TR_RAY_SHADOW);
    CHECK(np == PX && nd > PX / 2 && nd <= np && ns > 0 && ns <= nd, "counts %u %u %u", np, nd, ns);
    CHECK(tr_ray_sets_count(r, TR_RAY_KINDS) == 0 && tr_ray_kind_name(TR_RAY_KINDS) == NULL,
          "kind out of range");
    uint64_t hits[2][TR_RAY_KINDS];
    const tr_accel_type types[2] = {TR_ACCEL_TYPE_BVH, TR_ACCEL_TYPE_FLAT};
    for (int a = 0; a < 2; ++a) {
        CHECK(tr_scene_commit(s, types[a], &err) == TR_OK, "%s", err.msg);
        for (int k = 0; k < TR_RAY_KINDS; ++k) {
            CHECK(tr_ray_sets_trace(r, s, k, 2, 2, &hits[a][k]) >= 0.0, "trace");
        }
    }
    /* Most of the frame is the box; a bounce inside the box hits its walls. */
    CHECK(hits[0][TR_RAY_PRIMARY] > np / 2 && hits[0][TR_RAY_PRIMARY] <= np,
          "primary hits %llu of %u", (unsigned long long)hits[0][TR_RAY_PRIMARY], np);
    for (int k = 0; k < TR_RAY_KINDS; ++k) {
        CHECK(hits[0][k] == hits[1][k], "%s: bvh %llu, flat %llu", tr_ray_kind_name(k),
              (unsigned long long)hits[0][k], (unsigned long long)hits[1][k]);
    }
    CHECK(tr_ray_sets_reps(1.0) == 1 && tr_ray_sets_reps(0.001) == 51 &&
              tr_ray_sets_reps(0.0) == 1000,
          "reps");
    tr_ray_sets_destroy(r);
    tr_scene_destroy(s);
}

/* tr_measure_builds: a time for each structure timed (the flat structure builds nothing:
 * 0), 0 for one skipped, the scene left committed with the last structure not skipped
 * (each structure's builds are made in a row, in the list's order), and bad counts refused
 * before any commit. */
static void test_measure_builds(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    const tr_accel_type types[3] = {TR_ACCEL_TYPE_BVH, TR_ACCEL_TYPE_FLAT, TR_ACCEL_TYPE_BVH2};
    double ms[3] = {-1.0, -1.0, -1.0};
    CHECK(tr_measure_builds(s, types, NULL, 2, 3, ms, &err) == TR_OK, "%s", err.msg);
    CHECK(ms[0] > 0.0 && ms[1] == 0.0 && ms[2] == -1.0, "ms %g %g %g", ms[0], ms[1], ms[2]);
    CHECK(tr_scene_accel(s) == TR_ACCEL_TYPE_FLAT, "committed with %d", (int)tr_scene_accel(s));
    const int skip[3] = {0, 1, 0};
    CHECK(tr_measure_builds(s, types, skip, 3, 2, ms, &err) == TR_OK, "%s", err.msg);
    CHECK(ms[0] > 0.0 && ms[1] == 0.0 && ms[2] > 0.0, "ms %g %g %g", ms[0], ms[1], ms[2]);
    CHECK(tr_scene_accel(s) == TR_ACCEL_TYPE_BVH2, "committed with %d", (int)tr_scene_accel(s));
    CHECK(tr_measure_builds(s, types, NULL, 0, 3, ms, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "no structures");
    CHECK(tr_measure_builds(s, types, NULL, 2, TR_MEASURE_MAX_BUILDS + 1, ms, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "too many builds");
    CHECK(tr_measure_builds(s, types, NULL, 2, 0, ms, &err) == TR_ERR, "no builds");
    tr_scene_destroy(s);
}

/* A summary's means, worst frame, flicker over the frames that have one, region over the
 * frames that saw it, and frame rate, on frames built by hand. */
static void test_summary(void) {
    tr_frame_scores f[4];
    for (int i = 0; i < 4; ++i) {
        f[i] = (tr_frame_scores){.render_ms = 1.0 + i,
                                 .temporal_ms = 0.5,
                                 .spatial_ms = 0.5,
                                 .psnr = 30.0 + 2.0 * i,
                                 .ssim = 0.9,
                                 .flicker = i ? 0.3 : 0.0,
                                 .region_psnr = i == 2 ? NAN : 20.0 + i};
    }
    const tr_scores_summary s = tr_scores_summarize(f, 0, 4);
    CHECK(fabs(s.mean.render_ms - 2.5) < 1e-12 && fabs(s.total_ms - 3.5) < 1e-12 &&
              fabs(s.fps - 1000.0 / 3.5) < 1e-9,
          "times: render %g, total %g, fps %g", s.mean.render_ms, s.total_ms, s.fps);
    CHECK(fabs(s.mean.psnr - 33.0) < 1e-12 && s.psnr_min == 30.0 && fabs(s.mean.ssim - 0.9) < 1e-12,
          "psnr %g, worst %g", s.mean.psnr, s.psnr_min);
    CHECK(fabs(s.mean.flicker - 0.3) < 1e-12, "flicker %g (frame 0 has none)", s.mean.flicker);
    CHECK(s.region_frames == 3 && fabs(s.mean.region_psnr - (20.0 + 21.0 + 23.0) / 3.0) < 1e-12,
          "region: %u frames, %g dB", s.region_frames, s.mean.region_psnr);
    const tr_scores_summary late = tr_scores_summarize(f, 2, 4);
    CHECK(late.region_frames == 1 && late.mean.region_psnr == 23.0 &&
              fabs(late.mean.flicker - 0.3) < 1e-12 && late.psnr_min == 34.0,
          "frames 2..3: region %u, flicker %g, worst %g", late.region_frames, late.mean.flicker,
          late.psnr_min);
    double v[5] = {3.0, 1.0, 5.0, 2.0, 4.0};
    CHECK(tr_median(v, 5) == 3.0 && v[0] == 1.0 && v[4] == 5.0, "median of five");
    CHECK(tr_median(v, 4) == 2.5, "median of four");
    /* The process's CPU time grows while it computes. */
    const double c0 = tr_time_cpu();
    volatile double x = 0.0;
    const double w0 = tr_time_now();
    while (tr_time_cpu() - c0 < 0.02 && tr_time_now() - w0 < 5.0) {
        for (int i = 0; i < 100000; ++i) {
            x = x + 1e-9;
        }
    }
    CHECK(tr_time_cpu() > c0 && x > 0.0, "CPU time %g after %g", tr_time_cpu(), c0);
    const tr_scores_summary none = tr_scores_summarize(f, 2, 3);
    CHECK(none.region_frames == 0 && isnan(none.mean.region_psnr), "no region seen");
}

/* SSIM straight from Wang et al. 2004's definition: per pixel, the 11x11 Gaussian window
 * (sigma 1.5) over the pixels inside the image, its weights renormalised. */
static double ssim_direct(const float *a, const float *b, int w, int h) {
    double sum = 0.0;
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            double m[5] = {0.0, 0.0, 0.0, 0.0, 0.0}, wsum = 0.0;
            for (int dy = -5; dy <= 5; ++dy) {
                for (int dx = -5; dx <= 5; ++dx) {
                    const int yy = y + dy, xx = x + dx;
                    if (yy < 0 || yy >= h || xx < 0 || xx >= w) {
                        continue;
                    }
                    const double g = exp(-(double)(dx * dx + dy * dy) / (2.0 * 1.5 * 1.5));
                    double l[2];
                    const float *p[2] = {a + 3 * ((size_t)yy * w + xx),
                                         b + 3 * ((size_t)yy * w + xx)};
                    for (int k = 0; k < 2; ++k) {
                        double c[3];
                        for (int j = 0; j < 3; ++j) {
                            c[j] = p[k][j] != p[k][j] ? 0.0 : fmin(fmax(p[k][j], 0.0), 1.0);
                        }
                        l[k] = 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
                    }
                    m[0] += g * l[0];
                    m[1] += g * l[1];
                    m[2] += g * l[0] * l[0];
                    m[3] += g * l[1] * l[1];
                    m[4] += g * l[0] * l[1];
                    wsum += g;
                }
            }
            for (int k = 0; k < 5; ++k) {
                m[k] /= wsum;
            }
            const double vx = m[2] - m[0] * m[0], vy = m[3] - m[1] * m[1], cxy = m[4] - m[0] * m[1];
            const double c1 = 1e-4, c2 = 9e-4;
            sum += (2.0 * m[0] * m[1] + c1) * (2.0 * cxy + c2) /
                   ((m[0] * m[0] + m[1] * m[1] + c1) * (vx + vy + c2));
        }
    }
    return sum / ((double)w * h);
}

static void test_ssim(void) {
    /* (w, h): a pixel, narrower and shorter than the window, one band, several bands with
     * threads (over 65536 pixels) and a last band cut short. */
    static const int sizes[][2] = {{1, 1}, {7, 3}, {4, 40}, {40, 23}, {300, 233}};
    uint32_t state = 12345u;
    for (size_t t = 0; t < sizeof sizes / sizeof sizes[0]; ++t) {
        const int w = sizes[t][0], h = sizes[t][1];
        const size_t n = 3 * (size_t)w * h;
        float *a = malloc(n * sizeof *a), *b = malloc(n * sizeof *b);
        CHECK(a && b, "out of memory");
        for (size_t i = 0; i < n; ++i) {
            /* A ramp with noise, partly outside [0, 1], and a NaN: the clamp is tested. */
            state = state * 1664525u + 1013904223u;
            const float u = (float)(state >> 8) / 16777216.0f;
            a[i] = (float)(i % (3 * (size_t)w)) / (float)(3 * w) + 0.4f * u - 0.1f;
            b[i] = 0.8f * a[i] + 0.3f * (float)((state >> 4) & 0xff) / 255.0f;
        }
        a[n / 2] = NAN;
        const double got = tr_ssim(a, b, (uint32_t)w, (uint32_t)h);
        const double want = ssim_direct(a, b, w, h);
        CHECK(fabs(got - want) < 1e-12, "%dx%d: ssim %.15f, direct %.15f", w, h, got, want);
        CHECK(want > 0.05 && want < 0.95, "%dx%d: the images neither alike nor unrelated: %g", w, h,
              want);
        const double self = tr_ssim(b, b, (uint32_t)w, (uint32_t)h);
        CHECK(fabs(self - 1.0) < 1e-12, "%dx%d: ssim against itself %.15f", w, h, self);
        if (w * h >= 65536) {
            omp_set_num_threads(1);
            const double one = tr_ssim(a, b, (uint32_t)w, (uint32_t)h);
            omp_set_num_threads(2);
            const double two = tr_ssim(a, b, (uint32_t)w, (uint32_t)h);
            CHECK(one == two && one == got, "threads: %.17g (1) %.17g (2) %.17g", one, two, got);
        }
        free(a);
        free(b);
    }
    CHECK(isnan(tr_ssim(NULL, NULL, 0, 5)), "an empty image has no SSIM");
}

int main(void) {
    test_ssim();
    test_reference();
    test_summary();
    test_scorer();
    test_flicker_recovery();
    test_convergence();
    test_camera_path();
    test_ray_sets();
    test_measure_builds();
    return check_finish("test_measure");
}
