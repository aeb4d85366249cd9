/* render_mpi.c - `trac0r render` under mpirun: one render shared by many processes.
 *
 * The library shares the session's tiles between the ranks (tr_session_share, session.h:
 * rank 0 hands them out and renders tiles itself, the pixels come back in batches, the
 * film ends bit-identical to a single process's); this file carries its messages over MPI
 * and does what is MPI's: the setup, the agreement that every rank renders the same image,
 * the exit status and the --verbose report. A rank waiting for a message sleeps between
 * probes (wait_message) rather than spinning in Open MPI's blocking calls.
 *
 * Setup errors (a bad option, a scene, a device a rank cannot open) are gathered: each
 * rank's stderr goes to a temporary file until every rank has set up, then the lowest
 * failing rank alone prints its message and every rank exits with its status. An error
 * while rendering reaches rank 0, which prints it once, and all ranks exit with status
 * 1. A signal to any rank stops the job: rank 0 writes the tiles done, marked stopped,
 * and every rank exits with 128 + the signal. Rank 0 alone writes files and prints
 * progress. */
#define _POSIX_C_SOURCE 200809L
#include <limits.h>
#include <math.h>
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "progress.h"
#include "render_job.h"
#include "stop.h"

/* The --verbose report, after the share (whose tags are 1..TR_SHARE_TAGS). */
enum { TAG_PHASES = TR_SHARE_TAGS + 1 };

/* Where this rank's time went, in seconds (--verbose): rank 0 gathers and prints them. */
enum {
    PH_SETUP,  /* options, scene, acceleration structure, device */
    PH_RENDER, /* inside the tiles' renders */
    PH_WAIT,   /* blocked for a message (a worker for its next tile, rank 0 at the end) */
    PH_SERVE,  /* rank 0: answering the workers between its tiles */
    PH_PIXELS, /* reading the device film, packing, sending or copying pixels */
    PH_TOTAL,  /* from the end of the setup to the end of the hand-out */
    PH_CPU,    /* user + system CPU time of the process, setup included */
    PH_TILES,  /* tiles this rank rendered */
    PH_COUNT
};
static double phase[PH_COUNT];

/* Waits for a message without spinning: Open MPI's blocking calls poll the network at
 * full speed, which takes a core that a rank rendering on the same machine (or another
 * job) could use. The probe is repeated with sleeps growing from 20 us to 1 ms: a tile
 * takes far longer, so the latency this adds is lost in it. */
static void wait_message(int source, int tag, MPI_Status *st) {
    long ns = 20000;
    for (;;) {
        int flag = 0;
        MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, st);
        if (flag) {
            return;
        }
        const struct timespec pause = {0, ns};
        nanosleep(&pause, NULL);
        ns = ns < 1000000 ? 2 * ns : ns;
    }
}

int render_mpi_wanted(void) {
    /* Set by Open MPI's launcher (and by PMIx / PMI launchers of other MPIs). */
    return getenv("OMPI_COMM_WORLD_SIZE") || getenv("PMIX_RANK") || getenv("PMI_RANK");
}

/* The side, in traced pixels, of the pieces the CPU device cuts a tile into (its OpenMP
 * threads share them out; rank 0 answers messages between them): at least 8 pieces per
 * thread, so the threads end a tile together, and at least 16 pieces, so rank 0 answers
 * within a sixteenth of a tile. The pieces do not change the image (every pixel is still
 * one thread's, its samples in order). */
static uint32_t piece_side(const tr_render_config *cfg) {
    const int threads = cfg->threads > 0 ? cfg->threads : tr_default_threads();
    const double side = floor((double)TR_SESSION_TILE / sqrt(8.0 * threads));
    return side < 1.0 ? 1u : (side > TR_SESSION_TILE / 4 ? TR_SESSION_TILE / 4 : (uint32_t)side);
}

/* mpirun passes SIGINT/SIGTERM to every rank and soon kills them: a tile under way is
 * dropped (its pixels are not sent) so that rank 0 writes in time. */
static int stop_requested(void *user) {
    (void)user;
    return render_stop_signal() != 0;
}

/* The share's messages over MPI (tr_transport). */
static int mpi_send(void *user, int to, int tag, const void *data, size_t size) {
    (void)user;
    if (size > (size_t)INT_MAX) {
        return TR_ERR;
    }
    const int rc = MPI_Send(data, (int)size, MPI_BYTE, to, tag, MPI_COMM_WORLD);
    return rc == MPI_SUCCESS ? TR_OK : TR_ERR;
}

