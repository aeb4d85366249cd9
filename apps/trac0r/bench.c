/* bench.c - `trac0r bench`: speed measurements. Benchmarks, not tests: they report
 * medians over repeated runs and compare against references measured in the same run
 * or published in the thesis. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "bench.h"
#include "progress.h"
#include "commands.h"
#include "devices.h"
#include "trac0r/outfile.h"

/* A step of a benchmark failed: clears the progress bar and says why. */
static int bench_failed(progress *bar, const cli_args *a, const char *what, const tr_error *err) {
    progress_clear(bar);
    fprintf(stderr, "trac0r %s: %s%s\n", a->cmd, what, err->msg);
    return CLI_FAILURE;
}

static void bench_frame_help(FILE *fp) {
    fprintf(fp,
            "Usage: trac0r bench frame [options]\n"
            "\n"
            "The thesis's frame: median frame time, FPS and Mrays/s at 1 spp per frame\n"
            "(default: builtin:cornell, 800x600, naive, bvh). With --device opencl the same\n"
            "frames on the CPU too, and the ratio. The full manual: man trac0r.\n"
            "\n"
            "Options:\n"
            "%s"
            "  --frames N           frames to time, 1..100000 (default 20)\n"
            "  --animate            the scene's last shape moves before every frame\n"
            "  -h, --help           show this help\n",
            cli_common_help());
}

/* bench frame: its options, what it renders on, and what it measures. */
typedef struct frame_bench {
    cli_args a;
    cli_common c;
    int frames;  /* timed frames, after one warm-up frame */
    int animate; /* --animate: the scene changes before every frame */
    tr_scene *scene;
    cli_backend be, cpu; /* cpu: beside a device, the same frames on the CPU (else no dev) */
    tr_render_config cfg;
    progress bar;
    double *times, *update_times, *cpu_times; /* one per timed frame */
    uint64_t rays;
    double total; /* seconds of the timed frames */
} frame_bench;

/* One of bench frame's own options: CLI_OK, CLI_USAGE, or -1 if it is none of them. */
static int frame_option(cli_args *a, void *bench) {
    frame_bench *b = bench;
    if (cli_is(a, "--animate")) {
        b->animate = 1;
        return CLI_OK;
    }
    return cli_is(a, "--frames") ? cli_parse_int(a, 1, 100000, &b->frames) : -1;
}

/* The scene, the storage of the times, the image size, the device, and on a device the
 * CPU beside it (the reference its speed is reported against, under the same load). */
static int frame_open(frame_bench *b) {
    int rc = cli_load_scene(&b->a, &b->c, b->scene);
    if (rc != CLI_OK) {
        return rc;
    }
    if (!(b->times = malloc((size_t)b->frames * 3 * sizeof *b->times))) {
        fprintf(stderr, "trac0r bench frame: out of memory\n");
        return CLI_FAILURE;
    }
    b->update_times = b->times + b->frames;
    b->cpu_times = b->update_times + b->frames;
    tr_error err;
    if (tr_film_check_size(b->c.width, b->c.height, &err) != TR_OK) {
        return cli_error(&b->a, "--width/--height: %s", err.msg);
    }
    if ((rc = cli_backend_open(&b->a, &b->c, b->scene, &b->be)) != CLI_OK) {
        return rc;
    }
    b->cfg = cli_render_config(&b->c);
    char accel[160];
    tr_scene_accel_describe(b->scene, 1, accel, sizeof accel);
    printf("bench frame: %s, %ux%u, 1 spp/frame, integrator %s, max depth %d, %s, "
           "%u triangles, accel %s\n",
           b->c.scene, b->c.width, b->c.height, tr_integrator_name(b->c.integrator),
           b->c.max_depth ? b->c.max_depth : tr_default_max_depth(b->c.integrator), b->be.name,
           tr_scene_triangle_count(b->scene), accel);
    if (tr_device_caps(b->be.dev) & TR_DEVICE_CAP_HOST) {
        return CLI_OK;
    }
    cli_common cc = b->c;
    snprintf(cc.device, sizeof cc.device, "cpu");
    return cli_backend_open(&b->a, &cc, b->scene, &b->cpu);
}

