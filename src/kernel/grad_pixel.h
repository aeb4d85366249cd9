/* grad_pixel.h - the per-stratum and per-pixel steps of the real-time loop's temporal
 * gradients (A-SVGF: C. Schied, C. Peters, C. Dachsbacher, "Gradient Estimation for
 * Real-Time Adaptive Temporal Filtering", HPG 2018; the variant docs/realtime.md
 * describes). Single source: the host's loops (src/realtime/gradient.c) and the OpenCL
 * device's kernels (entry.cl's tr_cl_grad_*) call the same functions, so that both
 * measure the same gradients from the same samples.
 *
 * The image is cut into strata of TR_GRAD_STRATUM x TR_GRAD_STRATUM pixels; per frame one
 * pixel of each replays the previous frame's samples (its camera, sample numbers and
 * settings: the samplers are stateless, so the replay draws the same numbers) in the scene
 * as it is now. |now - before| and max(now, before) per stratum, spread by a few à-trous
 * steps, give each pixel the normalised gradient lambda and a history cap of
 * 1 / (alpha_min + (1 - alpha_min) lambda) frames. */
#ifndef TR_KERNEL_GRAD_PIXEL_H
#define TR_KERNEL_GRAD_PIXEL_H

#include "camera.h"
#include "compat.h"
#include "envmap.h"
#include "kernel.h"
#include "types.h"
#include "vec.h"

/* The luminance of a film pixel's mean: its radiance sums sum[0..2] over count samples
 * (0 without any). What the next frame's replay compares against. */
TR_FN float tr_grad_mean_luminance(TR_CONST_GLOBAL float *sum, uint32_t count) {
    if (!count) {
        return 0.0f;
    }
    const float c = (float)count;
    return tr_env_luminance(v3(sum[0] / c, sum[1] / c, sum[2] / c));
}

/* The stratum's side in pixels: one pixel in 9 is replayed. */
#define TR_GRAD_STRATUM 3
/* The à-trous steps that spread the strata's gradients (1, 2, 4 strata apart). */
#define TR_GRAD_ATROUS_STEPS 3
/* The cap of a pixel whose shading did not change: none (the largest float). */
#define TR_GRAD_NO_CAP 3.40282347e+38f

/* The pixel of stratum (sx, sy) (sw strata per row) replayed in frame `frame` of a w x h
 * image: one of its 3x3 by a hash, so that every pixel is measured now and then; clipped
 * into the image. */
TR_FN void tr_grad_stratum_pixel(uint32_t sw, uint32_t w, uint32_t h, uint32_t sx, uint32_t sy,
                                 uint32_t frame, uint32_t *x, uint32_t *y) {
    uint32_t v = (sy * sw + sx) * 0x9e3779b1u ^ frame * 0x85ebca6bu;
    v ^= v >> 16;
    v *= 0x7feb352du;
    v ^= v >> 15;
    v *= 0x846ca68bu;
    v ^= v >> 16;
    const uint32_t k = v % (TR_GRAD_STRATUM * TR_GRAD_STRATUM);
    uint32_t px = sx * TR_GRAD_STRATUM + k % TR_GRAD_STRATUM;
    uint32_t py = sy * TR_GRAD_STRATUM + k / TR_GRAD_STRATUM;
    *x = px < w ? px : w - 1u;
    *y = py < h ? py : h - 1u;
}

/* Stratum (sx, sy)'s replay: samples sample .. sample+count-1 of its pixel (x, y) through
 * the previous frame `prev` (its camera and settings) in the scene as it is now, against
 * that pixel's luminance prev_lum and first primitive prev_prim in the previous frame.
 * *num gets |now - before|, *den max(now, before); both 0 where the surface itself changed
 * (another first primitive, with has_prim, or one that moved: motion holds 3 floats per
 * primitive id below motion_count, as the reconstruction takes them), which the geometric
 * tests and the motion vectors judge instead. Returns 1 when the stratum counts as
 * changed (same surface, another luminance). */
