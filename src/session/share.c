/* share.c - one session's tiles shared by several processes (tr_session_share, session.h).
 *
 * Rank 0 hands the tiles out one at a time as ranks finish, and renders tiles itself,
 * answering the workers between the pieces of its tile (between_pieces), so a slower rank
 * simply takes fewer tiles and no worker waits for rank 0's tile to end. A rank renders
 * every sample of its tile in one call into its device's film and reports the tile done;
 * the pixels follow in batches (reading a device's film costs as much as the whole image,
 * so it is read when a checkpoint is due and at the end, not per tile), and rank 0 puts
 * them into its film. Every worker keeps two tiles in hand (the next one is on its way
 * while it renders), one near the end so that the ranks finish together.
 *
 * Messages (tag: contents):
 *   WORK      rank 0 -> worker: int32 tile index, -1 for "no more"
 *   DONE      worker -> rank 0: uint64 tile index, uint64 rays
 *   DATA      worker -> rank 0: uint32 final, uint32 count, then per tile uint32 index and
 *             its pixels (tr_film_pack_rect)
 *   CANCELLED worker -> rank 0: int32 tile index (a stop dropped it), int32 the stop's
 *             value (the signal that stopped the worker)
 *   ERROR     worker -> rank 0: a message, NUL-terminated; the worker has left */
#include "trac0r/session.h"

#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trac0r/film.h"

enum { TAG_WORK = 1, TAG_DONE = 2, TAG_DATA = 3, TAG_CANCELLED = 4, TAG_ERROR = 5 };
#define PREFETCH 2 /* tiles a worker holds */

/* What both sides share: the session, its plan and the transport. */
typedef struct share {
    tr_session *s;
    const tr_transport *t;
    const tr_share_desc *d;
    tr_share_stats *st;
    uint32_t count;     /* tiles */
    size_t pixel_bytes; /* of the film's layout, for the passes kept */
    size_t tile_bytes;  /* the largest tile's pixels */
    double last_flush;  /* when pixels last went out (worker) or a checkpoint (rank 0) */
} share;

/* Tiles a rank finished whose pixels are still in its device film only. */
typedef struct pending {
    uint32_t *tiles;
    uint32_t n;
} pending;

/* The stop callback's value: 0, or why to stop (a signal's number). */
static int stop_asked(const share *sh) {
    return sh->d->stop ? sh->d->stop(sh->d->user) : 0;
}

static int stop_cb(void *user) {
    return stop_asked(user);
}

static int send_int32(const share *sh, int to, int tag, int32_t v) {
    return sh->t->send(sh->t->user, to, tag, &v, sizeof v);
}

/* Renders every sample tile k lacks into this rank's device film. */
static int render_tile(share *sh, uint32_t k, int (*cancel)(void *), void *user, uint64_t *rays,
                       tr_error *err) {
    tr_render_stats rs;
    const double t0 = tr_time_now();
    const int rc = tr_session_render_tile(sh->s, k, cancel, user, &rs, err);
    sh->st->render += tr_time_now() - t0;
    if (rc == TR_OK) {
        sh->st->tiles += 1;
        sh->st->rays += rs.rays;
        *rays = rs.rays;
    }
    return rc;
}

/* Worker: sends the pending tiles' pixels to rank 0, the last message marked final if
 * asked; as many tiles per message as keep it under 1 GiB (MPI counts are ints). */
