/* compare.c - `trac0r compare A B`: image error metrics against a reference. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"

static void compare_help(FILE *fp) {
    fprintf(fp,
            "Usage: trac0r compare A B [options]\n"
            "\n"
            "Compares image A (.pfm, .exr or .png) against the reference B on linear radiance\n"
            "clamped to [0,1]: rmse, relmse (mean of (A - B)^2 / (B^2 + %g)) and psnr in dB.\n"
            "\n"
            "Options:\n"
            "  --error-image FILE   write the per-pixel absolute error, false-colour (.png/.pfm)\n"
            "  -h, --help           show this help\n"
            "\n"
            "Exit status: 0 done, 2 bad command line, unreadable images or different sizes,\n"
            "1 the error image could not be written.\n",
            TR_RELMSE_EPSILON);
}

int cmd_compare(int argc, char **argv) {
    cli_args a = {.cmd = "compare", .argc = argc, .argv = argv, .i = 0};
    const char *paths[2] = {NULL, NULL};
    int npaths = 0;
    const char *error_image = NULL;
    while (cli_next(&a)) {
        if (cli_is(&a, "-h") || cli_is(&a, "--help")) {
            compare_help(stdout);
            return CLI_OK;
        }
        if (cli_is(&a, "--error-image")) {
            if (cli_value(&a) != CLI_OK) {
                return CLI_USAGE;
            }
            error_image = a.value;
            if (tr_image_format_from_path(error_image) == TR_IMAGE_UNKNOWN) {
                return cli_error(&a,
                                 "--error-image: '%s' has an unknown extension (expected .png or "
                                 ".pfm)",
                                 error_image);
            }
        } else if (a.opt[0] == '-' && a.opt[1] != '\0') {
            return cli_unknown(&a, compare_help);
        } else if (npaths < 2) {
            paths[npaths++] = a.opt;
        } else {
            return cli_error(&a, "unexpected argument '%s' (expected two images)", a.opt);
        }
    }
    if (npaths != 2) {
        return cli_error(&a, "expected two images A and B (see 'trac0r compare --help')");
    }
    tr_error err;
    if (error_image && tr_image_check_writable(error_image, &err) != TR_OK) {
        return cli_error(&a, "--error-image: %s", err.msg);
    }
    tr_image img[2];
    memset(img, 0, sizeof img);
    for (int k = 0; k < 2; ++k) {
        if (tr_image_read(&img[k], paths[k], &err) != TR_OK) {
            tr_image_free(&img[0]);
            return cli_error(&a, "%s", err.msg);
        }
    }
    if (img[0].width != img[1].width || img[0].height != img[1].height) {
        int rc = cli_error(&a, "%s is %ux%u but %s is %ux%u", paths[0], img[0].width, img[0].height,
                           paths[1], img[1].width, img[1].height);
        tr_image_free(&img[0]);
        tr_image_free(&img[1]);
        return rc;
    }
    size_t pixels = (size_t)img[0].width * img[0].height;
    tr_image_metrics e = tr_image_compare(img[0].rgb, img[1].rgb, pixels);
    printf("size %ux%u\nrmse %.6g\nrelmse %.6g\npsnr %.3f dB\n", img[0].width, img[0].height,
           e.rmse, e.relmse, e.psnr);
    int rc = CLI_OK;
    if (error_image) {
        if (tr_error_map_write(img[0].rgb, img[1].rgb, img[0].width, img[0].height, e.max_error,
                               error_image, &err) != TR_OK) {
            fprintf(stderr, "trac0r compare: %s\n", err.msg);
            rc = CLI_FAILURE;
        } else {
            printf("error image %s (white = %.6g)\n", error_image, e.max_error);
        }
    }
    tr_image_free(&img[0]);
    tr_image_free(&img[1]);
    return rc;
}
