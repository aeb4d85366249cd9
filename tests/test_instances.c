/* test_instances.c - instances and the two-level structure.
 *
 * A prototype (a smooth icosphere and a box, with vertex normals) is placed several times
 * with matrices (rotation, non-uniform scale, a mirror, translation) beside a floor and
 * a lamp of the scene's own. Checked:
 * 1. An instanced scene renders like the same scene flattened (each placement added as
 *    plain triangles, tr_scene_add_prototype_copy, which writes the very triangles and
 *    vertex normals an instance's shape gets): bit for bit, radiance and primitive ids,
 *    when the only instance is the identity (the ray is then used unchanged, so every hit
 *    is the same float for float); with general matrices the hits are computed in object
 *    space against the untransformed triangles, so t, u and v differ from the flattened
 *    scene's in the last bits, the shading point moves by rounding, and a few paths take
 *    another branch: the images then agree to 0.1% in the mean and the primitive ids on
 *    all but 1% of the pixels.
 * 2. The two-level traversal (every ISA the CPU has) agrees with a brute-force test of
 *    every world triangle on random rays: the same triangle, or a hit at the same
 *    distance within float tolerance (a ray through an edge shared by two triangles).
 *    The structures that trace the instances flattened (bvh2, flat, and Embree over the
 *    scene the bvh2 commit flattened) agree with brute force too.
 * 3. Ids: tr_scene_triangle_instance names the instance and the primitive of a triangle.
 * 4. Bad matrices (singular, NaN, infinite) and bad references are refused with
 *    TR_STATUS_INVALID_ARGUMENT / TR_STATUS_NOT_FOUND.
 * 5. Moving instances (tr_scene_set_instance_transform, tr_scene_move_shape on an
 *    instance's shape) and tr_scene_update (a refit of the top level's path) trace exactly
 *    what a full commit of the moved scene traces. */
#include <stdlib.h>
#include <string.h>

#include "accel/wbvh.h"
#include "check.h"
#include "kernel/kernel.h"
#include "render_film.h"
#include "scene/scene_internal.h"
#include "scene_util.h"
#include "trac0r/trac0r.h"

#define W 64u
#define H 48u
#define SPP 4u
#define RAYS 20000u

static const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

/* The placements: identity; rotated and scaled non-uniformly; mirrored in x; sheared. */
static void placement(int k, float m[12]) {
    tr_transform tf;
    memset(&tf, 0, sizeof tf);
    switch (k) {
    case 0:
        memcpy(m, identity, sizeof identity);
        return;
    case 1:
        tf.position = v3(1.2f, 0.3f, -0.4f);
        tf.orientation = v3(0.3f, 0.9f, -0.2f);
        tf.scale = v3(0.5f, 0.8f, 0.6f);
        tr_transform_matrix(&tf, m);
        return;
    case 2:
        tf.position = v3(-1.1f, 0.2f, 0.5f);
        tf.orientation = v3(0.0f, -0.5f, 0.0f);
        tf.scale = v3(0.6f, 0.6f, 0.6f);
        tr_transform_matrix(&tf, m);
        m[0] = -m[0]; /* mirror x */
        m[4] = -m[4];
        m[8] = -m[8];
        return;
    default: {
        const float sh[12] = {0.4f, 0.2f,  0.0f, 0.1f, 0.0f,  0.5f,
                              0.1f, -0.2f, 0.1f, 0.0f, 0.45f, 1.0f};
        memcpy(m, sh, sizeof sh);
        return;
    }
    }
}

/* The scene: prototype 0, then floor and lamp, then `n` placements of it (from `first`),
 * as instances or, with flat set, as plain copies. */
