/* opencl.c - the OpenCL backend: the embedded kernel source compiled for one device,
 * the scene's arrays in device buffers and a float film accumulated on the device. */
#define _POSIX_C_SOURCE 200809L
#include "device/opencl.h"

#include <dirent.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "device/frame.h"
#include "device/vcm.h"
#include "kernel/integrator_bdpt.h"
#include "kernel/integrator_pt_wf.h"
#include "kernel/kernel.h"
#include "kernel/grad_pixel.h"
#include "kernel/restir_pass.h"
#include "accel/accel_internal.h"
#include "accel/cwbvh.h"
#include "scene/scene_internal.h"
#include "trac0r/parse.h"
#include "trac0r/accel.h"
#include "trac0r/registry.h"

#ifndef TRAC0R_HAVE_OPENCL

/* ---- builds without OpenCL ---------------------------------------------------- */

static const char no_opencl[] = "this build of trac0r has no OpenCL support (CMake found no "
                                "OpenCL headers and ICD loader; install ocl-icd-opencl-dev)";

int tr_cl_available(void) {
    return 0;
}
int tr_cl_list_devices(tr_cl_device_info *out, int max, int *count, tr_error *err) {
    (void)out;
    (void)max;
    *count = 0;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
tr_cl_context *tr_cl_open(int index, tr_error *err) {
    (void)index;
    tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
    return NULL;
}
tr_cl_context *tr_cl_open_source(int index, const char *source, tr_error *err) {
    (void)source;
    return tr_cl_open(index, err);
}
void tr_cl_close(tr_cl_context *ctx) {
    (void)ctx;
}
const tr_cl_device_info *tr_cl_device(const tr_cl_context *ctx) {
    (void)ctx;
    return NULL;
}
const char *tr_cl_build_log(const tr_cl_context *ctx) {
    (void)ctx;
    return "";
}
const char *tr_cl_last_build_log(void) {
    return "";
}
const char *tr_cl_build_options(const tr_cl_context *ctx) {
    (void)ctx;
    return "";
}
int tr_cl_upload_scene(tr_cl_context *ctx, const tr_scene *scene, tr_error *err) {
    (void)ctx;
    (void)scene;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
tr_accel_type tr_cl_scene_accel(const tr_cl_context *ctx) {
    (void)ctx;
    return TR_ACCEL_TYPE_FLAT;
}
uint64_t tr_cl_scene_bytes(const tr_cl_context *ctx) {
    (void)ctx;
    return 0;
}
void tr_cl_set_bvh(tr_cl_context *ctx, tr_device_bvh bvh) {
    (void)ctx;
    (void)bvh;
}
tr_device_bvh tr_cl_scene_bvh(const tr_cl_context *ctx) {
    (void)ctx;
    return TR_DEVICE_BVH_BVH2;
}
int tr_cl_render_frame(tr_cl_context *ctx, const tr_frame *f, uint64_t *rays, tr_error *err) {
    (void)ctx;
    (void)f;
    (void)rays;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_clear_film(tr_cl_context *ctx, tr_error *err) {
    (void)ctx;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_trace_rays(tr_cl_context *ctx, const tr_ray *rays, uint32_t count, int shadow, int reps,
                     uint64_t *hits, double *seconds, tr_error *err) {
    (void)ctx;
    (void)rays;
    (void)count;
    (void)shadow;
    (void)reps;
    *hits = 0;
    *seconds = 0.0;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_trace_rays_cwbvh(tr_cl_context *ctx, const struct tr_cwbvh *cw, const tr_ray *rays,
                           uint32_t count, int shadow, int reps, uint64_t *hits, double *seconds,
                           tr_error *err) {
    (void)ctx;
    (void)cw;
    (void)rays;
    (void)count;
    (void)shadow;
    (void)reps;
    *hits = 0;
    *seconds = 0.0;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_supports_integrator(tr_cl_context *ctx, int integrator, tr_error *err) {
    (void)ctx;
    (void)integrator;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_set_kernel(tr_cl_context *ctx, int kernel, tr_error *err) {
    (void)ctx;
    (void)kernel;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_frame_kernel(const tr_cl_context *ctx, int integrator) {
    (void)ctx;
    (void)integrator;
    return TR_OPENCL_KERNEL_MEGA;
}
void tr_cl_set_tile(tr_cl_context *ctx, uint32_t tile) {
    (void)ctx;
    (void)tile;
}
int tr_cl_splat_paths(tr_cl_context *ctx, int *emulated, int *host_fold, tr_error *err) {
    (void)ctx;
    *emulated = *host_fold = 0;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
void tr_cl_film_size(const tr_cl_context *ctx, uint32_t *width, uint32_t *height,
                     uint32_t *passes) {
    (void)ctx;
    *width = *height = *passes = 0u;
}
int tr_cl_read_film(tr_cl_context *ctx, tr_film *film, tr_error *err) {
    (void)ctx;
    (void)film;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_write_film(tr_cl_context *ctx, const tr_film *film, tr_error *err) {
    (void)ctx;
    (void)film;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
void tr_cl_set_memory_limit(tr_cl_context *ctx, uint64_t bytes) {
    (void)ctx;
    (void)bytes;
}
int tr_cl_restir_frame(tr_cl_context *ctx, const struct tr_restir_frame *fr, tr_error *err) {
    (void)ctx;
    (void)fr;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_prepare_restir(tr_cl_context *ctx, tr_error *err) {
    (void)ctx;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_upscale_emission(tr_cl_context *ctx, const tr_camera *cam, int n, uint32_t wl,
                           uint32_t hl, void *emission, void *prev, void *out, tr_error *err) {
    (void)ctx;
    (void)cam;
    (void)n;
    (void)wl;
    (void)hl;
    (void)emission;
    (void)prev;
    (void)out;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
uint64_t tr_cl_film_reads(const tr_cl_context *ctx) {
    (void)ctx;
    return 0;
}
int tr_cl_get_handles(const tr_cl_context *ctx, tr_cl_handles *out, tr_error *err) {
    (void)ctx;
    memset(out, 0, sizeof *out);
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_resolve_emission(tr_cl_context *ctx, const tr_camera *cam, int n, tr_error *err) {
    (void)ctx;
    (void)cam;
    (void)n;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_grad_frame(tr_cl_context *ctx, const tr_frame *prev, uint32_t sample, uint32_t count,
                     const tr_camera *cam, int same, uint32_t frame, const tr_vec3 *motion,
                     uint32_t motion_count, float amin, uint32_t *changed, tr_error *err) {
    (void)ctx;
    (void)prev;
    (void)sample;
    (void)count;
    (void)cam;
    (void)same;
    (void)frame;
    (void)motion;
    (void)motion_count;
    (void)amin;
    *changed = 0;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
int tr_cl_fresh_frame(tr_cl_context *ctx, const tr_camera *prev, const tr_camera *cam,
                      const tr_vec3 *motion, uint32_t motion_count, const tr_frame *extra,
                      uint32_t *fresh, tr_error *err) {
    (void)ctx;
    (void)prev;
    (void)cam;
    (void)motion;
    (void)motion_count;
    (void)extra;
    *fresh = 0;
    return tr_error_set(err, TR_STATUS_UNSUPPORTED, "%s", no_opencl);
}
const char *tr_cl_error_name(int code) {
    (void)code;
    return "CL_UNKNOWN_ERROR";
}

#else

/* ---- builds with OpenCL ------------------------------------------------------- */

#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

/* The kernel source, generated by cmake/EmbedKernel.cmake from src/kernel/entry.cl. */
extern const char tr_cl_kernel_source[];
extern const size_t tr_cl_kernel_source_length;

/* FP_CONTRACT is switched off in entry.cl (the host builds with -ffp-contract=off);
 * kernel argument names are kept so that tr_cl_open can check them against the host's
 * table of scene arrays. CPU devices that can divide and take square roots correctly
 * rounded, as the host does, are asked to (OpenCL 1.2 otherwise allows 2.5 and 3 ulp),
 * so that PoCL's numbers follow the host's. GPUs are not: on an H100 the correctly
 * rounded division and root made pt's 1080p frame 1.2x slower (13.65 against 11.34 ms,
 * docs/gpu.md), and their images differ from the host's in the last bits anyway through
 * the device's exp, pow, sin and cos (docs/opencl.md). */
static const char build_options[] = "-cl-std=CL1.2 -cl-kernel-arg-info -DTR_OPENCL_DEVICE=1";

/* The programs the kernel source is built as (entry.cl's TR_CL_PART): each is compiled
 * only when first needed, since a GPU driver takes minutes over the whole source. */
enum {
    TR_CL_PART_FRAME = 1, /* the megakernel, emission and ray kernels: built at the opening */
    TR_CL_PART_RESTIR,    /* ReSTIR DI's and GI's passes */
    TR_CL_PART_WAVEFRONT, /* pt's wavefront stages */
    TR_CL_PART_BDPT,      /* bdpt, vcm and their splats' fold */
    TR_CL_PARTS
};
static const char build_option_rounded[] = " -cl-fp32-correctly-rounded-divide-sqrt";

#define TR_CL_MAX_ARRAYS 24

/* One scene array as uploaded: a kernel argument of its own. */
typedef struct cl_array {
    const char *name; /* the kernel's argument name */
    const void *data;
    size_t count;
    size_t elem; /* bytes per element */
} cl_array;

/* The view's arrays, in kernel argument order: the one list TR_SCENE_ARRAYS
 * (src/kernel/scene_view.h) that entry.cl's arguments come from as well (tr_cl_open
 * checks the compiled kernel's argument names against it). */
static int scene_arrays(const tr_scene_view *v, cl_array *a) {
    int n = 0;
#define TR_CL_HOST_ARRAY(type, name, count)                                                        \
    a[n++] = (cl_array){#name, v->name, v->count, sizeof(type)};
    TR_SCENE_ARRAYS(TR_CL_HOST_ARRAY)
#undef TR_CL_HOST_ARRAY
    return n;
}

/* Kernel arguments after the scene arrays (entry.cl's tr_cl_render). */
enum {
    ARG_SCENE_INFO = 0,
    ARG_FRAME,
    ARG_FILM_SUM,
    ARG_FILM_COUNT,
    ARG_FILM_ALBEDO,
    ARG_FILM_NORMAL,
    ARG_FILM_DEPTH,
    ARG_FILM_PRIM,
    ARG_FILM_SQ,
    ARG_FILM_DIRECT,
    ARG_FILM_EMISSION,
    ARG_FILM_SPECULAR,
    ARG_RAYS,
    ARG_AFTER_ARRAYS
};
static const char *const arg_names[ARG_AFTER_ARRAYS] = {
    "scene_info",    "frame",         "film_sum",    "film_count", "film_albedo",
    "film_normal",   "film_depth",    "film_prim",   "film_sq",    "film_direct",
    "film_emission", "film_specular", "rays_per_row"};

/* The film's buffers on the device: radiance sum and count, then the passes in TR_PASS_*
 * bit order; a pass not kept has a one-element placeholder. */
enum {
    FILM_SUM = 0,
    FILM_COUNT,
    FILM_ALBEDO,
    FILM_NORMAL,
    FILM_DEPTH,
    FILM_PRIM,
    FILM_SQ,
    FILM_DIRECT,
    FILM_EMISSION,
    FILM_SPECULAR,
    FILM_BUFFERS
};
/* The buffers follow the film's layout (tr_film_array_*, film.h): buffer i is array i. */
_Static_assert(FILM_BUFFERS == TR_FILM_ARRAYS, "one OpenCL buffer per film array");
#define film_pass(i) tr_film_array_pass(i)
#define film_elem(i) tr_film_array_pixel_bytes(i)

struct tr_cl_context {
    tr_cl_device_info info;
    cl_platform_id platform;
    cl_device_id device;
    cl_context context;
    cl_command_queue queue;
    /* The kernel source's programs (entry.cl's TR_CL_PART): program, the frame's, built
     * when the context opens; parts[TR_CL_PART_*] each built the first time one of its
     * kernels is needed (need_part). A program of the tests' own (custom) is program
     * alone, with every kernel it has made at the opening. */
    cl_program program;
    cl_program parts[TR_CL_PARTS];
    int custom;
    cl_kernel kernel;
    cl_kernel resolve; /* tr_cl_resolve_emission */
    /* bdpt: tr_cl_render_bdpt and tr_cl_fold_splats (NULL where the device has no doubles:
     * the host folds), and whether the splat sums are 32-bit pairs (create_bdpt). */
    cl_kernel bdpt, fold;
    int splat_emulated;
    cl_kernel trace;       /* tr_cl_trace_rays */
    cl_kernel trace_cwbvh; /* tr_cl_trace_cwbvh */
    /* ReSTIR DI's passes (tr_cl_restir_frame) and the kernel that reports its structs' sizes;
     * the passes' buffers: this frame's and the last frame's surfaces, the reservoirs of
     * the first pass, of the second and of the last frame, all of rs_w x rs_h pixels. */
    cl_kernel restir_t, restir_s, restir_sizes;
    cl_kernel gi_t, gi_s; /* ReSTIR GI's passes, and their reservoirs as rs_res' */
    cl_mem rs_gres[3];
    cl_kernel up_emission; /* tr_cl_upscale_emission */
    /* The temporal gradients (tr_cl_grad_frame): the kernels, the previous frame's luminance
     * and first primitive and this frame's caps (grad_w x grad_h pixels), the strata's
     * num and den (two each, for the à-trous steps), the changed count, the replayed
     * frame's settings and the motion (room for grad_motion_cap ids); grad_valid: the caps
     * are this film's. */
    cl_kernel grad_replay, grad_atrous, grad_finish;
    cl_mem grad_lum, grad_prim, grad_cap, grad_num[2], grad_den[2], grad_changed, grad_frame;
    cl_mem grad_cams, grad_motion;
    uint32_t grad_w, grad_h, grad_motion_cap;
    int grad_valid;
    /* The fresh samples (tr_cl_fresh_frame): the kernels, the previous frame's mean depth,
     * normal, primitive and surface points, this frame's points, the mask and its count,
     * of fresh_w x fresh_h pixels. */
    cl_kernel render_masked, fresh_mask, fresh_remember;
    cl_mem fr_depth, fr_normal, fr_prim, fr_point, fr_cur, fr_mask, fr_count;
    uint32_t fresh_w, fresh_h;
    cl_mem rs_surf[2], rs_res[3], rs_frame;
    uint32_t rs_w, rs_h;
    uint64_t film_reads; /* tr_cl_read_film calls */
    cl_mem splat;
    size_t splat_bytes;
    char *build_log;
    char options[160]; /* the options the kernel was built with */
    size_t local[2];   /* the render kernel's work-group size; 0 x 0: the driver's choice */
    int array_count;   /* scene arrays the kernel takes */
    uint64_t memory_limit;
    /* The uploaded scene. */
    cl_mem arrays[TR_CL_MAX_ARRAYS];
    cl_mem scene_info;
    cl_mem frame;
    tr_frame frame_host; /* what the frame buffer is written from, without waiting */
    int have_scene;
    tr_accel_type accel;
    tr_device_bvh bvh;       /* the choice for uploads (tr_cl_set_bvh) */
    tr_device_bvh env_bvh;   /* TRAC0R_OPENCL_BVH's, for the choice auto */
    tr_device_bvh scene_bvh; /* the uploaded scene's: bvh2 or cwbvh */
    uint64_t scene_bytes;
    /* The film. */
    cl_mem film[FILM_BUFFERS], rays;
    cl_mem resolved; /* with TR_PASS_EMISSION: tr_cl_resolve_emission's output */
    uint32_t width, height, passes;
    uint32_t *rays_host;
    /* pt's wavefront (entry.cl's tr_cl_wf_*; NULL in a program without them, see
     * tr_cl_open_source), the paths and their queues (room for wf_cap paths), the kernel
     * asked for (tr_cl_set_kernel) and TRAC0R_OPENCL_KERNEL's (AUTO when unset). */
    cl_kernel wf_generate, wf_extend, wf_shade, wf_connect, wf_accumulate;
    cl_mem wf_paths, wf_queue[2], wf_shadow, wf_counters;
    size_t wf_cap, wf_max; /* wf_max: TRAC0R_OPENCL_WAVEFRONT_PATHS, 0 when unset */
    size_t wf_group;       /* the stages' work-group size */
    int kernel_request, kernel_env;
    /* vcm (vcm_render): its kernels (with bdpt's, NULL where those are), the uploaded
     * scene's bounds and whether light comes from outside (for the merge radius and the
     * facing test, as the CPU takes them), the CPU's tile side (the buckets' order) and
     * the buffers of one sample's grid, each with its size in elements. */
    cl_kernel vcm_light, vcm_gather, vcm_render;
    tr_aabb vcm_box;
    int vcm_outside;
    uint32_t vcm_tile;
    cl_mem vcm_params, vcm_counter;
    cl_mem vcm_entries, vcm_hash, vcm_sorted; /* vcm_room entries */
    cl_mem vcm_first, vcm_count;              /* vcm_points grid points */
    cl_mem vcm_cells, vcm_order;              /* vcm_cell_room + 1 offsets, vcm_room */
    size_t vcm_room, vcm_points, vcm_cell_room;
    uint32_t *vcm_host; /* the host's copies: first, count, hash, cells, fill, order */
    size_t vcm_host_words;
};

static int wf_open(tr_cl_context *ctx, tr_error *err);
static void vcm_release(tr_cl_context *ctx);
static int wf_create(tr_cl_context *ctx, cl_program prog, int custom, tr_error *err);
static void wf_release(tr_cl_context *ctx);
static int wf_set_scene(tr_cl_context *ctx, tr_error *err);
static int wf_render(tr_cl_context *ctx, const tr_frame *f, uint32_t ny, uint64_t *rays_out,
                     tr_error *err);

static char last_build_log[16384];

const char *tr_cl_error_name(int code) {
    switch (code) {
#define TR_CL_CASE(name)                                                                           \
    case name:                                                                                     \
        return #name;
        TR_CL_CASE(CL_SUCCESS)
        TR_CL_CASE(CL_DEVICE_NOT_FOUND)
        TR_CL_CASE(CL_DEVICE_NOT_AVAILABLE)
        TR_CL_CASE(CL_COMPILER_NOT_AVAILABLE)
        TR_CL_CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
        TR_CL_CASE(CL_OUT_OF_RESOURCES)
        TR_CL_CASE(CL_OUT_OF_HOST_MEMORY)
        TR_CL_CASE(CL_PROFILING_INFO_NOT_AVAILABLE)
        TR_CL_CASE(CL_MEM_COPY_OVERLAP)
        TR_CL_CASE(CL_IMAGE_FORMAT_MISMATCH)
        TR_CL_CASE(CL_IMAGE_FORMAT_NOT_SUPPORTED)
        TR_CL_CASE(CL_BUILD_PROGRAM_FAILURE)
        TR_CL_CASE(CL_MAP_FAILURE)
        TR_CL_CASE(CL_MISALIGNED_SUB_BUFFER_OFFSET)
        TR_CL_CASE(CL_EXEC_STATUS_ERROR_FOR_EVENTS_IN_WAIT_LIST)
        TR_CL_CASE(CL_COMPILE_PROGRAM_FAILURE)
        TR_CL_CASE(CL_LINKER_NOT_AVAILABLE)
        TR_CL_CASE(CL_LINK_PROGRAM_FAILURE)
        TR_CL_CASE(CL_DEVICE_PARTITION_FAILED)
        TR_CL_CASE(CL_KERNEL_ARG_INFO_NOT_AVAILABLE)
        TR_CL_CASE(CL_INVALID_VALUE)
        TR_CL_CASE(CL_INVALID_DEVICE_TYPE)
        TR_CL_CASE(CL_INVALID_PLATFORM)
        TR_CL_CASE(CL_INVALID_DEVICE)
        TR_CL_CASE(CL_INVALID_CONTEXT)
        TR_CL_CASE(CL_INVALID_QUEUE_PROPERTIES)
        TR_CL_CASE(CL_INVALID_COMMAND_QUEUE)
        TR_CL_CASE(CL_INVALID_HOST_PTR)
        TR_CL_CASE(CL_INVALID_MEM_OBJECT)
        TR_CL_CASE(CL_INVALID_IMAGE_FORMAT_DESCRIPTOR)
        TR_CL_CASE(CL_INVALID_IMAGE_SIZE)
        TR_CL_CASE(CL_INVALID_SAMPLER)
        TR_CL_CASE(CL_INVALID_BINARY)
        TR_CL_CASE(CL_INVALID_BUILD_OPTIONS)
        TR_CL_CASE(CL_INVALID_PROGRAM)
        TR_CL_CASE(CL_INVALID_PROGRAM_EXECUTABLE)
        TR_CL_CASE(CL_INVALID_KERNEL_NAME)
        TR_CL_CASE(CL_INVALID_KERNEL_DEFINITION)
        TR_CL_CASE(CL_INVALID_KERNEL)
        TR_CL_CASE(CL_INVALID_ARG_INDEX)
        TR_CL_CASE(CL_INVALID_ARG_VALUE)
        TR_CL_CASE(CL_INVALID_ARG_SIZE)
        TR_CL_CASE(CL_INVALID_KERNEL_ARGS)
        TR_CL_CASE(CL_INVALID_WORK_DIMENSION)
        TR_CL_CASE(CL_INVALID_WORK_GROUP_SIZE)
        TR_CL_CASE(CL_INVALID_WORK_ITEM_SIZE)
        TR_CL_CASE(CL_INVALID_GLOBAL_OFFSET)
        TR_CL_CASE(CL_INVALID_EVENT_WAIT_LIST)
        TR_CL_CASE(CL_INVALID_EVENT)
        TR_CL_CASE(CL_INVALID_OPERATION)
        TR_CL_CASE(CL_INVALID_GL_OBJECT)
        TR_CL_CASE(CL_INVALID_BUFFER_SIZE)
        TR_CL_CASE(CL_INVALID_MIP_LEVEL)
        TR_CL_CASE(CL_INVALID_GLOBAL_WORK_SIZE)
        TR_CL_CASE(CL_INVALID_PROPERTY)
        TR_CL_CASE(CL_INVALID_IMAGE_DESCRIPTOR)
        TR_CL_CASE(CL_INVALID_COMPILER_OPTIONS)
        TR_CL_CASE(CL_INVALID_LINKER_OPTIONS)
        TR_CL_CASE(CL_INVALID_DEVICE_PARTITION_COUNT)
#undef TR_CL_CASE
    case -1001:
        return "CL_PLATFORM_NOT_FOUND_KHR";
    default:
        return "CL_UNKNOWN_ERROR";
    }
}

/* "OpenCL: CALL failed: CL_NAME (code)". */
static int cl_fail(tr_error *err, const char *call, cl_int code) {
    return tr_error_set(err, TR_STATUS_DEVICE, "OpenCL: %s failed: %s (%d)", call,
                        tr_cl_error_name(code), code);
}

int tr_cl_available(void) {
    return 1;
}

const char *tr_cl_build_options(const tr_cl_context *ctx) {
    return ctx->options;
}

const char *tr_cl_last_build_log(void) {
    return last_build_log;
}

static const char *device_type_name(cl_device_type t) {
    if (t & CL_DEVICE_TYPE_GPU) {
        return "gpu";
    }
    if (t & CL_DEVICE_TYPE_CPU) {
        return "cpu";
    }
    if (t & CL_DEVICE_TYPE_ACCELERATOR) {
        return "accelerator";
    }
    return "other";
}

static void describe_device(cl_platform_id p, cl_device_id d, int index, int pindex,
                            tr_cl_device_info *info) {
    memset(info, 0, sizeof *info);
    info->index = index;
    info->platform_index = pindex;
    /* Strings stay empty where a query fails; sizes minus one keep the terminator. */
    clGetPlatformInfo(p, CL_PLATFORM_NAME, sizeof info->platform - 1, info->platform, NULL);
    clGetDeviceInfo(d, CL_DEVICE_NAME, sizeof info->name - 1, info->name, NULL);
    clGetDeviceInfo(d, CL_DEVICE_VENDOR, sizeof info->vendor - 1, info->vendor, NULL);
    clGetDeviceInfo(d, CL_DEVICE_VERSION, sizeof info->version - 1, info->version, NULL);
    cl_device_type type = 0;
    clGetDeviceInfo(d, CL_DEVICE_TYPE, sizeof type, &type, NULL);
    snprintf(info->type, sizeof info->type, "%s", device_type_name(type));
    cl_uint cu = 0;
    clGetDeviceInfo(d, CL_DEVICE_MAX_COMPUTE_UNITS, sizeof cu, &cu, NULL);
    info->compute_units = cu;
    cl_ulong mem = 0, alloc = 0;
    clGetDeviceInfo(d, CL_DEVICE_GLOBAL_MEM_SIZE, sizeof mem, &mem, NULL);
    clGetDeviceInfo(d, CL_DEVICE_MAX_MEM_ALLOC_SIZE, sizeof alloc, &alloc, NULL);
    info->global_mem = mem;
    info->max_alloc = alloc;
}

/* The OpenCL drivers the ICD loader would try: *.icd files in OCL_ICD_VENDORS (a
 * directory) or /etc/OpenCL/vendors. Their number; the first name goes to `first`. */
static int installed_icds(char *first, size_t n) {
    const char *env = getenv("OCL_ICD_VENDORS");
    DIR *d = opendir(env && *env ? env : "/etc/OpenCL/vendors");
    int count = 0;
    first[0] = '\0';
    for (struct dirent *e; d && (e = readdir(d));) {
        const size_t len = strlen(e->d_name);
        if (len > 4 && strcmp(e->d_name + len - 4, ".icd") == 0) {
            if (count++ == 0) {
                snprintf(first, n, "%s", e->d_name);
            }
        }
    }
    if (d) {
        closedir(d);
    }
    return count;
}

/* Walks every device of every platform. With want >= 0 it stops at device `want`
 * and returns its handles; it always counts the devices into *count. */
static int walk_devices(tr_cl_device_info *out, int max, int *count, int want,
                        cl_platform_id *want_p, cl_device_id *want_d, tr_cl_device_info *want_info,
                        tr_error *err) {
    *count = 0;
    cl_uint np = 0;
    cl_int rc = clGetPlatformIDs(0, NULL, &np);
    if (rc == -1001 /* CL_PLATFORM_NOT_FOUND_KHR: the ICD loader found no driver */ ||
        (rc == CL_SUCCESS && np == 0)) {
        /* Installed drivers that none of them loaded is another failure: low memory (a
         * driver's dlopen or initialisation fails) or a broken driver, not "no OpenCL". */
        char first[64];
        const int icds = installed_icds(first, sizeof first);
        if (icds > 0) {
            return tr_error_set(err, TR_STATUS_DEVICE,
                                "no OpenCL platform could be loaded, although %d driver%s %s "
                                "installed (%s%s): out of memory, or a broken driver",
                                icds, icds == 1 ? "" : "s", icds == 1 ? "is" : "are", first,
                                icds > 1 ? ", ..." : "");
        }
        return tr_error_set(err, TR_STATUS_NOT_FOUND,
                            "no OpenCL platform found (no ICD installed in "
                            "/etc/OpenCL/vendors, or OCL_ICD_VENDORS points elsewhere)");
    }
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clGetPlatformIDs", rc);
    }
    cl_platform_id *plats = calloc(np, sizeof *plats);
    if (!plats) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory listing OpenCL platforms");
    }
    rc = clGetPlatformIDs(np, plats, NULL);
    if (rc != CL_SUCCESS) {
        free(plats);
        return cl_fail(err, "clGetPlatformIDs", rc);
    }
    int found = 0;
    for (cl_uint p = 0; p < np && !found; ++p) {
        cl_uint nd = 0;
        rc = clGetDeviceIDs(plats[p], CL_DEVICE_TYPE_ALL, 0, NULL, &nd);
        if (rc == CL_DEVICE_NOT_FOUND || nd == 0) {
            continue; /* a platform without devices */
        }
        if (rc != CL_SUCCESS) {
            free(plats);
            return cl_fail(err, "clGetDeviceIDs", rc);
        }
        cl_device_id *devs = calloc(nd, sizeof *devs);
        if (!devs) {
            free(plats);
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                                "out of memory listing OpenCL devices");
        }
        rc = clGetDeviceIDs(plats[p], CL_DEVICE_TYPE_ALL, nd, devs, NULL);
        if (rc != CL_SUCCESS) {
            free(devs);
            free(plats);
            return cl_fail(err, "clGetDeviceIDs", rc);
        }
        for (cl_uint d = 0; d < nd; ++d) {
            if (*count < max && out) {
                describe_device(plats[p], devs[d], *count, (int)p, &out[*count]);
            }
            if (*count == want) {
                *want_p = plats[p];
                *want_d = devs[d];
                describe_device(plats[p], devs[d], want, (int)p, want_info);
                found = 1;
            }
            ++*count;
            if (found) {
                break;
            }
        }
        free(devs);
    }
    free(plats);
    return TR_OK;
}

int tr_cl_list_devices(tr_cl_device_info *out, int max, int *count, tr_error *err) {
    return walk_devices(out, max, count, -1, NULL, NULL, NULL, err);
}

/* ReSTIR DI's buffers (tr_cl_restir_frame). */
static void release_restir(tr_cl_context *ctx) {
    cl_mem *const bufs[9] = {&ctx->rs_surf[0], &ctx->rs_surf[1], &ctx->rs_res[0],
                             &ctx->rs_res[1],  &ctx->rs_res[2],  &ctx->rs_frame,
                             &ctx->rs_gres[0], &ctx->rs_gres[1], &ctx->rs_gres[2]};
    for (int i = 0; i < 9; ++i) {
        if (*bufs[i]) {
            clReleaseMemObject(*bufs[i]);
            *bufs[i] = NULL;
        }
    }
    ctx->rs_w = ctx->rs_h = 0;
}

/* The fresh samples' buffers (tr_cl_fresh_frame). */
static void release_fresh(tr_cl_context *ctx) {
    cl_mem *const bufs[7] = {&ctx->fr_depth, &ctx->fr_normal, &ctx->fr_prim, &ctx->fr_point,
                             &ctx->fr_cur,   &ctx->fr_mask,   &ctx->fr_count};
    for (int i = 0; i < 7; ++i) {
        if (*bufs[i]) {
            clReleaseMemObject(*bufs[i]);
            *bufs[i] = NULL;
        }
    }
    ctx->fresh_w = ctx->fresh_h = 0;
}

/* The temporal gradients' buffers (tr_cl_grad_frame). */
static void release_grad(tr_cl_context *ctx) {
    cl_mem *const bufs[10] = {&ctx->grad_lum,    &ctx->grad_prim,    &ctx->grad_cap,
                              &ctx->grad_num[0], &ctx->grad_num[1],  &ctx->grad_den[0],
                              &ctx->grad_den[1], &ctx->grad_changed, &ctx->grad_frame,
                              &ctx->grad_cams};
    for (int i = 0; i < 10; ++i) {
        if (*bufs[i]) {
            clReleaseMemObject(*bufs[i]);
            *bufs[i] = NULL;
        }
    }
    if (ctx->grad_motion) {
        clReleaseMemObject(ctx->grad_motion);
        ctx->grad_motion = NULL;
    }
    ctx->grad_w = ctx->grad_h = ctx->grad_motion_cap = 0;
    ctx->grad_valid = 0;
}

void tr_cl_close(tr_cl_context *ctx) {
    if (!ctx) {
        return;
    }
    for (int i = 0; i < TR_CL_MAX_ARRAYS; ++i) {
        if (ctx->arrays[i]) {
            clReleaseMemObject(ctx->arrays[i]);
        }
    }
    cl_mem bufs[] = {ctx->scene_info, ctx->frame, ctx->rays};
    for (size_t i = 0; i < sizeof bufs / sizeof bufs[0]; ++i) {
        if (bufs[i]) {
            clReleaseMemObject(bufs[i]);
        }
    }
    for (int i = 0; i < FILM_BUFFERS; ++i) {
        if (ctx->film[i]) {
            clReleaseMemObject(ctx->film[i]);
        }
    }
    if (ctx->kernel) {
        clReleaseKernel(ctx->kernel);
    }
    if (ctx->resolve) {
        clReleaseKernel(ctx->resolve);
    }
    if (ctx->bdpt) {
        clReleaseKernel(ctx->bdpt);
    }
    if (ctx->fold) {
        clReleaseKernel(ctx->fold);
    }
    vcm_release(ctx);
    if (ctx->trace) {
        clReleaseKernel(ctx->trace);
    }
    if (ctx->trace_cwbvh) {
        clReleaseKernel(ctx->trace_cwbvh);
    }
    release_grad(ctx);
    release_fresh(ctx);
    const cl_kernel grad_kernels[6] = {ctx->grad_replay,   ctx->grad_atrous, ctx->grad_finish,
                                       ctx->render_masked, ctx->fresh_mask,  ctx->fresh_remember};
    for (int i = 0; i < 6; ++i) {
        if (grad_kernels[i]) {
            clReleaseKernel(grad_kernels[i]);
        }
    }
    release_restir(ctx);
    const cl_kernel restir_kernels[6] = {ctx->restir_t,    ctx->restir_s, ctx->restir_sizes,
                                         ctx->up_emission, ctx->gi_t,     ctx->gi_s};
    for (int i = 0; i < 6; ++i) {
        if (restir_kernels[i]) {
            clReleaseKernel(restir_kernels[i]);
        }
    }
    wf_release(ctx);
    if (ctx->splat) {
        clReleaseMemObject(ctx->splat);
    }
    if (ctx->resolved) {
        clReleaseMemObject(ctx->resolved);
    }
    if (ctx->program) {
        clReleaseProgram(ctx->program);
    }
    for (int i = 0; i < TR_CL_PARTS; ++i) {
        if (ctx->parts[i]) {
            clReleaseProgram(ctx->parts[i]);
        }
    }
    if (ctx->queue) {
        clReleaseCommandQueue(ctx->queue);
    }
    if (ctx->context) {
        clReleaseContext(ctx->context);
    }
    free(ctx->build_log);
    free(ctx->rays_host);
    free(ctx);
}

/* Reads the program's build log into a malloc'ed string with surrounding white space
 * trimmed (PoCL reports a lone newline for a clean build). */
static char *read_build_log(cl_program prog, cl_device_id dev) {
    size_t n = 0;
    if (clGetProgramBuildInfo(prog, dev, CL_PROGRAM_BUILD_LOG, 0, NULL, &n) != CL_SUCCESS) {
        n = 0;
    }
    char *log = calloc(n + 1, 1);
    if (!log) {
        return NULL;
    }
    if (n > 0 &&
        clGetProgramBuildInfo(prog, dev, CL_PROGRAM_BUILD_LOG, n, log, NULL) != CL_SUCCESS) {
        log[0] = '\0';
    }
    log[n] = '\0';
    size_t len = strlen(log);
    while (len > 0 && (log[len - 1] == '\n' || log[len - 1] == ' ' || log[len - 1] == '\r' ||
                       log[len - 1] == '\t')) {
        log[--len] = '\0';
    }
    size_t start = 0;
    while (log[start] == '\n' || log[start] == ' ' || log[start] == '\r' || log[start] == '\t') {
        ++start;
    }
    memmove(log, log + start, len - start + 1);
    return log;
}

/* Checks the compiled kernel's argument names against the host's table. */
static int check_kernel_args(tr_cl_context *ctx, tr_error *err) {
    cl_uint nargs = 0;
    cl_int rc = clGetKernelInfo(ctx->kernel, CL_KERNEL_NUM_ARGS, sizeof nargs, &nargs, NULL);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clGetKernelInfo(CL_KERNEL_NUM_ARGS)", rc);
    }
    cl_array arrays[TR_CL_MAX_ARRAYS];
    tr_scene_view none;
    memset(&none, 0, sizeof none);
    const int na = scene_arrays(&none, arrays);
    if (nargs != (cl_uint)(na + ARG_AFTER_ARRAYS)) {
        return tr_error_set(err, TR_STATUS_DEVICE,
                            "OpenCL: the kernel takes %u arguments but the host passes %d: "
                            "src/device/opencl.c and src/kernel/entry.cl disagree",
                            nargs, na + ARG_AFTER_ARRAYS);
    }
    ctx->array_count = na;
    for (cl_uint i = 0; i < nargs; ++i) {
        char name[64] = "";
        rc = clGetKernelArgInfo(ctx->kernel, i, CL_KERNEL_ARG_NAME, sizeof name - 1, name, NULL);
        if (rc == CL_KERNEL_ARG_INFO_NOT_AVAILABLE) {
            return TR_OK; /* the driver keeps no names: trust the count */
        }
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clGetKernelArgInfo(CL_KERNEL_ARG_NAME)", rc);
        }
        const char *want = (int)i < na ? arrays[i].name : arg_names[(int)i - na];
        if (strcmp(name, want) != 0) {
            return tr_error_set(err, TR_STATUS_DEVICE,
                                "OpenCL: kernel argument %u is '%s' but the host passes '%s' "
                                "there: src/device/opencl.c and src/kernel/entry.cl disagree",
                                i, name, want);
        }
    }
    return TR_OK;
}

tr_cl_context *tr_cl_open(int index, tr_error *err) {
    return tr_cl_open_source(index, NULL, err);
}

/* The render kernel's work-group size. A GPU gets 8 x 8 pixels: neighbouring rays walk
 * the same nodes, and on an H100 it beat the driver's own choice for a 1920x1080 grid
 * (docs/gpu.md). A CPU device keeps its driver's choice (PoCL folds a work-group into
 * loops). TRAC0R_OPENCL_WORK_GROUP=WxH sets it, "driver" leaves it to the driver; the
 * variable is read before the kernel is built, checked against the kernel's limit after. */
static const char work_group_env[] = "TRAC0R_OPENCL_WORK_GROUP";

static int parse_work_group(size_t local[2], int *given, tr_error *err) {
    local[0] = local[1] = 0;
    const char *env = getenv(work_group_env);
    *given = env && *env;
    if (!*given || strcmp(env, "driver") == 0) {
        return TR_OK;
    }
    uint32_t w = 0, h = 0;
    if (tr_parse_size(env, 1024, &w, &h) != TR_OK) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "%s='%s' is not WxH (1..1024 each) or 'driver'", work_group_env, env);
    }
    local[0] = w;
    local[1] = h;
    return TR_OK;
}

static int check_work_group(tr_cl_context *ctx, int given, int cpu, tr_error *err) {
    size_t max = 0;
    clGetKernelWorkGroupInfo(ctx->kernel, ctx->device, CL_KERNEL_WORK_GROUP_SIZE, sizeof max, &max,
                             NULL);
    if (!given) {
        if (!cpu && max >= 64) {
            ctx->local[0] = ctx->local[1] = 8;
        }
        return TR_OK;
    }
    if (ctx->local[0] * ctx->local[1] > max) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "%s=%zux%zu: %s runs at most %zu work items in a group", work_group_env,
                            ctx->local[0], ctx->local[1], ctx->info.name, max);
    }
    return TR_OK;
}

/* TRAC0R_OPENCL_BVH=auto|bvh2|cwbvh: what the choice auto means (an explicit bvh2 or cwbvh
 * of tr_cl_set_bvh wins); a bad value fails the opening, as a bad work-group size does. */
static const char bvh_env[] = "TRAC0R_OPENCL_BVH";

static int parse_bvh_env(tr_device_bvh *bvh, tr_error *err) {
    const char *env = getenv(bvh_env);
    *bvh = TR_DEVICE_BVH_AUTO;
    if (!env || !*env) {
        return TR_OK;
    }
    const int b = tr_device_bvh_from_name(env);
    if (b < 0) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "%s='%s' is not auto, bvh2 or cwbvh",
                            bvh_env, env);
    }
    *bvh = (tr_device_bvh)b;
    return TR_OK;
}

/* The rule `auto` follows, and the one place it is written: the BVH a device of this type
 * walks. Both find the same hits; which is faster is a measurement per device type
 * (docs/gpu.md). CPU devices keep the binary BVH: on PoCL pt's frames took 1.4-1.5x as
 * long with the compressed one (docs/log/2026-cwbvh-render.md). GPUs keep it too until one
 * has measured both in the renderer (scripts/gpu-measure's cwbvh rows): the binary BVH is
 * what every earlier GPU figure was taken with. */
static tr_device_bvh auto_bvh(const tr_cl_device_info *info) {
    if (strcmp(info->type, "gpu") == 0) {
        return TR_DEVICE_BVH_BVH2;
    }
    return TR_DEVICE_BVH_BVH2;
}

void tr_cl_set_bvh(tr_cl_context *ctx, tr_device_bvh bvh) {
    ctx->bvh = bvh;
}

tr_device_bvh tr_cl_scene_bvh(const tr_cl_context *ctx) {
    return ctx->have_scene ? ctx->scene_bvh : TR_DEVICE_BVH_BVH2;
}

/* TRAC0R_OPENCL_DISABLE_EXT: a comma-separated list of cl_khr_int64_base_atomics and
 * cl_khr_fp64, extensions the kernel is then built as if the device lacked (bdpt's and
 * vcm's fallbacks, entry.cl, run on any device: the tests use it). Unset or empty: none. */
static int disabled_extensions(int *no_atomics, int *no_fp64, tr_error *err) {
    *no_atomics = *no_fp64 = 0;
    const char *e = getenv("TRAC0R_OPENCL_DISABLE_EXT");
    if (!e || !*e) {
        return TR_OK;
    }
    for (const char *p = e;;) {
        const char *end = strchr(p, ',');
        const size_t n = end ? (size_t)(end - p) : strlen(p);
        if (n == strlen("cl_khr_int64_base_atomics") &&
            strncmp(p, "cl_khr_int64_base_atomics", n) == 0) {
            *no_atomics = 1;
        } else if (n == strlen("cl_khr_fp64") && strncmp(p, "cl_khr_fp64", n) == 0) {
            *no_fp64 = 1;
        } else {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "TRAC0R_OPENCL_DISABLE_EXT=\"%s\": expected a comma-separated "
                                "list of cl_khr_int64_base_atomics and cl_khr_fp64",
                                e);
        }
        if (!end) {
            return TR_OK;
        }
        p = end + 1; /* an empty name after it is refused */
    }
}

/* Whether the device lists extension `name` (CL_DEVICE_EXTENSIONS). */
static int device_has_extension(cl_device_id dev, const char *name) {
    size_t n = 0;
    if (clGetDeviceInfo(dev, CL_DEVICE_EXTENSIONS, 0, NULL, &n) != CL_SUCCESS || n == 0) {
        return 0;
    }
    char *list = malloc(n + 1u);
    if (!list || clGetDeviceInfo(dev, CL_DEVICE_EXTENSIONS, n, list, NULL) != CL_SUCCESS) {
        free(list);
        return 0;
    }
    list[n] = '\0';
    const size_t len = strlen(name);
    int found = 0;
    for (const char *p = list; (p = strstr(p, name)) != NULL; p += len) {
        const int starts = p == list || p[-1] == ' ';
        found |= starts && (p[len] == ' ' || p[len] == '\0');
    }
    free(list);
    return found;
}

/* Builds part `part` of the kernel source (TR_CL_PART_*), or with part 0 the program
 * `source` (a test's own, every kernel it has), with the context's options, into *out.
 * The frame's program keeps its log as the context's build log; every build's log is the
 * last one (tr_cl_last_build_log). */
static int build_part(tr_cl_context *ctx, const char *source, int part, cl_program *out,
                      tr_error *err) {
    const char *src = source ? source : tr_cl_kernel_source;
    const size_t len = source ? strlen(source) : tr_cl_kernel_source_length;
    cl_int rc;
    cl_program prog = clCreateProgramWithSource(ctx->context, 1, &src, &len, &rc);
    if (!prog) {
        return cl_fail(err, "clCreateProgramWithSource", rc);
    }
    /* TRAC0R_OPENCL_INLINE=1: the functions kept out of line on devices inlined (compat.h's
     * TR_FN_NOINLINE), to measure both; the choice is in every part's options. */
    const char *inl = getenv("TRAC0R_OPENCL_INLINE");
    char part_option[32] = "";
    if (part) {
        snprintf(part_option, sizeof part_option, " -DTR_CL_PART=%d", part);
    }
    int no_atomics = 0, no_fp64 = 0;
    if (disabled_extensions(&no_atomics, &no_fp64, err) != TR_OK) {
        clReleaseProgram(prog);
        return TR_ERR;
    }
    char options[sizeof ctx->options + 128];
    snprintf(options, sizeof options, "%s%s%s%s%s", ctx->options,
             inl && strcmp(inl, "1") == 0 ? " -DTR_CL_INLINE_ALL=1" : "", part_option,
             no_atomics ? " -DTR_CL_NO_INT64_ATOMICS=1" : "", no_fp64 ? " -DTR_CL_NO_FP64=1" : "");
    rc = clBuildProgram(prog, 1, &ctx->device, options, NULL, NULL);
    char *log = read_build_log(prog, ctx->device);
    if (!log) {
        clReleaseProgram(prog);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory reading the OpenCL build log");
    }
    snprintf(last_build_log, sizeof last_build_log, "%s", log);
    if (rc != CL_SUCCESS) {
        tr_error_set(err, TR_STATUS_DEVICE,
                     "OpenCL: clBuildProgram failed on %s (part %d of the kernel): %s (%d); "
                     "build log: %s",
                     ctx->info.name, part, tr_cl_error_name(rc), rc, log);
        free(log);
        clReleaseProgram(prog);
        return TR_ERR;
    }
    if (part <= TR_CL_PART_FRAME) {
        free(ctx->build_log);
        ctx->build_log = log;
    } else {
        free(log);
    }
    *out = prog;
    return TR_OK;
}

/* ReSTIR's kernels from program prog; in a program of the tests' own (custom) they may be
 * missing. */
static int create_restir(tr_cl_context *ctx, cl_program prog, int custom, tr_error *err) {
    static const char *const names[5] = {"tr_cl_restir_temporal", "tr_cl_restir_spatial",
                                         "tr_cl_restir_sizes", "tr_cl_restir_gi_temporal",
                                         "tr_cl_restir_gi_spatial"};
    cl_kernel *const ks[5] = {&ctx->restir_t, &ctx->restir_s, &ctx->restir_sizes, &ctx->gi_t,
                              &ctx->gi_s};
    for (int i = 0; i < 5; ++i) {
        cl_int rc;
        *ks[i] = clCreateKernel(prog, names[i], &rc);
        if (!*ks[i] && !custom) {
            return cl_fail(err, names[i], rc);
        }
    }
    return TR_OK;
}

/* bdpt's and vcm's kernels from prog (absent from a test's own program without them), and
 * how their splats are summed and folded: the fold kernel is absent from a program built
 * without cl_khr_fp64 (the host folds then), and without cl_khr_int64_base_atomics the
 * sums are two 32-bit words each, low first, which the host reads as its 64-bit integers
 * only on a little-endian device (elsewhere bdpt and vcm are refused). */
static void create_bdpt(tr_cl_context *ctx, cl_program prog) {
    cl_int rc;
    int no_atomics = 0, no_fp64 = 0;
    tr_error ignored;
    if (disabled_extensions(&no_atomics, &no_fp64, &ignored) != TR_OK) {
        return; /* build_part has refused the value already */
    }
    ctx->splat_emulated =
        no_atomics || !device_has_extension(ctx->device, "cl_khr_int64_base_atomics");
    cl_bool little = CL_TRUE;
    clGetDeviceInfo(ctx->device, CL_DEVICE_ENDIAN_LITTLE, sizeof little, &little, NULL);
    if (ctx->splat_emulated && !little) {
        return;
    }
    ctx->bdpt = clCreateKernel(prog, "tr_cl_render_bdpt", &rc);
    ctx->fold = ctx->bdpt ? clCreateKernel(prog, "tr_cl_fold_splats", &rc) : NULL;
    if (ctx->bdpt) {
        ctx->vcm_light = clCreateKernel(prog, "tr_cl_vcm_light", &rc);
        ctx->vcm_gather = clCreateKernel(prog, "tr_cl_vcm_gather", &rc);
        ctx->vcm_render = clCreateKernel(prog, "tr_cl_render_vcm", &rc);
    }
}

/* The scene's arrays and scene_info as kernel k's first arguments. */
static int set_scene_args(tr_cl_context *ctx, cl_kernel k, tr_error *err) {
    const int na = ctx->array_count;
    for (int i = 0; i < na; ++i) {
        cl_int crc = clSetKernelArg(k, (cl_uint)i, sizeof(cl_mem), &ctx->arrays[i]);
        if (crc != CL_SUCCESS) {
            return cl_fail(err, "clSetKernelArg(scene array)", crc);
        }
    }
    cl_int crc =
        clSetKernelArg(k, (cl_uint)(na + ARG_SCENE_INFO), sizeof(cl_mem), &ctx->scene_info);
    return crc == CL_SUCCESS ? TR_OK : cl_fail(err, "clSetKernelArg(scene_info)", crc);
}

/* Builds part `part` of the kernel source and makes its kernels, with the uploaded
 * scene's arguments, unless that is done (or the program is a test's own). */
static int need_part(tr_cl_context *ctx, int part, tr_error *err) {
    if (ctx->custom || ctx->parts[part]) {
        return TR_OK;
    }
    cl_program prog = NULL;
    if (build_part(ctx, NULL, part, &prog, err) != TR_OK) {
        return TR_ERR;
    }
    ctx->parts[part] = prog;
    int rc = TR_OK;
    if (part == TR_CL_PART_RESTIR) {
        rc = create_restir(ctx, prog, 0, err);
        const cl_kernel ks[4] = {ctx->restir_t, ctx->restir_s, ctx->gi_t, ctx->gi_s};
        for (int i = 0; i < 4 && rc == TR_OK && ctx->have_scene; ++i) {
            rc = set_scene_args(ctx, ks[i], err);
        }
    } else if (part == TR_CL_PART_WAVEFRONT) {
        rc = wf_create(ctx, prog, 0, err);
        if (rc == TR_OK && ctx->have_scene) {
            rc = wf_set_scene(ctx, err);
        }
    } else if (part == TR_CL_PART_BDPT) {
        create_bdpt(ctx, prog);
        const cl_kernel ks[3] = {ctx->bdpt, ctx->vcm_light, ctx->vcm_render};
        for (int i = 0; i < 3 && rc == TR_OK && ctx->have_scene; ++i) {
            if (ks[i]) {
                rc = set_scene_args(ctx, ks[i], err);
            }
        }
    }
    return rc;
}

tr_cl_context *tr_cl_open_source(int index, const char *source, tr_error *err) {
    last_build_log[0] = '\0';
    int count = 0;
    cl_platform_id plat = NULL;
    cl_device_id dev = NULL;
    tr_cl_device_info info;
    if (index < 0) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "OpenCL device index %d must be at least 0",
                     index);
        return NULL;
    }
    if (walk_devices(NULL, 0, &count, index, &plat, &dev, &info, err) != TR_OK) {
        return NULL;
    }
    if (!dev) {
        tr_error_set(err, TR_STATUS_NOT_FOUND,
                     "OpenCL device %d does not exist: %d device%s found (0..%d; see 'trac0r "
                     "info --devices')",
                     index, count, count == 1 ? "" : "s", count - 1);
        return NULL;
    }
    tr_cl_context *ctx = calloc(1, sizeof *ctx);
    if (!ctx) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory opening an OpenCL context");
        return NULL;
    }
    ctx->info = info;
    int wg_given = 0;
    if (parse_work_group(ctx->local, &wg_given, err) != TR_OK ||
        parse_bvh_env(&ctx->env_bvh, err) != TR_OK) {
        goto fail;
    }
    ctx->platform = plat;
    ctx->device = dev;
    cl_int rc;
    cl_context_properties props[] = {CL_CONTEXT_PLATFORM, (cl_context_properties)plat, 0};
    ctx->context = clCreateContext(props, 1, &dev, NULL, NULL, &rc);
    if (!ctx->context) {
        cl_fail(err, "clCreateContext", rc);
        goto fail;
    }
    ctx->queue = clCreateCommandQueue(ctx->context, dev, 0, &rc);
    if (!ctx->queue) {
        cl_fail(err, "clCreateCommandQueue", rc);
        goto fail;
    }
    cl_device_fp_config fp = 0;
    clGetDeviceInfo(dev, CL_DEVICE_SINGLE_FP_CONFIG, sizeof fp, &fp, NULL);
    cl_device_type type = 0;
    clGetDeviceInfo(dev, CL_DEVICE_TYPE, sizeof type, &type, NULL);
    const int cpu = (type & CL_DEVICE_TYPE_CPU) != 0;
    snprintf(ctx->options, sizeof ctx->options, "%s%s", build_options,
             cpu && (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) ? build_option_rounded : "");
    ctx->custom = source != NULL;
    if (build_part(ctx, source, ctx->custom ? 0 : TR_CL_PART_FRAME, &ctx->program, err) != TR_OK) {
        goto fail;
    }
    ctx->kernel = clCreateKernel(ctx->program, "tr_cl_render", &rc);
    if (!ctx->kernel) {
        cl_fail(err, "clCreateKernel(tr_cl_render)", rc);
        goto fail;
    }
    ctx->resolve = clCreateKernel(ctx->program, "tr_cl_resolve_emission", &rc);
    if (!ctx->resolve) {
        cl_fail(err, "clCreateKernel(tr_cl_resolve_emission)", rc);
        goto fail;
    }
    ctx->trace = clCreateKernel(ctx->program, "tr_cl_trace_rays", &rc);
    if (!ctx->trace && !source) {
        cl_fail(err, "clCreateKernel(tr_cl_trace_rays)", rc);
        goto fail;
    }
    ctx->trace_cwbvh = clCreateKernel(ctx->program, "tr_cl_trace_cwbvh", &rc);
    if (!ctx->trace_cwbvh && !source) {
        cl_fail(err, "clCreateKernel(tr_cl_trace_cwbvh)", rc);
        goto fail;
    }
    ctx->up_emission = clCreateKernel(ctx->program, "tr_cl_upscale_emission", &rc);
    if (!ctx->up_emission && !source) {
        cl_fail(err, "clCreateKernel(tr_cl_upscale_emission)", rc);
        goto fail;
    }
    {
        /* The real-time loop's stages where the film lies: the temporal gradients and the
         * fresh samples. */
        static const char *const names[6] = {"tr_cl_grad_replay", "tr_cl_grad_atrous",
                                             "tr_cl_grad_finish", "tr_cl_render_masked",
                                             "tr_cl_fresh_mask",  "tr_cl_fresh_remember"};
        cl_kernel *const ks[6] = {&ctx->grad_replay,   &ctx->grad_atrous, &ctx->grad_finish,
                                  &ctx->render_masked, &ctx->fresh_mask,  &ctx->fresh_remember};
        for (int i = 0; i < 6; ++i) {
            *ks[i] = clCreateKernel(ctx->program, names[i], &rc);
            if (!*ks[i] && !source) {
                cl_fail(err, names[i], rc);
                goto fail;
            }
        }
    }
    if (check_kernel_args(ctx, err) != TR_OK ||
        check_work_group(ctx, wg_given, cpu, err) != TR_OK || wf_open(ctx, err) != TR_OK) {
        goto fail;
    }
    /* A program of the tests' own has whatever kernels it has now; the kernel source's
     * other parts wait until they are needed. */
    if (source && (create_restir(ctx, ctx->program, 1, err) != TR_OK ||
                   wf_create(ctx, ctx->program, 1, err) != TR_OK)) {
        goto fail;
    }
    if (source) {
        create_bdpt(ctx, ctx->program);
    }
    ctx->frame = clCreateBuffer(ctx->context, CL_MEM_READ_ONLY, sizeof(tr_frame), NULL, &rc);
    if (!ctx->frame) {
        cl_fail(err, "clCreateBuffer(frame)", rc);
        goto fail;
    }
    return ctx;
fail:
    tr_cl_close(ctx);
    return NULL;
}

const tr_cl_device_info *tr_cl_device(const tr_cl_context *ctx) {
    return &ctx->info;
}

const char *tr_cl_build_log(const tr_cl_context *ctx) {
    return ctx->build_log ? ctx->build_log : "";
}

void tr_cl_set_memory_limit(tr_cl_context *ctx, uint64_t bytes) {
    ctx->memory_limit = bytes;
}

static uint64_t memory_budget(const tr_cl_context *ctx) {
    if (ctx->memory_limit && ctx->memory_limit < ctx->info.global_mem) {
        return ctx->memory_limit;
    }
    return ctx->info.global_mem;
}

static uint64_t film_bytes(uint32_t w, uint32_t h, uint32_t passes) {
    uint64_t per_pixel = 0;
    for (int i = 0; i < FILM_BUFFERS; ++i) {
        if (film_pass(i) == 0u || (passes & film_pass(i)) != 0u) {
            per_pixel += film_elem(i);
        }
    }
    if (passes & TR_PASS_EMISSION) {
        per_pixel += 3 * sizeof(cl_float); /* the resolved emission */
    }
    return (uint64_t)w * h * per_pixel + (uint64_t)h * 4;
}

static void release_scene(tr_cl_context *ctx) {
    for (int i = 0; i < TR_CL_MAX_ARRAYS; ++i) {
        if (ctx->arrays[i]) {
            clReleaseMemObject(ctx->arrays[i]);
            ctx->arrays[i] = NULL;
        }
    }
    if (ctx->scene_info) {
        clReleaseMemObject(ctx->scene_info);
        ctx->scene_info = NULL;
    }
    ctx->have_scene = 0;
    ctx->scene_bytes = 0;
}

static double mib(uint64_t bytes) {
    return (double)bytes / (1024.0 * 1024.0);
}

int tr_cl_upload_scene(tr_cl_context *ctx, const tr_scene *scene, tr_error *err) {
    if (tr_scene_check_committed(scene, err) != TR_OK) {
        return TR_ERR;
    }
    /* Kept instances (placed, not stored: the CPU's two levels alone trace them) are
     * flattened here, once, and the scene committed again to its structure: the same
     * scene, now in the arrays the device reads (tr_scene_flatten_committed). */
    if (tr_scene_has_kept_instances(scene) &&
        tr_scene_flatten_committed((tr_scene *)scene, err) != TR_OK) {
        return TR_ERR;
    }
    /* The device walks what the host's view holds, except that a scene committed to
     * Embree (a host library) gets a BVH of its own, and bvh scenes upload the binary BVH
     * (the wide one is host code). A bvh scene with instances holds the two-level
     * structure, host code too: the device gets a binary BVH over the instances'
     * transformed triangles (flattened), built here like Embree's. */
    tr_scene_view view = tr_scene_view_of(scene);
    tr_bvh own;
    memset(&own, 0, sizeof own);
    tr_accel_type accel = TR_ACCEL_TYPE_FLAT;
    if ((scene->accel == TR_ACCEL_TYPE_BVH && !scene->two_level) ||
        scene->accel == TR_ACCEL_TYPE_BVH2) {
        accel = TR_ACCEL_TYPE_BVH;
    } else if (scene->accel != TR_ACCEL_TYPE_FLAT) {
        if (tr_bvh_build(&own, scene->triangles, scene->triangle_count, err) != TR_OK) {
            return TR_ERR;
        }
        view.bvh_nodes = own.nodes;
        view.bvh_node_count = own.node_count;
        view.bvh_tris = own.tris;
        view.bvh_tri_count = own.index_count;
        view.accel = TR_ACCEL_BVH;
        accel = TR_ACCEL_TYPE_BVH;
    }
    /* The compressed wide BVH, where chosen, converted from the binary one the device
     * would walk and uploaded beside it (tr_cl_trace_rays still walks the binary BVH). */
    tr_cwbvh cw;
    memset(&cw, 0, sizeof cw);
    tr_device_bvh bvh = ctx->bvh != TR_DEVICE_BVH_AUTO ? ctx->bvh : ctx->env_bvh;
    bvh = bvh != TR_DEVICE_BVH_AUTO ? bvh : auto_bvh(&ctx->info);
    if (accel == TR_ACCEL_TYPE_BVH && bvh == TR_DEVICE_BVH_CWBVH && view.bvh_node_count > 0u) {
        if (tr_cwbvh_build(&cw, view.bvh_nodes, view.bvh_node_count, view.bvh_tris, err) != TR_OK) {
            tr_bvh_free(&own);
            return TR_ERR;
        }
        view.cwbvh_nodes = cw.nodes;
        view.cwbvh_node_count = cw.node_count;
        view.cwbvh_tris = cw.tris;
        view.cwbvh_tri_count = cw.tri_count;
    }
    cl_array arrays[TR_CL_MAX_ARRAYS];
    const int na = scene_arrays(&view, arrays);
    int rc = TR_OK;
    /* Check the sizes before allocating anything: each buffer against the largest
     * allocation, all of them plus the film against the device's memory. */
    uint64_t total = film_bytes(scene->camera.screen_width, scene->camera.screen_height, 0u);
    for (int i = 0; i < na && rc == TR_OK; ++i) {
        uint64_t bytes = (uint64_t)arrays[i].count * arrays[i].elem;
        if (bytes > ctx->info.max_alloc) {
            rc = tr_error_set(err, TR_STATUS_LIMIT,
                              "the scene does not fit on OpenCL device %d (%s): its %s take "
                              "%.1f MiB but the device allocates at most %.1f MiB per buffer",
                              ctx->info.index, ctx->info.name, arrays[i].name, mib(bytes),
                              mib(ctx->info.max_alloc));
        }
        total += bytes;
    }
    if (rc == TR_OK && total > memory_budget(ctx)) {
        rc = tr_error_set(err, TR_STATUS_LIMIT,
                          "the scene does not fit on OpenCL device %d (%s): it needs %.1f MiB "
                          "with the film but the device has %.1f MiB",
                          ctx->info.index, ctx->info.name, mib(total), mib(memory_budget(ctx)));
    }
    if (rc != TR_OK) {
        tr_bvh_free(&own);
        tr_cwbvh_free(&cw);
        return rc;
    }
    release_scene(ctx);
    /* scene_info: the arrays' counts, then the view's scalars as 32-bit words (entry.cl
     * reads a float back from its bits with as_float). */
    cl_uint info[TR_CL_MAX_ARRAYS + 8];
    int ni = 0;
    for (int i = 0; i < na; ++i) {
        cl_int crc;
        const size_t bytes = arrays[i].count * arrays[i].elem;
        /* OpenCL has no empty buffers: an empty array gets one element nobody reads. */
        ctx->arrays[i] = clCreateBuffer(ctx->context, CL_MEM_READ_ONLY,
                                        bytes ? bytes : arrays[i].elem, NULL, &crc);
        if (!ctx->arrays[i]) {
            char call[96];
            snprintf(call, sizeof call, "clCreateBuffer(%s, %zu bytes)", arrays[i].name, bytes);
            rc = cl_fail(err, call, crc);
            break;
        }
        if (bytes) {
            crc = clEnqueueWriteBuffer(ctx->queue, ctx->arrays[i], CL_TRUE, 0, bytes,
                                       arrays[i].data, 0, NULL, NULL);
            if (crc != CL_SUCCESS) {
                char call[96];
                snprintf(call, sizeof call, "clEnqueueWriteBuffer(%s)", arrays[i].name);
                rc = cl_fail(err, call, crc);
                break;
            }
        }
        info[ni++] = (cl_uint)arrays[i].count;
        ctx->scene_bytes += bytes;
    }
#define TR_CL_HOST_SCALAR(type, name)                                                              \
    {                                                                                              \
        const type value = view.name;                                                              \
        _Static_assert(sizeof value == sizeof(cl_uint), "scene scalars are 32-bit words");         \
        memcpy(&info[ni++], &value, sizeof value);                                                 \
    }
    TR_SCENE_SCALARS(TR_CL_HOST_SCALAR)
#undef TR_CL_HOST_SCALAR
    if (rc == TR_OK) {
        cl_int crc;
        ctx->scene_info = clCreateBuffer(ctx->context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                                         (size_t)ni * sizeof info[0], info, &crc);
        if (!ctx->scene_info) {
            rc = cl_fail(err, "clCreateBuffer(scene_info)", crc);
        }
    }
    /* The kernels take the scene's arrays and scene_info first (those of the parts built
     * so far: need_part gives the others theirs). */
    const cl_kernel kernels[13] = {
        ctx->kernel,     ctx->resolve,     ctx->trace,        ctx->restir_t, ctx->restir_s,
        ctx->gi_t,       ctx->gi_s,        ctx->up_emission,  ctx->bdpt,     ctx->vcm_light,
        ctx->vcm_render, ctx->grad_replay, ctx->render_masked};
    for (int k = 0; k < 13 && rc == TR_OK; ++k) {
        if (kernels[k]) {
            rc = set_scene_args(ctx, kernels[k], err);
        }
    }
    if (rc == TR_OK) {
        rc = wf_set_scene(ctx, err);
    }
    tr_bvh_free(&own);
    tr_cwbvh_free(&cw);
    if (rc != TR_OK) {
        release_scene(ctx);
        return rc;
    }
    ctx->have_scene = 1;
    ctx->accel = accel;
    ctx->vcm_box = tr_vcm_scene_box(&view);
    ctx->vcm_outside = tr_bdpt_outside_on(&view);
    ctx->scene_bvh = view.cwbvh_node_count > 0u ? TR_DEVICE_BVH_CWBVH : TR_DEVICE_BVH_BVH2;
    return TR_OK;
}

tr_accel_type tr_cl_scene_accel(const tr_cl_context *ctx) {
    return ctx->accel;
}

uint64_t tr_cl_scene_bytes(const tr_cl_context *ctx) {
    return ctx->scene_bytes;
}

uint64_t tr_cl_film_bytes(const tr_cl_context *ctx) {
    return ctx->width ? film_bytes(ctx->width, ctx->height, ctx->passes) : 0;
}

uint64_t tr_cl_wavefront_path_bytes(void) {
    return sizeof(tr_pt_wf_path) + 3 * sizeof(cl_uint);
}

/* Bytes of film buffer i for the film's size (a placeholder element when not kept). */
static size_t film_buffer_bytes(const tr_cl_context *ctx, int i) {
    if (film_pass(i) != 0u && (ctx->passes & film_pass(i)) == 0u) {
        return film_elem(i);
    }
    return (size_t)ctx->width * ctx->height * film_elem(i);
}

int tr_cl_clear_film(tr_cl_context *ctx, tr_error *err) {
    ctx->grad_valid = 0; /* the caps describe the samples that were there */
    if (!ctx->film[FILM_SUM]) {
        return TR_OK;
    }
    const cl_uint zero = 0; /* the bits of 0.0f too */
    for (int i = 0; i < FILM_BUFFERS; ++i) {
        cl_int rc = clEnqueueFillBuffer(ctx->queue, ctx->film[i], &zero, sizeof zero, 0,
                                        film_buffer_bytes(ctx, i), 0, NULL, NULL);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueFillBuffer(film)", rc);
        }
    }
    return TR_OK;
}

static void release_film(tr_cl_context *ctx) {
    for (int i = 0; i < FILM_BUFFERS; ++i) {
        if (ctx->film[i]) {
            clReleaseMemObject(ctx->film[i]);
            ctx->film[i] = NULL;
        }
    }
    if (ctx->rays) {
        clReleaseMemObject(ctx->rays);
        ctx->rays = NULL;
    }
    if (ctx->resolved) {
        clReleaseMemObject(ctx->resolved);
        ctx->resolved = NULL;
    }
    free(ctx->rays_host);
    ctx->rays_host = NULL;
    ctx->width = ctx->height = ctx->passes = 0;
}

/* (Re)allocates a cleared film of w x h pixels keeping `passes`. */
static int make_film(tr_cl_context *ctx, uint32_t w, uint32_t h, uint32_t passes, tr_error *err) {
    release_film(ctx);
    const uint64_t need = film_bytes(w, h, passes);
    const uint64_t sum_bytes = (uint64_t)w * h * 3 * sizeof(cl_float);
    if (sum_bytes > ctx->info.max_alloc || ctx->scene_bytes + need > memory_budget(ctx)) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "a %ux%u film does not fit on OpenCL device %d (%s) next to the "
                            "scene (%.1f MiB + %.1f MiB of %.1f MiB)",
                            w, h, ctx->info.index, ctx->info.name, mib(ctx->scene_bytes), mib(need),
                            mib(memory_budget(ctx)));
    }
    ctx->width = w;
    ctx->height = h;
    ctx->passes = passes;
    cl_int rc = CL_SUCCESS;
    for (int i = 0; i < FILM_BUFFERS; ++i) {
        ctx->film[i] =
            clCreateBuffer(ctx->context, CL_MEM_READ_WRITE, film_buffer_bytes(ctx, i), NULL, &rc);
        if (!ctx->film[i]) {
            release_film(ctx);
            return cl_fail(err, "clCreateBuffer(film)", rc);
        }
    }
    if (passes & TR_PASS_EMISSION) {
        ctx->resolved = clCreateBuffer(ctx->context, CL_MEM_READ_WRITE,
                                       (size_t)w * h * 3 * sizeof(cl_float), NULL, &rc);
        if (!ctx->resolved) {
            release_film(ctx);
            return cl_fail(err, "clCreateBuffer(resolved emission)", rc);
        }
    }
    ctx->rays = clCreateBuffer(ctx->context, CL_MEM_READ_WRITE, h * sizeof(cl_uint), NULL, &rc);
    ctx->rays_host = malloc(h * sizeof *ctx->rays_host);
    if (!ctx->rays || !ctx->rays_host) {
        int r = ctx->rays_host ? cl_fail(err, "clCreateBuffer(rays_per_row)", rc)
                               : tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
        release_film(ctx);
        return r;
    }
    return tr_cl_clear_film(ctx, err);
}

