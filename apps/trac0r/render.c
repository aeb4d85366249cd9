/* render.c - `trac0r render`: render a scene progressively to an image file. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "devices.h"
#include "progress.h"
#include "render_adaptive.h"
#include "render_job.h"
#include "trac0r/outfile.h"

/* The film's radiance through the edge-avoiding a-trous filter guided by its albedo,
 * normal and depth passes, into `den` (radiance only, one sample per covered pixel). */
static int render_denoise(const tr_film *film, tr_film *den, tr_error *err) {
    tr_gbuffer g = {0};
    const tr_recon_params p = tr_recon_params_default();
    int rc = tr_gbuffer_init(&g, film->width, film->height, err);
    rc = rc == TR_OK ? tr_gbuffer_from_film(&g, film, err) : rc;
    rc = rc == TR_OK ? tr_film_init(den, film->width, film->height, err) : rc;
    rc = rc == TR_OK ? tr_filter_atrous(&g, g.color, den->sum, &p, 0, err) : rc;
    for (size_t i = 0; rc == TR_OK && i < (size_t)film->width * film->height; ++i) {
        den->count[i] = film->count[i] ? 1u : 0u;
    }
    tr_gbuffer_free(&g);
    return rc;
}

/* Writes the film (PNG or PFM), first through the a-trous filter (denoise) and, for a
 * PNG, the display curve; the plain path (clamp, no filter) is tr_film_write as before. */
static int render_write(const tr_film *film, const char *out, float exposure, int curve,
                        int denoise, tr_error *err) {
    const int png = tr_image_format_from_path(out) == TR_IMAGE_PNG;
    if (!denoise && (curve == TR_TONEMAP_CLAMP || !png)) {
        return tr_film_write(film, out, exposure, err);
    }
    tr_film den = {0}, disp = {0};
    const tr_film *img = film;
    int rc = TR_OK;
    if (denoise) {
        rc = render_denoise(film, &den, err);
        img = &den;
    }
    if (rc == TR_OK && png && curve != TR_TONEMAP_CLAMP) {
        rc = tr_tonemap_display_film(img, exposure, curve, &disp, err);
        img = &disp;
        exposure = 0.0f; /* applied */
    }
    rc = rc == TR_OK ? tr_film_write(img, out, exposure, err) : rc;
    tr_film_free(&disp);
    tr_film_free(&den);
    return rc;
}

