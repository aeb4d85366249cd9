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

static int cmp_double(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double bench_median(double *v, int n) {
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
           "  --animate            a dynamic scene: before every frame the scene's last\n"
           "                       shape moves (sways along x) and the structure is\n"
           "                       updated (bvh/bvh2: refit, embree: rebuild; a device gets\n"
           "                       the scene again); the update's median is printed\n"
           "                       apart from the frame's\n"
           "  -h, --help           show this help\n"
           "\n"
           "With --device opencl every device frame is followed by the same frame on the\n"
           "CPU, and the ratio of the two medians is printed too.\n"
           "\n"
           "The thesis (table 3.2) reports 11.6 FPS for this scene at 800x600 on an NVIDIA\n"
           "GeForce GTX 570.\n",
           cli_common_help());
}

static int bench_frame(int argc, char **argv) {
    cli_args a = {.cmd = "bench frame", .argc = argc, .argv = argv, .i = 0};
    cli_common c;
    cli_common_default(&c);
    c.integrator = TR_INTEGRATOR_NAIVE; /* the thesis's frame */
    int frames = 20;
    int animate = 0;
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
        } else if (cli_is(&a, "--animate")) {
            animate = 1;
            rc = CLI_OK;
        } else {
            return cli_unknown(&a);
        }
        if (rc != CLI_OK) {
            return CLI_USAGE;
        }
    }
    tr_scene *scene = tr_scene_create(NULL);
    int rc = cli_load_scene(&a, &c, scene);
    if (rc != CLI_OK) {
        tr_scene_destroy(scene);
        return rc;
    }
    tr_error err;
    double *times = malloc((size_t)frames * 2 * sizeof *times);
    double *update_times = times ? times + frames : NULL;
    if (!times) {
        tr_scene_destroy(scene);
        fprintf(stderr, "trac0r bench frame: out of memory\n");
        return CLI_FAILURE;
    }
    if (tr_film_check_size(c.width, c.height, &err) != TR_OK) {
        free(times);
        tr_scene_destroy(scene);
        return cli_error(&a, "--width/--height: %s", err.msg);
    }
    cli_backend be;
    rc = cli_backend_open(&a, &c, scene, &be);
    if (rc != CLI_OK) {
        free(times);
        tr_scene_destroy(scene);
        return rc;
    }
    tr_render_config cfg = cli_render_config(&c);

    char accel[160];
    cli_describe_accel(accel, sizeof accel, scene);
    printf("bench frame: %s, %ux%u, 1 spp/frame, integrator %s, max depth %d, %s, "
           "%u triangles, accel %s\n",
           c.scene, c.width, c.height, tr_integrator_name(c.integrator),
           c.max_depth ? c.max_depth : tr_default_max_depth(c.integrator), be.name,
           tr_scene_triangle_count(scene), accel);
    uint64_t rays = 0;
    double total = 0.0;
    rc = CLI_OK;
    /* On a device, every frame is followed by the same frame on the CPU: the reference
     * the device's speed is reported against, measured under the same load. */
    cli_backend cpu = {.dev = NULL};
    double *cpu_times = NULL;
    if (!cli_backend_is_cpu(&be)) {
        cli_common cc = c;
        snprintf(cc.device, sizeof cc.device, "cpu");
        cpu_times = malloc((size_t)frames * sizeof *cpu_times);
        if (!cpu_times) {
            fprintf(stderr, "trac0r bench frame: out of memory\n");
            rc = CLI_FAILURE;
        } else {
            rc = cli_backend_open(&a, &cc, scene, &cpu);
        }
    }
    /* Frame 0 warms caches and the thread pool and is not timed. */
    progress bar;
    progress_begin(&bar, "trac0r bench frame", "frames", (uint64_t)frames + 1, 0);
    for (int f = 0; f <= frames && rc == CLI_OK; ++f) {
        if (f > 0) {
            progress_update(&bar, (uint64_t)f, NULL);
        }
        tr_render_stats st;
        if (animate) {
            /* The scene changes, so each frame starts a new image. */
            const double t0 = tr_time_now(); /* the update and any upload, together */
            if (cli_animate(scene, (uint32_t)f, &err) != TR_OK ||
                tr_scene_update(scene, NULL, &err) != TR_OK) {
                progress_clear(&bar);
                fprintf(stderr, "trac0r bench frame: --animate: %s\n", err.msg);
                rc = CLI_FAILURE;
                break;
            }
            if ((rc = cli_backend_upload(&a, &be, scene)) != CLI_OK ||
                (cpu.dev && (rc = cli_backend_upload(&a, &cpu, scene)) != CLI_OK)) {
                break;
            }
            if (f > 0) {
                update_times[f - 1] = tr_time_now() - t0;
            }
            if (cli_backend_clear(&be, &err) != TR_OK) {
                progress_clear(&bar);
                fprintf(stderr, "trac0r bench frame: %s\n", err.msg);
                rc = CLI_FAILURE;
                break;
            }
        }
        if (cli_backend_frame(&be, scene, &cfg, (uint32_t)f, &st, &err) != TR_OK) {
            progress_clear(&bar);
            fprintf(stderr, "trac0r bench frame: %s\n", err.msg);
            rc = CLI_FAILURE;
        } else if (f > 0) {
            times[f - 1] = st.seconds;
            rays += st.rays;
            total += st.seconds;
        }
        if (rc == CLI_OK && cpu_times) {
            if (cli_backend_frame(&cpu, scene, &cfg, (uint32_t)f, &st, &err) != TR_OK) {
                progress_clear(&bar);
                fprintf(stderr, "trac0r bench frame: %s\n", err.msg);
                rc = CLI_FAILURE;
            } else if (f > 0) {
                cpu_times[f - 1] = st.seconds;
            }
        }
    }
    if (rc == CLI_OK) {
        progress_update(&bar, (uint64_t)frames + 1, NULL);
    }
    progress_end(&bar);
    if (rc == CLI_OK) {
        double mrays = (double)rays / total * 1e-6;
        double med = bench_median(times, frames);
        printf("frames %d  median %.2f ms  min %.2f ms  max %.2f ms\n", frames, med * 1e3,
               times[0] * 1e3, times[frames - 1] * 1e3);
        printf("fps %.2f (median)  Mrays/s %.2f (mean)\n", 1.0 / med, mrays);
        if (animate) {
            const double umed = bench_median(update_times, frames);
            printf("scene update per frame (%s%s): median %.3f ms  min %.3f ms  max %.3f ms; "
                   "frame + update %.2f ms (%.2f fps)\n",
                   tr_scene_update_kind(scene),
                   (tr_device_caps(be.dev) & TR_DEVICE_CAP_SCENE_COPY) != 0u
                       ? " + upload to the device"
                       : "",
                   umed * 1e3, update_times[0] * 1e3, update_times[frames - 1] * 1e3,
                   (med + umed) * 1e3, 1.0 / (med + umed));
        }
        printf("thesis (table 3.2): 11.6 fps on a GeForce GTX 570 -> ratio %.2f\n",
               (1.0 / med) / 11.6);
        if (cpu_times) {
            const int threads = cfg.threads ? cfg.threads : tr_default_threads();
            double cpu_med = bench_median(cpu_times, frames);
            printf("cpu (%d thread%s, interleaved with the device's frames): median %.2f ms, "
                   "fps %.2f -> device/cpu %.2f\n",
                   threads, threads == 1 ? "" : "s", cpu_med * 1e3, 1.0 / cpu_med, cpu_med / med);
        }
    }
    free(cpu_times);
    cli_backend_close(&cpu);
    cli_backend_close(&be);
    free(times);
    tr_scene_destroy(scene);
    return rc;
}

