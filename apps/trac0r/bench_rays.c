/* bench_rays.c - `trac0r bench rays`: ray throughput of each acceleration structure on
 * the same rays: primary (coherent), diffuse bounces (incoherent) and shadow rays. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "devices.h"
#include "progress.h"
#include "trac0r/measure.h"

static void bench_rays_help(FILE *fp) {
    fprintf(fp, "Usage: trac0r bench rays [options]\n"
                "\n"
                "Mrays/s of each acceleration structure on the same primary, diffuse and shadow\n"
                "rays, on builtin:cornell, builtin:cornell-ico-6 and builtin:cornell-ico-8; the\n"
                "median of the runs, with build times. The full manual: man trac0r.\n"
                "\n"
                "Options:\n"
                "  --width W, --height H, --seed S, --threads T   as for render (default 800x600)\n"
                "  --scene SCENE        measure only this scene\n"
                "  --runs N             timed passes over each ray set, 1..1000 (default 5)\n"
                "  --accels LIST        structures to compare (default bvh,embree)\n"
                "  --device DEV         trace on this device: cpu (default) or opencl[:N]; a\n"
                "                       device compares flat,bvh (it walks the binary BVH)\n"
                "  -h, --help           show this help\n");
}

typedef struct rays_opts {
    int runs;
    accel_set set;
    int accels_given;
} rays_opts;

static int rays_option(cli_args *a, void *user) {
    rays_opts *o = user;
    if (cli_is(a, "--runs")) {
        return cli_parse_int(a, 1, 1000, &o->runs);
    }
    if (cli_is(a, "--accels")) {
        o->accels_given = 1;
        return bench_parse_accels(a, &o->set);
    }
    return -1;
}

/* Opens the device and keeps the structures it walks (one named by --accels that it
 * cannot walk is an error). */
static int rays_device_open(cli_args *a, const cli_common *c, rays_opts *o, cli_backend *be) {
    int rc = cli_backend_open(a, c, NULL, be);
    for (int k = 0; k < o->set.count && rc == CLI_OK; ++k) {
        if (tr_device_traces(be->dev, o->set.type[k])) {
            continue;
        }
        if (o->accels_given) {
            rc =
                cli_error(a, "--accels: %s runs on the CPU only; with --device %s compare flat,bvh",
                          tr_accel_name(o->set.type[k]), tr_device_kind(be->dev));
            cli_backend_close(be);
            return rc;
        }
        o->set.type[k--] = o->set.type[--o->set.count];
    }
    return rc;
}

/* On a device, the row of the compressed wide BVH converted from the binary one just
 * measured (bvh_hits: its hits), on the same rays, and a note where the hits differ. */
static int rays_wide_row(const tr_ray_sets *sets, tr_device *dev, const tr_scene *scene,
                         const char *name, int runs, const uint64_t *bvh_hits, tr_error *err) {
    double m[TR_RAY_KINDS];
    uint64_t hits[TR_RAY_KINDS];
    for (int kind = 0; kind < TR_RAY_KINDS; ++kind) {
        if ((m[kind] = tr_ray_sets_mrays_device(sets, dev, scene, kind, runs, 1, &hits[kind],
                                                err)) < 0.0) {
            return TR_ERR;
        }
    }
    printf("%-24s %10u %-7s %10s %10.2f %10.2f %10.2f\n", name, tr_scene_triangle_count(scene),
           "cwbvh", "-", m[TR_RAY_PRIMARY], m[TR_RAY_DIFFUSE], m[TR_RAY_SHADOW]);
    for (int kind = 0; kind < TR_RAY_KINDS; ++kind) {
        if (hits[kind] != bvh_hits[kind]) {
            printf("  note: %s rays: bvh hit %llu, cwbvh hit %llu\n", tr_ray_kind_name(kind),
                   (unsigned long long)bvh_hits[kind], (unsigned long long)hits[kind]);
        }
    }
    return TR_OK;
}