/* --animate: the scene's change and its uploads (timed together), then a new image. */
static int frame_update(frame_bench *b, int f) {
    tr_error err;
    const double t0 = tr_time_now();
    if (tr_scene_animate_sway(b->scene, (uint32_t)f, &err) != TR_OK ||
        tr_scene_update(b->scene, NULL, &err) != TR_OK) {
        return bench_failed(&b->bar, &b->a, "--animate: ", &err);
    }
    int rc;
    if ((rc = cli_backend_upload(&b->a, &b->be, b->scene)) != CLI_OK ||
        (b->cpu.dev && (rc = cli_backend_upload(&b->a, &b->cpu, b->scene)) != CLI_OK)) {
        return rc;
    }
    if (f > 0) {
        b->update_times[f - 1] = tr_time_now() - t0;
    }
    return tr_device_clear(b->be.dev, &err) != TR_OK ? bench_failed(&b->bar, &b->a, "", &err)
                                                     : CLI_OK;
}

/* Frame f (0: the warm-up, not timed) on the device, and on the CPU beside it. */
static int frame_render(frame_bench *b, int f) {
    int rc = b->animate ? frame_update(b, f) : CLI_OK;
    tr_render_stats st;
    tr_error err;
    if (rc != CLI_OK) {
        return rc;
    }
    if (tr_device_render(b->be.dev, tr_scene_camera(b->scene), &b->cfg, (uint32_t)f, 1, NULL, &st,
                         &err) != TR_OK) {
        return bench_failed(&b->bar, &b->a, "", &err);
    }
    if (f > 0) {
        b->times[f - 1] = st.seconds;
        b->rays += st.rays;
        b->total += st.seconds;
    }
    if (b->cpu.dev && tr_device_render(b->cpu.dev, tr_scene_camera(b->scene), &b->cfg, (uint32_t)f,
                                       1, NULL, &st, &err) != TR_OK) {
        return bench_failed(&b->bar, &b->a, "", &err);
    }
    if (b->cpu.dev && f > 0) {
        b->cpu_times[f - 1] = st.seconds;
    }
    return CLI_OK;
}

static int frame_measure(frame_bench *b) {
    progress_begin(&b->bar, "trac0r bench frame", "frames", (uint64_t)b->frames + 1, 0);
    int rc = CLI_OK;
    for (int f = 0; f <= b->frames && rc == CLI_OK; ++f) {
        if (f > 0) {
            progress_update(&b->bar, (uint64_t)f, NULL);
        }
        rc = frame_render(b, f);
    }
    if (rc == CLI_OK) {
        progress_update(&b->bar, (uint64_t)b->frames + 1, NULL);
    }
    progress_end(&b->bar);
    return rc;
}

static void frame_report(frame_bench *b) {
    const int n = b->frames;
    const double med = tr_median(b->times, n);
    printf("frames %d  median %.2f ms  min %.2f ms  max %.2f ms\n", n, med * 1e3, b->times[0] * 1e3,
           b->times[n - 1] * 1e3);
    printf("fps %.2f (median)  Mrays/s %.2f (mean)\n", 1.0 / med,
           (double)b->rays / b->total * 1e-6);
    if (b->animate) {
        const double umed = tr_median(b->update_times, n);
        printf("scene update per frame (%s%s): median %.3f ms  min %.3f ms  max %.3f ms; "
               "frame + update %.2f ms (%.2f fps)\n",
               tr_scene_update_kind(b->scene),
               (tr_device_caps(b->be.dev) & TR_DEVICE_CAP_SCENE_COPY) != 0u
                   ? " + upload to the device"
                   : "",
               umed * 1e3, b->update_times[0] * 1e3, b->update_times[n - 1] * 1e3,
               (med + umed) * 1e3, 1.0 / (med + umed));
    }
    printf("thesis (table 3.2): 11.6 fps on a GeForce GTX 570 -> ratio %.2f\n", (1.0 / med) / 11.6);
    if (b->cpu.dev) {
        const int threads = b->cfg.threads ? b->cfg.threads : tr_default_threads();
        const double cpu_med = tr_median(b->cpu_times, n);
        printf("cpu (%d thread%s, interleaved with the device's frames): median %.2f ms, "
               "fps %.2f -> device/cpu %.2f\n",
               threads, threads == 1 ? "" : "s", cpu_med * 1e3, 1.0 / cpu_med, cpu_med / med);
    }
}