int bench_parse_accels(cli_args *a, accel_set *set) {
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    set->count = 0;
    char buf[128];
    snprintf(buf, sizeof buf, "%s", a->value);
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok;
         tok = strtok_r(NULL, ",", &save)) {
        int t = tr_accel_from_name(tok);
        if (t < 0) {
            return cli_error(a, "%s: unknown acceleration structure '%s' in '%s'", a->opt, tok,
                             a->value);
        }
        if (set->count == (int)(sizeof set->type / sizeof set->type[0])) {
            return cli_error(a, "%s: more than %d structures in '%s'", a->opt,
                             (int)(sizeof set->type / sizeof set->type[0]), a->value);
        }
        if (!tr_accel_available((tr_accel_type)t)) {
            return cli_error(a, "%s: '%s' is not available in this build", a->opt, tok);
        }
        set->type[set->count++] = (tr_accel_type)t;
    }
    if (set->count == 0) {
        return cli_error(a, "%s: expected a list such as 'flat,bvh,embree', got '%s'", a->opt,
                         a->value);
    }
    return CLI_OK;
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

double bench_build_seconds(const tr_scene *s) {
    return tr_scene_accel(s) == TR_ACCEL_TYPE_EMBREE ? tr_scene_embree_build_seconds(s)
                                                     : tr_scene_bvh_build_seconds(s);
}

