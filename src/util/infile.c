/* infile.c - regular files only, opened without ever blocking. */
#define _POSIX_C_SOURCE 200809L
#include "util/infile.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *kind(mode_t m) {
    return S_ISDIR(m)    ? "a directory"
           : S_ISFIFO(m) ? "a FIFO"
           : S_ISSOCK(m) ? "a socket"
           : S_ISCHR(m)  ? "a character device"
           : S_ISBLK(m)  ? "a block device"
                         : "an unknown kind of file";
}

FILE *tr_infile_open(const char *path, uint64_t *size, tr_error *err) {
    /* O_NONBLOCK: opening a FIFO for reading blocks until a writer appears; with it the
     * open returns at once and fstat() tells what the file is. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) {
        int e = errno;
        tr_error_set(err, tr_status_from_errno(e), "%.200s: cannot open: %s", path, strerror(e));
        return NULL;
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        tr_error_set(err, tr_status_from_errno(e), "%.200s: cannot open: %s", path, strerror(e));
        return NULL;
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        tr_error_set(err, TR_STATUS_IO, "%.200s: cannot open: not a regular file (%s)", path,
                     kind(st.st_mode));
        return NULL;
    }
    /* Reads from a regular file never block; the flag is dropped all the same so that
     * the stream behaves as fopen()'s would. */
    fcntl(fd, F_SETFL, fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    FILE *fp = fdopen(fd, "rb");
    if (!fp) {
        int e = errno;
        close(fd);
        tr_error_set(err, tr_status_from_errno(e), "%.200s: cannot open: %s", path, strerror(e));
        return NULL;
    }
    if (size) {
        *size = (uint64_t)st.st_size;
    }
    return fp;
}

int tr_infile_check(const char *path, tr_error *err) {
    FILE *fp = tr_infile_open(path, NULL, err);
    if (!fp) {
        return TR_ERR;
    }
    fclose(fp);
    return TR_OK;
}