static int bench_frame(int argc, char **argv) {
    frame_bench b = {.a = {.cmd = "bench frame", .argc = argc, .argv = argv}, .frames = 20};
    cli_common_default(&b.c);
    b.c.integrator = TR_INTEGRATOR_NAIVE; /* the thesis's frame */
    int rc = cli_parse(&b.a, &b.c, NULL, bench_frame_help, frame_option, &b);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? CLI_OK : rc;
    }
    b.scene = tr_scene_create(NULL);
    if ((rc = frame_open(&b)) == CLI_OK && (rc = frame_measure(&b)) == CLI_OK) {
        frame_report(&b);
    }
    cli_backend_close(&b.cpu);
    cli_backend_close(&b.be);
    free(b.times);
    tr_scene_destroy(b.scene);
    return rc;
}

int bench_parse_accels(cli_args *a, accel_set *set) {
    int t[sizeof set->type / sizeof set->type[0]];
    set->count = cli_parse_list(a, tr_accel_from_name, t, (int)(sizeof t / sizeof t[0]),
                                "acceleration structure", NULL);
    for (int k = 0; k < set->count; ++k) {
        if (!tr_accel_available((tr_accel_type)t[k])) {
            return cli_error(a, "%s: '%s' is not available in this build", a->opt,
                             tr_accel_name((tr_accel_type)t[k]));
        }
        set->type[k] = (tr_accel_type)t[k];
    }
    return set->count < 0 ? CLI_USAGE : CLI_OK;
}

void bench_accels_all(accel_set *set, int with_flat) {
    const tr_accel_type all[] = {TR_ACCEL_TYPE_FLAT, TR_ACCEL_TYPE_BVH, TR_ACCEL_TYPE_EMBREE};
    set->count = 0;
    for (int i = with_flat ? 0 : 1; i < 3; ++i) {
        if (tr_accel_available(all[i])) {
            set->type[set->count++] = all[i];
        }
    }
}

static void bench_complexity_help(FILE *fp) {
    fprintf(fp,
            "Usage: trac0r bench complexity [options]\n"
            "\n"
            "The thesis's figure 3.5: FPS against triangle count (builtin:cornell-ico-N) per\n"
            "acceleration structure; writes PREFIX.csv and PREFIX.png. The full manual: man\n"
            "trac0r.\n"
            "\n"
            "Options:\n"
            "  --width W, --height H, --max-depth D, --seed S, --threads T, --device DEV\n"
            "                       as for render (default 800x600)\n"
            "  --max-level L        highest subdivision level, 0..%d (default 8)\n"
            "  --frames N           timed frames per point, 1..1000 (default 5)\n"
            "  --builds N           timed builds per point, 1..%d, median shown (default 3)\n"
            "  --accels LIST        structures to compare (default flat,bvh,embree)\n"
            "  --limit SECONDS      drop a structure after a slower frame (default 10)\n"
            "  --out PREFIX         output file prefix (default complexity)\n"
            "  -h, --help           show this help\n",
            TR_ICOSPHERE_MAX_SUBDIVISIONS, TR_MEASURE_MAX_BUILDS);
}

#define CX_MAX_FRAMES 1000
#define CX_LEVELS (TR_ICOSPHERE_MAX_SUBDIVISIONS + 1)

