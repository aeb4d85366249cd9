/* test_light_tree.c - the light tree (src/scene/light_tree.c, src/kernel/light_tree.h).
 *
 * A generated scene: a diffuse floor, 24 x 24, under 49 small square lamps (a jittered
 * 7 x 7 grid, 98 emissive triangles) at heights from 0.8 to 2, of different powers, most
 * facing down, some facing up, some two-sided.
 *  (a) Structure: 2n - 1 nodes, every emitter in exactly one leaf, parents and children
 *      agree, each node's box holds its emitters' vertices, its power is theirs, and its
 *      cone holds their normals (two-sided ones: any direction).
 *  (b) The selection probability tr_light_select_pdf_n (with and without a receiver
 *      normal) sums to one over all emitters at points all around the scene (also where
 *      no lamp can light the point), and it is positive for every emitter that can light
 *      the point (a one-sided lamp with the point in front of it): the tree never cuts off
 *      a light.
 *  (c) Picks through tr_light_sample_n follow that probability (chi-square, bins with
 *      fewer than 8 expected picks merged), and the density a sample reports is
 *      tr_light_pdf_n's.
 *  (d) Equal samples per pixel: a 32x32 image of the floor, 16 samples per pixel of the
 *      ray through each pixel's centre (no jitter, whose variance would hide the light
 *      choice's) with independent random numbers, with the tree and with the power CDF.
 *      Both are unbiased (every 8x8-pixel region's means agree within 5 standard errors),
 *      so the error is the variance: the mean over pixels of the per-sample variance must
 *      be at least 2 times lower with the tree (it is about 4 times). Each pixel's
 *      variance estimate has a relative standard error near sqrt(2 / 15) (more with heavy
 *      tails), the mean over 1024 pixels a few percent, so a factor 2 cannot come from
 *      their noise.
 *  (e) The default (auto) builds the tree for this scene and not for one two-triangle
 *      lamp; power and tree are honoured; tr_scene_update rebuilds it after a lamp moved. */
#include "check.h"
#include "scene_util.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846
#define LAMPS 49

/* With `down_only` every lamp is one-sided and faces the floor, so the camera above sees
 * their dark backs: the image's noise is that of the floor's lighting. */
