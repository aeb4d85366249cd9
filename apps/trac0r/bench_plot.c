/* bench_plot.c - the benchmarks' plots: gnuplot run with no shell, and no path in its
 * script. The script goes to a temporary file of our own naming, which gnuplot is given as
 * its argument; with `set output` and no file name it writes the PNG to its standard
 * output, which is the tr_outfile of the plot. So an output prefix with an apostrophe or
 * `system(...)` in it is never gnuplot code, and the plot is written whole or not at all,
 * like every other file. */
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
    char path[4096];
    snprintf(path, sizeof path, "%s/trac0r-plot-XXXXXX", tmp && *tmp ? tmp : "/tmp");
    const int sfd = mkstemp(path);
    if (sfd < 0) {
        return 0; /* no place for the script: no plot */
    }
    FILE *sf = fdopen(sfd, "w");
    const int written = sf && fprintf(sf,
                                      "set terminal pngcairo size 900,600 noenhanced\n"
                                      "set output\n%s\n",
                                      script) > 0;
    const int closed = sf ? fclose(sf) == 0 : close(sfd) == 0;
    tr_outfile *f = written && closed ? tr_outfile_create(png, err) : NULL;
    int status = -1, spawned = 0;
    posix_spawn_file_actions_t fa;
    if (f && posix_spawn_file_actions_init(&fa) == 0) {
        posix_spawn_file_actions_adddup2(&fa, fileno(tr_outfile_stream(f)), 1);
        posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
        char *argv[] = {"gnuplot", path, NULL};
        pid_t pid;
        spawned = posix_spawnp(&pid, "gnuplot", &fa, NULL, argv, environ) == 0;
        posix_spawn_file_actions_destroy(&fa);
        while (spawned && waitpid(pid, &status, 0) < 0 && errno == EINTR) {
        }
    }
    unlink(path);
    if (!f) {
        return written && closed ? -1 : 0;
    }
    struct stat st;
    if (!spawned || !WIFEXITED(status) || WEXITSTATUS(status) != 0 ||
        fstat(fileno(tr_outfile_stream(f)), &st) != 0 || st.st_size == 0) {
        tr_outfile_abort(f); /* gnuplot missing or failed: no plot, nothing written */
        return 0;
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
