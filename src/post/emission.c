/* emission.c - the first hit's emission resolved over a pixel's area, for the real-time
 * reconstruction (tr_resolve_emission, post.h).
 *
 * At one sample per pixel a pixel on a lamp's edge sees either the lamp or the ceiling, so
 * the lamp is drawn a fraction of a pixel too small or too large and its edge flickers from
 * frame to frame; the history cannot fix that, because it is kept per surface. Here the
 * pixels next to an edge between emitting and non-emitting first hits, or across a step
 * between two emitters (tr_emission_step: an environment's horizon), trace n x n camera
 * rays each, which see only the first hit (no shading, no path), and average the emission
 * they find: the pixel's coverage times the emitter's radiance, as a converged image has
 * it. Every other pixel keeps the emission of its own sample, which is exact there (it
 * covers one emitter, or a smooth part of one, or none). The per-pixel arithmetic is the
 * kernel's (src/kernel/emission.h), which an OpenCL device runs as it is.
 *
 * The albedo pass is resolved the same way where the caller asks (tr_resolve_albedo): the
 * pixels whose albedo differs from a neighbour's take the mean base colour of an n x n
 * grid of first hits (src/kernel/albedo.h), for the reconstruction's demodulation; and
 * tr_albedo_image traces one such ray through every pixel of a camera. */
#include <omp.h>
#include <string.h>

#include "kernel/albedo.h"
#include "kernel/emission.h"
#include "scene/scene_internal.h"
#include "trac0r/post.h"
#include "trac0r/render.h"

/* edge[i] = tr_emission_on_edge(e, w, h, x, y) for every pixel, computed with the loops
 * turned round (the count of emitting pixels in each clipped 3 x 3 block, from
 * horizontal then vertical sums of a 0/1 mask) so that it costs a few passes over bytes
 * instead of nine tests per pixel; only a pixel whose whole block saw emission compares
 * its neighbours' luminances (tr_emission_step). */
static void edge_mask(const float *e, int w, int h, uint8_t *seen, uint8_t *hsum, uint8_t *edge,
                      int threads) {
    const long n = (long)w * h;
#pragma omp parallel num_threads(threads)
    {
#pragma omp for schedule(static)
        for (long i = 0; i < n; ++i) {
            seen[i] = (uint8_t)tr_emission_seen(e, (uint32_t)i);
        }
#pragma omp for schedule(static)
        for (int y = 0; y < h; ++y) {
            const uint8_t *m = seen + (size_t)y * w;
            uint8_t *s = hsum + (size_t)y * w;
            for (int x = 0; x < w; ++x) {
                s[x] = (uint8_t)((x > 0 ? m[x - 1] : 0) + m[x] + (x + 1 < w ? m[x + 1] : 0));
            }
        }
#pragma omp for schedule(static)
        for (int y = 0; y < h; ++y) {
            const uint8_t *up = hsum + (size_t)(y > 0 ? y - 1 : y) * w;
            const uint8_t *mid = hsum + (size_t)y * w;
            const uint8_t *dn = hsum + (size_t)(y + 1 < h ? y + 1 : y) * w;
            const int rows = 1 + (y > 0) + (y + 1 < h);
            const uint8_t *m = seen + (size_t)y * w;
            uint8_t *out = edge + (size_t)y * w;
            for (int x = 0; x < w; ++x) {
                const int cols = 1 + (x > 0) + (x + 1 < w);
                const int k = (y > 0 ? up[x] : 0) + mid[x] + (y + 1 < h ? dn[x] : 0);
                /* A block that is all one kind holds 0 emitting pixels or all of them. */
                out[x] = (uint8_t)(m[x] ? k < rows * cols : k > 0);
                /* All of them: the emission may still step between neighbours. */
                if (m[x] && !out[x]) {
                    out[x] = (uint8_t)tr_emission_on_edge(e, w, h, x, y);
                }
            }
        }
    }
}

int tr_resolve_emission(const struct tr_scene *scene, const tr_camera *cam, int n, int threads,
                        tr_gbuffer *g, uint32_t *resolved, tr_error *err) {
    if (resolved) {
        *resolved = 0;
    }
    if (!g->has_emission) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "resolving emission: the frame has no emission pass");
    }
    if (n < 1 || n > TR_RESOLVE_EMISSION_MAX) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "resolving emission: %d x %d rays per pixel (expected 1..%d)", n, n,
                            TR_RESOLVE_EMISSION_MAX);
    }
    if (cam->screen_width != g->width || cam->screen_height != g->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "resolving emission: a %ux%u camera for a %ux%u frame",
                            cam->screen_width, cam->screen_height, g->width, g->height);
    }
    if (!tr_scene_is_committed(scene)) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "resolving emission: the scene is not committed");
    }
    const int w = (int)g->width, h = (int)g->height;
    const size_t px = (size_t)w * h;
    uint8_t *mask = g->scratch;
    threads = threads > 0 ? threads : tr_default_threads();
    uint8_t *edge = mask + 2 * px;
    edge_mask(g->emission, w, h, mask, mask + px, edge, threads);
    const tr_scene_view view = tr_scene_view_of(scene);
    memcpy(g->emission_resolved, g->emission, 3 * px * sizeof(float));
    uint32_t count = 0;
    /* Few pixels are on an edge, and they cluster: rows go out a few at a time. */
