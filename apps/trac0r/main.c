/* main.c - the trac0r command: dispatches to a subcommand. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"
#include "trac0r/outfile.h"

/* A signal that ends the program removes the temporary files of outputs being written
 * (the manual: nothing is ever left half-written), then ends it as the signal would have:
 * SA_RESETHAND restored the default action, so raising it again kills with the same
 * status the shell expects. A command may install its own handler over this one (render's
 * graceful first SIGINT) and call tr_outfile_cleanup_all() itself. */
static void die_on_signal(int sig) {
    tr_outfile_cleanup_all();
    raise(sig);
}

static void install_signal_handlers(void) {
    static const int fatal[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = die_on_signal;
    sa.sa_flags = SA_RESETHAND;
    sigemptyset(&sa.sa_mask);
    for (size_t i = 0; i < sizeof fatal / sizeof fatal[0]; ++i) {
        struct sigaction old;
        /* A signal the parent ignored (nohup, a background job's SIGINT) stays ignored. */
        if (sigaction(fatal[i], NULL, &old) == 0 && old.sa_handler != SIG_IGN) {
            sigaction(fatal[i], &sa, NULL);
        }
    }
    /* Past `ulimit -f` a write fails with EFBIG instead of killing the process: the writer
     * then reports "File too large", removes its temporary file and exits 1. */
    signal(SIGXFSZ, SIG_IGN);
}

static int dispatch(int argc, char **argv);

int main(int argc, char **argv) {
    install_signal_handlers();
    int rc = dispatch(argc, argv);
    /* Whatever a command printed must have arrived: `trac0r info > /dev/full` is a
     * failure, not a success with the output lost. */
    errno = 0;
    if (fflush(stdout) != 0 || ferror(stdout)) {
        int e = errno ? errno : EIO;
        fprintf(stderr, "trac0r: cannot write standard output: %s\n", strerror(e));
        return rc == CLI_OK ? CLI_FAILURE : rc;
    }
    return rc;
}

static void usage(FILE *fp) {
    fprintf(fp, "Usage: trac0r COMMAND [options]\n"
                "\n"
                "A physically based, real-time Monte Carlo path tracer.\n"
                "\n"
                "Commands:\n"
                "  render   render a scene to a PNG, PFM or EXR image\n"
                "  view     interactive window: fly through a scene while it converges\n"
                "  bench    measure: 'trac0r bench frame|complexity|rays|convergence|realtime'\n"
                "  compare  error metrics (RMSE, relMSE, PSNR) of an image against a reference\n"
                "  info     describe a scene: counts, bounds, warnings; --devices: OpenCL devices\n"
                "\n"
                "Run 'trac0r COMMAND --help' for a command's options.\n"
                "  -h, --help      show this help\n"
                "  --version       print the version\n");
}

static int dispatch(int argc, char **argv) {
    if (argc < 2) {
        usage(stderr);
        return CLI_USAGE;
    }
    const char *cmd = argv[1];
    if (strcmp(cmd, "render") == 0) {
        return cmd_render(argc - 1, argv + 1);
    }
    if (strcmp(cmd, "bench") == 0) {
        return cmd_bench(argc - 1, argv + 1);
    }
    if (strcmp(cmd, "compare") == 0) {
        return cmd_compare(argc - 1, argv + 1);
    }
    if (strcmp(cmd, "info") == 0) {
        return cmd_info(argc - 1, argv + 1);
    }
    if (strcmp(cmd, "view") == 0) {
#ifdef TRAC0R_HAVE_VIEW
        return cmd_view(argc - 1, argv + 1);
#else
        fprintf(stderr, "trac0r: this build has no 'view' (SDL2, SDL2_ttf or fontconfig was "
                        "not found when it was configured)\n");
        return CLI_USAGE;
#endif
    }
    if (strcmp(cmd, "-h") == 0 || strcmp(cmd, "--help") == 0 || strcmp(cmd, "help") == 0) {
        usage(stdout);
        return CLI_OK;
    }
    if (strcmp(cmd, "--version") == 0) {
        printf("trac0r %s\n", TRAC0R_VERSION);
        return CLI_OK;
    }
    fprintf(stderr,
            "trac0r: unknown command '%s' (expected render, view, bench, compare or info; "
            "see 'trac0r --help')\n",
            cmd);
    return CLI_USAGE;
}
