/* test_share.c - one session shared by several processes (tr_session_share), with the
 * processes played by threads and the messages carried by in-memory queues.
 *
 * 1. Three ranks render the classic box: rank 0's film is bit-identical to one session's
 *    tr_session_run, every tile was rendered by some rank, progress reached every tile.
 * 2. A transport that fails a worker's tile reports: the worker leaves with an error
 *    message, rank 0 fails naming that rank, the other worker ends well (no hang).
 * 3. A worker whose stop callback fires (a signal to that process alone) after its first
 *    tile: rank 0 stops the hand-out, drops its own tile, ends well with the tiles done
 *    and learns which rank stopped and the callback's value; no rank hangs.
 * 4. Bad arguments are refused. */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "classic_box.h"
#include "trac0r/trac0r.h"

#define W 80
#define H 56
#define RANKS 3
#define MAXMSG 4096

typedef struct msg {
    int src, tag;
    void *data;
    size_t size;
} msg;

/* One mailbox per rank. */
typedef struct post {
    pthread_mutex_t lock;
    pthread_cond_t cond;
    msg box[RANKS][MAXMSG];
    int count[RANKS];
    int broken_rank; /* this rank's sends fail (-1: none) */
} post;

typedef struct rank_ctx {
    post *p;
    int rank;
} rank_ctx;

static int q_send(void *user, int to, int tag, const void *data, size_t size) {
    rank_ctx *c = user;
    post *p = c->p;
    if (c->rank == p->broken_rank && tag == 2) { /* its tile reports */
        return TR_ERR;
    }
    void *copy = malloc(size ? size : 1);
    memcpy(copy, data, size);
    pthread_mutex_lock(&p->lock);
    const int n = p->count[to]++;
    p->box[to][n] = (msg){c->rank, tag, copy, size};
    pthread_cond_broadcast(&p->cond);
    pthread_mutex_unlock(&p->lock);
    return n < MAXMSG - 1 ? TR_OK : TR_ERR;
}

static int q_recv(void *user, int from, int tag, int block, int *src, int *tag_out, void **data,
                  size_t *size) {
    rank_ctx *c = user;
    post *p = c->p;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        for (int i = 0; i < p->count[c->rank]; ++i) {
            msg *m = &p->box[c->rank][i];
            if ((from < 0 || m->src == from) && (tag < 0 || m->tag == tag)) {
                *src = m->src;
                *tag_out = m->tag;
                *data = m->data;
                *size = m->size;
                memmove(m, m + 1, (size_t)(p->count[c->rank] - i - 1) * sizeof *m);
                --p->count[c->rank];
                pthread_mutex_unlock(&p->lock);
                return 1;
            }
        }
        if (!block) {
            pthread_mutex_unlock(&p->lock);
            return 0;
        }
        pthread_cond_wait(&p->cond, &p->lock);
    }
}

typedef struct job {
    rank_ctx ctx;
    tr_scene *scene;
    tr_device *dev;
    tr_session *s;
    tr_share_stats st;
    int rc;
    tr_error err;
    uint32_t progress_done;
    uint32_t stop_after; /* > 0: the stop callback returns 15 after this many tiles */
} job;

static int on_stop(void *user) {
    const job *j = user;
    return j->stop_after > 0 && j->st.tiles >= j->stop_after ? 15 : 0;
}

static void on_progress(void *user, uint32_t done, uint32_t total) {
    (void)total;
    ((job *)user)->progress_done = done;
}

static void *run_rank(void *arg) {
    job *j = arg;
    const tr_transport t = {j->ctx.rank, RANKS, q_send, q_recv, &j->ctx};
    const tr_share_desc d = {.progress = on_progress, .stop = on_stop, .user = j};
    j->rc = tr_session_share(j->s, &t, &d, &j->st, &j->err);
    return NULL;
}

static void open_job(job *j, post *p, int rank) {
    memset(j, 0, sizeof *j);
    j->ctx.p = p;
    j->ctx.rank = rank;
    tr_error err;
    j->scene = classic_box(W, H, &err);
    j->dev = tr_device_create("cpu", &err);
    CHECK(j->scene && j->dev, "%s", err.msg);
    tr_render_config cfg = tr_render_config_default();
    cfg.threads = 1;
    tr_session_desc desc = {.spp = 3};
    j->s = tr_session_create(j->dev, j->scene, &cfg, &desc, &err);
    CHECK(j->s != NULL, "%s", err.msg);
}

static void close_job(job *j) {
    tr_session_destroy(j->s);
    tr_device_destroy(j->dev);
    tr_scene_destroy(j->scene);
}

static void run_all(post *p, job jobs[RANKS], int stopping_rank) {
    pthread_t th[RANKS];
    for (int r = 0; r < RANKS; ++r) {
        open_job(&jobs[r], p, r);
        jobs[r].stop_after = r == stopping_rank ? 1 : 0;
    }
    for (int r = 0; r < RANKS; ++r) {
        pthread_create(&th[r], NULL, run_rank, &jobs[r]);
    }
    for (int r = 0; r < RANKS; ++r) {
        pthread_join(th[r], NULL);
    }
}

