/* render.h - rendering frames into a film on the CPU backend. */
#ifndef TRAC0R_RENDER_H
#define TRAC0R_RENDER_H

#include <stdint.h>

#include "trac0r/types.h"
#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/scene.h"

#define TR_MAX_DEPTH_LIMIT 1024
/* max_depth 0 asks for the integrator's default (tr_default_max_depth): pt's paths end by
 * Russian roulette, so its bound is one users should not meet (as production renderers
 * do); naive keeps the thesis's 8, on which its depth-based roulette depends. */
#define TR_MAX_DEPTH_DEFAULT 0
#define TR_MAX_DEPTH_PT 64
/* Where pt's Russian roulette starts (tr_render_config.roulette_start): after 5
 * segments for the least error per sample (the default), after 2 for real-time frames,
 * which a filter reconstructs (view, bench realtime; docs/integrators.md). */
#define TR_ROULETTE_START_PT 5
#define TR_ROULETTE_START_REALTIME 2
#define TR_MAX_DEPTH_NAIVE 8
/* bdpt's default and its limit: its subpaths live in fixed arrays of 16 vertices. */
#define TR_MAX_DEPTH_BDPT 15

/* Where pt's uniform numbers come from (tr_render_config.sampler). sobol: the
 * Owen-scrambled Sobol sampler (stratified, the default); random: independent uniform
 * numbers per (seed, pixel, sample, dimension), for comparisons; zsobol: the Sobol points
 * with each pixel's sequence shifted by its point in a Z-ordered screen-space net
 * (stratified per pixel as sobol, and at every sample index across neighbouring pixels:
 * blue-noise error). naive always draws from its xorshift streams. */
#define TR_SAMPLER_SOBOL 0
#define TR_SAMPLER_RANDOM 1
#define TR_SAMPLER_ZSOBOL 2
/* The sampler of real-time frames (view's moving frames, bench realtime's frames):
 * independent numbers. Reprojection mixes the histories of four neighbouring pixels, whose
 * sequences are scrambled apart, so no sampler's stratification survives into the
 * reconstructed frame (docs/benchmarks.md); random costs about a tenth fewer instructions
 * than sobol (docs/realtime.md). */
#define TR_SAMPLER_REALTIME TR_SAMPLER_RANDOM

/* What to render and, for the CPU, how. A zero-initialised config is the default
 * (tr_render_config_default) except for the integrator: 0 names TR_INTEGRATOR_NAIVE. */
typedef struct tr_render_config {
    int max_depth;   /* the longest path; 0 (default): the integrator's default */
    uint64_t seed;   /* random streams are keyed by (seed, pixel, sample) */
    int threads;     /* CPU: OpenMP threads; 0 = all the machine has */
    int integrator;  /* TR_INTEGRATOR_* (default TR_INTEGRATOR_PT, as the command line) */
    int stride;      /* preview: trace every stride-th pixel, fill stride x stride blocks
                        (1..64; 0 means 1, the default) */
    uint32_t tile;   /* CPU: tile side in traced pixels (0 means 16, the default) */
    uint32_t passes; /* TR_PASS_* to accumulate beside radiance (default none) */
    int sampler;     /* TR_SAMPLER_*: pt's uniform numbers (default TR_SAMPLER_SOBOL) */
    /* pt: Russian roulette may end a path after this many segments (the camera ray is the
     * first), 1..TR_MAX_DEPTH_LIMIT; 0 (default): TR_ROULETTE_START_PT. */
    int roulette_start;
    /* Optional (default NULL): asked before each tile on the CPU; when it returns nonzero
     * the frame stops early, the film holds a partial sample and the call fails with
     * TR_STATUS_CANCELLED. For interactive use: another thread decides. */
    int (*cancel)(void *user);
    void *cancel_user;
    /* pt's firefly control, for frames a filter reconstructs (biased; off by default, so
     * that offline renders converge to the right image). clamp_indirect: the largest
     * luminance of a contribution arriving over an indirect vertex (light that bounced at
     * least once after the first non-specular surface), 0 (default): no clamp. regularize:
     * 1 roughens glossy and specular lobes after the first non-specular vertex (path
     * regularization: caustics through glass and mirrors become reachable by light
     * samples), 0 (default): off. tr_realtime turns both on for real-time frames. */
    float clamp_indirect;
    int regularize;
    /* 1: pt leaves out the direct light at the camera ray's first surface (where it is
     * not specular) that light
     * sampling can produce, for a stage that adds it (tr_realtime's ReSTIR DI); 2: its
     * indirect light there too (the path ends there; tr_realtime's ReSTIR GI adds it); 0
     * (default): pt's whole estimate. */
    int no_primary_direct;
    /* 1: pt's passes follow a camera ray that first meets a mirror or smooth glass to the
     * first surface behind it (primary surface replacement, src/kernel/psr.h: that
     * surface's albedo, primitive and mirrored normal, the chain's length as depth), for a
     * reconstruction that reprojects the reflected or refracted image where it appears;
     * the radiance is the same. 0 (default): the path's own first non-delta surface.
     * tr_realtime turns it on for real-time frames. */
    int psr;
    /* OpenCL devices: how pt's frames run, TR_OPENCL_KERNEL_* (docs/opencl.md). AUTO
     * (default) takes the environment variable TRAC0R_OPENCL_KERNEL (mega, wavefront or
     * auto) and otherwise the device type's rule; the CPU ignores it. */
    int opencl_kernel;
} tr_render_config;

