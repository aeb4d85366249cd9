/* recon_device.h - real-time reconstruction where the frame was rendered: on an OpenCL
 * device the film never leaves the device until the reconstructed image does.
 *
 *     tr_recon_device *rd = tr_recon_device_create(dev, w, h, &err);   // dev: tr_device_create
 *     for (each frame) {
 *         tr_device_render(dev, &cam, &cfg, ...);                     // cfg.passes TR_PASS_ALL
 *         tr_recon_device_frame(rd, &cam, NULL, 0, TR_RECON_SVGF, &params, out, &err);
 *         tr_device_clear(dev, &err);
 *     }
 *     tr_recon_device_destroy(rd);                                      // before tr_device_destroy
 *
 * On an OpenCL device each stage of tr_recon_frame (post.h) runs as a kernel built from
 * src/post/recon.cl, the per-pixel operators of src/post/filter.h that the host's filters
 * compute too, on buffers on the device (the history included); only `out` is read back.
 * On the CPU device it is tr_recon_frame on the film's means. The two agree to float
 * rounding (tests/test_opencl_recon.c). */
#ifndef TRAC0R_RECON_DEVICE_H
#define TRAC0R_RECON_DEVICE_H

#include <stdint.h>

#include "trac0r/device.h"
#include "trac0r/error.h"
#include "trac0r/post.h"
#include "trac0r/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tr_recon_device tr_recon_device;

/* Reconstruction state of width x height frames on `dev`, which must outlive it (close
 * this first). For OpenCL the filters are compiled for the device here (a compiler
 * failure's message holds the build log) and the history allocated on it. */
tr_recon_device *tr_recon_device_create(tr_device *dev, uint32_t width, uint32_t height,
                                        tr_error *err);
void tr_recon_device_destroy(tr_recon_device *r);
/* Forgets the history (a camera cut, a new scene). */
void tr_recon_device_clear(tr_recon_device *r);
/* 1 when the stages run on an OpenCL device, 0 on the host. */
int tr_recon_device_on_device(const tr_recon_device *r);

/* Reconstructs the device's film (the mean of its samples and its passes; it must have
 * the state's size), rendered through cam, with `method` into out (3 floats per pixel).
 * motion, motion_count: the primitives' motion since the previous frame as
 * tr_recon_frame_moving (post.h) takes it (NULL, 0: a static scene). The history then
 * holds this frame. Fails on another size or an unknown method. */
int tr_recon_device_frame(tr_recon_device *r, const tr_camera *cam, const tr_vec3 *motion,
                          uint32_t motion_count, int method, const tr_recon_params *p, float *out,
                          tr_error *err);
/* The same from a frame on the host, uploaded first: the same input through the host and
 * the device. */
int tr_recon_device_frame_gbuffer(tr_recon_device *r, const tr_gbuffer *g, const tr_camera *cam,
                                  const tr_vec3 *motion, uint32_t motion_count, int method,
                                  const tr_recon_params *p, float *out, tr_error *err);
/* The stages' wall times in the last frame, milliseconds (the device waited for). */
void tr_recon_device_times(const tr_recon_device *r, double *ms_temporal, double *ms_spatial);

#ifdef __cplusplus
}
#endif

#endif
