/* test_light_tree_punctual.c - point and spot lights in the light tree
 * (src/scene/light_tree.c, src/kernel/light_tree.h, tr_light_sample_np in light.h).
 *
 * A generated scene: a diffuse floor, 24 x 24, two small one-sided lamps (4 emissive
 * triangles) and 64 punctual lights of different powers, placed unevenly: 24 dim point
 * lights crowded into one corner, 16 brighter ones spread over the floor, 22 spots of
 * different cones aimed down, and 2 directional lights.
 *  (a) Structure: the leaf table has the emitters' entries and then one per punctual
 *      light; every point and spot light is in exactly one leaf, the directional ones in
 *      none; every node from a light's leaf up holds its position in its box, and its
 *      direction in its cone (a point light: any direction).
 *  (b) The walk's probabilities of all leaves (emitters and punctual lights) sum to one at
 *      points all around the scene, and no point or spot light that lights a point has
 *      probability 0 there.
 *  (c) Picks through tr_light_sample_np follow that probability (chi-square), and the
 *      probability it reports for a punctual light is tr_light_tree_prob's.
 *  (d) Equal samples per pixel, the light tree against the previous strategy (the
 *      emitters by the power CDF, the punctual lights by their own power CDF, both every
 *      vertex): a 32x32 image of the floor, 16 samples per pixel of the ray through each
 *      pixel's centre with independent random numbers. Both are unbiased (every 8x8-pixel
 *      region's means agree within 5 standard errors, from the per-pixel variances), and
 *      the mean per-sample variance is at least 2 times lower with the tree. Without the
 *      primary direct light (a stage's, as ReSTIR DI: pt then walks the tree for the
 *      punctual lights alone at the first vertex) the means agree as well.
 *  (e) Which scenes put them in the tree: more than 8 point and spot lights unless light
 *      sampling is power; 8 (with directional ones beside) keep their strategy of before. */
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
#define NPUNCT 64

static void add_light(tr_scene *s, uint32_t type, tr_vec3 pos, tr_vec3 dir, float intensity,
                      float cos_outer) {
    tr_punctual l;
    memset(&l, 0, sizeof l);
    l.type = type;
    l.pos = pos;
    l.dir = dir;
    l.intensity = v3(intensity, 0.9f * intensity, 0.8f * intensity);
    l.cos_outer = cos_outer;
    l.cos_inner = 0.5f * (1.0f + cos_outer);
    tr_error err;
    CHECK(tr_scene_add_punctual(s, &l, &err) == TR_OK, "light: %s", err.msg);
}