static void render_help(void) {
    printf("Usage: trac0r render [SCENE] [options]\n"
           "\n"
           "Renders a scene on the CPU or an OpenCL device (--device), accumulating one sample\n"
           "per pixel per pass (on a device, in a film read back once at the end),\n"
           "and writes the result. With no arguments it renders the thesis's Cornell box at\n"
           "800x600 to render.png. SCENE is a built-in scene or a scene file\n"
           "(docs/scene-format.md); a file's render defaults (size, spp, max depth,\n"
           "integrator, accel) apply unless the command line gives them.\n"
           "\n"
           "Options:\n"
           "%s"
           "  --spp N              samples per pixel, 1..1000000 (default 16)\n"
           "  --stride K           preview mode: trace every K-th pixel in x and y and fill\n"
           "                       KxK blocks, 1..64 (default 1: every pixel)\n"
           "  --exposure EV        PNG exposure in stops, -20..20 (default 0): radiance is\n"
           "                       scaled by 2^EV, clamped to [0,1] and sRGB-encoded\n"
           "  --out FILE           output image, .png (8-bit sRGB), .pfm (float linear RGB)\n"
           "                       or .exr (OpenEXR, linear RGB with the passes as layers)\n"
           "                       (default render.png); written to a temporary file and\n"
           "                       renamed, so it never exists half-written\n"
           "  --exr-type T         EXR channel type, half or float (default float)\n"
           "  --passes LIST        also write these passes beside the image, comma-separated:\n"
           "                       albedo, normal, depth, id, variance (or all); each goes to\n"
           "                       FILE-without-extension.PASS.pfm, or into the EXR as layers\n"
           "                       albedo.RGB, normal.XYZ, depth.Z, id, variance.RGB (float:\n"
           "                       the pixel's mean base colour, shading normal, distance\n"
           "                       from the camera, primitive id, at the first surface that\n"
           "                       is not a mirror or smooth glass, 0 where a sample met\n"
           "                       none; the variance of the pixel's mean radiance per\n"
           "                       channel, 0 below 2 samples)\n"
           "  --checkpoint FILE    save the film and what is needed to continue to FILE\n"
           "                       every --checkpoint-interval, on SIGINT/SIGTERM and at\n"
           "                       the end (atomically: the last complete one survives)\n"
           "  --checkpoint-interval S  seconds between checkpoints, 0..1e6 (default 60;\n"
           "                       0: after every pass)\n"
           "  --resume FILE        continue the render saved in FILE: the image is\n"
           "                       bit-identical to an uninterrupted render of --spp samples\n"
           "                       (default: the checkpoint's); the scene and options must\n"
           "                       be the checkpoint's\n"
           "  --noise-threshold E  adaptive sampling, 0..1 (default 0: off): 8x8-pixel tiles\n"
           "                       stop once their pixels' mean error estimate is below E (at\n"
           "                       16, 32, 64, ... spp: the mean of N samples against that\n"
           "                       of the first N/2, relative to the square root of the\n"
           "                       pixel's value; 0.01 is a good start); --spp is the most\n"
           "                       a pixel gets. Not with --stride, --checkpoint or mpirun\n"
           "  --tonemap CURVE      PNG display curve: clamp (default) or filmic (an ACES-like\n"
           "                       fitted curve that rolls highlights off); PFM and EXR\n"
           "                       stay linear\n"
           "  --denoise            filter the final image with the edge-avoiding a-trous\n"
           "                       filter guided by the albedo, normal and depth passes\n"
           "                       (docs/realtime.md); the passes are rendered for it\n"
           "  --time-limit S       stop before a pass that would end after S seconds,\n"
           "                       0..1e6 (default 0: none); the image is complete, and the\n"
           "                       same as one rendered with the spp it reached. Not with\n"
           "                       --checkpoint or mpirun\n"
           "  --verbose            after the summary, where the time went: setting up (scene,\n"
           "                       acceleration structure, device), rendering, and the CPU\n"
           "                       time used (user + system); under mpirun per rank, with\n"
           "                       the time spent waiting, on messages and on pixels\n"
           "  -h, --help           show this help\n"
           "\n"
           "Progress (a bar with the ETA on a terminal, otherwise a line a second) goes to\n"
           "stderr, then one summary line. SIGINT or SIGTERM (Ctrl-C) stops the render at the\n"
           "end of the pass under way and writes the image of the samples so far (and the\n"
           "checkpoint); a second signal ends it at once. Under mpirun the ranks share the\n"
           "tiles of the image (docs/distributed.md).\n"
           "Exit status: 0 on success, 2 on a bad command line or a checkpoint of another\n"
           "render, 1 when rendering or writing fails, 128+N after signal N (the image of\n"
           "the samples so far written).\n",
           cli_common_help());
}

/* --passes: "albedo,normal,depth,id,variance" or "all" into TR_PASS_* bits. */
static int parse_passes(cli_args *a, uint32_t *passes) {
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    *passes = 0;
    const char *p = a->value;
    while (*p) {
        size_t len = strcspn(p, ",");
        uint32_t bit = 0;
        if (len == 3 && strncmp(p, "all", 3) == 0) {
            /* The direct and emission passes feed the real-time filters; render does not
             * write them. */
            bit = TR_PASS_MASK & ~(TR_PASS_DIRECT | TR_PASS_EMISSION);
        }
        for (uint32_t k = 1; k <= TR_PASS_VARIANCE && !bit; k <<= 1) {
            const char *name = tr_pass_name(k);
            if (strlen(name) == len && strncmp(p, name, len) == 0) {
                bit = k;
            }
        }
        if (!bit) {
            return cli_error(a,
                             "%s: unknown pass '%.*s' (expected albedo, normal, depth, id, "
                             "variance or all)",
                             a->opt, (int)len, p);
        }
        *passes |= bit;
        p += len;
        if (*p == ',') {
            ++p;
            if (!*p) {
                return cli_error(a, "%s: '%s' ends with a comma", a->opt, a->value);
            }
        }
    }
    if (!*passes) {
        return cli_error(a, "%s: expected a list of passes", a->opt);
    }
    return CLI_OK;
}

