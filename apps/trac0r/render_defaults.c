/* render_defaults.c - what `trac0r render` does when no sample count is stated: adaptive
 * sampling to a noise threshold, up to a cap, and the offline denoiser on what it writes
 * (docs/cli.md). A stated --spp (or a scene file's render.spp) keeps the fixed count. */
#include "render_job.h"

void render_apply_defaults(render_job *job, int stride, int file_has_spp) {
    if (job->no_denoise) {
        job->denoise = 0;
    }
    /* Adaptive sampling needs every pixel traced and no checkpoint (its tiles stop on
     * tests of half-films a checkpoint does not keep): those renders keep 16 spp. */
    if (job->spp_given || file_has_spp || job->checkpoint || job->resume || stride > 1) {
        return;
    }
#ifdef TRAC0R_HAVE_MPI
    if (render_mpi_wanted()) {
        return;
    }
#endif
    job->auto_spp = 1;
    job->spp = RENDER_AUTO_SPP_CAP;
    if (job->noise_threshold == 0.0f) {
        job->noise_threshold = RENDER_AUTO_THRESHOLD;
    }
    if (!job->no_denoise) {
        job->denoise = 1;
    }
}
