/* cli.c - option parsing shared by the trac0r subcommands. */
#include "cli.h"
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
    "  --scene SCENE        scene to render: builtin:cornell (the thesis's Cornell box,\n"
    "                       the default), builtin:cornell-mirror (its glossy objects\n"
    "                       as perfect mirrors), builtin:cornell-diffuse (every object\n"
    "                       white diffuse), builtin:cornell-ico-N, or a scene file\n"
    "                       (docs/scene-format.md) whose render defaults apply to the\n"
    "                       options not given here, or a model file in any format\n"
    "                       Assimp reads (.glb, .gltf, .obj, .dae, .fbx, .ply, ...): a\n"
    "                       scene is built around it (its camera, else one framing it;\n"
    "                       its lights, else a white environment light)\n"
    "  --up y|z             a model file's up axis (default y; z stands z-up models up)\n"
    "  --scale S            a model file's scale, 1e-6..1e6 (default 1)\n"
    "  --camera N|NAME|frame  a model file's camera by number or name (default its\n"
    "                       first), or frame: one framing the model\n"
    "  --allow-dark         render a scene file that has no emitter\n"
    "  --width W            image width in pixels, 1..16384 (default 800)\n"
    "  --height H           image height in pixels, 1..16384 (default 600);\n"
    "                       at most 67108864 pixels in all\n"
    "  --max-depth D        path length limit of the integrator, 1..1024 (default 64 for\n"
    "                       pt, whose paths end by Russian roulette; 8 for naive; 15,\n"
    "                       also their limit, for bdpt and vcm): pt, bdpt and vcm\n"
    "                       follow at most D\n"
    "                       segments (camera ray included); the naive integrator's\n"
    "                       Russian roulette reaches at most D-2 surfaces\n"
    "  --seed S             random seed, 0..2^64-1 (default 0); the same seed gives the\n"
    "                       same image for any thread count\n"
    "  --threads T          CPU threads, 0..1024 (default 0: one per core)\n"
    "  --sampler NAME       pt's uniform numbers (default sobol; bench realtime's frames\n"
    "                       and the viewer's moving frames: random):\n"
    "                         sobol   Owen-scrambled Sobol points, stratified\n"
    "                         random  independent numbers, the cheapest\n"
    "                         zsobol  sobol, with errors as blue noise between pixels\n"
    "  --roulette-start N   pt's Russian roulette may end a path after N segments\n"
    "                       (the camera ray is the first), 1..1024 (default 5, the\n"
    "                       least error per sample; bench realtime's frames and the\n"
    "                       viewer's moving frames: 2, where the reconstruction\n"
    "                       hides the extra noise)\n"
    "  --light-sampling NAME  how pt picks an emitter for next-event estimation\n"
    "                       (default: the scene file's render.light_sampling, else auto):\n"
    "                         auto    tree from 8 emissive triangles on, else power\n"
    "                         tree    light tree: power, distance and orientation\n"
    "                         power   in proportion to emitted power\n"
    "  --clamp-indirect V   pt: a contribution arriving over an indirect vertex is\n"
    "                       clamped to luminance V, 0..1e30 (0: off; default off for\n"
    "                       render, 4 for real-time frames; biased: docs/realtime.md)\n"
    "  --regularize on|off  pt: glossy and specular lobes after the first non-specular\n"
    "                       vertex are roughened, so that light samples reach caustics\n"
    "                       (default off for render, on for real-time frames; biased)\n";
static const char help_after[] =
    "  --device DEV         cpu (the default), opencl (OpenCL device 0) or opencl:N\n"
    "                       (device N of 'trac0r info --devices'); the device traces\n"
    "                       the flat structure or the BVH (bvh2 and embree scenes: the\n"
    "                       binary BVH)\n";

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
    c->scene = "builtin:cornell";
    c->model_scale = 1.0f;
    c->up_z = 0;
    c->model_camera = NULL;
    c->width = 800;
    c->height = 600;
    c->max_depth = TR_MAX_DEPTH_DEFAULT;
    c->seed = 0;
    c->threads = 0;
    c->integrator = TR_INTEGRATOR_PT;
    c->accel = TR_ACCEL_TYPE_BVH;
    c->given = 0;
    c->allow_dark = 0;
    c->sampler = -1;
    c->roulette_start = 0;
    c->light_sampling = -1;
    c->clamp_indirect = -1.0f;
    c->regularize = -1;
    c->restir = TR_REALTIME_RESTIR_OFF;
    c->restir_unbiased = 0;
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

