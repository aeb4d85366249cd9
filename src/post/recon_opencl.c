/* recon_opencl.c - tr_recon_device (include/trac0r/recon_device.h): tr_recon_frame's
 * stages where the frame was rendered. On an OpenCL device, the program of
 * src/post/recon.cl (embedded as tr_cl_recon_source) is built in the device's context
 * and its kernels run on the device's film and on history kept on the device, in the
 * order and with the parameters filter.c uses; on the CPU, filter.c itself. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "device/opencl.h"
#include "post/dfg.h"
#include "post/recon_params.h"
#include "post/recon_upscale.h"
#include "trac0r/film.h"
#include "trac0r/post.h"
#include "trac0r/recon_device.h"
#include "trac0r/render.h"
#include "trac0r/upscale.h"

#ifdef TRAC0R_HAVE_OPENCL
#define CL_TARGET_OPENCL_VERSION 120
#include <CL/cl.h>

extern const char tr_cl_recon_source[];
extern const size_t tr_cl_recon_source_length;

enum {
    K_FROM_FILM = 0,
    K_MODULATE,
    K_TEMPORAL,
    K_BILATERAL,
    K_ATROUS,
    K_SVGF_VARIANCE,
    K_SVGF,
    K_TAA,
    K_ADD,
    K_UPSCALE,
    K_SPEC_PREPARE,
    K_SPEC_TEMPORAL,
    K_COUNT
};
static const char *const kernel_names[K_COUNT] = {
    "tr_recon_from_film", "tr_recon_modulate",     "tr_recon_temporal",
    "tr_recon_bilateral", "tr_recon_atrous",       "tr_recon_svgf_variance",
    "tr_recon_svgf",      "tr_recon_taa",          "tr_recon_add",
    "tr_recon_upscale",   "tr_recon_spec_prepare", "tr_recon_spec_temporal"};

/* The device's buffers: the frame (as tr_gbuffer), scratch, history, the two cameras. */
enum {
    B_COLOR = 0,
    B_ALBEDO,
    B_NORMAL,
    B_DEPTH,
    B_PRIM,
    B_ILLUM,
    B_HC0, /* history colour, moments and length, two of each (this frame's, the last) */
    B_HC1,
    B_HM0,
    B_HM1,
    B_HL0,
    B_HL1,
    B_HDEPTH, /* the geometry the history was seen with */
    B_HNORMAL,
    B_HPRIM,
    B_CA, /* filter ping, pong */
    B_CB,
    B_VA, /* SVGF's variance ping, pong */
    B_VB,
    B_OUT,
    B_TAA,  /* SVGF's last output */
    B_EMIS, /* the frame's own emission (TR_PASS_EMISSION) */
    B_HA0,  /* the albedo history (albedo_alpha), two */
    B_HA1,
    B_CAMS,
    B_COUNT
};
enum { SP_DIRECT = 0, SP_ILLUM, SP_HD0, SP_HD1, SP_HDM0, SP_HDM1, SP_COUNT };
static const int split_elems[SP_COUNT] = {3, 3, 3, 3, 2, 2};
/* Diffuse and specular apart (svgf_specular): the frame's specular pass (8 floats), its
 * specular albedo, specular light and diffuse colour, the specular histories (colour,
 * moments, lengths; two of each) and the DFG table (dfg.h). */
enum {
    SS_PASS = 0,
    SS_ALBEDO,
    SS_ILLUM,
    SS_DIFFUSE,
    SS_HS0,
    SS_HS1,
    SS_HSM0,
    SS_HSM1,
    SS_HSL0,
    SS_HSL1,
    SS_DFG,
    SS_COUNT
};
static const int spec_elems[SS_COUNT] = {8, 3, 3, 3, 3, 3, 2, 2, 1, 1, 0};
/* Floats (or uints) per pixel of each buffer; 0: the cameras. */
static const int buffer_elems[B_COUNT] = {3, 3, 3, 1, 1, 3, 3, 3, 2, 2, 1, 1, 1,
                                          3, 1, 3, 3, 1, 1, 3, 3, 3, 3, 3, 0};

typedef struct recon_cl {
    cl_context context;
    cl_command_queue queue;
    cl_program program;
    cl_kernel k[K_COUNT];
    cl_mem b[B_COUNT];
    cl_mem motion; /* the primitives' motion (tr_recon_frame_moving) */
    size_t motion_cap;
    tr_camera prev_cam;
    int have_history, cur, have_taa;
    int have_albedo;  /* B_HA0 + cur holds the last frame's albedo history */
    int has_emission; /* the frame came from a film with the emission pass */
    int result;       /* the buffer holding the last frame's reconstruction */
    /* Direct and indirect light apart (svgf_split): the frame's direct pass, its
     * demodulated light and the direct histories (colour, moments; two of each), made when
     * a frame first has the pass. The history's lengths are the sum's. */
    cl_mem sp[SP_COUNT];
    int has_direct;      /* the frame in the buffers has its direct pass in sp[SP_DIRECT] */
    int hist_split;      /* the history was kept with direct and indirect apart */
    cl_mem ss[SS_COUNT]; /* made when a frame first has the specular pass */
    int has_specular;    /* the frame in the buffers has its specular pass in ss[SS_PASS] */
    cl_mem len_cap;      /* the temporal gradients' history caps of the frame, or NULL */
    int hist_spec;       /* the history was kept with diffuse and specular apart */
    int modulated;       /* the albedo buffer it was multiplied by */
    cl_mem added;        /* the emission the reconstruction added to it (NULL: none) */
    /* Temporal upscaling (tr_recon_device_upscale): the output's history (colour, samples,
     * distance, two of each), its first hits' emission (this frame's and the last), the
     * output, the samples' positions and the two cameras, for up_w x up_h outputs. */
    cl_mem up_col[2], up_len[2], up_depth[2], up_emis[2], up_out, up_pos, up_cams, up_alb;
    float *up_low; /* the frame's albedo pass read back (upscale_albedo), up_low_len floats */
    size_t up_low_len;
    uint32_t up_w, up_h;
    int up_cur, up_have, emis_cur, emis_have;
    tr_camera up_prev;
} recon_cl;
#else
typedef struct recon_cl recon_cl;
#endif

struct tr_recon_device {
    tr_device *dev;
    uint32_t width, height;
    double ms_temporal, ms_spatial;
    recon_cl *cl; /* NULL: the host's tr_recon below */
    tr_recon host;
    tr_gbuffer gb;
    tr_film film;
};

