/* test_scene_update.c - dynamic scenes: tr_scene_move_shape + tr_scene_update.
 *
 * A shape of the Cornell box is moved several times; after each tr_scene_update every
 * structure (bvh refitted, bvh2 refitted, Embree rebuilt, flat) must find the same
 * closest hits and occlusions as the flat structure of a scene built from scratch with
 * the shape already in its new place. Half the rays aim at the moved shape, so an update
 * that left the old boxes in place would miss it (checked: before the update the BVH does
 * disagree). */
#include <stdint.h>
#include <string.h>

#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

static uint32_t rng_state = 12345u;
static float rnd(void) {
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 17;
    rng_state ^= rng_state << 5;
    return (float)(rng_state >> 8) * (1.0f / 16777216.0f);
}

static tr_vec3 lerp_box(tr_aabb b) {
    return v3(b.min.x + rnd() * (b.max.x - b.min.x), b.min.y + rnd() * (b.max.y - b.min.y),
              b.min.z + rnd() * (b.max.z - b.min.z));
}

/* Rays from the camera's position: toward the moved shape's box, and anywhere. */
static tr_ray test_ray(const tr_scene *s, uint32_t shape, int i) {
    tr_vec3 o = s->camera.pos;
    tr_vec3 d;
    if (i % 2 == 0) {
        d = v3_sub(lerp_box(s->shapes[shape].box), o);
    } else {
        d = v3(2.0f * rnd() - 1.0f, 2.0f * rnd() - 1.0f, 2.0f * rnd() - 1.0f);
    }
    return tr_ray_make(o, v3_normalize(d), 0.0f, TR_INFINITY);
}

/* Disagreements between `s` and the reference `ref` over n rays: another triangle, or a
 * hit distance more than rel_tol apart (0 for our structures, which compute t exactly as
 * the flat one does; Embree rounds it its own way). */
static int disagreements(const tr_scene *s, const tr_scene *ref, uint32_t shape, int n,
                         float rel_tol, int *hits_on_shape) {
    tr_scene_view v = tr_scene_view_of(s), rv = tr_scene_view_of(ref);
    int bad = 0;
    *hits_on_shape = 0;
    const tr_flat_node *node = &ref->shapes[shape];
    for (int i = 0; i < n; ++i) {
        tr_ray ray = test_ray(ref, shape, i);
        tr_hit h, rh;
        int hit = tr_intersect_scene(&v, &ray, &h);
        int rhit = tr_intersect_scene(&rv, &ray, &rh);
        if (hit != rhit ||
            (hit && (h.triangle != rh.triangle || fabsf(h.t - rh.t) > rel_tol * rh.t))) {
            ++bad;
        }
        if (rhit && rh.triangle >= node->first && rh.triangle < node->first + node->count) {
            ++*hits_on_shape;
        }
        tr_ray seg = ray;
        seg.tmax = rhit ? rh.t * 0.999f : 100.0f;
        if (tr_occluded_scene(&v, &seg) != tr_occluded_scene(&rv, &seg)) {
            ++bad;
        }
    }
    return bad;
}

/* Renders `spp` samples of the scene from its own camera with the naive integrator;
 * returns the rc of the first failing frame. */
static int render_film(const tr_scene *s, tr_film *f, uint32_t spp, tr_error *err) {
    tr_render_config cfg = tr_render_config_default();
    cfg.seed = 99;
    tr_film_clear(f);
    for (uint32_t k = 0; k < spp; ++k) {
        if (tr_render_frame(s, tr_scene_camera(s), &cfg, f, k, NULL, err) != TR_OK) {
            return TR_ERR;
        }
    }
    return TR_OK;
}

/* The generation counter through the public API only: every edit bumps it, a render of
 * a scene edited since its commit fails, and tr_scene_update after moving every shape
 * makes the scene render exactly as one committed with the shapes already moved. */