static void build(tr_scene *s, int mode, uint32_t w, uint32_t h) {
    tr_error err;
    tr_scene_init(s);
    uint32_t floor_m = add_mat(s, tr_material_diffuse(v3(0.7f, 0.7f, 0.7f)));
    add_shape(s, TR_SHAPE_PLANE, floor_m, v3(0, 0, 0), v3(0, 0, 0), v3(24, 1, 24));
    uint32_t lamp = add_mat(s, tr_material_emitter(v3(1.0f, 0.9f, 0.8f), 20.0f));
    add_shape(s, TR_SHAPE_PLANE, lamp, v3(-1, 2.5f, -7), v3((float)PI_D, 0, 0), v3s(0.3f));
    add_shape(s, TR_SHAPE_PLANE, lamp, v3(2, 2.2f, 7), v3((float)PI_D, 0, 0), v3s(0.3f));
    tr_rng rng;
    tr_rng_init(&rng, 31, 0, 0);
    for (int k = 0; k < NPUNCT; ++k) {
        float a = tr_rng_float(&rng), b = tr_rng_float(&rng), c = tr_rng_float(&rng);
        float d = tr_rng_float(&rng);
        if (k < 24) { /* crowded into a corner, dim */
            add_light(s, TR_PUNCTUAL_POINT, v3(-10.0f + 5.0f * a, 0.6f + b, -10.0f + 5.0f * c),
                      v3s(0.0f), 0.3f + 1.2f * d, -1.0f);
        } else if (k < 40) { /* spread, brighter */
            add_light(s, TR_PUNCTUAL_POINT,
                      v3(-10.0f + 20.0f * a, 0.8f + 1.7f * b, -10.0f + 20.0f * c), v3s(0.0f),
                      1.0f + 11.0f * d, -1.0f);
        } else if (k < 62) { /* spots aimed down, cones from 15 to 45 degrees half-angle */
            float x = k < 54 ? 4.0f + 6.0f * a : -6.0f + 12.0f * a;
            add_light(s, TR_PUNCTUAL_SPOT,
                      v3(x, 1.5f + 1.5f * b, -9.5f + 19.0f * (float)(k - 40) / 21.0f),
                      v3(0.6f * c - 0.3f, -1.0f, 0.6f * d - 0.3f), 2.0f + 23.0f * b,
                      cosf((float)(PI_D / 12.0 + PI_D / 6.0 * (double)c)));
        } else {
            add_light(s, TR_PUNCTUAL_DIRECTIONAL, v3s(0.0f),
                      v3(0.3f * (float)(k - 62) - 0.1f, -1, 0.2f), 0.02f, -1.0f);
        }
    }
    CHECK(tr_scene_set_light_sampling(s, mode, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_camera_make(&s->camera, v3(0.0f, 9.0f, -6.0f), v3(0.0f, -1.5f, 1.0f),
                         v3(0.0f, 1.0f, 0.0f), 60.0f, 0.001f, 100.0f, w, h, &err) == TR_OK,
          "camera: %s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
}

/* Whether p lies in the node's bounding sphere (the sphere around its box). */
static int inside(const tr_light_node *n, tr_vec3 p) {
    const tr_vec3 d = v3_sub(p, n->centre);
    return v3_dot(d, d) <= n->r2 * (1.0f + 1e-5f) + 1e-10f;
}

/* (a) */
static void structure(const tr_scene *s) {
    tr_scene_view v = tr_scene_view_of(s);
    const uint32_t ne = v.light_count, n = ne + v.punctual_count;
    CHECK(ne == 4 && v.punctual_count == NPUNCT && v.light_leaf_count == n &&
              v.light_node_count == 2 * (n - 2) - 1,
          "%u emitters, %u punctual, %u leaf slots, %u nodes", ne, v.punctual_count,
          v.light_leaf_count, v.light_node_count);
    uint32_t *seen = calloc(n, sizeof *seen);
    int bad_leaf = 0, bad_box = 0, bad_cone = 0;
    for (uint32_t i = 0; i < v.light_node_count; ++i) {
        const tr_light_node *nd = &v.light_nodes[i];
        if (nd->child & TR_LIGHT_LEAF) {
            uint32_t k = nd->child & ~TR_LIGHT_LEAF;
            bad_leaf += !(k < n) || v.light_leaf[k] != i;
            if (k < n) {
                seen[k]++;
            }
        }
    }
    for (uint32_t j = 0; j < v.punctual_count; ++j) {
        const tr_punctual *l = &v.punctual[j];
        const int dir = l->type == TR_PUNCTUAL_DIRECTIONAL;
        bad_leaf += seen[ne + j] != (dir ? 0u : 1u);
        if (dir || seen[ne + j] != 1u) {
            continue;
        }
        for (uint32_t nd = v.light_leaf[ne + j];; nd = v.light_nodes[nd].parent) {
            const tr_light_node *node = &v.light_nodes[nd];
            bad_box += !inside(node, l->pos);
            if (l->type == TR_PUNCTUAL_POINT) {
                bad_cone += !(node->cos_o <= -0.9999f);
            } else {
                bad_cone += !(v3_dot(node->axis, l->dir) >= node->cos_o - 1e-5f);
            }
            if (nd == 0) {
                break;
            }
        }
    }
    free(seen);
    CHECK(bad_leaf == 0, "%d leaves wrong", bad_leaf);
    CHECK(bad_box == 0 && bad_cone == 0, "bounds of punctual lights: box %d, cone %d", bad_box,
          bad_cone);
}

/* The probability of every leaf slot at p: emitters through tr_light_select_pdf_n, the
 * punctual lights through tr_light_tree_prob (directional ones 0). */
static void leaf_probs(const tr_scene_view *v, tr_vec3 p, tr_vec3 nr, double *pr) {
    for (uint32_t k = 0; k < v->light_count; ++k) {
        pr[k] = tr_light_select_pdf_n(v, p, nr, v->lights[k]);
    }
    for (uint32_t j = 0; j < v->punctual_count; ++j) {
        pr[v->light_count + j] = v->punctual[j].type == TR_PUNCTUAL_DIRECTIONAL
                                     ? 0.0
                                     : tr_light_tree_prob(v, p, nr, v->light_count + j);
    }
}

/* (b) and (c) */
static void probabilities(const tr_scene *s) {
    tr_scene_view v = tr_scene_view_of(s);
    const uint32_t n = v.light_leaf_count;
    double *pr = malloc(n * sizeof *pr);
    tr_rng rng;
    tr_rng_init(&rng, 9, 0, 0);
    int bad_sum = 0, cut_off = 0, lit = 0;
    double worst = 0.0;
    for (int i = 0; i < 400; ++i) {
        tr_vec3 p = v3(-13.0f + 26.0f * tr_rng_float(&rng), -0.5f + 4.0f * tr_rng_float(&rng),
                       -13.0f + 26.0f * tr_rng_float(&rng));
        tr_vec3 nr = i % 2 ? tr_sample_uniform_sphere(&rng) : v3s(0.0f);
        leaf_probs(&v, p, nr, pr);
        double sum = 0.0;
        for (uint32_t k = 0; k < n; ++k) {
            sum += pr[k];
        }
        for (uint32_t j = 0; j < v.punctual_count; ++j) {
            tr_vec3 wi;
            float dist;
            const tr_vec3 li = tr_punctual_incident(&v.punctual[j], p, &wi, &dist);
            const int lights = v.punctual[j].type != TR_PUNCTUAL_DIRECTIONAL &&
                               !tr_punctual_black(li) &&
                               (i % 2 == 0 || fabsf(v3_dot(wi, nr)) > 1e-3f);
            lit += lights;
            cut_off += lights && !(pr[v.light_count + j] > 0.0);
        }
        worst = fmax(worst, fabs(sum - 1.0));
        bad_sum += !(fabs(sum - 1.0) <= 1e-4);
    }
    CHECK(bad_sum == 0 && lit > 4000,
          "tree probabilities: %d of 400 points do not sum to 1 (worst %.2e; %d lit pairs)",
          bad_sum, worst, lit);
    CHECK(cut_off == 0, "%d punctual lights that light a point have probability 0 there", cut_off);

    /* (c) in the crowded corner, among the spots, and high above the middle. */
    const tr_vec3 pts[3] = {v3(-7.0f, 0.01f, -7.5f), v3(6.0f, 0.3f, 2.0f), v3(0.5f, 4.0f, 0.5f)};
    const tr_vec3 nrs[3] = {v3(0.0f, 1.0f, 0.0f), v3s(0.0f), v3(0.6f, -0.8f, 0.0f)};
    enum { PICKS = 200000 };
    uint32_t *count = malloc(n * sizeof *count);
    for (int q = 0; q < 3; ++q) {
        memset(count, 0, n * sizeof *count);
        leaf_probs(&v, pts[q], nrs[q], pr);
        int failed = 0, prob_bad = 0, punct_picks = 0;
        for (int i = 0; i < PICKS; ++i) {
            uint32_t t, pk;
            tr_vec3 y;
            float bu, bv, pp;
            float pl = tr_light_sample_np(&v, pts[q], nrs[q], tr_rng_float(&rng),
                                          tr_rng_float(&rng), &t, &y, &bu, &bv, &pk, &pp);
            if (pp > 0.0f) {
                ++punct_picks;
                count[v.light_count + pk]++;
                const double want = pr[v.light_count + pk];
                prob_bad += !(fabs(pp - want) <= 2e-5 * want);
            } else if (pl > 0.0f) {
                uint32_t k = tr_light_index_of(&v, t);
                count[k < v.light_count ? k : 0]++;
            } else {
                ++failed;
            }
        }
        double chi2 = 0.0, e_acc = 0.0, o_acc = 0.0;
        int dof = -1;
        for (uint32_t k = 0; k < n; ++k) {
            e_acc += pr[k] * PICKS;
            o_acc += count[k];
            if (e_acc >= 8.0) {
                chi2 += (o_acc - e_acc) * (o_acc - e_acc) / e_acc;
                ++dof;
                e_acc = o_acc = 0.0;
            }
        }
        if (e_acc > 0.0 || o_acc > 0.0) {
            chi2 += (o_acc - e_acc) * (o_acc - e_acc) / fmax(e_acc, 1.0);
            ++dof;
        }
        CHECK(failed < PICKS / 1000 && prob_bad == 0 && punct_picks > PICKS / 2,
              "point %d: %d picks failed, %d punctual picks of %d report another probability", q,
              failed, prob_bad, punct_picks);
        CHECK(dof >= 5 && chi2 < chi2_critical(dof),
              "point %d: chi2 %.1f with %d dof (critical %.1f)", q, chi2, dof,
              chi2_critical(dof > 0 ? dof : 1));
    }
    free(count);
    free(pr);
}

enum { W = 32, H = 32, SPP = 16, RS = 8, NR = (W / RS) * (H / RS) };

/* As test_light_tree.c: SPP samples of the path through each pixel's centre with
 * independent random numbers; sum and sum of squares of the luminance. */
static void trace_pixels(const tr_scene *s, uint32_t flags, double *s1, double *s2) {
    tr_scene_view v = tr_scene_view_of(s);
    for (uint32_t i = 0; i < W * H; ++i) {
        s1[i] = s2[i] = 0.0;
        tr_ray ray = tr_camera_ray(&s->camera, (float)(i % W), (float)(i / W), 0.5f, 0.5f);
        for (uint32_t k = 0; k < SPP; ++k) {
            tr_sampler smp = tr_sampler_make_kind(300, i, k, TR_SAMPLER_RANDOM);
            uint32_t rays = 0;
            tr_vec3 c = tr_trace_pt_ff(&v, ray, 64, TR_PT_RR_START, 0.0f, flags, &smp, &rays, NULL);
            double l = (c.x + c.y + c.z) / 3.0;
            s1[i] += l;
            s2[i] += l * l;
        }
    }
}

/* (d); with flags TR_FRAME_NO_PRIMARY_DIRECT, the variance is not compared. */
static void equal_spp(uint32_t flags) {
    tr_scene tree, power;
    build(&tree, TR_LIGHT_SAMPLING_AUTO, W, H);
    build(&power, TR_LIGHT_SAMPLING_POWER, W, H);
    CHECK(tr_scene_view_of(&tree).light_leaf_count > tr_scene_view_of(&tree).light_count &&
              tr_scene_view_of(&power).light_node_count == 0,
          "auto should put the lights in a tree, power build none");
    static double t1[W * H], t2[W * H], p1[W * H], p2[W * H];
    trace_pixels(&tree, flags, t1, t2);
    trace_pixels(&power, flags, p1, p2);
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
        rv[0][r] += vti / SPP / (RS * RS * RS * RS);
        rv[1][r] += vpi / SPP / (RS * RS * RS * RS);
    }
    vt /= W * H;
    vp /= W * H;
    int biased = 0;
    for (int r = 0; r < NR; ++r) {
        biased += !(fabs(rm[0][r] - rm[1][r]) <= 5.0 * sqrt(rv[0][r] + rv[1][r]));
    }
    printf("equal spp (%d, flags %u): mean pixel variance tree %.4e, power %.4e (%.1fx)\n", SPP,
           flags, vt, vp, vp / vt);
    CHECK(biased == 0, "flags %u: %d of %d regions differ between tree and power by more than 5 se",
          flags, biased, NR);
    CHECK(flags != 0u || (vt > 0.0 && vp > 2.0 * vt),
          "the tree's variance %.4e is not half the power CDF's %.4e", vt, vp);
    tr_scene_clear(&tree);
    tr_scene_clear(&power);
}

/* (e) */
static void modes(void) {
    for (int npoint = 8; npoint <= 9; ++npoint) {
        for (int mode = TR_LIGHT_SAMPLING_AUTO; mode <= TR_LIGHT_SAMPLING_TREE; ++mode) {
            tr_scene s;
            tr_error err;
            tr_scene_init(&s);
            uint32_t m = add_mat(&s, tr_material_diffuse(v3s(0.5f)));
            add_shape(&s, TR_SHAPE_PLANE, m, v3(0, 0, 0), v3(0, 0, 0), v3s(4.0f));
            for (int k = 0; k < npoint; ++k) {
                add_light(&s, k % 2 ? TR_PUNCTUAL_SPOT : TR_PUNCTUAL_POINT,
                          v3(0.3f * (float)k - 1.0f, 1.0f, 0.2f * (float)k), v3(0, -1, 0),
                          1.0f + (float)k, 0.7f);
            }
            add_light(&s, TR_PUNCTUAL_DIRECTIONAL, v3s(0.0f), v3(0, -1, 0), 1.0f, -1.0f);
            add_light(&s, TR_PUNCTUAL_DIRECTIONAL, v3s(0.0f), v3(0.2f, -1, 0), 1.0f, -1.0f);
            CHECK(tr_scene_set_light_sampling(&s, mode, &err) == TR_OK, "%s", err.msg);
            CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
            tr_scene_view v = tr_scene_view_of(&s);
            const int want = npoint > 8 && mode != TR_LIGHT_SAMPLING_POWER;
            CHECK((v.light_leaf_count > v.light_count) == want &&
                      (v.light_node_count > 0) == want &&
                      tr_scene_light_sampling(&s) ==
                          (want ? TR_LIGHT_SAMPLING_TREE : TR_LIGHT_SAMPLING_POWER),
                  "%d point and spot lights, mode %d: in the tree %d, expected %d", npoint, mode,
                  v.light_leaf_count > v.light_count, want);
            if (want) {
                CHECK(v.light_node_count == 2 * (uint32_t)npoint - 1 &&
                          v.light_leaf_count == (uint32_t)npoint + 2,
                      "%u nodes, %u leaf slots", v.light_node_count, v.light_leaf_count);
            }
            tr_scene_clear(&s);
        }
    }
}

int main(void) {
    modes();
    tr_scene s;
    build(&s, TR_LIGHT_SAMPLING_AUTO, 8, 8);
    structure(&s);
    probabilities(&s);
    tr_scene_clear(&s);
    equal_spp(0u);
    equal_spp(TR_FRAME_NO_PRIMARY_DIRECT);
    return check_finish("test_light_tree_punctual");
}