static int check_args(const tr_recon_device *r, const tr_camera *cam, int method, tr_error *err) {
    if (!tr_recon_name(method)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "reconstruction: unknown method %d",
                            method);
    }
    if (cam->screen_width != r->width || cam->screen_height != r->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "reconstruction: a %ux%u camera for a %ux%u state", cam->screen_width,
                            cam->screen_height, r->width, r->height);
    }
    return TR_OK;
}

#ifdef TRAC0R_HAVE_OPENCL
static int cl_fail(tr_error *err, const char *call, cl_int code) {
    return tr_error_set(err, TR_STATUS_DEVICE, "OpenCL reconstruction: %s failed: %s (%d)", call,
                        tr_cl_error_name(code), code);
}

/* The upscaling's buffers. */
static void up_release(recon_cl *c) {
    cl_mem *const m[12] = {&c->up_col[0],   &c->up_col[1],   &c->up_len[0],  &c->up_len[1],
                           &c->up_depth[0], &c->up_depth[1], &c->up_emis[0], &c->up_emis[1],
                           &c->up_out,      &c->up_pos,      &c->up_cams,    &c->up_alb};
    for (int i = 0; i < 12; ++i) {
        if (*m[i]) {
            clReleaseMemObject(*m[i]);
            *m[i] = NULL;
        }
    }
    c->up_w = c->up_h = 0;
    c->up_have = c->emis_have = 0;
}

static void cl_state_free(recon_cl *c) {
    if (!c) {
        return;
    }
    for (int i = 0; i < B_COUNT; ++i) {
        if (c->b[i]) {
            clReleaseMemObject(c->b[i]);
        }
    }
    if (c->motion) {
        clReleaseMemObject(c->motion);
    }
    for (int i = 0; i < SP_COUNT; ++i) {
        if (c->sp[i]) {
            clReleaseMemObject(c->sp[i]);
        }
    }
    for (int i = 0; i < SS_COUNT; ++i) {
        if (c->ss[i]) {
            clReleaseMemObject(c->ss[i]);
        }
    }
    up_release(c);
    free(c->up_low);
    for (int i = 0; i < K_COUNT; ++i) {
        if (c->k[i]) {
            clReleaseKernel(c->k[i]);
        }
    }
    if (c->program) {
        clReleaseProgram(c->program);
    }
    if (c->queue) {
        clReleaseCommandQueue(c->queue);
    }
    if (c->context) {
        clReleaseContext(c->context);
    }
    free(c);
}

/* The program built for the device of h with the render kernel's options (FP_CONTRACT
 * off in recon.cl) and divisions and square roots correctly rounded wherever the device
 * can, GPUs included (the render kernel asks for that on CPU devices only), so that it
 * computes what the host's filters compute: on an H100 the filters' approximate
 * division changed SVGF's output by 3e-3 (relative), and rounding correctly costs the
 * memory-bound filters nothing measurable. */
static recon_cl *cl_state_open(const tr_cl_handles *h, uint32_t w, uint32_t ht, tr_error *err) {
    recon_cl *c = calloc(1, sizeof *c);
    if (!c) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a reconstruction");
        return NULL;
    }
    c->context = (cl_context)h->context;
    c->queue = (cl_command_queue)h->queue;
    clRetainContext(c->context);
    clRetainCommandQueue(c->queue);
    cl_device_id dev = (cl_device_id)h->device;
    cl_int rc;
    const char *src = tr_cl_recon_source;
    const size_t len = tr_cl_recon_source_length;
    c->program = clCreateProgramWithSource(c->context, 1, &src, &len, &rc);
    if (!c->program) {
        cl_fail(err, "clCreateProgramWithSource", rc);
        goto fail;
    }
    static const char rounded[] = "-cl-fp32-correctly-rounded-divide-sqrt";
    cl_device_fp_config fp = 0;
    clGetDeviceInfo(dev, CL_DEVICE_SINGLE_FP_CONFIG, sizeof fp, &fp, NULL);
    const int add = (fp & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT) && !strstr(h->options, rounded);
    char options[320];
    snprintf(options, sizeof options, "%s%s%s", h->options, add ? " " : "", add ? rounded : "");
    rc = clBuildProgram(c->program, 1, &dev, options, NULL, NULL);
    if (rc != CL_SUCCESS) {
        char log[4096] = "";
        clGetProgramBuildInfo(c->program, dev, CL_PROGRAM_BUILD_LOG, sizeof log - 1, log, NULL);
        tr_error_set(err, TR_STATUS_DEVICE,
                     "OpenCL reconstruction: clBuildProgram failed: %s (%d); build log: %s",
                     tr_cl_error_name(rc), rc, log);
        goto fail;
    }
    for (int i = 0; i < K_COUNT; ++i) {
        c->k[i] = clCreateKernel(c->program, kernel_names[i], &rc);
        if (!c->k[i]) {
            cl_fail(err, kernel_names[i], rc);
            goto fail;
        }
    }
    const size_t n = (size_t)w * ht;
    for (int i = 0; i < B_COUNT; ++i) {
        const size_t bytes =
            buffer_elems[i] ? n * (size_t)buffer_elems[i] * sizeof(float) : 2 * sizeof(tr_camera);
        c->b[i] = clCreateBuffer(c->context, CL_MEM_READ_WRITE, bytes, NULL, &rc);
        if (!c->b[i]) {
            tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                         "OpenCL reconstruction: no device memory for a %ux%u frame: "
                         "clCreateBuffer failed: %s (%d)",
                         w, ht, tr_cl_error_name(rc), rc);
            goto fail;
        }
    }
    return c;
fail:
    cl_state_free(c);
    return NULL;
}

/* Kernel arguments: a buffer, or a value of its own size. */
typedef struct karg {
    size_t size;
    const void *ptr;
} karg;
#define KB(c, i) ((karg){sizeof(cl_mem), &(c)->b[i]})
#define KM(m) ((karg){sizeof(cl_mem), &(m)})
#define KI(v) ((karg){sizeof(cl_int), &(cl_int){(v)}})
#define KU(v) ((karg){sizeof(cl_uint), &(cl_uint){(v)}})
#define KF(v) ((karg){sizeof(cl_float), &(cl_float){(v)}})

/* Sets kernel k's n arguments and runs it over w x h pixels. */
static int run(recon_cl *c, int k, int w, int h, int n, const karg *a, tr_error *err) {
    for (int i = 0; i < n; ++i) {
        const cl_int rc = clSetKernelArg(c->k[k], (cl_uint)i, a[i].size, a[i].ptr);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, kernel_names[k], rc);
        }
    }
    const size_t global[2] = {(size_t)w, (size_t)h};
    const cl_int rc =
        clEnqueueNDRangeKernel(c->queue, c->k[k], 2, NULL, global, NULL, 0, NULL, NULL);
    return rc == CL_SUCCESS ? TR_OK : cl_fail(err, kernel_names[k], rc);
}
#define RUN(c, k, w, h, err, ...)                                                                  \
    run(c, k, w, h, (int)(sizeof((karg[]){__VA_ARGS__}) / sizeof(karg)), (karg[]){__VA_ARGS__}, err)

