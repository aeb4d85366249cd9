/* view_camera.h - the viewer's free-flying camera: pure functions,
 * no SDL, unit-tested in tests/test_view_camera.c. */
#ifndef TRAC0R_VIEW_CAMERA_H
#define TRAC0R_VIEW_CAMERA_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/types.h"

/* The camera the user steers. `mirrored` remembers a right-handed scene's camera, whose
 * right vector is dir x up where tr_camera_make builds up x dir (the scene file negates
 * it after tr_camera_make): every rebuild must negate it again, or the image flips. */
typedef struct fly_camera {
    tr_vec3 pos, dir, up; /* dir and up unit and orthogonal */
    float vfov, near_dist, far_dist;
    float speed; /* world units per second */
    int mirrored;
    float lens_radius, focus_dist; /* the scene camera's thin lens (0: a pinhole), kept */
} fly_camera;

/* The fly camera of a scene's camera, moving at `speed`. */
fly_camera fly_from_camera(const tr_camera *cam, float speed);
/* The tr_camera of f at w x h (right negated when mirrored); TR_OK or TR_ERR. */
int fly_make(const fly_camera *f, uint32_t w, uint32_t h, tr_camera *cam);
/* The screen's right in world space: where D moves and what a mouse pitch turns about. */
tr_vec3 fly_right(const fly_camera *f);
/* Keeps dir and up unit length and orthogonal after many small rotations. */
void fly_orthonormalize(fly_camera *f);

/* The default movement speed for a scene whose bounds are `b`: a quarter of the
 * diagonal per second, so that crossing the scene takes seconds whatever its units
 * (0.5 for an empty or unbounded scene). */
float view_default_speed(const tr_aabb *b);

/* Writes f as the "camera" object of a scene file (position, direction, up, fov, near,
 * far, handedness) into buf; returns what snprintf returns. */
int view_camera_json(const fly_camera *f, char *buf, size_t n);

#endif
