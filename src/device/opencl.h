/* opencl.h - the OpenCL backend (private to the library: applications open it as the
 * "opencl:N" tr_device, include/trac0r/device.h): the kernel of src/kernel/ on any
 * OpenCL 1.2+ device.
 *
 * The kernel source (src/kernel/entry.cl and every header it includes) is embedded
 * into libtrac0r at build time and compiled for the chosen device when a context
 * opens. The scene's arrays are uploaded once per scene change, the camera once per
 * frame; samples accumulate into a float film on the device (radiance sum and count
 * per pixel, as tr_film), which is read back only when asked for.
 *
 *     tr_error err;
 *     tr_cl_context *cl = tr_cl_open(0, &err);          // device 0 of `trac0r info --devices`
 *     if (!cl || tr_cl_upload_scene(cl, &scene, &err) != TR_OK) { puts(err.msg); ... }
 *     tr_frame f;                                       // device/frame.h
 *     tr_frame_make(&f, &scene.camera, &cfg, 0, spp, NULL, &err);
 *     tr_cl_render_frame(cl, &f, NULL, &err);
 *     tr_cl_read_film(cl, &film, &err);                 // film sized like the camera
 *     tr_cl_close(cl);
 *
 * Builds configured without OpenCL (CMake found no OpenCL) keep these functions:
 * tr_cl_available() returns 0 and tr_cl_open fails saying so. */
#ifndef TRAC0R_OPENCL_H
#define TRAC0R_OPENCL_H

#include <stdint.h>

#include "kernel/types.h"
#include "trac0r/device.h"
#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"

/* What is known of one OpenCL device. */
typedef struct tr_cl_device_info {
    int index;          /* position in tr_cl_list_devices' list: the N of --device opencl:N */
    int platform_index; /* the platform's position in clGetPlatformIDs' list */
    char platform[128]; /* platform name */
    char name[128];
    char vendor[128];
    char version[128]; /* CL_DEVICE_VERSION */
    char type[16];     /* "cpu", "gpu", "accelerator", ... */
    uint32_t compute_units;
    uint64_t global_mem; /* bytes, CL_DEVICE_GLOBAL_MEM_SIZE */
    uint64_t max_alloc;  /* bytes, CL_DEVICE_MAX_MEM_ALLOC_SIZE: the largest buffer */
} tr_cl_device_info;

typedef struct tr_cl_context tr_cl_context;

/* 1 in builds with the OpenCL backend, 0 otherwise. */
int tr_cl_available(void);

/* The devices of every platform, numbered in platform order, then device order. Fills
 * up to max entries of out (which may be NULL when max is 0) and sets *count to the
 * number of devices found. No platform at all is an error ("no OpenCL platform found"). */
int tr_cl_list_devices(tr_cl_device_info *out, int max, int *count, tr_error *err);

/* Opens device `index` of tr_cl_list_devices' list and compiles the kernel for it.
 * Returns NULL with a message when there is no platform, the index is out of range,
 * or the kernel fails to compile (the message then names the call and the OpenCL
 * error, and tr_cl_last_build_log() holds the compiler's log). */
tr_cl_context *tr_cl_open(int index, tr_error *err);
/* tr_cl_open with another kernel source (NULL: the embedded one), for tests of the
 * build error path; the source must define tr_cl_render as entry.cl does. */
tr_cl_context *tr_cl_open_source(int index, const char *source, tr_error *err);
void tr_cl_close(tr_cl_context *ctx);

const tr_cl_device_info *tr_cl_device(const tr_cl_context *ctx);
/* The device compiler's log of the kernel build ("" when it said nothing). */
const char *tr_cl_build_log(const tr_cl_context *ctx);
/* The build log of the most recent kernel build by tr_cl_open in this process, whether
 * it succeeded or not ("" if none, or if the compiler said nothing). */
const char *tr_cl_last_build_log(void);
/* Options the kernel was compiled with: -cl-std=CL1.2 -cl-kernel-arg-info, and
 * -cl-fp32-correctly-rounded-divide-sqrt where the device supports it. */
