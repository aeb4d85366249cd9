/* filter.c - the host side of real-time reconstruction: runs the per-pixel operators of
 * src/post/filter.h over images, rows spread over OpenMP threads. Every output pixel is
 * computed from read-only inputs in a fixed tap order, so results do not depend on the
 * thread count. */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "post/filter.h"
#include "trac0r/film.h"
#include "trac0r/post.h"
#include "trac0r/render.h"

static int nthreads(int threads) {
    return threads > 0 ? threads : omp_get_max_threads();
}

int tr_gbuffer_init(tr_gbuffer *g, uint32_t width, uint32_t height, tr_error *err) {
    memset(g, 0, sizeof *g);
    if (tr_film_check_size(width, height, err) != TR_OK) {
        return TR_ERR;
    }
    const size_t n = (size_t)width * height;
    g->width = width;
    g->height = height;
    g->color = calloc(3 * n, sizeof *g->color);
    g->albedo = calloc(3 * n, sizeof *g->albedo);
    g->normal = calloc(3 * n, sizeof *g->normal);
    g->depth = calloc(n, sizeof *g->depth);
    g->prim = calloc(n, sizeof *g->prim);
    if (!g->color || !g->albedo || !g->normal || !g->depth || !g->prim) {
        tr_gbuffer_free(g);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u frame", width,
                            height);
    }
    return TR_OK;
}

void tr_gbuffer_free(tr_gbuffer *g) {
    free(g->color);
    free(g->albedo);
    free(g->normal);
    free(g->depth);
    free(g->prim);
    memset(g, 0, sizeof *g);
}

int tr_gbuffer_from_film(tr_gbuffer *g, const struct tr_film *f, tr_error *err) {
    if (g->width != f->width || g->height != f->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "gbuffer: %ux%u frame for a %ux%u film", g->width, g->height, f->width,
                            f->height);
    }
    const size_t n = (size_t)f->width * f->height;
    for (size_t i = 0; i < n; ++i) {
        const uint32_t c = f->count[i];
        const float inv = c ? 1.0f / (float)c : 0.0f;
        for (int k = 0; k < 3; ++k) {
            g->color[3 * i + k] = f->sum[3 * i + k] * inv;
            g->albedo[3 * i + k] = f->albedo ? f->albedo[3 * i + k] * inv : 1.0f;
            g->normal[3 * i + k] = f->normal ? f->normal[3 * i + k] * inv : 0.0f;
        }
        g->depth[i] = f->depth ? f->depth[i] * inv : 0.0f;
        g->prim[i] = f->prim ? f->prim[i] : 0u;
    }
    return TR_OK;
}

static const char *const recon_names[TR_RECON_COUNT] = {"off", "accumulate", "bilateral", "atrous",
                                                        "svgf"};

const char *tr_recon_name(int method) {
    return method >= 0 && method < TR_RECON_COUNT ? recon_names[method] : NULL;
}

int tr_recon_parse(const char *name) {
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        if (strcmp(name, recon_names[m]) == 0) {
            return m;
        }
    }
    return -1;
}

tr_recon_params tr_recon_params_default(void) {
    tr_recon_params p;
    p.alpha_min = 0.1f;
    p.max_len = 64.0f;
    p.bilateral_radius = 3;
    p.bilateral_sigma_s = 2.0f;
    p.bilateral_sigma_r = 0.3f;
    p.atrous_iterations = 5;
    /* Dammertz et al.'s colour sigma acts on demodulated illumination in [0, ~1]. */
    p.atrous_sigma_c = 0.6f;
    p.atrous_sigma_n = 0.3f;
    p.atrous_sigma_z = 0.05f;
    p.atrous_sigma_a = 0.1f;
    /* Schied et al.'s values: sigma_l 4, sigma_n 128, sigma_z 1. */
    p.svgf_sigma_l = 4.0f;
    p.svgf_sigma_n = 128.0f;
    p.svgf_sigma_z = 1.0f;
    return p;
}

