/* vcm.h - vertex connection and merging's frame on the CPU device, and what an OpenCL
 * device's frame shares with it: the grid's radius and the order of its buckets (vcm.c). */
#ifndef TR_DEVICE_VCM_H
#define TR_DEVICE_VCM_H

#include <stdint.h>

#include "kernel/integrator_vcm.h"
#include "trac0r/error.h"

/* The first sample's merge radius in pixels (integrator_vcm.h): TR_VCM_RADIUS_DEFAULT, or
 * the environment's TRAC0R_VCM_RADIUS (a number in 0..1000; 0 turns merging off, leaving
 * BDPT's image). Fails with TR_STATUS_INVALID_ARGUMENT on a malformed value. */
int tr_vcm_radius_pixels(float *pixels, tr_error *err);

/* The scene's bounds as vcm takes them: the union of its shapes' boxes (the flat
 * structure's nodes), not a pass over every triangle. */
tr_aabb tr_vcm_scene_box(const tr_scene_view *view);

/* The grid's scalars for sample `sample` (0-based) of a frame of `points` grid points
 * through camera cam, in a scene bounded by box, with a first merge radius of `pixels`
 * pixel footprints; outside: the scene has light from outside (tr_bdpt_outside_on). The
 * cell mask is left 0 (it depends on how many vertices there are). Returns 0 where
 * nothing is merged (radius 0, or no points): *p then has eta 0. */
int tr_vcm_params_make(const tr_aabb *box, const tr_camera *cam, float pixels, uint32_t sample,
                       size_t points, int outside, tr_vcm_params *p);

/* The order a device's entries take in the buckets: the CPU's (tiles of tile x tile grid
 * points, each in rows, each point's vertices in subpath order), so that each pixel sums
 * its merges as the CPU does. The nx x ny grid points' blocks of entries start at
 * first[i] and hold count[i] (i = row * nx + column); hash[e] is entry e's full hash
 * (tr_vcm_point_hash). Sets p->cell_mask for `total` entries (as the CPU's grid), fills
 * cell_first (cells + 1 offsets, cells = p->cell_mask + 1, which the caller gets from
 * tr_vcm_cells first) and order (total entry numbers, bucket by bucket). */
uint32_t tr_vcm_cells(size_t total);
void tr_vcm_bucket_order(uint32_t nx, uint32_t ny, uint32_t tile, const uint32_t *first,
                         const uint32_t *count, const uint32_t *hash, uint32_t cells,
                         uint32_t *cell_first, uint32_t *fill, uint32_t *order);

/* Renders frame f with vcm into the film's view fv, light tracing into sp, on nthreads
 * threads over tiles of tile x tile grid points; adds the rays traced to *rays_out. A
 * cancelled frame sets *cancelled_out and returns TR_OK with a partial film. */
int tr_vcm_render(const tr_scene_view *view, const tr_frame *f, const tr_film_view *fv,
                  const tr_bdpt_splat *sp, int nthreads, uint32_t tile, int (*cancel)(void *),
                  void *cancel_user, uint64_t *rays_out, int *cancelled_out, tr_error *err);

#endif
