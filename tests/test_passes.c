/* test_passes.c - the film's passes and the device API's split renders.
 *
 * 1. Passes against geometry we can compute by hand: a camera straight above a diffuse
 *    floor sees the floor's colour, its normal and, per pixel, a depth between the
 *    distances along the rays through the pixel's corners; above a mirror floor the
 *    passes follow the mirror to a diffuse ceiling (depth down plus up).
 * 2. A render split by sample ranges or by rectangles, put back together with
 *    tr_film_accumulate, equals the whole render bit for bit (radiance and passes), and
 *    asking for passes leaves the radiance unchanged. */
#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "kernel/kernel.h"
#include "scene_util.h"
#include "trac0r/device.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 24
#define H 16

/* A camera at height `height` above the origin looking straight down (+z up in the image). */
static tr_camera down_camera(float height) {
    tr_camera cam;
    tr_error err;
    CHECK(tr_camera_make(&cam, v3(0.0f, height, 0.0f), v3(0.0f, -1.0f, 0.0f), v3(0.0f, 0.0f, 1.0f),
                         60.0f, 1e-3f, 1e4f, W, H, &err) == TR_OK,
          "camera: %s", err.msg);
    return cam;
}

/* The range of the distance to the plane y = plane along the rays through the corners of
 * pixel (x, y) of cam (the distance is monotone between corners: its mean lies inside). */
static void corner_range(const tr_camera *cam, uint32_t x, uint32_t y, float plane, double *lo,
                         double *hi) {
    *lo = INFINITY;
    *hi = 0.0;
    for (int k = 0; k < 4; ++k) {
        tr_ray r = tr_camera_ray(cam, (float)x, (float)y, (float)(k & 1), (float)(k >> 1));
        double t = ((double)plane - r.origin.y) / r.dir.y;
        *lo = fmin(*lo, t);
        *hi = fmax(*hi, t);
    }
}

/* The means of the four passes at pixel (x, y). */
static void read_passes(const tr_film *f, uint32_t x, uint32_t y, float a[3], float n[3],
                        float d[3], float id[3]) {
    tr_error err;
    const int ok = tr_film_pass_pixel(f, TR_PASS_ALBEDO, x, y, a, &err) == TR_OK &&
                   tr_film_pass_pixel(f, TR_PASS_NORMAL, x, y, n, &err) == TR_OK &&
                   tr_film_pass_pixel(f, TR_PASS_DEPTH, x, y, d, &err) == TR_OK &&
                   tr_film_pass_pixel(f, TR_PASS_PRIM, x, y, id, &err) == TR_OK;
    CHECK(ok, "pass read at (%u, %u): %s", x, y, err.msg);
}

