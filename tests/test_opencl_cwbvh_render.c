/* test_opencl_cwbvh_render.c - an OpenCL device (PoCL here) renders the same film whether
 * it walks the binary BVH or the compressed wide BVH converted from it
 * (tr_device_set_bvh): the wide traversal finds the same closest hit, so every integrator
 * the device runs (naive, pt, bdpt) traces the same paths, and radiance, counts and passes
 * agree bit for bit, as do the rays counted. Scenes: the classic box, an icosphere box and
 * a scene with instances (the device's own binary BVH over their triangles, then the wide
 * one from it). Also: the choice and its names, what the device reports it walked, flat
 * scenes (no BVH to choose), the CPU device (nothing to choose) and the environment
 * variable TRAC0R_OPENCL_BVH (auto takes it; an explicit choice wins; a bad value refuses
 * to open the device).
 *
 * Needs an OpenCL platform; it fails (not skips) when no device can be opened. */
#define _POSIX_C_SOURCE 200809L
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "trac0r/trac0r.h"

#define W 48u
#define H 36u
#define PASSES (TR_PASS_ALBEDO | TR_PASS_NORMAL | TR_PASS_DEPTH | TR_PASS_PRIM)

static tr_scene *builtin(const char *name, tr_accel_type accel) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    CHECK(s && tr_scene_builtin(s, name, W, H, &err) == TR_OK &&
              tr_scene_commit(s, accel, &err) == TR_OK,
          "%s: %s", name, err.msg);
    return s;
}

/* A floor, a lamp and three placements of one icosphere as instances. */
static tr_scene *instanced(void) {
    tr_error err;
    tr_scene *s = tr_scene_create(&err);
    uint32_t white = 0, red = 0, lamp = 0, proto = 0;
    CHECK(s &&
              tr_scene_add_material(s, tr_material_diffuse(tr_vec3_make(0.8f, 0.8f, 0.8f)), &white,
                                    &err) == TR_OK &&
              tr_scene_add_material(s, tr_material_glossy(tr_vec3_make(0.8f, 0.3f, 0.2f), 0.3f),
                                    &red, &err) == TR_OK &&
              tr_scene_add_material(s, tr_material_emitter(tr_vec3_make(1, 1, 1), 8.0f), &lamp,
                                    &err) == TR_OK,
          "materials: %s", err.msg);
    if (!s) {
        return NULL;
    }
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_ICOSPHERE_SMOOTH);
    d.subdivisions = 2;
    d.material = red;
    d.transform.scale = tr_vec3_make(0.5f, 0.5f, 0.5f);
    d.transform.position = tr_vec3_make(0.0f, 0.5f, 0.0f);
    tr_shape_desc floor = tr_shape_desc_default(TR_SHAPE_PLANE);
    floor.material = white;
    floor.transform.scale = tr_vec3_make(8.0f, 1.0f, 8.0f);
    tr_shape_desc light = tr_shape_desc_default(TR_SHAPE_PLANE);
    light.material = lamp;
    light.transform.position = tr_vec3_make(0.0f, 3.0f, 0.0f);
    light.transform.orientation = tr_vec3_make(3.14159265f, 0.0f, 0.0f);
    light.transform.scale = tr_vec3_make(1.5f, 1.0f, 1.5f);
    CHECK(tr_scene_add_shape(s, &d, &err) == TR_OK &&
              tr_scene_make_prototype(s, 0, &proto, &err) == TR_OK &&
              tr_scene_add_shape(s, &floor, &err) == TR_OK &&
              tr_scene_add_shape(s, &light, &err) == TR_OK,
          "shapes: %s", err.msg);
    const float m[3][12] = {
        {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0},
        {0.4f, 0.2f, 0.0f, 1.1f, 0.0f, 0.5f, 0.1f, -0.2f, 0.1f, 0.0f, 0.45f, 0.3f},
        {-0.6f, 0.0f, 0.1f, -1.0f, 0.0f, 0.7f, 0.0f, 0.1f, 0.2f, 0.0f, 0.6f, -0.5f},
    };
    for (int k = 0; k < 3; ++k) {
        CHECK(tr_scene_add_instance(s, proto, m[k], NULL, &err) == TR_OK, "instance %d: %s", k,
              err.msg);
    }
    tr_camera cam;
    CHECK(tr_camera_make(&cam, tr_vec3_make(0.0f, 1.6f, 4.0f), tr_vec3_make(0.0f, -0.3f, -1.0f),
                         tr_vec3_make(0.0f, 1.0f, 0.0f), 45.0f, 0.0f, 1e30f, W, H, &err) == TR_OK,
          "camera: %s", err.msg);
    tr_scene_set_camera(s, &cam);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, &err) == TR_OK, "commit: %s", err.msg);
    return s;
}