static int mpi_recv(void *user, int from, int tag, int block, int *src, int *tag_out, void **data,
                    size_t *size) {
    (void)user;
    const int source = from < 0 ? MPI_ANY_SOURCE : from, mtag = tag < 0 ? MPI_ANY_TAG : tag;
    MPI_Status st;
    int flag = 1;
    if (block) {
        wait_message(source, mtag, &st);
    } else {
        MPI_Iprobe(source, mtag, MPI_COMM_WORLD, &flag, &st);
    }
    if (!flag) {
        return 0;
    }
    int n = 0;
    MPI_Get_count(&st, MPI_BYTE, &n);
    unsigned char *buf = malloc(n > 0 ? (size_t)n : 1u);
    if (!buf) {
        return -1;
    }
    MPI_Recv(buf, n, MPI_BYTE, st.MPI_SOURCE, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    *src = st.MPI_SOURCE;
    *tag_out = st.MPI_TAG;
    *data = buf;
    *size = (size_t)n;
    return 1;
}

/* Rank 0's progress bar over the tiles. */
static void tiles_progress(void *user, uint32_t done, uint32_t total) {
    progress *bar = user;
    if (done == 0) {
        progress_begin(bar, "trac0r render", "tiles", total, 0);
    } else {
        progress_update(bar, done, NULL);
    }
}

static int share_stop(void *user) {
    (void)user;
    return render_stop_signal(); /* the signal's number reaches rank 0 */
}

/* Runs the setup on every rank with stderr captured; returns the status of the lowest
 * failing rank (which alone prints its messages), or CLI_OK. */
static int setup_all(render_job *job, int argc, char **argv, int rank, int size, int *done) {
    fflush(stderr);
    fflush(stdout);
    const int saved_err = dup(2), saved_out = dup(1);
    FILE *cap = tmpfile();
    if (cap) {
        dup2(fileno(cap), 2);
        if (rank != 0) {
            dup2(fileno(cap), 1); /* --help once */
        }
    }
    int rc = render_job_setup(job, argc, argv, done);
    if (rc == CLI_OK && !*done && (job->noise_threshold > 0.0f || job->time_limit > 0.0f)) {
        /* Ranks render tiles at their own pace: a tile-wise stop rule or a wall-clock
         * budget would make the image depend on the rank count. */
        rc = cli_error(&job->args, "%s: not under mpirun",
                       job->noise_threshold > 0.0f ? "--noise-threshold" : "--time-limit");
        *done = 1;
    }
    fflush(stderr);
    fflush(stdout);
    dup2(saved_err, 2);
    dup2(saved_out, 1);
    close(saved_err);
    close(saved_out);
    const int failed = *done && rc != CLI_OK;
    int mine = failed ? rank : size, first = size;
    MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (cap && (rank == first || (first == size && rank == 0))) {
        /* The failing rank's messages, or rank 0's warnings. */
        char line[1024];
        rewind(cap);
        while (fgets(line, sizeof line, cap)) {
            fputs(line, stderr);
        }
    }
    if (cap) {
        fclose(cap);
    }
    if (first < size) {
        MPI_Bcast(&rc, 1, MPI_INT, first, MPI_COMM_WORLD);
        *done = 1;
    }
    return rc;
}

/* Every rank opens its session (resuming reads the checkpoint on every rank, so that a
 * tile a checkpoint holds in part goes on from its very floats), and checks that all
 * render the same image: the same scene and options. Returns the status of the lowest
 * failing rank (which alone prints its message), or CLI_OK with *out set. */
static int open_sessions(render_job *job, int rank, int size, tr_session **out) {
    tr_error err;
    tr_session_desc desc = render_session_desc(job);
    tr_session *s = tr_session_create(job->be.dev, job->scene, &job->cfg, &desc, &err);
    const char *id = s ? tr_session_identity(s, NULL, &err) : NULL;
    int mine = id ? size : rank, first = size;
    MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (first < size) {
        int rc = rank == first ? render_session_error(job, &err) : CLI_OK;
        MPI_Bcast(&rc, 1, MPI_INT, first, MPI_COMM_WORLD);
        tr_session_destroy(s);
        return rc;
    }
    uint64_t hash = 0;
    tr_session_identity(s, &hash, &err);
    tr_session_progress p;
    tr_session_progress_get(s, &p);
    unsigned long long h[2] = {hash, 0};
    for (const char *c = id ? id : ""; *c; ++c) {
        h[1] = h[1] * 131u + (unsigned char)*c;
    }
    h[1] = h[1] * 131u + p.spp;
    unsigned long long lo[2], hi[2];
    MPI_Allreduce(h, lo, 2, MPI_UNSIGNED_LONG_LONG, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(h, hi, 2, MPI_UNSIGNED_LONG_LONG, MPI_MAX, MPI_COMM_WORLD);
    if (lo[0] != hi[0] || lo[1] != hi[1]) {
        if (rank == 0) {
            fprintf(stderr, "trac0r render: the ranks were given different scenes or options "
                            "(only --device and --threads may differ between ranks)\n");
        }
        tr_session_destroy(s);
        return CLI_USAGE;
    }
    *out = s;
    return CLI_OK;
}

/* --verbose: rank 0 prints where every rank's time went. Every rank sends its times (the
 * option may differ between ranks), one small message each, after the render. */
static void report_phases(const render_job *job, int rank, int size, int rc) {
    phase[PH_CPU] = tr_time_cpu();
    if (rank != 0) {
        MPI_Send(phase, PH_COUNT, MPI_DOUBLE, 0, TAG_PHASES, MPI_COMM_WORLD);
        return;
    }
    const int print = job->verbose && rc == CLI_OK;
    double cpu = 0.0, render = 0.0;
    for (int r = 0; r < size; ++r) {
        double p[PH_COUNT];
        if (r == 0) {
            memcpy(p, phase, sizeof p);
        } else {
            MPI_Recv(p, PH_COUNT, MPI_DOUBLE, r, TAG_PHASES, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        }
        if (print) {
            fprintf(stderr,
                    "trac0r render: rank %d: setup %.3f s, then %.3f s: rendering %.3f s (%.0f "
                    "tiles), waiting %.3f s, messages %.3f s, pixels %.3f s; CPU %.3f s\n",
                    r, p[PH_SETUP], p[PH_TOTAL], p[PH_RENDER], p[PH_TILES], p[PH_WAIT], p[PH_SERVE],
                    p[PH_PIXELS], p[PH_CPU]);
        }
        cpu += p[PH_CPU];
        render += p[PH_RENDER];
    }
    if (print) {
        fprintf(stderr, "trac0r render: %d ranks: rendering %.3f s, CPU %.3f s (user + system)\n",
                size, render, cpu);
    }
}

int render_mpi_main(int argc, char **argv) {
    int provided = 0;
    MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided);
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    render_job job;
    int done = 0;
    int rc = setup_all(&job, argc, argv, rank, size, &done);
    phase[PH_SETUP] = tr_time_now() - job.started;
    if (done) {
        render_job_free(&job);
        MPI_Finalize();
        return rc;
    }
    /* The tiles are rendered whole by whichever rank: the pieces the CPU cuts them into
     * let rank 0 answer between them, and a signal drop the tile under way. */
    job.cfg.cancel = stop_requested;
    job.cfg.tile = piece_side(&job.cfg);
    tr_session *s = NULL;
    rc = open_sessions(&job, rank, size, &s);
    if (rc != CLI_OK) {
        render_job_free(&job);
        MPI_Finalize();
        return rc;
    }
    render_stop_install(NULL);
    const tr_transport tp = {rank, size, mpi_send, mpi_recv, NULL};
    progress bar;
    memset(&bar, 0, sizeof bar);
    const tr_share_desc sd = {.checkpoint = job.checkpoint != NULL,
                              .checkpoint_interval = job.checkpoint_interval,
                              .stop = share_stop,
                              .progress = rank == 0 ? tiles_progress : NULL,
                              .user = &bar};
    tr_share_stats st;
    tr_error err;
    const int shared = tr_session_share(s, &tp, &sd, &st, &err);
    progress_end(&bar);
    phase[PH_RENDER] = st.render;
    phase[PH_WAIT] = st.wait;
    phase[PH_SERVE] = st.serve;
    phase[PH_PIXELS] = st.pixels;
    phase[PH_TOTAL] = st.total;
    phase[PH_TILES] = st.tiles;
    rc = shared == TR_OK ? CLI_OK : CLI_FAILURE;
    if (rank == 0 && shared != TR_OK) {
        fprintf(stderr, "trac0r render: %s\n", err.msg);
    }
    if (rank == 0 && rc == CLI_OK) {
        /* A signal to rank 0, or to a worker alone: either stops the whole job. */
        const int own = render_stop_signal();
        const int sig = own ? own : (st.stop_code > 0 && st.stop_code < 65 ? st.stop_code : 0);
        tr_session_progress prog;
        tr_session_progress_get(s, &prog);
        if (job.checkpoint && tr_session_checkpoint(s, NULL, &err) != TR_OK) {
            fprintf(stderr, "trac0r render: --checkpoint: %s\n", err.msg);
            rc = CLI_FAILURE;
        }
        if (rc == CLI_OK) {
            /* An interrupted render: the finished tiles have every sample, the others
             * what the checkpoint resumed held. */
            char note[96];
            snprintf(note, sizeof note, "stopped by signal %d to rank %d: %u of %u tiles done", sig,
                     own ? 0 : st.stop_rank, st.finished, tr_session_tile_count(s));
            rc = render_write_outputs(&job, s, prog.spp, st.total, st.rays, sig ? note : NULL);
            if (rc == CLI_OK && sig) {
                rc = 128 + sig;
            }
        }
    }
    render_stop_uninstall();
    /* Every rank ends with rank 0's status (a worker's failure is rank 0's too). */
    MPI_Bcast(&rc, 1, MPI_INT, 0, MPI_COMM_WORLD);
    report_phases(&job, rank, size, rc);
    tr_session_destroy(s);
    render_job_free(&job);
    MPI_Finalize();
    return rc;
}
