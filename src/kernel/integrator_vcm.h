/* integrator_vcm.h - vertex connection and merging (I. Georgiev, J. Krivanek, T. Davidovic
 * and P. Slusallek, "Light Transport Simulation with Vertex Connection and Merging",
 * SIGGRAPH Asia 2012; also Hachisuka, Pantaleoni and Jensen, "A Path Space Extension for
 * Robust Light Transport Simulation", the same conference).
 *
 * BDPT (integrator_bdpt.h) cannot sample a path whose only non-delta vertex between two
 * delta ones is diffuse: light -> glass -> floor -> glass -> camera, the caustic under a
 * glass sphere seen through it, or a wall lit through a mirror and seen in one. Every
 * connection would have to end at a delta vertex. Vertex merging samples those paths: a
 * frame first traces one light subpath per pixel (the subpath BDPT would trace for that
 * pixel with the same sampler) and keeps its vertices; then each camera subpath makes
 * BDPT's connections with its own pixel's light subpath and, at its first non-delta
 * vertex x, merges with every stored light vertex y within radius r of x: the path that
 * reached y from the light is continued as if it had reached x, the density estimate
 *     L(x, wo) += f(x, wo, wi_y) beta_y |wi_y . ns| / |wi_y . ng| / (N pi r^2)
 * (N light subpaths, beta_y the flux the subpath carries to y, wi_y its direction back
 * along the subpath, the cosine ratio Veach's shading-normal correction at x). All the
 * strategies are weighed with the power heuristic (tr_bdpt_mis_weight_vm), merges counted
 * at density eta = N pi r^2 relative to connections.
 *
 * Merging at the first non-delta camera vertex only (the paper merges at every one) is
 * this implementation's choice: it covers the specular-diffuse-specular paths (x seen
 * through a mirror or glass) and the first bounce's indirect light, where merging pays
 * most, with one range query per pixel instead of one per vertex. Merging at every
 * vertex measured about 1.4x fewer samples to 30 dB on scenes/cornell-glass.json than
 * BDPT at 2.1x the time per sample; first-hit merging 3-4x fewer samples at 1.5-2x
 * (docs/integrators.md). The MIS weights count exactly the merges made.
 *
 * Merging is biased for r > 0; the radius shrinks with the sample index i (1-based) as
 * r_i = r_1 i^((alpha - 1) / 2), alpha = 3/4, so that the bias and the variance both
 * vanish (Knaus and Zwicker, "Progressive Photon Mapping: A Probabilistic Approach", ACM
 * TOG 2011, the same schedule as the VCM paper's). r_1 is given in pixels: that many
 * pixel footprints at the distance from the camera to the centre of the scene's bounding
 * box, or at half its diagonal if that is more (a camera inside the scene), so that the
 * blur the bias brings is about the same on screen at any resolution
 * (TR_VCM_RADIUS_DEFAULT, or the environment's TRAC0R_VCM_RADIUS).
 *
 * The light vertices are found through a hashed uniform grid of cells 2r wide: a point's
 * neighbours within r lie in the 2 x 2 x 2 cells nearest it (the hash: Teschner et al.,
 * "Optimized Spatial Hashing for Collision Detection of Deformable Objects", VMV 2003).
 * The host builds it with a counting sort, stable in vertex order, so every pixel sums its
 * merges in an order fixed by the frame's tiling, not by the threads: from the light
 * subpaths the CPU device keeps (src/device/vcm.c), or from the entries and bucket hashes
 * an OpenCL device's light pass writes (tr_vcm_device_light below, src/device/opencl.c).
 * A device does not keep the light subpaths themselves (up to 16 vertices of some 200
 * bytes per pixel): its camera pass traces each pixel's light subpath again with the same
 * sampler, which gives the same vertices, for the connections. */
#ifndef TR_KERNEL_INTEGRATOR_VCM_H
#define TR_KERNEL_INTEGRATOR_VCM_H

#include "integrator_bdpt.h"

/* The 32-bit atomic addition a device's light pass reserves its entries with. */
#if defined(__OPENCL_C_VERSION__) || defined(__OPENCL_VERSION__)
#define TR_VCM_ATOMIC_ADD(p, v) atomic_add((p), (v))
#else
#define TR_VCM_ATOMIC_ADD(p, v) __atomic_fetch_add((p), (v), __ATOMIC_RELAXED)
#endif

