/* cli.c - option parsing shared by the trac0r subcommands. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "trac0r/parse.h"
#include "devices.h"
#include "trac0r/registry.h"
#include "trac0r/scene_file.h"

#include <errno.h>
#include <stdio.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char help_before[] =
    "  --scene SCENE        builtin:cornell (default), builtin:cornell-mirror,\n"
    "                       builtin:cornell-diffuse, builtin:cornell-ico-N, a scene\n"
    "                       file (.json) or a model file Assimp reads (.glb, .obj, ...)\n"
    "  --up y|z             a model file's up axis (default y)\n"
    "  --scale S            a model file's scale, 1e-6..1e6 (default 1)\n"
    "  --camera N|NAME|frame  a model file's camera (default its first)\n"
    "  --allow-dark         render a scene file that has no emitter\n"
    "  --env R,G,B|FILE     an environment light: a radiance, or an .hdr/.png map\n"
    "  --sun X,Y,Z          a sun towards that direction (irradiance 3)\n"
    "  --ground             a grey floor under the scene\n"
    "  --width W            image width, 1..16384 (default 800)\n"
    "  --height H           image height, 1..16384 (default 600)\n"
    "  --max-depth D        path segments at most, 1..1024 (default 64 for pt, 8 for\n"
    "                       naive, 15 for bdpt and vcm)\n"
    "  --seed S             random seed, 0..2^64-1 (default 0)\n"
    "  --threads T          CPU threads, 0..1024 (default 0: one per core)\n"
    "  --sampler NAME       pt's numbers: sobol (default), random or zsobol\n"
    "  --roulette-start N   pt's Russian roulette after N segments, 1..1024 (default 5)\n"
    "  --light-sampling NAME  pt's choice of emitter: auto (default), tree or power\n"
    "  --clamp-indirect V   pt: clamp indirect light to luminance V (0: off; biased)\n"
    "  --regularize on|off  pt: roughen lobes after a diffuse vertex (biased)\n";
static const char help_after[] =
    "  --device DEV         cpu (default), opencl or opencl:N (trac0r info --devices)\n"
    "  --cl-kernel NAME     OpenCL pt: mega, wavefront or auto (default)\n"
    "  --device-bvh NAME    the BVH an OpenCL device walks: auto (default), bvh2, cwbvh\n";

void cli_integrator_list(char *buf, size_t size) {
    size_t count;
    const char *const *names = tr_integrator_names(&count);
    tr_names_join(buf, size, names, count, NULL);
}

void cli_accel_list(char *buf, size_t size) {
    size_t count, n = 0;
    const char *const *names = tr_accel_names(&count);
    const char *avail[16];
    for (size_t i = 0; i < count && n < 16; ++i) {
        if (tr_accel_available((tr_accel_type)tr_accel_from_name(names[i]))) {
            avail[n++] = names[i];
        }
    }
    tr_names_join(buf, size, avail, n, NULL);
}

void cli_common_default(cli_common *c) {
    memset(c, 0, sizeof *c); /* every field below or zero: the extras, the default size */
    c->scene = "builtin:cornell";
    c->model_scale = 1.0f;
    c->width = 800;
    c->height = 600;
    c->max_depth = TR_MAX_DEPTH_DEFAULT;
    c->integrator = TR_INTEGRATOR_PT;
    c->accel = TR_ACCEL_TYPE_BVH;
    c->sampler = -1;
    c->light_sampling = -1;
    c->clamp_indirect = -1.0f;
    c->regularize = -1;
    c->restir = TR_REALTIME_RESTIR_OFF;
    snprintf(c->device, sizeof c->device, "cpu");
}

/* The integrator and accel options' text comes from the registries (trac0r/registry.h),
 * so that --help lists every name the parser takes. */
