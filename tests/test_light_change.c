/* test_light_change.c - lights that change at run time (scene.h: tr_scene_set_emittance,
 * tr_scene_set_sun_direction, tr_scene_animate_light).
 *
 * 1. Switching the built-in box's emitter off and on: the scene is stale until
 *    tr_scene_update, which rebuilds the emitter table (no emitter while off, the same
 *    table's total weight when on again, twice it at twice the emittance) and the light
 *    tree; a frame rendered with the light off is black; setting the value the material
 *    has keeps the scene committed.
 * 2. Refusals: an unknown material, one that is not an emitter, a negative or non-finite
 *    emittance; a sun direction for a scene without a sun.
 * 3. The animations: switch is on for frames 0-7, off for 8-15, on again from 16, at the
 *    first emittance; move sways the emitter's shape along x (frame 15 a quarter of its
 *    width to the side) and back; names round-trip. */
#include <math.h>
#include <string.h>

#include "check.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

#define W 24
#define H 18

static tr_scene *box(int sampling) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s && tr_scene_builtin(s, "cornell", W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_set_light_sampling(s, sampling, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    return s;
}

static uint32_t emitter_material(const tr_scene *s) {
    for (uint32_t i = 0; i < tr_scene_material_count(s); ++i) {
        if (tr_scene_material(s, i).type == TR_MATERIAL_EMITTER) {
            return i;
        }
    }
    CHECK(0, "the box has no emitter");
    return 0;
}

static double frame_sum(const tr_scene *s) {
    tr_error err;
    tr_film film;
    CHECK(tr_film_init(&film, W, H, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = 1;
    CHECK(tr_render_frame(s, tr_scene_camera(s), &cfg, &film, 0, NULL, &err) == TR_OK, "%s",
          err.msg);
    double sum = 0.0;
    for (uint32_t i = 0; i < 3u * W * H; ++i) {
        sum += film.sum[i];
    }
    tr_film_free(&film);
    return sum;
}

static void test_switch(int sampling) {
    tr_error err;
    tr_scene *s = box(sampling);
    const uint32_t m = emitter_material(s);
    const float base = tr_scene_material(s, m).emittance;
    const uint32_t lights = tr_scene_light_count(s);
    const float total = s->light_weight_total;
    CHECK(lights > 0 && base > 0.0f && frame_sum(s) > 0.0, "the box is lit");
    const int tree = s->light_node_count > 0;
    CHECK(tree == (sampling == TR_LIGHT_SAMPLING_TREE), "light tree %d for mode %d", tree,
          sampling);

    const uint64_t gen = tr_scene_generation(s);
    CHECK(tr_scene_set_emittance(s, m, base, &err) == TR_OK && tr_scene_generation(s) == gen &&
              tr_scene_is_committed(s),
          "the same value changes nothing");

    CHECK(tr_scene_set_emittance(s, m, 0.0f, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_generation(s) > gen && !tr_scene_is_committed(s), "off: the scene is stale");
    CHECK(tr_scene_update(s, NULL, &err) == TR_OK && tr_scene_is_committed(s), "update: %s",
          err.msg);
    CHECK(tr_scene_light_count(s) == 0 && s->light_node_count == 0, "off: %u emitters, %u nodes",
          tr_scene_light_count(s), s->light_node_count);
    CHECK(frame_sum(s) == 0.0, "off: the frame is black");

    CHECK(tr_scene_set_emittance(s, m, base, &err) == TR_OK &&
              tr_scene_update(s, NULL, &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_scene_light_count(s) == lights && s->light_weight_total == total,
          "on again: %u emitters, weight %g (was %u, %g)", tr_scene_light_count(s),
          (double)s->light_weight_total, lights, (double)total);
    CHECK((s->light_node_count > 0) == tree, "on again: the tree is back");

    CHECK(tr_scene_set_emittance(s, m, 2.0f * base, &err) == TR_OK &&
              tr_scene_update(s, NULL, &err) == TR_OK,
          "%s", err.msg);
    CHECK_NEAR(s->light_weight_total, 2.0 * total, 1e-5 * total, "twice the emittance");
    CHECK((s->light_node_count > 0) == tree, "twice: the tree is rebuilt");
    tr_scene_destroy(s);
}

static void test_refusals(void) {
    tr_error err;
    tr_scene *s = box(TR_LIGHT_SAMPLING_AUTO);
    const uint32_t m = emitter_material(s);
    const uint32_t other = m == 0 ? 1u : 0u;
    int rc = tr_scene_set_emittance(s, tr_scene_material_count(s), 1.0f, &err);
    CHECK_STATUS(rc, err, TR_STATUS_NOT_FOUND, "an unknown material");
    rc = tr_scene_set_emittance(s, other, 1.0f, &err);
    CHECK_STATUS(rc, err, TR_STATUS_INVALID_ARGUMENT, "not an emitter");
    rc = tr_scene_set_emittance(s, m, -1.0f, &err);
    CHECK_STATUS(rc, err, TR_STATUS_INVALID_ARGUMENT, "a negative emittance");
    rc = tr_scene_set_emittance(s, m, NAN, &err);
    CHECK_STATUS(rc, err, TR_STATUS_INVALID_ARGUMENT, "a NaN emittance");
    rc = tr_scene_set_sun_direction(s, tr_vec3_make(0.0f, 1.0f, 0.0f), &err);
    CHECK_STATUS(rc, err, TR_STATUS_NOT_FOUND, "no sun");
    rc = tr_scene_animate_light(s, 1, 7, &err);
    CHECK_STATUS(rc, err, TR_STATUS_INVALID_ARGUMENT, "an unknown animation");
    CHECK(tr_scene_is_committed(s), "refusals change nothing");
    tr_scene_destroy(s);
}

static void test_animations(void) {
    tr_error err;
    tr_scene *s = box(TR_LIGHT_SAMPLING_AUTO);
    const uint32_t m = emitter_material(s);
    const float base = tr_scene_material(s, m).emittance;
    for (uint32_t f = 0; f < 40; ++f) {
        CHECK(tr_scene_animate_light(s, f, TR_LIGHT_ANIMATION_SWITCH, &err) == TR_OK &&
                  tr_scene_update(s, NULL, &err) == TR_OK,
              "%s", err.msg);
        const int on = f < 8 || (f >= 16 && f < 24) || f >= 32;
        CHECK(tr_light_animation_on(f) == on, "frame %u: on %d", f, on);
        CHECK(tr_scene_material(s, m).emittance == (on ? base : 0.0f), "frame %u: emittance %g", f,
              (double)tr_scene_material(s, m).emittance);
    }
    /* The emitter's shape: the one whose triangles use m. */
    uint32_t shape = UINT32_MAX;
    for (uint32_t i = 0; i < tr_scene_shape_count(s); ++i) {
        const tr_flat_node *node = &s->shapes[i];
        if (node->count && s->triangles[node->first].material == m) {
            shape = i;
        }
    }
    CHECK(shape != UINT32_MAX, "the emitter's shape");
    const tr_aabb b0 = tr_scene_shape_box(s, shape);
    const double width = (double)b0.max.x - (double)b0.min.x;
    for (uint32_t f = 0; f <= 15; ++f) {
        CHECK(tr_scene_animate_light(s, f, TR_LIGHT_ANIMATION_MOVE, &err) == TR_OK &&
                  tr_scene_update(s, NULL, &err) == TR_OK,
              "%s", err.msg);
    }
    const tr_aabb b15 = tr_scene_shape_box(s, shape);
    CHECK_NEAR(b15.min.x - b0.min.x, 0.25 * width, 1e-3 * width, "frame 15: a quarter width");
    CHECK(b15.min.y == b0.min.y && b15.min.z == b0.min.z, "only along x");
    for (uint32_t f = 16; f <= 60; ++f) {
        CHECK(tr_scene_animate_light(s, f, TR_LIGHT_ANIMATION_MOVE, &err) == TR_OK, "%s", err.msg);
    }
    CHECK(tr_scene_update(s, NULL, &err) == TR_OK, "%s", err.msg);
    CHECK_NEAR(tr_scene_shape_box(s, shape).min.x, b0.min.x, 1e-3 * width, "frame 60: back");
    CHECK(tr_scene_animate_light(s, 3, TR_LIGHT_ANIMATION_NONE, &err) == TR_OK, "none");
    for (int k = TR_LIGHT_ANIMATION_NONE; k <= TR_LIGHT_ANIMATION_MOVE; ++k) {
        CHECK(tr_light_animation_from_name(tr_light_animation_name(k)) == k, "name %d", k);
    }
    CHECK(tr_light_animation_name(3) == NULL && tr_light_animation_from_name("blink") == -1,
          "unknown names");
    tr_scene_destroy(s);
}

int main(void) {
    test_switch(TR_LIGHT_SAMPLING_POWER);
    test_switch(TR_LIGHT_SAMPLING_TREE);
    test_refusals();
    test_animations();
    return check_finish("test_light_change");
}
