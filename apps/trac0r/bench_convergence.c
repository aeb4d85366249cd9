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
#include "devices.h"
#include "trac0r/outfile.h"

#define CONV_MAX_SIZES 4
#define CONV_MAX_POINTS 400
#define CONV_THRESHOLDS 4
#define CONV_MAX_METHODS 4 /* naive, pt, bdpt, vcm */
static const double conv_db[CONV_THRESHOLDS] = {25.0, 30.0, 35.0, 40.0};

typedef struct conv_point {
    uint32_t spp;
    double seconds;       /* render time only */
    tr_image_metrics raw; /* against the reference as it is */
    double psnr;          /* with the reference's own MSE taken out */
} conv_point;

typedef struct conv_run {
    int integrator;
    uint32_t width, height;
    conv_point pt[CONV_MAX_POINTS];
    int n;
} conv_run;

static void convergence_help(void) {
    printf("Usage: trac0r bench convergence [SCENE] [options]\n"
           "\n"
           "Renders a converged reference with pt (two independent halves, so that the\n"
           "reference's own error can be estimated and taken out), then for each method\n"
           "and image size accumulates 1 spp frames and records the error against the\n"
           "reference (trac0r compare's metrics) after geometrically spaced sample counts,\n"
           "until the time budget is spent or the PSNR passes 41 dB. The methods take turns\n"
           "frame by frame, so that they share whatever load the machine has. Prints the\n"
           "time and spp each method needs to reach 25, 30, 35 and 40 dB and writes\n"
           "PREFIX.csv and PREFIX.png (gnuplot: PSNR against time and against spp).\n"
           "\n"
           "SCENE defaults to builtin:cornell-mirror: the thesis's Cornell box with its glossy\n"
           "objects as perfect mirrors, on which naive and pt converge to the same image\n"
           "(they differ on rough glossy surfaces: naive keeps the thesis's cone lobe, pt\n"
           "uses GGX). naive runs with max depth D + 2, pt with D, so that both estimate\n"
           "paths of at most D segments.\n"
           "\n"
           "Options:\n"
           "  --sizes LIST         image sizes, e.g. 256x256,800x600 (the default)\n"
           "  --methods LIST       integrators to measure, up to four (default naive,pt,bdpt;\n"
           "                       vcm may be added); one that cannot render the scene (bdpt\n"
           "                       or vcm with an environment light or a sun) is refused\n"
           "                       before the reference is rendered\n"
           "  --budget SECONDS     render time per method and size, 0.1..86400 (default 30)\n"
           "  --reference-spp N    spp of the rendered reference, 2..1000000 (default 4096)\n"
           "  --reference FILE     read the reference (.pfm) instead (one size only; its own\n"
           "                       error is then unknown and not taken out)\n"
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
    snprintf(buf, sizeof buf, "%s", a->value);
    *n = 0;
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok;
         tok = strtok_r(NULL, ",", &save)) {
        unsigned x, y;
        char tail;
        if (*n == CONV_MAX_SIZES || sscanf(tok, "%ux%u%c", &x, &y, &tail) != 2 || x < 1 || y < 1 ||
            x > TR_FILM_MAX_SIDE || y > TR_FILM_MAX_SIDE || (uint64_t)x * y > TR_FILM_MAX_PIXELS) {
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
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    char buf[128];
    snprintf(buf, sizeof buf, "%s", a->value);
    *n = 0;
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok;
         tok = strtok_r(NULL, ",", &save)) {
        int k = tr_integrator_from_name(tok);
        if (k < 0 || *n == CONV_MAX_METHODS) {
            char names[128];
            cli_integrator_list(names, sizeof names);
            return cli_error(a, "%s: unknown integrator '%s' in '%s' (available: %s)", a->opt, tok,
                             a->value, names);
        }
        m[(*n)++] = k;
    }
    if (*n == 0) {
        return cli_error(a, "%s: expected a list such as 'naive,pt'", a->opt);
    }
    return CLI_OK;
}

/* Mean radiance of the film into rgb (3 floats per pixel). */
static void film_mean(const tr_film *f, float *rgb) {
    size_t n = (size_t)f->width * f->height;
    for (size_t i = 0; i < n; ++i) {
        float inv = f->count[i] ? 1.0f / (float)f->count[i] : 0.0f;
        for (int c = 0; c < 3; ++c) {
            rgb[3 * i + c] = f->sum[3 * i + c] * inv;
        }
    }
}

/* Releases what one image size of the benchmark holds. */
static void size_free(cli_backend *devs, int ndevs, float *ref, float *half, float *cur,
                      tr_film *film, tr_scene *scene) {
    for (int k = 0; k < ndevs; ++k) {
        cli_backend_close(&devs[k]);
    }
    free(ref);
    free(half);
    free(cur);
    tr_film_free(film);
    tr_scene_destroy(scene);
}

/* Renders samples [first, first + spp) on the device (its film cleared first) and reads
 * them into f. */
/* Renders samples first .. first+spp-1 into a cleared film, in calls of a few samples so
 * that `bar` moves (*done counts the samples so far); a pixel adds its samples in the
 * same order either way. */
static int render_spp(tr_device *dev, const tr_scene *s, const tr_render_config *cfg, tr_film *f,
                      uint32_t first, uint32_t spp, progress *bar, uint64_t *done, tr_error *err) {
    if (tr_device_clear(dev, err) != TR_OK) {
        return TR_ERR;
    }
    const uint32_t chunk = 16;
    for (uint32_t k = 0; k < spp; k += chunk) {
        const uint32_t n = spp - k < chunk ? spp - k : chunk;
        if (tr_device_render(dev, tr_scene_camera(s), cfg, first + k, n, NULL, NULL, err) !=
            TR_OK) {
            return TR_ERR;
        }
        *done += n;
        progress_update(bar, *done, NULL);
    }
    return tr_device_read_film(dev, f, err);
}

/* Time (or spp, with use_spp) at which the run first reaches `db`: interpolated
 * linearly in PSNR against log time between the bracketing points; < 0 if never. */
static double reach(const conv_run *r, double db, int use_spp) {
    for (int i = 0; i < r->n; ++i) {
        if (r->pt[i].psnr >= db) {
            double x1 = use_spp ? r->pt[i].spp : r->pt[i].seconds;
            if (i == 0) {
                return x1;
            }
            double x0 = use_spp ? r->pt[i - 1].spp : r->pt[i - 1].seconds;
            double p0 = r->pt[i - 1].psnr, p1 = r->pt[i].psnr;
            double f = p1 > p0 ? (db - p0) / (p1 - p0) : 1.0;
            return exp(log(x0) + f * (log(x1) - log(x0)));
        }
    }
    return -1.0;
}

int bench_convergence(int argc, char **argv) {
    cli_args a = {.cmd = "bench convergence", .argc = argc, .argv = argv, .i = 0};
    cli_common c;
    cli_common_default(&c);
    c.scene = "builtin:cornell-mirror";
    /* Both integrators estimate paths of the same length here (pt D, naive D + 2): the
     * comparison keeps the thesis's depth rather than each integrator's default. */
    c.max_depth = TR_MAX_DEPTH_NAIVE;
    uint32_t sw[CONV_MAX_SIZES] = {256, 800}, sh[CONV_MAX_SIZES] = {256, 600};
    int nsizes = 2;
    int methods[CONV_MAX_METHODS] = {TR_INTEGRATOR_NAIVE, TR_INTEGRATOR_PT, TR_INTEGRATOR_BDPT};
    int nmethods = 3;
    float budget = 30.0f;
    uint32_t ref_spp = 4096;
    const char *ref_path = NULL;
    const char *prefix = "convergence";
    while (cli_next(&a)) {
        if (cli_is(&a, "--width") || cli_is(&a, "--height") || cli_is(&a, "--integrator")) {
            return cli_error(&a, "%s: not an option of this benchmark (see --sizes, --methods)",
                             a.opt);
        }
        int rc = cli_common_option(&a, &c);
        if (rc == CLI_OK) {
            if (cli_is(&a, "--max-depth") && c.max_depth > TR_MAX_DEPTH_LIMIT - 2) {
                return cli_error(&a, "--max-depth: expected 1..%d here (naive gets D + 2)",
                                 TR_MAX_DEPTH_LIMIT - 2);
            }
            continue;
        }
        if (rc == CLI_USAGE) {
            return CLI_USAGE;
        }
        if (cli_is(&a, "-h") || cli_is(&a, "--help")) {
            convergence_help();
            return CLI_OK;
        } else if (cli_is(&a, "--sizes")) {
            rc = parse_sizes(&a, sw, sh, &nsizes);
        } else if (cli_is(&a, "--methods")) {
            rc = parse_methods(&a, methods, &nmethods);
        } else if (cli_is(&a, "--budget")) {
            rc = cli_parse_float(&a, 0.1f, 86400.0f, &budget);
        } else if (cli_is(&a, "--reference-spp")) {
            rc = cli_parse_u32(&a, 2, 1000000, &ref_spp);
        } else if (cli_is(&a, "--reference")) {
            rc = cli_value(&a);
            ref_path = a.value;
        } else if (cli_is(&a, "--out")) {
            rc = cli_value(&a);
            prefix = a.value;
        } else if (a.opt[0] != '-' && a.i == 1) {
            c.scene = a.opt;
            rc = CLI_OK;
        } else {
            return cli_unknown(&a);
        }
        if (rc != CLI_OK) {
            return CLI_USAGE;
        }
    }
    if (ref_path && nsizes != 1) {
        return cli_error(&a, "--reference: needs exactly one size in --sizes (it has %d)", nsizes);
    }
    char csv_path[4096], png_path[4096];
    if (snprintf(csv_path, sizeof csv_path, "%s.csv", prefix) >= (int)sizeof csv_path ||
        snprintf(png_path, sizeof png_path, "%s.png", prefix) >= (int)sizeof png_path) {
        return cli_error(&a, "--out: prefix too long");
    }
    tr_error err;
    if (tr_image_check_writable(csv_path, &err) != TR_OK ||
        tr_image_check_writable(png_path, &err) != TR_OK) {
        return cli_error(&a, "--out: %s", err.msg);
    }
    tr_image ref_img;
    memset(&ref_img, 0, sizeof ref_img);
    if (ref_path) {
        if (tr_image_format_from_path(ref_path) != TR_IMAGE_PFM) {
            return cli_error(&a, "--reference: '%s' is not a .pfm file", ref_path);
        }
        if (tr_image_read_pfm(&ref_img, ref_path, &err) != TR_OK) {
            return cli_error(&a, "--reference: %s", err.msg);
        }
        if (ref_img.width != sw[0] || ref_img.height != sh[0]) {
            int rc = cli_error(&a, "--reference: %s is %ux%u, not %ux%u", ref_path, ref_img.width,
                               ref_img.height, sw[0], sh[0]);
            tr_image_free(&ref_img);
            return rc;
        }
    }

    conv_run *runs = calloc((size_t)(nsizes * nmethods), sizeof *runs);
    if (!runs) {
        tr_image_free(&ref_img);
        return cli_error(&a, "out of memory");
    }
    const int threads = c.threads ? c.threads : tr_default_threads();
    printf("bench convergence: %s, pt max depth %d (naive %d), %d thread%s, budget %.1f s per "
           "method and size\n",
           c.scene, c.max_depth, c.max_depth + 2, threads, threads == 1 ? "" : "s", (double)budget);
    int rc = CLI_OK;
    for (int si = 0; si < nsizes && rc == CLI_OK; ++si) {
        c.width = sw[si];
        c.height = sh[si];
        tr_scene *scene = tr_scene_create(NULL);
        rc = cli_load_scene(&a, &c, scene);
        if (rc != CLI_OK) {
            tr_scene_destroy(scene);
            break;
        }
        /* A method that cannot render the scene (bdpt with an environment light or a sun)
         * fails here, not after the reference has been rendered. */
        for (int mi = 0; mi < nmethods && rc == CLI_OK; ++mi) {
            if (tr_integrator_supports(scene, methods[mi], &err) != TR_OK) {
                rc = cli_error(&a, "--methods %s: %s", tr_integrator_name(methods[mi]), err.msg);
            }
        }
        if (rc != CLI_OK) {
            tr_scene_destroy(scene);
            break;
        }
        if (si == 0) {
            for (uint32_t m = 0; m < tr_scene_material_count(scene); ++m) {
                const tr_material mat = tr_scene_material(scene, m);
                if (mat.type == TR_MATERIAL_GLOSSY && mat.roughness > 0.0f) {
                    printf("note: this scene has rough glossy materials, on which naive (cone "
                           "lobe) and pt (GGX) converge to different images\n");
                    break;
                }
            }
        }
        const size_t px = (size_t)c.width * c.height;
        float *ref = malloc(3 * px * sizeof *ref);
        float *half = malloc(3 * px * sizeof *half);
        float *cur = malloc(3 * px * sizeof *cur);
        tr_film film;
        int film_ok = ref && half && cur && tr_film_init(&film, c.width, c.height, &err) == TR_OK;
        /* One device for the reference and one per method: each keeps its own film. */
        cli_backend devs[CONV_MAX_METHODS + 1] = {{0}};
        for (int k = 0; film_ok && rc == CLI_OK && k <= nmethods; ++k) {
            rc = cli_backend_open(&a, &c, scene, &devs[k]);
        }
        if (rc != CLI_OK) {
            size_free(devs, nmethods + 1, ref, half, cur, &film, scene);
            break;
        }
        if (!film_ok) {
            fprintf(stderr, "trac0r bench convergence: %ux%u: %s\n", c.width, c.height,
                    ref && half && cur ? err.msg : "out of memory");
            free(ref);
            free(half);
            free(cur);
            tr_scene_destroy(scene);
            rc = CLI_FAILURE;
            break;
        }
        tr_render_config cfg = tr_render_config_default();
        cfg.threads = c.threads;
        cfg.integrator = TR_INTEGRATOR_PT;
        cfg.max_depth = c.max_depth;
        /* The reference's seed differs from the measured runs', so its noise is
         * independent of theirs. */
        cfg.seed = c.seed ^ 0x7265666572656e63ULL;
        double ref_mse = 0.0;
        if (ref_path) {
            memcpy(ref, ref_img.rgb, 3 * px * sizeof *ref);
            printf("%ux%u: reference %s (its own error unknown: not taken out)\n", c.width,
                   c.height, ref_path);
        } else {
            double t0 = tr_time_now();
            uint32_t h1 = ref_spp / 2, h2 = ref_spp - h1;
            char label[96];
            snprintf(label, sizeof label, "trac0r bench convergence: %ux%u reference", c.width,
                     c.height);
            progress bar;
            progress_begin(&bar, label, "spp", ref_spp, 0);
            uint64_t done_spp = 0;
            if (render_spp(devs[nmethods].dev, scene, &cfg, &film, 0, h1, &bar, &done_spp, &err) !=
                TR_OK) {
                rc = CLI_FAILURE;
            } else {
                film_mean(&film, half);
                if (render_spp(devs[nmethods].dev, scene, &cfg, &film, h1, h2, &bar, &done_spp,
                               &err) != TR_OK) {
                    rc = CLI_FAILURE;
                }
            }
            progress_end(&bar);
            if (rc != CLI_OK) {
                fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
            } else {
                film_mean(&film, cur);
                /* The halves' difference has twice a half's MSE (independent noise), and
                 * their mean a quarter of the difference's: MSE_ref = MSE(h1, h2) / 4
                 * (equal halves). Measured errors then have MSE_true + MSE_ref. */
                ref_mse = tr_image_compare(half, cur, px).mse / 4.0;
                for (size_t i = 0; i < 3 * px; ++i) {
                    ref[i] = ((float)h1 * half[i] + (float)h2 * cur[i]) / (float)ref_spp;
                }
                printf("%ux%u: reference pt %u spp in %.1f s, its own PSNR ~ %.1f dB\n", c.width,
                       c.height, ref_spp, tr_time_now() - t0, tr_psnr(ref_mse));
                fflush(stdout);
            }
        }
        /* The methods take turns, one frame at a time, the one with the least render
         * time so far next: on a machine shared with other work they see the same
         * load, which keeps their time ratio fair. */
        tr_film films[CONV_MAX_METHODS];
        uint32_t spp[CONV_MAX_METHODS] = {0}, next[CONV_MAX_METHODS] = {1, 1, 1};
        double elapsed[CONV_MAX_METHODS] = {0.0};
        int done[CONV_MAX_METHODS] = {0};
        int nfilms = 0;
        for (int mi = 0; mi < nmethods; ++mi) {
            conv_run *r = &runs[si * nmethods + mi];
            r->integrator = methods[mi];
            r->width = c.width;
            r->height = c.height;
            if (tr_film_init(&films[mi], c.width, c.height, &err) != TR_OK) {
                fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
                rc = CLI_FAILURE;
                break;
            }
            ++nfilms;
        }
        /* Progress in render time against the budget of every method (a method that
         * reaches 41 dB early counts as its whole budget). */
        char mlabel[96];
        snprintf(mlabel, sizeof mlabel, "trac0r bench convergence: %ux%u methods", c.width,
                 c.height);
        progress mbar;
        progress_begin(&mbar, mlabel, "ms of budget", (uint64_t)(budget * 1e3) * (uint64_t)nmethods,
                       0);
        while (rc == CLI_OK) {
            uint64_t used = 0;
            for (int k = 0; k < nmethods; ++k) {
                used += (uint64_t)((done[k] || elapsed[k] > budget ? budget : elapsed[k]) * 1e3);
            }
            progress_update(&mbar, used, NULL);
            int mi = -1;
            for (int k = 0; k < nmethods; ++k) {
                if (!done[k] && (mi < 0 || elapsed[k] < elapsed[mi])) {
                    mi = k;
                }
            }
            if (mi < 0) {
                break;
            }
            conv_run *r = &runs[si * nmethods + mi];
            cfg.integrator = methods[mi];
            cfg.max_depth = methods[mi] == TR_INTEGRATOR_NAIVE ? c.max_depth + 2 : c.max_depth;
            cfg.seed = c.seed;
            tr_render_stats st;
            if (cli_backend_frame(&devs[mi], scene, &cfg, spp[mi], &st, &err) != TR_OK) {
                progress_clear(&mbar);
                fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
                rc = CLI_FAILURE;
                break;
            }
            elapsed[mi] += st.seconds;
            ++spp[mi];
            int last = elapsed[mi] >= budget || r->n == CONV_MAX_POINTS - 1;
            if (spp[mi] == next[mi] || last) {
                if (cli_backend_read(&devs[mi], &films[mi], &err) != TR_OK) {
                    progress_clear(&mbar);
                    fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
                    rc = CLI_FAILURE;
                    break;
                }
                film_mean(&films[mi], cur);
                conv_point *p = &r->pt[r->n++];
                p->spp = spp[mi];
                p->seconds = elapsed[mi];
                p->raw = tr_image_compare(cur, ref, px);
                double mse = p->raw.mse - ref_mse;
                p->psnr = tr_psnr(mse);
                uint32_t step = (uint32_t)ceil(next[mi] * 0.19);
                next[mi] += step > 0 ? step : 1;
                if (p->psnr > 41.0 || last) {
                    done[mi] = 1;
                    progress_clear(&mbar);
                    printf("%ux%u %-5s: %u spp in %.2f s -> PSNR %.2f dB (raw %.2f), RMSE "
                           "%.5f, relMSE %.5f\n",
                           c.width, c.height, tr_integrator_name(r->integrator), p->spp, p->seconds,
                           p->psnr, p->raw.psnr, p->raw.rmse, p->raw.relmse);
                    fflush(stdout);
                }
            }
        }
        progress_end(&mbar);
        for (int k = 0; k < nfilms; ++k) {
            tr_film_free(&films[k]);
        }
        size_free(devs, nmethods + 1, ref, half, cur, &film, scene);
    }
    tr_image_free(&ref_img);
    if (rc != CLI_OK) {
        free(runs);
        return rc;
    }

    /* The table: time and spp to reach each PSNR. */
    printf("\n%-9s %-6s", "size", "method");
    for (int k = 0; k < CONV_THRESHOLDS; ++k) {
        printf("  %20.0f dB", conv_db[k]);
    }
    printf("\n");
    for (int i = 0; i < nsizes * nmethods; ++i) {
        const conv_run *r = &runs[i];
        char size[32];
        snprintf(size, sizeof size, "%ux%u", r->width, r->height);
        printf("%-9s %-6s", size, tr_integrator_name(r->integrator));
        for (int k = 0; k < CONV_THRESHOLDS; ++k) {
            double t = reach(r, conv_db[k], 0), s = reach(r, conv_db[k], 1);
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
    /* Speed-ups in time to each threshold: pt over naive, bdpt and vcm over pt. */
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
            if (!rn || !rp) {
                continue;
            }
            const char *sn = tr_integrator_name(rn->integrator);
            const char *sp = tr_integrator_name(rp->integrator);
            printf("%ux%u time %s / time %s:", rn->width, rn->height, sn, sp);
            for (int k = 0; k < CONV_THRESHOLDS; ++k) {
                double tn = reach(rn, conv_db[k], 0), tp = reach(rp, conv_db[k], 0);
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
    }

    tr_outfile *csv = tr_outfile_open(csv_path, &err);
    if (!csv) {
        free(runs);
        fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
        return CLI_FAILURE;
    }
    FILE *fp = tr_outfile_stream(csv);
    fprintf(fp, "method,width,height,spp,seconds,rmse,relmse,psnr_raw,psnr\n");
    for (int i = 0; i < nsizes * nmethods; ++i) {
        const conv_run *r = &runs[i];
        for (int k = 0; k < r->n; ++k) {
            const conv_point *p = &r->pt[k];
            fprintf(fp, "%s,%u,%u,%u,%.5f,%.6g,%.6g,%.4f,%.4f\n", tr_integrator_name(r->integrator),
                    r->width, r->height, p->spp, p->seconds, p->raw.rmse, p->raw.relmse,
                    p->raw.psnr, p->psnr);
        }
    }
    if (tr_outfile_commit(csv, &err) != TR_OK) {
        free(runs);
        fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
        return CLI_FAILURE;
    }

    /* gnuplot: one inline data block per run, PSNR against time and against spp. */
    size_t cap = 64 + (size_t)(nsizes * nmethods) * (CONV_MAX_POINTS * 48 + 256);
    char *script = malloc(cap);
    if (!script) {
        free(runs);
        return CLI_FAILURE;
    }
    size_t len = 0;
    for (int i = 0; i < nsizes * nmethods; ++i) {
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
    bench_plot_name(c.scene, name, sizeof name);
    for (int panel = 0; panel < 2; ++panel) {
        len += (size_t)snprintf(
            script + len, cap - len,
            "%sset logscale x\nset grid\nset key bottom right\nset ylabel 'PSNR (dB)'\n"
            "set xlabel '%s'\nset title 'PSNR against %s: %s'\nplot ",
            panel == 0 ? "set multiplot layout 1,2\n" : "",
            panel == 0 ? "render time (s)" : "samples per pixel", panel == 0 ? "time" : "spp",
            name);
        for (int i = 0; i < nsizes * nmethods; ++i) {
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
    int plotted = len < cap ? bench_plot_png(script, png_path, &err) : 0;
    free(script);
    free(runs);
    if (plotted < 0) {
        fprintf(stderr, "trac0r bench convergence: %s\n", err.msg);
        return CLI_FAILURE;
    }
    printf("wrote %s%s%s\n", csv_path, plotted ? " and " : " (gnuplot failed: no plot)",
           plotted ? png_path : "");
    return CLI_OK;
}
