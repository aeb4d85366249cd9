/* entry.cl - the OpenCL entry point: the __kernel that runs tr_render_grid_rows, the
 * same code the CPU device runs, for one traced pixel per work item, and accumulates its
 * samples into the film on the device with tr_film_add_block (src/kernel/film.h).
 *
 * cmake/EmbedKernel.cmake inlines this file and every kernel header it includes into
 * one string compiled by src/device/opencl.c. */
#pragma OPENCL FP_CONTRACT OFF

#include "cwbvh.h"
#include "emission.h"
#include "kernel.h"

/* The scene's arrays come as one __global buffer argument each, generated from the one
 * list of them (TR_SCENE_ARRAYS, scene_view.h); their element counts and then the view's
 * scalars, as 32-bit words, are the scene_info argument. src/device/opencl.c builds its
 * upload table from the same list and checks the compiled kernel's argument names. */
#define TR_CL_ARRAY_PARAM(type, name, count) __global const type *name,
#define TR_CL_INFO_ENUM(type, name, count) TR_CL_INFO_##count,
#define TR_CL_SCALAR_ENUM(type, name) TR_CL_INFO_##name,
enum { TR_SCENE_ARRAYS(TR_CL_INFO_ENUM) TR_SCENE_SCALARS(TR_CL_SCALAR_ENUM) TR_CL_INFO_COUNT };

/* The scene view `s` over the kernel's scene arguments. */
#define TR_CL_VIEW_ARRAY(type, name, count)                                                        \
    s.name = name;                                                                                 \
    s.count = scene_info[TR_CL_INFO_##count];
#define TR_CL_SCENE_VIEW(s)                                                                        \
    TR_SCENE_ARRAYS(TR_CL_VIEW_ARRAY)                                                              \
    s.accel = scene_info[TR_CL_INFO_accel];                                                        \
    s.light_weight_total = as_float(scene_info[TR_CL_INFO_light_weight_total])

/* The film view over the kernel's film arguments, every pass buffer in it. */
#define TR_CL_FILM_VIEW(f)                                                                         \
    tr_cl_film_view(film_sum, film_count, film_albedo, film_normal, film_depth, film_prim,         \
                    film_sq, film_direct, film_emission, (f).camera.screen_width, (f).passes)
static tr_film_view tr_cl_film_view(__global float *sum, __global uint *count,
                                    __global float *albedo, __global float *normal,
                                    __global float *depth, __global uint *prim, __global float *sq,
                                    __global float *direct, __global float *emission, uint width,
                                    uint passes) {
    tr_film_view v = tr_film_view_make(sum, count, albedo, normal, depth, prim, width, passes);
    v.sq = sq;
    v.direct = direct;
    v.emission = emission;
    return v;
}

/* One work item per traced pixel of the frame's grid (tr_frame_grid); with a stride above
 * 1 the traced pixel's value fills its stride x stride block (preview mode). Pass buffers
 * the frame does not ask for are one-element placeholders nobody writes.
 * rays_per_row[r] accumulates the intersection queries made for grid row r. */
__kernel void tr_cl_render(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                           __global const tr_frame *frame, __global float *film_sum,
                           __global uint *film_count, __global float *film_albedo,
                           __global float *film_normal, __global float *film_depth,
                           __global uint *film_prim, __global float *film_sq,
                           __global float *film_direct, __global float *film_emission,
                           __global uint *rays_per_row) {
    const tr_frame f = *frame;
    uint gx0, gy0, nx, ny;
    tr_frame_grid(&f, &gx0, &gy0, &nx, &ny);
    const uint gx = (uint)get_global_id(0), gy = (uint)get_global_id(1);
    if (gx >= nx || gy >= ny) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);

    tr_film_view film = TR_CL_FILM_VIEW(f);
    const uint rays =
        tr_render_grid_rows(&s, &f, &film, gx0 + gx, gy0 + gy, gx0 + gx + 1u, gy0 + gy + 1u);
    atomic_add(&rays_per_row[gy], rays);
}

/* The film's emission (TR_PASS_EMISSION) resolved over each pixel's area, as the host's
 * tr_resolve_emission does it (src/post/emission.c, src/kernel/emission.h): a pixel next
 * to an edge between emitting and non-emitting samples gets the mean over an n x n grid of
 * first-hit rays through the frame's camera, every other pixel its own mean emission.
 * One work item per pixel of the film (the camera's screen). */
__kernel void
tr_cl_resolve_emission(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                       __global const tr_frame *frame, __global const uint *film_count,
                       __global const float *film_emission, int n, __global float *resolved) {
    const tr_frame f = *frame;
    const int w = (int)f.camera.screen_width, h = (int)f.camera.screen_height;
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const uint i = (uint)(y * w + x);
    tr_vec3 e;
    if (tr_emission_on_edge(film_emission, w, h, x, y)) {
        tr_scene_view s;
        TR_CL_SCENE_VIEW(s);
        e = tr_emission_resolve_pixel(&s, &f.camera, x, y, n);
    } else {
        const uint c = film_count[i];
        const float inv = c ? 1.0f / (float)c : 0.0f;
        e = v3(film_emission[3u * i] * inv, film_emission[3u * i + 1u] * inv,
               film_emission[3u * i + 2u] * inv);
    }
    resolved[3u * i] = e.x;
    resolved[3u * i + 1u] = e.y;
    resolved[3u * i + 2u] = e.z;
}

