/* reproject.h - the tests by which a pixel finds its surface in the previous frame: where
 * a point falls in the previous camera (its bilinear footprint) and whether a previous
 * pixel describes the same surface. The reconstruction's temporal stage (src/post/filter.h)
 * and the real-time loop's fresh samples (src/realtime/fresh.c; entry.cl on a device) both
 * decide by them, so that a pixel has history for one exactly when it has for the other. */
#ifndef TR_KERNEL_REPROJECT_H
#define TR_KERNEL_REPROJECT_H

#include "camera.h"
#include "compat.h"
#include "types.h"
#include "vec.h"

/* The plane test's tolerance, as a fraction of the distance, for a pixel whose passes were
 * replaced through a curved delta surface or a refraction (TR_PRIM_PSR_CURVED, the id's top
 * bit). */
#define TR_REPROJECT_PSR_CURVED_TOL 0.1f

/* Whether a history sample describes the same surface as the current point p (normal
 * n, primitive prim, at distance dist from the previous camera): the same primitive, a
 * facing normal, and the history's point q (its pixel's ray at its depth) on p's tangent
 * plane within 2 % of the distance. A plane test rather than a depth test, because on a
 * surface seen at a grazing angle depth changes a lot from one pixel to the next while
 * the plane does not. Disocclusions fail here: where the previous camera saw another
 * surface in front of p, q lies off p's plane (or on another primitive). */
TR_FN int tr_reproject_consistent(uint32_t prim, tr_vec3 p, tr_vec3 n, float dist,
                                  uint32_t prev_prim, tr_vec3 q, tr_vec3 prev_n) {
    /* Id 0 on a surface: a shape that is not a triangle; then the geometry decides. */
    if (prim != prev_prim) {
        return 0;
    }
    /* Seen through a curved mirror or glass (primary surface replacement, psr.h): the virtual
     * point moves over its image as the camera moves, so the plane test is wider. */
    const float tol = (prim & TR_PRIM_PSR_CURVED) != 0u ? TR_REPROJECT_PSR_CURVED_TOL : 0.02f;
    if (tr_fabsf(v3_dot(v3_sub(q, p), n)) > tol * dist) {
        return 0;
    }
    return v3_dot(n, prev_n) > 0.9f;
}

/* Where the point p falls in the previous frame's camera prev: the top-left pixel (ix, iy)
 * of its bilinear footprint, the fractions (ax, ay) towards the next pixels, and its
 * distance from prev's eye; 0 where it lies behind prev or a pixel or more outside its
 * frame. The reconstruction's reprojection's first step (src/post/filter.h), and the
 * real-time loop's fresh samples' (src/realtime/fresh.c, entry.cl's tr_cl_fresh_mask). */
TR_FN int tr_reproject_footprint(const tr_camera *prev, tr_vec3 p, int *ix, int *iy, float *ax,
                                 float *ay, float *dist) {
    float px, py;
    if (!tr_camera_project(prev, p, &px, &py, dist)) {
        return 0;
    }
    const float fx = px - 0.5f, fy = py - 0.5f;
    if (!(fx > -1.0f && fy > -1.0f && fx < (float)prev->screen_width &&
          fy < (float)prev->screen_height)) {
        return 0;
    }
    /* floor, for fx, fy > -1 (compat.h has no floor of its own). */
    *ix = fx < 0.0f ? -1 : (int)fx;
    *iy = fy < 0.0f ? -1 : (int)fy;
    *ax = fx - (float)*ix;
    *ay = fy - (float)*iy;
    return 1;
}

/* The bilinear weights of the previous pixels around point p (normal n, primitive prim)
 * that pass tr_reproject_consistent, the previous frame (camera prev) given as its pixels'
 * mean depth, normal and primitive, and their surface points (tr_camera_point_at at that
 * depth, 3 floats each) where point is not null (else they are found here): zero for a
 * tap off screen or not consistent, in w[0..3] for the taps (x0, y0), (x0+1, y0), (x0,
 * y0+1), (x0+1, y0+1). *x0, *y0 receive the top-left tap. Returns the sum of the weights
 * (0: no history survives). */
