/* camera.h - setting up a pinhole camera (tr_camera, trac0r/types.h). */
#ifndef TRAC0R_CAMERA_H
#define TRAC0R_CAMERA_H

#include <stdint.h>

#include "trac0r/types.h"
#include "trac0r/error.h"

/* A pinhole camera at pos looking along dir, rolled so that world_up points up,
 * with a vertical field of view in degrees (0, 180), near/far distances along the
 * ray and the image size in pixels. Fails on a zero or non-finite direction, an up
 * vector parallel to the direction, or out-of-range values. */
int tr_camera_make(tr_camera *cam, tr_vec3 pos, tr_vec3 dir, tr_vec3 world_up, float vfov_deg,
                   float near_dist, float far_dist, uint32_t width, uint32_t height, tr_error *err);

/* The same camera for another image size (the vertical field of view is kept). */
int tr_camera_resize(tr_camera *cam, uint32_t width, uint32_t height, tr_error *err);

#endif
