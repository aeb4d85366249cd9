/* vcm.c - the CPU device's frame for vertex connection and merging (integrator_vcm.h).
 *
 * Each of the frame's samples is two passes over the frame's tiles: the first traces one
 * light subpath per grid point and keeps it in its tile's list; the lists are joined in
 * tile order, the mergeable vertices sorted into the hashed grid (a counting sort, stable
 * in vertex order), and the second pass traces the camera subpaths, connects each with
 * its own grid point's light subpath and merges with the grid. Nothing depends on which
 * thread ran which tile, so the image does not depend on the thread count. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "device/vcm.h"
#include "trac0r/parse.h"
#include "kernel/integrator_vcm.h"
#include "kernel/kernel.h"

/* One tile's light subpaths: their vertices, subpath after subpath in the tile's grid
 * order, and for each vertex past a subpath's origin its merge weight's light-side sums
 * (tr_vcm_light_sums: a, b, g), computed here by the threads rather than by the grid's
 * serial build. */
typedef struct vcm_tile {
    tr_bdpt_vertex *verts;
    float *sums; /* 3 per vertex */
    size_t count, cap;
    int failed; /* out of memory */
} vcm_tile;

/* A buffer that only grows. */
typedef struct vcm_buf {
    void *p;
    size_t cap; /* bytes */
} vcm_buf;

/* b's memory, at least `bytes` of it; NULL when out of memory (b unchanged). */
static void *vcm_buf_get(vcm_buf *b, size_t bytes) {
    if (bytes > b->cap) {
        void *q = realloc(b->p, bytes);
        if (!q) {
            return NULL;
        }
        b->p = q;
        b->cap = bytes;
    }
    return b->p;
}

/* What a frame allocates: the tiles' lists and the grid's arrays. */
typedef struct vcm_scratch {
    vcm_tile *tiles;
    uint32_t tile_count; /* tiles allocated (zeroed when added) */
    vcm_buf cell_first, entries, unsorted, bucket, fill;
} vcm_scratch;

int tr_vcm_radius_pixels(float *pixels, tr_error *err) {
    *pixels = TR_VCM_RADIUS_DEFAULT;
    const char *e = getenv("TRAC0R_VCM_RADIUS");
    if (!e || !*e) {
        return TR_OK;
    }
    double v = 0.0;
    if (tr_parse_double(e, 0.0, 1000.0, &v) != TR_OK) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "TRAC0R_VCM_RADIUS=\"%s\": expected a radius in pixels, 0..1000 (0: "
                            "no merging)",
                            e);
    }
    *pixels = (float)v;
    return TR_OK;
}

/* The scratch kept from one frame to the next: a frame's lists and grid are tens of MB,
 * and fresh pages for them every frame cost more than the merging (page faults). One
 * frame at a time holds the cache; a frame rendered concurrently allocates its own. */
static pthread_mutex_t vcm_cache_lock = PTHREAD_MUTEX_INITIALIZER;
static vcm_scratch vcm_cache;

/* Scratch with tile_count empty tiles: the cache when it is free (*cached set), else
 * `own`, zeroed. NULL when out of memory. */
static vcm_scratch *vcm_scratch_get(vcm_scratch *own, uint32_t tile_count, int *cached) {
    vcm_scratch *sc = own;
    memset(own, 0, sizeof *own);
    *cached = pthread_mutex_trylock(&vcm_cache_lock) == 0;
    if (*cached) {
        sc = &vcm_cache;
    }
    if (sc->tile_count < tile_count) {
        vcm_tile *p = realloc(sc->tiles, tile_count * sizeof *p);
        if (!p) {
            if (*cached) {
                pthread_mutex_unlock(&vcm_cache_lock);
            }
            return NULL;
        }
        memset(p + sc->tile_count, 0, (tile_count - sc->tile_count) * sizeof *p);
        sc->tiles = p;
        sc->tile_count = tile_count;
    }
    for (uint32_t i = 0; i < tile_count; ++i) {
        sc->tiles[i].count = 0;
        sc->tiles[i].failed = 0;
    }
    return sc;
}