/* "dir/img.png" -> "dir/img.albedo.pfm" for pass `bit`. */
static int pass_path(const char *out, uint32_t bit, char *buf, size_t size) {
    const char *slash = strrchr(out, '/');
    const char *dot = strrchr(out, '.');
    const size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - out) : strlen(out);
    const int n = snprintf(buf, size, "%.*s.%s.pfm", (int)stem, out, tr_pass_name(bit));
    return n < 0 || (size_t)n >= size ? -1 : 0;
}

double render_cpu_seconds(void) {
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) {
        return 0.0;
    }
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
           (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
}

/* The extra options of render (one block, so other commands' options merge apart). */
static int render_option(render_job *job, int *rc) {
    cli_args *a = &job->args;
    if (cli_is(a, "--checkpoint")) {
        *rc = cli_value(a);
        job->checkpoint = a->value;
    } else if (cli_is(a, "--checkpoint-interval")) {
        float s = 0.0f;
        *rc = cli_parse_float(a, 0.0f, 1e6f, &s);
        job->checkpoint_interval = s;
    } else if (cli_is(a, "--resume")) {
        *rc = cli_value(a);
        job->resume = a->value;
    } else if (cli_is(a, "--noise-threshold")) {
        *rc = cli_parse_float(a, 0.0f, 1.0f, &job->noise_threshold);
    } else if (cli_is(a, "--time-limit")) {
        *rc = cli_parse_float(a, 0.0f, 1e6f, &job->time_limit);
    } else if (cli_is(a, "--tonemap")) {
        *rc = cli_value(a);
        if (*rc == CLI_OK && (job->curve = tr_tonemap_curve_parse(a->value)) < 0) {
            *rc = cli_error(a, "--tonemap: expected clamp or filmic, got '%s'", a->value);
        }
    } else if (cli_is(a, "--denoise")) {
        job->denoise = 1;
        *rc = CLI_OK;
    } else if (cli_is(a, "--verbose")) {
        job->verbose = 1;
        *rc = CLI_OK;
    } else if (cli_is(a, "--exr-type")) {
        *rc = cli_value(a);
        if (*rc == CLI_OK && strcmp(a->value, "half") != 0 && strcmp(a->value, "float") != 0) {
            *rc = cli_error(a, "%s: expected half or float, got '%s'", a->opt, a->value);
        }
        job->exr_half = *rc == CLI_OK && strcmp(a->value, "half") == 0;
    } else {
        return 0;
    }
    return 1;
}

void render_job_free(render_job *job) {
    if (job->be_open) {
        cli_backend_close(&job->be);
        job->be_open = 0;
    }
    tr_scene_destroy(job->scene);
    job->scene = NULL;
}

