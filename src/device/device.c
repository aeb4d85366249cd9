/* device.c - tr_device: one API over the CPU device (cpu.c) and OpenCL devices
 * (opencl.c). Dispatch is a switch on the kind; each kind keeps its film its own way (the
 * CPU in host memory, OpenCL on the device) with the same semantics. */
#define _POSIX_C_SOURCE 200809L
#include "trac0r/device.h"

#include <errno.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "device/frame.h"
#include "device/opencl.h"
#include "scene/scene_internal.h"
#include "trac0r/registry.h"

struct tr_device {
    tr_device_kind_id kind;
    tr_device_info info;
    const tr_scene *scene; /* the uploaded scene (CPU: rendered from directly) */
    uint64_t generation;   /* its generation at upload (tr_scene_generation) */
    tr_accel_type accel;
    tr_film film; /* CPU: the device's film */
    tr_cl_context *cl;
    uint32_t punctual; /* the uploaded scene's punctual lights (naive cannot render them) */
};

/* The processor's name from /proc/cpuinfo ("" where it cannot be read). */
static void cpu_model(char *out, size_t size) {
    out[0] = '\0';
    FILE *fp = fopen("/proc/cpuinfo", "r");
    if (!fp) {
        return;
    }
    char line[512];
    while (fgets(line, sizeof line, fp)) {
        if (strncmp(line, "model name", 10) == 0) {
            const char *colon = strchr(line, ':');
            if (colon) {
                colon += colon[1] == ' ' ? 2 : 1;
                snprintf(out, size, "%s", colon);
                out[strcspn(out, "\n")] = '\0';
            }
            break;
        }
    }
    fclose(fp);
}

static void cpu_info(tr_device_info *info) {
    memset(info, 0, sizeof *info);
    snprintf(info->name, sizeof info->name, "cpu");
    snprintf(info->kind, sizeof info->kind, "cpu");
    snprintf(info->type, sizeof info->type, "cpu");
    cpu_model(info->model, sizeof info->model);
    info->compute_units = (uint32_t)omp_get_num_procs();
    info->platform_index = -1;
}

static void cl_info(const tr_cl_device_info *d, tr_device_info *info) {
    memset(info, 0, sizeof *info);
    snprintf(info->name, sizeof info->name, "opencl:%d", d->index);
    snprintf(info->kind, sizeof info->kind, "opencl");
    snprintf(info->model, sizeof info->model, "%s", d->name);
    snprintf(info->platform, sizeof info->platform, "%s", d->platform);
    snprintf(info->vendor, sizeof info->vendor, "%s", d->vendor);
    snprintf(info->version, sizeof info->version, "%s", d->version);
    snprintf(info->type, sizeof info->type, "%s", d->type);
    info->compute_units = d->compute_units;
    info->platform_index = d->platform_index;
    info->global_mem = d->global_mem;
    info->max_alloc = d->max_alloc;
}

int tr_device_list(const char *kind, tr_device_info *out, int max, int *count, tr_error *err) {
    *count = 0;
    if (kind && strcmp(kind, "cpu") != 0 && strcmp(kind, "opencl") != 0) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "unknown device kind '%s' (expected cpu or opencl)", kind);
    }
    if (!kind || strcmp(kind, "cpu") == 0) {
        if (max > 0 && out) {
            cpu_info(&out[0]);
        }
        *count = 1;
    }
    if (kind && strcmp(kind, "cpu") == 0) {
        return TR_OK;
    }
    int ncl = 0;
    tr_error clerr;
    if (tr_cl_list_devices(NULL, 0, &ncl, &clerr) != TR_OK) {
        if (kind) {
            if (err) {
                *err = clerr;
            }
            return TR_ERR;
        }
        return TR_OK; /* listing everything: OpenCL has none to add */
    }
    tr_cl_device_info *devs = calloc((size_t)(ncl ? ncl : 1), sizeof *devs);
    if (!devs) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory listing OpenCL devices");
    }
    if (tr_cl_list_devices(devs, ncl, &ncl, err) != TR_OK) {
        free(devs);
        return TR_ERR;
    }
    for (int i = 0; i < ncl; ++i) {
        if (*count < max && out) {
            cl_info(&devs[i], &out[*count]);
        }
        ++*count;
    }
    free(devs);
    return TR_OK;
}