/* Gives the cache back, or frees a frame's own scratch. */
static void vcm_scratch_put(vcm_scratch *sc, int cached) {
    if (cached) {
        pthread_mutex_unlock(&vcm_cache_lock);
        return;
    }
    for (uint32_t ti = 0; ti < sc->tile_count; ++ti) {
        free(sc->tiles[ti].verts);
        free(sc->tiles[ti].sums);
    }
    free(sc->tiles);
    free(sc->cell_first.p);
    free(sc->entries.p);
    free(sc->unsorted.p);
    free(sc->bucket.p);
    free(sc->fill.p);
}

/* Room for one more light subpath at the end of t's list; 0 when out of memory. */
static int vcm_tile_reserve(vcm_tile *t) {
    const size_t need = t->count + TR_BDPT_MAX_VERTS;
    if (need > t->cap) {
        size_t cap = t->cap ? 2u * t->cap : 4u * TR_BDPT_MAX_VERTS;
        cap = cap < need ? need : cap;
        tr_bdpt_vertex *p = realloc(t->verts, cap * sizeof *p);
        if (p) {
            t->verts = p;
        }
        float *q = p ? realloc(t->sums, 3u * cap * sizeof *q) : NULL;
        if (!q) {
            t->failed = 1;
            return 0;
        }
        t->sums = q;
        t->cap = cap;
    }
    return 1;
}

/* The frame's grid points in tiles of side x side. */
typedef struct vcm_tiling {
    uint32_t gx0, gy0, nx, ny, side, tiles_x, tiles_y;
} vcm_tiling;

static void vcm_tile_rect(const vcm_tiling *g, uint32_t t, uint32_t *x0, uint32_t *y0, uint32_t *x1,
                          uint32_t *y1) {
    *x0 = g->gx0 + (t % g->tiles_x) * g->side;
    *y0 = g->gy0 + (t / g->tiles_x) * g->side;
    *x1 = *x0 + g->side < g->gx0 + g->nx ? *x0 + g->side : g->gx0 + g->nx;
    *y1 = *y0 + g->side < g->gy0 + g->ny ? *y0 + g->side : g->gy0 + g->ny;
}

/* Grid point (gx, gy)'s index among the frame's points, tile by tile's arrays. */
static size_t vcm_point_index(const vcm_tiling *g, uint32_t gx, uint32_t gy) {
    return (size_t)(gy - g->gy0) * g->nx + (gx - g->gx0);
}

/* Grid point (gx, gy) of frame f: its pixel (tr_frame_point: (x, y), the block b[0..3] it
 * fills and the pixel's index, returned) and its index among the points in *pi. */
static uint64_t vcm_point(const tr_frame *f, const vcm_tiling *g, uint32_t gx, uint32_t gy,
                          uint32_t *x, uint32_t *y, uint32_t b[4], size_t *pi) {
    *pi = vcm_point_index(g, gx, gy);
    return tr_frame_point(f, gx, gy, x, y, &b[0], &b[1], &b[2], &b[3]);
}

/* Runs BODY for every mergeable light vertex path[j] (j >= 1: not a subpath's origin),
 * whose light-side sums are sums[3j .. 3j+2], tile after tile, each tile's subpaths in its
 * grid order. */
#define VCM_FOR_EACH_MERGEABLE(BODY)                                                               \
    for (uint32_t ti = 0; ti < tile_count; ++ti) {                                                 \
        uint32_t x0, y0, x1, y1;                                                                   \
        vcm_tile_rect(tl, ti, &x0, &y0, &x1, &y1);                                                 \
        for (uint32_t gy = y0; gy < y1; ++gy) {                                                    \
            for (uint32_t gx = x0; gx < x1; ++gx) {                                                \
                const size_t pi = vcm_point_index(tl, gx, gy);                                     \
                const tr_bdpt_vertex *path = tiles[ti].verts + path_at[pi];                        \
                const float *sums = tiles[ti].sums + 3u * (size_t)path_at[pi];                     \
                for (uint32_t j = 1; j < path_len[pi]; ++j) {                                      \
                    if (tr_vcm_mergeable(&path[j])) {                                              \
                        BODY                                                                       \
                    }                                                                              \
                }                                                                                  \
            }                                                                                      \
        }                                                                                          \
    }

/* Sorts the light subpaths' mergeable vertices into g's buckets (a counting sort, stable
 * in tile and grid order), in sc's buffers. Returns 0 when out of memory. */
