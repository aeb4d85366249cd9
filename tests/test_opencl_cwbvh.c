/* test_opencl_cwbvh.c - the compressed wide BVH (src/kernel/cwbvh.h, converted by
 * src/accel/cwbvh.c) agrees with the binary BVH it comes from, hit for hit, on random rays:
 * traversed on the host and on the OpenCL device (PoCL), closest hits and any-hit (shadow)
 * queries. A closest hit must have the same distance bit for bit; the same triangle too,
 * except where two triangles are hit at exactly that distance (a shared edge), where the
 * order of the tests decides. Fails, does not skip, without a device. */
#include <stdlib.h>
#include <string.h>

#include "accel/cwbvh.h"
#include "check.h"
#include "cl_test.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/scene.h"

enum { N = 20000 };
#define SHADOW_TMAX 1.5f

static const char test_kernel[] =
    "\n__kernel void tr_test_cwbvh(__global const tr_cwbvh_node *nodes, uint node_count,\n"
    "                            __global const tr_bvh_tri *tris, __global const tr_ray *rays,\n"
    "                            uint n, __global float *t_out, __global uint *tri_out,\n"
    "                            __global uint *occ_out) {\n"
    "    const uint i = (uint)get_global_id(0);\n"
    "    if (i >= n) return;\n"
    "    tr_ray r = rays[i];\n"
    "    tr_hit h;\n"
    "    const int f = tr_cwbvh_traverse(nodes, node_count, tris, &r, &h, 0);\n"
    "    t_out[i] = f ? h.t : -1.0f;\n"
    "    tri_out[i] = f ? h.triangle : 0xffffffffu;\n"
    "    r.tmax = 1.5f;\n"
    "    occ_out[i] = (uint)tr_cwbvh_traverse(nodes, node_count, tris, &r, &h, 1);\n"
    "}\n";

static uint64_t state = 0x9e3779b97f4a7c15ull;
static float rnd(void) {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return (float)(state >> 40) / 16777216.0f;
}

/* N rays: origins in the scene's box grown by a fifth, uniform directions. */
static void make_rays(const tr_scene *scene, tr_ray *rays) {
    const tr_aabb b = tr_scene_bounds(scene);
    const tr_vec3 ext = v3_sub(b.max, b.min);
    for (int i = 0; i < N; ++i) {
        const tr_vec3 o =
            v3(b.min.x + ext.x * (1.4f * rnd() - 0.2f), b.min.y + ext.y * (1.4f * rnd() - 0.2f),
               b.min.z + ext.z * (1.4f * rnd() - 0.2f));
        const float z = 2.0f * rnd() - 1.0f, a = TR_TWO_PI * rnd();
        const float s = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        rays[i] = tr_ray_make(o, v3(s * cosf(a), s * sinf(a), z), 0.0f, TR_INFINITY);
    }
}

/* Compares one query's results with the binary BVH's; counts ties and mismatches. */
static void compare(const tr_scene_view *v, const tr_ray *ray, float t, uint32_t tri, int occ,
                    size_t *hits, size_t *ties, size_t *bad) {
    tr_hit h;
    const int f = tr_traverse_bvh(v, ray, &h, 0);
    tr_ray s = *ray;
    s.tmax = SHADOW_TMAX;
    tr_hit hs;
    const int o = tr_traverse_bvh(v, &s, &hs, 1);
    if (f != (t >= 0.0f) || o != occ || (f && memcmp(&h.t, &t, sizeof t) != 0)) {
        ++*bad;
        return;
    }
    *hits += (size_t)f;
    *ties += (size_t)(f && h.triangle != tri);
}

