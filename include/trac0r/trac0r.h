/* trac0r.h - libtrac0r, a physically based Monte Carlo path tracer in C11.
 *
 * Usage:
 *
 *     tr_error err;
 *     tr_scene *scene = tr_scene_create(&err);
 *     if (!scene || tr_scene_builtin(scene, "cornell", 320, 240, &err) != TR_OK ||
 *         tr_scene_commit(scene, TR_ACCEL_TYPE_BVH, &err) != TR_OK) {
 *         fprintf(stderr, "%s\n", err.msg);
 *         tr_scene_destroy(scene);
 *         return 1;
 *     }
 *     tr_device *dev = tr_device_open("cpu", &err);      // or "opencl:0"
 *     tr_render_config cfg = tr_render_config_default(); // path tracing, 8 bounces
 *     tr_film film;
 *     if (!dev || tr_device_upload(dev, scene, &err) != TR_OK ||
 *         tr_device_render(dev, tr_scene_camera(scene), &cfg, 0, 4, NULL, NULL, &err) != TR_OK ||
 *         tr_film_init(&film, 320, 240, &err) != TR_OK) {           // samples 0..3 above
 *         fprintf(stderr, "%s\n", err.msg);
 *         tr_device_close(dev);
 *         tr_scene_destroy(scene);
 *         return 1;
 *     }
 *     tr_device_read_film(dev, &film, &err);
 *     tr_film_write(&film, "cornell.png", 0.0f, &err);
 *     tr_film_free(&film);
 *     tr_device_close(dev);
 *     tr_scene_destroy(scene);
 *
 * The scene is an opaque handle: edits (materials, shapes, moves) take effect at
 * tr_scene_commit / tr_scene_update, and rendering a scene edited since fails. Only
 * include/ is needed to compile against libtrac0r; every name it declares starts with
 * tr_ or TR_ (TRAC0R_ for the include guards and the version), and tr_abi_sizeof
 * (abi.h) tells a client whether it sees the structs as the library does.
 *
 * Every fallible call returns TR_OK or TR_ERR with a code and a message in tr_error
 * (error.h); nothing prints or exits. The same scene, config and sample numbers give bit-identical
 * films whatever the thread count. */
#ifndef TRAC0R_H
#define TRAC0R_H

#include "trac0r/abi.h"
#include "trac0r/accel.h"
#include "trac0r/camera.h"
#include "trac0r/device.h"
#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/image.h"
#include "trac0r/outfile.h"
#include "trac0r/post.h"
#include "trac0r/realtime.h"
#include "trac0r/recon_device.h"
#include "trac0r/registry.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"
#include "trac0r/scene_file.h"
#include "trac0r/types.h"

#define TRAC0R_VERSION "0.1.0"

#endif