static int vcm_build_grid(tr_vcm_grid *g, const vcm_tiling *tl, vcm_scratch *sc,
                          uint32_t tile_count, const uint8_t *path_len, const uint32_t *path_at) {
    const vcm_tile *tiles = sc->tiles;
    size_t merge = 0;
    VCM_FOR_EACH_MERGEABLE((void)sums; ++merge;)
    const uint32_t cells = tr_vcm_cells(merge);
    g->cell_mask = cells - 1u;
    const size_t n = merge ? merge : 1u;
    uint32_t *cell_first = vcm_buf_get(&sc->cell_first, ((size_t)cells + 1u) * sizeof(uint32_t));
    tr_vcm_entry *entries = vcm_buf_get(&sc->entries, n * sizeof(tr_vcm_entry));
    tr_vcm_entry *unsorted = vcm_buf_get(&sc->unsorted, n * sizeof(tr_vcm_entry));
    uint32_t *bucket = vcm_buf_get(&sc->bucket, n * sizeof(uint32_t));
    uint32_t *fill = vcm_buf_get(&sc->fill, (size_t)cells * sizeof(uint32_t));
    if (!cell_first || !entries || !unsorted || !bucket || !fill || merge > UINT32_MAX) {
        return 0;
    }
    memset(cell_first, 0, ((size_t)cells + 1u) * sizeof *cell_first);
    /* The entries in vertex order with their buckets, then scattered bucket by bucket. */
    size_t k = 0;
    VCM_FOR_EACH_MERGEABLE({
        unsorted[k] =
            tr_vcm_entry_of(path, (int)j, sums[3u * j], sums[3u * j + 1u], sums[3u * j + 2u]);
        const tr_vec3 c = v3_scale(v3_sub(unsorted[k].p, g->origin), g->inv_cell);
        bucket[k] = tr_vcm_cell_hash(tr_vcm_cell_of(c.x), tr_vcm_cell_of(c.y), tr_vcm_cell_of(c.z),
                                     g->cell_mask);
        cell_first[bucket[k] + 1u] += 1u;
        ++k;
    })
    for (uint32_t c = 0; c < cells; ++c) {
        cell_first[c + 1u] += cell_first[c];
    }
    memcpy(fill, cell_first, (size_t)cells * sizeof *fill);
    for (size_t i = 0; i < k; ++i) {
        entries[fill[bucket[i]]++] = unsorted[i];
    }
    g->cell_first = cell_first;
    g->entries = entries;
    return 1;
}

uint32_t tr_vcm_cells(size_t total) {
    /* Four buckets a vertex: fewer cells share one. */
    uint32_t cells = 1u;
    while (cells < 4u * total && cells < (1u << 30)) {
        cells *= 2u;
    }
    return cells;
}

void tr_vcm_bucket_order(uint32_t nx, uint32_t ny, uint32_t tile, const uint32_t *first,
                         const uint32_t *count, const uint32_t *hash, uint32_t cells,
                         uint32_t *cell_first, uint32_t *fill, uint32_t *order) {
    const uint32_t mask = cells - 1u;
    const uint32_t side = tile ? tile : 16u;
    vcm_tiling tl = {0u, 0u, nx, ny, side, (nx + side - 1u) / side, (ny + side - 1u) / side};
    const uint32_t tile_count = tl.tiles_x * tl.tiles_y;
    memset(cell_first, 0, ((size_t)cells + 1u) * sizeof *cell_first);
    for (int pass = 0; pass < 2; ++pass) {
        if (pass == 1) {
            for (uint32_t c = 0; c < cells; ++c) {
                cell_first[c + 1u] += cell_first[c];
            }
            memcpy(fill, cell_first, (size_t)cells * sizeof *fill);
        }
        for (uint32_t ti = 0; ti < tile_count; ++ti) {
            uint32_t x0, y0, x1, y1;
            vcm_tile_rect(&tl, ti, &x0, &y0, &x1, &y1);
            for (uint32_t gy = y0; gy < y1; ++gy) {
                for (uint32_t gx = x0; gx < x1; ++gx) {
                    const size_t pi = vcm_point_index(&tl, gx, gy);
                    for (uint32_t e = first[pi]; e < first[pi] + count[pi]; ++e) {
                        const uint32_t b = hash[e] & mask;
                        if (pass == 0) {
                            cell_first[b + 1u] += 1u;
                        } else {
                            order[fill[b]++] = e;
                        }
                    }
                }
            }
        }
    }
}

