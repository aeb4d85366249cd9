/* realtime.h - the real-time frame loop: one call renders a frame of few samples for a
 * camera and reconstructs it, on whatever device the caller opened.
 *
 *     tr_realtime_desc desc = {0};                        // every field has a default
 *     tr_realtime *rt = tr_realtime_create(dev, scene, &desc, &err);
 *     for (each frame) {
 *         tr_realtime_frame_desc fd = {0};
 *         fd.camera = &cam;
 *         fd.method = TR_RECON_SVGF;
 *         fd.moving = camera_changed;                      // hold fd.budget_ms
 *         fd.budget_ms = 1000.0 / 60.0;
 *         tr_realtime_result res;
 *         if (tr_realtime_frame(rt, &fd, &res, &err) != TR_OK) { ... }
 *         show(res.film);                                  // res.width x res.height
 *     }
 *     tr_realtime_destroy(rt);                             // before tr_device_destroy
 *
 * A frame goes through stages, each its own function in src/realtime/realtime.c:
 *
 *   1. sampling (tr_realtime_render): the film's size (a reduced resolution level while
 *      the camera moves under a budget), its passes (those the reconstruction reads), the
 *      sampler and Russian-roulette start of real-time frames, the sample numbers, the
 *      render on the device, and the primitives' motion of an animated scene;
 *   2. reconstruction (tr_realtime_reconstruct): the emission's resolve and the
 *      reconstruction's temporal and spatial stages (post.h), on the host or, on an
 *      OpenCL device, where the film lies (recon_device.h), with one history per method;
 *   3. the budget (tr_realtime_frame): the next moving frame's resolution divisor and
 *      samples from this one's time.
 *
 * tr_realtime_frame runs the three; tr_realtime_render and tr_realtime_reconstruct let a
 * caller hand one rendered frame to several methods (`trac0r bench realtime`).
 *
 * Deterministic: the same device kind, scene, descs and call sequence give the same bits
 * (moving frames under a budget depend on the measured times, as a budget must). */
#ifndef TRAC0R_REALTIME_H
#define TRAC0R_REALTIME_H

#include <stdint.h>

#include "trac0r/camera.h"
#include "trac0r/device.h"
#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/post.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"
#include "trac0r/types.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tr_realtime tr_realtime;

/* tr_realtime_desc.sampler naming sampler s (a TR_SAMPLER_* value). */
#define TR_REALTIME_SAMPLER(s) ((s) + 1)
/* The most samples per pixel a moving frame takes under a budget, and the spacing of
 * moving frames' sample numbers. */
#define TR_REALTIME_MAX_SPP 16
/* The indirect clamp of real-time frames where the desc names none
 * (tr_realtime_desc.clamp_indirect; docs/realtime.md has the measurements behind it). */
#define TR_REALTIME_CLAMP_INDIRECT 4.0f
/* The largest resolution divisor of a moving frame under a budget. */
#define TR_REALTIME_MAX_SCALE 16.0f

