/* main.c - the web build's entry points: the C interface web/app.js and web/test.js call
 * (through Emscripten's ccall/cwrap) to load a scene, render real-time frames with
 * tr_realtime and read their pixels and timings, and render a still as `trac0r render`
 * does, for the comparison with the native build (tests/web_check.sh).
 *
 * One scene, one CPU device and one real-time loop at a time, kept here; every function
 * returns 0 on success and -1 with tr_web_error() saying why. Strings and arrays returned
 * are owned here and stay valid until the next call that changes them. */
#include <emscripten.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accel/wbvh.h"
#include "trac0r/camera.h"
#include "trac0r/device.h"
#include "trac0r/film.h"
#include "trac0r/post.h"
#include "trac0r/realtime.h"
#include "trac0r/registry.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"
#include "trac0r/scene_file.h"
#include "trac0r/session.h"
#include "web_api.h"

#define WEB_API EMSCRIPTEN_KEEPALIVE

/* The statistics array tr_web_stats returns, by index (web/app.js names them). */
enum {
    ST_WIDTH,
    ST_HEIGHT,
    ST_SPP,
    ST_FRAME_SPP,
    ST_RENDER_MS,
    ST_TEMPORAL_MS,
    ST_SPATIAL_MS,
    ST_TONEMAP_MS,
    ST_SCALE,
    ST_TRIANGLES,
    ST_THREADS,
    ST_METHOD,
    ST_COUNT
};

static struct web_state {
    tr_device *dev;
    tr_scene *scene;
    tr_realtime *rt;
    tr_render_config cfg; /* the scene's integrator and depth */
    uint32_t rt_spp;      /* the loop's samples per frame */
    tr_camera cam;        /* the scene's camera: near and far distances */
    float view[10];       /* position, direction, up, vertical field of view */
    uint8_t *pixels;      /* RGBA, width x height */
    size_t pixels_cap;
    float *image; /* tr_web_render's mean radiance, RGB */
    double stats[ST_COUNT];
    double render_seconds;
    int threads;
    uint32_t meshes_skipped;
    char info[512];
    char error[512];
} web;

static int fail(const char *what, const tr_error *err) {
    snprintf(web.error, sizeof web.error, "%s%s", what, err ? err->msg : "");
    return -1;
}

WEB_API const char *tr_web_error(void) {
    return web.error;
}

/* Starts the team of threads (the page passes navigator.hardwareConcurrency; the
 * single-threaded module keeps one) and returns how many there are. */
WEB_API int tr_web_start(int threads) {
    web.threads = tr_web_omp_start(threads < 1 ? 1 : threads);
    return web.threads;
}

/* A description of the build for the page: threads and the wide BVH's traversal. */
WEB_API const char *tr_web_info(void) {
    snprintf(web.info, sizeof web.info, "%d thread%s, wide BVH traversal %s, %s", web.threads,
             web.threads == 1 ? "" : "s", tr_wbvh_isa(),
#ifdef __wasm_simd128__
             "WebAssembly SIMD"
#else
             "no SIMD"
#endif
    );
    return web.info;
}

static void drop_scene(void) {
    tr_realtime_destroy(web.rt);
    web.rt = NULL;
    tr_device_destroy(web.dev);
    web.dev = NULL;
    tr_scene_destroy(web.scene);
    web.scene = NULL;
}

static void take_view(const tr_camera *c) {
    const float v[10] = {c->pos.x, c->pos.y,      c->pos.z,      c->dir.x,      c->dir.y,
                         c->dir.z, c->world_up.x, c->world_up.y, c->world_up.z, c->vertical_fov};
    memcpy(web.view, v, sizeof v);
}

/* After a scene is built into web.scene: commit, device, upload, camera. */
static int finish_scene(tr_accel_type accel) {
    tr_error err;
    if (tr_scene_commit(web.scene, accel, &err) != TR_OK) {
        return fail("", &err);
    }
    web.dev = tr_device_create("cpu", &err);
    if (!web.dev || tr_device_upload(web.dev, web.scene, &err) != TR_OK) {
        return fail("cpu device: ", &err);
    }
    web.cam = *tr_scene_camera(web.scene);
    take_view(&web.cam);
    web.rt_spp = 0;
    web.stats[ST_TRIANGLES] = tr_scene_triangle_count(web.scene);
    return 0;
}

static int new_scene(void) {
    tr_error err;
    drop_scene();
    web.meshes_skipped = 0;
    web.scene = tr_scene_create(&err);
    return web.scene ? 0 : fail("", &err);
}

WEB_API int tr_web_load_builtin(const char *name, int width, int height) {
    tr_error err;
    if (new_scene() != 0) {
        return -1;
    }
    web.cfg = tr_render_config_default();
    if (tr_scene_builtin(web.scene, name, (uint32_t)width, (uint32_t)height, &err) != TR_OK) {
        return fail("", &err);
    }
    return finish_scene(TR_ACCEL_TYPE_BVH);
}

