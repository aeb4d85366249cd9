/* bench_realtime.c - `trac0r bench realtime`: the thesis's question, how much noise is
 * too much, answered per reconstruction method. A camera moves along a path through the
 * scene; every frame is rendered once with few samples and handed to every method (raw,
 * accumulate, bilateral, à-trous, SVGF); each output is compared with a converged
 * reference of that same frame: PSNR (the reference's own error taken out, as in `bench
 * convergence`), SSIM, and a temporal flicker measure; per stage the milliseconds. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench.h"
#include "cli.h"
#include "devices.h"
#include "trac0r/measure.h"

typedef tr_frame_scores rt_frame_stats;

static void realtime_help(FILE *fp) {
    fprintf(fp,
            "Usage: trac0r bench realtime [SCENE] [options]\n"
            "\n"
            "Renders frames along a moving camera path (SCENE: builtin:cornell), runs each\n"
            "reconstruction method on them, scores and times it; writes PREFIX.csv and .png.\n"
            "The full manual: man trac0r (docs/cli.md, docs/realtime.md).\n"
            "\n"
            "Options:\n"
            "  --width W, --height H   frame size (default 320x240)\n"
            "  --frames N           frames along the path, 2..100000 (default 32)\n"
            "  --spp S              samples per pixel per frame, 1..1024 (default 1)\n"
            "  --reference-spp R    samples of each frame's reference, 2..1000000 (default 256)\n"
            "  --cut K              jump to another view at frame K (default: no cut)\n"
            "  --upscale N          trace 1/N of the pixels and upscale, 1..16 (default 1)\n"
            "  --fraction F         the same as a fraction: 1/2, 1/4, 0.5, 0.25, ½, ¼\n"
            "  --psr on|off         primary surface replacement in the frames' passes (on)\n"
            "  --region X,Y,W,H     also score the pixels of this rectangle (PSNR)\n"
            "  --animate            the scene's last shape moves before every frame\n"
            "  --animate-frames A:B   the same, only before frames A to B-1\n"
            "  --animate-light switch|move   the lights go off and on, or move, every frame\n"
            "  --bias-reference-depth D2   also measure the depth limit's bias against D2\n"
            "  --methods LIST       of off,accumulate,bilateral,atrous,svgf (default all)\n"
            "  --seed S, --threads T, --max-depth D, --accel NAME, --device D   as for render\n"
            "  --sampler NAME, --light-sampling NAME   as for render (frames: random)\n"
            "  --roulette-start N   as for render (frames: 2, references: 5)\n"
            "  --clamp-indirect V, --regularize on|off   the frames' firefly control (4, on)\n"
            "  --reference-sampler NAME   the references' sampler (default sobol)\n"
            "  --out PREFIX         output file prefix (default realtime)\n"
            "  -h, --help           show this help\n"
            "\n"
            "The reconstruction's settings:\n");
    fputs(cli_recon_help, fp);
}

static int parse_methods(cli_args *a, int on[TR_RECON_COUNT]) {
    int m[4 * TR_RECON_COUNT];
    const int n = cli_parse_list(a, tr_recon_parse, m, 4 * TR_RECON_COUNT, "method",
                                 "off, accumulate, bilateral, atrous, svgf");
    memset(on, 0, TR_RECON_COUNT * sizeof *on);
    for (int i = 0; i < n; ++i) {
        on[m[i]] = 1;
    }
    return n < 0 ? CLI_USAGE : CLI_OK;
}

/* Per method, the frames from `until` on to return to within 0.5 dB of the PSNR over
 * frames [from, until) (tr_recovery_frames; over the region's pixels with `region`: after
 * --animate-frames A:B, the moving shape's before it moved), then a newline. */
static void print_recovery(const rt_frame_stats *st, const int *on, uint32_t frames, uint32_t from,
                           uint32_t until, int region) {
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        double steady = NAN;
        const int n = on[m] ? tr_recovery_frames(st + (size_t)m * frames, frames, from, until,
                                                 region, 0.5, &steady)
                            : 0;
        if (on[m]) {
            printf(steady != steady ? " %s -"
                   : n >= 0         ? " %s %d"
                                    : " %s never",
                   tr_recon_name(m), n);
        }
    }
    printf("\n");
}

/* "A:B" with 1 <= A < B <= 100000 into *from, *until. */
static int parse_window(cli_args *a, uint32_t *from, uint32_t *until) {
    if (cli_value(a) != CLI_OK) {
        return CLI_USAGE;
    }
    char *end = NULL;
    errno = 0;
    const unsigned long x = strtoul(a->value, &end, 10);
    unsigned long y = 0;
    int good = end != a->value && *end == ':' && a->value[0] != '-' && errno == 0;
    if (good) {
        const char *rest = end + 1;
        y = strtoul(rest, &end, 10);
        good = end != rest && *end == '\0' && *rest != '-' && errno == 0;
    }
    if (!good || x < 1 || y <= x || y > 100000) {
        return cli_error(a, "%s: expected A:B with 1 <= A < B <= 100000, got '%s'", a->opt,
                         a->value);
    }
    *from = (uint32_t)x;
    *until = (uint32_t)y;
    return CLI_OK;
}

