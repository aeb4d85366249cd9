/* mesh_guard.h - what a model file may do to the process that imports it.
 *
 * Assimp reads model files and the files they name (an OBJ's mtllib, a glTF buffer's
 * uri) through the callbacks here, which
 *   - open regular files only (a FIFO would block the import for ever);
 *   - confine the files a model names to the model's own directory tree, symbolic links
 *     resolved, unless the environment variable TRAC0R_MODEL_ROOT names a directory that
 *     holds them (TRAC0R_MODEL_ROOT=/ allows any file);
 *   - check the sizes a file declares in its header (a GLB's chunk lengths, a PLY's element
 *     counts) against the file's real size before Assimp allocates for them;
 *   - stop reading after TR_MESH_MAX_READ_BYTES in all (the import's input budget; with
 *     the declared sizes checked, Assimp's memory grows with what it reads).
 * Internal to the library. */
#ifndef TRAC0R_SCENE_MESH_GUARD_H
#define TRAC0R_SCENE_MESH_GUARD_H

#include <assimp/scene.h>

#include "trac0r/error.h"

#define TR_MESH_MAX_READ_BYTES (1ull << 30)

/* The limits of the trial import in a child process (below): CPU seconds (the
 * environment's TRAC0R_IMPORT_CPU_SECONDS, 1..86400, sets another) and address space. */
#define TR_MESH_IMPORT_CPU_SECONDS 120u
#define TR_MESH_IMPORT_MAX_MEMORY (16ull << 30)

/* aiImportFileEx through the callbacks above. NULL with `err` set ("Assimp cannot read
 * 'PATH': ...", or the guard's own reason) when the import fails. Where the system can
 * fork, the import runs in a child process under TR_MESH_IMPORT_CPU_SECONDS of CPU time
 * and TR_MESH_IMPORT_MAX_MEMORY of address space, which sends the scene back through a
 * pipe in Assimp's binary form (or, where that form would lose what trac0r reads, says
 * the import succeeded, and it runs again here): a crash or hang in Assimp becomes one
 * error naming the file ("the importer crashed on 'PATH': signal 11"), never this
 * process's end. */
const struct aiScene *tr_mesh_guarded_import(const char *path, unsigned int flags, tr_error *err);

/* The declared-size check alone, on `size` bytes of a file's start `head` whose whole size
 * is `file_size` (for the fuzzer and tests). TR_OK when nothing claims more than the file
 * holds. */
int tr_mesh_check_declared_sizes(const char *name, const unsigned char *head, size_t size,
                                 unsigned long long file_size, tr_error *err);

/* The model-confinement rule above for a file a model names outside Assimp (a texture):
 * TR_OK when `file` (symbolic links resolved) lies in the tree under `model_dir` or under
 * TRAC0R_MODEL_ROOT; TR_STATUS_LIMIT otherwise. */
int tr_mesh_check_confined(const char *model_dir, const char *file, tr_error *err);

#endif
