/* render_adaptive.c - passes with a noise threshold and a time budget (render_adaptive.h). */
#include "render_adaptive.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

double adapt_pixel_error(const float full[3], const float half[3]) {
    double diff = fabs((double)full[0] - half[0]) + fabs((double)full[1] - half[1]) +
                  fabs((double)full[2] - half[2]);
    double sum = fmax(0.0, (double)full[0] + full[1] + full[2]);
    return diff / (1e-4 + sqrt(sum));
}

/* The film's mean of pixel i into out (0 for a pixel without samples). */
static void pixel_mean(const tr_film *f, size_t i, float out[3]) {
    float inv = f->count[i] ? 1.0f / (float)f->count[i] : 0.0f;
    for (int c = 0; c < 3; ++c) {
        out[c] = f->sum[3 * i + c] * inv;
    }
}

/* Marks tiles converged whose pixels' mean error estimate is below the threshold: one
 * pixel's estimate, from two halves, is too noisy to decide on (its spread is about its
 * size), the mean of a tile's 64 is good to about 10 %. */
static void converge_tiles(const tr_film *full, const tr_film *half, unsigned char *active,
                           uint32_t tx, uint32_t ty, float threshold, uint32_t *converged) {
    for (uint32_t t = 0; t < tx * ty; ++t) {
        if (!active[t]) {
            continue;
        }
        const uint32_t x0 = (t % tx) * ADAPT_TILE, y0 = (t / tx) * ADAPT_TILE;
        const uint32_t x1 = x0 + ADAPT_TILE < full->width ? x0 + ADAPT_TILE : full->width;
        const uint32_t y1 = y0 + ADAPT_TILE < full->height ? y0 + ADAPT_TILE : full->height;
        double sum = 0.0;
        for (uint32_t y = y0; y < y1; ++y) {
            for (uint32_t x = x0; x < x1; ++x) {
                const size_t i = (size_t)y * full->width + x;
                float a[3], b[3];
                pixel_mean(full, i, a);
                pixel_mean(half, i, b);
                sum += adapt_pixel_error(a, b);
            }
        }
        if (sum < threshold * (double)((x1 - x0) * (y1 - y0))) {
            active[t] = 0;
            ++*converged;
        }
    }
}

/* One sample (number `sample`) of every active tile: each maximal run of active tiles in
 * a row of tiles is one rectangle, and rows that are wholly active merge into one. */
static int render_active(cli_backend *be, const tr_scene *scene, const tr_render_config *cfg,
                         uint32_t sample, const unsigned char *active, uint32_t tx, uint32_t ty,
                         adapt_result *res, tr_error *err) {
    const tr_camera *cam = tr_scene_camera(scene);
    const uint32_t w = cam->screen_width, h = cam->screen_height;
    uint32_t row = 0;
    while (row < ty) {
        uint32_t full_rows = 0;
        while (row + full_rows < ty) {
            uint32_t k = 0;
            while (k < tx && active[(row + full_rows) * tx + k]) {
                ++k;
            }
            if (k < tx) {
                break;
            }
            ++full_rows;
        }
        if (full_rows > 0) {
            const uint32_t y0 = row * ADAPT_TILE;
            const uint32_t y1 =
                (row + full_rows) * ADAPT_TILE < h ? (row + full_rows) * ADAPT_TILE : h;
            tr_rect r = {0, y0, w, y1 - y0};
            tr_render_stats st;
            if (tr_device_render(be->dev, cam, cfg, sample, 1, &r, &st, err) != TR_OK) {
                return TR_ERR;
            }
            res->rays += st.rays;
            res->samples += (uint64_t)r.width * r.height;
            row += full_rows;
            continue;
        }
        uint32_t k = 0;
        while (k < tx) {
            if (!active[row * tx + k]) {
                ++k;
                continue;
            }
            uint32_t k1 = k;
            while (k1 < tx && active[row * tx + k1]) {
                ++k1;
            }
            const uint32_t x0 = k * ADAPT_TILE, x1 = k1 * ADAPT_TILE < w ? k1 * ADAPT_TILE : w;
            const uint32_t y0 = row * ADAPT_TILE;
            const uint32_t y1 = y0 + ADAPT_TILE < h ? y0 + ADAPT_TILE : h;
            tr_rect r = {x0, y0, x1 - x0, y1 - y0};
            tr_render_stats st;
            if (tr_device_render(be->dev, cam, cfg, sample, 1, &r, &st, err) != TR_OK) {
                return TR_ERR;
            }
            res->rays += st.rays;
            res->samples += (uint64_t)r.width * r.height;
            k = k1;
        }
        ++row;
    }
    return TR_OK;
}

int adapt_render(cli_backend *be, const tr_scene *scene, const tr_render_config *cfg,
                 const adapt_options *opt, adapt_result *res, tr_error *err) {
    memset(res, 0, sizeof *res);
    const tr_camera *cam = tr_scene_camera(scene);
    const uint32_t w = cam->screen_width, h = cam->screen_height;
    const uint32_t tx = (w + ADAPT_TILE - 1) / ADAPT_TILE, ty = (h + ADAPT_TILE - 1) / ADAPT_TILE;
    const int adaptive = opt->noise_threshold > 0.0f;
    unsigned char *active = malloc((size_t)tx * ty);
    tr_film films[2];
    memset(films, 0, sizeof films);
    if (!active || (adaptive && (tr_film_init(&films[0], w, h, err) != TR_OK ||
                                 tr_film_init(&films[1], w, h, err) != TR_OK))) {
        free(active);
        tr_film_free(&films[0]);
        tr_film_free(&films[1]);
        return active ? TR_ERR : tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
    }
    memset(active, 1, (size_t)tx * ty);
    res->tiles = tx * ty;
    int half = 0; /* films[half] holds the film at the previous power of two */
    int have_half = 0;
    const double t0 = tr_time_now();
    double last_pass = 0.0;
    int rc = TR_OK;
    for (uint32_t s = 0; s < opt->spp && res->tiles_converged < res->tiles; ++s) {
        const double now = tr_time_now();
        if (opt->time_limit > 0.0 && s > 0 && now - t0 + last_pass > opt->time_limit) {
            res->stopped_by_time = 1; /* the next pass would end past the budget */
            break;
        }
        if (render_active(be, scene, cfg, s, active, tx, ty, res, err) != TR_OK) {
            rc = TR_ERR;
            break;
        }
        last_pass = tr_time_now() - now;
        res->passes = s + 1;
        const uint32_t n = s + 1;
        if (adaptive && n >= ADAPT_FIRST_CHECK / 2 && (n & (n - 1)) == 0 && n < opt->spp) {
            tr_film *cur = &films[1 - half];
            if (cli_backend_read(be, cur, err) != TR_OK) {
                rc = TR_ERR;
                break;
            }
            if (have_half) {
                converge_tiles(cur, &films[half], active, tx, ty, opt->noise_threshold,
                               &res->tiles_converged);
            }
            half = 1 - half;
            have_half = 1;
        }
        if (opt->progress) {
            double el = tr_time_now() - t0;
            fprintf(stderr,
                    "\rtrac0r render: %u/%u spp  %u/%u tiles converged  %.1f s elapsed  "
                    "%.2f Mrays/s ",
                    n, opt->spp, res->tiles_converged, res->tiles, el,
                    el > 0 ? (double)res->rays / el * 1e-6 : 0.0);
        }
    }
    res->seconds = tr_time_now() - t0;
    free(active);
    tr_film_free(&films[0]);
    tr_film_free(&films[1]);
    return rc;
}