static void test_generation(void) {
    tr_error err;
    const tr_accel_type accels[] = {TR_ACCEL_TYPE_FLAT, TR_ACCEL_TYPE_BVH, TR_ACCEL_TYPE_BVH2,
                                    TR_ACCEL_TYPE_EMBREE};
    const tr_vec3 delta = {0.05f, -0.02f, 0.03f};
    for (int k = 0; k < 4; ++k) {
        if (!tr_accel_available(accels[k])) {
            continue;
        }
        tr_scene *s = tr_scene_create(&err);
        tr_scene *ref = tr_scene_create(&err);
        CHECK(s && ref, "tr_scene_create: %s", err.msg);
        if (!s || !ref) {
            tr_scene_destroy(s);
            tr_scene_destroy(ref);
            return;
        }
        CHECK(tr_scene_generation(s) == 0 && !tr_scene_is_committed(s), "a new scene");
        CHECK(tr_scene_builtin(s, "cornell", 32, 24, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_scene_builtin(ref, "cornell", 32, 24, &err) == TR_OK, "%s", err.msg);
        tr_film film, want;
        CHECK(tr_film_init(&film, 32, 24, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_film_init(&want, 32, 24, &err) == TR_OK, "%s", err.msg);
        CHECK(render_film(s, &film, 1, &err) == TR_ERR, "%s: an uncommitted scene rendered",
              tr_accel_name(accels[k]));
        CHECK(tr_scene_commit(s, accels[k], &err) == TR_OK, "%s", err.msg);
        const uint64_t g0 = tr_scene_generation(s);
        CHECK(g0 > 0 && tr_scene_is_committed(s), "%s: committed at generation %llu",
              tr_accel_name(accels[k]), (unsigned long long)g0);

        /* The camera is no input to any structure: setting it keeps the commit. */
        tr_camera cam = *tr_scene_camera(s);
        tr_scene_set_camera(s, &cam);
        CHECK(tr_scene_generation(s) == g0 && tr_scene_is_committed(s), "set_camera bumped");

        /* Move every shape: each move bumps the generation, and the scene is stale. */
        const uint32_t shapes = tr_scene_shape_count(s);
        for (uint32_t i = 0; i < shapes; ++i) {
            const uint64_t before = tr_scene_generation(s);
            CHECK(tr_scene_move_shape(s, i, delta, &err) == TR_OK, "%s", err.msg);
            CHECK(tr_scene_move_shape(ref, i, delta, &err) == TR_OK, "%s", err.msg);
            CHECK(tr_scene_generation(s) > before, "move_shape did not bump the generation");
        }
        CHECK(!tr_scene_is_committed(s), "%s: moved shapes count as committed",
              tr_accel_name(accels[k]));
        CHECK(render_film(s, &film, 1, &err) == TR_ERR, "%s: rendered moved shapes unupdated",
              tr_accel_name(accels[k]));

        /* After the update: the same image as a scene committed with the shapes moved. */
        CHECK(tr_scene_update(s, NULL, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_scene_is_committed(s), "%s: not committed after the update",
              tr_accel_name(accels[k]));
        CHECK(tr_scene_commit(ref, accels[k], &err) == TR_OK, "%s", err.msg);
        CHECK(render_film(s, &film, 2, &err) == TR_OK, "%s", err.msg);
        CHECK(render_film(ref, &want, 2, &err) == TR_OK, "%s", err.msg);
        CHECK(memcmp(film.sum, want.sum, (size_t)32 * 24 * 3 * sizeof(float)) == 0,
              "%s: the updated scene renders differently from one built moved",
              tr_accel_name(accels[k]));

        /* Other edits: a material, a shape, a mesh each bump it; an update cannot stand in
         * for the commit a new shape needs. */
        uint64_t g = tr_scene_generation(s);
        uint32_t white;
        CHECK(tr_scene_add_material(s, tr_material_diffuse(tr_vec3_make(0.5f, 0.5f, 0.5f)), &white,
                                    &err) == TR_OK,
              "%s", err.msg);
        CHECK(tr_scene_generation(s) > g && !tr_scene_is_committed(s), "add_material");
        g = tr_scene_generation(s);
        tr_shape_desc box = tr_shape_desc_default(TR_SHAPE_BOX);
        box.material = white;
        box.transform.scale = tr_vec3_make(0.1f, 0.1f, 0.1f);
        CHECK(tr_scene_add_shape(s, &box, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_scene_generation(s) > g, "add_shape did not bump the generation");
        CHECK(tr_scene_update(s, NULL, &err) == TR_ERR, "%s: update stood in for a commit",
              tr_accel_name(accels[k]));
        g = tr_scene_generation(s);
        const float pos[9] = {0, 0, 0, 0.1f, 0, 0, 0, 0.1f, 0};
        const uint32_t idx[3] = {0, 1, 2};
        CHECK(tr_scene_add_mesh(s, pos, 3, idx, 1, NULL, white, NULL, NULL, &err) == TR_OK, "%s",
              err.msg);
        CHECK(tr_scene_generation(s) > g, "add_mesh did not bump the generation");
        CHECK(tr_scene_commit(s, accels[k], &err) == TR_OK, "%s", err.msg);
        CHECK(render_film(s, &film, 1, &err) == TR_OK, "%s", err.msg);

        /* Reloading the handle goes on counting, so that an upload of the old content
         * never matches the new one. */
        g = tr_scene_generation(s);
        CHECK(tr_scene_builtin(s, "cornell", 32, 24, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_scene_generation(s) > g && !tr_scene_is_committed(s), "reload: generation %llu",
              (unsigned long long)tr_scene_generation(s));
        tr_film_free(&film);
        tr_film_free(&want);
        tr_scene_destroy(s);
        tr_scene_destroy(ref);
    }
}

int main(void) {
    tr_error err;
    const tr_accel_type accels[] = {TR_ACCEL_TYPE_BVH, TR_ACCEL_TYPE_BVH2, TR_ACCEL_TYPE_EMBREE,
                                    TR_ACCEL_TYPE_FLAT};
    const tr_vec3 steps[] = {{0.06f, 0.0f, -0.04f}, {-0.02f, 0.03f, 0.05f}, {0.0f, -0.03f, 0.0f}};
    const int nrays = 4000;
    for (int k = 0; k < 4; ++k) {
        if (!tr_accel_available(accels[k])) {
            printf("%s: not in this build\n", tr_accel_name(accels[k]));
            continue;
        }
        tr_scene s = {0};
        tr_scene_init(&s);
        CHECK(tr_scene_builtin(&s, "cornell", 64, 48, &err) == TR_OK, "%s", err.msg);
        const uint32_t shape = s.shape_count - 1; /* the last object in the room */
        CHECK(tr_scene_commit(&s, accels[k], &err) == TR_OK, "%s", err.msg);
        const uint32_t lights = s.light_count;
        tr_vec3 total = v3(0.0f, 0.0f, 0.0f);
        for (int step = 0; step < 3; ++step) {
            CHECK(tr_scene_move_shape(&s, shape, steps[step], &err) == TR_OK, "%s", err.msg);
            total = v3_add(total, steps[step]);

            /* The reference: a fresh scene with the shape moved by the same steps. */
            tr_scene ref = {0};
            tr_scene_init(&ref);
            CHECK(tr_scene_builtin(&ref, "cornell", 64, 48, &err) == TR_OK, "%s", err.msg);
            for (int j = 0; j <= step; ++j) {
                CHECK(tr_scene_move_shape(&ref, shape, steps[j], &err) == TR_OK, "%s", err.msg);
            }
            CHECK(tr_scene_commit(&ref, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);

            int on_shape = 0;
            if (accels[k] == TR_ACCEL_TYPE_BVH || accels[k] == TR_ACCEL_TYPE_BVH2) {
                /* Stale boxes: the test below would notice a missing update. */
                int stale = disagreements(&s, &ref, shape, nrays, 0.0f, &on_shape);
                CHECK(stale > 0, "%s step %d: the BVH agreed before its update",
                      tr_accel_name(accels[k]), step);
            }
            double seconds = -1.0;
            CHECK(tr_scene_update(&s, &seconds, &err) == TR_OK, "%s", err.msg);
            CHECK(seconds >= 0.0, "update time %g", seconds);
            CHECK(s.accel == accels[k], "the update changed the structure to %s",
                  tr_accel_name(s.accel));
            /* bvh: the refitted wide BVH is what rays are traced through, not the binary
             * fallback. */
            CHECK(accels[k] != TR_ACCEL_TYPE_BVH || tr_scene_view_of(&s).wbvh != NULL,
                  "bvh step %d: the view fell back to the binary BVH", step);
            const float tol = accels[k] == TR_ACCEL_TYPE_EMBREE ? 1e-5f : 0.0f;
            int bad = disagreements(&s, &ref, shape, nrays, tol, &on_shape);
            CHECK(bad == 0, "%s step %d: %d of %d rays disagree with a fresh scene",
                  tr_accel_name(accels[k]), step, bad, 2 * nrays);
            CHECK(on_shape > nrays / 8, "%s step %d: only %d rays hit the moved shape",
                  tr_accel_name(accels[k]), step, on_shape);
            /* The shape's box and the emitter table follow. */
            const tr_flat_node *n = &s.shapes[shape];
            tr_aabb b = tr_triangles_bounds(s.triangles + n->first, n->count);
            CHECK(b.min.x == n->box.min.x && b.min.y == n->box.min.y && b.min.z == n->box.min.z &&
                      b.max.x == n->box.max.x && b.max.y == n->box.max.y && b.max.z == n->box.max.z,
                  "the shape's box was not moved");
            CHECK(s.light_count == lights, "emitter table changed: %u vs %u", s.light_count,
                  lights);
            tr_scene_clear(&ref);
        }
        printf("%s: update kind %s, moved by (%.2f, %.2f, %.2f)\n", tr_accel_name(accels[k]),
               tr_scene_update_kind(&s), (double)total.x, (double)total.y, (double)total.z);
        tr_scene_clear(&s);
    }

    /* Bad arguments. */
    tr_scene s = {0};
    tr_scene_init(&s);
    CHECK(tr_scene_builtin(&s, "cornell", 64, 48, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_scene_move_shape(&s, s.shape_count, v3(1, 0, 0), &err), err,
                 TR_STATUS_NOT_FOUND, "shape out of range");
    CHECK_STATUS(tr_scene_move_shape(&s, 0, v3(NAN, 0, 0), &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "NaN offset");
    CHECK(strcmp(tr_scene_update_kind(&s), "none") == 0, "flat scene update kind");
    tr_scene_clear(&s);
    test_generation();
    return check_finish("test_scene_update");
}