/* "opencl" -> 0, "opencl:N" -> N; -1 for anything else. */
static int opencl_index(const char *name) {
    if (strncmp(name, "opencl", 6) != 0) {
        return -1;
    }
    if (name[6] == '\0') {
        return 0;
    }
    if (name[6] != ':' || name[7] < '0' || name[7] > '9') {
        return -1;
    }
    char *end;
    errno = 0;
    long n = strtol(name + 7, &end, 10);
    if (*end != '\0' || errno == ERANGE || n > 1023) {
        return -1;
    }
    return (int)n;
}

int tr_device_name_check(const char *name, char *canonical, size_t size, tr_error *err) {
    const int cl_index = opencl_index(name);
    if (strcmp(name, "cpu") == 0 || cl_index >= 0) {
        if (canonical && size > 0) {
            if (cl_index >= 0) {
                snprintf(canonical, size, "opencl:%d", cl_index);
            } else {
                snprintf(canonical, size, "cpu");
            }
        }
        return TR_OK;
    }
    if (strncmp(name, "opencl", 6) == 0) {
        return tr_error_set(err, TR_STATUS_NOT_FOUND,
                            "expected opencl:N with N in 0..1023, got '%.100s'", name);
    }
    return tr_error_set(err, TR_STATUS_NOT_FOUND,
                        "unknown device '%.100s' (expected cpu, opencl or opencl:N with N in "
                        "0..1023)",
                        name);
}

tr_device *tr_device_create(const char *name, tr_error *err) {
    if (!name) {
        name = "cpu";
    }
    const int cl_index = opencl_index(name);
    if (tr_device_name_check(name, NULL, 0, err) != TR_OK) {
        return NULL;
    }
    tr_device *dev = calloc(1, sizeof *dev);
    if (!dev) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory opening device '%s'", name);
        return NULL;
    }
    if (cl_index < 0) {
        dev->kind = TR_DEVICE_CPU;
        cpu_info(&dev->info);
        return dev;
    }
    dev->kind = TR_DEVICE_OPENCL;
    dev->cl = tr_cl_open(cl_index, err);
    if (!dev->cl) {
        free(dev);
        return NULL;
    }
    cl_info(tr_cl_device(dev->cl), &dev->info);
    return dev;
}

void tr_device_destroy(tr_device *dev) {
    if (!dev) {
        return;
    }
    tr_cl_close(dev->cl);
    tr_film_free(&dev->film);
    free(dev);
}

const tr_device_info *tr_device_get_info(const tr_device *dev) {
    return &dev->info;
}

const char *tr_device_kind(const tr_device *dev) {
    return dev->info.kind;
}

tr_device_kind_id tr_device_get_kind(const tr_device *dev) {
    return dev->kind;
}

uint32_t tr_device_caps(const tr_device *dev) {
    return dev->kind == TR_DEVICE_CPU ? TR_DEVICE_CAP_HOST : TR_DEVICE_CAP_SCENE_COPY;
}

int tr_device_traces(const tr_device *dev, tr_accel_type accel) {
    if (dev->kind == TR_DEVICE_CPU) {
        return 1;
    }
    /* opencl.c walks the flat boxes and the binary BVH (bvh2 uploads it too). */
    return accel == TR_ACCEL_TYPE_FLAT || accel == TR_ACCEL_TYPE_BVH || accel == TR_ACCEL_TYPE_BVH2;
}

void tr_device_describe(const tr_device *dev, int threads, char *out, size_t size) {
    if (size == 0) {
        return;
    }
    if (dev->kind == TR_DEVICE_CPU) {
        const int n = threads > 0 ? threads : tr_default_threads();
        snprintf(out, size, "cpu, %d thread%s", n, n == 1 ? "" : "s");
    } else if (dev->scene && !tr_device_traces(dev, dev->scene->accel)) {
        snprintf(out, size, "%s (%s; %s is host-only, the device traces a %s; device bvh %s)",
                 dev->info.name, dev->info.model, tr_accel_name(dev->scene->accel),
                 tr_accel_name(dev->accel), tr_device_bvh_name(tr_device_get_bvh(dev)));
    } else if (dev->scene && dev->accel == TR_ACCEL_TYPE_BVH) {
        snprintf(out, size, "%s (%s; device bvh %s)", dev->info.name, dev->info.model,
                 tr_device_bvh_name(tr_device_get_bvh(dev)));
    } else {
        snprintf(out, size, "%s (%s)", dev->info.name, dev->info.model);
    }
}

const tr_scene *tr_device_scene(const tr_device *dev) {
    return dev->scene;
}

