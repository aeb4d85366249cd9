/* trac0r.h - libtrac0r, a physically based Monte Carlo path tracer in C11.
 *
 * A program that renders the thesis's Cornell box for at most a second, up to 256 samples
 * per pixel, with progress, and writes it (built and run as the test usage_block). Usage:
 *
 *     static int show(void *user, const tr_session_progress *p) { // after every pass
 *         (void)user;
 *         fprintf(stderr, "\r%u/%u spp, %.2f s", p->samples, p->spp, p->seconds);
 *         return 0; // nonzero would stop the render here
 *     }
 *     int main(void) {
 *         tr_error err;
 *         tr_scene *scene = tr_scene_create(&err);
 *         tr_device *dev = tr_device_create("cpu", &err); // or "opencl:0"
 *         if (!scene || !dev || tr_scene_builtin(scene, "cornell", 320, 240, &err) != TR_OK ||
 *             tr_scene_commit(scene, TR_ACCEL_TYPE_BVH, &err) != TR_OK) {
 *             return fprintf(stderr, "%s\n", err.msg), 1;
 *         }
 *         tr_session_desc desc = {0}; // zero means the defaults: 16 spp, no limits
 *         desc.spp = 256;
 *         desc.time_limit = 1.0; // seconds: the image is that of the passes made in time
 *         desc.progress = show;
 *         tr_session *s = tr_session_create(dev, scene, NULL, &desc, &err); // default config
 *         const tr_film *film = NULL;
 *         int rc = !s || tr_session_run(s, &err) != TR_OK || !(film = tr_session_film(s, &err)) ||
 *                  tr_film_write(film, "cornell.png", 0.0f, &err) != TR_OK;
 *         fprintf(stderr, "\n%s\n", rc ? err.msg : "cornell.png");
 *         tr_session_destroy(s);
 *         tr_device_destroy(dev);
 *         tr_scene_destroy(scene);
 *         return rc;
 *     }
 *
 * A render without the session's loop is one call: tr_device_render adds a range of
 * samples to the device's film (device.h), tr_device_read_film copies it out.
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
#include "trac0r/measure.h"
#include "trac0r/outfile.h"
#include "trac0r/parse.h"
#include "trac0r/post.h"
#include "trac0r/realtime.h"
#include "trac0r/recon_device.h"
#include "trac0r/registry.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"
#include "trac0r/scene_file.h"
#include "trac0r/session.h"
#include "trac0r/types.h"
#include "trac0r/upscale.h"

#define TRAC0R_VERSION "0.1.0"

#endif
