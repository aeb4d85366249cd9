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
                "  bench    measure speed: 'trac0r bench frame'\n"
                "  info     'trac0r info --devices': the OpenCL platforms and devices\n"
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
    if (strcmp(cmd, "info") == 0) {
        return cmd_info(argc - 1, argv + 1);
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
            "trac0r: unknown command '%s' (expected render, bench or info; see 'trac0r --help')\n",
            cmd);
    return CLI_USAGE;
}
