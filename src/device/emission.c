/* emission.c - the first hit's emission resolved over a pixel's area, for the real-time
 * reconstruction (tr_resolve_emission, post.h).
 *
 * At one sample per pixel a pixel on a lamp's edge sees either the lamp or the ceiling, so
 * the lamp is drawn a fraction of a pixel too small or too large and its edge flickers from
 * frame to frame; the history cannot fix that, because it is kept per surface. Here the
 * pixels next to an edge between emitting and non-emitting first hits trace a grid of n x n
 * camera rays each, which see only the first hit (no shading, no path), and average the
 * emission they find: the pixel's coverage times the emitter's radiance, as a converged
 * image has it. Every other pixel keeps the emission of its own sample, which is exact
 * there (it covers one emitter, or none). */
#include <omp.h>
#include <string.h>

#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/post.h"
#include "trac0r/render.h"

/* Whether pixel i's own sample saw any emission. */
static int emits(const tr_gbuffer *g, size_t i) {
    const float *e = g->emission + 3 * i;
    return e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f;
}

/* Whether a pixel of the 3 x 3 block around (x, y) differs from it in emits(). */
static int on_edge(const tr_gbuffer *g, int x, int y) {
    const int w = (int)g->width, h = (int)g->height;
    const int c = emits(g, (size_t)y * w + x);
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx >= 0 && yy >= 0 && xx < w && yy < h && emits(g, (size_t)yy * w + xx) != c) {
                return 1;
            }
        }
    }
    return 0;
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
    const tr_scene_view view = tr_scene_view_of(scene);
    const int w = (int)g->width, h = (int)g->height;
    memcpy(g->emission_resolved, g->emission, 3 * (size_t)w * h * sizeof(float));
    const float inv_n = 1.0f / (float)n, inv_nn = inv_n * inv_n;
    uint32_t count = 0;
    threads = threads > 0 ? threads : tr_default_threads();
    /* Few pixels are on an edge, and they cluster: rows go out a few at a time. */
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4) reduction(+ : count)
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            if (!on_edge(g, x, y)) {
                continue;
            }
            tr_vec3 sum = v3s(0.0f);
            for (int sy = 0; sy < n; ++sy) {
                for (int sx = 0; sx < n; ++sx) {
                    /* The centres of an n x n grid of cells over the pixel. */
                    const tr_ray ray =
                        tr_camera_ray(cam, (float)x, (float)y, ((float)sx + 0.5f) * inv_n,
                                      ((float)sy + 0.5f) * inv_n);
                    sum = v3_add(sum, tr_pt_first_emission(&view, ray));
                }
            }
            float *e = g->emission_resolved + 3 * ((size_t)y * w + x);
            e[0] = sum.x * inv_nn;
            e[1] = sum.y * inv_nn;
            e[2] = sum.z * inv_nn;
            ++count;
        }
    }
    g->has_resolved = 1;
    if (resolved) {
        *resolved = count;
    }
    return TR_OK;
}
