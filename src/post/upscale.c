/* upscale.c - the host side of temporal upscaling (include/trac0r/upscale.h): the
 * per-pixel operator of src/post/upscale.h over the output's rows, and the samples'
 * positions from the kernel's own jitter. */
/* As in filter.c: the row loops below vectorise only when gcc may if-convert their
 * selects, which it does not while it must keep floating-point exceptions exact. Nothing
 * here reads the exception flags; the values are the same either way. */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("no-trapping-math")
#endif
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "../kernel/albedo.h"
#include "../kernel/emission.h"
#include "../kernel/rng.h"
#include "../kernel/sampler.h"
#include "../kernel/sampling.h"
#include "post/upscale.h"
#include "scene/scene_internal.h"
#include "trac0r/film.h"
#include "trac0r/post.h"
#include "trac0r/render.h"
#include "trac0r/upscale.h"

int tr_upscale_init(tr_upscale *u, uint32_t width, uint32_t height, tr_error *err) {
    memset(u, 0, sizeof *u);
    if (tr_film_check_size(width, height, err) != TR_OK) {
        return TR_ERR;
    }
    const size_t n = (size_t)width * height;
    u->width = width;
    u->height = height;
    int bad = 0;
    for (int k = 0; k < 2; ++k) {
        u->color[k] = calloc(3 * n, sizeof(float));
        u->count[k] = calloc(n, sizeof(float));
        u->depth[k] = calloc(n, sizeof(float));
        bad |= !u->color[k] || !u->count[k] || !u->depth[k];
    }
    if (bad) {
        tr_upscale_free(u);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u upscaling",
                            width, height);
    }
    return TR_OK;
}

void tr_upscale_free(tr_upscale *u) {
    for (int k = 0; k < 2; ++k) {
        free(u->color[k]);
        free(u->count[k]);
        free(u->depth[k]);
    }
    free(u->box);
    memset(u, 0, sizeof *u);
}

void tr_upscale_clear(tr_upscale *u) {
    u->have_history = 0;
}

/* The host loop. tr_upscale_pixel per output pixel costs about 1000 instructions in
 * scalar code; here its steps run turned round, each over a run of a row's pixels with
 * its values in planar arrays (as filter.c runs the reconstruction's operators), so
 * that gcc vectorises them: the samples that fell in each pixel and the nearest one, the
 * pixel's point and its projection into the previous camera, the disocclusion test and
 * the Catmull-Rom read. The per-frame quantities (each column's traced pixels, its
 * camera ray's horizontal part) are computed once. Every value is computed by the same
 * operations in the same order as the operator's, so the output is the operator's. */

/* Pixels per run: the run's arrays live on the stack, in L1. */
#define UP_RUN 64

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define UP_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define UP_CLONES
#endif

typedef struct up_ctx {
    const tr_camera *cam, *prev;
    int w, h, wl, hl, span;
    float sxr, syr, max_len;
    const float *col, *pos, *depth;
    const uint32_t *prim;
    const float *motion;
    uint32_t motion_count;
    const float *hcol, *hlen, *hdepth;
    const float *box; /* the neighbourhoods' ranges: 6 planes (low Y, Co, Cg, high) */
    size_t box_plane;
    /* Per output column: its traced pixels tx0 .. tx1, the one under its centre, and the
     * horizontal part of its camera ray (cam->right times the screen offset). */
    const int *tx0, *tx1, *lx;
    const float *rx, *ry, *rz;
    float *oc, *ol, *od;
} up_ctx;

typedef struct up_run {
    float sr[UP_RUN], sg[UP_RUN], sb[UP_RUN], n[UP_RUN], best[UP_RUN], d[UP_RUN];
    uint32_t id[UP_RUN];
    float qx[UP_RUN], qy[UP_RUN], moved[UP_RUN], len[UP_RUN];
    int have[UP_RUN], fill[UP_RUN], j[UP_RUN], on[UP_RUN], k[UP_RUN];
    float ok[UP_RUN];
    float shift[UP_RUN];
    float hr[UP_RUN], hg[UP_RUN], hb[UP_RUN];
    float o0[UP_RUN], o1[UP_RUN], o2[UP_RUN], ol[UP_RUN];
} up_run;

static inline int up_clampi(int v, int lo, int hi) {
    return v < lo ? lo : v > hi ? hi : v;
}

/* The samples of the run's pixels (x0 + a, y): their sum and count, and the nearest
 * one's distance and primitive (the operator's first loop, in its order: the traced rows,
 * then the traced columns, ascending). */