const char *tr_cl_build_options(const tr_cl_context *ctx);

/* Uploads the scene's arrays (triangles, materials, flat nodes, BVH nodes and leaf
 * triangles) and releases those of the previous scene. The scene must be committed.
 * A scene committed to Embree (a host library) is traced on the device through a BVH
 * built here; tr_cl_scene_accel says which structure the device walks. Fails before
 * allocating anything when a buffer exceeds the device's largest allocation or the
 * scene plus a film of the camera's size exceeds its memory; the previous scene then
 * stays. The device film keeps its samples across uploads (tr_cl_clear_film). */
int tr_cl_upload_scene(tr_cl_context *ctx, const tr_scene *scene, tr_error *err);
/* The structure the uploaded scene is traced through on the device (flat or bvh). */
tr_accel_type tr_cl_scene_accel(const tr_cl_context *ctx);
/* The BVH choice for the next uploads (trac0r/device.h's tr_device_bvh: auto takes
 * TRAC0R_OPENCL_BVH's, read at opening, else the rule by device type), and the one the
 * uploaded scene is walked with: TR_DEVICE_BVH_CWBVH or TR_DEVICE_BVH_BVH2 (also flat). */
void tr_cl_set_bvh(tr_cl_context *ctx, tr_device_bvh bvh);
tr_device_bvh tr_cl_scene_bvh(const tr_cl_context *ctx);
/* Bytes of device memory the uploaded scene's buffers take. */
uint64_t tr_cl_scene_bytes(const tr_cl_context *ctx);
/* Bytes of device memory the film's buffers take (0 before the first render), and those
 * one path of the wavefront takes (its state and its places in the three queues). */
uint64_t tr_cl_film_bytes(const tr_cl_context *ctx);
uint64_t tr_cl_wavefront_path_bytes(void);

/* Adds frame f's samples (tr_frame_make: a sample range over a rectangle, with its
 * stride and passes) to the device film. The film takes the camera's screen size and the
 * frame's passes; a frame of another size or other passes than the previous one clears
 * it. Waits for the device to finish. *rays (may be NULL) gets the queries made. */
int tr_cl_render_frame(tr_cl_context *ctx, const tr_frame *f, uint64_t *rays, tr_error *err);
/* TR_OK if the device runs `integrator`; else TR_STATUS_UNSUPPORTED with the reason: bdpt
 * or vcm on a big-endian device without cl_khr_int64_base_atomics (their splats' sums as
 * 32-bit pairs), or in a test's own program without their kernels. tr_cl_render_frame
 * checks it too. */
int tr_cl_supports_integrator(tr_cl_context *ctx, int integrator, tr_error *err);
/* How bdpt's and vcm's splats are summed and folded on this device (building their kernels
 * first): *emulated when as two 32-bit atomic additions (no cl_khr_int64_base_atomics, or
 * TRAC0R_OPENCL_DISABLE_EXT names it), *host_fold when the host folds them into the film
 * (no cl_khr_fp64, or named likewise). */
int tr_cl_splat_paths(tr_cl_context *ctx, int *emulated, int *host_fold, tr_error *err);
/* The CPU device's tile side for the frames to come (render.h's tr_render_config.tile, 0
 * for the default): vcm's buckets list the light vertices in the CPU's tile order, so that
 * each pixel sums its merges as the CPU does. */
void tr_cl_set_tile(tr_cl_context *ctx, uint32_t tile);
/* The kernel pt's frames run with from now on, TR_OPENCL_KERNEL_* (render.h; AUTO at
 * first): TR_STATUS_INVALID_ARGUMENT for another value, TR_STATUS_UNSUPPORTED for the
 * wavefront in a program without it (tr_cl_open_source). */
int tr_cl_set_kernel(tr_cl_context *ctx, int kernel, tr_error *err);
/* The kernel a frame of `integrator` runs with: TR_OPENCL_KERNEL_MEGA or _WAVEFRONT, AUTO
 * resolved (TRAC0R_OPENCL_KERNEL, then the device type's rule in opencl.c). */
