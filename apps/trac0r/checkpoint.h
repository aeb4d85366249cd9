/* checkpoint.h - what a render needs to survive its process: a stop flag set by
 * SIGINT/SIGTERM, and checkpoint files holding the exact film and enough to continue.
 *
 * A checkpoint holds the film's sums and counts bit for bit, so continuing it adds the
 * remaining samples to the very floats an uninterrupted render would have held: the
 * resumed image is bit-identical. It also holds the render's identity (what decides the
 * image: the scene's geometry, materials and camera, the scene file's bytes, size, seed,
 * depth, integrator, accel, stride, passes, sampler, light selection, roulette start), and resuming
 * refuses any other. The format is trac0r's own, in the writing machine's byte order
 * (docs/distributed.md). */
#ifndef TRAC0R_CHECKPOINT_H
#define TRAC0R_CHECKPOINT_H

#include <stdint.h>

#include "cli.h"
#include "trac0r/film.h"

/* How a checkpoint's film was rendered: whole passes over the image (all pixels hold the
 * same count), or tile by tile under MPI (a tile holds every sample or none). */
#define CHECKPOINT_PASSES 0u
#define CHECKPOINT_TILES 1u

typedef struct checkpoint_id {
    char desc[512];      /* "size=800x600 seed=1 ..." (names the options in errors) */
    uint64_t scene_hash; /* FNV-1a over the scene's contents and the scene file */
} checkpoint_id;

/* The identity of a render of the committed `scene` with these options. */
int checkpoint_identity(checkpoint_id *id, const cli_common *c, const tr_scene *scene, int stride,
                        uint32_t passes, tr_error *err);

/* Writes the film (its samples: `samples` per pixel for CHECKPOINT_PASSES) through
 * outfile.h: the previous checkpoint at path stays until the new one is complete. */
int checkpoint_write(const char *path, const checkpoint_id *id, uint32_t mode, const tr_film *film,
                     uint32_t samples, uint32_t spp, tr_error *err);

/* Reads a checkpoint into `film` (allocated here: free it with tr_film_free) after
 * checking it belongs to a render with identity `id`: a damaged file is TR_STATUS_PARSE,
 * another render's TR_STATUS_INVALID_ARGUMENT with a message naming what differs. */
int checkpoint_read(const char *path, const checkpoint_id *id, uint32_t *mode, tr_film *film,
                    uint32_t *samples, uint32_t *spp, tr_error *err);

/* SIGINT and SIGTERM set a flag the render polls between passes; a second signal gets
 * the action installed before (the default one where it was ignored) and is raised
 * again: the process ends without waiting for the pass. */
void render_stop_install(void);
/* The signal that asked the render to stop, or 0. */
int render_stop_signal(void);
/* Restores the actions installed before. */
void render_stop_uninstall(void);

#endif
