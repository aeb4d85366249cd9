/* bench_convergence.c - `trac0r bench convergence`: error against a converged
 * reference as a function of samples per pixel and of time, per integrator: the
 * thesis's "how much noise is too much?" answered in dB. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "progress.h"
#include "cli.h"
#include "trac0r/parse.h"
#include "devices.h"
#include "trac0r/measure.h"
#include "trac0r/outfile.h"

#define CONV_MAX_SIZES 4
#define CONV_THRESHOLDS 4
typedef tr_convergence_run conv_run;
#define CONV_MAX_METHODS 4 /* naive, pt, bdpt, vcm */
static const double conv_db[CONV_THRESHOLDS] = {25.0, 30.0, 35.0, 40.0};

static void convergence_help(FILE *fp) {
    fprintf(fp, "Usage: trac0r bench convergence [SCENE] [options]\n"
                "\n"
                "Error against a converged reference (its own error taken out) over time and spp\n"
                "for each method and size; prints the time and spp to reach 25, 30, 35 and 40 dB\n"
                "and writes PREFIX.csv and PREFIX.png. SCENE defaults to builtin:cornell-mirror.\n"
                "The full manual: man trac0r.\n"
                "\n"
                "Options:\n"
                "  --sizes LIST         image sizes (default 256x256,800x600)\n"
                "  --methods LIST       up to four integrators (default naive,pt,bdpt)\n"
                "  --budget SECONDS     render time per method and size, 0.1..86400 (default 30)\n"
                "  --reference-spp N    spp of the reference, 2..1000000 (default 4096)\n"
                "  --reference FILE     read the reference (.pfm) instead (one size only)\n"
                "  --max-depth D        pt's path length, 1..1022 (default 8; naive gets D + 2)\n"
                "  --seed S, --threads T, --accel NAME   as for render\n"
                "  --out PREFIX         output file prefix (default convergence)\n"
                "  -h, --help           show this help\n");
}

static int parse_sizes(cli_args *a, uint32_t w[], uint32_t h[], int *n) {
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    char buf[256];
    /* A list longer than the buffer is refused, not cut to fit. */
    const int len = snprintf(buf, sizeof buf, "%s", a->value);
    *n = 0;
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok;
         tok = strtok_r(NULL, ",", &save)) {
        uint32_t x, y;
        if (len >= (int)sizeof buf || *n == CONV_MAX_SIZES ||
            tr_parse_size(tok, TR_FILM_MAX_SIDE, &x, &y) != TR_OK ||
            (uint64_t)x * y > TR_FILM_MAX_PIXELS) {
            return cli_error(a, "%s: expected up to %d sizes WxH such as 256x256,800x600, got '%s'",
                             a->opt, CONV_MAX_SIZES, a->value);
        }
        w[*n] = x;
        h[*n] = y;
        ++*n;
    }
    if (*n == 0) {
        return cli_error(a, "%s: expected sizes such as 256x256,800x600, got '%s'", a->opt,
                         a->value);
    }
    return CLI_OK;
}

static int parse_methods(cli_args *a, int m[], int *n) {
    char names[128];
    cli_integrator_list(names, sizeof names);
    *n = cli_parse_list(a, tr_integrator_from_name, m, CONV_MAX_METHODS, "integrator", names);
    return *n < 0 ? CLI_USAGE : CLI_OK;
}

/* What the command line asked for. */
typedef struct conv_options {
    cli_common c;
    uint32_t sw[CONV_MAX_SIZES], sh[CONV_MAX_SIZES];
    int nsizes;
    int methods[CONV_MAX_METHODS];
    int nmethods;
    float budget;
    uint32_t ref_spp;
    const char *ref_path; /* --reference, or NULL: render it */
    const char *prefix;
    char csv_path[4096], png_path[4096];
    tr_image ref_img; /* --reference's image, read by check_outputs */
} conv_options;

/* One image size under measurement: its scene, the reference and the devices. */
typedef struct conv_size {
    tr_scene *scene;
    size_t px;
    float *ref, *half;                      /* 3 floats per pixel: the reference, its first half */
    tr_film film;                           /* the reference's read-back */
    cli_backend devs[CONV_MAX_METHODS + 1]; /* one per method, then the reference's */
    double ref_mse;                         /* the reference's own error (0: unknown) */
} conv_size;