/* bench complexity: its options, the device, and the results for the CSV and the plot. */
typedef struct cx_bench {
    cli_args a;
    cli_common c;
    int frames, max_level, builds;
    float limit; /* a frame slower than this (seconds) drops its structure */
    const char *prefix;
    accel_set set;
    int accels_given;
    char csv_path[4096], png_path[4096];
    cli_backend be;
    tr_render_config cfg;
    progress bar;
    uint32_t tris[CX_LEVELS];
    double fps[CX_LEVELS][4]; /* [level][structure], 0: not measured */
    double build_ms[CX_LEVELS][4];
    int dropped[4]; /* a frame was slower than the limit: no higher levels */
} cx_bench;

/* One of bench complexity's own options: CLI_OK, CLI_USAGE, or -1 if it is none of them. */
static int cx_option(cli_args *a, void *bench) {
    cx_bench *b = bench;
    if (cli_is(a, "--frames") || cli_is(a, "--builds")) {
        const int frames = cli_is(a, "--frames");
        return cli_parse_int(a, 1, frames ? CX_MAX_FRAMES : TR_MEASURE_MAX_BUILDS,
                             frames ? &b->frames : &b->builds);
    }
    if (cli_is(a, "--max-level")) {
        return cli_parse_int(a, 0, TR_ICOSPHERE_MAX_SUBDIVISIONS, &b->max_level);
    }
    if (cli_is(a, "--limit")) {
        return cli_parse_float(a, 0.001f, 1e6f, &b->limit);
    }
    if (cli_is(a, "--accels")) {
        b->accels_given = 1;
        return bench_parse_accels(a, &b->set);
    }
    if (!cli_is(a, "--out")) {
        return -1;
    }
    const int rc = cli_value(a);
    b->prefix = a->value;
    return rc;
}

/* Before any work: the output files can be written, the image size is valid, and the
 * device walks the structures itself (Embree is host-only): one given with --accels that
 * it cannot walk is refused, one of the defaults is left out. */
static int cx_open(cx_bench *b) {
    snprintf(b->csv_path, sizeof b->csv_path, "%s.csv", b->prefix);
    snprintf(b->png_path, sizeof b->png_path, "%s.png", b->prefix);
    tr_error err;
    if (tr_image_check_writable(b->csv_path, &err) != TR_OK ||
        tr_image_check_writable(b->png_path, &err) != TR_OK) {
        return cli_error(&b->a, "--out: %s", err.msg);
    }
    if (tr_film_check_size(b->c.width, b->c.height, &err) != TR_OK) {
        return cli_error(&b->a, "--width/--height: %s", err.msg);
    }
    int rc = cli_backend_open(&b->a, &b->c, NULL, &b->be);
    for (int k = 0; k < b->set.count && rc == CLI_OK; ++k) {
        if (tr_device_traces(b->be.dev, b->set.type[k])) {
            continue;
        }
        if (b->accels_given) {
            return cli_error(&b->a,
                             "--accels: %s runs on the CPU only; with --device %s compare flat,bvh",
                             tr_accel_name(b->set.type[k]), tr_device_kind(b->be.dev));
        }
        b->set.type[k] = b->set.type[--b->set.count];
        --k; /* the structure moved into place k is checked next */
    }
    return rc;
}

/* One point: the scene committed with structure k, timed over a warm-up frame and
 * b->frames more, and its row of the table (its build time: tr_measure_builds). */
static int cx_point(cx_bench *b, tr_scene *scene, int level, int k) {
    tr_error err;
    if (tr_scene_commit(scene, b->set.type[k], &err) != TR_OK) {
        return bench_failed(&b->bar, &b->a, "", &err);
    }
    const int rc = cli_backend_upload(&b->a, &b->be, scene);
    if (rc != CLI_OK) {
        return rc;
    }
    if (tr_device_clear(b->be.dev, &err) != TR_OK) {
        return bench_failed(&b->bar, &b->a, "", &err);
    }
    double times[CX_MAX_FRAMES];
    int n = 0;
    for (int f = 0; f <= b->frames; ++f) {
        tr_render_stats st;
        if (tr_device_render(b->be.dev, tr_scene_camera(scene), &b->cfg, (uint32_t)f, 1, NULL, &st,
                             &err) != TR_OK) {
            return bench_failed(&b->bar, &b->a, "", &err);
        }
        if (st.seconds > b->limit) {
            /* Too slow to repeat: this frame is the measurement, and the structure sits
             * out the larger scenes. */
            times[0] = st.seconds;
            n = 1;
            b->dropped[k] = 1;
            break;
        }
        if (f > 0) {
            times[n++] = st.seconds;
        }
    }
    const double med = tr_median(times, n);
    b->fps[level][k] = 1.0 / med;
    progress_clear(&b->bar);
    printf("%5d %10u %-7s %10.1f %12.2f %9.3f%s\n", level, tr_scene_triangle_count(scene),
           tr_accel_name(b->set.type[k]), b->build_ms[level][k], med * 1e3, 1.0 / med,
           b->dropped[k] ? "  (slower than the limit: dropped for higher levels)" : "");
    fflush(stdout);
    return CLI_OK;
}

