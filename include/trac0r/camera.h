/* camera.h - setting up a pinhole or thin-lens camera (tr_camera, trac0r/types.h), and the
 * free-flying camera a viewer steers (tr_fly_camera). */
#ifndef TRAC0R_CAMERA_H
#define TRAC0R_CAMERA_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/types.h"
#include "trac0r/error.h"

/* A pinhole camera at pos looking along dir, rolled so that world_up points up,
 * with a vertical field of view in degrees (0, 180), near/far distances along the
 * ray and the image size in pixels. Fails on a zero or non-finite direction, an up
 * vector parallel to the direction, or out-of-range values. */
int tr_camera_make(tr_camera *cam, tr_vec3 pos, tr_vec3 dir, tr_vec3 world_up, float vfov_deg,
                   float near_dist, float far_dist, uint32_t width, uint32_t height, tr_error *err);

/* The same camera for another image size (the vertical field of view is kept; so are the
 * lens and the focus). */
int tr_camera_resize(tr_camera *cam, uint32_t width, uint32_t height, tr_error *err);

/* Depth of field: a thin lens of radius lens_radius (scene units, >= 0; 0 makes the camera a
 * pinhole again, rendering bit for bit as tr_camera_make's) focused on the plane at
 * focus_dist (> 0) along the view direction. A point at distance z along the view direction
 * images as a disc of diameter 2 lens_radius |1/focus_dist - 1/z| on the image plane at
 * distance 1 (canvas units; times screen_height / canvas_height in pixels). tr_camera_make
 * starts with radius 0 and focus distance 1. The pt and naive integrators sample the lens;
 * bdpt and vcm refuse a camera with an aperture (TR_STATUS_UNSUPPORTED). */
int tr_camera_set_lens(tr_camera *cam, float lens_radius, float focus_dist, tr_error *err);

/* The lens radius of a camera of f-number f_number whose image plane has the height
 * sensor_height (scene units) behind the lens: the focal length is
 * sensor_height / (2 tan(vertical_fov / 2)) and the radius focal length / (2 f_number).
 * (A 35 mm camera's sensor is 0.024 high in metres.) 0 where an argument is not positive
 * and finite. */
float tr_camera_lens_radius_for(const tr_camera *cam, float f_number, float sensor_height);

/* A camera as a viewer steers it (the command's `view`; any program with a window): its
 * position, unit direction and up (kept orthogonal), the lens, a speed in world units per
 * second, and whether the scene's camera was mirrored. A right-handed scene's camera has
 * its right vector negated after tr_camera_make (the scene file does that); every rebuild
 * must negate it again, or the image flips. */
typedef struct tr_fly_camera {
    tr_vec3 pos, dir, up;
    float vfov, near_dist, far_dist;
    float speed;
    int mirrored;
    float lens_radius, focus_dist; /* the scene camera's thin lens (0: a pinhole), kept */
} tr_fly_camera;

/* The fly camera of `cam`, moving at `speed`. */
tr_fly_camera tr_fly_from_camera(const tr_camera *cam, float speed);
/* The tr_camera of f at w x h (its right negated when mirrored). */
int tr_fly_make(const tr_fly_camera *f, uint32_t w, uint32_t h, tr_camera *cam, tr_error *err);
/* The screen's right in world space (where a sideways move goes). */
tr_vec3 tr_fly_right(const tr_fly_camera *f);
/* dt seconds of the controls held: a move at f->speed along forward * dir + side * right +
 * rise * up (each in -1..1, normalised together) and a roll of `roll` radians per second
 * about dir. Returns 1 when the camera changed. */
int tr_fly_step(tr_fly_camera *f, float forward, float side, float rise, float roll, float dt);
/* Turns by `yaw` radians about up (rightwards on screen, mirrored or not) and `pitch`
 * radians about the screen's horizontal axis (a mouse's motion times its sensitivity). */
void tr_fly_look(tr_fly_camera *f, float yaw, float pitch);
/* A speed for a scene whose bounds are b: a quarter of the diagonal per second, so that
 * crossing it takes seconds whatever its units (0.5 for an empty or unbounded scene). */
float tr_fly_default_speed(const tr_aabb *b);
/* f as the "camera" object of a scene file (position, direction, up, fov, near, far,
 * handedness; floats printed so that they read back exactly) into buf; returns what
 * snprintf returns. */
int tr_fly_json(const tr_fly_camera *f, char *buf, size_t n);

#endif
