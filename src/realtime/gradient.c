/* gradient.c - temporal gradients of the real-time loop (gradient.h). */
#include "realtime/gradient.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "device/frame.h"
#include "kernel/kernel.h"
#include "post/filter.h"
#include "scene/scene_internal.h"
#include "trac0r/render.h"

static float luminance(float r, float g, float b) {
    return 0.2126f * r + 0.7152f * g + 0.0722f * b;
}

void tr_grad_free(tr_grad *g) {
    free(g->prev);
    free(g->prev_prim);
    free(g->cap);
    free(g->num);
    free(g->den);
    free(g->tmp);
    memset(g, 0, sizeof *g);
}

void tr_grad_reset(tr_grad *g) {
    g->have_prev = 0;
    g->valid = 0;
}

static int grad_size(tr_grad *g, uint32_t w, uint32_t h, tr_error *err) {
    if (g->width == w && g->height == h && g->prev) {
        return TR_OK;
    }
    tr_grad_free(g);
    const size_t n = (size_t)w * h;
    const uint32_t sw = (w + TR_GRAD_STRATUM - 1) / TR_GRAD_STRATUM;
    const uint32_t sh = (h + TR_GRAD_STRATUM - 1) / TR_GRAD_STRATUM;
    const size_t ns = (size_t)sw * sh;
    g->prev = malloc(n * sizeof *g->prev);
    g->prev_prim = calloc(n, sizeof *g->prev_prim);
    g->cap = malloc(n * sizeof *g->cap);
    g->num = malloc(ns * sizeof *g->num);
    g->den = malloc(ns * sizeof *g->den);
    g->tmp = malloc(ns * sizeof *g->tmp);
    if (!g->prev || !g->prev_prim || !g->cap || !g->num || !g->den || !g->tmp) {
        tr_grad_free(g);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory for the temporal gradients of a %ux%u frame", w, h);
    }
    g->width = w;
    g->height = h;
    g->sw = sw;
    g->sh = sh;
    return TR_OK;
}

/* The pixel of stratum (sx, sy) replayed in frame `frame`: one of its 3x3 by a hash, so
 * that every pixel is measured now and then; clipped into the image. */
static void stratum_pixel(const tr_grad *g, uint32_t sx, uint32_t sy, uint32_t frame, uint32_t *x,
                          uint32_t *y) {
    uint32_t v = (sy * g->sw + sx) * 0x9e3779b1u ^ frame * 0x85ebca6bu;
    v ^= v >> 16;
    v *= 0x7feb352du;
    v ^= v >> 15;
    v *= 0x846ca68bu;
    v ^= v >> 16;
    const uint32_t k = v % (TR_GRAD_STRATUM * TR_GRAD_STRATUM);
    *x = sx * TR_GRAD_STRATUM + k % TR_GRAD_STRATUM;
    *y = sy * TR_GRAD_STRATUM + k / TR_GRAD_STRATUM;
    *x = *x < g->width ? *x : g->width - 1;
    *y = *y < g->height ? *y : g->height - 1;
}

/* One à-trous step over the strata (a 3x3 B-spline, taps `step` strata apart, those
 * outside left out and the rest renormalised): src into dst. */
static void atrous_strata(const tr_grad *g, const float *src, float *dst, int step, int threads) {
    static const float kw[3] = {0.25f, 0.5f, 0.25f};
    const int sw = (int)g->sw, sh = (int)g->sh;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < sh; ++y) {
        for (int x = 0; x < sw; ++x) {
            float sum = 0.0f, wsum = 0.0f;
            for (int dy = -1; dy <= 1; ++dy) {
                const int ty = y + dy * step;
                if (ty < 0 || ty >= sh) {
                    continue;
                }
                for (int dx = -1; dx <= 1; ++dx) {
                    const int tx = x + dx * step;
                    if (tx < 0 || tx >= sw) {
                        continue;
                    }
                    const float w = kw[dy + 1] * kw[dx + 1];
                    sum += w * src[ty * sw + tx];
                    wsum += w;
                }
            }
            dst[y * sw + x] = sum / wsum;
        }
    }
}

/* num and den spread over the strata by TR_GRAD_ATROUS_STEPS steps (1, 2, 4 apart). */
static void filter_strata(tr_grad *g, float *v, int threads) {
    for (int s = 0; s < TR_GRAD_ATROUS_STEPS; ++s) {
        atrous_strata(g, v, g->tmp, 1 << s, threads);
        memcpy(v, g->tmp, (size_t)g->sw * g->sh * sizeof *v);
    }
}

/* Whether the replay can use the previous frame: same size and config (the camera may
 * differ: the replay takes the previous one). */
static int replayable(const tr_grad *g, const tr_camera *cam, const tr_render_config *cfg) {
    return g->have_prev && g->cam.screen_width == cam->screen_width &&
           g->cam.screen_height == cam->screen_height && g->cfg.integrator == cfg->integrator &&
           g->cfg.stride == cfg->stride && g->cfg.seed == cfg->seed &&
           g->cfg.max_depth == cfg->max_depth && g->cfg.sampler == cfg->sampler &&
           g->cfg.roulette_start == cfg->roulette_start &&
           g->cfg.clamp_indirect == cfg->clamp_indirect && g->cfg.regularize == cfg->regularize &&
           g->cfg.no_primary_direct == cfg->no_primary_direct;
}