static int copy_mem(recon_cl *c, cl_mem from, cl_mem to, size_t bytes, tr_error *err) {
    const cl_int rc = clEnqueueCopyBuffer(c->queue, from, to, 0, 0, bytes, 0, NULL, NULL);
    return rc == CL_SUCCESS ? TR_OK : cl_fail(err, "clEnqueueCopyBuffer", rc);
}

static int copy(recon_cl *c, int from, int to, size_t bytes, tr_error *err) {
    return copy_mem(c, c->b[from], c->b[to], bytes, err);
}

/* SVGF on one illumination history `hist` (moments `mom`, lengths `len`), as the host's
 * svgf_part: the variance, the iterations (the first one's output fed back into hist
 * with svgf_feedback), remodulated by `albedo` into b[res], or added to it when add. */
static int svgf_part(recon_cl *c, int w, int h, cl_mem hist, cl_mem mom, cl_mem len,
                     const tr_recon_params *p, cl_mem albedo, int res, int add, tr_error *err) {
    const size_t n = (size_t)w * h;
    int rc = RUN(c, K_SVGF_VARIANCE, w, h, err, KM(hist), KM(mom), KM(len), KB(c, B_NORMAL), KI(w),
                 KI(h), KB(c, B_VA));
    cl_mem src = hist;
    int dst = B_CA, vs = B_VA, vd = B_VB;
    for (int it = 0; rc == TR_OK && it < p->svgf_iterations; ++it) {
        rc = RUN(c, K_SVGF, w, h, err, KM(src), KB(c, vs), KB(c, B_NORMAL), KB(c, B_DEPTH), KI(w),
                 KI(h), KI(1 << it), KF(p->svgf_sigma_l), KF(p->svgf_sigma_n), KF(p->svgf_sigma_z),
                 KB(c, dst), KB(c, vd));
        /* Schied et al. feed the first iteration's output back as the history. */
        if (rc == TR_OK && it == 0 && p->svgf_feedback) {
            rc = copy_mem(c, c->b[dst], hist, 3 * n * sizeof(float), err);
        }
        src = c->b[dst];
        dst = dst == B_CA ? B_CB : B_CA; /* now the one src is not */
        const int t = vs;
        vs = vd;
        vd = t;
    }
    if (rc != TR_OK) {
        return rc;
    }
    if (!add) {
        return RUN(c, K_MODULATE, w, h, err, KM(src), KM(albedo), KI(1), KI(w), KI(h), KB(c, res));
    }
    rc = RUN(c, K_MODULATE, w, h, err, KM(src), KM(albedo), KI(1), KI(w), KI(h), KB(c, dst));
    return rc ? rc : RUN(c, K_ADD, w, h, err, KB(c, res), KB(c, dst), KF(1.0f), KI(w), KI(h));
}

static int finish(recon_cl *c, tr_error *err) {
    const cl_int rc = clFinish(c->queue);
    return rc == CL_SUCCESS ? TR_OK : cl_fail(err, "clFinish", rc);
}

/* The split's buffers (recon_cl.sp), made once. */
static int split_buffers(recon_cl *c, size_t n, tr_error *err) {
    for (int i = 0; i < SP_COUNT; ++i) {
        if (c->sp[i]) {
            continue;
        }
        cl_int rc;
        c->sp[i] = clCreateBuffer(c->context, CL_MEM_READ_WRITE,
                                  n * (size_t)split_elems[i] * sizeof(float), NULL, &rc);
        if (!c->sp[i]) {
            return cl_fail(err, "clCreateBuffer(direct light)", rc);
        }
    }
    return TR_OK;
}

/* The specular split's buffers (recon_cl.ss), made once; the DFG table uploaded with them. */
static int spec_buffers(recon_cl *c, size_t n, tr_error *err) {
    for (int i = 0; i < SS_COUNT; ++i) {
        if (c->ss[i]) {
            continue;
        }
        const size_t bytes = i == SS_DFG ? 2 * TR_DFG_N * TR_DFG_N * sizeof(float)
                                         : n * (size_t)spec_elems[i] * sizeof(float);
        cl_int rc;
        c->ss[i] = clCreateBuffer(c->context, CL_MEM_READ_WRITE, bytes, NULL, &rc);
        if (!c->ss[i]) {
            return cl_fail(err, "clCreateBuffer(specular light)", rc);
        }
        if (i == SS_DFG) {
            rc = clEnqueueWriteBuffer(c->queue, c->ss[i], CL_TRUE, 0, bytes, tr_post_dfg_table(), 0,
                                      NULL, NULL);
            if (rc != CL_SUCCESS) {
                clReleaseMemObject(c->ss[i]);
                c->ss[i] = NULL;
                return cl_fail(err, "clEnqueueWriteBuffer(DFG table)", rc);
            }
        }
    }
    return TR_OK;
}

/* The device's film into the frame's buffers. */
static int cl_from_film(tr_recon_device *r, tr_error *err) {
    tr_cl_handles h;
    if (tr_cl_get_handles(tr_device_cl_context(r->dev), &h, err) != TR_OK) {
        return TR_ERR;
    }
    if (!h.film[0] || h.width != r->width || h.height != r->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "reconstruction: the device's film is %ux%u, the state %ux%u", h.width,
                            h.height, r->width, r->height);
    }
    const cl_uint passes =
        ((h.passes & TR_PASS_ALBEDO) ? 1u : 0u) | ((h.passes & TR_PASS_NORMAL) ? 2u : 0u) |
        ((h.passes & TR_PASS_DEPTH) ? 4u : 0u) | ((h.passes & TR_PASS_PRIM) ? 8u : 0u) |
        ((h.passes & TR_PASS_EMISSION) ? 16u : 0u) | ((h.passes & TR_PASS_DIRECT) ? 32u : 0u) |
        ((h.passes & TR_PASS_SPECULAR) ? 64u : 0u);
    cl_mem f[9];
    for (int i = 0; i < 6; ++i) {
        f[i] = (cl_mem)h.film[i];
    }
    f[6] = (cl_mem)h.emission;
    f[7] = (cl_mem)h.direct;
    f[8] = (cl_mem)h.specular;
    recon_cl *c = r->cl;
    c->has_emission = (h.passes & TR_PASS_EMISSION) != 0u;
    c->has_direct = (h.passes & TR_PASS_DIRECT) != 0u;
    c->has_specular = (h.passes & TR_PASS_SPECULAR) != 0u;
    c->len_cap = (cl_mem)h.grad_cap;
    const int w = (int)r->width, ht = (int)r->height;
    if ((c->has_direct && split_buffers(c, (size_t)w * ht, err) != TR_OK) ||
        (c->has_specular && spec_buffers(c, (size_t)w * ht, err) != TR_OK)) {
        return TR_ERR;
    }
    /* Without a pass nothing is written to its buffer: any one stands in. */
    const cl_mem direct = c->has_direct ? c->sp[SP_DIRECT] : c->b[B_ILLUM];
    const cl_mem specular = c->has_specular ? c->ss[SS_PASS] : c->b[B_ILLUM];
    return RUN(c, K_FROM_FILM, w, ht, err, KM(f[0]), KM(f[1]), KM(f[2]), KM(f[3]), KM(f[4]),
               KM(f[5]), KM(f[6]), KM(f[7]), KM(f[8]), KU(passes), KI(w), KI(ht), KB(c, B_COLOR),
               KB(c, B_ALBEDO), KB(c, B_NORMAL), KB(c, B_DEPTH), KB(c, B_PRIM), KB(c, B_EMIS),
               KM(direct), KM(specular));
}

