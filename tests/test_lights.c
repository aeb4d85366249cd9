/* test_lights.c - the emitter table (src/scene/lights.c) and light sampling
 * (src/kernel/light.h).
 *
 *  (a) The table holds exactly the emissive triangles of positive area, and each
 *      entry's probability (CDF step) is its power x area share, computed here in
 *      double from the materials: mean radiance x area x emitting sides.
 *  (b) Picks follow the table: counts of picked triangles against the CDF steps
 *      (chi-square), through the kernel's binary search.
 *  (c) Irradiance below a single square light: the next-event estimator
 *      L cos_x cos_l / (r^2 p_area) averaged over light samples against the closed form
 *      for a Lambertian polygon (Lambert's formula: E = L/2 sum_i beta_i (n . g_i),
 *      beta_i the angle each edge subtends and g_i the unit normal of the plane
 *      through the point and that edge), on and off the axis, within 5 standard
 *      errors of the measured variance.
 *  (d) A table older than the scene's triangles is not exposed to the kernel, and a
 *      scene without emitters has an empty table.
 *  (e) The built-in Cornell box's lamp faces up with our winding and is two-sided.
 *  (f) Light sampling's density, by solid angle and by area, matches its samples
 *      (chi-square; see pdf_chi_square).
 *  (g) The switch to area sampling for far triangles (tr_light_far) happens at four
 *      bounding radii from the centroid, in every direction, and there the density
 *      light sampling reports is the area density.
 *  (h) The pick's branch-free binary search returns what a linear scan returns (the
 *      first entry above u, the last where none is) for CDFs of 1 to 70 entries with
 *      repeated values and for u on, between and beyond the entries. */
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

/* A plane of sx by sz (scene_util.h's add_shape). */
static void add_plane(tr_scene *s, uint32_t mat, tr_vec3 pos, tr_vec3 rot, float sx, float sz) {
    add_shape(s, TR_SHAPE_PLANE, mat, pos, rot, v3(sx, 1.0f, sz));
}

static double expected_weight(const tr_material *m, const tr_triangle *t) {
    if (!(m->emittance > 0.0f) || !(t->area > 0.0f)) {
        return 0.0;
    }
    double l = (double)m->emittance * ((double)m->color.x + m->color.y + m->color.z) / 3.0;
    return l * t->area * ((m->flags & TR_MATERIAL_TWO_SIDED) ? 2.0 : 1.0);
}

