/* test_outfile.c - the write path every output file takes (outfile.h) and the read path
 * for inputs (util/infile.h): modes from the umask or the replaced file, non-regular
 * targets and inputs refused before any work, full files (RLIMIT_FSIZE) failing the
 * commit with the temporary file gone, tr_outfile_cleanup_all() removing every open
 * temporary file, and the declared-size check of model headers (mesh_guard.h). Where the
 * file system has O_TMPFILE, a file being written has no name until its commit, so even
 * SIGKILL leaves nothing behind; a read-only target is refused as open(2) would refuse it;
 * two outputs naming one file are refused before any work. */
#define _GNU_SOURCE /* O_TMPFILE, to tell whether the file system has it */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "check.h"
#include "util/infile.h"
#include "scene/mesh_guard.h"
#include "trac0r/outfile.h"

static char dir[256];

/* Entries of the scratch directory other than . and .. */
static int entries(void) {
    DIR *d = opendir(dir);
    int n = 0;
    for (struct dirent *e; d && (e = readdir(d));) {
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    }
    if (d) {
        closedir(d);
    }
    return n;
}

static int write_file(const char *path, const char *text, tr_error *err) {
    tr_outfile *f = tr_outfile_create(path, err);
    if (!f) {
        return TR_ERR;
    }
    fputs(text, tr_outfile_stream(f));
    return tr_outfile_commit(f, err);
}

static unsigned mode_of(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 ? (unsigned)(st.st_mode & 07777) : 0u;
}

static void test_modes(void) {
    char p[512];
    tr_error err;
    snprintf(p, sizeof p, "%s/new.txt", dir);
    mode_t old = umask(0022);
    CHECK(write_file(p, "a", &err) == TR_OK, "write: %s", err.msg);
    CHECK(mode_of(p) == 0644, "new file under umask 022: mode %o, expected 644", mode_of(p));
    umask(0002);
    unlink(p);
    CHECK(write_file(p, "a", &err) == TR_OK, "write: %s", err.msg);
    CHECK(mode_of(p) == 0664, "new file under umask 002: mode %o, expected 664", mode_of(p));
    /* Replacing keeps the target's mode, as fopen(path, "w") would. */
    chmod(p, 0640);
    umask(0077);
    CHECK(write_file(p, "b", &err) == TR_OK, "rewrite: %s", err.msg);
    CHECK(mode_of(p) == 0640, "replaced file: mode %o, expected 640", mode_of(p));
    umask(old);
    unlink(p);
}

static void test_targets(void) {
    char p[512];
    tr_error err;
    snprintf(p, sizeof p, "%s/sub.png", dir);
    mkdir(p, 0755);
    CHECK_STATUS(tr_outfile_check(p, &err), err, TR_STATUS_IO, "directory target");
    CHECK(tr_outfile_create(p, &err) == NULL, "a directory target was opened");
    CHECK(entries() == 1, "a refused target left %d entries", entries());
    rmdir(p);
    snprintf(p, sizeof p, "%s/fifo", dir);
    CHECK(mkfifo(p, 0644) == 0, "mkfifo: %s", strerror(errno));
    CHECK_STATUS(tr_outfile_check(p, &err), err, TR_STATUS_IO, "FIFO target");
    /* Reading a FIFO would block until a writer came: refused at once. */
    CHECK(tr_infile_open(p, NULL, &err) == NULL, "a FIFO was opened for reading");
    CHECK_STATUS(tr_infile_check(p, &err), err, TR_STATUS_IO, "FIFO input");
    unlink(p);
    CHECK_STATUS(tr_infile_check(dir, &err), err, TR_STATUS_IO, "directory input");
    CHECK_STATUS(tr_outfile_check("/dev/null", &err), err, TR_STATUS_IO, "device target");
}

/* A write beyond RLIMIT_FSIZE fails with EFBIG (SIGXFSZ ignored, as the CLI does): the
 * commit fails, the target is untouched and no temporary file stays. In a child, so
 * that the limit does not outlive it. */
static void test_full(void) {
    pid_t pid = fork();
    if (pid == 0) {
        signal(SIGXFSZ, SIG_IGN);
        struct rlimit rl = {4096, 4096};
        setrlimit(RLIMIT_FSIZE, &rl);
        char p[512];
        snprintf(p, sizeof p, "%s/big.bin", dir);
        tr_error err;
        tr_outfile *f = tr_outfile_create(p, &err);
        if (!f) {
            _exit(10);
        }
        static char block[65536];
        fwrite(block, 1, sizeof block, tr_outfile_stream(f));
        int rc = tr_outfile_commit(f, &err);
        _exit(rc == TR_ERR && err.code == TR_STATUS_IO ? 0 : 11);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0, "full file: child status %d", status);
    CHECK(entries() == 0, "a failed commit left %d entries", entries());
}

