/* Compiled as OpenCL C 1.2 by CTest (clang -x cl -fsyntax-only) to prove that the
 * single-source kernel stays inside the subset both languages share. */
#include "kernel/kernel.h"

__kernel void tr_check_render(__global const tr_triangle *triangles,
                              __global const tr_material *materials,
                              __global const tr_flat_node *nodes,
                              __global const tr_bvh_node *bvh_nodes,
                              __global const tr_bvh_tri *bvh_tris,
                              __global const uint *lights, __global const float *light_cdf,
                              uint light_count, float light_weight_total, uint triangle_count,
                              uint material_count, uint node_count, uint bvh_node_count,
                              uint accel, tr_camera cam, ulong seed, uint sample, int max_depth,
                              int integrator, __global float *out) {
    tr_scene_view s;
    s.triangles = triangles;
    s.materials = materials;
    s.flat_nodes = nodes;
    s.triangle_count = triangle_count;
    s.material_count = material_count;
    s.flat_node_count = node_count;
    s.bvh_nodes = bvh_nodes;
    s.bvh_tris = bvh_tris;
    s.bvh_node_count = bvh_node_count;
    s.accel = accel;
    s.lights = lights;
    s.light_cdf = light_cdf;
    s.light_count = light_count;
    s.light_weight_total = light_weight_total;
    uint x = get_global_id(0), y = get_global_id(1);
    uint rays = 0;
    tr_vec3 c = tr_render_sample(&s, &cam, x, y, sample, seed, max_depth,
                                 integrator == TR_INTEGRATOR_PT ? TR_INTEGRATOR_PT
                                                                : TR_INTEGRATOR_NAIVE,
                                 &rays);
    size_t i = (size_t)y * cam.screen_width + x;
    out[3 * i] = c.x;
    out[3 * i + 1] = c.y;
    out[3 * i + 2] = c.z;
}
