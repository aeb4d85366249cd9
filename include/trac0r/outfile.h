/* outfile.h - every file trac0r writes, written whole or not at all.
 *
 * A writer opens a temporary file next to the target (PATH.tmp.XXXXXX, so the final
 * rename() stays on one file system), writes through the stream, and commits: the stream
 * is flushed and closed with every error checked, and only then renamed onto PATH. Any
 * failure, or an abort, removes the temporary file. Images, CSV files, plot scripts,
 * checkpoints and the viewer's state file all go through here, so there is one place
 * where file modes, signals and full disks are handled. */
#ifndef TRAC0R_OUTFILE_H
#define TRAC0R_OUTFILE_H

#include <stdio.h>

#include "trac0r/error.h"

typedef struct tr_outfile tr_outfile;

/* Creates the temporary file for `path`. NULL (with `err` set) on failure. */
tr_outfile *tr_outfile_open(const char *path, tr_error *err);

/* The stream to write to (binary mode), and the temporary file's name (for libraries that
 * want a file name or descriptor of their own). */
FILE *tr_outfile_stream(tr_outfile *f);
const char *tr_outfile_temp_path(const tr_outfile *f);

/* Finishes the file: flush, close and rename onto the target. Frees `f` whatever happens;
 * on failure the target is untouched and the temporary file is gone. */
int tr_outfile_commit(tr_outfile *f, tr_error *err);

/* Removes the temporary file and frees `f` (NULL is fine). The target is untouched. */
void tr_outfile_abort(tr_outfile *f);

#endif /* TRAC0R_OUTFILE_H */
