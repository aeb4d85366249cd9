/* restir.c - the ReSTIR DI stage of the real-time loop (restir_stage.h): per pixel, the
 * camera ray's first surface, a reservoir of light samples by RIS, merged with the
 * previous frame's reservoir at the reprojected pixel and with neighbours' on similar
 * surfaces, shaded with one shadow ray (src/kernel/restir.h has the papers).
 *
 * Two passes over the pixels, each writing only its own pixel's entries: (1) the surface,
 * the initial reservoir and the temporal merge, into `cur`; (2) the spatial merge of
 * `cur`'s neighbours, the shading and the film's addition, into `out`, which the next
 * frame reuses. No pixel reads what another writes in the same pass, and each pixel's
 * random numbers are keyed by (seed, pixel, frame), so the result is the same for any
 * thread count. */
#include "realtime/restir_stage.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "device/opencl.h"
#include "kernel/restir.h"
#include "kernel/restir_pass.h"
#include "kernel/restir_gi.h"
#include "scene/scene_internal.h"
#include "trac0r/render.h"

struct tr_restir_stage {
    uint32_t w, h;
    tr_restir_surface *surf, *prev_surf;
    tr_reservoir *cur, *out, *prev;
    tr_gi_reservoir *gcur, *gout, *gprev; /* ReSTIR GI's, as cur, out, prev */
    tr_camera prev_cam;
    int have_prev;
};

tr_restir_params tr_restir_params_default(void) {
    tr_restir_params p;
    p.candidates = 8;
    p.spatial = 3;
    p.radius = 16.0f;
    p.temporal_cap = 20.0f;
    p.unbiased = 0;
    p.visibility_reuse = 0;
    p.temporal = 1;
    p.tree = 0;
    p.gi = 0;
    p.gi_temporal = 1;
    p.gi_unbiased = 0;
    p.gi_spatial = 3;
    p.gi_radius = 16.0f;
    p.gi_temporal_cap = 20.0f;
    p.max_depth = 8;
    p.rr_start = 2;
    p.clamp_indirect = 0.0f;
    p.regularize = 0;
    return p;
}

tr_restir_stage *tr_restir_stage_create(tr_error *err) {
    tr_restir_stage *st = calloc(1, sizeof *st);
    if (!st) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for the ReSTIR stage");
    }
    return st;
}

static void free_buffers(tr_restir_stage *st) {
    free(st->surf);
    free(st->prev_surf);
    free(st->cur);
    free(st->out);
    free(st->prev);
    free(st->gcur);
    free(st->gout);
    free(st->gprev);
    st->gcur = st->gout = st->gprev = NULL;
    st->surf = st->prev_surf = NULL;
    st->cur = st->out = st->prev = NULL;
    st->w = st->h = 0;
    st->have_prev = 0;
}

void tr_restir_stage_destroy(tr_restir_stage *st) {
    if (st) {
        free_buffers(st);
        free(st);
    }
}

void tr_restir_stage_reset(tr_restir_stage *st) {
    if (st) {
        st->have_prev = 0;
    }
}

/* The buffers for a w x h frame; ReSTIR GI's only where it runs (gi). */
static int size_buffers(tr_restir_stage *st, uint32_t w, uint32_t h, int gi, tr_error *err) {
    if (st->w == w && st->h == h && st->surf && (!gi || st->gcur)) {
        return TR_OK;
    }
    free_buffers(st);
    const size_t n = (size_t)w * h;
    st->surf = malloc(n * sizeof *st->surf);
    st->prev_surf = malloc(n * sizeof *st->prev_surf);
    st->cur = malloc(n * sizeof *st->cur);
    st->out = malloc(n * sizeof *st->out);
    st->prev = malloc(n * sizeof *st->prev);
    if (gi) {
        st->gcur = malloc(n * sizeof *st->gcur);
        st->gout = malloc(n * sizeof *st->gout);
        st->gprev = malloc(n * sizeof *st->gprev);
    }
    if (!st->surf || !st->prev_surf || !st->cur || !st->out || !st->prev ||
        (gi && (!st->gcur || !st->gout || !st->gprev))) {
        free_buffers(st);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for the ReSTIR stage");
    }
    st->w = w;
    st->h = h;
    return TR_OK;
}

/* The passes' settings for a frame of camera cam (restir_pass.h). */
static void restir_frame(const tr_restir_stage *st, const tr_camera *cam, const tr_restir_params *p,
                         uint64_t seed, uint32_t sample, uint32_t sampler, uint32_t spp,
                         uint64_t frame, uint32_t passes, tr_restir_frame *fr) {
    memset(fr, 0, sizeof *fr);
    fr->cam = *cam;
    fr->prev_cam = st->prev_cam;
    fr->seed_lo = (uint32_t)seed;
    fr->seed_hi = (uint32_t)(seed >> 32);
    fr->frame_lo = (uint32_t)frame;
    fr->frame_hi = (uint32_t)(frame >> 32);
    fr->sample = sample;
    fr->sampler = sampler;
    fr->spp = spp;
    fr->candidates = p->candidates;
    fr->spatial = p->spatial;
    fr->radius = p->radius;
    fr->temporal_cap = p->temporal_cap;
    fr->unbiased = p->unbiased != 0;
    fr->visibility_reuse = p->visibility_reuse != 0;
    fr->temporal = p->temporal && st->have_prev;
    fr->direct = (passes & TR_PASS_DIRECT) != 0u;
    fr->tree = p->tree != 0;
    fr->gi = p->gi != 0;
    fr->gi_temporal = p->gi_temporal && st->have_prev;
    fr->gi_unbiased = p->gi_unbiased != 0;
    fr->gi_spatial = p->gi_spatial;
    fr->gi_radius = p->gi_radius;
    fr->gi_temporal_cap = p->gi_temporal_cap;
    fr->max_depth = p->max_depth;
    fr->rr_start = p->rr_start;
    fr->clamp_indirect = p->clamp_indirect;
    fr->flags = p->regularize ? TR_FRAME_REGULARIZE : 0u;
}

