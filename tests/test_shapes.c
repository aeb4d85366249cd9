/* test_shapes.c - the shape generators of src/scene/shape.c, through tr_scene_add_shape.
 *
 * Geometry is recomputed in double from the stored float vertices, and transforms are
 * re-derived from an independent double-precision rotation matrix R = Rz * Ry * Rx, so
 * that the tolerances below only have to cover float rounding of the generator:
 * a handful of ulps (FLT_EPSILON ~ 1.2e-7) per operation on values of order one. */
#include "check.h"
#include "dvec.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define PI_D 3.14159265358979323846

static double fcomp(tr_vec3 a, int axis) {
    return axis == 0 ? a.x : axis == 1 ? a.y : a.z;
}

/* The documented transform, written independently of shape.c: scale, then
 * R = Rz(c) * Ry(b) * Rx(a) with right-handed rotations, then translate. */
static dvec transform_point(dvec p, tr_vec3 pos, tr_vec3 rot, tr_vec3 scale) {
    double m[3][3];
    double ca = cos(rot.x), sa = sin(rot.x), cb = cos(rot.y), sb = sin(rot.y);
    double cc = cos(rot.z), sc = sin(rot.z);
    /* Rz * Ry * Rx, multiplied out. */
    m[0][0] = cc * cb;
    m[0][1] = cc * sb * sa - sc * ca;
    m[0][2] = cc * sb * ca + sc * sa;
    m[1][0] = sc * cb;
    m[1][1] = sc * sb * sa + cc * ca;
    m[1][2] = sc * sb * ca - cc * sa;
    m[2][0] = -sb;
    m[2][1] = cb * sa;
    m[2][2] = cb * ca;
    double q[3] = {p.x * scale.x, p.y * scale.y, p.z * scale.z};
    dvec r = {m[0][0] * q[0] + m[0][1] * q[1] + m[0][2] * q[2] + pos.x,
              m[1][0] * q[0] + m[1][1] * q[1] + m[1][2] * q[2] + pos.y,
              m[2][0] * q[0] + m[2][1] * q[1] + m[2][2] * q[2] + pos.z};
    return r;
}

static tr_shape_desc make_desc(tr_shape_type type, tr_vec3 pos, tr_vec3 rot, tr_vec3 scale,
                               uint32_t subdivisions, uint32_t material) {
    tr_shape_desc d = tr_shape_desc_default(type);
    d.transform.position = pos;
    d.transform.orientation = rot;
    d.transform.scale = scale;
    d.subdivisions = subdivisions;
    d.material = material;
    return d;
}

/* A scene with `n` diffuse materials of distinct colours. */
static void scene_with_materials(tr_scene *s, uint32_t n) {
    tr_scene_init(s);
    for (uint32_t i = 0; i < n; ++i) {
        tr_error err;
        uint32_t idx = 99;
        int rc =
            tr_scene_add_material(s, tr_material_diffuse(v3s(0.1f * (float)(i + 1))), &idx, &err);
        CHECK(rc == TR_OK && idx == i, "adding material %u failed", i);
    }
}

static tr_vec3 tri_vertex(const tr_triangle *t, int k) {
    return k == 0 ? t->v0 : k == 1 ? t->v1 : t->v2;
}

/* Sum of the stored triangle areas of shape `i`, in double. */
static double shape_area(const tr_scene *s, uint32_t i) {
    double a = 0.0;
    const tr_flat_node *node = &s->shapes[i];
    for (uint32_t t = node->first; t < node->first + node->count; ++t) {
        a += s->triangles[t].area;
    }
    return a;
}

/* Checks that hold for every shape: unit normals consistent with the winding, areas equal
 * to 0.5 |(v1 - v0) x (v2 - v0)| recomputed in double, the material index, and a box that
 * contains every vertex and touches one on each of its six faces. With `outward`, also
 * that every normal points away from `center` (closed convex shapes). */
