/* Compiled as OpenCL C 1.2 by CTest (clang -x cl -fsyntax-only) to prove that the
 * single-source kernel stays inside the subset both languages share: a kernel that
 * renders one sample per pixel into a film through the same functions the devices use.
 * ReSTIR's reservoir functions, DI's and GI's (run on the host today), are held to the
 * same subset, so that a device stage can include them. */
#include "kernel/emission.h"
#include "kernel/kernel.h"
#include "kernel/restir.h"
#include "kernel/restir_gi.h"

#define CHECK_ARRAY_PARAM(type, name, count) __global const type *name, uint count,

__kernel void tr_check_render(TR_SCENE_ARRAYS(CHECK_ARRAY_PARAM) uint accel,
                              float light_weight_total, tr_frame f, __global float *sum,
                              __global uint *count, __global float *albedo, __global float *normal,
                              __global float *depth, __global uint *prim) {
    tr_scene_view s;
#define CHECK_VIEW(type, name, count)                                                              \
    s.name = name;                                                                                 \
    s.count = count;
    TR_SCENE_ARRAYS(CHECK_VIEW)
    s.accel = accel;
    s.light_weight_total = light_weight_total;
    s.sky_cx = s.sky_cy = s.sky_cz = s.sky_radius = 0.0f; /* no light subpaths from the sky */
    const tr_film_view film =
        tr_film_view_make(sum, count, albedo, normal, depth, prim, f.camera.screen_width, f.passes);
    uint gx0, gy0, nx, ny;
    tr_frame_grid(&f, &gx0, &gy0, &nx, &ny);
    uint x = get_global_id(0), y = get_global_id(1);
    if (x < nx && y < ny) {
        (void)tr_render_grid_rows(&s, &f, &film, gx0 + x, gy0 + y, gx0 + x + 1u, gy0 + y + 1u);
    }
}
