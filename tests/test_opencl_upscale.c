/* test_opencl_upscale.c - tr_realtime's upscaled frames on an OpenCL device (PoCL here)
 * against the CPU's: the same classic box, the same moving camera, a quarter of the pixels
 * traced, SVGF and the raw frame (off), reconstructed and upscaled on the device
 * (recon.cl's tr_recon_upscale, entry.cl's tr_cl_upscale_emission) and on the host. The two
 * devices trace the same samples at the same positions (the samplers are stateless), so
 * the outputs agree up to the float rounding in which the devices' renders,
 * reconstructions and upscalings differ (the host's upscaling is tr_upscale_pixel's
 * arithmetic with its loops turned round): every frame at least 80 dB apart from the
 * other (a 1-spp frame and the next one are about 20 dB apart), and the means within
 * 0.5 %. Both methods upscale the light apart from the albedo (the raw frame keeps its
 * passes when upscaled), the output's albedo made on the host from the frame's albedo
 * pass. The device's film is never read back: only the output is (and the frame's albedo,
 * for the output's).
 *
 * Needs an OpenCL platform; it fails (not skips) when no device can be opened. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "classic_box.h"
#include "device/opencl.h"
#include "trac0r/trac0r.h"

#define W 64
#define H 48

static double mean_of(const float *a, size_t n) {
    double s = 0.0;
    for (size_t i = 0; i < n; ++i) {
        s += a[i];
    }
    return s / (double)n;
}

static void compare(tr_scene *s, tr_device *dev[2]) {
    tr_error err;
    tr_realtime *rt[2] = {NULL, NULL};
    for (int d = 0; d < 2; ++d) {
        rt[d] = tr_realtime_create(dev[d], s, NULL, &err);
        CHECK(rt[d] != NULL, "create: %s", err.msg);
    }
    CHECK(!rt[1] || tr_realtime_on_device(rt[1]), "the OpenCL device reconstructs on the device");
    const size_t n = 3u * W * H;
    float *out[2] = {malloc(n * sizeof(float)), malloc(n * sizeof(float))};
    const int methods[2] = {TR_RECON_SVGF, TR_RECON_OFF};
    tr_cl_context *cl = tr_device_cl_context(dev[1]);
    const uint64_t reads0 = cl ? tr_cl_film_reads(cl) : 0;
    for (int f = 0; rt[0] && rt[1] && f < 6; ++f) {
        tr_camera cam = *tr_scene_camera(s);
        cam.pos.x += 4.0f * (float)f;
        for (int d = 0; d < 2; ++d) {
            tr_realtime_frame_desc fd = {0};
            fd.camera = &cam;
            fd.upscale = 4;
            CHECK(tr_realtime_render(rt[d], &fd, &err) == TR_OK, "render: %s", err.msg);
        }
        for (int m = 0; m < 2; ++m) {
            for (int d = 0; d < 2; ++d) {
                tr_realtime_result res;
                CHECK(tr_realtime_reconstruct(rt[d], methods[m], &res, &err) == TR_OK,
                      "reconstruct: %s", err.msg);
                CHECK(res.rgb && res.width == W && res.traced_width == W / 2, "an upscaled frame");
                if (res.rgb) {
                    memcpy(out[d], res.rgb, n * sizeof(float));
                }
            }
            const double psnr = tr_image_compare(out[1], out[0], (size_t)W * H).psnr;
            const double m0 = mean_of(out[0], n), m1 = mean_of(out[1], n);
            printf("frame %d, %s: %.2f dB apart, means %.6f and %.6f\n", f,
                   tr_recon_name(methods[m]), psnr, m0, m1);
            CHECK(psnr >= 80.0 && fabs(m1 / m0 - 1.0) < 0.005,
                  "frame %d, %s: the devices differ by %.2f dB, means %.5f and %.5f", f,
                  tr_recon_name(methods[m]), psnr, m0, m1);
        }
    }
    CHECK(cl && tr_cl_film_reads(cl) == reads0, "upscaled frames read the device's film %llu times",
          cl ? (unsigned long long)(tr_cl_film_reads(cl) - reads0) : 0ull);
    for (int d = 0; d < 2; ++d) {
        tr_realtime_destroy(rt[d]);
        free(out[d]);
    }
}

int main(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    tr_device *dev[2] = {tr_device_create("cpu", &err), tr_device_create("opencl:0", &err)};
    CHECK(dev[0] && dev[1], "devices: %s", err.msg);
    for (int d = 0; d < 2 && dev[d]; ++d) {
        CHECK(tr_device_upload(dev[d], s, &err) == TR_OK, "upload: %s", err.msg);
    }
    if (dev[0] && dev[1]) {
        compare(s, dev);
    }
    for (int d = 0; d < 2; ++d) {
        tr_device_destroy(dev[d]);
    }
    tr_scene_destroy(s);
    return check_finish("test_opencl_upscale");
}
