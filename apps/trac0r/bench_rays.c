/* bench_rays.c - `trac0r bench rays`: ray throughput of each acceleration structure on
 * the same rays: primary (coherent), diffuse bounces (incoherent) and shadow rays. */
#define _POSIX_C_SOURCE 200809L
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "progress.h"
/* The one app file that still reaches into the library (CMakeLists.txt): it traces its
 * rays with the kernel's functions through tr_scene_view_of. */
#include "kernel/kernel.h"
#include "scene/scene_internal.h"

typedef struct ray_set {
    tr_ray *rays;
    uint32_t count;
} ray_set;

enum { PRIMARY, DIFFUSE, SHADOW, KINDS };
static const char *const kind_name[KINDS] = {"primary", "diffuse", "shadow"};

/* Area-weighted emitter triangles, for aiming shadow rays at the lights. */
typedef struct emitters {
    uint32_t *tri;
    float *cdf;
    uint32_t count;
} emitters;

static int collect_emitters(const tr_scene *s, emitters *e) {
    const uint32_t n = tr_scene_triangle_count(s);
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
    float x = tr_rng_float(r) * e->cdf[e->count - 1];
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

/* Makes the three ray sets from one camera pass traced with the BVH: primary rays
 * through jittered pixel positions; at each primary hit, a cosine-weighted bounce and a
 * shadow ray towards a random point on an emitter. Every set is the same for every
 * structure it is then traced with. */
static int make_rays(const tr_scene *s, uint64_t seed, ray_set sets[KINDS]) {
    const tr_camera *cam = tr_scene_camera(s);
    const uint32_t n = cam->screen_width * cam->screen_height;
    for (int k = 0; k < KINDS; ++k) {
        sets[k].rays = malloc((size_t)n * sizeof *sets[k].rays);
        sets[k].count = 0;
        if (!sets[k].rays) {
            return TR_ERR;
        }
    }
    emitters e;
    if (collect_emitters(s, &e) != TR_OK) {
        free(e.tri);
        free(e.cdf);
        return TR_ERR;
    }
    const tr_scene_view view = tr_scene_view_of(s);
    for (uint32_t i = 0; i < n; ++i) {
        tr_rng r;
        tr_rng_init(&r, seed, i, 0);
        float jx, jy;
        tr_sample_pixel_jitter(&r, &jx, &jy);
        tr_ray ray = tr_camera_ray(cam, (float)(i % cam->screen_width),
                                   (float)(i / cam->screen_width), jx, jy);
        sets[PRIMARY].rays[sets[PRIMARY].count++] = ray;
        tr_hit hit;
        if (!tr_intersect_scene(&view, &ray, &hit)) {
            continue;
        }
        tr_vec3 p = v3_madd(ray.origin, ray.dir, hit.t);
        tr_vec3 n_geo = tr_scene_triangle(s, hit.triangle).normal;
        tr_vec3 nf = v3_dot(n_geo, ray.dir) > 0.0f ? v3_neg(n_geo) : n_geo;
        tr_vec3 o = tr_offset_origin(p, nf);
        sets[DIFFUSE].rays[sets[DIFFUSE].count++] =
            tr_ray_make(o, tr_sample_cosine_hemisphere(&r, nf), 0.0f, TR_INFINITY);
        if (e.count > 0) {
            tr_vec3 d = v3_sub(sample_emitter(s, &e, &r), o);
            float dist = v3_length(d);
            if (dist > 0.0f) {
                /* Stop just short of the light so that the light itself is no occluder. */
                sets[SHADOW].rays[sets[SHADOW].count++] =
                    tr_ray_make(o, v3_scale(d, 1.0f / dist), 0.0f, dist * 0.999f);
            }
        }
    }
    free(e.tri);
    free(e.cdf);
    return TR_OK;
}

/* Seconds to trace every ray of the set `reps` times; the hit count of one pass goes to
 * *hits so the work cannot be optimised away and the structures can be cross-checked. */
static double trace_set(const tr_scene *s, const ray_set *set, int shadow, int threads, int reps,
                        uint64_t *hits) {
    const tr_scene_view view = tr_scene_view_of(s);
    uint64_t h = 0;
    double t0 = tr_time_now();
    for (int rep = 0; rep < reps; ++rep) {
        h = 0;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 1024) reduction(+ : h)
        for (int64_t i = 0; i < (int64_t)set->count; ++i) {
            if (shadow) {
                h += (uint64_t)tr_occluded_scene(&view, &set->rays[i]);
            } else {
                tr_hit hit;
                h += (uint64_t)tr_intersect_scene(&view, &set->rays[i], &hit);
            }
        }
    }
    *hits = h;
    return tr_time_now() - t0;
}

