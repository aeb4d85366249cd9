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