int render_job_setup(render_job *job, int argc, char **argv, int *done) {
    memset(job, 0, sizeof *job);
    job->started = tr_time_now();
    job->args = (cli_args){.cmd = "render", .argc = argc, .argv = argv, .i = 0};
    cli_args *a = &job->args;
    cli_common *c = &job->common;
    cli_common_default(c);
    job->spp = 16;
    job->out = "render.png";
    job->checkpoint_interval = 60.0;
    int scene_arg = 0, stride = 1;
    *done = 1;

    while (cli_next(a)) {
        int rc = cli_common_option(a, c);
        if (rc == CLI_OK) {
            continue;
        }
        if (rc == CLI_USAGE) {
            return CLI_USAGE;
        }
        if (cli_is(a, "-h") || cli_is(a, "--help")) {
            render_help();
            return CLI_OK;
        } else if (cli_is(a, "--spp")) {
            rc = cli_parse_u32(a, 1, 1000000, &job->spp);
            job->spp_given = 1;
        } else if (cli_is(a, "--stride")) {
            rc = cli_parse_int(a, 1, 64, &stride);
        } else if (cli_is(a, "--exposure")) {
            rc = cli_parse_float(a, -20.0f, 20.0f, &job->exposure);
        } else if (cli_is(a, "--passes")) {
            rc = parse_passes(a, &job->passes);
        } else if (cli_is(a, "--out") || cli_is(a, "-o")) {
            rc = cli_value(a);
            job->out = a->value;
        } else if (render_option(job, &rc)) {
            /* handled */
        } else if (a->opt[0] != '-' && !scene_arg) {
            c->scene = a->opt; /* positional SCENE, anywhere on the line */
            scene_arg = 1;
            rc = CLI_OK;
        } else {
            return cli_unknown(a);
        }
        if (rc != CLI_OK) {
            return CLI_USAGE;
        }
    }
    if (job->noise_threshold > 0.0f && stride > 1) {
        return cli_error(a,
                         "--noise-threshold: not with --stride %d (a preview traces too few "
                         "pixels to estimate their noise)",
                         stride);
    }
    if ((job->noise_threshold > 0.0f || job->time_limit > 0.0f) &&
        (job->checkpoint || job->resume)) {
        /* A checkpoint holds whole passes over the image; an adaptive render's tiles stop
         * at different sample counts, which the checkpoint format does not record. */
        return cli_error(a, "%s: not with --checkpoint or --resume",
                         job->noise_threshold > 0.0f ? "--noise-threshold" : "--time-limit");
    }
    const tr_image_format fmt = tr_image_format_from_path(job->out);
    if (fmt == TR_IMAGE_UNKNOWN) {
        return cli_error(a, "--out: '%s' has an unknown extension (expected .png, .pfm or .exr)",
                         job->out);
    }
    tr_error err;
    if (tr_image_check_writable(job->out, &err) != TR_OK) {
        return cli_error(a, "--out: %s", err.msg);
    }
    if (job->checkpoint && tr_image_check_writable(job->checkpoint, &err) != TR_OK) {
        return cli_error(a, "--checkpoint: %s", err.msg);
    }
    for (int k = 0; k < 5 && fmt != TR_IMAGE_EXR; ++k) {
        const uint32_t bit = 1u << k;
        if ((job->passes & bit) != 0u &&
            pass_path(job->out, bit, job->pass_paths[k], sizeof job->pass_paths[k]) != 0) {
            return cli_error(a, "--out: '%s' is too long for the pass files' names", job->out);
        }
    }

    /* The passes written as files or layers are the ones asked for; --denoise needs the
     * guides in the film too (the radiance does not change with passes). */
    job->write_passes = job->passes;
    if (job->denoise) {
        job->passes |= TR_PASS_ALBEDO | TR_PASS_NORMAL | TR_PASS_DEPTH;
    }
    job->scene = tr_scene_create(NULL);
    tr_scene_file file;
    int rc = cli_load_scene_file(a, c, job->scene, &file);
    if (rc != CLI_OK) {
        return rc;
    }
    if (!job->spp_given && file.has_spp) {
        job->spp = file.spp;
    }
    if (tr_film_check_size(c->width, c->height, &err) != TR_OK) {
        return cli_error(a, "--width/--height: %s", err.msg);
    }
    if ((job->checkpoint || job->resume) &&
        checkpoint_identity(&job->id, c, job->scene, stride, job->passes, &err) != TR_OK) {
        return cli_error(a, "%s", err.msg);
    }
    rc = cli_backend_open(a, c, job->scene, &job->be);
    if (rc != CLI_OK) {
        return rc;
    }
    job->be_open = 1;
    job->cfg = cli_render_config(c);
    job->cfg.stride = stride;
    job->cfg.passes = job->passes;
    *done = 0;
    return CLI_OK;
}

int render_write_outputs(const render_job *job, const tr_film *film, uint32_t samples,
                         double elapsed, uint64_t rays, const char *stopped) {
    tr_error err;
    const char *out = job->out;
    int rc = CLI_OK;
    if (tr_image_format_from_path(out) == TR_IMAGE_EXR) {
        /* A view of the film with the layers asked for; its radiance denoised if asked
         * (the variance layer stays the noise of the rendered estimate). */
        tr_film view = *film, den = {0};
        view.passes = job->write_passes;
        if (job->denoise) {
            rc = render_denoise(film, &den, &err) == TR_OK ? CLI_OK : CLI_FAILURE;
        }
        if (rc == CLI_OK) {
            rc = tr_film_write_exr_rgb(&view, job->denoise ? &den : &view, out, job->exr_half,
                                       &err) == TR_OK
                     ? CLI_OK
                     : CLI_FAILURE;
        }
        tr_film_free(&den);
    } else {
        rc = render_write(film, out, job->exposure, job->curve, job->denoise, &err) == TR_OK
                 ? CLI_OK
                 : CLI_FAILURE;
        for (int k = 0; k < 5 && rc == CLI_OK; ++k) {
            tr_film pass;
            if ((job->write_passes & (1u << k)) == 0u) {
                continue;
            }
            if (tr_film_extract_pass(film, 1u << k, &pass, &err) != TR_OK ||
                tr_film_write_pfm(&pass, job->pass_paths[k], &err) != TR_OK) {
                rc = CLI_FAILURE;
            }
            tr_film_free(&pass);
        }
    }
    if (rc != CLI_OK) {
        fprintf(stderr, "trac0r render: %s\n", err.msg);
        return rc;
    }
    char accel[160];
    cli_describe_accel(accel, sizeof accel, job->scene);
    fprintf(stderr, "trac0r render: %s %ux%u, %u spp%s%s%s, %s, %s: %.2f s, %.2f Mrays/s -> %s\n",
            job->common.scene, job->common.width, job->common.height, samples, stopped ? " (" : "",
            stopped ? stopped : "", stopped ? ")" : "", job->be.name, accel, elapsed,
            elapsed > 0 ? (double)rays / elapsed * 1e-6 : 0.0, out);
    return CLI_OK;
}

