/* view_render.c - the viewer's render thread. */
#define _POSIX_C_SOURCE 200809L
#include "view_render.h"
#include "cli.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void view_tonemap(const tr_film *film, float exposure, uint32_t *pixels) {
    /* The PNG writer's transform (post.h): a screenshot holds the window's bytes. Cannot
     * fail: the rectangle is the whole film and the stride one row. */
    tr_tonemap_film(film, 0, 0, film->width, film->height, exposure, TR_PIXEL_ARGB8888, pixels,
                    (size_t)film->width * sizeof *pixels, NULL);
}

static int same_view(const tr_camera *a, const tr_camera *b) {
    /* Bitwise on purpose: any change of any bit is a new view (tr_camera has no
     * padding: 23 four-byte members). */
    return memcmp(a, b, sizeof *a) == 0; /* NOLINT(bugprone-suspicious-memory-comparison) */
}

/* Makes the film and back buffer match w x h (cleared). */
static int resize_buffers(view_renderer *r, uint32_t w, uint32_t h, tr_error *err) {
    if (r->film.sum && r->film.width == w && r->film.height == h) {
        tr_film_clear(&r->film);
        return TR_OK;
    }
    tr_film_free(&r->film);
    free(r->back);
    r->back = NULL;
    if (tr_film_init(&r->film, w, h, err) != TR_OK) {
        return TR_ERR;
    }
    r->back = malloc((size_t)w * h * sizeof *r->back);
    if (!r->back) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u frame", w, h);
    }
    return TR_OK;
}

/* The device asks this before each tile (the CPU device; others finish the frame). */
static int render_cancelled(void *user) {
    view_renderer *r = user;
    return atomic_load(&r->cancel);
}

/* One frame of sample `spp` on the device, read back into r->film. */
static int render_one(view_renderer *r, const tr_camera *cam, const tr_render_config *cfg,
                      uint32_t spp, tr_render_stats *st, tr_error *err) {
    if (tr_device_render(r->dev, cam, cfg, spp, 1, NULL, st, err) != TR_OK) {
        return TR_ERR;
    }
    if (atomic_load(&r->cancel)) {
        return tr_error_set(err, TR_STATUS_CANCELLED,
                            "frame cancelled"); /* the view changed meanwhile */
    }
    return tr_device_read_film(r->dev, &r->film, err);
}