static void table(void) {
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    uint32_t white = add_mat(&s, tr_material_diffuse(v3s(0.7f)));
    uint32_t warm = add_mat(&s, tr_material_emitter(v3(1.0f, 0.8f, 0.6f), 10.0f));
    tr_material cold_m = tr_material_emitter(v3(0.2f, 0.4f, 1.0f), 3.0f);
    cold_m.flags = TR_MATERIAL_TWO_SIDED;
    uint32_t cold = add_mat(&s, cold_m);
    tr_material glow_m = tr_material_diffuse(v3(0.5f, 0.5f, 0.5f));
    glow_m.emittance = 0.7f; /* a diffuse surface that also emits */
    uint32_t glow = add_mat(&s, glow_m);
    add_plane(&s, white, v3(0, 0, 0), v3(0, 0, 0), 4.0f, 4.0f);
    add_plane(&s, warm, v3(0, 2, 0), v3((float)PI_D, 0, 0), 0.5f, 0.3f);
    add_plane(&s, cold, v3(1, 1, 0), v3(0, 0, 1.0f), 1.5f, 0.2f);
    add_plane(&s, white, v3(-1, 1, 0), v3(0, 0, -1.0f), 2.0f, 2.0f);
    add_plane(&s, glow, v3(0, 1, 1), v3(0.5f, 0, 0), 0.7f, 0.9f);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);

    /* (a) */
    double total = 0.0;
    uint32_t emissive = 0;
    for (uint32_t i = 0; i < s.triangle_count; ++i) {
        double w = expected_weight(&s.materials[s.triangles[i].material], &s.triangles[i]);
        total += w;
        emissive += w > 0.0;
    }
    CHECK(s.light_count == emissive && emissive == 6, "table has %u entries, expected %u (6)",
          s.light_count, emissive);
    CHECK(fabs(s.light_weight_total - total) <= 1e-5 * total, "total weight %g vs %g",
          (double)s.light_weight_total, total);
    double prev = 0.0;
    for (uint32_t k = 0; k < s.light_count; ++k) {
        uint32_t t = s.lights[k];
        double w = expected_weight(&s.materials[s.triangles[t].material], &s.triangles[t]);
        double step = (double)s.light_cdf[k] - prev;
        CHECK(w > 0.0 && fabs(step - w / total) <= 1e-6, "entry %u (triangle %u): p %.7f vs %.7f",
              k, t, step, w / total);
        prev = s.light_cdf[k];
    }
    CHECK(s.light_count > 0 && s.light_cdf[s.light_count - 1] == 1.0f, "CDF ends at 1");

    /* (b) */
    tr_scene_view v = tr_scene_view_of(&s);
    CHECK(v.light_count == s.light_count && v.lights == s.lights, "view exposes the table");
    enum { PICKS = 200000 };
    double count[8] = {0};
    tr_rng rng;
    tr_rng_init(&rng, 42, 0, 0);
    for (int k = 0; k < PICKS; ++k) {
        uint32_t idx = tr_light_pick(&v, tr_rng_float(&rng));
        if (idx < 8) {
            count[idx] += 1;
        }
    }
    double chi2 = 0.0;
    prev = 0.0;
    for (uint32_t k = 0; k < s.light_count; ++k) {
        double e = ((double)s.light_cdf[k] - prev) * PICKS;
        prev = s.light_cdf[k];
        chi2 += (count[k] - e) * (count[k] - e) / e;
    }
    CHECK(chi2 < chi2_critical((int)s.light_count - 1), "picks: chi2 %.2f (critical %.2f)", chi2,
          chi2_critical((int)s.light_count - 1));
    /* The extreme u values stay inside the table. */
    CHECK(tr_light_pick(&v, 0.0f) == 0 && tr_light_pick(&v, 0.99999994f) == s.light_count - 1,
          "pick(0) and pick(1-)");

    /* (d) */
    add_plane(&s, warm, v3(0, 3, 0), v3(0, 0, 0), 1.0f, 1.0f);
    v = tr_scene_view_of(&s);
    CHECK(v.light_count == 0, "a stale table is hidden (%u entries exposed)", v.light_count);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "recommit: %s", err.msg);
    v = tr_scene_view_of(&s);
    CHECK(v.light_count == 8, "recommitted table has %u entries (8)", v.light_count);
    tr_scene_clear(&s);

    tr_scene_init(&s);
    add_plane(&s, add_mat(&s, tr_material_diffuse(v3s(0.5f))), v3(0, 0, 0), v3(0, 0, 0), 1, 1);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    v = tr_scene_view_of(&s);
    CHECK(v.light_count == 0 && s.lights == NULL, "no emitters, no table");
    uint32_t t;
    tr_vec3 p;
    float u, w;
    CHECK(tr_light_sample(&v, v3s(0.0f), tr_rng_float(&rng), tr_rng_float(&rng), &t, &p, &u, &w) ==
              0.0f,
          "sampling an empty table gives pdf 0");
    tr_scene_clear(&s);
}

/* Irradiance at x (normal +y) from a Lambertian polygon of radiance L (Lambert). */
static double polygon_irradiance(const double (*vtx)[3], int nv, const double x[3], double L) {
    double sum = 0.0;
    for (int i = 0; i < nv; ++i) {
        const double *a0 = vtx[i], *b0 = vtx[(i + 1) % nv];
        double a[3] = {a0[0] - x[0], a0[1] - x[1], a0[2] - x[2]};
        double b[3] = {b0[0] - x[0], b0[1] - x[1], b0[2] - x[2]};
        double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                       a[0] * b[1] - a[1] * b[0]};
        double lc = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        double beta = acos((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb));
        sum += beta * c[1] / lc; /* n = +y */
    }
    return 0.5 * L * fabs(sum);
}

