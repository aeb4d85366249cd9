/* cpu.c - the CPU device: the kernel run by OpenMP threads over screen tiles. */
#define _POSIX_C_SOURCE 200809L
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "device/frame.h"
#include "device/vcm.h"
#include "kernel/integrator_bdpt.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/registry.h"
#include "trac0r/render.h"

tr_render_config tr_render_config_default(void) {
    tr_render_config c;
    c.max_depth = TR_MAX_DEPTH_DEFAULT;
    c.seed = 0;
    c.threads = 0;
    /* The command line's default: path tracing with next-event estimation. */
    c.integrator = TR_INTEGRATOR_PT;
    c.stride = 1;
    c.tile = 16;
    c.passes = 0;
    c.sampler = TR_SAMPLER_SOBOL;
    c.roulette_start = 0;
    c.cancel = NULL;
    c.cancel_user = NULL;
    c.clamp_indirect = 0.0f;
    c.regularize = 0;
    c.no_primary_direct = 0;
    c.opencl_kernel = TR_OPENCL_KERNEL_AUTO;
    return c;
}

int tr_opencl_kernel_from_name(const char *name) {
    static const char *const names[] = {"auto", "mega", "wavefront"};
    for (int i = 0; name && i < 3; ++i) {
        if (strcmp(name, names[i]) == 0) {
            return i;
        }
    }
    return -1;
}

const char *tr_opencl_kernel_name(int kernel) {
    static const char *const names[] = {"auto", "mega", "wavefront"};
    return kernel >= 0 && kernel < 3 ? names[kernel] : "?";
}

TR_STATIC_ASSERT(TR_MAX_DEPTH_BDPT == TR_BDPT_MAX_DEPTH, "bdpt's depth limit");
TR_STATIC_ASSERT(TR_ROULETTE_START_PT == TR_PT_RR_START, "pt's roulette default");

int tr_integrator_is_bidirectional(int integrator) {
    return integrator == TR_INTEGRATOR_BDPT || integrator == TR_INTEGRATOR_VCM;
}

int tr_default_max_depth(int integrator) {
    if (tr_integrator_is_bidirectional(integrator)) {
        return TR_MAX_DEPTH_BDPT;
    }
    return integrator == TR_INTEGRATOR_NAIVE ? TR_MAX_DEPTH_NAIVE : TR_MAX_DEPTH_PT;
}

