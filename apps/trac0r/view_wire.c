/* view_wire.c - projection and near-plane clipping for the viewer's wireframes. */
#include "view_wire.h"

#include <math.h>

#include "view_vec.h"

const unsigned char view_box_edges[12][2] = {
    {0, 1}, {2, 3}, {4, 5}, {6, 7}, /* along x */
    {0, 2}, {1, 3}, {4, 6}, {5, 7}, /* along y */
    {0, 4}, {1, 5}, {2, 6}, {3, 7}, /* along z */
};

void view_box_corners(const tr_aabb *box, tr_vec3 corners[8]) {
    for (int i = 0; i < 8; ++i) {
        corners[i] = v3((i & 1) ? box->max.x : box->min.x, (i & 2) ? box->max.y : box->min.y,
                        (i & 4) ? box->max.z : box->min.z);
    }
}

tr_vec3 view_to_camera(const tr_camera *cam, tr_vec3 world) {
    tr_vec3 d = v3_sub(world, cam->pos);
    return v3(v3_dot(d, cam->right), v3_dot(d, cam->up), v3_dot(d, cam->dir));
}

/* Camera space (z > 0) to screen pixels: the inverse of tr_camera_ray's mapping. */
static void camera_to_screen(const tr_camera *cam, tr_vec3 p, float *sx, float *sy) {
    float u = p.x / p.z / cam->canvas_width;  /* -0.5 .. 0.5 across the screen */
    float v = p.y / p.z / cam->canvas_height; /* -0.5 .. 0.5, up */
    *sx = (u + 0.5f) * (float)cam->screen_width;
    *sy = (0.5f - v) * (float)cam->screen_height;
}

int view_project_segment(const tr_camera *cam, tr_vec3 a, tr_vec3 b, float out[4]) {
    tr_vec3 pa = view_to_camera(cam, a);
    tr_vec3 pb = view_to_camera(cam, b);
    /* The near plane z = near; a tiny floor keeps the division finite when near is 0. */
    const float near = cam->near_dist > 1e-6f ? cam->near_dist : 1e-6f;
    if (pa.z < near && pb.z < near) {
        return 0;
    }
    /* Cut the end behind the plane back to where the segment crosses it. */
    if (pa.z < near || pb.z < near) {
        float t = (near - pa.z) / (pb.z - pa.z); /* pa.z != pb.z: one is on each side */
        tr_vec3 c = v3_add(pa, v3_scale(v3_sub(pb, pa), t));
        c.z = near;
        if (pa.z < near) {
            pa = c;
        } else {
            pb = c;
        }
    }
    camera_to_screen(cam, pa, &out[0], &out[1]);
    camera_to_screen(cam, pb, &out[2], &out[3]);
    return 1;
}

tr_vec3 view_screen_to_camera(const tr_camera *cam, float sx, float sy) {
    return v3((sx / (float)cam->screen_width - 0.5f) * cam->canvas_width,
              (0.5f - sy / (float)cam->screen_height) * cam->canvas_height, 1.0f);
}

tr_vec3 view_screen_to_world(const tr_camera *cam, float sx, float sy) {
    tr_vec3 c = view_screen_to_camera(cam, sx, sy);
    return v3_add(cam->pos,
                  v3_add(cam->dir, v3_add(v3_scale(cam->right, c.x), v3_scale(cam->up, c.y))));
}

int view_clip_segment_2d(float out[4], float w, float h, float margin) {
    const float x0 = out[0], y0 = out[1];
    const float dx = out[2] - x0, dy = out[3] - y0;
    /* p * t <= q for each of the four edges: left, right, top, bottom. */
    const float p[4] = {-dx, dx, -dy, dy};
    const float q[4] = {x0 + margin, w + margin - x0, y0 + margin, h + margin - y0};
    float t0 = 0.0f, t1 = 1.0f;
    for (int i = 0; i < 4; ++i) {
        if (p[i] == 0.0f) {
            if (q[i] < 0.0f) {
                return 0; /* parallel to this edge and outside it */
            }
            continue;
        }
        float t = q[i] / p[i];
        if (p[i] < 0.0f) {
            if (t > t1) {
                return 0;
            }
            if (t > t0) {
                t0 = t;
            }
        } else {
            if (t < t0) {
                return 0;
            }
            if (t < t1) {
                t1 = t;
            }
        }
    }
    out[0] = x0 + t0 * dx;
    out[1] = y0 + t0 * dy;
    out[2] = x0 + t1 * dx;
    out[3] = y0 + t1 * dy;
    return 1;
}

tr_vec3 view_rotate(tr_vec3 v, tr_vec3 axis, float angle) {
    const float c = cosf(angle), s = sinf(angle);
    tr_vec3 k_x_v =
        v3(axis.y * v.z - axis.z * v.y, axis.z * v.x - axis.x * v.z, axis.x * v.y - axis.y * v.x);
    return v3_add(v3_add(v3_scale(v, c), v3_scale(k_x_v, s)),
                  v3_scale(axis, v3_dot(axis, v) * (1.0f - c)));
}