static post *new_post(int broken) {
    post *p = calloc(1, sizeof *p);
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->cond, NULL);
    p->broken_rank = broken;
    return p;
}

static void free_post(post *p) {
    for (int r = 0; r < RANKS; ++r) {
        for (int i = 0; i < p->count[r]; ++i) {
            free(p->box[r][i].data);
        }
    }
    pthread_mutex_destroy(&p->lock);
    pthread_cond_destroy(&p->cond);
    free(p);
}

static void test_shared_equals_single(void) {
    post *p = new_post(-1);
    job jobs[RANKS];
    run_all(p, jobs, -1);
    uint32_t tiles = 0;
    for (int r = 0; r < RANKS; ++r) {
        CHECK(jobs[r].rc == TR_OK, "rank %d: %s", r, jobs[r].err.msg);
        tiles += jobs[r].st.tiles;
    }
    const uint32_t count = tr_session_tile_count(jobs[0].s);
    CHECK(tiles == count && jobs[0].st.finished == count && jobs[0].progress_done == count &&
              jobs[0].st.failed_rank == -1,
          "tiles %u, finished %u, progress %u of %u", tiles, jobs[0].st.finished,
          jobs[0].progress_done, count);
    /* One process, the same render. */
    job single;
    open_job(&single, p, 0);
    tr_error err;
    CHECK(tr_session_run(single.s, &err) == TR_OK, "%s", err.msg);
    const tr_film *a = tr_session_film(jobs[0].s, &err), *b = tr_session_film(single.s, &err);
    CHECK(a && b, "%s", err.msg);
    const size_t px = (size_t)W * H;
    CHECK(memcmp(a->sum, b->sum, 3 * px * sizeof *a->sum) == 0 &&
              memcmp(a->count, b->count, px * sizeof *a->count) == 0,
          "the shared film differs from one process's");
    close_job(&single);
    for (int r = 0; r < RANKS; ++r) {
        close_job(&jobs[r]);
    }
    free_post(p);
}

static void test_broken_worker(void) {
    post *p = new_post(2);
    job jobs[RANKS];
    run_all(p, jobs, -1);
    CHECK(jobs[0].rc == TR_ERR && jobs[0].err.code == TR_STATUS_DEVICE &&
              jobs[0].st.failed_rank == 2,
          "rank 0: rc %d, failed rank %d, %s", jobs[0].rc, jobs[0].st.failed_rank, jobs[0].err.msg);
    CHECK(jobs[2].rc == TR_ERR, "the broken rank succeeded");
    CHECK(jobs[1].rc == TR_OK, "rank 1: %s", jobs[1].err.msg);
    for (int r = 0; r < RANKS; ++r) {
        close_job(&jobs[r]);
    }
    free_post(p);
}

static void test_stopped_worker(void) {
    post *p = new_post(-1);
    job jobs[RANKS];
    run_all(p, jobs, 2);
    const uint32_t count = tr_session_tile_count(jobs[0].s);
    for (int r = 0; r < RANKS; ++r) {
        CHECK(jobs[r].rc == TR_OK, "rank %d: %s", r, jobs[r].err.msg);
    }
    CHECK(jobs[0].st.stop_rank == 2 && jobs[0].st.stop_code == 15 && jobs[0].st.failed_rank == -1,
          "rank 0: stop rank %d, code %d", jobs[0].st.stop_rank, jobs[0].st.stop_code);
    CHECK(jobs[0].st.finished >= 1 && jobs[0].st.finished < count, "%u of %u tiles finished",
          jobs[0].st.finished, count);
    for (int r = 0; r < RANKS; ++r) {
        close_job(&jobs[r]);
    }
    free_post(p);
}

static void test_bad_arguments(void) {
    post *p = new_post(-1);
    job j;
    open_job(&j, p, 0);
    tr_error err;
    tr_transport t = {0, 0, q_send, q_recv, &j.ctx};
    CHECK_STATUS(tr_session_share(j.s, &t, NULL, NULL, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "size 0");
    t.size = 1;
    t.recv = NULL;
    CHECK_STATUS(tr_session_share(j.s, &t, NULL, NULL, &err), err, TR_STATUS_INVALID_ARGUMENT,
                 "no recv");
    /* One rank alone renders every tile itself. */
    t.recv = q_recv;
    tr_share_stats st;
    CHECK(tr_session_share(j.s, &t, NULL, &st, &err) == TR_OK, "%s", err.msg);
    CHECK(st.tiles == tr_session_tile_count(j.s) && st.rays > 0, "alone: %u tiles", st.tiles);
    close_job(&j);
    free_post(p);
}

int main(void) {
    test_shared_equals_single();
    test_broken_worker();
    test_stopped_worker();
    test_bad_arguments();
    return check_finish("test_share");
}
