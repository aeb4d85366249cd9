/* test_upscale.c - temporal upscaling (upscale.h) and tr_realtime's upscaled frames.
 *
 * 1. Convergence: a static view of a noise-free image with detail at the output's
 *    resolution (a checkerboard of 3 x 5 pixel cells and a smooth wave), point-sampled at
 *    the positions the kernel jitters its samples to (tr_upscale_positions) with a half
 *    and a quarter of the output's pixels traced per frame, converges to the image's
 *    pixels (their box-filtered means, what tracing every pixel converges to): PSNR
 *    rising, and at least 45 dB after 64 frames.
 * 2. A constant image stays constant, every pixel, every frame, under a moving camera
 *    (reprojection, Catmull-Rom reads, neighbourhood bounds and the spatial fill
 *    included), and the result does not depend on the thread count.
 * 3. tr_realtime on the classic box: a static view upscaled from a quarter of the pixels
 *    converges (PSNR against a converged render rising by several dB) and keeps the
 *    energy: its mean brightness within 1 % of the same pipeline's tracing every pixel
 *    (an emitter's radiance, which the passes record as its albedo, must not multiply
 *    light spread onto it), with the light upscaled apart from the albedo and without,
 *    and for the raw frame ("off", whose film keeps its passes when upscaled: with an
 *    albedo of 1 standing for a missing pass it came out 18 % dark, and its reprojection
 *    was blind without distances and ids);
 *    the frame is full size and says what it traced.
 * 4. The budget with budget_upscale: moving frames that no budget can hold stay at full
 *    resolution, tracing no fewer than a quarter of the pixels; without it they shrink.
 * 5. Failures: an upscale out of range, a camera of another size, NULL buffers, an
 *    albedo image of a scene not committed.
 * 6. The host loop (src/post/upscale.c, turned round and vectorised) gives what the
 *    per-pixel operator (src/post/upscale.h) gives, bit for bit, on every pixel of
 *    frames with detail, two surfaces at different distances (disocclusions), a
 *    primitive that moves, a moving camera and the first frame's fill, at a half and a
 *    quarter of the pixels traced; and 1 and 2 threads give the same bits.
 * 7. The output's albedo from the traced frame's (tr_upscale_albedo) on the classic box at
 *    twice a frame's resolution: it traces at most half of the output's pixels, and at
 *    most 1 % of them differ from tracing every pixel (tr_albedo_image) by more than
 *    twice the step; given the right previous output, none differs by more than the step;
 *    1 and 2 threads give the same bits; NULL buffers and a scene not committed fail. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "classic_box.h"
#include "kernel/camera.h"
#include "post/upscale.h"
#include "trac0r/trac0r.h"
#include "trac0r/upscale.h"

#define W 64
#define H 48

/* The test image in output pixel coordinates. */
static float image_at(float x, float y) {
    float c = 0.3f + 0.2f * sinf(x * 0.05f) * cosf(y * 0.07f);
    if (((int)floorf(x / 3.0f) + (int)floorf(y / 5.0f)) & 1) {
        c += 0.25f;
    }
    return c;
}

static tr_camera plane_camera(float ox, float oy) {
    tr_camera cam;
    tr_error err;
    CHECK(tr_camera_make(&cam, tr_vec3_make(ox, oy, -5.0f), tr_vec3_make(0.0f, 0.0f, 1.0f),
                         tr_vec3_make(0.0f, 1.0f, 0.0f), 45.0f, 0.001f, 1e6f, W, H, &err) == TR_OK,
          "camera: %s", err.msg);
    return cam;
}

/* The frame of w x h pixels for the output camera `cam`: sample positions for sample
 * `frame`, the value there (constant c, or image_at where c < 0), the distance to the
 * plane z = 0 along each sample's ray, one primitive. */
static void synth_input(const tr_camera *cam, int w, int h, uint32_t frame, float c, float *col,
                        float *pos, float *depth, uint32_t *prim) {
    tr_error err;
    tr_render_config cfg = tr_render_config_default();
    cfg.sampler = TR_SAMPLER_REALTIME;
    cfg.threads = 1;
    CHECK(tr_upscale_positions(&cfg, (uint32_t)w, (uint32_t)h, W, H, frame, 1, pos, &err) == TR_OK,
          "positions: %s", err.msg);
    for (int i = 0; i < w * h; ++i) {
        const float v = c >= 0.0f ? c : image_at(pos[2 * i], pos[2 * i + 1]);
        col[3 * i] = v;
        col[3 * i + 1] = c >= 0.0f ? 2.0f * v : v;
        col[3 * i + 2] = c >= 0.0f ? 3.0f * v : v;
        const tr_ray r = tr_camera_ray(cam, pos[2 * i], pos[2 * i + 1], 0.0f, 0.0f);
        depth[i] = (0.0f - cam->pos.z) / r.dir.z;
        prim[i] = 1u;
    }
}