const char *cli_common_help(void) {
    static char buf[8192];
    if (buf[0]) {
        return buf;
    }
    cli_common d;
    cli_common_default(&d);
    size_t used = (size_t)snprintf(buf, sizeof buf, "%s", help_before);
    used += (size_t)snprintf(buf + used, sizeof buf - used,
                             "  --integrator NAME    integrator (default %s):\n",
                             tr_integrator_name(d.integrator));
    size_t count;
    const char *const *names = tr_integrator_names(&count);
    for (size_t i = 0; i < count && used < sizeof buf; ++i) {
        used += (size_t)snprintf(buf + used, sizeof buf - used, "%25s%-8s%s\n", "", names[i],
                                 tr_integrator_description(tr_integrator_from_name(names[i])));
    }
    if (used < sizeof buf) {
        used += (size_t)snprintf(buf + used, sizeof buf - used,
                                 "  --accel NAME         acceleration structure (default %s):\n",
                                 tr_accel_name(d.accel));
    }
    names = tr_accel_names(&count);
    for (size_t i = 0; i < count && used < sizeof buf; ++i) {
        tr_accel_type t = (tr_accel_type)tr_accel_from_name(names[i]);
        used += (size_t)snprintf(buf + used, sizeof buf - used, "%25s%-8s%s\n", "", names[i],
                                 tr_accel_description(t));
    }
    if (used < sizeof buf) {
        snprintf(buf + used, sizeof buf - used, "%s", help_after);
    }
    return buf;
}

int cli_error(const cli_args *a, const char *fmt, ...) {
    fprintf(stderr, "trac0r %s: ", a->cmd);
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return CLI_USAGE;
}

/* The option closest to opt among those the help text names (every "--word" in it). */
static const char *closest_option(const char *opt, void (*help)(FILE *), char *buf, size_t n) {
    char *text = NULL, *save = NULL;
    size_t size = 0, count = 0;
    FILE *fp = open_memstream(&text, &size);
    if (!fp) {
        return NULL;
    }
    help(fp);
    fclose(fp);
    const char *names[256];
    for (char *w = strtok_r(text, " \t\n,:|=()[]", &save); w && count < 256;
         w = strtok_r(NULL, " \t\n,:|=()[]", &save)) {
        if (strncmp(w, "--", 2) == 0 && w[2] >= 'a' && w[2] <= 'z') {
            names[count++] = w;
        }
    }
    const char *near = tr_names_closest(opt, names, count);
    snprintf(buf, n, "%s", near ? near : "");
    free(text);
    return near ? buf : NULL;
}

int cli_unknown(const cli_args *a, void (*help)(FILE *)) {
    if (a->opt[0] == '-' && a->opt[1] != '\0') {
        char buf[64];
        const char *near = help ? closest_option(a->opt, help, buf, sizeof buf) : NULL;
        return cli_error(a, "unknown option '%s' (%s%s%ssee 'trac0r %s --help')", a->opt,
                         near ? "did you mean '" : "", near ? near : "", near ? "'? " : "", a->cmd);
    }
    /* Not an option at all: a second SCENE, or an argument where none is taken. */
    return cli_error(a, "unexpected argument '%s' (see 'trac0r %s --help')", a->opt, a->cmd);
}

int cli_next(cli_args *a) {
    if (++a->i >= a->argc) {
        return 0;
    }
    const char *arg = a->argv[a->i];
    const char *eq = strncmp(arg, "--", 2) == 0 ? strchr(arg, '=') : NULL;
    if (eq && (size_t)(eq - arg) < sizeof a->optbuf) {
        memcpy(a->optbuf, arg, (size_t)(eq - arg));
        a->optbuf[eq - arg] = '\0';
        a->opt = a->optbuf;
        a->value = eq + 1;
    } else {
        a->opt = arg;
        a->value = NULL;
    }
    return 1;
}

int cli_is(const cli_args *a, const char *name) {
    return strcmp(a->opt, name) == 0;
}

int cli_value(cli_args *a) {
    if (a->value) {
        return CLI_OK;
    }
    if (a->i + 1 >= a->argc) {
        return cli_error(a, "%s: missing value", a->opt);
    }
    a->value = a->argv[++a->i];
    return CLI_OK;
}

int cli_parse_on_off(cli_args *a, int *on) {
    int rc = cli_value(a);
    if (rc == CLI_OK && strcmp(a->value, "on") != 0 && strcmp(a->value, "off") != 0) {
        rc = cli_error(a, "%s: expected on or off, got '%s'", a->opt, a->value);
    }
    *on = rc == CLI_OK ? strcmp(a->value, "on") == 0 : *on;
    return rc;
}

/* Parses a whole decimal integer (no sign for unsigned ranges, no trailing text). */
static int parse_integer(cli_args *a, long long lo, long long hi, long long *out) {
    int rc = cli_value(a);
    int64_t x = 0;
    if (rc == CLI_OK && tr_parse_int64(a->value, lo, hi, &x) != TR_OK) { /* trac0r/parse.h */
        rc = cli_error(a, "%s: expected an integer in %lld..%lld, got '%s'", a->opt, lo, hi,
                       a->value);
    }
    *out = rc == CLI_OK ? (long long)x : *out;
    return rc;
}

