/* test_view_camera.c - the viewer's fly camera (tr_fly_camera, trac0r/camera.h) and the frame
 * budget of its moving frames (tr_realtime_budget_adapt, realtime.h).
 *
 * 1. A right-handed scene's camera rebuilt after a move keeps its mirrored right vector
 *    (the viewer's old rebuild dropped it and flipped the image), and the screen's right
 *    that D moves along is that vector.
 * 2. The budget: over budget the divisor grows (samples drop first), under budget it
 *    falls back to 1, and only at full resolution do samples grow; it stays in range.
 * 3. The default speed scales with the scene's size.
 * 4. A thin lens stays through moves and in the camera the viewer writes out. */
#include "check.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static void test_mirrored(void) {
    tr_camera cam;
    tr_error err;
    CHECK(tr_camera_make(&cam, tr_vec3_make(278, 273, -800), tr_vec3_make(0, 0, 1),
                         tr_vec3_make(0, 1, 0), 37.0f, 1.0f, 1e5f, 64, 48, &err) == TR_OK,
          "%s", err.msg);
    for (int mirrored = 0; mirrored < 2; ++mirrored) {
        tr_camera c = cam;
        if (mirrored) {
            c.right = tr_vec3_make(-c.right.x, -c.right.y, -c.right.z); /* as the scene file does */
        }
        tr_fly_camera f = tr_fly_from_camera(&c, 1.0f);
        CHECK(f.mirrored == mirrored, "mirrored %d detected as %d", mirrored, f.mirrored);
        f.pos.z += 10.0f; /* a move */
        tr_camera next;
        CHECK(tr_fly_make(&f, 64, 48, &next, &err) == TR_OK, "fly_make");
        CHECK(next.right.x == c.right.x && next.up.y == c.up.y,
              "mirrored %d: right %g after a move, %g before", mirrored, next.right.x, c.right.x);
        const tr_vec3 r = tr_fly_right(&f);
        CHECK(fabsf(r.x - c.right.x) < 1e-6f, "mirrored %d: D moves along %g, right is %g",
              mirrored, r.x, c.right.x);
    }
    /* A thin lens stays through the viewer's moves; a pinhole stays a pinhole. */
    tr_camera lens = cam;
    CHECK(tr_camera_set_lens(&lens, 12.5f, 900.0f, &err) == TR_OK, "%s", err.msg);
    tr_fly_camera f = tr_fly_from_camera(&lens, 1.0f);
    f.pos.x += 3.0f;
    tr_camera next;
    CHECK(tr_fly_make(&f, 64, 48, &next, &err) == TR_OK && next.lens_radius == 12.5f &&
              next.focus_dist == 900.0f,
          "the lens after a move: radius %g, focus %g", next.lens_radius, next.focus_dist);
    f = tr_fly_from_camera(&cam, 1.0f);
    CHECK(tr_fly_make(&f, 64, 48, &next, &err) == TR_OK && next.lens_radius == 0.0f,
          "a pinhole stays");
    /* The camera the viewer writes out keeps the lens: read back by the scene parser. */
    char json[1024], text[2048];
    f = tr_fly_from_camera(&lens, 1.0f);
    CHECK(tr_fly_json(&f, json, sizeof json) < (int)sizeof json, "camera json fits");
    snprintf(text, sizeof text,
             "{%s, \"materials\": {\"l\": {\"type\": \"emitter\", \"color\": [1, 1, 1], "
             "\"emittance\": 1}}, \"shapes\": [{\"type\": \"plane\", \"material\": \"l\"}]}",
             json);
    tr_scene *s = tr_scene_create(&err);
    CHECK(s && tr_scene_file_parse(s, "view.json", text, strlen(text), NULL, NULL, &err) == TR_OK,
          "%s", err.msg);
    if (s) {
        const tr_camera *back = tr_scene_camera(s);
        CHECK(back->lens_radius == 12.5f && back->focus_dist == 900.0f,
              "the written camera's lens: radius %g, focus %g", back->lens_radius,
              back->focus_dist);
        tr_scene_destroy(s);
    }
}

