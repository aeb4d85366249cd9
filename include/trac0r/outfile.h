/* outfile.h - every file trac0r writes, written whole or not at all.
 *
 * A writer opens a temporary file next to the target (so the final rename() stays on one
 * file system), writes through the stream, and commits: the stream is flushed and closed
 * with every error checked, and only then renamed onto PATH. Where the file system has
 * Linux's O_TMPFILE the temporary file has no name until the commit links it as
 * PATH.tmp.XXXXXX just before the rename, so a process killed while writing (SIGKILL)
 * leaves nothing; elsewhere it is created as PATH.tmp.XXXXXX. Any
 * failure, or an abort, removes the temporary file. Images, CSV files, plots, checkpoints
 * and the viewer's state file all go through here, so there is one place where file
 * modes, signals and full disks are handled.
 *
 * Modes: the finished file gets the mode fopen(PATH, "w") would have given it - an
 * existing target keeps its permission bits, a new one gets 0666 less the umask.
 * Targets: PATH must be a regular file or not exist; a directory, device, FIFO or socket
 * is refused when the file is opened (rename() would replace a device node, or fail only
 * after all the work), and so is an existing file this user may not write, as open(2)
 * would refuse it (rename() needs only the directory's permission).
 * Signals: tr_outfile_cleanup_all() removes every temporary file still open; a program's
 * fatal-signal handlers call it before dying (the trac0r command does). */
#ifndef TRAC0R_OUTFILE_H
#define TRAC0R_OUTFILE_H

#include <stdio.h>

#include "trac0r/error.h"

typedef struct tr_outfile tr_outfile;

/* Creates the temporary file for `path`. NULL (with `err` set) on failure, among them a
 * target that exists and is not a regular file. */
tr_outfile *tr_outfile_create(const char *path, tr_error *err);

/* Whether `path` could be written: its type is checked and a temporary file is created
 * and removed again. For commands to check their outputs before long work. */
int tr_outfile_check(const char *path, tr_error *err);

/* Fails with TR_STATUS_INVALID_ARGUMENT when two of the n paths (NULL entries skipped)
 * name one file - the same path, another path to an existing file, or one new name in one
 * directory - so that a command refuses outputs that would overwrite each other before
 * any work. */
int tr_outfile_check_distinct(const char *const *paths, int n, tr_error *err);

/* The stream to write to (binary mode), and a name that opens the temporary file (for
 * libraries that want a file name or descriptor of their own: /proc/self/fd/N for an
 * unnamed one). */
FILE *tr_outfile_stream(tr_outfile *f);
const char *tr_outfile_temp_path(const tr_outfile *f);

/* Finishes the file: flush, close and rename onto the target. Frees `f` whatever happens;
 * on failure the target is untouched and the temporary file is gone. */
int tr_outfile_commit(tr_outfile *f, tr_error *err);

/* Removes the temporary file and frees `f` (NULL is fine). The target is untouched. */
void tr_outfile_abort(tr_outfile *f);

/* `len` bytes of `data` as the whole of `path`, through a temporary file as above: the
 * target holds all of them or is untouched. TR_OK or TR_ERR with `err` set. */
int tr_outfile_write(const char *path, const void *data, size_t len, tr_error *err);

/* Unlinks the temporary file of every tr_outfile still open, from any thread. Safe to call
 * from a signal handler (it calls unlink() alone); the streams stay open and a later
 * commit of one of them fails. */
void tr_outfile_cleanup_all(void);

#endif /* TRAC0R_OUTFILE_H */