int cli_parse_u32(cli_args *a, uint32_t lo, uint32_t hi, uint32_t *out) {
    long long x = *out;
    const int rc = parse_integer(a, lo, hi, &x);
    *out = (uint32_t)x;
    return rc;
}

int cli_parse_int(cli_args *a, int lo, int hi, int *out) {
    long long x = *out;
    const int rc = parse_integer(a, lo, hi, &x);
    *out = (int)x;
    return rc;
}

int cli_parse_u64(cli_args *a, uint64_t *out) {
    int rc = cli_value(a);
    if (rc == CLI_OK && tr_parse_uint64(a->value, 0, UINT64_MAX, out) != TR_OK) {
        rc = cli_error(a, "%s: expected an integer in 0..%" PRIu64 ", got '%s'", a->opt, UINT64_MAX,
                       a->value);
    }
    return rc;
}

int cli_parse_float(cli_args *a, float lo, float hi, float *out) {
    int rc = cli_value(a);
    if (rc == CLI_OK && tr_parse_float(a->value, lo, hi, out) != TR_OK) {
        rc = cli_error(a, "%s: expected a number in %g..%g, got '%s'", a->opt, (double)lo,
                       (double)hi, a->value);
    }
    return rc;
}

int cli_parse_list(cli_args *a, int (*lookup)(const char *name), int *out, int max,
                   const char *kind, const char *available) {
    tr_error err;
    if (cli_value(a) != CLI_OK) {
        return -1;
    }
    const int n = tr_names_parse_list(a->value, lookup, out, max, a->opt, kind, available, &err);
    if (n < 0) {
        cli_error(a, "%s", err.msg);
    }
    return n;
}

const char *cli_sampler_name(int sampler) {
    return sampler == TR_SAMPLER_RANDOM   ? "random"
           : sampler == TR_SAMPLER_ZSOBOL ? "zsobol"
                                          : "sobol";
}

int cli_parse_sampler(cli_args *a, int *out) {
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    static const int kinds[] = {TR_SAMPLER_SOBOL, TR_SAMPLER_RANDOM, TR_SAMPLER_ZSOBOL};
    for (size_t k = 0; k < sizeof kinds / sizeof *kinds; ++k) {
        if (strcmp(a->value, cli_sampler_name(kinds[k])) == 0) {
            *out = kinds[k];
            return CLI_OK;
        }
    }
    return cli_error(a, "%s: unknown sampler '%s' (available: sobol, random, zsobol)", a->opt,
                     a->value);
}

