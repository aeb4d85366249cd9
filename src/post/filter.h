/* filter.h - per-pixel operators of real-time reconstruction: reprojection through the
 * previous camera, temporal accumulation, the bilateral filter, the edge-avoiding
 * à-trous wavelet filter and SVGF's variance-steered à-trous step.
 *
 * Single source like tonemap.h: C99 that also compiles as OpenCL C 1.2 (compat.h; the
 * CTest post_opencl_c checks it), so that a device can run the same text on its own
 * buffers. Each operator computes one output pixel from read-only inputs; the host's
 * wrappers (filter.c) run them over rows. Sums run in a fixed tap order, so that a
 * pixel's value never depends on how the image was split among threads.
 *
 * Buffers are planar per quantity, row-major, top row first: colour, albedo and normal
 * 3 floats per pixel, depth (distance along the camera ray, 0 where nothing was hit)
 * 1 float, the primitive id (triangle + 1, 0: nothing) 1 uint. */
#ifndef TR_POST_FILTER_H
#define TR_POST_FILTER_H

#include "../kernel/camera.h"
#include "../kernel/compat.h"
#include "../kernel/reproject.h"
#include "../kernel/types.h"
#include "../kernel/vec.h"

/* An IEEE single's bits as a float and back (OpenCL's as_float, as_uint; a union on
 * the host, which gcc vectorises). */
#if defined(__OPENCL_C_VERSION__) || defined(__OPENCL_VERSION__)
#define tr_post_bits_float(u) as_float(u)
#define tr_post_float_bits(f) as_uint(f)
#else
TR_FN float tr_post_bits_float(uint32_t u) {
    union {
        uint32_t u;
        float f;
    } v;
    v.u = u;
    return v.f;
}
TR_FN uint32_t tr_post_float_bits(float f) {
    union {
        uint32_t u;
        float f;
    } v;
    v.f = f;
    return v.u;
}
#endif

/* exp(-x) for the filters' weights, x >= 0 (below 0 it reads as 0; above ~69, NaN
 * included, as 69): 2^-t with t = x log2 e split into the nearest integer n, applied
 * through the exponent bits, and a remainder |f| <= ln2 / 2 whose exponential a
 * degree-5 Taylor polynomial gives to 6e-6 relative. n comes from the mantissa of
 * t + 1.5 * 2^23 (round to nearest, no float-to-int conversion), so there is no libm
 * call, no branch and nothing that traps: the host's loops over pixels vectorise, and a
 * device computes the same numbers. */
TR_FN float tr_post_exp_neg(float x) {
    float t = x * 1.44269504f;
    t = t < 100.0f ? t : 100.0f;
    t = t > 0.0f ? t : 0.0f;
    const float m = t + 12582912.0f;
    const uint32_t n = tr_post_float_bits(m) - 0x4B400000u;
    const float f = ((m - 12582912.0f) - t) * 0.693147181f;
    const float p =
        1.0f +
        f * (1.0f + f * (0.5f + f * (0.166666672f + f * (0.0416666679f + f * 0.00833333377f))));
    return p * tr_post_bits_float((127u - n) << 23);
}

/* Rec. 709 luminance of linear RGB. */
TR_FN float tr_post_luminance(float r, float g, float b) {
    return 0.2126f * r + 0.7152f * g + 0.0722f * b;
}

/* The reprojection of pixel (x, y) of the current frame (camera cam, its depth, normal
 * and primitive) into the previous frame (camera prev, its depth, normal and primitive
 * buffers): the bilinear weights of the four previous pixels around the reprojected
 * position, zero for a tap that is off screen or fails tr_reproject_consistent, in w[0..3]
 * for the taps (x0, y0), (x0+1, y0), (x0, y0+1), (x0+1, y0+1); *x0, *y0 receive the
 * top-left tap. Returns the sum of the weights (0: no history survives).
 *
 * Reprojection through the previous camera as in Nehab et al., "Accelerating
 * Real-Time Shading with Reverse Reprojection Caching", Graphics Hardware 2007.
 *
 * `motion` is how far the surface at the pixel moved since the previous frame (world
 * space; zero for a static scene): the point is followed back to where it was, p -
 * motion, before it is projected and tested, so that the history of a moving shape
 * (view --animate) follows it instead of failing the plane test: per-primitive motion
 * vectors, as a rasteriser's previous-frame transform gives them. Shapes translate
 * only, so the normal stays. tr_post_reproject is this with no motion (p - 0 is p:
 * the same numbers). */
TR_FN float tr_post_reproject_moving(const tr_camera *cam, const tr_camera *prev, uint32_t x,
                                     uint32_t y, float depth, tr_vec3 n, uint32_t prim,
                                     tr_vec3 motion, TR_CONST_GLOBAL float *prev_depth,
                                     TR_CONST_GLOBAL float *prev_normal,
                                     TR_CONST_GLOBAL uint32_t *prev_prim, int *x0, int *y0,
                                     float w[4]) {
    w[0] = w[1] = w[2] = w[3] = 0.0f;
    *x0 = *y0 = 0;
    if (!(depth > 0.0f)) {
        return 0.0f; /* nothing hit: no point to follow */
    }
    const tr_vec3 p = v3_sub(tr_camera_point_at(cam, (float)x, (float)y, depth), motion);
    return tr_reproject_weights(prev, p, n, prim, prev_depth, prev_normal, prev_prim, 0, x0, y0, w);
}