static void test_converges(void) {
    float *ref = malloc(3u * W * H * sizeof *ref), *out = malloc(3u * W * H * sizeof *out);
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            double a = 0.0;
            for (int j = 0; j < 16; ++j) {
                for (int i = 0; i < 16; ++i) {
                    a += image_at((float)x + ((float)i + 0.5f) / 16.0f,
                                  (float)y + ((float)j + 0.5f) / 16.0f);
                }
            }
            for (int k = 0; k < 3; ++k) {
                ref[3 * (y * W + x) + k] = (float)(a / 256.0);
            }
        }
    }
    const tr_camera cam = plane_camera(0.0f, 0.0f);
    for (int up = 2; up <= 4; up += 2) {
        const float s = sqrtf((float)up);
        const int w = (int)((float)W / s + 0.5f), h = (int)((float)H / s + 0.5f);
        float *col = malloc(3u * w * h * sizeof *col), *pos = malloc(2u * w * h * sizeof *pos),
              *depth = malloc((size_t)w * h * sizeof *depth);
        uint32_t *prim = malloc((size_t)w * h * sizeof *prim);
        tr_upscale u;
        tr_error err;
        CHECK(tr_upscale_init(&u, W, H, &err) == TR_OK, "init: %s", err.msg);
        double psnr8 = 0.0, psnr64 = 0.0;
        for (uint32_t f = 0; f < 64; ++f) {
            synth_input(&cam, w, h, f, -1.0f, col, pos, depth, prim);
            const tr_upscale_input in = {(uint32_t)w, (uint32_t)h, col, pos, depth, prim};
            CHECK(tr_upscale_frame(&u, &in, &cam, NULL, 0, 64.0f, 2, out, &err) == TR_OK,
                  "frame: %s", err.msg);
            const double p = tr_image_compare(out, ref, (size_t)W * H).psnr;
            psnr8 = f == 7 ? p : psnr8;
            psnr64 = p;
        }
        CHECK(psnr64 >= 45.0 && psnr64 > psnr8 + 10.0,
              "upscale %d: PSNR %.2f dB after 8 frames, %.2f dB after 64", up, psnr8, psnr64);
        tr_upscale_free(&u);
        free(col);
        free(pos);
        free(depth);
        free(prim);
    }
    free(ref);
    free(out);
}

static void test_constant(void) {
    const int w = W / 2, h = H / 2;
    float *col = malloc(3u * w * h * sizeof *col), *pos = malloc(2u * w * h * sizeof *pos),
          *depth = malloc((size_t)w * h * sizeof *depth);
    uint32_t *prim = malloc((size_t)w * h * sizeof *prim);
    float *out[2] = {malloc(3u * W * H * sizeof(float)), malloc(3u * W * H * sizeof(float))};
    tr_upscale u[2];
    tr_error err;
    for (int t = 0; t < 2; ++t) {
        CHECK(tr_upscale_init(&u[t], W, H, &err) == TR_OK, "init: %s", err.msg);
    }
    double worst = 0.0, mean_err = 0.0;
    for (uint32_t f = 0; f < 16; ++f) {
        /* The camera moves sideways and up, by fractions of a pixel and more. */
        const tr_camera cam = plane_camera(0.037f * (float)f, 0.011f * (float)(f * f));
        synth_input(&cam, w, h, f, 0.25f, col, pos, depth, prim);
        const tr_upscale_input in = {(uint32_t)w, (uint32_t)h, col, pos, depth, prim};
        for (int t = 0; t < 2; ++t) {
            CHECK(tr_upscale_frame(&u[t], &in, &cam, NULL, 0, 0.0f, t + 1, out[t], &err) == TR_OK,
                  "frame: %s", err.msg);
        }
        CHECK(memcmp(out[0], out[1], 3u * W * H * sizeof(float)) == 0,
              "frame %u: 1 and 2 threads differ", f);
        double sum = 0.0;
        for (int i = 0; i < W * H; ++i) {
            for (int k = 0; k < 3; ++k) {
                const double want = 0.25 * (k + 1);
                const double e = fabs(out[0][3 * i + k] - want) / want;
                worst = e > worst ? e : worst;
                sum += out[0][3 * i + k] / want;
            }
        }
        const double m = fabs(sum / (3.0 * W * H) - 1.0);
        mean_err = m > mean_err ? m : mean_err;
    }
    CHECK(worst < 1e-5, "a constant image changed by %.3g (relative)", worst);
    CHECK(mean_err < 0.01, "a constant image's mean changed by %.3g", mean_err);
    for (int t = 0; t < 2; ++t) {
        tr_upscale_free(&u[t]);
        free(out[t]);
    }
    free(col);
    free(pos);
    free(depth);
    free(prim);
}

