/* camera.h - pinhole camera: pixel to ray (thesis section 3.1.4), and the thin lens.
 *
 * Screen x grows to the camera's right, screen y downwards. The camera's right is
 * world_up x dir (the thesis's convention: looking down +z with +y up, +x is on the
 * right of the image). The image plane sits at distance 1; near and far are distances
 * along the ray. */
#ifndef TR_KERNEL_CAMERA_H
#define TR_KERNEL_CAMERA_H

#include "compat.h"
#include "intersect.h"
#include "types.h"
#include "vec.h"

/* The ray through the point (x + jx, y + jy) of the screen, where (x, y) is a pixel's
 * top-left corner and (jx, jy) in [0,1)^2 the sub-pixel offset. */
TR_FN tr_ray tr_camera_ray(const tr_camera *c, float x, float y, float jx, float jy) {
    float sx = ((x + jx) / (float)c->screen_width - 0.5f) * c->canvas_width;
    float sy = (0.5f - (y + jy) / (float)c->screen_height) * c->canvas_height;
    tr_vec3 d = v3_add(c->dir, v3_add(v3_scale(c->right, sx), v3_scale(c->up, sy)));
    return tr_ray_make(c->pos, v3_normalize(d), c->near_dist, c->far_dist);
}

/* A point of the unit disc from (u1, u2) in [0,1)^2 by Shirley and Chiu's concentric map
 * ("A Low Distortion Map Between Disk and Square", 1997): area-preserving, so uniform
 * points stay uniform and stratified points stay stratified. */
TR_FN void tr_concentric_disc(float u1, float u2, float *dx, float *dy) {
    const float a = 2.0f * u1 - 1.0f, b = 2.0f * u2 - 1.0f;
    if (a == 0.0f && b == 0.0f) {
        *dx = 0.0f;
        *dy = 0.0f;
        return;
    }
    float r, phi;
    if (a * a > b * b) {
        r = a;
        phi = (TR_PI / 4.0f) * (b / a);
    } else {
        r = b;
        phi = (TR_PI / 2.0f) - (TR_PI / 4.0f) * (a / b);
    }
    *dx = r * tr_cosf(phi);
    *dy = r * tr_sinf(phi);
}

/* tr_camera_ray through a thin lens: the ray leaves the lens point (lu, lv) in [0,1)^2
 * (mapped uniformly onto the lens's disc, in the camera's right/up plane) towards the point
 * of the plane in focus that the pinhole ray through the same screen point meets, so that
 * the plane in focus is sharp and a point at distance z blurs into a disc of diameter
 * 2 lens_radius |1/focus_dist - 1/z| on the image plane. A pinhole camera (lens_radius 0)
 * returns tr_camera_ray's ray exactly. */
TR_FN tr_ray tr_camera_ray_lens(const tr_camera *c, float x, float y, float jx, float jy, float lu,
                                float lv) {
    if (!(c->lens_radius > 0.0f)) {
        return tr_camera_ray(c, x, y, jx, jy);
    }
    float sx = ((x + jx) / (float)c->screen_width - 0.5f) * c->canvas_width;
    float sy = (0.5f - (y + jy) / (float)c->screen_height) * c->canvas_height;
    /* d has unit length along dir, so focus_dist * d lies on the plane in focus. */
    tr_vec3 d = v3_add(c->dir, v3_add(v3_scale(c->right, sx), v3_scale(c->up, sy)));
    float dx, dy;
    tr_concentric_disc(lu, lv, &dx, &dy);
    tr_vec3 off =
        v3_add(v3_scale(c->right, dx * c->lens_radius), v3_scale(c->up, dy * c->lens_radius));
    tr_vec3 dir = v3_sub(v3_scale(d, c->focus_dist), off);
    /* near and far stay distances along the ray, from the lens point. */
    return tr_ray_make(v3_add(c->pos, off), v3_normalize(dir), c->near_dist, c->far_dist);
}

/* The world point seen through the centre of pixel (x, y) of `cam` at distance `depth`
 * along the ray (the depth pass's definition; the ray as tr_camera_ray makes it for a
 * pinhole). */
TR_FN tr_vec3 tr_camera_point_at(const tr_camera *cam, float x, float y, float depth) {
    const float sx = ((x + 0.5f) / (float)cam->screen_width - 0.5f) * cam->canvas_width;
    const float sy = (0.5f - (y + 0.5f) / (float)cam->screen_height) * cam->canvas_height;
    const tr_vec3 d =
        v3_normalize(v3_add(cam->dir, v3_add(v3_scale(cam->right, sx), v3_scale(cam->up, sy))));
    return v3_add(cam->pos, v3_scale(d, depth));
}

/* The inverse of tr_camera_point_at: where point p lies on the screen (*x, *y in pixels,
 * the top-left corner at 0, pixel centres at k + 0.5) and its distance from the camera;
 * 0 when p lies behind the camera's plane. The reconstruction's reprojection
 * (src/post/filter.h), ReSTIR's temporal reuse (restir_pass.h) and the temporal
 * gradients (grad_pixel.h) all project with it. */
TR_FN int tr_camera_project(const tr_camera *cam, tr_vec3 p, float *x, float *y, float *dist) {
    const tr_vec3 v = v3_sub(p, cam->pos);
    const float z = v3_dot(v, cam->dir);
    if (!(z > 1e-6f)) {
        return 0;
    }
    const float cx = v3_dot(v, cam->right) / z, cy = v3_dot(v, cam->up) / z;
    *x = (cx / cam->canvas_width + 0.5f) * (float)cam->screen_width;
    *y = (0.5f - cy / cam->canvas_height) * (float)cam->screen_height;
    *dist = tr_sqrtf(v3_dot(v, v));
    return 1;
}

#endif