/* A timed run traces the set this often, so that it lasts at least MIN_RUN_SECONDS (the
 * warm-up pass measures one): runs of a few milliseconds would be at the mercy of the
 * scheduler's time slice on a loaded machine. */
#define MIN_RUN_SECONDS 0.05
static int reps_for(double one_pass_seconds) {
    double r = MIN_RUN_SECONDS / (one_pass_seconds > 1e-6 ? one_pass_seconds : 1e-6);
    return r < 1.0 ? 1 : r > 1000.0 ? 1000 : (int)r + 1;
}

static void bench_rays_help(void) {
    printf("Usage: trac0r bench rays [options]\n"
           "\n"
           "Million rays per second of each acceleration structure on the same rays: primary\n"
           "rays (one per pixel), diffuse bounces (cosine-weighted, incoherent) and shadow\n"
           "rays (any-hit, towards the lights), on builtin:cornell, builtin:cornell-ico-6 and\n"
           "builtin:cornell-ico-8 (1.3 M triangles). Each figure is the median of the runs\n"
           "(a run traces its set as often as it takes to last at least 50 ms);\n"
           "build times are reported beside them, and the ratio bvh/embree when both run.\n"
           "\n"
           "Options:\n"
           "  --width W, --height H, --seed S, --threads T   as for render (default 800x600)\n"
           "  --scene SCENE        measure only this scene\n"
           "  --runs N             timed passes over each ray set, 1..1000 (default 5)\n"
           "  --accels LIST        structures to compare (default: bvh,embree, those this\n"
           "                       build has; flat is only practical on small scenes; bvh2\n"
           "                       is the binary BVH without its SIMD wide form)\n"
           "  -h, --help           show this help\n");
}