static int send_pending(share *sh, pending *p, int final, tr_error *err) {
    const double t0 = tr_time_now();
    const tr_film *film = p->n > 0 ? tr_session_film(sh->s, err) : NULL;
    if (p->n > 0 && !film) {
        return TR_ERR;
    }
    const size_t per = sizeof(uint32_t) + sh->tile_bytes;
    const uint32_t most = ((size_t)1 << 30) / per > 0 ? (uint32_t)(((size_t)1 << 30) / per) : 1u;
    uint32_t sent = 0;
    int rc = TR_OK;
    do {
        const uint32_t n = p->n - sent < most ? p->n - sent : most;
        unsigned char *buf = malloc(2 * sizeof(uint32_t) + (size_t)n * per);
        if (!buf) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory sending tiles");
        }
        const uint32_t head[2] = {final && sent + n == p->n, n};
        memcpy(buf, head, sizeof head);
        unsigned char *q = buf + sizeof head;
        for (uint32_t i = 0; i < n && rc == TR_OK; ++i) {
            const uint32_t k = p->tiles[sent + i];
            tr_rect r;
            rc = tr_session_tile(sh->s, k, &r, NULL, err);
            memcpy(q, &k, sizeof k);
            q += sizeof k;
            const size_t bytes = (size_t)r.width * r.height * sh->pixel_bytes;
            if (rc == TR_OK) {
                rc = tr_film_pack_rect(film, &r, q, bytes, err);
            }
            q += bytes;
        }
        if (rc == TR_OK && sh->t->send(sh->t->user, 0, TAG_DATA, buf, (size_t)(q - buf)) != TR_OK) {
            rc = tr_error_set(err, TR_STATUS_DEVICE, "sending pixels failed");
        }
        free(buf);
        sent += n;
    } while (sent < p->n && rc == TR_OK);
    p->n = 0;
    sh->st->pixels += tr_time_now() - t0;
    return rc;
}

/* A worker: renders the tiles rank 0 sends until it sends -1, reporting each and sending
 * the pixels in batches. */
