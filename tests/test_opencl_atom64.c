/* test_opencl_atom64.c - the splat sums' 64-bit addition as two 32-bit atomic additions
 * (integrator_bdpt.h's tr_bdpt_atomic_add64), which bdpt and vcm use on a device without
 * cl_khr_int64_base_atomics. Renders hardly ever carry from the low word into the high
 * one (a pixel's splats would have to pass 256 in 2^-24 units), so this drives the
 * carries directly: on the OpenCL device (PoCL), 2^16 work items each add a value whose
 * low half is near 2^32 into one of a few sums, so that nearly every addition wraps the
 * low word, and every sum must equal the exact 64-bit sum the host computes. The kernel
 * source is the backend's, built as for a device without the extension. Fails, does not
 * skip, without a device. */
#include <stdint.h>
#include <stdio.h>

#include "cl_test.h"

enum { N = 1 << 16, SUMS = 7 };

static const char test_kernel[] =
    "\n__kernel void tr_test_add64(__global long *sums, __global const long *values) {\n"
    "    const uint i = (uint)get_global_id(0);\n"
    "    tr_bdpt_atomic_add64(&sums[i % 7u], values[i]);\n"
    "}\n";

int main(void) {
    cl_device_id dev;
    cl_context ctx;
    cl_command_queue q;
    if (!cl_test_open(&dev, &ctx, &q)) {
        return check_finish("test_opencl_atom64");
    }
    /* bdpt's part of the backend's source, as src/device/opencl.c builds it for a device
     * without 64-bit atomics (TRAC0R_OPENCL_DISABLE_EXT=cl_khr_int64_base_atomics). */
    cl_program prog = cl_test_program(ctx, dev, test_kernel,
                                      "-cl-std=CL1.2 -DTR_OPENCL_DEVICE=1 -DTR_CL_PART=4 "
                                      "-DTR_CL_NO_INT64_ATOMICS=1");
    if (!prog) {
        return check_finish("test_opencl_atom64");
    }
    cl_int rc;
    cl_kernel k = clCreateKernel(prog, "tr_test_add64", &rc);
    CHECK(rc == CL_SUCCESS, "clCreateKernel: %d", rc);

    /* Values below 2^34 whose low halves are within 2^16 of 2^32 (a fixed-seed LCG). */
    int64_t *values = malloc(N * sizeof *values);
    uint64_t expect[SUMS] = {0};
    CHECK(values != NULL, "out of memory");
    if (!values) {
        return check_finish("test_opencl_atom64");
    }
    uint64_t state = 12345u;
    for (int i = 0; i < N; ++i) {
        state = state * 6364136223846793005u + 1442695040888963407u;
        const uint64_t hi = (state >> 62) & 3u, lo = 0xffffffffu - ((state >> 20) & 0xffffu);
        values[i] = (int64_t)(hi << 32 | lo);
        expect[i % SUMS] += (uint64_t)values[i];
    }
    int64_t zero[SUMS] = {0}, got[SUMS] = {0};
    cl_mem bs =
        clCreateBuffer(ctx, CL_MEM_READ_WRITE | CL_MEM_COPY_HOST_PTR, sizeof zero, zero, &rc);
    CHECK(rc == CL_SUCCESS, "clCreateBuffer(sums): %d", rc);
    cl_mem bv = clCreateBuffer(ctx, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, N * sizeof *values,
                               values, &rc);
    CHECK(rc == CL_SUCCESS, "clCreateBuffer(values): %d", rc);
    rc = clSetKernelArg(k, 0, sizeof bs, &bs);
    rc |= clSetKernelArg(k, 1, sizeof bv, &bv);
    CHECK(rc == CL_SUCCESS, "clSetKernelArg: %d", rc);
    const size_t global = N;
    rc = clEnqueueNDRangeKernel(q, k, 1, NULL, &global, NULL, 0, NULL, NULL);
    CHECK(rc == CL_SUCCESS, "clEnqueueNDRangeKernel: %d", rc);
    rc = clEnqueueReadBuffer(q, bs, CL_TRUE, 0, sizeof got, got, 0, NULL, NULL);
    CHECK(rc == CL_SUCCESS, "clEnqueueReadBuffer: %d", rc);
    for (int s = 0; s < SUMS; ++s) {
        CHECK((uint64_t)got[s] == expect[s], "sum %d: %llu on the device, %llu exactly", s,
              (unsigned long long)got[s], (unsigned long long)expect[s]);
        /* The values' low halves alone carry about once per value. */
        CHECK(expect[s] >> 32 > (uint64_t)(N / SUMS), "sum %d carries too little to test", s);
    }
    printf("7 sums of %d values each wrapping the low word, compared with the exact sums\n",
           N / SUMS);
    clReleaseMemObject(bs);
    clReleaseMemObject(bv);
    clReleaseKernel(k);
    clReleaseProgram(prog);
    clReleaseCommandQueue(q);
    clReleaseContext(ctx);
    free(values);
    return check_finish("test_opencl_atom64");
}
