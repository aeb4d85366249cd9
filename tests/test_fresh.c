/* test_fresh.c - extra samples for the pixels without history (tr_recon_params.fresh_spp,
 * src/realtime/fresh.h) in the real-time loop on the CPU device, on the classic box.
 *
 * 1. The first frame: every pixel that hit a surface holds fresh_spp samples, the others
 *    the frame's one.
 * 2. At rest (the same camera twice more) and after a move sideways, exactly the pixels
 *    that hit a surface and for which the reconstruction's own temporal stage keeps no
 *    history (a tr_recon given the same frames' passes: history length 1; at rest the
 *    pixels whose sample crossed an edge between two triangles) hold fresh_spp samples,
 *    every other pixel its one sample, bit for bit the sample an instance without the
 *    extra samples renders; the move uncovers some pixels, under a quarter.
 * 3. The films do not depend on the thread count. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "classic_box.h"
#include "fresh_run.h"
#include "trac0r/trac0r.h"

#define W 64
#define H 48
#define FRESH 4

static tr_device *cpu(void) {
    tr_error err;
    tr_device *dev = tr_device_create("cpu", &err);
    CHECK(dev != NULL, "%s", err.msg);
    return dev;
}

static int same_film(const tr_film *a, const tr_film *b) {
    const size_t n = (size_t)W * H;
    return memcmp(a->sum, b->sum, 3 * n * sizeof *a->sum) == 0 &&
           memcmp(a->count, b->count, n * sizeof *a->count) == 0 &&
           memcmp(a->depth, b->depth, n * sizeof *a->depth) == 0 &&
           memcmp(a->normal, b->normal, 3 * n * sizeof *a->normal) == 0 &&
           memcmp(a->albedo, b->albedo, 3 * n * sizeof *a->albedo) == 0;
}

/* The history length the reconstruction's temporal stage gives each pixel of the frame
 * `film` after the frame `prev` (both of one sample, as an instance without the extra
 * samples renders them): hist_len of a tr_recon given both (accumulate). */
static void history_lengths(const tr_film *prev, const tr_camera *prev_cam, const tr_film *film,
                            const tr_camera *cam, float *len) {
    tr_error err;
    tr_recon r;
    tr_gbuffer g;
    CHECK(tr_recon_init(&r, W, H, &err) == TR_OK && tr_gbuffer_init(&g, W, H, &err) == TR_OK, "%s",
          err.msg);
    float *out = malloc(3u * W * H * sizeof *out);
    tr_recon_params p = tr_recon_params_default();
    p.emission_samples = 0;
    CHECK(tr_gbuffer_from_film(&g, prev, &err) == TR_OK &&
              tr_recon_frame(&r, &g, prev_cam, TR_RECON_ACCUMULATE, &p, 1, out, &err) == TR_OK,
          "%s", err.msg);
    CHECK(tr_gbuffer_from_film(&g, film, &err) == TR_OK &&
              tr_recon_frame(&r, &g, cam, TR_RECON_ACCUMULATE, &p, 1, out, &err) == TR_OK,
          "%s", err.msg);
    memcpy(len, r.hist_len[r.cur], (size_t)W * H * sizeof *len);
    free(out);
    tr_gbuffer_free(&g);
    tr_recon_free(&r);
}

/* Pixel i hit a surface (the depth pass is positive). */
static int hit(const tr_film *f, size_t i) {
    return f->depth[i] > 0.0f;
}

/* The pixels of frame `f` that hold another count than the rule's, from the history
 * lengths `len` of the same frame without the extra samples (`p`): FRESH where a pixel hit
 * a surface and has no history (length 1), the frame's one elsewhere. *traced: how many
 * pixels the rule traces again. */
static size_t wrong_counts(const tr_film *f, const tr_film *p, const float *len, size_t *traced) {
    size_t bad = 0, t = 0;
    for (size_t i = 0; i < (size_t)W * H; ++i) {
        const int again = hit(p, i) && len[i] == 1.0f;
        t += (size_t)again;
        bad += (size_t)(f->count[i] != (again ? FRESH : 1u));
    }
    *traced = t;
    return bad;
}