static void render_passes(const tr_scene *s, const tr_camera *cam, int integrator, tr_film *film) {
    tr_error err;
    CHECK(tr_film_init_passes(film, W, H, TR_PASS_ALL, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = integrator;
    cfg.passes = TR_PASS_ALL;
    cfg.seed = 7;
    /* naive's roulette ends a path before its next hit with probability 1/(max_depth -
     * depth): deep enough that few of the 8 samples of a pixel end before the surface. */
    cfg.max_depth = integrator == TR_INTEGRATOR_NAIVE ? 1000 : 8;
    for (uint32_t smp = 0; smp < 8; ++smp) {
        CHECK(tr_render_frame(s, cam, &cfg, film, smp, NULL, &err) == TR_OK, "%s", err.msg);
    }
}

/* Floor: colour, upward normal, depth within the corner range, one of its triangles. */
static void test_floor(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    const tr_vec3 colour = v3(0.2f, 0.5f, 0.8f);
    uint32_t floor = add_mat(&s, tr_material_diffuse(colour));
    uint32_t lamp = add_mat(&s, tr_material_emitter(v3s(1.0f), 1.0f));
    add_shape(&s, TR_SHAPE_PLANE, floor, v3s(0.0f), v3s(0.0f), v3(100.0f, 1.0f, 100.0f));
    add_shape(&s, TR_SHAPE_PLANE, lamp, v3(0.0f, 50.0f, 0.0f), v3s(0.0f), v3s(1.0f));
    tr_error err;
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    const tr_camera cam = down_camera(5.0f);
    tr_film f;
    render_passes(&s, &cam, TR_INTEGRATOR_PT, &f);
    int bad_albedo = 0, bad_normal = 0, bad_depth = 0, bad_prim = 0;
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            float a[3], n[3], d[3], id[3];
            read_passes(&f, x, y, a, n, d, id);
            bad_albedo += fabsf(a[0] - colour.x) > 1e-6f || fabsf(a[1] - colour.y) > 1e-6f ||
                          fabsf(a[2] - colour.z) > 1e-6f;
            bad_normal += fabsf(n[0]) > 1e-6f || fabsf(n[1] - 1.0f) > 1e-6f || fabsf(n[2]) > 1e-6f;
            double lo, hi;
            corner_range(&cam, x, y, 0.0f, &lo, &hi);
            bad_depth += !(d[0] >= lo * (1 - 1e-5) && d[0] <= hi * (1 + 1e-5));
            bad_prim += !(id[0] == 1.0f || id[0] == 2.0f); /* the floor's two triangles */
        }
    }
    CHECK(bad_albedo == 0, "%d pixels with another albedo than the floor's", bad_albedo);
    CHECK(bad_normal == 0, "%d pixels with another normal than +y", bad_normal);
    CHECK(bad_depth == 0, "%d pixels with a depth outside their corners' range", bad_depth);
    CHECK(bad_prim == 0, "%d pixels with another primitive than the floor's", bad_prim);
    float out[3];
    tr_film plain;
    CHECK(tr_film_init(&plain, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_pass_pixel(&plain, TR_PASS_ALBEDO, 0, 0, out, &err) == TR_ERR,
          "a pass read from a film without it");
    CHECK(tr_film_pass_pixel(&f, TR_PASS_DEPTH, W, 0, out, &err) == TR_ERR, "pixel outside");
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_NORMAL;
    CHECK(tr_render_frame(&s, &cam, &cfg, &plain, 0, NULL, &err) == TR_ERR,
          "rendered passes into a film without them");
    tr_film_free(&plain);
    tr_film_free(&f);
    tr_scene_clear(&s);
}

/* Mirror floor, diffuse ceiling at height 10 above it, the camera at 5 between: the passes
 * describe the ceiling seen in the mirror, with the distance down and up again. */
static void test_mirror(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    const tr_vec3 colour = v3(0.6f, 0.3f, 0.1f);
    uint32_t mirror = add_mat(&s, tr_material_glossy(v3s(1.0f), 0.0f));
    uint32_t ceiling = add_mat(&s, tr_material_diffuse(colour));
    uint32_t lamp = add_mat(&s, tr_material_emitter(v3s(1.0f), 1.0f));
    add_shape(&s, TR_SHAPE_PLANE, mirror, v3s(0.0f), v3s(0.0f), v3(100.0f, 1.0f, 100.0f));
    add_shape(&s, TR_SHAPE_PLANE, ceiling, v3(0.0f, 10.0f, 0.0f), v3s(0.0f),
              v3(100.0f, 1.0f, 100.0f));
    add_shape(&s, TR_SHAPE_PLANE, lamp, v3(0.0f, 9.0f, 0.0f), v3s(0.0f), v3s(0.1f));
    tr_error err;
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    const tr_camera cam = down_camera(5.0f);
    for (int integrator = 0; integrator < 2; ++integrator) {
        tr_film f;
        render_passes(&s, &cam, integrator == 0 ? TR_INTEGRATOR_PT : TR_INTEGRATOR_NAIVE, &f);
        int bad = 0, checked = 0;
        for (uint32_t y = 0; y < H; ++y) {
            for (uint32_t x = 0; x < W; ++x) {
                float a[3], n[3], d[3], id[3];
                read_passes(&f, x, y, a, n, d, id);
                double lo, hi;
                corner_range(&cam, x, y, 0.0f, &lo, &hi);
                /* Down to the mirror, up to the ceiling: three times the way down. */
                lo *= 3.0;
                hi *= 3.0;
                if (integrator == 1 && id[0] == 0.0f) {
                    continue; /* naive's roulette ended the first sample before any hit */
                }
                ++checked;
                const int ok = fabsf(a[0] - colour.x) <= 1e-6f && fabsf(a[2] - colour.z) <= 1e-6f &&
                               fabsf(n[1] + 1.0f) <= 1e-6f && d[0] >= lo * (1 - 1e-4) &&
                               d[0] <= hi * (1 + 1e-4) && (id[0] == 3.0f || id[0] == 4.0f);
                bad += !ok;
            }
        }
        /* naive ends a sample before the ceiling with probability about 2/1000: a pixel's
         * 8 samples all reach it with probability 0.98, so a few pixels may fall short. */
        const int allowed = integrator == 0 ? 0 : W * H / 10;
        CHECK(bad <= allowed && checked > W * H / 2,
              "%s: %d of %d pixels do not show the ceiling through the mirror",
              integrator == 0 ? "pt" : "naive", bad, checked);
        tr_film_free(&f);
    }
    tr_scene_clear(&s);
}

static int films_equal(const tr_film *a, const tr_film *b) {
    const size_t n = (size_t)a->width * a->height;
    if (a->width != b->width || a->height != b->height || a->passes != b->passes) {
        return 0;
    }
    int same = memcmp(a->sum, b->sum, 3 * n * sizeof(float)) == 0 &&
               memcmp(a->count, b->count, n * sizeof(uint32_t)) == 0;
    if (a->passes & TR_PASS_ALBEDO) {
        same &= memcmp(a->albedo, b->albedo, 3 * n * sizeof(float)) == 0;
    }
    if (a->passes & TR_PASS_NORMAL) {
        same &= memcmp(a->normal, b->normal, 3 * n * sizeof(float)) == 0;
    }
    if (a->passes & TR_PASS_DEPTH) {
        same &= memcmp(a->depth, b->depth, n * sizeof(float)) == 0;
    }
    if (a->passes & TR_PASS_PRIM) {
        same &= memcmp(a->prim, b->prim, n * sizeof(uint32_t)) == 0;
    }
    if (a->passes & TR_PASS_VARIANCE) {
        same &= memcmp(a->sq, b->sq, 3 * n * sizeof(float)) == 0;
    }
    if (a->passes & TR_PASS_DIRECT) {
        same &= memcmp(a->direct, b->direct, 3 * n * sizeof(float)) == 0;
    }
    return same;
}

/* Renders samples [first, first + count) of rect (NULL: all) on a fresh CPU device into
 * a new film with every pass. */
static void device_film(const tr_scene *s, const tr_render_config *cfg, uint32_t first,
                        uint32_t count, const tr_rect *rect, tr_film *out) {
    tr_error err;
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev != NULL, "%s", err.msg);
    const uint32_t w = s->camera.screen_width, h = s->camera.screen_height;
    CHECK(tr_film_init_passes(out, w, h, cfg->passes, &err) == TR_OK, "%s", err.msg);
    if (!dev) {
        return;
    }
    CHECK(tr_device_upload(dev, s, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_render(dev, &s->camera, cfg, first, count, rect, NULL, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_device_read_film(dev, out, &err) == TR_OK, "%s", err.msg);
    tr_device_destroy(dev);
}

static void test_splits(int integrator, int stride) {
    tr_error err;
    tr_scene s = {0};
    tr_scene_init(&s);
    CHECK(tr_scene_builtin(&s, "cornell", 37, 29, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = integrator;
    cfg.stride = stride;
    cfg.seed = 99;
    cfg.passes = TR_PASS_MASK; /* the surface passes, the variance and the direct part */
    if (integrator != TR_INTEGRATOR_PT) {
        cfg.passes &= ~(uint32_t)TR_PASS_SPECULAR; /* pt's alone */
    }
    const uint32_t spp = 6;

    /* One call for all samples equals one call per sample (tr_render_frame's loop). */
    tr_film whole, loop;
    device_film(&s, &cfg, 0, spp, NULL, &whole);
    CHECK(tr_film_init_passes(&loop, 37, 29, cfg.passes, &err) == TR_OK, "%s", err.msg);
    for (uint32_t k = 0; k < spp; ++k) {
        CHECK(tr_render_frame(&s, &s.camera, &cfg, &loop, k, NULL, &err) == TR_OK, "%s", err.msg);
    }
    CHECK(films_equal(&whole, &loop), "stride %d: a %u-sample call differs from %u calls", stride,
          spp, spp);

    /* Rectangles that cut through stride blocks, accumulated: bit for bit the whole. */
    const tr_rect rects[3] = {{0, 0, 11, 29}, {11, 0, 26, 13}, {11, 13, 26, 16}};
    tr_film sum;
    CHECK(tr_film_init_passes(&sum, 37, 29, cfg.passes, &err) == TR_OK, "%s", err.msg);
    for (int r = 0; r < 3; ++r) {
        tr_film part;
        device_film(&s, &cfg, 0, spp, &rects[r], &part);
        CHECK(tr_film_accumulate(&sum, &part, &err) == TR_OK, "%s", err.msg);
        tr_film_free(&part);
    }
    CHECK(films_equal(&whole, &sum), "stride %d: rectangles accumulated differ from the whole",
          stride);

    /* Sample ranges [0, 2) and [2, spp): counts add, ids come from the first range, sums
     * are the float sums of the two ranges' own sums. */
    tr_film a, b, ab;
    device_film(&s, &cfg, 0, 2, NULL, &a);
    device_film(&s, &cfg, 2, spp - 2, NULL, &b);
    CHECK(tr_film_init_passes(&ab, 37, 29, cfg.passes, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_accumulate(&ab, &a, &err) == TR_OK && tr_film_accumulate(&ab, &b, &err) == TR_OK,
          "%s", err.msg);
    const size_t n = 37 * 29;
    int bad = 0;
    for (size_t i = 0; i < n; ++i) {
        bad += ab.count[i] != whole.count[i] || ab.prim[i] != whole.prim[i];
        for (int c = 0; c < 3; ++c) {
            bad += ab.sum[3 * i + c] != a.sum[3 * i + c] + b.sum[3 * i + c];
            bad += ab.albedo[3 * i + c] != a.albedo[3 * i + c] + b.albedo[3 * i + c];
            bad += ab.sq[3 * i + c] != a.sq[3 * i + c] + b.sq[3 * i + c];
        }
    }
    CHECK(bad == 0, "stride %d: %d values of the sample-split film are not the ranges' sums",
          stride, bad);

    /* Passes do not change the radiance. */
    tr_render_config plain_cfg = cfg;
    plain_cfg.passes = 0;
    tr_film plain;
    device_film(&s, &plain_cfg, 0, spp, NULL, &plain);
    CHECK(memcmp(plain.sum, whole.sum, 3 * n * sizeof(float)) == 0 &&
              memcmp(plain.count, whole.count, n * sizeof(uint32_t)) == 0,
          "stride %d: asking for passes changed the radiance", stride);

    /* Misuse fails with an error. */
    tr_film small;
    CHECK(tr_film_init(&small, 8, 8, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_accumulate(&small, &whole, &err) == TR_ERR, "added films of other sizes");
    CHECK(tr_film_accumulate(&whole, &plain, &err) == TR_ERR,
          "added a film without the passes of the target");
    const tr_rect outside = {30, 20, 8, 2};
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev && tr_device_upload(dev, &s, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_render(dev, &s.camera, &cfg, 0, 1, &outside, NULL, &err) == TR_ERR,
          "rendered a rectangle outside the image");
    CHECK(tr_device_render(dev, &s.camera, &cfg, 0, 0, NULL, NULL, &err) == TR_ERR,
          "rendered zero samples");
    CHECK(tr_device_render(dev, &s.camera, &plain_cfg, 0, 1, NULL, NULL, &err) == TR_OK, "%s",
          err.msg);
    CHECK(tr_device_read_film(dev, &whole, &err) == TR_ERR,
          "read passes the device's film does not keep");
    /* The CPU device renders from the scene itself: a scene moved (and updated) since its
     * upload must be uploaded again before it renders. */
    CHECK(tr_scene_move_shape(&s, 0, v3(0.0f, 0.01f, 0.0f), &err) == TR_OK &&
              tr_scene_update(&s, NULL, &err) == TR_OK,
          "%s", err.msg);
    CHECK_STATUS(tr_device_render(dev, &s.camera, &plain_cfg, 0, 1, NULL, NULL, &err), err,
                 TR_STATUS_STALE_SCENE, "render of a scene changed since its upload");
    CHECK(tr_device_upload(dev, &s, &err) == TR_OK &&
              tr_device_render(dev, &s.camera, &plain_cfg, 0, 1, NULL, NULL, &err) == TR_OK,
          "after a new upload: %s", err.msg);
    tr_device_destroy(dev);
    CHECK(tr_device_create("vulkan", &err) == NULL, "opened an unknown device");

    tr_film *films[] = {&whole, &loop, &sum, &a, &b, &ab, &plain, &small};
    for (size_t i = 0; i < sizeof films / sizeof films[0]; ++i) {
        tr_film_free(films[i]);
    }
    tr_scene_clear(&s);
}

int main(void) {
    /* The library's defaults are the command line's (docs/cli.md): pt, the integrator's
     * max depth (64 for pt, 8 for naive), all threads, no preview stride, no passes. */
    const tr_render_config d = tr_render_config_default();
    CHECK(tr_default_max_depth(TR_INTEGRATOR_PT) == 64 &&
              tr_default_max_depth(TR_INTEGRATOR_NAIVE) == 8,
          "default depths %d (pt) and %d (naive)", tr_default_max_depth(TR_INTEGRATOR_PT),
          tr_default_max_depth(TR_INTEGRATOR_NAIVE));
    CHECK(d.integrator == TR_INTEGRATOR_PT && d.max_depth == TR_MAX_DEPTH_DEFAULT &&
              d.threads == 0 && d.stride == 1 && d.passes == 0 && d.cancel == NULL,
          "defaults: integrator %d, max depth %d, threads %d, stride %d, passes %u", d.integrator,
          d.max_depth, d.threads, d.stride, d.passes);
    test_floor();
    test_mirror();
    test_splits(TR_INTEGRATOR_PT, 1);
    test_splits(TR_INTEGRATOR_NAIVE, 1);
    test_splits(TR_INTEGRATOR_PT, 3);
    return check_finish("test_passes");
}