static int cl_upload(tr_recon_device *r, const tr_gbuffer *g, tr_error *err) {
    const size_t n = (size_t)r->width * r->height;
    recon_cl *c = r->cl;
    c->has_direct = g->has_direct;     /* for svgf_split */
    c->has_specular = g->has_specular; /* for svgf_specular */
    c->len_cap = NULL;                 /* the host's frame brings no gradients */
    if ((g->has_direct && split_buffers(c, n, err) != TR_OK) ||
        (g->has_specular && spec_buffers(c, n, err) != TR_OK)) {
        return TR_ERR;
    }
    /* The frame's buffers, then its direct and specular passes where it has them. */
    const cl_mem dst[7] = {c->b[B_COLOR],
                           c->b[B_ALBEDO],
                           c->b[B_NORMAL],
                           c->b[B_DEPTH],
                           c->b[B_PRIM],
                           g->has_direct ? c->sp[SP_DIRECT] : NULL,
                           g->has_specular ? c->ss[SS_PASS] : NULL};
    const void *src[7] = {g->color, g->albedo, g->normal,  g->depth,
                          g->prim,  g->direct, g->specular};
    const size_t bytes[7] = {3 * n * 4, 3 * n * 4, 3 * n * 4, n * 4, n * 4, 3 * n * 4, 8 * n * 4};
    for (int i = 0; i < 7; ++i) {
        if (!dst[i]) {
            continue;
        }
        const cl_int rc =
            clEnqueueWriteBuffer(c->queue, dst[i], CL_FALSE, 0, bytes[i], src[i], 0, NULL, NULL);
        if (rc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueWriteBuffer", rc);
        }
    }
    /* The host's frame comes with its emission filtered (the device takes no emission
     * from a gbuffer yet). */
    r->cl->has_emission = 0;
    /* The host's arrays may change once this returns. */
    return finish(r->cl, err);
}

/* The primitives' motion onto the device (count 0: none). */
static int cl_motion(recon_cl *c, const tr_vec3 *motion, uint32_t count, tr_error *err) {
    const size_t bytes = (size_t)count * 3 * sizeof(float);
    if (count == 0) {
        return TR_OK;
    }
    if (bytes > c->motion_cap) {
        if (c->motion) {
            clReleaseMemObject(c->motion);
        }
        cl_int rc;
        c->motion_cap = 0;
        c->motion = clCreateBuffer(c->context, CL_MEM_READ_ONLY, bytes, NULL, &rc);
        if (!c->motion) {
            return cl_fail(err, "clCreateBuffer(motion)", rc);
        }
        c->motion_cap = bytes;
    }
    float *flat = malloc(bytes);
    if (!flat) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for %u motions", count);
    }
    for (uint32_t i = 0; i < count; ++i) {
        flat[3 * i] = motion[i].x;
        flat[3 * i + 1] = motion[i].y;
        flat[3 * i + 2] = motion[i].z;
    }
    const cl_int rc =
        clEnqueueWriteBuffer(c->queue, c->motion, CL_TRUE, 0, bytes, flat, 0, NULL, NULL);
    free(flat);
    return rc == CL_SUCCESS ? TR_OK : cl_fail(err, "clEnqueueWriteBuffer(motion)", rc);
}

