/* camera.h - pinhole camera: pixel to ray (thesis section 3.1.4).
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

#endif