/* alpha of the radius schedule: r^2 shrinks as i^(alpha - 1). */
#define TR_VCM_ALPHA 0.75f
/* The first sample's merge radius, in pixel footprints at the distance from the camera to
 * the centre of the scene's bounding box (or half its diagonal, if more). */
#define TR_VCM_RADIUS_DEFAULT 3.0f

/* A light vertex merged with: vertex `index` of its light subpath, by value (what a merge
 * reads of it: position, direction back along the subpath, geometric normal, throughput
 * and area density), so that a bucket's entries are one contiguous array with no pointer
 * into the subpaths (an OpenCL device keeps none of them past the light pass), and the
 * light side's share of its merges' MIS weights (tr_vcm_light_sums: a, b, g). */
typedef struct tr_vcm_entry {
    tr_vec3 p;
    uint32_t index;
    tr_vec3 wo;
    float pdf_fwd;
    tr_vec3 ng;
    float a;
    tr_vec3 beta;
    float b, g;
} tr_vcm_entry;
TR_STATIC_ASSERT(sizeof(tr_vcm_entry) == 68, "tr_vcm_entry: the same 17 words on every device");

/* The grid over the light vertices of one sample's light subpaths. */
typedef struct tr_vcm_grid {
    TR_CONST_GLOBAL uint32_t *cell_first;  /* cell_count + 1 offsets into entries */
    TR_CONST_GLOBAL tr_vcm_entry *entries; /* the vertices merged with, cell by cell */
    uint32_t cell_mask;                    /* cell_count - 1, cell_count a power of two */
    tr_vec3 origin;                        /* cells are counted from here */
    float inv_cell;                        /* 1 / (2 r) */
    float radius2;                         /* r^2 */
    float eta;                             /* N pi r^2 (0: no merging) */
    float norm;                            /* 1 / (N pi r^2) */
    uint32_t facing;                       /* merge only light vertices on surfaces facing as x's */
} tr_vcm_grid;

/* The entry of light vertex path[j] whose light-side sums are a, b and g. */
TR_FN tr_vcm_entry tr_vcm_entry_of(const tr_bdpt_vertex *path, int j, float a, float b, float g) {
    tr_vcm_entry e;
    e.p = path[j].p;
    e.index = (uint32_t)j;
    e.wo = path[j].wo;
    e.pdf_fwd = path[j].pdf_fwd;
    e.ng = path[j].m.ng;
    e.a = a;
    e.beta = path[j].beta;
    e.b = b;
    e.g = g;
    return e;
}

/* With light subpaths from the environment and the sun, light vertices also lie on the
 * outer faces of a closed room's walls, which no emitter inside reaches: a merge near a
 * corner or through a wall without thickness would carry that outside light in. So in
 * such scenes (tr_bdpt_sky_on; the grid's `facing`) a light vertex y is merged with camera
 * vertex x only where their geometric normals, each turned towards its own incoming
 * direction, agree to within 60 degrees: on one smooth surface they always do once r is
 * small, so the estimate still converges. Scenes without a sky keep every merge, and
 * their images. */
#define TR_VCM_FACING_COS 0.5f

TR_FN int tr_vcm_facing(const tr_bdpt_vertex *x, tr_vec3 y_wo, tr_vec3 y_ng) {
    const float sx = v3_dot(x->wo, x->m.ng) < 0.0f ? -1.0f : 1.0f;
    const float sy = v3_dot(y_wo, y_ng) < 0.0f ? -1.0f : 1.0f;
    return sx * sy * v3_dot(x->m.ng, y_ng) > TR_VCM_FACING_COS;
}

/* The bucket of grid cell (ix, iy, iz). */
TR_FN uint32_t tr_vcm_cell_hash(int32_t ix, int32_t iy, int32_t iz, uint32_t mask) {
    const uint32_t h =
        ((uint32_t)ix * 73856093u) ^ ((uint32_t)iy * 19349663u) ^ ((uint32_t)iz * 83492791u);
    return h & mask;
}

