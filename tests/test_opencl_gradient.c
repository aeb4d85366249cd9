/* test_opencl_gradient.c - the temporal gradients (tr_recon_params.gradients) where an
 * OpenCL device's film lies (PoCL: the replay, the strata's filter and the caps as
 * entry.cl's tr_cl_grad_* kernels, the caps read by recon.cl's temporal kernels), on
 * test_gradient's scene: the built-in box at 48x36, SVGF at 1 spp, its light on for
 * frames 0-7, off 8-15, on 16-23 (gradient_run.h).
 *
 * 1. The device measures what the host measures: gradients valid on every frame after the
 *    first, strata changed exactly at the switches (frames 8 and 16), as many as the
 *    host's within 2 % (the two compile the same source; float rounding may differ); and
 *    its frames never read the film back.
 * 2. The device's reconstruction takes the caps: after the light switches off its 4th
 *    frame (frame 11) is dark, mean below 1 % of the lit frames', where the device
 *    without gradients keeps it above 3 %; from the 4th frame after the light comes on
 *    again the mean is within 1 % of the lit mean of the device's steady run.
 * 3. Each frame's image is the host's to within 10^-4 of the lit mean (mean absolute
 *    difference per value; measured: below 10^-7).
 * 4. A static scene, the camera still or panning: nothing changed and every frame's bits
 *    are those of the device's run without gradients. */
#include "gradient_run.h"

#define CL_DEVICE "opencl:0"

static double mean_abs_diff(const float *a, const float *b) {
    double sum = 0.0;
    for (uint32_t i = 0; i < N; ++i) {
        sum += fabs((double)a[i] - (double)b[i]);
    }
    return sum / N;
}

static void test_switch(void) {
    float *host = malloc((size_t)FRAMES * N * sizeof(float));
    float *dev = malloc((size_t)FRAMES * N * sizeof(float));
    float *dev_without = malloc((size_t)FRAMES * N * sizeof(float));
    float *dev_steady = malloc((size_t)FRAMES * N * sizeof(float));
    int vh[FRAMES], vd[FRAMES];
    uint32_t ch[FRAMES], cd[FRAMES];
    run_on("cpu", 1, TR_LIGHT_ANIMATION_SWITCH, 0, 0, host, vh, ch, NULL);
    uint64_t reads = 0;
    run_on(CL_DEVICE, 1, TR_LIGHT_ANIMATION_SWITCH, 0, 0, dev, vd, cd, &reads);
    CHECK(reads == 0, "the device's frames read its film back %llu times",
          (unsigned long long)reads);
    run_on(CL_DEVICE, 0, TR_LIGHT_ANIMATION_SWITCH, 0, 0, dev_without, NULL, NULL, NULL);
    run_on(CL_DEVICE, 1, TR_LIGHT_ANIMATION_NONE, 0, 0, dev_steady, NULL, NULL, NULL);
    const double lit = mean_of(dev_steady + 7u * N);
    for (int f = 0; f < FRAMES; ++f) {
        const size_t o = (size_t)f * N;
        fprintf(stderr,
                "frame %2d: valid %d/%d changed %4u/%4u  mean host %.4f device %.4f (without "
                "%.4f, steady %.4f)  |host - device| %.3g\n",
                f, vh[f], vd[f], ch[f], cd[f], mean_of(host + o), mean_of(dev + o),
                mean_of(dev_without + o), mean_of(dev_steady + o),
                mean_abs_diff(host + o, dev + o));
        CHECK(vd[f] == (f > 0) && vh[f] == vd[f], "frame %d: valid host %d, device %d", f, vh[f],
              vd[f]);
        const int sw = f == 8 || f == 16;
        CHECK(sw ? cd[f] > 0 : cd[f] == 0, "frame %d: %u strata changed on the device", f, cd[f]);
        CHECK(fabs((double)cd[f] - (double)ch[f]) <= 0.02 * (double)ch[f],
              "frame %d: %u strata changed on the device, %u on the host", f, cd[f], ch[f]);
        CHECK(mean_abs_diff(host + o, dev + o) < 1e-4 * lit, "frame %d: device and host differ", f);
    }
    const double off = mean_of(dev + 11u * N), off_without = mean_of(dev_without + 11u * N);
    CHECK(off < 0.01 * lit, "off, 4th frame on the device: mean %g of lit %g (a ghost)", off, lit);
    CHECK(off_without > 0.03 * lit, "the device without gradients lags: %g of %g", off_without,
          lit);
    for (uint32_t f = 19; f < FRAMES; ++f) {
        const double d = fabs(mean_of(dev + f * N) - mean_of(dev_steady + f * N));
        CHECK(d < 0.01 * lit, "on again, frame %u on the device: mean %g off the steady run's", f,
              d);
    }
    free(host);
    free(dev);
    free(dev_without);
    free(dev_steady);
}

static void test_static(void) {
    check_static(CL_DEVICE);
}

int main(void) {
    test_switch();
    test_static();
    return check_finish("test_opencl_gradient");
}
