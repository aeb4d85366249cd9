/* view.c - `trac0r view`: option parsing, headless frames and the benchmark; the
 * window itself is view_window.c. */
#define _POSIX_C_SOURCE 200809L
#include "view.h"
#include "trac0r/outfile.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "view_overlay.h"

#define VIEW_DEFAULT_FRAMES 16 /* --frames default of --screenshot and --benchmark */

static void view_help(FILE *fp) {
    fprintf(fp,
            "Usage: trac0r view [SCENE] [options]\n"
            "\n"
            "Opens a window that shows the scene converging; while the camera moves, frames\n"
            "hold --target-fps. The full manual: man trac0r (docs/cli.md, docs/viewer.md).\n"
            "\n"
            "Keys: W/S A/D Space/Left Ctrl Q/E move, right mouse looks, wheel speed, M the\n"
            "reconstruction, B debug view, R reset, F12 screenshot, Esc quit; H lists them all.\n"
            "\n"
            "Options:\n"
            "%s"
            "  --frames N           headless: render N frames, save --screenshot and quit\n"
            "  --screenshot FILE    headless output image, .png or .pfm\n"
            "  --benchmark LEVEL    headless: FPS on builtin:cornell-ico-LEVEL, 0..9 (%d frames)\n"
            "  --stride K           initial preview stride, 1, 2 or 4 (default 1)\n"
            "  --exposure EV        exposure in stops, -20..20 (default 0)\n"
            "  --target-fps F       frame budget while the camera moves, 1..1000 (default 60)\n"
            "  --tonemap CURVE      display curve: clamp (default) or filmic\n"
            "  --recon METHOD       off, accumulate, bilateral, atrous or svgf (default)\n"
            "  --max-spp N          stop accumulating after N samples per pixel (0: never)\n"
            "  --animate            the scene's last shape and the lights move every frame\n"
            "  --animate-light switch|move|none   what --animate does to the lights (default\n"
            "                       move); implies --animate\n"
            "  --font FILE          TrueType font of the debug view\n"
            "  --shot-dir DIR       where F12 saves trac0r-view-NNN.png (default: .)\n"
            "  --state-file FILE    rewrite FILE with the viewer's state as it changes\n"
            "  --dump-window FILE   on SIGUSR1 write the window's pixels to FILE (PPM)\n"
            "  -h, --help           show this help\n"
            "\n"
            "The reconstruction's settings:\n"
            "%s"
            "\n"
            "Exit status: 0 done, 2 bad command line or no display, 1 rendering failed.\n",
            cli_common_help(), VIEW_DEFAULT_FRAMES, cli_recon_help);
}

/* Renders `frames` frames of the scene's own camera, as `trac0r render` does; returns
 * the seconds taken in *seconds. */
static int render_frames(const cli_args *a, const view_options *o, const tr_scene *scene,
                         cli_backend *be, tr_film *film, uint32_t frames, double *seconds) {
    const tr_render_config cfg = cli_render_config(&o->c);
    tr_error err;
    const double t0 = tr_time_now();
    for (uint32_t s = 0; s < frames; ++s) {
        if (tr_device_render(be->dev, tr_scene_camera(scene), &cfg, s, 1, NULL, NULL, &err) !=
            TR_OK) {
            fprintf(stderr, "trac0r %s: %s\n", a->cmd, err.msg);
            return CLI_FAILURE;
        }
    }
    /* The device's film comes back once, inside the timed span (as a displayed frame would). */
    if (tr_device_read_film(be->dev, film, &err) != TR_OK) {
        fprintf(stderr, "trac0r %s: %s\n", a->cmd, err.msg);
        return CLI_FAILURE;
    }
    *seconds = tr_time_now() - t0;
    return CLI_OK;
}