static void bench_complexity_help(void) {
    printf("Usage: trac0r bench complexity [options]\n"
           "\n"
           "The thesis's figure 3.5: frames per second against triangle count for the Cornell\n"
           "scene with one (glass) icosphere subdivided 0..L times (builtin:cornell-ico-N),\n"
           "1 spp per frame, naive integrator, for each acceleration structure. A structure\n"
           "is dropped for the higher levels once one of its frames takes longer than the\n"
           "limit. Prints the table and writes PREFIX.csv and PREFIX.png (gnuplot).\n"
           "\n"
           "Options:\n"
           "  --width W, --height H, --max-depth D, --seed S, --threads T, --device DEV\n"
           "                       as for render (with --device opencl the structures are\n"
           "                       flat and bvh; Embree runs on the CPU only)\n"
           "                       (default 800x600)\n"
           "  --max-level L        highest subdivision level, 0..%d (default 8)\n"
           "  --frames N           timed frames per point after one warm-up, 1..1000\n"
           "                       (default 5); the median is reported\n"
           "  --accels LIST        structures to compare (default: flat,bvh,embree, those\n"
           "                       this build has; bvh2 adds the binary BVH alone)\n"
           "  --limit SECONDS      drop a structure after a frame slower than this (default 10)\n"
           "  --out PREFIX         output file prefix (default complexity)\n"
           "  -h, --help           show this help\n",
           TR_ICOSPHERE_MAX_SUBDIVISIONS);
}