int cli_common_option(cli_args *a, cli_common *c) {
    if (cli_is(a, "--scene")) {
        if (cli_value(a) != CLI_OK) {
            return CLI_USAGE;
        }
        c->scene = a->value;
        c->given |= CLI_GIVEN_SCENE;
        return CLI_OK;
    }
    if (cli_is(a, "--allow-dark") || cli_is(a, "--ground")) {
        *(cli_is(a, "--ground") ? &c->extras.ground : &c->allow_dark) = 1;
        return CLI_OK;
    }
    if (cli_is(a, "--env") || cli_is(a, "--sun")) {
        const int rc = cli_value(a);
        *(cli_is(a, "--env") ? &c->extras.env : &c->extras.sun) = a->value;
        return rc;
    }
    if (cli_is(a, "--up")) {
        if (cli_value(a) != CLI_OK) {
            return CLI_USAGE;
        }
        if (strcmp(a->value, "y") != 0 && strcmp(a->value, "z") != 0) {
            return cli_error(a, "--up: expected y or z, got '%s'", a->value);
        }
        c->up_z = a->value[0] == 'z';
        return CLI_OK;
    }
    if (cli_is(a, "--camera")) {
        if (cli_value(a) != CLI_OK) {
            return CLI_USAGE;
        }
        if (!a->value[0]) {
            return cli_error(a, "--camera: expected a camera's name or number, or 'frame'");
        }
        c->model_camera = a->value;
        return CLI_OK;
    }
    if (cli_is(a, "--scale")) {
        return cli_parse_float(a, 1e-6f, 1e6f, &c->model_scale);
    }
    if (cli_is(a, "--width") || cli_is(a, "--height")) {
        const int w = cli_is(a, "--width"); /* one alone keeps the shape: tr_scene_open */
        c->given |= w ? CLI_GIVEN_WIDTH : CLI_GIVEN_HEIGHT;
        return cli_parse_u32(a, 1, TR_FILM_MAX_SIDE, w ? &c->width : &c->height);
    }
    if (cli_is(a, "--max-depth")) {
        c->given |= CLI_GIVEN_MAX_DEPTH;
        return cli_parse_int(a, 1, TR_MAX_DEPTH_LIMIT, &c->max_depth);
    }
    if (cli_is(a, "--seed")) {
        return cli_parse_u64(a, &c->seed);
    }
    if (cli_is(a, "--threads")) {
        return cli_parse_int(a, 0, TR_MAX_THREADS, &c->threads);
    }
    if (cli_is(a, "--integrator")) {
        c->given |= CLI_GIVEN_INTEGRATOR;
        if (cli_value(a) != CLI_OK) {
            return CLI_USAGE;
        }
        int k = tr_integrator_from_name(a->value);
        if (k >= 0) {
            c->integrator = k;
            return CLI_OK;
        }
        char names[128];
        cli_integrator_list(names, sizeof names);
        return cli_error(a, "--integrator: unknown integrator '%s' (available: %s)", a->value,
                         names);
    }
    if (cli_is(a, "--accel")) {
        c->given |= CLI_GIVEN_ACCEL;
        if (cli_value(a) != CLI_OK) {
            return CLI_USAGE;
        }
        int accel = tr_accel_from_name(a->value);
        if (accel < 0) {
            char names[128];
            cli_accel_list(names, sizeof names);
            return cli_error(a, "--accel: unknown acceleration structure '%s' (available: %s)",
                             a->value, names);
        }
        if (!tr_accel_available((tr_accel_type)accel)) {
            return cli_error(a,
                             "--accel: '%s' is not available: this build of trac0r has no "
                             "Embree support",
                             a->value);
        }
        c->accel = (tr_accel_type)accel;
        return CLI_OK;
    }
    if (cli_is(a, "--device") || cli_is(a, "--device-bvh")) {
        return cli_parse_device(a, c);
    }
    if (cli_is(a, "--sampler")) {
        return cli_parse_sampler(a, &c->sampler);
    }
    if (cli_is(a, "--roulette-start")) {
        return cli_parse_int(a, 1, TR_MAX_DEPTH_LIMIT, &c->roulette_start);
    }
    if (cli_is(a, "--clamp-indirect")) {
        return cli_parse_float(a, 0.0f, 1e30f, &c->clamp_indirect);
    }
    if (cli_is(a, "--regularize")) {
        return cli_parse_on_off(a, &c->regularize);
    }
    if (cli_is(a, "--light-sampling") || cli_is(a, "--cl-kernel")) { /* names, as the library's */
        const int ls = a->opt[2] == 'l', rc = cli_value(a);
        const int k = rc != CLI_OK ? 0
                      : ls         ? tr_light_sampling_from_name(a->value)
                                   : tr_opencl_kernel_from_name(a->value);
        *(ls ? &c->light_sampling : &c->cl_kernel) = k >= 0 ? k : 0;
        return rc != CLI_OK || k >= 0
                   ? rc
                   : cli_error(a, "%s: unknown %s '%s' (available: %s)", a->opt,
                               ls ? "light sampling" : "kernel", a->value,
                               ls ? "auto, tree, power" : "mega, wavefront, auto");
    }
    return -1;
}

void cli_realtime_firefly(const cli_common *c, float *clamp_indirect, int *regularize) {
    /* tr_realtime_desc: 0 is the default, below 0 off. */
    *clamp_indirect = c->clamp_indirect < 0.0f    ? 0.0f
                      : c->clamp_indirect == 0.0f ? -1.0f
                                                  : c->clamp_indirect;
    *regularize = c->regularize < 0 ? 0 : c->regularize ? 1 : -1;
}

