/* test_view_wire.c - the viewer's wireframe geometry (apps/trac0r/view_wire.c):
 * projection against the kernel's own camera rays, near-plane clipping of segments
 * reaching behind the camera, 2D clipping, the screen-to-world inverse and rotation. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "kernel/camera.h"
#include "kernel/rng.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"
#include "view_wire.h"

static tr_camera make_cam(tr_vec3 pos, tr_vec3 dir, tr_vec3 up, float vfov, uint32_t w,
                          uint32_t h) {
    tr_camera cam;
    tr_error err;
    int rc = tr_camera_make(&cam, pos, dir, up, vfov, 0.01f, 100.0f, w, h, &err);
    CHECK(rc == TR_OK, "tr_camera_make: %s", err.msg);
    return cam;
}

static tr_vec3 world_of_camera(const tr_camera *c, tr_vec3 p) {
    return v3_add(c->pos, v3_add(v3_scale(c->right, p.x),
                                 v3_add(v3_scale(c->up, p.y), v3_scale(c->dir, p.z))));
}

/* Points along the kernel's ray through screen point (x, y) project back onto (x, y). */
static void test_projection_matches_rays(void) {
    tr_rng rng;
    tr_rng_init(&rng, 7, 0, 0);
    for (int k = 0; k < 200; ++k) {
        tr_vec3 dir =
            v3(tr_rng_range(&rng, -1, 1), tr_rng_range(&rng, -1, 1), tr_rng_range(&rng, -1, 1));
        if (v3_length(dir) < 0.1f || fabsf(v3_normalize(dir).y) > 0.95f) {
            continue;
        }
        tr_camera cam = make_cam(v3(tr_rng_range(&rng, -5, 5), tr_rng_range(&rng, -5, 5), 2.0f),
                                 dir, v3(0, 1, 0), tr_rng_range(&rng, 20, 120), 320, 200);
        float x = tr_rng_range(&rng, 0, 320), y = tr_rng_range(&rng, 0, 200);
        tr_ray ray = tr_camera_ray(&cam, x, y, 0.0f, 0.0f);
        tr_vec3 a = v3_add(ray.origin, v3_scale(ray.dir, tr_rng_range(&rng, 0.5f, 20.0f)));
        tr_vec3 b = v3_add(ray.origin, v3_scale(ray.dir, tr_rng_range(&rng, 0.5f, 20.0f)));
        float out[4];
        CHECK(view_project_segment(&cam, a, b, out) == 1, "segment in front is visible");
        CHECK_NEAR(out[0], x, 2e-3, "projected x of a");
        CHECK_NEAR(out[1], y, 2e-3, "projected y of a");
        CHECK_NEAR(out[2], x, 2e-3, "projected x of b");
        CHECK_NEAR(out[3], y, 2e-3, "projected y of b");
        /* And the inverse: the screen point on the image plane lies on the ray. */
        tr_vec3 w = view_screen_to_world(&cam, x, y);
        tr_vec3 d = v3_normalize(v3_sub(w, cam.pos));
        CHECK(v3_dot(d, ray.dir) > 1.0f - 1e-6f, "screen_to_world on the ray (%g)",
              (double)v3_dot(d, ray.dir));
        tr_vec3 c = view_screen_to_camera(&cam, x, y);
        CHECK_NEAR(c.z, 1.0, 0.0, "camera-space point on the plane at distance 1");
        tr_vec3 cw = view_to_camera(&cam, w);
        CHECK_NEAR(cw.x, c.x, 1e-4, "camera x");
        CHECK_NEAR(cw.y, c.y, 1e-4, "camera y");
    }
}

