/* test_recon_motion.c - per-primitive motion in the temporal stage (tr_recon_frame_moving,
 * tr_post_reproject_moving): a sphere moving sideways in front of a wall, the camera
 * still (tests/motion_scene.h).
 *
 * 1. With the sphere's motion given, most of the sphere's pixels keep their history
 *    frame after frame (their length grows as on a static surface); without it, they
 *    are rejected (another triangle of the sphere, or a point off the tangent plane,
 *    lies where the surface was) and start over. This is what `view --animate` gains.
 * 2. The wall, which does not move, keeps its history either way; and a motion table
 *    of zeros gives tr_recon_frame's numbers bit for bit. With the default cap of a
 *    moving surface's history (max_len_moving, 4 frames) the sphere keeps exactly that
 *    much and the wall all of its own.
 * 3. The scene's record of tr_scene_move_shape (tr_scene_take_motion, what the viewer
 *    passes) is the sphere's step each frame, and nothing before the first move.
 * 4. No ghost after a moving object: the sphere moves for a while and stops; 8 frames
 *    later every method's error over the pixels it ever covered (where a ghost or a
 *    smeared trail would lie) is no more than that of a history started fresh on the
 *    still scene 8 frames before, the same samples in the same frames. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "motion_scene.h"

#define FRAMES 6

/* The fraction of pixels whose id lies in [lo, hi) with a history of at least min_len
 * frames, and how many such pixels there are. */
static double kept(const tr_recon *r, const tr_gbuffer *g, uint32_t lo, uint32_t hi, float min_len,
                   int *pixels) {
    int n = 0, k = 0;
    for (size_t i = 0; i < (size_t)MOTION_W * MOTION_H; ++i) {
        if (g->prim[i] >= lo && g->prim[i] < hi) {
            ++n;
            k += r->hist_len[r->cur][i] >= min_len;
        }
    }
    *pixels = n;
    return n ? (double)k / n : 0.0;
}

/* Frame `first` .. first + spp - 1 of the scene at 48x36 with every pass, into g (made
 * here). */
