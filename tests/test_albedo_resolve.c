/* test_albedo_resolve.c - the albedo resolved over the pixels' area (tr_resolve_albedo)
 * for the real-time reconstruction's demodulation and remodulation.
 *
 * 1. Which pixels: every pixel whose 1-spp albedo differs from a neighbour's by more than
 *    TR_RESOLVE_ALBEDO_STEP is traced, and every other pixel keeps its albedo bit for bit.
 * 2. What they get: a traced pixel's albedo agrees with an independent estimate of the
 *    pixel's mean albedo, the albedo pass of 256 randomly jittered samples (the classic
 *    box's camera sees no sky, so every sample finds a surface); pixels on the edge
 *    between the red wall and the white back wall get a red between the two walls'.
 * 3. It does not follow the frame's jitter: two frames of other sample numbers give the
 *    same resolved albedo at every pixel both trace.
 * 4. Through tr_realtime: albedo_samples 0 leaves the frames as they were, bit for bit,
 *    and a value out of range, a camera of another size and an uncommitted scene are
 *    refused with their codes. */
#include "check.h"
#include "classic_box.h"
#include "render_film.h"
#include "trac0r/post.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 64
#define H 48

static void render(const tr_scene *s, uint32_t first, uint32_t spp, tr_film *f) {
    render_film(s, W, H, TR_INTEGRATOR_PT, 8, TR_PASS_ALL, 5, first, spp, f);
}

/* Whether pixel (x, y) of a's albedo differs from a neighbour's by more than the step. */
static int on_edge(const float *a, int x, int y) {
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= W || yy >= H) {
                continue;
            }
            for (int k = 0; k < 3; ++k) {
                if (fabsf(a[3 * (yy * W + xx) + k] - a[3 * (y * W + x) + k]) >
                    TR_RESOLVE_ALBEDO_STEP) {
                    return 1;
                }
            }
        }
    }
    return 0;
}

/* A 1-spp frame of samples [first, first + 1) with its albedo resolved at n x n: the
 * gbuffer, the frame's own albedo in own (3 W H floats) and the traced pixels' mask. */
static void resolved_frame(const tr_scene *s, uint32_t first, int n, tr_gbuffer *g, float *own,
                           uint8_t *edge) {
    tr_error err;
    tr_film f;
    render(s, first, 1, &f);
    CHECK(tr_gbuffer_init(g, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_from_film(g, &f, &err) == TR_OK, "%s", err.msg);
    memcpy(own, g->albedo, 3u * W * H * sizeof(float));
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            edge[y * W + x] = (uint8_t)on_edge(own, x, y);
        }
    }
    uint32_t traced = 0;
    CHECK(tr_resolve_albedo(s, tr_scene_camera(s), n, 2, g, &traced, &err) == TR_OK, "%s", err.msg);
    uint32_t want = 0;
    for (int i = 0; i < W * H; ++i) {
        want += edge[i];
    }
    CHECK(traced == want && want > 0, "%u pixels traced, %u on an edge", traced, want);
    tr_film_free(&f);
}

static void test_resolve(const tr_scene *s) {
    static float own[3 * W * H], own2[3 * W * H];
    static uint8_t edge[W * H], edge2[W * H];
    tr_gbuffer g, g2;
    resolved_frame(s, 0, 8, &g, own, edge);
    tr_film many;
    render(s, 100, 256, &many);
    const float inv = 1.0f / 256.0f;
    uint32_t kept_bad = 0, far = 0, traced = 0, between = 0;
    double worst = 0.0;
    for (int i = 0; i < W * H; ++i) {
        if (!edge[i]) {
            kept_bad += memcmp(own + 3 * i, g.albedo + 3 * i, 3 * sizeof(float)) != 0;
            continue;
        }
        ++traced;
        /* The 256 samples' mean counts a ray that leaves the box (through its open front)
         * as albedo 0; the resolve averages over the rays that hit. Pixels next to a miss
         * are left out of this comparison. */
        int miss = 0;
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                const int xx = i % W + dx, yy = i / W + dy;
                miss |= xx >= 0 && yy >= 0 && xx < W && yy < H && g.prim[yy * W + xx] == 0u;
            }
        }
        for (int k = 0; k < 3 && !miss; ++k) {
            /* 64 grid rays against 256 random ones: the coverage of a pixel split by an
             * edge differs by an eighth of the step at most (a row of cells), the random
             * estimate's own spread is a thirtieth of it. The step: the range of the
             * frame's albedo around the pixel (the lamp's base colour is 17, 12, 4). */
            float lo = 1e30f, hi = -1e30f;
            for (int dy = -1; dy <= 1; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = i % W + dx, yy = i / W + dy;
                    if (xx >= 0 && yy >= 0 && xx < W && yy < H) {
                        lo = fminf(lo, own[3 * (yy * W + xx) + k]);
                        hi = fmaxf(hi, own[3 * (yy * W + xx) + k]);
                    }
                }
            }
            const double d = fabs((double)g.albedo[3 * i + k] - many.albedo[3 * i + k] * inv);
            const double tol = 0.2 * (hi - lo) + 0.02;
            worst = d / tol > worst ? d / tol : worst;
            far += d > tol;
        }
        /* The red wall (0.65, 0.05, 0.05) against the white ones (0.73, 0.73, 0.73): a
         * pixel over both has its green channel strictly between them. */
        const float gr = g.albedo[3 * i + 1];
        between += gr > 0.1f && gr < 0.65f && g.albedo[3 * i] > 0.6f && g.albedo[3 * i] < 0.8f;
    }
    CHECK(kept_bad == 0, "%u pixels off the edges changed their albedo", kept_bad);
    CHECK(far == 0,
          "%u channels of %u traced pixels off the 256-sample mean (worst %.2f of the bound)", far,
          traced, worst);
    CHECK(between >= 10, "only %u pixels between the red and the white wall", between);

    /* Another frame's jitter: the same albedo wherever both frames trace the pixel. */
    resolved_frame(s, 7, 8, &g2, own2, edge2);
    uint32_t both = 0, differ = 0, own_differ = 0;
    for (int i = 0; i < W * H; ++i) {
        if (edge[i] && edge2[i]) {
            ++both;
            differ += memcmp(g.albedo + 3 * i, g2.albedo + 3 * i, 3 * sizeof(float)) != 0;
            own_differ += memcmp(own + 3 * i, own2 + 3 * i, 3 * sizeof(float)) != 0;
        }
    }
    CHECK(both > 50 && differ == 0, "%u of %u pixels differ between two frames", differ, both);
    CHECK(own_differ >= 20, "the frames' own albedo differs at %u of %u edge pixels only",
          own_differ, both);
    tr_film_free(&many);
    tr_gbuffer_free(&g);
    tr_gbuffer_free(&g2);
}

