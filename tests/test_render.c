/* test_render.c - end to end: the built-in scene renders to a plausible image, and
 * rendering is deterministic whatever the thread count and tile size. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

/* Projects a world point to pixel coordinates (inverse of tr_camera_ray). */
static void project(const tr_camera *c, tr_vec3 p, float *px, float *py) {
    tr_vec3 d = v3_sub(p, c->pos);
    float z = v3_dot(d, c->dir);
    float sx = v3_dot(d, c->right) / z, sy = v3_dot(d, c->up) / z;
    *px = (sx / c->canvas_width + 0.5f) * (float)c->screen_width;
    *py = (0.5f - sy / c->canvas_height) * (float)c->screen_height;
}

/* Mean colour of the (2r+1)^2 pixels around a world point's projection. */
static tr_vec3 region_mean(const tr_film *f, const tr_camera *c, tr_vec3 p, int r) {
    float fx, fy;
    project(c, p, &fx, &fy);
    tr_vec3 sum = v3s(0.0f);
    int n = 0;
    for (int y = (int)fy - r; y <= (int)fy + r; ++y) {
        for (int x = (int)fx - r; x <= (int)fx + r; ++x) {
            if (x >= 0 && y >= 0 && x < (int)f->width && y < (int)f->height) {
                sum = v3_add(sum, tr_film_pixel(f, (uint32_t)x, (uint32_t)y));
                ++n;
            }
        }
    }
    return v3_scale(sum, n ? 1.0f / (float)n : 0.0f);
}

static int render(const tr_scene *s, tr_film *f, int threads, uint32_t tile, int stride,
                  uint64_t seed, uint32_t spp) {
    tr_error err;
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = threads;
    cfg.tile = tile;
    cfg.stride = stride;
    cfg.seed = seed;
    tr_film_clear(f);
    for (uint32_t i = 0; i < spp; ++i) {
        if (tr_render_frame(s, &s->camera, &cfg, f, i, NULL, &err) != TR_OK) {
            fprintf(stderr, "render failed: %s\n", err.msg);
            return 0;
        }
    }
    return 1;
}

static int films_equal(const tr_film *a, const tr_film *b) {
    size_t n = (size_t)a->width * a->height;
    return memcmp(a->sum, b->sum, 3 * n * sizeof(float)) == 0 &&
           memcmp(a->count, b->count, n * sizeof(uint32_t)) == 0;
}

