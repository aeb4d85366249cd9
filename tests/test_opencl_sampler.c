/* test_opencl_sampler.c - the random numbers are bit-identical on the host and on the
 * OpenCL device (PoCL, or whatever device 0 is).
 *
 * A small __kernel, appended to the embedded kernel source (the very text the backend
 * compiles), evaluates the samplers at 3 x 4096 addresses (seed, pixel, sample index,
 * dimension pair): tr_sampler_2d and tr_sampler_1d for the sobol, random and zsobol kinds,
 * pt's camera jitter dimension included, and naive's xorshift1024* stream (tr_rng_float,
 * 8 draws per address). The host computes the same with the same headers; every 32-bit
 * float must be equal bit for bit. These are integer operations and one exact int-to-float
 * conversion, so they are equal by construction; the test keeps them so (a kernel change
 * that let a float operation into the sampler would show here). The images themselves
 * differ in the last bits of shading where the device's transcendental functions round
 * differently (docs/opencl.md; test_opencl bounds that). Fails, does not skip, without a
 * device, as test_opencl does. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "cl_test.h"
#include "kernel/kernel.h"
#include "trac0r/render.h"

enum { N = 3 * 4096, WORDS = 3 + 8, DRAWS = 8 };

static const char test_kernel[] =
    "\n__kernel void tr_test_sampler_points(__global const uint *addr, __global uint *out,\n"
    "                                       uint n) {\n"
    "    const uint i = (uint)get_global_id(0);\n"
    "    if (i >= n) {\n"
    "        return;\n"
    "    }\n"
    "    __global const uint *a = addr + 8u * i;\n"
    "    const ulong seed = ((ulong)a[1] << 32) | (ulong)a[0];\n"
    "    const ulong pixel = (ulong)a[3] * (ulong)a[7] + (ulong)a[2];\n"
    "    tr_sampler s = tr_sampler_make_pixel(seed, pixel, a[2], a[3], a[4], a[6]);\n"
    "    float u1, u2;\n"
    "    tr_sampler_2d(&s, a[5], &u1, &u2);\n"
    "    __global uint *o = out + 11u * i;\n"
    "    o[0] = as_uint(u1);\n"
    "    o[1] = as_uint(u2);\n"
    "    o[2] = as_uint(tr_sampler_1d(&s, a[5] + 1u));\n"
    "    tr_rng r;\n"
    "    tr_rng_init(&r, seed, pixel, (ulong)a[4]);\n"
    "    for (uint k = 0; k < 8u; ++k) {\n"
    "        o[3u + k] = as_uint(tr_rng_float(&r));\n"
    "    }\n"
    "}\n";

static void host_points(const uint32_t *a, uint32_t *o) {
    const uint64_t seed = ((uint64_t)a[1] << 32) | (uint64_t)a[0];
    const uint64_t pixel = (uint64_t)a[3] * (uint64_t)a[7] + (uint64_t)a[2];
    tr_sampler s = tr_sampler_make_pixel(seed, pixel, a[2], a[3], a[4], a[6]);
    float u1, u2, u3;
    tr_sampler_2d(&s, a[5], &u1, &u2);
    u3 = tr_sampler_1d(&s, a[5] + 1u);
    memcpy(&o[0], &u1, 4);
    memcpy(&o[1], &u2, 4);
    memcpy(&o[2], &u3, 4);
    tr_rng r;
    tr_rng_init(&r, seed, pixel, (uint64_t)a[4]);
    for (int k = 0; k < DRAWS; ++k) {
        float f = tr_rng_float(&r);
        memcpy(&o[3 + k], &f, 4);
    }
}

int main(void) {
    cl_device_id dev;
    cl_context ctx;
    cl_command_queue q;
    if (!cl_test_open(&dev, &ctx, &q)) {
        return check_finish("test_opencl_sampler");
    }
    /* Addresses: seeds over all 64 bits, pixels of a 1920-wide image and beyond the
     * 65536 tile of zsobol, sample indices up to 2^32 - 1, dimension pairs of long paths. */
    static uint32_t addr[N * 8], want[N * WORDS], got[N * WORDS];
    for (uint32_t i = 0; i < N; ++i) {
        uint32_t *a = addr + 8 * i;
        const uint64_t seed = tr_mix64(i) >> (i % 64u);
        a[0] = (uint32_t)seed;
        a[1] = (uint32_t)(seed >> 32);
        a[2] = i % 7u == 0 ? 70000u + i : (i * 37u) % 1920u;
        a[3] = (i * 11u) % 1080u;
        a[4] = i % 5u == 0 ? 0xffffffffu - i : i % 300u;
        a[5] = (i / 3u) % 64u;
        a[6] = i % 3u; /* TR_SAMPLER_SOBOL, RANDOM, ZSOBOL */
        a[7] = 1920u;
        host_points(a, want + WORDS * i);
    }
    CHECK(TR_SAMPLER_SOBOL == 0 && TR_SAMPLER_RANDOM == 1 && TR_SAMPLER_ZSOBOL == 2,
          "the kinds' numbers");

    /* The backend's options (src/device/opencl.c, without the argument info it reads). */
    cl_program prog = cl_test_program(ctx, dev, test_kernel, "-cl-std=CL1.2 -DTR_OPENCL_DEVICE=1");
    if (!prog) {
        return check_finish("test_opencl_sampler");
    }
    cl_int rc;
    cl_kernel k = clCreateKernel(prog, "tr_test_sampler_points", &rc);
    CHECK(rc == CL_SUCCESS, "clCreateKernel: %d", rc);
    cl_mem in =
        clCreateBuffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof addr, addr, &rc);
    CHECK(rc == CL_SUCCESS, "clCreateBuffer: %d", rc);
    cl_mem out = clCreateBuffer(ctx, CL_MEM_WRITE_ONLY, sizeof got, NULL, &rc);
    CHECK(rc == CL_SUCCESS, "clCreateBuffer: %d", rc);
    const cl_uint n = N;
    const size_t global = N;
    rc = clSetKernelArg(k, 0, sizeof in, &in) | clSetKernelArg(k, 1, sizeof out, &out) |
         clSetKernelArg(k, 2, sizeof n, &n);
    CHECK(rc == CL_SUCCESS, "clSetKernelArg: %d", rc);
    rc = clEnqueueNDRangeKernel(q, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    CHECK(rc == CL_SUCCESS, "clEnqueueNDRangeKernel: %d", rc);
    rc = clEnqueueReadBuffer(q, out, CL_TRUE, 0, sizeof got, got, 0, NULL, NULL);
    CHECK(rc == CL_SUCCESS, "clEnqueueReadBuffer: %d", rc);

    int bad[3] = {0, 0, 0}, bad_rng = 0;
    for (uint32_t i = 0; i < N; ++i) {
        bad[i % 3u] += memcmp(want + WORDS * i, got + WORDS * i, 3 * sizeof(uint32_t)) != 0;
        bad_rng += memcmp(want + WORDS * i + 3, got + WORDS * i + 3, DRAWS * sizeof(uint32_t)) != 0;
    }
    CHECK(bad[0] == 0 && bad[1] == 0 && bad[2] == 0,
          "host and device points differ: sobol %d, random %d, zsobol %d of %d", bad[0], bad[1],
          bad[2], N / 3);
    CHECK(bad_rng == 0, "naive's streams differ at %d of %d addresses", bad_rng, N);
    /* The comparison can fail: the device's values are not all alike. */
    int distinct = 0;
    for (uint32_t i = 1; i < N; ++i) {
        distinct += got[WORDS * i] != got[0];
    }
    CHECK(distinct > N / 2, "the device returned %d distinct values", distinct);

    clReleaseMemObject(in);
    clReleaseMemObject(out);
    clReleaseKernel(k);
    clReleaseProgram(prog);
    clReleaseCommandQueue(q);
    clReleaseContext(ctx);
    return check_finish("test_opencl_sampler");
}
