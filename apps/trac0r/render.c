/* render.c - `trac0r render`: render a scene progressively to an image file. */
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "commands.h"
#include "devices.h"

/* Writes the film, first through the a-trous filter (denoise) and, for a PNG, the
 * display curve; the plain path (clamp, no filter) is tr_film_write as before. */
static int render_write(const tr_film *film, const char *out, float exposure, int curve,
                        int denoise, tr_error *err) {
    const int png = tr_image_format_from_path(out) == TR_IMAGE_PNG;
    if (!denoise && (curve == TR_TONEMAP_CLAMP || !png)) {
        return tr_film_write(film, out, exposure, err);
    }
    tr_film den = {0}, disp = {0};
    tr_gbuffer g = {0};
    const tr_film *img = film;
    int rc = TR_OK;
    if (denoise) {
        const tr_recon_params p = tr_recon_params_default();
        rc = tr_gbuffer_init(&g, film->width, film->height, err);
        rc = rc == TR_OK ? tr_gbuffer_from_film(&g, film, err) : rc;
        rc = rc == TR_OK ? tr_film_init(&den, film->width, film->height, err) : rc;
        rc = rc == TR_OK ? tr_filter_atrous(&g, g.color, den.sum, &p, 0, err) : rc;
        for (size_t i = 0; rc == TR_OK && i < (size_t)film->width * film->height; ++i) {
            den.count[i] = film->count[i] ? 1u : 0u;
        }
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
    tr_gbuffer_free(&g);
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
           "  --out FILE           output image, .png (8-bit sRGB) or .pfm (float linear RGB)\n"
           "                       (default render.png); written to a temporary file and\n"
           "                       renamed, so it never exists half-written\n"
           "  --passes LIST        also write these passes beside the image, comma-separated:\n"
           "                       albedo, normal, depth, id (or all); each goes to\n"
           "                       FILE-without-extension.PASS.pfm (float: the pixel's mean\n"
           "                       base colour, shading normal, distance from the camera,\n"
           "                       primitive id), at the first surface that is not a mirror\n"
           "                       or smooth glass; 0 where a sample met none\n"
           "  --tonemap CURVE      PNG display curve: clamp (default) or filmic (an ACES-like\n"
           "                       fitted curve that rolls highlights off); PFM stays linear\n"
           "  --denoise            filter the final image with the edge-avoiding a-trous\n"
           "                       filter guided by the albedo, normal and depth passes\n"
           "                       (docs/realtime.md); the passes are rendered for it\n"
           "  -h, --help           show this help\n"
           "\n"
           "Progress (samples, elapsed, ETA, Mrays/s) goes to stderr while it is a terminal;\n"
           "otherwise one summary line is printed when the image is written.\n"
           "Exit status: 0 on success, 2 on a bad command line, 1 when rendering or writing\n"
           "fails.\n",
           cli_common_help());
}