int tr_recon_init(tr_recon *r, uint32_t width, uint32_t height, tr_error *err) {
    memset(r, 0, sizeof *r);
    if (tr_film_check_size(width, height, err) != TR_OK) {
        return TR_ERR;
    }
    const size_t n = (size_t)width * height;
    r->width = width;
    r->height = height;
    int bad = 0;
    for (int k = 0; k < 2; ++k) {
        r->hist_color[k] = calloc(3 * n, sizeof(float));
        r->hist_moments[k] = calloc(2 * n, sizeof(float));
        r->hist_len[k] = calloc(n, sizeof(float));
        bad |= !r->hist_color[k] || !r->hist_moments[k] || !r->hist_len[k];
    }
    r->hist_depth = calloc(n, sizeof(float));
    r->hist_normal = calloc(3 * n, sizeof(float));
    r->hist_prim = calloc(n, sizeof(uint32_t));
    r->illum = calloc(3 * n, sizeof(float));
    r->tmp_a = calloc(3 * n, sizeof(float));
    r->tmp_b = calloc(3 * n, sizeof(float));
    r->var_a = calloc(n, sizeof(float));
    r->var_b = calloc(n, sizeof(float));
    bad |= !r->hist_depth || !r->hist_normal || !r->hist_prim || !r->illum || !r->tmp_a ||
           !r->tmp_b || !r->var_a || !r->var_b;
    if (bad) {
        tr_recon_free(r);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory for a %ux%u reconstruction", width, height);
    }
    return TR_OK;
}

void tr_recon_free(tr_recon *r) {
    for (int k = 0; k < 2; ++k) {
        free(r->hist_color[k]);
        free(r->hist_moments[k]);
        free(r->hist_len[k]);
    }
    free(r->hist_depth);
    free(r->hist_normal);
    free(r->hist_prim);
    free(r->illum);
    free(r->tmp_a);
    free(r->tmp_b);
    free(r->var_a);
    free(r->var_b);
    memset(r, 0, sizeof *r);
}

void tr_recon_reset(tr_recon *r) {
    r->have_history = 0;
}

static int check_frame(uint32_t w, uint32_t h, const tr_gbuffer *g, tr_error *err) {
    if (g->width != w || g->height != h) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "reconstruction: %ux%u frame for a %ux%u state", g->width, g->height, w,
                            h);
    }
    return TR_OK;
}

/* One bilateral pass of `in` into `out`. */
static void bilateral(const tr_gbuffer *g, const float *in, float *out, const tr_recon_params *p,
                      int threads) {
    const int w = (int)g->width, h = (int)g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            tr_post_bilateral_pixel(in, w, h, x, y, p->bilateral_radius, p->bilateral_sigma_s,
                                    p->bilateral_sigma_r, out + 3 * ((size_t)y * w + x));
        }
    }
}

/* Dammertz et al.'s iterations on demodulated `illum` (overwritten): the result in the
 * buffer returned (illum or tmp); sigma_c halves each step as in the paper. */
static float *atrous(const tr_gbuffer *g, float *illum, float *tmp, const tr_recon_params *p,
                     int threads) {
    const int w = (int)g->width, h = (int)g->height;
    float *src = illum, *dst = tmp;
    for (int it = 0; it < p->atrous_iterations; ++it) {
        const int step = 1 << it;
        const float sc = p->atrous_sigma_c / (float)(1 << it);
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                tr_post_atrous_pixel(src, g->normal, g->depth, g->albedo, w, h, x, y, step, sc,
                                     p->atrous_sigma_n, p->atrous_sigma_z, p->atrous_sigma_a,
                                     dst + 3 * ((size_t)y * w + x));
            }
        }
        float *t = src;
        src = dst;
        dst = t;
    }
    return src;
}

static void demodulate(const tr_gbuffer *g, const float *in, float *out, int threads) {
    const long n = (long)g->width * g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            out[3 * i + k] = in[3 * i + k] / tr_post_demod_factor(g->albedo[3 * i + k]);
        }
    }
}

static void remodulate(const tr_gbuffer *g, const float *in, float *out, int threads) {
    const long n = (long)g->width * g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (long i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            out[3 * i + k] = in[3 * i + k] * tr_post_demod_factor(g->albedo[3 * i + k]);
        }
    }
}