/* The cell coordinate of c (in cells along one axis), clamped so that the conversion is
 * defined for any point (cells that far out only share buckets). */
TR_FN int32_t tr_vcm_cell_of(float c) {
    return (int32_t)tr_floorf(tr_fminf(tr_fmaxf(c, -1073741824.0f), 1073741824.0f));
}

/* Cell coordinate along one axis of c (in cells) and its neighbour on the side nearer c. */
TR_FN void tr_vcm_cell_pair(float c, int32_t *a, int32_t *b) {
    *a = tr_vcm_cell_of(c);
    *b = c - (float)*a < 0.5f ? *a - 1 : *a + 1;
}

/* Whether a light vertex is stored in the grid: a surface past the subpath's origin whose
 * BSDF is not all delta and which carries flux. */
TR_FN int tr_vcm_mergeable(const tr_bdpt_vertex *y) {
    return y->kind == TR_BDPT_SURFACE && !tr_bsdf_is_delta(&y->m) &&
           y->m.type != TR_MATERIAL_EMITTER && !tr_v3_is_zero(y->beta);
}

/* The light side of the MIS weight of a merge at light vertex y = lv[i] (i >= 1), with
 * the merged path's vertex i taken to lie at y rather than at the camera vertex x (an
 * O(r) approximation, as the VCM paper's implementation makes; the weights of the other
 * strategies are exact). In the notation of tr_bdpt_mis_weight_vm, relative to the
 * connection with i light vertices, the strategies with k < i light vertices weigh
 *     sum_k r_k^2 = pc[i-1]^2 * a,
 * where pc[i-1] = pdf_x(y.wo) * g is the camera vertex's density for lv[i-1] (its BSDF's
 * solid-angle density times g = |cos at lv[i-1]| / d^2) and a collects the rest, which the
 * light subpath alone determines; b is that connection's own term: 1, c^2 where it is
 * next-event estimation (i = 1), 0 where lv[i-1] is delta. */
TR_FN void tr_vcm_light_sums(const tr_bdpt_vertex *lv, int i, float *a, float *b, float *g) {
    const tr_bdpt_vertex *y = &lv[i], *q = &lv[i - 1];
    float d2;
    const tr_vec3 w = tr_bdpt_dir(q->p, y->p, &d2);
    *g = d2 > 0.0f ? tr_fabsf(v3_dot(w, q->m.ng)) / d2 : 0.0f;
    if (q->kind == TR_BDPT_INFINITE) {
        *g = 1.0f; /* a direction: the camera vertex's density for it is a solid angle's */
    }
    /* c: strategy 1 draws lv[0] by next-event estimation (tr_bdpt_mis_weight_vm). */
    float c = 0.0f;
    if (lv[0].pdf_fwd > 0.0f && (i == 1 || !lv[1].delta)) {
        c = lv[0].pdf_nee / lv[0].pdf_fwd;
    }
    float prod = 1.0f / tr_bdpt_remap0(q->pdf_fwd); /* r_k / pc[i-1], from k = i-1 down */
    float sum = 0.0f;
    for (int k = i - 1; k >= 0; --k) {
        /* Strategy 0 hits lv[0]: not a delta light. */
        const int ok = (k == 0 || !lv[k - 1].delta) && !lv[k].delta &&
                       !(k == 0 && tr_bdpt_delta_light(&lv[0]));
        const float rk = k == 1 ? prod * c : prod;
        sum += ok ? rk * rk : 0.0f;
        if (k > 0) {
            prod *= tr_bdpt_remap0(lv[k - 1].pdf_rev) / tr_bdpt_remap0(lv[k - 1].pdf_fwd);
        }
    }
    *a = lv[0].pdf_fwd > 0.0f ? sum : 0.0f;
    *b = q->delta ? 0.0f : (i == 1 ? c * c : 1.0f);
}

/* The power-heuristic weight of merging camera vertex pt = cv[t-1] (the camera subpath's
 * first non-delta vertex) with light vertex y, vertex i of its light subpath, which
 * arrived from direction y_wo with area density y_pdf_fwd and whose light-side sums are
 * a, b and g (tr_vcm_light_sums), at eta = N pi r^2. The strategies, relative to the connection
 * with the i light vertices before y: those with fewer light vertices, that connection itself (b),
 * light tracing (only for t = 2: past a delta vertex no other camera-side strategy can make the
 * path) and the merge. Equals tr_bdpt_mis_weight_vm's merge weight where pt lies at y (tested). */
