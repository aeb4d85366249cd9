/* cl_test.h - what the tests that run kernels of their own on the OpenCL device (PoCL)
 * share: the first device with a context and a queue, and a program of the backend's
 * kernel source (src/kernel/entry.cl as embedded) with a test kernel after it. */
#ifndef TR_TESTS_CL_TEST_H
#define TR_TESTS_CL_TEST_H

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"

extern const char tr_cl_kernel_source[];
extern const size_t tr_cl_kernel_source_length;

/* The first device of the first platform, a context and an in-order queue on it; 0 (a
 * check failed) where there is none: the tests fail, never skip, without a device. */
static int cl_test_open(cl_device_id *dev, cl_context *ctx, cl_command_queue *q) {
    cl_platform_id plat;
    cl_uint np = 0, nd = 0;
    CHECK(clGetPlatformIDs(1, &plat, &np) == CL_SUCCESS && np > 0, "no OpenCL platform");
    if (np == 0) {
        return 0;
    }
    CHECK(clGetDeviceIDs(plat, CL_DEVICE_TYPE_ALL, 1, dev, &nd) == CL_SUCCESS && nd > 0,
          "no OpenCL device");
    if (nd == 0) {
        return 0;
    }
    cl_int rc;
    *ctx = clCreateContext(NULL, 1, dev, NULL, NULL, &rc);
    CHECK(rc == CL_SUCCESS, "clCreateContext: %d", rc);
    *q = rc == CL_SUCCESS ? clCreateCommandQueue(*ctx, *dev, 0, &rc) : NULL;
    CHECK(rc == CL_SUCCESS, "clCreateCommandQueue: %d", rc);
    return rc == CL_SUCCESS;
}

/* The kernel source with `kernel` (a C string) after it, built with `options`; NULL (a
 * check failed, with the build log) where it does not build. */
static cl_program cl_test_program(cl_context ctx, cl_device_id dev, const char *kernel,
                                  const char *options) {
    const size_t n = strlen(kernel);
    char *src = malloc(tr_cl_kernel_source_length + n + 1u);
    CHECK(src != NULL, "out of memory");
    if (!src) {
        return NULL;
    }
    memcpy(src, tr_cl_kernel_source, tr_cl_kernel_source_length);
    memcpy(src + tr_cl_kernel_source_length, kernel, n + 1u);
    const char *srcs[1] = {src};
    cl_int rc;
    cl_program prog = clCreateProgramWithSource(ctx, 1, srcs, NULL, &rc);
    free(src);
    CHECK(rc == CL_SUCCESS, "clCreateProgramWithSource: %d", rc);
    if (rc != CL_SUCCESS) {
        return NULL;
    }
    rc = clBuildProgram(prog, 1, &dev, options, NULL, NULL);
    if (rc != CL_SUCCESS) {
        static char log[1 << 16];
        clGetProgramBuildInfo(prog, dev, CL_PROGRAM_BUILD_LOG, sizeof log - 1, log, NULL);
        CHECK(0, "clBuildProgram: %d: %s", rc, log);
        clReleaseProgram(prog);
        return NULL;
    }
    return prog;
}

#endif
