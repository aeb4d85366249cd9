/* motion_scene.h - a tiny dynamic scene for the tests of per-primitive motion
 * (test_recon_motion.c, test_opencl_recon.c): a diffuse back wall lit by an emitting
 * plane, and a flat-shaded icosphere in front of it, the last shape, which moves
 * sideways by MOTION_STEP every frame as `view --animate` moves the last shape. */
#ifndef TR_TEST_MOTION_SCENE_H
#define TR_TEST_MOTION_SCENE_H

#include <stdlib.h>

#include "check.h"
#include "trac0r/trac0r.h"

#define MOTION_W 48
#define MOTION_H 36
#define MOTION_STEP 0.15f

/* The scene, committed to a BVH; *cam gets its camera, *first and *count the sphere's
 * triangles. */
static tr_scene *motion_scene(tr_camera *cam, uint32_t *first, uint32_t *count) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s != NULL, "%s", err.msg);
    uint32_t white, light, red;
    CHECK(tr_scene_add_material(s, tr_material_diffuse(tr_vec3_make(0.7f, 0.7f, 0.7f)), &white,
                                &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_scene_add_material(s, tr_material_emitter(tr_vec3_make(1.0f, 1.0f, 1.0f), 5.0f),
                                &light, &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_scene_add_material(s, tr_material_diffuse(tr_vec3_make(0.8f, 0.2f, 0.2f)), &red,
                                &err) == TR_OK,
          "%s", err.msg);
    tr_shape_desc wall = tr_shape_desc_default(TR_SHAPE_BOX);
    wall.transform.position = tr_vec3_make(0.0f, 0.0f, 3.0f);
    wall.transform.scale = tr_vec3_make(8.0f, 6.0f, 0.2f);
    wall.material = white;
    CHECK(tr_scene_add_shape(s, &wall, &err) == TR_OK, "%s", err.msg);
    tr_shape_desc lamp = tr_shape_desc_default(TR_SHAPE_PLANE);
    lamp.transform.position = tr_vec3_make(0.0f, 2.5f, 0.0f);
    lamp.transform.orientation = tr_vec3_make(3.14159265f, 0.0f, 0.0f); /* facing down */
    lamp.transform.scale = tr_vec3_make(2.0f, 1.0f, 2.0f);
    lamp.material = light;
    CHECK(tr_scene_add_shape(s, &lamp, &err) == TR_OK, "%s", err.msg);
    tr_shape_desc ball = tr_shape_desc_default(TR_SHAPE_ICOSPHERE);
    ball.transform.position = tr_vec3_make(-0.5f, 0.0f, 1.0f);
    ball.transform.scale = tr_vec3_make(1.0f, 1.0f, 1.0f);
    ball.subdivisions = 1;
    ball.material = red;
    CHECK(tr_scene_add_shape(s, &ball, &err) == TR_OK, "%s", err.msg);
    *first = 0;
    const uint32_t shapes = tr_scene_shape_count(s);
    for (uint32_t i = 0; i + 1 < shapes; ++i) {
        *first += tr_scene_shape_triangle_count(s, i);
    }
    *count = tr_scene_shape_triangle_count(s, shapes - 1);
    CHECK(tr_camera_make(cam, tr_vec3_make(0.0f, 0.0f, -4.0f), tr_vec3_make(0.0f, 0.0f, 1.0f),
                         tr_vec3_make(0.0f, 1.0f, 0.0f), 45.0f, 1e-3f, 1e3f, MOTION_W, MOTION_H,
                         &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    return s;
}

/* Moves the sphere one step (frame k > 0) and renders frame k at 1 spp into g (made here). */
static void motion_frame(tr_scene *s, const tr_camera *cam, int k, tr_gbuffer *g) {
    tr_error err;
    if (k > 0) {
        CHECK(tr_scene_move_shape(s, tr_scene_shape_count(s) - 1,
                                  tr_vec3_make(MOTION_STEP, 0.0f, 0.0f), &err) == TR_OK &&
                  tr_scene_update(s, NULL, &err) == TR_OK,
              "%s", err.msg);
    }
    tr_film f;
    CHECK(tr_film_init_passes(&f, MOTION_W, MOTION_H, TR_PASS_ALL, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_ALL;
    cfg.threads = 2;
    CHECK(tr_render_frame(s, cam, &cfg, &f, (uint32_t)k, NULL, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_init(g, MOTION_W, MOTION_H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_from_film(g, &f, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&f);
}

/* The motion table of one step: the sphere's ids (triangle + 1) move by MOTION_STEP in x,
 * nothing else moves. table has first + count + 1 entries. */
static tr_vec3 *motion_table(uint32_t first, uint32_t count) {
    tr_vec3 *t = calloc(first + count + 1, sizeof *t);
    CHECK(t != NULL, "out of memory");
    for (uint32_t i = first; t && i < first + count; ++i) {
        t[i + 1] = tr_vec3_make(MOTION_STEP, 0.0f, 0.0f);
    }
    return t;
}

#endif