/* The instance's settings; a zeroed desc (or NULL) means every default. */
typedef struct tr_realtime_desc {
    /* What to render (copied): integrator, depth, seed, threads, and the sampler and
     * roulette start of frames that accumulate at rest. passes, cancel and cancel_user
     * are ignored (the instance sets them). NULL (default): tr_render_config_default(). */
    const tr_render_config *config;
    /* The reconstruction's settings (copied). NULL (default): tr_recon_params_default(). */
    const tr_recon_params *recon;
    /* The sampler of real-time frames (those that do not accumulate: moving, animated,
     * or every frame without `accumulate`): TR_REALTIME_SAMPLER(s) names TR_SAMPLER_s; 0
     * (default): TR_SAMPLER_REALTIME. Their roulette starts at the config's
     * roulette_start where it names one, else at TR_ROULETTE_START_REALTIME. */
    int sampler;
    /* Samples per pixel of a frame not under a budget, 1..TR_REALTIME_MAX_SPP * 64; 0
     * (default): 1. */
    uint32_t spp;
    /* 1: a frame of the same view as the film's (same camera, stride, method and moving
     * flag, the scene still) adds its samples to the film, so that the picture converges
     * at rest (the viewer). 0 (default): every frame is a new film of `spp` samples,
     * frame n taking sample numbers n * spp .. n * spp + spp - 1 (bench realtime). */
    int accumulate;
    /* 1: the scene's shapes move between frames (the caller moves them, commits with
     * tr_scene_update and uploads to the device): every frame takes the primitives'
     * motion from the scene (tr_scene_take_motion) for the reconstruction's reprojection,
     * and no frame accumulates. 0 (default): a static scene. */
    int animated;
    /* 1: the film always keeps the passes a reconstruction reads, so that one frame can
     * be handed to several methods, "off" included. 0 (default): only when the frame's
     * method is not off. */
    int keep_passes;
    /* Firefly control of real-time frames (tr_render_config.clamp_indirect and
     * regularize; frames that accumulate at rest take the config's). clamp_indirect: 0
     * (default): TR_REALTIME_CLAMP_INDIRECT; above 0: that luminance; below 0: no clamp.
     * regularize: 0 (default) or 1: path regularization on; -1: off. */
    float clamp_indirect;
    int regularize;
    /* Primary surface replacement in the frames' passes (tr_render_config.psr): 0 (default)
     * or 1: on; -1: off. */
    int psr;
    /* TR_REALTIME_RESTIR_DI: the direct light at the camera rays' first surfaces comes from
     * ReSTIR DI (spatiotemporal reservoir resampling, src/kernel/restir.h) instead of pt's
     * light sample, with pt only (else tr_realtime_create fails with
     * TR_STATUS_UNSUPPORTED), where the film lies (the CPU, or an OpenCL device's own
     * memory). 0 (default, TR_REALTIME_RESTIR_OFF): pt alone. TR_REALTIME_RESTIR_DI_GI: the
     * indirect light there too, by ReSTIR GI (src/kernel/restir_gi.h). restir_unbiased: 1
     * merges reservoirs with Talbot's MIS weights and no visibility reuse (unbiased); 0 (default):
     * 1/M weights and visibility reuse (biased, cheaper, less noisy). */
    int restir;
    int restir_unbiased;
    /* 1: a moving frame under a budget keeps the output's full resolution: where the
     * budget asks for fewer pixels it traces a fraction of them (down to a quarter, a
     * divisor of 2 per axis) and reconstructs the rest by temporal upscaling, as a frame's
     * `upscale` does, instead of showing a reduced resolution (blocks). 0 (default): the
     * budget reduces the resolution. */
    int budget_upscale;
} tr_realtime_desc;

#define TR_REALTIME_RESTIR_OFF 0
#define TR_REALTIME_RESTIR_DI 1
/* ReSTIR DI and ReSTIR GI (src/kernel/restir_gi.h): the indirect light at the first
 * surfaces by path resampling too; pt traces only up to them. */
#define TR_REALTIME_RESTIR_DI_GI 2

/* One frame's request; zeroed fields take their defaults, only camera is required. */
typedef struct tr_realtime_frame_desc {
    const tr_camera *camera; /* the view; its screen size is the full resolution */
    int method;              /* tr_recon_method (default TR_RECON_OFF: the film itself) */
    int moving;              /* 1: the camera is changing: hold budget_ms (default 0) */
    double budget_ms;        /* a moving frame's budget in milliseconds; 0 (default): none, frames
                                at full resolution with the desc's spp */
    double extra_ms;         /* the caller's own time per frame (its display), counted into the
                                budget (default 0) */
    int stride;              /* tr_render_config.stride; 0 (default): the config's */
    int restart;             /* 1: start the film over even for the same view (default 0) */
    /* Asked before each CPU tile, after the render and between the host reconstruction's
     * stages and spatial iterations: nonzero stops the frame, which fails with
     * TR_STATUS_CANCELLED and starts the next one over (default NULL). */
    int (*cancel)(void *user);
    void *cancel_user;
    /* Temporal upscaling: the frame traces 1/upscale of the output's pixels (a frame of
     * the same view, each side divided by sqrt(upscale)) and the output is reconstructed at
     * full resolution from it and from the output's history (upscale.h): 2 traces half
     * the pixels, 4 a quarter; 0 or 1 (default): every pixel. 1..16. Not with a stride
     * above 1 or a bidirectional integrator (every pixel is traced then). */
    int upscale;
} tr_realtime_frame_desc;