TR_FN float tr_post_reproject(const tr_camera *cam, const tr_camera *prev, uint32_t x, uint32_t y,
                              float depth, tr_vec3 n, uint32_t prim,
                              TR_CONST_GLOBAL float *prev_depth, TR_CONST_GLOBAL float *prev_normal,
                              TR_CONST_GLOBAL uint32_t *prev_prim, int *x0, int *y0, float w[4]) {
    return tr_post_reproject_moving(cam, prev, x, y, depth, n, prim, v3s(0.0f), prev_depth,
                                    prev_normal, prev_prim, x0, y0, w);
}

/* ---- Specular light apart (tr_recon_params.svgf_specular) ---------------------------- */

/* The specular history's reprojection by virtual motion: a reflection seen in a surface
 * moves with the reflected point's mirror image, which lies `virt` further along the camera
 * ray than the surface (the reflected hit's distance; for a flat mirror exactly the image).
 * The taps are found where that virtual point, followed back by the surface's motion,
 * projects into the previous camera, and tested as tr_post_reproject tests them, against the
 * surface point itself (same primitive, normal, tangent plane), so that the history still
 * belongs to this surface. Where that leaves less than 5 % of the weight (or virt is 0) it is
 * the surface's own reprojection, tr_post_reproject_moving. Same outputs as it. */
TR_FN float tr_post_reproject_virtual(const tr_camera *cam, const tr_camera *prev, uint32_t x,
                                      uint32_t y, float depth, float virt, tr_vec3 n, uint32_t prim,
                                      tr_vec3 motion, TR_CONST_GLOBAL float *prev_depth,
                                      TR_CONST_GLOBAL float *prev_normal,
                                      TR_CONST_GLOBAL uint32_t *prev_prim, int *x0, int *y0,
                                      float w[4]) {
    if (depth > 0.0f && virt > 0.0f) {
        const tr_vec3 p = v3_sub(tr_camera_point_at(cam, (float)x, (float)y, depth), motion);
        const tr_vec3 v = v3_sub(tr_camera_point_at(cam, (float)x, (float)y, depth + virt), motion);
        const tr_vec3 pd = v3_sub(p, prev->pos);
        const float dist = tr_sqrtf(v3_dot(pd, pd));
        float px, py, vd;
        const int pw = (int)prev->screen_width, ph = (int)prev->screen_height;
        if (tr_camera_project(prev, v, &px, &py, &vd) && px - 0.5f > -1.0f && py - 0.5f > -1.0f &&
            px - 0.5f < (float)pw && py - 0.5f < (float)ph) {
            const float fx = px - 0.5f, fy = py - 0.5f;
            const int ix = fx < 0.0f ? -1 : (int)fx, iy = fy < 0.0f ? -1 : (int)fy;
            const float ax = fx - (float)ix, ay = fy - (float)iy;
            float total = 0.0f;
            for (int k = 0; k < 4; ++k) {
                const int tx = ix + (k & 1), ty = iy + (k >> 1);
                w[k] = 0.0f;
                if (tx < 0 || ty < 0 || tx >= pw || ty >= ph) {
                    continue;
                }
                const int i = ty * pw + tx;
                if (!(prev_depth[i] > 0.0f)) {
                    continue;
                }
                const tr_vec3 pn =
                    v3(prev_normal[3 * i], prev_normal[3 * i + 1], prev_normal[3 * i + 2]);
                const tr_vec3 q = tr_camera_point_at(prev, (float)tx, (float)ty, prev_depth[i]);
                if (!tr_reproject_consistent(prim, p, n, dist, prev_prim[i], q, pn)) {
                    continue;
                }
                w[k] = ((k & 1) ? ax : 1.0f - ax) * ((k >> 1) ? ay : 1.0f - ay);
                total += w[k];
            }
            if (total > 0.05f) {
                *x0 = ix;
                *y0 = iy;
                return total;
            }
        }
    }
    return tr_post_reproject_moving(cam, prev, x, y, depth, n, prim, motion, prev_depth,
                                    prev_normal, prev_prim, x0, y0, w);
}

/* How far along the reflection the virtual point is taken for GGX alpha `alpha`: the whole
 * hit distance up to alpha 0.1 (a sharp reflection moves with its image), none from 0.5 on
 * (a rough lobe's light is spread over many directions and moves with the surface), a
 * smoothstep between. */
TR_FN float tr_post_spec_virtual(float alpha) {
    const float t = tr_fminf(tr_fmaxf((alpha - 0.1f) / 0.4f, 0.0f), 1.0f);
    return 1.0f - t * t * (3.0f - 2.0f * t);
}

/* The specular history's length cap for GGX alpha `alpha` under the cap max_len: a sharp
 * reflection changes with the view and keeps TR_POST_SPEC_MIN_LEN frames, a rough lobe
 * (alpha 0.5 on) as many as the diffuse light, a smoothstep between. */
#define TR_POST_SPEC_MIN_LEN 4.0f
TR_FN float tr_post_spec_max_len(float alpha, float max_len) {
    const float t = tr_fminf(tr_fmaxf((alpha - 0.05f) / 0.45f, 0.0f), 1.0f);
    const float s = t * t * (3.0f - 2.0f * t);
    const float lo = tr_fminf(TR_POST_SPEC_MIN_LEN, max_len);
    return lo + (max_len - lo) * s;
}

/* The history length cap of a pixel whose surface moved by `motion` since the previous
 * frame: max_len_moving where it moved (its shading changes with the motion, and a long
 * history would lag behind it), max_len elsewhere. */
TR_FN float tr_post_max_len(tr_vec3 motion, float max_len, float max_len_moving) {
    const int moved = motion.x != 0.0f || motion.y != 0.0f || motion.z != 0.0f;
    return moved ? tr_fminf(max_len, max_len_moving) : max_len;
}

