/* upscale.c - the host side of temporal upscaling (include/trac0r/upscale.h): the
 * per-pixel operator of src/post/upscale.h over the output's rows, and the samples'
 * positions from the kernel's own jitter. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

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
        for (int x = 0; x < wl; ++x) {
            tr_upscale_box_pixel(in->color, wl, hl, x, y, box + 6 * ((size_t)y * wl + x));
        }
    }
#pragma omp parallel for num_threads(nt) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            tr_upscale_pixel(cam, &pc, x, y, (int)in->width, (int)in->height, in->color, in->pos,
                             in->depth, in->prim, mot, motion ? motion_count : 0u, hcol,
                             u->count[prev], u->depth[prev], box, cap, oc + 3 * i, ol + i, od + i);
        }
    }
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

int tr_upscale_emission(const struct tr_scene *scene, const tr_camera *cam, int n, int threads,
                        uint32_t width, uint32_t height, const float *emission, const float *prev,
                        float *out, uint32_t *resolved, tr_error *err) {
    if (resolved) {
        *resolved = 0;
    }
    if (!scene || !cam || !emission || !out || width == 0 || height == 0 ||
        width > cam->screen_width || height > cam->screen_height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tr_upscale_emission: empty frame or NULL argument");
    }
    if (n < 1 || n > TR_RESOLVE_EMISSION_MAX) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tr_upscale_emission: %d x %d rays per pixel (expected 1..%d)", n, n,
                            TR_RESOLVE_EMISSION_MAX);
    }
    if (!tr_scene_is_committed(scene)) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "tr_upscale_emission: the scene is not committed");
    }
    const int W = (int)cam->screen_width, H = (int)cam->screen_height;
    const int wl = (int)width, hl = (int)height;
    const float sxr = (float)wl / (float)W, syr = (float)hl / (float)H;
    const tr_scene_view view = tr_scene_view_of(scene);
    const int nt = threads > 0 ? threads : omp_get_max_threads();
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
             * output saw emission and the neighbourhood sees none, trace it too. */
            const int missed = prev && tr_emission_seen(prev, (uint32_t)i) &&
                               !tr_emission_seen(emission, (uint32_t)k);
            if (missed || tr_emission_on_edge(emission, wl, hl, lx, ly)) {
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
    if (resolved) {
        *resolved = count;
    }
    return TR_OK;
}
