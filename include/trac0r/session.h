/* session.h - an offline render as one job: passes of samples over a device, adaptive
 * stopping, a time limit, cancelling, progress, checkpoints and resume, denoising, and the
 * tile plan of a render shared by several processes.
 *
 *     tr_session_desc desc = {0};           // zero means the defaults: 16 spp, no limits
 *     desc.spp = 64;
 *     desc.time_limit = 10.0;               // seconds
 *     desc.progress = on_progress;          // after every pass; nonzero stops the render
 *     tr_session *s = tr_session_create(dev, scene, &cfg, &desc, &err);
 *     if (!s || tr_session_run(s, &err) != TR_OK) { puts(err.msg); ... }
 *     const tr_film *film = tr_session_film(s, &err);
 *     tr_film_write(film, "out.png", 0.0f, &err);
 *     tr_session_destroy(s);
 *
 * Every decision is taken between passes, and the adaptive one from film values alone, so
 * the image depends only on the passes made: a render the time limit stopped after k
 * passes equals one asked for k samples, and a resumed render equals an uninterrupted one
 * bit for bit. The library installs no signal handlers: tr_session_cancel is one atomic
 * store, which a program may call from its own handler.
 *
 * A checkpoint holds the film's arrays bit for bit, the samples each tile of the tile plan
 * holds, and the render's identity (the scene's geometry, materials and camera, the scene
 * file's bytes, the size, seed, depth, integrator, structure, stride, passes, sampler,
 * light selection and roulette start); resuming refuses any other render. One format serves
 * a render in one process and one shared by many (tr_session_render_tile and
 * tr_session_put_tile): either resumes the other. */
#ifndef TRAC0R_SESSION_H
#define TRAC0R_SESSION_H

#include <stddef.h>
#include <stdint.h>

#include "trac0r/device.h"
#include "trac0r/error.h"
#include "trac0r/film.h"
#include "trac0r/render.h"
#include "trac0r/scene.h"

typedef struct tr_session tr_session;

#define TR_SESSION_SPP_DEFAULT 16u
#define TR_SESSION_SPP_MAX 1000000u
/* Seconds between checkpoints when tr_session_desc.checkpoint_interval is 0. */
#define TR_SESSION_CHECKPOINT_INTERVAL 60.0
/* The tile plan's squares, in traced pixels (times the stride in pixels). */
#define TR_SESSION_TILE 32u
/* Adaptive sampling's tiles (pixels) and the first sample count it tests at. */
#define TR_SESSION_ADAPT_TILE 8u
#define TR_SESSION_ADAPT_FIRST_CHECK 16u

/* Why tr_session_run returned. */
typedef enum tr_session_end {
    TR_SESSION_NOT_RUN = 0,
    TR_SESSION_DONE,       /* every pixel has the samples asked for */
    TR_SESSION_CONVERGED,  /* the noise threshold stopped every tile before that */
    TR_SESSION_TIME_LIMIT, /* the next pass would have ended after the time limit */
    TR_SESSION_CANCELLED   /* tr_session_cancel, or the progress callback said stop */
} tr_session_end;

/* Where a session stands (tr_session_progress_get, and the progress callback). */
typedef struct tr_session_progress {
    uint32_t samples;       /* passes made: the samples of every pixel still rendering */
    uint32_t spp;           /* the most a pixel gets */
    uint32_t first;         /* samples the film held when the session began (resumed) */
    uint32_t tiles;         /* adaptive tiles, or the tile plan's tiles after a resume
                               from a partial tile checkpoint */
    uint32_t tiles_done;    /* of them converged (adaptive) or finished */
    uint64_t pixel_samples; /* pixel samples traced by this session */
    uint64_t rays;          /* intersection queries made by this session */
    double seconds;         /* wall time inside tr_session_run */
    tr_session_end end;     /* TR_SESSION_NOT_RUN while running */
} tr_session_progress;

/* Called after every pass (or tile); a nonzero return stops the render there, as
 * tr_session_cancel does (Embree's progress monitor has this shape). */
typedef int (*tr_session_progress_fn)(void *user, const tr_session_progress *p);