/* A previous frame's three channels per pixel (`prev`, pw pixels wide) read at
 * reprojection taps: the weights w (of sum total) at x0, y0, normalised. */
TR_FN void tr_post_taps3(TR_CONST_GLOBAL float *prev, float total, const float w[4], int x0, int y0,
                         int pw, float out[3]) {
    out[0] = out[1] = out[2] = 0.0f;
    for (int k = 0; k < 4; ++k) {
        if (w[k] > 0.0f) {
            const int j = (y0 + (k >> 1)) * pw + x0 + (k & 1);
            const float wk = w[k] / total;
            out[0] += wk * prev[3 * j];
            out[1] += wk * prev[3 * j + 1];
            out[2] += wk * prev[3 * j + 2];
        }
    }
}

/* The blend of tr_post_temporal_pixel for a pixel whose reprojection kept weights w
 * (sum total > 0.05) on the previous pixels from (x0, y0) (tr_post_reproject's taps, pw
 * pixels a row): the history interpolated by the normalised weights, then the
 * exponential moving average with the new sample (r, g, b). Separate so that a host
 * which finds the weights its own way blends with the same arithmetic. */
TR_FN void tr_post_temporal_blend(float r, float g, float b, float total, const float w[4], int x0,
                                  int y0, int pw, TR_CONST_GLOBAL float *prev_color,
                                  TR_CONST_GLOBAL float *prev_moments,
                                  TR_CONST_GLOBAL float *prev_len, float alpha_min, float max_len,
                                  float out_color[3], float out_moments[2], float *out_len) {
    const float l = tr_post_luminance(r, g, b);
    float hc[3], hm[2] = {0.0f, 0.0f}, hl = 0.0f;
    tr_post_taps3(prev_color, total, w, x0, y0, pw, hc);
    for (int k = 0; k < 4; ++k) {
        if (w[k] > 0.0f) {
            const int j = (y0 + (k >> 1)) * pw + x0 + (k & 1);
            const float wk = w[k] / total;
            hm[0] += wk * prev_moments[2 * j];
            hm[1] += wk * prev_moments[2 * j + 1];
            hl += wk * prev_len[j];
        }
    }
    const float len = tr_fminf(hl + 1.0f, max_len);
    const float a = tr_fmaxf(alpha_min, 1.0f / len);
    out_color[0] = hc[0] + a * (r - hc[0]);
    out_color[1] = hc[1] + a * (g - hc[1]);
    out_color[2] = hc[2] + a * (b - hc[2]);
    out_moments[0] = hm[0] + a * (l - hm[0]);
    out_moments[1] = hm[1] + a * (l * l - hm[1]);
    *out_len = len;
}

/* The albedo history of one pixel (tr_recon_params.albedo_alpha) where
 * tr_post_temporal_blend blended its colour with the weights w (of sum total) at x0, y0
 * of a previous frame pw pixels wide: the previous albedo history interpolated the same
 * way, then the pixel's albedo this frame (cur, 3 floats) blended in at weight a. */
TR_FN void tr_post_albedo_blend(TR_CONST_GLOBAL float *cur, float total, const float w[4], int x0,
                                int y0, int pw, TR_CONST_GLOBAL float *prev, float a,
                                float out[3]) {
    float h[3];
    tr_post_taps3(prev, total, w, x0, y0, pw, h);
    out[0] = h[0] + a * (cur[0] - h[0]);
    out[1] = h[1] + a * (cur[1] - h[1]);
    out[2] = h[2] + a * (cur[2] - h[2]);
}

/* Temporal accumulation of pixel (x, y) (Schied et al. 2017, section 4.1): the
 * history (colour, luminance moments and length of the previous frame) reprojected by
 * tr_post_reproject's bilinear weights, blended with the new sample by an exponential
 * moving average of weight max(alpha_min, 1 / length), so that a fresh history averages
 * uniformly until it is long enough to become an EMA. No surviving history: the sample
 * alone, length 1. Writes colour, moments (mean luminance and mean squared luminance)
 * and the new length. `motion`: the surface's own movement since the previous frame
 * (tr_post_reproject_moving); tr_post_temporal_pixel is this with none.
 * tr_post_temporal_pixel_taps also gives the surviving taps (w, x0, y0) and returns their
 * sum, 0 where no history survives; tr_post_temporal_pixel_moving keeps them to itself. */
TR_FN float tr_post_temporal_pixel_taps(
    const tr_camera *cam, const tr_camera *prev, uint32_t x, uint32_t y, tr_vec3 motion,
    TR_CONST_GLOBAL float *color, TR_CONST_GLOBAL float *normal, TR_CONST_GLOBAL float *depth,
    TR_CONST_GLOBAL uint32_t *prim, TR_CONST_GLOBAL float *prev_color,
    TR_CONST_GLOBAL float *prev_moments, TR_CONST_GLOBAL float *prev_len,
    TR_CONST_GLOBAL float *prev_depth, TR_CONST_GLOBAL float *prev_normal,
    TR_CONST_GLOBAL uint32_t *prev_prim, float alpha_min, float max_len, float out_color[3],
    float out_moments[2], float *out_len, float w[4], int *x0, int *y0) {
    const int i = (int)(y * cam->screen_width + x);
    const float r = color[3 * i], g = color[3 * i + 1], b = color[3 * i + 2];
    const float l = tr_post_luminance(r, g, b);
    const tr_vec3 n = v3(normal[3 * i], normal[3 * i + 1], normal[3 * i + 2]);
    const float total = tr_post_reproject_moving(cam, prev, x, y, depth[i], n, prim[i], motion,
                                                 prev_depth, prev_normal, prev_prim, x0, y0, w);
    /* A sliver of a tap (a pixel at a silhouette) is not enough history to trust. */
    if (!(total > 0.05f)) {
        out_color[0] = r;
        out_color[1] = g;
        out_color[2] = b;
        out_moments[0] = l;
        out_moments[1] = l * l;
        *out_len = 1.0f;
        return 0.0f;
    }
    tr_post_temporal_blend(r, g, b, total, w, *x0, *y0, (int)prev->screen_width, prev_color,
                           prev_moments, prev_len, alpha_min, max_len, out_color, out_moments,
                           out_len);
    return total;
}