int tr_cl_frame_kernel(const tr_cl_context *ctx, int integrator);
/* Traces `count` rays `reps` times with the uploaded scene's structure (closest hit, or any
 * hit with `shadow`); *seconds: from the first pass's start to the last one's end (the rays'
 * upload excluded), *hits: the rays of one pass that hit. */
int tr_cl_trace_rays(tr_cl_context *ctx, const tr_ray *rays, uint32_t count, int shadow, int reps,
                     uint64_t *hits, double *seconds, tr_error *err);
/* tr_cl_trace_rays on an OpenCL device of the public API, with its uploaded scene
 * (device.c); TR_STATUS_UNSUPPORTED on the CPU device. */
int tr_device_trace_rays(tr_device *dev, const tr_ray *rays, uint32_t count, int shadow, int reps,
                         uint64_t *hits, double *seconds, tr_error *err);
/* tr_cl_trace_rays through the compressed wide BVH `cw` (src/accel/cwbvh.h), uploaded for
 * the call (before the clock starts) and released after. */
struct tr_cwbvh;
int tr_cl_trace_rays_cwbvh(tr_cl_context *ctx, const struct tr_cwbvh *cw, const tr_ray *rays,
                           uint32_t count, int shadow, int reps, uint64_t *hits, double *seconds,
                           tr_error *err);
/* The size and passes of the device film (those of the last frame; 0 before one). */
void tr_cl_film_size(const tr_cl_context *ctx, uint32_t *width, uint32_t *height, uint32_t *passes);
/* Forgets every sample of the device film. */
int tr_cl_clear_film(tr_cl_context *ctx, tr_error *err);
/* Copies the device film into `film`, which must have the size of the last frame's
 * camera and may keep no pass the device film lacks. */
int tr_cl_read_film(tr_cl_context *ctx, tr_film *film, tr_error *err);
/* Makes the device's film a copy of `film` (reallocated for its size and passes). */
int tr_cl_write_film(tr_cl_context *ctx, const tr_film *film, tr_error *err);

/* ReSTIR DI's two passes (src/kernel/restir_pass.h) on the device film, which must have
 * fr->cam's size (and the direct pass where fr->direct): the light at each pixel's first
 * surface added to the film's sums, the reservoirs and surfaces kept on the device for the
 * next call's temporal reuse (fr->temporal: whether to use them; buffers made anew for a
 * new size hold none). Waits for the device; reads nothing back. */
struct tr_restir_frame;
int tr_cl_restir_frame(tr_cl_context *ctx, const struct tr_restir_frame *fr, tr_error *err);
/* Builds ReSTIR's passes now (else the first tr_cl_restir_frame does): a real-time session
 * that will run them builds them when it is made, not inside its first frame's time. */
int tr_cl_prepare_restir(tr_cl_context *ctx, tr_error *err);
/* How many times tr_cl_read_film copied the film to the host since the context opened:
 * real-time frames keep it on the device until they are shown or saved. */
uint64_t tr_cl_film_reads(const tr_cl_context *ctx);

/* tr_upscale_emission (include/trac0r/upscale.h) on the device (entry.cl's
 * tr_cl_upscale_emission): the first hit's emission at the resolution of `cam`, the
 * output's camera, into `out` (a cl_mem of 3 floats per output pixel) from `emission` (a
 * cl_mem: the traced frame's mean emission, wl x hl) and `prev` (the previous output's,
 * or NULL), n x n rays per resolved pixel; enqueued, not waited for. */
int tr_cl_upscale_emission(tr_cl_context *ctx, const tr_camera *cam, int n, uint32_t wl,
                           uint32_t hl, void *emission, void *prev, void *out, tr_error *err);

