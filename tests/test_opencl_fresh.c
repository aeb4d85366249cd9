/* test_opencl_fresh.c - extra samples for the pixels without history
 * (tr_recon_params.fresh_spp) where an OpenCL device's film lies (PoCL: entry.cl's
 * tr_cl_fresh_mask, tr_cl_render_masked and tr_cl_fresh_remember, the mask's test in
 * src/kernel/reproject.h shared with the host), against the CPU device's, on the classic
 * box: the first frame, two more at rest and a move sideways (test_fresh's cameras).
 *
 * 1. Each frame's per-pixel sample counts are the CPU's (the same pixels traced again),
 *    but for at most 0.5 % of the pixels (a mean depth or normal rounded otherwise may
 *    tip the consistency test): the first frame traces more than half the pixels again,
 *    the move some but under a quarter. Measured: no pixel apart in any frame.
 * 2. The radiance sums are the CPU's within 10^-3 relative (10^-3 absolute below 1) in
 *    all but 0.5 % of the values (test_opencl's bounds for one film against another).
 * 3. On the device, every pixel not traced again holds the frame's own sample, bit for
 *    bit that of a device instance without the extra samples. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "classic_box.h"
#include "fresh_run.h"
#include "trac0r/trac0r.h"

#define W 64
#define H 48
#define FRESH 4

static tr_device *device(const char *name) {
    tr_error err;
    tr_device *dev = tr_device_create(name, &err);
    CHECK(dev != NULL, "%s: %s", name, err.msg);
    return dev;
}

int main(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    CHECK(s != NULL, "%s", err.msg);
    tr_device *dc = device("cpu"), *dd = device("opencl:0"), *dp = device("opencl:0");
    tr_realtime *host = make(dc, s, FRESH, 0);
    tr_realtime *dev = make(dd, s, FRESH, 0);
    tr_realtime *plain = make(dp, s, 0, 0);
    const size_t n = (size_t)W * H;

    tr_camera cam0 = *tr_scene_camera(s); /* as test_fresh: nearer the box's opening */
    const float fwd = 200.0f, side = 150.0f;
    cam0.pos.x += fwd * cam0.dir.x;
    cam0.pos.y += fwd * cam0.dir.y;
    cam0.pos.z += fwd * cam0.dir.z;
    tr_camera cam2 = cam0;
    cam2.pos.x += side * cam0.right.x;
    cam2.pos.y += side * cam0.right.y;
    cam2.pos.z += side * cam0.right.z;
    const tr_camera *cams[4] = {&cam0, &cam0, &cam0, &cam2};
    for (int k = 0; k < 4; ++k) {
        const tr_film *h = frame(host, cams[k]);
        const tr_film *d = frame(dev, cams[k]);
        const tr_film *p = frame(plain, cams[k]);
        size_t counts = 0, traced = 0, sums = 0, own = 0;
        for (size_t i = 0; i < n; ++i) {
            counts += (size_t)(h->count[i] != d->count[i]);
            traced += (size_t)(d->count[i] == FRESH);
            if (h->count[i] == d->count[i]) {
                for (int c = 0; c < 3; ++c) {
                    const double a = h->sum[3 * i + c], b = d->sum[3 * i + c];
                    sums += (size_t)(fabs(a - b) > 1e-3 * fmax(1.0, fabs(a)));
                }
            }
            if (d->count[i] == 1u) {
                own += (size_t)(memcmp(&d->sum[3 * i], &p->sum[3 * i], 3 * sizeof(float)) != 0 ||
                                d->depth[i] != p->depth[i] || d->prim[i] != p->prim[i]);
            }
        }
        fprintf(stderr,
                "frame %d: %zu pixels traced again on the device; counts differ at %zu, sums at "
                "%zu values; %zu pixels not traced again differ from the plain run\n",
                k, traced, counts, sums, own);
        CHECK(200 * counts <= n, "frame %d: %zu pixels traced again on one device only", k, counts);
        CHECK(200 * sums <= 3 * n, "frame %d: %zu values differ", k, sums);
        CHECK(own == 0, "frame %d: %zu pixels not traced again differ", k, own);
        CHECK(k != 0 || 2 * traced > n, "first frame: %zu of %zu traced again", traced, n);
        CHECK(k != 3 || (traced > 0 && 4 * traced < n), "a move: %zu of %zu traced again", traced,
              n);
    }
    tr_realtime_destroy(host);
    tr_realtime_destroy(dev);
    tr_realtime_destroy(plain);
    tr_device_destroy(dc);
    tr_device_destroy(dd);
    tr_device_destroy(dp);
    tr_scene_destroy(s);
    return check_finish("test_opencl_fresh");
}
