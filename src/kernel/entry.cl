/* entry.cl - the OpenCL entry point: the __kernel that runs tr_render_grid_rows, the
 * same code the CPU device runs, for one traced pixel per work item, and accumulates its
 * samples into the film on the device with tr_film_add_block (src/kernel/film.h).
 *
 * cmake/EmbedKernel.cmake inlines this file and every kernel header it includes into
 * one string compiled by src/device/opencl.c. */
#pragma OPENCL FP_CONTRACT OFF

#include "cwbvh.h"
#include "emission.h"
#include "grad_pixel.h"
#include "reproject.h"
#include "integrator_pt_wf.h"
#include "kernel.h"
#include "restir_pass.h"

/* The host builds the kernels below as four programs, each the first time it is needed
 * (src/device/opencl.c): the frame's (TR_CL_PART 1: the megakernel, the emission and ray
 * kernels), ReSTIR's passes (2), pt's wavefront stages (3) and bdpt's and vcm's (4). With
 * every function inlined, the whole source came to about 440,000 lines of PTX, about 9x
 * the kernel of four days earlier, so that a GPU driver compiling it for every process
 * spent minutes before the first frame; most runs need one part. A program built without
 * TR_CL_PART (the tests' own sources) holds them all. */
#ifdef TR_CL_PART
#define TR_CL_HAS(part) (TR_CL_PART == (part))
#else
#define TR_CL_HAS(part) 1
#endif

/* The scene's arrays come as one __global buffer argument each, generated from the one
 * list of them (TR_SCENE_ARRAYS, scene_view.h); their element counts and then the view's
 * scalars, as 32-bit words, are the scene_info argument. src/device/opencl.c builds its
 * upload table from the same list and checks the compiled kernel's argument names. */
#define TR_CL_ARRAY_PARAM(type, name, count) __global const type *name,
#define TR_CL_INFO_ENUM(type, name, count) TR_CL_INFO_##count,
#define TR_CL_SCALAR_ENUM(type, name) TR_CL_INFO_##name,
enum { TR_SCENE_ARRAYS(TR_CL_INFO_ENUM) TR_SCENE_SCALARS(TR_CL_SCALAR_ENUM) TR_CL_INFO_COUNT };

/* The scene view `s` over the kernel's scene arguments. */
#define TR_CL_VIEW_ARRAY(type, name, count)                                                        \
    s.name = name;                                                                                 \
    s.count = scene_info[TR_CL_INFO_##count];
#define TR_CL_SCENE_VIEW(s)                                                                        \
    TR_SCENE_ARRAYS(TR_CL_VIEW_ARRAY)                                                              \
    s.accel = scene_info[TR_CL_INFO_accel];                                                        \
    s.light_weight_total = as_float(scene_info[TR_CL_INFO_light_weight_total]);                    \
    s.sky_cx = as_float(scene_info[TR_CL_INFO_sky_cx]);                                            \
    s.sky_cy = as_float(scene_info[TR_CL_INFO_sky_cy]);                                            \
    s.sky_cz = as_float(scene_info[TR_CL_INFO_sky_cz]);                                            \
    s.sky_radius = as_float(scene_info[TR_CL_INFO_sky_radius])

/* The film view over the kernel's film arguments, every pass buffer in it. */
#define TR_CL_FILM_VIEW(f)                                                                         \
    tr_cl_film_view(film_sum, film_count, film_albedo, film_normal, film_depth, film_prim,         \
                    film_sq, film_direct, film_emission, film_specular, (f).camera.screen_width,   \
                    (f).passes)
static tr_film_view tr_cl_film_view(__global float *sum, __global uint *count,
                                    __global float *albedo, __global float *normal,
                                    __global float *depth, __global uint *prim, __global float *sq,
                                    __global float *direct, __global float *emission,
                                    __global float *specular, uint width, uint passes) {
    tr_film_view v = tr_film_view_make(sum, count, albedo, normal, depth, prim, width, passes);
    v.sq = sq;
    v.direct = direct;
    v.emission = emission;
    v.specular = specular;
    return v;
}

#if TR_CL_HAS(1)
/* One work item per traced pixel of the frame's grid (tr_frame_grid); with a stride above
 * 1 the traced pixel's value fills its stride x stride block (preview mode). Pass buffers
 * the frame does not ask for are one-element placeholders nobody writes.
 * rays_per_row[r] accumulates the intersection queries made for grid row r. */
__kernel void tr_cl_render(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                           __global const tr_frame *frame, __global float *film_sum,
                           __global uint *film_count, __global float *film_albedo,
                           __global float *film_normal, __global float *film_depth,
                           __global uint *film_prim, __global float *film_sq,
                           __global float *film_direct, __global float *film_emission,
                           __global float *film_specular, __global uint *rays_per_row) {
    const tr_frame f = *frame;
    uint gx0, gy0, nx, ny;
    tr_frame_grid(&f, &gx0, &gy0, &nx, &ny);
    const uint gx = (uint)get_global_id(0), gy = (uint)get_global_id(1);
    if (gx >= nx || gy >= ny) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);

    tr_film_view film = TR_CL_FILM_VIEW(f);
    const uint rays =
        tr_render_grid_rows(&s, &f, &film, gx0 + gx, gy0 + gy, gx0 + gx + 1u, gy0 + gy + 1u);
    atomic_add(&rays_per_row[gy], rays);
}

