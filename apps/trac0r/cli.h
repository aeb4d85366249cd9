/* cli.h - option parsing shared by the trac0r subcommands.
 *
 * Every parse error prints one line naming the command, the option and the value at
 * fault, and the caller exits with status 2 (CLI_USAGE). */
#ifndef TRAC0R_CLI_H
#define TRAC0R_CLI_H

#include <stddef.h>
#include <stdio.h>
#include <stdint.h>

#include "trac0r/registry.h"
#include "trac0r/scene_file.h"
#include "trac0r/trac0r.h"

#define CLI_OK 0
#define CLI_USAGE 2   /* bad command line */
#define CLI_FAILURE 1 /* the work itself failed (I/O, out of memory) */
#define CLI_HELP (-1) /* cli_parse printed the help: exit 0, nothing else to do */

/* Options that render, view and bench share. */
typedef struct cli_common {
    const char *scene; /* "builtin:cornell" */
    uint32_t width, height;
    int max_depth;
    uint64_t seed;
    int threads;
    int integrator;
    tr_accel_type accel;
    unsigned given;                 /* CLI_GIVEN_*: options set on the command line (a scene file's
                                       render defaults apply to the others) */
    int allow_dark;                 /* --allow-dark: render a scene file without an emitter */
    tr_scene_extras extras;         /* --env, --sun, --ground */
    uint32_t def_width, def_height; /* the command's size before the options (cli_parse) */
    char device[32];                /* --device: a tr_device name, "cpu" or "opencl:N" */
    int device_bvh;                 /* --device-bvh: TR_DEVICE_BVH_* (0: auto) */
    int up_z;                       /* --up z: a model file's +z is up */
    const char *model_camera; /* --camera: a model file's camera, or "frame"; NULL: its first */
    float model_scale;        /* --scale: a model file's scale */
    int sampler;              /* --sampler: TR_SAMPLER_*, -1 for the command's default */
    int roulette_start;       /* --roulette-start: pt's, 0 for the command's default */
    int light_sampling;       /* --light-sampling: TR_LIGHT_SAMPLING_*, -1 for the scene's own */
    float clamp_indirect;     /* --clamp-indirect: pt's indirect clamp, -1 for the default */
    int regularize;           /* --regularize: 1 on, 0 off, -1 for the default */
    int restir;               /* --restir: TR_REALTIME_RESTIR_* (view, bench realtime) */
    int restir_unbiased;      /* --restir-unbiased */
    int cl_kernel;            /* --cl-kernel: TR_OPENCL_KERNEL_* (0: auto) */
} cli_common;

#define CLI_GIVEN_WIDTH 1u
#define CLI_GIVEN_HEIGHT 2u
#define CLI_GIVEN_MAX_DEPTH 4u
#define CLI_GIVEN_INTEGRATOR 8u
#define CLI_GIVEN_ACCEL 16u
#define CLI_GIVEN_SCENE 32u

/* Cursor over argv for one subcommand. */
typedef struct cli_args {
    const char *cmd; /* "render", "bench frame", ... for messages */
    int argc;
    char **argv;
    int i;
    const char *opt;   /* the option being parsed, without any "=value" */
    const char *value; /* its value, once cli_value() has fetched it */
    char optbuf[64];
} cli_args;

void cli_common_default(cli_common *c);
/* The names --integrator takes, and the --accel names this build has, as "a, b, c". */
void cli_integrator_list(char *buf, size_t size);
void cli_accel_list(char *buf, size_t size);

/* Prints "trac0r CMD: message" to stderr and returns CLI_USAGE. */
int cli_error(const cli_args *a, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/* The current argument is not one the command takes: "unknown option '--x'" for an
 * option (with "did you mean" the closest option `help` prints, if one is close), and
 * "unexpected argument 'x'" for anything else (a second SCENE). Returns CLI_USAGE. */
int cli_unknown(const cli_args *a, void (*help)(FILE *));

/* Advances to the next argument; returns 0 at the end. Splits "--opt=value". */
int cli_next(cli_args *a);
/* True when the current argument is the option `name` (e.g. "--width"). */
int cli_is(const cli_args *a, const char *name);
/* Fetches the current option's value into a->value; CLI_USAGE when missing. */
int cli_value(cli_args *a);
/* An on|off value: *on 1 or 0 (else a usage error naming the option). */
int cli_parse_on_off(cli_args *a, int *on);

int cli_parse_u32(cli_args *a, uint32_t lo, uint32_t hi, uint32_t *out);
int cli_parse_int(cli_args *a, int lo, int hi, int *out);
int cli_parse_u64(cli_args *a, uint64_t *out);
int cli_parse_float(cli_args *a, float lo, float hi, float *out);
/* The option's value as a comma-separated list of names (tr_names_parse_list): their
 * values into out[0 .. max); the count, or -1 after a usage error naming the `kind` of item and
 * the `available` ones. */
int cli_parse_list(cli_args *a, int (*lookup)(const char *name), int *out, int max,
                   const char *kind, const char *available);

/* Handles an option of cli_common. Returns CLI_OK if handled, CLI_USAGE on a bad value,
 * and -1 if the option is not a common one. */
int cli_common_option(cli_args *a, cli_common *c);
/* A command's whole line: the common options (those in `refused`, a NULL-ended list, are
 * refused once parsed), -h/--help (prints `help`), and `own` for the rest, which returns
 * CLI_OK, CLI_USAGE, or -1 for an option that is none of its own (an unknown option).
 * Returns CLI_OK, CLI_USAGE or CLI_HELP. */
int cli_parse(cli_args *a, cli_common *c, const char *const *refused, void (*help)(FILE *),
              int (*own)(cli_args *, void *), void *user);

/* A TR_SAMPLER_* by its name (--sampler, --reference-sampler) into *out, and the name of
 * one (anything but random and zsobol reads as the default, sobol). */
int cli_parse_sampler(cli_args *a, int *out);
const char *cli_sampler_name(int sampler);

/* The reconstruction's settings (tr_recon_params) that bench realtime and view take;
 * cli_recon_help lists them for --help. Returns CLI_OK if handled, CLI_USAGE on a bad
 * value, and -1 if the option is not one of them. */
extern const char cli_recon_help[];
int cli_recon_option(cli_args *a, tr_recon_params *p);
/* --restir off|di|di+gi and --restir-unbiased (view, bench realtime; listed in cli_recon_help)
 * into c; the same return values. */
int cli_restir_option(cli_args *a, cli_common *c);

/* Builds the scene named by c->scene for c->width x c->height into `scene` (a handle
 * from tr_scene_create; NULL is reported as out of memory) and commits it with
 * c->accel. On failure the scene is left empty: the caller still destroys it. */
int cli_load_scene(const cli_args *a, const cli_common *c, tr_scene *scene);

/* cli_load_scene that also applies a scene file's render defaults to the options the
 * command line did not give (c is updated) and returns the file's settings in *file
 * (zeroed for a built-in scene; may be NULL). Scene file errors and a file without an
 * emitter (unless allowed) are CLI_USAGE; warnings go to stderr. */
int cli_load_scene_file(const cli_args *a, cli_common *c, tr_scene *scene, tr_scene_file *file);

/* The firefly control the common options name, for a real-time loop's frames: given
 * values into *clamp_indirect and *regularize (tr_realtime_desc's fields), defaults
 * (zero) where not given. */
void cli_realtime_firefly(const cli_common *c, float *clamp_indirect, int *regularize);

/* The help text of the common options. */
const char *cli_common_help(void);

#endif
