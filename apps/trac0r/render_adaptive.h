/* render_adaptive.h - `trac0r render`'s passes with a noise threshold and a time budget.
 *
 * A pass adds one sample to every pixel still rendering. With a noise threshold the image
 * is divided into ADAPT_TILE x ADAPT_TILE tiles; at every power-of-two sample count
 * N >= 16 each tile's pixels are tested against the threshold, comparing the mean of the
 * first N samples with that of the first N/2 (Cycles' half-buffer test; with the Sobol
 * sampler each half is itself a stratified set), and a tile whose pixels' mean error
 * estimate is below the threshold stops. With a time limit the render stops before a pass that
 * would end after it. Both decisions happen only at pass boundaries and the first from film values
 * alone, so the image depends on the number of passes made, never on timing or threads: a render
 * that the budget stopped after k passes equals one asked for k samples. */
#ifndef TRAC0R_RENDER_ADAPTIVE_H
#define TRAC0R_RENDER_ADAPTIVE_H

#include <stdint.h>
#include <stdio.h>

#include "devices.h"

#define ADAPT_TILE 8u
#define ADAPT_FIRST_CHECK 16u

typedef struct adapt_options {
    uint32_t spp;          /* samples per pixel asked for */
    float noise_threshold; /* 0: off */
    double time_limit;     /* seconds, 0: none */
    int progress;          /* print progress to stderr */
} adapt_options;

typedef struct adapt_result {
    uint32_t passes;  /* samples of the pixels that never stopped */
    uint64_t samples; /* pixel samples traced in all */
    uint64_t rays;
    double seconds;
    uint32_t tiles, tiles_converged;
    int stopped_by_time;
} adapt_result;

/* The error estimate of one pixel: the L1 distance between the means of all N samples
 * (full) and of the first N/2 (half), over the square root of full's sum, so that the
 * threshold reads as a relative error that is looser where the image is dark (Poisson-like
 * perception; the normalisation of Cycles' adaptive sampling). */
double adapt_pixel_error(const float full[3], const float half[3]);

/* Renders the passes into be's film (read back with cli_backend_read). Returns TR_OK, or
 * TR_ERR with err set when a frame fails. */
int adapt_render(cli_backend *be, const tr_scene *scene, const tr_render_config *cfg,
                 const adapt_options *opt, adapt_result *res, tr_error *err);

#endif