/* tr_cl_render for the pixels whose mask byte is set (the real-time loop's fresh samples:
 * tr_cl_fresh_frame); a frame of stride 1 over the whole image, one work item per pixel. */
__kernel void tr_cl_render_masked(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM)
                                      __global const uint *scene_info,
                                  __global const tr_frame *frame, __global float *film_sum,
                                  __global uint *film_count, __global float *film_albedo,
                                  __global float *film_normal, __global float *film_depth,
                                  __global uint *film_prim, __global float *film_sq,
                                  __global float *film_direct, __global float *film_emission,
                                  __global float *film_specular, __global uint *rays_per_row,
                                  __global const uchar *mask) {
    const tr_frame f = *frame;
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= f.camera.screen_width || y >= f.camera.screen_height ||
        !mask[y * f.camera.screen_width + x]) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    tr_film_view film = TR_CL_FILM_VIEW(f);
    atomic_add(&rays_per_row[y], tr_render_grid_rows(&s, &f, &film, x, y, x + 1u, y + 1u));
}

/* The real-time loop's fresh samples (src/realtime/fresh.h) where the film lies, one work
 * item per pixel of cams[0] (this frame; cams[1] the previous one): mask[i] = 1 where the
 * pixel hit a surface and has no history (tr_reproject_lost against the previous frame's
 * passes and points), its surface point into cur_point; *fresh counts the masked pixels. */
__kernel void tr_cl_fresh_mask(__global const tr_camera *cams, int have_prev,
                               __global const uint *film_count, __global const float *film_depth,
                               __global const float *film_normal, __global const uint *film_prim,
                               __global const float *prev_depth, __global const float *prev_normal,
                               __global const uint *prev_prim, __global const float *prev_point,
                               __global const float *motion, uint motion_count,
                               __global float *cur_point, __global uchar *mask,
                               __global uint *fresh) {
    const tr_camera cam = cams[0], prev = cams[1];
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= cam.screen_width || y >= cam.screen_height) {
        return;
    }
    const uint i = y * cam.screen_width + x;
    const uint c = film_count[i];
    const float inv = c ? 1.0f / (float)c : 0.0f;
    const float depth = film_depth[i] * inv;
    const tr_vec3 n = v3(film_normal[3u * i] * inv, film_normal[3u * i + 1u] * inv,
                         film_normal[3u * i + 2u] * inv);
    const uint prim = film_prim[i];
    const tr_vec3 m = prim < motion_count
                          ? v3(motion[3u * prim], motion[3u * prim + 1u], motion[3u * prim + 2u])
                          : v3s(0.0f);
    tr_vec3 p = v3s(0.0f);
    const int lost = tr_reproject_lost(&cam, &prev, have_prev, x, y, depth, n, prim, m, prev_depth,
                                       prev_normal, prev_prim, prev_point, &p);
    if (depth > 0.0f) {
        cur_point[3u * i] = p.x;
        cur_point[3u * i + 1u] = p.y;
        cur_point[3u * i + 2u] = p.z;
    }
    mask[i] = (uchar)lost;
    if (lost) {
        atomic_inc(fresh);
    }
}

/* This frame's passes as the previous frame's for the next tr_cl_fresh_mask (one work item
 * per pixel of cams[0]): the means of depth, normal and primitive, and the surface point of
 * each masked pixel again at its new mean depth. */