void tr_cl_film_size(const tr_cl_context *ctx, uint32_t *width, uint32_t *height,
                     uint32_t *passes) {
    *width = ctx->width;
    *height = ctx->height;
    *passes = ctx->passes;
}

/* bdpt's splat sums for frame f's rectangle, cleared, as the render kernel's last
 * argument. */
/* Reads the frame's rays per grid row back (a blocking read: the frame's kernels have
 * finished when it returns) and sums them into *rays_out (may be null). */
static int read_rays(tr_cl_context *ctx, uint32_t ny, uint64_t *rays_out, tr_error *err) {
    cl_int rc = clEnqueueReadBuffer(ctx->queue, ctx->rays, CL_TRUE, 0, ny * sizeof(cl_uint),
                                    ctx->rays_host, 0, NULL, NULL);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueReadBuffer(rays_per_row)", rc);
    }
    if (rays_out) {
        uint64_t rays = 0;
        for (uint32_t y = 0; y < ny; ++y) {
            rays += ctx->rays_host[y];
        }
        *rays_out = rays;
    }
    return TR_OK;
}

static int prepare_splats(tr_cl_context *ctx, const tr_frame *f, cl_kernel kernel, tr_error *err) {
    const size_t bytes = 3u * (size_t)f->rect_w * f->rect_h * sizeof(cl_long);
    if (bytes > ctx->info.max_alloc) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "%s's %ux%u splat buffer (%.1f MiB) exceeds OpenCL device %d's "
                            "largest allocation",
                            tr_integrator_name((int)f->integrator), f->rect_w, f->rect_h,
                            mib(bytes), ctx->info.index);
    }
    if (bytes > ctx->splat_bytes) {
        if (ctx->splat) {
            clReleaseMemObject(ctx->splat);
            ctx->splat = NULL;
            ctx->splat_bytes = 0;
        }
        cl_int rc;
        ctx->splat = clCreateBuffer(ctx->context, CL_MEM_READ_WRITE, bytes, NULL, &rc);
        if (!ctx->splat) {
            return cl_fail(err, "clCreateBuffer(splat)", rc);
        }
        ctx->splat_bytes = bytes;
    }
    const cl_long zero = 0;
    cl_int rc =
        clEnqueueFillBuffer(ctx->queue, ctx->splat, &zero, sizeof zero, 0, bytes, 0, NULL, NULL);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueFillBuffer(splat)", rc);
    }
    rc = clSetKernelArg(kernel, (cl_uint)ctx->array_count + ARG_AFTER_ARRAYS, sizeof(cl_mem),
                        &ctx->splat);
    return rc == CL_SUCCESS ? TR_OK : cl_fail(err, "clSetKernelArg(splat)", rc);
}