static void conv_defaults(conv_options *o) {
    memset(o, 0, sizeof *o);
    cli_common_default(&o->c);
    o->c.scene = "builtin:cornell-mirror";
    /* Both integrators estimate paths of the same length here (pt D, naive D + 2): the
     * comparison keeps the thesis's depth rather than each integrator's default. */
    o->c.max_depth = TR_MAX_DEPTH_NAIVE;
    o->sw[0] = 256;
    o->sh[0] = 256;
    o->sw[1] = 800;
    o->sh[1] = 600;
    o->nsizes = 2;
    o->methods[0] = TR_INTEGRATOR_NAIVE;
    o->methods[1] = TR_INTEGRATOR_PT;
    o->methods[2] = TR_INTEGRATOR_BDPT;
    o->nmethods = 3;
    o->budget = 30.0f;
    o->ref_spp = 4096;
    o->prefix = "convergence";
}

/* One of the benchmark's own options: CLI_OK, CLI_USAGE, or -1 if it is none of them. */
static int parse_own_option(cli_args *a, void *user) {
    conv_options *o = user;
    if (cli_is(a, "--sizes")) {
        return parse_sizes(a, o->sw, o->sh, &o->nsizes);
    }
    if (cli_is(a, "--methods")) {
        return parse_methods(a, o->methods, &o->nmethods);
    }
    if (cli_is(a, "--budget")) {
        return cli_parse_float(a, 0.1f, 86400.0f, &o->budget);
    }
    if (cli_is(a, "--reference-spp")) {
        return cli_parse_u32(a, 2, 1000000, &o->ref_spp);
    }
    if (cli_is(a, "--reference")) {
        const int rc = cli_value(a);
        o->ref_path = a->value;
        return rc;
    }
    if (cli_is(a, "--out")) {
        const int rc = cli_value(a);
        o->prefix = a->value;
        return rc;
    }
    if (a->opt[0] != '-' && a->i == 1) {
        o->c.scene = a->opt;
        return CLI_OK;
    }
    return -1;
}

/* The command line into o: CLI_OK, CLI_USAGE or CLI_HELP. */
static int parse_options(cli_args *a, conv_options *o) {
    static const char *const refused[] = {"--width", "--height", "--integrator", NULL};
    const int rc = cli_parse(a, &o->c, refused, convergence_help, parse_own_option, o);
    if (rc == CLI_OK && o->c.max_depth > TR_MAX_DEPTH_LIMIT - 2) {
        return cli_error(a, "--max-depth: expected 1..%d here (naive gets D + 2)",
                         TR_MAX_DEPTH_LIMIT - 2);
    }
    return rc;
}

/* Before any work: the output files can be written, and a --reference is a PFM of the
 * one size asked for (read into o->ref_img). */
static int check_outputs(cli_args *a, conv_options *o) {
    if (o->ref_path && o->nsizes != 1) {
        return cli_error(a, "--reference: needs exactly one size in --sizes (it has %d)",
                         o->nsizes);
    }
    if (snprintf(o->csv_path, sizeof o->csv_path, "%s.csv", o->prefix) >= (int)sizeof o->csv_path ||
        snprintf(o->png_path, sizeof o->png_path, "%s.png", o->prefix) >= (int)sizeof o->png_path) {
        return cli_error(a, "--out: prefix too long");
    }
    tr_error err;
    if (tr_image_check_writable(o->csv_path, &err) != TR_OK ||
        tr_image_check_writable(o->png_path, &err) != TR_OK) {
        return cli_error(a, "--out: %s", err.msg);
    }
    if (!o->ref_path) {
        return CLI_OK;
    }
    if (tr_image_format_from_path(o->ref_path) != TR_IMAGE_PFM) {
        return cli_error(a, "--reference: '%s' is not a .pfm file", o->ref_path);
    }
    if (tr_image_read_pfm(&o->ref_img, o->ref_path, &err) != TR_OK) {
        return cli_error(a, "--reference: %s", err.msg);
    }
    if (o->ref_img.width != o->sw[0] || o->ref_img.height != o->sh[0]) {
        const int rc = cli_error(a, "--reference: %s is %ux%u, not %ux%u", o->ref_path,
                                 o->ref_img.width, o->ref_img.height, o->sw[0], o->sh[0]);
        tr_image_free(&o->ref_img);
        return rc;
    }
    return CLI_OK;
}

