/* view_render.c - the viewer's render thread. */
#define _POSIX_C_SOURCE 200809L
#include "view_render.h"
#include "cli.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void view_tonemap(const tr_film *film, float exposure, int curve, uint32_t *pixels) {
    /* The PNG writer's transform (post.h): a screenshot holds the window's bytes. Cannot
     * fail: the rectangle is the whole film, the stride one row, the curve checked. */
    tr_tonemap_film_curve(film, 0, 0, film->width, film->height, exposure, curve, TR_PIXEL_ARGB8888,
                          pixels, (size_t)film->width * sizeof *pixels, NULL);
}

static int same_view(const tr_camera *a, const tr_camera *b) {
    /* Bitwise on purpose: any change of any bit is a new view (tr_camera has no
     * padding: 23 four-byte members). */
    return memcmp(a, b, sizeof *a) == 0; /* NOLINT(bugprone-suspicious-memory-comparison) */
}

/* Makes back hold at least w x h pixels. */
static int size_back(view_renderer *r, uint32_t w, uint32_t h) {
    const size_t px = (size_t)w * h;
    if (r->back && r->back_px >= px) {
        return TR_OK;
    }
    free(r->back);
    r->back = malloc(px * sizeof *r->back);
    r->back_px = r->back ? px : 0;
    return r->back ? TR_OK : TR_ERR;
}

/* The device asks this before each tile (the CPU device; others finish the frame), and
 * tr_realtime once the frame is done. */
static int render_cancelled(void *user) {
    view_renderer *r = user;
    return atomic_load(&r->cancel);
}

/* F12, under mu: the film of samples as `trac0r render` writes it. */
static void take_shot(view_renderer *r, uint32_t spp) {
    tr_error err;
    const tr_film *film = NULL;
    int ok = 0;
    if (spp == 0) {
        snprintf(r->shot_msg, sizeof r->shot_msg, "%s: no samples yet", r->shot_path);
    } else if (tr_realtime_film(r->rt, &film, &err) != TR_OK ||
               tr_film_write_curve(film, r->shot_path, r->exposure, r->curve, &err) != TR_OK) {
        snprintf(r->shot_msg, sizeof r->shot_msg, "%s", err.msg);
    } else {
        ok = 1;
        snprintf(r->shot_msg, sizeof r->shot_msg, "%s (%u spp)", r->shot_path, spp);
    }
    r->shot_ok = ok;
    r->shot_done = 1;
    r->shot_path[0] = '\0';
}

/* --animate, under mu (the UI thread reads the scene's boxes): moves the scene's last
 * shape, animates the lights (--animate-light) and uploads the scene. */
static int animate_scene(view_renderer *r, tr_error *err) {
    const double t0 = tr_time_now();
    const uint32_t frame = (uint32_t)(r->updates + 1);
    if (tr_scene_animate_sway(r->scene, frame, err) != TR_OK ||
        tr_scene_animate_light(r->scene, frame, r->animate - 1, err) != TR_OK ||
        tr_scene_update(r->scene, NULL, err) != TR_OK ||
        tr_device_upload(r->dev, r->scene, err) != TR_OK) {
        return TR_ERR;
    }
    r->rebuild_ms = (tr_time_now() - t0) * 1e3;
    r->updates += 1;
    return TR_OK;
}

/* Under mu: the frame `res` of generation gen, tonemapped into back, goes on screen. */
static void publish(view_renderer *r, const tr_realtime_result *res, uint64_t gen,
                    double tonemap_ms) {
    uint32_t *tmp = r->pixels;
    const size_t tmp_px = r->pixels_px;
    r->pixels = r->back;
    r->pixels_px = r->back_px;
    r->back = tmp;
    r->back_px = tmp_px;
    r->pw = res->width;
    r->ph = res->height;
    r->scale = res->scale;
    r->frame_spp = res->frame_spp;
    r->seq += 1;
    r->shown_gen = gen;
    r->spp = res->spp;
    r->render_ms = res->render_ms;
    r->tonemap_ms = tonemap_ms;
    r->temporal_ms = res->temporal_ms;
    r->spatial_ms = res->spatial_ms;
    r->frames_done += 1;
}

