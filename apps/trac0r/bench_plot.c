/* bench_plot.c - the benchmarks' plots: gnuplot run with no shell, and no path in its
 * script. The script goes to a temporary file of our own naming, which gnuplot is given as
 * its argument; with `set output` and no file name it writes the PNG to its standard
 * output, which is read back here and written through tr_outfile like every other file.
 * So an output prefix with an apostrophe or `system(...)` in it is never gnuplot code, and
 * a full disk is caught by the same checks as for images. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench.h"
#include "trac0r/outfile.h"

extern char **environ;

int bench_plot_png(const char *script, const char *png, tr_error *err) {
    const char *tmp = getenv("TMPDIR");
    char spath[4096];
    snprintf(spath, sizeof spath, "%s/trac0r-plot-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    const int sfd = mkstemp(spath);
    const char head[] = "set terminal pngcairo size 900,600 noenhanced\nset output\n";
    const int ready = sfd >= 0 && write(sfd, head, strlen(head)) == (ssize_t)strlen(head) &&
                      write(sfd, script, strlen(script)) == (ssize_t)strlen(script);
    tr_outfile *f = ready ? tr_outfile_create(png, err) : NULL;
    int out[2] = {-1, -1}, status = -1, spawned = 0, copy_error = 0;
    posix_spawn_file_actions_t fa;
    pid_t pid;
    if (f && pipe(out) == 0 && posix_spawn_file_actions_init(&fa) == 0) {
        posix_spawn_file_actions_adddup2(&fa, out[1], 1);
        posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
        posix_spawn_file_actions_addclose(&fa, out[0]);
        char *argv[] = {"gnuplot", spath, NULL};
        spawned = posix_spawnp(&pid, "gnuplot", &fa, NULL, argv, environ) == 0;
        posix_spawn_file_actions_destroy(&fa);
    }
    if (out[1] >= 0) {
        close(out[1]);
    }
    /* The script comes from a file, so one pipe is read to its end: no deadlock. A failed
     * write keeps draining, so that gnuplot is not left blocked on a full pipe. */
    char buf[65536];
    ssize_t got;
    while (spawned && ((got = read(out[0], buf, sizeof buf)) > 0 || (got < 0 && errno == EINTR))) {
        if (got > 0 && fwrite(buf, 1, (size_t)got, tr_outfile_stream(f)) != (size_t)got) {
            copy_error = copy_error ? copy_error : (errno ? errno : EIO);
        }
    }
    while (spawned && waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    if (out[0] >= 0) {
        close(out[0]);
    }
    if (sfd >= 0) {
        close(sfd);
        unlink(spath);
    }
    const int gnuplot_ok =
        spawned && WIFEXITED(status) && WEXITSTATUS(status) == 0 && ftell(tr_outfile_stream(f)) > 0;
    if (f && copy_error && gnuplot_ok) { /* gnuplot did its part; writing the file did not */
        tr_outfile_abort(f);
        tr_error_set(err, TR_STATUS_IO, "%.200s: write failed: %s", png, strerror(copy_error));
        return -1;
    }
    if (!gnuplot_ok || copy_error) {
        if (f) {
            tr_outfile_abort(f);
        }
        return ready && !f ? -1 : 0;
    }
    return tr_outfile_commit(f, err) == TR_OK ? 1 : -1;
}

void bench_plot_name(const char *path, char *out, size_t n) {
    const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    size_t k = 0;
    for (; base[k] && k + 1 < n; ++k) {
        const char ch = base[k];
        out[k] = (ch >= ' ' && ch <= '~' && ch != '\'' && ch != '\\') ? ch : '_';
    }
    out[k] = '\0';
}

void bench_plot_put(char *buf, size_t cap, size_t *len, const char *fmt, ...) {
    if (*len >= cap) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    const int n = vsnprintf(buf + *len, cap - *len, fmt, ap);
    va_end(ap);
    *len = n < 0 || (size_t)n >= cap - *len ? cap : *len + (size_t)n;
}
