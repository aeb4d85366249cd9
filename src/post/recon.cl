/* recon.cl - real-time reconstruction on an OpenCL device: one kernel per stage of
 * tr_recon_frame (src/post/filter.c), each a work item per pixel calling the per-pixel
 * operators of filter.h, the very text the host's filters are checked against. The
 * host side is src/post/recon_opencl.c; cmake/EmbedKernel.cmake inlines this file and
 * the headers it includes into one string (tr_cl_recon_source).
 *
 * Every kernel takes the image size and returns for work items outside it, so the
 * host may round the global size up. */
#pragma OPENCL FP_CONTRACT OFF

#include "filter.h"
#include "upscale.h"

/* The device film's means into the frame's buffers (tr_gbuffer_from_film's arithmetic):
 * passes bit 0 albedo, 1 normal, 2 depth, 3 primitive id, 4 emission, 5 direct light, 6
 * the specular split (8 floats); a pass the film lacks reads as albedo 1, normal, depth,
 * id and emission 0 (the direct and specular ones are then not written). */
__kernel void tr_recon_from_film(
    __global const float *sum, __global const uint *count, __global const float *albedo_sum,
    __global const float *normal_sum, __global const float *depth_sum, __global const uint *prim_in,
    __global const float *emission_sum, __global const float *direct_sum,
    __global const float *specular_sum, uint passes, int w, int h, __global float *color,
    __global float *albedo, __global float *normal, __global float *depth, __global uint *prim,
    __global float *emission, __global float *direct, __global float *specular) {
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const int i = y * w + x;
    const uint c = count[i];
    const float inv = c ? 1.0f / (float)c : 0.0f;
    for (int k = 0; k < 3; ++k) {
        color[3 * i + k] = sum[3 * i + k] * inv;
        albedo[3 * i + k] = (passes & 1u) ? albedo_sum[3 * i + k] * inv : 1.0f;
        normal[3 * i + k] = (passes & 2u) ? normal_sum[3 * i + k] * inv : 0.0f;
        emission[3 * i + k] = (passes & 16u) ? emission_sum[3 * i + k] * inv : 0.0f;
        if (passes & 32u) {
            direct[3 * i + k] = direct_sum[3 * i + k] * inv;
        }
    }
    if (passes & 64u) {
        for (int k = 0; k < 8; ++k) {
            specular[8 * i + k] = specular_sum[8 * i + k] * inv;
        }
    }
    depth[i] = (passes & 4u) ? depth_sum[i] * inv : 0.0f;
    prim[i] = (passes & 8u) ? prim_in[i] : 0u;
}

/* dst += scale * src, 3 floats per pixel: the emission taken out of the frame's colour
 * before the filters (scale -1) and added to their output after (scale 1). */
__kernel void tr_recon_add(__global float *dst, __global const float *src, float scale, int w,
                           int h) {
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const int i = y * w + x;
    for (int k = 0; k < 3; ++k) {
        dst[3 * i + k] += scale * src[3 * i + k];
    }
}

/* Demodulation (remod 0: in / albedo factor) or remodulation (remod 1: in * factor); 2 and
 * 3 the same with the upscaling's factor (tr_post_upscale_factor), 3 giving 0 where the
 * albedo is 0. */
__kernel void tr_recon_modulate(__global const float *in, __global const float *albedo, int remod,
                                int w, int h, __global float *out) {
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const int i = y * w + x;
    for (int k = 0; k < 3; ++k) {
        const float raw = albedo[3 * i + k];
        const float a = remod < 2 ? tr_post_demod_factor(raw) : tr_post_upscale_factor(raw);
        /* remod 3: an albedo of 0 (no surface) reflects nothing, whatever light the
         * upscaling spread there. */
        out[3 * i + k] = remod == 0 || remod == 2   ? in[3 * i + k] / a
                         : remod == 1 || raw > 0.0f ? in[3 * i + k] * a
                                                    : 0.0f;
    }
}

