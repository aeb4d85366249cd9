/* outfile.c - the write-temporary-then-rename path every output file takes. */
#define _GNU_SOURCE /* O_TMPFILE (Linux); the rest is POSIX */
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "trac0r/outfile.h"

/* The temporary files a signal handler may have to remove. A handler can take no lock and
 * must not follow a pointer another thread may free, so the names are copied into fixed
 * slots whose state is one lock-free atomic each: a slot's name is only read while its
 * state is LIVE. More open files than slots still work; those beyond are not cleaned up
 * on a signal. */
#define SLOTS 64
#define SLOT_NAME 4096
enum { SLOT_FREE, SLOT_BUSY, SLOT_LIVE };
static atomic_int slot_state[SLOTS];
static char slot_name[SLOTS][SLOT_NAME];

struct tr_outfile {
    FILE *fp;
    int slot;      /* -1: untracked */
    int unnamed;   /* O_TMPFILE: no name until the commit links one */
    char proc[40]; /* /proc/self/fd/N of an unnamed file */
    char *path;    /* the target */
    char tmp[];    /* PATH.tmp.XXXXXX */
};

static int slot_claim(const char *tmp) {
    size_t n = strlen(tmp);
    if (n >= SLOT_NAME) {
        return -1;
    }
    for (int i = 0; i < SLOTS; ++i) {
        int expected = SLOT_FREE;
        if (atomic_compare_exchange_strong(&slot_state[i], &expected, SLOT_BUSY)) {
            memcpy(slot_name[i], tmp, n + 1);
            atomic_store(&slot_state[i], SLOT_LIVE);
            return i;
        }
    }
    return -1;
}

static void slot_release(int i) {
    if (i >= 0) {
        atomic_store(&slot_state[i], SLOT_FREE);
    }
}

void tr_outfile_cleanup_all(void) {
    for (int i = 0; i < SLOTS; ++i) {
        if (atomic_load(&slot_state[i]) == SLOT_LIVE) {
            unlink(slot_name[i]);
        }
    }
}

/* Signals are held off while a temporary file comes into being or goes, so that a
 * handler never sees a file that exists but is not yet (or no longer) in a slot. */
static void block_signals(sigset_t *old) {
    sigset_t all;
    sigfillset(&all);
    pthread_sigmask(SIG_BLOCK, &all, old);
}

static void restore_signals(const sigset_t *old) {
    pthread_sigmask(SIG_SETMASK, old, NULL);
}

/* Fills the six X's at the end of `tmp` with letters and digits. mkstemp() is not used:
 * it creates the file 0600 whatever the umask, and the mode it should get is the one
 * open(2) derives from 0666 and the umask (reading the umask is not thread-safe). */
static void fill_suffix(char *x, uint64_t *state) {
    static const char abc[] = "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789";
    for (int i = 0; i < 6; ++i) {
        /* splitmix64 step (Steele, Lea and Flood, "Fast splittable pseudorandom number
         * generators", OOPSLA 2014): names need to differ, not to be secret - O_EXCL is
         * what makes the creation safe. */
        uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        z ^= z >> 31;
        x[i] = abc[z % (sizeof abc - 1)];
    }
}

static uint64_t suffix_seed(void) {
    static atomic_uint_fast64_t counter;
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (uint64_t)ts.tv_nsec ^ ((uint64_t)ts.tv_sec << 30) ^ ((uint64_t)getpid() << 16) ^
           atomic_fetch_add(&counter, 1) * 0x2545f491ull;
}

/* An unnamed file in the target's directory (Linux's O_TMPFILE), given a name by linkat()
 * through /proc/self/fd at the commit: a process killed while writing (SIGKILL, the OOM
 * killer) leaves nothing behind. -1 where the file system or the system has no such
 * files (the caller then makes a named one); errno says why for any other failure. */