TR_FN void
tr_post_temporal_pixel_moving(const tr_camera *cam, const tr_camera *prev, uint32_t x, uint32_t y,
                              tr_vec3 motion, TR_CONST_GLOBAL float *color,
                              TR_CONST_GLOBAL float *normal, TR_CONST_GLOBAL float *depth,
                              TR_CONST_GLOBAL uint32_t *prim, TR_CONST_GLOBAL float *prev_color,
                              TR_CONST_GLOBAL float *prev_moments, TR_CONST_GLOBAL float *prev_len,
                              TR_CONST_GLOBAL float *prev_depth, TR_CONST_GLOBAL float *prev_normal,
                              TR_CONST_GLOBAL uint32_t *prev_prim, float alpha_min, float max_len,
                              float out_color[3], float out_moments[2], float *out_len) {
    float w[4];
    int x0, y0;
    tr_post_temporal_pixel_taps(cam, prev, x, y, motion, color, normal, depth, prim, prev_color,
                                prev_moments, prev_len, prev_depth, prev_normal, prev_prim,
                                alpha_min, max_len, out_color, out_moments, out_len, w, &x0, &y0);
}

TR_FN void
tr_post_temporal_pixel(const tr_camera *cam, const tr_camera *prev, uint32_t x, uint32_t y,
                       TR_CONST_GLOBAL float *color, TR_CONST_GLOBAL float *normal,
                       TR_CONST_GLOBAL float *depth, TR_CONST_GLOBAL uint32_t *prim,
                       TR_CONST_GLOBAL float *prev_color, TR_CONST_GLOBAL float *prev_moments,
                       TR_CONST_GLOBAL float *prev_len, TR_CONST_GLOBAL float *prev_depth,
                       TR_CONST_GLOBAL float *prev_normal, TR_CONST_GLOBAL uint32_t *prev_prim,
                       float alpha_min, float max_len, float out_color[3], float out_moments[2],
                       float *out_len) {
    tr_post_temporal_pixel_moving(cam, prev, x, y, v3s(0.0f), color, normal, depth, prim,
                                  prev_color, prev_moments, prev_len, prev_depth, prev_normal,
                                  prev_prim, alpha_min, max_len, out_color, out_moments, out_len);
}

/* Temporal antialiasing of pixel (x, y) (Karis, "High Quality Temporal Supersampling",
 * SIGGRAPH 2014 course; the last stage of Schied et al. 2017): the previous output
 * `prev_out` reprojected as tr_post_reproject does (NULL: none), clamped per channel to
 * the range of the current output's 3x3 neighbourhood so that stale colour cannot
 * linger (ghosting), then blended with the current pixel by weight alpha. Where no
 * history survives, the current pixel as it is. */
TR_FN void tr_post_taa_pixel(const tr_camera *cam, const tr_camera *prev, int x, int y,
                             TR_CONST_GLOBAL float *cur, TR_CONST_GLOBAL float *normal,
                             TR_CONST_GLOBAL float *depth, TR_CONST_GLOBAL uint32_t *prim,
                             TR_CONST_GLOBAL float *prev_out, TR_CONST_GLOBAL float *prev_depth,
                             TR_CONST_GLOBAL float *prev_normal,
                             TR_CONST_GLOBAL uint32_t *prev_prim, float alpha, float out[3]) {
    const int w = (int)cam->screen_width, h = (int)cam->screen_height;
    const int c = y * w + x;
    out[0] = cur[3 * c];
    out[1] = cur[3 * c + 1];
    out[2] = cur[3 * c + 2];
    if (!prev_out) {
        return;
    }
    float wts[4];
    int x0, y0;
    const tr_vec3 n = v3(normal[3 * c], normal[3 * c + 1], normal[3 * c + 2]);
    const float total = tr_post_reproject(cam, prev, (uint32_t)x, (uint32_t)y, depth[c], n, prim[c],
                                          prev_depth, prev_normal, prev_prim, &x0, &y0, wts);
    if (!(total > 0.05f)) {
        return;
    }
    const int pw = (int)prev->screen_width;
    for (int k = 0; k < 3; ++k) {
        float lo = out[k], hi = out[k];
        for (int dy = -1; dy <= 1; ++dy) {
            for (int dx = -1; dx <= 1; ++dx) {
                const int tx = x + dx, ty = y + dy;
                if (tx >= 0 && ty >= 0 && tx < w && ty < h) {
                    const float v = cur[3 * (ty * w + tx) + k];
                    lo = tr_fminf(lo, v);
                    hi = tr_fmaxf(hi, v);
                }
            }
        }
        float hv = 0.0f;
        for (int t = 0; t < 4; ++t) {
            if (wts[t] > 0.0f) {
                hv += wts[t] / total * prev_out[3 * ((y0 + (t >> 1)) * pw + x0 + (t & 1)) + k];
            }
        }
        hv = tr_fminf(tr_fmaxf(hv, lo), hi);
        out[k] = hv + alpha * (out[k] - hv);
    }
}