static void test_cornell_image(void) {
    tr_error err;
    tr_scene s = {0};
    CHECK(tr_scene_builtin(&s, "cornell", 160, 120, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);
    tr_film f;
    CHECK(tr_film_init(&f, 160, 120, &err) == TR_OK, "%s", err.msg);
    CHECK(render(&s, &f, 0, 16, 1, 7, 64), "render");

    int bad = 0;
    for (size_t i = 0; i < 3u * 160u * 120u; ++i) {
        bad += !isfinite(f.sum[i]) || f.sum[i] < 0.0f;
    }
    CHECK(bad == 0, "%d film values are NaN, Inf or negative", bad);

    /* Points in the middle of the left and right walls, the back wall and the lamp. */
    tr_vec3 left = region_mean(&f, &s.camera, v3(-0.5f, 0.45f, 0.1f), 4);
    tr_vec3 right = region_mean(&f, &s.camera, v3(0.5f, 0.45f, 0.1f), 4);
    tr_vec3 lamp = region_mean(&f, &s.camera, v3(0.0f, 0.85f, -0.1f), 3);
    CHECK(left.x > 2.0f * left.y && left.x > 2.0f * left.z, "left wall not red: %g %g %g",
          (double)left.x, (double)left.y, (double)left.z);
    CHECK(right.y > 1.5f * right.x && right.y > 2.0f * right.z, "right wall not green: %g %g %g",
          (double)right.x, (double)right.y, (double)right.z);

    /* The lamp's block is the brightest 8x8 block of the image. */
    float lx, ly;
    project(&s.camera, v3(0.0f, 0.85f, -0.1f), &lx, &ly);
    float best = -1.0f;
    int bx = -1, by = -1;
    for (uint32_t y0 = 0; y0 + 8 <= f.height; y0 += 8) {
        for (uint32_t x0 = 0; x0 + 8 <= f.width; x0 += 8) {
            float lum = 0.0f;
            for (uint32_t y = y0; y < y0 + 8; ++y) {
                for (uint32_t x = x0; x < x0 + 8; ++x) {
                    tr_vec3 c = tr_film_pixel(&f, x, y);
                    lum += c.x + c.y + c.z;
                }
            }
            if (lum > best) {
                best = lum, bx = (int)x0, by = (int)y0;
            }
        }
    }
    float lamp_px_l, lamp_py_t, lamp_px_r, lamp_py_b;
    /* The lamp's near edge (z = -0.3) projects higher in the image than its far edge. */
    project(&s.camera, v3(-0.2f, 0.85f, -0.3f), &lamp_px_l, &lamp_py_t);
    project(&s.camera, v3(0.2f, 0.85f, 0.1f), &lamp_px_r, &lamp_py_b);
    CHECK(bx + 4 >= (int)lamp_px_l && bx + 4 <= (int)lamp_px_r + 1 && by + 4 >= (int)lamp_py_t &&
              by + 4 <= (int)lamp_py_b + 1,
          "brightest block at (%d,%d) is outside the lamp's projection x %g..%g y %g..%g", bx, by,
          (double)lamp_px_l, (double)lamp_px_r, (double)lamp_py_t, (double)lamp_py_b);
    CHECK(lamp.x + lamp.y + lamp.z > 3.0f * (left.x + left.y + left.z), "lamp %g not brighter",
          (double)(lamp.x + lamp.y + lamp.z));
    tr_film_free(&f);
    tr_scene_clear(&s);
}

static void test_determinism(void) {
    tr_error err;
    tr_scene s = {0};
    CHECK(tr_scene_builtin(&s, "cornell", 67, 41, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);
    tr_film a, b;
    CHECK(tr_film_init(&a, 67, 41, &err) == TR_OK && tr_film_init(&b, 67, 41, &err) == TR_OK, "%s",
          err.msg);
    /* Odd sizes make the last tiles partial. */
    CHECK(render(&s, &a, 1, 16, 1, 42, 4) && render(&s, &b, 2, 16, 1, 42, 4), "render");
    CHECK(films_equal(&a, &b), "1 and 2 threads differ");
    CHECK(render(&s, &b, 2, 5, 1, 42, 4), "render");
    CHECK(films_equal(&a, &b), "tile sizes 16 and 5 differ");
    for (int accel = TR_ACCEL_TYPE_BVH; accel <= TR_ACCEL_TYPE_EMBREE; ++accel) {
        if (!tr_accel_available((tr_accel_type)accel)) {
            continue;
        }
        CHECK(tr_scene_commit(&s, (tr_accel_type)accel, &err) == TR_OK, "%s", err.msg);
        CHECK(render(&s, &b, 1, 16, 1, 42, 4), "render");
        tr_film c;
        CHECK(tr_film_init(&c, 67, 41, &err) == TR_OK, "%s", err.msg);
        CHECK(render(&s, &c, 2, 7, 1, 42, 4), "render");
        CHECK(films_equal(&b, &c), "%s: 1 and 2 threads differ",
              tr_accel_name((tr_accel_type)accel));
        tr_film_free(&c);
    }
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);
    CHECK(render(&s, &b, 2, 16, 1, 43, 4), "render");
    CHECK(!films_equal(&a, &b), "seeds 42 and 43 give the same image");
    CHECK(render(&s, &a, 1, 16, 3, 42, 2) && render(&s, &b, 2, 7, 3, 42, 2), "render");
    CHECK(films_equal(&a, &b), "stride 3: 1 and 2 threads differ");
    /* Stride 3: every pixel of a 3x3 block holds the value traced at its corner. */
    int mismatch = 0;
    for (uint32_t y = 0; y < a.height; ++y) {
        for (uint32_t x = 0; x < a.width; ++x) {
            tr_vec3 p = tr_film_pixel(&a, x, y), q = tr_film_pixel(&a, x - x % 3, y - y % 3);
            mismatch += p.x != q.x || p.y != q.y || p.z != q.z || a.count[y * a.width + x] != 2;
        }
    }
    CHECK(mismatch == 0, "%d pixels differ from their stride block's corner", mismatch);
    tr_film_free(&a);
    tr_film_free(&b);
    tr_scene_clear(&s);
}

static void test_bad_config(void) {
    tr_error err;
    tr_scene s = {0};
    CHECK(tr_scene_builtin(&s, "cornell", 8, 6, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);
    tr_film f;
    CHECK(tr_film_init(&f, 9, 6, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    CHECK_STATUS(tr_render_frame(&s, &s.camera, &cfg, &f, 0, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "a film of the wrong size");
    tr_film_free(&f);
    CHECK(tr_film_init(&f, 8, 6, &err) == TR_OK, "%s", err.msg);
    cfg.max_depth = -1; /* 0 asks for the integrator's default */
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &f, 0, NULL, &err) == TR_ERR, "max depth -1");
    cfg = tr_render_config_default();
    cfg.stride = -1; /* 0 is the default, 1 (tests/test_defaults.c) */
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &f, 0, NULL, &err) == TR_ERR, "stride -1");
    tr_film_free(&f);
    CHECK(tr_film_init(&f, 0, 6, &err) == TR_ERR, "zero-width film accepted");
    CHECK(tr_film_init(&f, TR_FILM_MAX_SIDE, TR_FILM_MAX_SIDE, &err) == TR_ERR,
          "a film over the pixel limit is accepted");
    tr_scene_clear(&s);
    CHECK(tr_scene_builtin(&s, "nope", 8, 6, &err) == TR_ERR, "unknown scene accepted");
}

int main(void) {
    test_cornell_image();
    test_determinism();
    test_bad_config();
    return check_finish("test_render");
}