/* Each level's scene, and its point for each structure still in. */
static int cx_measure(cx_bench *b) {
    const uint64_t per_level = (uint64_t)b->set.count;
    progress_begin(&b->bar, "trac0r bench complexity", "steps",
                   (uint64_t)(b->max_level + 1) * per_level, 0);
    int rc = CLI_OK;
    for (int level = 0; level <= b->max_level && rc == CLI_OK; ++level) {
        progress_update(&b->bar, (uint64_t)level * per_level, NULL);
        char name[32];
        snprintf(name, sizeof name, "cornell-ico-%d", level);
        tr_error err;
        tr_scene *scene = tr_scene_create(&err);
        if (!scene || tr_scene_builtin(scene, name, b->c.width, b->c.height, &err) != TR_OK) {
            rc = bench_failed(&b->bar, &b->a, "", &err);
        } else {
            b->tris[level] = tr_scene_triangle_count(scene);
            rc = tr_measure_builds(scene, b->set.type, b->dropped, b->set.count, b->builds,
                                   b->build_ms[level], &err) != TR_OK
                     ? bench_failed(&b->bar, &b->a, "", &err)
                     : CLI_OK;
        }
        for (int k = 0; k < b->set.count && rc == CLI_OK; ++k) {
            rc = b->dropped[k] ? CLI_OK : cx_point(b, scene, level, k);
        }
        tr_scene_destroy(scene);
    }
    if (rc == CLI_OK) {
        progress_update(&b->bar, (uint64_t)(b->max_level + 1) * per_level, NULL);
    }
    progress_end(&b->bar);
    return rc;
}

/* The CSV: one row per (level, structure) measured. */
static int cx_write_csv(cx_bench *b) {
    tr_error err;
    tr_outfile *csv = tr_outfile_create(b->csv_path, &err);
    if (!csv) {
        return bench_failed(&b->bar, &b->a, "", &err);
    }
    FILE *fp = tr_outfile_stream(csv);
    fprintf(fp, "level,triangles,accel,build_ms,fps\n");
    for (int level = 0; level <= b->max_level; ++level) {
        for (int k = 0; k < b->set.count; ++k) {
            if (b->fps[level][k] > 0.0) {
                fprintf(fp, "%d,%u,%s,%.3f,%.5f\n", level, b->tris[level],
                        tr_accel_name(b->set.type[k]), b->build_ms[level][k], b->fps[level][k]);
            }
        }
    }
    return tr_outfile_commit(csv, &err) != TR_OK ? bench_failed(&b->bar, &b->a, "", &err) : CLI_OK;
}

