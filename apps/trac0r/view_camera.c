/* view_camera.c - the viewer's free-flying camera. */
#include "view_camera.h"

#include <math.h>
#include <stdio.h>

#include "trac0r/camera.h"
#include "view_vec.h"

fly_camera fly_from_camera(const tr_camera *cam, float speed) {
    fly_camera f;
    f.pos = cam->pos;
    f.dir = cam->dir;
    f.up = cam->up;
    f.vfov = cam->vertical_fov;
    f.near_dist = cam->near_dist;
    f.far_dist = cam->far_dist;
    f.speed = speed;
    /* tr_camera_make's right is up x dir; a camera whose right points the other way was
     * mirrored by its scene (handedness "right"). */
    f.mirrored = v3_dot(cam->right, v3_cross(cam->up, cam->dir)) < 0.0f;
    f.lens_radius = cam->lens_radius;
    f.focus_dist = cam->focus_dist;
    return f;
}

int fly_make(const fly_camera *f, uint32_t w, uint32_t h, tr_camera *cam) {
    tr_error err;
    tr_camera c;
    if (tr_camera_make(&c, f->pos, f->dir, f->up, f->vfov, f->near_dist, f->far_dist, w, h, &err) !=
        TR_OK) {
        return TR_ERR;
    }
    if (f->mirrored) {
        c.right = v3_scale(c.right, -1.0f); /* as the scene file does; up stays */
    }
    if (f->lens_radius > 0.0f &&
        tr_camera_set_lens(&c, f->lens_radius, f->focus_dist, &err) != TR_OK) {
        return TR_ERR;
    }
    *cam = c;
    return TR_OK;
}

tr_vec3 fly_right(const fly_camera *f) {
    const tr_vec3 r = v3_normalize(v3_cross(f->up, f->dir));
    return f->mirrored ? v3_scale(r, -1.0f) : r;
}

void fly_orthonormalize(fly_camera *f) {
    f->dir = v3_normalize(f->dir);
    f->up = v3_normalize(v3_sub(f->up, v3_scale(f->dir, v3_dot(f->up, f->dir))));
}

float view_default_speed(const tr_aabb *b) {
    const tr_vec3 d = v3_sub(b->max, b->min);
    const float diag = sqrtf(v3_dot(d, d));
    if (!(diag > 0.0f) || !isfinite(diag)) {
        return 0.5f;
    }
    return fminf(fmaxf(0.25f * diag, 1e-4f), 1e4f);
}

int view_camera_json(const fly_camera *f, char *buf, size_t n) {
    /* %.9g: a float's value comes back exactly when the file is read. A thin lens adds its
     * two keys before the last one. */
    char lens[96] = "";
    if (f->lens_radius > 0.0f) {
        snprintf(lens, sizeof lens, "  \"aperture_radius\": %.9g,\n  \"focus_distance\": %.9g,\n",
                 (double)f->lens_radius, (double)f->focus_dist);
    }
    return snprintf(buf, n,
                    "\"camera\": {\n"
                    "  \"position\": [%.9g, %.9g, %.9g],\n"
                    "  \"direction\": [%.9g, %.9g, %.9g],\n"
                    "  \"up\": [%.9g, %.9g, %.9g],\n"
                    "  \"fov\": %.9g,\n"
                    "  \"near\": %.9g,\n"
                    "  \"far\": %.9g,\n"
                    "%s"
                    "  \"handedness\": \"%s\"\n"
                    "}\n",
                    (double)f->pos.x, (double)f->pos.y, (double)f->pos.z, (double)f->dir.x,
                    (double)f->dir.y, (double)f->dir.z, (double)f->up.x, (double)f->up.y,
                    (double)f->up.z, (double)f->vfov, (double)f->near_dist, (double)f->far_dist,
                    lens, f->mirrored ? "right" : "left");
}