int tr_render_config_check(const tr_render_config *cfg, tr_error *err) {
    if (cfg->max_depth < 0 || cfg->max_depth > TR_MAX_DEPTH_LIMIT) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "max depth %d must be in 1..%d (0: the integrator's default)",
                            cfg->max_depth, TR_MAX_DEPTH_LIMIT);
    }
    if (tr_integrator_name(cfg->integrator) == NULL) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "unknown integrator %d",
                            cfg->integrator);
    }
    if (tr_integrator_is_bidirectional(cfg->integrator) && cfg->max_depth > TR_MAX_DEPTH_BDPT) {
        return tr_error_set(err, TR_STATUS_LIMIT, "max depth %d: %s supports at most %d",
                            cfg->max_depth, tr_integrator_name(cfg->integrator), TR_MAX_DEPTH_BDPT);
    }
    if (cfg->stride < 0 || cfg->stride > 64) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "stride %d must be in 1..64 (0: the default, 1)", cfg->stride);
    }
    if (cfg->threads < 0 || cfg->threads > TR_MAX_THREADS) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "threads %d must be in 0..%d",
                            cfg->threads, TR_MAX_THREADS);
    }
    if (cfg->sampler != TR_SAMPLER_SOBOL && cfg->sampler != TR_SAMPLER_RANDOM &&
        cfg->sampler != TR_SAMPLER_ZSOBOL) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "unknown sampler %d (expected TR_SAMPLER_SOBOL, TR_SAMPLER_RANDOM or "
                            "TR_SAMPLER_ZSOBOL)",
                            cfg->sampler);
    }
    if (cfg->roulette_start < 0 || cfg->roulette_start > TR_MAX_DEPTH_LIMIT) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "roulette start %d must be in 1..%d (0: the default, %d)",
                            cfg->roulette_start, TR_MAX_DEPTH_LIMIT, TR_ROULETTE_START_PT);
    }
    if (!(cfg->clamp_indirect >= 0.0f && cfg->clamp_indirect <= 3.0e38f)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "indirect clamp %g must be finite and at least 0 (0: off)",
                            (double)cfg->clamp_indirect);
    }
    if (cfg->regularize != 0 && cfg->regularize != 1) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "regularize %d must be 0 or 1",
                            cfg->regularize);
    }
    if (cfg->no_primary_direct < 0 || cfg->no_primary_direct > 2) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "no_primary_direct %d must be 0, 1 or 2", cfg->no_primary_direct);
    }
    if ((cfg->passes & ~TR_PASS_MASK) != 0u) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "unknown pass bits 0x%x",
                            cfg->passes & ~TR_PASS_MASK);
    }
    if ((cfg->passes & TR_PASS_DIRECT) != 0u && tr_integrator_is_bidirectional(cfg->integrator)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the direct pass needs the pt or naive integrator, not %s",
                            tr_integrator_name(cfg->integrator));
    }
    if ((cfg->passes & TR_PASS_EMISSION) != 0u && tr_integrator_is_bidirectional(cfg->integrator)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the emission pass needs the pt or naive integrator, not %s",
                            tr_integrator_name(cfg->integrator));
    }
    if ((cfg->passes & TR_PASS_SPECULAR) != 0u && cfg->integrator != TR_INTEGRATOR_PT) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the specular pass needs the pt integrator, not %s",
                            tr_integrator_name(cfg->integrator));
    }
    return TR_OK;
}

int tr_frame_make(tr_frame *f, const tr_camera *cam, const tr_render_config *cfg, uint32_t sample,
                  uint32_t sample_count, const tr_rect *rect, tr_error *err) {
    memset(f, 0, sizeof *f); /* defined even when a check below fails */
    if (tr_render_config_check(cfg, err) != TR_OK) {
        return TR_ERR;
    }
    if (cam->lens_radius > 0.0f && tr_integrator_is_bidirectional(cfg->integrator)) {
        /* Their light subpaths connect to a pinhole (integrator_bdpt.h): a lens would need
         * its own importance and MIS densities. */
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "%s does not support depth of field (camera.aperture_radius or "
                            "camera.f_number above 0): use pt",
                            tr_integrator_name(cfg->integrator));
    }
    const uint32_t w = cam->screen_width, h = cam->screen_height;
    if (tr_film_check_size(w, h, err) != TR_OK) {
        return TR_ERR; /* the film a frame of this camera would need */
    }
    if (sample_count == 0 || (uint64_t)sample + sample_count - 1u > UINT32_MAX) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "samples %u..%u+%u are out of range",
                            sample, sample, sample_count);
    }
    tr_rect r = {0, 0, w, h};
    if (rect) {
        r = *rect;
        if (r.width == 0 || r.height == 0 || r.x >= w || r.y >= h || r.width > w - r.x ||
            r.height > h - r.y) {
            return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                "rectangle %ux%u at (%u, %u) is empty or outside the %ux%u image",
                                r.width, r.height, r.x, r.y, w, h);
        }
    }
    f->camera = *cam;
    f->seed_lo = (uint32_t)cfg->seed;
    f->seed_hi = (uint32_t)(cfg->seed >> 32);
    f->sample = sample;
    f->sample_count = sample_count;
    f->max_depth = cfg->max_depth ? cfg->max_depth : tr_default_max_depth(cfg->integrator);
    f->integrator = (uint32_t)cfg->integrator;
    f->stride = cfg->stride ? (uint32_t)cfg->stride : 1u; /* 0: every pixel, as 1 */
    f->passes = cfg->passes;
    f->sampler = (uint32_t)cfg->sampler;
    f->rr_start = cfg->roulette_start ? cfg->roulette_start : TR_ROULETTE_START_PT;
    f->clamp_indirect = cfg->clamp_indirect;
    f->flags = (cfg->regularize ? TR_FRAME_REGULARIZE : 0u) |
               (cfg->no_primary_direct ? TR_FRAME_NO_PRIMARY_DIRECT : 0u) |
               (cfg->no_primary_direct == 2 ? TR_FRAME_NO_PRIMARY_INDIRECT : 0u) |
               (cfg->psr ? TR_FRAME_PSR : 0u) |
               ((cfg->passes & TR_PASS_SPECULAR) != 0u ? TR_FRAME_SPLIT_SPECULAR : 0u);
    f->rect_x = r.x;
    f->rect_y = r.y;
    f->rect_w = r.width;
    f->rect_h = r.height;
    return TR_OK;
}