/* The plot: one inline data block per structure, so each draws as one connected line. */
static int cx_write_plot(cx_bench *b) {
    char script[8192];
    size_t len = 0;
    for (int k = 0; k < b->set.count; ++k) {
        bench_plot_put(script, sizeof script, &len, "$d%d << EOD\n", k);
        for (int level = 0; level <= b->max_level; ++level) {
            if (b->fps[level][k] > 0.0) {
                bench_plot_put(script, sizeof script, &len, "%u %.5f\n", b->tris[level],
                               b->fps[level][k]);
            }
        }
        bench_plot_put(script, sizeof script, &len, "EOD\n");
    }
    bench_plot_put(script, sizeof script, &len,
                   "set logscale xy\nset grid\nset xlabel 'triangles'\n"
                   "set ylabel 'frames per second (%ux%u, 1 spp)'\n"
                   "set title 'trac0r bench complexity (thesis figure 3.5)'\n"
                   "set key top right\nplot ",
                   b->c.width, b->c.height);
    for (int k = 0; k < b->set.count; ++k) {
        bench_plot_put(script, sizeof script, &len, "%s$d%d with linespoints lw 2 title '%s'",
                       k ? ", " : "", k, tr_accel_name(b->set.type[k]));
    }
    tr_error err;
    const int plotted = len < sizeof script ? bench_plot_png(script, b->png_path, &err) : 0;
    if (plotted < 0) {
        return bench_failed(&b->bar, &b->a, "", &err);
    }
    printf("wrote %s%s%s\n", b->csv_path, plotted ? " and " : " (gnuplot failed: no plot)",
           plotted ? b->png_path : "");
    return CLI_OK;
}

static int bench_complexity(int argc, char **argv) {
    cx_bench b = {.a = {.cmd = "bench complexity", .argc = argc, .argv = argv},
                  .frames = 5,
                  .builds = 3,
                  .max_level = 8,
                  .limit = 10.0f,
                  .prefix = "complexity"};
    cli_common_default(&b.c);
    bench_accels_all(&b.set, 1);
    static const char *const refused[] = {"--scene", "--accel", NULL};
    int rc = cli_parse(&b.a, &b.c, refused, bench_complexity_help, cx_option, &b);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? CLI_OK : rc;
    }
    if ((rc = cx_open(&b)) == CLI_OK) {
        b.cfg = cli_render_config(&b.c);
        b.cfg.integrator = TR_INTEGRATOR_NAIVE; /* the thesis's figure 3.5 */
        printf("bench complexity: %ux%u, 1 spp/frame, naive, max depth %d, %s, median of %d "
               "frames\n",
               b.c.width, b.c.height,
               b.c.max_depth ? b.c.max_depth : tr_default_max_depth(TR_INTEGRATOR_NAIVE), b.be.name,
               b.frames);
        printf("%5s %10s %-7s %10s %12s %9s\n", "level", "triangles", "accel", "build ms",
               "frame ms", "fps");
        rc = cx_measure(&b);
    }
    cli_backend_close(&b.be);
    if (rc == CLI_OK && (rc = cx_write_csv(&b)) == CLI_OK) {
        rc = cx_write_plot(&b);
    }
    return rc;
}

static void bench_help(FILE *fp) {
    fprintf(fp, "Usage: trac0r bench BENCHMARK [options]\n"
                "\n"
                "Benchmarks:\n"
                "  frame        median frame time, FPS and Mrays/s of one scene\n"
                "  complexity   FPS against triangle count per acceleration structure\n"
                "               (the thesis's figure 3.5)\n"
                "  rays         Mrays/s of primary, diffuse and shadow rays per structure\n"
                "  convergence  error against a reference over time and spp, naive vs pt\n"
                "  realtime     quality and time per frame of each reconstruction method\n"
                "               along a moving camera (docs/realtime.md)\n"
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
    if (strcmp(argv[1], "complexity") == 0) {
        return bench_complexity(argc - 1, argv + 1);
    }
    if (strcmp(argv[1], "rays") == 0) {
        return bench_rays(argc - 1, argv + 1);
    }
    if (strcmp(argv[1], "convergence") == 0) {
        return bench_convergence(argc - 1, argv + 1);
    }
    if (strcmp(argv[1], "realtime") == 0) {
        return bench_realtime(argc - 1, argv + 1);
    }
    if (strcmp(argv[1], "-h") == 0 || strcmp(argv[1], "--help") == 0) {
        bench_help(stdout);
        return CLI_OK;
    }
    fprintf(stderr,
            "trac0r bench: unknown benchmark '%s' (available: frame, complexity, rays, "
            "convergence, realtime)\n",
            argv[1]);
    return CLI_USAGE;
}