static void check_scene(cl_context ctx, cl_command_queue q, cl_kernel k, const char *name) {
    tr_error err;
    tr_scene *scene = tr_scene_create(&err);
    CHECK(scene != NULL, "%s", err.msg);
    CHECK(tr_scene_builtin(scene, name, 64, 48, &err) == TR_OK, "%s: %s", name, err.msg);
    CHECK(tr_scene_commit(scene, TR_ACCEL_TYPE_BVH2, &err) == TR_OK, "%s: %s", name, err.msg);
    const tr_scene_view v = tr_scene_view_of(scene);
    tr_cwbvh cw;
    CHECK(tr_cwbvh_build(&cw, v.bvh_nodes, v.bvh_node_count, v.bvh_tris, &err) == TR_OK, "%s: %s",
          name, err.msg);
    CHECK(cw.tri_count == v.bvh_tri_count, "%s: %u of %u triangles in the wide BVH", name,
          cw.tri_count, v.bvh_tri_count);
    CHECK(cw.node_count * 2u < v.bvh_node_count, "%s: %u wide nodes for %u binary ones", name,
          cw.node_count, v.bvh_node_count);
    tr_ray *rays = malloc(N * sizeof *rays);
    float *t = malloc(N * sizeof *t);
    uint32_t *tri = malloc(N * sizeof *tri), *occ = malloc(N * sizeof *occ);
    CHECK(rays && t && tri && occ, "out of memory");
    make_rays(scene, rays);

    /* The host's traversal of the wide BVH. */
    size_t hits = 0, ties = 0, bad = 0;
    for (int i = 0; i < N; ++i) {
        tr_hit h;
        const int f = tr_cwbvh_traverse(cw.nodes, cw.node_count, cw.tris, &rays[i], &h, 0);
        tr_ray s = rays[i];
        s.tmax = SHADOW_TMAX;
        const int o = tr_cwbvh_traverse(cw.nodes, cw.node_count, cw.tris, &s, &h, 1);
        tr_hit hc;
        tr_cwbvh_traverse(cw.nodes, cw.node_count, cw.tris, &rays[i], &hc, 0);
        compare(&v, &rays[i], f ? hc.t : -1.0f, f ? hc.triangle : 0xffffffffu, o, &hits, &ties,
                &bad);
    }
    CHECK(bad == 0, "%s: host: %zu of %d rays disagree with the binary BVH", name, bad, N);
    CHECK(hits * 4 > N, "%s: host: only %zu of %d rays hit", name, hits, N);
    CHECK(ties * 1000 <= hits, "%s: host: %zu other triangles at equal distance", name, ties);
    printf("%s: host: %zu of %d rays hit, %zu ties, %zu disagree; %u wide nodes (binary %u), "
           "depth %u\n",
           name, hits, N, ties, bad, cw.node_count, v.bvh_node_count, cw.depth);

    /* The device's. */
    cl_int rc;
    cl_mem bn = clCreateBuffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                               cw.node_count * sizeof *cw.nodes, cw.nodes, &rc);
    cl_mem bt = clCreateBuffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                               cw.tri_count * sizeof *cw.tris, cw.tris, &rc);
    cl_mem br =
        clCreateBuffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, N * sizeof *rays, rays, &rc);
    cl_mem ot = clCreateBuffer(ctx, CL_MEM_WRITE_ONLY, N * sizeof *t, NULL, &rc);
    cl_mem oi = clCreateBuffer(ctx, CL_MEM_WRITE_ONLY, N * sizeof *tri, NULL, &rc);
    cl_mem oo = clCreateBuffer(ctx, CL_MEM_WRITE_ONLY, N * sizeof *occ, NULL, &rc);
    CHECK(bn && bt && br && ot && oi && oo, "clCreateBuffer: %d", rc);
    const cl_uint nc = cw.node_count, n = N;
    rc = clSetKernelArg(k, 0, sizeof bn, &bn) | clSetKernelArg(k, 1, sizeof nc, &nc) |
         clSetKernelArg(k, 2, sizeof bt, &bt) | clSetKernelArg(k, 3, sizeof br, &br) |
         clSetKernelArg(k, 4, sizeof n, &n) | clSetKernelArg(k, 5, sizeof ot, &ot) |
         clSetKernelArg(k, 6, sizeof oi, &oi) | clSetKernelArg(k, 7, sizeof oo, &oo);
    CHECK(rc == CL_SUCCESS, "clSetKernelArg: %d", rc);
    const size_t global = N;
    rc = clEnqueueNDRangeKernel(q, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    CHECK(rc == CL_SUCCESS, "clEnqueueNDRangeKernel: %d", rc);
    rc = clEnqueueReadBuffer(q, ot, CL_TRUE, 0, N * sizeof *t, t, 0, NULL, NULL) |
         clEnqueueReadBuffer(q, oi, CL_TRUE, 0, N * sizeof *tri, tri, 0, NULL, NULL) |
         clEnqueueReadBuffer(q, oo, CL_TRUE, 0, N * sizeof *occ, occ, 0, NULL, NULL);
    CHECK(rc == CL_SUCCESS, "clEnqueueReadBuffer: %d", rc);
    hits = ties = bad = 0;
    for (int i = 0; i < N; ++i) {
        compare(&v, &rays[i], t[i], tri[i], (int)occ[i], &hits, &ties, &bad);
    }
    CHECK(bad == 0, "%s: device: %zu of %d rays disagree with the binary BVH", name, bad, N);
    CHECK(hits * 4 > N, "%s: device: only %zu of %d rays hit", name, hits, N);
    CHECK(ties * 1000 <= hits, "%s: device: %zu other triangles at equal distance", name, ties);
    printf("%s: device: %zu of %d rays hit, %zu ties, %zu disagree\n", name, hits, N, ties, bad);
    cl_mem all[] = {bn, bt, br, ot, oi, oo};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i) {
        clReleaseMemObject(all[i]);
    }
    free(rays);
    free(t);
    free(tri);
    free(occ);
    tr_cwbvh_free(&cw);
    tr_scene_destroy(scene);
}

int main(void) {
    cl_device_id dev;
    cl_context ctx;
    cl_command_queue q;
    if (!cl_test_open(&dev, &ctx, &q)) {
        return check_finish("test_opencl_cwbvh");
    }
    /* The backend's options on a CPU device: the host's correctly rounded division. */
    cl_program prog = cl_test_program(
        ctx, dev, test_kernel,
        "-cl-std=CL1.2 -DTR_OPENCL_DEVICE=1 -cl-fp32-correctly-rounded-divide-sqrt");
    if (!prog) {
        return check_finish("test_opencl_cwbvh");
    }
    cl_int rc;
    cl_kernel k = clCreateKernel(prog, "tr_test_cwbvh", &rc);
    CHECK(rc == CL_SUCCESS, "clCreateKernel: %d", rc);
    check_scene(ctx, q, k, "cornell");
    check_scene(ctx, q, k, "cornell-ico-5");
    clReleaseKernel(k);
    clReleaseProgram(prog);
    clReleaseCommandQueue(q);
    clReleaseContext(ctx);
    return check_finish("test_opencl_cwbvh");
}