__kernel void tr_cl_fresh_remember(__global const tr_camera *cams, __global const uint *film_count,
                                   __global const float *film_depth,
                                   __global const float *film_normal,
                                   __global const uint *film_prim, __global const uchar *mask,
                                   __global float *cur_point, __global float *prev_depth,
                                   __global float *prev_normal, __global uint *prev_prim) {
    const tr_camera cam = cams[0];
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= cam.screen_width || y >= cam.screen_height) {
        return;
    }
    const uint i = y * cam.screen_width + x;
    const uint c = film_count[i];
    const float inv = c ? 1.0f / (float)c : 0.0f;
    const float depth = film_depth[i] * inv;
    prev_depth[i] = depth;
    prev_normal[3u * i] = film_normal[3u * i] * inv;
    prev_normal[3u * i + 1u] = film_normal[3u * i + 1u] * inv;
    prev_normal[3u * i + 2u] = film_normal[3u * i + 2u] * inv;
    prev_prim[i] = film_prim[i];
    if (mask[i] && depth > 0.0f) {
        const tr_vec3 p = tr_camera_point_at(&cam, (float)x, (float)y, depth);
        cur_point[3u * i] = p.x;
        cur_point[3u * i + 1u] = p.y;
        cur_point[3u * i + 2u] = p.z;
    }
}

/* The film's emission (TR_PASS_EMISSION) resolved over each pixel's area, as the host's
 * tr_resolve_emission does it (src/post/emission.c, src/kernel/emission.h): a pixel next
 * to an edge between emitting and non-emitting samples gets the mean over an n x n grid of
 * first-hit rays through the frame's camera, every other pixel its own mean emission.
 * One work item per pixel of the film (the camera's screen). */
__kernel void
tr_cl_resolve_emission(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                       __global const tr_frame *frame, __global const uint *film_count,
                       __global const float *film_emission, int n, __global float *resolved) {
    const tr_frame f = *frame;
    const int w = (int)f.camera.screen_width, h = (int)f.camera.screen_height;
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const uint i = (uint)(y * w + x);
    tr_vec3 e;
    if (tr_emission_on_edge(film_emission, w, h, x, y)) {
        tr_scene_view s;
        TR_CL_SCENE_VIEW(s);
        e = tr_emission_resolve_pixel(&s, &f.camera, x, y, n);
    } else {
        const uint c = film_count[i];
        const float inv = c ? 1.0f / (float)c : 0.0f;
        e = v3(film_emission[3u * i] * inv, film_emission[3u * i + 1u] * inv,
               film_emission[3u * i + 2u] * inv);
    }
    resolved[3u * i] = e.x;
    resolved[3u * i + 1u] = e.y;
    resolved[3u * i + 2u] = e.z;
}

/* The temporal gradients (grad_pixel.h) where the film lies, as src/realtime/gradient.c
 * computes them on the host; src/device/opencl.c's tr_cl_grad_frame runs the three.
 * tr_cl_grad_replay: one work item per stratum (sw x sh of them), replaying samples
 * sample .. sample+count-1 of the previous frame `frame` at the stratum's pixel of the
 * w x h image into num and den; counts the changed strata in *changed. */
__kernel void tr_cl_grad_replay(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                                __global const tr_frame *frame, uint w, uint h, uint sw, uint sh,
                                uint frame_no, uint sample, uint count,
                                __global const float *prev_lum, __global const uint *prev_prim,
                                int has_prim, __global const float *motion, uint motion_count,
                                __global float *num, __global float *den, __global uint *changed) {
    const uint sx = (uint)get_global_id(0), sy = (uint)get_global_id(1);
    if (sx >= sw || sy >= sh) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    const tr_frame f = *frame;
    uint x, y;
    tr_grad_stratum_pixel(sw, w, h, sx, sy, frame_no, &x, &y);
    const uint i = y * w + x, k = sy * sw + sx;
    float n, d;
    if (tr_grad_replay_stratum(&s, &f, x, y, sample, count, prev_lum[i], prev_prim[i], has_prim,
                               motion_count ? motion : 0, motion_count, &n, &d)) {
        atomic_inc(changed);
    }
    num[k] = n;
    den[k] = d;
}