/* Ray throughput (`trac0r bench rays --device opencl`, src/measure/rays.c): one work item
 * per ray of a set, the closest hit (or, for shadow rays, any hit) with the scene's
 * structure; hits[i] is 1 where ray i hit, for the host's cross-check of the counts. */
__kernel void tr_cl_trace_rays(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                               __global const tr_ray *rays, uint count, uint shadow,
                               __global uint *hits) {
    const uint i = (uint)get_global_id(0);
    if (i >= count) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    s.cwbvh_node_count = 0u; /* the binary BVH's row; tr_cl_trace_cwbvh is the wide one's */
    const tr_ray r = rays[i];
    uint h;
    if (shadow) {
        h = tr_occluded_scene(&s, &r) ? 1u : 0u;
    } else {
        tr_hit hit;
        h = tr_intersect_scene(&s, &r, &hit) ? 1u : 0u;
    }
    hits[i] = h;
}

/* tr_cl_trace_rays through a compressed wide BVH (cwbvh.h) given as its own buffers:
 * `bench rays --device` measures it beside the binary BVH. */
__kernel void tr_cl_trace_cwbvh(__global const tr_cwbvh_node *cw_nodes, uint cw_node_count,
                                __global const tr_bvh_tri *cw_tris, __global const tr_ray *rays,
                                uint count, uint shadow, __global uint *hits) {
    const uint i = (uint)get_global_id(0);
    if (i >= count) {
        return;
    }
    const tr_ray r = rays[i];
    tr_hit hit;
    hits[i] = tr_cwbvh_traverse(cw_nodes, cw_node_count, cw_tris, &r, &hit, shadow != 0u) ? 1u : 0u;
}

/* bdpt on the device: tr_cl_render's arguments and work items, and the light-tracing
 * splats' fixed-point sums (integrator_bdpt.h), one 64-bit integer per colour channel and
 * pixel of the frame's rectangle, added with atom_add. Integer addition is associative, so
 * the sums are those the CPU's threads make, whatever the order. tr_cl_fold_splats then
 * adds them to the film as the CPU's fold does (src/device/cpu.c), in double precision.
 * Compiled only where the device has both extensions; the host finds no kernel otherwise
 * and refuses bdpt on that device. */
#if defined(cl_khr_int64_base_atomics) && defined(cl_khr_fp64)
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
#include "integrator_bdpt.h"

__kernel void tr_cl_render_bdpt(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                                __global const tr_frame *frame, __global float *film_sum,
                                __global uint *film_count, __global float *film_albedo,
                                __global float *film_normal, __global float *film_depth,
                                __global uint *film_prim, __global float *film_sq,
                                __global float *film_direct, __global float *film_emission,
                                __global uint *rays_per_row, __global long *splat) {
    const tr_frame f = *frame;
    uint gx0, gy0, nx, ny;
    tr_frame_grid(&f, &gx0, &gy0, &nx, &ny);
    const uint gx = (uint)get_global_id(0), gy = (uint)get_global_id(1);
    if (gx >= nx || gy >= ny) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    tr_film_view film = TR_CL_FILM_VIEW(f);
    tr_bdpt_splat sp;
    sp.sum = splat;
    sp.x0 = f.rect_x;
    sp.y0 = f.rect_y;
    sp.w = f.rect_w;
    sp.h = f.rect_h;
    const uint rays = tr_bdpt_render_grid_rows(&s, &f, &film, &sp, gx0 + gx, gy0 + gy,
                                               gx0 + gx + 1u, gy0 + gy + 1u);
    atomic_add(&rays_per_row[gy], rays);
}

/* Adds the splat sums to the film after the frame: pixel (x, y) of the rectangle gets
 * (float)(sum * scale) per channel, scale = W H / (grid 2^24) as the host computed it
 * (the frame's grid points, src/device/cpu.c's tr_bdpt_fold_splats). One work item per
 * pixel of the rectangle. */
__kernel void tr_cl_fold_splats(__global const tr_frame *frame, __global const long *splat,
                                double scale, __global float *film_sum) {
    const uint w = frame->rect_w, h = frame->rect_h;
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const size_t i = (size_t)(frame->rect_y + y) * frame->camera.screen_width + (frame->rect_x + x);
    const size_t j = 3u * ((size_t)y * w + x);
    for (int c = 0; c < 3; ++c) {
        film_sum[3u * i + (size_t)c] += (float)((double)splat[j + (size_t)c] * scale);
    }
}
#endif