/* Demodulation (Dammertz et al. 2010, section 4; Schied et al. 2017, section 4.1): the
 * filters smooth illumination = radiance / albedo, so that texture and material edges
 * survive, and multiply the albedo back after.
 *
 * An albedo channel below TR_POST_ALBEDO_FLOOR counts as the floor, for two reasons.
 * - The base colour predicts a pixel's light only where the diffuse lobe dominates. A
 *   dielectric's specular lobe reflects, averaged over a cosine-weighted hemisphere, about
 *   9 % of light whatever its base colour (Fresnel's reflectance for index 1.5 integrated
 *   so: 0.0918). Where a channel's base colour is darker than that (the red plastic's
 *   green and blue, a dark texture), the pixel's light in that channel is mostly specular,
 *   and dividing it by the base colour only magnifies the specular noise that the filter
 *   then spreads.
 * - The factor must not jump. It used to be the albedo above 10^-3 and 1 below: a pixel
 *   whose blue channel was 10^-4 took its neighbours' illumination, divided by their
 *   0.02, undivided, and showed it as saturated blue (a dark spider's legs under a blue
 *   sky).
 * Measured on the standard bench (docs/realtime.md): the textured demo gains about 1 dB;
 * the other shipped real-time scenes move by 0.01 dB at most. */
#define TR_POST_ALBEDO_FLOOR 0.09f

TR_FN float tr_post_demod_factor(float albedo) {
    return albedo > TR_POST_ALBEDO_FLOOR ? albedo : TR_POST_ALBEDO_FLOOR;
}

/* The factor an upscaled frame's light is divided by (the traced frame's albedo) and
 * multiplied by (the output's) when tr_recon_params.upscale_albedo keeps it apart: the
 * albedo itself between 0.01 and 1. Nothing is filtered between the two, so a low floor
 * keeps the ratio exact where the two albedos agree (0.09: 0.15 dB worse on the textured
 * demo at a quarter of the pixels, docs/realtime.md); the cap keeps an emitter's
 * "albedo" (its radiance) from multiplying light spread onto it from its neighbours. */
#define TR_POST_UPSCALE_ALBEDO_FLOOR 0.01f
TR_FN float tr_post_upscale_factor(float albedo) {
    return albedo > 1.0f                           ? 1.0f
           : albedo > TR_POST_UPSCALE_ALBEDO_FLOOR ? albedo
                                                   : TR_POST_UPSCALE_ALBEDO_FLOOR;
}

/* The thesis's baseline: a bilateral filter (Tomasi and Manduchi, "Bilateral Filtering
 * for Gray and Color Images", ICCV 1998) of pixel (x, y) of the w x h colour image `in`
 * into out[0..2]: Gaussian weights in distance (sigma_s pixels) and in colour
 * difference (sigma_r), over a (2 radius + 1)^2 window. It knows nothing of the
 * geometry, which is why the guided filters below beat it. */
TR_FN void tr_post_bilateral_pixel(TR_CONST_GLOBAL float *in, int w, int h, int x, int y,
                                   int radius, float sigma_s, float sigma_r, float out[3]) {
    const int c = y * w + x;
    const float cr = in[3 * c], cg = in[3 * c + 1], cb = in[3 * c + 2];
    const float is = 1.0f / (2.0f * sigma_s * sigma_s), ir = 1.0f / (2.0f * sigma_r * sigma_r);
    float sr = 0.0f, sg = 0.0f, sb = 0.0f, sw = 0.0f;
    for (int dy = -radius; dy <= radius; ++dy) {
        const int ty = y + dy;
        if (ty < 0 || ty >= h) {
            continue;
        }
        for (int dx = -radius; dx <= radius; ++dx) {
            const int tx = x + dx;
            if (tx < 0 || tx >= w) {
                continue;
            }
            const int i = ty * w + tx;
            const float dr = in[3 * i] - cr, dg = in[3 * i + 1] - cg, db = in[3 * i + 2] - cb;
            const float wt = tr_post_exp_neg((float)(dx * dx + dy * dy) * is +
                                             (dr * dr + dg * dg + db * db) * ir);
            sr += wt * in[3 * i];
            sg += wt * in[3 * i + 1];
            sb += wt * in[3 * i + 2];
            sw += wt;
        }
    }
    out[0] = sr / sw;
    out[1] = sg / sw;
    out[2] = sb / sw;
}

/* The B3 spline's taps (1, 4, 6, 4, 1) / 16: the à-trous scaling function of both
 * Dammertz et al. and Schied et al. */
TR_FN float tr_post_b3(int k) {
    return k == 0 ? 0.375f : (k == 1 || k == -1) ? 0.25f : 0.0625f;
}

/* One iteration of the edge-avoiding à-trous wavelet transform (Dammertz, Sewtz,
 * Hanika and Lensch, "Edge-Avoiding À-Trous Wavelet Transform for fast Global
 * Illumination Filtering", HPG 2010) at pixel (x, y): the 5x5 B3 kernel with holes of
 * `step` pixels, each tap weighted by exp(-|Δ|^2 / sigma^2) of the differences in
 * (demodulated) colour, normal and depth (the paper uses world position; along one
 * camera ray depth carries the same edge, relative to the centre's depth) and albedo. */
