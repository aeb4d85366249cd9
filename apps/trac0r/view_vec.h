/* view_vec.h - the few vector operations the viewer's camera and wireframes need.
 *
 * The library's own (src/kernel/vec.h) are private to it; these are the viewer's,
 * static so that each file that includes them has its own copy. */
#ifndef TRAC0R_VIEW_VEC_H
#define TRAC0R_VIEW_VEC_H

#include <math.h>

#include "trac0r/types.h"

static inline tr_vec3 v3(float x, float y, float z) {
    return tr_vec3_make(x, y, z);
}
static inline tr_vec3 v3_add(tr_vec3 a, tr_vec3 b) {
    return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline tr_vec3 v3_sub(tr_vec3 a, tr_vec3 b) {
    return v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline tr_vec3 v3_scale(tr_vec3 a, float s) {
    return v3(a.x * s, a.y * s, a.z * s);
}
static inline float v3_dot(tr_vec3 a, tr_vec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline tr_vec3 v3_cross(tr_vec3 a, tr_vec3 b) {
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
/* a / |a|; the zero vector stays zero. */
static inline tr_vec3 v3_normalize(tr_vec3 a) {
    const float len = sqrtf(v3_dot(a, a));
    return len > 0.0f ? v3_scale(a, 1.0f / len) : a;
}

#endif