/* PREFIX.png (gnuplot, bench_plot_png): each method's PSNR per frame (the cut marked,
 * 30 dB dashed) and its frame time, render + reconstruction (16.7 and 33.3 ms dashed).
 * As bench_plot_png: 1 written, 0 no gnuplot, -1 the file could not be written. */
static int plot_realtime(const rt_frame_stats *st, const int *on, uint32_t frames, uint32_t cut,
                         const char *scene, const char *png, tr_error *err) {
    const size_t cap = 4096 + (size_t)TR_RECON_COUNT * (frames * 40u + 64u);
    char *script = malloc(cap);
    if (!script) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%.200s: out of memory", png);
        return -1;
    }
    size_t len = 0;
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        if (!on[m]) {
            continue;
        }
        bench_plot_put(script, cap, &len, "$d%d << EOD\n", m);
        for (uint32_t f = 0; f < frames; ++f) {
            const rt_frame_stats *s = &st[(size_t)m * frames + f];
            const double total = s->render_ms + s->temporal_ms + s->spatial_ms;
            /* An identical frame's PSNR is infinite: left out of the PSNR panel. */
            bench_plot_put(script, cap, &len, "%u %.4f %.4f\n", f,
                           isfinite(s->psnr) ? s->psnr : NAN, total);
        }
        bench_plot_put(script, cap, &len, "EOD\n");
    }
    char name[64];
    bench_plot_name(scene, name, sizeof name);
    bench_plot_put(script, cap, &len,
                   "set multiplot layout 1,2\nset grid\nset key below\n"
                   "set xlabel 'frame'\nset datafile missing 'nan'\n");
    if (cut) {
        bench_plot_put(script, cap, &len,
                       "set arrow 1 from %u, graph 0 to %u, graph 1 nohead dt 2 lw 2 lc 'black'\n"
                       "set label 1 'cut' at %u, graph 0.97 offset 0.5, 0\n",
                       cut, cut, cut);
    }
    for (int panel = 0; panel < 2; ++panel) {
        bench_plot_put(script, cap, &len, "set ylabel '%s'\nset title '%s: %s'\n",
                       panel == 0 ? "PSNR (dB)" : "render + reconstruction (ms)", name,
                       panel == 0 ? "PSNR per frame" : "frame time");
        bench_plot_put(script, cap, &len, "%splot ", panel == 0 ? "" : "set yrange [0:*]\n");
        int first = 1;
        for (int m = 0; m < TR_RECON_COUNT; ++m) {
            if (!on[m]) {
                continue;
            }
            bench_plot_put(script, cap, &len, "%s$d%d using 1:%d with linespoints lw 2 title '%s'",
                           first ? "" : ", ", m, panel == 0 ? 2 : 3, tr_recon_name(m));
            first = 0;
        }
        bench_plot_put(script, cap, &len, "%s\n",
                       panel == 0 ? ", 30 dt 2 lc 'gray' notitle"
                                  : ", 16.67 dt 2 lc 'gray' notitle, 33.33 dt 2 lc "
                                    "'gray' notitle");
    }
    bench_plot_put(script, cap, &len, "unset multiplot\n");
    const int plotted = len < cap ? bench_plot_png(script, png, err) : 0;
    free(script);
    return plotted;
}

/* The command's options. */
typedef struct rt_opts {
    cli_common c;
    uint32_t frames, spp, ref_spp, cut, bias_depth;
    int on[TR_RECON_COUNT];
    tr_recon_params params;         /* the library's defaults unless an option sets one */
    int ref_sampler;                /* TR_SAMPLER_*, -1: sobol, whatever the frames' */
    int animate;                    /* --animate: the scene's last shape moves every frame */
    uint32_t anim_from, anim_until; /* it moves before frames from .. until - 1 */
    char csv_path[4096], png_path[4096];
    uint32_t upscale; /* --upscale: frames trace 1/upscale of the pixels (1: every one) */
    /* --animate-light: TR_LIGHT_ANIMATION_* */
    int animate_light;
    int psr;            /* --psr: 0 on (default), -1 off */
    uint32_t region[4]; /* --region: x, y, width, height (width 0: none) */
} rt_opts;

/* One run: the scene, the device, the real-time loop and the measures. */
typedef struct rt_run {
    cli_args *a;
    const rt_opts *o;
    tr_scene *scene;
    cli_backend be;
    tr_realtime *rt;
    int host;       /* the reconstruction runs on the host (its passes there) */
    tr_camera cam0; /* the path's start, at the frames' size */
    float diag;     /* the scene's diagonal: the path's scale */
    size_t px;
    tr_render_config rcfg; /* the references' */
    int frame_sampler;     /* the frames' sampler, for the header */
    uint32_t frame_passes; /* the frames' passes, which the references keep too */
    int depth;
    tr_scorer *sc;               /* the references and the scores */
    double bias_mse, bias_own;   /* --bias-reference-depth's measures */
    rt_frame_stats *st;          /* per method and frame */
    uint32_t shape_lo, shape_hi; /* --animate: the moving shape's ids */
    double resolve_sum_ms;       /* tr_resolve_emission over the frames */
    uint64_t resolve_px;
    /* --upscale: the same pipeline tracing every pixel, on the same frames. */
    cli_backend be_full; /* its own device: one film size each */
    tr_realtime *rt_full;
    rt_frame_stats *st_full;
} rt_run;

