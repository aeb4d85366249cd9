/* measure.h - measuring the renderer's error: converged references that know their own
 * error, per-frame scores of real-time output against them, and integrators compared at
 * equal render time. What `trac0r bench realtime` and `trac0r bench convergence` report,
 * for any program that wants the same figures.
 *
 *     tr_scorer *sc = tr_scorer_create(w, h, 1, &err);
 *     for (each frame f) {
 *         tr_scorer_reference(sc, dev, &cam, &ref_cfg, 256, &err);   // the converged frame
 *         ... render the frame, reconstruct it into rgb ...
 *         tr_frame_scores s = tr_scorer_score(sc, 0, rgb);            // s.psnr, s.ssim
 *     }
 *     tr_scorer_destroy(sc);
 *
 * Every PSNR here has the reference's own error taken out: a reference of N samples is
 * rendered in two halves, and the MSE of the first half against the whole estimates the
 * whole's own MSE (for independent halves of equal size the difference of the halves has
 * twice a half's variance and the whole a quarter of it). An output's MSE against the
 * reference is its true MSE plus the reference's own; the latter is subtracted. */
#ifndef TRAC0R_MEASURE_H
#define TRAC0R_MEASURE_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/device.h"
#include "trac0r/error.h"
#include "trac0r/post.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"
#include "trac0r/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Called as samples finish with how many are done and how many there are; nonzero stops
 * the work (it fails with TR_STATUS_CANCELLED). */
typedef int (*tr_measure_progress_fn)(void *user, uint64_t done, uint64_t total);

/* The PSNR of an image whose MSE against a reference is `mse`, with the reference's own MSE
 * `own` taken out (measured = true + the reference's, the noises being independent). What
 * is left can only be told apart from the estimate's own error down to a tenth of `own`:
 * the estimate spreads by several per cent on images where a few bright paths carry the
 * error. Below that the image is as good as the reference can tell, and its score is
 * that floor's: at most 10 dB above the reference's own PSNR, never the MSE's 1e-12
 * (120 dB). own <= 0: nothing is taken out (floor 1e-12). */
#define TR_REFERENCE_RESOLUTION 0.1
double tr_psnr_less_reference(double mse, double own);

/* A reference image of `cam` rendered on dev into its cleared film in two independent
 * halves: samples 0 .. spp/2-1 of cfg, then samples 0 .. spp-spp/2-1 of cfg under another
 * seed (cfg.seed + 0x9e3779b97f4a7c15), an independent scrambling (16 samples per call, so
 * that `progress` moves). ref gets the mean radiance of all spp samples, half (scratch of
 * the same size) the first half's mean, *own_mse an unbiased estimate of the reference's
 * own MSE (from the first half's MSE against the whole; halves of one Sobol sequence would
 * overstate it). film is scratch of the camera's size; ref and half hold 3 floats per
 * pixel. spp >= 2. */
int tr_reference_render(tr_device *dev, const tr_camera *cam, const tr_render_config *cfg,
                        uint32_t spp, tr_film *film, float *ref, float *half, double *own_mse,
                        tr_measure_progress_fn progress, void *user, tr_error *err);

/* The temporal flicker of an output: the RMS over pixels of the change of luminance from
 * its previous frame (a, a_prev) minus the reference's change (r, r_prev), so that motion
 * the reference has is not counted. Values clamped to [0,1] as tr_image_compare does. */
double tr_image_flicker(const float *a, const float *a_prev, const float *r, const float *r_prev,
                        size_t pixels);

/* ---- Real-time frames against their references ---------------------------------- */

/* One output frame's scores. The times are the caller's (the scorer leaves them). */
typedef struct tr_frame_scores {
    double render_ms, temporal_ms, spatial_ms;
    double psnr;        /* the reference's own error taken out */
    double ssim;        /* tr_ssim against the reference */
    double flicker;     /* tr_image_flicker; 0 at a slot's first frame */
    double region_psnr; /* over tr_scorer_region's pixels; NaN: no region or none seen */
} tr_frame_scores;

typedef struct tr_scorer tr_scorer;

/* A scorer of width x height frames with `slots` outputs per frame (one per method
 * compared), 1..64. NULL on failure. */
tr_scorer *tr_scorer_create(uint32_t width, uint32_t height, int slots, tr_error *err);
void tr_scorer_destroy(tr_scorer *s);

/* The next frame's reference (tr_reference_render of spp samples); the previous one is
 * kept for the flicker. Forgets the region. */
int tr_scorer_reference(tr_scorer *s, tr_device *dev, const tr_camera *cam,
                        const tr_render_config *cfg, uint32_t spp, tr_error *err);
/* The current reference (3 floats per pixel) and its own MSE (NULL: not wanted). */
const float *tr_scorer_reference_rgb(const tr_scorer *s, double *own_mse);
/* A second reference of the current camera (another depth, say): *bias_mse the squared
 * difference of the two references less both their own errors (the bias between the two
 * configs), *own their own errors' sum, against which to judge it. */
