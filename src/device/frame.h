/* frame.h - what the devices share inside the library: turning a render config into the
 * kernel's frame struct, the film as the kernel writes it, and the CPU device's renderer
 * (tr_render_frame and tr_device's "cpu" both call it). */
#ifndef TR_DEVICE_FRAME_H
#define TR_DEVICE_FRAME_H

#include "kernel/film.h"
#include "kernel/scene_view.h"
#include "kernel/types.h"
#include "trac0r/film.h"
#include "trac0r/render.h"

/* Checks cfg (tr_render_config_check), the camera's size, the sample range and the
 * rectangle (NULL: the whole image), and fills the kernel's frame struct. */
int tr_frame_make(tr_frame *f, const tr_camera *cam, const tr_render_config *cfg, uint32_t sample,
                  uint32_t sample_count, const tr_rect *rect, tr_error *err);

/* The film's host buffers as the kernel writes them. */
tr_film_view tr_film_view_of(tr_film *film);

/* Renders frame f into film (host memory, the camera's size, keeping f->passes) with
 * OpenMP threads over tiles of the frame's grid. cancel (may be NULL) is asked before
 * each tile; when it answers nonzero the remaining tiles are skipped and the call fails
 * with "frame cancelled". *rays (may be NULL) gets the intersection queries made. */
int tr_cpu_render(const tr_scene_view *view, const tr_frame *f, tr_film *film, int threads,
                  uint32_t tile, int (*cancel)(void *), void *cancel_user, uint64_t *rays,
                  tr_error *err);

#endif
