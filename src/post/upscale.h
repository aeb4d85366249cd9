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
    /* floor without a libm call (fx, fy >= -0.5: the position lies on the image). */
    const int ix = (int)(fx + 1.0f) - 1, iy = (int)(fy + 1.0f) - 1;
    float wx[4], wy[4];
    tr_up_catmull_rom(fx - (float)ix, wx);
    tr_up_catmull_rom(fy - (float)iy, wy);
    out[0] = out[1] = out[2] = 0.0f;
    const int inside = ix >= 1 && iy >= 1 && ix + 2 < w && iy + 2 < h;
    for (int j = 0; j < 4; ++j) {
        int ty = iy - 1 + j;
        ty = inside ? ty : ty < 0 ? 0 : ty >= h ? h - 1 : ty;
        float r[3] = {0.0f, 0.0f, 0.0f};
        for (int i = 0; i < 4; ++i) {
            int tx = ix - 1 + i;
            tx = inside ? tx : tx < 0 ? 0 : tx >= w ? w - 1 : tx;
            const int k = 3 * (ty * w + tx);
            r[0] += wx[i] * hist[k];
            r[1] += wx[i] * hist[k + 1];
            r[2] += wx[i] * hist[k + 2];
        }
        out[0] += wy[j] * r[0];
        out[1] += wy[j] * r[1];
        out[2] += wy[j] * r[2];
    }
}

/* The range in YCoCg of the 3 x 3 traced pixels around (x, y) of a w x h frame (colour
 * col, 3 floats per pixel): low Y, Co, Cg then high into box[0..5]. */
TR_FN void tr_upscale_box_pixel(TR_CONST_GLOBAL float *col, int w, int h, int x, int y,
                                float box[6]) {
    box[0] = box[1] = box[2] = 1e30f;
    box[3] = box[4] = box[5] = -1e30f;
    for (int dy = -1; dy <= 1; ++dy) {
        const int ty = y + dy;
        for (int dx = -1; dx <= 1 && ty >= 0 && ty < h; ++dx) {
            const int tx = x + dx;
            if (tx < 0 || tx >= w) {
                continue;
            }
            const int k = ty * w + tx;
            const float c[3] = {col[3 * k], col[3 * k + 1], col[3 * k + 2]};
            float ck[3];
            tr_up_ycocg(c, ck);
            for (int j = 0; j < 3; ++j) {
                box[j] = tr_fminf(box[j], ck[j]);
                box[3 + j] = tr_fmaxf(box[3 + j], ck[j]);
            }
        }
    }
}

/* The spatial fill of output pixel (x, y) (traced pixel (lx, ly) under its centre, sxr
 * and syr the traced frame's size over the output's): a Gaussian of half a frame pixel's
 * width over the 3 x 3 traced values around it, into out. */
TR_FN void tr_upscale_fill(int x, int y, int wl, int hl, int lx, int ly, float sxr, float syr,
                           TR_CONST_GLOBAL float *col, TR_CONST_GLOBAL float *pos, float out[3]) {
    const float cx = (float)x + 0.5f, cy = (float)y + 0.5f;
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
}

/* The end of tr_upscale_pixel for a pixel with history hv (have: whether it has one; len
 * its count; moved: how far it moved, squared, in output pixels; b: the neighbourhood's
 * range, read only where it moved) and n new samples summing to sum: the bounded history
 * and the samples averaged by their counts into out and *out_len. Returns 0 for a pixel
 * with neither (the caller fills it, tr_upscale_fill). */