static inline __attribute__((always_inline)) void
up_gather(const up_ctx *restrict c, up_run *restrict r, int y, int x0, int n) {
    const float *restrict pos = c->pos, *restrict col = c->col, *restrict depth = c->depth;
    const uint32_t *restrict prim = c->prim;
    const int *restrict tx0 = c->tx0 + x0, *restrict tx1 = c->tx1 + x0;
    const int wl = c->wl, hl = c->hl;
    const float cy = (float)y + 0.5f;
    for (int a = 0; a < n; ++a) {
        r->sr[a] = r->sg[a] = r->sb[a] = r->n[a] = r->d[a] = 0.0f;
        r->best[a] = 1e30f;
        r->id[a] = 0u;
    }
    const int ty0 = (int)((float)y * c->syr - 1e-3f);
    const int ty1 = (int)((float)(y + 1) * c->syr + 1e-3f);
    for (int ty = ty0; ty <= ty1; ++ty) {
        if (ty < 0 || ty >= hl) {
            continue;
        }
        for (int s = 0; s < c->span; ++s) {
            /* The indices first, in a loop of their own: gcc then gathers through them
             * (from a select of indices it makes a select of pointers, which it does not
             * vectorise). */
            for (int a = 0; a < n; ++a) {
                const int tx = tx0[a] + s;
                const int ok = (tx <= tx1[a]) & (tx < wl);
                r->k[a] = ty * wl + (tx & -ok);
                r->ok[a] = ok ? 1.0f : 0.0f;
            }
            for (int a = 0; a < n; ++a) {
                const int x = x0 + a, k = r->k[a];
                const int ok = r->ok[a] > 0.0f;
                /* Every load unconditional (k is on the frame): the loop is one block
                 * of selects. */
                const float px = pos[2 * k], py = pos[2 * k + 1];
                const float cr = col[3 * k], cg = col[3 * k + 1], cb = col[3 * k + 2];
                const float dk = depth[k];
                const uint32_t pk = prim[k];
                const float ex = px - ((float)x + 0.5f), ey = py - cy, e2 = ex * ex + ey * ey;
                /* Selects by masks of bits (gcc turns a select of a loaded value into a
                 * masked load, which it does not vectorise); adding +0 changes no sum. */
                const uint32_t in = 0u - (uint32_t)(ok & ((int)px == x) & ((int)py == y));
                r->sr[a] += tr_post_bits_float(tr_post_float_bits(cr) & in);
                r->sg[a] += tr_post_bits_float(tr_post_float_bits(cg) & in);
                r->sb[a] += tr_post_bits_float(tr_post_float_bits(cb) & in);
                r->n[a] += tr_post_bits_float(tr_post_float_bits(1.0f) & in);
                const uint32_t near = 0u - (uint32_t)(ok & (e2 < r->best[a]));
                r->best[a] = near ? e2 : r->best[a];
                r->d[a] = tr_post_bits_float((tr_post_float_bits(dk) & near) |
                                             (tr_post_float_bits(r->d[a]) & ~near));
                r->id[a] = (pk & near) | (r->id[a] & ~near);
            }
        }
    }
}

/* The run's points reprojected into the previous camera and the disocclusion test (the
 * operator's second step): where the history survives, its position (qx, qy), count and
 * how far the pixel moved. */
