/* devices.h - the --device option's backends for render and bench, and the listing of
 * OpenCL devices for `trac0r info --devices`. */
#ifndef TRAC0R_DEVICES_H
#define TRAC0R_DEVICES_H

#include <stdio.h>

#include "cli.h"
#include "trac0r/opencl.h"

/* The backend frames are rendered with: the CPU (cl == NULL) or an OpenCL device. */
typedef struct cli_backend {
    tr_cl_context *cl;
    char name[192]; /* "cpu, 2 threads" / "opencl:0 (pthread-..., bvh on the device)" */
} cli_backend;

/* Opens the backend c->device names and, for OpenCL, uploads `scene` (NULL: none yet).
 * Prints one line and returns CLI_USAGE for a configuration the machine cannot run (no
 * platform, no such device, a scene too big for the device), CLI_FAILURE when the
 * kernel fails to build (the build log follows on stderr). */
int cli_backend_open(const cli_args *a, const cli_common *c, const tr_scene *scene,
                     cli_backend *be);
/* Uploads a new scene to an OpenCL backend (nothing for the CPU). Same statuses. */
int cli_backend_upload(const cli_args *a, cli_backend *be, const tr_scene *scene);
/* One frame: tr_render_frame into `film` on the CPU; on a device into its own film. */
int cli_backend_frame(cli_backend *be, const tr_scene *scene, const tr_render_config *cfg,
                      tr_film *film, uint32_t sample, tr_render_stats *stats, tr_error *err);
/* Brings the device film into `film` (nothing for the CPU). */
int cli_backend_read(cli_backend *be, tr_film *film, tr_error *err);
/* Forgets the samples of the backend's film (and clears `film`). */
int cli_backend_clear(cli_backend *be, tr_film *film, tr_error *err);
void cli_backend_close(cli_backend *be);

/* Parses the value of --device: "cpu", "opencl" (device 0) or "opencl:N". */
int cli_parse_device(cli_args *a, int *device);

/* `trac0r info --devices`: prints the OpenCL platforms and devices to fp. Returns the
 * exit status (CLI_USAGE with a message on stderr when there is no platform or no
 * OpenCL in this build). */
int cli_print_devices(FILE *fp);

#endif