/* fold_splats on the host, for a device without doubles: the sums and the rectangle's rows
 * of the film read back, added to as the CPU adds (src/device/cpu.c), written back. */
static int fold_splats_host(tr_cl_context *ctx, const tr_frame *f, double scale, tr_error *err) {
    const size_t sums = 3u * (size_t)f->rect_w * f->rect_h;
    const size_t row = 3u * (size_t)f->camera.screen_width, rows = f->rect_h;
    cl_long *q = malloc(sums * sizeof *q);
    float *film = malloc(row * rows * sizeof *film);
    cl_int rc = CL_SUCCESS;
    if (q && film) {
        const size_t at = (size_t)f->rect_y * row * sizeof *film;
        rc = clEnqueueReadBuffer(ctx->queue, ctx->splat, CL_TRUE, 0, sums * sizeof *q, q, 0, NULL,
                                 NULL);
        rc |= clEnqueueReadBuffer(ctx->queue, ctx->film[FILM_SUM], CL_TRUE, at,
                                  row * rows * sizeof *film, film, 0, NULL, NULL);
        for (size_t y = 0; y < rows && rc == CL_SUCCESS; ++y) {
            for (size_t x = 0; x < f->rect_w; ++x) {
                for (size_t c = 0; c < 3; ++c) {
                    film[y * row + 3u * (f->rect_x + x) + c] +=
                        (float)((double)q[3u * (y * f->rect_w + x) + c] * scale);
                }
            }
        }
        if (rc == CL_SUCCESS) {
            rc = clEnqueueWriteBuffer(ctx->queue, ctx->film[FILM_SUM], CL_TRUE, at,
                                      row * rows * sizeof *film, film, 0, NULL, NULL);
        }
    }
    free(q);
    free(film);
    if (!q || !film) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory folding %s's splats",
                            tr_integrator_name((int)f->integrator));
    }
    return rc == CL_SUCCESS ? TR_OK : cl_fail(err, "folding the splats on the host", rc);
}

