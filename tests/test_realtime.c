/* test_realtime.c - the real-time frame loop (tr_realtime, realtime.h) on the CPU device.
 *
 * 1. A zeroed desc and frame desc (a camera only) render a frame of one sample at full
 *    resolution and show the film itself; a NULL desc is the zeroed one.
 * 2. Deterministic: two instances on two devices given the same frames (a moving camera,
 *    SVGF, the emission resolved; and an animated scene) give the same bits, frame after
 *    frame, while consecutive frames differ.
 * 3. At rest with `accumulate` the film adds one sample per frame and equals the render of
 *    samples 0..n-1 with the config's sampler (what `trac0r render` computes).
 * 4. The budget: moving frames with a budget no frame can hold drop to a reduced
 *    resolution level; a frame at rest is at full resolution again; a budget far above
 *    the frame's time raises the samples per frame to TR_REALTIME_MAX_SPP; the levels.
 * 5. One frame handed to several methods: each keeps its own history, so SVGF after
 *    à-trous gives what SVGF alone gives; a history continues from frame to frame and
 *    starts over when its method skipped a frame.
 * 6. Failure paths: NULL arguments, a bad desc, an unknown method, no frame yet and a
 *    cancelled frame fail with their status, and a cancel starts the view over. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "classic_box.h"
#include "trac0r/trac0r.h"

#define BW 40
#define BH 30

/* The camera of frame k: the scene's, moved sideways a little more each frame. */
static tr_camera moved_camera(const tr_camera *a, int k) {
    tr_camera b = *a;
    b.pos.x += 8.0f * (float)k;
    b.pos.y += 3.0f * (float)k;
    return b;
}

static tr_device *cpu(void) {
    tr_error err;
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev != NULL, "%s", err.msg);
    return dev;
}

static tr_realtime *make(tr_device *dev, tr_scene *s, const tr_realtime_desc *desc) {
    tr_error err;
    CHECK(tr_device_upload(dev, s, &err) == TR_OK, "%s", err.msg);
    tr_realtime *rt = tr_realtime_create(dev, s, desc, &err);
    CHECK(rt != NULL, "create: %s", err.msg);
    return rt;
}

static void test_defaults(void) {
    tr_error err;
    tr_scene *s = classic_box(BW, BH, &err);
    tr_device *dev = cpu();
    for (int null_desc = 0; null_desc < 2; ++null_desc) {
        const tr_realtime_desc desc = {0};
        tr_realtime *rt = make(dev, s, null_desc ? NULL : &desc);
        tr_realtime_frame_desc fd = {0};
        fd.camera = tr_scene_camera(s);
        tr_realtime_result res;
        CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "frame: %s", err.msg);
        CHECK(res.film && res.width == BW && res.height == BH && res.scale == 1.0f,
              "zeroed desc: %ux%u scale %g", res.width, res.height, (double)res.scale);
        CHECK(res.spp == 1 && res.frame_spp == 1 && res.method == TR_RECON_OFF && !res.rgb,
              "zeroed desc: spp %u frame_spp %u method %d", res.spp, res.frame_spp, res.method);
        double sum = 0.0;
        for (size_t i = 0; res.film && i < 3u * BW * BH; ++i) {
            sum += res.film->sum[i];
        }
        CHECK(sum > 0.0, "zeroed desc: a black frame");
        CHECK(tr_realtime_passes(rt, TR_RECON_OFF) == 0 &&
                  (tr_realtime_passes(rt, TR_RECON_SVGF) & TR_PASS_ALL) == TR_PASS_ALL,
              "passes");
        CHECK(tr_realtime_on_device(rt) == 0, "the CPU device reconstructs on the host");
        tr_realtime_destroy(rt);
    }
    tr_device_destroy(dev);
    tr_scene_destroy(s);
}

