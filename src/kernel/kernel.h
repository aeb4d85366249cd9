/* kernel.h - one sample of one pixel: the entry point every backend runs.
 *
 * The CPU backend includes this header; the OpenCL backend compiles the same text,
 * wrapped in a __kernel that loops over its work items. */
#ifndef TR_KERNEL_KERNEL_H
#define TR_KERNEL_KERNEL_H

#include "camera.h"
#include "compat.h"
#include "film.h"
#include "integrator_naive.h"
#include "integrator_pt.h"
#include "trac0r/integrator_types.h"
#include "rng.h"
#include "sampler.h"
#include "sampling.h"
#include "scene_view.h"
#include "types.h"

/* Sample `sample` of pixel (x, y), the pixel_index-th of the image, seen from `cam`, with
 * jitter inside the pixel: radiance, rays and (with `passes`) the passes' surface into
 * *out. The random numbers depend only on (seed, pixel index, sample): pt reads them
 * from the low-discrepancy sampler (sampler.h; independent numbers with `sampler`
 * TR_SAMPLER_RANDOM, screen-space blue noise with TR_SAMPLER_ZSOBOL, which addresses the
 * pixel by (x, y) instead of its index), naive from the thesis's xorshift stream. pt's
 * Russian roulette starts after rr_start segments; its firefly control is clamp_indirect
 * and `flags` (tr_frame's, TR_FRAME_*: tr_trace_pt_ff). */
TR_FN void tr_render_pixel_sample_kind(const tr_scene_view *s, const tr_camera *cam, uint64_t seed,
                                       int max_depth, int rr_start, float clamp_indirect,
                                       uint32_t flags, uint32_t integrator, uint32_t sampler,
                                       uint32_t passes, uint32_t x, uint32_t y,
                                       uint64_t pixel_index, uint32_t sample, tr_sample *out) {
    tr_sample_clear(out);
    /* The integrators record the passes' surface only for a film that keeps surface
     * passes or the direct part (the variance needs the radiance alone). */
    tr_sample *surface =
        (passes & (TR_PASS_ALL | TR_PASS_DIRECT | TR_PASS_EMISSION | TR_PASS_SPECULAR)) != 0u ? out
                                                                                              : 0;
    float jx, jy;
    /* The host rejects unknown integrators before a frame starts. */
    if (integrator == TR_INTEGRATOR_PT) {
        tr_sampler smp = tr_sampler_make_pixel(seed, pixel_index, x, y, sample, sampler);
        tr_sampler_2d(&smp, TR_DIM_CAMERA, &jx, &jy);
        tr_ray ray = tr_camera_ray(cam, (float)x, (float)y, jx, jy);
        if (cam->lens_radius > 0.0f) {
            float lu, lv;
            tr_sampler_2d(&smp, TR_DIM_LENS, &lu, &lv);
            ray = tr_camera_ray_lens(cam, (float)x, (float)y, jx, jy, lu, lv);
        }
        out->radiance = tr_trace_pt_ff(s, ray, max_depth, rr_start, clamp_indirect, flags, &smp,
                                       &out->rays, surface);
    } else {
        tr_rng rng;
        tr_rng_init(&rng, seed, pixel_index, (uint64_t)sample);
        tr_sample_pixel_jitter(&rng, &jx, &jy);
        tr_ray ray = tr_camera_ray(cam, (float)x, (float)y, jx, jy);
        if (cam->lens_radius > 0.0f) {
            /* Drawn only with a lens: a pinhole camera's stream is unchanged. */
            float lu, lv;
            tr_sample_pixel_jitter(&rng, &lu, &lv);
            ray = tr_camera_ray_lens(cam, (float)x, (float)y, jx, jy, lu, lv);
        }
        out->radiance = tr_trace_naive(s, ray, max_depth, &rng, &out->rays, surface);
    }
    tr_sample_finish(out);
}

/* tr_render_pixel_sample_kind with the Sobol sampler. */
TR_FN void tr_render_pixel_sample(const tr_scene_view *s, const tr_camera *cam, uint64_t seed,
                                  int max_depth, uint32_t integrator, uint32_t passes, uint32_t x,
                                  uint32_t y, uint64_t pixel_index, uint32_t sample,
                                  tr_sample *out) {
    tr_render_pixel_sample_kind(s, cam, seed, max_depth, TR_PT_RR_START, 0.0f, 0u, integrator, 0u,
                                passes, x, y, pixel_index, sample, out);
}

/* Sample `sample` of pixel (x, y) of frame f (tr_render_pixel_sample with f's settings). */
TR_FN void tr_render_sample(const tr_scene_view *s, const tr_frame *f, uint32_t x, uint32_t y,
                            uint32_t sample, tr_sample *out) {
    const uint64_t seed = ((uint64_t)f->seed_hi << 32) | (uint64_t)f->seed_lo;
    const uint64_t pixel = (uint64_t)y * (uint64_t)f->camera.screen_width + (uint64_t)x;
    tr_render_pixel_sample_kind(s, &f->camera, seed, f->max_depth, f->rr_start, f->clamp_indirect,
                                f->flags, f->integrator, f->sampler, f->passes, x, y, pixel, sample,
                                out);
}