/* One of the benchmark's own options: CLI_OK, CLI_USAGE, or -1 if it is none of them. */
static int own_option(cli_args *a, void *user) {
    rt_opts *o = user;
    int rc = -1;
    if (cli_is(a, "--frames")) {
        rc = cli_parse_u32(a, 2, 100000, &o->frames);
    } else if (cli_is(a, "--spp")) {
        rc = cli_parse_u32(a, 1, 1024, &o->spp);
    } else if (cli_is(a, "--reference-spp")) {
        rc = cli_parse_u32(a, 2, 1000000, &o->ref_spp);
    } else if (cli_is(a, "--bias-reference-depth")) {
        rc = cli_parse_u32(a, 1, TR_MAX_DEPTH_LIMIT, &o->bias_depth);
    } else if (cli_is(a, "--reference-sampler")) {
        rc = cli_parse_sampler(a, &o->ref_sampler);
    } else if ((rc = cli_recon_option(a, &o->params)) != -1 ||
               (rc = cli_restir_option(a, &o->c)) != -1) {
        /* handled: rc is CLI_OK or CLI_USAGE */
    } else if (cli_is(a, "--psr")) {
        int on = 1;
        rc = cli_parse_on_off(a, &on);
        o->psr = on ? 0 : -1;
    } else if (cli_is(a, "--region")) {
        if ((rc = cli_value(a)) == CLI_OK &&
            tr_parse_rect(a->value, TR_FILM_MAX_SIDE, o->region) != TR_OK) {
            rc =
                cli_error(a, "--region: expected X,Y,W,H with W and H above 0, got '%s'", a->value);
        }
    } else if (cli_is(a, "--animate")) {
        o->animate = 1;
        rc = CLI_OK;
    } else if (cli_is(a, "--animate-frames")) {
        o->animate = 1;
        rc = parse_window(a, &o->anim_from, &o->anim_until);
    } else if (cli_is(a, "--animate-light")) {
        rc = cli_value(a);
        if (rc == CLI_OK) {
            o->animate_light = tr_light_animation_from_name(a->value);
            if (o->animate_light <= TR_LIGHT_ANIMATION_NONE) {
                rc = cli_error(a, "--animate-light: expected switch or move, got '%s'", a->value);
            }
        }
    } else if (cli_is(a, "--upscale")) {
        rc = cli_parse_u32(a, 1, 16, &o->upscale);
    } else if (cli_is(a, "--fraction")) { /* 1/N as "1/N", 0.25, ½ or ¼ (trac0r/parse.h) */
        if ((rc = cli_value(a)) == CLI_OK && tr_parse_fraction(a->value, 16, &o->upscale)) {
            rc = cli_error(a, "--fraction: expected 1/N for N in 1..16 (1/2, 0.25, ½, ...), got %s",
                           a->value);
        }
    } else if (cli_is(a, "--cut")) {
        rc = cli_parse_u32(a, 1, 100000, &o->cut);
    } else if (cli_is(a, "--methods")) {
        rc = parse_methods(a, o->on);
    } else if (cli_is(a, "--out")) {
        rc = cli_value(a);
        o->csv_path[0] = '\0';
        if (rc == CLI_OK && (snprintf(o->csv_path, sizeof o->csv_path, "%s.csv", a->value) >=
                                 (int)sizeof o->csv_path ||
                             snprintf(o->png_path, sizeof o->png_path, "%s.png", a->value) >=
                                 (int)sizeof o->png_path)) {
            o->csv_path[0] = '\0';
        }
    } else if (a->opt[0] != '-' && a->i == 1) {
        o->c.scene = a->opt;
        rc = CLI_OK;
    }
    return rc;
}

/* Parses the command line into o: CLI_OK to run, CLI_HELP, or the status to return. */
static int parse_options(cli_args *a, rt_opts *o) {
    const int rc = cli_parse(a, &o->c, NULL, realtime_help, own_option, o);
    if (rc != CLI_OK) {
        return rc;
    }
    if (o->cut >= o->frames) {
        return cli_error(a, "--cut: expected a frame before --frames (%u), got %u", o->frames,
                         o->cut);
    }
    if (o->upscale > 1 && (o->animate || o->animate_light)) {
        /* The scene's motion goes to one real-time loop, not to two. */
        return cli_error(a, "--upscale: not with --animate or --animate-light");
    }
    if (o->anim_until > o->frames) {
        return cli_error(a, "--animate-frames: expected B up to --frames (%u), got %u", o->frames,
                         o->anim_until);
    }
    if (!o->anim_until) {
        o->anim_until = o->frames;
    }
    if (!o->csv_path[0]) {
        return cli_error(a, "--out: prefix too long");
    }
    tr_error err;
    if (tr_image_check_writable(o->csv_path, &err) != TR_OK ||
        tr_image_check_writable(o->png_path, &err) != TR_OK) {
        return cli_error(a, "--out: %s", err.msg);
    }
    return CLI_OK;
}

