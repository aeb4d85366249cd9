/* client.c - a program built against an installed libtrac0r (tests/install.sh builds it
 * once through pkg-config and once through find_package). It renders builtin:cornell at
 * 16x12, 2 samples per pixel, with the default configuration, and compares every pixel
 * with the PFM that the installed `trac0r render` wrote for the same scene and samples
 * (argv[1]): library and command must agree bit for bit.
 * Exit status: 0 agree, 1 an API call failed, 3 a pixel differs, 4 a struct's size
 * differs between this program and the library. */
#include <stdio.h>

#include <trac0r/trac0r.h>

#define W 16
#define H 12
#define SPP 2

int main(int argc, char **argv) {
    if (argc != 2) {
        return 1;
    }
#define TR_CLIENT_CHECK_SIZE(name, type)                                                           \
    if (tr_abi_sizeof(TR_ABI_##name) != sizeof(type)) {                                            \
        fprintf(stderr, "client: sizeof(" #type ") differs from the library's\n");                 \
        return 4;                                                                                  \
    }
    TR_ABI_TYPES(TR_CLIENT_CHECK_SIZE)

    tr_error err;
    int status = 1;
    tr_film film = {0};
    tr_image ref = {0};
    tr_device *dev = NULL;
    tr_scene *scene = tr_scene_create(&err);
    if (!scene || tr_scene_builtin(scene, "cornell", W, H, &err) != TR_OK ||
        tr_scene_commit(scene, TR_ACCEL_TYPE_BVH, &err) != TR_OK) {
        goto done;
    }
    dev = tr_device_create("cpu", &err);
    tr_render_config cfg = tr_render_config_default();
    if (!dev || tr_device_upload(dev, scene, &err) != TR_OK ||
        tr_device_render(dev, tr_scene_camera(scene), &cfg, 0, SPP, NULL, NULL, &err) != TR_OK ||
        tr_film_init(&film, W, H, &err) != TR_OK ||
        tr_device_read_film(dev, &film, &err) != TR_OK ||
        tr_image_read_pfm(&ref, argv[1], &err) != TR_OK) {
        goto done;
    }
    if (ref.width != W || ref.height != H) {
        fprintf(stderr, "client: %s is %ux%u\n", argv[1], (unsigned)ref.width,
                (unsigned)ref.height);
        status = 3;
        goto done;
    }
    status = 0;
    for (uint32_t y = 0; y < H && status == 0; y++) {
        for (uint32_t x = 0; x < W && status == 0; x++) {
            tr_vec3 c = tr_film_pixel(&film, x, y);
            const float *r = ref.rgb + 3 * ((size_t)y * W + x);
            if (c.x != r[0] || c.y != r[1] || c.z != r[2]) {
                fprintf(stderr, "client: pixel (%u, %u) is (%g %g %g), trac0r wrote (%g %g %g)\n",
                        (unsigned)x, (unsigned)y, c.x, c.y, c.z, r[0], r[1], r[2]);
                status = 3;
            }
        }
    }
    if (status == 0 && !(tr_film_pixel(&film, W / 2, H / 2).x > 0.0f)) {
        fprintf(stderr, "client: the image is black\n");
        status = 3;
    }
done:
    if (status == 1) {
        fprintf(stderr, "client: %s\n", err.msg);
    }
    tr_image_free(&ref);
    tr_film_free(&film);
    tr_device_destroy(dev);
    tr_scene_destroy(scene);
    return status;
}