/* tr_recon_frame's stages (filter.c) on the frame in the device's frame buffers. */
static int cl_frame(tr_recon_device *r, const tr_camera *cam, const tr_vec3 *motion,
                    uint32_t motion_count, int method, const tr_recon_params *p, float *out,
                    tr_error *err) {
    const tr_recon_params resolved = tr_recon_params_for(p, method);
    p = &resolved;
    recon_cl *c = r->cl;
    if (!motion) {
        motion_count = 0;
    }
    if (cl_motion(c, motion, motion_count, err) != TR_OK) {
        return TR_ERR;
    }
    /* Any buffer stands in for the motion when there is none: nothing reads it. */
    cl_mem mbuf = motion_count ? c->motion : c->b[B_DEPTH];
    const int w = (int)r->width, h = (int)r->height;
    const size_t n = (size_t)w * h;
    int rc = TR_OK;
    const double t0 = tr_time_now();
    int result = B_COLOR; /* the buffer read back */
    c->added = NULL;
    c->modulated = B_ALBEDO;
    if (method == TR_RECON_OFF) {
        c->have_history = 0;
        goto read;
    }
    {
        const tr_camera cams[2] = {*cam, c->have_history ? c->prev_cam : *cam};
        cl_int crc = clEnqueueWriteBuffer(c->queue, c->b[B_CAMS], CL_TRUE, 0, sizeof cams, cams, 0,
                                          NULL, NULL);
        if (crc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueWriteBuffer(cameras)", crc);
        }
    }
    const int prev = c->cur, next = 1 - c->cur;
    const int hc = B_HC0 + next, hm = B_HM0 + next, hl = B_HL0 + next;
    /* SVGF with diffuse and specular light apart (the host's spec_prepare and
     * spec_temporal), which replaces direct and indirect apart (Schied et al.'s split; the
     * host's split_illum and direct_temporal); a history kept with another split starts
     * over. */
    const int spec = method == TR_RECON_SVGF && p->svgf_specular && c->has_specular;
    const int split = method == TR_RECON_SVGF && p->svgf_split && c->has_direct && !spec;
    if (c->hist_spec != spec) {
        c->have_history = 0;
    }
    const int hist = c->have_history && c->hist_split == split;
    /* With the emission pass the filters see the colour less the first hit's emission,
     * and the emission comes back after them: resolved over the pixels' area on the
     * device (tr_cl_resolve_emission) where asked for, else the frame's own. */
    cl_mem emis = c->b[B_EMIS];
    if (c->has_emission) {
        if (p->emission_samples > 0) {
            tr_cl_context *ctx = tr_device_cl_context(r->dev);
            tr_cl_handles hd;
            if (tr_cl_resolve_emission(ctx, cam, p->emission_samples, err) != TR_OK ||
                tr_cl_get_handles(ctx, &hd, err) != TR_OK) {
                return TR_ERR;
            }
            emis = (cl_mem)hd.resolved;
        }
        rc = RUN(c, K_ADD, w, h, err, KB(c, B_COLOR), KB(c, B_EMIS), KF(-1.0f), KI(w), KI(h));
        if (rc == TR_OK && split) {
            rc = RUN(c, K_ADD, w, h, err, KM(c->sp[SP_DIRECT]), KB(c, B_EMIS), KF(-1.0f), KI(w),
                     KI(h));
        }
    }
    if (rc == TR_OK && spec) {
        /* The specular part apart: its albedo, its light over it, the diffuse colour. */
        rc = RUN(c, K_SPEC_PREPARE, w, h, err, KB(c, B_CAMS), KB(c, B_COLOR), KB(c, B_NORMAL),
                 KB(c, B_PRIM), KM(c->ss[SS_PASS]), KM(c->ss[SS_DFG]), KM(c->ss[SS_ALBEDO]),
                 KM(c->ss[SS_ILLUM]), KM(c->ss[SS_DIFFUSE]));
    }
    rc = rc ? rc
            : RUN(c, K_MODULATE, w, h, err, spec ? KM(c->ss[SS_DIFFUSE]) : KB(c, B_COLOR),
                  KB(c, B_ALBEDO), KI(0), KI(w), KI(h), KB(c, B_ILLUM));
    if (rc == TR_OK && split) {
        /* The direct part demodulated, and the rest of the light the indirect part. */
        rc = RUN(c, K_MODULATE, w, h, err, KM(c->sp[SP_DIRECT]), KB(c, B_ALBEDO), KI(0), KI(w),
                 KI(h), KM(c->sp[SP_ILLUM]));
        rc = rc ? rc
                : RUN(c, K_ADD, w, h, err, KB(c, B_ILLUM), KM(c->sp[SP_ILLUM]), KF(-1.0f), KI(w),
                      KI(h));
    }
    /* SVGF's albedo history (albedo_alpha), where the host's temporal stage keeps it. */
    const int ha = p->albedo_alpha > 0.0f ? B_HA0 + next : B_ALBEDO;
    /* The temporal gradients' caps, where the device measured them for this frame. */
    const cl_mem cap = c->len_cap ? c->len_cap : c->b[B_DEPTH];
    const int have_cap = c->len_cap != NULL;
    rc = rc ? rc
            : RUN(c, K_TEMPORAL, w, h, err, KB(c, B_CAMS), KB(c, B_ILLUM), KB(c, B_NORMAL),
                  KB(c, B_DEPTH), KB(c, B_PRIM), KB(c, B_HC0 + prev), KB(c, B_HM0 + prev),
                  KB(c, B_HL0 + prev), KB(c, B_HDEPTH), KB(c, B_HNORMAL), KB(c, B_HPRIM), KM(mbuf),
                  KU(motion_count), KI(hist), KF(p->alpha_min), KF(p->max_len),
                  KF(p->max_len_moving), KB(c, hc), KB(c, hm), KB(c, hl), KB(c, B_ALBEDO),
                  KB(c, B_HA0 + prev), KI(c->have_albedo), KF(p->albedo_alpha), KB(c, B_HA0 + next),
                  KM(cap), KI(have_cap));
    if (rc == TR_OK && split) {
        /* The direct part through the same taps: the lengths it writes are the sum's. No
         * albedo history here (albedo_alpha 0): the sum's call kept it. */
        rc =
            RUN(c, K_TEMPORAL, w, h, err, KB(c, B_CAMS), KM(c->sp[SP_ILLUM]), KB(c, B_NORMAL),
                KB(c, B_DEPTH), KB(c, B_PRIM), KM(c->sp[SP_HD0 + prev]), KM(c->sp[SP_HDM0 + prev]),
                KB(c, B_HL0 + prev), KB(c, B_HDEPTH), KB(c, B_HNORMAL), KB(c, B_HPRIM), KM(mbuf),
                KU(motion_count), KI(hist), KF(p->alpha_min), KF(p->max_len), KF(p->max_len_moving),
                KM(c->sp[SP_HD0 + next]), KM(c->sp[SP_HDM0 + next]), KB(c, hl), KB(c, B_ALBEDO),
                KB(c, B_HA0 + prev), KI(0), KF(0.0f), KB(c, B_HA0 + next), KM(cap), KI(have_cap));
    }
    if (rc == TR_OK && spec) {
        rc = RUN(c, K_SPEC_TEMPORAL, w, h, err, KB(c, B_CAMS), KM(c->ss[SS_ILLUM]), KB(c, B_NORMAL),
                 KB(c, B_DEPTH), KB(c, B_PRIM), KM(c->ss[SS_PASS]), KM(c->ss[SS_HS0 + prev]),
                 KM(c->ss[SS_HSM0 + prev]), KM(c->ss[SS_HSL0 + prev]), KB(c, B_HDEPTH),
                 KB(c, B_HNORMAL), KB(c, B_HPRIM), KM(mbuf), KU(motion_count), KI(c->have_history),
                 KF(p->alpha_min), KF(p->max_len), KF(p->max_len_moving), KM(c->ss[SS_HS0 + next]),
                 KM(c->ss[SS_HSM0 + next]), KM(c->ss[SS_HSL0 + next]), KM(cap), KI(have_cap));
    }
    c->hist_split = split;
    c->hist_spec = spec;
    if (rc != TR_OK || (rc = finish(c, err)) != TR_OK) {
        return rc;
    }
    c->have_albedo = ha != B_ALBEDO;
    c->modulated = method == TR_RECON_SVGF ? ha : B_ALBEDO;
    c->cur = next;
    const double t1 = tr_time_now();
    r->ms_temporal = (t1 - t0) * 1e3;
    const int had_taa = c->have_taa && c->have_history;
    c->have_taa = 0;
    result = B_OUT;
    if (method == TR_RECON_ACCUMULATE) {
        rc = RUN(c, K_MODULATE, w, h, err, KB(c, hc), KB(c, B_ALBEDO), KI(1), KI(w), KI(h),
                 KB(c, B_OUT));
    } else if (method == TR_RECON_BILATERAL) {
        rc = RUN(c, K_MODULATE, w, h, err, KB(c, hc), KB(c, B_ALBEDO), KI(1), KI(w), KI(h),
                 KB(c, B_CA));
        rc = rc ? rc
                : RUN(c, K_BILATERAL, w, h, err, KB(c, B_CA), KI(w), KI(h), KI(p->bilateral_radius),
                      KF(p->bilateral_sigma_s), KF(p->bilateral_sigma_r), KB(c, B_OUT));
    } else if (method == TR_RECON_ATROUS) {
        int src = hc, dst = B_CA;
        for (int it = 0; rc == TR_OK && it < p->atrous_iterations; ++it) {
            rc = RUN(c, K_ATROUS, w, h, err, KB(c, src), KB(c, B_NORMAL), KB(c, B_DEPTH),
                     KB(c, B_ALBEDO), KI(w), KI(h), KI(1 << it),
                     KF(p->atrous_sigma_c / (float)(1 << it)), KF(p->atrous_sigma_n),
                     KF(p->atrous_sigma_z), KF(p->atrous_sigma_a), KB(c, dst));
            src = dst;
            dst = dst == B_CA ? B_CB : B_CA;
        }
        rc = rc ? rc
                : RUN(c, K_MODULATE, w, h, err, KB(c, src), KB(c, B_ALBEDO), KI(1), KI(w), KI(h),
                      KB(c, B_OUT));
    } else {
        /* With TAA the remodulated output goes to B_ILLUM (free by now) first. */
        const int res = p->svgf_taa_alpha > 0.0f ? B_ILLUM : B_OUT;
        if (spec) {
            /* Each part steered by its own variance, remodulated by its own albedo. */
            rc = svgf_part(c, w, h, c->b[hc], c->b[hm], c->b[hl], p, c->b[ha], res, 0, err);
            rc = rc ? rc
                    : svgf_part(c, w, h, c->ss[SS_HS0 + next], c->ss[SS_HSM0 + next],
                                c->ss[SS_HSL0 + next], p, c->ss[SS_ALBEDO], res, 1, err);
        } else if (split) {
            /* Schied et al. filter direct and indirect illumination apart, each steered by
             * its own variance, and add them after remodulation. */
            rc = svgf_part(c, w, h, c->sp[SP_HD0 + next], c->sp[SP_HDM0 + next], c->b[hl], p,
                           c->b[ha], res, 0, err);
            rc = rc ? rc
                    : svgf_part(c, w, h, c->b[hc], c->b[hm], c->b[hl], p, c->b[ha], res, 1, err);
        } else {
            rc = svgf_part(c, w, h, c->b[hc], c->b[hm], c->b[hl], p, c->b[ha], res, 0, err);
        }
        if (rc == TR_OK && p->svgf_taa_alpha > 0.0f) {
            /* Temporal antialiasing of the remodulated output against the last frame's. */
            rc = RUN(c, K_TAA, w, h, err, KB(c, B_CAMS), KB(c, B_ILLUM), KB(c, B_NORMAL),
                     KB(c, B_DEPTH), KB(c, B_PRIM), KB(c, B_TAA), KI(had_taa), KB(c, B_HDEPTH),
                     KB(c, B_HNORMAL), KB(c, B_HPRIM), KF(p->svgf_taa_alpha), KB(c, B_OUT));
            rc = rc ? rc : copy(c, B_OUT, B_TAA, 3 * n * sizeof(float), err);
            c->have_taa = rc == TR_OK;
        }
    }
    if (rc == TR_OK && c->has_emission) {
        rc = RUN(c, K_ADD, w, h, err, KB(c, B_OUT), KM(emis), KF(1.0f), KI(w), KI(h));
        c->added = emis;
    }
    /* The geometry this frame's history was seen with, for the next frame's tests. */
    rc = rc ? rc : copy(c, B_DEPTH, B_HDEPTH, n * sizeof(float), err);
    rc = rc ? rc : copy(c, B_NORMAL, B_HNORMAL, 3 * n * sizeof(float), err);
    rc = rc ? rc : copy(c, B_PRIM, B_HPRIM, n * sizeof(uint32_t), err);
    if (rc != TR_OK) {
        c->have_history = 0;
        return rc;
    }
    c->prev_cam = *cam;
    c->have_history = 1;
read:;
    c->result = result;
    /* No `out`: the result stays on the device (tr_recon_device_upscale reads it there). */
    const cl_int crc = out ? clEnqueueReadBuffer(c->queue, c->b[result], CL_TRUE, 0,
                                                 3 * n * sizeof(float), out, 0, NULL, NULL)
                           : clFinish(c->queue);
    if (crc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueReadBuffer(output)", crc);
    }
    const double t2 = tr_time_now();
    if (method == TR_RECON_OFF) {
        r->ms_temporal = 0.0;
    }
    r->ms_spatial = (t2 - t0) * 1e3 - r->ms_temporal;
    return TR_OK;
}
#endif