/* Frame k of instance rt into out (3 floats per pixel, BW x BH). */
static void svgf_frame(tr_realtime *rt, const tr_camera *cam, float *out) {
    tr_error err;
    tr_realtime_frame_desc fd = {0};
    fd.camera = cam;
    fd.method = TR_RECON_SVGF;
    tr_realtime_result res;
    CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "%s", err.msg);
    CHECK(res.rgb && res.width == BW && res.height == BH, "an SVGF frame has its rgb");
    if (res.rgb) {
        memcpy(out, res.rgb, 3u * BW * BH * sizeof *out);
    }
}

static void test_deterministic(void) {
    tr_error err;
    tr_scene *s = classic_box(BW, BH, &err);
    tr_device *d1 = cpu(), *d2 = cpu();
    tr_realtime_desc desc = {0};
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = 2;
    desc.config = &cfg;
    tr_realtime *a = make(d1, s, &desc);
    cfg.threads = 1; /* the result does not depend on the thread count */
    tr_realtime *b = make(d2, s, &desc);
    const size_t n = 3u * BW * BH;
    float *fa = malloc(n * sizeof *fa), *fb = malloc(n * sizeof *fb),
          *prev = calloc(n, sizeof *prev);
    for (int k = 0; k < 4; ++k) {
        const tr_camera cam = moved_camera(tr_scene_camera(s), k);
        svgf_frame(a, &cam, fa);
        svgf_frame(b, &cam, fb);
        CHECK(memcmp(fa, fb, n * sizeof *fa) == 0, "frame %d: two instances differ", k);
        CHECK(memcmp(fa, prev, n * sizeof *fa) != 0, "frame %d equals the one before", k);
        memcpy(prev, fa, n * sizeof *fa);
    }
    tr_realtime_destroy(a);
    tr_realtime_destroy(b);
    tr_device_destroy(d1);
    tr_device_destroy(d2);
    tr_scene_destroy(s);
    free(fa);
    free(fb);
    free(prev);
}

/* An animated scene, twice: the box's last shape moves before every frame. */
static void test_animated(void) {
    tr_error err;
    tr_scene *s[2] = {classic_box(BW, BH, &err), classic_box(BW, BH, &err)};
    tr_device *d[2] = {cpu(), cpu()};
    tr_realtime_desc desc = {0};
    desc.animated = 1;
    desc.accumulate = 1;
    tr_realtime *rt[2] = {make(d[0], s[0], &desc), make(d[1], s[1], &desc)};
    const size_t n = 3u * BW * BH;
    float *out[2] = {malloc(n * sizeof(float)), malloc(n * sizeof(float))};
    for (int k = 0; k < 3; ++k) {
        for (int i = 0; i < 2; ++i) {
            CHECK(tr_scene_move_shape(s[i], tr_scene_shape_count(s[i]) - 1,
                                      tr_vec3_make(20.0f, 0.0f, 0.0f), &err) == TR_OK &&
                      tr_scene_update(s[i], NULL, &err) == TR_OK &&
                      tr_device_upload(d[i], s[i], &err) == TR_OK,
                  "%s", err.msg);
            tr_realtime_frame_desc fd = {0};
            fd.camera = tr_scene_camera(s[i]);
            fd.method = TR_RECON_ACCUMULATE;
            tr_realtime_result res;
            CHECK(tr_realtime_frame(rt[i], &fd, &res, &err) == TR_OK, "%s", err.msg);
            /* Animated, no frame accumulates. */
            CHECK(res.spp == 1, "animated frame %d: %u spp", k, res.spp);
            if (res.rgb) {
                memcpy(out[i], res.rgb, n * sizeof(float));
            }
        }
        CHECK(memcmp(out[0], out[1], n * sizeof(float)) == 0, "animated frame %d differs", k);
    }
    for (int i = 0; i < 2; ++i) {
        tr_realtime_destroy(rt[i]);
        tr_device_destroy(d[i]);
        tr_scene_destroy(s[i]);
        free(out[i]);
    }
}