/* Releases what one image size of the benchmark holds. */
static void size_free(conv_size *z, int ndevs) {
    for (int k = 0; k < ndevs; ++k) {
        cli_backend_close(&z->devs[k]);
    }
    free(z->ref);
    free(z->half);
    tr_film_free(&z->film);
    tr_scene_destroy(z->scene);
}

/* Says once (at the first size) that naive and pt disagree on this scene's rough glossy
 * materials. */
static void note_rough_glossy(const tr_scene *scene) {
    for (uint32_t m = 0; m < tr_scene_material_count(scene); ++m) {
        const tr_material mat = tr_scene_material(scene, m);
        if (mat.type == TR_MATERIAL_GLOSSY && mat.roughness > 0.0f) {
            printf("note: this scene has rough glossy materials, on which naive (cone "
                   "lobe) and pt (GGX) converge to different images\n");
            return;
        }
    }
}

/* The scene at size si (o->c takes its size), checked against every method. On failure
 * nothing is left to free. */
static int size_scene(cli_args *a, conv_options *o, int si, conv_size *z) {
    o->c.width = o->sw[si];
    o->c.height = o->sh[si];
    z->scene = tr_scene_create(NULL);
    int rc = cli_load_scene(a, &o->c, z->scene);
    /* A method that cannot render the scene (naive with punctual lights)
     * fails here, not after the reference has been rendered. */
    for (int mi = 0; mi < o->nmethods && rc == CLI_OK; ++mi) {
        tr_error err;
        if (tr_integrator_supports(z->scene, o->methods[mi], &err) != TR_OK) {
            rc = cli_error(a, "--methods %s: %s", tr_integrator_name(o->methods[mi]), err.msg);
        }
    }
    if (rc != CLI_OK) {
        tr_scene_destroy(z->scene);
        return rc;
    }
    if (si == 0) {
        note_rough_glossy(z->scene);
    }
    return CLI_OK;
}

/* The scene, the image buffers, the reference's film and one device per method plus the
 * reference's, at size si. On failure nothing is left to free. */
static int size_open(cli_args *a, conv_options *o, int si, conv_size *z) {
    memset(z, 0, sizeof *z);
    int rc = size_scene(a, o, si, z);
    if (rc != CLI_OK) {
        return rc;
    }
    const uint32_t w = o->c.width, h = o->c.height;
    z->px = (size_t)w * h;
    z->ref = malloc(3 * z->px * sizeof *z->ref);
    z->half = malloc(3 * z->px * sizeof *z->half);
    tr_error err;
    const int buffers = z->ref && z->half;
    const int film_ok = buffers && tr_film_init(&z->film, w, h, &err) == TR_OK;
    for (int k = 0; film_ok && rc == CLI_OK && k <= o->nmethods; ++k) {
        rc = cli_backend_open(a, &o->c, z->scene, &z->devs[k]);
    }
    if (rc != CLI_OK) {
        size_free(z, o->nmethods + 1);
        return rc;
    }
    if (!film_ok) {
        fprintf(stderr, "trac0r bench convergence: %ux%u: %s\n", w, h,
                buffers ? err.msg : "out of memory");
        free(z->ref);
        free(z->half);
        tr_scene_destroy(z->scene);
        return CLI_FAILURE;
    }
    return CLI_OK;
}

/* The progress bar's callback. */
static int bar_progress(void *user, uint64_t done, uint64_t total) {
    (void)total;
    progress_update(user, done, NULL);
    return 0;
}

/* Renders the reference with pt in two halves (tr_reference_render), z->ref_mse its own
 * error. */
