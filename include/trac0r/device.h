/* device.h - where frames are rendered: the CPU or an OpenCL device, behind one API.
 *
 *     tr_error err;
 *     tr_device *dev = tr_device_create("cpu", &err);       // or "opencl", "opencl:1"
 *     if (!dev || tr_device_upload(dev, scene, &err) != TR_OK) { puts(err.msg); ... }
 *     tr_render_config cfg = tr_render_config_default();
 *     cfg.passes = TR_PASS_ALBEDO | TR_PASS_NORMAL;
 *     tr_device_render(dev, &camera, &cfg, 0, 16, NULL, NULL, &err);  // samples 0..15
 *     tr_film film;
 *     tr_film_init_passes(&film, camera.screen_width, camera.screen_height, cfg.passes, &err);
 *     tr_device_read_film(dev, &film, &err);
 *     tr_device_destroy(dev);
 *
 * A device owns a film of the camera's size that keeps the passes of the last render;
 * each render adds a range of samples over a rectangle of pixels to it, so a render can
 * be split by samples or by rectangles, on one device or several, and the films put
 * back together with tr_film_accumulate. The same scene, config, camera and sample
 * numbers give the same film on every device up to the float differences of its
 * compiler (bit-identical on the CPU whatever the thread count). */
#ifndef TRAC0R_DEVICE_H
#define TRAC0R_DEVICE_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"

typedef struct tr_device tr_device;

/* What is known of one device. */
typedef struct tr_device_info {
    char name[32];      /* what tr_device_create takes: "cpu", "opencl:0", ... */
    char kind[16];      /* "cpu" or "opencl" */
    char model[128];    /* the processor or OpenCL device name */
    char platform[128]; /* OpenCL platform name ("" for the CPU) */
    char vendor[128];
    char version[128]; /* OpenCL: CL_DEVICE_VERSION */
    char type[16];     /* "cpu", "gpu", "accelerator", ... */
    uint32_t compute_units;
    int platform_index;  /* OpenCL: the platform's position, -1 for the CPU */
    uint64_t global_mem; /* bytes (0 for the CPU: host memory) */
    uint64_t max_alloc;  /* bytes, the largest buffer (0 for the CPU) */
} tr_device_info;

/* Lists devices of one kind ("cpu" or "opencl"; NULL: the CPU, then every OpenCL device
 * that can be listed) into up to max entries of out (NULL when max is 0); *count gets how
 * many there are. Listing "opencl" fails when the build has no OpenCL or no platform is
 * installed. */
int tr_device_list(const char *kind, tr_device_info *out, int max, int *count, tr_error *err);

/* Opens a device by name: "cpu", "opencl" (= "opencl:0") or "opencl:N" (N as listed by
 * tr_device_list("opencl", ...)). For OpenCL the kernel is compiled here; a compiler
 * failure's message holds the build log. Returns NULL with a message on failure. */
tr_device *tr_device_create(const char *name, tr_error *err);
/* Checks a device name without opening it (a command line's parse): TR_OK with the
 * canonical name ("cpu", "opencl:N") in canonical[0 .. size), or TR_STATUS_NOT_FOUND with
 * a message naming what is expected. */
int tr_device_name_check(const char *name, char *canonical, size_t size, tr_error *err);
void tr_device_destroy(tr_device *dev);
const tr_device_info *tr_device_get_info(const tr_device *dev);
/* "cpu" or "opencl" (tr_device_get_kind names it as an enum). */
const char *tr_device_kind(const tr_device *dev);

/* The kinds of device. */
typedef enum tr_device_kind_id {
    TR_DEVICE_CPU = 0,    /* the host's cores, by OpenMP threads ("cpu") */
    TR_DEVICE_OPENCL = 1, /* an OpenCL device ("opencl:N") */
} tr_device_kind_id;
tr_device_kind_id tr_device_get_kind(const tr_device *dev);

/* What a device does, as flags (tr_device_caps), for programs that adapt to it without
 * naming its kind. */
/* Frames run on the calling process's CPU threads, as many as tr_render_config.threads
 * asks (0: tr_default_threads). */
#define TR_DEVICE_CAP_HOST 0x1u
/* tr_device_upload copies the scene into the device's own memory: a changed scene is
 * seen only after it is uploaded again, and the upload costs time of its own. */
#define TR_DEVICE_CAP_SCENE_COPY 0x2u
uint32_t tr_device_caps(const tr_device *dev);
/* Whether the device traces a scene committed with `accel` on that structure itself
 * (nonzero), or builds a structure of its own from it (0: OpenCL with Embree's). */
