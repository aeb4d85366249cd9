/* restir_pass.h - ReSTIR DI's two passes over a frame's pixels (restir.h has the method
 * and the papers), one pixel per call, so that the CPU's loops (src/realtime/restir.c)
 * and the OpenCL kernels (entry.cl: tr_cl_restir_temporal, tr_cl_restir_spatial) run the
 * same text:
 *
 *   temporal  the pixel's first surface, its initial reservoir by RIS and the merge with
 *             the previous frame's reservoir at the reprojected pixel, into `cur`;
 *   spatial   the merge of `cur`'s reservoirs of neighbours on similar surfaces, the
 *             shading with one shadow ray, added to the film's radiance sums (and its
 *             direct pass), into `out`, which the next frame reuses as `prev`.
 *
 * Each pass writes only its own pixel's entries and reads what the previous pass (or
 * frame) wrote, and each pixel's random numbers are keyed by (seed, pixel, frame, pass):
 * the result is the same whatever the order of the pixels or the number of threads.
 *
 * Valid C99 and OpenCL C (kernel style). */
#ifndef TR_KERNEL_RESTIR_PASS_H
#define TR_KERNEL_RESTIR_PASS_H

#include "camera.h"
#include "compat.h"
#include "restir.h"
#include "restir_gi.h"
#include "rng.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* One frame's settings of the passes: fixed-width 32-bit fields only, so that the host
 * hands it to a device as it is (the layout is the same in C and OpenCL C). */
typedef struct tr_restir_frame {
    tr_camera cam;               /* the frame's camera (pt's, the film's size) */
    tr_camera prev_cam;          /* the previous frame's, for the temporal reuse */
    uint32_t seed_lo, seed_hi;   /* pt's seed (its camera rays) and the stage's */
    uint32_t frame_lo, frame_hi; /* keys the stage's random numbers */
    uint32_t sample, sampler;    /* pt's sample number and sampler of the frame */
    uint32_t spp;                /* the film's samples per pixel of the frame */
    int32_t candidates;          /* RIS candidates per pixel */
    int32_t spatial;             /* neighbours per pixel */
    float radius;                /* of the neighbourhood, in pixels */
    float temporal_cap;          /* the previous frame's confidence at most this times the new */
    int32_t unbiased;            /* restir.h: the MIS weights and no visibility reuse */
    int32_t visibility_reuse;    /* biased mode: an occluded new sample passed on with W 0 */
    int32_t temporal;            /* 1: merge with the previous frame's reservoirs */
    int32_t direct;              /* 1: also add the light to the film's direct pass */
    int32_t tree; /* 1: candidates from the light tree (else the power CDF: the caller's view
                     then has light_node_count 0, as the device's kernels make it) */
    /* ReSTIR GI (restir_gi.h), where gi is 1: its passes after the direct light's, with
     * their own merges' settings (as the direct light's above) and the paths' depth,
     * roulette start, indirect clamp and frame flags (TR_FRAME_REGULARIZE). */
    int32_t gi, gi_temporal, gi_unbiased, gi_spatial;
    float gi_radius, gi_temporal_cap;
    int32_t max_depth, rr_start;
    float clamp_indirect;
    uint32_t flags;
} tr_restir_frame;
TR_STATIC_ASSERT(sizeof(tr_restir_frame) == 2 * sizeof(tr_camera) + 26 * 4,
                 "tr_restir_frame is unpadded 32-bit words");

TR_FN uint64_t tr_restir_frame_seed(const tr_restir_frame *fr) {
    return ((uint64_t)fr->seed_hi << 32) | (uint64_t)fr->seed_lo;
}

TR_FN uint64_t tr_restir_frame_number(const tr_restir_frame *fr) {
    return ((uint64_t)fr->frame_hi << 32) | (uint64_t)fr->frame_lo;
}

/* The stage's random numbers for pixel i of frame `frame`, pass `pass`. */
TR_FN void tr_restir_pixel_rng(tr_rng *rng, uint64_t seed, uint32_t i, uint64_t frame,
                               uint64_t pass) {
    tr_rng_init(rng, seed ^ (uint64_t)0x72657374697264UL, (uint64_t)i, frame * 2u + pass);
}

/* Surface i of a buffer the passes wrote, as a value. A surface keeps the scene's
 * multiple-scattering table as a pointer (tr_bsdf_params.ms), which a device need not
 * keep valid from one kernel to the next: it is taken from the scene view again. */
TR_FN tr_restir_surface tr_restir_surface_at(const tr_scene_view *s,
                                             TR_CONST_GLOBAL tr_restir_surface *surf, uint32_t i) {
    tr_restir_surface q = surf[i];
    if (q.m.ms) {
        q.m.ms = s->ggx_ms_count > 0u ? s->ggx_ms : 0;
    }
    return q;
}