static int create_unnamed(tr_outfile *f, mode_t keep_mode, int keep) {
#ifdef O_TMPFILE
    if (access("/proc/self/fd", X_OK) != 0) {
        return -1; /* no /proc: the commit could not link the file */
    }
    const char *slash = strrchr(f->path, '/');
    char *dir = NULL;
    if (slash) {
        const size_t n = slash == f->path ? 1 : (size_t)(slash - f->path);
        dir = malloc(n + 1);
        if (!dir) {
            return -1;
        }
        memcpy(dir, f->path, n);
        dir[n] = '\0';
    }
    const int fd = open(dir ? dir : ".", O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
    free(dir);
    if (fd < 0) {
        return -1;
    }
    if (keep && fchmod(fd, keep_mode) != 0) {
        const int e = errno;
        close(fd);
        errno = e;
        return -2;
    }
    f->unnamed = 1;
    snprintf(f->proc, sizeof f->proc, "/proc/self/fd/%d", fd);
    return fd;
#else
    (void)f;
    (void)keep_mode;
    (void)keep;
    return -1;
#endif
}

static int create_temp(tr_outfile *f, mode_t keep_mode, int keep) {
    const int u = create_unnamed(f, keep_mode, keep);
    if (u >= 0 || u == -2) {
        return u >= 0 ? u : -1;
    }
    uint64_t state = suffix_seed();
    char *x = f->tmp + strlen(f->tmp) - 6;
    for (int attempt = 0; attempt < 100; ++attempt) {
        fill_suffix(x, &state);
        sigset_t old;
        block_signals(&old);
        int fd = open(f->tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        int e = errno;
        if (fd >= 0) {
            f->slot = slot_claim(f->tmp);
        }
        restore_signals(&old);
        if (fd >= 0) {
            if (keep && fchmod(fd, keep_mode) != 0) {
                e = errno;
                close(fd);
                unlink(f->tmp);
                slot_release(f->slot);
                errno = e;
                return -1;
            }
            return fd;
        }
        if (e != EEXIST) {
            errno = e;
            return -1;
        }
    }
    errno = EEXIST;
    return -1;
}

static const char *type_name(mode_t m) {
    return S_ISDIR(m)    ? "a directory"
           : S_ISFIFO(m) ? "a FIFO"
           : S_ISSOCK(m) ? "a socket"
           : S_ISCHR(m)  ? "a character device"
           : S_ISBLK(m)  ? "a block device"
                         : "not a regular file";
}

tr_outfile *tr_outfile_create(const char *path, tr_error *err) {
    size_t n = strlen(path);
    if (n == 0) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "empty output path");
        return NULL;
    }
    /* The target's type first: rename() onto a directory fails only at the end, and onto
     * a device or FIFO it would replace the node itself. */
    struct stat st;
    int exists = stat(path, &st) == 0;
    if (exists && !S_ISREG(st.st_mode)) {
        tr_error_set(err, TR_STATUS_IO, "%.200s: cannot write: it is %s", path,
                     type_name(st.st_mode));
        return NULL;
    }
    /* The target's permission, as open(path, O_WRONLY) would judge it: rename() needs only
     * the directory's, and would replace a file this user may not write. */
    if (exists && faccessat(AT_FDCWD, path, W_OK, AT_EACCESS) != 0) {
        const int e = errno;
        tr_error_set(err, e == ENOENT ? TR_STATUS_NOT_FOUND : TR_STATUS_IO,
                     "%.200s: cannot write: %s", path, strerror(e));
        return NULL;
    }
    static const char suffix[] = ".tmp.XXXXXX";
    tr_outfile *f = malloc(sizeof *f + 2 * (n + 1) + sizeof suffix);
    if (!f) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%.200s: out of memory", path);
        return NULL;
    }
    memcpy(f->tmp, path, n);
    memcpy(f->tmp + n, suffix, sizeof suffix);
    f->path = f->tmp + n + sizeof suffix;
    memcpy(f->path, path, n + 1);
    f->slot = -1;
    f->unnamed = 0;
    f->proc[0] = '\0';
    int fd = create_temp(f, exists ? (st.st_mode & 0777) : 0, exists);
    if (fd < 0) {
        int e = errno;
        tr_error_set(err, tr_status_from_errno(e), "%.200s: cannot create file: %s", path,
                     strerror(e));
        free(f);
        return NULL;
    }
    f->fp = fdopen(fd, "wb");
    if (!f->fp) {
        int e = errno;
        close(fd);
        if (!f->unnamed) {
            unlink(f->tmp);
        }
        slot_release(f->slot);
        tr_error_set(err, tr_status_from_errno(e), "%.200s: cannot open file: %s", path,
                     strerror(e));
        free(f);
        return NULL;
    }
    return f;
}

int tr_outfile_check(const char *path, tr_error *err) {
    tr_outfile *t = tr_outfile_create(path, err);
    if (!t) {
        return TR_ERR;
    }
    tr_outfile_abort(t);
    return TR_OK;
}

int tr_outfile_write(const char *path, const void *data, size_t len, tr_error *err) {
    tr_outfile *f = tr_outfile_create(path, err);
    if (!f) {
        return TR_ERR;
    }
    fwrite(data, 1, len, tr_outfile_stream(f)); /* a short write fails the commit's flush */
    return tr_outfile_commit(f, err);
}

FILE *tr_outfile_stream(tr_outfile *f) {
    return f->fp;
}

const char *tr_outfile_temp_path(const tr_outfile *f) {
    return f->unnamed ? f->proc : f->tmp;
}

/* The commit of an unnamed file: flushed, linked under a free PATH.tmp.XXXXXX (linkat
 * cannot replace a file), closed, renamed onto the target. Signals are held off from the
 * link to the rename, so a handler never misses the name. */