/* Renders 4 samples of `integrator` with the device's BVH set to `bvh` into *film (freed
 * by the caller); returns the rays traced, 0 where the device refused the integrator. */
static uint64_t render(tr_device *dev, const tr_scene *s, int integrator, tr_device_bvh bvh,
                       tr_film *film) {
    tr_error err;
    memset(film, 0, sizeof *film);
    CHECK(tr_device_set_bvh(dev, bvh, &err) == TR_OK, "set_bvh: %s", err.msg);
    CHECK(tr_device_upload(dev, s, &err) == TR_OK && tr_device_clear(dev, &err) == TR_OK,
          "upload: %s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.integrator = integrator;
    cfg.passes = PASSES;
    cfg.seed = 7;
    tr_render_stats st;
    memset(&st, 0, sizeof st);
    if (tr_device_render(dev, tr_scene_camera(s), &cfg, 0, 4, NULL, &st, &err) != TR_OK) {
        CHECK(err.code == TR_STATUS_UNSUPPORTED, "%s: %s", tr_integrator_name(integrator), err.msg);
        return 0;
    }
    CHECK(tr_film_init_passes(film, W, H, PASSES, &err) == TR_OK &&
              tr_device_read_film(dev, film, &err) == TR_OK,
          "read: %s", err.msg);
    return st.rays;
}

static int same(const void *a, const void *b, size_t bytes) {
    return a && b && memcmp(a, b, bytes) == 0;
}

/* The binary and the wide BVH give the same film for every integrator. */
static void check_scene(tr_device *dev, const tr_scene *s, const char *name) {
    static const int integrators[] = {TR_INTEGRATOR_NAIVE, TR_INTEGRATOR_PT, TR_INTEGRATOR_BDPT};
    for (size_t k = 0; k < sizeof integrators / sizeof integrators[0]; ++k) {
        const int in = integrators[k];
        const char *iname = tr_integrator_name(in);
        tr_film a, b;
        const uint64_t ra = render(dev, s, in, TR_DEVICE_BVH_BVH2, &a);
        CHECK(tr_device_get_bvh(dev) == TR_DEVICE_BVH_BVH2, "%s: walks the binary BVH", name);
        const uint64_t rb = render(dev, s, in, TR_DEVICE_BVH_CWBVH, &b);
        CHECK(tr_device_get_bvh(dev) == TR_DEVICE_BVH_CWBVH, "%s: walks the wide BVH", name);
        char line[512];
        tr_device_describe(dev, 0, line, sizeof line);
        CHECK(strstr(line, "cwbvh") != NULL, "the device line names the wide BVH: %s", line);
        if (ra == 0 && rb == 0 && in == TR_INTEGRATOR_BDPT) {
            continue; /* a device without bdpt refuses it with both */
        }
        CHECK(ra > 0 && ra == rb, "%s %s: rays %llu (bvh2) and %llu (cwbvh)", name, iname,
              (unsigned long long)ra, (unsigned long long)rb);
        const size_t px = (size_t)W * H;
        uint32_t seen = 0;
        for (size_t i = 0; a.prim && i < px; ++i) {
            seen += a.prim[i] != 0u;
        }
        CHECK(seen > px / 4, "%s: the camera sees the scene (%u pixels)", name, seen);
        CHECK(same(a.sum, b.sum, px * 3 * sizeof(float)), "%s %s: radiance, bit for bit", name,
              iname);
        CHECK(same(a.count, b.count, px * sizeof(uint32_t)), "%s %s: counts", name, iname);
        CHECK(same(a.albedo, b.albedo, px * 3 * sizeof(float)) &&
                  same(a.normal, b.normal, px * 3 * sizeof(float)) &&
                  same(a.depth, b.depth, px * sizeof(float)) &&
                  same(a.prim, b.prim, px * sizeof(uint32_t)),
              "%s %s: albedo, normal, depth and id passes, bit for bit", name, iname);
        tr_film_free(&a);
        tr_film_free(&b);
    }
}

/* The names, bad values, the CPU device, and a flat scene. */
static void check_choice(tr_device *dev, const tr_scene *flat) {
    static const char *const names[] = {"auto", "bvh2", "cwbvh"};
    for (int i = 0; i < 3; ++i) {
        CHECK(tr_device_bvh_from_name(names[i]) == i &&
                  strcmp(tr_device_bvh_name((tr_device_bvh)i), names[i]) == 0,
              "name %s", names[i]);
    }
    CHECK(tr_device_bvh_from_name("wide") < 0 && tr_device_bvh_from_name("") < 0 &&
              tr_device_bvh_from_name(NULL) < 0 && tr_device_bvh_from_name("CWBVH") < 0,
          "unknown names are refused");
    tr_error err;
    CHECK_STATUS(tr_device_set_bvh(dev, (tr_device_bvh)3, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "a value outside the enum");
    CHECK_STATUS(tr_device_set_bvh(dev, (tr_device_bvh)-1, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "a negative value");
    tr_film f;
    render(dev, flat, TR_INTEGRATOR_NAIVE, TR_DEVICE_BVH_CWBVH, &f);
    CHECK(tr_device_get_bvh(dev) == TR_DEVICE_BVH_BVH2 &&
              tr_device_accel(dev) == TR_ACCEL_TYPE_FLAT,
          "a flat scene walks no BVH");
    tr_film_free(&f);
    tr_device *cpu = tr_device_create("cpu", &err);
    CHECK(cpu && tr_device_set_bvh(cpu, TR_DEVICE_BVH_CWBVH, &err) == TR_OK &&
              tr_device_get_bvh(cpu) == TR_DEVICE_BVH_BVH2,
          "the CPU takes the choice and walks its own structure");
    tr_device_destroy(cpu);
}

/* TRAC0R_OPENCL_BVH: what auto means, read when the device opens. */
static void check_env(const tr_scene *s) {
    tr_error err;
    setenv("TRAC0R_OPENCL_BVH", "wide", 1);
    tr_device *dev = tr_device_create("opencl:0", &err);
    CHECK(dev == NULL && err.code == TR_STATUS_INVALID_ARGUMENT,
          "a bad TRAC0R_OPENCL_BVH refuses the device");
    tr_device_destroy(dev);
    setenv("TRAC0R_OPENCL_BVH", "cwbvh", 1);
    dev = tr_device_create("opencl:0", &err);
    unsetenv("TRAC0R_OPENCL_BVH");
    CHECK(dev != NULL, "device: %s", err.msg);
    if (!dev) {
        return;
    }
    CHECK(tr_device_upload(dev, s, &err) == TR_OK && tr_device_get_bvh(dev) == TR_DEVICE_BVH_CWBVH,
          "auto takes TRAC0R_OPENCL_BVH=cwbvh");
    CHECK(tr_device_set_bvh(dev, TR_DEVICE_BVH_BVH2, &err) == TR_OK &&
              tr_device_upload(dev, s, &err) == TR_OK &&
              tr_device_get_bvh(dev) == TR_DEVICE_BVH_BVH2,
          "an explicit bvh2 wins over the variable");
    tr_device_destroy(dev);
}

int main(void) {
    tr_error err;
    unsetenv("TRAC0R_OPENCL_BVH");
    tr_device *dev = tr_device_create("opencl:0", &err);
    CHECK(dev != NULL, "device: %s", err.msg);
    tr_scene *box = builtin("cornell", TR_ACCEL_TYPE_BVH);
    tr_scene *ico = builtin("cornell-ico-3", TR_ACCEL_TYPE_BVH2);
    tr_scene *inst = instanced();
    tr_scene *flat = builtin("cornell", TR_ACCEL_TYPE_FLAT);
    if (dev && box && ico && inst && flat) {
        check_scene(dev, box, "cornell");
        check_scene(dev, ico, "cornell-ico-3");
        check_scene(dev, inst, "instances");
        check_choice(dev, flat);
        check_env(box);
    }
    tr_device_destroy(dev);
    tr_scene_destroy(box);
    tr_scene_destroy(ico);
    tr_scene_destroy(inst);
    tr_scene_destroy(flat);
    return check_finish("test_opencl_cwbvh_render");
}
