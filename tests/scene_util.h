/* scene_util.h - scene building for the C tests that make their own small scenes
 * (after check.h: failures are recorded with CHECK). */
#ifndef TR_TEST_SCENE_UTIL_H
#define TR_TEST_SCENE_UTIL_H

#include <math.h>

#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

/* Adds material m; returns its index. */
/* Built-in scene `name` at w x h, committed with the BVH (failures recorded with CHECK). */
static inline tr_scene *committed_builtin(const char *name, uint32_t w, uint32_t h) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s && tr_scene_builtin(s, name, w, h, &err) == TR_OK &&
              tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK,
          "%s", err.msg);
    return s;
}

static inline uint32_t add_mat(tr_scene *s, tr_material m) {
    tr_error err;
    uint32_t i = 0;
    CHECK(tr_scene_add_material(s, m, &i, &err) == TR_OK, "material: %s", err.msg);
    return i;
}

/* Adds a shape of the given type and material, placed by position, orientation (radians)
 * and scale; icospheres are subdivided twice. */
static inline void add_shape(tr_scene *s, tr_shape_type type, uint32_t mat, tr_vec3 pos,
                             tr_vec3 rot, tr_vec3 scale) {
    tr_error err;
    tr_shape_desc d = tr_shape_desc_default(type);
    d.material = mat;
    d.transform.position = pos;
    d.transform.orientation = rot;
    d.transform.scale = scale;
    d.subdivisions = 2;
    CHECK(tr_scene_add_shape(s, &d, &err) == TR_OK, "shape: %s", err.msg);
}

/* Irradiance at x, on a surface facing +y, from a polygon lamp of uniform radiance L
 * (vertices vtx[0..nv-1]): Lambert's polygon formula, the closed form the integrators'
 * one-bounce tests compare with. */
static inline double lambert_irradiance(const double (*vtx)[3], int nv, const double x[3],
                                        double L) {
    double sum = 0.0;
    for (int i = 0; i < nv; ++i) {
        const double *p0 = vtx[i], *p1 = vtx[(i + 1) % nv];
        double a[3] = {p0[0] - x[0], p0[1] - x[1], p0[2] - x[2]};
        double b[3] = {p1[0] - x[0], p1[1] - x[1], p1[2] - x[2]};
        double la = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        double lb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
        /* The y component of a x b over its length: the edge's contribution projected
         * onto the receiving normal. */
        double cy = a[2] * b[0] - a[0] * b[2];
        double cx = a[1] * b[2] - a[2] * b[1], cz = a[0] * b[1] - a[1] * b[0];
        double lc = sqrt(cx * cx + cy * cy + cz * cz);
        sum += acos((a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) / (la * lb)) * cy / lc;
    }
    return 0.5 * L * fabs(sum);
}

#endif