static void build(tr_scene *s, int mode, int down_only, uint32_t w, uint32_t h) {
    tr_error err;
    tr_scene_init(s);
    uint32_t floor_m = add_mat(s, tr_material_diffuse(v3(0.7f, 0.7f, 0.7f)));
    add_shape(s, TR_SHAPE_PLANE, floor_m, v3(0, 0, 0), v3(0, 0, 0), v3(24, 1, 24));
    tr_rng rng;
    tr_rng_init(&rng, 77, 0, 0);
    for (int k = 0; k < LAMPS; ++k) {
        tr_material m = tr_material_emitter(v3(1.0f, 0.5f + 0.5f * tr_rng_float(&rng), 0.7f),
                                            2.0f + 30.0f * tr_rng_float(&rng));
        if (k % 7 == 3 && !down_only) {
            m.flags = TR_MATERIAL_TWO_SIDED;
        }
        uint32_t mat = add_mat(s, m);
        /* A 7 x 7 grid (spacing 3.3) with a little jitter, heights 0.8 to 2. */
        float x = -9.9f + 3.3f * (float)(k % 7) + 0.6f * (tr_rng_float(&rng) - 0.5f);
        float z = -9.9f + 3.3f * (float)(k / 7) + 0.6f * (tr_rng_float(&rng) - 0.5f);
        float y = 0.8f + 1.2f * tr_rng_float(&rng);
        float size = 0.05f + 0.15f * tr_rng_float(&rng);
        /* Most face the floor (the plane's normal +y turned over), every fifth faces up. */
        tr_vec3 rot =
            k % 5 == 0 ? v3(0.2f, 0, 0) : v3((float)PI_D + 0.3f * tr_rng_float(&rng), 0, 0);
        add_shape(s, TR_SHAPE_PLANE, mat, v3(x, y, z), rot, v3(size, 1, size));
    }
    CHECK(tr_scene_set_light_sampling(s, mode, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_camera_make(&s->camera, v3(0.0f, 9.0f, -6.0f), v3(0.0f, -1.5f, 1.0f),
                         v3(0.0f, 1.0f, 0.0f), 60.0f, 0.001f, 100.0f, w, h, &err) == TR_OK,
          "camera: %s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
}

/* Whether p lies in the node's bounding sphere (the sphere around its box, which is all
 * the walk reads of the box). */
static int inside(const tr_light_node *n, tr_vec3 p) {
    const tr_vec3 d = v3_sub(p, n->centre);
    return v3_dot(d, d) <= n->r2 * (1.0f + 1e-5f) + 1e-10f;
}

/* (a) */
static void structure(const tr_scene *s) {
    tr_scene_view v = tr_scene_view_of(s);
    const uint32_t n = v.light_count;
    CHECK(n == 2 * LAMPS && v.light_node_count == 2 * n - 1 && v.light_leaf_count == n,
          "%u emitters, %u nodes, %u leaves", n, v.light_node_count, v.light_leaf_count);
    int bad_leaf = 0, bad_box = 0, bad_cone = 0, bad_power = 0, bad_link = 0;
    uint32_t *seen = calloc(n, sizeof *seen);
    for (uint32_t i = 0; i < v.light_node_count; ++i) {
        const tr_light_node *nd = &v.light_nodes[i];
        if (nd->child & TR_LIGHT_LEAF) {
            uint32_t k = nd->child & ~TR_LIGHT_LEAF;
            bad_leaf += !(k < n) || v.light_leaf[k] != i;
            if (k < n) {
                seen[k]++;
            }
            continue;
        }
        const tr_light_node *c0 = &v.light_nodes[nd->child], *c1 = &v.light_nodes[nd->child + 1];
        bad_link += c0->parent != i || c1->parent != i;
        bad_power += !(fabsf(c0->power + c1->power - nd->power) <= 1e-5f * nd->power);
    }
    for (uint32_t k = 0; k < n; ++k) {
        bad_leaf += seen[k] != 1;
        const tr_triangle *t = &s->triangles[v.lights[k]];
        const tr_material *m = &s->materials[t->material];
        /* Every node from the leaf up bounds this emitter. */
        for (uint32_t nd = v.light_leaf[k];; nd = v.light_nodes[nd].parent) {
            const tr_light_node *node = &v.light_nodes[nd];
            bad_box += !inside(node, t->v0) || !inside(node, t->v1) || !inside(node, t->v2);
            bad_cone += !(node->sin_o >= 0.0f && fabsf(node->sin_o * node->sin_o +
                                                       node->cos_o * node->cos_o - 1.0f) <= 1e-6f);
            if (m->flags & TR_MATERIAL_TWO_SIDED) {
                bad_cone += !(node->cos_o <= -0.9999f);
            } else {
                bad_cone += !(v3_dot(node->axis, t->normal) >= node->cos_o - 1e-5f);
            }
            bad_cone += !(node->cos_e < 1e-6f && node->cos_e > -1e-6f);
            if (nd == 0) {
                break;
            }
        }
    }
    free(seen);
    CHECK(bad_leaf == 0 && bad_link == 0, "leaves %d, links %d wrong", bad_leaf, bad_link);
    CHECK(bad_box == 0 && bad_cone == 0 && bad_power == 0, "bounds: box %d, cone %d, power %d",
          bad_box, bad_cone, bad_power);
}

/* Whether emitter triangle t can send light to p: p strictly in front of a one-sided
 * triangle (all of it), or any point off a two-sided one's plane. */
static int can_light(const tr_scene *s, const tr_triangle *t, tr_vec3 p) {
    int two = (s->materials[t->material].flags & TR_MATERIAL_TWO_SIDED) != 0;
    float d = v3_dot(t->normal, v3_sub(p, t->v0));
    return two ? fabsf(d) > 1e-3f : d > 1e-3f;
}

/* (b) and (c) */
static void probabilities(const tr_scene *s) {
    tr_scene_view v = tr_scene_view_of(s);
    const uint32_t n = v.light_count;
    tr_rng rng;
    tr_rng_init(&rng, 5, 0, 0);
    int bad_sum = 0, cut_off = 0, lit_points = 0;
    double worst = 0.0;
    for (int i = 0; i < 400; ++i) {
        tr_vec3 p = v3(-13.0f + 26.0f * tr_rng_float(&rng), -0.5f + 4.0f * tr_rng_float(&rng),
                       -13.0f + 26.0f * tr_rng_float(&rng));
        /* Half the points with a receiver normal (any direction), half without. */
        tr_vec3 nr = i % 2 ? tr_sample_uniform_sphere(&rng) : v3s(0.0f);
        double sum = 0.0;
        int any = 0;
        for (uint32_t k = 0; k < n; ++k) {
            const tr_triangle *t = &s->triangles[v.lights[k]];
            float pk = tr_light_select_pdf_n(&v, p, nr, v.lights[k]);
            sum += pk;
            if (can_light(s, t, p)) {
                any = 1;
                cut_off += !(pk > 0.0f);
            }
        }
        lit_points += any;
        worst = fmax(worst, fabs(sum - 1.0));
        bad_sum += !(fabs(sum - 1.0) <= 1e-4);
    }
    CHECK(lit_points > 300 && bad_sum == 0,
          "selection pdf: %d of 400 points do not sum to 1 (worst %.2e, %d lit)", bad_sum, worst,
          lit_points);
    CHECK(cut_off == 0, "%d emitters that can light a point have selection probability 0", cut_off);

    /* (c) at three points: above the floor among the lamps, low near the floor, high. */
    const tr_vec3 pts[3] = {v3(0.3f, 0.6f, -0.2f), v3(-2.0f, 0.02f, 1.5f), v3(1.0f, 2.5f, 2.0f)};
    enum { PICKS = 200000 };
    double *expect = malloc(n * sizeof *expect);
    uint32_t *count = malloc(n * sizeof *count);
    const tr_vec3 nrs[3] = {v3s(0.0f), v3(0.0f, 1.0f, 0.0f), v3(0.6f, -0.8f, 0.0f)};
    for (int q = 0; q < 3; ++q) {
        tr_vec3 p = pts[q], nr = nrs[q];
        memset(count, 0, n * sizeof *count);
        int pdf_bad = 0, failed = 0;
        for (int i = 0; i < PICKS; ++i) {
            uint32_t t;
            tr_vec3 y;
            float bu, bv;
            float pl = tr_light_sample_n(&v, p, nr, tr_rng_float(&rng), tr_rng_float(&rng), &t, &y,
                                         &bu, &bv);
            if (!(pl > 0.0f)) {
                ++failed;
                continue;
            }
            uint32_t k = tr_light_index_of(&v, t);
            count[k < n ? k : 0]++;
            float pe = tr_light_pdf_n(&v, p, nr, t, y);
            pdf_bad += !(fabsf(pl - pe) <= 2e-5f * pe);
        }
        double chi2 = 0.0, e_acc = 0.0, o_acc = 0.0;
        int dof = -1;
        for (uint32_t k = 0; k < n; ++k) {
            expect[k] = (double)tr_light_select_pdf_n(&v, p, nr, v.lights[k]) * PICKS;
            e_acc += expect[k];
            o_acc += count[k];
            if (e_acc >= 8.0) { /* a bin: this emitter with any small ones before it */
                chi2 += (o_acc - e_acc) * (o_acc - e_acc) / e_acc;
                ++dof;
                e_acc = o_acc = 0.0;
            }
        }
        if (e_acc > 0.0 || o_acc > 0.0) {
            chi2 += (o_acc - e_acc) * (o_acc - e_acc) / fmax(e_acc, 1.0);
            ++dof;
        }
        CHECK(failed < PICKS / 1000 && pdf_bad == 0,
              "point %d: %d samples failed, %d report another density than tr_light_pdf", q, failed,
              pdf_bad);
        CHECK(dof >= 5 && chi2 < chi2_critical(dof),
              "point %d: chi2 %.1f with %d dof (critical %.1f)", q, chi2, dof,
              chi2_critical(dof > 0 ? dof : 1));
    }
    free(expect);
    free(count);
}

enum { W = 32, H = 32, SPP = 16, RS = 8, NR = (W / RS) * (H / RS) };

/* Per pixel, SPP samples of the path through its centre (no jitter: the variance the
 * pixel's footprint would add is the same for both and would hide the light choice's),
 * with independent random numbers, so that the spread over the samples estimates the
 * variance of one: sum and sum of squares of the luminance. */
static void trace_pixels(const tr_scene *s, double *s1, double *s2) {
    tr_scene_view v = tr_scene_view_of(s);
    for (uint32_t i = 0; i < W * H; ++i) {
        s1[i] = s2[i] = 0.0;
        tr_ray ray = tr_camera_ray(&s->camera, (float)(i % W), (float)(i / W), 0.5f, 0.5f);
        for (uint32_t k = 0; k < SPP; ++k) {
            tr_sampler smp = tr_sampler_make_kind(100, i, k, TR_SAMPLER_RANDOM);
            uint32_t rays = 0;
            tr_vec3 c = tr_trace_pt(&v, ray, 64, &smp, &rays, NULL);
            double l = (c.x + c.y + c.z) / 3.0;
            s1[i] += l;
            s2[i] += l * l;
        }
    }
}

/* (d) */
static void equal_spp(void) {
    tr_scene tree, power;
    build(&tree, TR_LIGHT_SAMPLING_TREE, 1, W, H);
    build(&power, TR_LIGHT_SAMPLING_POWER, 1, W, H);
    static double t1[W * H], t2[W * H], p1[W * H], p2[W * H];
    trace_pixels(&tree, t1, t2);
    trace_pixels(&power, p1, p2);
    double vt = 0.0, vp = 0.0;
    double rm[2][NR] = {{0}}, rv[2][NR] = {{0}};
    for (uint32_t i = 0; i < W * H; ++i) {
        double mt = t1[i] / SPP, mp = p1[i] / SPP;
        double vti = fmax(0.0, (t2[i] - SPP * mt * mt) / (SPP - 1));
        double vpi = fmax(0.0, (p2[i] - SPP * mp * mp) / (SPP - 1));
        vt += vti;
        vp += vpi;
        int r = (int)((i / W / RS) * (W / RS) + (i % W) / RS);
        rm[0][r] += mt / (RS * RS);
        rm[1][r] += mp / (RS * RS);
        /* Pixels are independent: the region mean's variance is the sum of theirs. */
        rv[0][r] += vti / SPP / (RS * RS * RS * RS);
        rv[1][r] += vpi / SPP / (RS * RS * RS * RS);
    }
    vt /= W * H;
    vp /= W * H;
    int biased = 0;
    for (int r = 0; r < NR; ++r) {
        biased += !(fabs(rm[0][r] - rm[1][r]) <= 5.0 * sqrt(rv[0][r] + rv[1][r]));
    }
    printf("equal spp (%d): mean pixel variance tree %.4e, power %.4e (%.1fx)\n", SPP, vt, vp,
           vp / vt);
    CHECK(biased == 0, "%d of %d regions differ between tree and power by more than 5 se", biased,
          NR);
    CHECK(vt > 0.0 && vp > 2.0 * vt, "the tree's variance %.4e is not half the power CDF's %.4e",
          vt, vp);
    tr_scene_clear(&tree);
    tr_scene_clear(&power);
}

/* (e) */
static void modes(void) {
    tr_scene s;
    build(&s, TR_LIGHT_SAMPLING_AUTO, 0, 8, 8);
    CHECK(tr_scene_light_sampling(&s) == TR_LIGHT_SAMPLING_TREE, "auto with %u emitters: no tree",
          tr_scene_light_count(&s));
    structure(&s);
    probabilities(&s);
    /* Moving a lamp and updating rebuilds the tree around its new place. */
    tr_error err;
    uint32_t last = tr_scene_shape_count(&s) - 1;
    CHECK(tr_scene_move_shape(&s, last, v3(20.0f, 0.0f, 0.0f), &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_update(&s, NULL, &err) == TR_OK, "update: %s", err.msg);
    tr_scene_view v = tr_scene_view_of(&s);
    const tr_triangle *moved = &s.triangles[s.shapes[last].first];
    CHECK(v.light_node_count > 0 && inside(&v.light_nodes[0], moved->v0),
          "the root's box does not hold the moved lamp");
    structure(&s);
    tr_scene_clear(&s);

    build(&s, TR_LIGHT_SAMPLING_POWER, 0, 8, 8);
    CHECK(tr_scene_light_sampling(&s) == TR_LIGHT_SAMPLING_POWER &&
              tr_scene_view_of(&s).light_node_count == 0,
          "power: a tree was built");
    tr_scene_clear(&s);

    /* One two-triangle lamp: auto keeps the power CDF; tree is honoured. */
    for (int mode = TR_LIGHT_SAMPLING_AUTO; mode <= TR_LIGHT_SAMPLING_TREE; ++mode) {
        tr_scene_init(&s);
        uint32_t lamp = add_mat(&s, tr_material_emitter(v3s(1.0f), 5.0f));
        add_shape(&s, TR_SHAPE_PLANE, lamp, v3(0, 1, 0), v3((float)PI_D, 0, 0), v3s(0.5f));
        CHECK(tr_scene_set_light_sampling(&s, mode, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        int want =
            mode == TR_LIGHT_SAMPLING_TREE ? TR_LIGHT_SAMPLING_TREE : TR_LIGHT_SAMPLING_POWER;
        CHECK(tr_scene_light_sampling(&s) == want, "one lamp, mode %d: uses %d", mode,
              tr_scene_light_sampling(&s));
        tr_scene_clear(&s);
    }
    CHECK(tr_scene_set_light_sampling(&s, 7, &err) == TR_ERR, "mode 7 accepted");
    CHECK(tr_light_sampling_from_name("tree") == TR_LIGHT_SAMPLING_TREE &&
              tr_light_sampling_from_name("power") == TR_LIGHT_SAMPLING_POWER &&
              tr_light_sampling_from_name("auto") == TR_LIGHT_SAMPLING_AUTO &&
              tr_light_sampling_from_name("trees") == -1,
          "names");
}

int main(void) {
    modes();
    equal_spp();
    return check_finish("test_light_tree");
}
