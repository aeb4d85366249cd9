/* view_render.c - the viewer's render thread. */
#define _POSIX_C_SOURCE 200809L
#include "view_render.h"
#include "cli.h"
#include "view_camera.h"

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

/* F12: the film as `trac0r render --tonemap CURVE` writes it. */
static int write_shot(const tr_film *film, const char *path, float exposure, int curve,
                      tr_error *err) {
    if (curve == TR_TONEMAP_CLAMP || tr_image_format_from_path(path) != TR_IMAGE_PNG) {
        return tr_film_write(film, path, exposure, err);
    }
    tr_film disp;
    if (tr_tonemap_display_film(film, exposure, curve, &disp, err) != TR_OK) {
        return TR_ERR;
    }
    const int rc = tr_film_write(&disp, path, 0.0f, err);
    tr_film_free(&disp);
    return rc;
}

static int same_view(const tr_camera *a, const tr_camera *b) {
    /* Bitwise on purpose: any change of any bit is a new view (tr_camera has no
     * padding: 23 four-byte members). */
    return memcmp(a, b, sizeof *a) == 0; /* NOLINT(bugprone-suspicious-memory-comparison) */
}

/* Makes the film (keeping `passes`) and back buffer match w x h (cleared). */
static int resize_buffers(view_renderer *r, uint32_t w, uint32_t h, uint32_t passes,
                          tr_error *err) {
    if (r->film.sum && r->film.width == w && r->film.height == h && r->film.passes == passes) {
        tr_film_clear(&r->film);
        return TR_OK;
    }
    tr_film_free(&r->film);
    free(r->back);
    r->back = NULL;
    if (tr_film_init_passes(&r->film, w, h, passes, err) != TR_OK) {
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

/* One frame of samples spp .. spp + n - 1 on the device, read back into r->film unless
 * `read` is 0: a frame reconstructed on an OpenCL device needs its film only there, and at
 * 1920x1080 reading the film with its passes took 10-12 ms a frame on an H100
 * (docs/gpu.md). r->film_stale then says so, and F12 reads it. */
static int render_one(view_renderer *r, const tr_camera *cam, const tr_render_config *cfg,
                      uint32_t spp, uint32_t n, int read, tr_render_stats *st, tr_error *err) {
    if (tr_device_render(r->dev, cam, cfg, spp, n, NULL, st, err) != TR_OK) {
        return TR_ERR;
    }
    if (atomic_load(&r->cancel)) {
        return tr_error_set(err, TR_STATUS_CANCELLED,
                            "frame cancelled"); /* the view changed meanwhile */
    }
    r->film_stale = !read;
    return read ? tr_device_read_film(r->dev, &r->film, err) : TR_OK;
}

/* Reads the device's film into r->film if render_one left it there. */
static int film_current(view_renderer *r, tr_error *err) {
    if (r->film_stale) {
        if (tr_device_read_film(r->dev, &r->film, err) != TR_OK) {
            return TR_ERR;
        }
        r->film_stale = 0;
    }
    return TR_OK;
}

/* --animate: how far each primitive moved since the last reconstructed frame, as
 * tr_recon_frame_moving takes it (tr_scene_take_motion); NULL when nothing moved or memory
 * runs out (the history of moving shapes is then rejected, as without motion). *ids gets
 * the table's size. */
static const tr_vec3 *animate_motion(view_renderer *r, uint32_t *ids) {
    *ids = 0;
    if (!r->animate) {
        return NULL;
    }
    const uint32_t n = tr_scene_triangle_count(r->scene) + 1;
    if (r->motion_ids != n) {
        free(r->motion);
        r->motion = calloc(n, sizeof *r->motion);
        r->motion_ids = r->motion ? n : 0;
    }
    int moved = 0;
    tr_error err;
    if (!r->motion || tr_scene_take_motion(r->scene, r->motion, n, &moved, &err) != TR_OK ||
        !moved) {
        return NULL;
    }
    *ids = n;
    return r->motion;
}

/* The film through reconstruction `method` into r->disp (sized to the film; a new size
 * starts the history over). */
static int reconstruct(view_renderer *r, const tr_camera *cam, int method, int threads,
                       tr_error *err) {
    const uint32_t w = r->film.width, h = r->film.height;
    const tr_recon_params p = r->params;
    uint32_t ids;
    const tr_vec3 *motion = animate_motion(r, &ids);
    if (strcmp(tr_device_kind(r->dev), "opencl") == 0) {
        /* On an OpenCL device the stages run where the film lies (recon_device.h). */
        if (!r->rdev || r->disp.width != w || r->disp.height != h) {
            tr_recon_device_close(r->rdev);
            tr_film_free(&r->disp);
            if (!(r->rdev = tr_recon_device_open(r->dev, w, h, err)) ||
                tr_film_init(&r->disp, w, h, err) != TR_OK) {
                return TR_ERR;
            }
            for (size_t i = 0; i < (size_t)w * h; ++i) {
                r->disp.count[i] = 1;
            }
        }
        if (tr_recon_device_frame(r->rdev, cam, motion, ids, method, &p, r->disp.sum, err) !=
            TR_OK) {
            return TR_ERR;
        }
        tr_recon_device_times(r->rdev, &r->rec.ms_temporal, &r->rec.ms_spatial);
        return TR_OK;
    }
    if (r->gb.width != w || r->gb.height != h) {
        tr_gbuffer_free(&r->gb);
        tr_recon_free(&r->rec);
        tr_film_free(&r->disp);
        if (tr_gbuffer_init(&r->gb, w, h, err) != TR_OK ||
            tr_recon_init(&r->rec, w, h, err) != TR_OK ||
            tr_film_init(&r->disp, w, h, err) != TR_OK) {
            return TR_ERR;
        }
        for (size_t i = 0; i < (size_t)w * h; ++i) {
            r->disp.count[i] = 1;
        }
    }
    if (tr_gbuffer_from_film(&r->gb, &r->film, err) != TR_OK) {
        return TR_ERR;
    }
    /* Emitters' edges resolved over the pixels' area (post.h); shown as part of the
     * temporal stage's time. */
    double resolve_ms = 0.0;
    if (r->gb.has_emission && method != TR_RECON_OFF) {
        const double t0 = tr_time_now();
        if (tr_resolve_emission(r->scene, cam, p.emission_samples, threads, &r->gb, NULL, err) !=
            TR_OK) {
            return TR_ERR;
        }
        resolve_ms = (tr_time_now() - t0) * 1e3;
    }
    if (tr_recon_frame_moving(&r->rec, &r->gb, cam, motion, ids, method, &p, threads, r->disp.sum,
                              err) != TR_OK) {
        return TR_ERR;
    }
    r->rec.ms_temporal += resolve_ms;
    return TR_OK;
}

static void *render_main(void *arg) {
    view_renderer *r = arg;
    uint64_t gen = UINT64_MAX; /* the generation the film holds */
    uint32_t spp = 0;
    tr_camera rcam;  /* the camera the film is rendered with (reduced in motion) */
    int rmoving = 0; /* the film's generation was asked for while moving */
    memset(&rcam, 0, sizeof rcam);
    float tonemapped_exposure = 0.0f;
    tr_error err;
    pthread_mutex_lock(&r->mu);
    while (!r->quit) {
        if (r->shot_path[0]) {
            int ok = 0;
            if (spp == 0) {
                snprintf(r->shot_msg, sizeof r->shot_msg, "%s: no samples yet", r->shot_path);
            } else if (film_current(r, &err) != TR_OK ||
                       write_shot(&r->film, r->shot_path, r->exposure, r->curve, &err) != TR_OK) {
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
        const int moving = r->moving;
        const int method = r->recon;
        const double budget_ms = r->budget_ms;
        const uint64_t want = r->generation;
        if (want == gen && r->max_spp && spp >= r->max_spp) {
            if (exposure != tonemapped_exposure && r->pixels) {
                /* Idle, but the exposure changed: show the film with the new one. */
                view_tonemap(r->recon != TR_RECON_OFF && r->disp.sum ? &r->disp : &r->film,
                             exposure, r->curve, r->pixels);
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
        /* Only a refinement of a view on screen may be cancelled (view_render.h); an
         * animated frame is always a new image. */
        atomic_store(&r->refining, want == gen && spp > 0);
        pthread_mutex_unlock(&r->mu);

        if (want != gen) {
            rcam = cam;
            rmoving = moving;
            if (moving && r->motion_scale > 1.0f) {
                /* A few sizes only: every new size starts the reconstruction's history
                 * over, so the budget's small steps must not change it every frame. */
                static const float levels[] = {1.0f, 1.25f, 1.5f, 2.0f,  2.5f,  3.0f, 4.0f,
                                               5.0f, 6.0f,  8.0f, 10.0f, 12.0f, 16.0f};
                float s = 16.0f;
                for (size_t k = 0; k < sizeof levels / sizeof levels[0]; ++k) {
                    if (levels[k] >= 0.95f * r->motion_scale) {
                        s = levels[k];
                        break;
                    }
                }
                uint32_t w = (uint32_t)((float)cam.screen_width / s + 0.5f);
                uint32_t h = (uint32_t)((float)cam.screen_height / s + 0.5f);
                /* Cannot fail: the size only shrinks, and stays at least 1x1. */
                (void)tr_camera_resize(&rcam, w ? w : 1, h ? h : 1, &err);
            }
            /* The direct pass where SVGF filters direct and indirect light apart (not bdpt). */
            const uint32_t direct =
                r->params.svgf_split && !tr_integrator_is_bidirectional(r->cfg.integrator)
                    ? TR_PASS_DIRECT
                    : 0u;
            /* The emission pass where the reconstruction resolves emitters' edges (pt
             * only: the resolved edge follows pt's first segment). */
            const uint32_t emission =
                r->params.emission_samples > 0 && r->cfg.integrator == TR_INTEGRATOR_PT
                    ? TR_PASS_EMISSION
                    : 0u;
            if (resize_buffers(r, rcam.screen_width, rcam.screen_height,
                               method != TR_RECON_OFF ? TR_PASS_ALL | direct | emission : 0u,
                               &err) != TR_OK ||
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
        cfg.passes = r->film.passes;
        cfg.cancel = render_cancelled;
        cfg.cancel_user = r;
        tr_render_stats st;
        /* Animated or moving, each frame is a new image: a frame count picks its random
         * numbers instead of the sample count, so that the noise changes from frame to
         * frame (at rest sample k is frame k's, as `trac0r render` has it). */
        const uint32_t nspp = rmoving ? r->motion_spp : 1u;
        /* A moving or animated frame is reconstructed from few samples: pt's roulette
         * starts early there, which adds noise the filter hides and saves a fifth of the
         * frame, and its numbers are independent, which the reconstruction cannot tell
         * from Sobol points and cost less (docs/realtime.md). At rest the image converges
         * with the config's (by default the offline ones), so F12 equals `trac0r render`. */
        if (rmoving || r->animate) {
            cfg.roulette_start = r->motion_roulette;
            cfg.sampler = r->motion_sampler;
        }
        uint32_t sample = spp;
        if (r->animate) {
            sample = (uint32_t)r->updates;
        } else if (rmoving) {
            sample = (r->motion_frame++ & 0xffffu) * 16u + spp;
        }
        /* Reconstructed on an OpenCL device, the frame's film stays there. */
        const int device_recon =
            method != TR_RECON_OFF && strcmp(tr_device_kind(r->dev), "opencl") == 0;
        int rc = render_one(r, &rcam, &cfg, sample, nspp, !device_recon, &st, &err);
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
        spp += nspp;
        double t0 = tr_time_now();
        const tr_film *shown = &r->film;
        if (method != TR_RECON_OFF) {
            if (reconstruct(r, &rcam, method, cfg.threads, &err) != TR_OK) {
                pthread_mutex_lock(&r->mu);
                r->failed = 1;
                snprintf(r->error, sizeof r->error, "reconstruction: %s", err.msg);
                break;
            }
            shown = &r->disp;
        }
        const double t_rec = tr_time_now();
        view_tonemap(shown, exposure, r->curve, r->back);
        tonemapped_exposure = exposure;
        double t1 = tr_time_now();
        const float frame_scale = (float)cam.screen_width / (float)rcam.screen_width;
        if (rmoving) {
            view_budget_adapt(st.seconds * 1e3 + (t1 - t0) * 1e3, budget_ms, &r->motion_scale,
                              &r->motion_spp);
        }

        pthread_mutex_lock(&r->mu);
        uint32_t *tmp = r->pixels;
        r->pixels = r->back;
        r->back = tmp;
        if (!r->back || r->pw != rcam.screen_width || r->ph != rcam.screen_height) {
            free(r->back);
            r->back = malloc((size_t)rcam.screen_width * rcam.screen_height * sizeof *r->back);
            if (!r->back) {
                r->failed = 1;
                snprintf(r->error, sizeof r->error, "out of memory for a frame");
                break;
            }
        }
        r->pw = rcam.screen_width;
        r->ph = rcam.screen_height;
        r->scale = frame_scale;
        r->frame_spp = nspp;
        r->seq += 1;
        r->shown_gen = gen;
        r->spp = spp;
        r->render_ms = st.seconds * 1e3;
        r->tonemap_ms = (t1 - t_rec) * 1e3;
        r->temporal_ms = method != TR_RECON_OFF ? r->rec.ms_temporal : 0.0;
        r->spatial_ms = method != TR_RECON_OFF ? r->rec.ms_spatial : 0.0;
        r->frames_done += 1;
    }
    pthread_mutex_unlock(&r->mu);
    return NULL;
}

int view_renderer_start(view_renderer *r, tr_scene *scene, int animate, tr_device *dev,
                        const tr_render_config *cfg, int motion_sampler,
                        const tr_recon_params *params, const tr_camera *cam, int stride,
                        float exposure, int curve, uint32_t max_spp, tr_error *err) {
    memset(r, 0, sizeof *r);
    r->scene = scene;
    r->animate = animate;
    r->dev = dev;
    r->cfg = *cfg;
    r->motion_roulette = cfg->roulette_start ? cfg->roulette_start : TR_ROULETTE_START_REALTIME;
    r->motion_sampler = motion_sampler;
    r->params = *params;
    r->max_spp = max_spp;
    r->cam = *cam;
    r->stride = stride;
    r->exposure = exposure;
    r->curve = curve;
    r->generation = 1;
    r->budget_ms = 1000.0 / 60.0;
    r->motion_scale = 1.0f;
    r->motion_spp = 1;
    r->scale = 1.0f;
    atomic_init(&r->cancel, 0);
    atomic_init(&r->refining, 0);
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

void view_renderer_set_view(view_renderer *r, const tr_camera *cam, int stride, int moving) {
    pthread_mutex_lock(&r->mu);
    if (!same_view(&r->cam, cam) || r->stride != stride || r->moving != moving) {
        r->cam = *cam;
        r->stride = stride;
        r->moving = moving;
        r->generation += 1;
        if (atomic_load(&r->refining)) {
            atomic_store(&r->cancel, 1);
        }
        pthread_cond_signal(&r->cv);
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
        r->generation += 1;
        if (atomic_load(&r->refining)) {
            atomic_store(&r->cancel, 1);
        }
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
    tr_film_free(&r->disp);
    tr_gbuffer_free(&r->gb);
    tr_recon_free(&r->rec);
    tr_recon_device_close(r->rdev);
    r->rdev = NULL;
    free(r->motion);
    r->motion = NULL;
    free(r->back);
    free(r->pixels);
    r->back = NULL;
    r->pixels = NULL;
    r->started = 0;
}