/* Adds frame f's splat sums to the film (tr_cl_fold_splats, or on the host) with the CPU's
 * scale: the whole image's area over the frame's grid points, in 2^-24 units
 * (src/device/cpu.c). */
static int fold_splats(tr_cl_context *ctx, const tr_frame *f, uint32_t grid, tr_error *err) {
    const cl_double scale = (double)f->camera.screen_width * (double)f->camera.screen_height /
                            ((double)grid * TR_BDPT_SPLAT_ONE);
    if (!ctx->fold) {
        return fold_splats_host(ctx, f, scale, err);
    }
    cl_int rc = clSetKernelArg(ctx->fold, 0, sizeof(cl_mem), &ctx->frame);
    rc |= clSetKernelArg(ctx->fold, 1, sizeof(cl_mem), &ctx->splat);
    rc |= clSetKernelArg(ctx->fold, 2, sizeof scale, &scale);
    rc |= clSetKernelArg(ctx->fold, 3, sizeof(cl_mem), &ctx->film[FILM_SUM]);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clSetKernelArg(tr_cl_fold_splats)", rc);
    }
    const size_t global[2] = {f->rect_w, f->rect_h};
    rc = clEnqueueNDRangeKernel(ctx->queue, ctx->fold, 2, NULL, global, NULL, 0, NULL, NULL);
    return rc == CL_SUCCESS ? TR_OK : cl_fail(err, "clEnqueueNDRangeKernel(tr_cl_fold_splats)", rc);
}

/* ---- vcm ----------------------------------------------------------------------------
 *
 * Each sample of a vcm frame is, as on the CPU (src/device/vcm.c), a light pass and a
 * camera pass with the grid of the light vertices between them. The light pass
 * (tr_cl_vcm_light) writes each grid point's mergeable vertices as one block of entries
 * wherever an atomic counter puts it, with their buckets' hashes. The host reads the
 * blocks' places and the hashes back (4 bytes an entry, 8 a point; the entries
 * themselves stay on the device), orders the entries bucket by bucket in the CPU's order
 * (tr_vcm_bucket_order: tiles, rows, each subpath's vertices in turn), and sends the
 * buckets' offsets and that order; tr_cl_vcm_gather puts the entries in it, and the
 * camera pass (tr_cl_render_vcm) traces each pixel's light subpath again for the
 * connections and merges with the grid. So each pixel sums the same merges in the same
 * order as on the CPU. */

static void vcm_release_buffers(tr_cl_context *ctx) {
    cl_mem *const bufs[9] = {&ctx->vcm_params, &ctx->vcm_counter, &ctx->vcm_entries,
                             &ctx->vcm_hash,   &ctx->vcm_sorted,  &ctx->vcm_first,
                             &ctx->vcm_count,  &ctx->vcm_cells,   &ctx->vcm_order};
    for (int i = 0; i < 9; ++i) {
        if (*bufs[i]) {
            clReleaseMemObject(*bufs[i]);
            *bufs[i] = NULL;
        }
    }
    ctx->vcm_room = ctx->vcm_points = ctx->vcm_cell_room = 0;
    free(ctx->vcm_host);
    ctx->vcm_host = NULL;
    ctx->vcm_host_words = 0;
}