static int worker(share *sh, tr_error *err) {
    pending p = {calloc(sh->count ? sh->count : 1, sizeof(uint32_t)), 0};
    if (!p.tiles) {
        const char msg[] = "out of memory";
        sh->t->send(sh->t->user, 0, TAG_ERROR, msg, sizeof msg);
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
    }
    sh->last_flush = tr_time_now();
    int rc = TR_OK;
    for (;;) {
        int32_t k = -1;
        void *data = NULL;
        size_t n = 0;
        int src = 0, tag = 0;
        const double t0 = tr_time_now();
        const int got = sh->t->recv(sh->t->user, 0, TAG_WORK, 1, &src, &tag, &data, &n);
        sh->st->wait += tr_time_now() - t0;
        if (got == 1 && n == sizeof k) {
            memcpy(&k, data, sizeof k);
        }
        free(data);
        if (got != 1 || n != sizeof k) {
            rc = tr_error_set(err, TR_STATUS_DEVICE, "a malformed message from rank 0");
            break;
        }
        int ok = TR_OK;
        uint64_t rays = 0;
        if (k < 0) {
            ok = send_pending(sh, &p, 1, err);
        } else if ((ok = render_tile(sh, (uint32_t)k, stop_cb, sh, &rays, err)) == TR_OK) {
            p.tiles[p.n++] = (uint32_t)k;
            const uint64_t done[2] = {(uint64_t)k, rays};
            ok = sh->t->send(sh->t->user, 0, TAG_DONE, done, sizeof done);
            if (ok != TR_OK) {
                tr_error_set(err, TR_STATUS_DEVICE, "sending a tile report failed");
            }
            if (ok == TR_OK && sh->d->checkpoint &&
                tr_time_now() - sh->last_flush >= sh->d->checkpoint_interval) {
                ok = send_pending(sh, &p, 0, err);
                sh->last_flush = tr_time_now();
            }
        } else if (err->code == TR_STATUS_CANCELLED) {
            const int32_t why[2] = {k, stop_asked(sh)};
            sh->t->send(sh->t->user, 0, TAG_CANCELLED, why, sizeof why);
            continue; /* until rank 0 sends -1 */
        }
        if (ok != TR_OK) {
            sh->t->send(sh->t->user, 0, TAG_ERROR, err->msg, strlen(err->msg) + 1);
            rc = TR_ERR;
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
    share *sh;
    unsigned char *done; /* per tile: its pixels in the film (or from the checkpoint) */
    pending mine;        /* rank 0's finished tiles not yet marked done */
    uint32_t next;       /* the first tile not handed out */
    uint32_t finished;   /* tiles rendered (reported), the checkpoint's included */
    uint32_t resumed;    /* tiles finished in the checkpoint */
    int stopping;        /* hand out no more (a stop or an error) */
    int *outstanding;    /* per rank: tiles handed out, not yet reported */
    int *stopped;        /* per rank: sent -1 (or failed) */
    int *final;          /* per rank: its last pixels arrived (or it failed) */
    int rc;
    tr_error *err; /* the first failure */
} master;

/* The next tile to render, or -1. */
static int32_t take_tile(master *m) {
    if (m->stopping || stop_asked(m->sh)) {
        m->stopping = 1;
        return -1;
    }
    while (m->next < m->sh->count && m->done[m->next]) {
        ++m->next;
    }
    return m->next < m->sh->count ? (int32_t)m->next++ : -1;
}

/* The first failure is the one reported (and its rank); every failure stops the
 * hand-out. */
static void fail_rank(master *m, int rank, const tr_error *e) {
    if (m->rc == TR_OK) {
        *m->err = *e;
        m->sh->st->failed_rank = rank;
    }
    m->rc = TR_ERR;
    m->stopping = 1;
}

/* Rank 0's own failure. */
static void fail_err(master *m, const tr_error *e) {
    fail_rank(m, 0, e);
}

static void fail(master *m, int rank, const char *msg) {
    tr_error e;
    tr_error_set(&e, TR_STATUS_DEVICE, "rank %d: %s", rank, msg);
    fail_rank(m, rank, &e);
}

static void hand_out(master *m, int rank) {
    if (m->stopped[rank]) {
        return;
    }
    const int32_t k = take_tile(m);
    if (send_int32(m->sh, rank, TAG_WORK, k) != TR_OK) {
        fail(m, rank, "sending a tile failed");
        m->stopped[rank] = m->final[rank] = 1;
        m->outstanding[rank] = 0;
        return;
    }
    if (k < 0) {
        m->stopped[rank] = 1;
    } else {
        ++m->outstanding[rank];
    }
}

static void tile_reported(master *m) {
    ++m->finished;
    if (m->sh->d->progress) {
        m->sh->d->progress(m->sh->d->user, m->finished - m->resumed, m->sh->count - m->resumed);
    }
}

/* Marks rank 0's own finished tiles done: its session's film holds them. */
static void collect_own(master *m) {
    if (m->mine.n == 0) {
        return;
    }
    tr_error e;
    if (!tr_session_film(m->sh->s, &e)) {
        fail_err(m, &e);
        return;
    }
    for (uint32_t i = 0; i < m->mine.n; ++i) {
        m->done[m->mine.tiles[i]] = 1;
    }
    m->mine.n = 0;
}

static void maybe_checkpoint(master *m) {
    share *sh = m->sh;
    if (!sh->d->checkpoint || m->rc != TR_OK ||
        tr_time_now() - sh->last_flush < sh->d->checkpoint_interval) {
        return;
    }
    /* The workers' pixels come in their own batches, at the same interval: a checkpoint
     * holds the tiles whose pixels have arrived. */
    collect_own(m);
    tr_error e;
    if (m->rc == TR_OK && tr_session_checkpoint(sh->s, NULL, &e) != TR_OK) {
        fail_err(m, &e);
    }
    sh->last_flush = tr_time_now();
}

/* Unpacks a DATA message from rank src. */
static void take_pixels(master *m, int src, const unsigned char *buf, size_t n) {
    uint32_t head[2];
    if (n < sizeof head) {
        fail(m, src, "a malformed message");
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
        tr_rect r = {0, 0, 0, 0};
        tr_error e;
        const int known = k < m->sh->count && tr_session_tile(m->sh->s, k, &r, NULL, &e) == TR_OK;
        const size_t bytes = (size_t)r.width * r.height * m->sh->pixel_bytes;
        if (!known || (size_t)(q - buf) + bytes > n ||
            tr_session_put_tile(m->sh->s, k, q, bytes, &e) != TR_OK) {
            fail(m, src, "a malformed message");
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

/* Leaves every worker out of the hand-out (the transport failed). */
static void abandon(master *m) {
    fail(m, 0, "receiving a message failed");
    for (int w = 1; w < m->sh->t->size; ++w) {
        m->stopped[w] = m->final[w] = 1;
        m->outstanding[w] = 0;
    }
}

/* Takes one message from a worker (blocking or not). Returns whether one was taken. */
static int serve(master *m, int block) {
    share *sh = m->sh;
    void *data = NULL;
    size_t n = 0;
    int src = 0, tag = 0;
    const int got = sh->t->recv(sh->t->user, -1, -1, block, &src, &tag, &data, &n);
    if (got < 0 || (got == 1 && (src <= 0 || src >= sh->t->size))) {
        free(data);
        abandon(m);
        return 0;
    }
    if (got == 0) {
        return 0;
    }
    unsigned char *buf = data;
    if (tag == TAG_DONE && n == 2 * sizeof(uint64_t)) {
        uint64_t done[2];
        memcpy(done, buf, sizeof done);
        --m->outstanding[src];
        sh->st->rays += done[1];
        tile_reported(m);
        /* A second tile in hand hides rank 0's answer; near the end it would leave the
         * others idle while this worker renders it, so there a worker holds one. */
        if (m->outstanding[src] == 0 || sh->count - m->next > (uint32_t)(sh->t->size * PREFETCH)) {
            hand_out(m, src);
        }
    } else if (tag == TAG_CANCELLED) {
        /* A worker stopped (a signal to that rank alone): the whole job stops, as for
         * rank 0's own, and rank 0 learns why. */
        int32_t why[2] = {0, 0};
        memcpy(why, buf, n < sizeof why ? n : sizeof why);
        if (sh->st->stop_rank < 0 && why[1] != 0) {
            sh->st->stop_code = why[1];
            sh->st->stop_rank = src;
        }
        --m->outstanding[src];
        m->stopping = 1;
        hand_out(m, src);
    } else if (tag == TAG_DATA) {
        take_pixels(m, src, buf, n);
    } else { /* TAG_ERROR (or anything else): the worker has left the hand-out */
        char msg[200];
        snprintf(msg, sizeof msg, "%.*s", (int)(n < sizeof msg ? n : sizeof msg - 1),
                 n > 0 ? (const char *)buf : "");
        fail(m, src, tag == TAG_ERROR ? msg : "an unexpected message");
        m->stopped[src] = 1;
        m->outstanding[src] = 0;
        m->final[src] = 1;
    }
    free(data);
    return 1;
}

/* Asked by the device before each piece of rank 0's tile: a stop drops the tile; on the
 * calling thread (OpenMP's thread 0 of the device's loop, the one that may use the
 * transport) the workers' messages are answered meanwhile, so a worker waits for a piece
 * of rank 0's tile at most, not for all of it. */
static int between_pieces(void *user) {
    master *m = user;
    if (m->stopping || stop_asked(m->sh)) {
        return 1; /* a stop here or on a worker, or a failure, drops rank 0's tile */
    }
    if (omp_get_thread_num() == 0) {
        const double t0 = tr_time_now();
        while (serve(m, 0)) {
        }
        m->sh->st->serve += tr_time_now() - t0;
    }
    return 0;
}

static int master_loop(master *m) {
    share *sh = m->sh;
    const int size = sh->t->size;
    for (int p = 0; p < PREFETCH; ++p) {
        for (int w = 1; w < size; ++w) {
            hand_out(m, w);
        }
    }
    for (;;) {
        double t1 = tr_time_now();
        while (serve(m, 0)) {
        }
        sh->st->serve += tr_time_now() - t1;
        maybe_checkpoint(m);
        const int32_t k = take_tile(m);
        if (k >= 0) {
            tr_error e;
            uint64_t rays = 0;
            if (render_tile(sh, (uint32_t)k, between_pieces, m, &rays, &e) != TR_OK) {
                m->stopping = 1;
                if (e.code != TR_STATUS_CANCELLED) {
                    fail_err(m, &e);
                }
                continue;
            }
            m->mine.tiles[m->mine.n++] = (uint32_t)k;
            tile_reported(m);
            continue;
        }
        int busy = 0;
        for (int w = 1; w < size; ++w) {
            busy |= !m->stopped[w] || m->outstanding[w] > 0 || !m->final[w];
        }
        if (!busy) {
            break;
        }
        t1 = tr_time_now();
        serve(m, 1);
        sh->st->wait += tr_time_now() - t1;
    }
    const double t2 = tr_time_now();
    collect_own(m);
    sh->st->pixels += tr_time_now() - t2;
    return m->rc;
}

static int coordinate(share *sh, tr_error *err) {
    const int size = sh->t->size;
    master m;
    memset(&m, 0, sizeof m);
    m.sh = sh;
    m.err = err;
    m.done = calloc(sh->count ? sh->count : 1, 1);
    m.outstanding = calloc((size_t)size, sizeof *m.outstanding);
    m.stopped = calloc((size_t)size, sizeof *m.stopped);
    m.final = calloc((size_t)size, sizeof *m.final);
    m.mine.tiles = calloc(sh->count ? sh->count : 1, sizeof *m.mine.tiles);
    int rc = TR_OK;
    if (!m.done || !m.outstanding || !m.stopped || !m.final || !m.mine.tiles) {
        for (int w = 1; w < size; ++w) { /* let the workers go */
            send_int32(sh, w, TAG_WORK, -1);
        }
        rc = tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory");
    } else {
        tr_session_progress prog;
        tr_session_progress_get(sh->s, &prog);
        for (uint32_t k = 0; k < sh->count; ++k) {
            uint32_t have = 0;
            tr_session_tile(sh->s, k, NULL, &have, NULL);
            m.done[k] = have >= prog.spp;
            m.finished += m.done[k];
        }
        m.resumed = m.finished;
        if (sh->d->progress) {
            sh->d->progress(sh->d->user, 0, sh->count - m.resumed);
        }
        rc = master_loop(&m);
        sh->st->finished = 0;
        for (uint32_t k = 0; k < sh->count; ++k) {
            sh->st->finished += m.done[k];
        }
    }
    free(m.done);
    free(m.outstanding);
    free(m.stopped);
    free(m.final);
    free(m.mine.tiles);
    return rc;
}

int tr_session_share(tr_session *s, const tr_transport *t, const tr_share_desc *d,
                     tr_share_stats *stats, tr_error *err) {
    tr_share_stats local;
    tr_share_desc none;
    memset(&none, 0, sizeof none);
    stats = stats ? stats : &local;
    memset(stats, 0, sizeof *stats);
    stats->failed_rank = -1;
    stats->stop_rank = -1;
    if (!s || !t || !t->send || !t->recv || t->size < 1 || t->rank < 0 || t->rank >= t->size) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "share: needs a session and a transport with send, recv and a rank "
                            "below its size");
    }
    const tr_film *film = tr_session_film(s, err);
    if (!film) {
        return TR_ERR;
    }
    share sh = {s,
                t,
                d ? d : &none,
                stats,
                tr_session_tile_count(s),
                tr_film_pixel_bytes(film->passes),
                0,
                tr_time_now()};
    for (uint32_t k = 0; k < sh.count; ++k) {
        tr_rect r;
        if (tr_session_tile(s, k, &r, NULL, err) != TR_OK) {
            return TR_ERR;
        }
        const size_t b = (size_t)r.width * r.height * sh.pixel_bytes;
        sh.tile_bytes = b > sh.tile_bytes ? b : sh.tile_bytes;
    }
    const double t0 = tr_time_now();
    const int rc = t->rank == 0 ? coordinate(&sh, err) : worker(&sh, err);
    stats->total = tr_time_now() - t0;
    return rc;
}
