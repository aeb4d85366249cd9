/* test_direct.c - the direct-illumination pass (TR_PASS_DIRECT) and SVGF's split filter.
 *
 * 1. With max_depth 2 every path pt traces is direct (a camera segment and one bounce),
 *    so the direct pass equals the radiance bit for bit; with max_depth 8 on the same
 *    seed the direct pass is exactly the max-depth-2 radiance (the first two segments
 *    read the same sampler dimensions and roulette starts later), and the indirect rest
 *    is positive in the Cornell box: direct = light that reaches the first surface with
 *    no further bounce, no more and no less.
 * 2. Asking for the direct pass changes neither the radiance nor the other passes.
 * 3. The naive integrator's direct part lies between 0 and its radiance; bdpt with the
 *    direct pass is refused.
 * 4. SVGF with direct and indirect apart keeps a constant image constant (any split of
 *    it), keeps the mean of a noisy frame within 1 %, and does not blur across a depth
 *    and normal step; it differs from the unsplit filter (the split is really used). */
#include "check.h"
#include "synth_frame.h"
#include "classic_box.h"
#include "render_film.h"
#include "trac0r/post.h"
#include "trac0r/scene_file.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 32
#define H 24

static tr_scene *cornell(tr_error *err) {
    return classic_box(W, H, err);
}

static void render(const tr_scene *s, int integrator, int max_depth, uint32_t passes, uint32_t spp,
                   tr_film *f) {
    render_film(s, W, H, integrator, max_depth, passes, 11, 0, spp, f);
}

