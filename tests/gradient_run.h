/* gradient_run.h - the real-time runs the temporal gradients' tests share
 * (test_gradient.c on the CPU, test_opencl_gradient.c on an OpenCL device): the built-in
 * box at 48x36, SVGF at one sample per pixel, its light animated by
 * tr_scene_animate_light. */
#ifndef TR_TESTS_GRADIENT_RUN_H
#define TR_TESTS_GRADIENT_RUN_H

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "device/opencl.h"
#include "scene_util.h"
#include "trac0r/trac0r.h"

#define W 48
#define H 36
#define FRAMES 24
#define N (3u * W * H)

static tr_scene *box(void) {
    return committed_builtin("cornell", W, H);
}

static double mean_of(const float *a) {
    double sum = 0.0;
    for (uint32_t i = 0; i < N; ++i) {
        sum += a[i];
    }
    return sum / N;
}

/* FRAMES frames of SVGF on device `device` into out (FRAMES x N floats); `mode` the light
 * animation. *film_reads (may be NULL; OpenCL devices) gets how many times the frames read
 * the device's film back. */
static uint64_t device_film_reads(const tr_device *dev) {
    const tr_cl_context *cl = tr_device_cl_context(dev);
    return cl ? tr_cl_film_reads(cl) : 0u;
}

static void run_on(const char *device, int gradients, int mode, int threads, int move_camera,
                   float *out, int *valid, uint32_t *changed, uint64_t *film_reads) {
    tr_error err;
    tr_scene *s = box();
    tr_device *dev = tr_device_create(device, &err);
    CHECK(dev && tr_device_upload(dev, s, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = threads;
    tr_recon_params rp = tr_recon_params_default();
    rp.gradients = gradients;
    /* The histories the gradients keep or drop, compared with a steady run's, without the
     * extra samples for pixels without history: the steady run's first frame would get
     * them, the pixels whose history a switch drops would not (they are found by the
     * reprojection, not by the gradients). */
    rp.fresh_spp = 0;
    tr_realtime_desc desc = {0};
    desc.config = &cfg;
    desc.recon = &rp;
    desc.animated = 1;
    tr_realtime *rt = tr_realtime_create(dev, s, &desc, &err);
    CHECK(rt != NULL, "%s", err.msg);
    const uint64_t reads0 = dev ? device_film_reads(dev) : 0u;
    for (uint32_t f = 0; f < FRAMES && rt; ++f) {
        CHECK(tr_scene_animate_light(s, f, mode, &err) == TR_OK &&
                  tr_scene_update(s, NULL, &err) == TR_OK &&
                  tr_device_upload(dev, s, &err) == TR_OK,
              "%s", err.msg);
        tr_camera cam = *tr_scene_camera(s);
        if (move_camera) {
            /* A slow pan (half a percent of the box a frame): the gradients follow it. */
            const tr_aabb b = tr_scene_bounds(s);
            cam.pos.x += 0.005f * (b.max.x - b.min.x) * (float)f;
        }
        tr_realtime_frame_desc fd = {0};
        fd.camera = &cam;
        fd.method = TR_RECON_SVGF;
        tr_realtime_result res;
        CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK && res.rgb, "frame %u: %s", f,
              err.msg);
        if (res.rgb) {
            memcpy(out + (size_t)f * N, res.rgb, N * sizeof(float));
        }
        if (valid) {
            valid[f] = res.gradient_valid;
            changed[f] = res.gradient_changed;
        }
    }
    if (film_reads) {
        *film_reads = dev ? device_film_reads(dev) - reads0 : 0u;
    }
    tr_realtime_destroy(rt);
    tr_device_destroy(dev);
    tr_scene_destroy(s);
}

/* A static scene and light on `device`, the camera still or panning: gradients measured on
 * every frame after the first, none changed, and every frame's bits are those without
 * gradients. */
static void check_static(const char *device) {
    float *with = malloc((size_t)FRAMES * N * sizeof(float));
    float *without = malloc((size_t)FRAMES * N * sizeof(float));
    int valid[FRAMES];
    uint32_t changed[FRAMES];
    for (int move = 0; move < 2; ++move) {
        run_on(device, 1, TR_LIGHT_ANIMATION_NONE, 0, move, with, valid, changed, NULL);
        run_on(device, 0, TR_LIGHT_ANIMATION_NONE, 0, move, without, NULL, NULL, NULL);
        for (int f = 0; f < FRAMES; ++f) {
            CHECK(valid[f] == (f > 0) && changed[f] == 0,
                  "%s, camera %d, frame %d: valid %d, changed %u", device, move, f, valid[f],
                  changed[f]);
        }
        CHECK(memcmp(with, without, (size_t)FRAMES * N * sizeof(float)) == 0,
              "a static scene on %s (camera moving %d): gradients change nothing", device, move);
    }
    free(with);
    free(without);
}

#endif
