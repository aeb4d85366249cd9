/* upscale.h - the per-pixel operator of temporal upscaling: one output pixel of a full-
 * resolution image reconstructed from a frame that traced fewer pixels, and from the
 * output's own history (TAAU: Karis 2014's temporal antialiasing with an upsampling
 * step, as AMD's FSR 2 and Unreal's TAAU do it).
 *
 * The frame is wl x hl pixels seen through a camera of the same view as the output's
 * (W x H). Each of its pixels holds one value (the frame's colour, or a reconstruction of
 * it) and the position, in output pixels, of the sample it was traced at: the kernel
 * jitters every sample inside its pixel, and the stateless samplers let the host say
 * exactly where (tr_upscale_positions). A sample belongs to the output pixel it fell in.
 *
 * Output pixel (x, y) looks at the 3 x 3 frame pixels around the one its centre lies in:
 *
 *   - the samples that fell inside it are this frame's new estimate (n of them);
 *   - the sample nearest its centre gives its distance and primitive, through which the
 *     pixel's surface point is reprojected into the previous camera (following its
 *     primitive's motion, as the reconstruction's temporal stage does); the history is
 *     read there with a Catmull-Rom filter, which keeps the image sharp under motion
 *     where a bilinear read would blur it frame after frame;
 *   - the history survives where the surface it saw (its distance) is still among the
 *     nine samples, so that a disocclusion starts over, at rest too;
 *   - where the view moved, the nine values' range in YCoCg (Karis 2014) bounds the
 *     history, so that colour a surface no longer has cannot linger. A pixel at rest is
 *     not bounded: there the history is the better estimate, and nine samples at other
 *     places than the pixel's miss thin detail, which the bound would then erase;
 *   - the history and the new samples are averaged by their counts (a uniform mean up to
 *     max_len samples, an exponential one after), so a static view converges to the mean
 *     of every sample that fell in the pixel, which is what tracing every pixel gives;
 *   - a pixel with neither history nor a sample shows the Gaussian-weighted mean of the
 *     nine values (its count stays 0, so the next sample replaces it).
 *
 * Single source like filter.h: C99 that compiles as OpenCL C 1.2. */
#ifndef TR_POST_UPSCALE_H
#define TR_POST_UPSCALE_H

#include "filter.h"

/* Linear RGB to YCoCg and back. */
TR_FN void tr_up_ycocg(const float c[3], float o[3]) {
    o[0] = 0.25f * c[0] + 0.5f * c[1] + 0.25f * c[2];
    o[1] = 0.5f * c[0] - 0.5f * c[2];
    o[2] = -0.25f * c[0] + 0.5f * c[1] - 0.25f * c[2];
}
TR_FN void tr_up_rgb(const float y[3], float o[3]) {
    o[0] = y[0] + y[1] - y[2];
    o[1] = y[0] + y[2];
    o[2] = y[0] - y[1] - y[2];
}

/* The Catmull-Rom weights of the four taps around a position t in [0, 1) past tap 1. */
TR_FN void tr_up_catmull_rom(float t, float w[4]) {
    w[0] = t * (-0.5f + t * (1.0f - 0.5f * t));
    w[1] = 1.0f + t * t * (-2.5f + 1.5f * t);
    w[2] = t * (0.5f + t * (2.0f - 1.5f * t));
    w[3] = t * t * (-0.5f + 0.5f * t);
}

/* The history (3 floats per pixel, w x h) at the continuous position (qx, qy), pixel
 * centres at k + 0.5, through a 4 x 4 Catmull-Rom filter (taps clamped to the image). */
TR_FN void tr_up_history_read(TR_CONST_GLOBAL float *hist, int w, int h, float qx, float qy,
                              float out[3]) {
    const float fx = qx - 0.5f, fy = qy - 0.5f;
    const int ix = (int)tr_floorf(fx), iy = (int)tr_floorf(fy);
    float wx[4], wy[4];
    tr_up_catmull_rom(fx - (float)ix, wx);
    tr_up_catmull_rom(fy - (float)iy, wy);
    out[0] = out[1] = out[2] = 0.0f;
    for (int j = 0; j < 4; ++j) {
        int ty = iy - 1 + j;
        ty = ty < 0 ? 0 : ty >= h ? h - 1 : ty;
        for (int i = 0; i < 4; ++i) {
            int tx = ix - 1 + i;
            tx = tx < 0 ? 0 : tx >= w ? w - 1 : tx;
            const float wt = wx[i] * wy[j];
            const int k = 3 * (ty * w + tx);
            out[0] += wt * hist[k];
            out[1] += wt * hist[k + 1];
            out[2] += wt * hist[k + 2];
        }
    }
}