static int commit_unnamed(tr_outfile *f, tr_error *err) {
    int rc = TR_OK;
    errno = 0;
    if (fflush(f->fp) != 0 || ferror(f->fp)) {
        const int e = errno ? errno : EIO;
        rc = tr_error_set(err, tr_status_from_errno(e), "%.200s: write failed: %s", f->path,
                          strerror(e));
    }
    sigset_t old;
    block_signals(&old);
    int linked = 0;
    if (rc == TR_OK) {
        uint64_t state = suffix_seed();
        char *x = f->tmp + strlen(f->tmp) - 6;
        int e = EEXIST;
        for (int attempt = 0; attempt < 100 && e == EEXIST; ++attempt) {
            fill_suffix(x, &state);
            e = linkat(AT_FDCWD, f->proc, AT_FDCWD, f->tmp, AT_SYMLINK_FOLLOW) == 0 ? 0 : errno;
        }
        linked = e == 0;
        if (!linked) {
            rc = tr_error_set(err, tr_status_from_errno(e), "%.200s: cannot name the file: %s",
                              f->path, strerror(e));
        }
    }
    if (fclose(f->fp) != 0 && rc == TR_OK) {
        rc = tr_error_set(err, tr_status_from_errno(errno), "%.200s: write failed: %s", f->path,
                          strerror(errno));
    }
    if (rc == TR_OK && rename(f->tmp, f->path) != 0) {
        const int e = errno;
        rc = tr_error_set(err, tr_status_from_errno(e),
                          "%.200s: cannot rename the finished file into place: %s", f->path,
                          strerror(e));
    }
    if (rc != TR_OK && linked) {
        unlink(f->tmp);
    }
    restore_signals(&old);
    free(f);
    return rc;
}

int tr_outfile_commit(tr_outfile *f, tr_error *err) {
    if (f->unnamed) {
        return commit_unnamed(f, err);
    }
    int rc = TR_OK;
    errno = 0;
    if (fflush(f->fp) != 0 || ferror(f->fp)) {
        int e = errno ? errno : EIO;
        rc = tr_error_set(err, tr_status_from_errno(e), "%.200s: write failed: %s", f->path,
                          strerror(e));
    }
    if (fclose(f->fp) != 0 && rc == TR_OK) {
        rc = tr_error_set(err, tr_status_from_errno(errno), "%.200s: write failed: %s", f->path,
                          strerror(errno));
    }
    sigset_t old;
    block_signals(&old);
    if (rc == TR_OK && rename(f->tmp, f->path) != 0) {
        int e = errno;
        rc = tr_error_set(err, tr_status_from_errno(e),
                          "%.200s: cannot rename the finished file into place: %s", f->path,
                          strerror(e));
    }
    if (rc != TR_OK) {
        unlink(f->tmp);
    }
    slot_release(f->slot);
    restore_signals(&old);
    free(f);
    return rc;
}

void tr_outfile_abort(tr_outfile *f) {
    if (!f) {
        return;
    }
    fclose(f->fp);
    if (f->unnamed) {
        free(f); /* the file had no name: closing it was the end of it */
        return;
    }
    sigset_t old;
    block_signals(&old);
    unlink(f->tmp);
    slot_release(f->slot);
    restore_signals(&old);
    free(f);
}

/* Two paths name one file when both exist and are one inode, or when neither need exist
 * and their directories are one and their last components equal. */
static int same_target(const char *a, const char *b) {
    struct stat sa, sb;
    if (strcmp(a, b) == 0) {
        return 1;
    }
    const int ea = stat(a, &sa) == 0, eb = stat(b, &sb) == 0;
    if (ea && eb) {
        return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    }
    if (ea != eb) {
        return 0;
    }
    const char *ba = strrchr(a, '/'), *bb = strrchr(b, '/');
    const char *na = ba ? ba + 1 : a, *nb = bb ? bb + 1 : b;
    if (strcmp(na, nb) != 0) {
        return 0;
    }
    char da[4096], db[4096];
    snprintf(da, sizeof da, "%.*s", ba ? (int)(ba - a) + 1 : 1, ba ? a : ".");
    snprintf(db, sizeof db, "%.*s", bb ? (int)(bb - b) + 1 : 1, bb ? b : ".");
    return stat(da, &sa) == 0 && stat(db, &sb) == 0 && sa.st_dev == sb.st_dev &&
           sa.st_ino == sb.st_ino;
}

int tr_outfile_check_distinct(const char *const *paths, int n, tr_error *err) {
    for (int i = 0; i < n; ++i) {
        for (int j = i + 1; j < n && paths[i]; ++j) {
            if (paths[j] && same_target(paths[i], paths[j])) {
                return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                                    "'%.200s' and '%.200s' name one file: one output would "
                                    "overwrite the other",
                                    paths[i], paths[j]);
            }
        }
    }
    return TR_OK;
}