/* Whether surface b (a neighbour's, or the previous frame's) is similar enough to a for
 * their samples to be reused: the same material, normals within ~25 degrees and b's
 * point on a's tangent plane within 2 % of a's distance (the reconstruction's test,
 * tr_reproject_consistent, with the material in place of the primitive). */
TR_FN int tr_restir_similar(const tr_restir_surface *a, const tr_restir_surface *b) {
    if (!a->valid || !b->valid || a->material != b->material) {
        return 0;
    }
    if (v3_dot(a->n, b->n) <= 0.9f) {
        return 0;
    }
    return tr_fabsf(v3_dot(v3_sub(b->p, a->p), a->n)) <= 0.02f * a->dist;
}

/* Up to k neighbours of pixel (x, y) for a spatial merge: offsets drawn uniformly in a disc
 * of `radius` pixels (two numbers of rng per try, whether it is taken or not), kept where
 * they fall inside the w x h image, off the pixel itself and on a surface similar to its
 * own (surf: the frame's surfaces). Their indices go to out; returns how many. */
TR_FN int tr_restir_pick_neighbours(TR_CONST_GLOBAL tr_restir_surface *surf, uint32_t x, int y,
                                    uint32_t w, uint32_t h, float radius, int k, tr_rng *rng,
                                    uint32_t *out) {
    const tr_restir_surface q = surf[(uint32_t)y * w + x];
    int n = 0;
    for (int t = 0; t < k; ++t) {
        const float a = TR_TWO_PI * tr_rng_float(rng);
        const float rad = radius * tr_sqrtf(tr_rng_float(rng));
        const int nx = (int)x + (int)(rad * tr_cosf(a) + 0.5f);
        const int ny = y + (int)(rad * tr_sinf(a) + 0.5f);
        if (nx < 0 || ny < 0 || nx >= (int)w || ny >= (int)h || (nx == (int)x && ny == y)) {
            continue;
        }
        const uint32_t j = (uint32_t)ny * w + (uint32_t)nx;
        const tr_restir_surface b = surf[j];
        if (tr_restir_similar(&q, &b)) {
            out[n++] = j;
        }
    }
    return n;
}

/* The number of neighbours a spatial merge tries: fr->spatial within 0..MAX_MERGE-1. */
TR_FN int tr_restir_spatial_count(int spatial) {
    return spatial < 0 ? 0 : spatial > TR_RESTIR_MAX_MERGE - 1 ? TR_RESTIR_MAX_MERGE - 1 : spatial;
}

/* The first pass at pixel (x, y) of a fr->cam.screen_width x screen_height frame: its
 * surface into surf, its reservoir (the initial one merged with the previous frame's,
 * prev_surf and prev, where fr->temporal) into cur. s: the scene view the candidates come
 * from. */
TR_FN void tr_restir_pass_temporal(const tr_scene_view *s, const tr_restir_frame *fr, uint32_t x,
                                   uint32_t y, TR_GLOBAL tr_restir_surface *surf,
                                   TR_GLOBAL tr_reservoir *cur,
                                   TR_CONST_GLOBAL tr_restir_surface *prev_surf,
                                   TR_CONST_GLOBAL tr_reservoir *prev) {
    const uint32_t w = fr->cam.screen_width, h = fr->cam.screen_height;
    const uint32_t i = y * w + x;
    const uint64_t seed = tr_restir_frame_seed(fr);
    tr_rng rng;
    tr_restir_pixel_rng(&rng, seed, i, tr_restir_frame_number(fr), 0);
    tr_restir_surface q =
        tr_restir_primary(s, &fr->cam, seed, (uint64_t)i, x, y, fr->sample, fr->sampler);
    surf[i] = q;
    tr_restir_target_surface(&q);
    if (!q.valid) {
        cur[i] = tr_reservoir_empty();
        return;
    }
    tr_reservoir r = tr_restir_initial(s, &q, fr->candidates > 0 ? fr->candidates : 1, &rng);
    /* Visibility reuse (biased mode, when asked): an occluded sample is not passed on. Its
     * confidence still counts in every merge that takes the reservoir, so a neighbour's
     * merge loses the light this pixel's shadow hid from it; with the spatial output kept
     * as the next frame's history the loss compounds (-12 % over the window room at
     * rest), hence off by default. */
    if (fr->visibility_reuse && !fr->unbiased && r.W > 0.0f && !tr_restir_visible(s, &q, &r)) {
        r.W = 0.0f;
    }
    const float cap = fr->temporal_cap > 0.0f ? fr->temporal_cap : 20.0f;
    float px, py, dist;
    if (fr->temporal && tr_camera_project(&fr->prev_cam, q.p, &px, &py, &dist) && px >= 0.0f &&
        py >= 0.0f && px < (float)w && py < (float)h) {
        const uint32_t j = (uint32_t)py * w + (uint32_t)px;
        tr_restir_surface ss[2];
        ss[0] = q;
        ss[1] = tr_restir_surface_at(s, prev_surf, j);
        tr_restir_target_surface(&ss[1]);
        if (tr_restir_similar(&ss[0], &ss[1])) {
            tr_reservoir rr[2];
            rr[0] = r;
            rr[1] = prev[j];
            const float mcap = cap * r.M;
            if (rr[1].M > mcap) {
                rr[1].M = mcap;
            }
            r = tr_restir_merge(s, ss, rr, 2, fr->unbiased, cap + r.M, TR_RESTIR_KNOWN_OWN, &rng, 0,
                                0);
        }
    }
    cur[i] = r;
}

