/* gradient.c - temporal gradients of the real-time loop (gradient.h). */
#include "realtime/gradient.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "device/frame.h"
#include "device/opencl.h"
#include "kernel/kernel.h"
#include "post/filter.h"
#include "scene/scene_internal.h"
#include "trac0r/render.h"

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

/* One à-trous step over the strata (a 3x3 B-spline, taps `step` strata apart, those
 * outside left out and the rest renormalised): src into dst. */
static void atrous_strata(const tr_grad *g, const float *src, float *dst, int step, int threads) {
    const int sw = (int)g->sw, sh = (int)g->sh;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < sh; ++y) {
        for (int x = 0; x < sw; ++x) {
            dst[y * sw + x] = tr_grad_atrous_at(src, sw, sh, x, y, step);
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

/* This frame's settings as the previous frame's, for the next replay; the stage's time since
 * t0. */
static void keep_frame(tr_grad *g, const tr_camera *cam, const tr_render_config *cfg,
                       uint32_t sample, uint32_t count, double t0) {
    g->cam = *cam;
    g->cfg = *cfg;
    g->sample = sample;
    g->count = count;
    g->have_prev = 1;
    g->ms = (tr_time_now() - t0) * 1e3;
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
                tr_grad_stratum_pixel(g->sw, w, h, (uint32_t)sx, (uint32_t)sy, frame, &x, &y);
                const size_t i = (size_t)y * w + x;
                const size_t s = (size_t)sy * sw + sx;
                changed += (uint32_t)tr_grad_replay_stratum(
                    &view, &f, x, y, g->sample, g->count, g->prev[i], g->prev_prim[i], has_prim,
                    (const float *)motion, motion_count, &g->num[s], &g->den[s]);
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
                const float dep =
                    film->depth && film->count[i] ? film->depth[i] / (float)film->count[i] : 0.0f;
                g->cap[i] = tr_grad_cap_pixel(
                    cam, &pc, same, x, (uint32_t)y, dep, film->prim ? film->prim[i] : 0u,
                    (const float *)motion, motion_count, changed > 0, g->num, g->den, g->sw, amin);
            }
        }
        g->valid = 1;
    }
    /* This frame becomes the previous one: its means' luminance and first primitives. */
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < (long)n; ++i) {
        g->prev[i] = tr_grad_mean_luminance(film->sum + 3 * i, film->count[i]);
        g->prev_prim[i] = film->prim ? film->prim[i] : 0u;
    }
    keep_frame(g, cam, cfg, sample, count, t0);
    return TR_OK;
}

int tr_grad_frame_device(tr_grad *g, struct tr_device *dev, const tr_camera *cam,
                         const tr_render_config *cfg, uint32_t sample, uint32_t count,
                         uint32_t frame, const tr_vec3 *motion, uint32_t motion_count,
                         float alpha_min, tr_error *err) {
    const double t0 = tr_time_now();
    tr_cl_context *cl = tr_device_cl_context(dev);
    if (!cl) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "temporal gradients on the device: not an OpenCL device");
    }
    g->valid = 0;
    g->changed = 0;
    g->replayed = 0;
    const uint32_t w = cam->screen_width, h = cam->screen_height;
    g->width = w;
    g->height = h;
    g->sw = (w + TR_GRAD_STRATUM - 1) / TR_GRAD_STRATUM;
    g->sh = (h + TR_GRAD_STRATUM - 1) / TR_GRAD_STRATUM;
    const int replay = replayable(g, cam, cfg);
    tr_frame f;
    if (replay && tr_frame_make(&f, &g->cam, &g->cfg, g->sample, g->count, NULL, err) != TR_OK) {
        return TR_ERR;
    }
    const int same = memcmp(&g->cam, cam, sizeof *cam) == 0; /* NOLINT */
    const float amin = fminf(fmaxf(alpha_min, 0.0f), 1.0f);
    uint32_t changed = 0;
    if (tr_cl_grad_frame(cl, replay ? &f : NULL, g->sample, g->count, cam, same, frame, motion,
                         motion_count, amin, &changed, err) != TR_OK) {
        g->have_prev = 0;
        return TR_ERR;
    }
    g->changed = changed;
    g->replayed = replay ? g->sw * g->sh : 0u;
    g->valid = replay;
    keep_frame(g, cam, cfg, sample, count, t0);
    return TR_OK;
}
