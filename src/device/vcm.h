/* vcm.h - the CPU device's frame for vertex connection and merging (vcm.c). */
#ifndef TR_DEVICE_VCM_H
#define TR_DEVICE_VCM_H

#include <stdint.h>

#include "kernel/integrator_bdpt.h"
#include "trac0r/error.h"

/* The first sample's merge radius in pixels (integrator_vcm.h): TR_VCM_RADIUS_DEFAULT, or
 * the environment's TRAC0R_VCM_RADIUS (a number in 0..1000; 0 turns merging off, leaving
 * BDPT's image). Fails with TR_STATUS_INVALID_ARGUMENT on a malformed value. */
int tr_vcm_radius_pixels(float *pixels, tr_error *err);

/* Renders frame f with vcm into the film's view fv, light tracing into sp, on nthreads
 * threads over tiles of tile x tile grid points; adds the rays traced to *rays_out. A
 * cancelled frame sets *cancelled_out and returns TR_OK with a partial film. */
int tr_vcm_render(const tr_scene_view *view, const tr_frame *f, const tr_film_view *fv,
                  const tr_bdpt_splat *sp, int nthreads, uint32_t tile, int (*cancel)(void *),
                  void *cancel_user, uint64_t *rays_out, int *cancelled_out, tr_error *err);

#endif