int tr_scorer_bias(tr_scorer *s, tr_device *dev, const tr_camera *cam, const tr_render_config *cfg,
                   uint32_t spp, double *bias_mse, double *own, tr_error *err);
/* The region scored apart in this frame: the pixels whose id (a frame's TR_PASS_ID, the
 * primitive index + 1) lies in [lo, hi); ids NULL: none. Returns how many pixels. */
size_t tr_scorer_region(tr_scorer *s, const uint32_t *ids, uint32_t lo, uint32_t hi);
/* The region as a rectangle r = {x, y, width, height} of the frame's pixels; 0 (and no
 * region) where it is empty or does not lie inside the frame. */
size_t tr_scorer_region_rect(tr_scorer *s, const uint32_t r[4]);
/* Slot `slot`'s output of the current frame (3 floats per pixel) against the reference. */
tr_frame_scores tr_scorer_score(tr_scorer *s, int slot, const float *rgb);

/* How many frames from frame `after` on the PSNR (the region's with `region`) takes to
 * return to within `tolerance` dB of its steady value: the mean over the (up to) 8 frames
 * before frame `before` (frames without a value skipped), into *steady (NaN: none, and
 * the result is -1). -1: never. For a camera cut, before = after = the cut's frame. */
int tr_recovery_frames(const tr_frame_scores *frames, uint32_t count, uint32_t before,
                       uint32_t after, int region, double tolerance, double *steady);

/* Frames [from, until) of one output summed up: `mean` holds each field's mean (flicker
 * over the frames that have one: a run's first frame has none; region_psnr over the
 * frames whose region was seen, region_frames of them, NaN if none), psnr_min the worst
 * frame, total_ms the mean render + temporal + spatial time and fps 1000 / total_ms. */
typedef struct tr_scores_summary {
    tr_frame_scores mean;
    double psnr_min, total_ms, fps;
    uint32_t region_frames;
} tr_scores_summary;
/* The median of v[0 .. n), n >= 1 (the mean of the middle two for even n); sorts v in
 * place, so that v[0] and v[n - 1] are then the least and the greatest. */
double tr_median(double *v, int n);

tr_scores_summary tr_scores_summarize(const tr_frame_scores *frames, uint32_t from, uint32_t until);

/* ---- Integrators at equal time -------------------------------------------------- */

#define TR_CONVERGENCE_MAX_POINTS 400

/* A method's film at one sample count. */
typedef struct tr_convergence_point {
    uint32_t spp;
    double seconds;       /* render time only */
    tr_image_metrics raw; /* against the reference as it is */
    double psnr;          /* the reference's own MSE taken out */
} tr_convergence_point;

typedef struct tr_convergence_run {
    int integrator;
    uint32_t width, height;
    int n;
    tr_convergence_point pt[TR_CONVERGENCE_MAX_POINTS];
} tr_convergence_run;

typedef struct tr_convergence_desc {
    const tr_scene *scene;           /* rendered through its camera */
    int methods;                     /* 1..8 */
    tr_device **devs;                /* one per method, the scene uploaded */
    const tr_render_config *configs; /* one per method */
    const float *ref;                /* the reference, 3 floats per pixel */
    double ref_mse;                  /* its own MSE (0: unknown) */
    double budget;                   /* render seconds per method */
    double stop_psnr;                /* a method stops past it (0: 41 dB) */
    /* A method stops at this many samples per pixel (0: no limit); with a large budget
     * it makes the curve independent of the machine's speed and load. */
    uint32_t max_spp;
    /* Progress in milliseconds of budget used (a finished method counts its whole). */
    tr_measure_progress_fn progress;
    /* Called when a method finishes, with its run (NULL: none). */
    void (*finished)(void *user, const tr_convergence_run *run);
    void *user;
} tr_convergence_desc;

/* Renders every method one sample per pixel at a time, the one with the least render time
 * so far next (so that on a shared machine they see the same load), scoring each against
 * the reference at geometrically spaced sample counts (1, 2, 3, ... growing by ~19 %),
 * until its budget is spent, it reaches max_spp, it passes stop_psnr or it has
 * TR_CONVERGENCE_MAX_POINTS points. The devices' films are cleared first. runs[0 .. methods) get
 * the curves. */
int tr_convergence_measure(const tr_convergence_desc *d, tr_convergence_run *runs, tr_error *err);

/* The render time (or with use_spp the samples) at which a run first reaches `db`,
 * interpolated linearly in PSNR against log time between the bracketing points; < 0 if
 * never. */
double tr_convergence_reach(const tr_convergence_run *r, double db, int use_spp);

/* ---- Ray throughput ------------------------------------------------------------ */

/* Most builds tr_measure_builds times per structure, and most structures it compares. */
#define TR_MEASURE_MAX_BUILDS 100
#define TR_MEASURE_MAX_ACCELS 8