tr_film_view tr_film_view_of(tr_film *film) {
    tr_film_view v = tr_film_view_make(film->sum, film->count, film->albedo, film->normal,
                                       film->depth, film->prim, film->width, film->passes);
    v.sq = film->sq;
    v.direct = film->direct;
    v.emission = film->emission;
    v.specular = film->specular;
    return v;
}

/* Adds frame f's light-tracing splats to the film. The frame traced `grid` pixels x
 * sample_count light subpaths and adds sample_count samples to each pixel of its
 * rectangle; the splats carry the whole image's importance (integrator_bdpt.h), so pixel j
 * gets sample_count x (W H / (grid sample_count)) x its splat sum. Splats that fell outside
 * the rectangle were dropped: the pixels there get no samples from this frame. */
static void tr_bdpt_fold_splats(const tr_frame *f, const tr_bdpt_splat *sp, uint32_t grid,
                                tr_film *film) {
    const double scale = (double)f->camera.screen_width * (double)f->camera.screen_height /
                         ((double)grid * TR_BDPT_SPLAT_ONE);
    for (uint32_t y = 0; y < sp->h; ++y) {
        for (uint32_t x = 0; x < sp->w; ++x) {
            const size_t i = (size_t)(sp->y0 + y) * film->width + (sp->x0 + x);
            const int64_t *q = &sp->sum[3u * ((size_t)y * sp->w + x)];
            for (int c = 0; c < 3; ++c) {
                film->sum[3 * i + (size_t)c] += (float)((double)q[c] * scale);
            }
        }
    }
}

/* The scenes an integrator cannot render, for tr_cpu_render and tr_integrator_supports. */
static int tr_integrator_check_view(const tr_scene_view *view, int integrator, tr_error *err) {
    if (view->punctual_count > 0u && integrator == TR_INTEGRATOR_NAIVE) {
        /* Delta lights are found by next-event estimation alone, which naive has not (pt,
         * bdpt and vcm sample them: punctual.h, tr_bdpt_punctual_camera). */
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "%s does not support point, spot or directional lights: use pt",
                            tr_integrator_name(integrator));
    }
    return TR_OK;
}

int tr_integrator_supports(const tr_scene *scene, int integrator, tr_error *err) {
    const tr_scene_view view = tr_scene_view_of(scene);
    return tr_integrator_check_view(&view, integrator, err);
}

