/* checkpoint.h - the checkpoint file of a session (session.h): the film bit for bit, the
 * samples each tile of the tile plan holds, and the render's identity.
 *
 * Layout, in the writing machine's byte order (docs/distributed.md): the magic
 * "TRAC0RCK"; nine uint32 - version, byte-order mark, width, height, passes, spp, tile
 * side, tile count, length of the description; the uint64 scene hash; the description;
 * one uint32 per tile (its samples); the film's arrays in the film's layout order
 * (tr_film_array_*); an FNV-1a hash of everything before it. The size of the whole file
 * follows from the header, so a file is checked against it before anything is allocated. */
#ifndef TRAC0R_SESSION_CHECKPOINT_H
#define TRAC0R_SESSION_CHECKPOINT_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"

typedef struct tr_ck_id {
    char desc[512];      /* "size=800x600 seed=1 ..." (names the settings in errors) */
    uint64_t scene_hash; /* FNV-1a over the scene's contents and the scene file */
    /* What the film must be: a file whose header says otherwise is refused before its
     * film is allocated, whatever its description claims. */
    uint32_t width, height, passes;
    uint32_t spp_max; /* the most samples per pixel a file may name (--spp's limit) */
} tr_ck_id;

/* The identity of a render of the committed scene with cfg (stride and passes as cfg's;
 * scene_file, may be NULL, hashed too): session.c, apart from the file format so that the
 * reader builds and is fuzzed alone. */
int tr_ck_identity(tr_ck_id *id, const tr_scene *scene, const tr_render_config *cfg,
                   const char *scene_file, tr_error *err);

/* FNV-1a, 64-bit (Fowler, Noll, Vo) of n bytes, continuing from h (start: TR_CK_FNV_OFFSET):
 * checkpoints need to tell renders apart and catch damage, not resist an adversary. */
#define TR_CK_FNV_OFFSET 14695981039346656037ull
uint64_t tr_ck_fnv(uint64_t h, const void *data, size_t n);

/* The tiles of a film: side (pixels) and count, and the samples each holds. */
typedef struct tr_ck_tiles {
    uint32_t side, count;
    uint32_t *samples;
} tr_ck_tiles;

/* Writes a checkpoint through outfile.h: the previous file at path stays until the new
 * one is complete. */
int tr_ck_write(const char *path, const tr_ck_id *id, const tr_film *film, uint32_t spp,
                const tr_ck_tiles *tiles, tr_error *err);

/* Reads a checkpoint of the render `id` with the tile plan `tiles` (side and count; the
 * samples are filled in) into `film` (allocated here). The file is untrusted: its header
 * is checked first (magic, version, sizes against the file's length and against id's film)
 * before anything is allocated, and every pixel's sample count must be its tile's. A
 * damaged or inconsistent file is TR_STATUS_PARSE, another render's
 * TR_STATUS_INVALID_ARGUMENT, a sample count beyond id->spp_max TR_STATUS_LIMIT. */
int tr_ck_read(const char *path, const tr_ck_id *id, tr_ck_tiles *tiles, tr_film *film,
               uint32_t *spp, tr_error *err);

#endif
