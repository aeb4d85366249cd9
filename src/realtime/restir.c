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

#include "kernel/restir.h"
#include "kernel/restir_gi.h"
#include "post/filter.h"
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

/* Whether surface b (a neighbour's, or the previous frame's) is similar enough to a for
 * their samples to be reused: the same material, normals within ~25 degrees and b's
 * point on a's tangent plane within 2 % of a's distance (the reconstruction's test,
 * tr_post_consistent, with the material in place of the primitive). */
static int similar(const tr_restir_surface *a, const tr_restir_surface *b) {
    if (!a->valid || !b->valid || a->material != b->material) {
        return 0;
    }
    if (v3_dot(a->m.ns, b->m.ns) <= 0.9f) {
        return 0;
    }
    return tr_fabsf(v3_dot(v3_sub(b->p, a->p), a->m.ns)) <= 0.02f * a->dist;
}

/* The stage's random numbers for pixel i of frame `frame`, pass `pass`. */
/* Up to k neighbours of pixel (x, y) for a spatial merge: offsets drawn uniformly in a disc
 * of `radius` pixels (two numbers of rng per try, whether it is taken or not), kept where
 * they fall inside the w x h image, off the pixel itself and on a surface similar to its
 * own. Their indices go to out; returns how many. */
static int pick_neighbours(const tr_restir_stage *st, uint32_t x, int y, uint32_t w, uint32_t h,
                           float radius, int k, tr_rng *rng, size_t *out) {
    const tr_restir_surface *q = &st->surf[(size_t)y * w + x];
    int n = 0;
    for (int t = 0; t < k; ++t) {
        const float a = TR_TWO_PI * tr_rng_float(rng);
        const float rad = radius * tr_sqrtf(tr_rng_float(rng));
        const int nx = (int)x + (int)(rad * tr_cosf(a) + 0.5f);
        const int ny = y + (int)(rad * tr_sinf(a) + 0.5f);
        if (nx < 0 || ny < 0 || nx >= (int)w || ny >= (int)h || (nx == (int)x && ny == y)) {
            continue;
        }
        const size_t j = (size_t)ny * w + (size_t)nx;
        if (similar(q, &st->surf[j])) {
            out[n++] = j;
        }
    }
    return n;
}

static void pixel_rng(tr_rng *rng, uint64_t seed, size_t i, uint64_t frame, uint64_t pass) {
    tr_rng_init(rng, seed ^ 0x72657374697264ULL, (uint64_t)i, frame * 2u + pass);
}

/* ReSTIR GI's random numbers for pixel i of frame `frame`, pass `pass`. */
static void gi_rng(tr_rng *rng, uint64_t seed, size_t i, uint64_t frame, uint64_t pass) {
    tr_rng_init(rng, seed ^ 0x67692d72657374ULL, (uint64_t)i, frame * 2u + pass);
}

/* ReSTIR GI (src/kernel/restir_gi.h) on the surfaces st->surf of this frame: (1) every
 * pixel's initial sample and the temporal merge with the previous frame's reservoir at the
 * reprojected pixel, into gcur; (2) the spatial merge of gcur's neighbours (each one's
 * sample tested for visibility), the shading and the film's addition, into gout. As in
 * the direct light's passes, no pixel reads what another writes in the same pass. */