static void render_spp(const tr_scene *s, const tr_camera *cam, uint32_t first, uint32_t spp,
                       tr_gbuffer *g) {
    tr_error err;
    tr_film f;
    CHECK(tr_film_init_passes(&f, MOTION_W, MOTION_H, TR_PASS_ALL, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.passes = TR_PASS_ALL;
    cfg.threads = 2;
    for (uint32_t k = 0; k < spp; ++k) {
        CHECK(tr_render_frame(s, cam, &cfg, &f, first + k, NULL, &err) == TR_OK, "%s", err.msg);
    }
    CHECK(tr_gbuffer_init(g, MOTION_W, MOTION_H, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_gbuffer_from_film(g, &f, &err) == TR_OK, "%s", err.msg);
    tr_film_free(&f);
}

/* Mean squared error of img against ref (both clamped to [0, 1], as displayed) over the
 * pixels with mask[i] set. */
static double mse_mask(const float *img, const float *ref, const unsigned char *mask) {
    double sum = 0.0;
    size_t n = 0;
    for (size_t i = 0; i < (size_t)MOTION_W * MOTION_H; ++i) {
        if (!mask[i]) {
            continue;
        }
        for (int k = 0; k < 3; ++k) {
            const double d =
                fmin(fmax(img[3 * i + k], 0.0), 1.0) - fmin(fmax(ref[3 * i + k], 0.0), 1.0);
            sum += d * d;
        }
        n += 3;
    }
    return n ? sum / (double)n : 0.0;
}

enum { MOVES = 8, SETTLE = 8 };

/* Test 4: for each method, the sphere moves MOVES steps (the reconstruction told of each)
 * and then rests for SETTLE frames; a second, fresh history sees only those SETTLE frames
 * of the sphere at rest. Over the pixels the sphere covered at any time, the first may
 * not be worse than the second (a few per cent of slack): whatever the motion left in
 * the history is gone within 8 frames. Measured: 0.99-1.05 times the fresh error (the
 * bilateral filter's 1.05: the sphere's own pixels keep 4 frames of history while it
 * moves, max_len_moving, and the sharpest filter shows their lag most); with the
 * consistency test switched off (every history kept, a scratch build) 1.11-1.77 times. */
static void test_no_ghost(void) {
    tr_error err;
    tr_camera cam;
    uint32_t first, count;
    const uint32_t settle_seed = 1000;
    for (int m = TR_RECON_ACCUMULATE; m < TR_RECON_COUNT; ++m) {
        const tr_recon_params p = tr_recon_params_default();
        tr_scene *s = motion_scene(&cam, &first, &count);
        tr_vec3 *table = motion_table(first, count);
        const uint32_t ids = first + count + 1;
        unsigned char *mask = calloc((size_t)MOTION_W * MOTION_H, 1);
        const size_t n3 = 3 * (size_t)MOTION_W * MOTION_H;
        float *moved_out = malloc(n3 * sizeof *moved_out),
              *fresh_out = malloc(n3 * sizeof *fresh_out);
        CHECK(mask && moved_out && fresh_out, "out of memory");
        tr_recon r;
        CHECK(tr_recon_init(&r, MOTION_W, MOTION_H, &err) == TR_OK, "%s", err.msg);
        tr_gbuffer g;
        for (int k = 0; k <= MOVES; ++k) {
            motion_frame(s, &cam, k, &g);
            CHECK(tr_recon_frame_moving(&r, &g, &cam, k ? table : NULL, ids, m, &p, 2, moved_out,
                                        &err) == TR_OK,
                  "%s", err.msg);
            for (size_t i = 0; i < (size_t)MOTION_W * MOTION_H; ++i) {
                mask[i] |= g.prim[i] > first && g.prim[i] <= first + count;
            }
            tr_gbuffer_free(&g);
        }
        /* The sphere at rest where it stopped: the moved history and a fresh one see the
         * same frames. */
        tr_recon fresh;
        CHECK(tr_recon_init(&fresh, MOTION_W, MOTION_H, &err) == TR_OK, "%s", err.msg);
        for (uint32_t k = 0; k < SETTLE; ++k) {
            render_spp(s, &cam, settle_seed + k, 1, &g);
            CHECK(tr_recon_frame_moving(&r, &g, &cam, NULL, 0, m, &p, 2, moved_out, &err) ==
                          TR_OK &&
                      tr_recon_frame(&fresh, &g, &cam, m, &p, 2, fresh_out, &err) == TR_OK,
                  "%s", err.msg);
            for (size_t i = 0; i < (size_t)MOTION_W * MOTION_H; ++i) {
                mask[i] |= g.prim[i] > first && g.prim[i] <= first + count;
            }
            tr_gbuffer_free(&g);
        }
        tr_gbuffer ref;
        render_spp(s, &cam, 1u << 20, 256, &ref);
        const double e_moved = mse_mask(moved_out, ref.color, mask);
        const double e_fresh = mse_mask(fresh_out, ref.color, mask);
        int n = 0;
        for (size_t i = 0; i < (size_t)MOTION_W * MOTION_H; ++i) {
            n += mask[i];
        }
        printf("%s: %d px the sphere covered, MSE %.3g %d frames after it stopped, %.3g fresh\n",
               tr_recon_name(m), n, e_moved, SETTLE, e_fresh);
        CHECK(n > 200, "the sphere covered only %d pixels", n);
        CHECK(e_moved <= 1.10 * e_fresh,
              "%s: %d frames after the sphere stopped, MSE %g vs %g fresh", tr_recon_name(m),
              SETTLE, e_moved, e_fresh);
        tr_gbuffer_free(&ref);
        tr_recon_free(&fresh);
        tr_recon_free(&r);
        free(mask);
        free(moved_out);
        free(fresh_out);
        free(table);
        tr_scene_destroy(s);
    }
}

int main(void) {
    tr_camera cam;
    uint32_t first, count;
    tr_scene *s = motion_scene(&cam, &first, &count);
    tr_vec3 *table = motion_table(first, count);
    tr_vec3 *zeros = calloc(first + count + 1, sizeof *zeros);
    CHECK(zeros != NULL, "out of memory");
    tr_error err;
    tr_recon moving, still, zero, capped;
    CHECK(tr_recon_init(&moving, MOTION_W, MOTION_H, &err) == TR_OK &&
              tr_recon_init(&still, MOTION_W, MOTION_H, &err) == TR_OK &&
              tr_recon_init(&zero, MOTION_W, MOTION_H, &err) == TR_OK &&
              tr_recon_init(&capped, MOTION_W, MOTION_H, &err) == TR_OK,
          "%s", err.msg);
    /* Following the sphere: a moving surface may keep as long a history as any. */
    const tr_recon_params pd = tr_recon_params_default();
    tr_recon_params p = pd;
    p.max_len_moving = p.max_len;
    const size_t n3 = 3 * (size_t)MOTION_W * MOTION_H;
    float *a = malloc(n3 * sizeof *a), *b = malloc(n3 * sizeof *b), *c = malloc(n3 * sizeof *c);
    CHECK(a && b && c, "out of memory");
    const uint32_t ids = first + count + 1;
    tr_vec3 *taken = calloc(ids, sizeof *taken);
    CHECK(taken != NULL, "out of memory");
    /* The scene's own record (tr_scene_take_motion) against the table built by hand: a
     * table of another size is refused, and nothing has moved yet. */
    int moved = 1;
    CHECK(tr_scene_take_motion(s, taken, ids + 1, &moved, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "a motion table of the wrong size was accepted");
    CHECK(tr_scene_take_motion(s, taken, ids, &moved, &err) == TR_OK && !moved, "moved %d: %s",
          moved, err.msg);
    tr_gbuffer g;
    for (int k = 0; k < FRAMES; ++k) {
        motion_frame(s, &cam, k, &g);
        CHECK(tr_scene_take_motion(s, taken, ids, &moved, &err) == TR_OK, "%s", err.msg);
        CHECK(moved == (k > 0), "frame %d: moved %d", k, moved);
        CHECK(memcmp(taken, k ? table : zeros, ids * sizeof *taken) == 0,
              "frame %d: the scene's motion record is not the sphere's step", k);
        /* The first frame has no previous one: no motion either. */
        CHECK(tr_recon_frame_moving(&moving, &g, &cam, k ? taken : NULL, ids, TR_RECON_ACCUMULATE,
                                    &p, 2, a, &err) == TR_OK,
              "%s", err.msg);
        CHECK(tr_recon_frame(&still, &g, &cam, TR_RECON_ACCUMULATE, &p, 2, b, &err) == TR_OK, "%s",
              err.msg);
        CHECK(tr_recon_frame_moving(&capped, &g, &cam, k ? taken : NULL, ids, TR_RECON_ACCUMULATE,
                                    &pd, 2, c, &err) == TR_OK,
              "%s", err.msg);
        CHECK(tr_recon_frame_moving(&zero, &g, &cam, zeros, ids, TR_RECON_ACCUMULATE, &p, 2, c,
                                    &err) == TR_OK,
              "%s", err.msg);
        CHECK(memcmp(b, c, n3 * sizeof *b) == 0, "frame %d: zero motion changed the image", k);
        if (k + 1 < FRAMES) {
            tr_gbuffer_free(&g);
        }
    }
    /* The sphere's ids are first + 1 .. first + count; the wall's box is shape 0. */
    int np, nw;
    const float full = (float)FRAMES - 1.0f; /* more than half the frames kept at least */
    const double with = kept(&moving, &g, first + 1, first + count + 1, full, &np);
    const double without = kept(&still, &g, first + 1, first + count + 1, full, &np);
    CHECK(np > 100, "the sphere covers only %d pixels", np);
    printf("sphere (%d px): history of %g+ frames kept by %.2f with motion, %.2f without\n", np,
           (double)full, with, without);
    CHECK(with > 0.6, "with motion only %.2f of the sphere kept its history", with);
    CHECK(without < 0.2, "without motion %.2f of the sphere kept its history", without);
    const uint32_t wall = tr_scene_shape_triangle_count(s, 0);
    const double wall_m = kept(&moving, &g, 1, wall + 1, full, &nw);
    const double wall_s = kept(&still, &g, 1, wall + 1, full, &nw);
    printf("wall (%d px): %.2f with motion, %.2f without\n", nw, wall_m, wall_s);
    CHECK(wall_m > 0.9 && wall_s > 0.9, "the wall lost its history: %.2f, %.2f", wall_m, wall_s);
    /* The default cap: the sphere's pixels that follow it keep max_len_moving frames and
     * no more; the wall keeps its full history. */
    const double cap_at = kept(&capped, &g, first + 1, first + count + 1, pd.max_len_moving, &np);
    const double cap_over =
        kept(&capped, &g, first + 1, first + count + 1, pd.max_len_moving + 0.5f, &np);
    const double cap_wall = kept(&capped, &g, 1, wall + 1, full, &nw);
    printf("capped at %g frames: sphere %.2f at the cap, %.2f over it; wall %.2f\n",
           (double)pd.max_len_moving, cap_at, cap_over, cap_wall);
    CHECK(cap_at > 0.6 && cap_over == 0.0, "the cap: %.2f of the sphere at it, %.2f over it",
          cap_at, cap_over);
    CHECK(cap_wall == wall_m, "the cap changed the wall's history: %.2f vs %.2f", cap_wall, wall_m);
    tr_gbuffer_free(&g);
    free(a);
    free(b);
    free(c);
    free(table);
    free(taken);
    free(zeros);
    tr_recon_free(&moving);
    tr_recon_free(&still);
    tr_recon_free(&zero);
    tr_recon_free(&capped);
    tr_scene_destroy(s);
    test_no_ghost();
    return check_finish("test_recon_motion");
}