#pragma omp parallel for num_threads(threads) schedule(dynamic, 8) reduction(+ : count)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            if (!edge[i]) {
                continue;
            }
            const tr_vec3 e = tr_emission_resolve_pixel(&view, cam, x, y, n);
            g->emission_resolved[3 * i] = e.x;
            g->emission_resolved[3 * i + 1] = e.y;
            g->emission_resolved[3 * i + 2] = e.z;
            ++count;
        }
    }
    g->has_resolved = 1;
    if (resolved) {
        *resolved = count;
    }
    return TR_OK;
}

/* edge[i] = 1 where pixel i's albedo differs from a neighbour's by more than
 * TR_RESOLVE_ALBEDO_STEP in a channel. */
static void albedo_edges(const float *a, int w, int h, uint8_t *edge, int threads) {
#pragma omp parallel for num_threads(threads) schedule(static)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const float *c = a + 3 * ((size_t)y * w + x);
            int differs = 0;
            for (int dy = -1; dy <= 1 && !differs; ++dy) {
                for (int dx = -1; dx <= 1; ++dx) {
                    const int xx = x + dx, yy = y + dy;
                    if (xx < 0 || yy < 0 || xx >= w || yy >= h) {
                        continue;
                    }
                    const float *o = a + 3 * ((size_t)yy * w + xx);
                    if (tr_fabsf(o[0] - c[0]) > TR_RESOLVE_ALBEDO_STEP ||
                        tr_fabsf(o[1] - c[1]) > TR_RESOLVE_ALBEDO_STEP ||
                        tr_fabsf(o[2] - c[2]) > TR_RESOLVE_ALBEDO_STEP) {
                        differs = 1;
                        break;
                    }
                }
            }
            edge[(size_t)y * w + x] = (uint8_t)differs;
        }
    }
}

int tr_resolve_albedo(const struct tr_scene *scene, const tr_camera *cam, int n, int threads,
                      tr_gbuffer *g, uint32_t *resolved, tr_error *err) {
    if (resolved) {
        *resolved = 0;
    }
    if (n < 1 || n > TR_RESOLVE_ALBEDO_MAX) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "resolving the albedo: %d x %d rays per pixel (expected 1..%d)", n, n,
                            TR_RESOLVE_ALBEDO_MAX);
    }
    if (cam->screen_width != g->width || cam->screen_height != g->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "resolving the albedo: a %ux%u camera for a %ux%u frame",
                            cam->screen_width, cam->screen_height, g->width, g->height);
    }
    if (!tr_scene_is_committed(scene)) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "resolving the albedo: the scene is not committed");
    }
    const int w = (int)g->width, h = (int)g->height;
    threads = threads > 0 ? threads : tr_default_threads();
    uint8_t *edge = g->scratch;
    albedo_edges(g->albedo, w, h, edge, threads);
    const tr_scene_view view = tr_scene_view_of(scene);
    uint32_t count = 0;
    /* Every pixel's test read the albedo before any is replaced; the rays read the scene. */
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4) reduction(+ : count)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            if (!edge[i]) {
                continue;
            }
            const tr_vec3 a = tr_albedo_resolve_pixel(&view, cam, x, y, n);
            g->albedo[3 * i] = a.x;
            g->albedo[3 * i + 1] = a.y;
            g->albedo[3 * i + 2] = a.z;
            ++count;
        }
    }
    if (resolved) {
        *resolved = count;
    }
    return TR_OK;
}

int tr_albedo_image(const struct tr_scene *scene, const tr_camera *cam, int threads, float *out,
                    tr_error *err) {
    if (!scene || !cam || !out) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "the albedo image: NULL argument");
    }
    if (!tr_scene_is_committed(scene)) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "the albedo image: the scene is not committed");
    }
    const int w = (int)cam->screen_width, h = (int)cam->screen_height;
    threads = threads > 0 ? threads : tr_default_threads();
    const tr_scene_view view = tr_scene_view_of(scene);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const tr_vec3 a = tr_albedo_resolve_pixel(&view, cam, x, y, 1);
            out[3 * i] = a.x;
            out[3 * i + 1] = a.y;
            out[3 * i + 2] = a.z;
        }
    }
    return TR_OK;
}