static inline __attribute__((always_inline)) void
up_reproject(const up_ctx *restrict c, up_run *restrict r, int y, int x0, int n) {
    const tr_camera *cam = c->cam, *pc = c->prev;
    const float *restrict rx = c->rx + x0, *restrict ry = c->ry + x0, *restrict rz = c->rz + x0;
    const int *restrict lxs = c->lx + x0;
    const float *restrict motion = c->motion, *restrict depth = c->depth,
                          *restrict hdepth = c->hdepth, *restrict hlen = c->hlen;
    const uint32_t mc = c->motion_count;
    const int w = c->w, h = c->h, wl = c->wl, hl = c->hl;
    int ly = (int)(((float)y + 0.5f) * c->syr);
    ly = ly < hl - 1 ? ly : hl - 1;
    /* The vertical part of the row's camera ray (tr_camera_point_at). */
    const float sy = (0.5f - ((float)y + 0.5f) / (float)cam->screen_height) * cam->canvas_height;
    const float ux = cam->up.x * sy, uy = cam->up.y * sy, uz = cam->up.z * sy;
    const float cy = (float)y + 0.5f;
    const float pw = (float)pc->screen_width, ph = (float)pc->screen_height;
    for (int a = 0; a < n; ++a) {
        const float d = r->d[a];
        const float dist0 = d > 0.0f ? d : 1e6f;
        const float bx = cam->dir.x + (rx[a] + ux), by = cam->dir.y + (ry[a] + uy),
                    bz = cam->dir.z + (rz[a] + uz);
        const float l = sqrtf(bx * bx + by * by + bz * bz);
        const float il = 1.0f / l;
        const float nx = l > 0.0f ? bx * il : bx, ny = l > 0.0f ? by * il : by,
                    nz = l > 0.0f ? bz * il : bz;
        float px = cam->pos.x + nx * dist0, py = cam->pos.y + ny * dist0,
              pz = cam->pos.z + nz * dist0;
        const uint32_t id = r->id[a];
        const int mv = (d > 0.0f) & (id < mc);
        /* (motion has an entry at 0 in any case: tr_upscale_frame points it at zeros.) */
        /* (A mask, not a select: gcc turns a selected index into a selected pointer,
         * which it cannot gather from.) */
        const int mi = (int)(id & (0u - (uint32_t)mv));
        /* The motion, or +0 (subtracting which changes nothing), by a mask of its bits:
         * a select here becomes a masked load, which gcc does not vectorise. */
        const uint32_t keep = mv ? 0xffffffffu : 0u;
        const float m0 = tr_post_bits_float(tr_post_float_bits(motion[3 * mi]) & keep);
        const float m1 = tr_post_bits_float(tr_post_float_bits(motion[3 * mi + 1]) & keep);
        const float m2 = tr_post_bits_float(tr_post_float_bits(motion[3 * mi + 2]) & keep);
        px = px - m0;
        py = py - m1;
        pz = pz - m2;
        /* tr_camera_project into the previous camera. */
        const float vx = px - pc->pos.x, vy = py - pc->pos.y, vz = pz - pc->pos.z;
        const float z = vx * pc->dir.x + vy * pc->dir.y + vz * pc->dir.z;
        const int front = z > 1e-6f;
        const float zs = front ? z : 1.0f;
        const float ccx = (vx * pc->right.x + vy * pc->right.y + vz * pc->right.z) / zs;
        const float ccy = (vx * pc->up.x + vy * pc->up.y + vz * pc->up.z) / zs;
        const float qx = (ccx / pc->canvas_width + 0.5f) * pw;
        const float qy = (0.5f - ccy / pc->canvas_height) * ph;
        const float dist = sqrtf(vx * vx + vy * vy + vz * vz);
        const int on = front & (qx >= 0.0f) & (qy >= 0.0f) & (qx < (float)w) & (qy < (float)h);
        /* (Off the image: pixel 0, by the position rather than a select of the index,
         * which gcc would turn into a select of pointers, as for the motion above.) */
        const float qxs = on ? qx : 0.0f, qys = on ? qy : 0.0f;
        const int j = (int)qys * w + (int)qxs;
        const float mx = qx - ((float)(x0 + a) + 0.5f), my = qy - cy;
        r->moved[a] = mx * mx + my * my;
        r->j[a] = j;
        r->on[a] = on;
        r->qx[a] = qx;
        r->qy[a] = qy;
        r->shift[a] = d > 0.0f ? dist - d : 0.0f;
    }
    /* Apart from the loop above, so that gcc gathers through the index rather than
     * selecting among pointers (which it cannot vectorise). */
    for (int a = 0; a < n; ++a) {
        const int j = r->j[a], on = r->on[a];
        const float hd = hdepth[j], shift = r->shift[a];
        const int lx = lxs[a];
        /* The tests as 1.0f / 0.0f selects: gcc does not vectorise the mix of
         * comparison masks the integer form makes. */
        const float hit = hd > 0.0f ? 1.0f : 0.0f, none = 1.0f - hit;
        const float tol = 0.05f * hd;
        float found = 0.0f;
#pragma GCC unroll 3
        for (int dy = -1; dy <= 1; ++dy) {
            const int ty = ly + dy;
            const int row_ok = (ty >= 0) & (ty < hl);
#pragma GCC unroll 3
            for (int dx = -1; dx <= 1; ++dx) {
                const int tx = lx + dx;
                const int ok = row_ok & (tx >= 0) & (tx < wl);
                const float dk = depth[(ty * wl + tx) & -ok];
                const float near = fabsf(dk + shift - hd) <= tol ? hit : 0.0f;
                const float same = dk > 0.0f ? near : none;
                found = ok ? found + same : found;
            }
        }
        const float hl_j = hlen[j];
        const int have = on & (found > 0.0f) & (hl_j > 0.0f);
        r->have[a] = have;
        r->len[a] = have ? hl_j : 0.0f;
        r->qx[a] = have ? r->qx[a] : 0.5f;
        r->qy[a] = have ? r->qy[a] : 0.5f;
    }
}

/* The history at the run's positions through the Catmull-Rom filter (tr_up_history_read;
 * a tap's clamp to the image changes nothing where all sixteen lie inside). */