static int render_reference(const conv_options *o, conv_size *z) {
    const uint32_t w = o->c.width, h = o->c.height;
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = o->c.threads;
    cfg.integrator = TR_INTEGRATOR_PT;
    cfg.max_depth = o->c.max_depth;
    /* The reference's seed differs from the measured runs', so its noise is
     * independent of theirs. */
    cfg.seed = o->c.seed ^ 0x7265666572656e63ULL;
    const double t0 = tr_time_now();
    char label[96];
    snprintf(label, sizeof label, "trac0r bench convergence: %ux%u reference", w, h);
    progress bar;
    progress_begin(&bar, label, "spp", o->ref_spp, 0);
    tr_error err;
    const int rc =
        tr_reference_render(z->devs[o->nmethods].dev, tr_scene_camera(z->scene), &cfg, o->ref_spp,
                            &z->film, z->ref, z->half, &z->ref_mse, bar_progress, &bar, &err);
    progress_end(&bar);
    if (rc != TR_OK) {
        fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
        return CLI_FAILURE;
    }
    printf("%ux%u: reference pt %u spp in %.1f s, its own PSNR ~ %.1f dB\n", w, h, o->ref_spp,
           tr_time_now() - t0, tr_psnr(z->ref_mse));
    fflush(stdout);
    return CLI_OK;
}

/* The reference of size z: --reference's image, or rendered. */
static int size_reference(const conv_options *o, conv_size *z) {
    if (!o->ref_path) {
        return render_reference(o, z);
    }
    memcpy(z->ref, o->ref_img.rgb, 3 * z->px * sizeof *z->ref);
    z->ref_mse = 0.0;
    printf("%ux%u: reference %s (its own error unknown: not taken out)\n", o->c.width, o->c.height,
           o->ref_path);
    return CLI_OK;
}

/* A method's line once it has finished. */
static void method_finished(void *user, const conv_run *r) {
    progress_clear(user);
    const tr_convergence_point *p = &r->pt[r->n - 1];
    printf("%ux%u %-5s: %u spp in %.2f s -> PSNR %.2f dB (raw %.2f), RMSE %.5f, relMSE %.5f\n",
           r->width, r->height, tr_integrator_name(r->integrator), p->spp, p->seconds, p->psnr,
           p->raw.psnr, p->raw.rmse, p->raw.relmse);
    fflush(stdout);
}

/* Every method at size z until its budget is spent or it passes 41 dB, into runs[0 ..
 * nmethods): tr_convergence_measure, one device per method. */
static int run_methods(const conv_options *o, conv_size *z, conv_run *runs) {
    tr_render_config cfgs[CONV_MAX_METHODS];
    tr_device *devs[CONV_MAX_METHODS];
    for (int mi = 0; mi < o->nmethods; ++mi) {
        cfgs[mi] = tr_render_config_default();
        cfgs[mi].threads = o->c.threads;
        cfgs[mi].integrator = o->methods[mi];
        cfgs[mi].max_depth =
            o->methods[mi] == TR_INTEGRATOR_NAIVE ? o->c.max_depth + 2 : o->c.max_depth;
        cfgs[mi].seed = o->c.seed;
        devs[mi] = z->devs[mi].dev;
    }
    char label[96];
    snprintf(label, sizeof label, "trac0r bench convergence: %ux%u methods", o->c.width,
             o->c.height);
    progress bar;
    progress_begin(&bar, label, "ms of budget", (uint64_t)(o->budget * 1e3) * (uint64_t)o->nmethods,
                   0);
    tr_convergence_desc d = {.scene = z->scene,
                             .methods = o->nmethods,
                             .devs = devs,
                             .configs = cfgs,
                             .ref = z->ref,
                             .ref_mse = z->ref_mse,
                             .budget = o->budget,
                             .progress = bar_progress,
                             .finished = method_finished,
                             .user = &bar};
    tr_error err;
    const int rc = tr_convergence_measure(&d, runs, &err);
    progress_end(&bar);
    if (rc != TR_OK) {
        fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
        return CLI_FAILURE;
    }
    return CLI_OK;
}

/* Size si: its reference, then every method against it. */
static int measure_size(cli_args *a, conv_options *o, int si, conv_run *runs) {
    conv_size z;
    int rc = size_open(a, o, si, &z);
    if (rc != CLI_OK) {
        return rc;
    }
    rc = size_reference(o, &z);
    if (rc == CLI_OK) {
        rc = run_methods(o, &z, runs);
    }
    size_free(&z, o->nmethods + 1);
    return rc;
}