TR_FN void tr_post_atrous_pixel(TR_CONST_GLOBAL float *in, TR_CONST_GLOBAL float *normal,
                                TR_CONST_GLOBAL float *depth, TR_CONST_GLOBAL float *albedo, int w,
                                int h, int x, int y, int step, float sigma_c, float sigma_n,
                                float sigma_z, float sigma_a, float out[3]) {
    const int c = y * w + x;
    const float cr = in[3 * c], cg = in[3 * c + 1], cb = in[3 * c + 2];
    const tr_vec3 cn = v3(normal[3 * c], normal[3 * c + 1], normal[3 * c + 2]);
    const float cz = depth[c];
    const float ca0 = albedo[3 * c], ca1 = albedo[3 * c + 1], ca2 = albedo[3 * c + 2];
    const float icz = 1.0f / (cz > 1e-6f ? cz : 1.0f);
    const float ic = 1.0f / (sigma_c * sigma_c), in2 = 1.0f / (sigma_n * sigma_n);
    const float iz = 1.0f / (sigma_z * sigma_z), ia = 1.0f / (sigma_a * sigma_a);
    float sr = 0.0f, sg = 0.0f, sb = 0.0f, sw = 0.0f;
    for (int ky = -2; ky <= 2; ++ky) {
        const int ty = y + ky * step;
        if (ty < 0 || ty >= h) {
            continue;
        }
        for (int kx = -2; kx <= 2; ++kx) {
            const int tx = x + kx * step;
            if (tx < 0 || tx >= w) {
                continue;
            }
            const int i = ty * w + tx;
            const float dr = in[3 * i] - cr, dg = in[3 * i + 1] - cg, db = in[3 * i + 2] - cb;
            const tr_vec3 dn = v3_sub(v3(normal[3 * i], normal[3 * i + 1], normal[3 * i + 2]), cn);
            const float dz = (depth[i] - cz) * icz;
            const float da0 = albedo[3 * i] - ca0, da1 = albedo[3 * i + 1] - ca1,
                        da2 = albedo[3 * i + 2] - ca2;
            const float e = (dr * dr + dg * dg + db * db) * ic + v3_dot(dn, dn) * in2 +
                            dz * dz * iz + (da0 * da0 + da1 * da1 + da2 * da2) * ia;
            const float wt = tr_post_b3(kx) * tr_post_b3(ky) * tr_post_exp_neg(e);
            sr += wt * in[3 * i];
            sg += wt * in[3 * i + 1];
            sb += wt * in[3 * i + 2];
            sw += wt;
        }
    }
    out[0] = sr / sw;
    out[1] = sg / sw;
    out[2] = sb / sw;
}

/* SVGF's depth coefficient at pixel (x, y): 1 / (sigma_z |∇z|), with depth's
 * screen-space gradient by central differences (the paper takes it from the
 * rasteriser's derivatives) and a floor of 1e-3 of the depth itself, so that a surface
 * seen head-on still tolerates its own noise. */
TR_FN float tr_post_svgf_kz(TR_CONST_GLOBAL float *depth, int w, int h, int x, int y,
                            float sigma_z) {
    const int xl = x > 0 ? x - 1 : x, xr = x + 1 < w ? x + 1 : x;
    const int yu = y > 0 ? y - 1 : y, yd = y + 1 < h ? y + 1 : y;
    const float gx = (depth[y * w + xr] - depth[y * w + xl]) / (float)(xr - xl > 0 ? xr - xl : 1);
    const float gy = (depth[yd * w + x] - depth[yu * w + x]) / (float)(yd - yu > 0 ? yd - yu : 1);
    const float grad = tr_sqrtf(gx * gx + gy * gy) + 1e-3f * depth[y * w + x];
    return 1.0f / (sigma_z * grad + 1e-6f);
}

/* The boost of a short history's spatial variance estimate: TR_POST_SVGF_SHORT_BOOST /
 * length. It was 4 with sigma_l 8 and the first level fed back; with sigma_l 4 and no
 * feedback (tr_recon_params_default) 16 keeps the luminance weight of a one-frame history
 * what it was (4 sqrt(16) = 8 sqrt(4)), so that the frames after a cut or a disocclusion,
 * which no longer receive a filtered history, are filtered as strongly as before. */
#define TR_POST_SVGF_SHORT_BOOST 16.0f

/* SVGF's variance of pixel (x, y)'s luminance (Schied et al. 2017, section 4.2): from
 * the temporal moments once 4 frames of history exist, before that from the 5x5
 * neighbourhood's moments (the paper takes 7x7 on the same condition), restricted to
 * taps whose normal is within ~25 degrees so that it stays on one surface, and boosted
 * by TR_POST_SVGF_SHORT_BOOST / length, since so few frames are less to trust. */
TR_FN float tr_post_svgf_variance_pixel(TR_CONST_GLOBAL float *illum,
                                        TR_CONST_GLOBAL float *moments, TR_CONST_GLOBAL float *len,
                                        TR_CONST_GLOBAL float *normal, int w, int h, int x, int y) {
    const int c = y * w + x;
    if (len[c] >= 4.0f) {
        const float m = moments[2 * c];
        return tr_fmaxf(moments[2 * c + 1] - m * m, 0.0f);
    }
    float s1 = 0.0f, s2 = 0.0f, sw = 0.0f;
    for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx) {
            const int tx = x + dx, ty = y + dy;
            if (tx < 0 || ty < 0 || tx >= w || ty >= h) {
                continue;
            }
            const int i = ty * w + tx;
            const float nd = normal[3 * c] * normal[3 * i] + normal[3 * c + 1] * normal[3 * i + 1] +
                             normal[3 * c + 2] * normal[3 * i + 2];
            const float wt = (dx == 0 && dy == 0) || nd > 0.9f ? 1.0f : 0.0f;
            const float l = tr_post_luminance(illum[3 * i], illum[3 * i + 1], illum[3 * i + 2]);
            s1 += wt * l;
            s2 += wt * l * l;
            sw += wt;
        }
    }
    const float m = s1 / sw;
    return tr_fmaxf(s2 / sw - m * m, 0.0f) * (TR_POST_SVGF_SHORT_BOOST / len[c]);
}