static void check_shape(const tr_scene *s, uint32_t i, dvec center, int outward, uint32_t material,
                        const char *label) {
    const tr_flat_node *node = &s->shapes[i];
    CHECK(node->count > 0 && node->first + node->count <= s->triangle_count,
          "%s: triangle run [%u, +%u) outside the %u triangles", label, node->first, node->count,
          s->triangle_count);
    tr_aabb box = node->box;
    /* Tightness tolerance: 1e-6 relative to the box's magnitude (the box is built from the
     * same floats, so it should in fact be exact). */
    double mag = 0.0;
    for (int a = 0; a < 3; ++a) {
        mag = fmax(mag, fmax(fabs(fcomp(box.min, a)), fabs(fcomp(box.max, a))));
    }
    double tight_tol = 1e-6 * fmax(mag, 1e-30);
    int touch_min[3] = {0, 0, 0}, touch_max[3] = {0, 0, 0};
    int bad_unit = 0, bad_wind = 0, bad_area = 0, bad_out = 0, bad_box = 0, bad_mat = 0;
    double worst_unit = 0.0, worst_area = 0.0, worst_wind = 0.0;
    for (uint32_t t = node->first; t < node->first + node->count; ++t) {
        const tr_triangle *tri = &s->triangles[t];
        dvec v0 = dv(tri->v0), v1 = dv(tri->v1), v2 = dv(tri->v2);
        dvec c = dcross(dsub(v1, v0), dsub(v2, v0));
        double clen = dlen(c);
        dvec n = dv(tri->normal);
        /* A float normalisation is good to a few ulps. */
        double unit_err = fabs(dlen(n) - 1.0);
        worst_unit = fmax(worst_unit, unit_err);
        bad_unit += !(unit_err < 1e-6);
        /* The stored normal is the normalised cross product: the angle to the double
         * cross product is float rounding only (1e-5 rad covers ill-conditioned slivers
         * far worse than any generated triangle). */
        double wind = clen > 0.0 ? dlen(dcross(n, c)) / clen : 1.0;
        worst_wind = fmax(worst_wind, wind);
        bad_wind += !(wind < 1e-5 && ddot(n, c) > 0.0);
        /* Area: a float cross product of float differences, relative error ~ a few eps. */
        double area_err = fabs((double)tri->area - 0.5 * clen) / (0.5 * clen);
        worst_area = fmax(worst_area, area_err);
        bad_area += !(area_err < 1e-5);
        if (outward) {
            dvec centroid = {(v0.x + v1.x + v2.x) / 3.0, (v0.y + v1.y + v2.y) / 3.0,
                             (v0.z + v1.z + v2.z) / 3.0};
            bad_out += !(ddot(n, dsub(centroid, center)) > 0.0);
        }
        bad_mat += tri->material != material;
        for (int k = 0; k < 3; ++k) {
            tr_vec3 v = tri_vertex(tri, k);
            for (int a = 0; a < 3; ++a) {
                double x = fcomp(v, a), lo = fcomp(box.min, a), hi = fcomp(box.max, a);
                bad_box += !(x >= lo && x <= hi);
                touch_min[a] |= x - lo <= tight_tol;
                touch_max[a] |= hi - x <= tight_tol;
            }
        }
    }
    CHECK(bad_unit == 0, "%s: %d normals not unit (worst |n|-1 = %.3g)", label, bad_unit,
          worst_unit);
    CHECK(bad_wind == 0, "%s: %d normals disagree with the winding (worst sin = %.3g)", label,
          bad_wind, worst_wind);
    CHECK(bad_area == 0, "%s: %d areas differ from 0.5|cross| (worst rel = %.3g)", label, bad_area,
          worst_area);
    CHECK(bad_out == 0, "%s: %d of %u normals point inward", label, bad_out, node->count);
    CHECK(bad_mat == 0, "%s: %d triangles with a material other than %u", label, bad_mat, material);
    CHECK(bad_box == 0, "%s: %d vertex coordinates outside the shape's box", label, bad_box);
    for (int a = 0; a < 3; ++a) {
        CHECK(touch_min[a] && touch_max[a], "%s: box is not tight on axis %d ([%g, %g])", label, a,
              fcomp(box.min, a), fcomp(box.max, a));
    }
}