/* A scene file in Emscripten's file system (the page writes the shipped ones there,
 * textures beside them), read as `trac0r render FILE --width W --height H` reads it: the
 * size given, the file's integrator, depth and structure where it names them, else pt,
 * its default depth and the BVH. Meshes are not loaded (no Assimp in the web build):
 * tr_web_meshes_skipped says how many the file names. */
/* After tr_scene_file_load or tr_scene_file_parse filled web.scene and *file: the render
 * request of `trac0r render FILE --width W --height H`, then commit and upload. */
static int apply_file(const char *path, const tr_scene_file *file, int width, int height) {
    tr_error err;
    web.meshes_skipped = file->mesh_count;
    tr_render_request req = {0};
    req.width = (uint32_t)width;
    req.height = (uint32_t)height;
    if (!file->has_integrator) {
        req.integrator = "pt";
    }
    if (!file->has_accel) {
        req.accel = "bvh";
    }
    req.allow_dark = file->mesh_count > 0; /* the emitters may be in the meshes */
    tr_render_settings st;
    if (tr_scene_file_apply(web.scene, path, file, &req, &st, &err) != TR_OK) {
        return fail("", &err);
    }
    web.cfg = tr_render_config_default();
    web.cfg.integrator = st.config.integrator;
    web.cfg.max_depth = st.config.max_depth;
    return finish_scene(st.accel);
}

/* A scene file in Emscripten's file system (the page writes the shipped ones there,
 * textures beside them), read as `trac0r render FILE --width W --height H` reads it: the
 * size given, the file's integrator, depth and structure where it names them, else pt,
 * its default depth and the BVH. Meshes are not loaded (no Assimp in the web build):
 * tr_web_meshes_skipped says how many the file names. */
WEB_API int tr_web_load_file(const char *path, int width, int height) {
    tr_error err;
    if (new_scene() != 0) {
        return -1;
    }
    tr_scene_file file;
    const tr_scene_file_options opt = {0, 0};
    if (tr_scene_file_load(web.scene, path, &opt, &file, &err) != TR_OK) {
        return fail("", &err);
    }
    return apply_file(path, &file, width, height);
}

/* The same from the text of a scene file (`name` in messages, and the directory relative
 * paths in it start from). */
WEB_API int tr_web_load_json(const char *name, const char *text, int width, int height) {
    tr_error err;
    if (new_scene() != 0) {
        return -1;
    }
    tr_scene_file file;
    const tr_scene_file_options opt = {0, 0};
    if (tr_scene_file_parse(web.scene, name, text, strlen(text), &opt, &file, &err) != TR_OK) {
        return fail("", &err);
    }
    return apply_file(name, &file, width, height);
}

WEB_API int tr_web_meshes_skipped(void) {
    return (int)web.meshes_skipped;
}

/* The view the page moves: position, direction, up, vertical field of view (degrees);
 * the scene's camera after a load. The page writes it before tr_web_frame. */
WEB_API float *tr_web_view(void) {
    return web.view;
}

static int ensure_pixels(uint32_t w, uint32_t h) {
    const size_t need = (size_t)w * h * 4;
    if (need <= web.pixels_cap) {
        return 0;
    }
    uint8_t *p = realloc(web.pixels, need);
    if (!p) {
        return -1;
    }
    web.pixels = p;
    web.pixels_cap = need;
    return 0;
}

/* One real-time frame of the view at width x height: `method` a tr_recon_method, `spp`
 * samples per pixel, `moving` 1 while the view changes (then `budget_ms` > 0 lowers the
 * resolution to hold it), 0 at rest, where frames of the same view add up. The frame's
 * RGBA pixels: tr_web_pixels, tr_web_stats' size. */