static void test_accumulate(void) {
    tr_error err;
    tr_scene *s = classic_box(BW, BH, &err);
    tr_device *dev = cpu();
    tr_realtime_desc desc = {0};
    desc.accumulate = 1;
    tr_realtime *rt = make(dev, s, &desc);
    tr_realtime_frame_desc fd = {0};
    fd.camera = tr_scene_camera(s);
    tr_realtime_result res;
    for (uint32_t k = 1; k <= 3; ++k) {
        CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "%s", err.msg);
        CHECK(res.spp == k && res.frame_spp == 1, "at rest frame %u: %u spp", k, res.spp);
    }
    /* The render of samples 0..2 with the default config. */
    tr_film ref;
    CHECK(tr_film_init(&ref, BW, BH, &err) == TR_OK, "%s", err.msg);
    const tr_render_config cfg = tr_render_config_default();
    for (uint32_t k = 0; k < 3; ++k) {
        CHECK(tr_render_frame(s, tr_scene_camera(s), &cfg, &ref, k, NULL, &err) == TR_OK, "%s",
              err.msg);
    }
    const tr_film *film = NULL;
    CHECK(tr_realtime_film(rt, &film, &err) == TR_OK, "%s", err.msg);
    CHECK(film && memcmp(film->sum, ref.sum, 3u * BW * BH * sizeof(float)) == 0,
          "the film at rest differs from a render of 3 samples");
    /* restart starts the film over. */
    fd.restart = 1;
    CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK && res.spp == 1, "restart: %u spp",
          res.spp);
    tr_film_free(&ref);
    tr_realtime_destroy(rt);
    tr_device_destroy(dev);
    tr_scene_destroy(s);
}

static void test_budget(void) {
    tr_error err;
    tr_scene *s = classic_box(64, 48, &err);
    tr_device *dev = cpu();
    tr_realtime_desc desc = {0};
    desc.accumulate = 1;
    tr_realtime *rt = make(dev, s, &desc);
    tr_realtime_frame_desc fd = {0};
    fd.method = TR_RECON_SVGF;
    fd.moving = 1;
    fd.budget_ms = 1e-9; /* no frame holds it */
    tr_realtime_result res;
    tr_camera cam; /* outlives the loop: the frame at rest below looks through it */
    fd.camera = &cam;
    for (int k = 0; k < 3; ++k) {
        cam = moved_camera(tr_scene_camera(s), k);
        CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "%s", err.msg);
    }
    CHECK(res.scale > 1.0f && res.width < 64 && res.height < 48 && res.frame_spp == 1,
          "a tiny budget: %ux%u, scale %g, %u spp", res.width, res.height, (double)res.scale,
          res.frame_spp);
    CHECK(res.scale == (float)64 / (float)res.width, "scale %g for width %u", (double)res.scale,
          res.width);
    /* At rest: full resolution again. */
    fd.moving = 0;
    CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "%s", err.msg);
    CHECK(res.scale == 1.0f && res.width == 64 && res.height == 48, "at rest: %ux%u", res.width,
          res.height);
    tr_realtime_destroy(rt);

    /* A budget far above any frame's time: full resolution, samples up to the most. */
    rt = make(dev, s, &desc);
    fd.moving = 1;
    fd.budget_ms = 1e9;
    for (int k = 0; k < 8; ++k) {
        cam = moved_camera(tr_scene_camera(s), k);
        CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "%s", err.msg);
    }
    CHECK(res.scale == 1.0f && res.frame_spp == TR_REALTIME_MAX_SPP,
          "a generous budget: scale %g, %u spp", (double)res.scale, res.frame_spp);
    tr_realtime_destroy(rt);
    tr_device_destroy(dev);
    tr_scene_destroy(s);

    CHECK(tr_realtime_level(0.5f) == 1.0f && tr_realtime_level(1.0f) == 1.0f &&
              tr_realtime_level(1.1f) == 1.25f && tr_realtime_level(7.0f) == 8.0f &&
              tr_realtime_level(100.0f) == 16.0f,
          "resolution levels");
}