/* Icospheres: 20 * 4^n triangles, all vertices on the sphere, outward normals, and a
 * total area that grows monotonically towards 4 pi r^2 from below. */
static void test_icosphere(void) {
    const tr_vec3 pos = v3(0.3f, -1.2f, 2.0f), rot = v3(0.3f, 0.7f, -1.1f);
    const float r = 2.5f;
    const double sphere_area = 4.0 * PI_D * (double)r * (double)r;
    double prev_area = 0.0, prev_deficit = 0.0;
    for (uint32_t n = 0; n <= 5; ++n) {
        tr_scene s = {0};
        scene_with_materials(&s, 1);
        tr_shape_desc d = make_desc(TR_SHAPE_ICOSPHERE, pos, rot, v3s(r), n, 0);
        tr_error err;
        err.msg[0] = '\0';
        int rc = tr_scene_add_shape(&s, &d, &err);
        CHECK(rc == TR_OK, "icosphere n=%u rejected: %s", n, err.msg);
        uint64_t expect = 20ull;
        for (uint32_t k = 0; k < n; ++k) {
            expect *= 4ull;
        }
        CHECK(tr_shape_triangle_count(&d) == expect, "n=%u: tr_shape_triangle_count %llu != %llu",
              n, (unsigned long long)tr_shape_triangle_count(&d), (unsigned long long)expect);
        CHECK(s.triangle_count == expect && s.shape_count == 1 && s.shapes[0].first == 0 &&
                  s.shapes[0].count == expect,
              "n=%u: %u triangles / %u shapes, run (%u, %u); expected %llu", n, s.triangle_count,
              s.shape_count, s.shape_count ? s.shapes[0].first : 0,
              s.shape_count ? s.shapes[0].count : 0, (unsigned long long)expect);
        if (rc != TR_OK || s.triangle_count != expect) {
            tr_scene_clear(&s);
            continue;
        }
        /* Every vertex at the radius: the unit vertices are normalised in float (a few
         * ulps), then scaled, rotated and translated by values of order one; 1e-5 relative
         * leaves a margin of ~50 ulps. */
        dvec c = dv(pos);
        double worst = 0.0;
        for (uint32_t t = 0; t < s.triangle_count; ++t) {
            for (int k = 0; k < 3; ++k) {
                double dist = dlen(dsub(dv(tri_vertex(&s.triangles[t], k)), c));
                worst = fmax(worst, fabs(dist - (double)r) / (double)r);
            }
        }
        CHECK(worst < 1e-5, "n=%u: vertex off the sphere by %.3g relative", n, worst);
        char label[64];
        snprintf(label, sizeof label, "icosphere n=%u", n);
        check_shape(&s, 0, c, 1, 0, label);

        /* Inscribed polyhedra: the area is below the sphere's and grows with n. */
        double area = shape_area(&s, 0);
        CHECK(area < sphere_area, "n=%u: area %.9g not below 4 pi r^2 = %.9g", n, area,
              sphere_area);
        CHECK(area > prev_area, "n=%u: area %.9g did not grow (previous %.9g)", n, area, prev_area);
        /* The deficit of an inscribed mesh is second order in the edge length, which
         * halves per level: it must shrink by a factor near 4 (3..5 allows for the
         * non-uniform triangles of the first levels). */
        double deficit = (sphere_area - area) / sphere_area;
        if (n >= 2) {
            CHECK(prev_deficit / deficit > 3.0 && prev_deficit / deficit < 5.0,
                  "n=%u: area deficit %.4g vs %.4g at n-1 is not second-order convergence", n,
                  deficit, prev_deficit);
        }
        printf("icosphere n=%u: %u triangles, radius err %.2g, area %.6f / 4 pi r^2 %.6f "
               "(deficit %.3g)\n",
               n, s.triangle_count, worst, area, sphere_area, deficit);
        prev_area = area;
        prev_deficit = deficit;
        tr_scene_clear(&s);
    }
}