TR_FN int tr_grad_replay_stratum(const tr_scene_view *s, const tr_frame *prev, uint32_t x,
                                 uint32_t y, uint32_t sample, uint32_t count, float prev_lum,
                                 uint32_t prev_prim, int has_prim, TR_CONST_GLOBAL float *motion,
                                 uint32_t motion_count, float *num, float *den) {
    float s0 = 0.0f, s1 = 0.0f, s2 = 0.0f;
    uint32_t prim = 0u;
    for (uint32_t k = 0; k < count; ++k) {
        tr_sample smp;
        tr_render_sample(s, prev, x, y, sample + k, &smp);
        s0 += smp.radiance.x;
        s1 += smp.radiance.y;
        s2 += smp.radiance.z;
        if (k == 0u) {
            prim = smp.prim;
        }
    }
    /* The film's mean, as the previous frame's luminance was taken. */
    const float c = (float)count;
    const float lr = tr_env_luminance(v3(s0 / c, s1 / c, s2 / c));
    int moved = 0;
    if (has_prim) {
        moved = prim != prev_prim;
        if (!moved && motion && prim < motion_count) {
            moved = motion[3u * prim] != 0.0f || motion[3u * prim + 1u] != 0.0f ||
                    motion[3u * prim + 2u] != 0.0f;
        }
    }
    *num = moved ? 0.0f : tr_fabsf(lr - prev_lum);
    *den = moved ? 0.0f : tr_fmaxf(lr, prev_lum);
    return !moved && lr != prev_lum;
}

/* One à-trous step over the strata at (x, y) of an sw x sh grid: a 3x3 B-spline with taps
 * `step` strata apart, those outside left out and the rest renormalised. */
TR_FN float tr_grad_atrous_at(TR_CONST_GLOBAL float *src, int sw, int sh, int x, int y, int step) {
    const float kw[3] = {0.25f, 0.5f, 0.25f};
    float sum = 0.0f, wsum = 0.0f;
    for (int dy = -1; dy <= 1; ++dy) {
        const int ty = y + dy * step;
        if (ty < 0 || ty >= sh) {
            continue;
        }
        for (int dx = -1; dx <= 1; ++dx) {
            const int tx = x + dx * step;
            if (tx < 0 || tx >= sw) {
                continue;
            }
            const float w = kw[dy + 1] * kw[dx + 1];
            sum += w * src[ty * sw + tx];
            wsum += w;
        }
    }
    return sum / wsum;
}

/* Pixel (x, y)'s history cap from the filtered strata num and den (sw per row), or
 * TR_GRAD_NO_CAP where its shading did not change (`changed`: whether any stratum did).
 * The gradients lie in the previous frame's screen: with the same camera (`same`) a pixel
 * reads its own stratum; after a camera move its surface point (at its mean depth `depth`,
 * 0: none, followed back by its primitive id's motion) is projected into the previous
 * camera pc, as the temporal stage reprojects it. amin: alpha_min in [0, 1]. */
TR_FN float tr_grad_cap_pixel(const tr_camera *cam, const tr_camera *pc, int same, uint32_t x,
                              uint32_t y, float depth, uint32_t id, TR_CONST_GLOBAL float *motion,
                              uint32_t motion_count, int changed, TR_CONST_GLOBAL float *num,
                              TR_CONST_GLOBAL float *den, uint32_t sw, float amin) {
    const uint32_t w = cam->screen_width, h = cam->screen_height;
    int32_t sx = (int32_t)(x / TR_GRAD_STRATUM), sy = (int32_t)(y / TR_GRAD_STRATUM);
    if (!same) {
        sx = -1;
        if (depth > 0.0f && changed) {
            tr_vec3 p = tr_camera_point_at(cam, (float)x, (float)y, depth);
            if (motion && id < motion_count) {
                p = v3_sub(p, v3(motion[3u * id], motion[3u * id + 1u], motion[3u * id + 2u]));
            }
            float fx, fy, dist;
            if (tr_camera_project(pc, p, &fx, &fy, &dist) && fx >= 0.0f && fy >= 0.0f &&
                fx < (float)w && fy < (float)h) {
                sx = (int32_t)fx / TR_GRAD_STRATUM;
                sy = (int32_t)fy / TR_GRAD_STRATUM;
            }
        }
    }
    const uint32_t s = sx >= 0 ? (uint32_t)sy * sw + (uint32_t)sx : 0u;
    const float d = changed && sx >= 0 ? den[s] : 0.0f;
    const float lambda = d > 0.0f ? tr_fminf(1.0f, num[s] / d) : 0.0f;
    return lambda > 0.0f ? 1.0f / (amin + (1.0f - amin) * lambda) : TR_GRAD_NO_CAP;
}

#endif
