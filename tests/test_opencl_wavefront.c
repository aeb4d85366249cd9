/* test_opencl_wavefront.c - pt's wavefront path tracer on an OpenCL device (PoCL here:
 * entry.cl's tr_cl_wf_* stages over src/kernel/integrator_pt_wf.h) gives the megakernel's
 * film bit for bit: every sum, count and pass, and the same ray count. Its stages run
 * tr_trace_pt_ff's statements in its order on a path's state, and the samplers are
 * stateless (a number depends on seed, pixel, sample and dimension only), so nothing but
 * a mistake can make the two differ.
 *
 * Cases: the thesis's box (glass, glossy) and the measured classic box; a scene with an
 * environment map, a sun, a textured principled floor and point and spot lights; many
 * point and spot lights in the light tree (scenes/many-punctual.json); depth
 * limits, roulette from the first segment, the passes, the real-time flags (clamp,
 * regularization, primary surface replacement, ReSTIR's cuts); an odd 37x23 image with a
 * stride and a rectangle; frames split into chunks of a few paths
 * (TRAC0R_OPENCL_WAVEFRONT_PATHS); and the choice itself: the environment variable, the
 * device type's rule, bad values refused. */
#define _POSIX_C_SOURCE 200809L /* setenv, unsetenv */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "device/opencl.h"
#include "trac0r/trac0r.h"

#ifndef TR_SOURCE_DIR
#error "TR_SOURCE_DIR must name the source tree"
#endif

/* Renders samples [first, first+spp) of `scene` with cfg and the given kernel on dev
 * into *film (initialised here with cfg's passes); *rays gets the ray count. */
static int render(tr_device *dev, const tr_scene *scene, tr_render_config cfg, int kernel,
                  uint32_t spp, const tr_rect *rect, tr_film *film, uint64_t *rays) {
    tr_error err;
    const tr_camera *cam = tr_scene_camera(scene);
    cfg.opencl_kernel = kernel;
    tr_render_stats st;
    int ok = tr_film_init_passes(film, cam->screen_width, cam->screen_height, cfg.passes, &err) ==
                 TR_OK &&
             tr_device_clear(dev, &err) == TR_OK &&
             tr_device_render(dev, cam, &cfg, 0, spp, rect, &st, &err) == TR_OK &&
             tr_device_read_film(dev, film, &err) == TR_OK;
    CHECK(ok, "render with kernel %s: %s", tr_opencl_kernel_name(kernel), err.msg);
    *rays = ok ? st.rays : 0;
    return ok;
}

/* Whether two films hold the same bits in every array. */
static int films_equal(const tr_film *a, const tr_film *b, const char *what) {
    const size_t n = (size_t)a->width * a->height;
    for (int i = 0; i < TR_FILM_ARRAYS; ++i) {
        const void *da = tr_film_array_data(a, i), *db = tr_film_array_data(b, i);
        if (!da || !db) {
            CHECK(da == db, "%s: array %d kept by one film only", what, i);
            continue;
        }
        const size_t bytes = n * tr_film_array_pixel_bytes(i);
        if (memcmp(da, db, bytes) != 0) {
            size_t diff = 0;
            for (size_t k = 0; k < bytes; ++k) {
                diff += ((const unsigned char *)da)[k] != ((const unsigned char *)db)[k];
            }
            CHECK(0, "%s: film array %d differs in %zu of %zu bytes", what, i, diff, bytes);
            return 0;
        }
    }
    return 1;
}

/* The mean radiance of a film (over the pixels with samples). */
static double film_mean(const tr_film *f) {
    double s = 0.0;
    size_t n = 0;
    for (size_t i = 0; i < (size_t)f->width * f->height; ++i) {
        if (f->count[i]) {
            s += (f->sum[3 * i] + f->sum[3 * i + 1] + f->sum[3 * i + 2]) / f->count[i];
            ++n;
        }
    }
    return n ? s / (double)n : 0.0;
}

/* Renders with the megakernel and the wavefront; checks that the films and ray counts
 * are equal and that something was rendered. Returns the megakernel's mean. */