/* What the job is. Zero-initialised, every field means its default. */
typedef struct tr_session_desc {
    uint32_t spp;          /* samples per pixel, 1..TR_SESSION_SPP_MAX; 0: 16, or the
                              checkpoint's when resuming */
    float noise_threshold; /* adaptive sampling (0: off): every 8x8 tile stops once its
                              pixels' mean error estimate is below this, tested at 16, 32,
                              64, ... samples; not with a stride above 1 or checkpoints */
    double time_limit;     /* seconds (0: none): stop before a pass that would end later */
    tr_session_progress_fn progress; /* NULL: none */
    void *progress_user;
    const char *checkpoint;     /* write checkpoints here (NULL: none): every interval,
                                   when cancelled, and at the end; atomically */
    double checkpoint_interval; /* seconds; 0: TR_SESSION_CHECKPOINT_INTERVAL; < 0: after
                                   every pass */
    const char *resume;         /* continue the render saved here (NULL: start empty) */
    const char *scene_file;     /* the file the scene came from, hashed into the
                                   checkpoint's identity (NULL: none, a built-in scene) */
    int denoise;                /* keep the albedo, normal and depth passes in the film so
                                   that tr_session_denoise can guide its filter */
} tr_session_desc;

/* A session rendering `scene` (committed; uploaded to dev here unless it is dev's scene
 * already) from its camera with cfg's settings (NULL: the defaults). With desc->resume the
 * checkpoint is read and checked here: a damaged file is TR_STATUS_PARSE, another render's
 * TR_STATUS_INVALID_ARGUMENT naming the first setting that differs, a desc.spp below the
 * samples it holds TR_STATUS_LIMIT. The device and scene
 * must outlive the session. */
tr_session *tr_session_create(tr_device *dev, const tr_scene *scene, const tr_render_config *cfg,
                              const tr_session_desc *desc, tr_error *err);
void tr_session_destroy(tr_session *s);

/* Renders until the samples are made, the noise threshold or time limit stops it, or it is
 * cancelled (tr_session_progress_get says which); may be called again after a cancel to
 * go on. TR_ERR when a frame or a checkpoint fails. */
int tr_session_run(tr_session *s, tr_error *err);
/* Asks the run to stop at the end of the pass under way. Async-signal-safe. */
void tr_session_cancel(tr_session *s);
void tr_session_progress_get(const tr_session *s, tr_session_progress *out);

/* The film as the passes left it (read back from the device when it changed): sums and
 * counts of radiance and of the passes kept. Owned by the session. */
const tr_film *tr_session_film(tr_session *s, tr_error *err);
/* The film's radiance through the edge-avoiding a-trous filter guided by its albedo,
 * normal and depth (desc.denoise keeps them), into `out` (allocated here, radiance only,
 * one sample per covered pixel; free it with tr_film_free). */
int tr_session_denoise(tr_session *s, tr_film *out, tr_error *err);
/* Writes a checkpoint of the film as it stands to path (NULL: desc.checkpoint). */
int tr_session_checkpoint(tr_session *s, const char *path, tr_error *err);
/* The render's identity: a "size=WxH seed=S ..." description (naming the settings) and a
 * hash of the scene's contents; two processes that agree on both render the same image. */
const char *tr_session_identity(tr_session *s, uint64_t *scene_hash, tr_error *err);

/* The tile plan, for a render shared by several processes: squares of TR_SESSION_TILE
 * traced pixels, row by row. Rendering a tile whole, in one call, accumulates each pixel's
 * samples in the same order as passes do, so tiles rendered anywhere make the image a
 * single process makes, bit for bit. */
uint32_t tr_session_tile_count(const tr_session *s);
/* Tile k's rectangle and the samples its pixels hold in the session's film. */
int tr_session_tile(const tr_session *s, uint32_t k, tr_rect *rect, uint32_t *samples,
                    tr_error *err);
/* Renders the samples tile k lacks, up to the session's spp, into the device's film in one
 * call; `cancel` (may be NULL) is asked between pieces of the tile as
 * tr_render_config.cancel is (a cancelled tile fails with TR_STATUS_CANCELLED and is
 * dropped). tr_session_film then holds the tile. */
