/* render_job.h - one `trac0r render` as the single-process flow (render.c) and the MPI
 * flow (render_mpi.c) share it: the options, the scene and device, and the session
 * (include/trac0r/session.h) that renders. */
#ifndef TRAC0R_RENDER_JOB_H
#define TRAC0R_RENDER_JOB_H

#include "cli.h"
#include "devices.h"
#include "trac0r/session.h"

typedef struct render_job {
    cli_args args;
    cli_common common;
    tr_scene *scene;
    cli_backend be;
    int be_open;
    tr_render_config cfg;
    uint32_t spp;
    int spp_given;
    int stride; /* --stride */
    float exposure;
    const char *out;
    int exr_half;             /* --exr-type half */
    uint32_t passes;          /* TR_PASS_* written as files or EXR layers (--passes); the
                                 session adds --denoise's guides to the film */
    int curve;                /* --tonemap: TR_TONEMAP_* (PNG only) */
    int denoise;              /* --denoise */
    char pass_paths[5][4096]; /* PFM paths of the passes, by bit (not for EXR) */
    const char *checkpoint;   /* --checkpoint FILE or NULL */
    double checkpoint_interval;
    const char *resume;    /* --resume FILE or NULL */
    float noise_threshold; /* --noise-threshold (0: off) */
    float time_limit;      /* --time-limit seconds (0: none) */
    int verbose;           /* --verbose: where the time went */
    int no_denoise;        /* --no-denoise */
    int auto_spp;          /* no sample count stated: adaptive to a threshold, denoised */
    double started;        /* tr_time_now() when the setup began */
} render_job;

/* Parses the command line, loads the scene and opens the device. Returns CLI_OK with
 * *done = 0 when the job is ready (render_job_free releases it), or an exit status with
 * *done = 1 (help printed, or an error reported). */
int render_job_setup(render_job *job, int argc, char **argv, int *done);
void render_job_free(render_job *job);

/* Without a stated sample count: samples up to this cap (64: a cap of 4096 kept a few
 * tiles rendering for thousands of small passes, minutes on the box at threshold 0.1;
 * 64 denoised measured 38.9 dB in 7 s, docs/log/2026-denoise.md), adaptively to this noise
 * threshold (--noise-threshold when given), and denoised unless --no-denoise. */
#define RENDER_AUTO_SPP_CAP 64u
#define RENDER_AUTO_THRESHOLD 0.01f
/* Turns those defaults on when the job states no sample count and may sample adaptively
 * (every pixel traced, no checkpoint, a single process); render_job_setup calls it. */
void render_apply_defaults(render_job *job, int stride, int file_has_spp);

/* The session's settings the options describe (progress left to the caller). */
tr_session_desc render_session_desc(const render_job *job);
/* Reports a failed tr_session_create: a checkpoint of another render, a damaged one or
 * settings that do not go together are the command line's (exit 2), the rest exit 1. */
int render_session_error(render_job *job, const tr_error *err);

/* Writes the session's image (and its passes) and the summary line, with `stopped` (NULL:
 * none) saying why the render ended early. CLI_OK or CLI_FAILURE. */
int render_write_outputs(const render_job *job, tr_session *s, uint32_t samples, double elapsed,
                         uint64_t rays, const char *stopped);

#ifdef TRAC0R_HAVE_MPI
/* Whether this process was started by mpirun (and MPI should be used). */
int render_mpi_wanted(void);
/* `trac0r render` under MPI: tiles handed out by rank 0 (render_mpi.c); returns the
 * exit status. */
int render_mpi_main(int argc, char **argv);
#endif

#endif