/* One sample per pixel added to a film in host memory (a resumed render's): on the CPU
 * straight into it, as the device would into its own; elsewhere through the device's
 * film, cleared, and added - one float addition per sum either way, so the bits are
 * those of the device's own accumulation. */
static int host_frame(render_job *job, tr_film *film, tr_film *scratch, uint32_t s,
                      tr_render_stats *st, tr_error *err) {
    if (cli_backend_is_cpu(&job->be)) {
        return tr_render_frame(job->scene, tr_scene_camera(job->scene), &job->cfg, film, s, st,
                               err);
    }
    if (cli_backend_clear(&job->be, err) != TR_OK ||
        cli_backend_frame(&job->be, job->scene, &job->cfg, s, st, err) != TR_OK ||
        cli_backend_read(&job->be, scratch, err) != TR_OK) {
        return TR_ERR;
    }
    return tr_film_accumulate(film, scratch, err);
}

/* The single-process render with a noise threshold or a time limit (render_adaptive.c). */
static int render_budgeted(render_job *job, tr_film *film) {
    tr_error err;
    adapt_options ao = {job->spp, job->noise_threshold, job->time_limit, isatty(fileno(stderr))};
    adapt_result ares;
    memset(&ares, 0, sizeof ares);
    const double t0 = tr_time_now();
    if (adapt_render(&job->be, job->scene, &job->cfg, &ao, &ares, &err) != TR_OK ||
        cli_backend_read(&job->be, film, &err) != TR_OK) {
        fprintf(stderr, "trac0r render: %s\n", err.msg);
        return CLI_FAILURE;
    }
    char note[160];
    snprintf(note, sizeof note, "of %u%s, %.1f spp on average, %u of %u tiles converged", job->spp,
             ares.stopped_by_time ? ", time limit" : "",
             (double)ares.samples / ((double)job->common.width * job->common.height),
             ares.tiles_converged, ares.tiles);
    return render_write_outputs(job, film, ares.passes, tr_time_now() - t0, ares.rays, note);
}