/* Output pixel (x, y) of a camera `cam` (W x H) from the frame (wl x hl: colour col, 3
 * per pixel; sample positions pos in output pixels, 2 per pixel; distance along the ray
 * depth and primitive prim, 1 per pixel) and the history (hcol, hlen and hdepth of the
 * previous output, seen through `prev`; hcol NULL: none). motion: 3 floats per primitive
 * id below motion_count (NULL: nothing moved). Writes the pixel's colour (3 floats), its
 * count of samples and its distance, for the next frame's history. */
TR_FN void tr_upscale_pixel(const tr_camera *cam, const tr_camera *prev, int x, int y, int wl,
                            int hl, TR_CONST_GLOBAL float *col, TR_CONST_GLOBAL float *pos,
                            TR_CONST_GLOBAL float *depth, TR_CONST_GLOBAL uint32_t *prim,
                            TR_CONST_GLOBAL float *motion, uint32_t motion_count,
                            TR_CONST_GLOBAL float *hcol, TR_CONST_GLOBAL float *hlen,
                            TR_CONST_GLOBAL float *hdepth, float max_len, float out[3],
                            float *out_len, float *out_depth) {
    const int w = (int)cam->screen_width, h = (int)cam->screen_height;
    const float cx = (float)x + 0.5f, cy = (float)y + 0.5f;
    const float sxr = (float)wl / (float)w, syr = (float)hl / (float)h;
    int lx = (int)(cx * sxr), ly = (int)(cy * syr);
    lx = lx < wl - 1 ? lx : wl - 1;
    ly = ly < hl - 1 ? ly : hl - 1;
    float sum[3] = {0.0f, 0.0f, 0.0f};
    float n = 0.0f, best = 1e30f, d = 0.0f;
    uint32_t id = 0u;
    for (int dy = -1; dy <= 1; ++dy) {
        const int ty = ly + dy;
        if (ty < 0 || ty >= hl) {
            continue;
        }
        for (int dx = -1; dx <= 1; ++dx) {
            const int tx = lx + dx;
            if (tx < 0 || tx >= wl) {
                continue;
            }
            const int k = ty * wl + tx;
            const float px = pos[2 * k], py = pos[2 * k + 1];
            const float ex = px - cx, ey = py - cy, e2 = ex * ex + ey * ey;
            if ((int)tr_floorf(px) == x && (int)tr_floorf(py) == y) {
                sum[0] += col[3 * k];
                sum[1] += col[3 * k + 1];
                sum[2] += col[3 * k + 2];
                n += 1.0f;
            }
            if (e2 < best) {
                best = e2;
                d = depth[k];
                id = prim[k];
            }
        }
    }
    *out_depth = d;
    /* The history: the pixel's point (its centre's ray at the nearest sample's distance,
     * far away where that sample saw nothing) followed back by its primitive's motion and
     * projected into the previous camera. */
    int have = 0;
    float hv[3] = {0.0f, 0.0f, 0.0f}, len = 0.0f, moved = 0.0f;
    if (hcol) {
        tr_vec3 p = tr_post_world_point(cam, (float)x, (float)y, d > 0.0f ? d : 1e6f);
        if (motion && d > 0.0f && id < motion_count) {
            p = v3_sub(p, v3(motion[3 * id], motion[3 * id + 1], motion[3 * id + 2]));
        }
        float qx, qy, dist;
        if (tr_post_project(prev, p, &qx, &qy, &dist) && qx >= 0.0f && qy >= 0.0f &&
            qx < (float)w && qy < (float)h) {
            const int nx = (int)qx, ny = (int)qy, j = ny * w + nx;
            const float mx = qx - cx, my = qy - cy;
            moved = mx * mx + my * my;
            /* The surface the history saw there must still be in the neighbourhood: one
             * of the nine samples at its distance (within 5 %, each moved as the nearest
             * one did from the previous camera), or nothing hit for nothing hit. Else it
             * was uncovered (a disocclusion, a shape that moved away) and starts over. */
            const float hd = hdepth[j], shift = d > 0.0f ? dist - d : 0.0f;
            int found = 0;
            for (int dy = -1; dy <= 1 && !found; ++dy) {
                const int ty = ly + dy;
                for (int dx = -1; dx <= 1 && ty >= 0 && ty < hl; ++dx) {
                    const int tx = lx + dx;
                    if (tx < 0 || tx >= wl) {
                        continue;
                    }
                    const float dk = depth[ty * wl + tx];
                    if (dk > 0.0f ? hd > 0.0f && tr_fabsf(dk + shift - hd) <= 0.05f * hd
                                  : !(hd > 0.0f)) {
                        found = 1;
                        break;
                    }
                }
            }
            if (found && hlen[j] > 0.0f) {
                tr_up_history_read(hcol, w, h, qx, qy, hv);
                len = hlen[j];
                have = 1;
            }
        }
    }
    if (have && moved >= 1e-4f) {
        /* Where the view moved: bounded by the neighbourhood's range. */
        float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
        for (int dy = -1; dy <= 1; ++dy) {
            const int ty = ly + dy;
            for (int dx = -1; dx <= 1 && ty >= 0 && ty < hl; ++dx) {
                const int tx = lx + dx;
                if (tx < 0 || tx >= wl) {
                    continue;
                }
                const int k = ty * wl + tx;
                const float c[3] = {col[3 * k], col[3 * k + 1], col[3 * k + 2]};
                float ck[3];
                tr_up_ycocg(c, ck);
                for (int j = 0; j < 3; ++j) {
                    lo[j] = tr_fminf(lo[j], ck[j]);
                    hi[j] = tr_fmaxf(hi[j], ck[j]);
                }
            }
        }
        float yc[3], rgb[3];
        tr_up_ycocg(hv, yc);
        for (int j = 0; j < 3; ++j) {
            yc[j] = tr_fminf(tr_fmaxf(yc[j], lo[j]), hi[j]);
        }
        tr_up_rgb(yc, rgb);
        hv[0] = tr_fmaxf(rgb[0], 0.0f);
        hv[1] = tr_fmaxf(rgb[1], 0.0f);
        hv[2] = tr_fmaxf(rgb[2], 0.0f);
    }
    if (n > 0.0f) {
        if (have) {
            const float keep = tr_fminf(len, tr_fmaxf(max_len - n, 0.0f));
            const float inv = 1.0f / (keep + n);
            for (int j = 0; j < 3; ++j) {
                out[j] = (hv[j] * keep + sum[j]) * inv;
            }
            *out_len = keep + n;
        } else {
            for (int j = 0; j < 3; ++j) {
                out[j] = sum[j] / n;
            }
            *out_len = n;
        }
    } else if (have) {
        out[0] = hv[0];
        out[1] = hv[1];
        out[2] = hv[2];
        *out_len = len;
    } else {
        /* The spatial fill: a Gaussian of half a frame pixel's width over the nine. */
        const float sigma = 0.5f / (sxr < syr ? sxr : syr);
        const float inv2s2 = 1.0f / (2.0f * sigma * sigma);
        float sp[3] = {0.0f, 0.0f, 0.0f}, spw = 0.0f;
        for (int dy = -1; dy <= 1; ++dy) {
            const int ty = ly + dy;
            for (int dx = -1; dx <= 1 && ty >= 0 && ty < hl; ++dx) {
                const int tx = lx + dx;
                if (tx < 0 || tx >= wl) {
                    continue;
                }
                const int k = ty * wl + tx;
                const float ex = pos[2 * k] - cx, ey = pos[2 * k + 1] - cy;
                const float g = tr_post_exp_neg((ex * ex + ey * ey) * inv2s2);
                sp[0] += g * col[3 * k];
                sp[1] += g * col[3 * k + 1];
                sp[2] += g * col[3 * k + 2];
                spw += g;
            }
        }
        const float inv = spw > 0.0f ? 1.0f / spw : 0.0f;
        out[0] = sp[0] * inv;
        out[1] = sp[1] * inv;
        out[2] = sp[2] * inv;
        *out_len = 0.0f;
    }
}

#endif