/* One à-trous step (tr_grad_atrous_at) of num and den over the sw x sh strata. */
__kernel void tr_cl_grad_atrous(__global const float *num, __global const float *den, int sw,
                                int sh, int step, __global float *num_out,
                                __global float *den_out) {
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= sw || y >= sh) {
        return;
    }
    num_out[y * sw + x] = tr_grad_atrous_at(num, sw, sh, x, y, step);
    den_out[y * sw + x] = tr_grad_atrous_at(den, sw, sh, x, y, step);
}

/* One work item per pixel of cams[0]'s screen: with `replayed`, its history cap from the
 * filtered strata (tr_grad_cap_pixel, cams[1] the previous camera) into cap; then this
 * frame's mean luminance and first primitive into prev_lum and prev_prim, for the next
 * frame's replay. has_depth, has_prim: whether the film keeps those passes. */
__kernel void tr_cl_grad_finish(__global const tr_camera *cams, int same, int replayed, int changed,
                                uint sw, __global const float *film_sum,
                                __global const uint *film_count, __global const float *film_depth,
                                __global const uint *film_prim, int has_depth, int has_prim,
                                __global const float *motion, uint motion_count,
                                __global const float *num, __global const float *den, float amin,
                                __global float *cap, __global float *prev_lum,
                                __global uint *prev_prim) {
    const tr_camera cam = cams[0], pc = cams[1];
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= cam.screen_width || y >= cam.screen_height) {
        return;
    }
    const uint i = y * cam.screen_width + x;
    const uint c = film_count[i];
    const uint id = has_prim ? film_prim[i] : 0u;
    if (replayed) {
        const float dep = has_depth && c ? film_depth[i] / (float)c : 0.0f;
        cap[i] = tr_grad_cap_pixel(&cam, &pc, same, x, y, dep, id, motion_count ? motion : 0,
                                   motion_count, changed, num, den, sw, amin);
    }
    prev_lum[i] = tr_grad_mean_luminance(film_sum + 3u * i, c);
    prev_prim[i] = id;
}

#endif

#if TR_CL_HAS(2)
/* ReSTIR DI's passes (restir_pass.h) on the device, one work item per pixel of the frame's
 * camera: tr_cl_restir_temporal fills this frame's surfaces and first reservoirs,
 * tr_cl_restir_spatial merges neighbours, shades and adds to the film; the host
 * (src/device/opencl.c, tr_cl_restir_frame) swaps the buffers from frame to frame. The
 * candidates come from the power CDF unless the frame asks for the light tree. */
__kernel void tr_cl_restir_temporal(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM)
                                        __global const uint *scene_info,
                                    __global const tr_restir_frame *frame,
                                    __global tr_restir_surface *surf, __global tr_reservoir *cur,
                                    __global const tr_restir_surface *prev_surf,
                                    __global const tr_reservoir *prev) {
    const tr_restir_frame fr = *frame;
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= fr.cam.screen_width || y >= fr.cam.screen_height) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    if (!fr.tree) {
        s.light_node_count = 0u;
    }
    tr_restir_pass_temporal(&s, &fr, x, y, surf, cur, prev_surf, prev);
}

__kernel void tr_cl_restir_spatial(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM)
                                       __global const uint *scene_info,
                                   __global const tr_restir_frame *frame,
                                   __global const tr_restir_surface *surf,
                                   __global const tr_reservoir *cur, __global tr_reservoir *out,
                                   __global float *film_sum, __global float *film_direct) {
    const tr_restir_frame fr = *frame;
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= fr.cam.screen_width || y >= fr.cam.screen_height) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    if (!fr.tree) {
        s.light_node_count = 0u;
    }
    tr_restir_pass_spatial(&s, &fr, x, y, surf, cur, out, film_sum, film_direct);
}

/* The sizes of the structs the ReSTIR buffers hold, as this device lays them out. */
__kernel void tr_cl_restir_sizes(__global uint *out) {
    out[0] = (uint)sizeof(tr_restir_surface);
    out[1] = (uint)sizeof(tr_reservoir);
    out[2] = (uint)sizeof(tr_gi_reservoir);
}

/* ReSTIR GI's passes (restir_pass.h) after the direct light's, as the CPU runs them: the
 * scene view as pt sees it (the light tree kept), the surfaces the direct light's first
 * pass found. */