/* Diffuse and specular apart (svgf_specular), filter.c's spec_prepare: the pixel's
 * specular albedo F0 A + B (the DFG table `dfg` at its mean F0 and alpha and the cosine
 * between its normal and the camera ray of cams[0]; 0 where it has no specular lobe) into
 * spec_alb, its specular light over it into illum_s, the rest of its colour (the diffuse
 * light) into diffuse. A pixel replaced through a refraction or a curved mirror
 * (TR_PRIM_PSR_CURVED) keeps all its light in the diffuse part. */
__kernel void tr_recon_spec_prepare(__global const tr_camera *cams, __global const float *color,
                                    __global const float *normal, __global const uint *prim,
                                    __global const float *specular, __global const float *dfg,
                                    __global float *spec_alb, __global float *illum_s,
                                    __global float *diffuse) {
    const tr_camera cam = cams[0];
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= cam.screen_width || y >= cam.screen_height) {
        return;
    }
    const uint i = y * cam.screen_width + x;
    const tr_vec3 n = v3(normal[3 * i], normal[3 * i + 1], normal[3 * i + 2]);
    float alb[3], ill[3], dif[3];
    tr_post_spec_split_pixel(&cam, x, y, n, prim[i], specular + 8 * i, dfg, color + 3 * i, alb, ill,
                             dif);
    for (int k = 0; k < 3; ++k) {
        spec_alb[3 * i + k] = alb[k];
        illum_s[3 * i + k] = ill[k];
        diffuse[3 * i + k] = dif[k];
    }
}

/* A pixel's history cap: tr_post_max_len's, lowered to the temporal gradients' len_cap[i]
 * where the shading changed (have_cap: the frame has them; the host's tr_recon.len_cap). */
static float tr_recon_cap(tr_vec3 m, float max_len, float max_len_moving,
                          __global const float *len_cap, int have_cap, uint i) {
    const float cap = tr_post_max_len(m, max_len, max_len_moving);
    return have_cap ? tr_fminf(cap, len_cap[i]) : cap;
}

/* The specular part's temporal stage, filter.c's spec_temporal: illum_s reprojected by
 * virtual motion (the reflection's distance weighed by the roughness) with a history cap
 * from the roughness, or a fresh history where fewer than 5 % of the taps' weight survive
 * or without history. */
__kernel void tr_recon_spec_temporal(
    __global const tr_camera *cams, __global const float *illum_s, __global const float *normal,
    __global const float *depth, __global const uint *prim, __global const float *specular,
    __global const float *prev_color, __global const float *prev_moments,
    __global const float *prev_len, __global const float *prev_depth,
    __global const float *prev_normal, __global const uint *prev_prim, __global const float *motion,
    uint motion_count, int have_history, float alpha_min, float max_len, float max_len_moving,
    __global float *out_color, __global float *out_moments, __global float *out_len,
    __global const float *len_cap, int have_cap) {
    const tr_camera cam = cams[0], prev = cams[1];
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    const int w = (int)cam.screen_width;
    if (x >= cam.screen_width || y >= cam.screen_height) {
        return;
    }
    const uint i = y * cam.screen_width + x;
    const float c[3] = {illum_s[3 * i], illum_s[3 * i + 1], illum_s[3 * i + 2]};
    const uint id = prim[i];
    const tr_vec3 m =
        id < motion_count ? v3(motion[3 * id], motion[3 * id + 1], motion[3 * id + 2]) : v3s(0.0f);
    const tr_vec3 n = v3(normal[3 * i], normal[3 * i + 1], normal[3 * i + 2]);
    float oc[3], om[2], ol;
    tr_post_spec_temporal_pixel(
        &cam, &prev, x, y, w, c, n, depth[i], id, m, specular[8 * i + 6], specular[8 * i + 7],
        have_history, prev_color, prev_moments, prev_len, prev_depth, prev_normal, prev_prim,
        alpha_min, tr_recon_cap(m, max_len, max_len_moving, len_cap, have_cap, i), oc, om, &ol);
    out_color[3 * i] = oc[0];
    out_color[3 * i + 1] = oc[1];
    out_color[3 * i + 2] = oc[2];
    out_moments[2 * i] = om[0];
    out_moments[2 * i + 1] = om[1];
    out_len[i] = ol;
}