TR_FN float tr_vcm_merge_weight(const tr_bdpt_vertex *pt, int t, tr_vec3 y_wo, float y_pdf_fwd,
                                float a, float b, float g, float eta) {
    const float pc = tr_bdpt_remap0(tr_bsdf_pdf(&pt->m, pt->wo, y_wo) * g);
    const float pl = tr_bdpt_remap0(y_pdf_fwd);
    const float m = pl * eta;
    float sum = pc * pc * a + b + m * m;
    if (t == 2) {
        const float r = pl / tr_bdpt_remap0(pt->pdf_fwd);
        sum += r * r;
    }
    return sum > 0.0f ? m * m / sum : 0.0f;
}

/* The merges of camera subpath cv[0 .. nc-1] with the grid's light vertices: what they
 * bring to the pixel. Paths stay within max_depth segments. */
TR_FN tr_vec3 tr_vcm_merge(const tr_bdpt_vertex *cv, int nc, int max_depth, const tr_vcm_grid *g) {
    tr_vec3 radiance = v3s(0.0f);
    if (!(g->eta > 0.0f)) {
        return radiance;
    }
    /* Only at the first non-delta vertex. */
    int t = 2;
    while (t <= nc && cv[t - 1].delta) {
        ++t;
    }
    if (t <= nc && t - 1 < max_depth) {
        const tr_bdpt_vertex *pt = &cv[t - 1];
        if (tr_bsdf_is_delta(&pt->m) || pt->m.type == TR_MATERIAL_EMITTER ||
            tr_v3_is_zero(pt->beta)) {
            return radiance;
        }
        const tr_vec3 c = v3_scale(v3_sub(pt->p, g->origin), g->inv_cell);
        int32_t xs[2], ys[2], zs[2];
        tr_vcm_cell_pair(c.x, &xs[0], &xs[1]);
        tr_vcm_cell_pair(c.y, &ys[0], &ys[1]);
        tr_vcm_cell_pair(c.z, &zs[0], &zs[1]);
        uint32_t seen[8];
        for (int j = 0; j < 8; ++j) {
            const uint32_t h =
                tr_vcm_cell_hash(xs[j & 1], ys[(j >> 1) & 1], zs[j >> 2], g->cell_mask);
            int dup = 0;
            for (int i = 0; i < j; ++i) {
                dup |= seen[i] == h; /* two cells in one bucket: visit it once */
            }
            seen[j] = h;
            if (dup) {
                continue;
            }
            for (uint32_t e = g->cell_first[h]; e < g->cell_first[h + 1u]; ++e) {
                const tr_vcm_entry en = g->entries[e];
                const tr_vec3 d = v3_sub(en.p, pt->p);
                if (!(v3_dot(d, d) <= g->radius2)) {
                    continue;
                }
                const int sv = (int)en.index + 1; /* light vertices up to y */
                if ((sv - 1) + (t - 1) > max_depth ||
                    (g->facing && !tr_vcm_facing(pt, en.wo, en.ng))) {
                    continue;
                }
                const float den = tr_fabsf(v3_dot(en.wo, pt->m.ng));
                if (!(den > 0.0f)) {
                    continue;
                }
                const tr_vec3 f = tr_bsdf_eval(&pt->m, pt->wo, en.wo);
                const float fix = tr_fabsf(v3_dot(en.wo, pt->m.ns)) / den;
                tr_vec3 v = v3_scale(v3_mul(v3_mul(pt->beta, f), en.beta), fix * g->norm);
                if (tr_v3_is_zero(v)) {
                    continue;
                }
                const float w =
                    tr_vcm_merge_weight(pt, t, en.wo, en.pdf_fwd, en.a, en.b, en.g, g->eta);
                radiance = v3_add(radiance, v3_scale(v, w));
            }
        }
    }
    return radiance;
}