/* The second pass at pixel (x, y): the spatial merge of cur's reservoirs around it, into
 * out, and the light it shades with, times fr->spp, added to the radiance sums `sum` (3
 * floats a pixel) and, where fr->direct, to the direct pass `direct`. */
TR_FN void tr_restir_pass_spatial(const tr_scene_view *s, const tr_restir_frame *fr, uint32_t x,
                                  uint32_t y, TR_CONST_GLOBAL tr_restir_surface *surf,
                                  TR_CONST_GLOBAL tr_reservoir *cur, TR_GLOBAL tr_reservoir *out,
                                  TR_GLOBAL float *sum, TR_GLOBAL float *direct) {
    const uint32_t w = fr->cam.screen_width, h = fr->cam.screen_height;
    const uint32_t i = y * w + x;
    tr_restir_surface ss[TR_RESTIR_MAX_MERGE];
    ss[0] = tr_restir_surface_at(s, surf, i);
    if (!ss[0].valid) {
        out[i] = tr_reservoir_empty();
        return;
    }
    /* The merge sees the targets' surfaces; the shading the exact one (its tables back). */
    TR_CONST_GLOBAL float *const ms = ss[0].m.ms;
    tr_restir_target_surface(&ss[0]);
    tr_rng rng;
    tr_restir_pixel_rng(&rng, tr_restir_frame_seed(fr), i, tr_restir_frame_number(fr), 1);
    tr_reservoir rr[TR_RESTIR_MAX_MERGE];
    rr[0] = cur[i];
    uint32_t nb[TR_RESTIR_MAX_MERGE];
    const int m = tr_restir_pick_neighbours(surf, x, (int)y, w, h, fr->radius,
                                            tr_restir_spatial_count(fr->spatial), &rng, nb);
    int n = 1;
    for (int t = 0; t < m; ++t, ++n) {
        /* The biased merge evaluates targets at this pixel's surface only. */
        if (fr->unbiased) {
            ss[n] = tr_restir_surface_at(s, surf, nb[t]);
            tr_restir_target_surface(&ss[n]);
        }
        rr[n] = cur[nb[t]];
    }
    /* All of these reservoirs were made in this frame, each at its own pixel's surface: the
     * merge takes their targets there as they hold them. */
    tr_vec3 cs = v3s(0.0f);
    int cs_known = 0;
    const tr_reservoir r = n > 1 ? tr_restir_merge(s, ss, rr, n, fr->unbiased, 1e30f,
                                                   TR_RESTIR_KNOWN_ALL, &rng, &cs, &cs_known)
                                 : rr[0];
    out[i] = r;
    /* The merge's contribution was the target's: the exact one where the BSDF differs. */
    ss[0].m.ms = ms;
    const tr_vec3 c = v3_scale(tr_restir_shade(s, &ss[0], &r, cs, cs_known && !ms), (float)fr->spp);
    sum[3u * i] += c.x;
    sum[3u * i + 1u] += c.y;
    sum[3u * i + 2u] += c.z;
    if (fr->direct) {
        direct[3u * i] += c.x;
        direct[3u * i + 1u] += c.y;
        direct[3u * i + 2u] += c.z;
    }
}

/* ReSTIR GI's random numbers for pixel i of frame `frame`, pass `pass`. */
TR_FN void tr_restir_gi_rng(tr_rng *rng, uint64_t seed, uint32_t i, uint64_t frame, uint64_t pass) {
    tr_rng_init(rng, seed ^ (uint64_t)0x67692d72657374UL, (uint64_t)i, frame * 2u + pass);
}

/* ReSTIR GI's first pass at pixel (x, y), after the direct light's passes (surf: this
 * frame's surfaces): the pixel's initial path sample and the merge with the previous
 * frame's reservoir (prev_surf, gprev) at the reprojected pixel where fr->gi_temporal,
 * into gcur. s: the scene view as pt sees it (its light tree kept). */