static void vcm_release(tr_cl_context *ctx) {
    const cl_kernel ks[3] = {ctx->vcm_light, ctx->vcm_gather, ctx->vcm_render};
    for (int i = 0; i < 3; ++i) {
        if (ks[i]) {
            clReleaseKernel(ks[i]);
        }
    }
    ctx->vcm_light = ctx->vcm_gather = ctx->vcm_render = NULL;
    vcm_release_buffers(ctx);
}

void tr_cl_set_tile(tr_cl_context *ctx, uint32_t tile) {
    ctx->vcm_tile = tile;
}

int tr_cl_splat_paths(tr_cl_context *ctx, int *emulated, int *host_fold, tr_error *err) {
    if (need_part(ctx, TR_CL_PART_BDPT, err) != TR_OK) {
        return TR_ERR;
    }
    *emulated = ctx->splat_emulated;
    *host_fold = ctx->bdpt && !ctx->fold;
    return TR_OK;
}

/* *b with room for `count` elements of `elem` bytes (at least one), made anew (contents
 * lost) when *have is less. */
static int vcm_buffer(tr_cl_context *ctx, cl_mem *b, size_t *have, size_t count, size_t elem,
                      const char *what, tr_error *err) {
    count = count ? count : 1u;
    if (*b && *have >= count) {
        return TR_OK;
    }
    if (count > ctx->info.max_alloc / elem) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "vcm's %s (%.1f MiB) exceeds OpenCL device %d's largest allocation",
                            what, mib(count * elem), ctx->info.index);
    }
    if (*b) {
        clReleaseMemObject(*b);
        *b = NULL;
        *have = 0;
    }
    cl_int rc;
    *b = clCreateBuffer(ctx->context, CL_MEM_READ_WRITE, count * elem, NULL, &rc);
    if (!*b) {
        char call[80];
        snprintf(call, sizeof call, "clCreateBuffer(vcm %s)", what);
        return cl_fail(err, call, rc);
    }
    *have = count;
    return TR_OK;
}

/* The host's arrays for `points` grid points, `entries` entries and `cells` buckets. */
static uint32_t *vcm_host(tr_cl_context *ctx, size_t points, size_t entries, size_t cells,
                          tr_error *err) {
    const size_t words = 2u * points + 2u * entries + 2u * cells + 1u;
    if (words > ctx->vcm_host_words) {
        uint32_t *p = realloc(ctx->vcm_host, words * sizeof *p);
        if (!p) {
            tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for vcm's grid (%.1f MiB)",
                         mib(words * sizeof *p));
            return NULL;
        }
        ctx->vcm_host = p;
        ctx->vcm_host_words = words;
    }
    return ctx->vcm_host;
}

/* Runs kernel k over the frame's grid points (global, local as render_frame chose). */
static int vcm_run(tr_cl_context *ctx, cl_kernel k, const size_t global[2], const size_t *local,
                   const char *name, tr_error *err) {
    cl_int rc = clEnqueueNDRangeKernel(ctx->queue, k, 2, NULL, global, local, 0, NULL, NULL);
    if (rc != CL_SUCCESS) {
        char call[80];
        snprintf(call, sizeof call, "clEnqueueNDRangeKernel(%s)", name);
        return cl_fail(err, call, rc);
    }
    return TR_OK;
}

/* Room for `want` entries (at least one) in the entries' buffers: made anew, all four,
 * when they hold fewer. */
static int vcm_make_room(tr_cl_context *ctx, size_t want, tr_error *err) {
    if (ctx->vcm_entries && ctx->vcm_room >= want) {
        return TR_OK;
    }
    cl_mem *const bufs[4] = {&ctx->vcm_entries, &ctx->vcm_hash, &ctx->vcm_sorted, &ctx->vcm_order};
    const size_t elem[4] = {sizeof(tr_vcm_entry), sizeof(cl_uint), sizeof(tr_vcm_entry),
                            sizeof(cl_uint)};
    static const char *const what[4] = {"light vertices", "hashes", "sorted light vertices",
                                        "order"};
    ctx->vcm_room = 0;
    for (int i = 0; i < 4; ++i) {
        size_t have = 0;
        if (*bufs[i]) {
            clReleaseMemObject(*bufs[i]);
            *bufs[i] = NULL;
        }
        if (vcm_buffer(ctx, bufs[i], &have, want, elem[i], what[i], err) != TR_OK) {
            return TR_ERR;
        }
    }
    ctx->vcm_room = want ? want : 1u;
    return TR_OK;
}

/* One sample's light pass: the entries, their hashes and the points' blocks on the device,
 * room made until they fit; *total gets the entries' number. */
static int vcm_light_pass(tr_cl_context *ctx, const size_t global[2], const size_t *local,
                          uint32_t *total, tr_error *err) {
    for (;;) {
        const cl_uint zero = 0, room = (cl_uint)ctx->vcm_room;
        cl_int rc = clEnqueueWriteBuffer(ctx->queue, ctx->vcm_counter, CL_TRUE, 0, sizeof zero,
                                         &zero, 0, NULL, NULL);
        const cl_uint base = (cl_uint)ctx->array_count + ARG_FRAME;
        const cl_mem args[8] = {ctx->frame, ctx->vcm_params,  ctx->vcm_entries, ctx->vcm_hash,
                                NULL,       ctx->vcm_counter, ctx->vcm_first,   ctx->vcm_count};
        for (cl_uint i = 0; i < 8 && rc == CL_SUCCESS; ++i) {
            rc = i == 4 ? clSetKernelArg(ctx->vcm_light, base + i, sizeof room, &room)
                        : clSetKernelArg(ctx->vcm_light, base + i, sizeof(cl_mem), &args[i]);
        }
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clSetKernelArg(tr_cl_vcm_light)", rc);
        }
        if (vcm_run(ctx, ctx->vcm_light, global, local, "tr_cl_vcm_light", err) != TR_OK) {
            return TR_ERR;
        }
        cl_uint n = 0;
        rc = clEnqueueReadBuffer(ctx->queue, ctx->vcm_counter, CL_TRUE, 0, sizeof n, &n, 0, NULL,
                                 NULL);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueReadBuffer(vcm counter)", rc);
        }
        if (n <= ctx->vcm_room) {
            *total = n;
            return TR_OK;
        }
        /* Too many for the room: the pass again (the same subpaths) with a quarter more. */
        if (vcm_make_room(ctx, (size_t)n + n / 4u, err) != TR_OK) {
            return TR_ERR;
        }
    }
}

/* The grid of the light pass's `total` entries: ordered on the host, gathered on the
 * device; sets p->cell_mask and writes p. */
static int vcm_grid(tr_cl_context *ctx, tr_vcm_params *p, uint32_t nx, uint32_t ny, uint32_t total,
                    tr_error *err) {
    const size_t points = (size_t)nx * ny;
    const uint32_t cells = tr_vcm_cells(total);
    p->cell_mask = cells - 1u;
    uint32_t *host = vcm_host(ctx, points, total, cells, err);
    if (!host || vcm_buffer(ctx, &ctx->vcm_cells, &ctx->vcm_cell_room, (size_t)cells + 1u,
                            sizeof(cl_uint), "buckets", err) != TR_OK) {
        return TR_ERR;
    }
    uint32_t *first = host, *count = first + points, *hash = count + points;
    uint32_t *cell_first = hash + total, *fill = cell_first + cells + 1u, *order = fill + cells;
    cl_int rc = CL_SUCCESS;
    if (total == 0u) {
        /* No entries (or no light pass: merging off), one empty bucket; the blocks may not
         * have been written this frame. */
        memset(cell_first, 0, ((size_t)cells + 1u) * sizeof *cell_first);
    } else {
        rc = clEnqueueReadBuffer(ctx->queue, ctx->vcm_first, CL_TRUE, 0, points * sizeof *first,
                                 first, 0, NULL, NULL);
        rc |= clEnqueueReadBuffer(ctx->queue, ctx->vcm_count, CL_TRUE, 0, points * sizeof *count,
                                  count, 0, NULL, NULL);
        rc |= clEnqueueReadBuffer(ctx->queue, ctx->vcm_hash, CL_TRUE, 0, total * sizeof *hash, hash,
                                  0, NULL, NULL);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueReadBuffer(vcm blocks)", rc);
        }
        tr_vcm_bucket_order(nx, ny, ctx->vcm_tile, first, count, hash, cells, cell_first, fill,
                            order);
    }
    rc = clEnqueueWriteBuffer(ctx->queue, ctx->vcm_cells, CL_TRUE, 0,
                              ((size_t)cells + 1u) * sizeof *cell_first, cell_first, 0, NULL, NULL);
    rc |=
        clEnqueueWriteBuffer(ctx->queue, ctx->vcm_params, CL_TRUE, 0, sizeof *p, p, 0, NULL, NULL);
    if (total > 0u) {
        rc |= clEnqueueWriteBuffer(ctx->queue, ctx->vcm_order, CL_TRUE, 0, total * sizeof *order,
                                   order, 0, NULL, NULL);
    }
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueWriteBuffer(vcm grid)", rc);
    }
    if (total == 0u) {
        return TR_OK;
    }
    const cl_uint n = total;
    rc = clSetKernelArg(ctx->vcm_gather, 0, sizeof(cl_mem), &ctx->vcm_entries);
    rc |= clSetKernelArg(ctx->vcm_gather, 1, sizeof(cl_mem), &ctx->vcm_order);
    rc |= clSetKernelArg(ctx->vcm_gather, 2, sizeof n, &n);
    rc |= clSetKernelArg(ctx->vcm_gather, 3, sizeof(cl_mem), &ctx->vcm_sorted);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clSetKernelArg(tr_cl_vcm_gather)", rc);
    }
    const size_t global = total;
    rc = clEnqueueNDRangeKernel(ctx->queue, ctx->vcm_gather, 1, NULL, &global, NULL, 0, NULL, NULL);
    return rc == CL_SUCCESS ? TR_OK : cl_fail(err, "clEnqueueNDRangeKernel(tr_cl_vcm_gather)", rc);
}

/* Frame f's samples with vcm: per sample the light pass, the grid and the camera pass
 * (whose other arguments render_frame has set), over the nx x ny grid points in
 * global/local. */
static int vcm_frame(tr_cl_context *ctx, const tr_frame *f, uint32_t nx, uint32_t ny,
                     const size_t global[2], const size_t *local, tr_error *err) {
    float pixels;
    if (tr_vcm_radius_pixels(&pixels, err) != TR_OK) {
        return TR_ERR;
    }
    const size_t points = (size_t)nx * ny;
    size_t one = ctx->vcm_params ? 1u : 0u, have_count = ctx->vcm_points;
    if (vcm_buffer(ctx, &ctx->vcm_params, &one, 1u, sizeof(tr_vcm_params), "parameters", err) !=
            TR_OK ||
        vcm_buffer(ctx, &ctx->vcm_counter, &one, 1u, sizeof(cl_uint), "counter", err) != TR_OK ||
        /* About three mergeable vertices a point on the shipped scenes: room for four. */
        vcm_make_room(ctx, ctx->vcm_room ? ctx->vcm_room : 4u * points, err) != TR_OK ||
        vcm_buffer(ctx, &ctx->vcm_count, &have_count, points, sizeof(cl_uint), "blocks", err) !=
            TR_OK ||
        vcm_buffer(ctx, &ctx->vcm_first, &ctx->vcm_points, points, sizeof(cl_uint), "blocks",
                   err) != TR_OK) {
        return TR_ERR;
    }
    for (uint32_t n = 0; n < f->sample_count; ++n) {
        tr_vcm_params p;
        const int merge = tr_vcm_params_make(&ctx->vcm_box, &f->camera, pixels, f->sample + n,
                                             points, ctx->vcm_outside, &p);
        uint32_t total = 0;
        if (merge) {
            cl_int rc = clEnqueueWriteBuffer(ctx->queue, ctx->vcm_params, CL_TRUE, 0, sizeof p, &p,
                                             0, NULL, NULL);
            if (rc != CL_SUCCESS) {
                return cl_fail(err, "clEnqueueWriteBuffer(vcm parameters)", rc);
            }
            if (vcm_light_pass(ctx, global, local, &total, err) != TR_OK) {
                return TR_ERR;
            }
        }
        /* Without merging the grid is one empty bucket (eta 0: tr_vcm_merge reads none). */
        if (vcm_grid(ctx, &p, nx, ny, total, err) != TR_OK) {
            return TR_ERR;
        }
        const cl_uint base = (cl_uint)ctx->array_count + ARG_AFTER_ARRAYS + 1u;
        cl_int rc = clSetKernelArg(ctx->vcm_render, base, sizeof(cl_mem), &ctx->vcm_params);
        rc |= clSetKernelArg(ctx->vcm_render, base + 1u, sizeof(cl_mem), &ctx->vcm_cells);
        rc |= clSetKernelArg(ctx->vcm_render, base + 2u, sizeof(cl_mem), &ctx->vcm_sorted);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clSetKernelArg(tr_cl_render_vcm)", rc);
        }
        if (vcm_run(ctx, ctx->vcm_render, global, local, "tr_cl_render_vcm", err) != TR_OK) {
            return TR_ERR;
        }
    }
    return TR_OK;
}

/* Times `reps` passes of `kernel` over the rays; its arguments from `base` on are the rays,
 * their count, the shadow flag and the hits (the ones before are set by the caller). */
static int trace_timed(tr_cl_context *ctx, cl_kernel kernel, cl_uint base, const tr_ray *rays,
                       uint32_t count, int shadow, int reps, uint64_t *hits, double *seconds,
                       tr_error *err) {
    *hits = 0;
    *seconds = 0.0;
    if (count == 0u) {
        return TR_OK;
    }
    const size_t bytes = (size_t)count * sizeof *rays;
    if (bytes > ctx->info.max_alloc) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "%u rays exceed OpenCL device %d's largest "
                            "allocation",
                            count, ctx->info.index);
    }
    cl_int rc;
    cl_mem rbuf = clCreateBuffer(ctx->context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, bytes,
                                 (void *)rays, &rc);
    if (!rbuf) {
        return cl_fail(err, "clCreateBuffer(rays)", rc);
    }
    cl_mem hbuf =
        clCreateBuffer(ctx->context, CL_MEM_READ_WRITE, (size_t)count * sizeof(cl_uint), NULL, &rc);
    uint32_t *h = malloc((size_t)count * sizeof *h);
    int out = TR_OK;
    if (!hbuf || !h) {
        out = h ? cl_fail(err, "clCreateBuffer(hits)", rc)
                : tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for %u hits", count);
    }
    const cl_uint n = count, sh = shadow ? 1u : 0u;
    if (out == TR_OK) {
        rc = clSetKernelArg(kernel, base, sizeof(cl_mem), &rbuf);
        rc |= clSetKernelArg(kernel, base + 1u, sizeof n, &n);
        rc |= clSetKernelArg(kernel, base + 2u, sizeof sh, &sh);
        rc |= clSetKernelArg(kernel, base + 3u, sizeof(cl_mem), &hbuf);
        if (rc != CL_SUCCESS) {
            out = cl_fail(err, "clSetKernelArg(tr_cl_trace_rays)", rc);
        }
    }
    const size_t group = 64u;
    const size_t global = (count + group - 1u) / group * group;
    const size_t *local = ctx->local[0] ? &group : NULL;
    /* Every buffer the kernel reads is on the device before the clock starts: a driver may
     * move a buffer made from host memory at its first use (NVIDIA's does), so one untimed
     * pass goes first. Then the passes are queued back to back and the clock stops when
     * the last one has finished. */
    if (out == TR_OK && (rc = clEnqueueNDRangeKernel(ctx->queue, kernel, 1, NULL, &global, local, 0,
                                                     NULL, NULL)) != CL_SUCCESS) {
        out = cl_fail(err, "clEnqueueNDRangeKernel(tr_cl_trace_rays)", rc);
    }
    if (out == TR_OK && (rc = clFinish(ctx->queue)) != CL_SUCCESS) {
        out = cl_fail(err, "clFinish", rc);
    }
    const double t0 = tr_time_now();
    for (int r = 0; r < reps && out == TR_OK; ++r) {
        rc = clEnqueueNDRangeKernel(ctx->queue, kernel, 1, NULL, &global, local, 0, NULL, NULL);
        if (rc != CL_SUCCESS) {
            out = cl_fail(err, "clEnqueueNDRangeKernel(tr_cl_trace_rays)", rc);
        }
    }
    if (out == TR_OK && (rc = clFinish(ctx->queue)) != CL_SUCCESS) {
        out = cl_fail(err, "clFinish", rc);
    }
    *seconds = tr_time_now() - t0;
    if (out == TR_OK) {
        rc = clEnqueueReadBuffer(ctx->queue, hbuf, CL_TRUE, 0, (size_t)count * sizeof *h, h, 0,
                                 NULL, NULL);
        if (rc != CL_SUCCESS) {
            out = cl_fail(err, "clEnqueueReadBuffer(hits)", rc);
        }
        for (uint32_t i = 0; i < count && out == TR_OK; ++i) {
            *hits += h[i];
        }
    }
    free(h);
    if (hbuf) {
        clReleaseMemObject(hbuf);
    }
    clReleaseMemObject(rbuf);
    return out;
}

int tr_cl_trace_rays(tr_cl_context *ctx, const tr_ray *rays, uint32_t count, int shadow, int reps,
                     uint64_t *hits, double *seconds, tr_error *err) {
    *hits = 0;
    *seconds = 0.0;
    if (!ctx->have_scene || !ctx->trace) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "no scene uploaded to the OpenCL device");
    }
    return trace_timed(ctx, ctx->trace, (cl_uint)ctx->array_count + ARG_FRAME, rays, count, shadow,
                       reps, hits, seconds, err);
}

int tr_cl_trace_rays_cwbvh(tr_cl_context *ctx, const struct tr_cwbvh *cw, const tr_ray *rays,
                           uint32_t count, int shadow, int reps, uint64_t *hits, double *seconds,
                           tr_error *err) {
    *hits = 0;
    *seconds = 0.0;
    if (!ctx->trace_cwbvh || cw->node_count == 0u) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION, "no wide BVH for the OpenCL device");
    }
    const size_t nb = cw->node_count * sizeof *cw->nodes, tb = cw->tri_count * sizeof *cw->tris;
    if (nb > ctx->info.max_alloc || tb > ctx->info.max_alloc) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "the wide BVH exceeds OpenCL device %d's largest allocation",
                            ctx->info.index);
    }
    cl_int rc;
    cl_mem bn =
        clCreateBuffer(ctx->context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, nb, cw->nodes, &rc);
    if (!bn) {
        return cl_fail(err, "clCreateBuffer(wide BVH nodes)", rc);
    }
    cl_mem bt = clCreateBuffer(ctx->context, CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                               tb ? tb : sizeof *cw->tris, cw->tris, &rc);
    if (!bt) {
        clReleaseMemObject(bn);
        return cl_fail(err, "clCreateBuffer(wide BVH triangles)", rc);
    }
    const cl_uint nc = cw->node_count;
    rc = clSetKernelArg(ctx->trace_cwbvh, 0, sizeof bn, &bn);
    rc |= clSetKernelArg(ctx->trace_cwbvh, 1, sizeof nc, &nc);
    rc |= clSetKernelArg(ctx->trace_cwbvh, 2, sizeof bt, &bt);
    int out = rc == CL_SUCCESS ? trace_timed(ctx, ctx->trace_cwbvh, 3u, rays, count, shadow, reps,
                                             hits, seconds, err)
                               : cl_fail(err, "clSetKernelArg(tr_cl_trace_cwbvh)", rc);
    clReleaseMemObject(bn);
    clReleaseMemObject(bt);
    return out;
}