const char cli_recon_help[] =
    "  --alpha-min A, --svgf-alpha-min A   a new frame's least weight (0.1; SVGF 0.2)\n"
    "  --max-history L      frames of history, 1..1024 (default 64)\n"
    "  --max-history-moving L   the same where a shape moved, 1..1024 (default 4)\n"
    "  --svgf-iterations N  SVGF's a-trous steps, 1..8 (default 3)\n"
    "  --svgf-sigma-l S     SVGF's luminance weight, 0.1..1000 (default 4)\n"
    "  --taa A              SVGF's temporal antialiasing, 0..1 (default 0: off)\n"
    "  --svgf-split         filter direct and indirect light apart\n"
    "  --split-specular     filter diffuse and specular light apart (pt only)\n"
    "  --gradients on|off   temporal gradients: shorten the history where the lighting\n"
    "                       changed (A-SVGF; default off)\n"
    "  --resolve-emission N emitters' edges traced at N x N rays, 0..16 (default 4)\n"
    "  --resolve-albedo N   albedo's edges traced at N x N rays, 0..8 (default 0: off)\n"
    "  --albedo-alpha A     SVGF's albedo history, frame weight 0..1 (0.35; 0: off)\n"
    "  --fresh-spp N        pixels without history traced at N spp in all (0: off)\n"
    "  --restir off|di|di+gi  ReSTIR DI for the first surfaces' direct light, di+gi\n"
    "                       ReSTIR GI for their indirect light too (default off)\n"
    "  --restir-unbiased    ReSTIR with Talbot's MIS weights (default: biased 1/M)\n";

int cli_restir_option(cli_args *a, cli_common *c) {
    if (cli_is(a, "--restir")) {
        if (cli_value(a) != CLI_OK) {
            return CLI_USAGE;
        }
        if (strcmp(a->value, "off") != 0 && strcmp(a->value, "di") != 0 &&
            strcmp(a->value, "di+gi") != 0) {
            return cli_error(a, "--restir: expected off, di or di+gi, got '%s'", a->value);
        }
        c->restir = strcmp(a->value, "di") == 0      ? TR_REALTIME_RESTIR_DI
                    : strcmp(a->value, "di+gi") == 0 ? TR_REALTIME_RESTIR_DI_GI
                                                     : TR_REALTIME_RESTIR_OFF;
        return CLI_OK;
    }
    if (cli_is(a, "--restir-unbiased")) {
        c->restir_unbiased = 1;
        return CLI_OK;
    }
    return -1;
}

int cli_parse(cli_args *a, cli_common *c, const char *const *refused, void (*help)(FILE *),
              int (*own)(cli_args *, void *), void *user) {
    c->def_width = c->width; /* the command's own size, before the options change it */
    c->def_height = c->height;
    while (cli_next(a)) {
        int rc = cli_common_option(a, c);
        for (const char *const *r = refused; rc == CLI_OK && r && *r; ++r) {
            if (cli_is(a, *r)) {
                return cli_error(a, "%s: not an option of this benchmark", a->opt);
            }
        }
        if (rc != -1) {
            if (rc != CLI_OK) {
                return CLI_USAGE;
            }
        } else if (cli_is(a, "-h") || cli_is(a, "--help")) {
            help(stdout);
            return CLI_HELP;
        } else if ((rc = own(a, user)) != CLI_OK) {
            return rc < 0 ? cli_unknown(a, help) : CLI_USAGE;
        }
    }
    return CLI_OK;
}

int cli_recon_option(cli_args *a, tr_recon_params *p) {
    /* The float and int (iv) settings by name, with their ranges. */
    const struct {
        const char *name;
        float lo, hi, *v;
        int *iv;
    } f[] = {{"--alpha-min", 0.01f, 1.0f, &p->alpha_min, NULL},
             {"--svgf-alpha-min", 0.01f, 1.0f, &p->svgf_alpha_min, NULL},
             {"--albedo-alpha", 0.0f, 1.0f, &p->albedo_alpha, NULL},
             {"--max-history", 1.0f, 1024.0f, &p->max_len, NULL},
             {"--max-history-moving", 1.0f, 1024.0f, &p->max_len_moving, NULL},
             {"--svgf-sigma-l", 0.1f, 1000.0f, &p->svgf_sigma_l, NULL},
             {"--taa", 0.0f, 1.0f, &p->svgf_taa_alpha, NULL},
             {"--svgf-iterations", 1, 8, NULL, &p->svgf_iterations},
             {"--resolve-emission", 0, TR_RESOLVE_EMISSION_MAX, NULL, &p->emission_samples},
             {"--resolve-albedo", 0, TR_RESOLVE_ALBEDO_MAX, NULL, &p->albedo_samples},
             {"--fresh-spp", 0, 64, NULL, &p->fresh_spp}};
    for (size_t k = 0; k < sizeof f / sizeof f[0]; ++k) {
        if (cli_is(a, f[k].name)) {
            return f[k].v ? cli_parse_float(a, f[k].lo, f[k].hi, f[k].v)
                          : cli_parse_int(a, (int)f[k].lo, (int)f[k].hi, f[k].iv);
        }
    }
    if (cli_is(a, "--svgf-split") || cli_is(a, "--split-specular")) {
        *(cli_is(a, "--svgf-split") ? &p->svgf_split : &p->svgf_specular) = 1;
        return CLI_OK;
    }
    if (cli_is(a, "--gradients")) {
        return cli_parse_on_off(a, &p->gradients);
    }
    return -1;
}

