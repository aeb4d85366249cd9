/* gradient.h - temporal gradients for the real-time loop (A-SVGF: C. Schied, C. Peters,
 * C. Dachsbacher, "Gradient Estimation for Real-Time Adaptive Temporal Filtering", HPG
 * 2018), in the variant docs/realtime.md describes: one pixel of each 3x3 stratum
 * re-shades the previous frame's samples (its camera, sample numbers and settings: the
 * samplers are stateless, so the replay draws the same numbers) in the scene as it is
 * now; the difference from what that pixel showed in the previous frame is the change of
 * the scene's shading alone. Internal to src/realtime. */
#ifndef TRAC0R_REALTIME_GRADIENT_H
#define TRAC0R_REALTIME_GRADIENT_H

#include <stdint.h>

#include "kernel/grad_pixel.h"
#include "trac0r/camera.h"
#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"

typedef struct tr_grad {
    uint32_t width, height; /* the frames' size (0: none yet) */
    uint32_t sw, sh;        /* strata per row and column */
    float *prev;            /* the previous frame's luminance, per pixel */
    uint32_t *prev_prim;    /* ... and its first hit's primitive (the prim pass) */
    float *cap;             /* this frame's history caps, per pixel (tr_recon.len_cap) */
    float *num, *den, *tmp; /* per stratum: |change|, the larger luminance, scratch */
    int have_prev;          /* prev and the fields below hold the previous frame */
    tr_camera cam;
    tr_render_config cfg;
    uint32_t sample, count;
    int valid;         /* cap holds this frame's gradients */
    uint32_t changed;  /* strata whose replay differed */
    uint32_t replayed; /* pixels replayed this frame */
    double ms;         /* the stage's wall time */
} tr_grad;

void tr_grad_free(tr_grad *g);
/* Forgets the previous frame: the next frame measures nothing. */
void tr_grad_reset(tr_grad *g);
/* One frame: `film` holds only this frame's `count` samples from `sample` on, rendered
 * through cam with cfg (the config the device ran, its passes included) in `scene` as it
 * is now (committed). With a previous frame of the same size and config (its camera may
 * differ: the replay takes it, and each pixel reads the gradient where its surface lay in
 * the previous frame, through the depth pass), its samples are replayed at one pixel per stratum
 * (chosen by `frame`) and g->cap gets each pixel's history cap from the filtered, normalised
 * gradient (g->valid = 1; a pixel whose shading did not change gets no cap, FLT_MAX); otherwise
 * g->valid = 0. Then this frame becomes the previous one. A stratum whose replay hits another
 * primitive than the previous frame did, or one that moved (motion[prim] for prim < motion_count,
 * as the reconstruction takes it), measures nothing: its history is the geometric tests'. The
 * result does not depend on `threads`. */
int tr_grad_frame(tr_grad *g, const tr_scene *scene, const tr_film *film, const tr_camera *cam,
                  const tr_render_config *cfg, uint32_t sample, uint32_t count, uint32_t frame,
                  const tr_vec3 *motion, uint32_t motion_count, float alpha_min, int threads,
                  tr_error *err);

/* tr_grad_frame where the film lies: the device's film (an OpenCL device; rendered
 * through cam with cfg) measured by the device's kernels (src/device/opencl.h,
 * tr_cl_grad_frame), which keep the previous frame and hand the caps to the device's
 * reconstruction of this film. g keeps the settings and the counts (valid, changed,
 * replayed, ms); its per-pixel arrays stay empty. */
struct tr_device;
int tr_grad_frame_device(tr_grad *g, struct tr_device *dev, const tr_camera *cam,
                         const tr_render_config *cfg, uint32_t sample, uint32_t count,
                         uint32_t frame, const tr_vec3 *motion, uint32_t motion_count,
                         float alpha_min, tr_error *err);

#endif