int tr_cl_supports_integrator(tr_cl_context *ctx, int integrator, tr_error *err) {
    if (!tr_integrator_is_bidirectional(integrator)) {
        return TR_OK;
    }
    if (need_part(ctx, TR_CL_PART_BDPT, err) != TR_OK) {
        return TR_ERR;
    }
    const cl_kernel k = integrator == TR_INTEGRATOR_VCM ? ctx->vcm_render : ctx->bdpt;
    if (!k) {
        /* A big-endian device without 64-bit atomics (create_bdpt), or a test's own
         * program without the kernels. */
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "%s's kernels are not available on OpenCL device %d (%s)",
                            tr_integrator_name(integrator), ctx->info.index, ctx->info.name);
    }
    return TR_OK;
}

/* The frame, film and rays_per_row arguments of tr_cl_render (or a kernel that takes the
 * same ones after the scene's). */
static int set_film_args(tr_cl_context *ctx, cl_kernel kernel, tr_error *err) {
    const cl_uint base = (cl_uint)ctx->array_count;
    const cl_mem *bufs[ARG_AFTER_ARRAYS] = {NULL,
                                            &ctx->frame,
                                            &ctx->film[FILM_SUM],
                                            &ctx->film[FILM_COUNT],
                                            &ctx->film[FILM_ALBEDO],
                                            &ctx->film[FILM_NORMAL],
                                            &ctx->film[FILM_DEPTH],
                                            &ctx->film[FILM_PRIM],
                                            &ctx->film[FILM_SQ],
                                            &ctx->film[FILM_DIRECT],
                                            &ctx->film[FILM_EMISSION],
                                            &ctx->film[FILM_SPECULAR],
                                            &ctx->rays};
    for (int a = ARG_FRAME; a < ARG_AFTER_ARRAYS; ++a) {
        const cl_int rc = clSetKernelArg(kernel, base + (cl_uint)a, sizeof(cl_mem), bufs[a]);
        if (rc != CL_SUCCESS) {
            char call[64];
            snprintf(call, sizeof call, "clSetKernelArg(%s)", arg_names[a]);
            return cl_fail(err, call, rc);
        }
    }
    return TR_OK;
}

static int render_frame(tr_cl_context *ctx, const tr_frame *f, uint64_t *rays_out, tr_error *err) {
    ctx->grad_valid = 0; /* the caps were the last frame's */
    if (!ctx->have_scene) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "no scene uploaded to the OpenCL device");
    }
    if (tr_cl_supports_integrator(ctx, (int)f->integrator, err) != TR_OK) {
        return TR_ERR;
    }
    const int vcm = f->integrator == TR_INTEGRATOR_VCM;
    const int bdpt = f->integrator == TR_INTEGRATOR_BDPT || vcm; /* splats and 8x8 groups */
    cl_kernel kernel = vcm ? ctx->vcm_render : bdpt ? ctx->bdpt : ctx->kernel;
    const uint32_t w = f->camera.screen_width, h = f->camera.screen_height;
    if ((w != ctx->width || h != ctx->height || f->passes != ctx->passes) &&
        make_film(ctx, w, h, f->passes, err) != TR_OK) {
        return TR_ERR;
    }
    uint32_t gx0, gy0, nx, ny;
    tr_frame_grid(f, &gx0, &gy0, &nx, &ny);
    const cl_uint zero = 0;
    cl_int rc = clEnqueueFillBuffer(ctx->queue, ctx->rays, &zero, sizeof zero, 0,
                                    ny * sizeof(cl_uint), 0, NULL, NULL);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueFillBuffer(rays_per_row)", rc);
    }
    /* The write does not wait: the in-order queue runs it before the frame's kernel, and
     * the frame's last read (or clFinish on a failure) waits for both, so the copy it reads
     * stays as it is until then. One round trip to the device fewer per frame. */
    ctx->frame_host = *f;
    rc = clEnqueueWriteBuffer(ctx->queue, ctx->frame, CL_FALSE, 0, sizeof *f, &ctx->frame_host, 0,
                              NULL, NULL);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueWriteBuffer(frame)", rc);
    }
    /* The wavefront does not take the light apart into its specular part: a frame with
     * the specular pass runs the megakernel. */
    if (tr_cl_frame_kernel(ctx, (int)f->integrator) == TR_OPENCL_KERNEL_WAVEFRONT &&
        (f->passes & TR_PASS_SPECULAR) == 0u) {
        if (need_part(ctx, TR_CL_PART_WAVEFRONT, err) != TR_OK) {
            return TR_ERR;
        }
        return wf_render(ctx, f, ny, rays_out, err);
    }
    if (set_film_args(ctx, kernel, err) != TR_OK) {
        return TR_ERR;
    }
    /* With a work-group size the grid is rounded up to whole groups; the kernel returns
     * at once for the work items beyond the frame's grid. bdpt's work items keep two
     * subpaths of vertices each (several KB): left to the driver, PoCL made groups so
     * large that their private memory overflowed its thread's stack, so bdpt runs in 8x8
     * groups wherever no size is set and the kernel allows them. */
    size_t small[2] = {8u, 8u}, bmax = 0;
    if (bdpt && !ctx->local[0]) {
        clGetKernelWorkGroupInfo(kernel, ctx->device, CL_KERNEL_WORK_GROUP_SIZE, sizeof bmax, &bmax,
                                 NULL);
    }
    const size_t *local = ctx->local[0] ? ctx->local : bmax >= 64u ? small : NULL;
    const size_t global[2] = {local ? (nx + local[0] - 1) / local[0] * local[0] : nx,
                              local ? (ny + local[1] - 1) / local[1] * local[1] : ny};
    if (bdpt && prepare_splats(ctx, f, kernel, err) != TR_OK) {
        return TR_ERR;
    }
    if (vcm) {
        if (vcm_frame(ctx, f, nx, ny, global, local, err) != TR_OK) {
            return TR_ERR;
        }
    } else {
        rc = clEnqueueNDRangeKernel(ctx->queue, kernel, 2, NULL, global, local, 0, NULL, NULL);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueNDRangeKernel(tr_cl_render)", rc);
        }
    }
    /* The in-order queue runs the fold after the frame's kernel. */
    if (bdpt && fold_splats(ctx, f, nx * ny, err) != TR_OK) {
        return TR_ERR;
    }
    /* The blocking read waits for the kernel: the frame is done when it returns. */
    return read_rays(ctx, ny, rays_out, err);
}

int tr_cl_render_frame(tr_cl_context *ctx, const tr_frame *f, uint64_t *rays_out, tr_error *err) {
    if (render_frame(ctx, f, rays_out, err) != TR_OK) {
        clFinish(ctx->queue); /* nothing queued may still read the frame's copy */
        return TR_ERR;
    }
    return TR_OK;
}

int tr_cl_read_film(tr_cl_context *ctx, tr_film *film, tr_error *err) {
    if (!ctx->film[FILM_SUM]) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "the OpenCL film is empty: no frame was rendered");
    }
    if (film->width != ctx->width || film->height != ctx->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the film is %ux%u but the OpenCL film is %ux%u", film->width,
                            film->height, ctx->width, ctx->height);
    }
    if ((film->passes & ~ctx->passes) != 0u) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the OpenCL film does not keep passes 0x%x",
                            film->passes & ~ctx->passes);
    }
    ctx->film_reads += 1;
    for (int i = 0; i < FILM_BUFFERS; ++i) {
        void *dst = tr_film_array_data(film, i);
        if (!dst) {
            continue;
        }
        cl_int rc = clEnqueueReadBuffer(ctx->queue, ctx->film[i], CL_TRUE, 0,
                                        film_buffer_bytes(ctx, i), dst, 0, NULL, NULL);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueReadBuffer(film)", rc);
        }
    }
    return TR_OK;
}

int tr_cl_write_film(tr_cl_context *ctx, const tr_film *film, tr_error *err) {
    ctx->grad_valid = 0; /* the caps describe the samples that were there */
    if ((!ctx->film[FILM_SUM] || film->width != ctx->width || film->height != ctx->height ||
         film->passes != ctx->passes) &&
        make_film(ctx, film->width, film->height, film->passes, err) != TR_OK) {
        return TR_ERR;
    }
    for (int i = 0; i < FILM_BUFFERS; ++i) {
        const void *src = tr_film_array_data(film, i);
        if (!src) {
            continue;
        }
        cl_int rc = clEnqueueWriteBuffer(ctx->queue, ctx->film[i], CL_TRUE, 0,
                                         film_buffer_bytes(ctx, i), src, 0, NULL, NULL);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueWriteBuffer(film)", rc);
        }
    }
    return TR_OK;
}

int tr_cl_resolve_emission(tr_cl_context *ctx, const tr_camera *cam, int n, tr_error *err) {
    if (!ctx->resolved || !ctx->have_scene) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "resolving emission: the OpenCL film has no emission pass or no "
                            "scene");
    }
    if (cam->screen_width != ctx->width || cam->screen_height != ctx->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "resolving emission: a %ux%u camera for a %ux%u film",
                            cam->screen_width, cam->screen_height, ctx->width, ctx->height);
    }
    tr_frame f;
    memset(&f, 0, sizeof f);
    f.camera = *cam;
    cl_int rc =
        clEnqueueWriteBuffer(ctx->queue, ctx->frame, CL_TRUE, 0, sizeof f, &f, 0, NULL, NULL);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueWriteBuffer(frame)", rc);
    }
    const cl_uint base = (cl_uint)ctx->array_count + ARG_FRAME;
    const cl_int nn = n;
    const struct {
        size_t size;
        const void *ptr;
    } args[5] = {{sizeof(cl_mem), &ctx->frame},
                 {sizeof(cl_mem), &ctx->film[FILM_COUNT]},
                 {sizeof(cl_mem), &ctx->film[FILM_EMISSION]},
                 {sizeof(cl_int), &nn},
                 {sizeof(cl_mem), &ctx->resolved}};
    for (cl_uint a = 0; a < 5; ++a) {
        rc = clSetKernelArg(ctx->resolve, base + a, args[a].size, args[a].ptr);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clSetKernelArg(tr_cl_resolve_emission)", rc);
        }
    }
    const size_t global[2] = {ctx->width, ctx->height};
    rc = clEnqueueNDRangeKernel(ctx->queue, ctx->resolve, 2, NULL, global, NULL, 0, NULL, NULL);
    return rc == CL_SUCCESS ? TR_OK : cl_fail(err, "clEnqueueNDRangeKernel(resolve)", rc);
}

int tr_cl_get_handles(const tr_cl_context *ctx, tr_cl_handles *out, tr_error *err) {
    (void)err;
    memset(out, 0, sizeof *out);
    out->context = ctx->context;
    out->device = ctx->device;
    out->queue = ctx->queue;
    out->options = ctx->options;
    for (int i = 0; i < 6; ++i) {
        out->film[i] = ctx->film[i];
    }
    out->emission = ctx->film[FILM_EMISSION];
    out->direct = ctx->film[FILM_DIRECT];
    out->specular = ctx->film[FILM_SPECULAR];
    out->resolved = ctx->resolved;
    out->grad_cap = ctx->grad_valid ? ctx->grad_cap : NULL;
    out->width = ctx->width;
    out->height = ctx->height;
    out->passes = ctx->passes;
    return TR_OK;
}

uint64_t tr_cl_film_reads(const tr_cl_context *ctx) {
    return ctx->film_reads;
}

/* ReSTIR DI's buffers for a w x h frame, their element sizes as the device compiled them
 * (tr_cl_restir_sizes: a surface holds a pointer, whose size is the device's). */
static int restir_buffers(tr_cl_context *ctx, uint32_t w, uint32_t h, tr_error *err) {
    if (ctx->rs_w == w && ctx->rs_h == h && ctx->rs_frame) {
        return TR_OK;
    }
    release_restir(ctx);
    cl_int rc;
    cl_uint sizes[3] = {0, 0, 0};
    cl_mem out = clCreateBuffer(ctx->context, CL_MEM_WRITE_ONLY, sizeof sizes, NULL, &rc);
    if (!out) {
        return cl_fail(err, "clCreateBuffer(ReSTIR sizes)", rc);
    }
    const size_t one = 1;
    rc = clSetKernelArg(ctx->restir_sizes, 0, sizeof(cl_mem), &out);
    if (rc == CL_SUCCESS) {
        rc = clEnqueueNDRangeKernel(ctx->queue, ctx->restir_sizes, 1, NULL, &one, NULL, 0, NULL,
                                    NULL);
    }
    if (rc == CL_SUCCESS) {
        rc = clEnqueueReadBuffer(ctx->queue, out, CL_TRUE, 0, sizeof sizes, sizes, 0, NULL, NULL);
    }
    clReleaseMemObject(out);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "tr_cl_restir_sizes", rc);
    }
    const size_t n = (size_t)w * h;
    const uint64_t surf = (uint64_t)n * sizes[0], res = (uint64_t)n * sizes[1];
    const uint64_t gres = (uint64_t)n * sizes[2];
    const uint64_t need = 2 * surf + 3 * res + 3 * gres;
    if (surf > ctx->info.max_alloc ||
        ctx->scene_bytes + film_bytes(ctx->width, ctx->height, ctx->passes) + need >
            memory_budget(ctx)) {
        return tr_error_set(err, TR_STATUS_LIMIT,
                            "ReSTIR's reservoirs for %ux%u pixels do not fit on OpenCL device %d "
                            "(%s) next to the scene and the film (%.1f MiB more of %.1f MiB)",
                            w, h, ctx->info.index, ctx->info.name, mib(need),
                            mib(memory_budget(ctx)));
    }
    for (int i = 0; i < 2; ++i) {
        ctx->rs_surf[i] = clCreateBuffer(ctx->context, CL_MEM_READ_WRITE, (size_t)surf, NULL, &rc);
        if (!ctx->rs_surf[i]) {
            release_restir(ctx);
            return cl_fail(err, "clCreateBuffer(ReSTIR surfaces)", rc);
        }
    }
    for (int i = 0; i < 3; ++i) {
        ctx->rs_res[i] = clCreateBuffer(ctx->context, CL_MEM_READ_WRITE, (size_t)res, NULL, &rc);
        ctx->rs_gres[i] = ctx->rs_res[i] ? clCreateBuffer(ctx->context, CL_MEM_READ_WRITE,
                                                          (size_t)gres, NULL, &rc)
                                         : NULL;
        if (!ctx->rs_res[i] || !ctx->rs_gres[i]) {
            release_restir(ctx);
            return cl_fail(err, "clCreateBuffer(ReSTIR reservoirs)", rc);
        }
    }
    ctx->rs_frame =
        clCreateBuffer(ctx->context, CL_MEM_READ_ONLY, sizeof(tr_restir_frame), NULL, &rc);
    if (!ctx->rs_frame) {
        release_restir(ctx);
        return cl_fail(err, "clCreateBuffer(ReSTIR frame)", rc);
    }
    ctx->rs_w = w;
    ctx->rs_h = h;
    return TR_OK;
}

/* Sets kernel k's arguments after the scene's (its own: `count` buffers). */
static int set_args_after_scene(tr_cl_context *ctx, cl_kernel k, const cl_mem *const *bufs,
                                int count, const char *what, tr_error *err) {
    const cl_uint base = (cl_uint)ctx->array_count + ARG_FRAME;
    for (int a = 0; a < count; ++a) {
        const cl_int rc = clSetKernelArg(k, base + (cl_uint)a, sizeof(cl_mem), bufs[a]);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, what, rc);
        }
    }
    return TR_OK;
}

int tr_cl_prepare_restir(tr_cl_context *ctx, tr_error *err) {
    return need_part(ctx, TR_CL_PART_RESTIR, err);
}

int tr_cl_restir_frame(tr_cl_context *ctx, const tr_restir_frame *fr, tr_error *err) {
    if (need_part(ctx, TR_CL_PART_RESTIR, err) != TR_OK) {
        return TR_ERR;
    }
    if (!ctx->restir_t || !ctx->restir_s || !ctx->restir_sizes || !ctx->gi_t || !ctx->gi_s) {
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "this OpenCL program has no ReSTIR kernels");
    }
    const uint32_t w = fr->cam.screen_width, h = fr->cam.screen_height;
    if (!ctx->have_scene || !ctx->film[FILM_SUM] || w != ctx->width || h != ctx->height) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "ReSTIR on the OpenCL device: a %ux%u frame for a %ux%u film%s", w, h,
                            ctx->width, ctx->height, ctx->have_scene ? "" : " and no scene");
    }
    if (fr->direct && (ctx->passes & TR_PASS_DIRECT) == 0u) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "ReSTIR on the OpenCL device: the film keeps no direct pass");
    }
    if (restir_buffers(ctx, w, h, err) != TR_OK) {
        return TR_ERR;
    }
    cl_int rc =
        clEnqueueWriteBuffer(ctx->queue, ctx->rs_frame, CL_TRUE, 0, sizeof *fr, fr, 0, NULL, NULL);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueWriteBuffer(ReSTIR frame)", rc);
    }
    /* rs_surf[0] this frame's surfaces, [1] the last frame's; rs_res[0] the first pass's
     * reservoirs, [1] the second's, [2] the last frame's second pass's. */
    const cl_mem *const t_args[5] = {&ctx->rs_frame, &ctx->rs_surf[0], &ctx->rs_res[0],
                                     &ctx->rs_surf[1], &ctx->rs_res[2]};
    const cl_mem *const s_args[6] = {&ctx->rs_frame,       &ctx->rs_surf[0],
                                     &ctx->rs_res[0],      &ctx->rs_res[1],
                                     &ctx->film[FILM_SUM], &ctx->film[FILM_DIRECT]};
    if (set_args_after_scene(ctx, ctx->restir_t, t_args, 5, "clSetKernelArg(ReSTIR temporal)",
                             err) != TR_OK ||
        set_args_after_scene(ctx, ctx->restir_s, s_args, 6, "clSetKernelArg(ReSTIR spatial)",
                             err) != TR_OK) {
        return TR_ERR;
    }
    const size_t global[2] = {w, h};
    rc = clEnqueueNDRangeKernel(ctx->queue, ctx->restir_t, 2, NULL, global, NULL, 0, NULL, NULL);
    if (rc == CL_SUCCESS) {
        rc =
            clEnqueueNDRangeKernel(ctx->queue, ctx->restir_s, 2, NULL, global, NULL, 0, NULL, NULL);
    }
    /* ReSTIR GI after the direct light, on the same surfaces; its reservoirs as rs_res'. */
    if (rc == CL_SUCCESS && fr->gi) {
        const cl_mem *const gt_args[5] = {&ctx->rs_frame, &ctx->rs_surf[0], &ctx->rs_gres[0],
                                          &ctx->rs_surf[1], &ctx->rs_gres[2]};
        const cl_mem *const gs_args[5] = {&ctx->rs_frame, &ctx->rs_surf[0], &ctx->rs_gres[0],
                                          &ctx->rs_gres[1], &ctx->film[FILM_SUM]};
        if (set_args_after_scene(ctx, ctx->gi_t, gt_args, 5, "clSetKernelArg(ReSTIR GI temporal)",
                                 err) != TR_OK ||
            set_args_after_scene(ctx, ctx->gi_s, gs_args, 5, "clSetKernelArg(ReSTIR GI spatial)",
                                 err) != TR_OK) {
            return TR_ERR;
        }
        rc = clEnqueueNDRangeKernel(ctx->queue, ctx->gi_t, 2, NULL, global, NULL, 0, NULL, NULL);
        if (rc == CL_SUCCESS) {
            rc =
                clEnqueueNDRangeKernel(ctx->queue, ctx->gi_s, 2, NULL, global, NULL, 0, NULL, NULL);
        }
    }
    if (rc == CL_SUCCESS) {
        rc = clFinish(ctx->queue);
    }
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "ReSTIR's passes", rc);
    }
    /* The next frame reuses this one's surfaces and final reservoirs. */
    cl_mem t = ctx->rs_surf[0];
    ctx->rs_surf[0] = ctx->rs_surf[1];
    ctx->rs_surf[1] = t;
    t = ctx->rs_res[2];
    ctx->rs_res[2] = ctx->rs_res[1];
    ctx->rs_res[1] = t;
    t = ctx->rs_gres[2];
    ctx->rs_gres[2] = ctx->rs_gres[1];
    ctx->rs_gres[1] = t;
    return TR_OK;
}