/* tr_outfile_cleanup_all() from a signal handler: the temporary files of open outfiles
 * go, and the process dies of the signal as it would have. */
static void on_term(int sig) {
    tr_outfile_cleanup_all();
    signal(sig, SIG_DFL);
    raise(sig);
}

/* Whether the scratch directory's file system creates unnamed files (O_TMPFILE). */
static int have_tmpfile(void) {
#ifdef O_TMPFILE
    const int fd = open(dir, O_TMPFILE | O_WRONLY | O_CLOEXEC, 0600);
    if (fd >= 0) {
        close(fd);
        return 1;
    }
#endif
    return 0;
}

static void test_cleanup(void) {
    int ready[2];
    CHECK(pipe(ready) == 0, "pipe");
    pid_t pid = fork();
    if (pid == 0) {
        signal(SIGTERM, on_term);
        tr_error err;
        for (int i = 0; i < 3; ++i) {
            char p[512];
            snprintf(p, sizeof p, "%s/open%d.pfm", dir, i);
            tr_outfile *f = tr_outfile_create(p, &err);
            if (!f) {
                _exit(10);
            }
            fputs("partial", tr_outfile_stream(f));
            fflush(tr_outfile_stream(f));
        }
        char c = 'x';
        if (write(ready[1], &c, 1) != 1) {
            _exit(11);
        }
        for (;;) {
            pause();
        }
    }
    close(ready[1]);
    char c;
    CHECK(read(ready[0], &c, 1) == 1, "the child did not get ready");
    close(ready[0]);
    const int named = have_tmpfile() ? 0 : 3;
    CHECK(entries() == named, "%d temporary files before the signal, expected %d", entries(),
          named);
    kill(pid, SIGTERM);
    int status = 0;
    waitpid(pid, &status, 0);
    CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM, "child status %d", status);
    CHECK(entries() == 0, "%d files left after SIGTERM", entries());
}

/* SIGKILL runs no handler: with O_TMPFILE the files being written have no name, so none
 * is left; the target written before stays as it was. */
static void test_kill(void) {
    if (!have_tmpfile()) {
        printf("test_outfile: no O_TMPFILE on this file system, SIGKILL check skipped\n");
        return;
    }
    char p[512];
    tr_error err;
    snprintf(p, sizeof p, "%s/kept.pfm", dir);
    CHECK(write_file(p, "old", &err) == TR_OK, "write: %s", err.msg);
    int ready[2];
    CHECK(pipe(ready) == 0, "pipe");
    pid_t pid = fork();
    if (pid == 0) {
        tr_outfile *f = tr_outfile_create(p, &err);
        if (!f) {
            _exit(10);
        }
        fputs("partial", tr_outfile_stream(f));
        fflush(tr_outfile_stream(f));
        char c = 'x';
        if (write(ready[1], &c, 1) != 1) {
            _exit(11);
        }
        for (;;) {
            pause();
        }
    }
    close(ready[1]);
    char c;
    CHECK(read(ready[0], &c, 1) == 1, "the child did not get ready");
    close(ready[0]);
    kill(pid, SIGKILL);
    int status = 0;
    waitpid(pid, &status, 0);
    CHECK(entries() == 1, "%d entries after SIGKILL, expected the target alone", entries());
    FILE *fp = fopen(p, "rb");
    char got[8] = {0};
    CHECK(fp && fread(got, 1, sizeof got, fp) == 3 && memcmp(got, "old", 3) == 0,
          "the target changed under a killed writer");
    if (fp) {
        fclose(fp);
    }
    unlink(p);
}

/* A target open(2) would not write (no write permission for this user) is refused, not
 * replaced through rename(); root may write anything, as open lets it. Two outputs that
 * name one file, by the same path or another, are refused. */