int tr_filter_bilateral(const tr_gbuffer *g, const float *in, float *out, const tr_recon_params *p,
                        int threads, tr_error *err) {
    (void)err;
    bilateral(g, in, out, p, nthreads(threads));
    return TR_OK;
}

int tr_filter_atrous(const tr_gbuffer *g, const float *in, float *out, const tr_recon_params *p,
                     int threads, tr_error *err) {
    const size_t n = (size_t)g->width * g->height;
    float *a = malloc(3 * n * sizeof *a), *b = malloc(3 * n * sizeof *b);
    if (!a || !b) {
        free(a);
        free(b);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u filter",
                            g->width, g->height);
    }
    threads = nthreads(threads);
    demodulate(g, in, a, threads);
    remodulate(g, atrous(g, a, b, p, threads), out, threads);
    free(a);
    free(b);
    return TR_OK;
}

/* SVGF's variance of each pixel's luminance: from the temporal moments once 4 frames of
 * history exist, before that from the 5x5 neighbourhood's moments (Schied et al. take
 * 7x7 on the same condition), weighted by the normal so that it stays on one surface. */
static void svgf_variance(const tr_gbuffer *g, const float *illum, const float *moments,
                          const float *len, float *var, int threads) {
    const int w = (int)g->width, h = (int)g->height;
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const int c = y * w + x;
            if (len[c] >= 4.0f) {
                const float m = moments[2 * c];
                var[c] = tr_fmaxf(moments[2 * c + 1] - m * m, 0.0f);
                continue;
            }
            float s1 = 0.0f, s2 = 0.0f, sw = 0.0f;
            for (int dy = -2; dy <= 2; ++dy) {
                for (int dx = -2; dx <= 2; ++dx) {
                    const int tx = x + dx, ty = y + dy;
                    if (tx < 0 || ty < 0 || tx >= w || ty >= h) {
                        continue;
                    }
                    const int i = ty * w + tx;
                    const float nd = g->normal[3 * c] * g->normal[3 * i] +
                                     g->normal[3 * c + 1] * g->normal[3 * i + 1] +
                                     g->normal[3 * c + 2] * g->normal[3 * i + 2];
                    const float wt = (dx == 0 && dy == 0) || nd > 0.9f ? 1.0f : 0.0f;
                    const float l =
                        tr_post_luminance(illum[3 * i], illum[3 * i + 1], illum[3 * i + 2]);
                    s1 += wt * l;
                    s2 += wt * l * l;
                    sw += wt;
                }
            }
            const float m = s1 / sw;
            /* Few frames: trust the estimate less, as the paper boosts it. */
            var[c] = tr_fmaxf(s2 / sw - m * m, 0.0f) * (4.0f / len[c]);
        }
    }
}

/* SVGF's iterations on `illum`; the variance in var_a (overwritten). */
static float *svgf(const tr_gbuffer *g, float *illum, float *tmp, float *var_a, float *var_b,
                   const tr_recon_params *p, int threads) {
    const int w = (int)g->width, h = (int)g->height;
    float *src = illum, *dst = tmp, *vs = var_a, *vd = var_b;
    for (int it = 0; it < p->atrous_iterations; ++it) {
        const int step = 1 << it;
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                /* The centre's variance through a 3x3 Gaussian (the paper's prefilter),
                 * which keeps one noisy estimate from stopping the filter. */
                float cv = 0.0f, cw = 0.0f;
                for (int dy = -1; dy <= 1; ++dy) {
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int tx = x + dx, ty = y + dy;
                        if (tx < 0 || ty < 0 || tx >= w || ty >= h) {
                            continue;
                        }
                        const float k = (dx ? 0.5f : 1.0f) * (dy ? 0.5f : 1.0f);
                        cv += k * vs[ty * w + tx];
                        cw += k;
                    }
                }
                const size_t c = (size_t)y * w + x;
                tr_post_svgf_pixel(src, vs, g->normal, g->depth, w, h, x, y, step, p->svgf_sigma_l,
                                   p->svgf_sigma_n, p->svgf_sigma_z, cv / cw, dst + 3 * c, vd + c);
            }
        }
        float *t = src;
        src = dst;
        dst = t;
        t = vs;
        vs = vd;
        vd = t;
    }
    return src;
}

