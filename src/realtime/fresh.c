/* fresh.c - the pixels without history and their extra samples (fresh.h). */
#include "realtime/fresh.h"

#include <stdlib.h>
#include <string.h>

#include "device/frame.h"
#include "device/opencl.h"
#include "kernel/kernel.h"
#include "post/filter.h"
#include "scene/scene_internal.h"

void tr_fresh_free(tr_fresh *f) {
    free(f->depth);
    free(f->normal);
    free(f->point);
    free(f->cur);
    free(f->prim);
    free(f->mask);
    memset(f, 0, sizeof *f);
}

void tr_fresh_reset(tr_fresh *f) {
    f->have_prev = 0;
}

static int fresh_size(tr_fresh *f, uint32_t w, uint32_t h, tr_error *err) {
    if (f->width == w && f->height == h && f->mask) {
        return TR_OK;
    }
    tr_fresh_free(f);
    const size_t n = (size_t)w * h;
    f->depth = malloc(n * sizeof *f->depth);
    f->normal = malloc(3 * n * sizeof *f->normal);
    f->point = malloc(3 * n * sizeof *f->point);
    f->cur = malloc(3 * n * sizeof *f->cur);
    f->prim = malloc(n * sizeof *f->prim);
    f->mask = malloc(n);
    if (!f->depth || !f->normal || !f->point || !f->cur || !f->prim || !f->mask) {
        tr_fresh_free(f);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u frame", w, h);
    }
    f->width = w;
    f->height = h;
    return TR_OK;
}

/* Pixel i's pass means (the film's sums over its count), as tr_gbuffer_from_film takes
 * them. */
static void pixel_passes(const tr_film *film, size_t i, float *depth, tr_vec3 *n, uint32_t *prim) {
    const uint32_t c = film->count[i];
    const float inv = c ? 1.0f / (float)c : 0.0f;
    *depth = film->depth[i] * inv;
    *n = tr_vec3_make(film->normal[3 * i] * inv, film->normal[3 * i + 1] * inv,
                      film->normal[3 * i + 2] * inv);
    *prim = film->prim[i];
}

int tr_fresh_mask(tr_fresh *f, const tr_film *film, const tr_camera *cam, const tr_vec3 *motion,
                  uint32_t motion_count, int threads, tr_error *err) {
    const uint32_t w = film->width, h = film->height;
    const int prev = f->have_prev && f->width == w && f->height == h && f->cam.screen_width == w &&
                     f->cam.screen_height == h;
    if (fresh_size(f, w, h, err) != TR_OK) {
        return TR_ERR;
    }
    const int iw = (int)w, ih = (int)h;
    threads = threads > 0 ? threads : tr_default_threads();
    uint32_t fresh = 0;
#pragma omp parallel for num_threads(threads) schedule(static) reduction(+ : fresh)
    for (int y = 0; y < ih; ++y) {
        for (int x = 0; x < iw; ++x) {
            const size_t i = (size_t)y * w + (size_t)x;
            float depth;
            tr_vec3 n;
            uint32_t prim;
            pixel_passes(film, i, &depth, &n, &prim);
            const tr_vec3 m = motion && prim < motion_count ? motion[prim] : v3s(0.0f);
            tr_vec3 p = v3s(0.0f);
            const int lost =
                tr_reproject_lost(cam, &f->cam, prev, (uint32_t)x, (uint32_t)y, depth, n, prim, m,
                                  f->depth, f->normal, f->prim, f->point, &p);
            if (depth > 0.0f) {
                /* The point the temporal stage reprojects, kept for tr_fresh_remember. */
                f->cur[3 * i] = p.x;
                f->cur[3 * i + 1] = p.y;
                f->cur[3 * i + 2] = p.z;
            }
            f->mask[i] = (uint8_t)lost;
            fresh += (uint32_t)lost;
        }
    }
    f->fresh = fresh;
    return TR_OK;
}

int tr_fresh_trace(const tr_fresh *f, const tr_scene *scene, const tr_camera *cam,
                   const tr_render_config *cfg, uint32_t sample, uint32_t count, int threads,
                   tr_film *film, tr_error *err) {
    tr_frame fr;
    if (tr_frame_make(&fr, cam, cfg, sample, count, NULL, err) != TR_OK) {
        return TR_ERR;
    }
    const tr_scene_view view = tr_scene_view_of(scene);
    tr_film_view fv = tr_film_view_of(film);
    fv.passes = fr.passes;
    const int w = (int)film->width, h = (int)film->height;
    const int nt = threads > 0 ? threads : tr_default_threads();
    /* Rows apart: no two threads add to one pixel. */
#pragma omp parallel for num_threads(nt) schedule(dynamic, 4)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            if (f->mask[(size_t)y * (size_t)w + (size_t)x]) {
                (void)tr_render_grid_rows(&view, &fr, &fv, (uint32_t)x, (uint32_t)y,
                                          (uint32_t)x + 1u, (uint32_t)y + 1u);
            }
        }
    }
    return TR_OK;
}

int tr_fresh_remember(tr_fresh *f, const tr_film *film, const tr_camera *cam, tr_error *err) {
    if (fresh_size(f, film->width, film->height, err) != TR_OK) {
        return TR_ERR;
    }
    const uint32_t w = film->width;
    const size_t n = (size_t)w * film->height;
    for (size_t i = 0; i < n; ++i) {
        tr_vec3 nn;
        pixel_passes(film, i, &f->depth[i], &nn, &f->prim[i]);
        f->normal[3 * i] = nn.x;
        f->normal[3 * i + 1] = nn.y;
        f->normal[3 * i + 2] = nn.z;
        if (f->mask[i] && f->depth[i] > 0.0f) {
            /* Traced again: its depth is the mean of more samples now. */
            const tr_vec3 p = tr_camera_point_at(cam, (float)(i % w), (float)(i / w), f->depth[i]);
            f->cur[3 * i] = p.x;
            f->cur[3 * i + 1] = p.y;
            f->cur[3 * i + 2] = p.z;
        }
    }
    float *t = f->point;
    f->point = f->cur;
    f->cur = t;
    f->cam = *cam;
    f->have_prev = 1;
    return TR_OK;
}

int tr_fresh_frame_device(tr_fresh *f, struct tr_device *dev, const tr_camera *cam,
                          const tr_render_config *cfg, uint32_t sample, uint32_t count,
                          const tr_vec3 *motion, uint32_t motion_count, tr_error *err) {
    tr_cl_context *cl = tr_device_cl_context(dev);
    if (!cl) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "fresh samples on the device: not an OpenCL device");
    }
    tr_frame fr;
    if (count > 0u && tr_frame_make(&fr, cam, cfg, sample, count, NULL, err) != TR_OK) {
        return TR_ERR;
    }
    uint32_t fresh = 0;
    if (tr_cl_fresh_frame(cl, f->have_prev ? &f->cam : NULL, cam, motion, motion_count,
                          count > 0u ? &fr : NULL, &fresh, err) != TR_OK) {
        f->have_prev = 0;
        return TR_ERR;
    }
    f->fresh = fresh;
    f->cam = *cam;
    f->have_prev = 1;
    return TR_OK;
}