/* Loads the scene and sets the path's camera; CLI_OK or the status to return. */
static int load_scene(rt_run *r, rt_opts *o) {
    r->scene = tr_scene_create(NULL);
    int rc = cli_load_scene_file(r->a, &o->c, r->scene, NULL);
    if (rc != CLI_OK) {
        return rc;
    }
    /* The integrator may come from the scene file: checked once it is loaded. */
    if (tr_integrator_is_bidirectional(o->c.integrator) && o->bias_depth > TR_MAX_DEPTH_BDPT) {
        return cli_error(r->a, "--bias-reference-depth: %s supports at most %d, got %u",
                         tr_integrator_name(o->c.integrator), TR_MAX_DEPTH_BDPT, o->bias_depth);
    }
    tr_error err;
    r->cam0 = *tr_scene_camera(r->scene);
    if (tr_camera_resize(&r->cam0, o->c.width, o->c.height, &err) != TR_OK) {
        return cli_error(r->a, "--width/--height: %s", err.msg);
    }
    const tr_aabb b = tr_scene_bounds(r->scene);
    const tr_vec3 d = tr_vec3_make(b.max.x - b.min.x, b.max.y - b.min.y, b.max.z - b.min.z);
    const float diag = sqrtf(d.x * d.x + d.y * d.y + d.z * d.z);
    r->diag = diag > 0.0f && isfinite(diag) ? diag : 1.0f;
    r->px = (size_t)o->c.width * o->c.height;
    return CLI_OK;
}

/* The scorer and the table's rows; CLI_OK or the status to return. */
static int alloc_buffers(rt_run *r) {
    tr_error err;
    r->st = calloc((size_t)TR_RECON_COUNT * r->o->frames, sizeof *r->st);
    if (!r->st ||
        !(r->sc = tr_scorer_create(r->o->c.width, r->o->c.height, 2 * TR_RECON_COUNT, &err))) {
        fprintf(stderr, "trac0r bench realtime: %s\n", r->st ? err.msg : "out of memory");
        return CLI_FAILURE;
    }
    const uint32_t *g = r->o->region;
    if (g[2] > 0 && tr_scorer_region_rect(r->sc, g) == 0) {
        fprintf(stderr, "trac0r bench realtime: --region %u,%u,%u,%u: outside the %ux%u frame\n",
                g[0], g[1], g[2], g[3], r->o->c.width, r->o->c.height);
        return CLI_USAGE;
    }
    return CLI_OK;
}

/* The device, the real-time loop (the frames' settings) and the references' config. */
static int open_loop(rt_run *r) {
    const rt_opts *o = r->o;
    tr_error err;
    int rc = cli_backend_open(r->a, &o->c, r->scene, &r->be);
    if (rc != CLI_OK) {
        return rc;
    }
    const tr_render_config cfg = cli_render_config(&o->c);
    /* The frames' sampler is TR_SAMPLER_REALTIME unless given, and their roulette starts
     * early (TR_ROULETTE_START_REALTIME unless given): realtime.h. */
    tr_realtime_desc desc = {0};
    desc.config = &cfg;
    desc.recon = &o->params;
    desc.sampler = o->c.sampler >= 0 ? TR_REALTIME_SAMPLER(o->c.sampler) : 0;
    desc.spp = o->spp;
    desc.animated = o->animate || o->animate_light;
    desc.keep_passes = 1; /* one frame goes to every method */
    cli_realtime_firefly(&o->c, &desc.clamp_indirect, &desc.regularize);
    desc.psr = o->psr;
    desc.restir = o->c.restir;
    desc.restir_unbiased = o->c.restir_unbiased;
    if (!(r->rt = tr_realtime_create(r->be.dev, r->scene, &desc, &err))) {
        fprintf(stderr, "trac0r bench realtime: %s\n", err.msg);
        return CLI_FAILURE;
    }
    if (o->upscale > 1) {
        rc = cli_backend_open(r->a, &o->c, r->scene, &r->be_full);
        if (rc != CLI_OK) {
            return rc;
        }
        r->rt_full = tr_realtime_create(r->be_full.dev, r->scene, &desc, &err);
        r->st_full = calloc((size_t)TR_RECON_COUNT * o->frames, sizeof *r->st_full);
        if (!r->rt_full || !r->st_full) {
            fprintf(stderr, "trac0r bench realtime: %s\n", r->rt_full ? "out of memory" : err.msg);
            return CLI_FAILURE;
        }
    }
    r->host = !tr_realtime_on_device(r->rt);
    r->frame_sampler = o->c.sampler >= 0 ? o->c.sampler : TR_SAMPLER_REALTIME;
    r->frame_passes = tr_realtime_passes(r->rt, TR_RECON_SVGF);
    /* The references keep the frames' passes too, although only their radiance is read
     * (the passes do not change it): a device keeps one film for one set of passes, and
     * alternating them reallocated the device's film twice per frame, inside the timed
     * render. */
    r->rcfg = cfg;
    r->rcfg.passes = r->frame_passes;
    /* The references' seed differs from the frames', so their noise is independent. */
    r->rcfg.seed = o->c.seed ^ 0x7265666572656e63ULL;
    /* The references keep the offline sampler (sobol) unless --reference-sampler names
     * one, and the offline roulette start, the least error per sample, whatever
     * --roulette-start the frames have (both are unbiased). */
    r->rcfg.sampler = o->ref_sampler >= 0 ? o->ref_sampler : TR_SAMPLER_SOBOL;
    r->rcfg.roulette_start = TR_ROULETTE_START_PT;
    r->rcfg.clamp_indirect = 0.0f; /* the references are unbiased */
    r->rcfg.regularize = 0;
    /* Frames and references alike are rendered at this depth. */
    r->depth = cfg.max_depth ? cfg.max_depth : tr_default_max_depth(cfg.integrator);
    return CLI_OK;
}