static void build(tr_scene *s, int first, int n, int flat) {
    tr_error err;
    tr_scene_init(s);
    uint32_t white = add_mat(s, tr_material_diffuse(v3(0.8f, 0.8f, 0.8f)));
    uint32_t red = add_mat(s, tr_material_glossy(v3(0.8f, 0.3f, 0.2f), 0.3f));
    uint32_t lamp = add_mat(s, tr_material_emitter(v3(1.0f, 1.0f, 1.0f), 8.0f));
    add_shape(s, TR_SHAPE_ICOSPHERE_SMOOTH, red, v3(0.0f, 0.5f, 0.0f), v3s(0.0f), v3s(0.5f));
    add_shape(s, TR_SHAPE_BOX, white, v3(0.0f, 0.1f, 0.6f), v3(0.0f, 0.4f, 0.0f), v3s(0.3f));
    uint32_t proto = 99;
    CHECK(tr_scene_make_prototype(s, 0, &proto, &err) == TR_OK, "prototype: %s", err.msg);
    CHECK(proto == 0 && tr_scene_triangle_count(s) == 0 && tr_scene_shape_count(s) == 0,
          "the prototype's shapes left the scene (%u triangles)", tr_scene_triangle_count(s));
    add_shape(s, TR_SHAPE_PLANE, white, v3s(0.0f), v3s(0.0f), v3(8.0f, 1.0f, 8.0f));
    add_shape(s, TR_SHAPE_PLANE, lamp, v3(0.0f, 3.0f, 0.0f), v3(3.14159265f, 0.0f, 0.0f),
              v3(1.5f, 1.0f, 1.5f));
    for (int k = first; k < first + n; ++k) {
        float m[12];
        placement(k, m);
        if (flat) {
            CHECK(tr_scene_add_prototype_copy(s, proto, m, &err) == TR_OK, "copy %d: %s", k,
                  err.msg);
        } else {
            CHECK(tr_scene_add_instance(s, proto, m, NULL, &err) == TR_OK, "instance %d: %s", k,
                  err.msg);
        }
    }
    tr_camera cam;
    CHECK(tr_camera_make(&cam, v3(0.0f, 1.6f, 4.0f), v3(0.0f, -0.3f, -1.0f), v3(0.0f, 1.0f, 0.0f),
                         45.0f, 0.0f, 1e30f, W, H, &err) == TR_OK,
          "camera: %s", err.msg);
    tr_scene_set_camera(s, &cam);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
}

static void compare_renders(const char *name, int first, int n, int exact) {
    tr_scene a, b;
    build(&a, first, n, 0);
    build(&b, first, n, 1);
    CHECK(a.two_level && !b.two_level, "%s: the instanced scene traces two levels", name);
    /* The instances are kept (placed, not stored): their ids follow the scene's own two
     * triangles, as the copies' do, and read the very triangles the copies store. */
    CHECK(tr_scene_triangle_count(&a) == b.triangle_count && a.triangle_count == 4,
          "%s: %u (%u stored) vs %u triangles", name, tr_scene_triangle_count(&a), a.triangle_count,
          b.triangle_count);
    uint32_t tri_diff = 0;
    for (uint32_t i = 0; i < b.triangle_count; ++i) {
        const tr_triangle t = tr_scene_triangle(&a, i);
        tri_diff += memcmp(&t, &b.triangles[i], sizeof t) != 0;
    }
    CHECK(tri_diff == 0, "%s: %u of an instance's triangles differ from the flattened ones", name,
          tri_diff);
    tr_film fa, fb;
    memset(&fa, 0, sizeof fa);
    memset(&fb, 0, sizeof fb);
    render_film(&a, W, H, TR_INTEGRATOR_PT, 6, TR_PASS_PRIM, 7, 0, SPP, &fa);
    render_film(&b, W, H, TR_INTEGRATOR_PT, 6, TR_PASS_PRIM, 7, 0, SPP, &fb);
    double sa = 0.0, sb = 0.0;
    uint32_t id_diff = 0, hit = 0;
    for (uint32_t i = 0; fa.sum && fb.sum && i < W * H; ++i) {
        for (int c = 0; c < 3; ++c) {
            sa += fa.sum[3 * i + c];
            sb += fb.sum[3 * i + c];
        }
        id_diff += fa.prim[i] != fb.prim[i];
        hit += fa.prim[i] != 0;
    }
    CHECK(hit > W * H / 2, "%s: the camera sees the scene (%u of %u pixels)", name, hit, W * H);
    if (exact) {
        CHECK(fa.sum && fb.sum && memcmp(fa.sum, fb.sum, (size_t)W * H * 3 * sizeof(float)) == 0,
              "%s: radiance bit for bit", name);
        CHECK(id_diff == 0, "%s: %u pixels' ids differ", name, id_diff);
    } else {
        CHECK(fabs(sa - sb) <= 0.001 * sb, "%s: mean radiance %.6g vs %.6g", name, sa, sb);
        CHECK(id_diff <= W * H / 100, "%s: %u pixels' ids differ", name, id_diff);
    }
    /* Every id names a triangle; those of instances name the instance and primitive. */
    uint32_t named = 0;
    for (uint32_t i = 0; fa.prim && i < W * H; ++i) {
        uint32_t inst, prim;
        if (fa.prim[i] && tr_scene_triangle_instance(&a, fa.prim[i] - 1, &inst, &prim)) {
            const tr_flat_node *sh = &a.shapes[a.instances[inst].shape];
            CHECK(inst < (uint32_t)n && sh->first + prim == fa.prim[i] - 1 &&
                      prim < tr_scene_prototype_triangle_count(&a, 0),
                  "%s: id %u named as instance %u primitive %u", name, fa.prim[i], inst, prim);
            named++;
        }
    }
    CHECK(named > 0, "%s: the instances are seen", name);
    tr_film_free(&fa);
    tr_film_free(&fb);
    tr_scene_clear(&a);
    tr_scene_clear(&b);
}