tr_cl_context *tr_device_cl_context(const tr_device *dev) {
    return dev->cl;
}

int tr_device_upload(tr_device *dev, const tr_scene *scene, tr_error *err) {
    if (tr_scene_check_committed(scene, err) != TR_OK) {
        return TR_ERR;
    }
    if (dev->kind == TR_DEVICE_OPENCL) {
        if (tr_cl_upload_scene(dev->cl, scene, err) != TR_OK) {
            return TR_ERR;
        }
        dev->accel = tr_cl_scene_accel(dev->cl);
    } else {
        dev->accel = scene->accel;
    }
    dev->scene = scene;
    dev->generation = tr_scene_generation(scene);
    dev->punctual = tr_scene_view_of(scene).punctual_count;
    return TR_OK;
}

tr_accel_type tr_device_accel(const tr_device *dev) {
    return dev->accel;
}

static const char *const bvh_names[] = {"auto", "bvh2", "cwbvh"};

int tr_device_bvh_from_name(const char *name) {
    for (int i = 0; name && i < (int)(sizeof bvh_names / sizeof bvh_names[0]); ++i) {
        if (strcmp(name, bvh_names[i]) == 0) {
            return i;
        }
    }
    return -1;
}

const char *tr_device_bvh_name(tr_device_bvh bvh) {
    return (unsigned)bvh < sizeof bvh_names / sizeof bvh_names[0] ? bvh_names[bvh] : "unknown";
}

int tr_device_set_bvh(tr_device *dev, tr_device_bvh bvh, tr_error *err) {
    if ((unsigned)bvh > (unsigned)TR_DEVICE_BVH_CWBVH) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "unknown device BVH %d (expected auto, bvh2 or cwbvh)", (int)bvh);
    }
    if (dev->kind == TR_DEVICE_OPENCL) {
        tr_cl_set_bvh(dev->cl, bvh);
    }
    return TR_OK;
}

tr_device_bvh tr_device_get_bvh(const tr_device *dev) {
    return dev->kind == TR_DEVICE_OPENCL && dev->scene ? tr_cl_scene_bvh(dev->cl)
                                                       : TR_DEVICE_BVH_BVH2;
}

uint64_t tr_device_scene_bytes(const tr_device *dev) {
    return dev->kind == TR_DEVICE_OPENCL ? tr_cl_scene_bytes(dev->cl) : 0u;
}

/* The CPU film for frame f: (re)allocated, cleared, when its size or passes change. */
static int cpu_film_for(tr_device *dev, const tr_frame *f, tr_error *err) {
    const uint32_t w = f->camera.screen_width, h = f->camera.screen_height;
    if (dev->film.sum && dev->film.width == w && dev->film.height == h &&
        dev->film.passes == f->passes) {
        return TR_OK;
    }
    tr_film_free(&dev->film);
    return tr_film_init_passes(&dev->film, w, h, f->passes, err);
}

int tr_device_render(tr_device *dev, const tr_camera *cam, const tr_render_config *cfg,
                     uint32_t sample, uint32_t sample_count, const tr_rect *rect,
                     tr_render_stats *stats, tr_error *err) {
    const double t0 = tr_time_now();
    if (!dev->scene) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION, "no scene uploaded to device %s",
                            dev->info.name);
    }
    /* The CPU renders from the scene itself: it must be the one uploaded. (OpenCL renders
     * its own copy, and the scene may be gone by now.) */
    if (dev->kind == TR_DEVICE_CPU && tr_scene_generation(dev->scene) != dev->generation) {
        return tr_error_set(err, TR_STATUS_STALE_SCENE,
                            "the scene changed since it was uploaded to device %s", dev->info.name);
    }
    tr_frame f;
    if (tr_frame_make(&f, cam, cfg, sample, sample_count, rect, err) != TR_OK) {
        return TR_ERR;
    }
    uint64_t rays = 0;
    if (dev->kind == TR_DEVICE_OPENCL &&
        tr_cl_supports_integrator(dev->cl, (int)f.integrator, err) != TR_OK) {
        /* bdpt or vcm on a device without 64-bit atomics and doubles. */
        return TR_ERR;
    }
    if (dev->kind == TR_DEVICE_OPENCL && dev->punctual > 0u &&
        f.integrator == TR_INTEGRATOR_NAIVE) {
        /* The CPU's check (tr_integrator_supports) on the copy the device holds. */
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "%s does not support point, spot or directional lights: use pt",
                            tr_integrator_name((int)f.integrator));
    }
    if (dev->kind == TR_DEVICE_OPENCL) {
        tr_cl_set_tile(dev->cl, cfg->tile);
        if (tr_cl_set_kernel(dev->cl, cfg->opencl_kernel, err) != TR_OK ||
            tr_cl_render_frame(dev->cl, &f, &rays, err) != TR_OK) {
            return TR_ERR;
        }
    } else {
        if (cpu_film_for(dev, &f, err) != TR_OK) {
            return TR_ERR;
        }
        const tr_scene_view view = tr_scene_view_of(dev->scene);
        if (tr_cpu_render(&view, &f, &dev->film, cfg->threads, cfg->tile, cfg->cancel,
                          cfg->cancel_user, &rays, err) != TR_OK) {
            return TR_ERR;
        }
    }
    if (stats) {
        stats->rays = rays;
        stats->seconds = tr_time_now() - t0;
    }
    return TR_OK;
}