static inline __attribute__((always_inline)) void up_history(const up_ctx *restrict c,
                                                             up_run *restrict r, int n) {
    const float *restrict hist = c->hcol;
    const int w = c->w, h = c->h;
    for (int a = 0; a < n; ++a) {
        const float fx = r->qx[a] - 0.5f, fy = r->qy[a] - 0.5f;
        const int ix = (int)(fx + 1.0f) - 1, iy = (int)(fy + 1.0f) - 1;
        float wx[4], wy[4];
        tr_up_catmull_rom(fx - (float)ix, wx);
        tr_up_catmull_rom(fy - (float)iy, wy);
        float o0 = 0.0f, o1 = 0.0f, o2 = 0.0f;
#pragma GCC unroll 4
        for (int j = 0; j < 4; ++j) {
            const int ty = up_clampi(iy - 1 + j, 0, h - 1);
            float r0 = 0.0f, r1 = 0.0f, r2 = 0.0f;
#pragma GCC unroll 4
            for (int i = 0; i < 4; ++i) {
                const int tx = up_clampi(ix - 1 + i, 0, w - 1);
                const int k = 3 * (ty * w + tx);
                r0 += wx[i] * hist[k];
                r1 += wx[i] * hist[k + 1];
                r2 += wx[i] * hist[k + 2];
            }
            o0 += wy[j] * r0;
            o1 += wy[j] * r1;
            o2 += wy[j] * r2;
        }
        const int have = r->have[a];
        r->hr[a] = have ? o0 : 0.0f;
        r->hg[a] = have ? o1 : 0.0f;
        r->hb[a] = have ? o2 : 0.0f;
    }
}

/* Rows y0 .. y1 - 1 of the neighbourhoods' ranges (tr_upscale_box_pixel) into the six
 * planes at box (each wl * hl): the inner pixels of a row in one vectorised loop, the
 * taps in the operator's order (the minimum and maximum as in up_blend), the two end
 * pixels by the operator itself. */
UP_CLONES static void up_box_rows(const float *restrict col, int wl, int hl, float *restrict box,
                                  int y0, int y1) {
    const size_t np = (size_t)wl * hl;
    for (int y = y0; y < y1; ++y) {
        float *restrict l0 = box + (size_t)y * wl, *restrict l1 = l0 + np, *restrict l2 = l1 + np,
                        *restrict u0 = l2 + np, *restrict u1 = u0 + np, *restrict u2 = u1 + np;
        for (int x = 1; x < wl - 1; ++x) {
            float a0 = 1e30f, a1 = 1e30f, a2 = 1e30f, z0 = -1e30f, z1 = -1e30f, z2 = -1e30f;
#pragma GCC unroll 3
            for (int dy = -1; dy <= 1; ++dy) {
                const int ty = y + dy;
                if (ty < 0 || ty >= hl) {
                    continue;
                }
#pragma GCC unroll 3
                for (int dx = -1; dx <= 1; ++dx) {
                    const int k = 3 * (ty * wl + x + dx);
                    const float r = col[k], g = col[k + 1], b = col[k + 2];
                    const float c0 = 0.25f * r + 0.5f * g + 0.25f * b;
                    const float c1 = 0.5f * r - 0.5f * b;
                    const float c2 = -0.25f * r + 0.5f * g - 0.25f * b;
                    a0 = a0 < c0 ? a0 : c0;
                    a1 = a1 < c1 ? a1 : c1;
                    a2 = a2 < c2 ? a2 : c2;
                    z0 = z0 > c0 ? z0 : c0;
                    z1 = z1 > c1 ? z1 : c1;
                    z2 = z2 > c2 ? z2 : c2;
                }
            }
            l0[x] = a0;
            l1[x] = a1;
            l2[x] = a2;
            u0[x] = z0;
            u1[x] = z1;
            u2[x] = z2;
        }
        for (int e = 0; e < 2; ++e) {
            const int x = e ? wl - 1 : 0;
            float b[6];
            tr_upscale_box_pixel(col, wl, hl, x, y, b);
            l0[x] = b[0];
            l1[x] = b[1];
            l2[x] = b[2];
            u0[x] = b[3];
            u1[x] = b[4];
            u2[x] = b[5];
        }
    }
}

/* tr_upscale_blend over the run: the history bounded by the neighbourhood's range where
 * the view moved, averaged with the samples; r->fill marks the pixels with neither. The
 * minimum and maximum are the selects fminf and fmaxf compute for numbers (not NaN),
 * which gcc vectorises (a call to fminf it does not). */
