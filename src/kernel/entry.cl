/* entry.cl - the OpenCL entry point: the __kernel that runs tr_render_sample, the same
 * code the CPU backend runs, for one pixel per work item and accumulates the result
 * into a float film on the device (sum of radiance and sample count per pixel, as
 * src/film/film.c on the host).
 *
 * cmake/EmbedKernel.cmake inlines this file and every kernel header it includes into
 * one string compiled by src/backend/opencl.c. */
#pragma OPENCL FP_CONTRACT OFF

#include "kernel.h"

/* The scene arrays the kernel reads, X(type, name), in kernel argument order: each is
 * a __global buffer argument, and its element count is entry TR_CL_INFO_<name> of the
 * scene_info argument. The host's table in src/backend/opencl.c lists the same names
 * in the same order (checked against the compiled kernel's argument names when a
 * context opens). */
#define TR_CL_SCENE_ARRAYS(X)                                                            \
    X(tr_triangle, triangles)                                                            \
    X(tr_material, materials)                                                            \
    X(tr_flat_node, flat_nodes)                                                          \
    X(tr_bvh_node, bvh_nodes)                                                            \
    X(tr_bvh_tri, bvh_tris)                                                              \
    X(uint32_t, lights)                                                                  \
    X(float, light_cdf)

#define TR_CL_INFO_ENUM(type, name) TR_CL_INFO_##name,
enum {
    TR_CL_SCENE_ARRAYS(TR_CL_INFO_ENUM) TR_CL_INFO_ACCEL,
    TR_CL_INFO_LIGHT_WEIGHT, /* the float light_weight_total, as its bits */
    TR_CL_INFO_COUNT
};

#define TR_CL_PARAM(type, name) __global const type *name,

/* One work item per traced pixel (x, y) = (gx * stride, gy * stride); with a stride
 * above 1 the traced pixel's value fills its stride x stride block (preview mode).
 * rays_per_row[y] accumulates the intersection queries made for row y. */
__kernel void tr_cl_render(TR_CL_SCENE_ARRAYS(TR_CL_PARAM) __global const uint *scene_info,
                           __global const tr_camera *camera, ulong seed, uint sample,
                           int max_depth, int integrator, uint stride, __global float *film_sum,
                           __global uint *film_count, __global uint *rays_per_row) {
    const uint gx = (uint)get_global_id(0), gy = (uint)get_global_id(1);
    const tr_camera cam = *camera;
    const uint x = gx * stride, y = gy * stride;
    if (x >= cam.screen_width || y >= cam.screen_height) {
        return;
    }
    tr_scene_view s;
#define TR_CL_VIEW_ARRAY(type, name) s.name = name;
    TR_CL_SCENE_ARRAYS(TR_CL_VIEW_ARRAY)
    s.triangle_count = scene_info[TR_CL_INFO_triangles];
    s.material_count = scene_info[TR_CL_INFO_materials];
    s.flat_node_count = scene_info[TR_CL_INFO_flat_nodes];
    s.bvh_node_count = scene_info[TR_CL_INFO_bvh_nodes];
    s.accel = scene_info[TR_CL_INFO_ACCEL];
    s.light_count = scene_info[TR_CL_INFO_lights];
    s.light_weight_total = as_float(scene_info[TR_CL_INFO_LIGHT_WEIGHT]);

    uint rays = 0;
    const tr_vec3 c =
        tr_render_sample(&s, &cam, x, y, sample, seed, max_depth, integrator, &rays);
    const uint x1 = min(x + stride, cam.screen_width);
    const uint y1 = min(y + stride, cam.screen_height);
    for (uint by = y; by < y1; ++by) {
        for (uint bx = x; bx < x1; ++bx) {
            const size_t i = (size_t)by * cam.screen_width + bx;
            film_sum[3 * i] += c.x;
            film_sum[3 * i + 1] += c.y;
            film_sum[3 * i + 2] += c.z;
            film_count[i] += 1;
        }
    }
    atomic_add(&rays_per_row[y], rays);
}