int cli_unknown(const cli_args *a) {
    if (a->opt[0] == '-' && a->opt[1] != '\0') {
        return cli_error(a, "unknown option '%s' (see 'trac0r %s --help')", a->opt, a->cmd);
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

/* Parses a whole decimal integer (no sign for unsigned ranges, no trailing text). */
static int parse_integer(cli_args *a, long long lo, long long hi, long long *out) {
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    const char *v = a->value;
    char *end;
    errno = 0;
    long long x = strtoll(v, &end, 10);
    if (*v == '\0' || *end != '\0' || errno == ERANGE || x < lo || x > hi) {
        return cli_error(a, "%s: expected an integer in %lld..%lld, got '%s'", a->opt, lo, hi, v);
    }
    *out = x;
    return CLI_OK;
}

int cli_parse_u32(cli_args *a, uint32_t lo, uint32_t hi, uint32_t *out) {
    long long x = 0;
    if (parse_integer(a, lo, hi, &x) != CLI_OK) {
        return CLI_USAGE;
    }
    *out = (uint32_t)x;
    return CLI_OK;
}

int cli_parse_int(cli_args *a, int lo, int hi, int *out) {
    long long x = 0;
    if (parse_integer(a, lo, hi, &x) != CLI_OK) {
        return CLI_USAGE;
    }
    *out = (int)x;
    return CLI_OK;
}

int cli_parse_u64(cli_args *a, uint64_t *out) {
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    const char *v = a->value;
    char *end;
    errno = 0;
    unsigned long long x = strtoull(v, &end, 10);
    if (*v < '0' || *v > '9' || *end != '\0' || errno == ERANGE) {
        return cli_error(a, "%s: expected an integer in 0..%" PRIu64 ", got '%s'", a->opt,
                         UINT64_MAX, v);
    }
    *out = (uint64_t)x;
    return CLI_OK;
}

int cli_parse_float(cli_args *a, float lo, float hi, float *out) {
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    const char *v = a->value;
    char *end;
    errno = 0;
    double x = strtod(v, &end);
    if (*v == '\0' || *end != '\0' || errno == ERANGE || !isfinite(x) || x < lo || x > hi) {
        return cli_error(a, "%s: expected a number in %g..%g, got '%s'", a->opt, (double)lo,
                         (double)hi, v);
    }
    *out = (float)x;
    return CLI_OK;
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
    if (cli_is(a, "--allow-dark")) {
        c->allow_dark = 1;
        return CLI_OK;
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
    if (cli_is(a, "--width")) {
        c->given |= CLI_GIVEN_WIDTH;
        return cli_parse_u32(a, 1, TR_FILM_MAX_SIDE, &c->width);
    }
    if (cli_is(a, "--height")) {
        c->given |= CLI_GIVEN_HEIGHT;
        return cli_parse_u32(a, 1, TR_FILM_MAX_SIDE, &c->height);
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
    if (cli_is(a, "--device")) {
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
        if (cli_value(a) != CLI_OK) {
            return CLI_USAGE;
        }
        if (strcmp(a->value, "on") != 0 && strcmp(a->value, "off") != 0) {
            return cli_error(a, "--regularize: expected on or off, got '%s'", a->value);
        }
        c->regularize = strcmp(a->value, "on") == 0;
        return CLI_OK;
    }
    if (cli_is(a, "--light-sampling")) {
        if (cli_value(a) != CLI_OK) {
            return CLI_USAGE;
        }
        c->light_sampling = tr_light_sampling_from_name(a->value);
        if (c->light_sampling < 0) {
            return cli_error(a,
                             "--light-sampling: unknown light sampling '%s' (available: auto, "
                             "tree, power)",
                             a->value);
        }
        return CLI_OK;
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
    "  --alpha-min A        the temporal average's least weight of a new frame,\n"
    "                       0.01..1 (default 0.1)\n"
    "  --max-history L      frames of history at most, 1..1024 (default 64; 1: no\n"
    "                       temporal accumulation)\n"
    "  --max-history-moving L   the same where a shape moved since the previous frame\n"
    "                       (--animate), 1..1024 (default 4: its shading follows the motion)\n"
    "  --svgf-iterations N  SVGF's a-trous steps, 1..8 (default 3)\n"
    "  --svgf-sigma-l S     SVGF's luminance weight, 0.1..1000 (default 8)\n"
    "  --taa A              SVGF's temporal antialiasing, the new frame's weight,\n"
    "                       0..1 (default 0: off)\n"
    "  --svgf-split         SVGF filters direct and indirect light apart (CPU only)\n"
    "  --resolve-emission N emitters' edges: N x N camera rays per edge pixel, added\n"
    "                       after the filters, 0..16 (default 4; 0: the emission is\n"
    "                       filtered with the rest; pt only, CPU reconstruction only)\n"
    "  --restir off|di|di+gi  di: the direct light at the first surfaces by ReSTIR DI\n"
    "                       (reservoir resampling reused over frames and neighbours;\n"
    "                       pt on the CPU only; default off); di+gi: the indirect\n"
    "                       light there too, by ReSTIR GI (path resampling)\n"
    "  --restir-unbiased    ReSTIR merges with Talbot's MIS weights, no visibility reuse\n"
    "                       (unbiased; default: 1/M weights, biased, less noisy)\n";

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

int cli_parse(cli_args *a, cli_common *c, const char *const *refused, void (*help)(void),
              int (*own)(cli_args *, void *), void *user) {
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
            help();
            return CLI_HELP;
        } else if ((rc = own(a, user)) != CLI_OK) {
            return rc < 0 ? cli_unknown(a) : CLI_USAGE;
        }
    }
    return CLI_OK;
}

int cli_recon_option(cli_args *a, tr_recon_params *p) {
    if (cli_is(a, "--alpha-min")) {
        return cli_parse_float(a, 0.01f, 1.0f, &p->alpha_min);
    }
    if (cli_is(a, "--max-history")) {
        return cli_parse_float(a, 1.0f, 1024.0f, &p->max_len);
    }
    if (cli_is(a, "--max-history-moving")) {
        return cli_parse_float(a, 1.0f, 1024.0f, &p->max_len_moving);
    }
    if (cli_is(a, "--svgf-iterations")) {
        return cli_parse_int(a, 1, 8, &p->svgf_iterations);
    }
    if (cli_is(a, "--svgf-sigma-l")) {
        return cli_parse_float(a, 0.1f, 1000.0f, &p->svgf_sigma_l);
    }
    if (cli_is(a, "--taa")) {
        return cli_parse_float(a, 0.0f, 1.0f, &p->svgf_taa_alpha);
    }
    if (cli_is(a, "--resolve-emission")) {
        return cli_parse_int(a, 0, TR_RESOLVE_EMISSION_MAX, &p->emission_samples);
    }
    if (cli_is(a, "--svgf-split")) {
        p->svgf_split = 1;
        return CLI_OK;
    }
    return -1;
}

/* The request over a scene file's render defaults: the options the command line gave,
 * and the command's own defaults (bench realtime's 320x240, bench's naive integrator)
 * where the file has no value; the rest stay 0, the file's. */
static tr_render_request file_request(const cli_common *c, const tr_scene_file *f) {
    tr_render_request r = {0};
    if ((c->given & CLI_GIVEN_WIDTH) || !f->has_width) {
        r.width = c->width;
    }
    if ((c->given & CLI_GIVEN_HEIGHT) || !f->has_height) {
        r.height = c->height;
    }
    if ((c->given & CLI_GIVEN_MAX_DEPTH) || !f->has_max_depth) {
        r.max_depth = c->max_depth; /* 0 without either: the integrator's default */
    }
    if ((c->given & CLI_GIVEN_INTEGRATOR) || !f->has_integrator) {
        r.integrator = tr_integrator_name(c->integrator);
    }
    if ((c->given & CLI_GIVEN_ACCEL) || !f->has_accel) {
        r.accel = tr_accel_name(c->accel);
    }
    if (c->light_sampling >= 0) { /* the command line over render.light_sampling */
        r.light_sampling = tr_light_sampling_name(c->light_sampling);
    }
    r.allow_dark = c->allow_dark;
    return r;
}

/* tr_scene_file_apply's failure in the command's words: its options named where they
 * are the way out. Every one is a usage error. */
static int apply_error(const cli_args *a, const cli_common *c, const tr_render_settings *st,
                       const tr_error *err) {
    switch (err->code) {
    case TR_STATUS_UNSUPPORTED:
        return cli_error(a, "%s (use --accel)", err->msg);
    case TR_STATUS_NOT_FOUND:
        return cli_error(a,
                         "%s: the scene has no emitter, so the image would be black (set "
                         "render.allow_no_emitter or pass --allow-dark if that is intended)",
                         c->scene);
    case TR_STATUS_LIMIT:
        return cli_error(a, "--width/--height: %ux%u is more than %u pixels", st->width, st->height,
                         TR_FILM_MAX_PIXELS);
    default:
        return cli_error(a, "%s", err->msg);
    }
}

int cli_load_scene_file(const cli_args *a, cli_common *c, tr_scene *scene, tr_scene_file *file) {
    tr_scene_file local;
    if (!file) {
        file = &local;
    }
    if (!scene) {
        return cli_error(a, "out of memory creating the scene");
    }
    memset(file, 0, sizeof *file);
    if (tr_scene_name_is_builtin(c->scene)) {
        return cli_load_scene(a, c, scene);
    }
    /* A scene file, or a model file (glTF, OBJ, ...) with a scene built around it. */
    tr_error err;
    const tr_model_options mo = {c->up_z, c->model_scale, c->width,
                                 c->given & CLI_GIVEN_HEIGHT ? c->height : 0, c->model_camera};
    if (tr_scene_load(scene, c->scene, &mo, file, &err) != TR_OK) {
        return cli_error(a, "%s", err.msg);
    }
    tr_render_settings st;
    const tr_render_request req = file_request(c, file);
    if (tr_scene_file_apply(scene, c->scene, file, &req, &st, &err) != TR_OK) {
        tr_scene_clear(scene);
        return apply_error(a, c, &st, &err);
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
    if (tr_scene_commit(scene, c->accel, &err) != TR_OK) {
        fprintf(stderr, "trac0r %s: %s\n", a->cmd, err.msg);
        tr_scene_clear(scene);
        return CLI_FAILURE;
    }
    return CLI_OK;
}

int cli_load_scene(const cli_args *a, const cli_common *c, tr_scene *scene) {
    if (!scene) {
        return cli_error(a, "out of memory creating the scene");
    }
    if (!tr_scene_name_is_builtin(c->scene)) {
        /* The caller's options are final here (its film has their size): the file's
         * render defaults do not apply. */
        cli_common copy = *c;
        copy.given = ~0u;
        return cli_load_scene_file(a, &copy, scene, NULL);
    }
    if ((uint64_t)c->width * c->height > TR_FILM_MAX_PIXELS) {
        return cli_error(a, "--width/--height: %ux%u is more than %u pixels", c->width, c->height,
                         TR_FILM_MAX_PIXELS);
    }
    tr_error err;
    const tr_model_options size = {0, 1.0f, c->width, c->height, NULL};
    if (tr_scene_load(scene, c->scene, &size, NULL, &err) != TR_OK) {
        return cli_error(a, "--scene: %s", err.msg);
    }
    if (c->light_sampling >= 0) {
        tr_scene_set_light_sampling(scene, c->light_sampling, NULL);
    }
    if (tr_scene_commit(scene, c->accel, &err) != TR_OK) {
        fprintf(stderr, "trac0r %s: %s\n", a->cmd, err.msg);
        tr_scene_clear(scene);
        return CLI_FAILURE;
    }
    return CLI_OK;
}

void cli_describe_accel(char *buf, size_t n, const tr_scene *s) {
    tr_accel_info info;
    tr_scene_accel_info(s, &info);
    if (info.type == TR_ACCEL_TYPE_BVH) {
        /* The traversal's ISA is chosen at run time; a TRAC0R_ISA the CPU (or build)
         * cannot honour is said here rather than silently replaced. */
        const char *asked = getenv("TRAC0R_ISA");
        char note[96] = "";
        if (asked && *asked && strcmp(asked, info.wide_isa) != 0) {
            snprintf(note, sizeof note, ", TRAC0R_ISA=%.40s unavailable", asked);
        }
        snprintf(buf, n,
                 "bvh (%u-wide %s%s: %u nodes, %u leaves, depth %u, from %u binary nodes; built "
                 "in %.1f ms, %.1f ms of it the collapse)",
                 info.wide_width, info.wide_isa, note, info.wide_nodes, info.wide_leaves,
                 info.wide_depth, info.bvh_nodes, tr_scene_bvh_build_seconds(s) * 1e3,
                 info.wide_seconds * 1e3);
    } else if (info.type == TR_ACCEL_TYPE_BVH2) {
        snprintf(buf, n, "bvh2 (%u nodes, %u leaves, depth %u, built in %.1f ms)", info.bvh_nodes,
                 info.bvh_leaves, info.bvh_depth, info.bvh_seconds * 1e3);
    } else if (info.type == TR_ACCEL_TYPE_EMBREE) {
        snprintf(buf, n, "embree (built in %.1f ms)", info.embree_seconds * 1e3);
    } else {
        snprintf(buf, n, "flat (%u shape boxes)", tr_scene_shape_count(s));
    }
}
