/* info.c - `trac0r info SCENE`: what a scene holds, without rendering it. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "devices.h"
#include "trac0r/registry.h"
#include "trac0r/scene_file.h"

static void info_help(FILE *fp) {
    fprintf(fp, "Usage: trac0r info SCENE [options]\n"
                "       trac0r info --devices\n"
                "\n"
                "Describes a scene (counts, bounds, camera, materials, render defaults, warnings)\n"
                "without rendering it, or lists the OpenCL devices as --device opencl:N numbers\n"
                "them. Exit status 2 when the scene does not load or no OpenCL platform is found.\n"
                "\n"
                "Options:\n"
                "  --devices            list the OpenCL devices instead of describing a scene\n"
                "  --up y|z             a model file's up axis (default y)\n"
                "  --scale S            a model file's scale (default 1)\n"
                "  --camera N|NAME|frame  a model file's camera (default its first)\n"
                "  -h, --help           show this help\n");
}

int cmd_info(int argc, char **argv) {
    cli_args a = {.cmd = "info", .argc = argc, .argv = argv, .i = 0};
    const char *path = NULL;
    int devices = 0;
    cli_common mc; /* --up, --scale for model files */
    cli_common_default(&mc);
    while (cli_next(&a)) {
        if (cli_is(&a, "-h") || cli_is(&a, "--help")) {
            info_help(stdout);
            return CLI_OK;
        } else if (cli_is(&a, "--devices")) {
            devices = 1;
        } else if (cli_is(&a, "--up") || cli_is(&a, "--scale") || cli_is(&a, "--camera")) {
            if (cli_common_option(&a, &mc) != CLI_OK) {
                return CLI_USAGE;
            }
        } else if (a.opt[0] != '-' && !path) {
            path = a.opt;
        } else {
            return cli_unknown(&a, info_help);
        }
    }
    if (devices && path) {
        return cli_error(&a, "--devices takes no SCENE (see 'trac0r info --help')");
    }
    if (devices) {
        return cli_print_devices(stdout);
    }
    if (!path) {
        return cli_error(&a, "missing SCENE or --devices (see 'trac0r info --help')");
    }
    tr_scene_file f;
    memset(&f, 0, sizeof f);
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    if (!s) {
        return cli_error(&a, "%s", err.msg);
    }
    const tr_model_options mo = {mc.up_z, mc.model_scale, 0, 0, mc.model_camera};
    if (tr_scene_load(s, path, &mo, &f, &err) != TR_OK) {
        tr_scene_destroy(s);
        return cli_error(&a, "%s", err.msg);
    }
    char *text = tr_scene_describe(s, path, &f, 32);
    tr_scene_destroy(s);
    if (!text) {
        fprintf(stderr, "trac0r info: out of memory\n");
        return CLI_FAILURE;
    }
    fputs(text, stdout);
    free(text);
    return CLI_OK;
}