static void test_near_plane_clipping(void) {
    /* Looking down +z from the origin: camera space equals world space. */
    tr_camera cam = make_cam(v3(0, 0, 0), v3(0, 0, 1), v3(0, 1, 0), 90.0f, 200, 100);
    float out[4];
    /* Wholly behind, and wholly between the eye and the near plane. */
    CHECK(view_project_segment(&cam, v3(0, 0, -1), v3(1, 1, -3), out) == 0, "behind");
    CHECK(view_project_segment(&cam, v3(0, 0, 0.005f), v3(1, 0, 0.001f), out) == 0,
          "in front of the eye but nearer than near");
    /* From in front (right of centre) to behind: the naive projection of the back end
     * would land left of centre; clipped, the line runs off to the right. */
    tr_vec3 a = world_of_camera(&cam, v3(0.2f, 0.1f, 1.0f));
    tr_vec3 b = world_of_camera(&cam, v3(0.2f, 0.1f, -1.0f));
    CHECK(view_project_segment(&cam, a, b, out) == 1, "crossing segment visible");
    const float cx = 100.0f, cy = 50.0f;
    CHECK(out[0] > cx && out[2] > out[0], "clipped end runs right: %g %g", (double)out[0],
          (double)out[2]);
    /* The clipped end is the segment's point at z = near, projected. */
    const double near = cam.near_dist;
    const double px = 0.2 / near / cam.canvas_width; /* -0.5..0.5 across */
    CHECK_NEAR(out[2], (px + 0.5) * 200.0, 1e-2 * fabs((px + 0.5) * 200.0), "clipped x");
    CHECK(out[3] < cy, "clipped end above the centre: %g", (double)out[3]);
    /* The same with the ends swapped gives the same line. */
    float swapped[4];
    CHECK(view_project_segment(&cam, b, a, swapped) == 1, "swapped visible");
    CHECK_NEAR(swapped[0], out[2], 1e-3 * fabs((double)out[2]), "swapped x0");
    CHECK_NEAR(swapped[2], out[0], 1e-3, "swapped x1");
    /* Random crossing segments: the clipped end lies on the original segment at
     * camera z = near (checked by projecting the exact point found in double). */
    tr_rng rng;
    tr_rng_init(&rng, 11, 0, 0);
    for (int k = 0; k < 500; ++k) {
        tr_vec3 p =
            v3(tr_rng_range(&rng, -3, 3), tr_rng_range(&rng, -3, 3), tr_rng_range(&rng, 0.1f, 5));
        tr_vec3 q =
            v3(tr_rng_range(&rng, -3, 3), tr_rng_range(&rng, -3, 3), tr_rng_range(&rng, -5, -0.1f));
        CHECK(view_project_segment(&cam, p, q, out) == 1, "crossing visible");
        double t = (near - p.z) / ((double)q.z - p.z);
        double xn = p.x + t * ((double)q.x - p.x), yn = p.y + t * ((double)q.y - p.y);
        double sx = (xn / near / cam.canvas_width + 0.5) * 200.0;
        double sy = (0.5 - yn / near / cam.canvas_height) * 100.0;
        CHECK_NEAR(out[2], sx, 1e-3 * (fabs(sx) + 200.0), "random clipped x");
        CHECK_NEAR(out[3], sy, 1e-3 * (fabs(sy) + 100.0), "random clipped y");
        CHECK(isfinite(out[0]) && isfinite(out[1]), "front end finite");
    }
}

static void test_clip_2d(void) {
    tr_rng rng;
    tr_rng_init(&rng, 13, 0, 0);
    const float w = 100.0f, h = 60.0f, m = 2.0f;
    int visible = 0, hidden = 0;
    for (int k = 0; k < 2000; ++k) {
        float s[4] = {tr_rng_range(&rng, -300, 300), tr_rng_range(&rng, -300, 300),
                      tr_rng_range(&rng, -300, 300), tr_rng_range(&rng, -300, 300)};
        float c[4] = {s[0], s[1], s[2], s[3]};
        int rc = view_clip_segment_2d(c, w, h, m);
        /* Brute force: is any sampled point of the segment inside the rectangle? */
        int inside = 0;
        for (int i = 0; i <= 4000 && !inside; ++i) {
            float t = (float)i / 4000.0f;
            float x = s[0] + t * (s[2] - s[0]), y = s[1] + t * (s[3] - s[1]);
            inside = x > -m + 0.1f && x < w + m - 0.1f && y > -m + 0.1f && y < h + m - 0.1f;
        }
        if (inside) {
            CHECK(rc == 1, "segment through the rectangle kept");
        }
        if (rc) {
            ++visible;
            for (int e = 0; e < 2; ++e) {
                float x = c[2 * e], y = c[2 * e + 1];
                CHECK(x >= -m - 1e-3f && x <= w + m + 1e-3f && y >= -m - 1e-3f &&
                          y <= h + m + 1e-3f,
                      "clipped end inside: %g %g", (double)x, (double)y);
                /* On the original line: cross product with the direction ~ 0. */
                double cross = ((double)x - s[0]) * ((double)s[3] - s[1]) -
                               ((double)y - s[1]) * ((double)s[2] - s[0]);
                double len = hypot((double)s[2] - s[0], (double)s[3] - s[1]);
                CHECK(fabs(cross) <= 1e-3 * len * (len + 1.0), "clipped end on the line");
            }
        } else {
            ++hidden;
        }
    }
    CHECK(visible > 100 && hidden > 100, "both cases exercised: %d visible, %d hidden", visible,
          hidden);
    float inside[4] = {10, 10, 50, 40};
    CHECK(view_clip_segment_2d(inside, w, h, m) == 1 && inside[0] == 10 && inside[3] == 40,
          "a segment inside is unchanged");
    float parallel_out[4] = {-50, 70, 150, 70};
    CHECK(view_clip_segment_2d(parallel_out, w, h, m) == 0, "horizontal line below: hidden");
}