__kernel void tr_cl_restir_gi_temporal(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM)
                                           __global const uint *scene_info,
                                       __global const tr_restir_frame *frame,
                                       __global const tr_restir_surface *surf,
                                       __global tr_gi_reservoir *gcur,
                                       __global const tr_restir_surface *prev_surf,
                                       __global const tr_gi_reservoir *gprev) {
    const tr_restir_frame fr = *frame;
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= fr.cam.screen_width || y >= fr.cam.screen_height) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    tr_restir_gi_pass_temporal(&s, &fr, x, y, surf, gcur, prev_surf, gprev);
}

__kernel void tr_cl_restir_gi_spatial(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM)
                                          __global const uint *scene_info,
                                      __global const tr_restir_frame *frame,
                                      __global const tr_restir_surface *surf,
                                      __global const tr_gi_reservoir *gcur,
                                      __global tr_gi_reservoir *gout, __global float *film_sum) {
    const tr_restir_frame fr = *frame;
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= fr.cam.screen_width || y >= fr.cam.screen_height) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    tr_restir_gi_pass_spatial(&s, &fr, x, y, surf, gcur, gout, film_sum);
}

#endif

#if TR_CL_HAS(1)
/* The first hit's emission at an upscaled output's resolution (src/post/upscale.c's
 * tr_upscale_emission, per output pixel): from the traced frame's emission (wl x hl, the
 * mean per pixel), an output pixel whose traced pixel lies on an emitter's edge, or where
 * the previous output (prev, when have_prev) saw an emitter small enough to lie between
 * the samples (tr_emission_missed) and its traced pixel sees none, traces n x n first-hit
 * rays through the output's camera (the frame's); any other takes its traced pixel's
 * emission. One work item per output pixel. */
__kernel void tr_cl_upscale_emission(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM)
                                         __global const uint *scene_info,
                                     __global const tr_frame *frame, int wl, int hl,
                                     __global const float *emission, int have_prev,
                                     __global const float *prev, int n, __global float *out) {
    const tr_frame f = *frame;
    const int w = (int)f.camera.screen_width, h = (int)f.camera.screen_height;
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const float sxr = (float)wl / (float)w, syr = (float)hl / (float)h;
    int lx = (int)(((float)x + 0.5f) * sxr), ly = (int)(((float)y + 0.5f) * syr);
    lx = lx < wl - 1 ? lx : wl - 1;
    ly = ly < hl - 1 ? ly : hl - 1;
    const uint i = (uint)(y * w + x), k = (uint)(ly * wl + lx);
    const int seen = tr_emission_seen(emission, k);
    const int dx = (int)ceil(2.0f / sxr), dy = (int)ceil(2.0f / syr);
    const int missed = have_prev && !seen && tr_emission_missed(prev, w, h, x, y, dx, dy);
    tr_vec3 e;
    if (missed || tr_emission_on_edge(emission, wl, hl, lx, ly)) {
        tr_scene_view s;
        TR_CL_SCENE_VIEW(s);
        e = tr_emission_resolve_pixel(&s, &f.camera, x, y, n);
    } else {
        e = v3(emission[3u * k], emission[3u * k + 1u], emission[3u * k + 2u]);
    }
    out[3u * i] = e.x;
    out[3u * i + 1u] = e.y;
    out[3u * i + 2u] = e.z;
}

/* Ray throughput (`trac0r bench rays --device opencl`, src/measure/rays.c): one work item
 * per ray of a set, the closest hit (or, for shadow rays, any hit) with the scene's
 * structure; hits[i] is 1 where ray i hit, for the host's cross-check of the counts. */
__kernel void tr_cl_trace_rays(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                               __global const tr_ray *rays, uint count, uint shadow,
                               __global uint *hits) {
    const uint i = (uint)get_global_id(0);
    if (i >= count) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    s.cwbvh_node_count = 0u; /* the binary BVH's row; tr_cl_trace_cwbvh is the wide one's */
    const tr_ray r = rays[i];
    uint h;
    if (shadow) {
        h = tr_occluded_scene(&s, &r) ? 1u : 0u;
    } else {
        tr_hit hit;
        h = tr_intersect_scene(&s, &r, &hit) ? 1u : 0u;
    }
    hits[i] = h;
}

/* tr_cl_trace_rays through a compressed wide BVH (cwbvh.h) given as its own buffers:
 * `bench rays --device` measures it beside the binary BVH. */