static void test_budget(void) {
    float scale = 1.0f;
    uint32_t spp = 1;
    /* Four times over budget: the divisor grows, step by step, towards 2 * sqrt(...). */
    for (int i = 0; i < 40; ++i) {
        const double ms = 4.0 * 16.7 / (scale * scale); /* time falls with the pixel count */
        tr_realtime_budget_adapt(ms, 16.7, &scale, &spp);
    }
    CHECK(scale > 1.9f && scale < 2.6f && spp == 1, "4x over budget: scale %g, spp %u", scale, spp);
    /* Far under budget: back to full resolution, then more samples per frame. */
    for (int i = 0; i < 40; ++i) {
        tr_realtime_budget_adapt(0.5, 16.7, &scale, &spp);
    }
    CHECK(scale == 1.0f && spp == 16, "under budget: scale %g, spp %u", scale, spp);
    /* Over budget with many samples: samples drop before the resolution does. */
    tr_realtime_budget_adapt(40.0, 16.7, &scale, &spp);
    CHECK(scale == 1.0f && spp == 8, "over budget at 16 spp: scale %g, spp %u", scale, spp);
    /* Never beyond 16, whatever the time. */
    spp = 1;
    for (int i = 0; i < 100; ++i) {
        tr_realtime_budget_adapt(1e6, 16.7, &scale, &spp);
    }
    CHECK(scale == 16.0f, "hopeless budget: scale %g", scale);
}

static void test_speed(void) {
    tr_aabb small = {{0, 0, 0}, {1, 1, 1}}, big = {{0, 0, 0}, {556, 548, 559}};
    const float a = tr_fly_default_speed(&small), b = tr_fly_default_speed(&big);
    const float ratio = sqrtf(556.0f * 556.0f + 548.0f * 548.0f + 559.0f * 559.0f) / sqrtf(3.0f);
    CHECK(fabsf(b / a - ratio) < 0.01f * ratio, "speed %g for a unit box, %g for the classic box",
          a, b);
    tr_aabb empty = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
    CHECK(tr_fly_default_speed(&empty) == 0.5f, "empty scene: %g", tr_fly_default_speed(&empty));
}

static float dot3(tr_vec3 a, tr_vec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

/* Steering: a move covers speed x dt along the controls' normalised sum; a roll and a look
 * keep dir and up unit and orthogonal; a positive yaw turns towards the screen's right,
 * mirrored or not; nothing held changes nothing. */
static void test_steer(void) {
    tr_camera cam;
    tr_error err;
    CHECK(tr_camera_make(&cam, tr_vec3_make(0, 0, 0), tr_vec3_make(0, 0, 1), tr_vec3_make(0, 1, 0),
                         40.0f, 0.1f, 100.0f, 64, 48, &err) == TR_OK,
          "%s", err.msg);
    for (int mirrored = 0; mirrored < 2; ++mirrored) {
        tr_camera c = cam;
        if (mirrored) {
            c.right = tr_vec3_make(-c.right.x, -c.right.y, -c.right.z);
        }
        tr_fly_camera f = tr_fly_from_camera(&c, 2.0f);
        CHECK(tr_fly_step(&f, 0, 0, 0, 0, 0.5f) == 0 && f.pos.z == 0.0f, "nothing held moved");
        CHECK(tr_fly_step(&f, 1, 0, 0, 0, 0.5f) == 1 && fabsf(f.pos.z - 1.0f) < 1e-6f,
              "forward: z %g", f.pos.z);
        const tr_vec3 right = tr_fly_right(&f), p0 = f.pos;
        tr_fly_step(&f, 1, 1, 0, 0, 1.0f);
        const tr_vec3 d = tr_vec3_make(f.pos.x - p0.x, f.pos.y - p0.y, f.pos.z - p0.z);
        CHECK(fabsf(sqrtf(dot3(d, d)) - 2.0f) < 1e-5f && dot3(d, right) > 1.4f,
              "diagonal move: length %g, along right %g", sqrtf(dot3(d, d)), dot3(d, right));
        tr_fly_step(&f, 0, 0, 0, 1, 0.3f);
        tr_fly_look(&f, 0.2f, -0.1f);
        CHECK(fabsf(dot3(f.dir, f.dir) - 1.0f) < 1e-5f && fabsf(dot3(f.up, f.up) - 1.0f) < 1e-5f &&
                  fabsf(dot3(f.dir, f.up)) < 1e-5f,
              "roll and look: not orthonormal");
        const tr_vec3 r = tr_fly_right(&f), d0 = f.dir;
        tr_fly_look(&f, 0.1f, 0.0f);
        CHECK(dot3(f.dir, r) > dot3(d0, r) + 0.05f, "mirrored %d: yaw turned away from the right",
              mirrored);
    }
}

int main(void) {
    test_mirrored();
    test_steer();
    test_budget();
    test_speed();
    return check_finish("test_view_camera");
}