/* The table: time and spp to reach each PSNR. */
static void print_table(const conv_run *runs, int n) {
    printf("\n%-9s %-6s", "size", "method");
    for (int k = 0; k < CONV_THRESHOLDS; ++k) {
        printf("  %20.0f dB", conv_db[k]);
    }
    printf("\n");
    for (int i = 0; i < n; ++i) {
        const conv_run *r = &runs[i];
        char size[32];
        snprintf(size, sizeof size, "%ux%u", r->width, r->height);
        printf("%-9s %-6s", size, tr_integrator_name(r->integrator));
        for (int k = 0; k < CONV_THRESHOLDS; ++k) {
            double t = tr_convergence_reach(r, conv_db[k], 0),
                   s = tr_convergence_reach(r, conv_db[k], 1);
            char cell[64];
            if (t < 0.0) {
                snprintf(cell, sizeof cell, "not reached");
            } else {
                snprintf(cell, sizeof cell, "%.3g s / %.0f spp", t, ceil(s));
            }
            printf("  %23s", cell);
        }
        printf("\n");
    }
}

/* One line: how many times longer rn takes than rp to reach each threshold. */
static void print_speedup(const conv_run *rn, const conv_run *rp) {
    const char *sn = tr_integrator_name(rn->integrator);
    const char *sp = tr_integrator_name(rp->integrator);
    printf("%ux%u time %s / time %s:", rn->width, rn->height, sn, sp);
    for (int k = 0; k < CONV_THRESHOLDS; ++k) {
        double tn = tr_convergence_reach(rn, conv_db[k], 0),
               tp = tr_convergence_reach(rp, conv_db[k], 0);
        if (tn > 0.0 && tp > 0.0) {
            printf("  %.0f dB: %.1fx", conv_db[k], tn / tp);
        } else if (tp > 0.0) {
            printf("  %.0f dB: > %.1fx (%s not there in %.1f s)", conv_db[k],
                   rn->n ? rn->pt[rn->n - 1].seconds / tp : 0.0, sn,
                   rn->n ? rn->pt[rn->n - 1].seconds : 0.0);
        } else {
            printf("  %.0f dB: -", conv_db[k]);
        }
    }
    printf("\n");
}

/* Speed-ups in time to each threshold: pt over naive, bdpt and vcm over pt. */
static void print_speedups(const conv_run *runs, int nsizes, int nmethods) {
    static const int pairs[3][2] = {{0, 1}, {1, 2}, {1, 3}};
    for (int si = 0; si < nsizes; ++si) {
        const conv_run *by[4] = {NULL, NULL, NULL, NULL}; /* naive, pt, bdpt, vcm */
        for (int mi = 0; mi < nmethods; ++mi) {
            const conv_run *r = &runs[si * nmethods + mi];
            by[r->integrator == TR_INTEGRATOR_NAIVE  ? 0
               : r->integrator == TR_INTEGRATOR_PT   ? 1
               : r->integrator == TR_INTEGRATOR_BDPT ? 2
                                                     : 3] = r;
        }
        for (int pair = 0; pair < 3; ++pair) {
            const conv_run *rn = by[pairs[pair][0]], *rp = by[pairs[pair][1]];
            if (rn && rp) {
                print_speedup(rn, rp);
            }
        }
    }
}

/* Every point of every run as CSV, written atomically. */
static int write_csv(const char *path, const conv_run *runs, int n) {
    tr_error err;
    tr_outfile *csv = tr_outfile_create(path, &err);
    if (!csv) {
        fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
        return CLI_FAILURE;
    }
    FILE *fp = tr_outfile_stream(csv);
    fprintf(fp, "method,width,height,spp,seconds,rmse,relmse,psnr_raw,psnr\n");
    for (int i = 0; i < n; ++i) {
        const conv_run *r = &runs[i];
        for (int k = 0; k < r->n; ++k) {
            const tr_convergence_point *p = &r->pt[k];
            fprintf(fp, "%s,%u,%u,%u,%.5f,%.6g,%.6g,%.4f,%.4f\n", tr_integrator_name(r->integrator),
                    r->width, r->height, p->spp, p->seconds, p->raw.rmse, p->raw.relmse,
                    p->raw.psnr, p->psnr);
        }
    }
    if (tr_outfile_commit(csv, &err) != TR_OK) {
        fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
        return CLI_FAILURE;
    }
    return CLI_OK;
}

/* gnuplot's script: one inline data block per run, then PSNR against time and against
 * spp side by side. Returns the length written (cap or more: it did not fit). */