static tr_vec3 rand_unit(tr_rng *r) {
    float z = tr_rng_range(r, -1.0f, 1.0f);
    float phi = tr_rng_range(r, 0.0f, TR_TWO_PI);
    float s = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return v3(s * cosf(phi), s * sinf(phi), z);
}

/* Aimed at a random point of a random triangle from a random origin (mostly hits), or in
 * a random direction (many misses). */
static tr_ray rand_ray(tr_rng *r, const tr_scene *s) {
    tr_vec3 o = v3(tr_rng_range(r, -3.0f, 3.0f), tr_rng_range(r, -0.5f, 3.5f),
                   tr_rng_range(r, -3.0f, 3.0f));
    const tr_triangle tt = tr_scene_triangle(s, tr_rng_next(r) % tr_scene_triangle_count(s));
    const tr_triangle *t = &tt;
    float a = tr_rng_float(r), c = tr_rng_float(r);
    if (a + c > 1.0f) {
        a = 1.0f - a;
        c = 1.0f - c;
    }
    tr_vec3 target = v3_madd(v3_madd(t->v0, v3_sub(t->v1, t->v0), a), v3_sub(t->v2, t->v0), c);
    tr_vec3 d = tr_rng_next(r) % 4 == 0 ? rand_unit(r) : v3_normalize(v3_sub(target, o));
    return tr_ray_make(o, d, 0.0f, tr_rng_next(r) % 5 == 0 ? 2.0f : TR_INFINITY);
}

static int brute(const tr_scene *s, const tr_ray *ray, tr_hit *hit) {
    tr_ray r = *ray;
    int found = 0;
    for (uint32_t i = 0; i < tr_scene_triangle_count(s); ++i) {
        const tr_triangle tri = tr_scene_triangle(s, i);
        const tr_triangle *t = &tri;
        float tt, u, v;
        if (t->area > 0.0f && tr_intersect_triangle(&r, t->v0, t->v1, t->v2, &tt, &u, &v)) {
            r.tmax = tt;
            hit->t = tt;
            hit->triangle = i;
            found = 1;
        }
    }
    return found;
}

static void compare_brute(void) {
    tr_scene s;
    build(&s, 0, 4, 0);
    const tr_scene_view v = tr_scene_view_of(&s);
    CHECK(v.wbvh == &s.tlas.wbvh, "the view traces the top level");
    const unsigned mask = tr_wbvh_isa_mask();
    for (int isa = 0; isa < TR_WBVH_ISA_COUNT; ++isa) {
        if (!(mask >> isa & 1u)) {
            continue;
        }
        tr_rng r;
        tr_rng_init(&r, 99, (uint64_t)isa, 3);
        uint32_t hits = 0, bad = 0, occ_bad = 0;
        for (uint32_t k = 0; k < RAYS; ++k) {
            tr_ray ray = rand_ray(&r, &s);
            tr_hit hb, ht;
            memset(&hb, 0, sizeof hb);
            memset(&ht, 0, sizeof ht);
            int fb = brute(&s, &ray, &hb);
            int ft = tr_wbvh_trace_isa(isa, v.wbvh, &ray, &ht, 0);
            int ot = tr_wbvh_trace_isa(isa, v.wbvh, &ray, NULL, 1);
            hits += fb;
            /* Hits at a grazing distance from an edge may go either way in object space. */
            int same = fb == ft && (!fb || ht.triangle == hb.triangle ||
                                    fabsf(ht.t - hb.t) <= 1e-4f * fmaxf(1.0f, hb.t));
            if (fb == ft && fb && same) {
                same = fabsf(ht.t - hb.t) <= 1e-4f * fmaxf(1.0f, hb.t);
            }
            bad += !same;
            occ_bad += ot != fb;
        }
        CHECK(hits > RAYS / 2, "%s: %u of %u random rays hit", tr_wbvh_isa_name(isa), hits, RAYS);
        /* Rays grazing an edge of the scene (a hit in one space, a miss in the other). */
        CHECK(bad <= RAYS / 2000, "%s: %u of %u rays disagree with brute force",
              tr_wbvh_isa_name(isa), bad, RAYS);
        CHECK(occ_bad <= RAYS / 2000, "%s: %u of %u occlusion answers disagree",
              tr_wbvh_isa_name(isa), occ_bad, RAYS);
    }
    tr_scene_clear(&s);
}

