/* view_wire.h - the viewer's geometry: projecting world-space segments and boxes
 * through the pinhole camera onto the screen, clipped against the near plane, and
 * mapping a screen position back to camera and world space. Pure functions, no SDL. */
#ifndef TRAC0R_VIEW_WIRE_H
#define TRAC0R_VIEW_WIRE_H

#include "trac0r/types.h"

/* A point in camera space: x right, y up, z along the view direction (all in world
 * units, so z is the distance in front of the camera's plane). */
tr_vec3 view_to_camera(const tr_camera *cam, tr_vec3 world);

/* Projects the world-space segment a-b onto the screen of `cam` (pixels, x right, y
 * down, (0,0) the top-left corner of the top-left pixel). The part of the segment
 * closer than the camera's near distance (in camera z) is cut off first, so that
 * segments reaching behind the camera project correctly. Returns 1 and the screen end
 * points in out[0..3] (x0, y0, x1, y1) when something is left, 0 when the whole
 * segment lies behind the near plane. The end points
 * may lie outside the screen; the caller's line drawing clips them to the window. */
int view_project_segment(const tr_camera *cam, tr_vec3 a, tr_vec3 b, float out[4]);

/* The 12 edges of an axis-aligned box as pairs of corner indices into the corners
 * that view_box_corners returns. */
extern const unsigned char view_box_edges[12][2];

/* The 8 corners of a box: bit 0 of the index picks max.x, bit 1 max.y, bit 2 max.z. */
void view_box_corners(const tr_aabb *box, tr_vec3 corners[8]);

/* A screen position (pixels, as above) on the image plane at distance 1 in camera
 * space, and the same point in world space. */
tr_vec3 view_screen_to_camera(const tr_camera *cam, float sx, float sy);
tr_vec3 view_screen_to_world(const tr_camera *cam, float sx, float sy);

/* Clips the screen segment out[0..3] to the rectangle [-margin, w + margin] x
 * [-margin, h + margin] (Liang and Barsky, "A New Concept and Method for Line
 * Clipping", ACM TOG 3(1), 1984), so that line drawing gets small coordinates.
 * Returns 0 when nothing of the segment is inside. */
int view_clip_segment_2d(float out[4], float w, float h, float margin);

/* v rotated by `angle` radians about the unit axis (right-handed, Rodrigues). */
tr_vec3 view_rotate(tr_vec3 v, tr_vec3 axis, float angle);

#endif