/* The pixels frame f traces and the blocks they fill: the traced pixels are those of the
 * rectangle's stride grid (coordinates multiples of the stride, counted from the image's
 * corner, so that a frame split into rectangles traces the same pixels as a whole one);
 * each fills its stride x stride block clipped to the rectangle. *gx0, *gy0 get the grid
 * index of the first traced column and row, *nx, *ny the number of them. */
TR_FN void tr_frame_grid(const tr_frame *f, uint32_t *gx0, uint32_t *gy0, uint32_t *nx,
                         uint32_t *ny) {
    const uint32_t k = f->stride;
    const uint32_t x1 = f->rect_x + f->rect_w, y1 = f->rect_y + f->rect_h;
    *gx0 = f->rect_x / k;
    *gy0 = f->rect_y / k;
    *nx = f->rect_w ? (x1 + k - 1u) / k - *gx0 : 0u;
    *ny = f->rect_h ? (y1 + k - 1u) / k - *gy0 : 0u;
}

/* Grid point (gx, gy) of frame f: its traced pixel (*x, *y), returned as the pixel index
 * the samplers key on, and the block it fills, [*bx0, *bx1) x [*by0, *by1). */
TR_FN uint64_t tr_frame_point(const tr_frame *f, uint32_t gx, uint32_t gy, uint32_t *x, uint32_t *y,
                              uint32_t *bx0, uint32_t *by0, uint32_t *bx1, uint32_t *by1) {
    const uint32_t k = f->stride;
    const uint32_t rx1 = f->rect_x + f->rect_w, ry1 = f->rect_y + f->rect_h;
    *x = gx * k;
    *y = gy * k;
    *bx0 = *x > f->rect_x ? *x : f->rect_x;
    *by0 = *y > f->rect_y ? *y : f->rect_y;
    *bx1 = *x + k < rx1 ? *x + k : rx1;
    *by1 = *y + k < ry1 ? *y + k : ry1;
    return (uint64_t)*y * f->camera.screen_width + (uint64_t)*x;
}

/* tr_render_grid_rows with the frame's integrator given as `integrator`. Always inlined,
 * so that each of tr_render_grid_rows's two calls holds one integrator's code: with the
 * choice made per sample, the compiler hoisted pt's sampler set-up (invariant over a
 * pixel's samples) above the branch, and naive paid for it at every pixel. */
TR_FN_INLINE uint32_t tr_render_grid_rows_as(const tr_scene_view *s, const tr_frame *f,
                                             const tr_film_view *film, uint32_t gx0, uint32_t gy0,
                                             uint32_t gx1, uint32_t gy1, uint32_t integrator) {
    const tr_camera cam = f->camera;
    const uint64_t seed = ((uint64_t)f->seed_hi << 32) | (uint64_t)f->seed_lo;
    const int max_depth = f->max_depth, rr_start = f->rr_start;
    const float clamp_indirect = f->clamp_indirect;
    const uint32_t flags = f->flags;
    const uint32_t passes = f->passes, sampler = f->sampler;
    const uint32_t first = f->sample, count = f->sample_count;
    const uint32_t k = f->stride;
    const uint32_t rx0 = f->rect_x, ry0 = f->rect_y;
    const uint32_t rx1 = rx0 + f->rect_w, ry1 = ry0 + f->rect_h;
    const uint64_t width = cam.screen_width;
    uint32_t rays = 0;
    for (uint32_t gy = gy0; gy < gy1; ++gy) {
        const uint32_t y = gy * k;
        const uint32_t by0 = y > ry0 ? y : ry0;
        const uint32_t by1 = y + k < ry1 ? y + k : ry1;
        for (uint32_t gx = gx0; gx < gx1; ++gx) {
            const uint32_t x = gx * k;
            const uint32_t bx0 = x > rx0 ? x : rx0;
            const uint32_t bx1 = x + k < rx1 ? x + k : rx1;
            const uint64_t pixel = (uint64_t)y * width + (uint64_t)x;
            for (uint32_t n = 0; n < count; ++n) {
                tr_sample smp;
                tr_render_pixel_sample_kind(s, &cam, seed, max_depth, rr_start, clamp_indirect,
                                            flags, integrator, sampler, passes, x, y, pixel,
                                            first + n, &smp);
                rays += smp.rays;
                tr_film_add_block(film, &smp, bx0, by0, bx1, by1);
            }
        }
    }
    return rays;
}

/* Traces grid points [gx0, gx1) x [gy0, gy1) of frame f for samples sample ..
 * sample+sample_count-1, adding each to its block of the film; returns the rays traced.
 * A grid point whose anchor lies left of or above the rectangle is traced all the same
 * (its block overlaps it). The frame's fields are read once, into locals: the film's
 * stores could otherwise alias them and force a reload after every sample. */
TR_FN uint32_t tr_render_grid_rows(const tr_scene_view *s, const tr_frame *f,
                                   const tr_film_view *film, uint32_t gx0, uint32_t gy0,
                                   uint32_t gx1, uint32_t gy1) {
    if (f->integrator == TR_INTEGRATOR_PT) {
        return tr_render_grid_rows_as(s, f, film, gx0, gy0, gx1, gy1, TR_INTEGRATOR_PT);
    }
    return tr_render_grid_rows_as(s, f, film, gx0, gy0, gx1, gy1, TR_INTEGRATOR_NAIVE);
}

#endif