int tr_grad_frame(tr_grad *g, const tr_scene *scene, const tr_film *film, const tr_camera *cam,
                  const tr_render_config *cfg, uint32_t sample, uint32_t count, uint32_t frame,
                  const tr_vec3 *motion, uint32_t motion_count, float alpha_min, int threads,
                  tr_error *err) {
    const double t0 = tr_time_now();
    const uint32_t w = film->width, h = film->height;
    if (grad_size(g, w, h, err) != TR_OK) {
        return TR_ERR;
    }
    g->valid = 0;
    g->changed = 0;
    g->replayed = 0;
    const size_t n = (size_t)w * h;
    if (replayable(g, cam, cfg)) {
        tr_frame f;
        if (tr_frame_make(&f, &g->cam, &g->cfg, g->sample, g->count, NULL, err) != TR_OK) {
            return TR_ERR;
        }
        const tr_scene_view view = tr_scene_view_of(scene);
        const int sw = (int)g->sw, sh = (int)g->sh;
        const int has_prim = film->prim != NULL;
        uint32_t changed = 0;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1) reduction(+ : changed)
        for (int sy = 0; sy < sh; ++sy) {
            for (int sx = 0; sx < sw; ++sx) {
                uint32_t x, y;
                stratum_pixel(g, (uint32_t)sx, (uint32_t)sy, frame, &x, &y);
                const size_t i = (size_t)y * w + x;
                float s0 = 0.0f, s1 = 0.0f, s2 = 0.0f;
                uint32_t prim = 0;
                for (uint32_t k = 0; k < g->count; ++k) {
                    tr_sample smp;
                    tr_render_sample(&view, &f, x, y, g->sample + k, &smp);
                    s0 += smp.radiance.x;
                    s1 += smp.radiance.y;
                    s2 += smp.radiance.z;
                    if (k == 0) {
                        prim = smp.prim;
                    }
                }
                /* The film's mean, as tr_grad_frame took the previous one. */
                const float c = (float)g->count;
                const float lr = luminance(s0 / c, s1 / c, s2 / c);
                const float lp = g->prev[i];
                /* Where the surface itself changed (another primitive, or one that moved)
                 * the geometric tests and the motion vectors judge the history: the
                 * gradient measures the shading of the same surface. */
                const int moved = has_prim && (prim != g->prev_prim[i] ||
                                               (motion && prim < motion_count &&
                                                (motion[prim].x != 0.0f || motion[prim].y != 0.0f ||
                                                 motion[prim].z != 0.0f)));
                const size_t s = (size_t)sy * sw + sx;
                g->num[s] = moved ? 0.0f : fabsf(lr - lp);
                g->den[s] = moved ? 0.0f : fmaxf(lr, lp);
                changed += !moved && lr != lp;
            }
        }
        g->changed = changed;
        g->replayed = (uint32_t)(sw * sh);
        if (changed > 0) {
            filter_strata(g, g->num, threads);
            filter_strata(g, g->den, threads);
        }
        /* A-SVGF's weight: alpha = alpha_min + (1 - alpha_min) lambda, lambda the
         * normalised gradient, as a cap of 1 / alpha frames on the history. The gradients
         * lie in the previous frame's screen: with the same camera a pixel reads its own
         * stratum; after a camera move its surface point (followed back by its motion)
         * is projected into the previous camera, as the temporal stage reprojects it. */
        const float amin = fminf(fmaxf(alpha_min, 0.0f), 1.0f);
        const int same = memcmp(&g->cam, cam, sizeof *cam) == 0; /* NOLINT */
        const tr_camera pc = g->cam;
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int y = 0; y < (int)h; ++y) {
            for (uint32_t x = 0; x < w; ++x) {
                const size_t i = (size_t)y * w + x;
                long sx = (long)x / TR_GRAD_STRATUM, sy = (long)y / TR_GRAD_STRATUM;
                if (!same) {
                    sx = -1;
                    const float dep = film->depth && film->count[i]
                                          ? film->depth[i] / (float)film->count[i]
                                          : 0.0f;
                    if (dep > 0.0f && changed > 0) {
                        tr_vec3 p = tr_post_world_point(cam, (float)x, (float)y, dep);
                        const uint32_t id = film->prim ? film->prim[i] : 0u;
                        if (motion && id < motion_count) {
                            p = v3_sub(p, motion[id]);
                        }
                        float fx, fy, dist;
                        if (tr_post_project(&pc, p, &fx, &fy, &dist) && fx >= 0.0f && fy >= 0.0f &&
                            fx < (float)w && fy < (float)h) {
                            sx = (long)fx / TR_GRAD_STRATUM;
                            sy = (long)fy / TR_GRAD_STRATUM;
                        }
                    }
                }
                const size_t s = sx >= 0 ? (size_t)sy * g->sw + (size_t)sx : 0u;
                const float d = changed > 0 && sx >= 0 ? g->den[s] : 0.0f;
                const float lambda = d > 0.0f ? fminf(1.0f, g->num[s] / d) : 0.0f;
                g->cap[i] = lambda > 0.0f ? 1.0f / (amin + (1.0f - amin) * lambda) : FLT_MAX;
            }
        }
        g->valid = 1;
    }
    /* This frame becomes the previous one: its means' luminance and first primitives. */
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < (long)n; ++i) {
        const float c = (float)film->count[i];
        g->prev[i] = film->count[i] ? luminance(film->sum[3 * i] / c, film->sum[3 * i + 1] / c,
                                                film->sum[3 * i + 2] / c)
                                    : 0.0f;
        g->prev_prim[i] = film->prim ? film->prim[i] : 0u;
    }
    g->cam = *cam;
    g->cfg = *cfg;
    g->sample = sample;
    g->count = count;
    g->have_prev = 1;
    g->ms = (tr_time_now() - t0) * 1e3;
    return TR_OK;
}