/* Each structure's build time for one scene, in milliseconds (tr_scene_build_seconds): the
 * median of `builds` commits with accels[k] into ms[k], 0 where skip (may be NULL) has
 * skip[k] set. Each structure in turn is committed once untimed and then `builds` times in a
 * row, as the frames of an animation rebuild it: each build then runs in the memory its
 * builder kept from the build before (this library's kept blocks, Embree's allocator), not
 * in memory written for the first time, which can cost 20 times as much as memory just
 * freed (docs/benchmarks.md), and not in what another structure freed.
 * The scene stays committed with the last structure committed. TR_STATUS_INVALID_ARGUMENT
 * for a count outside 1..TR_MEASURE_MAX_ACCELS or builds outside 1..TR_MEASURE_MAX_BUILDS;
 * a commit's failure as tr_scene_commit reports it. */
int tr_measure_builds(tr_scene *scene, const tr_accel_type *accels, const int *skip, int count,
                      int builds, double *ms, tr_error *err);

/* The kinds of rays of a set: one primary ray per pixel through a jittered position
 * (coherent), at each primary hit a cosine-weighted bounce (incoherent) and a shadow ray
 * (any hit) towards a random point of an emitter, area-weighted. */
enum { TR_RAY_PRIMARY, TR_RAY_DIFFUSE, TR_RAY_SHADOW, TR_RAY_KINDS };

typedef struct tr_ray_sets tr_ray_sets;

/* The three sets of the scene's camera, traced once with the scene's structure: every
 * structure then traces the same rays. NULL on failure. */
tr_ray_sets *tr_ray_sets_create(const tr_scene *scene, uint64_t seed, tr_error *err);
void tr_ray_sets_destroy(tr_ray_sets *r);
uint32_t tr_ray_sets_count(const tr_ray_sets *r, int kind);
/* "primary", "diffuse", "shadow"; NULL for another kind. */
const char *tr_ray_kind_name(int kind);
/* Seconds to trace every ray of a set `reps` times with the scene's committed structure
 * on `threads` threads (0: tr_default_threads); the hits of one pass into *hits, so that
 * the work is done and structures can be cross-checked. */
double tr_ray_sets_trace(const tr_ray_sets *r, const tr_scene *scene, int kind, int threads,
                         int reps, uint64_t *hits);
/* tr_ray_sets_trace on an OpenCL device (tr_device_create("opencl:N")) holding the scene
 * (tr_device_upload): the rays go to the device first, then `reps` passes are timed into
 * *seconds. TR_STATUS_UNSUPPORTED on the CPU device. */
int tr_ray_sets_trace_device(const tr_ray_sets *r, tr_device *dev, int kind, int reps,
                             uint64_t *hits, double *seconds, tr_error *err);
/* tr_ray_sets_trace_device through a compressed wide BVH converted from the scene's binary
 * BVH (the scene committed with bvh or bvh2; src/accel/cwbvh.c) for the call. */
int tr_ray_sets_trace_device_wide(const tr_ray_sets *r, tr_device *dev, const tr_scene *scene,
                                  int kind, int reps, uint64_t *hits, double *seconds,
                                  tr_error *err);
/* Mrays/s of set `kind` on an OpenCL device, as bench rays reports it: a warm-up pass sets
 * the repetitions (tr_ray_sets_reps), then the median of `runs` timed runs; through the
 * binary BVH the device holds, or with `wide` through the compressed wide BVH. *hits: one
 * pass's. -1 on failure (err says why). */
double tr_ray_sets_mrays_device(const tr_ray_sets *r, tr_device *dev, const tr_scene *scene,
                                int kind, int runs, int wide, uint64_t *hits, tr_error *err);
/* The same on the CPU with the scene's committed structure on `threads` threads (0:
 * tr_default_threads): what bench rays reports. -1 on failure (err says why). */
double tr_ray_sets_mrays(const tr_ray_sets *r, const tr_scene *scene, int kind, int threads,
                         int runs, uint64_t *hits, tr_error *err);
/* How often a timed run traces a set whose one pass took `one_pass_seconds`, so that it
 * lasts at least 50 ms (a run of a few ms is at the mercy of the scheduler), 1..1000. */
int tr_ray_sets_reps(double one_pass_seconds);

/* ---- Camera paths --------------------------------------------------------------- */

/* Frame f of `frames` on the benchmark's path from camera c0 through a scene of bounding
 * diagonal `diag`: a sideways sway, a slow dolly forward and a small yaw, scaled to the
 * scene; from frame `cut` on (cut > 0) another view, offset and looking back towards the
 * middle. c0's handedness is kept. */
int tr_camera_path(const tr_camera *c0, float diag, uint32_t f, uint32_t frames, uint32_t cut,
                   tr_camera *out, tr_error *err);

#ifdef __cplusplus
}
#endif

#endif
