/* infile.h - opening the files trac0r reads (scene files, model files and the files they
 * name, images): regular files only. A FIFO named as a scene or model would block open()
 * or read() forever, and a device could be read without end, so the file is opened
 * without blocking and its type checked before a byte is read. Internal to the library. */
#ifndef TRAC0R_UTIL_INFILE_H
#define TRAC0R_UTIL_INFILE_H

#include <stdint.h>
#include <stdio.h>

#include "trac0r/error.h"

/* Opens `path` for reading ("rb") when it is a regular file, and gives its size (size may
 * be NULL). NULL with `err` set otherwise, the message always "PATH: cannot open: REASON"
 * (PATH cut at 200 bytes; REASON strerror's or "not a regular file (a FIFO)"). */
FILE *tr_infile_open(const char *path, uint64_t *size, tr_error *err);

/* The same check without opening: TR_OK when `path` is a regular file. */
int tr_infile_check(const char *path, tr_error *err);

#endif