static void gi_passes(tr_restir_stage *st, const tr_scene_view *s, const tr_restir_params *p,
                      uint64_t seed, uint32_t spp, uint64_t frame, int threads, int temporal,
                      const tr_camera *prev_cam, tr_film *film) {
    const uint32_t w = st->w, h = st->h;
    const float cap = p->gi_temporal_cap > 0.0f ? p->gi_temporal_cap : 20.0f;
    const uint32_t flags = p->regularize ? TR_FRAME_REGULARIZE : 0u;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int y = 0; y < (int)h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const tr_restir_surface *q = &st->surf[i];
            if (!q->valid) {
                st->gcur[i] = tr_gi_reservoir_empty();
                continue;
            }
            tr_rng rng;
            gi_rng(&rng, seed, i, frame, 0);
            const float ulobe = tr_rng_float(&rng), u1 = tr_rng_float(&rng);
            const float u2 = tr_rng_float(&rng);
            const tr_sampler smp =
                tr_sampler_make_kind(seed ^ 0x67692d70617468ULL, (uint64_t)i, (uint32_t)frame, 1u);
            uint32_t rays = 0u;
            tr_gi_reservoir r = tr_gi_initial(s, q, ulobe, u1, u2, &smp, p->max_depth, p->rr_start,
                                              p->clamp_indirect, flags, &rays);
            float px, py, dist;
            if (temporal && tr_post_project(prev_cam, q->p, &px, &py, &dist) && px >= 0.0f &&
                py >= 0.0f && px < (float)w && py < (float)h) {
                const size_t j = (size_t)(uint32_t)py * w + (uint32_t)px;
                if (similar(q, &st->prev_surf[j])) {
                    tr_restir_surface ss[2];
                    tr_gi_reservoir rr[2];
                    const int vis[2] = {0, 0};
                    ss[0] = *q;
                    ss[1] = st->prev_surf[j];
                    rr[0] = r;
                    rr[1] = st->gprev[j];
                    if (rr[1].M > cap * r.M) {
                        rr[1].M = cap * r.M;
                    }
                    r = tr_gi_merge(s, ss, rr, vis, 2, p->gi_unbiased, cap + r.M, &rng);
                }
            }
            st->gcur[i] = r;
        }
    }

    const int k = p->gi_spatial < 0                         ? 0
                  : p->gi_spatial > TR_RESTIR_MAX_MERGE - 1 ? TR_RESTIR_MAX_MERGE - 1
                                                            : p->gi_spatial;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int y = 0; y < (int)h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const tr_restir_surface *q = &st->surf[i];
            if (!q->valid) {
                st->gout[i] = tr_gi_reservoir_empty();
                continue;
            }
            tr_rng rng;
            gi_rng(&rng, seed, i, frame, 1);
            tr_restir_surface ss[TR_RESTIR_MAX_MERGE];
            tr_gi_reservoir rr[TR_RESTIR_MAX_MERGE];
            int vis[TR_RESTIR_MAX_MERGE];
            ss[0] = *q;
            rr[0] = st->gcur[i];
            vis[0] = 0;
            size_t nb[TR_RESTIR_MAX_MERGE];
            const int m = pick_neighbours(st, x, y, w, h, p->gi_radius, k, &rng, nb);
            int n = 1;
            for (int t = 0; t < m; ++t, ++n) {
                ss[n] = st->surf[nb[t]];
                rr[n] = st->gcur[nb[t]];
                vis[n] = 1;
            }
            tr_gi_reservoir r =
                n > 1 ? tr_gi_merge(s, ss, rr, vis, n, p->gi_unbiased, 1e30f, &rng) : rr[0];
            st->gout[i] = r;
            const tr_vec3 c = v3_scale(tr_gi_shade(q, &r), (float)spp);
            film->sum[3 * i] += c.x;
            film->sum[3 * i + 1] += c.y;
            film->sum[3 * i + 2] += c.z;
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
    const int temporal = p->temporal && st->have_prev;
    const tr_camera prev_cam = st->prev_cam;
    const int candidates = p->candidates > 0 ? p->candidates : 1;
    const float cap = p->temporal_cap > 0.0f ? p->temporal_cap : 20.0f;

    /* Pass 1: surfaces, initial reservoirs, temporal merge. */
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int y = 0; y < (int)h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            tr_rng rng;
            pixel_rng(&rng, seed, i, frame, 0);
            tr_restir_surface q =
                tr_restir_primary(s, cam, seed, (uint64_t)i, x, (uint32_t)y, sample, sampler);
            st->surf[i] = q;
            if (!q.valid) {
                st->cur[i] = tr_reservoir_empty();
                continue;
            }
            tr_reservoir r = tr_restir_initial(s, &q, candidates, &rng);
            /* Visibility reuse (biased mode, when asked): an occluded sample is not passed
             * on. Its confidence still counts in every merge that takes the reservoir, so
             * a neighbour's merge loses the light this pixel's shadow hid from it; with the
             * spatial output kept as the next frame's history the loss compounds (−12 % over
             * the window room at rest), hence off by default. */
            if (p->visibility_reuse && !p->unbiased && r.W > 0.0f &&
                !tr_restir_visible(s, &q, &r)) {
                r.W = 0.0f;
            }
            float px, py, dist;
            if (temporal && tr_post_project(&prev_cam, q.p, &px, &py, &dist) && px >= 0.0f &&
                py >= 0.0f && px < (float)w && py < (float)h) {
                const size_t j = (size_t)(uint32_t)py * w + (uint32_t)px;
                if (similar(&q, &st->prev_surf[j])) {
                    tr_restir_surface ss[2];
                    tr_reservoir rr[2];
                    ss[0] = q;
                    ss[1] = st->prev_surf[j];
                    rr[0] = r;
                    rr[1] = st->prev[j];
                    const float mcap = cap * r.M;
                    if (rr[1].M > mcap) {
                        rr[1].M = mcap;
                    }
                    r = tr_restir_merge(s, ss, rr, 2, p->unbiased, cap + r.M, &rng);
                }
            }
            st->cur[i] = r;
        }
    }

    /* Pass 2: spatial merge, shading, the film. */
    const int k = p->spatial < 0                         ? 0
                  : p->spatial > TR_RESTIR_MAX_MERGE - 1 ? TR_RESTIR_MAX_MERGE - 1
                                                         : p->spatial;
    float *direct = (film->passes & TR_PASS_DIRECT) != 0u ? film->direct : NULL;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 4)
    for (int y = 0; y < (int)h; ++y) {
        for (uint32_t x = 0; x < w; ++x) {
            const size_t i = (size_t)y * w + x;
            const tr_restir_surface *q = &st->surf[i];
            if (!q->valid) {
                st->out[i] = tr_reservoir_empty();
                continue;
            }
            tr_rng rng;
            pixel_rng(&rng, seed, i, frame, 1);
            tr_restir_surface ss[TR_RESTIR_MAX_MERGE];
            tr_reservoir rr[TR_RESTIR_MAX_MERGE];
            ss[0] = *q;
            rr[0] = st->cur[i];
            size_t nb[TR_RESTIR_MAX_MERGE];
            const int m = pick_neighbours(st, x, y, w, h, p->radius, k, &rng, nb);
            int n = 1;
            for (int t = 0; t < m; ++t, ++n) {
                ss[n] = st->surf[nb[t]];
                rr[n] = st->cur[nb[t]];
            }
            tr_reservoir r =
                n > 1 ? tr_restir_merge(s, ss, rr, n, p->unbiased, 1e30f, &rng) : rr[0];
            st->out[i] = r;
            const tr_vec3 c = v3_scale(tr_restir_shade(s, q, &r), (float)spp);
            film->sum[3 * i] += c.x;
            film->sum[3 * i + 1] += c.y;
            film->sum[3 * i + 2] += c.z;
            if (direct) {
                direct[3 * i] += c.x;
                direct[3 * i + 1] += c.y;
                direct[3 * i + 2] += c.z;
            }
        }
    }

    if (p->gi) {
        gi_passes(st, &full, p, seed, spp, frame, threads, p->gi_temporal && st->have_prev,
                  &prev_cam, film);
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