int tr_session_render_tile(tr_session *s, uint32_t k, int (*cancel)(void *user), void *user,
                           tr_render_stats *stats, tr_error *err);
/* Puts tile k, rendered whole by another process and packed by tr_film_pack_rect from its
 * session's film, into this session's film. */
int tr_session_put_tile(tr_session *s, uint32_t k, const void *pixels, size_t size, tr_error *err);

/* ---- One session shared by several processes -------------------------------------- */

/* How the processes of a shared render reach each other: the library makes and reads the
 * messages, the program carries them (MPI, sockets). Tags are 1..TR_SHARE_TAGS; a program
 * may use higher tags of its own before and after tr_session_share. */
#define TR_SHARE_TAGS 5
typedef struct tr_transport {
    int rank, size; /* this process and how many there are; rank 0 coordinates */
    /* Sends `size` bytes to rank `to` as message kind `tag`. TR_OK or TR_ERR. */
    int (*send)(void *user, int to, int tag, const void *data, size_t size);
    /* The next message for this process from rank `from` (-1: any) of kind `tag` (-1:
     * any). Without `block` it returns 0 at once when none is waiting (a blocking wait
     * should not spin: the other ranks may share the cores). 1: *src, *tag_out, and
     * *data (malloc'ed; the library frees it) of *size bytes. Negative on failure. */
    int (*recv)(void *user, int from, int tag, int block, int *src, int *tag_out, void **data,
                size_t *size);
    void *user;
} tr_transport;

/* A shared render's settings. Zero-initialised: no checkpoints, no stop, no progress. */
typedef struct tr_share_desc {
    int checkpoint;             /* rank 0 writes the session's checkpoint (desc.checkpoint) */
    double checkpoint_interval; /* every this many seconds (0: whenever it can) */
    int (*stop)(void *user);    /* asked often: nonzero hands out no more tiles and drops
                                   the tiles under way (a signal); a worker's value
                                   reaches rank 0 (tr_share_stats.stop_code), whose own
                                   tile is dropped too */
    /* rank 0: tiles finished of those to do, after each; may be NULL */
    void (*progress)(void *user, uint32_t done, uint32_t total);
    void *user;
} tr_share_desc;

/* Where a rank's time went, and what it did. */
typedef struct tr_share_stats {
    double render, wait, serve, pixels, total; /* seconds: rendering tiles, blocked on a
                                                  message, answering between tiles (rank
                                                  0), reading and moving pixels; all */
    uint32_t tiles;                            /* tiles this rank rendered */
    uint64_t rays;     /* rank 0: of every rank's tiles; others: their own */
    uint32_t finished; /* rank 0: tiles whose pixels the film holds in full (a checkpoint's
                          included) */
    int failed_rank;   /* rank 0: the rank whose failure ended the share (-1: none) */
    int stop_rank;     /* rank 0: the worker whose stop ended the share (-1: none) */
    int stop_code;     /* and the nonzero value its tr_share_desc.stop returned */
} tr_share_stats;

/* Renders the session's tile plan shared between the transport's ranks, each with its
 * own session of the same render (tr_session_identity agrees: check it before). Rank 0
 * hands the tiles out one at a time as ranks finish (each worker holds two, one near the
 * end) and renders tiles itself, answering between the pieces of its tile; workers send
 * their pixels in batches (at each checkpoint interval and at the end). Tiles never
 * overlap, so rank 0's film ends bit-identical to a single process's, whatever the ranks
 * and whichever took which tile. An error on any rank stops the hand-out; rank 0 fails with
 * the first one ("rank N: ..."). Every rank returns once the hand-out is over. */
int tr_session_share(tr_session *s, const tr_transport *t, const tr_share_desc *d,
                     tr_share_stats *stats, tr_error *err);

/* The error estimate adaptive sampling gives one pixel: the L1 distance between the means
 * of all N samples (full) and of the first N/2 (half), over the square root of full's sum,
 * so that the threshold reads as a relative error, looser where the image is dark (the
 * normalisation of Cycles' adaptive sampling). */
double tr_session_pixel_error(const float full[3], const float half[3]);

#endif