/* --animate: the moving shape's ids in the id pass (triangle index + 1: the last shape's
 * triangles come last). */
static int setup_shape(rt_run *r) {
    const rt_opts *o = r->o;
    const uint32_t ids = tr_scene_triangle_count(r->scene) + 1u;
    r->shape_lo = r->shape_hi = 1u;
    if (tr_scene_shape_count(r->scene) > 0) {
        const uint32_t last = tr_scene_shape_count(r->scene) - 1u;
        r->shape_hi = ids;
        r->shape_lo = ids - tr_scene_shape_triangle_count(r->scene, last);
    }
    if (o->anim_from == 1 && o->anim_until == o->frames) {
        printf("animated: the scene's last shape moves every frame\n");
    } else {
        printf("animated: the scene's last shape moves before frames %u to %u\n", o->anim_from,
               o->anim_until - 1);
    }
    return CLI_OK;
}

static void print_header(const rt_run *r) {
    const rt_opts *o = r->o;
    const tr_recon_params *p = &o->params;
    printf("bench realtime: %s %ux%u, %u frames at %u spp, references %u spp, max depth %d, "
           "%s%s\n",
           o->c.scene, o->c.width, o->c.height, o->frames, o->spp, o->ref_spp, r->depth, r->be.name,
           o->cut ? ", camera cut" : "");
    if (o->cut) {
        printf("camera cut at frame %u\n", o->cut);
    }
    printf("samplers: frames %s, references %s\n", cli_sampler_name(r->frame_sampler),
           cli_sampler_name(r->rcfg.sampler));
    printf("reconstruction: alpha-min %g (svgf %g), max-history %g, max-history-moving %g, "
           "svgf-iterations %d, svgf-sigma-l %g, taa %g, svgf-split %s, gradients %s\n",
           (double)p->alpha_min, (double)p->svgf_alpha_min, (double)p->max_len,
           (double)p->max_len_moving, p->svgf_iterations, (double)p->svgf_sigma_l,
           (double)p->svgf_taa_alpha, p->svgf_split ? "on" : "off", p->gradients ? "on" : "off");
    if (!(r->frame_passes & TR_PASS_EMISSION)) {
        printf("emission: filtered with the rest (%s)\n",
               p->emission_samples == 0 ? "--resolve-emission 0"
                                        : "the emission pass needs --integrator pt");
    } else if (!r->host) {
        printf("emission: kept out of the filters, resolved on the OpenCL device with %d x "
               "%d rays per pixel on emitter edges (its time counted in temporal_ms)\n",
               p->emission_samples, p->emission_samples);
    } else {
        printf("emission: kept out of the filters, resolved with %d x %d rays per pixel on "
               "emitter edges (its time counted in temporal_ms)\n",
               p->emission_samples, p->emission_samples);
    }
}

/* Frame f's reference (and at frame 0 the depth limit's bias). */
static int frame_reference(rt_run *r, const tr_camera *cam, uint32_t f) {
    const rt_opts *o = r->o;
    tr_error err;
    if (tr_scorer_reference(r->sc, r->be.dev, cam, &r->rcfg, o->ref_spp, &err) != TR_OK) {
        fprintf(stderr, "trac0r bench realtime: reference of frame %u: %s\n", f, err.msg);
        return CLI_FAILURE;
    }
    if (f == 0 && o->bias_depth) {
        /* The bias of the depth limit: frame 0's reference against one at bias_depth,
         * with another seed so that the two references' noise is independent. */
        tr_render_config bcfg = r->rcfg;
        bcfg.max_depth = (int)o->bias_depth;
        bcfg.seed = r->rcfg.seed ^ 0x6269617364657074ULL;
        if (tr_scorer_bias(r->sc, r->be.dev, cam, &bcfg, o->ref_spp, &r->bias_mse, &r->bias_own,
                           &err) != TR_OK) {
            fprintf(stderr, "trac0r bench realtime: depth-%u reference of frame 0: %s\n",
                    o->bias_depth, err.msg);
            return CLI_FAILURE;
        }
    }
    return CLI_OK;
}

/* --upscale: frame f again through the same pipeline tracing every pixel, scored into
 * st_full (the scorer's slots after the methods' own). */