TR_FN float tr_reproject_weights(const tr_camera *prev, tr_vec3 p, tr_vec3 n, uint32_t prim,
                                 TR_CONST_GLOBAL float *depth, TR_CONST_GLOBAL float *normal,
                                 TR_CONST_GLOBAL uint32_t *prims, TR_CONST_GLOBAL float *point,
                                 int *x0, int *y0, float w[4]) {
    w[0] = w[1] = w[2] = w[3] = 0.0f;
    *x0 = *y0 = 0;
    int ix, iy;
    float ax, ay, dist;
    if (!tr_reproject_footprint(prev, p, &ix, &iy, &ax, &ay, &dist)) {
        return 0.0f;
    }
    *x0 = ix;
    *y0 = iy;
    const int pw = (int)prev->screen_width, ph = (int)prev->screen_height;
    float total = 0.0f;
    for (int k = 0; k < 4; ++k) {
        const int tx = ix + (k & 1), ty = iy + (k >> 1);
        if (tx < 0 || ty < 0 || tx >= pw || ty >= ph) {
            continue;
        }
        const uint32_t i = (uint32_t)ty * (uint32_t)pw + (uint32_t)tx;
        if (!(depth[i] > 0.0f) || prims[i] != prim) {
            continue; /* tr_reproject_consistent's first test, before any arithmetic */
        }
        const tr_vec3 pn = v3(normal[3u * i], normal[3u * i + 1u], normal[3u * i + 2u]);
        const tr_vec3 q = point ? v3(point[3u * i], point[3u * i + 1u], point[3u * i + 2u])
                                : tr_camera_point_at(prev, (float)tx, (float)ty, depth[i]);
        if (!tr_reproject_consistent(prim, p, n, dist, prims[i], q, pn)) {
            continue;
        }
        const float bw = ((k & 1) ? ax : 1.0f - ax) * ((k >> 1) ? ay : 1.0f - ay);
        w[k] = bw;
        total += bw;
    }
    return total;
}

/* The total of tr_reproject_weights: the reconstruction's temporal stage keeps a history
 * where it exceeds 0.05 (tr_post_temporal_pixel_moving). */
TR_FN float tr_reproject_total(const tr_camera *prev, tr_vec3 p, tr_vec3 n, uint32_t prim,
                               TR_CONST_GLOBAL float *depth, TR_CONST_GLOBAL float *normal,
                               TR_CONST_GLOBAL uint32_t *prims, TR_CONST_GLOBAL float *point) {
    int x0, y0;
    float w[4];
    return tr_reproject_weights(prev, p, n, prim, depth, normal, prims, point, &x0, &y0, w);
}

/* Pixel (x, y) of a frame through cam (its mean depth, normal and primitive) has no
 * history: it hit a surface, and with a previous frame (have_prev) that surface, followed
 * back by its motion m, reprojects onto no more than 0.05 of consistent previous pixels.
 * *point gets its surface point where it hit one. */
TR_FN int tr_reproject_lost(const tr_camera *cam, const tr_camera *prev, int have_prev, uint32_t x,
                            uint32_t y, float depth, tr_vec3 n, uint32_t prim, tr_vec3 m,
                            TR_CONST_GLOBAL float *prev_depth, TR_CONST_GLOBAL float *prev_normal,
                            TR_CONST_GLOBAL uint32_t *prev_prim, TR_CONST_GLOBAL float *prev_point,
                            tr_vec3 *point) {
    if (!(depth > 0.0f)) {
        return 0;
    }
    const tr_vec3 p = tr_camera_point_at(cam, (float)x, (float)y, depth);
    *point = p;
    return !have_prev || !(tr_reproject_total(prev, v3_sub(p, m), n, prim, prev_depth, prev_normal,
                                              prev_prim, prev_point) > 0.05f);
}

#endif