/* Temporal accumulation (tr_post_temporal_pixel_taps) through cams[0] (this frame) and
 * cams[1] (the previous one); without history (have_history 0) each pixel starts over
 * with its own sample, length 1. motion: 3 floats per primitive id below motion_count,
 * its movement since the previous frame (tr_recon_frame_moving). With albedo_alpha > 0
 * the albedo history too (filter.c's temporal stage): where the colour's history
 * survives, prev_albedo read at the same taps and blended with this frame's albedo at
 * weight max(albedo_alpha, 1 / the new length) (tr_post_albedo_blend), elsewhere or
 * without one (have_albedo 0) this frame's albedo, into out_albedo. */
__kernel void tr_recon_temporal(__global const tr_camera *cams, __global const float *illum,
                                __global const float *normal, __global const float *depth,
                                __global const uint *prim, __global const float *prev_color,
                                __global const float *prev_moments, __global const float *prev_len,
                                __global const float *prev_depth, __global const float *prev_normal,
                                __global const uint *prev_prim, __global const float *motion,
                                uint motion_count, int have_history, float alpha_min, float max_len,
                                float max_len_moving, __global float *out_color,
                                __global float *out_moments, __global float *out_len,
                                __global const float *albedo, __global const float *prev_albedo,
                                int have_albedo, float albedo_alpha, __global float *out_albedo,
                                __global const float *len_cap, int have_cap) {
    const tr_camera cam = cams[0], prev = cams[1];
    const uint x = (uint)get_global_id(0), y = (uint)get_global_id(1);
    if (x >= cam.screen_width || y >= cam.screen_height) {
        return;
    }
    const uint i = y * cam.screen_width + x;
    float c[3], m[2], len, w[4], total = 0.0f;
    int x0 = 0, y0 = 0;
    if (!have_history) {
        const float l = tr_post_luminance(illum[3 * i], illum[3 * i + 1], illum[3 * i + 2]);
        c[0] = illum[3 * i];
        c[1] = illum[3 * i + 1];
        c[2] = illum[3 * i + 2];
        m[0] = l;
        m[1] = l * l;
        len = 1.0f;
    } else {
        const uint id = prim[i];
        const tr_vec3 mv = id < motion_count
                               ? v3(motion[3 * id], motion[3 * id + 1], motion[3 * id + 2])
                               : v3s(0.0f);
        total = tr_post_temporal_pixel_taps(
            &cam, &prev, x, y, mv, illum, normal, depth, prim, prev_color, prev_moments, prev_len,
            prev_depth, prev_normal, prev_prim, alpha_min,
            tr_recon_cap(mv, max_len, max_len_moving, len_cap, have_cap, i), c, m, &len, w, &x0,
            &y0);
    }
    out_color[3 * i] = c[0];
    out_color[3 * i + 1] = c[1];
    out_color[3 * i + 2] = c[2];
    out_moments[2 * i] = m[0];
    out_moments[2 * i + 1] = m[1];
    out_len[i] = len;
    if (albedo_alpha > 0.0f) {
        float a[3] = {albedo[3 * i], albedo[3 * i + 1], albedo[3 * i + 2]};
        if (total > 0.0f && have_albedo) {
            tr_post_albedo_blend(albedo + 3 * i, total, w, x0, y0, (int)prev.screen_width,
                                 prev_albedo, tr_fmaxf(albedo_alpha, 1.0f / len), a);
        }
        out_albedo[3 * i] = a[0];
        out_albedo[3 * i + 1] = a[1];
        out_albedo[3 * i + 2] = a[2];
    }
}

__kernel void tr_recon_bilateral(__global const float *in, int w, int h, int radius, float sigma_s,
                                 float sigma_r, __global float *out) {
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const int i = y * w + x;
    float o[3];
    tr_post_bilateral_pixel(in, w, h, x, y, radius, sigma_s, sigma_r, o);
    out[3 * i] = o[0];
    out[3 * i + 1] = o[1];
    out[3 * i + 2] = o[2];
}

__kernel void tr_recon_atrous(__global const float *in, __global const float *normal,
                              __global const float *depth, __global const float *albedo, int w,
                              int h, int step, float sigma_c, float sigma_n, float sigma_z,
                              float sigma_a, __global float *out) {
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const int i = y * w + x;
    float o[3];
    tr_post_atrous_pixel(in, normal, depth, albedo, w, h, x, y, step, sigma_c, sigma_n, sigma_z,
                         sigma_a, o);
    out[3 * i] = o[0];
    out[3 * i + 1] = o[1];
    out[3 * i + 2] = o[2];
}