int tr_cpu_render(const tr_scene_view *view, const tr_frame *f, tr_film *film, int threads,
                  uint32_t tile_side, int (*cancel)(void *), void *cancel_user, uint64_t *rays_out,
                  tr_error *err) {
    if (f->camera.screen_width != film->width || f->camera.screen_height != film->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "camera is %ux%u but the film is %ux%u", f->camera.screen_width,
                            f->camera.screen_height, film->width, film->height);
    }
    if ((f->passes & ~film->passes) != 0u) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the film does not keep the passes asked for (0x%x of 0x%x)",
                            f->passes & ~film->passes, f->passes);
    }
    tr_film_view fv = tr_film_view_of(film);
    fv.passes = f->passes;
    uint32_t gx0, gy0, nx, ny;
    tr_frame_grid(f, &gx0, &gy0, &nx, &ny);
    /* Tiles of grid points: every stride x stride block belongs to exactly one grid point,
     * so no two threads write the same pixel. */
    const uint32_t tile = tile_side ? tile_side : 16u;
    const uint32_t tiles_x = (nx + tile - 1) / tile;
    const uint32_t tiles_y = (ny + tile - 1) / tile;
    const int tile_count = (int)(tiles_x * tiles_y);
    const int nthreads = threads > 0 ? threads : tr_default_threads();
    int cancelled = 0;
    uint64_t rays = 0;
    const int bdpt = tr_integrator_is_bidirectional((int)f->integrator);
    tr_bdpt_splat sp = {NULL, f->rect_x, f->rect_y, f->rect_w, f->rect_h};
    if (tr_integrator_check_view(view, f->integrator, err) != TR_OK) {
        return TR_ERR;
    }
    if (bdpt) {
        /* Light tracing's splats, in fixed point (integrator_bdpt.h): per frame, for the
         * rectangle. */
        sp.sum = calloc(3u * (size_t)f->rect_w * f->rect_h, sizeof *sp.sum);
        if (!sp.sum) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                                "out of memory for bdpt's %ux%u splat buffer", f->rect_w,
                                f->rect_h);
        }
    }
    if (f->integrator == TR_INTEGRATOR_VCM) {
        /* Two passes per sample over the tiles (vcm.c). */
        if (tr_vcm_render(view, f, &fv, &sp, nthreads, tile, cancel, cancel_user, &rays, &cancelled,
                          err) != TR_OK) {
            free(sp.sum);
            return TR_ERR;
        }
    } else {

#pragma omp parallel for num_threads(nthreads) schedule(dynamic, 1) reduction(+ : rays)
        for (int t = 0; t < tile_count; ++t) {
            int stop;
#pragma omp atomic read
            stop = cancelled;
            if (stop) {
                continue; /* an OpenMP loop cannot break: skip the remaining tiles */
            }
            if (cancel && cancel(cancel_user)) {
#pragma omp atomic write
                cancelled = 1;
                continue;
            }
            const uint32_t tx0 = gx0 + ((uint32_t)t % tiles_x) * tile;
            const uint32_t ty0 = gy0 + ((uint32_t)t / tiles_x) * tile;
            const uint32_t tx1 = tx0 + tile < gx0 + nx ? tx0 + tile : gx0 + nx;
            const uint32_t ty1 = ty0 + tile < gy0 + ny ? ty0 + tile : gy0 + ny;
            if (bdpt) {
                rays += tr_bdpt_render_grid_rows(view, f, &fv, &sp, tx0, ty0, tx1, ty1);
            } else {
                rays += tr_render_grid_rows(view, f, &fv, tx0, ty0, tx1, ty1);
            }
        }
    }
    if (bdpt) {
        if (!cancelled) {
            tr_bdpt_fold_splats(f, &sp, nx * ny, film);
        }
        free(sp.sum);
    }
    if (cancelled) {
        return tr_error_set(err, TR_STATUS_CANCELLED, "frame cancelled");
    }
    if (rays_out) {
        *rays_out = rays;
    }
    return TR_OK;
}

int tr_render_frame(const tr_scene *scene, const tr_camera *cam, const tr_render_config *cfg,
                    tr_film *film, uint32_t sample, tr_render_stats *stats, tr_error *err) {
    const double t0 = tr_time_now();
    if (tr_scene_check_committed(scene, err) != TR_OK) {
        return TR_ERR;
    }
    tr_frame f;
    if (tr_frame_make(&f, cam, cfg, sample, 1, NULL, err) != TR_OK) {
        return TR_ERR;
    }
    const tr_scene_view view = tr_scene_view_of(scene);
    uint64_t rays = 0;
    if (tr_cpu_render(&view, &f, film, cfg->threads, cfg->tile, cfg->cancel, cfg->cancel_user,
                      &rays, err) != TR_OK) {
        return TR_ERR;
    }
    if (stats) {
        stats->rays = rays;
        stats->seconds = tr_time_now() - t0;
    }
    return TR_OK;
}
