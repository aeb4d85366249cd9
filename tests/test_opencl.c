/* test_opencl.c - the OpenCL backend on PoCL (or whatever device 0 is): the embedded
 * kernel compiles without warnings, OpenCL and CPU films agree for the same scene,
 * seed and spp, and bad configurations fail with clear messages.
 *
 * One context (one kernel build) serves the whole binary: PoCL's first compile takes
 * seconds. Needs an OpenCL platform; tests/CMakeLists.txt registers this test only in
 * builds with the backend, and it fails (not skips) when no device can be opened. */
#define _POSIX_C_SOURCE 200809L /* setenv, unsetenv */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "device/opencl.h"
#include "trac0r/device.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/trac0r.h"

extern const char tr_cl_kernel_source[];
extern const size_t tr_cl_kernel_source_length;

/* Case-insensitive substring search. */
static int contains_ci(const char *hay, const char *needle) {
    size_t n = strlen(needle);
    for (; *hay; ++hay) {
        size_t i = 0;
        while (i < n && hay[i] &&
               tolower((unsigned char)hay[i]) == tolower((unsigned char)needle[i])) {
            ++i;
        }
        if (i == n) {
            return 1;
        }
    }
    return 0;
}

/* The log without the lines NVIDIA's drivers (550 on) print for every kernel, "Warning:
 * Function K is a kernel, so overriding noinline attribute", whatever the source: the
 * rest must be clean. */
static void strip_vendor_noise(const char *log, char *out, size_t cap) {
    size_t n = 0;
    while (*log && n + 1 < cap) {
        const char *end = strchr(log, '\n');
        const size_t len = end ? (size_t)(end - log) + 1 : strlen(log);
        char line[512];
        snprintf(line, sizeof line, "%.*s", (int)(len < sizeof line ? len : sizeof line - 1), log);
        if (!strstr(line, "is a kernel, so overriding noinline attribute")) {
            const size_t k = len < cap - 1 - n ? len : cap - 1 - n;
            memcpy(out + n, log, k);
            n += k;
        }
        log += len;
    }
    out[n] = '\0';
}

/* Renders 4 samples of `scene` with the naive integrator on a device opened with
 * TRAC0R_OPENCL_WORK_GROUP set to `wg` (NULL: unset) into f. */
static int render_with_work_group(tr_scene *scene, const char *wg, tr_film *f, tr_error *err) {
    if (wg) {
        setenv("TRAC0R_OPENCL_WORK_GROUP", wg, 1);
    } else {
        unsetenv("TRAC0R_OPENCL_WORK_GROUP");
    }
    tr_device *d = tr_device_create("opencl:0", err);
    unsetenv("TRAC0R_OPENCL_WORK_GROUP");
    if (!d) {
        return TR_ERR;
    }
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = TR_INTEGRATOR_NAIVE;
    int rc = tr_device_upload(d, scene, err) == TR_OK && tr_device_clear(d, err) == TR_OK &&
                     tr_device_render(d, &scene->camera, &cfg, 0, 4, NULL, NULL, err) == TR_OK &&
                     tr_device_read_film(d, f, err) == TR_OK
                 ? TR_OK
                 : TR_ERR;
    tr_device_destroy(d);
    return rc;
}

static double luminance(const tr_film *f, size_t i) {
    if (f->count[i] == 0) {
        return 0.0;
    }
    return (f->sum[3 * i] + f->sum[3 * i + 1] + f->sum[3 * i + 2]) / (3.0 * f->count[i]);
}

/* Region means of two films of the same scene agree within statistical bounds. The
 * noise of a region's mean is measured from two further CPU films with other seeds,
 * r1 and r2: per pixel, d = L(r1) - L(r2) has variance 2 sigma^2 (sigma^2 the per-pixel
 * Monte Carlo variance; pixels are independent, their random streams being keyed by
 * pixel), so the mean over the region's n pixels of L(a) - L(b), for independent a and
 * b, has variance var(d) / n. Films that share their random streams (a and b here)
 * differ by less. Each of the R x R regions must satisfy
 * |mean(L(a) - scale * L(b))| <= z * sqrt(var(d) / n) with z = 4.9 (two-sided
 * p = 1e-6 per region under the normal approximation), plus 1 % of the image's mean: a
 * region that is black but for a couple of pixels (outside the box) has a variance
 * estimate of two or three degrees of freedom, which a heavy-tailed pixel (a caustic
 * path found by BSDF sampling) exceeds by chance; a 20 % scaling stays far beyond the
 * floor. Returns the failing regions.
 */
static int region_failures(const tr_film *a, const tr_film *b, const tr_film *r1, const tr_film *r2,
                           double scale, uint32_t stride, int verbose) {
    /* With a preview stride only the traced pixel of each block is an independent
     * estimate: use those, in one region. */
    const int R = stride > 1 ? 1 : 4;
    int failures = 0;
    double image_mean = 0.0;
    for (size_t i = 0; i < (size_t)a->width * a->height; ++i) {
        image_mean += luminance(a, i);
    }
    image_mean /= (double)a->width * a->height;
    for (int ry = 0; ry < R; ++ry) {
        for (int rx = 0; rx < R; ++rx) {
            uint32_t x0 = a->width * (uint32_t)rx / R, x1 = a->width * (uint32_t)(rx + 1) / R;
            uint32_t y0 = a->height * (uint32_t)ry / R, y1 = a->height * (uint32_t)(ry + 1) / R;
            double sab = 0, sd = 0, qd = 0, n = 0;
            for (uint32_t y = y0; y < y1; ++y) {
                for (uint32_t x = x0; x < x1; ++x) {
                    if (x % stride || y % stride) {
                        continue;
                    }
                    size_t i = (size_t)y * a->width + x;
                    sab += luminance(a, i) - scale * luminance(b, i);
                    double d = luminance(r1, i) - luminance(r2, i);
                    sd += d;
                    qd += d * d;
                    n += 1;
                }
            }
            double md = sd / n;
            double vd = (qd - n * md * md) / (n - 1);
            double bound = 4.9 * sqrt(fmax(vd, 0) / n) + 0.01 * image_mean;
            if (!(fabs(sab / n) <= bound)) {
                ++failures;
            }
            if (verbose > 1 || (verbose && !(fabs(sab / n) <= bound))) {
                fprintf(stderr, "region (%d,%d): mean difference %.4g, bound %.4g\n", rx, ry,
                        sab / n, bound);
            }
        }
    }
    return failures;
}

