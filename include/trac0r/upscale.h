/* upscale.h - temporal upscaling: a full-resolution image reconstructed from frames that
 * each trace a fraction of its pixels, and from its own history (TAAU, as in AMD's FSR 2).
 *
 *     tr_upscale up;
 *     tr_upscale_init(&up, W, H, &err);                   // the output's size
 *     for (each frame) {
 *         // render wl x hl pixels through the same view (tr_camera_resize), then:
 *         tr_upscale_positions(&cfg, wl, hl, W, H, first_sample, spp, pos, &err);
 *         tr_upscale_input in = {wl, hl, colour, pos, depth, prim};
 *         tr_upscale_frame(&up, &in, &cam, NULL, 0, 0.0f, 0, out, &err);  // out: W x H
 *     }
 *     tr_upscale_free(&up);
 *
 * The per-pixel operator is src/post/upscale.h (single source, as the reconstruction's);
 * tr_realtime runs it when a frame asks for `upscale` (realtime.h, docs/realtime.md). */
#ifndef TRAC0R_UPSCALE_H
#define TRAC0R_UPSCALE_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/error.h"
#include "trac0r/render.h"
#include "trac0r/types.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The history between frames; the caller owns it. */
typedef struct tr_upscale {
    uint32_t width, height; /* the output's size */
    int have_history;
    int cur;            /* which of the two buffers is the newest */
    tr_camera prev_cam; /* the output's camera of the newest history */
    float *color[2];    /* 3 floats per pixel */
    float *count[2];    /* samples behind each pixel (capped by max_len) */
    float *depth[2];    /* the distance each pixel's point was taken at */
    double ms;          /* the last tr_upscale_frame's wall time */
    float *box;         /* scratch: the traced frame's neighbourhood ranges */
    size_t box_len;
} tr_upscale;

/* One traced frame: width x height pixels, planar buffers, row-major, top row first. */
typedef struct tr_upscale_input {
    uint32_t width, height;
    const float *color;   /* 3 floats per pixel: the value to upscale */
    const float *pos;     /* 2 floats per pixel: where its sample lies, in output pixels */
    const float *depth;   /* 1 per pixel: distance along the camera ray, 0: nothing hit */
    const uint32_t *prim; /* 1 per pixel: triangle index + 1, 0: nothing hit */
} tr_upscale_input;

/* The history cap of tr_upscale_frame's max_len 0. */
#define TR_UPSCALE_MAX_LEN 32.0f

int tr_upscale_init(tr_upscale *u, uint32_t width, uint32_t height, tr_error *err);
void tr_upscale_free(tr_upscale *u);
/* Forgets the history (a cut, a new size of the traced frame). */
void tr_upscale_clear(tr_upscale *u);

/* The output of camera `cam` (the state's size) from frame `in` and the history, into out
 * (3 floats per pixel): src/post/upscale.h. motion[id] is how far primitive id moved
 * since the previous frame (as tr_recon_frame_moving; NULL: nothing moved). max_len caps
 * the samples a pixel's history counts (0: TR_UPSCALE_MAX_LEN). Up to `threads` OpenMP
 * threads (0: the default); the result does not depend on their number. Fails on a
 * camera of another size than the state's, an empty frame or a NULL buffer. */
int tr_upscale_frame(tr_upscale *u, const tr_upscale_input *in, const tr_camera *cam,
                     const tr_vec3 *motion, uint32_t motion_count, float max_len, int threads,
                     float *out, tr_error *err);

/* Where the samples of a frame of width x height pixels rendered with cfg (its seed,
 * integrator and sampler) for samples [first, first + count) lie, in the pixels of an
 * out_width x out_height output of the same view: 2 floats per frame pixel into pos,
 * the mean position of its samples. The kernel's own jitter (the samplers are
 * stateless), so the positions are exact, on every device. */
int tr_upscale_positions(const tr_render_config *cfg, uint32_t width, uint32_t height,
                         uint32_t out_width, uint32_t out_height, uint32_t first, uint32_t count,
                         float *pos, tr_error *err);

struct tr_scene;
/* The first hit's emission at the output's resolution into out (3 floats per output
 * pixel of `cam`), from a traced frame's emission pass (width x height, 3 floats per
 * pixel, TR_PASS_EMISSION): an output pixel whose traced pixel has emitting and
 * non-emitting samples among its 3 x 3 neighbours traces an n x n grid of first-hit rays
 * into the committed scene and takes their mean (as tr_resolve_emission does for a frame
 * at its own resolution), and so does one where `prev` (the previous call's out, or
 * NULL) saw emission and its traced pixel sees none, of an emitter small enough for the
 * samples to miss (one that does not reach two traced pixels away in both axes; a larger
 * one that none of them saw has moved away); any other takes its traced pixel's emission.
 * The upscaling then carries only reflected light, and an emitter's edge stays sharp at
 * the output's resolution. n in 1..16; *resolved (may be NULL) gets the pixels traced. */
int tr_upscale_emission(const struct tr_scene *scene, const tr_camera *cam, int n, int threads,
                        uint32_t width, uint32_t height, const float *emission, const float *prev,
                        float *out, uint32_t *resolved, tr_error *err);

/* Two albedos differ for tr_upscale_albedo where a channel's difference exceeds
 * TR_UPSCALE_ALBEDO_ABS + TR_UPSCALE_ALBEDO_REL times the larger of the two. */
#define TR_UPSCALE_ALBEDO_ABS 0.004f
#define TR_UPSCALE_ALBEDO_REL 0.04f

/* The passes' albedo at the output's resolution into out (3 floats per output pixel of
 * `cam`), as tr_albedo_image (post.h) traces it, but tracing only where the traced frame's
 * albedo (width x height, 3 floats per pixel, the frame's albedo pass) does not already
 * give it: an output pixel whose traced pixel's 3 x 3 neighbours' albedos all agree with
 * it (TR_UPSCALE_ALBEDO_ABS, _REL) takes the bilinear interpolation of the traced albedo at
 * its centre, unless `prev` (the previous call's out, or NULL; it may be out itself)
 * differs from that there (a detail narrower than the traced pixels, which their samples
 * can miss); any other traces one first-hit ray through its centre. *traced (may be NULL)
 * gets the pixels traced. Up to `threads` threads (0: the default); the result does not
 * depend on their number. */
int tr_upscale_albedo(const struct tr_scene *scene, const tr_camera *cam, int threads,
                      uint32_t width, uint32_t height, const float *albedo, const float *prev,
                      float *out, uint32_t *traced, tr_error *err);

#ifdef __cplusplus
}
#endif

#endif