static double mean_of(const float *a, size_t n) {
    double s = 0.0;
    for (size_t i = 0; i < n; ++i) {
        s += a[i];
    }
    return s / (double)n;
}

static void test_realtime(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev && tr_device_upload(dev, s, &err) == TR_OK, "device: %s", err.msg);
    /* The converged image: 1024 samples per pixel. */
    tr_render_config rcfg = tr_render_config_default();
    rcfg.seed = 99;
    tr_film ref;
    CHECK(tr_film_init(&ref, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_render(dev, tr_scene_camera(s), &rcfg, 0, 1024, NULL, NULL, &err) == TR_OK &&
              tr_device_read_film(dev, &ref, &err) == TR_OK,
          "reference: %s", err.msg);
    float *refc = malloc(3u * W * H * sizeof *refc);
    for (size_t i = 0; i < (size_t)W * H; ++i) {
        for (int k = 0; k < 3; ++k) {
            refc[3 * i + k] = ref.sum[3 * i + k] / (float)ref.count[i];
        }
    }
    /* The same pipeline tracing every pixel (upscale 1) and a quarter of them (4); then a
     * quarter again with the colour upscaled instead of the light apart from the albedo
     * (upscale_albedo 0); then the raw frame (off) upscaled with upscale_albedo on. */
    double psnr4 = 0.0, psnr = 0.0, mean[4] = {0.0, 0.0, 0.0, 0.0};
    for (int v = 0; v < 4; ++v) {
        tr_recon_params rp = tr_recon_params_default();
        rp.upscale_albedo = v != 2;
        tr_realtime_desc desc = {0};
        desc.recon = &rp;
        tr_realtime *rt = tr_realtime_create(dev, s, &desc, &err);
        CHECK(rt != NULL, "create: %s", err.msg);
        for (int f = 0; rt && f < 128; ++f) {
            tr_realtime_frame_desc fd = {0};
            fd.camera = tr_scene_camera(s);
            fd.method = v == 3 ? TR_RECON_OFF : TR_RECON_ACCUMULATE;
            fd.upscale = v ? 4 : 1;
            tr_realtime_result res;
            CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "frame %d: %s", f, err.msg);
            if (f == 0 && v) {
                CHECK(res.width == W && res.height == H && res.scale == 1.0f && res.rgb &&
                          res.traced_width == W / 2 && res.traced_height == H / 2,
                      "an upscaled frame: %ux%u (scale %g) traced %ux%u", res.width, res.height,
                      (double)res.scale, res.traced_width, res.traced_height);
            }
            if (!res.rgb) {
                break;
            }
            if (v == 1) {
                psnr = tr_image_compare(res.rgb, refc, (size_t)W * H).psnr;
                psnr4 = f == 3 ? psnr : psnr4;
            }
            /* The frames' mean brightness over the last 96 frames. */
            mean[v] += f >= 32 ? mean_of(res.rgb, 3u * W * H) / 96.0 : 0.0;
        }
        if (v == 3) {
            /* The upscaled raw frame's passes: the distances and ids its reprojection reads. */
            const tr_gbuffer *g = tr_realtime_gbuffer(rt);
            size_t hit = 0;
            for (size_t i = 0; g && i < (size_t)g->width * g->height; ++i) {
                hit += g->prim[i] != 0u && g->depth[i] > 0.0f;
            }
            CHECK(g && hit > (size_t)g->width * g->height / 2,
                  "the upscaled raw frame's passes: %zu pixels with a surface", hit);
        }
        tr_realtime_destroy(rt);
    }
    CHECK(psnr > psnr4 + 6.0, "a static view: PSNR %.2f dB after 4 frames, %.2f after 128", psnr4,
          psnr);
    CHECK(fabs(mean[1] / mean[0] - 1.0) < 0.01,
          "energy: mean %.5f upscaled, %.5f tracing every pixel", mean[1], mean[0]);
    CHECK(fabs(mean[2] / mean[0] - 1.0) < 0.01,
          "energy: mean %.5f upscaling the colour, %.5f tracing every pixel", mean[2], mean[0]);
    CHECK(fabs(mean[3] / mean[0] - 1.0) < 0.01,
          "energy: mean %.5f of the raw frame upscaled, %.5f tracing every pixel", mean[3],
          mean[0]);
    tr_device_destroy(dev);
    tr_film_free(&ref);
    free(refc);
    tr_scene_destroy(s);
}