/* The passes (the variance's sums of squares and the direct part too) of the CPU's and the device's
 * films: filled by the same kernel code (src/kernel/film.h), so they agree exactly except where a
 * path took another turn through the device's last-bit float differences, as radiance does (at most
 * 1 % of the pixels); the primitive ids, discrete, must agree on nearly every pixel. */
/* The values of the specular pass (8 per pixel) the last compare_passes found nonzero. */
static size_t last_specular_nonzero;

static void compare_passes(const tr_film *cpu, const tr_film *dev, const char *what) {
    const size_t n = (size_t)cpu->width * cpu->height;
    size_t far[7] = {0, 0, 0, 0, 0, 0, 0}, nonzero = 0;
    last_specular_nonzero = 0;
    CHECK(!cpu->specular == !dev->specular, "%s: one film has the specular pass", what);
    for (size_t i = 0; cpu->specular && dev->specular && i < 8 * n; ++i) {
        const double a = cpu->specular[i], b = dev->specular[i];
        far[6] += fabs(a - b) > 1e-4 * fmax(1.0, fmax(fabs(a), fabs(b)));
        last_specular_nonzero += a != 0.0;
    }
    for (size_t i = 0; i < n; ++i) {
        for (int c = 0; c < 3; ++c) {
            const float pa[5] = {cpu->albedo[3 * i + c], cpu->normal[3 * i + c],
                                 c == 0 ? cpu->depth[i] : 0.0f, cpu->sq[3 * i + c],
                                 cpu->direct ? cpu->direct[3 * i + c] : 0.0f};
            const float pb[5] = {dev->albedo[3 * i + c], dev->normal[3 * i + c],
                                 c == 0 ? dev->depth[i] : 0.0f, dev->sq[3 * i + c],
                                 dev->direct ? dev->direct[3 * i + c] : 0.0f};
            for (int p = 0; p < 5; ++p) {
                const double d = fabs((double)pa[p] - pb[p]);
                if (d > 1e-4 * fmax(1.0, fmax(fabs((double)pa[p]), fabs((double)pb[p])))) {
                    far[p < 4 ? p : 5] += 1;
                }
            }
        }
        far[4] += cpu->prim[i] != dev->prim[i];
        nonzero += cpu->prim[i] != 0u && cpu->count[i] > 0u;
    }
    /* The thesis's camera sees past the room's edges (black), and naive paths may end
     * before their first hit: a fifth of the pixels with a surface is a safe floor. */
    CHECK(nonzero * 5 > n, "%s: only %zu of %zu pixels have a surface in the passes", what, nonzero,
          n);
    const char *names[7] = {"albedo",       "normal", "depth",   "variance",
                            "primitive id", "direct", "specular"};
    for (int p = 0; p < 7; ++p) {
        const size_t values = p == 6 ? 8 * n : 3 * n;
        CHECK(far[p] * 100 <= 3 * values, "%s: %zu of %zu values of the %s pass differ", what,
              far[p], values, names[p]);
    }
    printf("%s: passes differ in %zu/%zu/%zu/%zu/%zu/%zu/%zu values "
           "(albedo/normal/depth/variance/id/direct/specular; %zu specular values nonzero)\n",
           what, far[0], far[1], far[2], far[3], far[4], far[5], far[6], last_specular_nonzero);
}