tr_recon_device *tr_recon_device_create(tr_device *dev, uint32_t width, uint32_t height,
                                        tr_error *err) {
    if (tr_film_check_size(width, height, err) != TR_OK) {
        return NULL;
    }
    tr_recon_device *r = calloc(1, sizeof *r);
    if (!r) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a reconstruction");
        return NULL;
    }
    r->dev = dev;
    r->width = width;
    r->height = height;
    tr_cl_context *cl = tr_device_cl_context(dev);
    if (cl) {
#ifdef TRAC0R_HAVE_OPENCL
        tr_cl_handles h;
        if (tr_cl_get_handles(cl, &h, err) != TR_OK ||
            !(r->cl = cl_state_open(&h, width, height, err))) {
            free(r);
            return NULL;
        }
        return r;
#endif
    }
    if (tr_recon_init(&r->host, width, height, err) != TR_OK) {
        free(r);
        return NULL;
    }
    if (tr_gbuffer_init(&r->gb, width, height, err) != TR_OK) {
        tr_recon_free(&r->host);
        free(r);
        return NULL;
    }
    return r;
}

void tr_recon_device_destroy(tr_recon_device *r) {
    if (!r) {
        return;
    }
#ifdef TRAC0R_HAVE_OPENCL
    cl_state_free(r->cl);
#endif
    if (!r->cl) {
        tr_recon_free(&r->host);
        tr_gbuffer_free(&r->gb);
        tr_film_free(&r->film);
    }
    free(r);
}

