/* vec.h - 3-component float vectors.
 *
 * tr_vec3 is a plain struct of three floats (12 bytes) rather than OpenCL's float3
 * (16 bytes), so that arrays of it have the same layout on the host and the device; it
 * is declared in the public include/trac0r/types.h. The helpers below are the kernel's
 * own (v3, v3_add, ...): not part of the public API. */
#ifndef TR_KERNEL_VEC_H
#define TR_KERNEL_VEC_H

#include "compat.h"
#include "trac0r/types.h"
TR_STATIC_ASSERT(sizeof(tr_vec3) == 12, "tr_vec3 must be 12 bytes on host and device");

TR_FN tr_vec3 v3(float x, float y, float z) {
    tr_vec3 r;
    r.x = x;
    r.y = y;
    r.z = z;
    return r;
}
TR_FN tr_vec3 v3s(float s) {
    return v3(s, s, s);
}
TR_FN tr_vec3 v3_add(tr_vec3 a, tr_vec3 b) {
    return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
TR_FN tr_vec3 v3_sub(tr_vec3 a, tr_vec3 b) {
    return v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
TR_FN tr_vec3 v3_mul(tr_vec3 a, tr_vec3 b) {
    return v3(a.x * b.x, a.y * b.y, a.z * b.z);
}
TR_FN tr_vec3 v3_scale(tr_vec3 a, float s) {
    return v3(a.x * s, a.y * s, a.z * s);
}
/* a + b * s */
TR_FN tr_vec3 v3_madd(tr_vec3 a, tr_vec3 b, float s) {
    return v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s);
}
TR_FN tr_vec3 v3_neg(tr_vec3 a) {
    return v3(-a.x, -a.y, -a.z);
}
TR_FN float v3_dot(tr_vec3 a, tr_vec3 b) {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
TR_FN tr_vec3 v3_cross(tr_vec3 a, tr_vec3 b) {
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
TR_FN float v3_length(tr_vec3 a) {
    return tr_sqrtf(v3_dot(a, a));
}
TR_FN tr_vec3 v3_normalize(tr_vec3 a) {
    float len = v3_length(a);
    return len > 0.0f ? v3_scale(a, 1.0f / len) : a;
}
TR_FN tr_vec3 v3_min(tr_vec3 a, tr_vec3 b) {
    return v3(tr_fminf(a.x, b.x), tr_fminf(a.y, b.y), tr_fminf(a.z, b.z));
}
TR_FN tr_vec3 v3_max(tr_vec3 a, tr_vec3 b) {
    return v3(tr_fmaxf(a.x, b.x), tr_fmaxf(a.y, b.y), tr_fmaxf(a.z, b.z));
}
TR_FN float v3_max_component(tr_vec3 a) {
    return tr_fmaxf(a.x, tr_fmaxf(a.y, a.z));
}
/* Mirror direction d about the normal n (both unit length). */
TR_FN tr_vec3 v3_reflect(tr_vec3 d, tr_vec3 n) {
    return v3_sub(d, v3_scale(n, 2.0f * v3_dot(d, n)));
}
TR_FN int v3_is_finite(tr_vec3 a) {
    return tr_isfinite(a.x) && tr_isfinite(a.y) && tr_isfinite(a.z);
}

/* An orthonormal basis (t, b, n) around the unit vector n, without branches on the
 * dominant axis (Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 2017). */
TR_FN void v3_basis(tr_vec3 n, tr_vec3 *t, tr_vec3 *b) {
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    *t = v3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    *b = v3(c, sign + n.y * n.y * a, -n.y);
}

#endif