int bench_rays(int argc, char **argv) {
    cli_args a = {.cmd = "bench rays", .argc = argc, .argv = argv, .i = 0};
    cli_common c;
    cli_common_default(&c);
    rays_opts o = {5, {{TR_ACCEL_TYPE_FLAT}, 0}, 0};
    bench_accels_all(&o.set, 0);
    static const char *const refused[] = {"--accel", "--integrator", "--max-depth", NULL};
    int rc = cli_parse(&a, &c, refused, bench_rays_help, rays_option, &o);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? CLI_OK : rc;
    }
    const int runs = o.runs, one_scene = (c.given & CLI_GIVEN_SCENE) != 0;
    /* On a device the rays are traced there, with the structures it walks itself. */
    cli_backend be = {0};
    const int on_device = strcmp(c.device, "cpu") != 0;
    if (on_device && (rc = rays_device_open(&a, &c, &o, &be)) != CLI_OK) {
        return rc;
    }
    const accel_set set = o.set;
    const char *scenes[] = {"builtin:cornell", "builtin:cornell-ico-6", "builtin:cornell-ico-8"};
    const int scene_count = one_scene ? 1 : 3;
    const int threads = c.threads ? c.threads : tr_default_threads();
    if (on_device) {
        printf("bench rays: %ux%u rays per set, on %s, median of %d runs\n", c.width, c.height,
               be.name, runs);
    } else {
        printf("bench rays: %ux%u rays per set, %d thread%s, median of %d runs\n", c.width,
               c.height, threads, threads == 1 ? "" : "s", runs);
    }
    printf("%-24s %10s %-7s %10s %10s %10s %10s\n", "scene", "triangles", "accel", "build ms",
           "primary", "diffuse", "shadow");
    progress bar;
    progress_begin(
        &bar, "trac0r bench rays", "runs",
        (uint64_t)scene_count * (uint64_t)set.count * TR_RAY_KINDS * (uint64_t)(runs + 1), 0);
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
        tr_error err;
        tr_ray_sets *sets = tr_ray_sets_create(scene, c.seed, &err);
        if (!sets) {
            fprintf(stderr, "trac0r bench rays: %s\n", err.msg);
            rc = CLI_FAILURE;
        }
        double mrays[4][TR_RAY_KINDS] = {{0}};
        uint64_t hits[4][TR_RAY_KINDS] = {{0}};
        for (int k = 0; k < set.count && rc == CLI_OK; ++k) {
            if (tr_scene_commit(scene, set.type[k], &err) != TR_OK) {
                progress_clear(&bar);
                fprintf(stderr, "trac0r bench rays: %s\n", err.msg);
                rc = CLI_FAILURE;
                break;
            }
            if (on_device) {
                progress_clear(&bar);
                rc = cli_backend_upload(&a, &be, scene);
                if (rc != CLI_OK) {
                    break;
                }
            }
            int failed = 0;
            for (int kind = 0; kind < TR_RAY_KINDS && !failed; ++kind) {
                mrays[k][kind] = on_device ? tr_ray_sets_mrays_device(sets, be.dev, scene, kind,
                                                                      runs, 0, &hits[k][kind], &err)
                                           : tr_ray_sets_mrays(sets, scene, kind, threads, runs,
                                                               &hits[k][kind], &err);
                failed = mrays[k][kind] < 0.0;
                steps += (uint64_t)runs + 1u;
                progress_update(&bar, steps, NULL);
            }
            progress_clear(&bar);
            printf("%-24s %10u %-7s %10.1f %10.2f %10.2f %10.2f\n", sc_opts.scene,
                   tr_scene_triangle_count(scene), tr_accel_name(set.type[k]),
                   tr_scene_build_seconds(scene) * 1e3, mrays[k][TR_RAY_PRIMARY],
                   mrays[k][TR_RAY_DIFFUSE], mrays[k][TR_RAY_SHADOW]);
            fflush(stdout);
            failed = failed || (on_device && set.type[k] == TR_ACCEL_TYPE_BVH &&
                                rays_wide_row(sets, be.dev, scene, sc_opts.scene, runs, hits[k],
                                              &err) != TR_OK);
            if (failed) {
                progress_clear(&bar);
                fprintf(stderr, "trac0r bench rays: %s\n", err.msg);
                rc = CLI_FAILURE;
                break;
            }
            if (k > 0) {
                for (int kind = 0; kind < TR_RAY_KINDS; ++kind) {
                    if (hits[k][kind] != hits[0][kind]) {
                        printf("  note: %s rays: %s hit %llu, %s hit %llu\n",
                               tr_ray_kind_name(kind), tr_accel_name(set.type[0]),
                               (unsigned long long)hits[0][kind], tr_accel_name(set.type[k]),
                               (unsigned long long)hits[k][kind]);
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
                   mrays[bvh][TR_RAY_PRIMARY] / mrays[emb][TR_RAY_PRIMARY],
                   mrays[bvh][TR_RAY_DIFFUSE] / mrays[emb][TR_RAY_DIFFUSE],
                   mrays[bvh][TR_RAY_SHADOW] / mrays[emb][TR_RAY_SHADOW]);
        }
        tr_ray_sets_destroy(sets);
        tr_scene_destroy(scene);
    }
    progress_end(&bar);
    cli_backend_close(&be);
    return rc;
}
