/* rays.c - ray sets for measuring an acceleration structure's throughput (measure.h):
 * the same primary, diffuse and shadow rays traced by every structure. */
#include "trac0r/measure.h"

#include <omp.h>
#include <stdlib.h>

#include "accel/cwbvh.h"
#include "device/opencl.h"
#include "kernel/kernel.h"
#include "scene/scene_internal.h"
#include "trac0r/render.h"

struct tr_ray_sets {
    tr_ray *rays[TR_RAY_KINDS];
    uint32_t count[TR_RAY_KINDS];
};

/* Area-weighted emitter triangles, for aiming shadow rays at the lights. */
typedef struct emitters {
    uint32_t *tri;
    float *cdf;
    uint32_t count;
} emitters;

static int collect_emitters(const tr_scene *s, emitters *e) {
    const uint32_t n = tr_scene_stored_triangle_count(s); /* kept instances never emit */
    e->tri = malloc((size_t)(n ? n : 1) * sizeof *e->tri);
    e->cdf = malloc((size_t)(n ? n : 1) * sizeof *e->cdf);
    e->count = 0;
    if (!e->tri || !e->cdf) {
        return TR_ERR;
    }
    float total = 0.0f;
    for (uint32_t i = 0; i < n; ++i) {
        const tr_triangle t = tr_scene_triangle(s, i);
        if (tr_scene_material(s, t.material).emittance > 0.0f && t.area > 0.0f) {
            total += t.area;
            e->tri[e->count] = i;
            e->cdf[e->count++] = total;
        }
    }
    return TR_OK;
}

static tr_vec3 sample_emitter(const tr_scene *s, const emitters *e, tr_rng *r) {
    const float x = tr_rng_float(r) * e->cdf[e->count - 1];
    uint32_t k = 0;
    while (k + 1 < e->count && e->cdf[k] <= x) {
        ++k;
    }
    const tr_triangle t = tr_scene_triangle(s, e->tri[k]);
    float u = tr_rng_float(r), v = tr_rng_float(r);
    if (u + v > 1.0f) {
        u = 1.0f - u, v = 1.0f - v;
    }
    return v3_add(t.v0, v3_add(v3_scale(v3_sub(t.v1, t.v0), u), v3_scale(v3_sub(t.v2, t.v0), v)));
}

const char *tr_ray_kind_name(int kind) {
    static const char *const names[TR_RAY_KINDS] = {"primary", "diffuse", "shadow"};
    return kind >= 0 && kind < TR_RAY_KINDS ? names[kind] : NULL;
}

void tr_ray_sets_destroy(tr_ray_sets *r) {
    if (r) {
        for (int k = 0; k < TR_RAY_KINDS; ++k) {
            free(r->rays[k]);
        }
        free(r);
    }
}

tr_ray_sets *tr_ray_sets_create(const tr_scene *s, uint64_t seed, tr_error *err) {
    const tr_camera *cam = tr_scene_camera(s);
    const uint32_t n = cam->screen_width * cam->screen_height;
    tr_ray_sets *r = calloc(1, sizeof *r);
    emitters e = {NULL, NULL, 0};
    int ok = r != NULL && collect_emitters(s, &e) == TR_OK;
    for (int k = 0; ok && k < TR_RAY_KINDS; ++k) {
        ok = (r->rays[k] = malloc((size_t)(n ? n : 1) * sizeof *r->rays[k])) != NULL;
    }
    if (!ok) {
        free(e.tri);
        free(e.cdf);
        tr_ray_sets_destroy(r);
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "ray sets: out of memory for %u rays", n);
        return NULL;
    }
    const tr_scene_view view = tr_scene_view_of(s);
    for (uint32_t i = 0; i < n; ++i) {
        tr_rng rng;
        tr_rng_init(&rng, seed, i, 0);
        float jx, jy;
        tr_sample_pixel_jitter(&rng, &jx, &jy);
        tr_ray ray = tr_camera_ray(cam, (float)(i % cam->screen_width),
                                   (float)(i / cam->screen_width), jx, jy);
        r->rays[TR_RAY_PRIMARY][r->count[TR_RAY_PRIMARY]++] = ray;
        tr_hit hit;
        if (!tr_intersect_scene(&view, &ray, &hit)) {
            continue;
        }
        const tr_vec3 p = v3_madd(ray.origin, ray.dir, hit.t);
        const tr_vec3 n_geo = tr_scene_triangle(s, hit.triangle).normal;
        const tr_vec3 nf = v3_dot(n_geo, ray.dir) > 0.0f ? v3_neg(n_geo) : n_geo;
        const tr_vec3 o = tr_offset_origin(p, nf);
        r->rays[TR_RAY_DIFFUSE][r->count[TR_RAY_DIFFUSE]++] =
            tr_ray_make(o, tr_sample_cosine_hemisphere(&rng, nf), 0.0f, TR_INFINITY);
        if (e.count > 0) {
            const tr_vec3 d = v3_sub(sample_emitter(s, &e, &rng), o);
            const float dist = v3_length(d);
            if (dist > 0.0f) {
                /* Stop just short of the light so that the light itself is no occluder. */
                r->rays[TR_RAY_SHADOW][r->count[TR_RAY_SHADOW]++] =
                    tr_ray_make(o, v3_scale(d, 1.0f / dist), 0.0f, dist * 0.999f);
            }
        }
    }
    free(e.tri);
    free(e.cdf);
    return r;
}

