/* render_mpi.c - `trac0r render` under mpirun: one render shared by many processes.
 *
 * The image is cut into tiles (32 x 32 traced pixels, aligned to the stride). Rank 0
 * hands them out one at a time as ranks finish, and renders tiles itself, answering the
 * workers between the pieces of its tile (between_pieces), so a slower machine simply
 * takes fewer tiles and no worker waits for rank 0's tile to end. A rank renders every sample
 * of its tile in one call, in the device's own order, into its device's film, and
 * reports the tile done; the pixels follow in batches (reading a device's film costs as
 * much as the whole image, so it is read when a checkpoint is due and at the end, not
 * per tile), and rank 0 copies them into its film. Tiles never overlap, so the film is
 * the one a single process accumulates, bit for bit, whatever the number of ranks and
 * whichever rank took which tile. Every worker keeps two tiles in hand (the next one is
 * already on its way while it renders), one near the end so that the ranks finish
 * together. A rank waiting for a message sleeps between probes (wait_message) rather than
 * spinning in Open MPI's blocking calls. --verbose reports where each rank's time went.
 *
 * Setup errors (a bad option, a scene, a device a rank cannot open) are gathered: each
 * rank's stderr goes to a temporary file until every rank has set up, then the lowest
 * failing rank alone prints its message and every rank exits with its status. An error
 * while rendering is sent to rank 0, which stops handing out tiles, prints it once, and
 * all ranks exit with status 1. Rank 0 alone writes files and prints progress. */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <mpi.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "progress.h"
#include "render_job.h"
#include "stop.h"

enum { TAG_WORK = 1, TAG_DONE = 2, TAG_DATA = 3, TAG_ERROR = 4, TAG_CANCELLED = 5, TAG_PHASES = 6 };
#define PREFETCH 2 /* tiles a worker holds */

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

/* The session's tile plan (tr_session_tile_*): the tiles' count, side and rectangles. */
typedef struct tiling {
    tr_session *s;
    uint32_t side, count;
    size_t pixel_bytes; /* of the film's layout, for the passes kept */
} tiling;

static tiling make_tiling(tr_session *s, const render_job *job) {
    tiling t;
    t.s = s;
    t.side = TR_SESSION_TILE * (uint32_t)job->cfg.stride;
    t.count = tr_session_tile_count(s);
    t.pixel_bytes = tr_film_pixel_bytes(tr_session_film(s, NULL)->passes); /* with guides */
    return t;
}

static tr_rect tile_rect(const tiling *t, uint32_t k) {
    tr_rect r = {0, 0, 0, 0};
    tr_session_tile(t->s, k, &r, NULL, NULL);
    return r;
}