/* The 8 corners of the unit cube transformed in double must be exactly the vertex set. */
static void check_box_corners(const tr_scene *s, uint32_t i, tr_vec3 pos, tr_vec3 rot,
                              tr_vec3 scale, const char *label) {
    dvec corners[8];
    for (int k = 0; k < 8; ++k) {
        dvec p = {(k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5};
        corners[k] = transform_point(p, pos, rot, scale);
    }
    /* Float rotation of values of order one: 1e-5 absolute is ~100 ulps. */
    const double tol = 1e-5;
    int used[8] = {0};
    int stray = 0;
    const tr_flat_node *node = &s->shapes[i];
    for (uint32_t t = node->first; t < node->first + node->count; ++t) {
        for (int k = 0; k < 3; ++k) {
            dvec v = dv(tri_vertex(&s->triangles[t], k));
            int found = 0;
            for (int j = 0; j < 8; ++j) {
                if (dlen(dsub(v, corners[j])) < tol) {
                    used[j] = found = 1;
                }
            }
            stray += !found;
        }
    }
    int all = 1;
    for (int j = 0; j < 8; ++j) {
        all &= used[j];
    }
    CHECK(stray == 0 && all, "%s: %d vertices are not transformed cube corners (all used: %d)",
          label, stray, all);
}

/* Boxes: 12 triangles, outward normals, area 2(ab + bc + ca), corners where the documented
 * transform puts them; unrotated and rotated about all three axes. */
static void test_box(void) {
    const struct {
        tr_vec3 pos, rot, scale;
        const char *label;
    } cases[] = {
        {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 1.0f}, "unit box"},
        {{1.5f, -0.25f, 3.0f}, {0.0f, 0.0f, 0.0f}, {0.7f, 1.9f, 0.3f}, "axis-aligned box"},
        {{-0.4f, 0.8f, 1.1f}, {0.4f, -0.9f, 1.3f}, {0.7f, 1.9f, 0.3f}, "rotated box"},
        {{2.0f, 1.0f, -3.0f}, {2.5f, 0.6f, -2.2f}, {4.0f, 0.05f, 1.5f}, "rotated flat box"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        tr_scene s = {0};
        scene_with_materials(&s, 2);
        tr_shape_desc d = make_desc(TR_SHAPE_BOX, cases[c].pos, cases[c].rot, cases[c].scale, 0, 1);
        tr_error err;
        err.msg[0] = '\0';
        int rc = tr_scene_add_shape(&s, &d, &err);
        CHECK(rc == TR_OK, "%s rejected: %s", cases[c].label, err.msg);
        CHECK(tr_shape_triangle_count(&d) == 12 && s.triangle_count == 12 && s.shape_count == 1,
              "%s: %u triangles, %u shapes", cases[c].label, s.triangle_count, s.shape_count);
        if (rc != TR_OK || s.triangle_count != 12) {
            tr_scene_clear(&s);
            continue;
        }
        check_shape(&s, 0, dv(cases[c].pos), 1, 1, cases[c].label);
        check_box_corners(&s, 0, cases[c].pos, cases[c].rot, cases[c].scale, cases[c].label);
        double a = cases[c].scale.x, b = cases[c].scale.y, cc = cases[c].scale.z;
        double expect = 2.0 * (a * b + b * cc + cc * a);
        /* Sum of 12 float areas, each good to ~1e-6 relative. */
        CHECK_NEAR(shape_area(&s, 0), expect, 1e-5 * expect, cases[c].label);
        tr_scene_clear(&s);
    }
}

/* Planes: 2 triangles whose normal is the rotated +y, area size_x * size_z. */
static void test_plane(void) {
    const struct {
        tr_vec3 pos, rot, scale;
        const char *label;
    } cases[] = {
        {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, {1.0f, 1.0f, 1.0f}, "unit plane"},
        {{0.5f, 2.0f, -1.0f}, {0.5f, 0.2f, -0.8f}, {3.0f, 1.0f, 0.5f}, "rotated plane"},
        {{-2.0f, 0.0f, 4.0f}, {3.0f, -1.2f, 0.4f}, {0.25f, 7.0f, 6.0f}, "flipped plane"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        tr_scene s = {0};
        scene_with_materials(&s, 1);
        tr_shape_desc d =
            make_desc(TR_SHAPE_PLANE, cases[c].pos, cases[c].rot, cases[c].scale, 0, 0);
        tr_error err;
        err.msg[0] = '\0';
        int rc = tr_scene_add_shape(&s, &d, &err);
        CHECK(rc == TR_OK, "%s rejected: %s", cases[c].label, err.msg);
        CHECK(tr_shape_triangle_count(&d) == 2 && s.triangle_count == 2 && s.shape_count == 1,
              "%s: %u triangles, %u shapes", cases[c].label, s.triangle_count, s.shape_count);
        if (rc != TR_OK || s.triangle_count != 2) {
            tr_scene_clear(&s);
            continue;
        }
        check_shape(&s, 0, dv(cases[c].pos), 0, 0, cases[c].label);
        /* The rotated +y: R applied to a direction (no scale, no translation). */
        dvec up = {0.0, 1.0, 0.0};
        dvec n = transform_point(up, v3s(0.0f), cases[c].rot, v3s(1.0f));
        for (int t = 0; t < 2; ++t) {
            double dev = dlen(dsub(dv(s.triangles[t].normal), n));
            CHECK(dev < 1e-5, "%s: triangle %d normal is %.3g away from the rotated +y",
                  cases[c].label, t, dev);
        }
        double expect = (double)cases[c].scale.x * (double)cases[c].scale.z;
        CHECK_NEAR(shape_area(&s, 0), expect, 1e-5 * expect, cases[c].label);
        tr_scene_clear(&s);
    }
}

/* Several shapes in one scene: runs are contiguous, in order, and cover every triangle. */
static void test_runs(void) {
    tr_scene s = {0};
    scene_with_materials(&s, 4);
    tr_shape_desc descs[] = {
        make_desc(TR_SHAPE_PLANE, v3(0, -1, 0), v3(0, 0, 0), v3(4, 1, 4), 0, 3),
        make_desc(TR_SHAPE_BOX, v3(1, 0, 0), v3(0.1f, 0.2f, 0.3f), v3(1, 2, 3), 0, 1),
        make_desc(TR_SHAPE_ICOSPHERE, v3(-1, 0.5f, 0), v3(0, 0, 0), v3s(0.5f), 2, 2),
        make_desc(TR_SHAPE_BOX, v3(0, 3, 1), v3(0, 0, 0), v3(0.5f, 0.5f, 0.5f), 0, 0),
        make_desc(TR_SHAPE_ICOSPHERE, v3(2, 2, 2), v3(1, 2, 3), v3s(0.25f), 0, 3),
    };
    const uint32_t nd = (uint32_t)(sizeof descs / sizeof descs[0]);
    uint32_t expect_total = 0;
    for (uint32_t i = 0; i < nd; ++i) {
        tr_error err;
        err.msg[0] = '\0';
        CHECK(tr_scene_add_shape(&s, &descs[i], &err) == TR_OK, "shape %u rejected: %s", i,
              err.msg);
        expect_total += (uint32_t)tr_shape_triangle_count(&descs[i]);
    }
    CHECK(s.shape_count == nd, "%u shapes, expected %u", s.shape_count, nd);
    CHECK(s.triangle_count == expect_total, "%u triangles, expected %u", s.triangle_count,
          expect_total);
    uint32_t next = 0;
    for (uint32_t i = 0; i < s.shape_count && i < nd; ++i) {
        CHECK(s.shapes[i].first == next, "shape %u starts at %u, expected %u", i, s.shapes[i].first,
              next);
        CHECK(s.shapes[i].count == tr_shape_triangle_count(&descs[i]),
              "shape %u has %u triangles, expected %llu", i, s.shapes[i].count,
              (unsigned long long)tr_shape_triangle_count(&descs[i]));
        char label[32];
        snprintf(label, sizeof label, "scene shape %u", i);
        /* The plane (shape 0) is open; every other shape is closed and convex. */
        check_shape(&s, i, dv(descs[i].transform.position), i != 0, descs[i].material, label);
        next = s.shapes[i].first + s.shapes[i].count;
    }
    CHECK(next == s.triangle_count, "runs end at %u of %u triangles", next, s.triangle_count);
    tr_scene_clear(&s);
}

/* A rejected descriptor returns TR_ERR with a message and leaves every array as it was. */
static void test_rejects(void) {
    tr_scene s = {0};
    scene_with_materials(&s, 2);
    tr_error err;
    tr_shape_desc good = make_desc(TR_SHAPE_BOX, v3(0, 0, 0), v3(0, 0, 0), v3s(1.0f), 0, 1);
    CHECK(tr_scene_add_shape(&s, &good, &err) == TR_OK, "reference box rejected: %s", err.msg);

    const uint32_t tri_n = s.triangle_count, shape_n = s.shape_count, mat_n = s.material_count;
    tr_triangle *tri_copy = malloc((size_t)tri_n * sizeof *tri_copy);
    tr_flat_node *shape_copy = malloc((size_t)shape_n * sizeof *shape_copy);
    tr_material *mat_copy = malloc((size_t)mat_n * sizeof *mat_copy);
    CHECK(tri_copy && shape_copy && mat_copy, "out of memory");
    if (!tri_copy || !shape_copy || !mat_copy) {
        free(tri_copy);
        free(shape_copy);
        free(mat_copy);
        tr_scene_clear(&s);
        return;
    }
    memcpy(tri_copy, s.triangles, (size_t)tri_n * sizeof *tri_copy);
    memcpy(shape_copy, s.shapes, (size_t)shape_n * sizeof *shape_copy);
    memcpy(mat_copy, s.materials, (size_t)mat_n * sizeof *mat_copy);

    const float nan = NAN, inf = INFINITY;
    tr_shape_desc bad[20];
    const char *what[20];
    tr_status want[20];
    int nb = 0;
    const tr_vec3 zero = v3s(0.0f), one = v3s(1.0f);
    bad[nb] = make_desc(TR_SHAPE_ICOSPHERE, zero, zero, one, TR_ICOSPHERE_MAX_SUBDIVISIONS + 1, 0);
    what[nb] = "subdivisions = max + 1";
    want[nb++] = TR_STATUS_LIMIT;
    bad[nb] = make_desc(TR_SHAPE_ICOSPHERE, zero, zero, one, 1000, 0);
    what[nb] = "subdivisions = 1000";
    want[nb++] = TR_STATUS_LIMIT;
    bad[nb] = make_desc(TR_SHAPE_ICOSPHERE, zero, zero, v3s(0.0f), 1, 0);
    what[nb] = "icosphere radius 0";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;
    bad[nb] = make_desc(TR_SHAPE_BOX, zero, zero, v3(1, 0, 1), 0, 0);
    what[nb] = "zero scale";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;
    bad[nb] = make_desc(TR_SHAPE_BOX, zero, zero, v3(-1, 1, 1), 0, 0);
    what[nb] = "negative scale";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;
    bad[nb] = make_desc(TR_SHAPE_ICOSPHERE, zero, zero, v3s(-2.0f), 1, 0);
    what[nb] = "negative radius";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;
    bad[nb] = make_desc(TR_SHAPE_PLANE, zero, zero, v3(1, 1, nan), 0, 0);
    what[nb] = "NaN scale";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;
    bad[nb] = make_desc(TR_SHAPE_BOX, zero, zero, v3(inf, 1, 1), 0, 0);
    what[nb] = "infinite scale";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;
    bad[nb] = make_desc(TR_SHAPE_BOX, v3(0, nan, 0), zero, one, 0, 0);
    what[nb] = "NaN position";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;
    bad[nb] = make_desc(TR_SHAPE_BOX, v3(-inf, 0, 0), zero, one, 0, 0);
    what[nb] = "infinite position";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;
    bad[nb] = make_desc(TR_SHAPE_BOX, zero, v3(0, 0, nan), one, 0, 0);
    what[nb] = "NaN orientation";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;
    bad[nb] = make_desc(TR_SHAPE_BOX, zero, zero, one, 0, 2);
    what[nb] = "material == material count";
    want[nb++] = TR_STATUS_NOT_FOUND;
    bad[nb] = make_desc(TR_SHAPE_PLANE, zero, zero, one, 0, UINT32_MAX);
    what[nb] = "material UINT32_MAX";
    want[nb++] = TR_STATUS_NOT_FOUND;
    bad[nb] = make_desc((tr_shape_type)0, zero, zero, one, 0, 0);
    what[nb] = "type 0";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;
    bad[nb] = make_desc((tr_shape_type)99, zero, zero, one, 0, 0);
    what[nb] = "type 99";
    want[nb++] = TR_STATUS_INVALID_ARGUMENT;

    for (int i = 0; i < nb; ++i) {
        memset(err.msg, 0, sizeof err.msg);
        int rc = tr_scene_add_shape(&s, &bad[i], &err);
        CHECK_STATUS(rc, err, want[i], what[i]);
        CHECK(err.msg[0] != '\0', "%s: rejected without a message", what[i]);
        int same = s.triangle_count == tri_n && s.shape_count == shape_n &&
                   s.material_count == mat_n &&
                   memcmp(s.triangles, tri_copy, (size_t)tri_n * sizeof *tri_copy) == 0 &&
                   memcmp(s.shapes, shape_copy, (size_t)shape_n * sizeof *shape_copy) == 0 &&
                   memcmp(s.materials, mat_copy, (size_t)mat_n * sizeof *mat_copy) == 0;
        CHECK(same, "%s: the scene changed (%u triangles, %u shapes)", what[i], s.triangle_count,
              s.shape_count);
        /* A NULL error pointer is allowed and must not crash. */
        CHECK(tr_scene_add_shape(&s, &bad[i], NULL) == TR_ERR, "%s: accepted with err = NULL",
              what[i]);
    }
    /* Descriptions the generator cannot make have no triangle count. */
    CHECK(tr_shape_triangle_count(&bad[0]) == 0, "too many subdivisions counted %llu triangles",
          (unsigned long long)tr_shape_triangle_count(&bad[0]));
    CHECK(tr_shape_triangle_count(&bad[nb - 1]) == 0, "unknown type counted %llu triangles",
          (unsigned long long)tr_shape_triangle_count(&bad[nb - 1]));

    /* The scene still accepts a valid shape afterwards. */
    CHECK(tr_scene_add_shape(&s, &good, &err) == TR_OK && s.shape_count == shape_n + 1 &&
              s.triangle_count == tri_n + 12,
          "valid box after the rejections: %u shapes, %u triangles", s.shape_count,
          s.triangle_count);
    free(tri_copy);
    free(shape_copy);
    free(mat_copy);
    tr_scene_clear(&s);
}

/* The thesis's Cornell scene (listing 16). */
static void test_cornell(void) {
    tr_scene s = {0};
    tr_error err;
    err.msg[0] = '\0';
    int rc = tr_scene_builtin(&s, "cornell", 800, 600, &err);
    CHECK(rc == TR_OK, "cornell: %s", err.msg);
    if (rc != TR_OK) {
        return;
    }
    CHECK(s.shape_count == 10, "cornell has %u shapes, expected 10", s.shape_count);
    CHECK(s.material_count == 6, "cornell has %u materials, expected 6", s.material_count);
    /* 5 walls and the lamp are planes, two boxes, two icospheres with 2 subdivisions. */
    const uint32_t expect = 5 * 2 + 2 + 2 * 12 + 2 * 320;
    CHECK(s.triangle_count == expect, "cornell has %u triangles, expected %u", s.triangle_count,
          expect);
    uint32_t next = 0;
    for (uint32_t i = 0; i < s.shape_count; ++i) {
        CHECK(s.shapes[i].first == next, "cornell shape %u starts at %u, expected %u", i,
              s.shapes[i].first, next);
        next = s.shapes[i].first + s.shapes[i].count;
    }
    CHECK(next == s.triangle_count, "cornell runs end at %u of %u", next, s.triangle_count);
    CHECK(s.camera.screen_width == 800 && s.camera.screen_height == 600, "cornell camera is %ux%u",
          s.camera.screen_width, s.camera.screen_height);

    if (s.shape_count >= 1 && s.shapes[0].count == 2) {
        /* Left wall: the red diffuse material. */
        const tr_triangle *t = &s.triangles[s.shapes[0].first];
        uint32_t m = t[0].material;
        CHECK(t[1].material == m && m < s.material_count, "left wall materials %u, %u",
              t[0].material, t[1].material);
        if (m < s.material_count) {
            const tr_material *red = &s.materials[m];
            CHECK(red->type == TR_MATERIAL_DIFFUSE && red->color.x == 0.366046f &&
                      red->color.y == 0.0371827f && red->color.z == 0.0416385f,
                  "left wall material type %u colour (%g, %g, %g) is not the thesis's red",
                  red->type, (double)red->color.x, (double)red->color.y, (double)red->color.z);
        }
        /* Spans x = -0.5, y in [-0.1, 0.9], z in [-0.5, 0.5]; cos(pi/2) in float is
         * ~4e-8, so the flat axis is -0.5 to within 1e-6. */
        tr_aabb b = s.shapes[0].box;
        CHECK_NEAR(b.min.x, -0.5, 1e-6, "left wall min x");
        CHECK_NEAR(b.max.x, -0.5, 1e-6, "left wall max x");
        CHECK_NEAR(b.min.y, -0.1, 1e-6, "left wall min y");
        CHECK_NEAR(b.max.y, 0.9, 1e-6, "left wall max y");
        CHECK_NEAR(b.min.z, -0.5, 1e-6, "left wall min z");
        CHECK_NEAR(b.max.z, 0.5, 1e-6, "left wall max z");
        /* Its normal faces into the room (+x). */
        CHECK(t[0].normal.x > 0.999f && t[1].normal.x > 0.999f,
              "left wall normals (%g, %g, %g) do not face +x", (double)t[0].normal.x,
              (double)t[0].normal.y, (double)t[0].normal.z);
    } else {
        CHECK(0, "cornell shape 0 is not a plane");
    }
    tr_scene_clear(&s);

    /* An unknown name fails with a message and leaves an empty scene. */
    CHECK_STATUS(tr_scene_builtin(&s, "no-such-scene", 64, 64, &err), err, TR_STATUS_NOT_FOUND,
                 "unknown built-in scene");
    CHECK(s.triangle_count == 0 && s.shape_count == 0 && s.triangles == NULL,
          "unknown built-in scene left %u triangles", s.triangle_count);
    tr_scene_clear(&s);
}

int main(void) {
    test_icosphere();
    test_box();
    test_plane();
    test_runs();
    test_rejects();
    test_cornell();
    return check_finish("test_shapes");
}