/* SVGF's variance estimate (tr_post_svgf_variance_pixel) of the accumulated illumination. */
__kernel void tr_recon_svgf_variance(__global const float *illum, __global const float *moments,
                                     __global const float *len, __global const float *normal, int w,
                                     int h, __global float *var) {
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    var[y * w + x] = tr_post_svgf_variance_pixel(illum, moments, len, normal, w, h, x, y);
}

/* One SVGF iteration (tr_post_svgf_pixel), the centre's variance through the paper's
 * 3x3 Gaussian (tr_post_var3x3) as the host prefilters it. */
__kernel void tr_recon_svgf(__global const float *in, __global const float *var,
                            __global const float *normal, __global const float *depth, int w, int h,
                            int step, float sigma_l, float sigma_n, float sigma_z,
                            __global float *out, __global float *out_var) {
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= w || y >= h) {
        return;
    }
    const int i = y * w + x;
    float o[3], v;
    tr_post_svgf_pixel(in, var, normal, depth, w, h, x, y, step, sigma_l, sigma_n, sigma_z,
                       tr_post_var3x3(var, w, h, x, y), o, &v);
    out[3 * i] = o[0];
    out[3 * i + 1] = o[1];
    out[3 * i + 2] = o[2];
    out_var[i] = v;
}

/* SVGF's temporal antialiasing (tr_post_taa_pixel); have_prev 0: no previous output. */
__kernel void tr_recon_taa(__global const tr_camera *cams, __global const float *cur,
                           __global const float *normal, __global const float *depth,
                           __global const uint *prim, __global const float *prev_out, int have_prev,
                           __global const float *prev_depth, __global const float *prev_normal,
                           __global const uint *prev_prim, float alpha, __global float *out) {
    const tr_camera cam = cams[0], prev = cams[1];
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= (int)cam.screen_width || y >= (int)cam.screen_height) {
        return;
    }
    const int i = y * (int)cam.screen_width + x;
    float o[3];
    tr_post_taa_pixel(&cam, &prev, x, y, cur, normal, depth, prim,
                      have_prev ? prev_out : (__global const float *)0, prev_depth, prev_normal,
                      prev_prim, alpha, o);
    out[3 * i] = o[0];
    out[3 * i + 1] = o[1];
    out[3 * i + 2] = o[2];
}

/* Temporal upscaling (upscale.h's tr_upscale_pixel, the host's tr_upscale_frame per output
 * pixel): the output of cams[0] (w x h, its screen) from a traced frame of wl x hl (col,
 * its samples' positions pos, depth and prim) and the output's history seen through
 * cams[1] (have 0: none); motion: 3 floats per primitive id below motion_count (0: none).
 * Writes the new history: colour, sample count and distance per output pixel. */
__kernel void tr_recon_upscale(__global const tr_camera *cams, int wl, int hl,
                               __global const float *col, __global const float *pos,
                               __global const float *depth, __global const uint *prim,
                               __global const float *motion, uint motion_count, int have,
                               __global const float *hcol, __global const float *hlen,
                               __global const float *hdepth, float max_len, __global float *ocol,
                               __global float *olen, __global float *odepth) {
    const tr_camera cam = cams[0], prev = cams[1];
    const int x = (int)get_global_id(0), y = (int)get_global_id(1);
    if (x >= (int)cam.screen_width || y >= (int)cam.screen_height) {
        return;
    }
    const int i = y * (int)cam.screen_width + x;
    float o[3], len, d;
    tr_upscale_pixel(&cam, &prev, x, y, wl, hl, col, pos, depth, prim,
                     motion_count ? motion : (__global const float *)0, motion_count,
                     have ? hcol : (__global const float *)0, hlen, hdepth,
                     (__global const float *)0, max_len, o, &len, &d);
    ocol[3 * i] = o[0];
    ocol[3 * i + 1] = o[1];
    ocol[3 * i + 2] = o[2];
    olen[i] = len;
    odepth[i] = d;
}