static void test_budget(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev && tr_device_upload(dev, s, &err) == TR_OK, "device: %s", err.msg);
    for (int up = 0; up < 2; ++up) {
        tr_realtime_desc desc = {0};
        desc.accumulate = 1;
        desc.budget_upscale = up;
        tr_realtime *rt = tr_realtime_create(dev, s, &desc, &err);
        CHECK(rt != NULL, "create: %s", err.msg);
        tr_realtime_result res;
        memset(&res, 0, sizeof res);
        for (int f = 0; rt && f < 24; ++f) {
            tr_camera cam = *tr_scene_camera(s);
            cam.pos.x += (float)f;
            tr_realtime_frame_desc fd = {0};
            fd.camera = &cam;
            fd.method = TR_RECON_ACCUMULATE;
            fd.moving = 1;
            fd.budget_ms = 1e-6; /* no frame holds it */
            CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "frame %d: %s", f, err.msg);
        }
        if (up) {
            CHECK(res.width == W && res.height == H && res.traced_width >= W / 2 &&
                      res.traced_width < W && res.traced_height >= H / 2,
                  "budget_upscale: shown %ux%u, traced %ux%u", res.width, res.height,
                  res.traced_width, res.traced_height);
        } else {
            CHECK(res.width < W / 2 && res.traced_width == res.width,
                  "without budget_upscale: shown %ux%u", res.width, res.height);
        }
        tr_realtime_destroy(rt);
    }
    tr_device_destroy(dev);
    tr_scene_destroy(s);
}