static inline __attribute__((always_inline)) void
up_blend(const up_ctx *restrict c, up_run *restrict r, int y, int x0, int n, int ly) {
    const float *restrict b0 = c->box, *restrict b1 = b0 + c->box_plane,
                          *restrict b2 = b1 + c->box_plane, *restrict b3 = b2 + c->box_plane,
                          *restrict b4 = b3 + c->box_plane, *restrict b5 = b4 + c->box_plane;
    const int *restrict lxs = c->lx + x0;
    float *restrict oc = c->oc + 3 * ((size_t)y * c->w + x0);
    float *restrict ol = c->ol + (size_t)y * c->w + x0, *restrict od =
                                                            c->od + (size_t)y * c->w + x0;
    const float max_len = c->max_len;
    const int row = ly * c->wl;
    for (int a = 0; a < n; ++a) {
        const int have = r->have[a];
        const int k = row + lxs[a];
        float h0 = r->hr[a], h1 = r->hg[a], h2 = r->hb[a];
        /* tr_up_ycocg, the clamp, tr_up_rgb and the floor at 0. */
        const float y0 = 0.25f * h0 + 0.5f * h1 + 0.25f * h2;
        const float y1 = 0.5f * h0 - 0.5f * h2;
        const float y2 = -0.25f * h0 + 0.5f * h1 - 0.25f * h2;
        const float lo0 = b0[k], lo1 = b1[k], lo2 = b2[k], hi0 = b3[k], hi1 = b4[k], hi2 = b5[k];
        float c0 = y0 > lo0 ? y0 : lo0, c1 = y1 > lo1 ? y1 : lo1, c2 = y2 > lo2 ? y2 : lo2;
        c0 = c0 < hi0 ? c0 : hi0;
        c1 = c1 < hi1 ? c1 : hi1;
        c2 = c2 < hi2 ? c2 : hi2;
        const float g0 = c0 + c1 - c2, g1 = c0 + c2, g2 = c0 - c1 - c2;
        const int bound = have & (r->moved[a] >= 1e-4f);
        h0 = bound ? (g0 > 0.0f ? g0 : 0.0f) : h0;
        h1 = bound ? (g1 > 0.0f ? g1 : 0.0f) : h1;
        h2 = bound ? (g2 > 0.0f ? g2 : 0.0f) : h2;
        const float ns = r->n[a], len = r->len[a];
        const float room = max_len - ns > 0.0f ? max_len - ns : 0.0f;
        const float keep = len < room ? len : room;
        const float inv = 1.0f / (keep + ns);
        const float m0 = (h0 * keep + r->sr[a]) * inv, m1 = (h1 * keep + r->sg[a]) * inv,
                    m2 = (h2 * keep + r->sb[a]) * inv;
        const float nz = ns > 0.0f ? ns : 1.0f;
        const float s0 = r->sr[a] / nz, s1 = r->sg[a] / nz, s2 = r->sb[a] / nz;
        const int some = ns > 0.0f;
        const float v0 = have ? m0 : s0, v1 = have ? m1 : s1, v2 = have ? m2 : s2;
        const float vl = have ? keep + ns : ns, hl = have ? len : 0.0f;
        r->o0[a] = some ? v0 : h0;
        r->o1[a] = some ? v1 : h1;
        r->o2[a] = some ? v2 : h2;
        r->ol[a] = some ? vl : hl;
        r->fill[a] = !some & !have;
    }
    /* Stored apart: gcc does not vectorise the selects above into interleaved stores. */
    for (int a = 0; a < n; ++a) {
        oc[3 * a] = r->o0[a];
        oc[3 * a + 1] = r->o1[a];
        oc[3 * a + 2] = r->o2[a];
        ol[a] = r->ol[a];
        od[a] = r->d[a];
    }
}

/* Rows y0 .. y1 - 1 of the output. */
UP_CLONES static void up_rows(const up_ctx *c, int y0, int y1) {
    up_run r;
    const int w = c->w, wl = c->wl, hl = c->hl;
    for (int y = y0; y < y1; ++y) {
        int ly = (int)(((float)y + 0.5f) * c->syr);
        ly = ly < hl - 1 ? ly : hl - 1;
        for (int x0 = 0; x0 < w; x0 += UP_RUN) {
            const int n = w - x0 < UP_RUN ? w - x0 : UP_RUN;
            up_gather(c, &r, y, x0, n);
            if (c->hcol) {
                up_reproject(c, &r, y, x0, n);
                up_history(c, &r, n);
            } else {
                for (int a = 0; a < n; ++a) {
                    r.have[a] = 0;
                    r.len[a] = r.moved[a] = r.hr[a] = r.hg[a] = r.hb[a] = 0.0f;
                }
            }
            up_blend(c, &r, y, x0, n, ly);
            /* The pixels with neither history nor a sample: the spatial fill. */
            for (int a = 0; a < n; ++a) {
                if (r.fill[a]) {
                    const int x = x0 + a;
                    const size_t i = (size_t)y * w + x;
                    tr_upscale_fill(x, y, wl, hl, c->lx[x], ly, c->sxr, c->syr, c->col, c->pos,
                                    c->oc + 3 * i);
                }
            }
        }
    }
}

