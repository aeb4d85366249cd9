/* Compiled as OpenCL C 1.2 by CTest (clang -x cl -fsyntax-only) to prove that the post
 * layer's per-pixel operators (src/post/tonemap.h) stay single-source: a device can
 * tonemap its own film with the code the host's PNG writer and viewer run. */
#pragma OPENCL FP_CONTRACT OFF

#include "post/tonemap.h"

__kernel void tr_check_tonemap(__global const float *film_sum, __global const uint *film_count,
                               float scale, uint pixels, __global uint *argb) {
    const uint i = (uint)get_global_id(0);
    if (i >= pixels) {
        return;
    }
    argb[i] = 0xff000000u | tr_tonemap_film_pixel(film_sum[3 * i], film_sum[3 * i + 1],
                                                  film_sum[3 * i + 2], film_count[i], scale);
}

__kernel void tr_check_srgb_decode(__global float *values, uint n) {
    const uint i = (uint)get_global_id(0);
    if (i < n) {
        values[i] = tr_srgb_decode(values[i]);
    }
}

#include "post/filter.h"

/* The reconstruction's operators (src/post/filter.h), one work item per pixel, as a
 * device would run them on its own film. */
__kernel void tr_check_temporal(tr_camera cam, tr_camera prev, __global const float *color,
                                __global const float *normal, __global const float *depth,
                                __global const uint *prim, __global const float *prev_color,
                                __global const float *prev_moments, __global const float *prev_len,
                                __global const float *prev_depth,
                                __global const float *prev_normal, __global const uint *prev_prim,
                                __global float *out_color, __global float *out_moments,
                                __global float *out_len) {
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= cam.screen_width || y >= cam.screen_height) {
        return;
    }
    const uint i = y * cam.screen_width + x;
    float c[3], m[2], l;
    tr_post_temporal_pixel(&cam, &prev, x, y, color, normal, depth, prim, prev_color,
                           prev_moments, prev_len, prev_depth, prev_normal, prev_prim, 0.1f,
                           64.0f, c, m, &l);
    out_color[3 * i] = c[0];
    out_color[3 * i + 1] = c[1];
    out_color[3 * i + 2] = c[2];
    out_moments[2 * i] = m[0];
    out_moments[2 * i + 1] = m[1];
    out_len[i] = l;
}

__kernel void tr_check_filters(__global const float *in, __global const float *var,
                               __global const float *normal, __global const float *depth,
                               __global const float *albedo, int w, int h, int step,
                               __global float *out, __global float *out_var) {
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const int i = y * w + x;
    float a[3], b[3], c[3], v;
    tr_post_bilateral_pixel(in, w, h, x, y, 3, 2.0f, 0.3f, a);
    tr_post_atrous_pixel(in, normal, depth, albedo, w, h, x, y, step, 0.6f, 0.3f, 0.05f, 0.1f, b);
    tr_post_svgf_pixel(in, var, normal, depth, w, h, x, y, step, 4.0f, 128.0f, 1.0f, var[i], c,
                       &v);
    out[3 * i] = a[0] + b[0] + c[0] * tr_post_demod_factor(albedo[3 * i]);
    out[3 * i + 1] = a[1] + b[1] + c[1];
    out[3 * i + 2] = a[2] + b[2] + c[2];
    out_var[i] = v;
}