__kernel void tr_cl_trace_cwbvh(__global const tr_cwbvh_node *cw_nodes, uint cw_node_count,
                                __global const tr_bvh_tri *cw_tris, __global const tr_ray *rays,
                                uint count, uint shadow, __global uint *hits) {
    const uint i = (uint)get_global_id(0);
    if (i >= count) {
        return;
    }
    const tr_ray r = rays[i];
    tr_hit hit;
    hits[i] = tr_cwbvh_traverse(cw_nodes, cw_node_count, cw_tris, &r, &hit, shadow != 0u) ? 1u : 0u;
}

#endif

#if TR_CL_HAS(3)
/* pt as a wavefront (integrator_pt_wf.h, docs/opencl.md): the host runs a frame in
 * chunks of paths, path i of a chunk being sample f.sample + s_off + i % k of grid point
 * g0 + i / k; for each chunk tr_cl_wf_generate, then extend, shade and connect over the
 * queue of live paths until none is left, then tr_cl_wf_accumulate. Queues hold path
 * numbers; counters[0] counts the next extend queue, counters[1] the shadow queue. */
__kernel void tr_cl_wf_generate(__global const tr_frame *frame, __global tr_pt_wf_path *paths,
                                __global uint *queue, uint g0, uint k, uint s_off, uint n) {
    const uint i = (uint)get_global_id(0);
    if (i >= n) {
        return;
    }
    const tr_frame f = *frame;
    uint gx0, gy0, nx, ny, x, y, bx0, by0, bx1, by1;
    tr_frame_grid(&f, &gx0, &gy0, &nx, &ny);
    const uint g = g0 + i / k;
    const uint64_t pixel =
        tr_frame_point(&f, gx0 + g % nx, gy0 + g / nx, &x, &y, &bx0, &by0, &bx1, &by1);
    const uint64_t seed = ((uint64_t)f.seed_hi << 32) | (uint64_t)f.seed_lo;
    tr_pt_wf_path p;
    tr_pt_wf_generate(&p, &f.camera, seed, f.max_depth, f.sampler, f.passes, x, y, pixel,
                      f.sample + s_off + i % k);
    paths[i] = p;
    queue[i] = i;
}

/* Extend: the closest hit of every queued path's ray. */
__kernel void tr_cl_wf_extend(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                              __global tr_pt_wf_path *paths, __global const uint *queue,
                              uint count) {
    const uint i = (uint)get_global_id(0);
    if (i >= count) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    __global tr_pt_wf_path *gp = &paths[queue[i]];
    const tr_ray r = gp->ray;
    tr_hit hit;
    const uint found = tr_intersect_scene(&s, &r, &hit) ? 1u : 0u;
    gp->hit = hit;
    gp->found = found;
    gp->out.rays += 1u;
}

/* Shade: every queued path's vertex; live paths go to next_queue, paths with light
 * samples to add to shadow_queue. */
__kernel void tr_cl_wf_shade(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                             __global const tr_frame *frame, __global tr_pt_wf_path *paths,
                             __global const uint *queue, uint count, __global uint *next_queue,
                             __global uint *shadow_queue, __global uint *counters) {
    const uint i = (uint)get_global_id(0);
    if (i >= count) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    const uint idx = queue[i];
    tr_pt_wf_path p = paths[idx];
    const int alive = tr_pt_wf_shade(&s, &p, frame->max_depth, frame->rr_start,
                                     frame->clamp_indirect, frame->flags);
    paths[idx] = p;
    if (alive) {
        next_queue[atomic_inc(&counters[0])] = idx;
    }
    if (p.pending != 0u) {
        shadow_queue[atomic_inc(&counters[1])] = idx;
    }
}

/* Connect: the shadow queue's paths (counters[1] of them; the host launches at least that
 * many work items). */
__kernel void tr_cl_wf_connect(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                               __global const tr_frame *frame, __global tr_pt_wf_path *paths,
                               __global const uint *shadow_queue, __global const uint *counters) {
    const uint i = (uint)get_global_id(0);
    if (i >= counters[1]) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    const uint idx = shadow_queue[i];
    tr_pt_wf_path p = paths[idx];
    tr_pt_wf_connect(&s, &p, frame->clamp_indirect);
    paths[idx] = p;
}