/* ReSTIR GI (src/kernel/restir_gi.h) on the surfaces st->surf of this frame: (1) every
 * pixel's initial sample and the temporal merge with the previous frame's reservoir at the
 * reprojected pixel, into gcur; (2) the spatial merge of gcur's neighbours (each one's
 * sample tested for visibility), the shading and the film's addition, into gout. As in
 * the direct light's passes, no pixel reads what another writes in the same pass. */
static void gi_passes(tr_restir_stage *st, const tr_scene_view *s, const tr_restir_frame *fr,
                      int threads, tr_film *film) {
    const uint32_t w = st->w, h = st->h;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int y = 0; y < (int)h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            tr_restir_gi_pass_temporal(s, fr, x, (uint32_t)y, st->surf, st->gcur, st->prev_surf,
                                       st->gprev);
        }
    }
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int y = 0; y < (int)h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            tr_restir_gi_pass_spatial(s, fr, x, (uint32_t)y, st->surf, st->gcur, st->gout,
                                      film->sum);
        }
    }
}

int tr_restir_stage_run(tr_restir_stage *st, const tr_scene *scene, const tr_camera *cam,
                        const tr_restir_params *p, uint64_t seed, uint32_t sample, uint32_t sampler,
                        uint32_t spp, uint64_t frame, int threads, tr_film *film, tr_error *err) {
    const uint32_t w = cam->screen_width, h = cam->screen_height;
    if (film->width != w || film->height != h) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "ReSTIR: a %ux%u camera for a %ux%u film", w, h, film->width,
                            film->height);
    }
    if (size_buffers(st, w, h, p->gi, err) != TR_OK) {
        return TR_ERR;
    }
    threads = threads > 0 ? threads : tr_default_threads();
    tr_scene_view view = tr_scene_view_of(scene);
    const tr_scene_view full = view; /* ReSTIR GI's paths sample the lights as pt does */
    if (!p->tree) {
        view.light_node_count = 0u; /* tr_light_sample_n then draws from the power CDF */
    }
    const tr_scene_view *s = &view;
    tr_restir_frame fr;
    restir_frame(st, cam, p, seed, sample, sampler, spp, frame, film->passes, &fr);

    /* Pass 1: surfaces, initial reservoirs, temporal merge. */
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int y = 0; y < (int)h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            tr_restir_pass_temporal(s, &fr, x, (uint32_t)y, st->surf, st->cur, st->prev_surf,
                                    st->prev);
        }
    }

    /* Pass 2: spatial merge, shading, the film. */
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int y = 0; y < (int)h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            tr_restir_pass_spatial(s, &fr, x, (uint32_t)y, st->surf, st->cur, st->out, film->sum,
                                   film->direct);
        }
    }

    if (p->gi) {
        gi_passes(st, &full, &fr, threads, film);
    }

    /* The next frame reuses this one's reservoirs and surfaces. */
    tr_gi_reservoir *g = st->gprev;
    st->gprev = st->gout;
    st->gout = g;
    tr_reservoir *t = st->prev;
    st->prev = st->out;
    st->out = t;
    tr_restir_surface *u = st->prev_surf;
    st->prev_surf = st->surf;
    st->surf = u;
    st->prev_cam = *cam;
    st->have_prev = 1;
    return TR_OK;
}

int tr_restir_stage_prepare_device(tr_device *dev, tr_error *err) {
    tr_cl_context *cl = tr_device_cl_context(dev);
    if (!cl) {
        return tr_error_set(err, TR_STATUS_UNSUPPORTED, "ReSTIR on a device: not an OpenCL device");
    }
    return tr_cl_prepare_restir(cl, err);
}

int tr_restir_stage_run_device(tr_restir_stage *st, tr_device *dev, const tr_camera *cam,
                               const tr_restir_params *p, uint64_t seed, uint32_t sample,
                               uint32_t sampler, uint32_t spp, uint64_t frame, uint32_t passes,
                               tr_error *err) {
    tr_cl_context *cl = tr_device_cl_context(dev);
    if (!cl) {
        return tr_error_set(err, TR_STATUS_UNSUPPORTED, "ReSTIR on a device: not an OpenCL device");
    }
    const uint32_t w = cam->screen_width, h = cam->screen_height;
    if (st->w != w || st->h != h || st->surf) {
        /* The device's buffers are made anew for another size: nothing to reuse. */
        free_buffers(st);
        st->w = w;
        st->h = h;
    }
    tr_restir_frame fr;
    restir_frame(st, cam, p, seed, sample, sampler, spp, frame, passes, &fr);
    if (tr_cl_restir_frame(cl, &fr, err) != TR_OK) {
        st->have_prev = 0;
        return TR_ERR;
    }
    st->prev_cam = *cam;
    st->have_prev = 1;
    return TR_OK;
}