int tr_upscale_frame(tr_upscale *u, const tr_upscale_input *in, const tr_camera *cam,
                     const tr_vec3 *motion, uint32_t motion_count, float max_len, int threads,
                     float *out, tr_error *err) {
    if (!u || !in || !cam || !out || !in->color || !in->pos || !in->depth || !in->prim) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_upscale_frame: NULL argument");
    }
    if (cam->screen_width != u->width || cam->screen_height != u->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tr_upscale_frame: a %ux%u camera for a %ux%u output",
                            cam->screen_width, cam->screen_height, u->width, u->height);
    }
    if (in->width == 0 || in->height == 0 || in->width > u->width || in->height > u->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tr_upscale_frame: a %ux%u frame for a %ux%u output", in->width,
                            in->height, u->width, u->height);
    }
    const double t0 = tr_time_now();
    const int nt = threads > 0 ? threads : omp_get_max_threads();
    const float cap = max_len > 0.0f ? max_len : TR_UPSCALE_MAX_LEN;
    const int w = (int)u->width, h = (int)u->height;
    const int prev = u->cur, next = 1 - u->cur;
    const tr_camera pc = u->have_history ? u->prev_cam : *cam;
    const float *hcol = u->have_history ? u->color[prev] : NULL;
    /* tr_vec3 is three packed floats (types.h), as the operator reads them. */
    const float *mot = motion ? &motion[0].x : NULL;
    float *oc = u->color[next], *ol = u->count[next], *od = u->depth[next];
    /* The neighbourhoods' ranges, once per traced pixel rather than per output pixel. */
    const int wl = (int)in->width, hl = (int)in->height;
    if (u->box_len < 6 * (size_t)wl * hl) {
        free(u->box);
        u->box_len = 0;
        if (!(u->box = malloc(6 * (size_t)wl * hl * sizeof *u->box))) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u frame",
                                in->width, in->height);
        }
        u->box_len = 6 * (size_t)wl * hl;
    }
    float *box = u->box;
#pragma omp parallel for num_threads(nt) schedule(static)
    for (int y = 0; y < hl; ++y) {
        up_box_rows(in->color, wl, hl, box, y, y + 1);
    }
    /* Per column: the traced pixels its samples can come from (the operator's bounds) and
     * its camera ray's horizontal part (tr_camera_point_at's). */
    int *cols = malloc(3 * (size_t)w * sizeof *cols);
    float *ray = malloc(3 * (size_t)w * sizeof *ray);
    if (!cols || !ray) {
        free(cols);
        free(ray);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u output",
                            u->width, u->height);
    }
    up_ctx c = {0};
    c.cam = cam;
    c.prev = &pc;
    c.w = w;
    c.h = h;
    c.wl = wl;
    c.hl = hl;
    c.sxr = (float)wl / (float)w;
    c.syr = (float)hl / (float)h;
    c.max_len = cap;
    c.col = in->color;
    c.pos = in->pos;
    c.depth = in->depth;
    c.prim = in->prim;
    static const float no_motion[3] = {0.0f, 0.0f, 0.0f};
    c.motion = mot && motion_count > 0 ? mot : no_motion;
    c.motion_count = mot && motion_count > 0 ? motion_count : 0u;
    c.hcol = hcol;
    c.hlen = u->count[prev];
    c.hdepth = u->depth[prev];
    c.box = box;
    c.box_plane = (size_t)wl * hl;
    c.oc = oc;
    c.ol = ol;
    c.od = od;
    int *tx0 = cols, *tx1 = cols + w, *lxs = cols + 2 * w;
    float *rx = ray, *ry = ray + w, *rz = ray + 2 * w;
    c.span = 1;
    for (int x = 0; x < w; ++x) {
        tx0[x] = (int)((float)x * c.sxr - 1e-3f);
        tx1[x] = (int)((float)(x + 1) * c.sxr + 1e-3f);
        c.span = tx1[x] - tx0[x] + 1 > c.span ? tx1[x] - tx0[x] + 1 : c.span;
        const int lx = (int)(((float)x + 0.5f) * c.sxr);
        lxs[x] = lx < wl - 1 ? lx : wl - 1;
        const float sx = (((float)x + 0.5f) / (float)cam->screen_width - 0.5f) * cam->canvas_width;
        rx[x] = cam->right.x * sx;
        ry[x] = cam->right.y * sx;
        rz[x] = cam->right.z * sx;
    }
    c.tx0 = tx0;
    c.tx1 = tx1;
    c.lx = lxs;
    c.rx = rx;
    c.ry = ry;
    c.rz = rz;
#pragma omp parallel for num_threads(nt) schedule(static)
    for (int y = 0; y < h; ++y) {
        up_rows(&c, y, y + 1);
    }
    free(cols);
    free(ray);
    memcpy(out, oc, 3 * (size_t)w * h * sizeof *out);
    u->cur = next;
    u->prev_cam = *cam;
    u->have_history = 1;
    u->ms = (tr_time_now() - t0) * 1e3;
    return TR_OK;
}

int tr_upscale_positions(const tr_render_config *cfg, uint32_t width, uint32_t height,
                         uint32_t out_width, uint32_t out_height, uint32_t first, uint32_t count,
                         float *pos, tr_error *err) {
    if (!cfg || !pos || width == 0 || height == 0 || count == 0) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tr_upscale_positions: empty frame or NULL argument");
    }
    const float sx = (float)out_width / (float)width, sy = (float)out_height / (float)height;
    const float inv = 1.0f / (float)count;
    const long n = (long)width * height;
