/* trac0r.h - libtrac0r, a physically based Monte Carlo path tracer in C11.
 *
 * Usage:
 *
 *     tr_error err;
 *     tr_scene scene;
 *     tr_scene_init(&scene);
 *     if (tr_scene_builtin(&scene, "cornell", 800, 600, &err) != TR_OK) { puts(err.msg); ... }
 *     tr_film film;
 *     tr_film_init(&film, 800, 600, &err);
 *     tr_render_config cfg = tr_render_config_default();
 *     for (uint32_t s = 0; s < 16; ++s)
 *         tr_render_frame(&scene, &scene.camera, &cfg, &film, s, NULL, &err);
 *     tr_film_write(&film, "cornell.png", 0.0f, &err);
 *     tr_film_free(&film);
 *     tr_scene_free(&scene);
 *
 * Every fallible call returns TR_OK or TR_ERR with a code and a message in tr_error
 * (error.h); nothing prints or exits. The same scene, config and sample numbers give bit-identical
 * films whatever the thread count. */
#ifndef TRAC0R_H
#define TRAC0R_H

#include "trac0r/camera.h"
#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/image.h"
#include "trac0r/post.h"
#include "trac0r/registry.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"
#include "trac0r/scene_file.h"

#define TRAC0R_VERSION "0.1.0"

#endif