/* Copies every array dst keeps from src (of one size; src keeps at least dst's passes). */
static void copy_arrays(tr_film *dst, const tr_film *src) {
    const size_t n = (size_t)src->width * src->height;
    for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
        void *a = tr_film_array_data(dst, i);
        if (a) {
            memcpy(a, tr_film_array_data(src, i), n * tr_film_array_pixel_bytes(i));
        }
    }
}

int tr_device_trace_rays(tr_device *dev, const tr_ray *rays, uint32_t count, int shadow, int reps,
                         uint64_t *hits, double *seconds, tr_error *err) {
    if (dev->kind != TR_DEVICE_OPENCL) {
        return tr_error_set(err, TR_STATUS_UNSUPPORTED,
                            "tr_device_trace_rays: device %s is not OpenCL", dev->info.name);
    }
    if (!dev->scene) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION, "no scene uploaded to device %s",
                            dev->info.name);
    }
    return tr_cl_trace_rays(dev->cl, rays, count, shadow, reps, hits, seconds, err);
}

int tr_device_read_film(tr_device *dev, tr_film *film, tr_error *err) {
    if (dev->kind == TR_DEVICE_OPENCL) {
        return tr_cl_read_film(dev->cl, film, err);
    }
    const tr_film *src = &dev->film;
    if (!src->sum) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION,
                            "the film of device %s is empty: no frame was rendered",
                            dev->info.name);
    }
    if (film->width != src->width || film->height != src->height) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the film is %ux%u but the film of device %s is %ux%u", film->width,
                            film->height, dev->info.name, src->width, src->height);
    }
    if ((film->passes & ~src->passes) != 0u) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "the film of device %s does not keep passes 0x%x", dev->info.name,
                            film->passes & ~src->passes);
    }
    copy_arrays(film, src);
    return TR_OK;
}

int tr_device_write_film(tr_device *dev, const tr_film *film, tr_error *err) {
    if (!film || !film->sum) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "no film to write to device %s",
                            dev->info.name);
    }
    if (dev->kind == TR_DEVICE_OPENCL) {
        return tr_cl_write_film(dev->cl, film, err);
    }
    if (!dev->film.sum || dev->film.width != film->width || dev->film.height != film->height ||
        dev->film.passes != film->passes) {
        tr_film_free(&dev->film);
        if (tr_film_init_passes(&dev->film, film->width, film->height, film->passes, err) !=
            TR_OK) {
            return TR_ERR;
        }
    }
    copy_arrays(&dev->film, film);
    return TR_OK;
}

int tr_device_clear(tr_device *dev, tr_error *err) {
    if (dev->kind == TR_DEVICE_OPENCL) {
        return tr_cl_clear_film(dev->cl, err);
    }
    if (dev->film.sum) {
        tr_film_clear(&dev->film);
    }
    return TR_OK;
}

void tr_device_film_size(const tr_device *dev, uint32_t *width, uint32_t *height,
                         uint32_t *passes) {
    if (dev->kind == TR_DEVICE_OPENCL) {
        tr_cl_film_size(dev->cl, width, height, passes);
        return;
    }
    *width = dev->film.width;
    *height = dev->film.height;
    *passes = dev->film.passes;
}

void tr_device_set_memory_limit(tr_device *dev, uint64_t bytes) {
    if (dev->kind == TR_DEVICE_OPENCL) {
        tr_cl_set_memory_limit(dev->cl, bytes);
    }
}
