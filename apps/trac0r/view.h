/* view.h - `trac0r view`: options shared by its parts. */
#ifndef TRAC0R_VIEW_H
#define TRAC0R_VIEW_H

#include <stdint.h>

#include "cli.h"
#include "devices.h"

typedef struct view_options {
    cli_common c;
    uint32_t frames;        /* headless: frames to render (0: not given) */
    const char *screenshot; /* headless output image */
    int benchmark;          /* complexity level, -1: none */
    int stride;             /* initial preview stride: 1, 2 or 4 */
    float exposure;
    float target_fps;             /* --target-fps: the frame budget while moving */
    int recon;                    /* --recon: tr_recon_method shown (M cycles) */
    tr_recon_params recon_params; /* its settings (--svgf-iterations, ...) */
    int curve;                    /* --tonemap: tr_tonemap_curve_kind */
    uint32_t max_spp;             /* stop accumulating after this many (0: never) */
    int animate;                  /* --animate: the scene's last shape moves every frame */
    const char *font;             /* --font, or NULL for fontconfig */
    const char *state_file;       /* rewritten with the viewer's state after changes */
    const char *dump_file;        /* SIGUSR1 writes the window's pixels here (PPM) */
    const char *shot_dir;         /* where F12 writes (default ".") */
    char font_path[4096];         /* the font found for the debug view */
    char bench_scene[64];         /* --benchmark's scene name */
} view_options;

/* The interactive window (view_window.c), rendering on `be` (the CPU or an OpenCL device
 * holding the scene); returns the exit status. */
int view_run_window(const cli_args *a, const view_options *o, tr_scene *scene, cli_backend *be);

#endif
