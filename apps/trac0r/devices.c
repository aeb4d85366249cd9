/* devices.c - the --device option's backends, and `trac0r info --devices`. */
#include "devices.h"
#include "commands.h"

#include <stdlib.h>
#include <string.h>

int cli_parse_device(cli_args *a, cli_common *c) {
    tr_error err;
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    if (cli_is(a, "--device-bvh")) { /* the names and their meaning: trac0r/device.h */
        c->device_bvh = tr_device_bvh_from_name(a->value);
        return c->device_bvh >= 0
                   ? CLI_OK
                   : cli_error(a, "%s: unknown BVH '%s' (expected auto, bvh2 or cwbvh)", a->opt,
                               a->value);
    }
    if (tr_device_name_check(a->value, c->device, sizeof c->device, &err) != TR_OK) {
        return cli_error(a, "%s: %s", a->opt, err.msg);
    }
    return CLI_OK;
}

tr_render_config cli_render_config(const cli_common *c) {
    tr_render_config cfg = tr_render_config_default();
    cfg.max_depth = c->max_depth;
    cfg.seed = c->seed;
    cfg.threads = c->threads;
    cfg.integrator = c->integrator;
    cfg.sampler = c->sampler >= 0 ? c->sampler : TR_SAMPLER_SOBOL;
    cfg.roulette_start = c->roulette_start;
    cfg.clamp_indirect = c->clamp_indirect > 0.0f ? c->clamp_indirect : 0.0f;
    cfg.regularize = c->regularize == 1;
    cfg.opencl_kernel = c->cl_kernel;
    return cfg;
}

/* Reports a failure to open a device or upload to it. An OpenCL call that failed on a
 * device that exists (the compiler rejected the kernel, ...) or memory running out is a
 * fault of this build, driver or machine (exit 1; a build failure's message holds the
 * build log); anything else - no such device, no OpenCL, a scene too big for the
 * device - is the command line's (exit 2). */
static int device_error(const cli_args *a, const tr_error *err) {
    if (err->code == TR_STATUS_DEVICE || err->code == TR_STATUS_OUT_OF_MEMORY) {
        fprintf(stderr, "trac0r %s: %s\n", a->cmd, err->msg);
        return CLI_FAILURE;
    }
    return cli_error(a, "--device: %s", err->msg);
}

int cli_backend_open(const cli_args *a, const cli_common *c, const tr_scene *scene,
                     cli_backend *be) {
    memset(be, 0, sizeof *be);
    tr_error err;
    be->dev = tr_device_create(c->device, &err);
    if (!be->dev) {
        return device_error(a, &err);
    }
    tr_device_set_bvh(be->dev, (tr_device_bvh)c->device_bvh, NULL); /* valid: parsed */
    be->threads = c->threads;
    tr_device_describe(be->dev, be->threads, be->name, sizeof be->name);
    const int rc = scene ? cli_backend_upload(a, be, scene) : CLI_OK;
    if (rc != CLI_OK) {
        cli_backend_close(be);
    }
    return rc;
}

int cli_backend_upload(const cli_args *a, cli_backend *be, const tr_scene *scene) {
    tr_error err;
    if (tr_device_upload(be->dev, scene, &err) != TR_OK) {
        return device_error(a, &err);
    }
    /* The description names the structure the device traces when it is not the scene's. */
    tr_device_describe(be->dev, be->threads, be->name, sizeof be->name);
    return CLI_OK;
}

void cli_backend_close(cli_backend *be) {
    tr_device_destroy(be->dev);
    be->dev = NULL;
}

int cli_print_devices(FILE *fp) {
    tr_error err;
    int count = 0;
    if (tr_device_list("opencl", NULL, 0, &count, &err) != TR_OK) {
        fprintf(stderr, "trac0r info: --devices: %s\n", err.msg);
        /* No OpenCL is the machine's setup (2); a driver that fails or memory running out
         * is a failure while working (1), as for device_error(). */
        return err.code == TR_STATUS_DEVICE || err.code == TR_STATUS_OUT_OF_MEMORY ? CLI_FAILURE
                                                                                   : CLI_USAGE;
    }
    tr_device_info *devs = calloc((size_t)(count ? count : 1), sizeof *devs);
    if (!devs || tr_device_list("opencl", devs, count, &count, &err) != TR_OK) {
        free(devs);
        fprintf(stderr, "trac0r info: --devices: %s\n", devs ? err.msg : "out of memory");
        return CLI_FAILURE;
    }
    fprintf(fp, "OpenCL devices (use with --device opencl:N):\n");
    if (count == 0) {
        fprintf(fp, "  none: the OpenCL platforms found have no devices\n");
    }
    for (int i = 0; i < count; ++i) {
        const tr_device_info *d = &devs[i];
        fprintf(fp, "  %d: %s\n", i, d->model);
        fprintf(fp, "     platform %d: %s\n", d->platform_index, d->platform);
        fprintf(fp, "     vendor: %s, type: %s, %s\n", d->vendor, d->type, d->version);
        fprintf(fp, "     compute units: %u, memory: %.0f MiB (largest buffer %.0f MiB)\n",
                d->compute_units, (double)d->global_mem / (1024.0 * 1024.0),
                (double)d->max_alloc / (1024.0 * 1024.0));
    }
    free(devs);
    return CLI_OK;
}