static void irradiance(void) {
    const double side = 0.8, h = 1.0, L = 6.0;
    tr_scene s = {0};
    tr_scene_init(&s);
    tr_error err;
    uint32_t em = add_mat(&s, tr_material_emitter(v3s(1.0f), (float)L));
    /* A square at height h, rotated by pi about x so that its normal points down. */
    add_plane(&s, em, v3(0.0f, (float)h, 0.0f), v3((float)PI_D, 0, 0), (float)side, (float)side);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    CHECK(s.triangle_count == 2 && s.triangles[0].normal.y < -0.999f, "light faces down");
    tr_scene_view v = tr_scene_view_of(&s);
    const double hs = side / 2.0;
    const double vtx[4][3] = {{-hs, h, -hs}, {hs, h, -hs}, {hs, h, hs}, {-hs, h, hs}};
    /* Points where the light subtends a solid angle sampled as such, one close to its
     * plane, and one far below where it is sampled by area. */
    const double points[5][3] = {
        {0.0, 0.0, 0.0}, {0.3, 0.2, -0.5}, {1.2, 0.6, 0.1}, {0.1, 0.9, 0.2}, {0.5, -30.0, 1.0}};
    int spherical = 0;
    for (int q = 0; q < 5; ++q) {
        double expect = polygon_irradiance(vtx, 4, points[q], L);
        if (q == 0) {
            /* On the axis of a square of half-side s at height h each edge lies at
             * distance r = sqrt(h^2 + s^2), subtends beta = 2 atan(s / r), and its
             * plane through the point has n . g = s / r, so
             * E = L/2 * 4 * 2 atan(s / r) * s / r = 4 L (s / r) atan(s / r). */
            double r = sqrt(h * h + hs * hs);
            double onaxis = 4.0 * L * (hs / r) * atan(hs / r);
            CHECK(fabs(onaxis - expect) <= 1e-9 * expect, "Lambert %.9f vs on-axis form %.9f",
                  expect, onaxis);
        }
        tr_vec3 x = v3((float)points[q][0], (float)points[q][1], (float)points[q][2]);
        tr_rng rng;
        tr_rng_init(&rng, 7, (uint64_t)q, 1);
        const int N = 400000;
        double s1 = 0.0, s2 = 0.0;
        for (int k = 0; k < N; ++k) {
            uint32_t t;
            tr_vec3 y;
            float bu, bv;
            float u1 = tr_rng_float(&rng), u2 = tr_rng_float(&rng);
            float pw = tr_light_sample(&v, x, u1, u2, &t, &y, &bu, &bv);
            tr_vec3 d = v3_sub(y, x);
            float r2 = v3_dot(d, d);
            tr_vec3 w = v3_scale(d, 1.0f / sqrtf(r2));
            tr_bsdf_params m = tr_material_eval(&v, t, bu, bv, y, s.triangles[t].normal, w);
            double le = tr_emitted(&m, v3_neg(w)).x;
            double cos_x = w.y > 0.0f ? w.y : 0.0;
            double e = pw > 0.0f ? le * cos_x / pw : 0.0;
            s1 += e;
            s2 += e * e;
        }
        tr_vec3 va, vb, vc;
        float ca, sa;
        spherical += tr_light_spherical(&s.triangles[0], x, &va, &vb, &vc, &ca, &sa) > 0.0f;
        double mean = s1 / N, se = sqrt(fmax(0.0, s2 / N - mean * mean) / N);
        CHECK(fabs(mean - expect) <= NSIGMA * se && se < 0.01 * expect,
              "point %d: NEE irradiance %.5f +- %.5f vs analytic %.5f", q, mean, se, expect);
    }
    CHECK(spherical == 4,
          "%d of the 4 near points sample the light by solid angle, the far "
          "point by area",
          spherical);
    tr_scene_clear(&s);
}

/* (e) The built-in Cornell box's lamp: a plane whose normal points up (towards the
 * ceiling) with our winding, so its material must be two-sided for pt to light the box;
 * the table weighs it twice. */