/* Renders every sample tile k lacks into this rank's device film. */
static int render_tile(render_job *job, const tiling *t, uint32_t k, uint64_t *rays,
                       tr_error *err) {
    tr_render_stats st;
    const double t0 = tr_time_now();
    const int rc = tr_session_render_tile(t->s, k, job->cfg.cancel, job->cfg.cancel_user, &st, err);
    phase[PH_RENDER] += tr_time_now() - t0;
    if (rc != TR_OK) {
        return TR_ERR;
    }
    phase[PH_TILES] += 1.0;
    *rays += st.rays;
    return TR_OK;
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

/* Tiles a rank finished whose pixels are still in its device film only. Reading that
 * film costs as much as the whole image, so it is read once per batch: when a
 * checkpoint is due and at the end, not once per tile. */
typedef struct pending {
    uint32_t *tiles;
    uint32_t n;
} pending;

/* The most tiles one message carries (MPI counts are ints). */
static uint32_t tiles_per_message(const tiling *t) {
    const size_t per = sizeof(uint32_t) + (size_t)t->side * t->side * t->pixel_bytes;
    const size_t n = ((size_t)1 << 30) / per;
    return n > 0 ? (uint32_t)n : 1u;
}

/* Worker: sends the pending tiles' pixels to rank 0 (TAG_DATA: uint32 final, uint32
 * count, then per tile its index and pixels), the last message marked final if asked. */
static int send_pending(const tiling *t, pending *p, int final, tr_error *err) {
    const tr_film *film = p->n > 0 ? tr_session_film(t->s, err) : NULL;
    if (p->n > 0 && !film) {
        return TR_ERR;
    }
    const uint32_t most = tiles_per_message(t);
    const size_t per = sizeof(uint32_t) + (size_t)t->side * t->side * t->pixel_bytes;
    uint32_t sent = 0;
    do {
        const uint32_t n = p->n - sent < most ? p->n - sent : most;
        unsigned char *buf = malloc(2 * sizeof(uint32_t) + (size_t)n * per);
        if (!buf) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory sending tiles");
        }
        const uint32_t head[2] = {final && sent + n == p->n, n};
        memcpy(buf, head, sizeof head);
        unsigned char *q = buf + sizeof head;
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t k = p->tiles[sent + i];
            const tr_rect r = tile_rect(t, k);
            memcpy(q, &k, sizeof k);
            q += sizeof k;
            const size_t bytes = (size_t)r.width * r.height * t->pixel_bytes;
            if (tr_film_pack_rect(film, &r, q, bytes, err) != TR_OK) {
                free(buf);
                return TR_ERR;
            }
            q += bytes;
        }
        MPI_Send(buf, (int)(q - buf), MPI_BYTE, 0, TAG_DATA, MPI_COMM_WORLD);
        free(buf);
        sent += n;
    } while (sent < p->n);
    p->n = 0;
    return TR_OK;
}

/* A worker: renders the tiles rank 0 sends until it sends -1, reporting each (TAG_DONE:
 * uint64 index, rays) and sending the pixels in batches. */