int tr_cl_upscale_emission(tr_cl_context *ctx, const tr_camera *cam, int n, uint32_t wl,
                           uint32_t hl, void *emission, void *prev, void *out, tr_error *err) {
    if (!ctx->up_emission || !ctx->have_scene) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "upscaling emission: no scene or no kernel on the OpenCL device");
    }
    tr_frame f;
    memset(&f, 0, sizeof f);
    f.camera = *cam;
    cl_int rc =
        clEnqueueWriteBuffer(ctx->queue, ctx->frame, CL_TRUE, 0, sizeof f, &f, 0, NULL, NULL);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueWriteBuffer(frame)", rc);
    }
    const cl_int iwl = (cl_int)wl, ihl = (cl_int)hl, have = prev != NULL, nn = n;
    const cl_mem em = (cl_mem)emission, pv = (cl_mem)(prev ? prev : emission), o = (cl_mem)out;
    const struct {
        size_t size;
        const void *ptr;
    } args[8] = {{sizeof(cl_mem), &ctx->frame}, {sizeof(cl_int), &iwl},  {sizeof(cl_int), &ihl},
                 {sizeof(cl_mem), &em},         {sizeof(cl_int), &have}, {sizeof(cl_mem), &pv},
                 {sizeof(cl_int), &nn},         {sizeof(cl_mem), &o}};
    const cl_uint base = (cl_uint)ctx->array_count + ARG_FRAME;
    for (cl_uint a = 0; a < 8; ++a) {
        rc = clSetKernelArg(ctx->up_emission, base + a, args[a].size, args[a].ptr);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clSetKernelArg(tr_cl_upscale_emission)", rc);
        }
    }
    const size_t global[2] = {cam->screen_width, cam->screen_height};
    rc = clEnqueueNDRangeKernel(ctx->queue, ctx->up_emission, 2, NULL, global, NULL, 0, NULL, NULL);
    return rc == CL_SUCCESS ? TR_OK : cl_fail(err, "clEnqueueNDRangeKernel(upscale emission)", rc);
}

/* ---- the temporal gradients (entry.cl's tr_cl_grad_*) ------------------------- */

/* One kernel argument: its size and where its value lies. */
typedef struct cl_arg_ref {
    size_t size;
    const void *ptr;
} cl_arg_ref;

/* Sets kernel k's arguments base .. base+count-1 from args. */
static int set_arg_list(cl_kernel k, cl_uint base, const cl_arg_ref *args, int count,
                        const char *what, tr_error *err) {
    for (int a = 0; a < count; ++a) {
        const cl_int rc = clSetKernelArg(k, base + (cl_uint)a, args[a].size, args[a].ptr);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, what, rc);
        }
    }
    return TR_OK;
}

/* The gradients' buffers for a w x h film and room for motion_count motion ids. */
static int grad_buffers(tr_cl_context *ctx, uint32_t w, uint32_t h, uint32_t motion_count,
                        tr_error *err) {
    cl_int rc = CL_SUCCESS;
    if (ctx->grad_w != w || ctx->grad_h != h || !ctx->grad_cams) {
        release_grad(ctx);
        const size_t n = (size_t)w * h;
        const size_t ns = (size_t)((w + TR_GRAD_STRATUM - 1) / TR_GRAD_STRATUM) *
                          ((h + TR_GRAD_STRATUM - 1) / TR_GRAD_STRATUM);
        const struct {
            cl_mem *mem;
            size_t bytes;
        } bufs[10] = {
            {&ctx->grad_lum, n * sizeof(float)},     {&ctx->grad_prim, n * sizeof(cl_uint)},
            {&ctx->grad_cap, n * sizeof(float)},     {&ctx->grad_num[0], ns * sizeof(float)},
            {&ctx->grad_num[1], ns * sizeof(float)}, {&ctx->grad_den[0], ns * sizeof(float)},
            {&ctx->grad_den[1], ns * sizeof(float)}, {&ctx->grad_changed, sizeof(cl_uint)},
            {&ctx->grad_frame, sizeof(tr_frame)},    {&ctx->grad_cams, 2 * sizeof(tr_camera)}};
        for (int i = 0; i < 10; ++i) {
            *bufs[i].mem =
                clCreateBuffer(ctx->context, CL_MEM_READ_WRITE, bufs[i].bytes, NULL, &rc);
            if (!*bufs[i].mem) {
                release_grad(ctx);
                return cl_fail(err, "clCreateBuffer(temporal gradients)", rc);
            }
        }
        ctx->grad_w = w;
        ctx->grad_h = h;
    }
    const uint32_t need = motion_count > 0u ? motion_count : 1u;
    if (!ctx->grad_motion || ctx->grad_motion_cap < need) {
        if (ctx->grad_motion) {
            clReleaseMemObject(ctx->grad_motion);
        }
        ctx->grad_motion_cap = 0;
        ctx->grad_motion = clCreateBuffer(ctx->context, CL_MEM_READ_ONLY,
                                          (size_t)need * 3 * sizeof(float), NULL, &rc);
        if (!ctx->grad_motion) {
            return cl_fail(err, "clCreateBuffer(temporal gradients' motion)", rc);
        }
        ctx->grad_motion_cap = need;
    }
    return TR_OK;
}

int tr_cl_grad_frame(tr_cl_context *ctx, const tr_frame *prev, uint32_t sample, uint32_t count,
                     const tr_camera *cam, int same, uint32_t frame, const tr_vec3 *motion,
                     uint32_t motion_count, float amin, uint32_t *changed, tr_error *err) {
    *changed = 0;
    ctx->grad_valid = 0;
    const uint32_t w = cam->screen_width, h = cam->screen_height;
    if (!ctx->grad_replay || !ctx->grad_atrous || !ctx->grad_finish || !ctx->have_scene) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "temporal gradients: no scene or no kernel on the OpenCL device");
    }
    if (!ctx->film[FILM_SUM] || w != ctx->width || h != ctx->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "temporal gradients: the camera's %ux%u is not the film's %ux%u", w, h,
                            ctx->width, ctx->height);
    }
    if (prev && (prev->camera.screen_width != w || prev->camera.screen_height != h)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "temporal gradients: the previous frame is not %ux%u", w, h);
    }
    if (!motion) {
        motion_count = 0;
    }
    if (grad_buffers(ctx, w, h, motion_count, err) != TR_OK) {
        return TR_ERR;
    }
    const cl_uint sw = (w + TR_GRAD_STRATUM - 1) / TR_GRAD_STRATUM;
    const cl_uint sh = (h + TR_GRAD_STRATUM - 1) / TR_GRAD_STRATUM;
    const cl_int has_prim = (ctx->passes & TR_PASS_PRIM) != 0u;
    const cl_int has_depth = (ctx->passes & TR_PASS_DEPTH) != 0u;
    const cl_uint mc = motion_count;
    const tr_camera cams[2] = {*cam, prev ? prev->camera : *cam};
    cl_int rc = clEnqueueWriteBuffer(ctx->queue, ctx->grad_cams, CL_TRUE, 0, sizeof cams, cams, 0,
                                     NULL, NULL);
    if (rc == CL_SUCCESS && mc > 0u) {
        rc = clEnqueueWriteBuffer(ctx->queue, ctx->grad_motion, CL_TRUE, 0,
                                  (size_t)mc * 3 * sizeof(float), motion, 0, NULL, NULL);
    }
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueWriteBuffer(temporal gradients)", rc);
    }
    cl_uint nchanged = 0;
    if (prev) {
        const cl_uint zero = 0, fno = frame, smp = sample, cnt = count, cw = w, ch = h;
        rc = clEnqueueWriteBuffer(ctx->queue, ctx->grad_frame, CL_TRUE, 0, sizeof *prev, prev, 0,
                                  NULL, NULL);
        if (rc == CL_SUCCESS) {
            rc = clEnqueueWriteBuffer(ctx->queue, ctx->grad_changed, CL_TRUE, 0, sizeof zero, &zero,
                                      0, NULL, NULL);
        }
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueWriteBuffer(temporal gradients)", rc);
        }
        const cl_arg_ref args[16] = {{sizeof(cl_mem), &ctx->grad_frame},
                                     {sizeof(cl_uint), &cw},
                                     {sizeof(cl_uint), &ch},
                                     {sizeof(cl_uint), &sw},
                                     {sizeof(cl_uint), &sh},
                                     {sizeof(cl_uint), &fno},
                                     {sizeof(cl_uint), &smp},
                                     {sizeof(cl_uint), &cnt},
                                     {sizeof(cl_mem), &ctx->grad_lum},
                                     {sizeof(cl_mem), &ctx->grad_prim},
                                     {sizeof(cl_int), &has_prim},
                                     {sizeof(cl_mem), &ctx->grad_motion},
                                     {sizeof(cl_uint), &mc},
                                     {sizeof(cl_mem), &ctx->grad_num[0]},
                                     {sizeof(cl_mem), &ctx->grad_den[0]},
                                     {sizeof(cl_mem), &ctx->grad_changed}};
        if (set_arg_list(ctx->grad_replay, (cl_uint)ctx->array_count + ARG_FRAME, args, 16,
                         "clSetKernelArg(tr_cl_grad_replay)", err) != TR_OK) {
            return TR_ERR;
        }
        const size_t global[2] = {sw, sh};
        rc = clEnqueueNDRangeKernel(ctx->queue, ctx->grad_replay, 2, NULL, global, NULL, 0, NULL,
                                    NULL);
        if (rc == CL_SUCCESS) {
            rc = clEnqueueReadBuffer(ctx->queue, ctx->grad_changed, CL_TRUE, 0, sizeof nchanged,
                                     &nchanged, 0, NULL, NULL);
        }
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "the gradients' replay", rc);
        }
        /* Spread over the strata (1, 2, 4 apart), the result back in [0]. */
        for (int step = 1; nchanged > 0u && step < (1 << TR_GRAD_ATROUS_STEPS); step *= 2) {
            const cl_int isw = (cl_int)sw, ish = (cl_int)sh, st = step;
            const cl_arg_ref a[7] = {{sizeof(cl_mem), &ctx->grad_num[0]},
                                     {sizeof(cl_mem), &ctx->grad_den[0]},
                                     {sizeof(cl_int), &isw},
                                     {sizeof(cl_int), &ish},
                                     {sizeof(cl_int), &st},
                                     {sizeof(cl_mem), &ctx->grad_num[1]},
                                     {sizeof(cl_mem), &ctx->grad_den[1]}};
            if (set_arg_list(ctx->grad_atrous, 0, a, 7, "clSetKernelArg(tr_cl_grad_atrous)", err) !=
                TR_OK) {
                return TR_ERR;
            }
            rc = clEnqueueNDRangeKernel(ctx->queue, ctx->grad_atrous, 2, NULL, global, NULL, 0,
                                        NULL, NULL);
            if (rc != CL_SUCCESS) {
                return cl_fail(err, "clEnqueueNDRangeKernel(tr_cl_grad_atrous)", rc);
            }
            cl_mem t = ctx->grad_num[0];
            ctx->grad_num[0] = ctx->grad_num[1];
            ctx->grad_num[1] = t;
            t = ctx->grad_den[0];
            ctx->grad_den[0] = ctx->grad_den[1];
            ctx->grad_den[1] = t;
        }
    }
    const cl_int isame = same != 0, replayed = prev != NULL, ich = nchanged > 0u;
    const float am = amin;
    const cl_arg_ref f[19] = {{sizeof(cl_mem), &ctx->grad_cams},
                              {sizeof(cl_int), &isame},
                              {sizeof(cl_int), &replayed},
                              {sizeof(cl_int), &ich},
                              {sizeof(cl_uint), &sw},
                              {sizeof(cl_mem), &ctx->film[FILM_SUM]},
                              {sizeof(cl_mem), &ctx->film[FILM_COUNT]},
                              {sizeof(cl_mem), &ctx->film[FILM_DEPTH]},
                              {sizeof(cl_mem), &ctx->film[FILM_PRIM]},
                              {sizeof(cl_int), &has_depth},
                              {sizeof(cl_int), &has_prim},
                              {sizeof(cl_mem), &ctx->grad_motion},
                              {sizeof(cl_uint), &mc},
                              {sizeof(cl_mem), &ctx->grad_num[0]},
                              {sizeof(cl_mem), &ctx->grad_den[0]},
                              {sizeof(float), &am},
                              {sizeof(cl_mem), &ctx->grad_cap},
                              {sizeof(cl_mem), &ctx->grad_lum},
                              {sizeof(cl_mem), &ctx->grad_prim}};
    if (set_arg_list(ctx->grad_finish, 0, f, 19, "clSetKernelArg(tr_cl_grad_finish)", err) !=
        TR_OK) {
        return TR_ERR;
    }
    const size_t global[2] = {w, h};
    rc = clEnqueueNDRangeKernel(ctx->queue, ctx->grad_finish, 2, NULL, global, NULL, 0, NULL, NULL);
    if (rc == CL_SUCCESS) {
        rc = clFinish(ctx->queue);
    }
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "the gradients' caps", rc);
    }
    *changed = nchanged;
    ctx->grad_valid = prev != NULL;
    return TR_OK;
}

/* ---- the fresh samples (entry.cl's tr_cl_fresh_*, tr_cl_render_masked) ----------- */

/* The fresh samples' buffers for a w x h film. */
static int fresh_buffers(tr_cl_context *ctx, uint32_t w, uint32_t h, tr_error *err) {
    if (ctx->fresh_w == w && ctx->fresh_h == h && ctx->fr_count) {
        return TR_OK;
    }
    release_fresh(ctx);
    const size_t n = (size_t)w * h;
    const struct {
        cl_mem *mem;
        size_t bytes;
    } bufs[7] = {{&ctx->fr_depth, n * sizeof(float)},   {&ctx->fr_normal, 3 * n * sizeof(float)},
                 {&ctx->fr_prim, n * sizeof(cl_uint)},  {&ctx->fr_point, 3 * n * sizeof(float)},
                 {&ctx->fr_cur, 3 * n * sizeof(float)}, {&ctx->fr_mask, n},
                 {&ctx->fr_count, sizeof(cl_uint)}};
    for (int i = 0; i < 7; ++i) {
        cl_int rc;
        *bufs[i].mem = clCreateBuffer(ctx->context, CL_MEM_READ_WRITE, bufs[i].bytes, NULL, &rc);
        if (!*bufs[i].mem) {
            release_fresh(ctx);
            return cl_fail(err, "clCreateBuffer(fresh samples)", rc);
        }
    }
    ctx->fresh_w = w;
    ctx->fresh_h = h;
    return TR_OK;
}

/* tr_cl_render_masked over frame f (stride 1, the film's size) with the mask. */
static int render_masked(tr_cl_context *ctx, const tr_frame *f, tr_error *err) {
    cl_int rc =
        clEnqueueWriteBuffer(ctx->queue, ctx->frame, CL_TRUE, 0, sizeof *f, f, 0, NULL, NULL);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueWriteBuffer(frame)", rc);
    }
    if (set_film_args(ctx, ctx->render_masked, err) != TR_OK) {
        return TR_ERR;
    }
    rc = clSetKernelArg(ctx->render_masked, (cl_uint)ctx->array_count + ARG_AFTER_ARRAYS,
                        sizeof(cl_mem), &ctx->fr_mask);
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clSetKernelArg(tr_cl_render_masked)", rc);
    }
    const size_t global[2] = {f->camera.screen_width, f->camera.screen_height};
    rc = clEnqueueNDRangeKernel(ctx->queue, ctx->render_masked, 2, NULL, global, NULL, 0, NULL,
                                NULL);
    return rc == CL_SUCCESS ? TR_OK
                            : cl_fail(err, "clEnqueueNDRangeKernel(tr_cl_render_masked)", rc);
}

