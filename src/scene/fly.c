/* fly.c - the free-flying camera a viewer steers (trac0r/camera.h). */
#include <math.h>
#include <stdio.h>

#include "kernel/vec.h"
#include "trac0r/camera.h"

/* v turned by `angle` radians about the unit axis (Rodrigues' formula). */
static tr_vec3 rotate(tr_vec3 v, tr_vec3 axis, float angle) {
    const float c = cosf(angle), s = sinf(angle);
    return v3_add(v3_add(v3_scale(v, c), v3_scale(v3_cross(axis, v), s)),
                  v3_scale(axis, v3_dot(axis, v) * (1.0f - c)));
}

/* Keeps dir and up unit length and orthogonal after many small rotations. */
static void orthonormalize(tr_fly_camera *f) {
    f->dir = v3_normalize(f->dir);
    f->up = v3_normalize(v3_sub(f->up, v3_scale(f->dir, v3_dot(f->up, f->dir))));
}

tr_fly_camera tr_fly_from_camera(const tr_camera *cam, float speed) {
    tr_fly_camera f;
    f.pos = cam->pos;
    f.dir = cam->dir;
    f.up = cam->up;
    f.vfov = cam->vertical_fov;
    f.near_dist = cam->near_dist;
    f.far_dist = cam->far_dist;
    f.speed = speed;
    /* tr_camera_make's right is up x dir; one pointing the other way was mirrored. */
    f.mirrored = v3_dot(cam->right, v3_cross(cam->up, cam->dir)) < 0.0f;
    f.lens_radius = cam->lens_radius;
    f.focus_dist = cam->focus_dist;
    return f;
}

int tr_fly_make(const tr_fly_camera *f, uint32_t w, uint32_t h, tr_camera *cam, tr_error *err) {
    tr_camera c;
    if (tr_camera_make(&c, f->pos, f->dir, f->up, f->vfov, f->near_dist, f->far_dist, w, h, err) !=
        TR_OK) {
        return TR_ERR;
    }
    if (f->mirrored) {
        c.right = v3_neg(c.right); /* as the scene file does; up stays */
    }
    if (f->lens_radius > 0.0f &&
        tr_camera_set_lens(&c, f->lens_radius, f->focus_dist, err) != TR_OK) {
        return TR_ERR;
    }
    *cam = c;
    return TR_OK;
}

tr_vec3 tr_fly_right(const tr_fly_camera *f) {
    const tr_vec3 r = v3_normalize(v3_cross(f->up, f->dir));
    return f->mirrored ? v3_neg(r) : r;
}

int tr_fly_step(tr_fly_camera *f, float forward, float side, float rise, float roll, float dt) {
    int changed = 0;
    const tr_vec3 move = v3_add(v3_add(v3_scale(f->dir, forward), v3_scale(tr_fly_right(f), side)),
                                v3_scale(f->up, rise));
    if (v3_dot(move, move) > 0.0f) {
        f->pos = v3_add(f->pos, v3_scale(v3_normalize(move), f->speed * dt));
        changed = 1;
    }
    if (roll != 0.0f) {
        f->up = rotate(f->up, f->dir, roll * dt);
        orthonormalize(f);
        changed = 1;
    }
    return changed;
}

void tr_fly_look(tr_fly_camera *f, float yaw, float pitch) {
    /* The pitch axis is up x dir whatever the handedness; a mirrored image turns the
     * other way on screen, so its yaw is negated. */
    const tr_vec3 right = v3_normalize(v3_cross(f->up, f->dir));
    f->dir = rotate(f->dir, f->up, f->mirrored ? -yaw : yaw);
    f->dir = rotate(f->dir, right, pitch);
    f->up = rotate(f->up, right, pitch);
    orthonormalize(f);
}

float tr_fly_default_speed(const tr_aabb *b) {
    const tr_vec3 d = v3_sub(b->max, b->min);
    const float diag = sqrtf(v3_dot(d, d));
    if (!(diag > 0.0f) || !isfinite(diag)) {
        return 0.5f;
    }
    return fminf(fmaxf(0.25f * diag, 1e-4f), 1e4f);
}

int tr_fly_json(const tr_fly_camera *f, char *buf, size_t n) {
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