uint32_t tr_ray_sets_count(const tr_ray_sets *r, int kind) {
    return r && kind >= 0 && kind < TR_RAY_KINDS ? r->count[kind] : 0u;
}

double tr_ray_sets_trace(const tr_ray_sets *r, const tr_scene *s, int kind, int threads, int reps,
                         uint64_t *hits) {
    const tr_scene_view view = tr_scene_view_of(s);
    const tr_ray *rays = r->rays[kind];
    const int64_t count = (int64_t)r->count[kind];
    const int shadow = kind == TR_RAY_SHADOW;
    const int nthreads = threads > 0 ? threads : tr_default_threads();
    uint64_t h = 0;
    const double t0 = tr_time_now();
    for (int rep = 0; rep < reps; ++rep) {
        h = 0;
#pragma omp parallel for num_threads(nthreads) schedule(dynamic, 1024) reduction(+ : h)
        for (int64_t i = 0; i < count; ++i) {
            if (shadow) {
                h += (uint64_t)tr_occluded_scene(&view, &rays[i]);
            } else {
                tr_hit hit;
                h += (uint64_t)tr_intersect_scene(&view, &rays[i], &hit);
            }
        }
    }
    *hits = h;
    return tr_time_now() - t0;
}

int tr_ray_sets_trace_device(const tr_ray_sets *r, tr_device *dev, int kind, int reps,
                             uint64_t *hits, double *seconds, tr_error *err) {
    return tr_device_trace_rays(dev, r->rays[kind], r->count[kind], kind == TR_RAY_SHADOW, reps,
                                hits, seconds, err);
}

int tr_ray_sets_trace_device_wide(const tr_ray_sets *r, tr_device *dev, const tr_scene *scene,
                                  int kind, int reps, uint64_t *hits, double *seconds,
                                  tr_error *err) {
    *hits = 0;
    *seconds = 0.0;
    tr_cl_context *cl = tr_device_cl_context(dev);
    if (!cl) {
        return tr_error_set(err, TR_STATUS_UNSUPPORTED, "the wide BVH is traced on OpenCL only");
    }
    const tr_scene_view v = tr_scene_view_of(scene);
    if (v.accel != TR_ACCEL_BVH) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the wide BVH is converted from a scene committed with a BVH");
    }
    tr_cwbvh cw;
    if (tr_cwbvh_build(&cw, v.bvh_nodes, v.bvh_node_count, v.bvh_tris, err) != TR_OK) {
        return TR_ERR;
    }
    const int rc = tr_cl_trace_rays_cwbvh(cl, &cw, r->rays[kind], r->count[kind],
                                          kind == TR_RAY_SHADOW, reps, hits, seconds, err);
    tr_cwbvh_free(&cw);
    return rc;
}

double tr_ray_sets_mrays_device(const tr_ray_sets *r, tr_device *dev, const tr_scene *scene,
                                int kind, int runs, int wide, uint64_t *hits, tr_error *err) {
    double *times = malloc((size_t)(runs > 0 ? runs : 1) * sizeof *times);
    if (!times) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
        return -1.0;
    }
    double one = 0.0;
    int reps = 1, rc = TR_OK;
    for (int run = -1; run < runs && rc == TR_OK; ++run) {
        double *t = run < 0 ? &one : &times[run]; /* run -1: the warm-up, which sets reps */
        rc = wide ? tr_ray_sets_trace_device_wide(r, dev, scene, kind, reps, hits, t, err)
                  : tr_ray_sets_trace_device(r, dev, kind, reps, hits, t, err);
        reps = run < 0 ? tr_ray_sets_reps(one) : reps;
    }
    const double m =
        rc == TR_OK ? (double)r->count[kind] * reps / tr_median(times, runs) * 1e-6 : -1.0;
    free(times);
    return m;
}

double tr_ray_sets_mrays(const tr_ray_sets *r, const tr_scene *scene, int kind, int threads,
                         int runs, uint64_t *hits, tr_error *err) {
    double *times = malloc((size_t)(runs > 0 ? runs : 1) * sizeof *times);
    if (!times) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
        return -1.0;
    }
    const int reps = tr_ray_sets_reps(tr_ray_sets_trace(r, scene, kind, threads, 1, hits));
    for (int run = 0; run < runs; ++run) {
        times[run] = tr_ray_sets_trace(r, scene, kind, threads, reps, hits);
    }
    const double m = (double)r->count[kind] * reps / tr_median(times, runs) * 1e-6;
    free(times);
    return m;
}

int tr_ray_sets_reps(double one_pass_seconds) {
    const double r = 0.05 / (one_pass_seconds > 1e-6 ? one_pass_seconds : 1e-6);
    return r < 1.0 ? 1 : r > 1000.0 ? 1000 : (int)r + 1;
}