/* The structures that trace the instances flattened (bvh2, flat, and Embree where built,
 * which gets the scene bvh2 flattened: its own instancing is test_instances_kept's)
 * against brute force: the same triangles, so the same closest hits but for ties. */
static void compare_flattened(void) {
    tr_scene s;
    tr_error err;
    build(&s, 0, 4, 0);
    const tr_accel_type kinds[3] = {TR_ACCEL_TYPE_BVH2, TR_ACCEL_TYPE_FLAT, TR_ACCEL_TYPE_EMBREE};
    for (int a = 0; a < 3; ++a) {
        if (!tr_accel_available(kinds[a])) {
            continue;
        }
        CHECK(tr_scene_commit(&s, kinds[a], &err) == TR_OK && !s.two_level, "commit %s: %s",
              tr_accel_name(kinds[a]), err.msg);
        const tr_scene_view v = tr_scene_view_of(&s);
        tr_rng r;
        tr_rng_init(&r, 17, (uint64_t)a, 1);
        uint32_t bad = 0, hits = 0;
        for (uint32_t k = 0; k < RAYS / 4; ++k) {
            tr_ray ray = rand_ray(&r, &s);
            tr_hit hb, ht;
            memset(&hb, 0, sizeof hb);
            memset(&ht, 0, sizeof ht);
            int fb = brute(&s, &ray, &hb);
            int ft = tr_intersect_scene(&v, &ray, &ht);
            hits += fb;
            bad += fb != ft || (fb && fabsf(ht.t - hb.t) > 1e-5f * fmaxf(1.0f, hb.t));
        }
        /* bvh2 and flat test triangles as brute force does; Embree's own (watertight)
         * test may decide a ray through an edge the other way. */
        const uint32_t allowed = kinds[a] == TR_ACCEL_TYPE_EMBREE ? RAYS / 2000 : 0;
        CHECK(hits > RAYS / 8 && bad <= allowed, "%s: %u of %u rays disagree with brute force",
              tr_accel_name(kinds[a]), bad, RAYS / 4);
    }
    tr_scene_clear(&s);
}