int main(void) {
    tr_error err;
    tr_scene *s = classic_box(W, H, &err);
    tr_device *d0 = cpu(), *d1 = cpu(), *d2 = cpu();
    tr_realtime *plain = make(d0, s, 0, 2);
    tr_realtime *fresh = make(d1, s, FRESH, 2);
    tr_realtime *fresh1 = make(d2, s, FRESH, 1); /* one thread */
    const size_t n = (size_t)W * H;
    tr_film keep; /* the previous film of the instance with the extra samples */
    CHECK(tr_film_init_passes(&keep, W, H, TR_PASS_ALL, &err) == TR_OK, "%s", err.msg);
    float *len = malloc(n * sizeof *len);

    tr_camera cam0 = *tr_scene_camera(s); /* nearer the box's opening */
    const float fwd = 200.0f;
    cam0.pos.x += fwd * cam0.dir.x;
    cam0.pos.y += fwd * cam0.dir.y;
    cam0.pos.z += fwd * cam0.dir.z;
    tr_camera cam2 = cam0; /* a move sideways: a strip and the boxes' sides uncovered */
    const float side = 150.0f;
    cam2.pos.x += side * cam0.right.x;
    cam2.pos.y += side * cam0.right.y;
    cam2.pos.z += side * cam0.right.z;
    const tr_camera *cams[4] = {&cam0, &cam0, &cam0, &cam2};
    for (int k = 0; k < 4; ++k) {
        const tr_film *p = frame(plain, cams[k]);
        const tr_film *f = frame(fresh, cams[k]);
        const tr_film *f1 = frame(fresh1, cams[k]);
        CHECK(same_film(f, f1), "frame %d: the film depends on the thread count", k);
        size_t bad = 0, traced = 0;
        if (k == 0) {
            /* No history anywhere: every pixel that hit a surface traced again. */
            for (size_t i = 0; i < n; ++i) {
                traced += (size_t)hit(p, i);
                bad += (size_t)(f->count[i] != (hit(p, i) ? FRESH : 1u));
            }
            CHECK(bad == 0 && traced > n / 2,
                  "first frame: %zu of %zu pixels hit, %zu with another count", traced, n, bad);
        } else {
            history_lengths(&keep, cams[k - 1], p, cams[k], len);
            bad = wrong_counts(f, p, len, &traced);
            CHECK(bad == 0, "frame %d: %zu pixels hold another count than the rules'", k, bad);
        }
        if (k > 0) {
            /* Every pixel not traced again holds the frame's own sample, bit for bit. */
            size_t differ = 0;
            for (size_t i = 0; i < n; ++i) {
                if (f->count[i] == 1u) {
                    differ += (size_t)(memcmp(&f->sum[3 * i], &p->sum[3 * i], 3 * sizeof(float)) ||
                                       f->depth[i] != p->depth[i] || f->prim[i] != p->prim[i]);
                }
            }
            CHECK(differ == 0, "frame %d: %zu pixels not traced again differ", k, differ);
        }
        if (k == 3) {
            CHECK(traced > 0 && 4 * traced < n, "a move: %zu of %zu pixels traced again", traced,
                  n);
        }
        /* The film of the instance with the extra samples, whose passes are the history
         * the next frame reprojects onto. */
        memcpy(keep.sum, f->sum, 3 * n * sizeof *f->sum);
        memcpy(keep.count, f->count, n * sizeof *f->count);
        memcpy(keep.albedo, f->albedo, 3 * n * sizeof *f->albedo);
        memcpy(keep.normal, f->normal, 3 * n * sizeof *f->normal);
        memcpy(keep.depth, f->depth, n * sizeof *f->depth);
        memcpy(keep.prim, f->prim, n * sizeof *f->prim);
    }
    free(len);
    tr_film_free(&keep);
    tr_realtime_destroy(plain);
    tr_realtime_destroy(fresh);
    tr_realtime_destroy(fresh1);
    tr_device_destroy(d0);
    tr_device_destroy(d1);
    tr_device_destroy(d2);
    tr_scene_destroy(s);
    return check_finish("test_fresh");
}
