/* Compiled as OpenCL C 1.2 by CTest (clang -x cl -fsyntax-only) to prove that temporal
 * upscaling's per-pixel operator (src/post/upscale.h) stays single-source: a device can run
 * the text the host runs (src/post/upscale.c). */
#pragma OPENCL FP_CONTRACT OFF
#include "post/upscale.h"
__kernel void tr_check_upscale(tr_camera cam, tr_camera prev, int wl, int hl,
                               __global const float *col, __global const float *pos,
                               __global const float *depth, __global const uint *prim,
                               __global const float *hcol, __global const float *hlen,
                               __global const float *hdepth, __global float *out,
                               __global float *olen, __global float *odepth) {
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    const int i = y * (int)cam.screen_width + x;
    float o[3], l, d;
    tr_upscale_pixel(&cam, &prev, x, y, wl, hl, col, pos, depth, prim, 0, 0u, hcol, hlen, hdepth, 0,
                     32.0f, o, &l, &d);
    out[3 * i] = o[0];
    out[3 * i + 1] = o[1];
    out[3 * i + 2] = o[2];
    olen[i] = l;
    odepth[i] = d;
}