/* tr_scene_open's failure in the command's words: its options named where they are the
 * way out. Running out of memory is a failure (1); the rest are usage errors (2). */
static int open_error(const cli_args *a, const tr_scene_file *f, const tr_error *err) {
    if (err->code == TR_STATUS_OUT_OF_MEMORY) {
        fprintf(stderr, "trac0r %s: %s\n", a->cmd, err->msg);
        return CLI_FAILURE;
    }
    if (err->code == TR_STATUS_NOT_FOUND && f->open_stage == TR_SCENE_OPEN_SETTINGS &&
        f->emissive_triangles == 0) { /* loaded, but without an emitter */
        return cli_error(a, "%s (or pass --allow-dark)", err->msg);
    }
    /* An extra's message begins with its option's name, as does a size over the limit. */
    const int option = f->open_stage == TR_SCENE_OPEN_EXTRAS ||
                       (f->open_stage == TR_SCENE_OPEN_SETTINGS && err->code == TR_STATUS_LIMIT);
    return cli_error(a, "%s%s%s", option ? "--" : "", err->msg,
                     f->open_stage == TR_SCENE_OPEN_COMMIT && err->code == TR_STATUS_UNSUPPORTED
                         ? " (use --accel)"
                         : "");
}

int cli_load_scene_file(const cli_args *a, cli_common *c, tr_scene *scene, tr_scene_file *file) {
    tr_scene_file local;
    file = file ? file : &local;
    memset(file, 0, sizeof *file);
    if (!scene) {
        return cli_error(a, "out of memory creating the scene");
    }
    /* What the command line gave is asked for; the command's own defaults apply where the
     * file has no value (bench realtime's 320x240, bench's naive integrator). */
    tr_scene_open_desc d = {.model = {c->up_z, c->model_scale, 0, 0, c->model_camera},
                            .extras = c->extras};
    tr_render_request *given = &d.request, *def = &d.defaults;
    given->width = c->given & CLI_GIVEN_WIDTH ? c->width : 0;
    given->height = c->given & CLI_GIVEN_HEIGHT ? c->height : 0;
    def->width = c->def_width ? c->def_width : c->width;
    def->height = c->def_height ? c->def_height : c->height;
    *(c->given & CLI_GIVEN_MAX_DEPTH ? &given->max_depth : &def->max_depth) = c->max_depth;
    *(c->given & CLI_GIVEN_INTEGRATOR ? &given->integrator : &def->integrator) =
        tr_integrator_name(c->integrator);
    *(c->given & CLI_GIVEN_ACCEL ? &given->accel : &def->accel) = tr_accel_name(c->accel);
    given->light_sampling =
        c->light_sampling >= 0 ? tr_light_sampling_name(c->light_sampling) : NULL;
    given->allow_dark = c->allow_dark;
    tr_render_settings st;
    tr_error err;
    if (tr_scene_open(scene, c->scene, &d, file, &st, &err) != TR_OK) {
        return open_error(a, file, &err);
    }
    c->width = st.width;
    c->height = st.height;
    c->accel = st.accel;
    c->integrator = st.config.integrator;
    c->max_depth = st.config.max_depth;
    for (uint32_t i = 0; i < file->warning_count; ++i) {
        if (file->emissive_triangles == 0 && strstr(file->warnings[i], "no emitter")) {
            continue; /* allowed, said so above */
        }
        fprintf(stderr, "trac0r %s: warning: %s: %s\n", a->cmd, c->scene, file->warnings[i]);
    }
    return CLI_OK;
}

int cli_load_scene(const cli_args *a, const cli_common *c, tr_scene *scene) {
    /* The caller's options are final here (its film has their size): a scene file's
     * render defaults do not apply. */
    cli_common copy = *c;
    copy.given = ~0u;
    return cli_load_scene_file(a, &copy, scene, NULL);
}