TR_FN void tr_restir_gi_pass_temporal(const tr_scene_view *s, const tr_restir_frame *fr, uint32_t x,
                                      uint32_t y, TR_CONST_GLOBAL tr_restir_surface *surf,
                                      TR_GLOBAL tr_gi_reservoir *gcur,
                                      TR_CONST_GLOBAL tr_restir_surface *prev_surf,
                                      TR_CONST_GLOBAL tr_gi_reservoir *gprev) {
    const uint32_t w = fr->cam.screen_width, h = fr->cam.screen_height;
    const uint32_t i = y * w + x;
    const tr_restir_surface q = tr_restir_surface_at(s, surf, i);
    if (!q.valid) {
        gcur[i] = tr_gi_reservoir_empty();
        return;
    }
    const uint64_t seed = tr_restir_frame_seed(fr), frame = tr_restir_frame_number(fr);
    tr_rng rng;
    tr_restir_gi_rng(&rng, seed, i, frame, 0);
    const float ulobe = tr_rng_float(&rng), u1 = tr_rng_float(&rng);
    const float u2 = tr_rng_float(&rng);
    const tr_sampler smp =
        tr_sampler_make_kind(seed ^ (uint64_t)0x67692d70617468UL, (uint64_t)i, (uint32_t)frame, 1u);
    uint32_t rays = 0u;
    tr_gi_reservoir r = tr_gi_initial(s, &q, ulobe, u1, u2, &smp, fr->max_depth, fr->rr_start,
                                      fr->clamp_indirect, fr->flags, &rays);
    const float cap = fr->gi_temporal_cap > 0.0f ? fr->gi_temporal_cap : 20.0f;
    float px, py, dist;
    if (fr->gi_temporal && tr_camera_project(&fr->prev_cam, q.p, &px, &py, &dist) && px >= 0.0f &&
        py >= 0.0f && px < (float)w && py < (float)h) {
        const uint32_t j = (uint32_t)py * w + (uint32_t)px;
        tr_restir_surface ss[2];
        ss[0] = q;
        ss[1] = tr_restir_surface_at(s, prev_surf, j);
        if (tr_restir_similar(&ss[0], &ss[1])) {
            tr_gi_reservoir rr[2];
            const int vis[2] = {0, 0};
            rr[0] = r;
            rr[1] = gprev[j];
            if (rr[1].M > cap * r.M) {
                rr[1].M = cap * r.M;
            }
            r = tr_gi_merge(s, ss, rr, vis, 2, fr->gi_unbiased, cap + r.M, &rng);
        }
    }
    gcur[i] = r;
}

/* ReSTIR GI's second pass at pixel (x, y): the spatial merge of gcur's reservoirs around it
 * (each neighbour's sample tested for visibility), into gout, and its indirect light,
 * times fr->spp, added to the radiance sums. */
TR_FN void tr_restir_gi_pass_spatial(const tr_scene_view *s, const tr_restir_frame *fr, uint32_t x,
                                     uint32_t y, TR_CONST_GLOBAL tr_restir_surface *surf,
                                     TR_CONST_GLOBAL tr_gi_reservoir *gcur,
                                     TR_GLOBAL tr_gi_reservoir *gout, TR_GLOBAL float *sum) {
    const uint32_t w = fr->cam.screen_width, h = fr->cam.screen_height;
    const uint32_t i = y * w + x;
    tr_restir_surface ss[TR_RESTIR_MAX_MERGE];
    ss[0] = tr_restir_surface_at(s, surf, i);
    if (!ss[0].valid) {
        gout[i] = tr_gi_reservoir_empty();
        return;
    }
    tr_rng rng;
    tr_restir_gi_rng(&rng, tr_restir_frame_seed(fr), i, tr_restir_frame_number(fr), 1);
    tr_gi_reservoir rr[TR_RESTIR_MAX_MERGE];
    int vis[TR_RESTIR_MAX_MERGE];
    rr[0] = gcur[i];
    vis[0] = 0;
    uint32_t nb[TR_RESTIR_MAX_MERGE];
    const int m = tr_restir_pick_neighbours(surf, x, (int)y, w, h, fr->gi_radius,
                                            tr_restir_spatial_count(fr->gi_spatial), &rng, nb);
    int n = 1;
    for (int t = 0; t < m; ++t, ++n) {
        ss[n] = tr_restir_surface_at(s, surf, nb[t]);
        rr[n] = gcur[nb[t]];
        vis[n] = 1;
    }
    const tr_gi_reservoir r =
        n > 1 ? tr_gi_merge(s, ss, rr, vis, n, fr->gi_unbiased, 1e30f, &rng) : rr[0];
    gout[i] = r;
    const tr_vec3 c = v3_scale(tr_gi_shade(&ss[0], &r), (float)fr->spp);
    sum[3u * i] += c.x;
    sum[3u * i + 1u] += c.y;
    sum[3u * i + 2u] += c.z;
}

#endif