static size_t plot_script(char *script, size_t cap, const char *scene, const conv_run *runs,
                          int n) {
    size_t len = 0;
    for (int i = 0; i < n; ++i) {
        bench_plot_put(script, cap, &len, "$d%d << EOD\n", i);
        for (int k = 0; k < runs[i].n; ++k) {
            if (isfinite(runs[i].pt[k].psnr)) {
                bench_plot_put(script, cap, &len, "%u %.5f %.4f\n", runs[i].pt[k].spp,
                               runs[i].pt[k].seconds, runs[i].pt[k].psnr);
            }
        }
        bench_plot_put(script, cap, &len, "EOD\n");
    }
    /* The title names the scene by its file name, kept out of gnuplot's quoting. */
    char name[64];
    bench_plot_name(scene, name, sizeof name);
    for (int panel = 0; panel < 2; ++panel) {
        len += (size_t)snprintf(
            script + len, cap - len,
            "%sset logscale x\nset grid\nset key bottom right\nset ylabel 'PSNR (dB)'\n"
            "set xlabel '%s'\nset title 'PSNR against %s: %s'\nplot ",
            panel == 0 ? "set multiplot layout 1,2\n" : "",
            panel == 0 ? "render time (s)" : "samples per pixel", panel == 0 ? "time" : "spp",
            name);
        for (int i = 0; i < n; ++i) {
            len += (size_t)snprintf(
                script + len, cap - len, "%s$d%d using %d:3 with linespoints lw 2 title '%s %ux%u'",
                i ? ", " : "", i, panel == 0 ? 2 : 1, tr_integrator_name(runs[i].integrator),
                runs[i].width, runs[i].height);
        }
        bench_plot_put(script, cap, &len,
                       ", 25 dt 2 lc 'gray' notitle, 30 dt 2 "
                       "lc 'gray' notitle, 35 dt 2 lc 'gray' "
                       "notitle, 40 dt 2 lc 'gray' notitle\n");
    }
    bench_plot_put(script, cap, &len, "unset multiplot\n");
    return len;
}

/* The CSV and the plot, and the line naming them. */
static int write_outputs(const conv_options *o, const conv_run *runs) {
    const int n = o->nsizes * o->nmethods;
    int rc = write_csv(o->csv_path, runs, n);
    if (rc != CLI_OK) {
        return rc;
    }
    const size_t cap = 64 + (size_t)n * (TR_CONVERGENCE_MAX_POINTS * 48 + 256);
    char *script = malloc(cap);
    if (!script) {
        return CLI_FAILURE;
    }
    tr_error err;
    const size_t len = plot_script(script, cap, o->c.scene, runs, n);
    const int plotted = len < cap ? bench_plot_png(script, o->png_path, &err) : 0;
    free(script);
    if (plotted < 0) {
        fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
        return CLI_FAILURE;
    }
    printf("wrote %s%s%s\n", o->csv_path, plotted ? " and " : " (gnuplot failed: no plot)",
           plotted ? o->png_path : "");
    return CLI_OK;
}

int bench_convergence(int argc, char **argv) {
    cli_args a = {.cmd = "bench convergence", .argc = argc, .argv = argv, .i = 0};
    conv_options o;
    conv_defaults(&o);
    int rc = parse_options(&a, &o);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? CLI_OK : rc;
    }
    rc = check_outputs(&a, &o);
    if (rc != CLI_OK) {
        return rc;
    }
    conv_run *runs = calloc((size_t)(o.nsizes * o.nmethods), sizeof *runs);
    if (!runs) {
        tr_image_free(&o.ref_img);
        return cli_error(&a, "out of memory");
    }
    const int threads = o.c.threads ? o.c.threads : tr_default_threads();
    printf("bench convergence: %s, pt max depth %d (naive %d), %d thread%s, budget %.1f s per "
           "method and size\n",
           o.c.scene, o.c.max_depth, o.c.max_depth + 2, threads, threads == 1 ? "" : "s",
           (double)o.budget);
    for (int si = 0; si < o.nsizes && rc == CLI_OK; ++si) {
        rc = measure_size(&a, &o, si, &runs[si * o.nmethods]);
    }
    tr_image_free(&o.ref_img);
    if (rc == CLI_OK) {
        print_table(runs, o.nsizes * o.nmethods);
        print_speedups(runs, o.nsizes, o.nmethods);
        rc = write_outputs(&o, runs);
    }
    free(runs);
    return rc;
}