static void builtin_lamp(void) {
    tr_scene s = {0};
    tr_error err;
    CHECK(tr_scene_builtin(&s, "cornell", 64, 48, &err) == TR_OK, "builtin: %s", err.msg);
    CHECK(tr_scene_commit(&s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    CHECK(s.light_count == 2, "the lamp is two triangles (%u)", s.light_count);
    for (uint32_t k = 0; k < s.light_count; ++k) {
        const tr_triangle *t = &s.triangles[s.lights[k]];
        const tr_material *m = &s.materials[t->material];
        CHECK(t->normal.y > 0.999f, "lamp triangle normal (%g %g %g) points up",
              (double)t->normal.x, (double)t->normal.y, (double)t->normal.z);
        CHECK(m->flags & TR_MATERIAL_TWO_SIDED, "the built-in lamp is two-sided");
        tr_vec3 down = v3(0.0f, -1.0f, 0.0f);
        tr_bsdf_params b = tr_material_params(m, t->normal);
        CHECK(tr_emitted(&b, down).x > 0.0f, "the lamp shines down into the box");
    }
    tr_scene_clear(&s);
}

/* (f) The density light sampling reports is the density it samples: points drawn by
 * tr_light_sample on one triangle, binned on a 16 x 16 grid of the triangle's uniform-area
 * parametrisation (u1 = (b1 + b2)^2, u2 = b1 / (b1 + b2); each cell 1/256 of the area),
 * against the probability tr_light_pdf gives each cell, integrated by the midpoint rule
 * on 8 x 8 sub-cells (the solid-angle density times |cos theta_l| / r^2 is the area
 * density). Chi-square at p = 1e-4 with 255 degrees of freedom, from points where the
 * triangle is sampled by solid angle and by area. The expected probabilities must sum to
 * 1 (the density is normalised), and the uniform-area density must fail against the
 * solid-angle samples of a near point (the test can tell them apart). */
enum { PK = 16, PM = 8 };

static double pdf_cell_prob(const tr_scene_view *v, const tr_triangle *tri, tr_vec3 x, int i, int j,
                            int area_only) {
    double sum = 0.0;
    for (int a = 0; a < PM; ++a) {
        for (int b = 0; b < PM; ++b) {
            double u1 = (i + (a + 0.5) / PM) / PK, u2 = (j + (b + 0.5) / PM) / PK;
            double su = sqrt(u1), b1 = u2 * su, b2 = su - b1;
            tr_vec3 y = v3_add(
                v3_add(v3_scale(tri->v0, (float)(1.0 - b1 - b2)), v3_scale(tri->v1, (float)b1)),
                v3_scale(tri->v2, (float)b2));
            if (area_only) {
                sum += 1.0 / tri->area;
                continue;
            }
            tr_vec3 d = v3_sub(y, x);
            double r2 = v3_dot(d, d);
            double cos_l = fabs(v3_dot(d, tri->normal)) / sqrt(r2);
            sum += (double)tr_light_pdf(v, x, 0, y) * cos_l / r2;
        }
    }
    return sum / (PM * PM) * tri->area / (PK * PK);
}

/* A scene of one emissive triangle (vertices pos), committed with the flat structure. */
static void one_light(tr_scene *s, const float pos[9]) {
    tr_scene_init(s);
    tr_error err;
    uint32_t em = add_mat(s, tr_material_emitter(v3s(1.0f), 2.0f));
    const uint32_t idx[3] = {0, 1, 2};
    CHECK(tr_scene_add_mesh(s, pos, 3, idx, 1, NULL, em, NULL, NULL, &err) == TR_OK, "mesh: %s",
          err.msg);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "commit: %s", err.msg);
}

static void pdf_chi_square(void) {
    tr_scene s = {0};
    const float pos[9] = {-0.5f, 1.0f, -0.3f, 0.6f, 1.0f, -0.4f, 0.1f, 1.2f, 0.7f};
    one_light(&s, pos);
    tr_scene_view v = tr_scene_view_of(&s);
    const tr_triangle *tri = &s.triangles[0];
    /* The third point lies five bounding radii below the triangle, where it subtends
     * some 0.03 sr: sampled by area through tr_light_far's test alone. */
    const tr_vec3 points[4] = {v3(0.0f, 0.7f, 0.0f), v3(0.8f, 0.2f, 0.4f), v3(0.0f, -2.5f, 0.0f),
                               v3(3.0f, -40.0f, 2.0f)};
    const int want_spherical[4] = {1, 1, 0, 0};
    static double obs[PK * PK];
    for (int q = 0; q < 4; ++q) {
        tr_vec3 va, vb, vc;
        float ca, sa;
        int sph = tr_light_spherical(tri, points[q], &va, &vb, &vc, &ca, &sa) > 0.0f;
        CHECK(sph == want_spherical[q], "point %d: spherical %d, expected %d", q, sph,
              want_spherical[q]);
        memset(obs, 0, sizeof obs);
        tr_rng rng;
        tr_rng_init(&rng, 555, (uint64_t)q, 0);
        const int N = 300000;
        int failed = 0;
        for (int k = 0; k < N; ++k) {
            float u1 = tr_rng_float(&rng), u2 = tr_rng_float(&rng);
            uint32_t t;
            tr_vec3 y;
            float bu, bw;
            if (!(tr_light_sample(&v, points[q], u1, u2, &t, &y, &bu, &bw) > 0.0f)) {
                ++failed;
                continue;
            }
            double sum = (double)bu + bw;
            double c1 = sum * sum, c2 = sum > 0.0 ? bu / sum : 0.0;
            int i = (int)(c1 * PK), j = (int)(c2 * PK);
            i = i < 0 ? 0 : (i >= PK ? PK - 1 : i);
            j = j < 0 ? 0 : (j >= PK ? PK - 1 : j);
            obs[i * PK + j] += 1.0;
        }
        CHECK(failed == 0, "point %d: %d samples failed", q, failed);
        for (int area_only = 0; area_only < 2; ++area_only) {
            double chi2 = 0.0, total = 0.0;
            for (int i = 0; i < PK; ++i) {
                for (int j = 0; j < PK; ++j) {
                    double pr = pdf_cell_prob(&v, tri, points[q], i, j, area_only);
                    total += pr;
                    double e = pr * N, o = obs[i * PK + j];
                    chi2 += (o - e) * (o - e) / e;
                }
            }
            double crit = chi2_critical(PK * PK - 1);
            if (!area_only) {
                CHECK(fabs(total - 1.0) < 2e-3, "point %d: the density integrates to %.5f", q,
                      total);
                CHECK(chi2 < crit, "point %d: chi-square %.1f, critical %.1f", q, chi2, crit);
                printf("point %d (%s): chi-square %.1f (critical %.1f)\n", q,
                       sph ? "solid angle" : "area", chi2, crit);
            } else if (q == 0) {
                CHECK(chi2 > crit,
                      "the uniform-area density passes for solid-angle samples "
                      "(chi-square %.1f)",
                      chi2);
            }
        }
    }
    tr_scene_clear(&s);
}

/* (g) A point at f bounding radii from the centroid of a triangle, in direction dir,
 * crosses to area sampling at f = 4 and not before; beyond, tr_light_pdf is the area
 * density seen from the point. The solid angle there (Van Oosterom and Strackee, in
 * double) is far above TR_LIGHT_SPHERICAL_MIN, so the distance test alone decides. */
static double solid_angle_d(const tr_triangle *t, tr_vec3 p) {
    double v[3][3], l[3];
    const tr_vec3 vs[3] = {t->v0, t->v1, t->v2};
    for (int k = 0; k < 3; ++k) {
        v[k][0] = (double)vs[k].x - p.x;
        v[k][1] = (double)vs[k].y - p.y;
        v[k][2] = (double)vs[k].z - p.z;
        l[k] = sqrt(v[k][0] * v[k][0] + v[k][1] * v[k][1] + v[k][2] * v[k][2]);
    }
    double cx = v[1][1] * v[2][2] - v[1][2] * v[2][1], cy = v[1][2] * v[2][0] - v[1][0] * v[2][2],
           cz = v[1][0] * v[2][1] - v[1][1] * v[2][0];
    double triple = fabs(v[0][0] * cx + v[0][1] * cy + v[0][2] * cz);
    double dots = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double *a = v[k], *b = v[(k + 1) % 3];
        dots += (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) * l[(k + 2) % 3];
    }
    return 2.0 * atan2(triple, l[0] * l[1] * l[2] + dots);
}