int tr_device_traces(const tr_device *dev, tr_accel_type accel);
/* One line that says what frames run on, into out (size bytes, always terminated): "cpu,
 * 4 threads" (threads as tr_render_config.threads, 0: tr_default_threads) or
 * "opencl:0 (MODEL)", followed for an uploaded scene the device does not trace on its own
 * structure by which one it traces ("opencl:0 (MODEL; embree is host-only, the device
 * traces a bvh)"). */
void tr_device_describe(const tr_device *dev, int threads, char *out, size_t size);

/* Hands a committed scene to the device: the CPU keeps a reference (the scene must
 * outlive the device's use of it), OpenCL copies its arrays. Call again after changing
 * the scene; rendering a scene changed since its upload fails. The film is kept. */
int tr_device_upload(tr_device *dev, const tr_scene *scene, tr_error *err);
/* The scene last uploaded (NULL before the first upload). */
const tr_scene *tr_device_scene(const tr_device *dev);
/* The structure the device walks for the uploaded scene: the scene's own, except that
 * OpenCL walks the binary BVH for bvh and bvh2, and a BVH of its own for a scene
 * committed to Embree (a host library). */
tr_accel_type tr_device_accel(const tr_device *dev);
/* Which BVH an OpenCL device walks where it walks a BVH (scenes committed with bvh or bvh2,
 * and the BVH it builds for Embree's and instanced scenes): the binary BVH, or the
 * compressed 8-wide BVH converted from it at upload (Ylitie, Karras and Laine 2017: 80-byte
 * nodes of 8 quantized child boxes), which finds the same closest hits. AUTO follows one
 * rule by device type (src/device/opencl.c). The CPU device and the flat structure take no
 * BVH from it. */
typedef enum tr_device_bvh {
    TR_DEVICE_BVH_AUTO = 0,
    TR_DEVICE_BVH_BVH2 = 1,  /* "bvh2": the binary BVH */
    TR_DEVICE_BVH_CWBVH = 2, /* "cwbvh": the compressed wide BVH */
} tr_device_bvh;
/* "auto", "bvh2" or "cwbvh" -> the value; -1 for any other name. */
int tr_device_bvh_from_name(const char *name);
const char *tr_device_bvh_name(tr_device_bvh bvh);
/* Sets the choice for the device's next uploads (a device opens with AUTO). AUTO takes the
 * environment variable TRAC0R_OPENCL_BVH's name where it is set (another value than the
 * three names fails tr_device_create with TR_STATUS_INVALID_ARGUMENT), else the rule.
 * TR_STATUS_INVALID_ARGUMENT for a value outside the enum; the CPU accepts and ignores it. */
int tr_device_set_bvh(tr_device *dev, tr_device_bvh bvh, tr_error *err);
/* The BVH the device walks for the uploaded scene: TR_DEVICE_BVH_CWBVH where it walks the
 * compressed wide BVH, otherwise TR_DEVICE_BVH_BVH2 (also the CPU, a flat scene and before
 * an upload). */
tr_device_bvh tr_device_get_bvh(const tr_device *dev);
/* Bytes of device memory the uploaded scene takes (0 on the CPU: it shares the host's). */
uint64_t tr_device_scene_bytes(const tr_device *dev);

/* Adds samples sample .. sample+sample_count-1 of every pixel of `rect` (NULL: the whole
 * image) to the device's film, traced from `cam`. The film takes the camera's screen size
 * and the passes cfg->passes asks for: a render of another size or other passes than the
 * previous one clears it first. cfg->threads, tile and cancel apply to the CPU only.
 * stats (may be NULL) gets the rays traced and the wall time of the call. */
int tr_device_render(tr_device *dev, const tr_camera *cam, const tr_render_config *cfg,
                     uint32_t sample, uint32_t sample_count, const tr_rect *rect,
                     tr_render_stats *stats, tr_error *err);
/* Copies the device's film into `film`, which must have its size and may keep only passes
 * it keeps. */
int tr_device_read_film(tr_device *dev, tr_film *film, tr_error *err);
/* Replaces the device's film by a copy of `film` (its size, passes and every sum and
 * count): a render continued from a film kept elsewhere (a checkpoint) adds its samples to
 * those very floats, so it ends with the bits of an uninterrupted one. */
int tr_device_write_film(tr_device *dev, const tr_film *film, tr_error *err);
/* Forgets every sample of the device's film. */
int tr_device_clear(tr_device *dev, tr_error *err);
/* The size and passes of the device's film (0 x 0 before the first render). */
void tr_device_film_size(const tr_device *dev, uint32_t *width, uint32_t *height, uint32_t *passes);

/* Pretends an OpenCL device has only `bytes` of memory (0: its real size), for tests of
 * the out-of-memory path; nothing on the CPU. */
void tr_device_set_memory_limit(tr_device *dev, uint64_t bytes);

#endif