TR_FN int tr_upscale_blend(int have, float moved, const float b[6], float hv[3], float len, float n,
                           const float sum[3], float max_len, float out[3], float *out_len) {
    if (have && moved >= 1e-4f) {
        float yc[3], rgb[3];
        tr_up_ycocg(hv, yc);
        for (int j = 0; j < 3; ++j) {
            yc[j] = tr_fminf(tr_fmaxf(yc[j], b[j]), b[3 + j]);
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
        return 1;
    }
    if (have) {
        out[0] = hv[0];
        out[1] = hv[1];
        out[2] = hv[2];
        *out_len = len;
        return 1;
    }
    return 0;
}

/* Output pixel (x, y) of a camera `cam` (W x H) from the frame (wl x hl: colour col, 3
 * per pixel; sample positions pos in output pixels, 2 per pixel; distance along the ray
 * depth and primitive prim, 1 per pixel) and the history (hcol, hlen and hdepth of the
 * previous output, seen through `prev`; hcol NULL: none), and the range of the 3 x 3
 * traced pixels around each (box, tr_upscale_box_pixel, 6 floats per traced pixel; NULL:
 * computed per output pixel). motion: 3 floats per primitive
 * id below motion_count (NULL: nothing moved). Writes the pixel's colour (3 floats), its
 * count of samples and its distance, for the next frame's history. */
TR_FN void tr_upscale_pixel(const tr_camera *cam, const tr_camera *prev, int x, int y, int wl,
                            int hl, TR_CONST_GLOBAL float *col, TR_CONST_GLOBAL float *pos,
                            TR_CONST_GLOBAL float *depth, TR_CONST_GLOBAL uint32_t *prim,
                            TR_CONST_GLOBAL float *motion, uint32_t motion_count,
                            TR_CONST_GLOBAL float *hcol, TR_CONST_GLOBAL float *hlen,
                            TR_CONST_GLOBAL float *hdepth, TR_CONST_GLOBAL float *box,
                            float max_len, float out[3], float *out_len, float *out_depth) {
    const int w = (int)cam->screen_width, h = (int)cam->screen_height;
    const float cx = (float)x + 0.5f, cy = (float)y + 0.5f;
    const float sxr = (float)wl / (float)w, syr = (float)hl / (float)h;
    int lx = (int)(cx * sxr), ly = (int)(cy * syr);
    lx = lx < wl - 1 ? lx : wl - 1;
    ly = ly < hl - 1 ? ly : hl - 1;
    float sum[3] = {0.0f, 0.0f, 0.0f};
    float n = 0.0f, best = 1e30f, d = 0.0f;
    uint32_t id = 0u;
    /* The traced pixels whose area overlaps this pixel: the only ones whose sample can
     * fall in it (with a margin for rounding; the test below decides). */
    /* (Truncation is floor here: the values are at least -1e-3, and -1 is off the frame.) */
    const int tx0 = (int)((float)x * sxr - 1e-3f);
    const int tx1 = (int)((float)(x + 1) * sxr + 1e-3f);
    const int ty0 = (int)((float)y * syr - 1e-3f);
    const int ty1 = (int)((float)(y + 1) * syr + 1e-3f);
    for (int ty = ty0; ty <= ty1; ++ty) {
        if (ty < 0 || ty >= hl) {
            continue;
        }
        for (int tx = tx0; tx <= tx1; ++tx) {
            if (tx < 0 || tx >= wl) {
                continue;
            }
            const int k = ty * wl + tx;
            const float px = pos[2 * k], py = pos[2 * k + 1];
            const float ex = px - cx, ey = py - cy, e2 = ex * ex + ey * ey;
            if ((int)px == x && (int)py == y) { /* positions are not negative */
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
        tr_vec3 p = tr_camera_point_at(cam, (float)x, (float)y, d > 0.0f ? d : 1e6f);
        if (motion && d > 0.0f && id < motion_count) {
            p = v3_sub(p, v3(motion[3 * id], motion[3 * id + 1], motion[3 * id + 2]));
        }
        float qx, qy, dist;
        if (tr_camera_project(prev, p, &qx, &qy, &dist) && qx >= 0.0f && qy >= 0.0f &&
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
    float b[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    if (have && moved >= 1e-4f) {
        /* Where the view moved: bounded by the neighbourhood's range (box: per traced
         * pixel, tr_upscale_box_pixel; NULL: computed here). */
        if (box) {
            for (int j = 0; j < 6; ++j) {
                b[j] = box[6 * (ly * wl + lx) + j];
            }
        } else {
            tr_upscale_box_pixel(col, wl, hl, lx, ly, b);
        }
    }
    if (!tr_upscale_blend(have, moved, b, hv, len, n, sum, max_len, out, out_len)) {
        tr_upscale_fill(x, y, wl, hl, lx, ly, sxr, syr, col, pos, out);
        *out_len = 0.0f;
    }
}

#endif