/* Under mu: the thread stops, r->error saying why. */
static void fail(view_renderer *r, const char *what, const char *msg) {
    r->failed = 1;
    snprintf(r->error, sizeof r->error, "%s%s", what, msg);
}

static void *render_main(void *arg) {
    view_renderer *r = arg;
    uint64_t gen = UINT64_MAX; /* the generation the film holds */
    uint32_t spp = 0;
    float tonemapped_exposure = 0.0f;
    double tonemap_ms = 0.0; /* the last frame's, counted into the budget */
    tr_error err;
    pthread_mutex_lock(&r->mu);
    while (!r->quit) {
        if (r->shot_path[0]) {
            take_shot(r, spp);
        }
        const tr_camera cam = r->cam;
        const float exposure = r->exposure;
        const uint64_t want = r->generation;
        tr_realtime_frame_desc fd = {0};
        fd.camera = &cam;
        fd.stride = r->stride;
        fd.moving = r->moving;
        fd.method = r->recon;
        fd.budget_ms = r->budget_ms;
        fd.extra_ms = tonemap_ms;
        fd.cancel = render_cancelled;
        fd.cancel_user = r;
        if (want == gen && r->max_spp && spp >= r->max_spp) {
            if (exposure != tonemapped_exposure && r->pixels && r->shown) {
                /* Idle, but the exposure changed: show the frame with the new one. */
                view_tonemap(r->shown, exposure, r->curve, r->pixels);
                tonemapped_exposure = exposure;
                r->seq += 1;
                continue;
            }
            pthread_cond_wait(&r->cv, &r->mu); /* converged: idle until something changes */
            continue;
        }
        atomic_store(&r->cancel, 0);
        if (r->animate) {
            /* The scene moves: every frame is a new image. */
            if (animate_scene(r, &err) != TR_OK) {
                fail(r, "--animate: ", err.msg);
                break;
            }
            gen = UINT64_MAX;
        }
        /* Only a refinement of a view on screen may be cancelled (view_render.h); an
         * animated frame is always a new image. */
        atomic_store(&r->refining, want == gen && spp > 0);
        fd.restart = want != gen;
        r->shown = NULL; /* tr_realtime_frame replaces it */
        pthread_mutex_unlock(&r->mu);

        tr_realtime_result res;
        const int rc = tr_realtime_frame(r->rt, &fd, &res, &err);
        if (rc != TR_OK) {
            pthread_mutex_lock(&r->mu);
            if (err.code == TR_STATUS_CANCELLED) {
                /* The film holds part of a sample: start this view over. */
                gen = UINT64_MAX;
                r->cancelled += 1;
                continue;
            }
            fail(r, "", err.msg);
            break;
        }
        gen = want;
        spp = res.spp;
        const double t0 = tr_time_now();
        const int sized = size_back(r, res.width, res.height);
        if (sized == TR_OK) {
            view_tonemap(res.film, exposure, r->curve, r->back);
            tonemapped_exposure = exposure;
        }
        tonemap_ms = (tr_time_now() - t0) * 1e3;
        pthread_mutex_lock(&r->mu);
        if (sized != TR_OK) {
            fail(r, "", "out of memory for a frame");
            break;
        }
        r->shown = res.film;
        publish(r, &res, gen, tonemap_ms);
    }
    pthread_mutex_unlock(&r->mu);
    return NULL;
}