/* One VCM sample for the camera ray through raster point (x + jx, y + jy), with the
 * pixel's own light subpath lv[0 .. nl-1] (traced by tr_bdpt_light_subpath with the same
 * sampler in the frame's first pass): BDPT's connections, weighed with merging among the
 * strategies, and the merges. Light tracing splats into sp. */
TR_FN tr_vec3 tr_trace_vcm(const tr_scene_view *s, const tr_camera *cam, float x, float y,
                           int max_depth, const tr_sampler *smp, const tr_bdpt_splat *sp,
                           const tr_bdpt_vertex *lv, int nl, const tr_vcm_grid *g, uint32_t *rays,
                           tr_sample *surface) {
    if (max_depth > TR_BDPT_MAX_DEPTH) {
        max_depth = TR_BDPT_MAX_DEPTH;
    }
    tr_bdpt_vertex cv[TR_BDPT_MAX_VERTS];
    const tr_bdpt_select all = {0, 0};
    tr_bdpt_escape esc;
    int nc = tr_bdpt_camera_subpath(s, cam, x, y, max_depth, smp, cv, rays, surface, &esc);
    tr_vec3 c = tr_bdpt_connect(s, cam, cv, nc, lv, nl, max_depth, smp, sp, all, g->eta, rays);
    if (tr_bdpt_sky_on(s)) {
        c = v3_add(c, tr_bdpt_sky_camera(s, cam, cv, nc, &esc, max_depth, smp, g->eta, rays));
    }
    if (tr_bdpt_punctual_on(s)) {
        c = v3_add(c, tr_bdpt_punctual_camera(s, cam, cv, nc, max_depth, smp, g->eta, rays));
    }
    c = v3_add(c, tr_bdpt_infinite(s, cv, nc, &esc, max_depth, smp, rays));
    return v3_add(c, tr_vcm_merge(cv, nc, max_depth, g));
}

/* The grid's scalars for one sample, as the host computes them for a device (no pointers,
 * so the same bytes on both sides). */
typedef struct tr_vcm_params {
    tr_vec3 origin;
    float inv_cell, radius2, eta, norm;
    uint32_t facing, cell_mask;
    uint32_t sample; /* the sample these are for */
} tr_vcm_params;
TR_STATIC_ASSERT(sizeof(tr_vcm_params) == 40, "tr_vcm_params: the same 10 words everywhere");

/* The grid of params over the buckets cell_first and entries. */
TR_FN tr_vcm_grid tr_vcm_grid_of(const tr_vcm_params *p, TR_CONST_GLOBAL uint32_t *cell_first,
                                 TR_CONST_GLOBAL tr_vcm_entry *entries) {
    tr_vcm_grid g;
    g.cell_first = cell_first;
    g.entries = entries;
    g.cell_mask = p->cell_mask;
    g.origin = p->origin;
    g.inv_cell = p->inv_cell;
    g.radius2 = p->radius2;
    g.eta = p->eta;
    g.norm = p->norm;
    g.facing = p->facing;
    return g;
}

/* The bucket of point q before it is reduced to the grid's size: tr_vcm_cell_hash with
 * every bit kept (the hash of a cell masked by any cell_mask is this masked). */
TR_FN uint32_t tr_vcm_point_hash(const tr_vcm_params *p, tr_vec3 q) {
    const tr_vec3 c = v3_scale(v3_sub(q, p->origin), p->inv_cell);
    return tr_vcm_cell_hash(tr_vcm_cell_of(c.x), tr_vcm_cell_of(c.y), tr_vcm_cell_of(c.z),
                            0xffffffffu);
}

/* Grid point (gx, gy)'s light subpath for `sample` of frame f, into lv (the vertices the
 * CPU device's first pass keeps): returns their number and adds its rays to *rays. */
TR_FN int tr_vcm_light_path(const tr_scene_view *s, const tr_frame *f, uint32_t gx, uint32_t gy,
                            uint32_t sample, tr_bdpt_vertex *lv, uint32_t *rays) {
    const uint64_t seed = ((uint64_t)f->seed_hi << 32) | (uint64_t)f->seed_lo;
    const int max_depth = f->max_depth > TR_BDPT_MAX_DEPTH ? TR_BDPT_MAX_DEPTH : f->max_depth;
    uint32_t x, y, bx0, by0, bx1, by1;
    const uint64_t pixel = tr_frame_point(f, gx, gy, &x, &y, &bx0, &by0, &bx1, &by1);
    tr_sampler smp = tr_sampler_make(seed, pixel, sample);
    return tr_bdpt_light_subpath(s, max_depth, &smp, lv, rays);
}

