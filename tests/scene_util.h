/* scene_util.h - scene building for the C tests that make their own small scenes
 * (after check.h: failures are recorded with CHECK). */
#ifndef TR_TEST_SCENE_UTIL_H
#define TR_TEST_SCENE_UTIL_H

#include "check.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

/* Adds material m; returns its index. */
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

#endif