int view_renderer_start(view_renderer *r, tr_scene *scene, int animate, tr_device *dev,
                        const tr_render_config *cfg, int motion_sampler,
                        const tr_recon_params *params, const tr_camera *cam, int stride,
                        float exposure, int curve, uint32_t max_spp, const tr_realtime_desc *rt,
                        tr_error *err) {
    memset(r, 0, sizeof *r);
    r->scene = scene;
    r->animate = animate;
    r->dev = dev;
    r->cfg = *cfg;
    r->max_spp = max_spp;
    r->cam = *cam;
    r->stride = stride;
    r->exposure = exposure;
    r->curve = curve;
    r->generation = 1;
    r->budget_ms = 1000.0 / 60.0;
    r->scale = 1.0f;
    /* At rest the film accumulates with cfg's sampler, so that F12 equals `trac0r
     * render`; moving or animated frames take motion_sampler. */
    tr_realtime_desc desc = {0};
    if (rt) {
        desc = *rt;
    }
    desc.config = cfg;
    desc.recon = params;
    desc.sampler = TR_REALTIME_SAMPLER(motion_sampler);
    desc.accumulate = 1;
    desc.animated = animate;
    /* Moving frames keep the window's resolution: under the budget they trace down to a
     * quarter of the pixels and are upscaled, never shown as blocks (realtime.h). */
    desc.budget_upscale = 1;
    if (!(r->rt = tr_realtime_create(dev, scene, &desc, err))) {
        return TR_ERR;
    }
    atomic_init(&r->cancel, 0);
    atomic_init(&r->refining, 0);
    pthread_mutex_init(&r->mu, NULL);
    pthread_cond_init(&r->cv, NULL);
    int rc = pthread_create(&r->thread, NULL, render_main, r);
    if (rc != 0) {
        tr_realtime_destroy(r->rt);
        r->rt = NULL;
        pthread_cond_destroy(&r->cv);
        pthread_mutex_destroy(&r->mu);
        return tr_error_set(err, TR_STATUS_LIMIT, "cannot start the render thread: %s",
                            strerror(rc));
    }
    r->started = 1;
    return TR_OK;
}

/* A new view (under r->mu): a new generation, a refinement under way dropped. */
static void new_generation(view_renderer *r) {
    r->generation += 1;
    if (atomic_load(&r->refining)) {
        atomic_store(&r->cancel, 1);
    }
    pthread_cond_signal(&r->cv);
}

void view_renderer_set_view(view_renderer *r, const tr_camera *cam, int stride, int moving) {
    pthread_mutex_lock(&r->mu);
    if (!same_view(&r->cam, cam) || r->stride != stride || r->moving != moving) {
        r->cam = *cam;
        r->stride = stride;
        r->moving = moving;
        new_generation(r);
    }
    pthread_mutex_unlock(&r->mu);
}

void view_renderer_set_budget(view_renderer *r, double budget_ms) {
    pthread_mutex_lock(&r->mu);
    r->budget_ms = budget_ms;
    pthread_mutex_unlock(&r->mu);
}

void view_renderer_set_recon(view_renderer *r, int method) {
    pthread_mutex_lock(&r->mu);
    if (r->recon != method) {
        r->recon = method;
        new_generation(r);
    }
    pthread_mutex_unlock(&r->mu);
}

void view_renderer_set_exposure(view_renderer *r, float exposure) {
    pthread_mutex_lock(&r->mu);
    r->exposure = exposure;
    pthread_cond_signal(&r->cv);
    pthread_mutex_unlock(&r->mu);
}

void view_renderer_screenshot(view_renderer *r, const char *path) {
    pthread_mutex_lock(&r->mu);
    snprintf(r->shot_path, sizeof r->shot_path, "%s", path);
    r->shot_done = 0;
    pthread_cond_signal(&r->cv);
    pthread_mutex_unlock(&r->mu);
}

void view_renderer_stop(view_renderer *r) {
    if (!r->started) {
        return;
    }
    pthread_mutex_lock(&r->mu);
    r->quit = 1;
    atomic_store(&r->cancel, 1);
    pthread_cond_signal(&r->cv);
    pthread_mutex_unlock(&r->mu);
    pthread_join(r->thread, NULL);
    pthread_cond_destroy(&r->cv);
    pthread_mutex_destroy(&r->mu);
    tr_realtime_destroy(r->rt);
    r->rt = NULL;
    r->shown = NULL;
    free(r->back);
    free(r->pixels);
    r->back = NULL;
    r->pixels = NULL;
    r->started = 0;
}
