/* bench.c - `trac0r bench`: speed measurements. Benchmarks, not tests: they report
 * medians over repeated runs and compare against references measured in the same run
 * or published in the thesis. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n) {
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static void bench_frame_help(void) {
    printf("Usage: trac0r bench frame [options]\n"
           "\n"
           "Renders the scene at 1 sample per pixel per frame (the thesis's frame) and\n"
           "prints the median frame time, frames per second and Mrays/s over the frames,\n"
           "after one warm-up frame. Defaults: the built-in Cornell box at 800x600, the\n"
           "naive integrator, the BVH, 20 frames (the thesis measured --accel flat).\n"
           "\n"
           "Options:\n"
           "%s"
           "  --frames N           frames to time, 1..100000 (default 20)\n"
           "  -h, --help           show this help\n"
           "\n"
           "The thesis (table 3.2) reports 11.6 FPS for this scene at 800x600 on an NVIDIA\n"
           "GeForce GTX 570.\n",
           cli_common_help);
}

static int bench_frame(int argc, char **argv) {
    cli_args a = {.cmd = "bench frame", .argc = argc, .argv = argv, .i = 0};
    cli_common c;
    cli_common_default(&c);
    int frames = 20;
    while (cli_next(&a)) {
        int rc = cli_common_option(&a, &c);
        if (rc == CLI_OK) {
            continue;
        }
        if (rc == CLI_USAGE) {
            return CLI_USAGE;
        }
        if (cli_is(&a, "-h") || cli_is(&a, "--help")) {
            bench_frame_help();
            return CLI_OK;
        } else if (cli_is(&a, "--frames")) {
            rc = cli_parse_int(&a, 1, 100000, &frames);
        } else {
            return cli_error(&a, "unknown option '%s' (see 'trac0r bench frame --help')", a.opt);
        }
        if (rc != CLI_OK) {
            return CLI_USAGE;
        }
    }
    tr_scene scene;
    int rc = cli_load_scene(&a, &c, &scene);
    if (rc != CLI_OK) {
        return rc;
    }
    tr_error err;
    tr_film film;
    double *times = malloc((size_t)frames * sizeof *times);
    if (!times || tr_film_init(&film, c.width, c.height, &err) != TR_OK) {
        free(times);
        tr_scene_free(&scene);
        return cli_error(&a, "--width/--height: %s", times ? err.msg : "out of memory");
    }
    tr_render_config cfg = tr_render_config_default();
    cfg.max_depth = c.max_depth;
    cfg.seed = c.seed;
    cfg.threads = c.threads;
    cfg.integrator = c.integrator;
    const int threads = cfg.threads ? cfg.threads : tr_default_threads();

    char accel[160];
    cli_describe_accel(accel, sizeof accel, &scene);
    printf("bench frame: %s, %ux%u, 1 spp/frame, integrator naive, max depth %d, %d thread%s, "
           "%u triangles, accel %s\n",
           c.scene, c.width, c.height, c.max_depth, threads, threads == 1 ? "" : "s",
           scene.triangle_count, accel);
    uint64_t rays = 0;
    double total = 0.0;
    rc = CLI_OK;
    /* Frame 0 warms caches and the thread pool and is not timed. */
    for (int f = 0; f <= frames && rc == CLI_OK; ++f) {
        tr_render_stats st;
        if (tr_render_frame(&scene, &scene.camera, &cfg, &film, (uint32_t)f, &st, &err) != TR_OK) {
            fprintf(stderr, "trac0r bench frame: %s\n", err.msg);
            rc = CLI_FAILURE;
        } else if (f > 0) {
            times[f - 1] = st.seconds;
            rays += st.rays;
            total += st.seconds;
        }
    }
    if (rc == CLI_OK) {
        double mrays = (double)rays / total * 1e-6;
        double med = median(times, frames);
        printf("frames %d  median %.2f ms  min %.2f ms  max %.2f ms\n", frames, med * 1e3,
               times[0] * 1e3, times[frames - 1] * 1e3);
        printf("fps %.2f (median)  Mrays/s %.2f (mean)\n", 1.0 / med, mrays);
        printf("thesis (table 3.2): 11.6 fps on a GeForce GTX 570 -> ratio %.2f\n",
               (1.0 / med) / 11.6);
    }
    free(times);
    tr_film_free(&film);
    tr_scene_free(&scene);
    return rc;
}

static void bench_help(FILE *fp) {
    fprintf(fp, "Usage: trac0r bench BENCHMARK [options]\n"
                "\n"
                "Benchmarks:\n"
                "  frame    median frame time, FPS and Mrays/s of the built-in scene\n"
                "\n"
                "Run 'trac0r bench BENCHMARK --help' for its options.\n");
}

int cmd_bench(int argc, char **argv) {
    if (argc < 2) {
        bench_help(stderr);
        return CLI_USAGE;
    }
    if (strcmp(argv[1], "frame") == 0) {
        return bench_frame(argc - 1, argv + 1);
    }
    if (strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0) {
        bench_help(stdout);
        return CLI_OK;
    }
    fprintf(stderr, "trac0r bench: unknown benchmark '%s' (available: frame)\n", argv[1]);
    return CLI_USAGE;
}
