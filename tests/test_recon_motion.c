/* test_recon_motion.c - per-primitive motion in the temporal stage (tr_recon_frame_moving,
 * tr_post_reproject_moving): a sphere moving sideways in front of a wall, the camera
 * still (tests/motion_scene.h).
 *
 * 1. With the sphere's motion given, most of the sphere's pixels keep their history
 *    frame after frame (their length grows as on a static surface); without it, they
 *    are rejected (another triangle of the sphere, or a point off the tangent plane,
 *    lies where the surface was) and start over. This is what `view --animate` gains.
 * 2. The wall, which does not move, keeps its history either way; and a motion table
 *    of zeros gives tr_recon_frame's numbers bit for bit.
 * 3. The scene's record of tr_scene_move_shape (tr_scene_take_motion, what the viewer
 *    passes) is the sphere's step each frame, and nothing before the first move. */
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

int main(void) {
    tr_camera cam;
    uint32_t first, count;
    tr_scene *s = motion_scene(&cam, &first, &count);
    tr_vec3 *table = motion_table(first, count);
    tr_vec3 *zeros = calloc(first + count + 1, sizeof *zeros);
    CHECK(zeros != NULL, "out of memory");
    tr_error err;
    tr_recon moving, still, zero;
    CHECK(tr_recon_init(&moving, MOTION_W, MOTION_H, &err) == TR_OK &&
              tr_recon_init(&still, MOTION_W, MOTION_H, &err) == TR_OK &&
              tr_recon_init(&zero, MOTION_W, MOTION_H, &err) == TR_OK,
          "%s", err.msg);
    const tr_recon_params p = tr_recon_params_default();
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
    tr_scene_destroy(s);
    return check_finish("test_recon_motion");
}
