/* camera.c - host-side set-up of the kernel's camera. */
#include <string.h>

#include "kernel/vec.h"
#include "trac0r/camera.h"
#include "trac0r/film.h"

static int camera_frame(tr_camera *c, tr_error *err) {
    if (c->screen_width == 0 || c->screen_height == 0 || c->screen_width > TR_FILM_MAX_SIDE ||
        c->screen_height > TR_FILM_MAX_SIDE) {
        return tr_error_set(err,
                            c->screen_width == 0 || c->screen_height == 0
                                ? TR_STATUS_INVALID_ARGUMENT
                                : TR_STATUS_LIMIT,
                            "camera image size %ux%u must be 1..%u on each side", c->screen_width,
                            c->screen_height, TR_FILM_MAX_SIDE);
    }
    float half = tanf(c->vertical_fov * (TR_PI / 180.0f) * 0.5f);
    c->canvas_height = 2.0f * half;
    c->canvas_width = c->canvas_height * (float)c->screen_width / (float)c->screen_height;
    c->horizontal_fov = 2.0f * atanf(0.5f * c->canvas_width) * (180.0f / TR_PI);
    return TR_OK;
}

int tr_camera_make(tr_camera *cam, tr_vec3 pos, tr_vec3 dir, tr_vec3 world_up, float vfov_deg,
                   float near_dist, float far_dist, uint32_t width, uint32_t height,
                   tr_error *err) {
    if (!v3_is_finite(pos) || !v3_is_finite(dir) || !v3_is_finite(world_up)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "camera position, direction and up must be finite");
    }
    if (!(v3_length(dir) > 0.0f) || !(v3_length(world_up) > 0.0f)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "camera direction and up must be non-zero vectors");
    }
    if (!(vfov_deg > 0.0f && vfov_deg < 180.0f)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "camera vertical field of view %g must be in (0, 180) degrees",
                            (double)vfov_deg);
    }
    if (!(near_dist >= 0.0f && far_dist > near_dist) || !isfinite(near_dist)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "camera near %g / far %g must satisfy 0 <= near < far",
                            (double)near_dist, (double)far_dist);
    }
    tr_camera c;
    memset(&c, 0, sizeof c);
    c.pos = pos;
    c.dir = v3_normalize(dir);
    c.world_up = v3_normalize(world_up);
    tr_vec3 right = v3_cross(c.world_up, c.dir);
    if (!(v3_length(right) > 1e-6f)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "camera up vector is parallel to the view direction");
    }
    c.right = v3_normalize(right);
    c.up = v3_cross(c.dir, c.right);
    c.vertical_fov = vfov_deg;
    c.near_dist = near_dist;
    c.far_dist = far_dist;
    c.screen_width = width;
    c.screen_height = height;
    c.lens_radius = 0.0f;
    c.focus_dist = 1.0f;
    if (camera_frame(&c, err) != TR_OK) {
        return TR_ERR;
    }
    *cam = c;
    return TR_OK;
}

int tr_camera_resize(tr_camera *cam, uint32_t width, uint32_t height, tr_error *err) {
    tr_camera c = *cam;
    c.screen_width = width;
    c.screen_height = height;
    if (camera_frame(&c, err) != TR_OK) {
        return TR_ERR;
    }
    *cam = c;
    return TR_OK;
}

int tr_camera_set_lens(tr_camera *cam, float lens_radius, float focus_dist, tr_error *err) {
    if (!(lens_radius >= 0.0f) || !isfinite(lens_radius)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "camera lens radius %g must be finite and >= 0", (double)lens_radius);
    }
    if (!(focus_dist > 0.0f) || !isfinite(focus_dist)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "camera focus distance %g must be finite and > 0", (double)focus_dist);
    }
    cam->lens_radius = lens_radius;
    cam->focus_dist = focus_dist;
    return TR_OK;
}

float tr_camera_lens_radius_for(const tr_camera *cam, float f_number, float sensor_height) {
    if (!(f_number > 0.0f) || !isfinite(f_number) || !(sensor_height > 0.0f) ||
        !isfinite(sensor_height)) {
        return 0.0f;
    }
    const float focal = sensor_height / (2.0f * tanf(cam->vertical_fov * (TR_PI / 180.0f) * 0.5f));
    return focal / (2.0f * f_number);
}
