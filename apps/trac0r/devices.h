/* devices.h - the --device option: opening a tr_device (include/trac0r/device.h) for
 * render, view and bench with the command line's exit statuses, the render config the
 * common options describe, and the listing for `trac0r info --devices`. */
#ifndef TRAC0R_DEVICES_H
#define TRAC0R_DEVICES_H

#include <stdio.h>

#include "cli.h"
#include "trac0r/device.h"

/* The device frames are rendered with, and a one-line description of it. */
typedef struct cli_backend {
    tr_device *dev;
    char name[384]; /* "cpu, 2 threads" / "opencl:0 (pthread-..., bvh on the device)" */
    int threads;    /* the --threads the description counts (0: all) */
} cli_backend;

/* Opens the device c->device names and uploads `scene` (NULL: none yet). Prints one line
 * and returns CLI_USAGE for a configuration the machine cannot run (no platform, no such
 * device, a scene too big for the device), CLI_FAILURE when the kernel fails to build
 * (the build log follows on stderr). */
int cli_backend_open(const cli_args *a, const cli_common *c, const tr_scene *scene,
                     cli_backend *be);
/* Hands a new or changed scene to the device. Same statuses. */
int cli_backend_upload(const cli_args *a, cli_backend *be, const tr_scene *scene);
void cli_backend_close(cli_backend *be);

/* The render config the common options describe (max depth, seed, threads, integrator). */
tr_render_config cli_render_config(const cli_common *c);

/* Parses the value of --device: "cpu", "opencl" (device 0) or "opencl:N" into c->device. */
int cli_parse_device(cli_args *a, cli_common *c);

/* `trac0r info --devices`: prints the OpenCL platforms and devices to fp. Returns the
 * exit status (CLI_USAGE with a message on stderr when there is no platform or no
 * OpenCL in this build). */
int cli_print_devices(FILE *fp);

#endif