/* A device's first pass at grid point (gx, gy): its light subpath's mergeable vertices
 * (tr_vcm_mergeable, past the origin) go to out[0 ..] with their buckets' full hashes in
 * hash[] (tr_vcm_point_hash), in vertex order, where at most `room` fit; returns how many
 * there are (also when they do not fit, so that the host can make room and run the pass
 * again). The rays are counted by the second pass, which traces the subpath again. */
TR_FN uint32_t tr_vcm_device_light(const tr_scene_view *s, const tr_frame *f,
                                   const tr_vcm_params *p, uint32_t gx, uint32_t gy,
                                   TR_GLOBAL tr_vcm_entry *out, TR_GLOBAL uint32_t *hash,
                                   TR_GLOBAL uint32_t *counter, uint32_t room,
                                   uint32_t *first_out) {
    tr_bdpt_vertex lv[TR_BDPT_MAX_VERTS];
    uint32_t rays = 0;
    const int nl = tr_vcm_light_path(s, f, gx, gy, p->sample, lv, &rays);
    uint32_t n = 0;
    for (int j = 1; j < nl; ++j) {
        n += tr_vcm_mergeable(&lv[j]) ? 1u : 0u;
    }
    *first_out = 0;
    if (n == 0u) {
        return 0;
    }
    /* One block for the subpath, wherever the device's scheduling puts it: the host sorts
     * the entries by grid point before the buckets are made. */
    const uint32_t first = TR_VCM_ATOMIC_ADD(counter, n);
    *first_out = first;
    if (first > room || n > room - first) {
        return n;
    }
    uint32_t k = first;
    for (int j = 1; j < nl; ++j) {
        if (!tr_vcm_mergeable(&lv[j])) {
            continue;
        }
        float a, b, g;
        tr_vcm_light_sums(lv, j, &a, &b, &g);
        out[k] = tr_vcm_entry_of(lv, j, a, b, g);
        hash[k] = tr_vcm_point_hash(p, lv[j].p);
        ++k;
    }
    return n;
}

/* A device's second pass at grid point (gx, gy) for the sample of p: the pixel's light
 * subpath traced again, the camera subpath, their connections and the merges with grid g,
 * added to the film (the block the point fills) as the CPU's second pass adds them;
 * returns the rays of both subpaths and the connections. */
TR_FN uint32_t tr_vcm_device_camera(const tr_scene_view *s, const tr_frame *f,
                                    const tr_film_view *film, const tr_bdpt_splat *sp,
                                    const tr_vcm_grid *g, uint32_t sample, uint32_t gx,
                                    uint32_t gy) {
    tr_bdpt_vertex lv[TR_BDPT_MAX_VERTS];
    uint32_t rays = 0;
    const int nl = tr_vcm_light_path(s, f, gx, gy, sample, lv, &rays);
    const uint64_t seed = ((uint64_t)f->seed_hi << 32) | (uint64_t)f->seed_lo;
    const int max_depth = f->max_depth > TR_BDPT_MAX_DEPTH ? TR_BDPT_MAX_DEPTH : f->max_depth;
    const tr_camera cam = f->camera;
    uint32_t x, y, bx0, by0, bx1, by1;
    const uint64_t pixel = tr_frame_point(f, gx, gy, &x, &y, &bx0, &by0, &bx1, &by1);
    tr_sample out;
    tr_sample_clear(&out);
    tr_sampler smp = tr_sampler_make(seed, pixel, sample);
    out.radiance = tr_trace_vcm(s, &cam, (float)x, (float)y, max_depth, &smp, sp, lv, nl, g,
                                &out.rays, f->passes != 0u ? &out : 0);
    tr_sample_finish(&out);
    tr_film_add_block(film, &out, bx0, by0, bx1, by1);
    return rays + out.rays;
}

#endif