/* The variance of pixel (x, y) through SVGF's 3x3 Gaussian prefilter (taps 1, 1/2, 1/4,
 * renormalised at the border), which keeps one noisy estimate from stopping the filter. */
TR_FN float tr_post_var3x3(TR_CONST_GLOBAL float *var, int w, int h, int x, int y) {
    float cv = 0.0f, cw = 0.0f;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const int tx = x + dx, ty = y + dy;
            if (tx < 0 || ty < 0 || tx >= w || ty >= h) {
                continue;
            }
            const float k = (dx ? 0.5f : 1.0f) * (dy ? 0.5f : 1.0f);
            cv += k * var[ty * w + tx];
            cw += k;
        }
    }
    return cv / cw;
}

/* SVGF's luminance coefficient for a centre of (prefiltered) variance var:
 * 1 / (sigma_l sqrt(var)). */
TR_FN float tr_post_svgf_kl(float var, float sigma_l) {
    return 1.0f / (sigma_l * tr_sqrtf(tr_fmaxf(var, 0.0f)) + 1e-6f);
}

/* 1 / |offset| in pixels of tap (kx, ky) at hole size `step`; 0 for the centre (whose
 * depth difference is 0). */
TR_FN float tr_post_svgf_idist(int kx, int ky, int step) {
    return kx || ky ? 1.0f / (tr_sqrtf((float)(kx * kx + ky * ky)) * (float)step) : 0.0f;
}

/* The exponent of SVGF's edge-stopping weight (Schied et al. 2017, eq. 3-5): depth
 * |Δz| / (sigma_z |∇z| |offset|), luminance |Δl| / (sigma_l sqrt(g(Var))), and the
 * normal term max(0, n·n')^sigma_n written as exp(-sigma_n (1 - n·n')) (kn = sigma_n,
 * or 0 where the centre has no normal): ln(d) = -(1 - d) to first order, the same
 * weight to within 1 % wherever it is above 0.01 (d > 0.96 for sigma_n 128), and one
 * exponential per tap instead of a pow and an exp. */
TR_FN float tr_post_svgf_exponent(float dz, float kz, float idist, float dl, float kl, float kn,
                                  float nd) {
    return tr_fabsf(dz) * kz * idist + tr_fabsf(dl) * kl + kn * (1.0f - nd);
}

/* One iteration of SVGF's à-trous step (Schied et al., "Spatiotemporal
 * Variance-Guided Filtering: Real-Time Reconstruction for Path-Traced Global
 * Illumination", HPG 2017, section 4.3) at pixel (x, y): the B3 kernel with holes of
 * `step` pixels, weighted by tr_post_svgf_exponent's terms, the luminance one steered
 * by centre_var (the centre's variance through the paper's 3x3 Gaussian; the caller's).
 * Filters colour into out[0..2] and the variance with squared weights into *out_var
 * (eq. 5), for the next iteration. The host's vectorised loops (filter.c) compute the
 * same sums in the same order. */
TR_FN void tr_post_svgf_pixel(TR_CONST_GLOBAL float *in, TR_CONST_GLOBAL float *var,
                              TR_CONST_GLOBAL float *normal, TR_CONST_GLOBAL float *depth, int w,
                              int h, int x, int y, int step, float sigma_l, float sigma_n,
                              float sigma_z, float centre_var, float out[3], float *out_var) {
    const int c = y * w + x;
    const float cl = tr_post_luminance(in[3 * c], in[3 * c + 1], in[3 * c + 2]);
    const float cnx = normal[3 * c], cny = normal[3 * c + 1], cnz = normal[3 * c + 2];
    /* No surface hit: no normal term. */
    const float kn = cnx * cnx + cny * cny + cnz * cnz > 0.25f ? sigma_n : 0.0f;
    const float cz = depth[c];
    const float kz = tr_post_svgf_kz(depth, w, h, x, y, sigma_z);
    const float kl = tr_post_svgf_kl(centre_var, sigma_l);
    float sr = 0.0f, sg = 0.0f, sb = 0.0f, sw = 0.0f, sv = 0.0f;
    for (int ky = -2; ky <= 2; ++ky) {
        const int ty = y + ky * step;
        if (ty < 0 || ty >= h) {
            continue;
        }
        for (int kx = -2; kx <= 2; ++kx) {
            const int tx = x + kx * step;
            if (tx < 0 || tx >= w) {
                continue;
            }
            const int i = ty * w + tx;
            const float li = tr_post_luminance(in[3 * i], in[3 * i + 1], in[3 * i + 2]);
            const float nd =
                cnx * normal[3 * i] + cny * normal[3 * i + 1] + cnz * normal[3 * i + 2];
            const float e = tr_post_svgf_exponent(
                depth[i] - cz, kz, tr_post_svgf_idist(kx, ky, step), li - cl, kl, kn, nd);
            const float wt = tr_post_b3(kx) * tr_post_b3(ky) * tr_post_exp_neg(e);
            sr += wt * in[3 * i];
            sg += wt * in[3 * i + 1];
            sb += wt * in[3 * i + 2];
            sv += wt * wt * var[i];
            sw += wt;
        }
    }
    /* The centre's own weight is b3(0)^2 > 0: sw never vanishes. */
    out[0] = sr / sw;
    out[1] = sg / sw;
    out[2] = sb / sw;
    *out_var = sv / (sw * sw);
}