int tr_recon_frame(tr_recon *r, const tr_gbuffer *g, const tr_camera *cam, int method,
                   const tr_recon_params *p, int threads, float *out, tr_error *err) {
    if (check_frame(r->width, r->height, g, err) != TR_OK) {
        return TR_ERR;
    }
    if (!tr_recon_name(method)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "reconstruction: unknown method %d",
                            method);
    }
    if (cam->screen_width != g->width || cam->screen_height != g->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "reconstruction: a %ux%u camera for a %ux%u frame", cam->screen_width,
                            cam->screen_height, g->width, g->height);
    }
    threads = nthreads(threads);
    const int w = (int)g->width, h = (int)g->height;
    const size_t n = (size_t)w * h;
    r->ms_temporal = r->ms_spatial = 0.0;
    if (method == TR_RECON_OFF) {
        memcpy(out, g->color, 3 * n * sizeof *out);
        r->have_history = 0;
        return TR_OK;
    }
    const double t0 = tr_time_now();
    demodulate(g, g->color, r->illum, threads);
    const int prev = r->cur, next = 1 - r->cur;
    float *hc = r->hist_color[next], *hm = r->hist_moments[next], *hl = r->hist_len[next];
    if (r->have_history) {
        const tr_camera pc = r->prev_cam;
        const float *pcol = r->hist_color[prev], *pmom = r->hist_moments[prev],
                    *plen = r->hist_len[prev];
#pragma omp parallel for num_threads(threads) schedule(static)
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                const size_t i = (size_t)y * w + x;
                tr_post_temporal_pixel(cam, &pc, (uint32_t)x, (uint32_t)y, r->illum, g->normal,
                                       g->depth, g->prim, pcol, pmom, plen, r->hist_depth,
                                       r->hist_normal, r->hist_prim, p->alpha_min, p->max_len,
                                       hc + 3 * i, hm + 2 * i, hl + i);
            }
        }
    } else {
        for (size_t i = 0; i < n; ++i) {
            const float l =
                tr_post_luminance(r->illum[3 * i], r->illum[3 * i + 1], r->illum[3 * i + 2]);
            memcpy(hc + 3 * i, r->illum + 3 * i, 3 * sizeof *hc);
            hm[2 * i] = l;
            hm[2 * i + 1] = l * l;
            hl[i] = 1.0f;
        }
    }
    /* The geometry this history was seen with, for the next frame's test. */
    memcpy(r->hist_depth, g->depth, n * sizeof *r->hist_depth);
    memcpy(r->hist_normal, g->normal, 3 * n * sizeof *r->hist_normal);
    memcpy(r->hist_prim, g->prim, n * sizeof *r->hist_prim);
    r->prev_cam = *cam;
    r->cur = next;
    r->have_history = 1;
    const double t1 = tr_time_now();
    r->ms_temporal = (t1 - t0) * 1e3;

    memcpy(r->tmp_a, hc, 3 * n * sizeof *hc);
    if (method == TR_RECON_ACCUMULATE) {
        remodulate(g, r->tmp_a, out, threads);
    } else if (method == TR_RECON_BILATERAL) {
        remodulate(g, r->tmp_a, r->tmp_b, threads);
        bilateral(g, r->tmp_b, out, p, threads);
    } else if (method == TR_RECON_ATROUS) {
        remodulate(g, atrous(g, r->tmp_a, r->tmp_b, p, threads), out, threads);
    } else {
        svgf_variance(g, r->tmp_a, hm, hl, r->var_a, threads);
        remodulate(g, svgf(g, r->tmp_a, r->tmp_b, r->var_a, r->var_b, p, threads), out, threads);
    }
    r->ms_spatial = (tr_time_now() - t1) * 1e3;
    return TR_OK;
}