static int run_full(rt_run *r, const tr_realtime_frame_desc *fd, uint32_t f) {
    tr_error err;
    tr_realtime_frame_desc full = *fd;
    full.upscale = 0;
    if (tr_realtime_render(r->rt_full, &full, &err) != TR_OK) {
        fprintf(stderr, "trac0r bench realtime: frame %u, every pixel: %s\n", f, err.msg);
        return CLI_FAILURE;
    }
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        tr_realtime_result res;
        if (!r->o->on[m]) {
            continue;
        }
        if (tr_realtime_reconstruct(r->rt_full, m, &res, &err) != TR_OK) {
            fprintf(stderr, "trac0r bench realtime: %s, every pixel: %s\n", tr_recon_name(m),
                    err.msg);
            return CLI_FAILURE;
        }
        rt_frame_stats *s = &r->st_full[(size_t)m * r->o->frames + f];
        *s = tr_scorer_score(r->sc, TR_RECON_COUNT + m, res.rgb);
        s->render_ms = res.render_ms;
        s->temporal_ms = res.temporal_ms;
        s->spatial_ms = res.spatial_ms;
    }
    return CLI_OK;
}

/* --upscale: per method the upscaled pipeline against the same one tracing every pixel. */
static void report_full(const rt_run *r) {
    const rt_opts *o = r->o;
    const uint32_t frames = o->frames;
    printf("upscaled (1/%u of the pixels traced) against the same pipeline tracing every "
           "pixel:\n",
           o->upscale);
    printf("%-11s %9s %9s %9s %9s %10s\n", "method", "fps_up", "fps_full", "psnr_up", "psnr_full",
           "difference");
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        if (!o->on[m]) {
            continue;
        }
        const tr_scores_summary up = tr_scores_summarize(r->st + (size_t)m * frames, 0, frames);
        const tr_scores_summary full =
            tr_scores_summarize(r->st_full + (size_t)m * frames, 0, frames);
        printf("%-11s %9.1f %9.1f %9.2f %9.2f %+10.2f\n", tr_recon_name(m), up.fps, full.fps,
               up.mean.psnr, full.mean.psnr, up.mean.psnr - full.mean.psnr);
    }
}

/* Frame f: the scene moved (--animate), its reference, the frame rendered once and
 * handed to every method. */
static int run_frame(rt_run *r, uint32_t f) {
    const rt_opts *o = r->o;
    tr_error err;
    tr_camera cam;
    if (tr_camera_path(&r->cam0, r->diag, f, o->frames, o->cut, &cam, &err) != TR_OK) {
        fprintf(stderr, "trac0r bench realtime: frame %u camera: %s\n", f, err.msg);
        return CLI_FAILURE;
    }
    if (o->animate || o->animate_light) {
        /* Outside the timed render: the scene's update is not the reconstruction's. The
         * shape's own frame count: 1 at the first frame it moves, 0 (no move) outside; the
         * lights in their state of frame f. */
        const uint32_t af = f >= o->anim_from && f < o->anim_until ? f - o->anim_from + 1 : 0;
        if ((o->animate && tr_scene_animate_sway(r->scene, af, &err) != TR_OK) ||
            (o->animate_light && tr_scene_animate_light(r->scene, f, o->animate_light, &err)) ||
            tr_scene_update(r->scene, NULL, &err) != TR_OK) {
            fprintf(stderr, "trac0r bench realtime: --animate: frame %u: %s\n", f, err.msg);
            return CLI_FAILURE;
        }
        const int rc = cli_backend_upload(r->a, &r->be, r->scene);
        if (rc != CLI_OK) {
            return rc;
        }
    }
    int rc = frame_reference(r, &cam, f);
    if (rc != CLI_OK) {
        return rc;
    }
    /* The frame itself: samples numbered by frame, so that noise changes over time. */
    tr_realtime_frame_desc fd = {0};
    fd.camera = &cam;
    fd.upscale = (int)o->upscale;
    if (tr_realtime_render(r->rt, &fd, &err) != TR_OK) {
        fprintf(stderr, "trac0r bench realtime: frame %u: %s\n", f, err.msg);
        return CLI_FAILURE;
    }
    int first = 1;
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        if (!o->on[m]) {
            continue;
        }
        tr_realtime_result res;
        if (tr_realtime_reconstruct(r->rt, m, &res, &err) != TR_OK) {
            fprintf(stderr, "trac0r bench realtime: %s: %s\n", tr_recon_name(m), err.msg);
            return CLI_FAILURE;
        }
        if (first) {
            /* The emitters' edges were resolved once for every method. With a moving
             * shape and the frame's id pass on the host, its pixels are scored apart. */
            r->resolve_sum_ms += res.resolve_ms;
            r->resolve_px += res.resolved;
            const tr_gbuffer *g = tr_realtime_gbuffer(r->rt);
            if (o->animate && g) {
                tr_scorer_region(r->sc, g->prim, r->shape_lo, r->shape_hi);
            } else if (o->region[2] > 0) {
                tr_scorer_region_rect(r->sc, o->region);
            }
            first = 0;
        }
        rt_frame_stats *s = &r->st[(size_t)m * o->frames + f];
        *s = tr_scorer_score(r->sc, m, res.rgb);
        s->render_ms = res.render_ms;
        s->temporal_ms = res.temporal_ms;
        s->spatial_ms = res.spatial_ms;
    }
    if (r->rt_full && run_full(r, &fd, f) != CLI_OK) {
        return CLI_FAILURE;
    }
    return CLI_OK;
}