/* The single-process render: whole passes over the image, sample by sample. */
static int render_local(render_job *job) {
    cli_args *a = &job->args;
    tr_error err;
    tr_film film, scratch;
    memset(&scratch, 0, sizeof scratch);
    uint32_t first = 0;
    int host = 0; /* the film lives in host memory (resumed) rather than on the device */
    if (job->resume) {
        uint32_t mode = 0, ck_spp = 0;
        if (checkpoint_read(job->resume, &job->id, &mode, &film, &first, &ck_spp, &err) != TR_OK) {
            return err.code == TR_STATUS_INVALID_ARGUMENT || err.code == TR_STATUS_PARSE
                       ? cli_error(a, "--resume: %s", err.msg)
                       : (fprintf(stderr, "trac0r render: --resume: %s\n", err.msg), CLI_FAILURE);
        }
        if (mode != CHECKPOINT_PASSES) {
            tr_film_free(&film);
            return cli_error(a, "--resume: %s was written by an MPI render: resume it under mpirun",
                             job->resume);
        }
        if (!job->spp_given) {
            job->spp = ck_spp;
        }
        if (job->spp < first) {
            tr_film_free(&film);
            return cli_error(a, "--spp: %u is fewer than the %u samples of %s", job->spp, first,
                             job->resume);
        }
        host = 1;
        if (!cli_backend_is_cpu(&job->be) &&
            tr_film_init_passes(&scratch, film.width, film.height, film.passes, &err) != TR_OK) {
            tr_film_free(&film);
            fprintf(stderr, "trac0r render: %s\n", err.msg);
            return CLI_FAILURE;
        }
    } else if (tr_film_init_passes(&film, job->common.width, job->common.height, job->passes,
                                   &err) != TR_OK) {
        fprintf(stderr, "trac0r render: %s\n", err.msg);
        return CLI_FAILURE;
    }

    if (job->noise_threshold > 0.0f || job->time_limit > 0.0f) {
        const int rc = render_budgeted(job, &film);
        tr_film_free(&film);
        return rc;
    }
    render_stop_install();
    progress bar;
    progress_begin(&bar, "trac0r render", "spp", job->spp, 0);
    const double t0 = tr_time_now();
    double last_checkpoint = t0;
    uint64_t rays = 0;
    int rc = CLI_OK;
    uint32_t s = first;
    /* The film as the last pass left it, in `film`: reading it off the device is
     * needed only for a checkpoint or the image. */
    for (; s < job->spp && !render_stop_signal(); ++s) {
        tr_render_stats st;
        const int ok = host ? host_frame(job, &film, &scratch, s, &st, &err)
                            : cli_backend_frame(&job->be, job->scene, &job->cfg, s, &st, &err);
        if (ok != TR_OK) {
            progress_end(&bar);
            fprintf(stderr, "trac0r render: %s\n", err.msg);
            rc = CLI_FAILURE;
            break;
        }
        rays += st.rays;
        const double el = tr_time_now() - t0;
        char rate[48];
        snprintf(rate, sizeof rate, "%.2f Mrays/s", el > 0 ? (double)rays / el * 1e-6 : 0.0);
        progress_update(&bar, s + 1, rate);
        if (job->checkpoint && s + 1 < job->spp &&
            tr_time_now() - last_checkpoint >= job->checkpoint_interval) {
            if ((!host && cli_backend_read(&job->be, &film, &err) != TR_OK) ||
                checkpoint_write(job->checkpoint, &job->id, CHECKPOINT_PASSES, &film, s + 1,
                                 job->spp, &err) != TR_OK) {
                progress_end(&bar);
                fprintf(stderr, "trac0r render: --checkpoint: %s\n", err.msg);
                rc = CLI_FAILURE;
                break;
            }
            last_checkpoint = tr_time_now();
        }
    }
    progress_end(&bar);
    const double elapsed = tr_time_now() - t0;
    const int sig = render_stop_signal();
    if (rc == CLI_OK && s == 0) {
        fprintf(stderr,
                "trac0r render: stopped by signal %d before the first sample: nothing "
                "written\n",
                sig);
    } else if (rc == CLI_OK) {
        if (!host && cli_backend_read(&job->be, &film, &err) != TR_OK) {
            fprintf(stderr, "trac0r render: %s\n", err.msg);
            rc = CLI_FAILURE;
        }
        if (rc == CLI_OK && job->checkpoint &&
            checkpoint_write(job->checkpoint, &job->id, CHECKPOINT_PASSES, &film, s, job->spp,
                             &err) != TR_OK) {
            fprintf(stderr, "trac0r render: --checkpoint: %s\n", err.msg);
            rc = CLI_FAILURE;
        }
        char note[96];
        snprintf(note, sizeof note, "stopped by signal %d after %u of %u", sig, s, job->spp);
        if (rc == CLI_OK) {
            rc = render_write_outputs(job, &film, s, elapsed, rays, sig ? note : NULL);
        }
    }
    render_stop_uninstall();
    if (rc == CLI_OK && job->verbose) {
        fprintf(stderr,
                "trac0r render: setup %.3f s, rendering %.3f s, output %.3f s; CPU %.3f s (user "
                "+ system)\n",
                t0 - job->started, elapsed, tr_time_now() - t0 - elapsed, render_cpu_seconds());
    }
    tr_film_free(&scratch);
    tr_film_free(&film);
    return rc == CLI_OK && sig ? 128 + sig : rc;
}

int cmd_render(int argc, char **argv) {
#ifdef TRAC0R_HAVE_MPI
    if (render_mpi_wanted()) {
        return render_mpi_main(argc, argv);
    }
#endif
    render_job job;
    int done = 0;
    int rc = render_job_setup(&job, argc, argv, &done);
    if (!done) {
        rc = render_local(&job);
    }
    render_job_free(&job);
    return rc;
}
