/* fresh.h - more samples where the reconstruction has no history: the real-time loop's
 * pixels whose surface the previous frame did not see (the first frame, a camera cut, a
 * disocclusion) start their history from one frame's samples alone, and the spatial filter
 * is all that stands between their noise and the screen. Every other pixel's history
 * averages several frames' samples. So the frames with least history - the first, the
 * cut - are the worst ones (docs/realtime.md, "The hard scenes"), and extra samples spent
 * on those pixels only (adaptive sampling by the temporal filter's own rejection test:
 * the reprojection of Nehab et al., "Accelerating Real-Time Shading with Reverse
 * Reprojection Caching", GH 2007, as src/post/filter.h implements it) go where the error
 * is largest: the first frame and a cut cost more, the other frames little more
 * (docs/log/2026-realtime.md has the times). Internal to src/realtime. */
#ifndef TRAC0R_REALTIME_FRESH_H
#define TRAC0R_REALTIME_FRESH_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/camera.h"
#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"

/* The extra samples' numbers start here, apart from the frames' own (which count up from
 * 0 by frame), so that no frame draws another's numbers. */
#define TR_FRESH_SAMPLE_BASE 0x80000000u

typedef struct tr_fresh {
    uint32_t width, height;
    float *depth, *normal; /* the previous frame's passes (means), 1 and 3 per pixel */
    uint32_t *prim;
    float *point;   /* its pixels' surface points (tr_camera_point_at), 3 per pixel */
    float *cur;     /* this frame's, 3 per pixel */
    tr_camera cam;  /* its camera */
    int have_prev;  /* depth, normal, prim and cam hold the previous frame */
    uint8_t *mask;  /* this frame: 1 where a pixel hit a surface and has no history */
    uint32_t fresh; /* ... and how many */
} tr_fresh;

void tr_fresh_free(tr_fresh *f);
/* Forgets the previous frame: every pixel of the next one has no history. */
void tr_fresh_reset(tr_fresh *f);
/* This frame's mask from `film` (its depth, normal and id passes' means),
 * rendered through cam: a pixel has no history where there is no previous frame of this
 * size or where its surface, followed back by its primitive's motion (motion[prim] for
 * prim < motion_count; NULL: none, as tr_recon_frame_moving takes it), reprojects onto
 * less than the temporal stage's 5 % of consistent previous pixels (tr_post_reproject_moving,
 * the very test the reconstruction makes). The temporal gradients' caps are not counted.
 * Pixels that hit nothing keep no history either and are left out (the sky's emission is
 * exact at one sample). Returns TR_OK, or TR_ERR out of memory. */
int tr_fresh_mask(tr_fresh *f, const tr_film *film, const tr_camera *cam, const tr_vec3 *motion,
                  uint32_t motion_count, int threads, tr_error *err);
/* Adds samples sample .. sample + count - 1 of every pixel of the mask to the host film
 * `film` (the device's film keeps only the frame's own), traced through cam with cfg in
 * `scene` as the CPU device traces them (the kernel's tr_render_grid_rows for one pixel):
 * pixel by pixel, so that no pixel with history gets one. cfg: stride 1, not bdpt or vcm.
 * The result does not depend on `threads`. */
int tr_fresh_trace(const tr_fresh *f, const tr_scene *scene, const tr_camera *cam,
                   const tr_render_config *cfg, uint32_t sample, uint32_t count, int threads,
                   tr_film *film, tr_error *err);
/* Keeps `film`'s passes and cam as the previous frame for the next tr_fresh_mask. */
int tr_fresh_remember(tr_fresh *f, const tr_film *film, const tr_camera *cam, tr_error *err);

/* The three steps above where an OpenCL device's film lies (src/device/opencl.h,
 * tr_cl_fresh_frame): the mask, samples sample .. sample + count - 1 at its pixels through
 * cam with cfg (count 0: none), and this frame kept on the device for the next call.
 * f keeps the camera and the count of fresh pixels; its arrays stay empty. */
struct tr_device;
int tr_fresh_frame_device(tr_fresh *f, struct tr_device *dev, const tr_camera *cam,
                          const tr_render_config *cfg, uint32_t sample, uint32_t count,
                          const tr_vec3 *motion, uint32_t motion_count, tr_error *err);

#endif