/* What a frame gave; its pointers stay valid until the next call on the instance. */
typedef struct tr_realtime_result {
    /* The frame to show, width x height: the reconstruction as a film of one sample per
     * pixel, or with method off the film of samples itself. */
    const tr_film *film;
    /* The reconstruction, 3 floats per pixel; NULL where film is the film of samples. */
    const float *rgb;
    uint32_t width, height;
    float scale;        /* the full resolution's width over width (1: full resolution) */
    uint32_t spp;       /* samples per pixel in the film (more than frame_spp at rest) */
    uint32_t frame_spp; /* samples per pixel this frame traced */
    int method;         /* the reconstruction that ran (TR_RECON_OFF: none) */
    double render_ms;   /* the sampling stage: render and, where needed, film read */
    double temporal_ms; /* the temporal stage, the emission's resolve included */
    double spatial_ms;  /* the spatial filter */
    double resolve_ms;  /* the emission's resolve on the host (0 elsewhere) */
    uint32_t resolved;  /* the pixels it traced */
    double restir_ms;   /* the ReSTIR stage, DI and GI (part of render_ms; 0 without it) */
    /* The traced frame's size: width x height, or less where the frame was upscaled. */
    uint32_t traced_width, traced_height;
    double upscale_ms; /* the upscaling (counted into temporal_ms too); 0 without */
    /* Temporal gradients (tr_recon_params.gradients): the replay's time (part of
     * render_ms), whether this frame measured them (a previous frame of the same camera
     * and settings), and the strata whose replay differed from the previous frame. */
    double gradient_ms;
    int gradient_valid;
    uint32_t gradient_changed;
} tr_realtime_result;

/* A real-time loop rendering `scene` (uploaded to dev already) on dev, which both must
 * outlive it. NULL with err set on a NULL device or scene, a bad desc (an unknown sampler,
 * spp out of range, a config tr_render_config_check refuses) or no memory. */
tr_realtime *tr_realtime_create(tr_device *dev, tr_scene *scene, const tr_realtime_desc *desc,
                                tr_error *err);
/* Frees everything (NULL: nothing). */
void tr_realtime_destroy(tr_realtime *rt);

/* Renders and reconstructs one frame with fd->method, then adapts the budget of later
 * moving frames; fills *out. Fails on a NULL argument or camera, an unknown method, a
 * device failure or a cancel (TR_STATUS_CANCELLED). */
int tr_realtime_frame(tr_realtime *rt, const tr_realtime_frame_desc *fd, tr_realtime_result *out,
                      tr_error *err);

/* The sampling stage alone: one frame into the film (on the device, read to the host
 * where the reconstruction runs there). Its method says which passes to keep. */
int tr_realtime_render(tr_realtime *rt, const tr_realtime_frame_desc *fd, tr_error *err);
/* The reconstruction of the last rendered frame with `method` (off included), once per
 * frame and method: each method keeps its own history, which starts over when the method
 * skipped a frame or the size changed. Fails before any frame was rendered. */
int tr_realtime_reconstruct(tr_realtime *rt, int method, tr_realtime_result *out, tr_error *err);

/* The film of samples (read from the device if it lies there only), for a screenshot:
 * *film gets it, valid until the next call. Fails before any frame was rendered. */
int tr_realtime_film(tr_realtime *rt, const tr_film **film, tr_error *err);
/* The last frame's passes on the host after tr_realtime_reconstruct ran there (for
 * measures over primitives); NULL where the reconstruction runs on the device. */
const tr_gbuffer *tr_realtime_gbuffer(const tr_realtime *rt);
/* 1 when the reconstruction runs on the device where the film lies, 0 on the host. */
int tr_realtime_on_device(const tr_realtime *rt);
/* The TR_PASS_* the film keeps for `method` (for an upscaled frame: those of "accumulate"
 * also for "off", whose upscaling uses them). */
uint32_t tr_realtime_passes(const tr_realtime *rt, int method);

/* The budget's step: after a frame that took frame_ms of budget_ms at resolution divisor
 * *scale (1: full resolution, up to TR_REALTIME_MAX_SCALE) with *spp samples per pixel,
 * the divisor and samples of the next one. Over budget samples are dropped first, then
 * the divisor grows; under budget it shrinks to 1, and only at full resolution do samples
 * grow (up to TR_REALTIME_MAX_SPP). Steps are damped (a quarter power of the time ratio,
 * the divisor's square being the pixel count) so one slow frame does not make the
 * picture jump. Nothing changes for a budget not above 0 or a negative or NaN time. */
void tr_realtime_budget_adapt(double frame_ms, double budget_ms, float *scale, uint32_t *spp);
/* The resolution divisor a moving frame takes for the budget's divisor `scale`: the
 * smallest of a few fixed levels (1, 1.25, 1.5, 2, 2.5, 3, 4, 5, 6, 8, 10, 12, 16) at or
 * above 0.95 scale, so that the budget's small steps do not change the film's size, which
 * starts the reconstruction's history over, every frame. */
float tr_realtime_level(float scale);

#ifdef __cplusplus
}
#endif

#endif