static void test_permission_and_distinct(void) {
    char p[512], q[512], r[512];
    tr_error err;
    snprintf(p, sizeof p, "%s/ro.png", dir);
    CHECK(write_file(p, "old", &err) == TR_OK, "write: %s", err.msg);
    chmod(p, 0444);
    if (geteuid() != 0) {
        CHECK_STATUS(tr_outfile_check(p, &err), err, TR_STATUS_IO, "a read-only target");
        CHECK(tr_outfile_create(p, &err) == NULL, "a read-only target was opened");
    } else {
        /* As root (CI runs so), the same as another user: a child process that becomes
         * `nobody` meets root's 0444 file in a directory it may write to, where rename()
         * could replace what open() refuses. */
        chmod(dir, 0777);
        const pid_t pid = fork();
        if (pid == 0) {
            if (setgid(65534) != 0 || setuid(65534) != 0) {
                _exit(3);
            }
            tr_error e;
            /* It can read the file (0444): the refusal is for writing, not for reaching it. */
            const int refused = access(p, R_OK) == 0 && tr_outfile_check(p, &e) == TR_ERR &&
                                e.code == TR_STATUS_IO && tr_outfile_create(p, &e) == NULL;
            _exit(refused ? 0 : 1);
        }
        int status = -1;
        CHECK(pid > 0 && waitpid(pid, &status, 0) == pid && WIFEXITED(status) &&
                  WEXITSTATUS(status) == 0,
              "another user's read-only target: child status %d", status);
        chmod(dir, 0700);
        char got[8] = {0};
        FILE *fp = fopen(p, "rb");
        CHECK(fp && fread(got, 1, sizeof got, fp) == 3 && memcmp(got, "old", 3) == 0,
              "another user's read-only target was replaced");
        if (fp) {
            fclose(fp);
        }
    }
    chmod(p, 0644);
    snprintf(q, sizeof q, "%s/./ro.png", dir);
    snprintf(r, sizeof r, "%s/other.png", dir);
    const char *same[3] = {p, NULL, q};
    CHECK_STATUS(tr_outfile_check_distinct(same, 3, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "one file by two paths");
    const char *twice[2] = {r, r};
    CHECK_STATUS(tr_outfile_check_distinct(twice, 2, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "one new file twice");
    const char *apart[3] = {p, r, NULL};
    CHECK(tr_outfile_check_distinct(apart, 3, &err) == TR_OK, "two files refused: %s", err.msg);
    unlink(p);
}

static void test_declared_sizes(void) {
    tr_error err;
    /* A 50-byte GLB whose JSON chunk claims 4 GB. */
    unsigned char glb[50] = {'g', 'l', 'T', 'F', 2, 0,    0,   0,   50,  0,
                             0,   0,   0,   0,   0, 0xf0, 'J', 'S', 'O', 'N'};
    CHECK_STATUS(tr_mesh_check_declared_sizes("a.glb", glb, sizeof glb, sizeof glb, &err), err,
                 TR_STATUS_LIMIT, "GLB chunk beyond the file");
    glb[12] = 30;
    glb[15] = 0;
    CHECK(tr_mesh_check_declared_sizes("a.glb", glb, sizeof glb, sizeof glb, &err) == TR_OK,
          "a consistent GLB header was refused: %s", err.msg);
    const char ply_big[] = "ply\nformat ascii 1.0\nelement vertex 100000000\nproperty float x\n"
                           "end_header\n0\n";
    CHECK_STATUS(tr_mesh_check_declared_sizes("a.ply", (const unsigned char *)ply_big,
                                              strlen(ply_big), strlen(ply_big), &err),
                 err, TR_STATUS_LIMIT, "PLY count beyond the file");
    /* Three vertices of three ASCII properties need at least 18 bytes after the header. */
    const char ply_ok[] = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                          "property float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    CHECK(tr_mesh_check_declared_sizes("a.ply", (const unsigned char *)ply_ok, strlen(ply_ok),
                                       strlen(ply_ok), &err) == TR_OK,
          "a consistent PLY was refused: %s", err.msg);
    CHECK_STATUS(tr_mesh_check_declared_sizes("a.ply", (const unsigned char *)ply_ok,
                                              strlen(ply_ok), strlen(ply_ok) - 10, &err),
                 err, TR_STATUS_LIMIT, "PLY data shorter than its counts");
}

int main(void) {
    snprintf(dir, sizeof dir, "%s/trac0r-test-outfile-XXXXXX",
             getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    test_modes();
    test_targets();
    test_full();
    test_cleanup();
    test_kill();
    test_permission_and_distinct();
    test_declared_sizes();
    rmdir(dir);
    return check_finish("test_outfile");
}