tr_aabb tr_vcm_scene_box(const tr_scene_view *view) {
    tr_aabb box = {{0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}};
    for (uint32_t i = 0; i < view->flat_node_count; ++i) {
        const tr_aabb b = view->flat_nodes[i].box;
        box.min = i ? v3_min(box.min, b.min) : b.min;
        box.max = i ? v3_max(box.max, b.max) : b.max;
    }
    return box;
}

int tr_vcm_params_make(const tr_aabb *box, const tr_camera *cam, float pixels, uint32_t sample,
                       size_t points, int outside, tr_vcm_params *p) {
    memset(p, 0, sizeof *p);
    p->sample = sample;
    /* A pixel's footprint at the distance of the scene's centre, or at half the scene's
     * diagonal where the camera is nearer the centre than that (inside the scene). */
    const tr_vec3 centre = v3_scale(v3_add(box->min, box->max), 0.5f);
    const float dist =
        fmaxf(v3_length(v3_sub(centre, cam->pos)), 0.5f * v3_length(v3_sub(box->max, box->min)));
    const float footprint =
        dist * cam->canvas_width / (float)(cam->screen_width ? cam->screen_width : 1u);
    /* The merge radius of this sample. */
    const float r = pixels * footprint * powf((float)sample + 1.0f, 0.5f * (TR_VCM_ALPHA - 1.0f));
    if (!(r > 0.0f) || points == 0) {
        return 0;
    }
    const float area = (float)TR_PI * r * r;
    p->origin = box->min;
    p->inv_cell = 0.5f / r;
    p->radius2 = r * r;
    p->eta = (float)points * area;
    p->norm = 1.0f / p->eta;
    p->facing = outside ? 1u : 0u; /* integrator_vcm.h: tr_vcm_facing */
    return 1;
}

/* Whether a tile should be skipped: the frame was cancelled, or the caller's cancel
 * callback asks for it now (then *cancelled is set for the other threads). */
static int vcm_stopped(int *cancelled, int (*cancel)(void *), void *cancel_user) {
    int stop;
#pragma omp atomic read
    stop = *cancelled;
    if (stop) {
        return 1;
    }
    if (cancel && cancel(cancel_user)) {
#pragma omp atomic write
        *cancelled = 1;
        return 1;
    }
    return 0;
}