/* --passes: "albedo,normal,depth,id" or "all" into TR_PASS_* bits. */
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
            bit = TR_PASS_ALL;
        }
        for (uint32_t k = 1; k <= TR_PASS_PRIM && !bit; k <<= 1) {
            const char *name = tr_pass_name(k);
            if (strlen(name) == len && strncmp(p, name, len) == 0) {
                bit = k;
            }
        }
        if (!bit) {
            return cli_error(a,
                             "%s: unknown pass '%.*s' (expected albedo, normal, depth, id or all)",
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

int cmd_render(int argc, char **argv) {
    cli_args a = {.cmd = "render", .argc = argc, .argv = argv, .i = 0};
    cli_common c;
    cli_common_default(&c);
    uint32_t spp = 16;
    int spp_given = 0, scene_arg = 0;
    int stride = 1;
    float exposure = 0.0f;
    const char *out = "render.png";
    uint32_t passes = 0;
    int curve = TR_TONEMAP_CLAMP, denoise = 0;

    while (cli_next(&a)) {
        int rc = cli_common_option(&a, &c);
        if (rc == CLI_OK) {
            continue;
        }
        if (rc == CLI_USAGE) {
            return CLI_USAGE;
        }
        if (cli_is(&a, "-h") || cli_is(&a, "--help")) {
            render_help();
            return CLI_OK;
        } else if (cli_is(&a, "--spp")) {
            rc = cli_parse_u32(&a, 1, 1000000, &spp);
            spp_given = 1;
        } else if (cli_is(&a, "--stride")) {
            rc = cli_parse_int(&a, 1, 64, &stride);
        } else if (cli_is(&a, "--exposure")) {
            rc = cli_parse_float(&a, -20.0f, 20.0f, &exposure);
        } else if (cli_is(&a, "--passes")) {
            rc = parse_passes(&a, &passes);
        } else if (cli_is(&a, "--tonemap")) {
            rc = cli_value(&a);
            if (rc == CLI_OK && (curve = tr_tonemap_curve_parse(a.value)) < 0) {
                return cli_error(&a, "--tonemap: expected clamp or filmic, got '%s'", a.value);
            }
        } else if (cli_is(&a, "--denoise")) {
            denoise = 1;
            rc = CLI_OK;
        } else if (cli_is(&a, "--out") || cli_is(&a, "-o")) {
            rc = cli_value(&a);
            out = a.value;
        } else if (a.opt[0] != '-' && !scene_arg) {
            c.scene = a.opt; /* positional SCENE, anywhere on the line */
            scene_arg = 1;
            rc = CLI_OK;
        } else {
            return cli_error(&a, "unknown option '%s' (see 'trac0r render --help')", a.opt);
        }
        if (rc != CLI_OK) {
            return CLI_USAGE;
        }
    }
    if (tr_image_format_from_path(out) == TR_IMAGE_UNKNOWN) {
        return cli_error(&a, "--out: '%s' has an unknown extension (expected .png or .pfm)", out);
    }
    tr_error err;
    if (tr_image_check_writable(out, &err) != TR_OK) {
        return cli_error(&a, "--out: %s", err.msg);
    }
    char pass_paths[4][4096];
    for (int k = 0; k < 4; ++k) {
        const uint32_t bit = 1u << k;
        if ((passes & bit) != 0u && pass_path(out, bit, pass_paths[k], sizeof pass_paths[k]) != 0) {
            return cli_error(&a, "--out: '%s' is too long for the pass files' names", out);
        }
    }

    tr_scene *scene = tr_scene_create(NULL);
    tr_scene_file file;
    int rc = cli_load_scene_file(&a, &c, scene, &file);
    if (rc != CLI_OK) {
        tr_scene_destroy(scene);
        return rc;
    }
    if (!spp_given && file.has_spp) {
        spp = file.spp;
    }
    tr_film film;
    /* --denoise needs the guides; the radiance does not change with passes. */
    const uint32_t render_passes =
        passes | (denoise ? TR_PASS_ALBEDO | TR_PASS_NORMAL | TR_PASS_DEPTH : 0u);
    if (tr_film_init_passes(&film, c.width, c.height, render_passes, &err) != TR_OK) {
        tr_scene_free(scene);
        return cli_error(&a, "--width/--height: %s", err.msg);
    }
    cli_backend be;
    rc = cli_backend_open(&a, &c, scene, &be);
    if (rc != CLI_OK) {
        tr_film_free(&film);
        tr_scene_destroy(scene);
        return rc;
    }
    tr_render_config cfg = cli_render_config(&c);
    cfg.stride = stride;
    cfg.passes = render_passes;

    const int tty = isatty(fileno(stderr));
    const double t0 = tr_time_now();
    uint64_t rays = 0;
    rc = CLI_OK;
    for (uint32_t s = 0; s < spp; ++s) {
        tr_render_stats st;
        if (cli_backend_frame(&be, scene, &cfg, s, &st, &err) != TR_OK) {
            fprintf(stderr, "%strac0r render: %s\n", tty ? "\n" : "", err.msg);
            rc = CLI_FAILURE;
            break;
        }
        rays += st.rays;
        if (tty) {
            double el = tr_time_now() - t0;
            double eta = el / (s + 1) * (spp - s - 1);
            fprintf(stderr, "\rtrac0r render: %u/%u spp  %.1f s elapsed  ETA %.1f s  %.2f Mrays/s ",
                    s + 1, spp, el, eta, el > 0 ? (double)rays / el * 1e-6 : 0.0);
        }
    }
    const double elapsed = tr_time_now() - t0;
    if (tty) {
        fputc('\n', stderr);
    }
    if (rc == CLI_OK && cli_backend_read(&be, &film, &err) != TR_OK) {
        fprintf(stderr, "trac0r render: %s\n", err.msg);
        rc = CLI_FAILURE;
    }
    if (rc == CLI_OK && render_write(&film, out, exposure, curve, denoise, &err) != TR_OK) {
        fprintf(stderr, "trac0r render: %s\n", err.msg);
        rc = CLI_FAILURE;
    }
    for (int k = 0; k < 4 && rc == CLI_OK; ++k) {
        tr_film pass;
        if ((passes & (1u << k)) == 0u) {
            continue;
        }
        if (tr_film_extract_pass(&film, 1u << k, &pass, &err) != TR_OK ||
            tr_film_write_pfm(&pass, pass_paths[k], &err) != TR_OK) {
            fprintf(stderr, "trac0r render: %s\n", err.msg);
            rc = CLI_FAILURE;
        }
        tr_film_free(&pass);
    }
    if (rc == CLI_OK) {
        char accel[160];
        cli_describe_accel(accel, sizeof accel, scene);
        fprintf(stderr, "trac0r render: %s %ux%u, %u spp, %s, %s: %.2f s, %.2f Mrays/s -> %s\n",
                c.scene, c.width, c.height, spp, be.name, accel, elapsed,
                elapsed > 0 ? (double)rays / elapsed * 1e-6 : 0.0, out);
    }
    cli_backend_close(&be);
    tr_film_free(&film);
    tr_scene_destroy(scene);
    return rc;
}