static void test_methods(void) {
    tr_error err;
    tr_scene *s = classic_box(BW, BH, &err);
    tr_device *d1 = cpu(), *d2 = cpu();
    tr_realtime_desc desc = {0};
    desc.keep_passes = 1;
    tr_realtime *both = make(d1, s, &desc);
    tr_realtime *one = make(d2, s, &desc);
    const size_t n = 3u * BW * BH;
    float *atrous = malloc(n * sizeof *atrous);
    for (int k = 0; k < 3; ++k) {
        const tr_camera cam = moved_camera(tr_scene_camera(s), k);
        tr_realtime_frame_desc fd = {0};
        fd.camera = &cam;
        tr_realtime_result ra, rb, rc;
        CHECK(tr_realtime_render(both, &fd, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_realtime_reconstruct(both, TR_RECON_ATROUS, &ra, &err) == TR_OK, "%s", err.msg);
        memcpy(atrous, ra.rgb, n * sizeof *atrous);
        CHECK(tr_realtime_reconstruct(both, TR_RECON_SVGF, &rb, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_realtime_gbuffer(both) != NULL, "the passes on the host");
        CHECK(tr_realtime_render(one, &fd, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_realtime_reconstruct(one, TR_RECON_SVGF, &rc, &err) == TR_OK, "%s", err.msg);
        CHECK(memcmp(rb.rgb, rc.rgb, n * sizeof(float)) == 0,
              "frame %d: SVGF after a-trous differs from SVGF alone", k);
        CHECK(memcmp(atrous, rc.rgb, n * sizeof(float)) != 0, "frame %d: a-trous is SVGF", k);
    }
    free(atrous);
    tr_realtime_destroy(both);
    tr_realtime_destroy(one);
    tr_device_destroy(d1);
    tr_device_destroy(d2);
    tr_scene_destroy(s);
}

/* Three frames; method accumulate reconstructs those whose bit is set in `mask`; the
 * last frame's output into out. */
static void history_run(tr_scene *s, unsigned mask, float *out) {
    tr_error err;
    tr_device *dev = cpu();
    tr_realtime *rt = make(dev, s, NULL);
    for (int k = 0; k < 3; ++k) {
        const tr_camera cam = moved_camera(tr_scene_camera(s), k);
        tr_realtime_frame_desc fd = {0};
        fd.camera = &cam;
        fd.method = TR_RECON_ACCUMULATE;
        CHECK(tr_realtime_render(rt, &fd, &err) == TR_OK, "%s", err.msg);
        tr_realtime_result res;
        if (mask & (1u << k)) {
            CHECK(tr_realtime_reconstruct(rt, TR_RECON_ACCUMULATE, &res, &err) == TR_OK, "%s",
                  err.msg);
            if (k == 2 && res.rgb) {
                memcpy(out, res.rgb, 3u * BW * BH * sizeof *out);
            }
        }
    }
    tr_realtime_destroy(rt);
    tr_device_destroy(dev);
}

static void test_history(void) {
    tr_error err;
    tr_scene *s = classic_box(BW, BH, &err);
    const size_t n = 3u * BW * BH;
    float *all = calloc(n, sizeof *all), *gap = calloc(n, sizeof *gap);
    float *fresh = calloc(n, sizeof *fresh);
    history_run(s, 7u, all);   /* every frame: the history continues */
    history_run(s, 5u, gap);   /* frame 1 skipped: frame 2 starts over */
    history_run(s, 4u, fresh); /* frame 2 alone */
    CHECK(memcmp(gap, fresh, n * sizeof *gap) == 0, "a history continued over a skipped frame");
    CHECK(memcmp(all, fresh, n * sizeof *all) != 0, "the history was not used");
    free(all);
    free(gap);
    free(fresh);
    tr_scene_destroy(s);
}

static int always_cancel(void *user) {
    (void)user;
    return 1;
}

static void test_failures(void) {
    tr_error err;
    tr_scene *s = classic_box(BW, BH, &err);
    tr_device *dev = cpu();
    CHECK(tr_device_upload(dev, s, &err) == TR_OK, "%s", err.msg);
    CHECK(!tr_realtime_create(NULL, s, NULL, &err) && err.code == TR_STATUS_INVALID_ARGUMENT,
          "no device");
    CHECK(!tr_realtime_create(dev, NULL, NULL, &err) && err.code == TR_STATUS_INVALID_ARGUMENT,
          "no scene");
    tr_realtime_desc bad = {0};
    bad.sampler = 99;
    CHECK(!tr_realtime_create(dev, s, &bad, &err) && err.code == TR_STATUS_INVALID_ARGUMENT,
          "an unknown sampler");
    bad.sampler = 0;
    bad.spp = 100000;
    CHECK(!tr_realtime_create(dev, s, &bad, &err) && err.code == TR_STATUS_INVALID_ARGUMENT,
          "spp out of range");
    tr_render_config cfg = tr_render_config_default();
    cfg.stride = -1; /* refused: 1..64 (0 means the default, 1) */
    bad.spp = 0;
    bad.config = &cfg;
    CHECK(!tr_realtime_create(dev, s, &bad, &err) && err.code == TR_STATUS_INVALID_ARGUMENT,
          "a config tr_render_config_check refuses");
    tr_realtime_destroy(NULL);

    tr_realtime_desc desc = {0};
    desc.accumulate = 1;
    tr_realtime *rt = tr_realtime_create(dev, s, &desc, &err);
    CHECK(rt != NULL, "%s", err.msg);
    tr_realtime_frame_desc fd = {0};
    tr_realtime_result res;
    const tr_film *film = NULL;
    CHECK_STATUS(tr_realtime_frame(NULL, &fd, &res, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "no instance");
    CHECK_STATUS(tr_realtime_frame(rt, NULL, &res, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "no frame desc");
    CHECK_STATUS(tr_realtime_frame(rt, &fd, &res, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "no camera");
    fd.camera = tr_scene_camera(s);
    CHECK_STATUS(tr_realtime_frame(rt, &fd, NULL, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "no result");
    fd.method = 99;
    CHECK_STATUS(tr_realtime_frame(rt, &fd, &res, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "an unknown method");
    fd.method = TR_RECON_OFF;
    CHECK_STATUS(tr_realtime_reconstruct(rt, TR_RECON_SVGF, &res, &err), err,
                 TR_STATUS_INVALID_OPERATION, "reconstruct before a frame");
    CHECK_STATUS(tr_realtime_film(rt, &film, &err), err, TR_STATUS_INVALID_OPERATION,
                 "film before a frame");
    CHECK(tr_realtime_gbuffer(rt) == NULL, "passes before a frame");

    CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_realtime_reconstruct(rt, -1, &res, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "reconstruct an unknown method");
    CHECK_STATUS(tr_realtime_reconstruct(rt, TR_RECON_SVGF, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "reconstruct into NULL");
    fd.cancel = always_cancel;
    CHECK_STATUS(tr_realtime_frame(rt, &fd, &res, &err), err, TR_STATUS_CANCELLED, "cancelled");
    fd.cancel = NULL;
    /* The cancelled frame's film held part of a sample: the view starts over. */
    CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK && res.spp == 1, "after a cancel: %u spp",
          res.spp);
    tr_realtime_destroy(rt);
    tr_device_destroy(dev);
    tr_scene_destroy(s);
}

int main(void) {
    test_defaults();
    test_deterministic();
    test_animated();
    test_accumulate();
    test_budget();
    test_methods();
    test_history();
    test_failures();
    return check_finish("test_realtime");
}