/* Method m's row of the table (with the frames to recover after a cut) and its CSV rows. */
static void report_method(const rt_run *r, int m, FILE *csv) {
    const rt_opts *o = r->o;
    const uint32_t frames = o->frames, cut = o->cut;
    const rt_frame_stats *st = r->st;
    for (uint32_t f = 0; f < frames; ++f) {
        const rt_frame_stats *s = &st[(size_t)m * frames + f];
        fprintf(csv, "%s,%u,%.4f,%.4f,%.4f,%.4f,%.4f,%.5f,%.6f", tr_recon_name(m), f, s->render_ms,
                s->temporal_ms, s->spatial_ms, s->render_ms + s->temporal_ms + s->spatial_ms,
                s->psnr, s->ssim, s->flicker);
        if (o->animate) { /* empty where the shape was not seen or not measured */
            if (s->region_psnr == s->region_psnr) {
                fprintf(csv, ",%.4f", s->region_psnr);
            } else {
                fputc(',', csv);
            }
        }
        fputc('\n', csv);
    }
    const tr_scores_summary sum = tr_scores_summarize(st + (size_t)m * frames, 0, frames);
    const tr_frame_scores *mean = &sum.mean;
    printf("%-11s %9.2f %11.2f %10.2f %9.2f %7.1f %9.2f %9.2f %7.4f %8.5f", tr_recon_name(m),
           mean->render_ms, mean->temporal_ms, mean->spatial_ms, sum.total_ms, sum.fps, mean->psnr,
           sum.psnr_min, mean->ssim, mean->flicker);
    if (!cut) {
        printf("\n");
        return;
    }
    /* Recovered at the first frame from the cut on within 0.5 dB of the mean PSNR of the
     * (up to) 8 frames before it. */
    double steady = 0.0;
    const int rec_frames =
        tr_recovery_frames(st + (size_t)m * frames, frames, cut, cut, 0, 0.5, &steady);
    if (rec_frames >= 0) {
        printf(" %7d\n", rec_frames);
    } else {
        printf(" %7s\n", "never");
    }
}

/* --animate-light switch: per switch and method, the frames from the switch on to return
 * to within 0.5 dB of (or above) the mean PSNR of the lit frames before it (before a switch
 * off, the 8 frames before it; before a switch on, the 8 before the light went off). */
static void print_switch_recovery(const rt_frame_stats *st, const int *on, uint32_t frames) {
    const uint32_t half = TR_LIGHT_SWITCH_PERIOD / 2u;
    for (uint32_t e = half; e < frames; e += half) {
        const int off = !tr_light_animation_on(e);
        printf("light switched %s at frame %u, frames to recover:", off ? "off" : "on", e);
        print_recovery(st, on, frames, off ? e : e - half, e, 0);
    }
}

/* The lines after the table: the emission's resolve, the moving shape, the depth bias. */
/* Each method's mean PSNR over the region in frames [from, until), then a newline. */
static void print_region(const rt_run *r, uint32_t from, uint32_t until) {
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        if (r->o->on[m]) {
            const tr_scores_summary sum =
                tr_scores_summarize(r->st + (size_t)m * r->o->frames, from, until);
            printf(sum.region_frames > 0 ? " %s %.2f dB" : " %s -", tr_recon_name(m),
                   sum.mean.region_psnr);
        }
    }
    printf("\n");
}

static void report_extras(const rt_run *r) {
    const rt_opts *o = r->o;
    const uint32_t frames = o->frames;
    if (r->resolve_px > 0 || (r->host && (r->frame_passes & TR_PASS_EMISSION))) {
        printf("emission resolved: %.1f pixels and %.2f ms per frame (mean)\n",
               (double)r->resolve_px / frames, r->resolve_sum_ms / frames);
    }
    if (o->region[2] > 0) {
        printf("region %u,%u %ux%u, PSNR over its pixels (mean over the frames):", o->region[0],
               o->region[1], o->region[2], o->region[3]);
        print_region(r, 0, frames);
    }
    if (o->animate && r->host) {
        /* Ghosting of the moving shape: each method's PSNR over its pixels. */
        printf("moving shape, PSNR over its pixels (mean over the frames it moved):");
        print_region(r, o->anim_from, o->anim_until);
        if (o->anim_from >= 2 && o->anim_until < frames) {
            printf("moving shape stopped at frame %u, frames to return to its PSNR before it "
                   "moved:",
                   o->anim_until);
            print_recovery(r->st, o->on, frames, o->anim_from, o->anim_until, 1);
        }
    }
    if (o->animate_light == TR_LIGHT_ANIMATION_SWITCH) {
        print_switch_recovery(r->st, o->on, frames);
    }
    if (o->bias_depth) {
        /* The depth limit's own error, which no reconstruction can take out: the frames'
         * converged image against the deeper one. A bias below a tenth of the references'
         * own MSE is not resolved by them: only a bound is printed. */
        printf("bias of max depth %d against max depth %u (frame 0's references, %u spp "
               "each): ",
               r->depth, o->bias_depth, o->ref_spp);
        if (r->bias_mse > 0.1 * r->bias_own) {
            printf("PSNR %.2f dB (MSE %.3g; the references' own MSE %.3g taken out)\n",
                   tr_psnr(r->bias_mse > 1e-12 ? r->bias_mse : 1e-12), r->bias_mse, r->bias_own);
        } else {
            printf("PSNR above %.2f dB (MSE %.3g, below a tenth of the references' own "
                   "MSE %.3g: more --reference-spp resolve it)\n",
                   tr_psnr(0.1 * r->bias_own > 1e-12 ? 0.1 * r->bias_own : 1e-12), r->bias_mse,
                   r->bias_own);
        }
    }
}