/* Accumulate: one work item per grid point of the chunk (points g0 .. g0+n-1) adds its k
 * finished samples to the film in sample order, as tr_render_grid_rows does. */
__kernel void tr_cl_wf_accumulate(__global const tr_frame *frame, __global float *film_sum,
                                  __global uint *film_count, __global float *film_albedo,
                                  __global float *film_normal, __global float *film_depth,
                                  __global uint *film_prim, __global float *film_sq,
                                  __global float *film_direct, __global float *film_emission,
                                  __global float *film_specular, __global uint *rays_per_row,
                                  __global const tr_pt_wf_path *paths, uint g0, uint k, uint n) {
    const uint j = (uint)get_global_id(0);
    if (j >= n) {
        return;
    }
    const tr_frame f = *frame;
    uint gx0, gy0, nx, ny, x, y, bx0, by0, bx1, by1;
    tr_frame_grid(&f, &gx0, &gy0, &nx, &ny);
    const uint g = g0 + j;
    tr_frame_point(&f, gx0 + g % nx, gy0 + g / nx, &x, &y, &bx0, &by0, &bx1, &by1);
    tr_film_view film = TR_CL_FILM_VIEW(f);
    uint rays = 0u;
    for (uint m = 0; m < k; ++m) {
        const tr_pt_wf_path p = paths[j * k + m];
        tr_sample smp;
        tr_pt_wf_finish(&p, &smp);
        rays += smp.rays;
        tr_film_add_block(&film, &smp, bx0, by0, bx1, by1);
    }
    atomic_add(&rays_per_row[g / nx], rays);
}

#endif

#if TR_CL_HAS(4)
/* bdpt and vcm on the device: tr_cl_render's arguments and work items, and the
 * light-tracing splats' fixed-point sums (integrator_bdpt.h), one 64-bit integer per colour
 * channel and pixel of the frame's rectangle, added with atom_add where the device has
 * cl_khr_int64_base_atomics, else with two 32-bit atomic additions that leave the same
 * sum (tr_bdpt_atomic_add64). Integer addition is associative, so the sums are those the
 * CPU's threads make, whatever the order. tr_cl_fold_splats then adds them to the film as
 * the CPU's fold does (src/device/cpu.c), in double precision, where the device has
 * cl_khr_fp64; elsewhere the host folds them. TR_CL_NO_INT64_ATOMICS and TR_CL_NO_FP64
 * (TRAC0R_OPENCL_DISABLE_EXT, src/device/opencl.c) take those paths on any device. */
#if defined(cl_khr_int64_base_atomics) && !defined(TR_CL_NO_INT64_ATOMICS)
#pragma OPENCL EXTENSION cl_khr_int64_base_atomics : enable
#else
#define TR_BDPT_ATOM64_EMULATED 1
#endif
#include "integrator_bdpt.h"
#include "integrator_vcm.h"

/* tr_cl_render's arguments after the scene's, and the splat sums: what tr_cl_render_bdpt and
 * tr_cl_render_vcm take first. */
#define TR_CL_BIDIR_PARAMS                                                                         \
    TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM)                                                             \
    __global const uint *scene_info, __global const tr_frame *frame, __global float *film_sum,     \
        __global uint *film_count, __global float *film_albedo, __global float *film_normal,       \
        __global float *film_depth, __global uint *film_prim, __global float *film_sq,             \
        __global float *film_direct, __global float *film_emission, __global float *film_specular, \
        __global uint *rays_per_row, __global long *splat

/* The splat sums of frame f's rectangle. */
static tr_bdpt_splat tr_cl_splat(const tr_frame *f, __global long *splat) {
    tr_bdpt_splat sp;
    sp.sum = splat;
    sp.x0 = f->rect_x;
    sp.y0 = f->rect_y;
    sp.w = f->rect_w;
    sp.h = f->rect_h;
    return sp;
}

__kernel void tr_cl_render_bdpt(TR_CL_BIDIR_PARAMS) {
    const tr_frame f = *frame;
    uint gx0, gy0, nx, ny;
    tr_frame_grid(&f, &gx0, &gy0, &nx, &ny);
    const uint gx = (uint)get_global_id(0), gy = (uint)get_global_id(1);
    if (gx >= nx || gy >= ny) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    tr_film_view film = TR_CL_FILM_VIEW(f);
    const tr_bdpt_splat sp = tr_cl_splat(&f, splat);
    const uint rays = tr_bdpt_render_grid_rows(&s, &f, &film, &sp, gx0 + gx, gy0 + gy,
                                               gx0 + gx + 1u, gy0 + gy + 1u);
    atomic_add(&rays_per_row[gy], rays);
}

