/* render.c - `trac0r render`: render a scene progressively to an image file. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "devices.h"
#include "progress.h"
#include "render_job.h"
#include "stop.h"
#include "trac0r/outfile.h"

static void render_help(FILE *fp) {
    fprintf(fp,
            "Usage: trac0r render [SCENE] [options]\n"
            "\n"
            "Renders SCENE (default builtin:cornell, the thesis's Cornell box) and writes\n"
            "the image. A scene file's render defaults apply to the options not given.\n"
            "The full manual: man trac0r (docs/cli.md).\n"
            "\n"
            "Options:\n"
            "%s"
            "  --spp N              samples per pixel, 1..1000000 (default: the file's, else\n"
            "                       adaptive to 0.01 up to 64 spp, then --denoise)\n"
            "  --stride K           preview: trace every K-th pixel, 1..64 (default 1)\n"
            "  --exposure EV        PNG exposure in stops, -20..20 (default 0)\n"
            "  --out FILE           .png, .pfm or .exr (default render.png)\n"
            "  --exr-type T         EXR channel type, half or float (default float)\n"
            "  --passes LIST        also write albedo,normal,depth,id,variance (or all)\n"
            "  --checkpoint FILE    save the render to FILE to continue it later\n"
            "  --checkpoint-interval S  seconds between checkpoints, 0..1e6 (default 60)\n"
            "  --resume FILE        continue the render saved in FILE (bit-identical)\n"
            "  --noise-threshold E  adaptive sampling per 8x8 tile, 0..1 (0: off)\n"
            "  --tonemap CURVE      PNG display curve: clamp (default) or filmic\n"
            "  --denoise            filter the image with the offline denoiser\n"
            "  --no-denoise         write the image as rendered\n"
            "  --time-limit S       stop before a pass would end after S seconds, 0..1e6\n"
            "  --verbose            the structure's size, and where the time went\n"
            "  -h, --help           show this help\n"
            "\n"
            "SIGINT or SIGTERM writes the image of the samples so far. Exit status: 0 done,\n"
            "2 bad command line or input, 1 rendering or writing failed, 128+N signal N.\n",
            cli_common_help());
}

/* --passes' names: a pass's TR_PASS_* bit, or all: every pass render writes (the direct,
 * emission and specular passes feed the real-time filters only). */
static int pass_bits(const char *name) {
    if (strcmp(name, "all") == 0) {
        return (int)(TR_PASS_ALL | TR_PASS_VARIANCE);
    }
    for (uint32_t k = 1; k <= TR_PASS_VARIANCE; k <<= 1) {
        if (strcmp(tr_pass_name(k), name) == 0) {
            return (int)k;
        }
    }
    return -1;
}

/* --passes: "albedo,normal,depth,id,variance" or "all" into TR_PASS_* bits. */
static int parse_passes(cli_args *a, uint32_t *passes) {
    int bits[16];
    const int n =
        cli_parse_list(a, pass_bits, bits, 16, "pass", "albedo, normal, depth, id, variance, all");
    *passes = 0;
    for (int i = 0; i < n; ++i) {
        *passes |= (uint32_t)bits[i];
    }
    return n < 0 ? CLI_USAGE : CLI_OK;
}

/* "dir/img.png" -> "dir/img.albedo.pfm" for pass `bit`. */
static int pass_path(const char *out, uint32_t bit, char *buf, size_t size) {
    const char *slash = strrchr(out, '/');
    const char *dot = strrchr(out, '.');
    const size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - out) : strlen(out);
    const int n = snprintf(buf, size, "%.*s.%s.pfm", (int)stem, out, tr_pass_name(bit));
    return n < 0 || (size_t)n >= size ? -1 : 0;
}