static void test_failures(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev && tr_device_upload(dev, s, &err) == TR_OK, "device: %s", err.msg);
    tr_realtime *rt = tr_realtime_create(dev, s, NULL, &err);
    tr_realtime_frame_desc fd = {0};
    fd.camera = tr_scene_camera(s);
    fd.upscale = 17;
    tr_realtime_result res;
    CHECK_STATUS(tr_realtime_frame(rt, &fd, &res, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "upscale 17");
    tr_upscale u;
    CHECK(tr_upscale_init(&u, W, H, &err) == TR_OK, "init: %s", err.msg);
    float col[3] = {0}, pos[2] = {0}, depth[1] = {0}, out[3u * W * H];
    uint32_t prim[1] = {0};
    const tr_upscale_input in = {1, 1, col, pos, depth, prim};
    const tr_camera other = *tr_scene_camera(s);
    tr_camera small = other;
    CHECK(tr_camera_resize(&small, W / 2, H, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_upscale_frame(&u, &in, &small, NULL, 0, 0.0f, 1, out, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "a camera of another size");
    const tr_upscale_input none = {1, 1, NULL, pos, depth, prim};
    CHECK_STATUS(tr_upscale_frame(&u, &none, &other, NULL, 0, 0.0f, 1, out, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "no colour");
    tr_upscale_free(&u);
    /* The output's albedo image: NULL buffers, and a scene not committed. */
    CHECK_STATUS(tr_albedo_image(s, &other, 1, NULL, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "an albedo image into NULL");
    tr_scene *empty = tr_scene_create(&err);
    CHECK_STATUS(tr_albedo_image(empty, &other, 1, out, &err), err, TR_STATUS_INVALID_OPERATION,
                 "an albedo image of a scene not committed");
    tr_scene_destroy(empty);
    tr_realtime_destroy(rt);
    tr_device_destroy(dev);
    tr_scene_destroy(s);
}

/* Test 6's frame f: the image with a near square (primitive 2, 2 units closer, moving
 * right by `step` per frame) over the plane (primitive 1). */
static void host_input(const tr_camera *cam, int w, int h, uint32_t f, float step, float *col,
                       float *pos, float *depth, uint32_t *prim) {
    synth_input(cam, w, h, f, -1.0f, col, pos, depth, prim);
    for (int i = 0; i < w * h; ++i) {
        const float px = pos[2 * i], py = pos[2 * i + 1];
        const float sx = 20.0f + step * (float)f;
        if (px >= sx && px < sx + 14.0f && py >= 12.0f && py < 30.0f) {
            depth[i] -= 2.0f;
            prim[i] = 2u;
            col[3 * i] = 0.9f;
            col[3 * i + 1] = 0.1f + 0.01f * px;
            col[3 * i + 2] = 0.2f;
        }
        if (i % 37 == 5) {
            depth[i] = 0.0f; /* nothing hit */
            prim[i] = 0u;
        }
    }
}

static void test_host_equals_operator(void) {
    const int sizes[2][2] = {{45, 34}, {W / 2, H / 2}}; /* a half, a quarter */
    for (int z = 0; z < 2; ++z) {
        const int w = sizes[z][0], h = sizes[z][1];
        float *col = malloc(3u * w * h * sizeof *col), *pos = malloc(2u * w * h * sizeof *pos),
              *depth = malloc((size_t)w * h * sizeof *depth);
        uint32_t *prim = malloc((size_t)w * h * sizeof *prim);
        float *out[2] = {malloc(3u * W * H * sizeof(float)), malloc(3u * W * H * sizeof(float))};
        float *want = malloc(3u * W * H * sizeof(float)), *want_len = malloc(W * H * sizeof(float)),
              *want_depth = malloc(W * H * sizeof(float));
        tr_upscale u[2];
        tr_error err;
        for (int t = 0; t < 2; ++t) {
            CHECK(tr_upscale_init(&u[t], W, H, &err) == TR_OK, "init: %s", err.msg);
        }
        long differ = 0, with_history = 0, filled = 0;
        for (uint32_t f = 0; f < 8; ++f) {
            /* The camera moves, then rests for two frames (the unbounded history). */
            const float m = f < 5 ? (float)f : 4.0f;
            const tr_camera cam = plane_camera(0.05f * m, 0.013f * m * m);
            host_input(&cam, w, h, f, 1.5f, col, pos, depth, prim);
            /* Primitive 2 moved 1.5 output pixels' worth since the previous frame. */
            const tr_vec3 motion[3] = {tr_vec3_make(0.0f, 0.0f, 0.0f),
                                       tr_vec3_make(0.0f, 0.0f, 0.0f),
                                       tr_vec3_make(0.12f, 0.0f, 0.0f)};
            const tr_upscale_input in = {(uint32_t)w, (uint32_t)h, col, pos, depth, prim};
            /* The operator on the history the host loop is about to read. */
            const tr_upscale *s = &u[0];
            const tr_camera pc = s->have_history ? s->prev_cam : cam;
            const float *hc = s->have_history ? s->color[s->cur] : NULL;
            for (int y = 0; y < H; ++y) {
                for (int x = 0; x < W; ++x) {
                    const int i = y * W + x;
                    tr_upscale_pixel(&cam, &pc, x, y, w, h, col, pos, depth, prim, &motion[0].x, 3u,
                                     hc, s->count[s->cur], s->depth[s->cur], NULL,
                                     TR_UPSCALE_MAX_LEN, want + 3 * i, want_len + i,
                                     want_depth + i);
                }
            }
            for (int t = 0; t < 2; ++t) {
                CHECK(tr_upscale_frame(&u[t], &in, &cam, motion, 3u, 0.0f, t + 1, out[t], &err) ==
                          TR_OK,
                      "frame: %s", err.msg);
            }
            CHECK(memcmp(out[0], out[1], 3u * W * H * sizeof(float)) == 0 &&
                      memcmp(u[0].count[u[0].cur], u[1].count[u[1].cur], W * H * sizeof(float)) ==
                          0,
                  "%dx%d, frame %u: 1 and 2 threads differ", w, h, f);
            const float *ol = u[0].count[u[0].cur], *od = u[0].depth[u[0].cur];
            for (int i = 0; i < W * H; ++i) {
                differ += memcmp(out[0] + 3 * i, want + 3 * i, 3 * sizeof(float)) != 0 ||
                          memcmp(ol + i, want_len + i, sizeof(float)) != 0 ||
                          memcmp(od + i, want_depth + i, sizeof(float)) != 0;
                with_history += hc && want_len[i] > 1.0f;
                filled += want_len[i] == 0.0f;
            }
        }
        CHECK(differ == 0, "%dx%d: %ld pixel-frames differ from the operator", w, h, differ);
        /* The frames exercised the paths: history kept, and the fill. */
        CHECK(with_history > W * H && filled > 0,
              "%dx%d: %ld pixel-frames with history, %ld filled", w, h, with_history, filled);
        for (int t = 0; t < 2; ++t) {
            tr_upscale_free(&u[t]);
            free(out[t]);
        }
        free(want);
        free(want_len);
        free(want_depth);
        free(col);
        free(pos);
        free(depth);
        free(prim);
    }
}

/* Whether two albedos differ by more than `k` steps (TR_UPSCALE_ALBEDO_ABS, _REL). */
static int albedo_off(const float *a, const float *b, float k) {
    for (int c = 0; c < 3; ++c) {
        const float m = fmaxf(a[c], b[c]);
        if (fabsf(a[c] - b[c]) > k * (TR_UPSCALE_ALBEDO_ABS + TR_UPSCALE_ALBEDO_REL * m)) {
            return 1;
        }
    }
    return 0;
}

static void test_albedo(void) {
    enum { OW = 2 * W, OH = 2 * H };
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    CHECK(s != NULL, "scene: %s", err.msg);
    tr_camera out_cam = *tr_scene_camera(s);
    CHECK(tr_camera_resize(&out_cam, OW, OH, &err) == TR_OK, "%s", err.msg);
    const size_t n = (size_t)OW * OH;
    float *low = malloc(3u * W * H * sizeof *low);
    float *full = malloc(3 * n * sizeof *full);
    float *a1 = malloc(3 * n * sizeof *a1);
    float *a2 = malloc(3 * n * sizeof *a2);
    CHECK(low && full && a1 && a2, "out of memory");
    if (!low || !full || !a1 || !a2) {
        free(low);
        free(full);
        free(a1);
        free(a2);
        tr_scene_destroy(s);
        return;
    }
    /* The frame's albedo: one ray through each of its pixels' centres. */
    CHECK(tr_albedo_image(s, tr_scene_camera(s), 2, low, &err) == TR_OK, "low: %s", err.msg);
    CHECK(tr_albedo_image(s, &out_cam, 2, full, &err) == TR_OK, "full: %s", err.msg);
    uint32_t traced1 = 0, traced2 = 0;
    CHECK(tr_upscale_albedo(s, &out_cam, 1, W, H, low, NULL, a1, &traced1, &err) == TR_OK &&
              tr_upscale_albedo(s, &out_cam, 2, W, H, low, NULL, a2, &traced2, &err) == TR_OK,
          "sparse: %s", err.msg);
    CHECK(traced1 == traced2 && memcmp(a1, a2, 3 * n * sizeof *a1) == 0,
          "1 and 2 threads: %u and %u traced, or other bits", traced1, traced2);
    CHECK(traced1 > 0 && traced1 <= n / 2, "traced %u of %zu output pixels", traced1, n);
    size_t off = 0;
    for (size_t i = 0; i < n; ++i) {
        off += (size_t)albedo_off(a1 + 3 * i, full + 3 * i, 2.0f);
    }
    CHECK(off <= n / 100, "%zu of %zu pixels off by more than twice the step", off, n);
    /* With the right previous output every pixel is within the step of it. */
    memcpy(a2, full, 3 * n * sizeof *a2);
    CHECK(tr_upscale_albedo(s, &out_cam, 2, W, H, low, a2, a2, &traced2, &err) == TR_OK,
          "with prev: %s", err.msg);
    size_t off_prev = 0;
    for (size_t i = 0; i < n; ++i) {
        off_prev += (size_t)albedo_off(a2 + 3 * i, full + 3 * i, 1.0f);
    }
    CHECK(off_prev == 0 && traced2 >= traced1,
          "with the previous output: %zu pixels off, %u traced (%u without)", off_prev, traced2,
          traced1);
    CHECK_STATUS(tr_upscale_albedo(s, &out_cam, 1, W, H, NULL, NULL, a1, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "no traced albedo");
    CHECK_STATUS(tr_upscale_albedo(s, &out_cam, 1, OW + 1, H, low, NULL, a1, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "a frame wider than the output");
    tr_scene *empty = tr_scene_create(&err);
    CHECK_STATUS(tr_upscale_albedo(empty, &out_cam, 1, W, H, low, NULL, a1, NULL, &err), err,
                 TR_STATUS_INVALID_OPERATION, "a scene not committed");
    tr_scene_destroy(empty);
    free(low);
    free(full);
    free(a1);
    free(a2);
    tr_scene_destroy(s);
}

int main(void) {
    test_converges();
    test_constant();
    test_realtime();
    test_budget();
    test_failures();
    test_host_equals_operator();
    test_albedo();
    return check_finish("test_upscale");
}