static void far_switch(void) {
    tr_scene s = {0};
    const float pos[9] = {0.0f, 0.0f, 0.0f, 2.0f, 0.0f, 0.0f, 0.5f, 0.0f, 1.5f};
    one_light(&s, pos);
    tr_scene_view v = tr_scene_view_of(&s);
    const tr_triangle *tri = &s.triangles[0];
    const double cen[3] = {2.5 / 3.0, 0.0, 0.5};
    double r2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        double dx = pos[3 * k] - cen[0], dy = pos[3 * k + 1] - cen[1], dz = pos[3 * k + 2] - cen[2];
        r2 = fmax(r2, dx * dx + dy * dy + dz * dz);
    }
    const double radius = sqrt(r2);
    const double dirs[3][3] = {{0.0, -1.0, 0.0}, {0.6, -0.64, -0.48}, {0.48, 0.6, 0.64}};
    for (int d = 0; d < 3; ++d) {
        for (int side = 0; side < 2; ++side) {
            const double f = side ? 4.02 : 3.98;
            tr_vec3 p = v3((float)(cen[0] + f * radius * dirs[d][0]),
                           (float)(cen[1] + f * radius * dirs[d][1]),
                           (float)(cen[2] + f * radius * dirs[d][2]));
            tr_vec3 va, vb, vc;
            float ca, sa;
            const float omega = tr_light_spherical(tri, p, &va, &vb, &vc, &ca, &sa);
            CHECK(tr_light_far(tri, p) == side, "direction %d at %.2f radii: far %d", d, f,
                  tr_light_far(tri, p));
            const double exact = solid_angle_d(tri, p);
            if (!side) {
                CHECK(omega > 0.0f && fabs(omega - exact) < 1e-4 * exact,
                      "direction %d inside: solid angle %g, exact %g", d, (double)omega, exact);
                continue;
            }
            CHECK(omega == 0.0f && exact > 10.0 * TR_LIGHT_SPHERICAL_MIN,
                  "direction %d outside: spherical %g (solid angle %g)", d, (double)omega, exact);
            /* Beyond the switch the reported density is the area density: the light's
             * centroid seen from p, sel = 1 (one emitter). */
            tr_vec3 y = v3((float)cen[0], (float)cen[1], (float)cen[2]);
            tr_vec3 dv = v3_sub(y, p);
            double dist2 = v3_dot(dv, dv),
                   cos_l = fabs((double)v3_dot(dv, tri->normal)) / sqrt(dist2);
            double want = dist2 / (cos_l * tri->area);
            double got = tr_light_pdf(&v, p, 0, y);
            CHECK(fabs(got - want) < 1e-4 * want, "direction %d: density %g, area density %g", d,
                  got, want);
        }
    }
    tr_scene_clear(&s);
}

