/* test_opencl_firefly.c - pt's firefly control (the indirect clamp and path
 * regularization, tr_render_config) gives the same image on an OpenCL device (PoCL here)
 * as on the CPU: the frame carries both settings to the device, and the same kernel text
 * runs there. The thesis's Cornell box has glass and a glossy object, which
 * regularization changes, and bright indirect light, which the clamp changes; the CPU's
 * controlled film must differ from its plain one (so that the comparison is not of two
 * unchanged films), and the device's must match the controlled one as test_opencl's
 * films do: at most 1 % of the pixels more than 1e-4 apart (a path turned elsewhere by a
 * last-bit difference of the device's sin or cos), and the image means within 0.5 %. */
#include "check.h"
#include "trac0r/trac0r.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define W 48
#define H 36
#define SPP 8

static double mean(const tr_film *f) {
    double s = 0.0;
    for (size_t i = 0; i < 3u * W * H; ++i) {
        s += f->sum[i];
    }
    return s / (3.0 * W * H * SPP);
}

int main(void) {
    tr_error err;
    tr_device *dev = tr_device_create("opencl:0", &err);
    CHECK(dev != NULL, "tr_device_create(opencl:0): %s", err.msg);
    if (!dev) {
        return check_finish("test_opencl_firefly");
    }
    tr_scene *scene = tr_scene_create(&err);
    CHECK(tr_scene_builtin(scene, "cornell", W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_scene_commit(scene, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_upload(dev, scene, &err) == TR_OK, "%s", err.msg);
    const tr_camera *cam = tr_scene_camera(scene);

    tr_render_config plain = tr_render_config_default();
    plain.seed = 77;
    plain.threads = 2;
    tr_render_config ff = plain;
    ff.clamp_indirect = 0.5f;
    ff.regularize = 1;

    tr_film cpu, cpu_plain, gpu;
    CHECK(tr_film_init(&cpu, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_init(&cpu_plain, W, H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_film_init(&gpu, W, H, &err) == TR_OK, "%s", err.msg);
    for (uint32_t s = 0; s < SPP; ++s) {
        CHECK(tr_render_frame(scene, cam, &ff, &cpu, s, NULL, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_render_frame(scene, cam, &plain, &cpu_plain, s, NULL, &err) == TR_OK, "%s",
              err.msg);
    }
    CHECK(tr_device_clear(dev, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_render(dev, cam, &ff, 0, SPP, NULL, NULL, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_read_film(dev, &gpu, &err) == TR_OK, "%s", err.msg);

    size_t changed = 0, far = 0;
    const size_t n = (size_t)W * H;
    for (size_t i = 0; i < n; ++i) {
        int px_far = 0;
        for (int c = 0; c < 3; ++c) {
            const float a = cpu.sum[3 * i + c], b = gpu.sum[3 * i + c];
            changed += a != cpu_plain.sum[3 * i + c];
            if (a != b) {
                const double rel = fabs((double)a - b) / fmax(fabs((double)a), fabs((double)b));
                px_far |= rel > 1e-4;
            }
        }
        far += (size_t)px_far;
    }
    const double m_cpu = mean(&cpu), m_gpu = mean(&gpu), m_plain = mean(&cpu_plain);
    printf("firefly control: %zu values changed on the CPU; %zu of %zu pixels differ by more "
           "than 1e-4 on the device; means %.5f (CPU), %.5f (device), %.5f (plain)\n",
           changed, far, n, m_cpu, m_gpu, m_plain);
    CHECK(changed > n / 20, "firefly control changed only %zu values of the box", changed);
    CHECK(far * 100 <= n, "%zu of %zu pixels differ by more than 1e-4 between CPU and device", far,
          n);
    CHECK(fabs(m_cpu - m_gpu) <= 0.005 * m_cpu, "means %g (CPU) and %g (device)", m_cpu, m_gpu);
    tr_film_free(&cpu);
    tr_film_free(&cpu_plain);
    tr_film_free(&gpu);
    tr_scene_destroy(scene);
    tr_device_destroy(dev);
    return check_finish("test_opencl_firefly");
}
