/* cpu.c - the CPU backend: the kernel run by OpenMP threads over screen tiles. */
#define _POSIX_C_SOURCE 200809L
#include <omp.h>
#include <time.h>

#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/render.h"

tr_render_config tr_render_config_default(void) {
    tr_render_config c;
    c.max_depth = 8;
    c.seed = 0;
    c.threads = 0;
    c.integrator = TR_INTEGRATOR_NAIVE;
    c.stride = 1;
    c.tile = 16;
    c.cancel = NULL;
    return c;
}

int tr_default_threads(void) {
    return omp_get_max_threads();
}

double tr_time_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int tr_render_config_check(const tr_render_config *cfg, tr_error *err) {
    if (cfg->max_depth < 1 || cfg->max_depth > TR_MAX_DEPTH_LIMIT) {
        return tr_error_set(err, "max depth %d must be in 1..%d", cfg->max_depth,
                            TR_MAX_DEPTH_LIMIT);
    }
    if (cfg->integrator != TR_INTEGRATOR_NAIVE && cfg->integrator != TR_INTEGRATOR_PT) {
        return tr_error_set(err, "unknown integrator %d", cfg->integrator);
    }
    if (cfg->stride < 1 || cfg->stride > 64) {
        return tr_error_set(err, "stride %d must be in 1..64", cfg->stride);
    }
    return TR_OK;
}

int tr_render_frame(const tr_scene *scene, const tr_camera *cam, const tr_render_config *cfg,
                    tr_film *film, uint32_t sample, tr_render_stats *stats, tr_error *err) {
    double t0 = tr_time_now();
    if (cam->screen_width != film->width || cam->screen_height != film->height) {
        return tr_error_set(err, "camera is %ux%u but the film is %ux%u", cam->screen_width,
                            cam->screen_height, film->width, film->height);
    }
    if (tr_scene_check_committed(scene, err) != TR_OK) {
        return TR_ERR;
    }
    if (tr_render_config_check(cfg, err) != TR_OK) {
        return TR_ERR;
    }
    const tr_scene_view view = tr_scene_view_of(scene);
    const uint32_t stride = (uint32_t)cfg->stride;
    /* Tiles are whole multiples of the stride so that every k x k block belongs to
     * exactly one tile and no two threads write the same pixel. */
    const uint32_t tile = (cfg->tile ? cfg->tile : 16u) * stride;
    const uint32_t tiles_x = (film->width + tile - 1) / tile;
    const uint32_t tiles_y = (film->height + tile - 1) / tile;
    const int tile_count = (int)(tiles_x * tiles_y);
    const int threads = cfg->threads > 0 ? cfg->threads : tr_default_threads();
    const int max_depth = cfg->max_depth;
    const uint64_t seed = cfg->seed;
    const int integrator = cfg->integrator;
    const atomic_int *cancel = cfg->cancel;
    uint64_t rays = 0;

#pragma omp parallel for num_threads(threads) schedule(dynamic, 1) reduction(+ : rays)
    for (int t = 0; t < tile_count; ++t) {
        if (cancel && atomic_load_explicit(cancel, memory_order_relaxed)) {
            continue; /* an OpenMP loop cannot break: skip the remaining tiles */
        }
        const uint32_t x0 = ((uint32_t)t % tiles_x) * tile;
        const uint32_t y0 = ((uint32_t)t / tiles_x) * tile;
        const uint32_t x1 = x0 + tile < film->width ? x0 + tile : film->width;
        const uint32_t y1 = y0 + tile < film->height ? y0 + tile : film->height;
        for (uint32_t y = y0; y < y1; y += stride) {
            for (uint32_t x = x0; x < x1; x += stride) {
                uint32_t r = 0;
                tr_vec3 c =
                    tr_render_sample(&view, cam, x, y, sample, seed, max_depth, integrator, &r);
                rays += r;
                /* Preview: the traced pixel stands for its whole block. */
                const uint32_t bx1 = x + stride < x1 ? x + stride : x1;
                const uint32_t by1 = y + stride < y1 ? y + stride : y1;
                for (uint32_t by = y; by < by1; ++by) {
                    for (uint32_t bx = x; bx < bx1; ++bx) {
                        size_t i = (size_t)by * film->width + bx;
                        film->sum[3 * i] += c.x;
                        film->sum[3 * i + 1] += c.y;
                        film->sum[3 * i + 2] += c.z;
                        film->count[i] += 1;
                    }
                }
            }
        }
    }
    if (cancel && atomic_load(cancel)) {
        return tr_error_set(err, "frame cancelled");
    }
    if (stats) {
        stats->rays = rays;
        stats->seconds = tr_time_now() - t0;
    }
    return TR_OK;
}