/* Renders `spp` samples of `scene` on the CPU and on the device and compares. */
static void compare_backends(tr_device *cl, tr_scene *scene, int stride, int integrator,
                             uint32_t spp, const char *what) {
    tr_error err;
    const uint32_t w = scene->camera.screen_width, h = scene->camera.screen_height;
    tr_film cpu, dev, r1, r2;
    /* bdpt keeps no direct or emission pass (tr_render_config_check refuses them), and only
     * pt the specular pass. */
    const uint32_t mask =
        tr_integrator_is_bidirectional(integrator)
            ? TR_PASS_MASK & ~(uint32_t)(TR_PASS_DIRECT | TR_PASS_EMISSION | TR_PASS_SPECULAR)
        : integrator == TR_INTEGRATOR_PT ? TR_PASS_MASK
                                         : TR_PASS_MASK & ~(uint32_t)TR_PASS_SPECULAR;
    CHECK(tr_film_init_passes(&cpu, w, h, mask, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_init_passes(&dev, w, h, mask, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_init(&r1, w, h, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_init(&r2, w, h, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.seed = 12345;
    cfg.stride = stride;
    cfg.integrator = integrator;
    CHECK(tr_device_upload(cl, scene, &err) == TR_OK, "%s: upload: %s", what, err.msg);
    CHECK(tr_device_clear(cl, &err) == TR_OK, "%s", err.msg);
    uint64_t rays_cpu = 0, rays_dev = 0;
    for (uint32_t s = 0; s < spp; ++s) {
        tr_render_stats st;
        tr_render_config with_passes = cfg;
        with_passes.passes = mask;
        CHECK(tr_render_frame(scene, &scene->camera, &with_passes, &cpu, s, &st, &err) == TR_OK,
              "%s", err.msg);
        rays_cpu += st.rays;
        tr_render_config passes = cfg;
        passes.passes = mask;
        CHECK(tr_device_render(cl, &scene->camera, &passes, s, 1, NULL, &st, &err) == TR_OK,
              "%s: %s", what, err.msg);
        rays_dev += st.rays;
        tr_render_config other = cfg;
        other.seed = 1;
        CHECK(tr_render_frame(scene, &scene->camera, &other, &r1, s, NULL, &err) == TR_OK, "%s",
              err.msg);
        other.seed = 2;
        CHECK(tr_render_frame(scene, &scene->camera, &other, &r2, s, NULL, &err) == TR_OK, "%s",
              err.msg);
    }
    CHECK(tr_device_read_film(cl, &dev, &err) == TR_OK, "%s", err.msg);
    compare_passes(&cpu, &dev, what);

    /* Sample counts depend on geometry only: identical. */
    size_t n = (size_t)w * h, count_diff = 0, pix_diff = 0, pix_far = 0;
    double max_rel = 0;
    for (size_t i = 0; i < n; ++i) {
        count_diff += cpu.count[i] != dev.count[i];
        int differs = 0, far = 0;
        for (int c = 0; c < 3; ++c) {
            float a = cpu.sum[3 * i + c], b = dev.sum[3 * i + c];
            if (a != b) {
                differs = 1;
                double rel = fabs((double)a - b) / fmax(fabs((double)a), fabs((double)b));
                max_rel = fmax(max_rel, rel);
                far |= rel > 1e-4;
            }
        }
        pix_diff += (size_t)differs;
        pix_far += (size_t)far;
    }
    CHECK(count_diff == 0, "%s: %zu pixels got a different sample count", what, count_diff);
    /* The device's sin/cos/exp/log1p/expm1/pow differ from glibc's by up to 1 ulp in a
     * fraction of inputs (docs/opencl.md). With the naive integrator a path's value only
     * depends on the discrete choices along it (triangles hit, reflect or refract):
     * cosine and lobe sampling make each bounce's weight the material colour, so a
     * 1-ulp change of a direction matters only where it changes such a choice (a ray
     * grazing an edge): nearly every pixel is bit-identical. An integrator whose weights
     * depend on angles differs in the last bits everywhere; either way, a pixel more
     * than 1e-4 apart (relative) has taken another path, and at most 1 % may. */
    CHECK(pix_far * 100 <= n,
          "%s: %zu of %zu pixels differ by more than 1e-4 between CPU and OpenCL", what, pix_far,
          n);
    printf("%s: %zu of %zu pixels differ at all, %zu by more than 1e-4 (max relative "
           "difference %.3g), rays %llu vs %llu\n",
           what, pix_diff, n, pix_far, max_rel, (unsigned long long)rays_cpu,
           (unsigned long long)rays_dev);
    /* The ray counts differ only through such paths. */
    CHECK(fabs((double)rays_cpu - (double)rays_dev) <= 0.01 * (double)rays_cpu,
          "%s: %llu rays on the CPU, %llu on the device", what, (unsigned long long)rays_cpu,
          (unsigned long long)rays_dev);
    int rf = region_failures(&cpu, &dev, &r1, &r2, 1.0, (uint32_t)stride, 1);
    CHECK(rf == 0, "%s: %d region means differ beyond their statistical bound", what, rf);
    /* The check would notice an independent film (another seed) only by chance, and a
     * brightness error of 20 % for sure: the bound is tight enough to matter (with a
     * stride, the few traced pixels leave too wide a bound for that). */
    CHECK(region_failures(&cpu, &r1, &r1, &r2, 1.0, (uint32_t)stride, 1) == 0,
          "%s: two CPU films with other seeds fail the region check", what);
    CHECK(stride > 1 || region_failures(&cpu, &dev, &r1, &r2, 1.2, (uint32_t)stride, 0) > 0,
          "%s: the region check does not notice a 20 %% scaling", what);
    tr_film_free(&cpu);
    tr_film_free(&dev);
    tr_film_free(&r1);
    tr_film_free(&r2);
}

int main(void) {
    tr_error err;
    int count = 0;
    tr_cl_device_info devs[16];
    CHECK(tr_cl_available() == 1, "this test is only built with the OpenCL backend");
    CHECK(tr_cl_list_devices(devs, 16, &count, &err) == TR_OK, "%s", err.msg);
    CHECK(count >= 1, "no OpenCL device (PoCL is installed by scripts/install-deps)");
    if (count < 1) {
        return check_finish("test_opencl");
    }
    CHECK(devs[0].index == 0 && devs[0].name[0] != '\0', "device 0 has no name");
    CHECK(devs[0].compute_units >= 1, "device 0: %u compute units", devs[0].compute_units);
    CHECK(devs[0].global_mem > 0 && devs[0].max_alloc > 0 &&
              devs[0].max_alloc <= devs[0].global_mem,
          "device 0: memory %llu, largest buffer %llu", (unsigned long long)devs[0].global_mem,
          (unsigned long long)devs[0].max_alloc);

    /* The embedded source is the kernel headers inlined behind entry.cl. */
    CHECK(tr_cl_kernel_source_length == strlen(tr_cl_kernel_source), "embedded length");
    const char *headers[] = {"kernel.h", "compat.h",     "types.h",           "vec.h",
                             "rng.h",    "sampling.h",   "material.h",        "intersect.h",
                             "camera.h", "scene_view.h", "integrator_naive.h"};
    for (size_t i = 0; i < sizeof headers / sizeof headers[0]; ++i) {
        char tag[64];
        snprintf(tag, sizeof tag, "#line 1 \"%s\"", headers[i]);
        CHECK(strstr(tr_cl_kernel_source, tag) != NULL, "%s is not embedded", headers[i]);
    }
    CHECK(strstr(tr_cl_kernel_source, "#include \"") == NULL,
          "the embedded source still has a quoted #include");

    /* Out-of-range device indices. */
    CHECK_STATUS(tr_cl_open(count, &err) ? TR_OK : TR_ERR, err, TR_STATUS_NOT_FOUND,
                 "device index = device count");
    CHECK_STATUS(tr_cl_open(-1, &err) ? TR_OK : TR_ERR, err, TR_STATUS_INVALID_ARGUMENT,
                 "device -1");

    tr_cl_context *cl = tr_cl_open(0, &err);
    CHECK(cl != NULL, "tr_cl_open(0): %s", err.msg);
    if (!cl) {
        fprintf(stderr, "build log:\n%s\n", tr_cl_last_build_log());
        return check_finish("test_opencl");
    }
    const char *log = tr_cl_build_log(cl);
    char clean[4096];
    strip_vendor_noise(log, clean, sizeof clean);
    CHECK(!contains_ci(clean, "warning") && !contains_ci(clean, "error"),
          "the kernel build log is not clean:\n%s", log);
    strip_vendor_noise("a\n(): Warning: Function k is a kernel, so overriding noinline attribute. "
                       "The function may be inlined when called.\nwarning: b\n",
                       clean, sizeof clean);
    CHECK(strcmp(clean, "a\nwarning: b\n") == 0, "stripped: '%s'", clean);
    CHECK(strstr(tr_cl_build_options(cl), "-cl-std=CL1.2") != NULL, "options: %s",
          tr_cl_build_options(cl));
    printf("device 0: %s (%s), %u compute units; build log: '%s'\n", tr_cl_device(cl)->name,
           tr_cl_device(cl)->vendor, tr_cl_device(cl)->compute_units, log);

    /* The build log shows warnings (so a clean log means something), and a kernel that
     * does not compile is reported with the call, the error name and the log. */
    const char *warns =
        "#warning this line warns\n__kernel void other(__global int *p) { p[0] = 1; }\n";
    CHECK_STATUS(tr_cl_open_source(0, warns, &err) ? TR_OK : TR_ERR, err, TR_STATUS_DEVICE,
                 "a kernel without tr_cl_render");
    /* docs/opencl.md promises the failing call and the error's name in the message. */
    CHECK(strstr(err.msg, "clCreateKernel(tr_cl_render)") &&
              strstr(err.msg, "CL_INVALID_KERNEL_NAME"),
          "message: %s", err.msg);
    CHECK(contains_ci(tr_cl_last_build_log(), "warning"), "no warning in the log of %s: '%s'",
          warns, tr_cl_last_build_log());
    const char *broken = "__kernel void tr_cl_render(__global int *p) { p[0] = undeclared; }\n";
    CHECK_STATUS(tr_cl_open_source(0, broken, &err) ? TR_OK : TR_ERR, err, TR_STATUS_DEVICE,
                 "a broken kernel");
    CHECK(strstr(err.msg, "clBuildProgram") && strstr(err.msg, "CL_BUILD_PROGRAM_FAILURE") &&
              strstr(err.msg, "undeclared"),
          "message: %s", err.msg);
    CHECK(contains_ci(tr_cl_last_build_log(), "error"), "build log: '%s'", tr_cl_last_build_log());

    tr_cl_close(cl);
    /* From here on through the device API, as applications use it. */
    tr_device *dev = tr_device_create("opencl:0", &err);
    CHECK(dev != NULL, "tr_device_create(opencl:0): %s", err.msg);
    if (!dev) {
        return check_finish("test_opencl");
    }
    CHECK(strcmp(tr_device_kind(dev), "opencl") == 0, "kind %s", tr_device_kind(dev));
    CHECK(tr_device_create("opencl:x", &err) == NULL && tr_device_create("gpu", &err) == NULL,
          "bad device names opened");
    tr_render_config cfg = tr_render_config_default();
    tr_scene scene = {0};
    tr_scene_init(&scene);
    CHECK(tr_scene_builtin(&scene, "cornell", 48, 36, &err) == TR_OK, "%s", err.msg);
    /* Nothing uploaded yet. */
    CHECK_STATUS(tr_device_render(dev, &scene.camera, &cfg, 0, 1, NULL, NULL, &err), err,
                 TR_STATUS_INVALID_OPERATION, "a frame without a scene");
    CHECK_STATUS(tr_device_read_film(dev, &(tr_film){0}, &err), err, TR_STATUS_INVALID_OPERATION,
                 "reading an unrendered film");

    /* Both device structures, and Embree's scene traced through a device BVH. */
    const tr_accel_type accels[] = {TR_ACCEL_TYPE_FLAT, TR_ACCEL_TYPE_BVH, TR_ACCEL_TYPE_BVH2,
                                    TR_ACCEL_TYPE_EMBREE};
    for (int k = 0; k < 4; ++k) {
        if (!tr_accel_available(accels[k])) {
            printf("accel %s: not in this build\n", tr_accel_name(accels[k]));
            continue;
        }
        CHECK(tr_scene_commit(&scene, accels[k], &err) == TR_OK, "%s", err.msg);
        char what[64];
        snprintf(what, sizeof what, "accel %s", tr_accel_name(accels[k]));
        compare_backends(dev, &scene, 1, TR_INTEGRATOR_NAIVE, 64, what);
        tr_accel_type want =
            accels[k] == TR_ACCEL_TYPE_FLAT ? TR_ACCEL_TYPE_FLAT : TR_ACCEL_TYPE_BVH;
        CHECK(tr_device_accel(dev) == want, "%s: the device walks %s", what,
              tr_accel_name(tr_device_accel(dev)));
    }
    /* Preview stride: the same blocks filled as on the CPU. */
    CHECK(tr_scene_commit(&scene, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    compare_backends(dev, &scene, 5, TR_INTEGRATOR_NAIVE, 64, "bvh, stride 5");
    /* The pt integrator with its emitter table on the device. */
    compare_backends(dev, &scene, 1, TR_INTEGRATOR_PT, 64, "bvh, pt");
    CHECK(tr_scene_commit(&scene, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);
    compare_backends(dev, &scene, 1, TR_INTEGRATOR_PT, 64, "flat, pt");
    /* bdpt: light tracing's splats summed with 64-bit atomics on the device and folded into
     * the film after each frame, as the CPU does (integrator_bdpt.h). */
    compare_backends(dev, &scene, 1, TR_INTEGRATOR_BDPT, 32, "flat, bdpt");
    CHECK(tr_scene_commit(&scene, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    compare_backends(dev, &scene, 1, TR_INTEGRATOR_BDPT, 32, "bvh, bdpt");
    /* vcm: the light pass's entries ordered into the CPU's buckets, the camera pass tracing
     * each light subpath again. Every fifth point first: the full frame after it has five
     * times the light vertices the device made room for, so its light pass runs again with
     * more room (opencl.c, vcm_light_pass). */
    compare_backends(dev, &scene, 5, TR_INTEGRATOR_VCM, 8, "bvh, vcm, stride 5");
    compare_backends(dev, &scene, 1, TR_INTEGRATOR_VCM, 16, "bvh, vcm");
    CHECK(tr_scene_commit(&scene, TR_ACCEL_TYPE_FLAT, &err) == TR_OK, "%s", err.msg);
    /* bdpt's light subpaths from a sky and a sun, seen through the box's open front: the
     * scene's bounding sphere travels with the scene's scalars. */
    {
        tr_scene sky = {0};
        tr_scene_init(&sky);
        CHECK(tr_scene_builtin(&sky, "cornell", 48, 36, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_scene_set_environment(&sky, v3(0.6f, 0.8f, 1.0f), 1.5f, 0.0f, NULL, 0, 0, &err) ==
                  TR_OK,
              "%s", err.msg);
        CHECK(tr_scene_set_sun(&sky, v3(0.2f, 0.5f, -1.0f), 2.0f, v3(5.0f, 4.5f, 4.0f), &err) ==
                  TR_OK,
              "%s", err.msg);
        CHECK(tr_scene_commit(&sky, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        compare_backends(dev, &sky, 1, TR_INTEGRATOR_BDPT, 32, "bvh, bdpt, sky and sun");
        /* Light from outside: merges only between surfaces that face alike. */
        compare_backends(dev, &sky, 1, TR_INTEGRATOR_VCM, 16, "bvh, vcm, sky and sun");
        tr_scene_clear(&sky);
    }
    /* A thin lens (camera.h) focused on the box's centre, sampled alike by both. */
    {
        const tr_camera pinhole = scene.camera;
        const tr_aabb b = tr_scene_bounds(&scene);
        const tr_vec3 mid = v3_scale(v3_add(b.min, b.max), 0.5f);
        const float focus = v3_dot(v3_sub(mid, pinhole.pos), pinhole.dir);
        CHECK(tr_camera_set_lens(&scene.camera, 0.04f * (b.max.y - b.min.y), focus, &err) == TR_OK,
              "%s", err.msg);
        compare_backends(dev, &scene, 1, TR_INTEGRATOR_PT, 64, "flat, pt, thin lens");
        compare_backends(dev, &scene, 1, TR_INTEGRATOR_NAIVE, 64, "flat, naive, thin lens");
        scene.camera = pinhole;
    }
    /* Point, spot and directional lights (punctual.h) in a box of its own: each sampled at
     * every vertex, and with more of them than that, one picked by the power CDF; with
     * more than 8 point and spot lights (24 lights), those picked through the light tree
     * beside the box's lamp (light_tree.h). */
    for (int many = 0; many < 3; ++many) {
        tr_scene lit = {0};
        tr_scene_init(&lit);
        CHECK(tr_scene_builtin(&lit, "cornell", 48, 36, &err) == TR_OK, "%s", err.msg);
        const tr_aabb b = tr_scene_bounds(&lit);
        const tr_vec3 mid = v3_scale(v3_add(b.min, b.max), 0.5f);
        const tr_vec3 ext = v3_sub(b.max, b.min);
        const int n = many == 2 ? 24 : many ? 10 : 3;
        for (int i = 0; i < n; ++i) {
            tr_punctual l;
            memset(&l, 0, sizeof l);
            l.type = (uint32_t)(i % 3);
            l.pos = v3_add(mid, v3(ext.x * (0.1f * (float)(i % 5) - 0.2f), ext.y * 0.3f,
                                   ext.z * (0.05f * (float)i - 0.2f)));
            l.dir = v3(0.1f * (float)i - 0.3f, -1.0f, 0.2f);
            l.intensity = v3(0.5f + 0.1f * (float)i, 0.4f, 0.3f);
            l.intensity = v3_scale(
                l.intensity, l.type == TR_PUNCTUAL_DIRECTIONAL ? 0.5f : 0.02f * ext.y * ext.y);
            l.cos_outer = 0.7f;
            l.cos_inner = 0.85f;
            CHECK(tr_scene_add_punctual(&lit, &l, &err) == TR_OK, "%s", err.msg);
        }
        CHECK(tr_scene_commit(&lit, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        compare_backends(dev, &lit, 1, TR_INTEGRATOR_PT, 64,
                         many == 2 ? "bvh, pt, punctual lights in the light tree"
                         : many    ? "bvh, pt, ten punctual lights"
                                   : "bvh, pt, punctual lights");
        if (many == 2) {
            CHECK(tr_scene_view_of(&lit).light_leaf_count > tr_scene_view_of(&lit).light_count,
                  "24 punctual lights are not in the light tree");
        }
        if (!many) {
            /* bdpt adds them along the camera subpath (tr_bdpt_infinite). */
            compare_backends(dev, &lit, 1, TR_INTEGRATOR_BDPT, 64, "bvh, bdpt, punctual lights");
        }
        tr_render_config naive = tr_render_config_default();
        naive.integrator = TR_INTEGRATOR_NAIVE;
        CHECK_STATUS(tr_device_render(dev, &lit.camera, &naive, 0, 1, NULL, NULL, &err), err,
                     TR_STATUS_UNSUPPORTED, "naive with punctual lights on the device");
        tr_scene_clear(&lit);
    }
    /* Multiple-scattering compensation (ggx_ms.h): the box's diffuse walls made rough
     * conductors that ask for it, the table uploaded with the scene. */
    {
        tr_scene ms = {0};
        tr_scene_init(&ms);
        CHECK(tr_scene_builtin(&ms, "cornell", 48, 36, &err) == TR_OK, "%s", err.msg);
        for (uint32_t i = 0; i < ms.material_count; ++i) {
            if (ms.materials[i].type == TR_MATERIAL_DIFFUSE) {
                ms.materials[i].type = TR_MATERIAL_GLOSSY;
                ms.materials[i].roughness = 0.3f + 0.2f * (float)(i % 4);
                ms.materials[i].flags |= TR_MATERIAL_MULTISCATTER;
            }
        }
        CHECK(tr_scene_commit(&ms, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_scene_view_of(&ms).ggx_ms_count == TR_GGX_MS_COUNT, "the table is in the view");
        compare_backends(dev, &ms, 1, TR_INTEGRATOR_PT, 64, "bvh, pt, multiscatter glossy");
        /* The glossy walls' specular pass is written on both sides, not zero on both. */
        CHECK(last_specular_nonzero * 4 >
                  8 * (size_t)ms.camera.screen_width * ms.camera.screen_height,
              "multiscatter glossy: only %zu specular values nonzero", last_specular_nonzero);
        tr_scene_clear(&ms);
    }
    /* The principled material's clear coat (bsdf_principled.h): the box's diffuse walls made
     * principled with coats of several weights and roughnesses, through material extras. */
    {
        tr_scene cc = {0};
        tr_scene_init(&cc);
        CHECK(tr_scene_builtin(&cc, "cornell", 48, 36, &err) == TR_OK, "%s", err.msg);
        for (uint32_t i = 0; i < cc.material_count; ++i) {
            if (cc.materials[i].type == TR_MATERIAL_DIFFUSE) {
                cc.materials[i].type = TR_MATERIAL_PRINCIPLED;
                cc.materials[i].roughness = 0.5f;
                tr_material_ext e = tr_material_ext_default();
                e.metallic = (float)(i % 2) * 0.8f;
                e.clearcoat = 0.5f + 0.25f * (float)(i % 3);
                e.clearcoat_roughness = 0.1f * (float)(i % 4);
                CHECK(tr_scene_set_material_ext(&cc, i, &e, &err) == TR_OK, "%s", err.msg);
            }
        }
        CHECK(tr_scene_commit(&cc, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        compare_backends(dev, &cc, 1, TR_INTEGRATOR_PT, 64, "bvh, pt, clear-coated principled");
        tr_scene_clear(&cc);
    }
    /* The clear coat's maps (glTF's clearcoatTexture, red, and clearcoatRoughnessTexture,
     * green, times the factors): a texture whose red and green run against each other,
     * one map or both on each wall. */
    {
        tr_scene cm = {0};
        tr_scene_init(&cm);
        CHECK(tr_scene_builtin(&cm, "cornell", 48, 36, &err) == TR_OK, "%s", err.msg);
        uint32_t rg[16], tex = 0;
        for (uint32_t k = 0; k < 16; ++k) {
            const uint32_t r = 17u * k, g = 255u - 17u * ((k * 7u) % 16u);
            rg[k] = 0xff000000u | (g << 8) | r;
        }
        CHECK(tr_scene_add_texture(&cm, rg, 4, 4, 0u, &tex, &err) == TR_OK, "%s", err.msg);
        for (uint32_t i = 0; i < cm.material_count; ++i) {
            if (cm.materials[i].type == TR_MATERIAL_DIFFUSE) {
                cm.materials[i].type = TR_MATERIAL_PRINCIPLED;
                cm.materials[i].roughness = 0.5f;
                tr_material_ext e = tr_material_ext_default();
                e.clearcoat = 1.0f;
                e.clearcoat_roughness = 0.6f;
                e.clearcoat_tex = i % 3 != 1 ? tex : TR_NO_INDEX;
                e.clearcoat_rough_tex = i % 3 != 0 ? tex : TR_NO_INDEX;
                CHECK(tr_scene_set_material_ext(&cm, i, &e, &err) == TR_OK, "%s", err.msg);
            }
        }
        CHECK(tr_scene_commit(&cm, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        compare_backends(dev, &cm, 1, TR_INTEGRATOR_PT, 64, "bvh, pt, clear coat maps");
        tr_scene_clear(&cm);
    }
    /* The principled material's sheen (bsdf_principled.h) over dielectric and metallic
     * bases, some under a coat, some with the energy compensation (its tables uploaded with
     * the scene), some with KHR_materials_specular. */
    {
        tr_scene sh = {0};
        tr_scene_init(&sh);
        CHECK(tr_scene_builtin(&sh, "cornell", 48, 36, &err) == TR_OK, "%s", err.msg);
        for (uint32_t i = 0; i < sh.material_count; ++i) {
            if (sh.materials[i].type == TR_MATERIAL_DIFFUSE) {
                sh.materials[i].type = TR_MATERIAL_PRINCIPLED;
                sh.materials[i].roughness = 0.3f + 0.2f * (float)(i % 3);
                sh.materials[i].flags |= i % 2 ? TR_MATERIAL_MULTISCATTER : 0u;
                tr_material_ext e = tr_material_ext_default();
                e.metallic = (float)(i % 3 == 1);
                e.clearcoat = i % 4 == 0 ? 0.6f : 0.0f;
                e.clearcoat_roughness = 0.2f;
                e.sheen_color = v3(0.9f, 0.5f * (float)(i % 2), 0.7f);
                e.sheen_roughness = 0.2f + 0.25f * (float)(i % 4);
                if (i % 3 == 0) {
                    /* KHR_materials_specular: a weaker, tinted dielectric layer. */
                    e.flags |= TR_MATEXT_SPECULAR;
                    e.specular = 0.7f;
                    e.specular_color = v3(1.5f, 1.0f, 0.5f);
                }
                CHECK(tr_scene_set_material_ext(&sh, i, &e, &err) == TR_OK, "%s", err.msg);
            }
        }
        CHECK(tr_scene_commit(&sh, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_scene_view_of(&sh).ggx_ms_count == TR_GGX_MS_COUNT, "the table is in the view");
        compare_backends(dev, &sh, 1, TR_INTEGRATOR_PT, 64, "bvh, pt, principled with a sheen");
        tr_scene_clear(&sh);
    }
    /* The sheen's maps (colour, sRGB, and roughness in alpha) and the clear coat's own
     * normal map (material_eval.h, bsdf_principled.h) on a quad with texture coordinates
     * in front of the back wall, with and without the energy compensation. */
    {
        tr_scene sm = {0};
        tr_scene_init(&sm);
        CHECK(tr_scene_builtin(&sm, "cornell", 48, 36, &err) == TR_OK, "%s", err.msg);
        uint32_t col[16], nrm[16], ctex = 0, ntex = 0;
        for (uint32_t k = 0; k < 16; ++k) {
            const uint32_t r = 17u * k, g = 255u - 17u * ((k * 7u) % 16u), a = 40u + 13u * k;
            col[k] = (a << 24) | ((r ^ g) << 16) | (g << 8) | r;
            /* Tangent-space normals tilted up to about 40 degrees, every way. */
            const uint32_t nx = 68u + 40u * (k % 4u), ny = 68u + 40u * (k / 4u);
            nrm[k] = 0xff000000u | (230u << 16) | (ny << 8) | nx;
        }
        CHECK(tr_scene_add_texture(&sm, col, 4, 4, 0u, &ctex, &err) == TR_OK &&
                  tr_scene_add_texture(&sm, nrm, 4, 4, 0u, &ntex, &err) == TR_OK,
              "%s", err.msg);
        const float pos[12] = {0.45f,  0.0f, 0.45f, -0.45f, 0.0f, 0.45f,
                               -0.45f, 0.8f, 0.45f, 0.45f,  0.8f, 0.45f};
        const float uv[8] = {0, 1, 1, 1, 1, 0, 0, 0};
        const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
        const tr_transform tf = {{0, 0, 0}, {0, 0, 0}, {1, 1, 1}};
        for (uint32_t q = 0; q < 2; ++q) {
            tr_material pm;
            memset(&pm, 0, sizeof pm);
            pm.type = TR_MATERIAL_PRINCIPLED;
            pm.color = v3(0.7f, 0.4f, 0.2f);
            pm.roughness = 0.5f;
            pm.ior = 1.5f;
            pm.flags = q ? TR_MATERIAL_MULTISCATTER : 0u;
            uint32_t mi = 0, dropped = 0;
            CHECK(tr_scene_add_material(&sm, pm, &mi, &err) == TR_OK, "%s", err.msg);
            tr_material_ext e = tr_material_ext_default();
            e.metallic = 0.3f * (float)q;
            e.sheen_color = v3(0.9f, 0.7f, 0.8f);
            e.sheen_roughness = 0.6f;
            e.sheen_color_tex = ctex;
            e.sheen_rough_tex = ctex;
            e.clearcoat = 0.8f;
            e.clearcoat_roughness = 0.15f + 0.3f * (float)q;
            e.clearcoat_normal_tex = ntex;
            e.clearcoat_normal_scale = 1.0f - 0.4f * (float)q;
            CHECK(tr_scene_set_material_ext(&sm, mi, &e, &err) == TR_OK, "%s", err.msg);
            float p2[12];
            for (int k = 0; k < 12; ++k) {
                p2[k] = pos[k] * (q ? 0.5f : 1.0f) + (q && k % 3 == 2 ? -0.3f : 0.0f);
            }
            CHECK(tr_scene_add_mesh_uv(&sm, p2, 4, idx, 2, NULL, uv, mi, &tf, &dropped, &err) ==
                      TR_OK,
                  "%s", err.msg);
        }
        CHECK(tr_scene_commit(&sm, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        compare_backends(dev, &sm, 1, TR_INTEGRATOR_PT, 64, "bvh, pt, sheen and coat normal maps");
        tr_scene_clear(&sm);
    }
    /* Transmission (the rough dielectric boundary of bsdf_dielectric.h) with several
     * weights, indices and roughnesses, the volume's absorption behind back faces, and a
     * base map seen through a texture transform (texture.h; without vertex attributes the
     * barycentrics are the coordinates). */
    {
        tr_scene tm = {0};
        tr_scene_init(&tm);
        CHECK(tr_scene_builtin(&tm, "cornell", 48, 36, &err) == TR_OK, "%s", err.msg);
        uint32_t checker[16], tex = 0, moved = 0;
        for (uint32_t k = 0; k < 16; ++k) {
            checker[k] = ((k + k / 4) % 2 ? 0xffffffffu : 0xff402010u);
        }
        float xf[6];
        tr_texture_transform_glTF(xf, 0.25f, -0.5f, 0.7f, 3.0f, 2.0f);
        CHECK(tr_scene_add_texture(&tm, checker, 4, 4, 0u, &tex, &err) == TR_OK &&
                  tr_scene_texture_transformed(&tm, tex, xf, &moved, &err) == TR_OK,
              "%s", err.msg);
        for (uint32_t i = 0; i < tm.material_count; ++i) {
            if (tm.materials[i].type == TR_MATERIAL_DIFFUSE) {
                tm.materials[i].type = TR_MATERIAL_PRINCIPLED;
                tm.materials[i].roughness = 0.15f + 0.25f * (float)(i % 3);
                tm.materials[i].ior = 1.2f + 0.15f * (float)(i % 4);
                tr_material_ext e = tr_material_ext_default();
                e.transmission = 0.5f + 0.25f * (float)(i % 3);
                e.metallic = 0.2f * (float)(i % 2);
                e.absorption = v3(0.5f, 1.0f * (float)(i % 2), 2.0f);
                e.base_tex = i % 2 ? moved : tex;
                CHECK(tr_scene_set_material_ext(&tm, i, &e, &err) == TR_OK, "%s", err.msg);
            }
        }
        CHECK(tr_scene_commit(&tm, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
        compare_backends(dev, &tm, 1, TR_INTEGRATOR_PT, 64, "bvh, pt, transmissive principled");
        tr_scene_clear(&tm);
    }
    CHECK(tr_device_upload(dev, &scene, &err) == TR_OK, "%s", err.msg);

    /* Film handling: a wrongly sized film, clearing, a bad config. */
    tr_film small;
    CHECK(tr_film_init(&small, 8, 8, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_device_read_film(dev, &small, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "read into an 8x8 film");
    tr_film film;
    CHECK(tr_film_init(&film, 48, 36, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_clear(dev, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_read_film(dev, &film, &err) == TR_OK, "%s", err.msg);
    uint64_t total = 0;
    for (size_t i = 0; i < 48 * 36; ++i) {
        total += film.count[i];
    }
    CHECK(total == 0, "%llu samples left after tr_device_clear", (unsigned long long)total);
    cfg.integrator = 99;
    CHECK_STATUS(tr_device_render(dev, &scene.camera, &cfg, 0, 1, NULL, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "integrator 99");
    cfg = tr_render_config_default();
    cfg.max_depth = -1; /* 0 asks for the integrator's default */
    CHECK_STATUS(tr_device_render(dev, &scene.camera, &cfg, 0, 1, NULL, NULL, &err), err,
                 TR_STATUS_INVALID_ARGUMENT, "max depth -1");
    cfg = tr_render_config_default();

    /* A device without enough memory: the upload fails before touching the scene on
     * the device, which keeps rendering the previous one. */
    tr_scene big = {0};
    tr_scene_init(&big);
    CHECK(tr_scene_builtin(&big, "cornell-ico-5", 48, 36, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&big, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_device_set_memory_limit(dev, 1u << 20); /* 1 MiB: cornell-ico-5 needs about 3 */
    CHECK_STATUS(tr_device_upload(dev, &big, &err), err, TR_STATUS_LIMIT,
                 "a scene beyond the memory limit");
    CHECK(tr_device_render(dev, &scene.camera, &cfg, 0, 1, NULL, NULL, &err) == TR_OK,
          "the previous scene is gone after a failed upload: %s", err.msg);
    tr_device_set_memory_limit(dev, 0);
    CHECK(tr_device_upload(dev, &big, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_scene_bytes(dev) > (1u << 20), "scene bytes %llu",
          (unsigned long long)tr_device_scene_bytes(dev));
    tr_render_stats st;
    CHECK(tr_device_render(dev, &big.camera, &cfg, 0, 1, NULL, &st, &err) == TR_OK, "%s", err.msg);
    CHECK(st.rays >= 48 * 36, "%llu rays for a 48x36 frame", (unsigned long long)st.rays);
    /* A shape added after the commit: the upload refuses the stale structure. */
    tr_shape_desc box = tr_shape_desc_default(TR_SHAPE_BOX);
    box.transform.scale = v3s(0.1f);
    CHECK(tr_scene_add_shape(&big, &box, &err) == TR_OK, "%s", err.msg);
    CHECK_STATUS(tr_device_upload(dev, &big, &err), err, TR_STATUS_STALE_SCENE,
                 "uploading a scene changed since its commit");

    /* The work-group size (TRAC0R_OPENCL_WORK_GROUP; GPUs default to 8x8): a 37x23 frame
     * is no multiple of it, the grid is rounded up, and every size gives the driver's
     * image bit for bit. Malformed sizes are refused when the device opens. */
    tr_scene odd = {0};
    tr_scene_init(&odd);
    CHECK(tr_scene_builtin(&odd, "cornell", 37, 23, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(&odd, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    tr_film wref, wgot;
    CHECK(tr_film_init(&wref, 37, 23, &err) == TR_OK && tr_film_init(&wgot, 37, 23, &err) == TR_OK,
          "%s", err.msg);
    CHECK(render_with_work_group(&odd, "driver", &wref, &err) == TR_OK, "driver: %s", err.msg);
    const char *sizes[] = {NULL, "8x8", "5x3", "1x1", "16x4"};
    for (int k = 0; k < 5; ++k) {
        CHECK(render_with_work_group(&odd, sizes[k], &wgot, &err) == TR_OK, "%s: %s",
              sizes[k] ? sizes[k] : "default", err.msg);
        CHECK(memcmp(wref.sum, wgot.sum, 3 * 37 * 23 * sizeof *wref.sum) == 0 &&
                  memcmp(wref.count, wgot.count, 37 * 23 * sizeof *wref.count) == 0,
              "work group %s: the image differs from the driver's choice",
              sizes[k] ? sizes[k] : "default");
    }
    const char *bad[] = {"0x8", "8x", "8x8x", "axb", "2000x1", "1024x1024", ""};
    for (int k = 0; k < 6; ++k) {
        CHECK_STATUS(render_with_work_group(&odd, bad[k], &wgot, &err), err,
                     TR_STATUS_INVALID_ARGUMENT, bad[k]);
    }
    /* Empty means unset. */
    CHECK(render_with_work_group(&odd, bad[6], &wgot, &err) == TR_OK, "'': %s", err.msg);
    tr_film_free(&wref);
    tr_film_free(&wgot);
    tr_scene_clear(&odd);

    /* bdpt and vcm as on a device without cl_khr_int64_base_atomics and cl_khr_fp64: the
     * splat sums as pairs of 32-bit words added with 32-bit atomics, folded on the host;
     * the films as the CPU's, as with the extensions. */
    {
        int emulated = 1, host_fold = 1;
        CHECK(tr_cl_splat_paths(tr_device_cl_context(dev), &emulated, &host_fold, &err) == TR_OK,
              "%s", err.msg);
        CHECK(!emulated && !host_fold, "PoCL has both extensions: emulated %d, host fold %d",
              emulated, host_fold);
        setenv("TRAC0R_OPENCL_DISABLE_EXT", "cl_khr_int64_base_atomics,cl_khr_fp64", 1);
        tr_device *fb = tr_device_create("opencl:0", &err);
        CHECK(fb != NULL, "tr_device_create without the extensions: %s", err.msg);
        if (fb) {
            CHECK(tr_cl_splat_paths(tr_device_cl_context(fb), &emulated, &host_fold, &err) == TR_OK,
                  "%s", err.msg);
            CHECK(emulated && host_fold, "without the extensions: emulated %d, host fold %d",
                  emulated, host_fold);
            CHECK(tr_scene_commit(&scene, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
            compare_backends(fb, &scene, 1, TR_INTEGRATOR_BDPT, 16,
                             "bvh, bdpt, 32-bit atomics, host fold");
            compare_backends(fb, &scene, 1, TR_INTEGRATOR_VCM, 16,
                             "bvh, vcm, 32-bit atomics, host fold");
            tr_device_destroy(fb);
        }
        /* Only those two names. */
        const char *bad_ext[3] = {"cl_khr_fp16", "cl_khr_fp64,", "cl_khr_fp64 "};
        for (int k = 0; k < 3; ++k) {
            setenv("TRAC0R_OPENCL_DISABLE_EXT", bad_ext[k], 1);
            tr_device *no = tr_device_create("opencl:0", &err);
            CHECK_STATUS(no ? TR_OK : TR_ERR, err, TR_STATUS_INVALID_ARGUMENT, bad_ext[k]);
            if (no) {
                tr_device_destroy(no);
            }
        }
        unsetenv("TRAC0R_OPENCL_DISABLE_EXT");
    }

    tr_scene_clear(&big);
    tr_film_free(&small);
    tr_film_free(&film);
    tr_scene_clear(&scene);
    tr_device_destroy(dev);
    return check_finish("test_opencl");
}
