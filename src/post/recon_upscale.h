/* recon_upscale.h - temporal upscaling where the frame lies (private to the library: the
 * real-time loop, src/realtime/realtime.c, calls it for upscaled frames on an OpenCL
 * device). The reconstruction of the device's film (tr_recon_device_frame's stages) stays
 * on the device, and the upscaling (src/post/upscale.h's tr_upscale_pixel, recon.cl's
 * tr_recon_upscale) and the first hits' emission at the output's resolution (entry.cl's
 * tr_cl_upscale_emission) run there too, on the output's history kept there: only the
 * output is read back, and only the samples' positions go up (and for
 * tr_recon_params.upscale_albedo the frame's albedo comes back and the output's goes up). */
#ifndef TR_POST_RECON_UPSCALE_H
#define TR_POST_RECON_UPSCALE_H

#include <stdint.h>

#include "trac0r/error.h"
#include "trac0r/post.h"
#include "trac0r/recon_device.h"
#include "trac0r/types.h"

/* Reconstructs the device's film (rendered through cam, the state's size) with `method`
 * and upscales it to out_cam's size into out (3 floats per output pixel), as the host's
 * upscale stage does with tr_upscale_frame and tr_upscale_emission: pos holds the traced
 * samples' positions in output pixels (2 floats per traced pixel, tr_upscale_positions);
 * motion as tr_recon_device_frame's. albedo (NULL: none) upscales the light apart from the
 * output's albedo (tr_recon_params.upscale_albedo): the reconstruction divided by the
 * albedo it multiplied by, the upscaled light multiplied by the output's; albedo is called
 * once with the traced frame's albedo pass, read back (3 floats per traced pixel), and
 * returns the output's (3 floats per output pixel, made on the host: tr_upscale_albedo),
 * which is uploaded, or NULL with *err set. keep 0 forgets the output's history first (a
 * frame that does not follow the last one). *ms: the upscaling's wall time. Fails with
 * TR_STATUS_UNSUPPORTED where the state is not on an OpenCL device (the host upscales). */
typedef const float *(*tr_recon_albedo_fn)(void *user, const float *frame_albedo, tr_error *err);
int tr_recon_device_upscale(tr_recon_device *r, const tr_camera *cam, const tr_camera *out_cam,
                            const float *pos, tr_recon_albedo_fn albedo, void *albedo_user,
                            const tr_vec3 *motion, uint32_t motion_count, int method,
                            const tr_recon_params *p, int keep, float *out, double *ms,
                            tr_error *err);

#endif
