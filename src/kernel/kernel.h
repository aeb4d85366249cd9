/* kernel.h - one sample of one pixel: the entry point every backend runs.
 *
 * The CPU backend includes this header; the OpenCL backend compiles the same text,
 * wrapped in a __kernel that loops over its work items. */
#ifndef TR_KERNEL_KERNEL_H
#define TR_KERNEL_KERNEL_H

#include "camera.h"
#include "compat.h"
#include "integrator_naive.h"
#include "integrator_pt.h"
#include "rng.h"
#include "sampling.h"
#include "scene_view.h"
#include "types.h"

/* TR_INTEGRATOR_NAIVE / TR_INTEGRATOR_PT: include/trac0r/types.h. */

/* Radiance of sample `sample` of pixel (x, y), with jitter inside the pixel. The random
 * stream depends only on (seed, pixel index, sample). */
TR_FN tr_vec3 tr_render_sample(const tr_scene_view *s, const tr_camera *cam, uint32_t x, uint32_t y,
                               uint32_t sample, uint64_t seed, int max_depth, int integrator,
                               uint32_t *rays) {
    tr_rng rng;
    uint64_t pixel = (uint64_t)y * (uint64_t)cam->screen_width + (uint64_t)x;
    tr_rng_init(&rng, seed, pixel, (uint64_t)sample);
    float jx, jy;
    tr_sample_pixel_jitter(&rng, &jx, &jy);
    tr_ray ray = tr_camera_ray(cam, (float)x, (float)y, jx, jy);
    /* The host rejects unknown integrators before a frame starts. */
    switch (integrator) {
    case TR_INTEGRATOR_PT:
        return tr_trace_pt(s, ray, max_depth, &rng, rays);
    case TR_INTEGRATOR_NAIVE:
    default:
        return tr_trace_naive(s, ray, max_depth, &rng, rays);
    }
}

#endif