int tr_cl_fresh_frame(tr_cl_context *ctx, const tr_camera *prev, const tr_camera *cam,
                      const tr_vec3 *motion, uint32_t motion_count, const tr_frame *extra,
                      uint32_t *fresh, tr_error *err) {
    *fresh = 0;
    const uint32_t w = cam->screen_width, h = cam->screen_height;
    if (!ctx->render_masked || !ctx->fresh_mask || !ctx->fresh_remember || !ctx->have_scene) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "fresh samples: no scene or no kernel on the OpenCL device");
    }
    const uint32_t need = TR_PASS_DEPTH | TR_PASS_NORMAL | TR_PASS_PRIM;
    if (!ctx->film[FILM_SUM] || w != ctx->width || h != ctx->height ||
        (ctx->passes & need) != need) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "fresh samples: the film (%ux%u) is not the camera's %ux%u or lacks "
                            "the depth, normal and id passes",
                            ctx->width, ctx->height, w, h);
    }
    if (extra && (extra->camera.screen_width != w || extra->camera.screen_height != h ||
                  extra->stride != 1u || extra->integrator == TR_INTEGRATOR_BDPT ||
                  extra->integrator == TR_INTEGRATOR_VCM)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "fresh samples: the extra samples' frame must be the film's size, "
                            "stride 1, pt or naive");
    }
    if (!motion) {
        motion_count = 0;
    }
    /* The gradients' camera and motion buffers serve here too (sized for the film). */
    if (fresh_buffers(ctx, w, h, err) != TR_OK ||
        grad_buffers(ctx, w, h, motion_count, err) != TR_OK) {
        return TR_ERR;
    }
    const int have_prev = prev && prev->screen_width == w && prev->screen_height == h;
    const tr_camera cams[2] = {*cam, have_prev ? *prev : *cam};
    const cl_uint zero = 0, mc = motion_count;
    cl_int rc = clEnqueueWriteBuffer(ctx->queue, ctx->grad_cams, CL_TRUE, 0, sizeof cams, cams, 0,
                                     NULL, NULL);
    if (rc == CL_SUCCESS && mc > 0u) {
        rc = clEnqueueWriteBuffer(ctx->queue, ctx->grad_motion, CL_TRUE, 0,
                                  (size_t)mc * 3 * sizeof(float), motion, 0, NULL, NULL);
    }
    if (rc == CL_SUCCESS) {
        rc = clEnqueueWriteBuffer(ctx->queue, ctx->fr_count, CL_TRUE, 0, sizeof zero, &zero, 0,
                                  NULL, NULL);
    }
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueWriteBuffer(fresh samples)", rc);
    }
    const cl_int hp = have_prev;
    const cl_arg_ref m[15] = {{sizeof(cl_mem), &ctx->grad_cams},
                              {sizeof(cl_int), &hp},
                              {sizeof(cl_mem), &ctx->film[FILM_COUNT]},
                              {sizeof(cl_mem), &ctx->film[FILM_DEPTH]},
                              {sizeof(cl_mem), &ctx->film[FILM_NORMAL]},
                              {sizeof(cl_mem), &ctx->film[FILM_PRIM]},
                              {sizeof(cl_mem), &ctx->fr_depth},
                              {sizeof(cl_mem), &ctx->fr_normal},
                              {sizeof(cl_mem), &ctx->fr_prim},
                              {sizeof(cl_mem), &ctx->fr_point},
                              {sizeof(cl_mem), &ctx->grad_motion},
                              {sizeof(cl_uint), &mc},
                              {sizeof(cl_mem), &ctx->fr_cur},
                              {sizeof(cl_mem), &ctx->fr_mask},
                              {sizeof(cl_mem), &ctx->fr_count}};
    if (set_arg_list(ctx->fresh_mask, 0, m, 15, "clSetKernelArg(tr_cl_fresh_mask)", err) != TR_OK) {
        return TR_ERR;
    }
    const size_t global[2] = {w, h};
    rc = clEnqueueNDRangeKernel(ctx->queue, ctx->fresh_mask, 2, NULL, global, NULL, 0, NULL, NULL);
    cl_uint count = 0;
    if (rc == CL_SUCCESS) {
        rc = clEnqueueReadBuffer(ctx->queue, ctx->fr_count, CL_TRUE, 0, sizeof count, &count, 0,
                                 NULL, NULL);
    }
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "the fresh samples' mask", rc);
    }
    if (count > 0u && extra && render_masked(ctx, extra, err) != TR_OK) {
        clFinish(ctx->queue);
        return TR_ERR;
    }
    const cl_arg_ref r[10] = {
        {sizeof(cl_mem), &ctx->grad_cams},        {sizeof(cl_mem), &ctx->film[FILM_COUNT]},
        {sizeof(cl_mem), &ctx->film[FILM_DEPTH]}, {sizeof(cl_mem), &ctx->film[FILM_NORMAL]},
        {sizeof(cl_mem), &ctx->film[FILM_PRIM]},  {sizeof(cl_mem), &ctx->fr_mask},
        {sizeof(cl_mem), &ctx->fr_cur},           {sizeof(cl_mem), &ctx->fr_depth},
        {sizeof(cl_mem), &ctx->fr_normal},        {sizeof(cl_mem), &ctx->fr_prim}};
    if (set_arg_list(ctx->fresh_remember, 0, r, 10, "clSetKernelArg(tr_cl_fresh_remember)", err) !=
        TR_OK) {
        clFinish(ctx->queue);
        return TR_ERR;
    }
    rc = clEnqueueNDRangeKernel(ctx->queue, ctx->fresh_remember, 2, NULL, global, NULL, 0, NULL,
                                NULL);
    if (rc == CL_SUCCESS) {
        rc = clFinish(ctx->queue);
    }
    if (rc != CL_SUCCESS) {
        return cl_fail(err, "the fresh samples' frame", rc);
    }
    /* This frame's points are the next call's previous ones. */
    cl_mem t = ctx->fr_point;
    ctx->fr_point = ctx->fr_cur;
    ctx->fr_cur = t;
    *fresh = count;
    return TR_OK;
}

/* ---- pt as a wavefront (entry.cl's tr_cl_wf_*, src/kernel/integrator_pt_wf.h) ------- */

/* The kernel TR_OPENCL_KERNEL_AUTO runs pt with, by device type (CL_DEVICE_TYPE): the one
 * place the rule is written. Types not listed run the megakernel. */
static const struct {
    const char *type;
    int kernel;
} wf_auto_rule[] = {
    /* Not yet measured on a GPU (docs/gpu.md says what to measure): the megakernel,
     * measured on the H100, until the wavefront's figures are beside it. */
    {"gpu", TR_OPENCL_KERNEL_MEGA},
    /* PoCL: a work item per path already runs whole paths on a core; the stages only add
     * passes over the path states in memory. */
    {"cpu", TR_OPENCL_KERNEL_MEGA},
};

static const char kernel_env[] = "TRAC0R_OPENCL_KERNEL";
/* The most paths in flight (default TR_CL_WF_MAX_PATHS): for measuring the wavefront's
 * chunk size, and for the tests, whose frames are smaller than one chunk. */
static const char paths_env[] = "TRAC0R_OPENCL_WAVEFRONT_PATHS";

/* Paths in flight at most: a 1920x1080 frame's samples in one chunk (380 bytes of state
 * each); fewer where the device allocates less per buffer. */
#define TR_CL_WF_MAX_PATHS ((size_t)1 << 21)

/* Work items per group for the stages (fewer where a kernel allows fewer). */
#define TR_CL_WF_GROUP 64u

int tr_cl_set_kernel(tr_cl_context *ctx, int kernel, tr_error *err) {
    if (kernel < TR_OPENCL_KERNEL_AUTO || kernel > TR_OPENCL_KERNEL_WAVEFRONT) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "OpenCL kernel %d is none of auto (0), mega (1) and wavefront (2)",
                            kernel);
    }
    if (kernel == TR_OPENCL_KERNEL_WAVEFRONT &&
        need_part(ctx, TR_CL_PART_WAVEFRONT, err) != TR_OK) {
        return TR_ERR;
    }
    if (kernel == TR_OPENCL_KERNEL_WAVEFRONT && !ctx->wf_generate) {
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "the wavefront path tracer is not in this OpenCL program");
    }
    ctx->kernel_request = kernel;
    return TR_OK;
}

int tr_cl_frame_kernel(const tr_cl_context *ctx, int integrator) {
    /* The kernel source's wavefront is built when first run (need_part). */
    if (integrator != TR_INTEGRATOR_PT || (ctx->custom && !ctx->wf_generate)) {
        return TR_OPENCL_KERNEL_MEGA;
    }
    if (ctx->kernel_request != TR_OPENCL_KERNEL_AUTO) {
        return ctx->kernel_request;
    }
    if (ctx->kernel_env != TR_OPENCL_KERNEL_AUTO) {
        return ctx->kernel_env;
    }
    for (size_t i = 0; i < sizeof wf_auto_rule / sizeof wf_auto_rule[0]; ++i) {
        if (strcmp(ctx->info.type, wf_auto_rule[i].type) == 0) {
            return wf_auto_rule[i].kernel;
        }
    }
    return TR_OPENCL_KERNEL_MEGA;
}

/* Reads TRAC0R_OPENCL_KERNEL and TRAC0R_OPENCL_WAVEFRONT_PATHS. */
static int wf_open(tr_cl_context *ctx, tr_error *err) {
    const char *env = getenv(kernel_env);
    ctx->kernel_env = env && *env ? tr_opencl_kernel_from_name(env) : TR_OPENCL_KERNEL_AUTO;
    if (ctx->kernel_env < 0) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "%s='%s' is none of mega, wavefront and auto", kernel_env, env);
    }
    const char *paths = getenv(paths_env);
    if (paths && *paths) {
        int64_t v = 0;
        if (tr_parse_int64(paths, 1, (int64_t)1 << 28, &v) != TR_OK) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "%s='%s' is not a number of paths in 1..268435456", paths_env,
                                paths);
        }
        ctx->wf_max = (size_t)v;
    }
    return TR_OK;
}

/* Creates the stages' kernels from prog. A program of the tests' own (custom) may lack
 * them: it runs the megakernel only. */
static int wf_create(tr_cl_context *ctx, cl_program prog, int custom, tr_error *err) {
    static const char *const names[5] = {"tr_cl_wf_generate", "tr_cl_wf_extend", "tr_cl_wf_shade",
                                         "tr_cl_wf_connect", "tr_cl_wf_accumulate"};
    cl_kernel *kernels[5] = {&ctx->wf_generate, &ctx->wf_extend, &ctx->wf_shade, &ctx->wf_connect,
                             &ctx->wf_accumulate};
    for (int i = 0; i < 5; ++i) {
        cl_int rc;
        *kernels[i] = clCreateKernel(prog, names[i], &rc);
        if (!*kernels[i]) {
            wf_release(ctx);
            if (custom) {
                return TR_OK;
            }
            char call[64];
            snprintf(call, sizeof call, "clCreateKernel(%s)", names[i]);
            return cl_fail(err, call, rc);
        }
    }
    ctx->wf_group = TR_CL_WF_GROUP;
    for (int i = 0; i < 5; ++i) {
        size_t max = 0;
        if (clGetKernelWorkGroupInfo(*kernels[i], ctx->device, CL_KERNEL_WORK_GROUP_SIZE,
                                     sizeof max, &max, NULL) == CL_SUCCESS &&
            max >= 1 && max < ctx->wf_group) {
            ctx->wf_group = max;
        }
    }
    return TR_OK;
}

static void wf_release_buffers(tr_cl_context *ctx) {
    cl_mem *bufs[5] = {&ctx->wf_paths, &ctx->wf_queue[0], &ctx->wf_queue[1], &ctx->wf_shadow,
                       &ctx->wf_counters};
    for (int i = 0; i < 5; ++i) {
        if (*bufs[i]) {
            clReleaseMemObject(*bufs[i]);
            *bufs[i] = NULL;
        }
    }
    ctx->wf_cap = 0;
}

static void wf_release(tr_cl_context *ctx) {
    cl_kernel *kernels[5] = {&ctx->wf_generate, &ctx->wf_extend, &ctx->wf_shade, &ctx->wf_connect,
                             &ctx->wf_accumulate};
    for (int i = 0; i < 5; ++i) {
        if (*kernels[i]) {
            clReleaseKernel(*kernels[i]);
            *kernels[i] = NULL;
        }
    }
    wf_release_buffers(ctx);
}

/* The scene's arrays and scene_info as the first arguments of extend, shade and connect. */
static int wf_set_scene(tr_cl_context *ctx, tr_error *err) {
    const cl_kernel kernels[3] = {ctx->wf_extend, ctx->wf_shade, ctx->wf_connect};
    const int na = ctx->array_count;
    for (int k = 0; k < 3 && kernels[k]; ++k) {
        for (int i = 0; i <= na; ++i) {
            const cl_mem *m = i < na ? &ctx->arrays[i] : &ctx->scene_info;
            cl_int rc = clSetKernelArg(kernels[k], (cl_uint)i, sizeof(cl_mem), m);
            if (rc != CL_SUCCESS) {
                return cl_fail(err, "clSetKernelArg(wavefront scene)", rc);
            }
        }
    }
    return TR_OK;
}

/* Room for `paths` paths and their queues. */
static int wf_buffers(tr_cl_context *ctx, size_t paths, tr_error *err) {
    if (ctx->wf_cap >= paths) {
        return TR_OK;
    }
    wf_release_buffers(ctx);
    const size_t sizes[5] = {paths * sizeof(tr_pt_wf_path), paths * sizeof(cl_uint),
                             paths * sizeof(cl_uint), paths * sizeof(cl_uint), 2 * sizeof(cl_uint)};
    cl_mem *bufs[5] = {&ctx->wf_paths, &ctx->wf_queue[0], &ctx->wf_queue[1], &ctx->wf_shadow,
                       &ctx->wf_counters};
    for (int i = 0; i < 5; ++i) {
        cl_int rc;
        *bufs[i] = clCreateBuffer(ctx->context, CL_MEM_READ_WRITE, sizes[i], NULL, &rc);
        if (!*bufs[i]) {
            wf_release_buffers(ctx);
            return cl_fail(err, "clCreateBuffer(wavefront paths)", rc);
        }
    }
    ctx->wf_cap = paths;
    return TR_OK;
}

/* Sets `n` arguments of kernel k from `first` on: (size, pointer) pairs. */
typedef struct wf_arg {
    size_t size;
    const void *ptr;
} wf_arg;

static int wf_run(tr_cl_context *ctx, cl_kernel k, const char *name, cl_uint first,
                  const wf_arg *args, int n, size_t items, tr_error *err) {
    for (int i = 0; i < n; ++i) {
        cl_int rc = clSetKernelArg(k, first + (cl_uint)i, args[i].size, args[i].ptr);
        if (rc != CL_SUCCESS) {
            char call[80];
            snprintf(call, sizeof call, "clSetKernelArg(%s)", name);
            return cl_fail(err, call, rc);
        }
    }
    if (items == 0) {
        return TR_OK;
    }
    /* Whole groups of one size (the kernels return at once past their count): the queues'
     * lengths change from bounce to bounce, and a driver left to choose picks a group size
     * per length; PoCL compiles the kernel anew for each (seconds each time). */
    const size_t local = ctx->wf_group;
    const size_t global = (items + local - 1) / local * local;
    cl_int rc = clEnqueueNDRangeKernel(ctx->queue, k, 1, NULL, &global, &local, 0, NULL, NULL);
    if (rc != CL_SUCCESS) {
        char call[80];
        snprintf(call, sizeof call, "clEnqueueNDRangeKernel(%s)", name);
        return cl_fail(err, call, rc);
    }
    return TR_OK;
}

/* One chunk: paths [0, g_n * k), path i being sample f->sample + s_off + i % k of grid
 * point g0 + i / k, from the camera to the film. */
static int wf_chunk(tr_cl_context *ctx, const tr_frame *f, cl_uint g0, cl_uint g_n, cl_uint k,
                    cl_uint s_off, tr_error *err) {
    const cl_uint n = g_n * k;
    const wf_arg gen[] = {{sizeof(cl_mem), &ctx->frame},
                          {sizeof(cl_mem), &ctx->wf_paths},
                          {sizeof(cl_mem), &ctx->wf_queue[0]},
                          {sizeof g0, &g0},
                          {sizeof k, &k},
                          {sizeof s_off, &s_off},
                          {sizeof n, &n}};
    if (wf_run(ctx, ctx->wf_generate, "tr_cl_wf_generate", 0, gen, 7, n, err) != TR_OK) {
        return TR_ERR;
    }
    const cl_uint base = (cl_uint)ctx->array_count + 1u; /* after the scene and scene_info */
    cl_uint count = f->max_depth >= 1 ? n : 0u;
    int cur = 0;
    while (count > 0u) {
        const cl_uint zero = 0;
        cl_int rc = clEnqueueFillBuffer(ctx->queue, ctx->wf_counters, &zero, sizeof zero, 0,
                                        2 * sizeof zero, 0, NULL, NULL);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueFillBuffer(wavefront counters)", rc);
        }
        const wf_arg ext[] = {{sizeof(cl_mem), &ctx->wf_paths},
                              {sizeof(cl_mem), &ctx->wf_queue[cur]},
                              {sizeof count, &count}};
        const wf_arg sh[] = {{sizeof(cl_mem), &ctx->frame},
                             {sizeof(cl_mem), &ctx->wf_paths},
                             {sizeof(cl_mem), &ctx->wf_queue[cur]},
                             {sizeof count, &count},
                             {sizeof(cl_mem), &ctx->wf_queue[1 - cur]},
                             {sizeof(cl_mem), &ctx->wf_shadow},
                             {sizeof(cl_mem), &ctx->wf_counters}};
        const wf_arg con[] = {{sizeof(cl_mem), &ctx->frame},
                              {sizeof(cl_mem), &ctx->wf_paths},
                              {sizeof(cl_mem), &ctx->wf_shadow},
                              {sizeof(cl_mem), &ctx->wf_counters}};
        /* Connect runs over the shadow queue, at most `count` paths long. */
        if (wf_run(ctx, ctx->wf_extend, "tr_cl_wf_extend", base, ext, 3, count, err) != TR_OK ||
            wf_run(ctx, ctx->wf_shade, "tr_cl_wf_shade", base, sh, 7, count, err) != TR_OK ||
            wf_run(ctx, ctx->wf_connect, "tr_cl_wf_connect", base, con, 4, count, err) != TR_OK) {
            return TR_ERR;
        }
        rc = clEnqueueReadBuffer(ctx->queue, ctx->wf_counters, CL_TRUE, 0, sizeof count, &count, 0,
                                 NULL, NULL);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueReadBuffer(wavefront counters)", rc);
        }
        cur = 1 - cur;
    }
    wf_arg acc[FILM_BUFFERS + 6];
    int na = 0;
    acc[na++] = (wf_arg){sizeof(cl_mem), &ctx->frame};
    for (int i = 0; i < FILM_BUFFERS; ++i) {
        acc[na++] = (wf_arg){sizeof(cl_mem), &ctx->film[i]};
    }
    acc[na++] = (wf_arg){sizeof(cl_mem), &ctx->rays};
    acc[na++] = (wf_arg){sizeof(cl_mem), &ctx->wf_paths};
    acc[na++] = (wf_arg){sizeof g0, &g0};
    acc[na++] = (wf_arg){sizeof k, &k};
    acc[na++] = (wf_arg){sizeof g_n, &g_n};
    return wf_run(ctx, ctx->wf_accumulate, "tr_cl_wf_accumulate", 0, acc, na, g_n, err);
}

/* Frame f through the stages, in chunks of at most wf_cap paths: all the grid's points
 * with as many samples as fit, or a run of points with one sample; the chunks go sample
 * range by sample range, so every pixel receives its samples in order. */
static int wf_render(tr_cl_context *ctx, const tr_frame *f, uint32_t ny, uint64_t *rays_out,
                     tr_error *err) {
    uint32_t gx0, gy0, nx, ny_grid;
    tr_frame_grid(f, &gx0, &gy0, &nx, &ny_grid);
    const size_t points = (size_t)nx * ny_grid, samples = f->sample_count;
    size_t cap = ctx->wf_max ? ctx->wf_max : TR_CL_WF_MAX_PATHS;
    const size_t fit = ctx->info.max_alloc / sizeof(tr_pt_wf_path);
    if (fit > 0 && fit < cap) {
        cap = fit;
    }
    /* The paths and their three queues share the device's memory with the scene and the
     * film (the memory check's budget): fewer paths in flight where they would not fit. */
    const uint64_t used = ctx->scene_bytes + tr_cl_film_bytes(ctx);
    const uint64_t left = memory_budget(ctx) > used ? memory_budget(ctx) - used : 0;
    const uint64_t per_path = tr_cl_wavefront_path_bytes();
    if (left / per_path < cap) {
        cap = (size_t)(left / per_path);
        if (cap < ctx->wf_group) {
            return tr_error_set(err, TR_STATUS_LIMIT,
                                "the wavefront's paths do not fit on OpenCL device %d (%s) next "
                                "to the scene and the film (%.1f MiB left of %.1f MiB)",
                                ctx->info.index, ctx->info.name, mib(left),
                                mib(memory_budget(ctx)));
        }
    }
    if (points * samples < cap) {
        cap = points * samples;
    }
    if (points == 0 || samples == 0) {
        cap = 0;
    } else if (wf_buffers(ctx, cap, err) != TR_OK) {
        return TR_ERR;
    }
    const size_t k = cap == 0                  ? 0
                     : points * samples <= cap ? samples
                     : cap / points            ? cap / points
                                               : 1;
    const size_t g_step = k ? cap / k : 0;
    for (size_t s = 0; s < samples && k; s += k) {
        const size_t kk = samples - s < k ? samples - s : k;
        for (size_t g = 0; g < points; g += g_step) {
            const size_t gn = points - g < g_step ? points - g : g_step;
            if (wf_chunk(ctx, f, (cl_uint)g, (cl_uint)gn, (cl_uint)kk, (cl_uint)s, err) != TR_OK) {
                return TR_ERR;
            }
        }
    }
    return read_rays(ctx, ny, rays_out, err);
}

#endif
