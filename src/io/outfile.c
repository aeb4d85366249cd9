/* outfile.c - the write-temporary-then-rename path every output file takes. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "trac0r/outfile.h"

struct tr_outfile {
    FILE *fp;
    char *path; /* the target */
    char tmp[]; /* PATH.tmp.XXXXXX */
};

tr_outfile *tr_outfile_open(const char *path, tr_error *err) {
    size_t n = strlen(path);
    if (n == 0) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "empty output path");
        return NULL;
    }
    static const char suffix[] = ".tmp.XXXXXX";
    tr_outfile *f = malloc(sizeof *f + 2 * (n + 1) + sizeof suffix);
    if (!f) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%s: out of memory", path);
        return NULL;
    }
    memcpy(f->tmp, path, n);
    memcpy(f->tmp + n, suffix, sizeof suffix);
    f->path = f->tmp + n + sizeof suffix;
    memcpy(f->path, path, n + 1);
    int fd = mkstemp(f->tmp);
    if (fd < 0) {
        tr_error_set(err, tr_status_from_errno(errno), "%s: cannot create file: %s", path,
                     strerror(errno));
        free(f);
        return NULL;
    }
    f->fp = fdopen(fd, "wb");
    if (!f->fp) {
        int e = errno;
        close(fd);
        unlink(f->tmp);
        tr_error_set(err, tr_status_from_errno(e), "%s: cannot open file: %s", path, strerror(e));
        free(f);
        return NULL;
    }
    return f;
}

FILE *tr_outfile_stream(tr_outfile *f) {
    return f->fp;
}

const char *tr_outfile_temp_path(const tr_outfile *f) {
    return f->tmp;
}

int tr_outfile_commit(tr_outfile *f, tr_error *err) {
    int rc = TR_OK;
    if (fflush(f->fp) != 0 || ferror(f->fp)) {
        rc = tr_error_set(err, tr_status_from_errno(errno), "%s: write failed: %s", f->path,
                          strerror(errno));
    }
    if (fclose(f->fp) != 0 && rc == TR_OK) {
        rc = tr_error_set(err, tr_status_from_errno(errno), "%s: write failed: %s", f->path,
                          strerror(errno));
    }
    if (rc == TR_OK && rename(f->tmp, f->path) != 0) {
        rc = tr_error_set(err, tr_status_from_errno(errno),
                          "%s: cannot rename the finished file into place: %s", f->path,
                          strerror(errno));
    }
    if (rc != TR_OK) {
        unlink(f->tmp);
    }
    free(f);
    return rc;
}

void tr_outfile_abort(tr_outfile *f) {
    if (!f) {
        return;
    }
    fclose(f->fp);
    unlink(f->tmp);
    free(f);
}