int bench_rays(int argc, char **argv) {
    cli_args a = {.cmd = "bench rays", .argc = argc, .argv = argv, .i = 0};
    cli_common c;
    cli_common_default(&c);
    int runs = 5, one_scene = 0;
    accel_set set;
    bench_accels_all(&set, 0);
    while (cli_next(&a)) {
        int rc = cli_common_option(&a, &c);
        if (rc == CLI_OK && (cli_is(&a, "--accel") || cli_is(&a, "--integrator") ||
                             cli_is(&a, "--max-depth") || cli_is(&a, "--device"))) {
            return cli_error(&a, "%s: not an option of this benchmark", a.opt);
        }
        if (rc == CLI_OK) {
            one_scene |= cli_is(&a, "--scene");
            continue;
        }
        if (rc == CLI_USAGE) {
            return CLI_USAGE;
        }
        if (cli_is(&a, "-h") || cli_is(&a, "--help")) {
            bench_rays_help();
            return CLI_OK;
        } else if (cli_is(&a, "--runs")) {
            rc = cli_parse_int(&a, 1, 1000, &runs);
        } else if (cli_is(&a, "--accels")) {
            rc = bench_parse_accels(&a, &set);
        } else {
            return cli_unknown(&a);
        }
        if (rc != CLI_OK) {
            return CLI_USAGE;
        }
    }
    const char *scenes[] = {"builtin:cornell", "builtin:cornell-ico-6", "builtin:cornell-ico-8"};
    const int scene_count = one_scene ? 1 : 3;
    const int threads = c.threads ? c.threads : tr_default_threads();
    double *times = malloc((size_t)runs * sizeof *times);
    if (!times) {
        return cli_error(&a, "out of memory");
    }
    printf("bench rays: %ux%u rays per set, %d thread%s, median of %d runs\n", c.width, c.height,
           threads, threads == 1 ? "" : "s", runs);
    printf("%-24s %10s %-7s %10s %10s %10s %10s\n", "scene", "triangles", "accel", "build ms",
           "primary", "diffuse", "shadow");
    int rc = CLI_OK;
    progress bar;
    progress_begin(&bar, "trac0r bench rays", "runs",
                   (uint64_t)scene_count * (uint64_t)set.count * KINDS * (uint64_t)(runs + 1), 0);
    uint64_t steps = 0;
    for (int sc = 0; sc < scene_count && rc == CLI_OK; ++sc) {
        cli_common sc_opts = c;
        if (!one_scene) {
            sc_opts.scene = scenes[sc];
        }
        sc_opts.accel = TR_ACCEL_TYPE_BVH; /* the rays are generated with the BVH */
        tr_scene *scene = tr_scene_create(NULL);
        progress_clear(&bar); /* before any message of the loader */
        rc = cli_load_scene(&a, &sc_opts, scene);
        if (rc != CLI_OK) {
            tr_scene_destroy(scene);
            break;
        }
        ray_set sets[KINDS] = {{0}};
        if (make_rays(scene, c.seed, sets) != TR_OK) {
            fprintf(stderr, "trac0r bench rays: out of memory generating rays\n");
            rc = CLI_FAILURE;
        }
        double mrays[4][KINDS] = {{0}};
        uint64_t hits[4][KINDS] = {{0}};
        tr_error err;
        for (int k = 0; k < set.count && rc == CLI_OK; ++k) {
            if (tr_scene_commit(scene, set.type[k], &err) != TR_OK) {
                progress_clear(&bar);
                fprintf(stderr, "trac0r bench rays: %s\n", err.msg);
                rc = CLI_FAILURE;
                break;
            }
            for (int kind = 0; kind < KINDS; ++kind) {
                int reps = reps_for(trace_set(scene, &sets[kind], kind == SHADOW, threads, 1,
                                              &hits[k][kind])); /* warm-up */
                progress_update(&bar, ++steps, NULL);
                for (int r = 0; r < runs; ++r) {
                    times[r] = trace_set(scene, &sets[kind], kind == SHADOW, threads, reps,
                                         &hits[k][kind]);
                    progress_update(&bar, ++steps, NULL);
                }
                mrays[k][kind] = (double)sets[kind].count * reps / bench_median(times, runs) * 1e-6;
            }
            progress_clear(&bar);
            printf("%-24s %10u %-7s %10.1f %10.2f %10.2f %10.2f\n", sc_opts.scene,
                   tr_scene_triangle_count(scene), tr_accel_name(set.type[k]),
                   bench_build_seconds(scene) * 1e3, mrays[k][PRIMARY], mrays[k][DIFFUSE],
                   mrays[k][SHADOW]);
            fflush(stdout);
            if (k > 0) {
                for (int kind = 0; kind < KINDS; ++kind) {
                    if (hits[k][kind] != hits[0][kind]) {
                        printf("  note: %s rays: %s hit %llu, %s hit %llu\n", kind_name[kind],
                               tr_accel_name(set.type[0]), (unsigned long long)hits[0][kind],
                               tr_accel_name(set.type[k]), (unsigned long long)hits[k][kind]);
                    }
                }
            }
        }
        int bvh = -1, emb = -1;
        for (int k = 0; k < set.count; ++k) {
            bvh = set.type[k] == TR_ACCEL_TYPE_BVH ? k : bvh;
            emb = set.type[k] == TR_ACCEL_TYPE_EMBREE ? k : emb;
        }
        if (rc == CLI_OK && bvh >= 0 && emb >= 0) {
            printf("%-24s %10s %-7s %10s %10.2f %10.2f %10.2f\n", "", "", "bvh/emb", "",
                   mrays[bvh][PRIMARY] / mrays[emb][PRIMARY],
                   mrays[bvh][DIFFUSE] / mrays[emb][DIFFUSE],
                   mrays[bvh][SHADOW] / mrays[emb][SHADOW]);
        }
        for (int kind = 0; kind < KINDS; ++kind) {
            free(sets[kind].rays);
        }
        tr_scene_destroy(scene);
    }
    progress_end(&bar);
    free(times);
    return rc;
}