void tr_recon_device_clear(tr_recon_device *r) {
#ifdef TRAC0R_HAVE_OPENCL
    if (r->cl) {
        r->cl->have_history = 0;
        return;
    }
#endif
    tr_recon_clear(&r->host);
}

int tr_recon_device_on_device(const tr_recon_device *r) {
    return r->cl != NULL;
}

void tr_recon_device_times(const tr_recon_device *r, double *ms_temporal, double *ms_spatial) {
    *ms_temporal = r->cl ? r->ms_temporal : r->host.ms_temporal;
    *ms_spatial = r->cl ? r->ms_spatial : r->host.ms_spatial;
}

int tr_recon_device_frame_gbuffer(tr_recon_device *r, const tr_gbuffer *g, const tr_camera *cam,
                                  const tr_vec3 *motion, uint32_t motion_count, int method,
                                  const tr_recon_params *p, float *out, tr_error *err) {
    if (check_args(r, cam, method, err) != TR_OK) {
        return TR_ERR;
    }
    if (g->width != r->width || g->height != r->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "reconstruction: %ux%u frame for a %ux%u state", g->width, g->height,
                            r->width, r->height);
    }
#ifdef TRAC0R_HAVE_OPENCL
    if (r->cl) {
        if (cl_upload(r, g, err) != TR_OK) {
            return TR_ERR;
        }
        return cl_frame(r, cam, motion, motion_count, method, p, out, err);
    }
#endif
    return tr_recon_frame_moving(&r->host, g, cam, motion, motion_count, method, p, 0, out, err);
}

int tr_recon_device_frame(tr_recon_device *r, const tr_camera *cam, const tr_vec3 *motion,
                          uint32_t motion_count, int method, const tr_recon_params *p, float *out,
                          tr_error *err) {
    if (check_args(r, cam, method, err) != TR_OK) {
        return TR_ERR;
    }
#ifdef TRAC0R_HAVE_OPENCL
    if (r->cl) {
        if (cl_from_film(r, err) != TR_OK) {
            return TR_ERR;
        }
        return cl_frame(r, cam, motion, motion_count, method, p, out, err);
    }
#endif
    uint32_t w, h, passes;
    tr_device_film_size(r->dev, &w, &h, &passes);
    if (w != r->width || h != r->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "reconstruction: the device's film is %ux%u, the state %ux%u", w, h,
                            r->width, r->height);
    }
    if (!r->film.sum || r->film.passes != passes) {
        tr_film_free(&r->film);
        if (tr_film_init_passes(&r->film, w, h, passes, err) != TR_OK) {
            return TR_ERR;
        }
    }
    if (tr_device_read_film(r->dev, &r->film, err) != TR_OK ||
        tr_gbuffer_from_film(&r->gb, &r->film, err) != TR_OK) {
        return TR_ERR;
    }
    /* As on the OpenCL device: emitters' edges resolved where asked for, timed with the
     * temporal stage. */
    const double t0 = tr_time_now();
    if (r->gb.has_emission && p->emission_samples > 0 && method != TR_RECON_OFF &&
        tr_resolve_emission(tr_device_scene(r->dev), cam, p->emission_samples, 0, &r->gb, NULL,
                            err) != TR_OK) {
        return TR_ERR;
    }
    const double resolve_ms = (tr_time_now() - t0) * 1e3;
    if (tr_recon_frame_moving(&r->host, &r->gb, cam, motion, motion_count, method, p, 0, out,
                              err) != TR_OK) {
        return TR_ERR;
    }
    r->host.ms_temporal += method != TR_RECON_OFF ? resolve_ms : 0.0;
    return TR_OK;
}

#ifdef TRAC0R_HAVE_OPENCL
/* The upscaling's buffers for a W x H output of a wl x hl frame (made anew, the history
 * forgotten, for another output size). */
static int up_buffers(recon_cl *c, uint32_t W, uint32_t H, tr_error *err) {
    if (c->up_w == W && c->up_h == H && c->up_out) {
        return TR_OK;
    }
    up_release(c);
    const size_t n = (size_t)W * H;
    cl_mem *const m[12] = {&c->up_col[0],   &c->up_col[1],   &c->up_len[0],  &c->up_len[1],
                           &c->up_depth[0], &c->up_depth[1], &c->up_emis[0], &c->up_emis[1],
                           &c->up_out,      &c->up_pos,      &c->up_cams,    &c->up_alb};
    /* The positions take 2 floats per traced pixel, at most as many as the output's. */
    const size_t bytes[12] = {3 * n * 4,
                              3 * n * 4,
                              n * 4,
                              n * 4,
                              n * 4,
                              n * 4,
                              3 * n * 4,
                              3 * n * 4,
                              3 * n * 4,
                              2 * n * 4,
                              2 * sizeof(tr_camera),
                              3 * n * 4};
    for (int i = 0; i < 12; ++i) {
        cl_int rc;
        *m[i] = clCreateBuffer(c->context, CL_MEM_READ_WRITE, bytes[i], NULL, &rc);
        if (!*m[i]) {
            up_release(c);
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                                "OpenCL upscaling: no device memory for a %ux%u output: "
                                "clCreateBuffer failed: %s (%d)",
                                W, H, tr_cl_error_name(rc), rc);
        }
    }
    c->up_w = W;
    c->up_h = H;
    return TR_OK;
}
#endif

#ifdef TRAC0R_HAVE_OPENCL
/* The output's albedo into c->up_alb: the frame's albedo pass (nl pixels) read back into a
 * host buffer kept between frames, the output's (n pixels) made from it by the caller's fn
 * on the host and uploaded. */
static int up_albedo(recon_cl *c, tr_recon_albedo_fn fn, void *user, size_t nl, size_t n,
                     tr_error *err) {
    if (c->up_low_len != 3 * nl) {
        free(c->up_low);
        c->up_low_len = 0;
        if (!(c->up_low = malloc(3 * nl * sizeof *c->up_low))) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a frame's albedo");
        }
        c->up_low_len = 3 * nl;
    }
    cl_int crc = clEnqueueReadBuffer(c->queue, c->b[B_ALBEDO], CL_TRUE, 0, 3 * nl * sizeof(float),
                                     c->up_low, 0, NULL, NULL);
    if (crc != CL_SUCCESS) {
        return cl_fail(err, "clEnqueueReadBuffer(albedo)", crc);
    }
    const float *alb = fn(user, c->up_low, err);
    if (!alb) {
        return TR_ERR;
    }
    crc = clEnqueueWriteBuffer(c->queue, c->up_alb, CL_TRUE, 0, 3 * n * sizeof(float), alb, 0, NULL,
                               NULL);
    return crc == CL_SUCCESS ? TR_OK : cl_fail(err, "clEnqueueWriteBuffer(albedo)", crc);
}
#endif