/* vcm's first pass for one sample (integrator_vcm.h, tr_vcm_device_light): one work item
 * per grid point traces its light subpath and writes its mergeable vertices as one block
 * of entries, reserved with an atomic addition on *counter, with their buckets' full
 * hashes; point_first and point_count say where each point's block lies. Where the
 * entries do not fit in `room`, the counter still says how many there are. */
__kernel void tr_cl_vcm_light(TR_SCENE_ARRAYS(TR_CL_ARRAY_PARAM) __global const uint *scene_info,
                              __global const tr_frame *frame, __global const tr_vcm_params *params,
                              __global tr_vcm_entry *entries, __global uint *hash, uint room,
                              __global uint *counter, __global uint *point_first,
                              __global uint *point_count) {
    const tr_frame f = *frame;
    uint gx0, gy0, nx, ny;
    tr_frame_grid(&f, &gx0, &gy0, &nx, &ny);
    const uint gx = (uint)get_global_id(0), gy = (uint)get_global_id(1);
    if (gx >= nx || gy >= ny) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    const tr_vcm_params p = *params;
    uint first;
    const uint n =
        tr_vcm_device_light(&s, &f, &p, gx0 + gx, gy0 + gy, entries, hash, counter, room, &first);
    point_first[gy * nx + gx] = first;
    point_count[gy * nx + gx] = n;
}

/* The entries in bucket order: sorted[k] = entries[order[k]] (the order the host made,
 * tr_vcm_bucket_order). One work item per entry. */
__kernel void tr_cl_vcm_gather(__global const tr_vcm_entry *entries, __global const uint *order,
                               uint count, __global tr_vcm_entry *sorted) {
    const uint k = (uint)get_global_id(0);
    if (k < count) {
        sorted[k] = entries[order[k]];
    }
}

/* vcm's second pass for one sample: tr_cl_render_bdpt's arguments and work items, then the
 * sample's grid (its scalars, the buckets' offsets and the sorted entries). */
__kernel void tr_cl_render_vcm(TR_CL_BIDIR_PARAMS, __global const tr_vcm_params *params,
                               __global const uint *cell_first,
                               __global const tr_vcm_entry *sorted) {
    const tr_frame f = *frame;
    uint gx0, gy0, nx, ny;
    tr_frame_grid(&f, &gx0, &gy0, &nx, &ny);
    const uint gx = (uint)get_global_id(0), gy = (uint)get_global_id(1);
    if (gx >= nx || gy >= ny) {
        return;
    }
    tr_scene_view s;
    TR_CL_SCENE_VIEW(s);
    tr_film_view film = TR_CL_FILM_VIEW(f);
    const tr_bdpt_splat sp = tr_cl_splat(&f, splat);
    const tr_vcm_params p = *params;
    const tr_vcm_grid g = tr_vcm_grid_of(&p, cell_first, sorted);
    const uint rays = tr_vcm_device_camera(&s, &f, &film, &sp, &g, p.sample, gx0 + gx, gy0 + gy);
    atomic_add(&rays_per_row[gy], rays);
}

#if defined(cl_khr_fp64) && !defined(TR_CL_NO_FP64)
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
/* Adds the splat sums to the film after the frame: pixel (x, y) of the rectangle gets
 * (float)(sum * scale) per channel, scale = W H / (grid 2^24) as the host computed it
 * (the frame's grid points, src/device/cpu.c's tr_bdpt_fold_splats). One work item per
 * pixel of the rectangle. */
__kernel void tr_cl_fold_splats(__global const tr_frame *frame, __global const long *splat,
                                double scale, __global float *film_sum) {
    const uint w = frame->rect_w, h = frame->rect_h;
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const size_t i = (size_t)(frame->rect_y + y) * frame->camera.screen_width + (frame->rect_x + x);
    const size_t j = 3u * ((size_t)y * w + x);
    for (int c = 0; c < 3; ++c) {
        film_sum[3u * i + (size_t)c] += (float)((double)splat[j + (size_t)c] * scale);
    }
}
#endif
#endif