/* (h) */
static void pick_scan(void) {
    enum { N = 70 };
    float cdf[N];
    tr_scene_view v;
    memset(&v, 0, sizeof v);
    v.light_cdf = cdf;
    tr_rng rng;
    tr_rng_init(&rng, 8, 0, 0);
    int bad = 0, tried = 0;
    for (uint32_t n = 1; n <= N; ++n) {
        for (int trial = 0; trial < 20; ++trial) {
            float acc = 0.0f;
            for (uint32_t k = 0; k < n; ++k) {
                /* A fifth of the steps empty: runs of equal entries. */
                acc += tr_rng_float(&rng) < 0.2f ? 0.0f : tr_rng_float(&rng);
                cdf[k] = acc;
            }
            for (uint32_t k = 0; k < n; ++k) {
                cdf[k] = acc > 0.0f ? cdf[k] / acc : 1.0f;
            }
            v.light_count = n;
            for (int t = 0; t < 3 * (int)n + 20; ++t) {
                float u;
                const int kind = t % 4;
                if (kind == 0) {
                    u = cdf[(uint32_t)(tr_rng_float(&rng) * (float)n) % n]; /* on an entry */
                } else if (kind == 3 && t % 8 == 3) {
                    u = t % 16 == 3 ? 1.0f : 0.0f;
                } else {
                    u = tr_rng_float(&rng);
                }
                uint32_t want = n - 1u;
                for (uint32_t k = 0; k < n; ++k) {
                    if (cdf[k] > u) {
                        want = k;
                        break;
                    }
                }
                ++tried;
                if (tr_light_pick(&v, u) != want) {
                    ++bad;
                }
            }
        }
    }
    CHECK(bad == 0, "%d of %d picks differ from the linear scan", bad, tried);
}

int main(void) {
    pick_scan();
    table();
    builtin_lamp();
    irradiance();
    pdf_chi_square();
    far_switch();
    return check_finish("test_lights");
}