int tr_recon_device_upscale(tr_recon_device *r, const tr_camera *cam, const tr_camera *out_cam,
                            const float *pos, tr_recon_albedo_fn albedo, void *albedo_user,
                            const tr_vec3 *motion, uint32_t motion_count, int method,
                            const tr_recon_params *p, int keep, float *out, double *ms,
                            tr_error *err) {
    *ms = 0.0;
    if (check_args(r, cam, method, err) != TR_OK) {
        return TR_ERR;
    }
    const uint32_t W = out_cam->screen_width, H = out_cam->screen_height;
    if (W < r->width || H < r->height || !pos || !out) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "upscaling: a %ux%u output of a %ux%u frame, or NULL positions or "
                            "output",
                            W, H, r->width, r->height);
    }
#ifdef TRAC0R_HAVE_OPENCL
    if (r->cl) {
        recon_cl *c = r->cl;
        if (cl_from_film(r, err) != TR_OK ||
            cl_frame(r, cam, motion, motion_count, method, p, NULL, err) != TR_OK ||
            up_buffers(c, W, H, err) != TR_OK) {
            return TR_ERR;
        }
        const double t0 = tr_time_now();
        const int wl = (int)r->width, hl = (int)r->height, w = (int)W, h = (int)H;
        const size_t nl = (size_t)wl * hl, n = (size_t)W * H;
        if (!keep) {
            c->up_have = 0;
        }
        /* As the host's upscale stage: with the emission pass (and its resolve asked for)
         * the upscaling sees the reconstruction less the emission it added back (the
         * frame's own for "off"), and the emission at the output's resolution comes back
         * after it. */
        const int emission = c->has_emission && p->emission_samples > 0;
        cl_mem low = c->b[c->result];
        int rc = TR_OK;
        cl_int crc = clEnqueueWriteBuffer(c->queue, c->up_pos, CL_FALSE, 0, 2 * nl * sizeof(float),
                                          pos, 0, NULL, NULL);
        const tr_camera cams[2] = {*out_cam, c->up_have ? c->up_prev : *out_cam};
        if (crc == CL_SUCCESS) {
            crc = clEnqueueWriteBuffer(c->queue, c->up_cams, CL_TRUE, 0, sizeof cams, cams, 0, NULL,
                                       NULL);
        }
        if (crc != CL_SUCCESS) {
            return cl_fail(err, "clEnqueueWriteBuffer(upscaling)", crc);
        }
        if (emission || albedo) {
            rc = copy(c, c->result, B_CA, 3 * nl * sizeof(float), err);
            low = c->b[B_CA];
        }
        if (emission) {
            cl_mem e = c->added ? c->added : c->b[B_EMIS];
            rc =
                rc ? rc : RUN(c, K_ADD, wl, hl, err, KB(c, B_CA), KM(e), KF(-1.0f), KI(wl), KI(hl));
        }
        if (albedo) {
            /* The light apart from the albedo, as the host's upscale stage: divided by the
             * albedo the reconstruction multiplied by, multiplied by the output's after. */
            rc = rc ? rc : up_albedo(c, albedo, albedo_user, nl, n, err);
            rc = rc ? rc
                    : RUN(c, K_MODULATE, wl, hl, err, KB(c, B_CA), KB(c, c->modulated), KI(2),
                          KI(wl), KI(hl), KB(c, B_CA));
        }
        const int prev = c->up_cur, next = 1 - c->up_cur;
        cl_mem mbuf = motion && motion_count ? c->motion : c->b[B_DEPTH];
        const uint32_t mcount = motion && motion_count ? motion_count : 0u;
        rc = rc ? rc
                : RUN(c, K_UPSCALE, w, h, err, KM(c->up_cams), KI(wl), KI(hl), KM(low),
                      KM(c->up_pos), KB(c, B_DEPTH), KB(c, B_PRIM), KM(mbuf), KU(mcount),
                      KI(c->up_have), KM(c->up_col[prev]), KM(c->up_len[prev]),
                      KM(c->up_depth[prev]), KF(TR_UPSCALE_MAX_LEN), KM(c->up_col[next]),
                      KM(c->up_len[next]), KM(c->up_depth[next]));
        cl_mem result = c->up_col[next];
        if (rc == TR_OK && albedo) {
            rc = RUN(c, K_MODULATE, w, h, err, KM(c->up_col[next]), KM(c->up_alb), KI(3), KI(w),
                     KI(h), KM(c->up_out));
            result = c->up_out;
        }
        if (rc == TR_OK && emission) {
            tr_cl_context *ctx = tr_device_cl_context(r->dev);
            const int ecur = 1 - c->emis_cur;
            rc = tr_cl_upscale_emission(
                ctx, out_cam, p->emission_samples, (uint32_t)wl, (uint32_t)hl, c->b[B_EMIS],
                keep && c->emis_have ? c->up_emis[c->emis_cur] : NULL, c->up_emis[ecur], err);
            if (rc == TR_OK && !albedo) {
                const cl_int k = clEnqueueCopyBuffer(c->queue, c->up_col[next], c->up_out, 0, 0,
                                                     3 * n * sizeof(float), 0, NULL, NULL);
                rc = k == CL_SUCCESS ? TR_OK : cl_fail(err, "clEnqueueCopyBuffer", k);
            }
            rc = rc ? rc
                    : RUN(c, K_ADD, w, h, err, KM(c->up_out), KM(c->up_emis[ecur]), KF(1.0f), KI(w),
                          KI(h));
            c->emis_cur = ecur;
            c->emis_have = rc == TR_OK;
            result = c->up_out;
        }
        if (rc == TR_OK) {
            crc = clEnqueueReadBuffer(c->queue, result, CL_TRUE, 0, 3 * n * sizeof(float), out, 0,
                                      NULL, NULL);
            rc = crc == CL_SUCCESS ? TR_OK : cl_fail(err, "clEnqueueReadBuffer(upscaled)", crc);
        }
        if (rc != TR_OK) {
            c->up_have = 0;
            return TR_ERR;
        }
        c->up_cur = next;
        c->up_prev = *out_cam;
        c->up_have = 1;
        *ms = (tr_time_now() - t0) * 1e3;
        return TR_OK;
    }
#else
    (void)albedo;
    (void)albedo_user;
    (void)motion;
    (void)motion_count;
    (void)keep;
    (void)p;
#endif
    return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                        "upscaling on the device: not an OpenCL device (the host upscales)");
}
