/* intersect.h - ray/triangle and ray/AABB intersection. */
#ifndef TR_KERNEL_INTERSECT_H
#define TR_KERNEL_INTERSECT_H

#include "compat.h"
#include "types.h"
#include "vec.h"

TR_FN tr_ray tr_ray_make(tr_vec3 origin, tr_vec3 dir, float tmin, float tmax) {
    tr_ray r;
    r.origin = origin;
    r.dir = dir;
    /* IEEE division gives +-inf for a zero component, which the slab test relies on. */
    r.inv_dir = v3(1.0f / dir.x, 1.0f / dir.y, 1.0f / dir.z);
    r.tmin = tmin;
    r.tmax = tmax;
    return r;
}

/* Moller-Trumbore ("Fast, minimum storage ray/triangle intersection", JGT 1997).
 * Two-sided. Returns 1 and sets *t, *u, *v when the ray meets the triangle at a
 * distance in (tmin, tmax). Edges and vertices count as inside (u, v >= 0,
 * u + v <= 1); rays parallel to the plane and degenerate triangles never hit. */
TR_FN int tr_intersect_triangle_edges(const tr_ray *ray, tr_vec3 v0, tr_vec3 e1, tr_vec3 e2,
                                      float *t, float *u, float *v) {
    tr_vec3 p = v3_cross(ray->dir, e2);
    float det = v3_dot(e1, p);
    /* Parallel ray or zero-area triangle; a NaN det also fails this test. */
    if (!(tr_fabsf(det) > 1e-12f)) {
        return 0;
    }
    float inv_det = 1.0f / det;
    tr_vec3 s = v3_sub(ray->origin, v0);
    float uu = v3_dot(s, p) * inv_det;
    if (!(uu >= 0.0f && uu <= 1.0f)) {
        return 0;
    }
    tr_vec3 q = v3_cross(s, e1);
    float vv = v3_dot(ray->dir, q) * inv_det;
    if (!(vv >= 0.0f && uu + vv <= 1.0f)) {
        return 0;
    }
    float tt = v3_dot(e2, q) * inv_det;
    if (!(tt > ray->tmin && tt < ray->tmax)) {
        return 0;
    }
    *t = tt;
    *u = uu;
    *v = vv;
    return 1;
}

/* The same test for a triangle given by v0 and its edges e1 = v1 - v0, e2 = v2 - v0
 * (as the BVH stores its triangles); both give bit-identical results. */
TR_FN int tr_intersect_triangle(const tr_ray *ray, tr_vec3 v0, tr_vec3 v1, tr_vec3 v2, float *t,
                                float *u, float *v) {
    return tr_intersect_triangle_edges(ray, v0, v3_sub(v1, v0), v3_sub(v2, v0), t, u, v);
}

/* Slab test (Kay and Kajiya 1986; the robust form of Williams et al. 2005). Returns 1
 * when the closed segment [tmin, tmax] of the ray overlaps the closed box, and the
 * entry distance clamped to tmin in *tnear (so an origin inside the box gives tmin).
 * Axis-parallel rays use the infinite reciprocal. A ray lying in one of a slab's planes
 * (direction component 0, origin on the plane) gives 0 * inf = NaN there: such a ray
 * lies in the closed slab for every t, so that axis puts no limit on the segment.
 * A direction so small that every reciprocal overflows would put the entry at +inf;
 * that never counts as a hit. */
TR_FN void tr_slab(float lo_plane, float hi_plane, float o, float inv, float *t0, float *t1) {
    float ta = (lo_plane - o) * inv;
    float tb = (hi_plane - o) * inv;
    int in_plane = (ta != ta) | (tb != tb);
    float lo = in_plane ? -TR_INFINITY : tr_fminf(ta, tb);
    float hi = in_plane ? TR_INFINITY : tr_fmaxf(ta, tb);
    *t0 = tr_fmaxf(*t0, lo);
    *t1 = tr_fminf(*t1, hi);
}

TR_FN int tr_intersect_aabb(const tr_ray *ray, tr_aabb box, float *tnear) {
    float t0 = ray->tmin, t1 = ray->tmax;
    tr_slab(box.min.x, box.max.x, ray->origin.x, ray->inv_dir.x, &t0, &t1);
    tr_slab(box.min.y, box.max.y, ray->origin.y, ray->inv_dir.y, &t0, &t1);
    tr_slab(box.min.z, box.max.z, ray->origin.z, ray->inv_dir.z, &t0, &t1);
    *tnear = t0;
    return t0 <= t1 && t0 < TR_INFINITY;
}

#endif