static int bench_complexity(int argc, char **argv) {
    cli_args a = {.cmd = "bench complexity", .argc = argc, .argv = argv, .i = 0};
    cli_common c;
    cli_common_default(&c);
    int frames = 5, max_level = 8;
    float limit = 10.0f;
    const char *prefix = "complexity";
    accel_set set;
    bench_accels_all(&set, 1);
    int accels_given = 0;
    while (cli_next(&a)) {
        int rc = cli_common_option(&a, &c);
        if (rc == CLI_OK && (cli_is(&a, "--scene") || cli_is(&a, "--accel"))) {
            return cli_error(&a, "%s: not an option of this benchmark", a.opt);
        }
        if (rc == CLI_OK) {
            continue;
        }
        if (rc == CLI_USAGE) {
            return CLI_USAGE;
        }
        if (cli_is(&a, "-h") || cli_is(&a, "--help")) {
            bench_complexity_help();
            return CLI_OK;
        } else if (cli_is(&a, "--frames")) {
            rc = cli_parse_int(&a, 1, 1000, &frames);
        } else if (cli_is(&a, "--max-level")) {
            rc = cli_parse_int(&a, 0, TR_ICOSPHERE_MAX_SUBDIVISIONS, &max_level);
        } else if (cli_is(&a, "--limit")) {
            rc = cli_parse_float(&a, 0.001f, 1e6f, &limit);
        } else if (cli_is(&a, "--accels")) {
            rc = bench_parse_accels(&a, &set);
            accels_given = 1;
        } else if (cli_is(&a, "--out")) {
            rc = cli_value(&a);
            prefix = a.value;
        } else {
            return cli_unknown(&a);
        }
        if (rc != CLI_OK) {
            return CLI_USAGE;
        }
    }
    char csv_path[4096], png_path[4096];
    snprintf(csv_path, sizeof csv_path, "%s.csv", prefix);
    snprintf(png_path, sizeof png_path, "%s.png", prefix);
    tr_error err;
    if (tr_image_check_writable(csv_path, &err) != TR_OK ||
        tr_image_check_writable(png_path, &err) != TR_OK) {
        return cli_error(&a, "--out: %s", err.msg);
    }
    double *times = malloc((size_t)frames * sizeof *times);
    if (!times) {
        fprintf(stderr, "trac0r bench complexity: out of memory\n");
        return CLI_FAILURE;
    }
    if (tr_film_check_size(c.width, c.height, &err) != TR_OK) {
        free(times);
        return cli_error(&a, "--width/--height: %s", err.msg);
    }
    cli_backend be;
    int rc = cli_backend_open(&a, &c, NULL, &be);
    if (rc != CLI_OK) {
        free(times);
        return rc;
    }
    /* Only the structures the device walks itself are compared (Embree is host-only). */
    for (int k = 0; k < set.count; ++k) {
        if (!tr_device_traces(be.dev, set.type[k])) {
            if (accels_given) {
                rc = cli_error(&a,
                               "--accels: %s runs on the CPU only; with --device %s "
                               "compare flat,bvh",
                               tr_accel_name(set.type[k]), tr_device_kind(be.dev));
                cli_backend_close(&be);
                free(times);
                return rc;
            }
            set.type[k] = set.type[--set.count];
            --k;
        }
    }
    tr_render_config cfg = cli_render_config(&c);
    cfg.integrator = TR_INTEGRATOR_NAIVE; /* the thesis's figure 3.5 */
    printf("bench complexity: %ux%u, 1 spp/frame, naive, max depth %d, %s, median of %d "
           "frames\n",
           c.width, c.height, c.max_depth ? c.max_depth : tr_default_max_depth(TR_INTEGRATOR_NAIVE),
           be.name, frames);
    printf("%5s %10s %-7s %10s %12s %9s\n", "level", "triangles", "accel", "build ms", "frame ms",
           "fps");
    /* Results, for the CSV and plot: fps[level][accel] (0 = not measured). */
    double fps[TR_ICOSPHERE_MAX_SUBDIVISIONS + 1][4] = {{0}};
    uint32_t tris[TR_ICOSPHERE_MAX_SUBDIVISIONS + 1] = {0};
    double build_ms[TR_ICOSPHERE_MAX_SUBDIVISIONS + 1][4] = {{0}};
    int dropped[4] = {0};
    progress bar;
    progress_begin(&bar, "trac0r bench complexity", "steps",
                   (uint64_t)(max_level + 1) * (uint64_t)set.count, 0);
    for (int level = 0; level <= max_level && rc == CLI_OK; ++level) {
        progress_update(&bar, (uint64_t)level * (uint64_t)set.count, NULL);
        char name[32];
        snprintf(name, sizeof name, "cornell-ico-%d", level);
        tr_scene *scene = tr_scene_create(&err);
        if (!scene || tr_scene_builtin(scene, name, c.width, c.height, &err) != TR_OK) {
            progress_clear(&bar);
            fprintf(stderr, "trac0r bench complexity: %s\n", err.msg);
            tr_scene_destroy(scene);
            rc = CLI_FAILURE;
            break;
        }
        tris[level] = tr_scene_triangle_count(scene);
        for (int k = 0; k < set.count && rc == CLI_OK; ++k) {
            if (dropped[k]) {
                continue;
            }
            if (tr_scene_commit(scene, set.type[k], &err) != TR_OK) {
                progress_clear(&bar);
                fprintf(stderr, "trac0r bench complexity: %s\n", err.msg);
                rc = CLI_FAILURE;
                break;
            }
            build_ms[level][k] = bench_build_seconds(scene) * 1e3;
            rc = cli_backend_upload(&a, &be, scene);
            if (rc != CLI_OK) {
                break;
            }
            if (cli_backend_clear(&be, &err) != TR_OK) {
                progress_clear(&bar);
                fprintf(stderr, "trac0r bench complexity: %s\n", err.msg);
                rc = CLI_FAILURE;
                break;
            }
            int n = 0;
            for (int f = 0; f <= frames; ++f) {
                tr_render_stats st;
                if (cli_backend_frame(&be, scene, &cfg, (uint32_t)f, &st, &err) != TR_OK) {
                    progress_clear(&bar);
                    fprintf(stderr, "trac0r bench complexity: %s\n", err.msg);
                    rc = CLI_FAILURE;
                    break;
                }
                if (st.seconds > limit) {
                    /* Too slow to repeat: this frame is the measurement, and the
                     * structure sits out the larger scenes. */
                    times[0] = st.seconds;
                    n = 1;
                    dropped[k] = 1;
                    break;
                }
                if (f > 0) {
                    times[n++] = st.seconds;
                }
            }
            if (rc != CLI_OK) {
                break;
            }
            double med = bench_median(times, n);
            fps[level][k] = 1.0 / med;
            progress_clear(&bar);
            printf("%5d %10u %-7s %10.1f %12.2f %9.3f%s\n", level, tr_scene_triangle_count(scene),
                   tr_accel_name(set.type[k]), build_ms[level][k], med * 1e3, 1.0 / med,
                   dropped[k] ? "  (slower than the limit: dropped for higher levels)" : "");
            fflush(stdout);
        }
        tr_scene_destroy(scene);
    }
    if (rc == CLI_OK) {
        progress_update(&bar, (uint64_t)(max_level + 1) * (uint64_t)set.count, NULL);
    }
    progress_end(&bar);
    cli_backend_close(&be);
    free(times);
    if (rc != CLI_OK) {
        return rc;
    }
    /* CSV: one row per (level, structure) measured. */
    tr_outfile *csv = tr_outfile_create(csv_path, &err);
    if (!csv) {
        fprintf(stderr, "trac0r bench complexity: %s\n", err.msg);
        return CLI_FAILURE;
    }
    FILE *fp = tr_outfile_stream(csv);
    fprintf(fp, "level,triangles,accel,build_ms,fps\n");
    for (int level = 0; level <= max_level; ++level) {
        for (int k = 0; k < set.count; ++k) {
            if (fps[level][k] > 0.0) {
                fprintf(fp, "%d,%u,%s,%.3f,%.5f\n", level, tris[level], tr_accel_name(set.type[k]),
                        build_ms[level][k], fps[level][k]);
            }
        }
    }
    if (tr_outfile_commit(csv, &err) != TR_OK) {
        fprintf(stderr, "trac0r bench complexity: %s\n", err.msg);
        return CLI_FAILURE;
    }
    /* One inline data block per structure, so each draws as one connected line. */
    char script[8192];
    size_t len = 0;
    for (int k = 0; k < set.count; ++k) {
        bench_plot_put(script, sizeof script, &len, "$d%d << EOD\n", k);
        for (int level = 0; level <= max_level; ++level) {
            if (fps[level][k] > 0.0) {
                bench_plot_put(script, sizeof script, &len, "%u %.5f\n", tris[level],
                               fps[level][k]);
            }
        }
        bench_plot_put(script, sizeof script, &len, "EOD\n");
    }
    bench_plot_put(script, sizeof script, &len,
                   "set logscale xy\nset grid\nset xlabel 'triangles'\n"
                   "set ylabel 'frames per second (%ux%u, 1 spp)'\n"
                   "set title 'trac0r bench complexity (thesis figure 3.5)'\n"
                   "set key top right\nplot ",
                   c.width, c.height);
    for (int k = 0; k < set.count; ++k) {
        bench_plot_put(script, sizeof script, &len, "%s$d%d with linespoints lw 2 title '%s'",
                       k ? ", " : "", k, tr_accel_name(set.type[k]));
    }
    int plotted = len < sizeof script ? bench_plot_png(script, png_path, &err) : 0;
    if (plotted < 0) {
        fprintf(stderr, "trac0r bench complexity: %s\n", err.msg);
        return CLI_FAILURE;
    }
    printf("wrote %s%s%s\n", csv_path, plotted ? " and " : " (gnuplot failed: no plot)",
           plotted ? png_path : "");
    return CLI_OK;
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
