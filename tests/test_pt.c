/* test_pt.c - the pt integrator (src/kernel/integrator_pt.h).
 *
 *  (a) MIS, with the power CDF and with the light tree (light_tree.h, which weighs by the
 *      vertex's shading normal as the integrator does): for paths that reach an emitter
 *      from a surface vertex, the power-heuristic weights the integrator gives the light
 *      strategy (next-event estimation) and the BSDF strategy (hitting the emitter) sum
 *      to one. Both weights are computed as the
 *      integrator computes them: the light pdf once from the sampled point, once from
 *      the traced hit, so a mismatch between the two code paths would show.
 *  (b) Unbiasedness: the naive integrator (max depth D + 2, i.e. at most D segments)
 *      and pt (max depth D) estimate the same truncated series. On a diffuse-only box
 *      and on builtin:cornell-mirror (diffuse, smooth glass, perfect mirrors) the mean
 *      over each 16x16 region of a small image agrees per channel within 5 standard
 *      errors, the errors measured from the per-frame region means (one sample per
 *      pixel per frame: frames are independent).
 *  (c) pt's variance is lower than naive's on the same scene (what NEE is for).
 *  (d) One bounce under a square lamp against rho/pi times Lambert's irradiance, and
 *      one-sided emission seen through the whole integrator.
 *
 * Fixed seeds throughout. */
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
#define NSIGMA 5.0

/* A closed diffuse box [-1,1]^3 with an inner block, a glossy GGX sphere when
 * `glossy`, and two two-sided lamps under the ceiling (naive ignores sidedness). */
