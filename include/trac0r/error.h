/* error.h - how libtrac0r reports failure.
 *
 * Every fallible function returns TR_OK (0) or TR_ERR (-1) and, on failure, fills the
 * caller's tr_error (which may be NULL) with two things:
 *   - code: a tr_status saying what kind of failure it was, for programs to branch on;
 *   - msg:  a one-line, human-readable reason (naming the file, value or limit at fault),
 *           for people. Its wording may change between versions; the codes do not.
 * Both are meaningful only after a call returned TR_ERR: success leaves err untouched.
 * The library never prints and never exits.
 *
 *     tr_error err;
 *     if (tr_scene_file_load(&scene, path, NULL, NULL, &err) != TR_OK) {
 *         fprintf(stderr, "%s\n", err.msg);
 *         return err.code == TR_STATUS_PARSE ? EXIT_USAGE : EXIT_FAILURE;
 *     }
 *
 * The header is plain C99 and also compiles as C++. */
#ifndef TRAC0R_ERROR_H
#define TRAC0R_ERROR_H

#define TR_OK 0
#define TR_ERR (-1)

/* What kind of failure a tr_error reports; docs/architecture.md ("Errors") lists which
 * calls give which code. New codes are only ever added at the end. */
typedef enum tr_status {
    /* No failure: a tr_error nobody has set. */
    TR_STATUS_OK = 0,
    /* A value outside its documented range: NaN, a zero size, an unknown enum value. */
    TR_STATUS_INVALID_ARGUMENT,
    /* A valid call at the wrong time: nothing uploaded or rendered yet. */
    TR_STATUS_INVALID_OPERATION,
    /* A host allocation failed. */
    TR_STATUS_OUT_OF_MEMORY,
    /* A size or budget beyond what trac0r or the device can hold. */
    TR_STATUS_LIMIT,
    /* What was named does not exist: a file, a device, a shape or material index, a scene name. */
    TR_STATUS_NOT_FOUND,
    /* A file exists but cannot be read, written or renamed. */
    TR_STATUS_IO,
    /* A file's content is wrong: scene-file syntax or meaning, an image header, a model. */
    TR_STATUS_PARSE,
    /* Not in this build or not handled: no Embree, no OpenCL, an image format. */
    TR_STATUS_UNSUPPORTED,
    /* The scene is not committed, or changed since its commit or upload: commit it again. */
    TR_STATUS_STALE_SCENE,
    /* The caller's cancel flag stopped the work. */
    TR_STATUS_CANCELLED,
    /* A device or driver call failed (OpenCL, Embree): a fault of the driver or the build. */
    TR_STATUS_DEVICE,
    /* Not a status: the number of codes above. */
    TR_STATUS_COUNT
} tr_status;

typedef struct tr_error {
    tr_status code; /* what kind of failure */
    char msg[512];  /* why, in one line with no trailing newline */
} tr_error;

#if defined(__GNUC__) || defined(__clang__)
#define TR_PRINTF_FORMAT(fmt_index, first_arg) __attribute__((format(printf, fmt_index, first_arg)))
#else
#define TR_PRINTF_FORMAT(fmt_index, first_arg)
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Sets err's code and formats its message (if err is non-NULL); returns TR_ERR. */
int tr_error_set(tr_error *err, tr_status code, const char *fmt, ...) TR_PRINTF_FORMAT(3, 4);

/* The code's name as written here ("TR_STATUS_IO"); "TR_STATUS_UNKNOWN" for no code. */
const char *tr_status_name(tr_status code);

/* The code for a failed file operation's errno: ENOENT and ENOTDIR are NOT_FOUND,
 * ENOMEM OUT_OF_MEMORY, ENAMETOOLONG INVALID_ARGUMENT, anything else IO. */
tr_status tr_status_from_errno(int errnum);

#ifdef __cplusplus
}
#endif

#endif