int tr_vcm_render(const tr_scene_view *view, const tr_frame *f, const tr_film_view *fv,
                  const tr_bdpt_splat *sp, int nthreads, uint32_t tile, int (*cancel)(void *),
                  void *cancel_user, uint64_t *rays_out, int *cancelled_out, tr_error *err) {
    float pixels;
    if (tr_vcm_radius_pixels(&pixels, err) != TR_OK) {
        return TR_ERR;
    }
    vcm_tiling tl;
    tr_frame_grid(f, &tl.gx0, &tl.gy0, &tl.nx, &tl.ny);
    tl.side = tile;
    tl.tiles_x = (tl.nx + tile - 1u) / tile;
    tl.tiles_y = (tl.ny + tile - 1u) / tile;
    const uint32_t tile_count = tl.tiles_x * tl.tiles_y;
    const size_t points = (size_t)tl.nx * tl.ny;
    const tr_camera cam = f->camera;
    const uint64_t seed = ((uint64_t)f->seed_hi << 32) | (uint64_t)f->seed_lo;
    const int max_depth = f->max_depth > TR_BDPT_MAX_DEPTH ? TR_BDPT_MAX_DEPTH : f->max_depth;
    const tr_aabb box = tr_vcm_scene_box(view);
    uint64_t rays = 0;
    int cancelled = 0, failed = 0;

    int cached = 0;
    vcm_scratch own;
    vcm_scratch *sc = vcm_scratch_get(&own, tile_count ? tile_count : 1u, &cached);
    vcm_tile *tiles = sc ? sc->tiles : NULL;
    uint8_t *path_len = malloc(points ? points : 1u);
    uint32_t *path_at = malloc((points ? points : 1u) * sizeof *path_at);
    if (!tiles || !path_len || !path_at) {
        if (sc) {
            vcm_scratch_put(sc, cached);
        }
        free(path_len);
        free(path_at);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for vcm's light subpaths");
    }
    for (uint32_t n = 0; n < f->sample_count && !cancelled && !failed; ++n) {
        const uint32_t sample = f->sample + n;
        /* Pass 1: the light subpaths. */
#pragma omp parallel for num_threads(nthreads) schedule(dynamic, 1) reduction(+ : rays)
        for (int ti = 0; ti < (int)tile_count; ++ti) {
            if (vcm_stopped(&cancelled, cancel, cancel_user)) {
                continue; /* an OpenMP loop cannot break: skip the remaining tiles */
            }
            vcm_tile *tt = &tiles[ti];
            tt->count = 0;
            uint32_t x0, y0, x1, y1;
            vcm_tile_rect(&tl, (uint32_t)ti, &x0, &y0, &x1, &y1);
            for (uint32_t gy = y0; gy < y1; ++gy) {
                for (uint32_t gx = x0; gx < x1; ++gx) {
                    uint32_t x, y, blk[4];
                    size_t pi;
                    const uint64_t pixel = vcm_point(f, &tl, gx, gy, &x, &y, blk, &pi);
                    path_at[pi] = (uint32_t)tt->count;
                    path_len[pi] = 0;
                    if (!vcm_tile_reserve(tt)) {
                        continue;
                    }
                    tr_sampler smp = tr_sampler_make(seed, pixel, sample);
                    uint32_t r = 0;
                    const int nl =
                        tr_bdpt_light_subpath(view, max_depth, &smp, tt->verts + tt->count, &r);
                    rays += r;
                    const tr_bdpt_vertex *path = tt->verts + tt->count;
                    float *sums = tt->sums + 3u * tt->count;
                    for (int j = 1; j < nl; ++j) {
                        tr_vcm_light_sums(path, j, &sums[3 * j], &sums[3 * j + 1],
                                          &sums[3 * j + 2]);
                    }
                    tt->count += (size_t)nl;
                    path_len[pi] = (uint8_t)nl;
                }
            }
        }
        if (cancelled) {
            break;
        }
        for (uint32_t ti = 0; ti < tile_count; ++ti) {
            failed |= tiles[ti].failed;
        }
        if (failed) {
            break;
        }
        tr_vcm_params p;
        tr_vcm_grid g;
        memset(&g, 0, sizeof g);
        if (tr_vcm_params_make(&box, &cam, pixels, sample, points, tr_bdpt_outside_on(view), &p)) {
            g = tr_vcm_grid_of(&p, NULL, NULL);
            if (!vcm_build_grid(&g, &tl, sc, tile_count, path_len, path_at)) {
                failed = 1;
            }
        }
        /* Pass 2: the camera subpaths, their connections and merges. */
        if (!failed) {
#pragma omp parallel for num_threads(nthreads) schedule(dynamic, 1) reduction(+ : rays)
            for (int ti = 0; ti < (int)tile_count; ++ti) {
                if (vcm_stopped(&cancelled, cancel, cancel_user)) {
                    continue;
                }
                uint32_t x0, y0, x1, y1;
                vcm_tile_rect(&tl, (uint32_t)ti, &x0, &y0, &x1, &y1);
                for (uint32_t gy = y0; gy < y1; ++gy) {
                    for (uint32_t gx = x0; gx < x1; ++gx) {
                        uint32_t x, y, blk[4];
                        size_t pi;
                        const uint64_t pixel = vcm_point(f, &tl, gx, gy, &x, &y, blk, &pi);
                        tr_sample out;
                        tr_sample_clear(&out);
                        tr_sampler smp = tr_sampler_make(seed, pixel, sample);
                        out.radiance = tr_trace_vcm(view, &cam, (float)x, (float)y, max_depth, &smp,
                                                    sp, tiles[ti].verts + path_at[pi], path_len[pi],
                                                    &g, &out.rays, f->passes != 0u ? &out : 0);
                        tr_sample_finish(&out);
                        rays += out.rays;
                        tr_film_add_block(fv, &out, blk[0], blk[1], blk[2], blk[3]);
                    }
                }
            }
        }
    }
    vcm_scratch_put(sc, cached);
    free(path_len);
    free(path_at);
    *cancelled_out = cancelled;
    if (failed) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY,
                            "out of memory for vcm's light subpaths (%ux%u points)", tl.nx, tl.ny);
    }
    *rays_out += rays;
    return TR_OK;
}