#pragma omp parallel for num_threads(cfg->threads > 0 ? cfg->threads : omp_get_max_threads())      \
    schedule(static)
    for (long i = 0; i < n; ++i) {
        const uint32_t x = (uint32_t)(i % width), y = (uint32_t)(i / width);
        float ax = 0.0f, ay = 0.0f;
        for (uint32_t s = first; s < first + count; ++s) {
            float jx, jy;
            /* As tr_render_pixel_sample_kind draws the camera ray's jitter. */
            if (cfg->integrator == TR_INTEGRATOR_PT) {
                tr_sampler smp =
                    tr_sampler_make_pixel(cfg->seed, (uint64_t)i, x, y, s, (uint32_t)cfg->sampler);
                tr_sampler_2d(&smp, TR_DIM_CAMERA, &jx, &jy);
            } else {
                tr_rng rng;
                tr_rng_init(&rng, cfg->seed, (uint64_t)i, (uint64_t)s);
                tr_sample_pixel_jitter(&rng, &jx, &jy);
            }
            ax += jx;
            ay += jy;
        }
        pos[2 * i] = ((float)x + ax * inv) * sx;
        pos[2 * i + 1] = ((float)y + ay * inv) * sy;
    }
    return TR_OK;
}

/* The checks tr_upscale_emission and tr_upscale_albedo share (function `fn`): a traced
 * frame of width x height no larger than cam's output, its pass `in` and `out` given, and
 * a committed scene to trace. */
static int output_trace_args(const char *fn, const struct tr_scene *scene, const tr_camera *cam,
                             uint32_t width, uint32_t height, const float *in, const float *out,
                             tr_error *err) {
    if (!scene || !cam || !in || !out || width == 0 || height == 0 || width > cam->screen_width ||
        height > cam->screen_height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "%s: empty frame or NULL argument",
                            fn);
    }
    if (!tr_scene_is_committed(scene)) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION, "%s: the scene is not committed", fn);
    }
    return TR_OK;
}

int tr_upscale_emission(const struct tr_scene *scene, const tr_camera *cam, int n, int threads,
                        uint32_t width, uint32_t height, const float *emission, const float *prev,
                        float *out, uint32_t *resolved, tr_error *err) {
    if (resolved) {
        *resolved = 0;
    }
    if (n < 1 || n > TR_RESOLVE_EMISSION_MAX) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tr_upscale_emission: %d x %d rays per pixel (expected 1..%d)", n, n,
                            TR_RESOLVE_EMISSION_MAX);
    }
    if (output_trace_args("tr_upscale_emission", scene, cam, width, height, emission, out, err) !=
        TR_OK) {
        return TR_ERR;
    }
    const int W = (int)cam->screen_width, H = (int)cam->screen_height;
    const int wl = (int)width, hl = (int)height;
    const float sxr = (float)wl / (float)W, syr = (float)hl / (float)H;
    /* Two traced pixels in output pixels (tr_emission_missed). */
    const int dx = (int)ceilf(2.0f / sxr), dy = (int)ceilf(2.0f / syr);
    const tr_scene_view view = tr_scene_view_of(scene);
    const int nt = threads > 0 ? threads : omp_get_max_threads();
    /* Per traced pixel, once rather than per output pixel over it: whether its samples
     * saw emission (bit 0) and whether it lies on an emitter's edge (bit 1). */
    unsigned char *flag = malloc((size_t)wl * hl);
    if (!flag) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u frame", width,
                            height);
    }
#pragma omp parallel for num_threads(nt) schedule(static)
    for (int y = 0; y < hl; ++y) {
        for (int x = 0; x < wl; ++x) {
            const size_t k = (size_t)y * wl + x;
            flag[k] = (unsigned char)(tr_emission_seen(emission, (uint32_t)k) |
                                      tr_emission_on_edge(emission, wl, hl, x, y) << 1);
        }
    }
    uint32_t count = 0;
#pragma omp parallel for num_threads(nt) schedule(dynamic, 8) reduction(+ : count)
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            int lx = (int)(((float)x + 0.5f) * sxr), ly = (int)(((float)y + 0.5f) * syr);
            lx = lx < wl - 1 ? lx : wl - 1;
            ly = ly < hl - 1 ? ly : hl - 1;
            const size_t i = (size_t)y * W + x;
            const size_t k = (size_t)ly * wl + lx;
            /* A small emitter can fall between the traced samples: where the previous
             * output saw one and the traced pixel sees none, trace it too. */
            const int missed =
                prev && !(flag[k] & 1) && tr_emission_missed(prev, W, H, x, y, dx, dy);
            if (missed || (flag[k] & 2)) {
                const tr_vec3 e = tr_emission_resolve_pixel(&view, cam, x, y, n);
                out[3 * i] = e.x;
                out[3 * i + 1] = e.y;
                out[3 * i + 2] = e.z;
                ++count;
            } else {
                out[3 * i] = emission[3 * k];
                out[3 * i + 1] = emission[3 * k + 1];
                out[3 * i + 2] = emission[3 * k + 2];
            }
        }
    }
    free(flag);
    if (resolved) {
        *resolved = count;
    }
    return TR_OK;
}