static void refused(void) {
    tr_scene s;
    tr_error err;
    build(&s, 0, 2, 0);
    float m[12];
    memcpy(m, identity, sizeof m);
    m[5] = 0.0f; /* y collapses */
    CHECK_STATUS(tr_scene_add_instance(&s, 0, m, NULL, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "singular matrix");
    memcpy(m, identity, sizeof m);
    m[0] = 1.0f;
    m[4] = 1.0f;
    m[8] = 0.0f;
    m[1] = 1.0f;
    m[5] = 1.0f;
    m[9] = 0.0f; /* two equal columns */
    CHECK_STATUS(tr_scene_add_instance(&s, 0, m, NULL, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "rank-2 matrix");
    memcpy(m, identity, sizeof m);
    m[7] = NAN;
    CHECK_STATUS(tr_scene_add_instance(&s, 0, m, NULL, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "NaN translation");
    CHECK_STATUS(tr_scene_set_instance_transform(&s, 1, m, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "NaN in a move");
    memcpy(m, identity, sizeof m);
    m[2] = INFINITY;
    CHECK_STATUS(tr_scene_add_prototype_copy(&s, 0, m, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "infinite entry");
    CHECK_STATUS(tr_scene_add_instance(&s, 1, identity, NULL, &err), err, TR_STATUS_NOT_FOUND,
                 "unknown prototype");
    CHECK_STATUS(tr_scene_set_instance_transform(&s, 7, identity, &err), err, TR_STATUS_NOT_FOUND,
                 "unknown instance");
    CHECK_STATUS(tr_scene_make_prototype(&s, 2, NULL, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "a prototype of instances");
    CHECK(tr_scene_instance_count(&s) == 2 && tr_scene_is_committed(&s),
          "refused calls change nothing (%u instances)", tr_scene_instance_count(&s));
    tr_scene_clear(&s);
}

static void moves(void) {
    tr_scene s;
    tr_error err;
    build(&s, 0, 4, 0);
    float m[12];
    placement(1, m);
    m[3] += 0.7f;
    m[11] -= 0.3f;
    CHECK(tr_scene_set_instance_transform(&s, 0, m, &err) == TR_OK, "move: %s", err.msg);
    placement(3, m);
    CHECK(tr_scene_set_instance_transform(&s, 2, m, &err) == TR_OK, "move: %s", err.msg);
    CHECK(tr_scene_move_shape(&s, s.instances[3].shape, v3(0.0f, 0.4f, -0.5f), &err) == TR_OK,
          "move shape: %s", err.msg);
    CHECK(tr_scene_instance_transform(&s, 3, m) && m[7] != 0.0f,
          "the shape's move moved the matrix");
    CHECK(tr_scene_move_shape(&s, 0, v3(0.0f, -0.1f, 0.0f), &err) == TR_OK, "floor: %s", err.msg);
    CHECK(!tr_scene_is_committed(&s), "a move makes the structure stale");
    CHECK(tr_scene_update(&s, NULL, &err) == TR_OK, "update: %s", err.msg);
    CHECK(tr_scene_is_committed(&s) && s.two_level && s.tlas.moves >= 4,
          "the update refitted the top level (%u path refits)", s.tlas.moves);
    enum { N = 4000 };
    tr_ray *rays = malloc(N * sizeof *rays);
    tr_hit *hits = calloc(N, sizeof *hits);
    int *found = calloc(N, sizeof *found);
    tr_rng r;
    tr_rng_init(&r, 5, 0, 0);
    tr_scene_view v = tr_scene_view_of(&s);
    for (int k = 0; rays && hits && found && k < N; ++k) {
        rays[k] = rand_ray(&r, &s);
        found[k] = tr_intersect_scene(&v, &rays[k], &hits[k]);
    }
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    v = tr_scene_view_of(&s);
    uint32_t diff = 0, n_hit = 0;
    for (int k = 0; rays && hits && found && k < N; ++k) {
        tr_hit h;
        memset(&h, 0, sizeof h);
        int f = tr_intersect_scene(&v, &rays[k], &h);
        n_hit += f;
        /* The same closest hit, bit for bit; two triangles at exactly the same distance
         * (a shared edge) may come in either order. */
        diff += f != found[k] || (f && (memcmp(&h.t, &hits[k].t, sizeof h.t) != 0));
    }
    CHECK(n_hit > N / 2, "%u of %d rays hit", n_hit, N);
    CHECK(diff == 0, "%u of %d rays differ between the refit and the rebuild", diff, N);
    free(rays);
    free(hits);
    free(found);
    tr_scene_clear(&s);
}

/* The generated forest: every tree an instance of one prototype, traced in two levels. */
static void forest(void) {
    tr_scene s;
    tr_error err;
    tr_scene_init(&s);
    CHECK(tr_scene_builtin(&s, "forest-3", 32, 24, &err) == TR_OK, "forest-3: %s", err.msg);
    CHECK(tr_scene_instance_count(&s) == 9 && tr_scene_prototype_count(&s) == 1 &&
              tr_scene_triangle_count(&s) == 2 + 9 * tr_scene_prototype_triangle_count(&s, 0),
          "forest-3: %u instances, %u triangles", tr_scene_instance_count(&s),
          tr_scene_triangle_count(&s));
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK && s.two_level, "commit: %s",
          err.msg);
    CHECK(tr_scene_builtin(&s, "forest-0", 32, 24, &err) == TR_ERR &&
              tr_scene_builtin(&s, "forest-1001", 32, 24, &err) == TR_ERR &&
              tr_scene_builtin(&s, "forest-2x", 32, 24, &err) == TR_ERR,
          "forest sizes outside 1..1000 are refused");
    tr_scene_clear(&s);
    /* Lit by its sun and sky, it needs no emitter (nor --allow-dark) to be rendered. */
    tr_scene_file info;
    tr_render_settings rs;
    tr_scene_init(&s);
    CHECK(tr_scene_load(&s, "builtin:forest-2", NULL, &info, &err) == TR_OK, "%s", err.msg);
    const int rc = tr_scene_file_apply(&s, "builtin:forest-2", &info, NULL, &rs, &err);
    CHECK(info.emissive_triangles == 0 && rc == TR_OK, "forest-2: %u emissive triangles, %s",
          info.emissive_triangles, rc == TR_OK ? "accepted" : err.msg);
    tr_scene_clear(&s);
}

int main(void) {
    compare_renders("identity instance", 0, 1, 1);
    compare_renders("general matrices", 0, 4, 0);
    compare_brute();
    compare_flattened();
    refused();
    moves();
    forest();
    return check_finish("test_instances");
}