static int worker(render_job *job, const tiling *t) {
    tr_error err;
    pending p = {calloc(t->count, sizeof(uint32_t)), 0};
    if (!p.tiles) {
        const char msg[] = "out of memory";
        MPI_Send(msg, (int)sizeof msg, MPI_CHAR, 0, TAG_ERROR, MPI_COMM_WORLD);
        return CLI_FAILURE;
    }
    double last_flush = tr_time_now();
    int rc = CLI_OK;
    for (;;) {
        int32_t k;
        double t0 = tr_time_now();
        MPI_Status st;
        wait_message(0, TAG_WORK, &st);
        MPI_Recv(&k, 1, MPI_INT32_T, 0, TAG_WORK, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        phase[PH_WAIT] += tr_time_now() - t0;
        uint64_t rays = 0;
        int ok = TR_OK;
        if (k < 0) {
            t0 = tr_time_now();
            ok = send_pending(t, &p, 1, &err);
            phase[PH_PIXELS] += tr_time_now() - t0;
        } else if ((ok = render_tile(job, t, (uint32_t)k, &rays, &err)) == TR_OK) {
            p.tiles[p.n++] = (uint32_t)k;
            const uint64_t done[2] = {(uint64_t)k, rays};
            MPI_Send(done, 2, MPI_UINT64_T, 0, TAG_DONE, MPI_COMM_WORLD);
            if (job->checkpoint && tr_time_now() - last_flush >= job->checkpoint_interval) {
                t0 = tr_time_now();
                ok = send_pending(t, &p, 0, &err);
                last_flush = tr_time_now();
                phase[PH_PIXELS] += last_flush - t0;
            }
        } else if (err.code == TR_STATUS_CANCELLED) {
            MPI_Send(&k, 1, MPI_INT32_T, 0, TAG_CANCELLED, MPI_COMM_WORLD);
            continue; /* until rank 0 sends -1 */
        }
        if (ok != TR_OK) {
            MPI_Send(err.msg, (int)strlen(err.msg) + 1, MPI_CHAR, 0, TAG_ERROR, MPI_COMM_WORLD);
            rc = CLI_FAILURE;
            break;
        }
        if (k < 0) {
            break;
        }
    }
    free(p.tiles);
    return rc;
}

/* Rank 0's side of the hand-out. */
typedef struct master {
    render_job *job;
    const tiling *t;     /* over rank 0's session, whose film is the image */
    unsigned char *done; /* per tile: its pixels in the image (or from the checkpoint) */
    pending mine;        /* rank 0's finished tiles not yet copied into `film` */
    uint32_t next;       /* the first tile not handed out */
    uint32_t finished;   /* tiles rendered (reported), the checkpoint's included */
    uint32_t resumed;    /* tiles finished in the checkpoint */
    int stopping;        /* hand out no more (a signal or an error) */
    int *outstanding;    /* per rank: tiles handed out, not yet reported */
    int *stopped;        /* per rank: sent -1 (or failed) */
    int *final;          /* per rank: its last pixels arrived (or it failed) */
    int size;            /* ranks */
    uint64_t rays;
    int rc;
    progress bar;
} master;

/* The next tile to render, or -1. */
static int32_t take_tile(master *m) {
    if (m->stopping || render_stop_signal()) {
        m->stopping = 1;
        return -1;
    }
    while (m->next < m->t->count && m->done[m->next]) {
        ++m->next;
    }
    return m->next < m->t->count ? (int32_t)m->next++ : -1;
}

static void hand_out(master *m, int rank) {
    if (m->stopped[rank]) {
        return;
    }
    const int32_t k = take_tile(m);
    MPI_Send(&k, 1, MPI_INT32_T, rank, TAG_WORK, MPI_COMM_WORLD);
    if (k < 0) {
        m->stopped[rank] = 1;
    } else {
        ++m->outstanding[rank];
    }
}

static void tile_reported(master *m) {
    ++m->finished;
    progress_update(&m->bar, m->finished - m->resumed, NULL);
}

static void fail(master *m, const char *who, const char *msg) {
    progress_end(&m->bar);
    if (m->rc == CLI_OK) {
        fprintf(stderr, "trac0r render: %s%s\n", who, msg);
    }
    m->rc = CLI_FAILURE;
    m->stopping = 1;
}

/* Copies rank 0's own finished tiles from its device film into the image. */
static void collect_own(master *m) {
    tr_error err;
    if (m->mine.n == 0) {
        return;
    }
    if (!tr_session_film(m->t->s, &err)) {
        fail(m, "", err.msg);
        return;
    }
    for (uint32_t i = 0; i < m->mine.n; ++i) {
        m->done[m->mine.tiles[i]] = 1;
    }
    m->mine.n = 0;
}

static void maybe_checkpoint(master *m, double *last) {
    render_job *job = m->job;
    tr_error err;
    if (!job->checkpoint || m->rc != CLI_OK || tr_time_now() - *last < job->checkpoint_interval) {
        return;
    }
    /* The workers' pixels come in their own batches, at the same interval: a
     * checkpoint holds the tiles whose pixels have arrived. */
    collect_own(m);
    if (m->rc == CLI_OK && tr_session_checkpoint(m->t->s, NULL, &err) != TR_OK) {
        fail(m, "--checkpoint: ", err.msg);
    }
    *last = tr_time_now();
}

/* Unpacks a TAG_DATA message. */
static void take_pixels(master *m, int src, const unsigned char *buf, size_t n) {
    uint32_t head[2];
    if (n < sizeof head) {
        fail(m, "", "a malformed message from a worker");
        m->final[src] = 1;
        return;
    }
    memcpy(head, buf, sizeof head);
    const unsigned char *q = buf + sizeof head;
    for (uint32_t i = 0; i < head[1]; ++i) {
        uint32_t k = UINT32_MAX;
        if ((size_t)(q - buf) + sizeof k <= n) {
            memcpy(&k, q, sizeof k);
            q += sizeof k;
        }
        const tr_rect r = tile_rect(m->t, k < m->t->count ? k : 0);
        const size_t bytes = (size_t)r.width * r.height * m->t->pixel_bytes;
        tr_error err;
        if (k >= m->t->count || (size_t)(q - buf) + bytes > n ||
            tr_session_put_tile(m->t->s, k, q, bytes, &err) != TR_OK) {
            fail(m, "", "a malformed message from a worker");
            m->final[src] = 1; /* waiting for more from it would be in vain */
            return;
        }
        q += bytes;
        m->done[k] = 1;
    }
    if (head[0]) {
        m->final[src] = 1;
    }
}

/* Takes one message from a worker (blocking or not). Returns whether one was taken. */
static int serve(master *m, int block) {
    MPI_Status st;
    int flag = 1;
    if (block) {
        wait_message(MPI_ANY_SOURCE, MPI_ANY_TAG, &st);
    } else {
        MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
    }
    if (!flag) {
        return 0;
    }
    int n = 0;
    MPI_Get_count(&st, MPI_BYTE, &n);
    const int src = st.MPI_SOURCE;
    unsigned char *buf = malloc(n > 0 ? (size_t)n : 1u);
    if (!buf) {
        /* Nothing sensible is left: the message cannot be taken. */
        fprintf(stderr, "trac0r render: out of memory receiving %d bytes\n", n);
        MPI_Abort(MPI_COMM_WORLD, CLI_FAILURE);
    }
    MPI_Recv(buf, n, MPI_BYTE, src, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (st.MPI_TAG == TAG_DONE) {
        uint64_t done[2];
        memcpy(done, buf, sizeof done);
        --m->outstanding[src];
        m->rays += done[1];
        tile_reported(m);
        /* A second tile in hand hides rank 0's answer; near the end it would leave the
         * others idle while this worker renders it, so there a worker holds one. */
        if (m->outstanding[src] == 0 || m->t->count - m->next > (uint32_t)(m->size * PREFETCH)) {
            hand_out(m, src);
        }
    } else if (st.MPI_TAG == TAG_CANCELLED) {
        --m->outstanding[src];
        m->stopping = 1;
        hand_out(m, src);
    } else if (st.MPI_TAG == TAG_DATA) {
        take_pixels(m, src, buf, (size_t)n);
    } else { /* TAG_ERROR: the worker has left the hand-out */
        buf[n > 0 ? n - 1 : 0] = '\0';
        char who[32];
        snprintf(who, sizeof who, "rank %d: ", src);
        fail(m, who, (const char *)buf);
        m->stopped[src] = 1;
        m->outstanding[src] = 0;
        m->final[src] = 1;
    }
    free(buf);
    return 1;
}

/* Asked by the CPU device before each piece of rank 0's tile (tr_render_config.cancel):
 * a stop signal drops the tile; on the main thread (the one that calls MPI, and OpenMP's
 * thread 0 of the device's loop) the workers' messages are answered meanwhile, so a
 * worker waits for a piece of rank 0's tile at most, not for all of it. */
static int between_pieces(void *user) {
    if (render_stop_signal() != 0) {
        return 1;
    }
    if (omp_get_thread_num() == 0) {
        const double t0 = tr_time_now();
        while (serve(user, 0)) {
        }
        phase[PH_SERVE] += tr_time_now() - t0;
    }
    return 0;
}

static int master_run(render_job *job, const tiling *t, unsigned char *done, int size,
                      double *elapsed, uint64_t *rays) {
    master m;
    memset(&m, 0, sizeof m);
    m.job = job;
    m.t = t;
    m.done = done;
    m.size = size;
    m.outstanding = calloc((size_t)size, sizeof *m.outstanding);
    m.stopped = calloc((size_t)size, sizeof *m.stopped);
    m.final = calloc((size_t)size, sizeof *m.final);
    m.mine.tiles = calloc(t->count, sizeof *m.mine.tiles);
    if (!m.outstanding || !m.stopped || !m.final || !m.mine.tiles) {
        fprintf(stderr, "trac0r render: out of memory\n");
        MPI_Abort(MPI_COMM_WORLD, CLI_FAILURE);
    }
    for (uint32_t k = 0; k < t->count; ++k) {
        m.finished += done[k];
    }
    m.resumed = m.finished;
    job->cfg.cancel = between_pieces;
    job->cfg.cancel_user = &m;
    progress_begin(&m.bar, "trac0r render", "tiles", t->count - m.resumed, 0);
    const double t0 = tr_time_now();
    double last = t0;
    for (int p = 0; p < PREFETCH; ++p) {
        for (int w = 1; w < size; ++w) {
            hand_out(&m, w);
        }
    }
    tr_error err;
    for (;;) {
        double t1 = tr_time_now();
        while (serve(&m, 0)) {
        }
        phase[PH_SERVE] += tr_time_now() - t1;
        maybe_checkpoint(&m, &last);
        const int32_t k = take_tile(&m);
        if (k >= 0) {
            if (render_tile(job, t, (uint32_t)k, &m.rays, &err) != TR_OK) {
                m.stopping = 1;
                if (err.code != TR_STATUS_CANCELLED) {
                    fail(&m, "", err.msg);
                }
                continue;
            }
            m.mine.tiles[m.mine.n++] = (uint32_t)k;
            tile_reported(&m);
            continue;
        }
        int busy = 0;
        for (int w = 1; w < size; ++w) {
            busy |= !m.stopped[w] || m.outstanding[w] > 0 || !m.final[w];
        }
        if (!busy) {
            break;
        }
        t1 = tr_time_now();
        serve(&m, 1);
        phase[PH_WAIT] += tr_time_now() - t1;
    }
    const double t2 = tr_time_now();
    collect_own(&m);
    phase[PH_PIXELS] += tr_time_now() - t2;
    progress_end(&m.bar);
    *elapsed = tr_time_now() - t0;
    *rays = m.rays;
    free(m.outstanding);
    free(m.stopped);
    free(m.final);
    free(m.mine.tiles);
    return m.rc;
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
    phase[PH_CPU] = render_cpu_seconds();
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
    const tiling t = make_tiling(s, &job);
    unsigned char *tiles_done = calloc(t.count, 1);
    if (!tiles_done) {
        fprintf(stderr, "trac0r render: rank %d: out of memory\n", rank);
        MPI_Abort(MPI_COMM_WORLD, CLI_FAILURE);
    }
    tr_session_progress prog;
    tr_session_progress_get(s, &prog);
    for (uint32_t k = 0; k < t.count; ++k) {
        uint32_t have = 0;
        tr_session_tile(s, k, NULL, &have, NULL);
        tiles_done[k] = have >= prog.spp;
    }
    render_stop_install(NULL);
    if (rank == 0) {
        double elapsed = 0.0;
        uint64_t rays = 0;
        rc = master_run(&job, &t, tiles_done, size, &elapsed, &rays);
        phase[PH_TOTAL] = elapsed;
        const int sig = render_stop_signal();
        uint32_t finished = 0;
        for (uint32_t k = 0; k < t.count; ++k) {
            finished += tiles_done[k];
        }
        tr_error err;
        if (rc == CLI_OK && job.checkpoint && tr_session_checkpoint(s, NULL, &err) != TR_OK) {
            fprintf(stderr, "trac0r render: --checkpoint: %s\n", err.msg);
            rc = CLI_FAILURE;
        }
        if (rc == CLI_OK) {
            /* An interrupted render: the finished tiles have every sample, the others
             * what the checkpoint resumed held. */
            char note[96];
            snprintf(note, sizeof note, "stopped by signal %d: %u of %u tiles done", sig, finished,
                     t.count);
            rc = render_write_outputs(&job, s, prog.spp, elapsed, rays, sig ? note : NULL);
            if (rc == CLI_OK && sig) {
                rc = 128 + sig;
            }
        }
    } else {
        const double t0 = tr_time_now();
        rc = worker(&job, &t);
        phase[PH_TOTAL] = tr_time_now() - t0;
    }
    render_stop_uninstall();
    /* Every rank ends with rank 0's status (a worker's failure is rank 0's too). */
    MPI_Bcast(&rc, 1, MPI_INT, 0, MPI_COMM_WORLD);
    report_phases(&job, rank, size, rc);
    free(tiles_done);
    tr_session_destroy(s);
    render_job_free(&job);
    MPI_Finalize();
    return rc;
}