WEB_API int tr_web_frame(int width, int height, int method, int spp, int moving, double budget_ms,
                         float exposure) {
    tr_error err;
    if (!web.scene) {
        return fail("no scene loaded", NULL);
    }
    if (spp < 1) {
        spp = 1;
    }
    if (!web.rt || web.rt_spp != (uint32_t)spp) {
        tr_realtime_destroy(web.rt);
        tr_realtime_desc desc = {0};
        desc.config = &web.cfg;
        desc.spp = (uint32_t)spp;
        desc.accumulate = 1;
        web.rt = tr_realtime_create(web.dev, web.scene, &desc, &err);
        if (!web.rt) {
            return fail("", &err);
        }
        web.rt_spp = (uint32_t)spp;
    }
    const float *v = web.view;
    tr_camera cam;
    if (tr_camera_make(&cam, (tr_vec3){v[0], v[1], v[2]}, (tr_vec3){v[3], v[4], v[5]},
                       (tr_vec3){v[6], v[7], v[8]}, v[9], web.cam.near_dist, web.cam.far_dist,
                       (uint32_t)width, (uint32_t)height, &err) != TR_OK) {
        return fail("camera: ", &err);
    }
    tr_realtime_frame_desc fd = {0};
    fd.camera = &cam;
    fd.method = method;
    fd.moving = moving;
    fd.budget_ms = budget_ms;
    fd.extra_ms = web.stats[ST_TONEMAP_MS];
    tr_realtime_result res;
    if (tr_realtime_frame(web.rt, &fd, &res, &err) != TR_OK) {
        return fail("", &err);
    }
    const double t0 = tr_time_now();
    if (ensure_pixels(res.width, res.height) != 0) {
        return fail("out of memory for the pixels", NULL);
    }
    /* ARGB words (0xAARRGGBB) to the canvas's R, G, B, A bytes. */
    uint32_t *argb = (uint32_t *)(void *)web.pixels;
    if (tr_tonemap_film_curve(res.film, 0, 0, res.width, res.height, exposure, TR_TONEMAP_CLAMP,
                              TR_PIXEL_ARGB8888, argb, (size_t)res.width * 4, &err) != TR_OK) {
        return fail("", &err);
    }
    const size_t n = (size_t)res.width * res.height;
    for (size_t i = 0; i < n; ++i) {
        const uint32_t p = argb[i];
        web.pixels[4 * i] = (uint8_t)(p >> 16);
        web.pixels[4 * i + 1] = (uint8_t)(p >> 8);
        web.pixels[4 * i + 2] = (uint8_t)p;
        web.pixels[4 * i + 3] = 255;
    }
    web.stats[ST_WIDTH] = res.width;
    web.stats[ST_HEIGHT] = res.height;
    web.stats[ST_SPP] = res.spp;
    web.stats[ST_FRAME_SPP] = res.frame_spp;
    web.stats[ST_RENDER_MS] = res.render_ms;
    web.stats[ST_TEMPORAL_MS] = res.temporal_ms;
    web.stats[ST_SPATIAL_MS] = res.spatial_ms;
    web.stats[ST_TONEMAP_MS] = (tr_time_now() - t0) * 1e3;
    web.stats[ST_SCALE] = res.scale;
    web.stats[ST_THREADS] = web.threads;
    web.stats[ST_METHOD] = res.method;
    return 0;
}

WEB_API uint8_t *tr_web_pixels(void) {
    return web.pixels;
}

WEB_API double *tr_web_stats(void) {
    return web.stats;
}

/* A still of the loaded scene as `trac0r render` makes it (a session of `spp` samples,
 * Sobol sampler, `seed`, `threads` (0: all)), at the size the scene was loaded with. The
 * mean radiance, RGB floats with the top row first: tr_web_image; the render's wall time:
 * tr_web_render_seconds. */
WEB_API int tr_web_render(int spp, int seed, int threads) {
    tr_error err;
    if (!web.scene) {
        return fail("no scene loaded", NULL);
    }
    tr_render_config cfg = web.cfg;
    cfg.seed = (uint32_t)seed;
    cfg.threads = threads;
    cfg.sampler = TR_SAMPLER_SOBOL;
    tr_session_desc desc = {0};
    desc.spp = (uint32_t)spp;
    tr_session *s = tr_session_create(web.dev, web.scene, &cfg, &desc, &err);
    if (!s) {
        return fail("", &err);
    }
    const double t0 = tr_time_now();
    if (tr_session_run(s, &err) != TR_OK) {
        tr_session_destroy(s);
        return fail("", &err);
    }
    web.render_seconds = tr_time_now() - t0;
    const tr_film *film = tr_session_film(s, &err);
    if (!film) {
        tr_session_destroy(s);
        return fail("", &err);
    }
    free(web.image);
    web.image = malloc((size_t)film->width * film->height * 3 * sizeof *web.image);
    if (!web.image) {
        tr_session_destroy(s);
        return fail("out of memory for the image", NULL);
    }
    for (uint32_t y = 0; y < film->height; ++y) {
        for (uint32_t x = 0; x < film->width; ++x) {
            const tr_vec3 c = tr_film_pixel(film, x, y);
            float *o = web.image + 3 * ((size_t)y * film->width + x);
            o[0] = c.x;
            o[1] = c.y;
            o[2] = c.z;
        }
    }
    web.stats[ST_WIDTH] = film->width;
    web.stats[ST_HEIGHT] = film->height;
    tr_session_destroy(s);
    return 0;
}

WEB_API float *tr_web_image(void) {
    return web.image;
}

WEB_API double tr_web_render_seconds(void) {
    return web.render_seconds;
}