/* tr_render_config.opencl_kernel. MEGA: one kernel runs every sample's whole path.
 * WAVEFRONT: the path tracer in stages (generate, extend, shade, connect) over queues of
 * paths on the device. Both give the same film bit for bit; integrators other than pt
 * always run as one kernel. */
#define TR_OPENCL_KERNEL_AUTO 0
#define TR_OPENCL_KERNEL_MEGA 1
#define TR_OPENCL_KERNEL_WAVEFRONT 2
/* TR_OPENCL_KERNEL_* by its name ("auto", "mega", "wavefront"); -1 for any other. */
int tr_opencl_kernel_from_name(const char *name);
/* The name of a TR_OPENCL_KERNEL_* ("?" for any other value). */
const char *tr_opencl_kernel_name(int kernel);

typedef struct tr_render_stats {
    uint64_t rays;  /* intersection queries made */
    double seconds; /* wall time of the call */
} tr_render_stats;

tr_render_config tr_render_config_default(void);
/* The max depth a config with max_depth 0 uses with `integrator`: TR_MAX_DEPTH_PT (64)
 * for pt, TR_MAX_DEPTH_NAIVE (8) for naive, TR_MAX_DEPTH_BDPT (15) for bdpt. */
int tr_default_max_depth(int integrator);

/* Whether an integrator traces light subpaths (bdpt, vcm): CPU only, TR_MAX_DEPTH_BDPT at
 * most, no environment light or sun, no direct pass. */
int tr_integrator_is_bidirectional(int integrator);
/* Checks the settings every backend takes alike (max depth, integrator, stride); fails
 * with a message naming the value out of range. */
int tr_render_config_check(const tr_render_config *cfg, tr_error *err);

/* Adds one sample per pixel (sample number `sample`) to the film on the CPU (the "cpu"
 * device without its own film: device.h renders through devices), tracing `scene` from
 * `cam`, whose screen size must equal the film's. Deterministic: the result depends on
 * the scene, camera, config (except threads and tile) and sample number only.
 * stats may be NULL. */
int tr_render_frame(const tr_scene *scene, const tr_camera *cam, const tr_render_config *cfg,
                    tr_film *film, uint32_t sample, tr_render_stats *stats, tr_error *err);

/* Whether `integrator` (TR_INTEGRATOR_*) can render `scene`: TR_OK, or
 * TR_STATUS_UNSUPPORTED with the reason (naive: scenes with punctual lights).
 * Rendering such a pair fails the same way on its first frame; this asks before any work
 * (bench convergence, before it renders its reference). */
int tr_integrator_supports(const tr_scene *scene, int integrator, tr_error *err);

/* The most CPU threads trac0r runs in one team (tr_render_config.threads and the
 * OpenMP default alike: OMP_NUM_THREADS=100000 would otherwise overflow the team's
 * stack). */
#define TR_MAX_THREADS 1024

/* The number of threads a config with threads = 0 uses: OpenMP's default, at most
 * TR_MAX_THREADS. Every parallel region of the library uses it. */
int tr_default_threads(void);

/* Monotonic wall clock in seconds. */
double tr_time_now(void);
/* The CPU time the process has used, user and system, all threads, in seconds (0 where
 * the system cannot tell). */
double tr_time_cpu(void);

#endif
