/* restir_stage.h - ReSTIR DI as a stage of the real-time loop (realtime.c): after pt has
 * rendered a frame without the direct light at its camera rays' first surfaces
 * (tr_render_config.no_primary_direct), the stage estimates that light by spatiotemporal
 * reservoir resampling (src/kernel/restir.h) and adds it to the film: on the host's film
 * (tr_restir_stage_run) or where an OpenCL device's film lies (tr_restir_stage_run_device),
 * both by the per-pixel passes of src/kernel/restir_pass.h. */
#ifndef TR_REALTIME_RESTIR_STAGE_H
#define TR_REALTIME_RESTIR_STAGE_H

#include <stdint.h>

#include "trac0r/camera.h"
#include "trac0r/device.h"
#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/scene.h"

/* The stage's settings. */
typedef struct tr_restir_params {
    int candidates;     /* RIS candidates per pixel and frame */
    int spatial;        /* neighbours merged per pixel */
    float radius;       /* in pixels, of the spatial neighbourhood */
    float temporal_cap; /* the previous frame's confidence at most this times the new one's */
    int unbiased;       /* Talbot MIS (else 1/M) */
    /* 1: the biased mode passes a new candidate occluded at its own pixel on with W 0
     * (Bitterli et al.'s visibility reuse). Off by default: the neighbours' reservoirs
     * then carry their own pixels' shadows into this one's estimate (docs/realtime.md). */
    int visibility_reuse;
    int temporal; /* reuse the previous frame's reservoirs */
    int tree;     /* candidates from the light tree where the scene has one (else the
                     power CDF, cheaper: resampling weighs distance and angle) */
    /* ReSTIR GI (src/kernel/restir_gi.h): 1 adds the indirect light at the first surfaces
     * too, for a pt frame rendered with no_primary_direct 2. Its paths from the sample
     * points take the frame's depth, roulette start, indirect clamp and regularization. */
    int gi;
    int gi_temporal;       /* reuse the previous frame's GI reservoirs */
    int gi_unbiased;       /* as unbiased, for GI's merges */
    int gi_spatial;        /* neighbours merged per pixel */
    float gi_radius;       /* in pixels */
    float gi_temporal_cap; /* as temporal_cap */
    int max_depth, rr_start;
    float clamp_indirect;
    int regularize;
} tr_restir_params;

tr_restir_params tr_restir_params_default(void);

typedef struct tr_restir_stage tr_restir_stage;

tr_restir_stage *tr_restir_stage_create(tr_error *err);
void tr_restir_stage_destroy(tr_restir_stage *st);
/* Forgets the previous frame (a cut, a new size). */
void tr_restir_stage_reset(tr_restir_stage *st);

/* Adds `spp` times the direct light estimate (and with p->gi the indirect light's) at every pixel's
 * first surface (seen through sample `sample`'s camera ray of pixel (x, y), as pt traced it with
 * `seed` and `sampler`) to film's radiance sums (and its direct pass if kept). `frame` keys the
 * stage's own random numbers. Bit-identical for any thread count. */
int tr_restir_stage_run(tr_restir_stage *st, const tr_scene *scene, const tr_camera *cam,
                        const tr_restir_params *p, uint64_t seed, uint32_t sample, uint32_t sampler,
                        uint32_t spp, uint64_t frame, int threads, tr_film *film, tr_error *err);

/* Builds the passes tr_restir_stage_run_device runs on `dev` (an OpenCL device), which its
 * first run would otherwise build: a driver may take tens of seconds without its cache.
 * Other devices are refused (TR_STATUS_UNSUPPORTED). */
int tr_restir_stage_prepare_device(tr_device *dev, tr_error *err);

/* tr_restir_stage_run on an OpenCL device's film (which must have the camera's size and
 * keep `passes`, TR_PASS_DIRECT included where it adds to that pass), ReSTIR GI included
 * with p->gi: the reservoirs stay on the device. Other devices are refused
 * (TR_STATUS_UNSUPPORTED). The same passes as the host's: the results agree to the
 * device's float rounding (docs/opencl.md). */
int tr_restir_stage_run_device(tr_restir_stage *st, tr_device *dev, const tr_camera *cam,
                               const tr_restir_params *p, uint64_t seed, uint32_t sample,
                               uint32_t sampler, uint32_t spp, uint64_t frame, uint32_t passes,
                               tr_error *err);

#endif
