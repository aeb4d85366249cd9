/* test_intersect.c - ray/triangle (Moller-Trumbore) and ray/box (slab) intersection.
 *
 * The hand-made cases use coordinates that are exact in binary, so that t, u and v
 * can be compared exactly and edge/vertex hits land exactly on the boundary. The
 * randomised cases compare against double-precision references written differently
 * (Cramer's rule for triangles, Liang-Barsky plane clipping for boxes), skipping only
 * rays whose answer would change under a tiny perturbation of the geometry. */
#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "dvec.h"
#include "kernel/intersect.h"
#include "kernel/rng.h"

#include <float.h>
#include <stdint.h>

/* Sentinel that a miss must leave in the output arguments. */
#define UNTOUCHED -12345.0f

static int tri(const tr_ray *ray, tr_vec3 a, tr_vec3 b, tr_vec3 c, float *t, float *u, float *v) {
    *t = *u = *v = UNTOUCHED;
    return tr_intersect_triangle(ray, a, b, c, t, u, v);
}

static tr_ray down_at(float x, float y) {
    return tr_ray_make(v3(x, y, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
}

static void test_triangle_hits(void) {
    float t, u, v;
    /* Plane z = 1, e1 = (2,0,0), e2 = (0,4,0); the ray meets it at v0 + e1/4 + e2/4. */
    tr_vec3 a = v3(1.0f, 1.0f, 1.0f), b = v3(3.0f, 1.0f, 1.0f), c = v3(1.0f, 5.0f, 1.0f);
    tr_ray r = tr_ray_make(v3(1.5f, 2.0f, 5.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    CHECK(tri(&r, a, b, c, &t, &u, &v), "axis-aligned ray misses the triangle");
    CHECK(t == 4.0f && u == 0.25f && v == 0.25f, "t, u, v = %.9g %.9g %.9g, want 4 0.25 0.25",
          (double)t, (double)u, (double)v);

    /* Oblique ray through a chosen barycentric point of a tilted triangle:
     * P = v0 + 0.2 e1 + 0.3 e2 = (0.1, 0.1, 2.4), and |P - O| = sqrt(0.16 + 0.16 + 11.56). */
    a = v3(-1.0f, -1.0f, 2.0f);
    b = v3(3.0f, 0.0f, 2.5f);
    c = v3(0.0f, 2.0f, 3.0f);
    tr_vec3 o = v3(0.5f, -0.3f, -1.0f);
    tr_vec3 d = v3_normalize(v3(0.1f - 0.5f, 0.1f + 0.3f, 2.4f + 1.0f));
    r = tr_ray_make(o, d, 0.0f, INFINITY);
    CHECK(tri(&r, a, b, c, &t, &u, &v), "oblique ray misses the tilted triangle");
    CHECK_NEAR(t, sqrt(0.16 + 0.16 + 11.56), 1e-5, "oblique t");
    CHECK_NEAR(u, 0.2, 1e-5, "oblique u");
    CHECK_NEAR(v, 0.3, 1e-5, "oblique v");

    /* Two-sided: the same triangle from below, and with the winding reversed. */
    a = v3(0.0f, 0.0f, 0.0f);
    b = v3(1.0f, 0.0f, 0.0f);
    c = v3(0.0f, 1.0f, 0.0f);
    r = tr_ray_make(v3(0.25f, 0.5f, -1.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY);
    CHECK(tri(&r, a, b, c, &t, &u, &v), "back face missed");
    CHECK(t == 1.0f && u == 0.25f && v == 0.5f, "back face: t, u, v = %.9g %.9g %.9g", (double)t,
          (double)u, (double)v);
    r = down_at(0.25f, 0.5f);
    CHECK(tri(&r, a, c, b, &t, &u, &v), "reversed winding missed");
    CHECK(t == 1.0f && u == 0.5f && v == 0.25f, "reversed winding: t, u, v = %.9g %.9g %.9g",
          (double)t, (double)u, (double)v);

    /* Misses just outside each edge, by one part in 2^20. */
    const float eps = 1.0f / 1048576.0f;
    r = down_at(-eps, 0.5f);
    CHECK(!tri(&r, a, b, c, &t, &u, &v), "hit beyond the edge u = 0");
    CHECK(t == UNTOUCHED && u == UNTOUCHED && v == UNTOUCHED, "a miss wrote its outputs");
    r = down_at(0.5f, -eps);
    CHECK(!tri(&r, a, b, c, &t, &u, &v), "hit beyond the edge v = 0");
    r = down_at(0.5f, 0.5f + eps);
    CHECK(!tri(&r, a, b, c, &t, &u, &v), "hit beyond the edge u + v = 1");
    r = down_at(2.0f, 2.0f);
    CHECK(!tri(&r, a, b, c, &t, &u, &v), "hit far outside the triangle");
}

/* Boundaries count as inside, so that a ray through the shared edge of a mesh does not
 * slip between its two triangles. */
static void test_triangle_edges_and_vertices(void) {
    float t, u, v;
    tr_vec3 a = v3(0.0f, 0.0f, 0.0f), b = v3(1.0f, 0.0f, 0.0f), c = v3(0.0f, 1.0f, 0.0f);
    const float pts[][4] = {
        /* x, y, expected u, expected v */
        {0.0f, 0.5f, 0.0f, 0.5f},     /* edge v0-v2 (u = 0) */
        {0.25f, 0.0f, 0.25f, 0.0f},   /* edge v0-v1 (v = 0) */
        {0.25f, 0.75f, 0.25f, 0.75f}, /* edge v1-v2 (u + v = 1) */
        {0.0f, 0.0f, 0.0f, 0.0f},     /* v0 */
        {1.0f, 0.0f, 1.0f, 0.0f},     /* v1 */
        {0.0f, 1.0f, 0.0f, 1.0f},     /* v2 */
    };
    for (int i = 0; i < 6; ++i) {
        for (int side = 0; side < 2; ++side) {
            float dz = side ? 1.0f : -1.0f;
            tr_ray r =
                tr_ray_make(v3(pts[i][0], pts[i][1], -dz), v3(0.0f, 0.0f, dz), 0.0f, INFINITY);
            int hit = tri(&r, a, b, c, &t, &u, &v);
            CHECK(hit, "boundary point %d (side %d) missed", i, side);
            CHECK(!hit || (t == 1.0f && u == pts[i][2] && v == pts[i][3]),
                  "boundary point %d: t, u, v = %.9g %.9g %.9g", i, (double)t, (double)u,
                  (double)v);
        }
    }

    /* A unit quad split along its diagonal: points on the diagonal hit both halves. */
    tr_vec3 q0 = v3(0.0f, 0.0f, 0.0f), q1 = v3(1.0f, 0.0f, 0.0f), q2 = v3(1.0f, 1.0f, 0.0f),
            q3 = v3(0.0f, 1.0f, 0.0f);
    int both = 0;
    for (int k = 0; k <= 16; ++k) {
        float x = (float)k / 16.0f;
        tr_ray r = down_at(x, 1.0f - x);
        both += tri(&r, q0, q1, q3, &t, &u, &v) && tri(&r, q1, q2, q3, &t, &u, &v);
    }
    CHECK(both == 17, "only %d of 17 points of a shared edge hit both triangles", both);
}

static void test_triangle_parallel_and_limits(void) {
    float t, u, v;
    tr_vec3 a = v3(0.0f, 0.0f, 0.0f), b = v3(1.0f, 0.0f, 0.0f), c = v3(0.0f, 1.0f, 0.0f);

    /* Parallel: in the plane (through the triangle) and above it. */
    tr_ray r = tr_ray_make(v3(-1.0f, 0.25f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY);
    CHECK(!tri(&r, a, b, c, &t, &u, &v), "ray in the triangle's plane hits");
    r = tr_ray_make(v3(-1.0f, 0.25f, 0.5f), v3(0.6f, 0.8f, 0.0f), 0.0f, INFINITY);
    CHECK(!tri(&r, a, b, c, &t, &u, &v), "ray parallel above the plane hits");

    /* The hit is at t = 4; the interval (tmin, tmax) is open at both ends. */
    tr_vec3 o = v3(0.25f, 0.25f, 4.0f), d = v3(0.0f, 0.0f, -1.0f);
    const struct {
        float tmin, tmax;
        int hit;
    } lim[] = {{0.0f, INFINITY, 1}, {3.999f, 4.001f, 1}, {4.0f, INFINITY, 0}, {4.5f, INFINITY, 0},
               {0.0f, 4.0f, 0},     {0.0f, 3.9f, 0},     {-INFINITY, 1.0f, 0}};
    for (int i = 0; i < (int)(sizeof lim / sizeof lim[0]); ++i) {
        r = tr_ray_make(o, d, lim[i].tmin, lim[i].tmax);
        int hit = tri(&r, a, b, c, &t, &u, &v);
        CHECK(hit == lim[i].hit, "t = 4 with (tmin, tmax) = (%g, %g): hit %d", (double)lim[i].tmin,
              (double)lim[i].tmax, hit);
    }
    /* A triangle behind the origin. */
    r = tr_ray_make(v3(0.25f, 0.25f, -1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    CHECK(!tri(&r, a, b, c, &t, &u, &v), "triangle behind the ray is hit");

    /* Closest hit: shrinking tmax to each hit must reject every farther triangle and keep
     * every nearer one, whatever the order. */
    const float heights[] = {3.0f, -2.0f, 1.0f, 2.0f, 0.5f, 2.5f};
    r = tr_ray_make(v3(0.25f, 0.25f, -4.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY);
    int hits = 0, best = -1;
    for (int i = 0; i < 6; ++i) {
        float h = heights[i];
        if (tri(&r, v3(0.0f, 0.0f, h), v3(1.0f, 0.0f, h), v3(0.0f, 1.0f, h), &t, &u, &v)) {
            CHECK(t < r.tmax, "a hit at %g is not before tmax %g", (double)t, (double)r.tmax);
            r.tmax = t;
            best = i;
            ++hits;
        }
    }
    CHECK(best == 1 && r.tmax == 2.0f, "closest hit is triangle %d at %g, want 1 at 2", best,
          (double)r.tmax);
    CHECK(hits == 2, "%d hits while shrinking tmax, want 2 (z = 3, then z = -2)", hits);
}

static void test_triangle_degenerate(void) {
    float t, u, v;
    tr_ray r = tr_ray_make(v3(0.5f, 0.5f, 3.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    /* Zero area: collinear, with two equal vertices, and all equal, each lying on the ray. */
    const tr_vec3 zero_area[][3] = {
        {{0.0f, 0.0f, 0.0f}, {0.5f, 0.5f, 0.0f}, {1.0f, 1.0f, 0.0f}},
        {{0.5f, 0.5f, 0.0f}, {0.5f, 0.5f, 0.0f}, {1.0f, 0.0f, 0.0f}},
        {{0.5f, 0.5f, 0.0f}, {0.5f, 0.5f, 0.0f}, {0.5f, 0.5f, 0.0f}},
        {{0.5f, 0.5f, -1.0f}, {0.5f, 0.5f, 0.0f}, {0.5f, 0.5f, 1.0f}},
    };
    for (int i = 0; i < 4; ++i) {
        CHECK(!tri(&r, zero_area[i][0], zero_area[i][1], zero_area[i][2], &t, &u, &v),
              "zero-area triangle %d is hit", i);
    }

    /* A non-finite value in any coordinate of any vertex, with the ray aimed at where the
     * finite triangle would be hit. */
    const float bad[] = {NAN, INFINITY, -INFINITY};
    for (int which = 0; which < 9; ++which) {
        for (int k = 0; k < 3; ++k) {
            float coords[9] = {0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f};
            coords[which] = bad[k];
            tr_ray rr = tr_ray_make(v3(0.25f, 0.25f, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
            int hit =
                tri(&rr, v3(coords[0], coords[1], coords[2]), v3(coords[3], coords[4], coords[5]),
                    v3(coords[6], coords[7], coords[8]), &t, &u, &v);
            CHECK(!hit, "vertex coordinate %d = %g: hit at t = %g, u = %g, v = %g", which,
                  (double)bad[k], (double)t, (double)u, (double)v);
        }
    }
    /* Non-finite rays. */
    tr_vec3 a = v3(0.0f, 0.0f, 0.0f), b = v3(1.0f, 0.0f, 0.0f), c = v3(0.0f, 1.0f, 0.0f);
    r = tr_ray_make(v3(0.25f, NAN, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    CHECK(!tri(&r, a, b, c, &t, &u, &v), "ray with a NaN origin hits");
    r = tr_ray_make(v3(0.25f, 0.25f, 1.0f), v3(NAN, 0.0f, -1.0f), 0.0f, INFINITY);
    CHECK(!tri(&r, a, b, c, &t, &u, &v), "ray with a NaN direction hits");
    r = tr_ray_make(v3(0.25f, 0.25f, 1.0f), v3(0.0f, 0.0f, -1.0f), NAN, NAN);
    CHECK(!tri(&r, a, b, c, &t, &u, &v), "ray with NaN limits hits");

    /* Small and large but valid triangles must not be mistaken for degenerate ones. */
    const float scales[] = {1e-4f, 1e-2f, 1e2f, 1e4f};
    for (int i = 0; i < 4; ++i) {
        float s = scales[i];
        tr_ray rs = tr_ray_make(v3(0.25f * s, 0.25f * s, s), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
        int hit = tri(&rs, v3(0.0f, 0.0f, 0.0f), v3(s, 0.0f, 0.0f), v3(0.0f, s, 0.0f), &t, &u, &v);
        CHECK(hit, "a triangle of size %g is missed", (double)s);
        CHECK(!hit || (fabs(t / s - 1.0) < 1e-6 && fabs(u - 0.25) < 1e-6 && fabs(v - 0.25) < 1e-6),
              "size %g: t, u, v = %.9g %.9g %.9g", (double)s, (double)t, (double)u, (double)v);
    }
}

/* det [a b c] with a, b, c as columns. */
static double det3(dvec a, dvec b, dvec c) {
    return a.x * (b.y * c.z - b.z * c.y) - b.x * (a.y * c.z - a.z * c.y) +
           c.x * (a.y * b.z - a.z * b.y);
}

static float frand(tr_rng *r, float lo, float hi) {
    return tr_rng_range(r, lo, hi);
}

static tr_vec3 vrand(tr_rng *r, float lo, float hi) {
    return v3(frand(r, lo, hi), frand(r, lo, hi), frand(r, lo, hi));
}

/* Random rays and triangles against Cramer's rule for o + t d = v0 + u e1 + v e2, in
 * double. Cases within the float error bound of a decision boundary (an edge, t = tmin
 * or tmax) and rays within 1e-3 radians of the plane are skipped; the rest must agree
 * exactly in hit/miss and within the error bound in t, u, v. */
static void test_triangle_random(void) {
    enum { N = 100000 };
    tr_rng rng;
    tr_rng_init(&rng, 7, 0, 0);
    int compared = 0, mismatched = 0, hits = 0, bad_values = 0;
    double worst_ratio = 0.0;
    for (int i = 0; i < N; ++i) {
        tr_vec3 a = vrand(&rng, -2.0f, 2.0f), b = vrand(&rng, -2.0f, 2.0f),
                c = vrand(&rng, -2.0f, 2.0f);
        tr_vec3 o = vrand(&rng, -4.0f, 4.0f);
        /* Half the rays aim at a point near the triangle so that hits are common. */
        tr_vec3 d;
        if (i & 1) {
            float s = frand(&rng, -0.2f, 1.2f), w = frand(&rng, -0.2f, 1.2f - s);
            tr_vec3 target =
                v3_add(a, v3_add(v3_scale(v3_sub(b, a), s), v3_scale(v3_sub(c, a), w)));
            d = v3_sub(target, o);
        } else {
            d = vrand(&rng, -1.0f, 1.0f);
        }
        d = v3_normalize(d);
        float tmax = (i % 3 == 0) ? frand(&rng, 0.0f, 8.0f) : INFINITY;
        tr_ray ray = tr_ray_make(o, d, 0.0f, tmax);

        dvec e1 = dsub(dv(b), dv(a)), e2 = dsub(dv(c), dv(a)), s = dsub(dv(o), dv(a));
        dvec dd = dv(d), nd = {-dd.x, -dd.y, -dd.z};
        double den = det3(nd, e1, e2);
        double nx = e1.y * e2.z - e1.z * e2.y, ny = e1.z * e2.x - e1.x * e2.z,
               nz = e1.x * e2.y - e1.y * e2.x;
        double n_len = sqrt(nx * nx + ny * ny + nz * nz);
        /* |den| = |d . (e1 x e2)|: the sine of the ray's angle to the plane times 2 area. */
        if (fabs(den) < 1e-3 * n_len) {
            continue;
        }
        double rt = det3(s, e1, e2) / den;
        double ru = det3(nd, s, e2) / den;
        double rv = det3(nd, e1, s) / den;
        /* Every numerator and den is a sum of triple products bounded by
         * |d| (|s| + |e1| + |e2|)^2, each computed with a few roundings, so the float
         * quotients are off by at most a small multiple of eps * bound / |den|. */
        double len = sqrt(s.x * s.x + s.y * s.y + s.z * s.z) +
                     sqrt(e1.x * e1.x + e1.y * e1.y + e1.z * e1.z) +
                     sqrt(e2.x * e2.x + e2.y * e2.y + e2.z * e2.z);
        double err = 8.0 * FLT_EPSILON * len * len / fabs(den);
        double tol_uv = err * (1.0 + fabs(ru) + fabs(rv)), tol_t = err * (1.0 + fabs(rt));
        double margin = fmin(fmin(ru, rv), 1.0 - ru - rv);
        double tm = fmin(rt, (double)tmax - rt);
        if (fabs(margin) < tol_uv || fabs(tm) < tol_t) {
            continue;
        }
        int want = margin > 0.0 && tm > 0.0;
        float t, u, v;
        int got = tri(&ray, a, b, c, &t, &u, &v);
        ++compared;
        hits += want;
        if (got != want) {
            ++mismatched;
            continue;
        }
        if (got) {
            double r_t = fabs(t - rt) / tol_t;
            double r_uv = fmax(fabs(u - ru), fabs(v - rv)) / tol_uv;
            worst_ratio = fmax(worst_ratio, fmax(r_t, r_uv));
            bad_values += r_t > 1.0 || r_uv > 1.0;
        }
    }
    printf("triangles: %d of %d random cases compared, %d hits, %d mismatches, worst t/u/v "
           "error %.3g of the bound\n",
           compared, N, hits, mismatched, worst_ratio);
    CHECK(mismatched == 0, "%d of %d random triangle cases disagree with the reference", mismatched,
          compared);
    CHECK(bad_values == 0, "%d hits with t, u or v off the reference", bad_values);
    /* The comparison must not be vacuous. */
    CHECK(compared > N * 3 / 4 && hits > compared / 10 && hits < compared * 9 / 10,
          "random triangle cases are unbalanced: %d compared, %d hits", compared, hits);
}

static int box(tr_vec3 o, tr_vec3 d, float tmin, float tmax, tr_aabb bx, float *tnear) {
    tr_ray r = tr_ray_make(o, d, tmin, tmax);
    *tnear = UNTOUCHED;
    return tr_intersect_aabb(&r, bx, tnear);
}

static tr_aabb aabb(tr_vec3 lo, tr_vec3 hi) {
    tr_aabb b;
    b.min = lo;
    b.max = hi;
    return b;
}

static void test_aabb_cases(void) {
    tr_aabb unit = aabb(v3(-1.0f, -1.0f, -1.0f), v3(1.0f, 1.0f, 1.0f));
    float tn;
    CHECK(box(v3(-5.0f, 0.2f, 0.3f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, unit, &tn) && tn == 4.0f,
          "ray along +x: entry %g, want 4", (double)tn);
    CHECK(
        box(v3(-3.0f, -3.0f, -3.0f), v3_normalize(v3(1.0f, 1.0f, 1.0f)), 0.0f, INFINITY, unit, &tn),
        "diagonal ray misses");
    CHECK_NEAR(tn, 2.0 * sqrt(3.0), 1e-5, "diagonal entry");
    CHECK(!box(v3(-5.0f, 2.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, unit, &tn),
          "ray passing beside the box hits");
    CHECK(
        !box(v3(-5.0f, 0.0f, 0.0f), v3_normalize(v3(1.0f, 1.0f, 0.0f)), 0.0f, INFINITY, unit, &tn),
        "oblique ray passing above the box hits");

    /* Along each axis both ways, with the other components +0 and -0 (the reciprocals
     * are then +inf and -inf): through the box, and offset to miss it. */
    for (int axis = 0; axis < 3; ++axis) {
        for (int sign = -1; sign <= 1; sign += 2) {
            for (int negzero = 0; negzero < 2; ++negzero) {
                float zero = negzero ? -0.0f : 0.0f;
                float dc[3] = {zero, zero, zero}, oc[3] = {0.2f, -0.3f, 0.7f};
                dc[axis] = (float)sign;
                oc[axis] = -5.0f * (float)sign;
                tr_vec3 d = v3(dc[0], dc[1], dc[2]);
                int hit = box(v3(oc[0], oc[1], oc[2]), d, 0.0f, INFINITY, unit, &tn);
                CHECK(hit && tn == 4.0f, "axis %d sign %d zero %g: hit %d entry %g", axis, sign,
                      (double)zero, hit, (double)tn);
                oc[(axis + 1) % 3] = 1.5f;
                hit = box(v3(oc[0], oc[1], oc[2]), d, 0.0f, INFINITY, unit, &tn);
                CHECK(!hit, "axis %d sign %d zero %g: offset ray hits", axis, sign, (double)zero);
                /* Pointing away from the box. */
                oc[(axis + 1) % 3] = 0.2f;
                hit = box(v3(oc[0], oc[1], oc[2]), v3_neg(d), 0.0f, INFINITY, unit, &tn);
                CHECK(!hit, "axis %d sign %d zero %g: ray away from the box hits", axis, sign,
                      (double)zero);
            }
        }
    }

    /* An origin inside is a hit, whatever the direction, including axis directions. */
    CHECK(
        box(v3(0.1f, 0.2f, 0.3f), v3_normalize(v3(1.0f, -2.0f, 0.5f)), 0.0f, INFINITY, unit, &tn) &&
            tn <= 0.0f,
        "origin inside: entry %g", (double)tn);
    CHECK(box(v3(0.1f, 0.2f, 0.3f), v3(0.0f, -0.0f, 1.0f), 0.0f, INFINITY, unit, &tn),
          "origin inside, axis direction: missed");
    CHECK(box(v3(0.1f, 0.2f, 0.3f), v3(0.0f, 1.0f, 0.0f), 0.0f, 0.01f, unit, &tn),
          "origin inside, short segment: missed");

    /* Behind the ray. */
    CHECK(!box(v3(5.0f, 0.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, unit, &tn),
          "box behind the ray is hit");
    CHECK(!box(v3(3.0f, 3.0f, 3.0f), v3_normalize(v3(1.0f, 1.0f, 1.0f)), 0.0f, INFINITY, unit, &tn),
          "box behind the diagonal ray is hit");

    /* The box spans t in [4, 6] along this ray. */
    tr_vec3 o = v3(-5.0f, 0.0f, 0.0f), d = v3(1.0f, 0.0f, 0.0f);
    CHECK(!box(o, d, 0.0f, 3.9f, unit, &tn), "tmax before the box: hit");
    CHECK(box(o, d, 0.0f, 4.1f, unit, &tn) && tn == 4.0f, "tmax inside the box: entry %g",
          (double)tn);
    CHECK(box(o, d, 5.0f, INFINITY, unit, &tn) && tn == 5.0f, "tmin inside the box: entry %g",
          (double)tn);
    CHECK(!box(o, d, 6.1f, INFINITY, unit, &tn), "tmin beyond the box: hit");

    /* Flat boxes of zero thickness, crossed straight and obliquely, and missed. */
    tr_aabb flat = aabb(v3(-1.0f, -1.0f, 0.0f), v3(1.0f, 1.0f, 0.0f));
    CHECK(box(v3(0.2f, 0.3f, -1.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY, flat, &tn) && tn == 1.0f,
          "flat box crossed along z: entry %g", (double)tn);
    CHECK(
        box(v3(0.2f, 0.3f, 2.0f), v3_normalize(v3(0.3f, -0.2f, -1.0f)), 0.0f, INFINITY, flat, &tn),
        "flat box crossed obliquely: missed");
    CHECK(!box(v3(1.5f, 0.3f, -1.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY, flat, &tn),
          "flat box: ray beside it hits");
    tr_aabb line = aabb(v3(-1.0f, 0.0f, 0.0f), v3(1.0f, 0.0f, 0.0f));
    CHECK(
        box(v3(0.5f, -1.0f, -1.0f), v3_normalize(v3(0.0f, 1.0f, 1.0f)), 0.0f, INFINITY, line, &tn),
        "a box degenerate to a segment, crossed exactly: missed");
    tr_aabb point = aabb(v3(1.0f, 2.0f, 3.0f), v3(1.0f, 2.0f, 3.0f));
    CHECK(box(v3(1.0f, 2.0f, 0.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY, point, &tn) && tn == 3.0f,
          "a point box on the ray: entry %g", (double)tn);
}

/* Liang-Barsky: clip the parameter interval [tmin, tmax] of o + t d against the six
 * half-spaces of the closed box, in double. Returns whether anything is left. */
static int ref_box(dvec o, dvec d, double tmin, double tmax, dvec lo, dvec hi, double *t_enter) {
    const double oc[3] = {o.x, o.y, o.z}, dc[3] = {d.x, d.y, d.z};
    const double lc[3] = {lo.x, lo.y, lo.z}, hc[3] = {hi.x, hi.y, hi.z};
    double t0 = tmin, t1 = tmax;
    for (int k = 0; k < 3; ++k) {
        /* Each plane as p . t <= q: -d t <= o - lo, and d t <= hi - o. */
        const double p[2] = {-dc[k], dc[k]}, q[2] = {oc[k] - lc[k], hc[k] - oc[k]};
        for (int j = 0; j < 2; ++j) {
            if (p[j] == 0.0) {
                if (q[j] < 0.0) {
                    return 0;
                }
            } else if (p[j] < 0.0) {
                t0 = fmax(t0, q[j] / p[j]);
            } else {
                t1 = fmin(t1, q[j] / p[j]);
            }
        }
    }
    *t_enter = t0;
    return t0 <= t1;
}

/* Whether the answer is the same for every box within delta of this one: grown by
 * delta on all sides with the interval widened (a miss there is a robust miss), or
 * shrunk by delta with the interval narrowed, a thin axis becoming a plane that is
 * moved by +-delta independently of the others (a hit in all such boxes is a robust
 * hit; a ray through a box that is a segment or a point never is one). */
static int ref_box_robust(dvec o, dvec d, double tmin, double tmax, dvec lo, dvec hi, double delta,
                          int *hit) {
    double l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z}, unused;
    double dt0 = delta * (1.0 + fabs(tmin)), dt1 = delta * (1.0 + fabs(tmax));
    dvec gl = {l[0] - delta, l[1] - delta, l[2] - delta};
    dvec gh = {h[0] + delta, h[1] + delta, h[2] + delta};
    if (!ref_box(o, d, tmin - dt0, isinf(tmax) ? tmax : tmax + dt1, gl, gh, &unused)) {
        *hit = 0;
        return 1;
    }
    for (int mask = 0; mask < 8; ++mask) {
        double sl[3], sh[3];
        for (int k = 0; k < 3; ++k) {
            if (h[k] - l[k] > 2.0 * delta) {
                sl[k] = l[k] + delta;
                sh[k] = h[k] - delta;
            } else {
                sl[k] = sh[k] = 0.5 * (l[k] + h[k]) + ((mask >> k) & 1 ? delta : -delta);
            }
        }
        dvec pl = {sl[0], sl[1], sl[2]}, ph = {sh[0], sh[1], sh[2]};
        if (!ref_box(o, d, tmin + dt0, isinf(tmax) ? tmax : tmax - dt1, pl, ph, &unused)) {
            return 0;
        }
    }
    *hit = 1;
    return 1;
}

static float rand_component(tr_rng *r) {
    float u = tr_rng_float(r);
    float x = frand(r, -1.0f, 1.0f);
    if (u < 0.06f) {
        return 0.0f;
    }
    if (u < 0.12f) {
        return -0.0f;
    }
    if (u < 0.15f) {
        return x * 1e-6f; /* nearly parallel: a huge but finite reciprocal */
    }
    if (u < 0.16f) {
        return x * 1e-39f; /* subnormal: the reciprocal overflows to infinity */
    }
    return x;
}

/* Random boxes (some flat) and rays (some along axes, some aimed at the box). */
static void test_aabb_random(void) {
    enum { N = 100000 };
    tr_rng rng;
    tr_rng_init(&rng, 11, 0, 0);
    int compared = 0, skipped = 0, mismatched = 0, hits = 0, bad_entry = 0, inconsistent = 0;
    double worst_entry = 0.0;
    for (int i = 0; i < N; ++i) {
        tr_vec3 center = vrand(&rng, -2.0f, 2.0f), half = vrand(&rng, 0.0f, 1.5f);
        if (tr_rng_float(&rng) < 0.1f) {
            half.x = 0.0f;
        }
        if (tr_rng_float(&rng) < 0.1f) {
            half.z = 0.0f;
        }
        tr_aabb bx = aabb(v3_sub(center, half), v3_add(center, half));
        tr_vec3 o = vrand(&rng, -4.0f, 4.0f);
        tr_vec3 d;
        if (tr_rng_float(&rng) < 0.5f) {
            tr_vec3 target = v3_add(center, v3_mul(half, vrand(&rng, -1.2f, 1.2f)));
            d = v3_sub(target, o);
            if (tr_rng_float(&rng) < 0.3f) {
                d.y = tr_rng_float(&rng) < 0.5f ? 0.0f : -0.0f;
            }
        } else {
            d = v3(rand_component(&rng), rand_component(&rng), rand_component(&rng));
        }
        /* A ray needs a direction: with all three reciprocals infinite the slab test
         * reports a hit at t = inf for some origins outside the box. */
        if (fmaxf(fabsf(d.x), fmaxf(fabsf(d.y), fabsf(d.z))) < 1e-3f) {
            d.x = 1.0f;
        }
        float tmin = tr_rng_float(&rng) < 0.2f ? frand(&rng, -1.0f, 3.0f) : 0.0f;
        float tmax = tr_rng_float(&rng) < 0.4f ? frand(&rng, 0.0f, 8.0f) : INFINITY;

        dvec od = dv(o), dd = dv(d), lo = dv(bx.min), hi = dv(bx.max);
        /* 100 times the float error of the slab test here (mismatches appear at 1e-7). */
        const double delta = 1e-5;
        int want;
        if (!ref_box_robust(od, dd, tmin, tmax, lo, hi, delta, &want)) {
            ++skipped;
            continue;
        }
        double t_enter;
        int plain = ref_box(od, dd, tmin, tmax, lo, hi, &t_enter);
        inconsistent += plain != want;
        float tn;
        int got = box(o, d, tmin, tmax, bx, &tn);
        ++compared;
        hits += want;
        if (got != want) {
            if (mismatched < 5) {
                fprintf(
                    stderr,
                    "aabb case %d: got %d want %d: o (%a %a %a) d (%a %a %a) box (%a %a %a)-(%a "
                    "%a %a) t (%a %a)\n",
                    i, got, want, (double)o.x, (double)o.y, (double)o.z, (double)d.x, (double)d.y,
                    (double)d.z, (double)bx.min.x, (double)bx.min.y, (double)bx.min.z,
                    (double)bx.max.x, (double)bx.max.y, (double)bx.max.z, (double)tmin,
                    (double)tmax);
            }
            ++mismatched;
            continue;
        }
        if (got) {
            /* The entry is a product of two rounded floats: a few ulps of itself. */
            double e = fabs(tn - t_enter) / (1.0 + fabs(t_enter));
            worst_entry = fmax(worst_entry, e);
            bad_entry += e > 1e-5;
        }
    }
    printf("boxes: %d of %d random cases compared (%d within 1e-5 of grazing skipped), %d hits, "
           "%d mismatches, worst entry error %.2g\n",
           compared, N, skipped, hits, mismatched, worst_entry);
    CHECK(inconsistent == 0, "the reference contradicts its perturbations %d times", inconsistent);
    CHECK(mismatched == 0, "%d of %d random box cases disagree with the reference", mismatched,
          compared);
    CHECK(bad_entry == 0, "%d hits with an entry distance off the reference", bad_entry);
    CHECK(skipped < N / 100 && hits > compared / 5 && hits < compared * 4 / 5,
          "random box cases are unbalanced: %d skipped, %d hits of %d", skipped, hits, compared);
}

int main(void) {
    test_triangle_hits();
    test_triangle_edges_and_vertices();
    test_triangle_parallel_and_limits();
    test_triangle_degenerate();
    test_triangle_random();
    test_aabb_cases();
    test_aabb_random();
    return check_finish("test_intersect");
}
