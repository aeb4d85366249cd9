/* error.h - how libtrac0r reports failure.
 *
 * Every fallible function returns TR_OK (0) or TR_ERR (-1) and, on failure, writes a
 * one-line, human-readable reason into the caller's tr_error (which may be NULL).
 * The library never prints and never exits. */
#ifndef TRAC0R_ERROR_H
#define TRAC0R_ERROR_H

#define TR_OK 0
#define TR_ERR (-1)

typedef struct tr_error {
    char msg[512];
} tr_error;

/* Formats a message into err (if non-NULL) and returns TR_ERR. */
int tr_error_set(tr_error *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

#endif