/* The GGX lobe's pre-integrated albedo table's lookup (dfg.h: A at [2 (j N + i)], B at
 * [2 (j N + i) + 1] over TR_DFG_N x TR_DFG_N nodes of mu and alpha): A and B at (mu,
 * alpha), bilinear between the nodes, clamped to the table. Here so that a device reads
 * the host's table with the host's arithmetic. */
#define TR_DFG_N 32

/* Position x in [0, 1] on the table's axis: the lower node and the next one's weight. */
TR_FN int tr_post_dfg_cell(float x, float *w) {
    const float t = tr_fminf(tr_fmaxf(x, 0.0f), 1.0f) * (float)(TR_DFG_N - 1);
    int i = (int)t;
    if (i > TR_DFG_N - 2) {
        i = TR_DFG_N - 2;
    }
    *w = t - (float)i;
    return i;
}

TR_FN void tr_post_dfg_at(TR_CONST_GLOBAL float *table, float mu, float alpha, float *a, float *b) {
    float wm, wa;
    const int i = tr_post_dfg_cell(mu, &wm), j = tr_post_dfg_cell(alpha, &wa);
    for (int c = 0; c < 2; ++c) {
        TR_CONST_GLOBAL float *r0 = table + 2 * (j * TR_DFG_N) + c;
        TR_CONST_GLOBAL float *r1 = r0 + 2 * TR_DFG_N;
        const float e0 = r0[2 * i] + (r0[2 * i + 2] - r0[2 * i]) * wm;
        const float e1 = r1[2 * i] + (r1[2 * i + 2] - r1[2 * i]) * wm;
        if (c == 0) {
            *a = e0 + (e1 - e0) * wa;
        } else {
            *b = e0 + (e1 - e0) * wa;
        }
    }
}

/* Diffuse and specular apart (svgf_specular) at pixel (x, y) of cam: from its specular
 * pass sp (8 floats: the specular light, F0, GGX alpha, the reflection's distance), its
 * normal n, primitive id and colour (3 floats), the specular albedo F0 A + B (the DFG table
 * at its mean F0 and alpha and the cosine between n and the camera ray; 0 where it has no
 * specular lobe) into alb, its specular light over it into illum, the rest of its colour
 * (the diffuse light) into diffuse. A pixel replaced through a refraction or a curved
 * mirror (TR_PRIM_PSR_CURVED) keeps all its light in the diffuse part. */
TR_FN void tr_post_spec_split_pixel(const tr_camera *cam, uint32_t x, uint32_t y, tr_vec3 n,
                                    uint32_t prim, TR_CONST_GLOBAL float *sp,
                                    TR_CONST_GLOBAL float *dfg, TR_CONST_GLOBAL float *color,
                                    float alb[3], float illum[3], float diffuse[3]) {
    const tr_vec3 d = v3_sub(tr_camera_point_at(cam, (float)x, (float)y, 1.0f), cam->pos);
    float a, b;
    tr_post_dfg_at(dfg, tr_fabsf(v3_dot(n, d)), sp[6], &a, &b);
    const int lobe = sp[3] > 0.0f || sp[4] > 0.0f || sp[5] > 0.0f;
    const int apart = (prim & TR_PRIM_PSR_CURVED) == 0u;
    for (int k = 0; k < 3; ++k) {
        alb[k] = lobe && apart ? sp[3 + k] * a + b : 0.0f;
        const float spec = apart ? sp[k] : 0.0f;
        illum[k] = spec / tr_post_demod_factor(alb[k]);
        diffuse[k] = color[k] - spec;
    }
}

/* The specular part's temporal stage at pixel (x, y) (w pixels a row) of cam: its light c
 * reprojected into prev by virtual motion (tr_post_reproject_virtual, the reflection's
 * distance `dist` weighed by tr_post_spec_virtual(alpha)) and blended with the history
 * under the cap `cap` lowered by the roughness (tr_post_spec_max_len); where fewer than
 * 5 % of the taps' weight survive, or without history, a fresh history of c. */
TR_FN void tr_post_spec_temporal_pixel(
    const tr_camera *cam, const tr_camera *prev, uint32_t x, uint32_t y, int w, const float c[3],
    tr_vec3 n, float depth, uint32_t id, tr_vec3 m, float alpha, float dist, int have_history,
    TR_CONST_GLOBAL float *prev_color, TR_CONST_GLOBAL float *prev_moments,
    TR_CONST_GLOBAL float *prev_len, TR_CONST_GLOBAL float *prev_depth,
    TR_CONST_GLOBAL float *prev_normal, TR_CONST_GLOBAL uint32_t *prev_prim, float alpha_min,
    float cap, float out_color[3], float out_moments[2], float *out_len) {
    float wt[4] = {0.0f, 0.0f, 0.0f, 0.0f}, total = 0.0f;
    int x0 = 0, y0 = 0;
    if (have_history) {
        total =
            tr_post_reproject_virtual(cam, prev, x, y, depth, dist * tr_post_spec_virtual(alpha), n,
                                      id, m, prev_depth, prev_normal, prev_prim, &x0, &y0, wt);
    }
    if (total > 0.05f) {
        tr_post_temporal_blend(c[0], c[1], c[2], total, wt, x0, y0, w, prev_color, prev_moments,
                               prev_len, alpha_min, tr_post_spec_max_len(alpha, cap), out_color,
                               out_moments, out_len);
    } else {
        const float l = tr_post_luminance(c[0], c[1], c[2]);
        out_color[0] = c[0];
        out_color[1] = c[1];
        out_color[2] = c[2];
        out_moments[0] = l;
        out_moments[1] = l * l;
        *out_len = 1.0f;
    }
}

#endif