static void test_pass(void) {
    tr_error err;
    tr_scene *s = cornell(&err);
    const size_t n3 = 3u * W * H;
    tr_film d2, d8, plain, all;
    render(s, TR_INTEGRATOR_PT, 2, TR_PASS_DIRECT, 4, &d2);
    render(s, TR_INTEGRATOR_PT, 8, TR_PASS_DIRECT, 4, &d8);
    CHECK(memcmp(d2.direct, d2.sum, n3 * sizeof(float)) == 0,
          "max depth 2: the direct pass is not the radiance");
    CHECK(memcmp(d8.direct, d2.sum, n3 * sizeof(float)) == 0,
          "max depth 8: the direct pass is not the max-depth-2 radiance");
    double direct = 0.0, indirect = 0.0;
    for (size_t i = 0; i < n3; ++i) {
        direct += d8.direct[i];
        indirect += d8.sum[i] - d8.direct[i];
    }
    CHECK(direct > 0.0 && indirect > 0.02 * direct,
          "the box has direct %g and indirect %g: interreflection lost", direct, indirect);

    /* The direct pass leaves radiance and the surface passes as they were. */
    render(s, TR_INTEGRATOR_PT, 8, 0u, 4, &plain);
    render(s, TR_INTEGRATOR_PT, 8, TR_PASS_ALL | TR_PASS_VARIANCE, 4, &all);
    CHECK(memcmp(plain.sum, d8.sum, n3 * sizeof(float)) == 0, "the direct pass changed radiance");
    tr_film both;
    render(s, TR_INTEGRATOR_PT, 8, TR_PASS_MASK, 4, &both);
    CHECK(memcmp(all.sum, both.sum, n3 * sizeof(float)) == 0 &&
              memcmp(all.albedo, both.albedo, n3 * sizeof(float)) == 0 &&
              memcmp(all.normal, both.normal, n3 * sizeof(float)) == 0 &&
              memcmp(all.depth, both.depth, (n3 / 3) * sizeof(float)) == 0 &&
              memcmp(all.prim, both.prim, (n3 / 3) * sizeof(uint32_t)) == 0 &&
              memcmp(all.sq, both.sq, n3 * sizeof(float)) == 0,
          "the direct pass changed another pass");
    CHECK(memcmp(both.direct, d8.direct, n3 * sizeof(float)) == 0,
          "the direct pass depends on the other passes");
    /* The pass's mean through the film API, and its name. */
    float v[3];
    CHECK(tr_film_pass_pixel(&d8, TR_PASS_DIRECT, W / 2, H / 2, v, &err) == TR_OK, "%s", err.msg);
    const size_t c = 3u * ((size_t)(H / 2) * W + W / 2);
    CHECK_NEAR(v[1], d8.direct[c + 1] / (float)d8.count[c / 3], 1e-6, "direct pass mean");
    CHECK(tr_pass_name(TR_PASS_DIRECT) && strcmp(tr_pass_name(TR_PASS_DIRECT), "direct") == 0,
          "pass name");

    /* naive: the direct part is part of the radiance, per pixel and channel. */
    tr_film nv;
    render(s, TR_INTEGRATOR_NAIVE, 8, TR_PASS_DIRECT, 4, &nv);
    size_t bad = 0;
    double nd = 0.0, nr = 0.0;
    for (size_t i = 0; i < n3; ++i) {
        bad += nv.direct[i] < 0.0f || nv.direct[i] > nv.sum[i] * (1.0f + 1e-5f) + 1e-6f;
        nd += nv.direct[i];
        nr += nv.sum[i];
    }
    CHECK(bad == 0 && nd > 0.0 && nd < nr, "naive: %zu values outside [0, radiance]; %g of %g", bad,
          nd, nr);

    /* bdpt writes no direct pass: asking for one is an error. */
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = TR_INTEGRATOR_BDPT;
    cfg.passes = TR_PASS_DIRECT;
    CHECK_STATUS(tr_render_frame(s, tr_scene_camera(s), &cfg, &nv, 0, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "bdpt with the direct pass");

    tr_film_free(&d2);
    tr_film_free(&d8);
    tr_film_free(&plain);
    tr_film_free(&all);
    tr_film_free(&both);
    tr_film_free(&nv);
    tr_scene_destroy(s);
}

/* Left half a wall facing the camera at depth 1, right half one at depth 2 turned away;
 * colour c_left / c_right plus uniform noise of amplitude `noise`, of which the fraction
 * `dfrac` is the direct part (with its own noise). Albedo 0.5. */
static void synth(tr_gbuffer *g, float c_left, float c_right, float noise, float dfrac,
                  uint32_t seed) {
    synth_frame(g, W, H, c_left, c_right, noise, dfrac, seed);
}

static tr_camera front_camera(void) {
    tr_camera cam;
    tr_error err;
    CHECK(tr_camera_make(&cam, tr_vec3_make(0, 0, -1), tr_vec3_make(0, 0, 1), tr_vec3_make(0, 1, 0),
                         60.0f, 1e-3f, 1e4f, W, H, &err) == TR_OK,
          "%s", err.msg);
    return cam;
}

/* SVGF (split or not) over `frames` frames of g, the camera still; the last output. */
static void run_svgf(const tr_gbuffer *g, int split, int frames, float *out) {
    tr_recon r;
    tr_error err;
    const tr_camera cam = front_camera();
    tr_recon_params p = tr_recon_params_default();
    p.svgf_split = split;
    CHECK(tr_recon_init(&r, W, H, &err) == TR_OK, "%s", err.msg);
    for (int f = 0; f < frames; ++f) {
        CHECK(tr_recon_frame(&r, g, &cam, TR_RECON_SVGF, &p, 2, out, &err) == TR_OK, "%s", err.msg);
    }
    tr_recon_free(&r);
}

static double mean(const float *img, int x0, int x1) {
    double s = 0.0;
    for (int y = 0; y < H; ++y) {
        for (int x = x0; x < x1; ++x) {
            for (int k = 0; k < 3; ++k) {
                s += img[3 * (y * W + x) + k];
            }
        }
    }
    return s / (3.0 * H * (x1 - x0));
}

static void test_split_filter(void) {
    tr_error err;
    tr_gbuffer g;
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    float *out = malloc(3u * W * H * sizeof *out), *ref = malloc(3u * W * H * sizeof *ref);
    CHECK(out && ref, "out of memory");
    /* A constant image stays constant however it is split (and on the first frame,
     * whose variance is the spatial estimate, as on later ones). */
    const float fracs[3] = {0.0f, 0.3f, 1.0f};
    for (int k = 0; k < 3; ++k) {
        synth(&g, 0.4f, 0.4f, 0.0f, fracs[k], 1);
        for (int frames = 1; frames <= 5; frames += 4) {
            run_svgf(&g, 1, frames, out);
            double worst = 0.0;
            for (size_t i = 0; i < 3u * W * H; ++i) {
                worst = fmax(worst, fabs(out[i] - 0.4));
            }
            CHECK(worst < 1e-5, "split %g, %d frames: a constant image moved by %g", fracs[k],
                  frames, worst);
        }
    }
    /* Energy: the mean of a noisy frame within 1 %, per side of the step; no blur
     * across the step (the right side's mean stays its own). */
    synth(&g, 0.2f, 0.8f, 0.15f, 0.4f, 7);
    run_svgf(&g, 1, 1, out);
    const double ml = mean(g.color, 0, W / 2), mr = mean(g.color, W / 2, W);
    CHECK(fabs(mean(out, 0, W / 2) - ml) < 0.01 * ml, "left mean %g, frame %g", mean(out, 0, W / 2),
          ml);
    CHECK(fabs(mean(out, W / 2, W) - mr) < 0.01 * mr, "right mean %g, frame %g",
          mean(out, W / 2, W), mr);
    CHECK(fabs(mean(out, W / 2 - 2, W / 2) - 0.2) < 0.03 &&
              fabs(mean(out, W / 2, W / 2 + 2) - 0.8) < 0.05,
          "the columns at the step blurred: %g, %g", mean(out, W / 2 - 2, W / 2),
          mean(out, W / 2, W / 2 + 2));
    /* It smooths: the noise's variance falls. */
    double vin = 0.0, vout = 0.0;
    for (int y = 0; y < H; ++y) {
        for (int x = 2; x < W / 2 - 2; ++x) {
            const double a = g.color[3 * (y * W + x)] - ml, b = out[3 * (y * W + x)] - ml;
            vin += a * a;
            vout += b * b;
        }
    }
    CHECK(vout < 0.5 * vin, "split SVGF left the noise at %g of the frame's", vout / vin);
    /* The split is used: its result differs from filtering the sum. */
    run_svgf(&g, 0, 1, ref);
    double diff = 0.0;
    for (size_t i = 0; i < 3u * W * H; ++i) {
        diff = fmax(diff, fabs(out[i] - ref[i]));
    }
    CHECK(diff > 1e-4, "split and unsplit SVGF agree to %g", diff);
    /* Without the direct pass SVGF filters the sum, split asked for or not. */
    g.has_direct = 0;
    run_svgf(&g, 1, 1, out);
    CHECK(memcmp(out, ref, 3u * W * H * sizeof *out) == 0,
          "without the direct pass the split changed SVGF");
    free(out);
    free(ref);
    tr_gbuffer_free(&g);
}

int main(void) {
    test_pass();
    test_split_filter();
    return check_finish("test_direct");
}
