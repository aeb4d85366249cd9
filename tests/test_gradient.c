/* test_gradient.c - temporal gradients of the real-time loop (tr_recon_params.gradients,
 * src/realtime/gradient.h) on the built-in box at 48x36, SVGF at one sample per pixel,
 * its light switched by tr_scene_animate_light (on for frames 0-7, off 8-15, on 16-23).
 *
 * 1. After the light switches off, the 4th frame (frame 11) is dark: its mean is below 1 %
 *    of the lit frames' (no ghost), where without gradients the lagging history keeps
 *    it above 3 %. After it switches on again, from the 4th frame (frame 19) on the mean
 *    is within 1 % of the lit mean of a run whose light never switched (without
 *    gradients it is more than 3 % darker at frame 19), and the error against a
 *    converged render (as displayed, clipped at 1) is within 1.1 times that run's.
 * 2. A static scene and light, the camera still or panning: gradients measured on every
 *    frame after the first, none changed, and every frame's bits are those without
 *    gradients.
 * 3. With gradients, the light switching and the camera panning, the switches are
 *    measured and 1 and 2 threads give the same bits, frame after frame. */
#include "gradient_run.h"

static double mse(const float *a, const float *b) {
    double sum = 0.0;
    for (uint32_t i = 0; i < N; ++i) {
        /* As displayed: values above 1 (the lamp) clip. */
        const double d = fmin((double)a[i], 1.0) - fmin((double)b[i], 1.0);
        sum += d * d;
    }
    return sum / N;
}

/* On the CPU. */
static void run(int gradients, int mode, int threads, int move_camera, float *out, int *valid,
                uint32_t *changed) {
    run_on("cpu", gradients, mode, threads, move_camera, out, valid, changed, NULL);
}

/* The lit box converged: 256 samples per pixel. */
static void reference(float *ref) {
    tr_error err;
    tr_scene *s = box();
    tr_film film;
    CHECK(tr_film_init(&film, W, H, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    for (uint32_t k = 0; k < 256; ++k) {
        CHECK(tr_render_frame(s, tr_scene_camera(s), &cfg, &film, k, NULL, &err) == TR_OK, "%s",
              err.msg);
    }
    for (uint32_t i = 0; i < W * H; ++i) {
        for (int c = 0; c < 3; ++c) {
            ref[3 * i + c] = film.count[i] ? film.sum[3 * i + c] / (float)film.count[i] : 0.0f;
        }
    }
    tr_film_free(&film);
    tr_scene_destroy(s);
}

static void test_switch(void) {
    float *ref = malloc(N * sizeof(float));
    float *steady = malloc((size_t)FRAMES * N * sizeof(float));
    float *with = malloc((size_t)FRAMES * N * sizeof(float));
    float *without = malloc((size_t)FRAMES * N * sizeof(float));
    reference(ref);
    run(1, TR_LIGHT_ANIMATION_NONE, 0, 0, steady, NULL, NULL);
    run(1, TR_LIGHT_ANIMATION_SWITCH, 0, 0, with, NULL, NULL);
    run(0, TR_LIGHT_ANIMATION_SWITCH, 0, 0, without, NULL, NULL);
    const double lit = mean_of(steady + 7u * N);
    for (int f = 0; f < FRAMES; ++f) {
        fprintf(stderr, "frame %2d: mean %.4f %.4f %.4f  mse %.3g %.3g %.3g\n", f,
                mean_of(steady + (size_t)f * N), mean_of(with + (size_t)f * N),
                mean_of(without + (size_t)f * N), mse(steady + (size_t)f * N, ref),
                mse(with + (size_t)f * N, ref), mse(without + (size_t)f * N, ref));
    }
    /* Off: the 4th frame is dark. */
    const double off_with = mean_of(with + 11u * N), off_without = mean_of(without + 11u * N);
    CHECK(off_with < 0.01 * lit, "off, 4th frame: mean %g of lit %g (a ghost)", off_with, lit);
    CHECK(off_without > 0.03 * lit, "without gradients the history lags: %g of %g", off_without,
          lit);
    /* On again: from the 4th frame the mean is the steady run's (no dark ghost) and the
     * error is back to the steady run's. */
    for (uint32_t f = 19; f < FRAMES; ++f) {
        const double ms = mean_of(steady + f * N);
        const double dw = fabs(mean_of(with + f * N) - ms),
                     dn = fabs(mean_of(without + f * N) - ms);
        CHECK(dw < 0.01 * lit, "on again, frame %u: mean %g off the steady run's", f, dw);
        CHECK(f > 19 || dn > 0.03 * lit, "without gradients, frame %u: %g", f, dn);
        const double e_steady = mse(steady + f * N, ref), e_with = mse(with + f * N, ref);
        CHECK(e_with < 1.1 * e_steady, "on again, frame %u: error %g, steady %g", f, e_with,
              e_steady);
    }
    free(ref);
    free(steady);
    free(with);
    free(without);
}

static void test_static(void) {
    check_static("cpu");
}

static void test_threads(void) {
    float *a = malloc((size_t)FRAMES * N * sizeof(float));
    float *b = malloc((size_t)FRAMES * N * sizeof(float));
    int valid[FRAMES];
    uint32_t changed[FRAMES];
    run(1, TR_LIGHT_ANIMATION_SWITCH, 1, 1, a, valid, changed);
    run(1, TR_LIGHT_ANIMATION_SWITCH, 2, 1, b, NULL, NULL);
    CHECK(changed[8] > 0 && changed[16] > 0, "the switches are measured: %u, %u", changed[8],
          changed[16]);
    CHECK(memcmp(a, b, (size_t)FRAMES * N * sizeof(float)) == 0, "1 and 2 threads differ");
    free(a);
    free(b);
}

int main(void) {
    test_switch();
    test_static();
    test_threads();
    return check_finish("test_gradient");
}