static int run_headless(const cli_args *a, const view_options *o, tr_scene *scene,
                        cli_backend *be) {
    tr_error err;
    tr_film film;
    if (tr_film_init(&film, o->c.width, o->c.height, &err) != TR_OK) {
        if (err.code == TR_STATUS_OUT_OF_MEMORY) {
            fprintf(stderr, "trac0r view: %s\n", err.msg); /* status 1, not a usage error */
            return CLI_FAILURE;
        }
        return cli_error(a, "--width/--height: %s", err.msg);
    }
    double seconds = 0.0;
    const uint32_t frames = o->frames ? o->frames : VIEW_DEFAULT_FRAMES;
    int rc = render_frames(a, o, scene, be, &film, frames, &seconds);
    if (rc == CLI_OK && o->benchmark >= 0) {
        printf("trac0r view: benchmark cornell-ico-%d (%u triangles) %ux%u, %u frames in "
               "%.2f s: %.3f average FPS (%.1f ms/frame)\n",
               o->benchmark, tr_scene_triangle_count(scene), o->c.width, o->c.height, frames,
               seconds, seconds > 0 ? frames / seconds : 0.0, seconds * 1e3 / frames);
    }
    if (rc == CLI_OK && o->screenshot) {
        if (tr_film_write_curve(&film, o->screenshot, o->exposure, o->curve, &err) != TR_OK) {
            fprintf(stderr, "trac0r view: %s\n", err.msg);
            rc = CLI_FAILURE;
        } else {
            fprintf(stderr, "trac0r view: %u frames of %s %ux%u in %.2f s -> %s\n", frames,
                    o->c.scene, o->c.width, o->c.height, seconds, o->screenshot);
        }
    }
    tr_film_free(&film);
    return rc;
}

/* One of view's own options: CLI_OK, CLI_USAGE, or -1 if it is none of them. */
static int view_option(cli_args *a, void *user) {
    view_options *o = user;
    int rc = cli_recon_option(a, &o->recon_params);
    if (rc != -1) {
        return rc;
    }
    if ((rc = cli_restir_option(a, &o->c)) != -1) {
        return rc;
    }
    const struct {
        const char *name;
        const char **value;
    } paths[] = {{"--screenshot", &o->screenshot},
                 {"--font", &o->font},
                 {"--shot-dir", &o->shot_dir},
                 {"--state-file", &o->state_file},
                 {"--dump-window", &o->dump_file}};
    for (size_t k = 0; k < sizeof paths / sizeof paths[0]; ++k) {
        if (cli_is(a, paths[k].name)) {
            rc = cli_value(a);
            *paths[k].value = a->value;
            return rc;
        }
    }
    if (cli_is(a, "--frames")) {
        return cli_parse_u32(a, 1, 1000000, &o->frames);
    }
    if (cli_is(a, "--benchmark")) {
        return cli_parse_int(a, 0, TR_ICOSPHERE_MAX_SUBDIVISIONS, &o->benchmark);
    }
    if (cli_is(a, "--stride")) {
        rc = cli_parse_int(a, 1, 4, &o->stride);
        return rc == CLI_OK && o->stride == 3
                   ? cli_error(a, "--stride: expected 1, 2 or 4, got '3'")
                   : rc;
    }
    if (cli_is(a, "--exposure")) {
        return cli_parse_float(a, -20.0f, 20.0f, &o->exposure);
    }
    if (cli_is(a, "--target-fps")) {
        return cli_parse_float(a, 1.0f, 1000.0f, &o->target_fps);
    }
    if (cli_is(a, "--tonemap")) {
        rc = cli_value(a);
        if (rc == CLI_OK && (o->curve = tr_tonemap_curve_parse(a->value)) < 0) {
            return cli_error(a, "--tonemap: expected clamp or filmic, got '%s'", a->value);
        }
        return rc;
    }
    if (cli_is(a, "--recon")) {
        rc = cli_value(a);
        if (rc == CLI_OK && (o->recon = tr_recon_parse(a->value)) < 0) {
            return cli_error(
                a, "--recon: expected off, accumulate, bilateral, atrous or svgf, got '%s'",
                a->value);
        }
        return rc;
    }
    if (cli_is(a, "--max-spp")) {
        return cli_parse_u32(a, 0, 100000000, &o->max_spp);
    }
    /* o->animate - 1 is the lights' TR_LIGHT_ANIMATION_* (view_renderer's animate). */
    if (cli_is(a, "--animate")) {
        if (!o->animate) {
            o->animate = 1 + TR_LIGHT_ANIMATION_MOVE;
        }
        return CLI_OK;
    }
    if (cli_is(a, "--animate-light")) {
        if (cli_value(a) != CLI_OK) {
            return CLI_USAGE;
        }
        const int mode = tr_light_animation_from_name(a->value);
        if (mode < 0) {
            return cli_error(a, "--animate-light: expected switch, move or none, got '%s'",
                             a->value);
        }
        o->animate = 1 + mode;
        return CLI_OK;
    }
    if (a->opt[0] != '-' && a->i == 1) {
        o->c.scene = a->opt; /* positional SCENE */
        return CLI_OK;
    }
    return -1;
}

