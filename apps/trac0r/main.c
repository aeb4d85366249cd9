/* main.c - the trac0r command: dispatches to a subcommand. */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "commands.h"

static void usage(FILE *fp) {
    fprintf(fp, "Usage: trac0r COMMAND [options]\n"
                "\n"
                "A physically based, real-time Monte Carlo path tracer.\n"
                "\n"
                "Commands:\n"
                "  render   render a scene to a PNG or PFM image\n"
                "  view     interactive window: fly through a scene while it converges\n"
                "  bench    measure speed: 'trac0r bench frame|complexity|rays|convergence'\n"
                "  compare  error metrics (RMSE, relMSE, PSNR) of an image against a reference\n"
                "  info     describe a scene: counts, bounds, warnings; --devices: OpenCL devices\n"
                "\n"
                "Run 'trac0r COMMAND --help' for a command's options.\n"
                "  -h, --help      show this help\n"
                "  --version       print the version\n");
}

int main(int argc, char **argv) {
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