static void *render_main(void *arg) {
    view_renderer *r = arg;
    uint64_t gen = UINT64_MAX; /* the generation the film holds */
    uint32_t spp = 0;
    float tonemapped_exposure = 0.0f;
    tr_error err;
    pthread_mutex_lock(&r->mu);
    while (!r->quit) {
        if (r->shot_path[0]) {
            int ok = 0;
            if (spp == 0) {
                snprintf(r->shot_msg, sizeof r->shot_msg, "%s: no samples yet", r->shot_path);
            } else if (tr_film_write(&r->film, r->shot_path, r->exposure, &err) != TR_OK) {
                snprintf(r->shot_msg, sizeof r->shot_msg, "%s", err.msg);
            } else {
                ok = 1;
                snprintf(r->shot_msg, sizeof r->shot_msg, "%s (%u spp)", r->shot_path, spp);
            }
            r->shot_ok = ok;
            r->shot_done = 1;
            r->shot_path[0] = '\0';
        }
        tr_camera cam = r->cam;
        const int stride = r->stride;
        const float exposure = r->exposure;
        const uint64_t want = r->generation;
        if (want == gen && r->max_spp && spp >= r->max_spp) {
            if (exposure != tonemapped_exposure && r->pixels) {
                /* Idle, but the exposure changed: show the film with the new one. */
                view_tonemap(&r->film, exposure, r->pixels);
                tonemapped_exposure = exposure;
                r->seq += 1;
                continue;
            }
            pthread_cond_wait(&r->cv, &r->mu); /* converged: idle until something changes */
            continue;
        }
        atomic_store(&r->cancel, 0);
        if (r->animate) {
            /* The scene moves: every frame is a new image. Under mu, as the UI thread
             * reads the scene's boxes. */
            const double t0 = tr_time_now();
            if (cli_animate(r->scene, (uint32_t)(r->updates + 1), &err) != TR_OK ||
                tr_scene_update(r->scene, NULL, &err) != TR_OK ||
                tr_device_upload(r->dev, r->scene, &err) != TR_OK) {
                r->failed = 1;
                snprintf(r->error, sizeof r->error, "--animate: %s", err.msg);
                break;
            }
            r->rebuild_ms = (tr_time_now() - t0) * 1e3;
            r->updates += 1;
            gen = UINT64_MAX;
        }
        pthread_mutex_unlock(&r->mu);

        if (want != gen) {
            if (resize_buffers(r, cam.screen_width, cam.screen_height, &err) != TR_OK ||
                tr_device_clear(r->dev, &err) != TR_OK) {
                pthread_mutex_lock(&r->mu);
                r->failed = 1;
                snprintf(r->error, sizeof r->error, "%s", err.msg);
                break;
            }
            gen = want;
            spp = 0;
        }
        tr_render_config cfg = r->cfg;
        cfg.stride = stride;
        cfg.cancel = render_cancelled;
        cfg.cancel_user = r;
        tr_render_stats st;
        /* Animated, each frame is sample 0 of a new image: the frame count picks its
         * random numbers instead, so that the noise changes from frame to frame. */
        const uint32_t sample = r->animate ? (uint32_t)r->updates : spp;
        int rc = render_one(r, &cam, &cfg, sample, &st, &err);
        if (rc != TR_OK) {
            pthread_mutex_lock(&r->mu);
            if (err.code == TR_STATUS_CANCELLED) {
                /* The film holds part of a sample: start this view over. */
                gen = UINT64_MAX;
                r->cancelled += 1;
                continue;
            }
            r->failed = 1;
            snprintf(r->error, sizeof r->error, "%s", err.msg);
            break;
        }
        ++spp;
        double t0 = tr_time_now();
        view_tonemap(&r->film, exposure, r->back);
        tonemapped_exposure = exposure;
        double t1 = tr_time_now();

        pthread_mutex_lock(&r->mu);
        uint32_t *tmp = r->pixels;
        r->pixels = r->back;
        r->back = tmp;
        if (!r->back || r->pw != cam.screen_width || r->ph != cam.screen_height) {
            free(r->back);
            r->back = malloc((size_t)cam.screen_width * cam.screen_height * sizeof *r->back);
            if (!r->back) {
                r->failed = 1;
                snprintf(r->error, sizeof r->error, "out of memory for a frame");
                break;
            }
        }
        r->pw = cam.screen_width;
        r->ph = cam.screen_height;
        r->seq += 1;
        r->shown_gen = gen;
        r->spp = spp;
        r->render_ms = st.seconds * 1e3;
        r->tonemap_ms = (t1 - t0) * 1e3;
        r->frames_done += 1;
    }
    pthread_mutex_unlock(&r->mu);
    return NULL;
}

int view_renderer_start(view_renderer *r, tr_scene *scene, int animate, tr_device *dev,
                        const tr_render_config *cfg, const tr_camera *cam, int stride,
                        float exposure, uint32_t max_spp, tr_error *err) {
    memset(r, 0, sizeof *r);
    r->scene = scene;
    r->animate = animate;
    r->dev = dev;
    r->cfg = *cfg;
    r->max_spp = max_spp;
    r->cam = *cam;
    r->stride = stride;
    r->exposure = exposure;
    r->generation = 1;
    atomic_init(&r->cancel, 0);
    pthread_mutex_init(&r->mu, NULL);
    pthread_cond_init(&r->cv, NULL);
    int rc = pthread_create(&r->thread, NULL, render_main, r);
    if (rc != 0) {
        pthread_cond_destroy(&r->cv);
        pthread_mutex_destroy(&r->mu);
        return tr_error_set(err, TR_STATUS_LIMIT, "cannot start the render thread: %s",
                            strerror(rc));
    }
    r->started = 1;
    return TR_OK;
}

void view_renderer_set_view(view_renderer *r, const tr_camera *cam, int stride) {
    pthread_mutex_lock(&r->mu);
    if (!same_view(&r->cam, cam) || r->stride != stride) {
        r->cam = *cam;
        r->stride = stride;
        r->generation += 1;
        atomic_store(&r->cancel, 1);
        pthread_cond_signal(&r->cv);
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
    tr_film_free(&r->film);
    free(r->back);
    free(r->pixels);
    r->back = NULL;
    r->pixels = NULL;
    r->started = 0;
}