/* render's own options: CLI_OK, CLI_USAGE, or -1 for none of them. */
static int render_option(cli_args *a, void *user) {
    render_job *job = user;
    int rcv = -1, *rc = &rcv;
    if (cli_is(a, "--spp")) {
        *rc = cli_parse_u32(a, 1, 1000000, &job->spp);
        job->spp_given = 1;
    } else if (cli_is(a, "--stride")) {
        *rc = cli_parse_int(a, 1, 64, &job->stride);
    } else if (cli_is(a, "--exposure")) {
        *rc = cli_parse_float(a, -20.0f, 20.0f, &job->exposure);
    } else if (cli_is(a, "--passes")) {
        *rc = parse_passes(a, &job->passes);
    } else if (cli_is(a, "--out") || cli_is(a, "-o")) {
        *rc = cli_value(a);
        job->out = a->value;
    } else if (a->opt[0] != '-' && !(job->common.given & CLI_GIVEN_SCENE)) {
        job->common.scene = a->opt; /* positional SCENE, anywhere on the line */
        job->common.given |= CLI_GIVEN_SCENE;
        *rc = CLI_OK;
    } else if (cli_is(a, "--checkpoint")) {
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
    } else if (cli_is(a, "--no-denoise")) {
        job->no_denoise = 1;
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
    }
    return rcv;
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
    job->stride = 1;
    *done = 1;
    const int rc0 = cli_parse(a, c, NULL, render_help, render_option, job);
    if (rc0 != CLI_OK) {
        return rc0 == CLI_HELP ? CLI_OK : rc0;
    }
    if (job->noise_threshold > 0.0f && job->stride > 1) {
        return cli_error(a,
                         "--noise-threshold: not with --stride %d (a preview traces too few "
                         "pixels to estimate their noise)",
                         job->stride);
    }
    if (job->noise_threshold > 0.0f && (job->checkpoint || job->resume)) {
        /* An adaptive render's tiles stop at different sample counts, on tests of
         * half-films that a checkpoint does not keep. */
        return cli_error(a, "--noise-threshold: not with --checkpoint or --resume");
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
        /* A pass file's target is checked now too, not found a directory after rendering. */
        if ((job->passes & bit) != 0u &&
            tr_image_check_writable(job->pass_paths[k], &err) != TR_OK) {
            return cli_error(a, "--passes: %s", err.msg);
        }
    }
    const char *targets[7] = {job->out, job->checkpoint};
    for (int k = 0; k < 5 && fmt != TR_IMAGE_EXR; ++k) {
        targets[2 + k] = (job->passes & (1u << k)) != 0u ? job->pass_paths[k] : NULL;
    }
    if (tr_outfile_check_distinct(targets, 7, &err) != TR_OK) {
        return cli_error(a, "--out/--checkpoint/--passes: %s", err.msg);
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
    render_apply_defaults(job, job->stride, file.has_spp);
    if (tr_film_check_size(c->width, c->height, &err) != TR_OK) {
        return cli_error(a, "--width/--height: %s", err.msg);
    }
    rc = cli_backend_open(a, c, job->scene, &job->be);
    if (rc != CLI_OK) {
        return rc;
    }
    job->be_open = 1;
    job->cfg = cli_render_config(c);
    job->cfg.stride = job->stride;
    job->cfg.passes = job->passes;
    *done = 0;
    return CLI_OK;
}

tr_session_desc render_session_desc(const render_job *job) {
    tr_session_desc d = {0};
    /* Resumed without --spp: the checkpoint's. */
    d.spp = job->resume && !job->spp_given ? 0u : job->spp;
    d.noise_threshold = job->noise_threshold;
    d.time_limit = job->time_limit;
    d.checkpoint = job->checkpoint;
    /* --checkpoint-interval 0 means after every pass. */
    d.checkpoint_interval = job->checkpoint_interval > 0.0 ? job->checkpoint_interval : -1.0;
    d.resume = job->resume;
    d.scene_file = tr_scene_name_is_builtin(job->common.scene) ? NULL : job->common.scene;
    d.denoise = job->denoise;
    return d;
}

int render_session_error(render_job *job, const tr_error *err) {
    if (err->code == TR_STATUS_LIMIT && job->resume) {
        return cli_error(&job->args, "--spp: %s", err->msg); /* below the checkpoint's */
    }
    if (err->code == TR_STATUS_UNSUPPORTED) { /* the integrator and the scene's lights */
        return cli_error(&job->args, "--integrator: %s: %s", job->common.scene, err->msg);
    }
    if (err->code == TR_STATUS_INVALID_ARGUMENT || err->code == TR_STATUS_PARSE ||
        (job->resume && err->code == TR_STATUS_NOT_FOUND)) {
        return cli_error(&job->args, "%s%s", job->resume ? "--resume: " : "", err->msg);
    }
    fprintf(stderr, "trac0r render: %s%s\n", job->resume ? "--resume: " : "", err->msg);
    return CLI_FAILURE;
}

/* The image and its passes written as PFM files beside it (not EXR). */
static int write_plain(const render_job *job, const tr_film *film, const tr_film *img,
                       tr_error *err) {
    int rc = tr_film_write_curve(img, job->out, job->exposure, job->curve, err);
    for (int k = 0; k < 5 && rc == TR_OK; ++k) {
        tr_film pass;
        if ((job->passes & (1u << k)) == 0u) {
            continue;
        }
        rc = tr_film_extract_pass(film, 1u << k, &pass, err);
        rc = rc == TR_OK ? tr_film_write_pfm(&pass, job->pass_paths[k], err) : rc;
        tr_film_free(&pass);
    }
    return rc;
}

int render_write_outputs(const render_job *job, tr_session *s, uint32_t samples, double elapsed,
                         uint64_t rays, const char *stopped) {
    tr_error err;
    const tr_film *film = tr_session_film(s, &err);
    tr_film den = {0};
    int rc = film ? TR_OK : TR_ERR;
    if (rc == TR_OK && job->denoise) {
        /* The variance layer stays the noise of the rendered estimate. */
        rc = tr_session_denoise(s, &den, &err);
    }
    if (rc == TR_OK && tr_image_format_from_path(job->out) == TR_IMAGE_EXR) {
        tr_film view = *film; /* the layers asked for */
        view.passes = job->passes;
        rc = tr_film_write_exr_rgb(&view, job->denoise ? &den : &view, job->out, job->exr_half,
                                   &err);
    } else if (rc == TR_OK) {
        rc = write_plain(job, film, job->denoise ? &den : film, &err);
    }
    char note[400]; /* a black or white image is not left silent */
    if (rc == TR_OK &&
        tr_image_exposure_note(job->denoise ? &den : film, job->exposure, note, sizeof note)) {
        fprintf(stderr, "trac0r render: warning: %s: %s\n", job->out, note);
    }
    tr_film_free(&den);
    if (rc != TR_OK) {
        fprintf(stderr, "trac0r render: %s\n", err.msg);
        return CLI_FAILURE;
    }
    char accel[160];
    tr_scene_accel_describe(job->scene, job->verbose, accel, sizeof accel);
    fprintf(stderr, "trac0r render: %s %ux%u, %u spp%s%s%s, %s, %s: %.2f s, %.2f Mrays/s -> %s\n",
            job->common.scene, job->common.width, job->common.height, samples, stopped ? " (" : "",
            stopped ? stopped : "", stopped ? ")" : "", job->be.name, accel, elapsed,
            elapsed > 0 ? (double)rays / elapsed * 1e-6 : 0.0, job->out);
    return CLI_OK;
}

/* Progress on stderr: the bar (spp, or tiles when a resumed tile checkpoint is finished
 * tile by tile), or with a noise threshold or time limit a line redrawn on a terminal. */
typedef struct render_progress {
    progress bar;
    int begun;
    int budgeted; /* --noise-threshold or --time-limit */
    int tty;
} render_progress;

static int on_progress(void *user, const tr_session_progress *p) {
    render_progress *rp = user;
    const double rate = p->seconds > 0 ? (double)p->rays / p->seconds * 1e-6 : 0.0;
    if (rp->budgeted) {
        if (rp->tty) {
            fprintf(stderr,
                    "\rtrac0r render: %u/%u spp  %u/%u tiles converged  %.1f s elapsed  "
                    "%.2f Mrays/s ",
                    p->samples, p->spp, p->tiles_done, p->tiles, p->seconds, rate);
        }
        return 0;
    }
    const int tiles = p->tiles > 0;
    if (!rp->begun) {
        progress_begin(&rp->bar, "trac0r render", tiles ? "tiles" : "spp",
                       tiles ? p->tiles : p->spp, 0);
        rp->begun = 1;
    }
    char extra[48];
    snprintf(extra, sizeof extra, "%.2f Mrays/s", rate);
    progress_update(&rp->bar, tiles ? p->tiles_done : p->samples, extra);
    return 0;
}

/* Why the render ended early, for the summary line (NULL: it did not). */
static const char *stop_note(const render_job *job, const tr_session_progress *p, int sig,
                             char *buf, size_t size) {
    if (sig) {
        snprintf(buf, size, "stopped by signal %d after %u of %u", sig, p->samples, p->spp);
        return buf;
    }
    if (job->noise_threshold > 0.0f || job->time_limit > 0.0f) {
        const double pixels = (double)job->common.width * job->common.height;
        const int n =
            snprintf(buf, size, "of %u%s, %.1f spp on average", p->spp,
                     p->end == TR_SESSION_TIME_LIMIT  ? ", time limit"
                     : p->end == TR_SESSION_CONVERGED ? ", noise threshold reached"
                     : p->end == TR_SESSION_DONE && job->noise_threshold > 0.0f ? ", cap reached"
                                                                                : "",
                     (double)(p->pixel_samples + (uint64_t)p->first * (uint64_t)pixels) / pixels);
        if (job->noise_threshold > 0.0f && n > 0 && (size_t)n < size) {
            snprintf(buf + n, size - (size_t)n, ", %u of %u tiles converged", p->tiles_done,
                     p->tiles);
        }
        return buf;
    }
    return NULL;
}

/* The single-process render: one session on the job's device. */
static int render_local(render_job *job) {
    tr_error err;
    render_progress rp;
    memset(&rp, 0, sizeof rp);
    rp.budgeted = job->noise_threshold > 0.0f || job->time_limit > 0.0f;
    rp.tty = isatty(fileno(stderr));
    tr_session_desc desc = render_session_desc(job);
    desc.progress = on_progress;
    desc.progress_user = &rp;
    tr_session *s = tr_session_create(job->be.dev, job->scene, &job->cfg, &desc, &err);
    if (!s) {
        return render_session_error(job, &err);
    }
    render_stop_install(s);
    const double t0 = tr_time_now();
    int rc = tr_session_run(s, &err) == TR_OK ? CLI_OK : CLI_FAILURE;
    const double t1 = tr_time_now();
    if (rp.begun) {
        progress_end(&rp.bar);
    }
    if (rp.budgeted && rp.tty) {
        fputc('\n', stderr);
    }
    tr_session_progress p;
    tr_session_progress_get(s, &p);
    const int sig = render_stop_signal();
    if (rc != CLI_OK) {
        fprintf(stderr, "trac0r render: %s\n", err.msg);
    } else if (p.samples == 0 && p.tiles_done == 0) {
        fprintf(stderr,
                "trac0r render: stopped by signal %d before the first sample: nothing "
                "written\n",
                sig);
    } else {
        char note[160];
        rc = render_write_outputs(job, s, p.samples, p.seconds, p.rays,
                                  stop_note(job, &p, sig, note, sizeof note));
    }
    if (rc == CLI_OK && job->verbose) {
        fprintf(stderr,
                "trac0r render: setup %.3f s, rendering %.3f s, output %.3f s; CPU %.3f s (user "
                "+ system)\n",
                t0 - job->started, t1 - t0, tr_time_now() - t1, tr_time_cpu());
    }
    /* The handlers stay until the files are written: a signal during the writing is noted,
     * the files are finished whole, and the status still says it came (a second one ends
     * the process at once, its temporary files removed). */
    const int sig_late = render_stop_signal();
    render_stop_uninstall();
    tr_session_destroy(s);
    return rc == CLI_OK && sig_late ? 128 + sig_late : rc;
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
