/* test_opencl_instances.c - a scene with instances on an OpenCL device (PoCL here).
 *
 * The device does not walk the two-level structure (host code): given a scene committed
 * to bvh with instances it builds a binary BVH of its own over the instances' transformed
 * triangles, the same build the flattened scene (each placement added as plain triangles,
 * tr_scene_add_prototype_copy) gets at its commit. So the instanced and the flattened
 * scene render to the same bits on the device: radiance and primitive ids.
 *
 * Needs an OpenCL platform; it fails (not skips) when no device can be opened. */
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "trac0r/trac0r.h"

#define W 48u
#define H 36u

static tr_scene *build(int flat, tr_error *err) {
    tr_scene *s = tr_scene_create(err);
    uint32_t white = 0, red = 0, lamp = 0, proto = 0;
    CHECK(s &&
              tr_scene_add_material(s, tr_material_diffuse(tr_vec3_make(0.8f, 0.8f, 0.8f)), &white,
                                    err) == TR_OK &&
              tr_scene_add_material(s, tr_material_glossy(tr_vec3_make(0.8f, 0.3f, 0.2f), 0.3f),
                                    &red, err) == TR_OK &&
              tr_scene_add_material(s, tr_material_emitter(tr_vec3_make(1, 1, 1), 8.0f), &lamp,
                                    err) == TR_OK,
          "materials: %s", err->msg);
    if (!s) {
        return NULL;
    }
    tr_shape_desc d = tr_shape_desc_default(TR_SHAPE_ICOSPHERE_SMOOTH);
    d.subdivisions = 2;
    d.material = red;
    d.transform.scale = tr_vec3_make(0.5f, 0.5f, 0.5f);
    d.transform.position = tr_vec3_make(0.0f, 0.5f, 0.0f);
    CHECK(tr_scene_add_shape(s, &d, err) == TR_OK &&
              tr_scene_make_prototype(s, 0, &proto, err) == TR_OK,
          "prototype: %s", err->msg);
    tr_shape_desc floor = tr_shape_desc_default(TR_SHAPE_PLANE);
    floor.material = white;
    floor.transform.scale = tr_vec3_make(8.0f, 1.0f, 8.0f);
    tr_shape_desc light = tr_shape_desc_default(TR_SHAPE_PLANE);
    light.material = lamp;
    light.transform.position = tr_vec3_make(0.0f, 3.0f, 0.0f);
    light.transform.orientation = tr_vec3_make(3.14159265f, 0.0f, 0.0f);
    light.transform.scale = tr_vec3_make(1.5f, 1.0f, 1.5f);
    CHECK(tr_scene_add_shape(s, &floor, err) == TR_OK &&
              tr_scene_add_shape(s, &light, err) == TR_OK,
          "shapes: %s", err->msg);
    const float m[3][12] = {
        {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0},
        {0.4f, 0.2f, 0.0f, 1.1f, 0.0f, 0.5f, 0.1f, -0.2f, 0.1f, 0.0f, 0.45f, 0.3f},
        {-0.6f, 0.0f, 0.1f, -1.0f, 0.0f, 0.7f, 0.0f, 0.1f, 0.2f, 0.0f, 0.6f, -0.5f},
    };
    for (int k = 0; k < 3; ++k) {
        int rc = flat ? tr_scene_add_prototype_copy(s, proto, m[k], err)
                      : tr_scene_add_instance(s, proto, m[k], NULL, err);
        CHECK(rc == TR_OK, "placement %d: %s", k, err->msg);
    }
    tr_camera cam;
    CHECK(tr_camera_make(&cam, tr_vec3_make(0.0f, 1.6f, 4.0f), tr_vec3_make(0.0f, -0.3f, -1.0f),
                         tr_vec3_make(0.0f, 1.0f, 0.0f), 45.0f, 0.0f, 1e30f, W, H, err) == TR_OK,
          "camera: %s", err->msg);
    tr_scene_set_camera(s, &cam);
    CHECK(tr_scene_commit(s, TR_ACCEL_TYPE_BVH, err) == TR_OK, "commit: %s", err->msg);
    return s;
}

int main(void) {
    tr_error err;
    tr_scene *sc[2] = {build(0, &err), build(1, &err)};
    tr_device *dev = tr_device_create("opencl:0", &err);
    CHECK(dev != NULL, "device: %s", err.msg);
    tr_film film[2];
    memset(film, 0, sizeof film);
    for (int k = 0; k < 2 && dev && sc[k]; ++k) {
        tr_render_config cfg = tr_render_config_default();
        cfg.passes = TR_PASS_PRIM;
        cfg.seed = 11;
        CHECK(tr_device_upload(dev, sc[k], &err) == TR_OK && tr_device_clear(dev, &err) == TR_OK,
              "upload: %s", err.msg);
        CHECK(tr_device_render(dev, tr_scene_camera(sc[k]), &cfg, 0, 4, NULL, NULL, &err) == TR_OK,
              "render: %s", err.msg);
        CHECK(tr_film_init_passes(&film[k], W, H, TR_PASS_PRIM, &err) == TR_OK, "film: %s",
              err.msg);
        CHECK(tr_device_read_film(dev, &film[k], &err) == TR_OK, "read: %s", err.msg);
    }
    if (film[0].sum && film[1].sum) {
        uint32_t seen = 0;
        for (uint32_t i = 0; i < W * H; ++i) {
            seen += film[0].prim[i] != 0;
        }
        CHECK(seen > W * H / 2, "the camera sees the scene (%u pixels)", seen);
        CHECK(memcmp(film[0].sum, film[1].sum, (size_t)W * H * 3 * sizeof(float)) == 0,
              "instanced and flattened radiance, bit for bit");
        CHECK(memcmp(film[0].prim, film[1].prim, (size_t)W * H * sizeof(uint32_t)) == 0,
              "instanced and flattened ids");
    }
    for (int k = 0; k < 2; ++k) {
        tr_film_free(&film[k]);
        tr_scene_destroy(sc[k]);
    }
    tr_device_destroy(dev);
    return check_finish("test_opencl_instances");
}