static double compare(tr_device *dev, const tr_scene *scene, tr_render_config cfg, uint32_t spp,
                      const tr_rect *rect, const char *what) {
    tr_film mega, wave;
    uint64_t rays_mega = 0, rays_wave = 0;
    double mean = 0.0;
    if (render(dev, scene, cfg, TR_OPENCL_KERNEL_MEGA, spp, rect, &mega, &rays_mega) &&
        render(dev, scene, cfg, TR_OPENCL_KERNEL_WAVEFRONT, spp, rect, &wave, &rays_wave)) {
        films_equal(&mega, &wave, what);
        CHECK(rays_mega == rays_wave, "%s: rays %llu (mega) against %llu (wavefront)", what,
              (unsigned long long)rays_mega, (unsigned long long)rays_wave);
        mean = film_mean(&mega);
        CHECK(mean > 0.0 && rays_mega > 0, "%s: an empty film (mean %g, %llu rays)", what, mean,
              (unsigned long long)rays_mega);
        printf("%-44s mean %.6f, %llu rays: identical\n", what, mean,
               (unsigned long long)rays_mega);
    }
    tr_film_free(&mega);
    tr_film_free(&wave);
    return mean;
}

static tr_scene *builtin(const char *name, uint32_t w, uint32_t h) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s && tr_scene_builtin(s, name, w, h, &err) == TR_OK &&
              tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK,
          "%s: %s", name, err.msg);
    return s;
}

static tr_scene *from_text(const char *name, const char *text, uint32_t w, uint32_t h) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/%s", TR_SOURCE_DIR, name);
    int ok = s && tr_scene_file_parse(s, path, text, strlen(text), NULL, NULL, &err) == TR_OK;
    tr_camera cam = ok ? *tr_scene_camera(s) : (tr_camera){0};
    ok = ok && tr_camera_resize(&cam, w, h, &err) == TR_OK;
    if (ok) {
        tr_scene_set_camera(s, &cam);
    }
    ok = ok && tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK;
    CHECK(ok, "%s: %s", name, err.msg);
    return s;
}

static tr_scene *from_file(const char *name, uint32_t w, uint32_t h) {
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/%s", TR_SOURCE_DIR, name);
    FILE *f = fopen(path, "rb");
    CHECK(f != NULL, "cannot open %s", path);
    static char text[1 << 16];
    size_t n = f ? fread(text, 1, sizeof text - 1, f) : 0;
    if (f) {
        fclose(f);
    }
    text[n] = '\0';
    return from_text(name, text, w, h);
}

/* An environment map, a sun, a textured principled floor, glass, gold, a transmissive
 * principled sphere that absorbs (volume attenuation), and a point and a
 * spot light: every light sample shade takes and connect adds. */
static const char outdoor[] =
    "{\"version\": 1,"
    " \"camera\": {\"position\": [0.2, 1.1, 4.2], \"look_at\": [0, 0.45, 0], \"up\": [0, 1, 0],"
    "  \"fov\": 38, \"handedness\": \"right\"},"
    " \"environment\": {\"map\": \"textures/sky.hdr\", \"strength\": 1.0, \"rotation\": 20},"
    " \"sun\": {\"direction\": [-0.6, 0.55, 0.4]},"
    " \"lights\": [{\"type\": \"point\", \"position\": [1, 1.5, 1], \"intensity\": 2},"
    "  {\"type\": \"spot\", \"position\": [-1, 2, 1], \"direction\": [0.3, -1, -0.2],"
    "   \"intensity\": 5, \"color\": [1, 0.8, 0.6]}],"
    " \"materials\": {"
    "  \"floor\": {\"type\": \"principled\", \"color\": [1, 1, 1], \"roughness\": 0.55,"
    "   \"texture\": \"textures/checker.png\"},"
    "  \"gold\": {\"type\": \"principled\", \"color\": [1.0, 0.78, 0.34], \"roughness\": 0.25,"
    "   \"metallic\": 1},"
    "  \"glass\": {\"type\": \"glass\", \"color\": [0.95, 0.97, 1.0], \"ior\": 1.5},"
    "  \"jade\": {\"type\": \"principled\", \"color\": [0.9, 1, 0.9], \"roughness\": 0.2,"
    "   \"transmission\": 1, \"attenuation_color\": [0.4, 0.8, 0.5],"
    "   \"attenuation_distance\": 0.3},"
    "  \"lamp\": {\"type\": \"emitter\", \"color\": [4, 4, 3], \"emittance\": 1}},"
    " \"shapes\": ["
    "  {\"type\": \"quad\", \"vertices\": [[-4, 0, -4], [4, 0, -4], [4, 0, 4], [-4, 0, 4]],"
    "   \"material\": \"floor\"},"
    "  {\"type\": \"icosphere\", \"smooth\": true, \"subdivisions\": 2,"
    "   \"position\": [-1.0, 0.45, 0.2], \"scale\": 0.45, \"material\": \"gold\"},"
    "  {\"type\": \"icosphere\", \"smooth\": true, \"subdivisions\": 2,"
    "   \"position\": [0.35, 0.3, 1.3], \"scale\": 0.3, \"material\": \"glass\"},"
    "  {\"type\": \"icosphere\", \"smooth\": true, \"subdivisions\": 2,"
    "   \"position\": [1.2, 0.35, 0.6], \"scale\": 0.35, \"material\": \"jade\"},"
    "  {\"type\": \"quad\", \"vertices\": [[0.5, 2, -1], [1.5, 2, -1], [1.5, 2, 0], [0.5, 2, 0]],"
    "   \"material\": \"lamp\"}]}";

