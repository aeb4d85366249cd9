/* devices.c - the --device option's backends, and `trac0r info --devices`. */
#include "devices.h"
#include "commands.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

int cli_parse_device(cli_args *a, int *device) {
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    const char *v = a->value;
    if (strcmp(v, "cpu") == 0) {
        *device = CLI_DEVICE_CPU;
        return CLI_OK;
    }
    if (strncmp(v, "opencl", 6) == 0 && (v[6] == '\0' || v[6] == ':')) {
        if (!tr_cl_available()) {
            return cli_error(a,
                             "%s: '%s' is not available: this build of trac0r has no OpenCL "
                             "support",
                             a->opt, v);
        }
        if (v[6] == '\0') {
            *device = 0;
            return CLI_OK;
        }
        const char *num = v + 7;
        char *end;
        errno = 0;
        long n = strtol(num, &end, 10);
        if (*num < '0' || *num > '9' || *end != '\0' || errno == ERANGE || n > 1023) {
            return cli_error(a, "%s: expected opencl:N with N in 0..1023, got '%s'", a->opt, v);
        }
        *device = (int)n;
        return CLI_OK;
    }
    return cli_error(a, "%s: unknown device '%s' (expected cpu, opencl or opencl:N)", a->opt, v);
}

static void describe(cli_backend *be, const cli_common *c) {
    if (!be->cl) {
        const int threads = c->threads ? c->threads : tr_default_threads();
        snprintf(be->name, sizeof be->name, "cpu, %d thread%s", threads, threads == 1 ? "" : "s");
        return;
    }
    const tr_cl_device_info *d = tr_cl_device(be->cl);
    snprintf(be->name, sizeof be->name, "opencl:%d (%s)", d->index, d->name);
}

int cli_backend_open(const cli_args *a, const cli_common *c, const tr_scene *scene,
                     cli_backend *be) {
    memset(be, 0, sizeof *be);
    if (c->device == CLI_DEVICE_CPU) {
        describe(be, c);
        return CLI_OK;
    }
    tr_error err;
    be->cl = tr_cl_open(c->device, &err);
    if (!be->cl) {
        if (strncmp(err.msg, "OpenCL: ", 8) == 0) {
            /* An OpenCL call failed on a device that exists (the compiler rejected the
             * kernel, ...): a fault of this build or driver, not of the command line.
             * A build failure's message holds the build log. */
            fprintf(stderr, "trac0r %s: %s\n", a->cmd, err.msg);
            return CLI_FAILURE;
        }
        return cli_error(a, "--device: %s", err.msg);
    }
    describe(be, c);
    if (scene) {
        int rc = cli_backend_upload(a, be, scene);
        if (rc != CLI_OK) {
            cli_backend_close(be);
            return rc;
        }
    }
    return CLI_OK;
}

int cli_backend_upload(const cli_args *a, cli_backend *be, const tr_scene *scene) {
    if (!be->cl) {
        return CLI_OK;
    }
    tr_error err;
    if (tr_cl_upload_scene(be->cl, scene, &err) != TR_OK) {
        return cli_error(a, "--device: %s", err.msg);
    }
    const tr_cl_device_info *d = tr_cl_device(be->cl);
    /* bvh and bvh2 both upload the binary BVH (the wide BVH is host code). */
    if (tr_scene_accel(scene) != tr_cl_scene_accel(be->cl) &&
        tr_scene_accel(scene) != TR_ACCEL_TYPE_BVH2) {
        /* Embree is a host library: the device gets a BVH of its own. */
        snprintf(be->name, sizeof be->name,
                 "opencl:%d (%s; %s is host-only, the device traces a %s)", d->index, d->name,
                 tr_accel_name(tr_scene_accel(scene)), tr_accel_name(tr_cl_scene_accel(be->cl)));
    } else {
        snprintf(be->name, sizeof be->name, "opencl:%d (%s)", d->index, d->name);
    }
    return CLI_OK;
}

int cli_backend_frame(cli_backend *be, const tr_scene *scene, const tr_render_config *cfg,
                      tr_film *film, uint32_t sample, tr_render_stats *stats, tr_error *err) {
    if (!be->cl) {
        return tr_render_frame(scene, tr_scene_camera(scene), cfg, film, sample, stats, err);
    }
    return tr_cl_render_frame(be->cl, tr_scene_camera(scene), cfg, sample, stats, err);
}

int cli_backend_read(cli_backend *be, tr_film *film, tr_error *err) {
    return be->cl ? tr_cl_read_film(be->cl, film, err) : TR_OK;
}

int cli_backend_clear(cli_backend *be, tr_film *film, tr_error *err) {
    tr_film_clear(film);
    return be->cl ? tr_cl_clear_film(be->cl, err) : TR_OK;
}

void cli_backend_close(cli_backend *be) {
    tr_cl_close(be->cl);
    be->cl = NULL;
}

int cli_print_devices(FILE *fp) {
    tr_error err;
    int count = 0;
    if (tr_cl_list_devices(NULL, 0, &count, &err) != TR_OK) {
        fprintf(stderr, "trac0r info: --devices: %s\n", err.msg);
        return CLI_USAGE;
    }
    tr_cl_device_info *devs = calloc((size_t)(count ? count : 1), sizeof *devs);
    if (!devs || tr_cl_list_devices(devs, count, &count, &err) != TR_OK) {
        free(devs);
        fprintf(stderr, "trac0r info: --devices: %s\n", devs ? err.msg : "out of memory");
        return CLI_FAILURE;
    }
    fprintf(fp, "OpenCL devices (use with --device opencl:N):\n");
    if (count == 0) {
        fprintf(fp, "  none: the OpenCL platforms found have no devices\n");
    }
    for (int i = 0; i < count; ++i) {
        const tr_cl_device_info *d = &devs[i];
        fprintf(fp, "  %d: %s\n", d->index, d->name);
        fprintf(fp, "     platform %d: %s\n", d->platform_index, d->platform);
        fprintf(fp, "     vendor: %s, type: %s, %s\n", d->vendor, d->type, d->version);
        fprintf(fp, "     compute units: %u, memory: %.0f MiB (largest buffer %.0f MiB)\n",
                d->compute_units, (double)d->global_mem / (1024.0 * 1024.0),
                (double)d->max_alloc / (1024.0 * 1024.0));
    }
    free(devs);
    return CLI_OK;
}