static void build_box(tr_scene *s, int glossy, uint32_t w, uint32_t h) {
    tr_error err;
    tr_scene_init(s);
    uint32_t white = add_mat(s, tr_material_diffuse(v3(0.7f, 0.7f, 0.7f)));
    uint32_t red = add_mat(s, tr_material_diffuse(v3(0.7f, 0.15f, 0.1f)));
    tr_material lamp = tr_material_emitter(v3(1.0f, 0.9f, 0.7f), 8.0f);
    lamp.flags = TR_MATERIAL_TWO_SIDED;
    uint32_t l1 = add_mat(s, lamp);
    tr_material lamp2 = tr_material_emitter(v3(0.3f, 0.5f, 1.0f), 4.0f);
    lamp2.flags = TR_MATERIAL_TWO_SIDED; /* naive's emitters shine both ways */
    uint32_t l2 = add_mat(s, lamp2);
    add_shape(s, TR_SHAPE_BOX, white, v3(0, 0, 0), v3(0, 0, 0), v3(2, 2, 2));
    add_shape(s, TR_SHAPE_BOX, red, v3(0.3f, -0.6f, 0.4f), v3(0, 0.5f, 0), v3(0.6f, 0.8f, 0.6f));
    add_shape(s, TR_SHAPE_PLANE, l1, v3(-0.3f, 0.9f, 0.2f), v3((float)PI_D, 0, 0),
              v3(0.6f, 1, 0.5f));
    add_shape(s, TR_SHAPE_PLANE, l2, v3(0.5f, 0.95f, -0.5f), v3((float)PI_D, 0, 0),
              v3(0.3f, 1, 0.3f));
    if (glossy) {
        uint32_t g = add_mat(s, tr_material_glossy(v3(0.9f, 0.8f, 0.6f), 0.4f));
        add_shape(s, TR_SHAPE_ICOSPHERE, g, v3(-0.4f, -0.6f, 0.1f), v3(0, 0, 0), v3s(0.35f));
    }
    CHECK(tr_camera_make(&s->camera, v3(0.0f, 0.0f, -0.95f), v3(0.0f, -0.1f, 1.0f),
                         v3(0.0f, 1.0f, 0.0f), 80.0f, 0.001f, 100.0f, w, h, &err) == TR_OK,
          "camera: %s", err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
}

/* (a), with light sampling `mode` (TR_LIGHT_SAMPLING_*). */
static void mis_weights(int mode) {
    tr_scene s = {0};
    build_box(&s, 1, 8, 8);
    tr_error err;
    CHECK(tr_scene_set_light_sampling(&s, mode, &err) == TR_OK &&
              tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK,
          "light sampling %d: %s", mode, err.msg);
    CHECK(tr_scene_light_sampling(&s) == mode, "light sampling %d not used", mode);
    tr_scene_view v = tr_scene_view_of(&s);
    tr_rng rng;
    tr_rng_init(&rng, 2024, 0, 0);
    int paths = 0, bad = 0, nee_paths = 0, pdf_bad = 0;
    double worst = 0.0;
    for (int k = 0; k < 20000; ++k) {
        /* A vertex: trace a random ray from the camera position. */
        tr_vec3 d = tr_sample_uniform_sphere(&rng);
        tr_ray r = tr_ray_make(s.camera.pos, d, 0.0f, TR_INFINITY);
        tr_hit hit;
        if (!tr_intersect_scene(&v, &r, &hit)) {
            continue;
        }
        const tr_triangle *tri = &s.triangles[hit.triangle];
        tr_vec3 p = v3_madd(r.origin, r.dir, hit.t);
        tr_bsdf_params m = tr_material_eval(&v, hit.triangle, hit.u, hit.v, p, tri->normal, d);
        if (tr_bsdf_is_delta(&m) || m.type == TR_MATERIAL_EMITTER) {
            continue;
        }
        tr_vec3 wo = v3_neg(d);
        for (int strategy = 0; strategy < 2; ++strategy) {
            tr_vec3 wi;
            float pl_sampled = 0.0f;
            uint32_t sampled_tri = 0;
            if (strategy == 0) { /* light sample */
                uint32_t lt;
                tr_vec3 y;
                float lu, lv;
                float u1 = tr_rng_float(&rng), u2 = tr_rng_float(&rng);
                float pl = tr_light_sample_n(&v, p, m.ns, u1, u2, &lt, &y, &lu, &lv);
                if (pl <= 0.0f) {
                    continue;
                }
                /* The density sampling reports is the one MIS evaluates. */
                float pe = tr_light_pdf_n(&v, p, m.ns, lt, y);
                pdf_bad += !(fabsf(pl - pe) <= 1e-5f * pe);
                pl_sampled = pl;
                sampled_tri = lt;
                wi = v3_normalize(v3_sub(y, p));
            } else { /* BSDF sample */
                tr_scatter bs;
                if (!tr_bsdf_sample(&m, wo, tr_rng_float(&rng), tr_rng_float(&rng),
                                    tr_rng_float(&rng), &bs)) {
                    continue;
                }
                wi = bs.wi;
            }
            /* Follow wi: the path counts for both strategies only if it reaches an
             * emitting side unoccluded. */
            tr_vec3 o = tr_offset_origin(p, v3_dot(wi, tri->normal) > 0.0f ? tri->normal
                                                                           : v3_neg(tri->normal));
            tr_ray r2 = tr_ray_make(o, wi, 0.0f, TR_INFINITY);
            tr_hit h2;
            if (!tr_intersect_scene(&v, &r2, &h2)) {
                continue;
            }
            const tr_triangle *lt = &s.triangles[h2.triangle];
            tr_vec3 y = v3_madd(o, wi, h2.t);
            tr_bsdf_params lm = tr_material_eval(&v, h2.triangle, h2.u, h2.v, y, lt->normal, wi);
            tr_vec3 le = tr_emitted(&lm, v3_neg(wi));
            float pb = tr_bsdf_pdf(&m, wo, wi);
            if (le.x <= 0.0f || pb <= 0.0f) {
                continue;
            }
            /* The light strategy's density of the path from p to y as the BSDF strategy's
             * hit evaluates it (at the traced point), and as next-event estimation has it
             * (what sampling reported, for light samples). */
            float pl_hit = tr_light_pdf_n(&v, p, m.ns, h2.triangle, y);
            if (strategy == 0 && h2.triangle != sampled_tri) {
                /* A point on an edge the tracer assigns to the neighbour: a measure-zero
                 * set whose densities belong to different triangles. */
                continue;
            }
            float pl_nee = strategy == 0 ? pl_sampled : pl_hit;
            double sum = (double)tr_mis_power(pl_nee, pb) + (double)tr_mis_power(pb, pl_hit);
            double dev = fabs(sum - 1.0);
            worst = dev > worst ? dev : worst;
            bad += !(dev <= 1e-3);
            ++paths;
            nee_paths += strategy == 0;
        }
    }
    CHECK(paths > 2000 && nee_paths > 1000 && bad == 0,
          "MIS weights (light sampling %d): %d of %d paths (%d light-sampled) do not sum to 1 "
          "(worst %.2e)",
          mode, bad, paths, nee_paths, worst);
    CHECK(pdf_bad == 0, "%d light samples report another density than tr_light_pdf", pdf_bad);
    /* Away from the two-strategy case the heuristic gives all weight to the only one. */
    CHECK(tr_mis_power(1.0f, 0.0f) == 1.0f && tr_mis_power(0.0f, 1.0f) == 0.0f &&
              tr_mis_power(0.0f, 0.0f) == 0.0f,
          "power heuristic limits");
    tr_scene_clear(&s);
}

enum { W = 32, H = 32, RS = 16, NR = (W / RS) * (H / RS) };

typedef struct region_stats {
    double mean[NR][3];
    double se[NR][3];
    double var_sum; /* sum over regions and channels of the per-frame variance */
} region_stats;

static void run(const tr_scene *s, int integrator, int max_depth, int frames, uint64_t seed,
                region_stats *out) {
    tr_error err;
    tr_film film;
    CHECK(tr_film_init(&film, W, H, &err) == TR_OK, "film: %s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = integrator;
    cfg.max_depth = max_depth;
    cfg.seed = seed;
    static double s1[NR][3], s2[NR][3];
    memset(s1, 0, sizeof s1);
    memset(s2, 0, sizeof s2);
    for (int f = 0; f < frames; ++f) {
        tr_film_clear(&film);
        CHECK(tr_render_frame(s, &s->camera, &cfg, &film, (uint32_t)f, NULL, &err) == TR_OK,
              "render: %s", err.msg);
        double reg[NR][3] = {{0}};
        for (uint32_t y = 0; y < H; ++y) {
            for (uint32_t x = 0; x < W; ++x) {
                tr_vec3 c = tr_film_pixel(&film, x, y);
                int r = (int)((y / RS) * (W / RS) + x / RS);
                reg[r][0] += c.x;
                reg[r][1] += c.y;
                reg[r][2] += c.z;
            }
        }
        for (int r = 0; r < NR; ++r) {
            for (int ch = 0; ch < 3; ++ch) {
                double m = reg[r][ch] / (RS * RS);
                s1[r][ch] += m;
                s2[r][ch] += m * m;
            }
        }
    }
    out->var_sum = 0.0;
    for (int r = 0; r < NR; ++r) {
        for (int ch = 0; ch < 3; ++ch) {
            double m = s1[r][ch] / frames;
            double var = fmax(0.0, (s2[r][ch] / frames - m * m)) * frames / (frames - 1);
            out->mean[r][ch] = m;
            out->se[r][ch] = sqrt(var / frames);
            out->var_sum += var;
        }
    }
    tr_film_free(&film);
}

static void unbiased(const char *name, const tr_scene *s, int depth, int naive_frames,
                     int pt_frames) {
    static region_stats a, b;
    run(s, TR_INTEGRATOR_NAIVE, depth + 2, naive_frames, 0xabcdULL, &a);
    run(s, TR_INTEGRATOR_PT, depth, pt_frames, 0x1234ULL, &b);
    int bad = 0, lit = 0;
    double worst = 0.0;
    for (int r = 0; r < NR; ++r) {
        for (int ch = 0; ch < 3; ++ch) {
            double se = sqrt(a.se[r][ch] * a.se[r][ch] + b.se[r][ch] * b.se[r][ch]);
            double z = se > 0.0 ? fabs(a.mean[r][ch] - b.mean[r][ch]) / se : 0.0;
            worst = z > worst ? z : worst;
            bad += !(z <= NSIGMA);
            lit += a.mean[r][ch] > 0.0 && b.mean[r][ch] > 0.0;
        }
    }
    CHECK(bad == 0 && lit == 3 * NR,
          "%s: %d of %d region means differ by more than %.0f sigma (worst %.2f), %d lit", name,
          bad, 3 * NR, NSIGMA, worst, lit);
    /* Per frame, pt's region means scatter less than naive's (NEE). */
    CHECK(b.var_sum < a.var_sum, "%s: pt variance %.4g not below naive %.4g", name, b.var_sum,
          a.var_sum);
    printf("%s: worst |naive - pt| = %.2f sigma; per-frame variance naive %.4g, pt %.4g\n", name,
           worst, a.var_sum, b.var_sum);
}

/* (d) One bounce against a closed form: a diffuse floor (albedo rho) under a square
 * lamp of radiance L, seen by a ray at a slant; with max depth 2 (camera ray, then the
 * segment to the lamp by either strategy) the pixel's radiance is rho / pi * E(x), E
 * from Lambert's polygon formula. A one-sided lamp turned away gives exactly 0; a
 * two-sided one turned away gives the same as one facing the floor. */
static void one_bounce(void) {
    const double rho = 0.6, L = 5.0, hs = 0.3, h = 0.8;
    const double vtx[4][3] = {{-hs, h, -hs}, {hs, h, -hs}, {hs, h, hs}, {-hs, h, hs}};
    const double x[3] = {0.25, 0.0, -0.4};
    const double expect = rho / PI_D * lambert_irradiance(vtx, 4, x, L);
    /* 0: lamp faces down; 1: one-sided, faces up; 2: two-sided, faces up. */
    for (int variant = 0; variant < 3; ++variant) {
        tr_scene s = {0};
        tr_scene_init(&s);
        tr_error err;
        uint32_t floor_m = add_mat(&s, tr_material_diffuse(v3s((float)rho)));
        tr_material lm = tr_material_emitter(v3s(1.0f), (float)L);
        lm.flags = variant == 2 ? TR_MATERIAL_TWO_SIDED : 0u;
        uint32_t lamp = add_mat(&s, lm);
        add_shape(&s, TR_SHAPE_PLANE, floor_m, v3(0, 0, 0), v3(0, 0, 0), v3(40.0f, 1, 40.0f));
        add_shape(&s, TR_SHAPE_PLANE, lamp, v3(0, (float)h, 0),
                  v3(variant == 0 ? (float)PI_D : 0.0f, 0, 0),
                  v3(2.0f * (float)hs, 1, 2.0f * (float)hs));
        CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
        tr_scene_view v = tr_scene_view_of(&s);
        tr_vec3 target = v3((float)x[0], (float)x[1], (float)x[2]);
        tr_vec3 from = v3(1.5f, 0.5f, -1.2f); /* below the lamp's height, off to the side */
        tr_vec3 dir = v3_normalize(v3_sub(target, from));
        const int N = 200000;
        double s1 = 0.0, s2 = 0.0;
        int nonzero = 0;
        for (int k = 0; k < N; ++k) {
            tr_sampler smp = tr_sampler_make(31, (uint64_t)variant, (uint32_t)k);
            uint32_t rays = 0;
            tr_vec3 c =
                tr_trace_pt(&v, tr_ray_make(from, dir, 0.0f, TR_INFINITY), 2, &smp, &rays, NULL);
            s1 += c.x;
            s2 += (double)c.x * c.x;
            nonzero += c.x != 0.0f;
        }
        double mean = s1 / N, se = sqrt(fmax(0.0, s2 / N - mean * mean) / N);
        if (variant == 1) {
            CHECK(nonzero == 0, "one-sided lamp facing away: %d of %d samples lit", nonzero, N);
        } else {
            CHECK(fabs(mean - expect) <= NSIGMA * se && se < 0.01 * expect,
                  "lamp variant %d: pt radiance %.5f +- %.5f vs rho/pi E = %.5f", variant, mean, se,
                  expect);
        }
        tr_scene_clear(&s);
    }
}

int main(void) {
    mis_weights(TR_LIGHT_SAMPLING_POWER);
    mis_weights(TR_LIGHT_SAMPLING_TREE);
    one_bounce();
    tr_scene s = {0};
    build_box(&s, 0, W, H);
    unbiased("diffuse box", &s, 5, 2048, 256);
    tr_scene_clear(&s);
    tr_error err;
    CHECK(tr_scene_builtin(&s, "cornell-mirror", W, H, &err) == TR_OK, "builtin: %s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    unbiased("cornell-mirror", &s, 5, 2048, 256);
    tr_scene_clear(&s);
    return check_finish("test_pt");
}