/* The temporal gradients of a real-time frame where its film lies (src/realtime/gradient.h
 * on the device: entry.cl's tr_cl_grad_*, grad_pixel.h's steps). With `prev` (the
 * previous frame's settings and camera, of this film's size) one pixel per stratum
 * replays its samples sample .. sample+count-1 and the film's pixels get history caps,
 * which tr_cl_get_handles then hands out as grad_cap until the next frame is rendered;
 * without, nothing is measured. Either way the film's means become the next call's
 * previous frame. cam: the camera the film was rendered with; same: whether it equals
 * prev's; frame: picks the strata's pixels; motion, motion_count: as the reconstruction
 * takes them (NULL, 0: none); amin: alpha_min. *changed gets the strata whose shading
 * changed. Waits for the device. */
int tr_cl_grad_frame(tr_cl_context *ctx, const tr_frame *prev, uint32_t sample, uint32_t count,
                     const tr_camera *cam, int same, uint32_t frame, const tr_vec3 *motion,
                     uint32_t motion_count, float amin, uint32_t *changed, tr_error *err);

/* The real-time loop's fresh samples where the film lies (src/realtime/fresh.h on the
 * device: entry.cl's tr_cl_fresh_mask, tr_cl_render_masked, tr_cl_fresh_remember). The
 * film (rendered through cam, with the depth, normal and id passes) gets its mask of
 * pixels without history against the previous call's frame (prev: its camera; NULL or
 * another size: none, every pixel that hit a surface is fresh), extra's samples added at
 * those pixels (extra NULL: none; stride 1, pt or naive, the film's size), and becomes
 * the next call's previous frame. motion, motion_count: as the reconstruction takes them.
 * *fresh gets the masked pixels. Waits for the device. */
int tr_cl_fresh_frame(tr_cl_context *ctx, const tr_camera *prev, const tr_camera *cam,
                      const tr_vec3 *motion, uint32_t motion_count, const tr_frame *extra,
                      uint32_t *fresh, tr_error *err);

/* Pretends the device has only `bytes` of global memory (0: its real size), for tests
 * of the out-of-memory path on devices that have plenty. */
void tr_cl_set_memory_limit(tr_cl_context *ctx, uint64_t bytes);

/* The context's OpenCL objects, for programs of the library's own that work on its
 * film where it lies (src/post/recon_opencl.c): cl_context, cl_device_id and
 * cl_command_queue as void pointers (this header does not need CL/cl.h), the options
 * its kernel was built with, and the film's buffers (cl_mem: radiance sum, count,
 * albedo, normal, depth, primitive id; NULL before the first frame; a pass the film
 * does not keep is a one-element placeholder) with its size and passes. */
typedef struct tr_cl_handles {
    void *context, *device, *queue;
    const char *options;
    void *film[6];
    void *emission; /* the film's emission pass (a placeholder when not kept) */
    void *direct;   /* the film's direct pass (a placeholder when not kept) */
    void *specular; /* the film's specular pass (a placeholder when not kept) */
    void *resolved; /* tr_cl_resolve_emission's output; NULL without the emission pass */
    void *grad_cap; /* this frame's history caps (tr_cl_grad_frame), 1 float a pixel; or NULL */
    uint32_t width, height, passes;
} tr_cl_handles;
/* Resolves the film's emission pass over each pixel's area (tr_cl_resolve_emission in
 * entry.cl: post.h's tr_resolve_emission on the device) into the handles' `resolved`
 * buffer, n x n rays per edge pixel through `cam`, the camera the film was rendered with;
 * enqueued, not waited for. Fails without the emission pass or a scene. */
int tr_cl_resolve_emission(tr_cl_context *ctx, const tr_camera *cam, int n, tr_error *err);
/* Fails only in builds without OpenCL. */
int tr_cl_get_handles(const tr_cl_context *ctx, tr_cl_handles *out, tr_error *err);
/* The OpenCL context of device dev (src/device/device.c); NULL for the CPU device. */
struct tr_device;
tr_cl_context *tr_device_cl_context(const struct tr_device *dev);

/* "CL_OUT_OF_RESOURCES" for -5 etc.; "CL_UNKNOWN_ERROR" for codes it does not know. */
const char *tr_cl_error_name(int code);

#endif