static void test_rotate_and_boxes(void) {
    tr_vec3 r = view_rotate(v3(1, 0, 0), v3(0, 0, 1), 1.57079632679f);
    CHECK_NEAR(r.x, 0, 1e-6, "rot x");
    CHECK_NEAR(r.y, 1, 1e-6, "rot y");
    CHECK_NEAR(r.z, 0, 1e-6, "rot z");
    tr_vec3 v = v3(0.3f, -0.5f, 0.8f), axis = v3_normalize(v3(1, 2, 3));
    tr_vec3 rv = view_rotate(v, axis, 1.234f);
    CHECK_NEAR(v3_length(rv), v3_length(v), 1e-6, "rotation keeps length");
    CHECK_NEAR(v3_dot(rv, axis), v3_dot(v, axis), 1e-6, "rotation keeps the axial part");
    tr_vec3 back = view_rotate(rv, axis, -1.234f);
    CHECK_NEAR(back.x, v.x, 1e-6, "inverse rotation");

    tr_aabb box = {v3(-1, -2, -3), v3(4, 5, 6)};
    tr_vec3 c[8];
    view_box_corners(&box, c);
    for (int e = 0; e < 12; ++e) {
        int i = view_box_edges[e][0], j = view_box_edges[e][1];
        int diff = i ^ j;
        CHECK(diff == 1 || diff == 2 || diff == 4, "edge %d joins corners one axis apart", e);
        float len = v3_length(v3_sub(c[i], c[j]));
        float want = diff == 1 ? 5.0f : diff == 2 ? 7.0f : 9.0f;
        CHECK_NEAR(len, want, 1e-6, "edge length");
    }
}

/* The cancel callback: answers the flag it is given. */
static int flag_set(void *user) {
    return *(const int *)user;
}

/* tr_render_config.cancel: a callback answering "stop" stops the frame before any tile and
 * fails; one answering "go on" changes nothing. */
static void test_cancel(void) {
    tr_scene s = {0};
    tr_error err;
    CHECK(tr_scene_builtin(&s, "cornell", 40, 30, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film a, b;
    tr_film_init(&a, 40, 30, &err);
    tr_film_init(&b, 40, 30, &err);
    tr_render_config cfg = tr_render_config_default();
    int flag = 0;
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &a, 0, NULL, &err) == TR_OK, "%s", err.msg);
    cfg.cancel = flag_set;
    cfg.cancel_user = &flag;
    CHECK(tr_render_frame(&s, &s.camera, &cfg, &b, 0, NULL, &err) == TR_OK, "%s", err.msg);
    int same = 1;
    for (uint32_t i = 0; i < 40 * 30 * 3; ++i) {
        same &= a.sum[i] == b.sum[i];
    }
    CHECK(same, "a clear cancel flag leaves the frame unchanged");
    flag = 1;
    tr_film_clear(&b);
    CHECK_STATUS(tr_render_frame(&s, &s.camera, &cfg, &b, 1, NULL, &err), err, TR_STATUS_CANCELLED,
                 "a set cancel flag");
    uint64_t n = 0;
    for (uint32_t i = 0; i < 40 * 30; ++i) {
        n += b.count[i];
    }
    CHECK(n == 0, "no tile rendered after the flag was set (%llu samples)", (unsigned long long)n);
    tr_film_free(&a);
    tr_film_free(&b);
    tr_scene_clear(&s);
}

int main(void) {
    test_projection_matches_rays();
    test_near_plane_clipping();
    test_clip_2d();
    test_rotate_and_boxes();
    test_cancel();
    return check_finish("test_view_wire");
}