static int view_parse(cli_args *a, view_options *o) {
    memset(o, 0, sizeof *o);
    cli_common_default(&o->c);
    o->benchmark = -1;
    o->stride = 1;
    o->target_fps = 60.0f;
    o->recon_params = tr_recon_params_default();
    /* SVGF measured best in motion (docs/realtime.md); at rest it follows the film. */
    o->recon = TR_RECON_SVGF;
    o->shot_dir = ".";
    o->recon_params.gradients = -1; /* unset: decided below */
    const int rc = cli_parse(a, &o->c, NULL, view_help, view_option, o);
    /* Temporal gradients where the scene changes (--animate: its lights too), unless
     * --gradients says: a still scene gains nothing from their replay (docs/realtime.md). */
    if (o->recon_params.gradients < 0) {
        o->recon_params.gradients = o->animate != 0;
    }
    return rc;
}

/* Before the scene: the options agree, and the files they name can be written (the
 * window's are written while it runs: a directory or an unwritable place is said now, not
 * found never written). */
static int view_check(const cli_args *a, view_options *o, int headless) {
    if (o->frames && !headless) {
        return cli_error(a, "--frames: needs --screenshot FILE or --benchmark LEVEL");
    }
    if (o->animate && headless) {
        return cli_error(a, "--animate: only in the interactive window ('trac0r bench frame "
                            "--animate' measures a dynamic scene headless)");
    }
    tr_error err;
    if (o->screenshot && tr_image_format_from_path(o->screenshot) == TR_IMAGE_UNKNOWN) {
        return cli_error(a, "--screenshot: '%s' has an unknown extension (expected .png or .pfm)",
                         o->screenshot);
    }
    if (o->screenshot && tr_image_check_writable(o->screenshot, &err) != TR_OK) {
        return cli_error(a, "--screenshot: %s", err.msg);
    }
    if (o->state_file && tr_outfile_check(o->state_file, &err) != TR_OK) {
        return cli_error(a, "--state-file: %s", err.msg);
    }
    if (o->dump_file && tr_outfile_check(o->dump_file, &err) != TR_OK) {
        return cli_error(a, "--dump-window: %s", err.msg);
    }
    if (o->benchmark >= 0) {
        snprintf(o->bench_scene, sizeof o->bench_scene, "builtin:cornell-ico-%d", o->benchmark);
        o->c.scene = o->bench_scene;
    }
    if (!headless && view_font_find(o->font, o->font_path, sizeof o->font_path, &err) != TR_OK) {
        return cli_error(a, "%s", err.msg);
    }
    return CLI_OK;
}

/* Whether a window could open: an X11 display, an SDL video driver or a Wayland one. */
static int have_display(void) {
    const char *vars[] = {"DISPLAY", "SDL_VIDEODRIVER", "WAYLAND_DISPLAY"};
    for (size_t k = 0; k < sizeof vars / sizeof vars[0]; ++k) {
        const char *v = getenv(vars[k]);
        if (v && *v) {
            return 1;
        }
    }
    return 0;
}

int cmd_view(int argc, char **argv) {
    cli_args a = {.cmd = "view", .argc = argc, .argv = argv, .i = 0};
    view_options o;
    int rc = view_parse(&a, &o);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? CLI_OK : rc;
    }
    const int headless = o.screenshot || o.benchmark >= 0;
    if ((rc = view_check(&a, &o, headless)) != CLI_OK) {
        return rc;
    }
    tr_scene *scene = tr_scene_create(NULL);
    /* A scene file's render defaults (size, max depth, integrator, accel) apply to the
     * options not given, as in `trac0r render`. */
    rc = cli_load_scene_file(&a, &o.c, scene, NULL);
    if (rc == CLI_OK && !headless && !have_display()) {
        rc = cli_error(&a, "no display: DISPLAY is not set (the window needs an X11 display; use "
                           "--frames N --screenshot FILE to render without one)");
    }
    cli_backend be = {.dev = NULL};
    if (rc == CLI_OK && (rc = cli_backend_open(&a, &o.c, scene, &be)) == CLI_OK) {
        if ((tr_device_caps(be.dev) & TR_DEVICE_CAP_HOST) == 0u) {
            fprintf(stderr, "trac0r view: rendering on %s\n", be.name);
        }
        rc = headless ? run_headless(&a, &o, scene, &be) : view_run_window(&a, &o, scene, &be);
    }
    cli_backend_close(&be);
    tr_scene_destroy(scene);
    return rc;
}