/* The table, PREFIX.csv and PREFIX.png. */
static int report(const rt_run *r) {
    const rt_opts *o = r->o;
    FILE *csv = fopen(o->csv_path, "w");
    if (!csv) {
        fprintf(stderr, "trac0r bench realtime: cannot write %s\n", o->csv_path);
        return CLI_FAILURE;
    }
    fprintf(csv,
            "method,frame,render_ms,temporal_ms,spatial_ms,total_ms,psnr_db,ssim,"
            "flicker%s\n",
            o->animate ? ",shape_psnr_db" : "");
    printf("%-11s %9s %11s %10s %9s %7s %9s %9s %7s %8s", "method", "render_ms", "temporal_ms",
           "spatial_ms", "total_ms", "fps", "psnr_mean", "psnr_min", "ssim", "flicker");
    printf(o->cut ? " recover\n" : "\n");
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        if (o->on[m]) {
            report_method(r, m, csv);
        }
    }
    report_extras(r);
    if (r->rt_full) {
        report_full(r);
    }
    if (fclose(csv) != 0) {
        fprintf(stderr, "trac0r bench realtime: cannot write %s\n", o->csv_path);
        return CLI_FAILURE;
    }
    tr_error err;
    const int plotted =
        plot_realtime(r->st, o->on, o->frames, o->cut, o->c.scene, o->png_path, &err);
    if (plotted < 0) {
        fprintf(stderr, "trac0r bench realtime: %s\n", err.msg);
    }
    printf("wrote %s%s%s\n", o->csv_path, plotted > 0 ? " and " : " (gnuplot failed: no plot)",
           plotted > 0 ? o->png_path : "");
    return plotted < 0 ? CLI_FAILURE : CLI_OK;
}

static void free_run(rt_run *r) {
    tr_realtime_destroy(r->rt); /* before the device */
    tr_realtime_destroy(r->rt_full);
    if (r->be_full.dev) {
        cli_backend_close(&r->be_full);
    }
    free(r->st_full);
    if (r->be.dev) {
        cli_backend_close(&r->be);
    }
    tr_scorer_destroy(r->sc);
    free(r->st);
    tr_scene_destroy(r->scene);
}

/* Everything after the options: setup, the frames, the report. */
static int run_bench(cli_args *a, rt_opts *o) {
    rt_run r;
    memset(&r, 0, sizeof r);
    r.a = a;
    r.o = o;
    int rc = load_scene(&r, o);
    if (rc != CLI_OK) {
        free_run(&r);
        return rc;
    }
    rc = alloc_buffers(&r);
    if (rc == CLI_OK) {
        rc = open_loop(&r);
    }
    if (rc == CLI_OK) {
        print_header(&r);
    }
    if (rc == CLI_OK && o->animate) {
        rc = setup_shape(&r);
    }
    if (rc == CLI_OK && o->animate_light) {
        printf("animated light: %s%s\n", tr_light_animation_name(o->animate_light),
               o->animate_light == TR_LIGHT_ANIMATION_SWITCH
                   ? " (the emitters are off for frames 8-15, 24-31, ...)"
                   : " (the emitters sway along x, the sun turns, one period per 60 frames)");
    }
    const double t_start = tr_time_now();
    for (uint32_t f = 0; rc == CLI_OK && f < o->frames; ++f) {
        rc = run_frame(&r, f);
        if (rc == CLI_OK) {
            fprintf(stderr, "\rbench realtime: frame %u/%u (reference %u spp)  %.1f s ", f + 1,
                    o->frames, o->ref_spp, tr_time_now() - t_start);
        }
    }
    fputc('\n', stderr);
    if (rc == CLI_OK) {
        rc = report(&r);
    }
    free_run(&r);
    return rc;
}

int bench_realtime(int argc, char **argv) {
    cli_args a = {.cmd = "bench realtime", .argc = argc, .argv = argv, .i = 0};
    rt_opts o;
    memset(&o, 0, sizeof o);
    cli_common_default(&o.c);
    o.c.width = 320;
    o.c.height = 240;
    o.frames = 32;
    o.spp = 1;
    o.ref_spp = 256;
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        o.on[m] = 1;
    }
    o.params = tr_recon_params_default();
    o.ref_sampler = -1;
    o.anim_from = 1;
    snprintf(o.csv_path, sizeof o.csv_path, "realtime.csv");
    snprintf(o.png_path, sizeof o.png_path, "realtime.png");
    const int rc = parse_options(&a, &o);
    if (rc != CLI_OK) {
        return rc == CLI_HELP ? CLI_OK : rc;
    }
    return run_bench(&a, &o);
}