int main(void) {
    tr_error err;
    unsetenv("TRAC0R_OPENCL_KERNEL");
    unsetenv("TRAC0R_OPENCL_WAVEFRONT_PATHS");
    tr_device *dev = tr_device_create("opencl:0", &err);
    CHECK(dev != NULL, "tr_device_create(opencl:0): %s", err.msg);
    if (!dev) {
        return check_finish("test_opencl_wavefront");
    }
    tr_cl_context *cl = tr_device_cl_context(dev);

    /* The thesis's box (glass, a glossy sphere), 48x36. */
    tr_scene *box = builtin("cornell", 48, 36);
    CHECK(tr_device_upload(dev, box, &err) == TR_OK, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.seed = 5;
    const double full = compare(dev, box, cfg, 16, NULL, "cornell 48x36, 16 spp");
    cfg.sampler = TR_SAMPLER_ZSOBOL;
    compare(dev, box, cfg, 4, NULL, "cornell, zsobol");
    cfg.sampler = TR_SAMPLER_SOBOL;

    /* Depth limits and roulette: the same on both, and they change the image. */
    cfg.max_depth = 2;
    const double short2 = compare(dev, box, cfg, 16, NULL, "cornell, max depth 2");
    CHECK(short2 < full, "max depth 2 should darken the box: %g against %g", short2, full);
    cfg.max_depth = 1;
    compare(dev, box, cfg, 4, NULL, "cornell, max depth 1");
    cfg.max_depth = 0;
    cfg.roulette_start = 1;
    compare(dev, box, cfg, 16, NULL, "cornell, roulette from segment 1");
    cfg.roulette_start = 0;

    /* Every pass, and the real-time flags. */
    cfg.passes = TR_PASS_ALL | TR_PASS_VARIANCE | TR_PASS_DIRECT | TR_PASS_EMISSION;
    compare(dev, box, cfg, 8, NULL, "cornell, every pass");
    cfg.clamp_indirect = 0.5f;
    cfg.regularize = 1;
    cfg.psr = 1;
    compare(dev, box, cfg, 8, NULL, "cornell, clamp + regularize + psr");
    cfg.no_primary_direct = 1;
    compare(dev, box, cfg, 8, NULL, "cornell, no primary direct");
    cfg.no_primary_direct = 2;
    compare(dev, box, cfg, 8, NULL, "cornell, no primary indirect");
    cfg = tr_render_config_default();
    cfg.seed = 5;

    /* Split into chunks of a few paths: 101 paths (fewer than the 1728 points, one sample
     * at a time) and 5000 (two samples of every point at a time, the last chunk short). */
    tr_device_destroy(dev);
    setenv("TRAC0R_OPENCL_WAVEFRONT_PATHS", "101", 1);
    dev = tr_device_create("opencl:0", &err);
    CHECK(dev && tr_device_upload(dev, box, &err) == TR_OK, "%s", err.msg);
    compare(dev, box, cfg, 5, NULL, "cornell, chunks of 101 paths");
    tr_device_destroy(dev);
    setenv("TRAC0R_OPENCL_WAVEFRONT_PATHS", "5000", 1);
    dev = tr_device_create("opencl:0", &err);
    CHECK(dev && tr_device_upload(dev, box, &err) == TR_OK, "%s", err.msg);
    compare(dev, box, cfg, 5, NULL, "cornell, chunks of 5000 paths");
    tr_device_destroy(dev);
    setenv("TRAC0R_OPENCL_WAVEFRONT_PATHS", "0", 1);
    dev = tr_device_create("opencl:0", &err);
    CHECK(!dev && err.code == TR_STATUS_INVALID_ARGUMENT,
          "TRAC0R_OPENCL_WAVEFRONT_PATHS=0 should be refused (code %d)", (int)err.code);
    tr_device_destroy(dev);
    unsetenv("TRAC0R_OPENCL_WAVEFRONT_PATHS");
    dev = tr_device_create("opencl:0", &err);
    CHECK(dev != NULL, "%s", err.msg);
    if (!dev) {
        tr_scene_destroy(box);
        return check_finish("test_opencl_wavefront");
    }
    cl = tr_device_cl_context(dev);

    /* The memory check counts the wavefront's paths: with room for 300 of them beside the
     * scene and the film it renders in chunks (the same image as the megakernel's); with
     * room for fewer than a work group of them it refuses, and the device still works. */
    CHECK(tr_device_upload(dev, box, &err) == TR_OK, "%s", err.msg);
    compare(dev, box, cfg, 2, NULL, "cornell, no memory limit");
    const uint64_t held = tr_cl_scene_bytes(cl) + tr_cl_film_bytes(cl);
    CHECK(tr_cl_film_bytes(cl) > 0, "no film after a render");
    tr_device_set_memory_limit(dev, held + 300 * tr_cl_wavefront_path_bytes());
    compare(dev, box, cfg, 3, NULL, "cornell, room for 300 paths");
    tr_device_set_memory_limit(dev, held + 10 * tr_cl_wavefront_path_bytes());
    {
        tr_render_config small = cfg;
        small.opencl_kernel = TR_OPENCL_KERNEL_WAVEFRONT;
        tr_render_stats st;
        CHECK(tr_device_render(dev, tr_scene_camera(box), &small, 0, 1, NULL, &st, &err) ==
                      TR_ERR &&
                  err.code == TR_STATUS_LIMIT,
              "room for 10 paths should be refused (code %d)", (int)err.code);
    }
    tr_device_set_memory_limit(dev, 0);
    compare(dev, box, cfg, 2, NULL, "cornell, the limit lifted");

    /* An odd mid-size image, whole, with a stride, and a rectangle of it. */
    tr_scene *odd = builtin("cornell", 37, 23);
    CHECK(tr_device_upload(dev, odd, &err) == TR_OK, "%s", err.msg);
    compare(dev, odd, cfg, 9, NULL, "cornell 37x23");
    cfg.stride = 3;
    compare(dev, odd, cfg, 3, NULL, "cornell 37x23, stride 3");
    const tr_rect rect = {5, 3, 19, 13};
    compare(dev, odd, cfg, 3, &rect, "cornell 37x23, stride 3, rectangle");
    cfg.stride = 1;
    compare(dev, odd, cfg, 3, &rect, "cornell 37x23, rectangle");
    tr_scene_destroy(odd);

    /* The measured classic box. */
    tr_scene *classic = from_file("cornell-classic.json", 40, 40);
    CHECK(tr_device_upload(dev, classic, &err) == TR_OK, "%s", err.msg);
    compare(dev, classic, cfg, 8, NULL, "cornell-classic 40x40");
    tr_scene_destroy(classic);

    /* Environment map, sun, texture, punctual lights. */
    tr_scene *out = from_text("wavefront-outdoor.json", outdoor, 40, 24);
    CHECK(tr_device_upload(dev, out, &err) == TR_OK, "%s", err.msg);
    compare(dev, out, cfg, 8, NULL, "sky, sun, texture, point and spot 40x24");
    cfg.max_depth = 3;
    cfg.passes = TR_PASS_ALL | TR_PASS_DIRECT | TR_PASS_EMISSION;
    compare(dev, out, cfg, 8, NULL, "sky, sun, ..., max depth 3, passes");
    cfg = tr_render_config_default();
    tr_scene_destroy(out);

    /* 62 point and spot lights in the light tree beside two lamps, two directional ones;
     * without the primary direct light, pt's own walk of the tree for them at the first
     * vertex. */
    tr_scene *many = from_file("many-punctual.json", 40, 30);
    CHECK(tr_device_upload(dev, many, &err) == TR_OK, "%s", err.msg);
    compare(dev, many, cfg, 8, NULL, "many punctual lights 40x30");
    cfg.no_primary_direct = 1;
    compare(dev, many, cfg, 4, NULL, "many punctual lights, no primary direct");
    cfg = tr_render_config_default();
    tr_scene_destroy(many);

    /* The choice. naive always runs as one kernel; auto follows the rule (the
     * megakernel on every device type until a GPU has measured both) unless
     * TRAC0R_OPENCL_KERNEL says otherwise; bad values are refused. */
    CHECK(tr_cl_set_kernel(cl, TR_OPENCL_KERNEL_AUTO, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_cl_frame_kernel(cl, TR_INTEGRATOR_NAIVE) == TR_OPENCL_KERNEL_MEGA, "naive: mega");
    CHECK(tr_cl_frame_kernel(cl, TR_INTEGRATOR_PT) == TR_OPENCL_KERNEL_MEGA,
          "auto on %s should be the megakernel", tr_device_get_info(dev)->type);
    CHECK(tr_cl_set_kernel(cl, TR_OPENCL_KERNEL_WAVEFRONT, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_cl_frame_kernel(cl, TR_INTEGRATOR_PT) == TR_OPENCL_KERNEL_WAVEFRONT, "wavefront");
    CHECK(tr_cl_frame_kernel(cl, TR_INTEGRATOR_NAIVE) == TR_OPENCL_KERNEL_MEGA, "naive: mega");
    CHECK(tr_cl_set_kernel(cl, 3, &err) == TR_ERR && err.code == TR_STATUS_INVALID_ARGUMENT,
          "kernel 3 should be refused");
    CHECK(tr_cl_set_kernel(cl, TR_OPENCL_KERNEL_AUTO, &err) == TR_OK, "%s", err.msg);
    CHECK(tr_device_upload(dev, box, &err) == TR_OK, "%s", err.msg);
    cfg.opencl_kernel = -1;
    CHECK(tr_device_render(dev, tr_scene_camera(box), &cfg, 0, 1, NULL, NULL, &err) == TR_ERR &&
              err.code == TR_STATUS_INVALID_ARGUMENT,
          "opencl_kernel -1 should be refused (code %d)", (int)err.code);
    cfg.opencl_kernel = TR_OPENCL_KERNEL_AUTO;
    cfg.integrator = TR_INTEGRATOR_NAIVE;
    cfg.seed = 3;
    {
        tr_film a, b;
        uint64_t ra = 0, rb = 0;
        if (render(dev, box, cfg, TR_OPENCL_KERNEL_MEGA, 4, NULL, &a, &ra) &&
            render(dev, box, cfg, TR_OPENCL_KERNEL_WAVEFRONT, 4, NULL, &b, &rb)) {
            films_equal(&a, &b, "naive asked to run as a wavefront");
            CHECK(ra == rb, "naive: rays %llu against %llu", (unsigned long long)ra,
                  (unsigned long long)rb);
        }
        tr_film_free(&a);
        tr_film_free(&b);
    }
    tr_device_destroy(dev);

    setenv("TRAC0R_OPENCL_KERNEL", "wavefront", 1);
    dev = tr_device_create("opencl:0", &err);
    CHECK(dev != NULL, "%s", err.msg);
    if (dev) {
        cl = tr_device_cl_context(dev);
        CHECK(tr_cl_frame_kernel(cl, TR_INTEGRATOR_PT) == TR_OPENCL_KERNEL_WAVEFRONT,
              "TRAC0R_OPENCL_KERNEL=wavefront");
        CHECK(tr_cl_set_kernel(cl, TR_OPENCL_KERNEL_MEGA, &err) == TR_OK, "%s", err.msg);
        CHECK(tr_cl_frame_kernel(cl, TR_INTEGRATOR_PT) == TR_OPENCL_KERNEL_MEGA,
              "the config's choice wins over the environment");
        tr_device_destroy(dev);
    }
    setenv("TRAC0R_OPENCL_KERNEL", "fast", 1);
    dev = tr_device_create("opencl:0", &err);
    CHECK(!dev && err.code == TR_STATUS_INVALID_ARGUMENT,
          "TRAC0R_OPENCL_KERNEL=fast should be refused (code %d)", (int)err.code);
    tr_device_destroy(dev);
    unsetenv("TRAC0R_OPENCL_KERNEL");

    tr_scene_destroy(box);
    return check_finish("test_opencl_wavefront");
}