static void test_errors(const tr_scene *s) {
    tr_error err;
    tr_gbuffer g;
    CHECK(tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_resolve_albedo(s, tr_scene_camera(s), 0, 1, &g, NULL, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "n = 0 accepted");
    CHECK(tr_resolve_albedo(s, tr_scene_camera(s), TR_RESOLVE_ALBEDO_MAX + 1, 1, &g, NULL, &err) ==
                  TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "n over the maximum accepted");
    tr_camera small = *tr_scene_camera(s);
    CHECK(tr_camera_resize(&small, W / 2, H / 2, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_resolve_albedo(s, &small, 2, 1, &g, NULL, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "a camera of another size accepted");
    tr_scene *empty = tr_scene_create(&err);
    CHECK(empty != NULL, "%s", err.msg);
    CHECK(tr_resolve_albedo(empty, tr_scene_camera(s), 2, 1, &g, NULL, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_OPERATION,
          "an uncommitted scene accepted");
    tr_scene_destroy(empty);
    tr_gbuffer_free(&g);
}

/* Four reconstructed SVGF frames of a moving camera through tr_realtime into out. */
static void realtime_frames(tr_scene *s, int albedo_samples, float *out) {
    tr_error err;
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev != NULL && tr_device_upload(dev, s, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = 2;
    cfg.seed = 3;
    tr_recon_params p = tr_recon_params_default();
    p.albedo_samples = albedo_samples;
    tr_realtime_desc desc = {0};
    desc.config = &cfg;
    desc.recon = &p;
    tr_realtime *rt = tr_realtime_create(dev, s, &desc, &err);
    CHECK(rt != NULL, "%s", err.msg);
    for (int f = 0; rt && f < 4; ++f) {
        tr_camera cam = *tr_scene_camera(s);
        cam.pos.x += 2.0f * (float)f; /* millimetres */
        tr_realtime_frame_desc fd = {0};
        fd.camera = &cam;
        fd.method = TR_RECON_SVGF;
        tr_realtime_result res;
        CHECK(tr_realtime_frame(rt, &fd, &res, &err) == TR_OK, "%s", err.msg);
        if (res.rgb) {
            memcpy(out + (size_t)f * 3 * W * H, res.rgb, 3u * W * H * sizeof(float));
        }
    }
    tr_realtime_destroy(rt);
    tr_device_destroy(dev);
}

static void test_realtime(tr_scene *s) {
    static float a[4 * 3 * W * H], b[4 * 3 * W * H], c[4 * 3 * W * H];
    realtime_frames(s, 0, a);
    realtime_frames(s, 0, b);
    realtime_frames(s, 4, c);
    CHECK(memcmp(a, b, sizeof a) == 0, "two runs without the resolve differ");
    CHECK(memcmp(a, c, sizeof a) != 0, "the resolve changed nothing");
}

int main(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    CHECK(s != NULL, "%s", err.msg);
    if (s) {
        test_resolve(s);
        test_errors(s);
        test_realtime(s);
        tr_scene_destroy(s);
    }
    return check_finish("test_albedo_resolve");
}