/* Whether albedos a and b differ for tr_upscale_albedo (upscale.h). */
static int albedo_differs(const float *a, const float *b) {
    for (int c = 0; c < 3; ++c) {
        const float m = a[c] > b[c] ? a[c] : b[c];
        if (fabsf(a[c] - b[c]) > TR_UPSCALE_ALBEDO_ABS + TR_UPSCALE_ALBEDO_REL * m) {
            return 1;
        }
    }
    return 0;
}

int tr_upscale_albedo(const struct tr_scene *scene, const tr_camera *cam, int threads,
                      uint32_t width, uint32_t height, const float *albedo, const float *prev,
                      float *out, uint32_t *traced, tr_error *err) {
    if (traced) {
        *traced = 0;
    }
    if (output_trace_args("tr_upscale_albedo", scene, cam, width, height, albedo, out, err) !=
        TR_OK) {
        return TR_ERR;
    }
    const int W = (int)cam->screen_width, H = (int)cam->screen_height;
    const int wl = (int)width, hl = (int)height;
    const float sxr = (float)wl / (float)W, syr = (float)hl / (float)H;
    const tr_scene_view view = tr_scene_view_of(scene);
    const int nt = threads > 0 ? threads : omp_get_max_threads();
    /* Per traced pixel, once rather than per output pixel over it: whether its 3 x 3
     * neighbourhood (clipped to the frame) is flat. */
    unsigned char *flat = malloc((size_t)wl * hl);
    if (!flat) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u frame", width,
                            height);
    }
#pragma omp parallel for num_threads(nt) schedule(static)
    for (int y = 0; y < hl; ++y) {
        for (int x = 0; x < wl; ++x) {
            const float *c = albedo + 3 * ((size_t)y * wl + x);
            int f = 1;
            for (int dy = -1; dy <= 1 && f; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx >= 0 && yy >= 0 && xx < wl && yy < hl &&
                        albedo_differs(c, albedo + 3 * ((size_t)yy * wl + xx))) {
                        f = 0;
                        break;
                    }
                }
            }
            flat[(size_t)y * wl + x] = (unsigned char)f;
        }
    }
    uint32_t count = 0;
#pragma omp parallel for num_threads(nt) schedule(dynamic, 8) reduction(+ : count)
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            const float fx = ((float)x + 0.5f) * sxr, fy = ((float)y + 0.5f) * syr;
            int lx = (int)fx, ly = (int)fy;
            lx = lx < wl - 1 ? lx : wl - 1;
            ly = ly < hl - 1 ? ly : hl - 1;
            const size_t i = (size_t)y * W + x;
            int trace = !flat[(size_t)ly * wl + lx];
            float v[3] = {0.0f, 0.0f, 0.0f};
            if (!trace) {
                /* Bilinear between the traced pixels' centres: its four taps lie in the
                 * flat 3 x 3 block around (lx, ly). */
                float gx = fx - 0.5f, gy = fy - 0.5f;
                gx = gx > 0.0f ? gx : 0.0f;
                gy = gy > 0.0f ? gy : 0.0f;
                int x0 = (int)gx, y0 = (int)gy;
                x0 = x0 < wl - 1 ? x0 : wl - 1;
                y0 = y0 < hl - 1 ? y0 : hl - 1;
                const int x1 = x0 + 1 < wl ? x0 + 1 : x0, y1 = y0 + 1 < hl ? y0 + 1 : y0;
                const float tx = gx - (float)x0 < 1.0f ? gx - (float)x0 : 1.0f;
                const float ty = gy - (float)y0 < 1.0f ? gy - (float)y0 : 1.0f;
                const float *a00 = albedo + 3 * ((size_t)y0 * wl + x0);
                const float *a10 = albedo + 3 * ((size_t)y0 * wl + x1);
                const float *a01 = albedo + 3 * ((size_t)y1 * wl + x0);
                const float *a11 = albedo + 3 * ((size_t)y1 * wl + x1);
                for (int c = 0; c < 3; ++c) {
                    const float top = a00[c] + (a10[c] - a00[c]) * tx;
                    const float bottom = a01[c] + (a11[c] - a01[c]) * tx;
                    v[c] = top + (bottom - top) * ty;
                }
                trace = prev && albedo_differs(prev + 3 * i, v);
            }
            if (trace) {
                const tr_vec3 a = tr_albedo_resolve_pixel(&view, cam, x, y, 1);
                v[0] = a.x;
                v[1] = a.y;
                v[2] = a.z;
                ++count;
            }
            out[3 * i] = v[0];
            out[3 * i + 1] = v[1];
            out[3 * i + 2] = v[2];
        }
    }
    free(flat);
    if (traced) {
        *traced = count;
    }
    return TR_OK;
}
