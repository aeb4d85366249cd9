/* bench_plot.c - the benchmarks' plots: gnuplot run with no shell, and no path in its
 * script. gnuplot reads the script on its standard input and, with `set output` and no
 * file name, writes the PNG to its standard output, which is read back here and written
 * through tr_outfile like every other file. So an output prefix with an apostrophe or
 * `system(...)` in it is never gnuplot code, and a full disk is caught by the same checks
 * as for images. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdarg.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench.h"
#include "trac0r/outfile.h"

extern char **environ;

/* Feeds `in` to gnuplot's stdin and copies its stdout to `out` at the same time, so that
 * neither pipe can fill while the other side waits. 0 on success, else an errno value
 * (EPIPE: gnuplot stopped reading, i.e. it failed). */
static int pump(int to, int from, const char *in, size_t n, FILE *out) {
    size_t sent = 0;
    char buf[65536];
    int rc = 0;
    for (;;) {
        struct pollfd p[2] = {{from, POLLIN, 0}, {to, POLLOUT, 0}};
        nfds_t np = to >= 0 ? 2 : 1;
        if (poll(p, np, -1) < 0) {
            if (errno == EINTR) {
                continue;
            }
            return errno;
        }
        if (to >= 0 && (p[1].revents & (POLLOUT | POLLERR | POLLHUP))) {
            ssize_t w = write(to, in + sent, n - sent);
            if (w < 0 && errno != EAGAIN && errno != EINTR) {
                rc = errno;
                close(to);
                to = -1;
            } else if (w > 0) {
                sent += (size_t)w;
            }
            if (to >= 0 && sent == n) {
                close(to); /* end of script: gnuplot finishes the plot and exits */
                to = -1;
            }
        }
        if (p[0].revents & (POLLIN | POLLHUP | POLLERR)) {
            ssize_t r = read(from, buf, sizeof buf);
            if (r < 0 && errno == EINTR) {
                continue;
            }
            if (r <= 0) {
                if (to >= 0) {
                    close(to);
                }
                return r < 0 ? errno : rc;
            }
            if (fwrite(buf, 1, (size_t)r, out) != (size_t)r) {
                /* Keep draining so that gnuplot is not left blocked on a full pipe. */
                rc = rc ? rc : (errno ? errno : EIO);
            }
        }
    }
}

int bench_plot_png(const char *script, const char *png, tr_error *err) {
    static const char head[] = "set terminal pngcairo size 900,600 noenhanced\nset output\n";
    size_t n = strlen(head) + strlen(script) + 2;
    char *text = malloc(n);
    if (!text) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%.200s: out of memory", png);
        return -1;
    }
    snprintf(text, n, "%s%s\n", head, script);
    tr_outfile *f = tr_outfile_create(png, err);
    if (!f) {
        free(text);
        return -1;
    }
    int in[2] = {-1, -1}, out[2] = {-1, -1};
    posix_spawn_file_actions_t fa;
    int ready = pipe(in) == 0 && pipe(out) == 0 && posix_spawn_file_actions_init(&fa) == 0;
    pid_t pid = -1;
    int spawned = 0;
    if (ready) {
        posix_spawn_file_actions_adddup2(&fa, in[0], 0);
        posix_spawn_file_actions_adddup2(&fa, out[1], 1);
        posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
        posix_spawn_file_actions_addclose(&fa, in[1]);
        posix_spawn_file_actions_addclose(&fa, out[0]);
        char *argv[] = {"gnuplot", NULL};
        spawned = posix_spawnp(&pid, "gnuplot", &fa, NULL, argv, environ) == 0;
        posix_spawn_file_actions_destroy(&fa);
    }
    if (in[0] >= 0) {
        close(in[0]);
    }
    if (out[1] >= 0) {
        close(out[1]);
    }
    int copy_error = 0, status = -1;
    if (spawned) {
        /* gnuplot dying early must fail the plot, not kill the benchmark with SIGPIPE. */
        struct sigaction ign, old;
        memset(&ign, 0, sizeof ign);
        ign.sa_handler = SIG_IGN;
        sigaction(SIGPIPE, &ign, &old);
        fcntl(in[1], F_SETFL, fcntl(in[1], F_GETFL) | O_NONBLOCK);
        copy_error = pump(in[1], out[0], text, strlen(text), tr_outfile_stream(f));
        sigaction(SIGPIPE, &old, NULL);
        while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
        }
    } else if (in[1] >= 0) {
        close(in[1]);
    }
    if (out[0] >= 0) {
        close(out[0]);
    }
    free(text);
    const int gnuplot_ok =
        spawned && WIFEXITED(status) && WEXITSTATUS(status) == 0 && ftell(tr_outfile_stream(f)) > 0;
    if (copy_error && copy_error != EPIPE && gnuplot_ok) {
        /* gnuplot did its part; writing the file here did not. */
        tr_outfile_abort(f);
        tr_error_set(err, TR_STATUS_IO, "%.200s: write failed: %s", png, strerror(copy_error));
        return -1;
    }
    if (!gnuplot_ok || copy_error) {
        tr_outfile_abort(f);
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
