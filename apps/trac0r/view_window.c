/* view_window.c - the interactive window of `trac0r view`: events, camera, the
 * texture, the debug overlay and the state file. Rendering runs on view_render.c's
 * thread; this thread never waits for a frame. */
#define _POSIX_C_SOURCE 200809L
#include <SDL.h>
#include <SDL_ttf.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "view.h"
#include "view_overlay.h"
#include "view_render.h"
#include "view_wire.h"
#include "trac0r/outfile.h"

static volatile sig_atomic_t dump_requested = 0;

static void on_sigusr1(int sig) {
    (void)sig;
    dump_requested = 1;
}

typedef struct view_state {
    int overlay, help, bvh, timings, mouselook;
    SDL_Rect overlay_rect, help_rect; /* where they were last drawn */
    uint32_t bvh_depth;
    int stride;
    int recon; /* tr_recon_method */
    float exposure;
    uint64_t dumps, shots, cameras;
    uint64_t updates; /* scene updates (--animate) */
    double rebuild_ms;
} view_state;

/* What the render thread last published, for the state file. */
typedef struct shown_frame {
    uint64_t frames, cancelled, gen, view_gen;
    uint32_t spp, frame_spp;
    float scale;
    int moving;
} shown_frame;

static int write_state(const char *path, const view_state *s, const tr_fly_camera *f,
                       const shown_frame *sf, uint32_t w, uint32_t h, double fps, tr_error *err) {
    tr_outfile *out = tr_outfile_create(path, err);
    if (!out) {
        return -1;
    }
    fprintf(
        tr_outfile_stream(out),
        "spp %u\ngeneration %llu\nview_generation %llu\nframes %llu\ncancelled %llu\nsize %u %u\n"
        "pos %.6f %.6f %.6f\ndir %.6f %.6f %.6f\nup %.6f %.6f %.6f\nspeed %.6f\n"
        "overlay %d\nhelp %d\nbvh %d\nbvh_depth %u\ntimings %d\nmouselook %d\nstride %d\n"
        "exposure %.2f\nfps %.3f\ndumps %llu\nshots %llu\nupdates %llu\nrebuild_ms %.3f\n"
        "moving %d\nscale %.3f\nframe_spp %u\ncameras %llu\nmirrored %d\nrecon %s\n"
        "overlay_rect %d %d %d %d\nhelp_rect %d %d %d %d\nfocus %.6f\n",
        sf->spp, (unsigned long long)sf->gen, (unsigned long long)sf->view_gen,
        (unsigned long long)sf->frames, (unsigned long long)sf->cancelled, w, h, f->pos.x, f->pos.y,
        f->pos.z, f->dir.x, f->dir.y, f->dir.z, f->up.x, f->up.y, f->up.z, f->speed, s->overlay,
        s->help, s->bvh, s->bvh_depth, s->timings, s->mouselook, s->stride, s->exposure, fps,
        (unsigned long long)s->dumps, (unsigned long long)s->shots, (unsigned long long)s->updates,
        s->rebuild_ms, sf->moving, (double)sf->scale, sf->frame_spp, (unsigned long long)s->cameras,
        f->mirrored, tr_recon_name(s->recon), s->overlay_rect.x, s->overlay_rect.y,
        s->overlay_rect.w, s->overlay_rect.h, s->help_rect.x, s->help_rect.y, s->help_rect.w,
        s->help_rect.h, f->focus_dist);
    return tr_outfile_commit(out, err) == TR_OK ? 0 : -1;
}

/* Writes the renderer's current output (the window's pixels) as a binary PPM. */
static int dump_window(SDL_Renderer *ren, const char *path, tr_error *err) {
    int w = 0, h = 0;
    if (SDL_GetRendererOutputSize(ren, &w, &h) != 0 || w <= 0 || h <= 0) {
        tr_error_set(err, TR_STATUS_DEVICE, "%s: no window size: %s", path, SDL_GetError());
        return -1;
    }
    char head[40]; /* the file: this header, then the pixels */
    const size_t hn = (size_t)snprintf(head, sizeof head, "P6\n%d %d\n255\n", w, h);
    uint8_t *file = malloc(hn + (size_t)w * h * 3);
    if (!file) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%s: out of memory", path);
        return -1;
    }
    memcpy(file, head, hn);
    int rc = SDL_RenderReadPixels(ren, NULL, SDL_PIXELFORMAT_RGB24, file + hn, w * 3) != 0
                 ? tr_error_set(err, TR_STATUS_DEVICE, "%s: cannot read the window: %s", path,
                                SDL_GetError())
                 : tr_outfile_write(path, file, hn + (size_t)w * h * 3, err);
    free(file);
    return rc == TR_OK ? 0 : -1;
}

/* The first free STEM-NNN.EXT in dir. */
static void next_file_path(const char *dir, const char *stem, const char *ext, char *path,
                           size_t n) {
    for (int i = 0; i < 100000; ++i) {
        snprintf(path, n, "%s/%s-%03d.%s", dir, stem, i, ext);
        struct stat st; /* not fopen(): a FIFO of that name would block */
        if (stat(path, &st) != 0) {
            return;
        }
    }
}

static const char help_text[] = "trac0r view - keys\n"
                                "W/S          forward / back\n"
                                "A/D          left / right\n"
                                "Space/LCtrl  up / down\n"
                                "Q/E          roll\n"
                                "right mouse  toggle mouse-look\n"
                                "wheel        movement speed\n"
                                "R            reset the camera\n"
                                "C            camera as scene JSON\n"
                                "F            focus on the point under the mouse\n"
                                "M            reconstruction method\n"
                                "+/-          exposure\n"
                                "1/2/3        preview stride 1/2/4\n"
                                "B            debug view\n"
                                "V  [ ]       BVH boxes, depth\n"
                                "N            timings on stdout\n"
                                "F12          screenshot PNG\n"
                                "H            this help\n"
                                "Esc          quit";

/* The render resolution for a window of w x h output pixels: the window's own, scaled
 * down (aspect kept) where it exceeds the film's limits; the texture is stretched to the
 * window then. A window grown past the limits must not end the viewer. */
static void fit_film_limits(SDL_Renderer *ren, uint32_t *w, uint32_t *h) {
    /* The renderer's largest texture too (0: no limit). */
    uint32_t max_w = TR_FILM_MAX_SIDE, max_h = TR_FILM_MAX_SIDE;
    SDL_RendererInfo info;
    if (SDL_GetRendererInfo(ren, &info) == 0) {
        if (info.max_texture_width > 0 && (uint32_t)info.max_texture_width < max_w) {
            max_w = (uint32_t)info.max_texture_width;
        }
        if (info.max_texture_height > 0 && (uint32_t)info.max_texture_height < max_h) {
            max_h = (uint32_t)info.max_texture_height;
        }
    }
    double k = 1.0;
    if (*w > max_w) {
        k = fmin(k, (double)max_w / *w);
    }
    if (*h > max_h) {
        k = fmin(k, (double)max_h / *h);
    }
    if ((double)*w * *h * k * k > (double)TR_FILM_MAX_PIXELS) {
        k = fmin(k, sqrt((double)TR_FILM_MAX_PIXELS / ((double)*w * *h)));
    }
    if (k < 1.0) {
        *w = (uint32_t)fmax(1.0, floor(*w * k));
        *h = (uint32_t)fmax(1.0, floor(*h * k));
    }
}

/* The stage times of the frame on screen, in milliseconds. */
typedef struct stage_times {
    double input, rebuild, render, temporal, spatial, tonemap, upload;
} stage_times;

/* Everything the window's loop keeps between ticks. */
typedef struct view_window {
    const view_options *o;
    tr_scene *scene;
    SDL_Window *win;
    SDL_Renderer *ren;
    SDL_Texture *tex;
    TTF_Font *font;
    int ttf;
    view_renderer r;
    uint32_t w, h, tex_w, tex_h;
    tr_fly_camera fly0, fly;
    tr_camera cam;
    view_state st;
    uint64_t shown_seq, shown_gen, last_printed_seq, fps_frames0, frames_done, cancelled;
    uint32_t spp;
    stage_times times;
    double fps, fps_t0, last, title_t, drawn_t, last_change_t;
    int state_dirty, state_failed, mouse_x, mouse_y, was_moving, running;
    shown_frame sf;
} view_window;

/* SDL's video on the display the environment names. CLI_OK, or the status to exit with. */
static int open_video(const cli_args *a) {
    /* With DISPLAY set and no driver asked for, use X11 only: SDL would otherwise fall
     * back to other drivers when the X server cannot be reached. */
    const char *driver = getenv("SDL_VIDEODRIVER"), *wayland = getenv("WAYLAND_DISPLAY");
    const char *display = getenv("DISPLAY");
    if ((!driver || !*driver) && (!wayland || !*wayland)) {
        SDL_SetHint(SDL_HINT_VIDEODRIVER, "x11");
    }
    if (SDL_Init(SDL_INIT_VIDEO) != 0) {
        cli_error(a, "cannot open a window on DISPLAY='%s': %s", display ? display : "",
                  SDL_GetError());
        SDL_Quit();
        return CLI_USAGE;
    }
    /* When no real display can be reached SDL falls back to its offscreen or dummy
     * driver: no window, no events, a loop that never ends. Unless one was asked for
     * (SDL_VIDEODRIVER), that is "no display". */
    const char *got = SDL_GetCurrentVideoDriver();
    if (got && (strcmp(got, "offscreen") == 0 || strcmp(got, "dummy") == 0) &&
        !(driver && strcmp(driver, got) == 0)) {
        cli_error(a,
                  "cannot open a window: no display reachable (DISPLAY='%s', WAYLAND_DISPLAY='%s'; "
                  "SDL fell back to its %s driver)",
                  display ? display : "", wayland ? wayland : "", got);
        SDL_Quit();
        return CLI_USAGE;
    }
    return CLI_OK;
}

/* The font, the window and its renderer, and the render size from the window's.
 * CLI_OK, or the status to exit with (its message printed). */
static int open_window(view_window *vw) {
    const view_options *o = vw->o;
    if (TTF_Init() != 0) {
        fprintf(stderr, "trac0r view: SDL2_ttf: %s\n", TTF_GetError());
        return CLI_FAILURE;
    }
    vw->ttf = 1;
    /* A smaller font in a small window, so that the help and the debug view fit it. */
    vw->font = TTF_OpenFont(o->font_path, o->c.height < 540 ? 10 : 14);
    if (!vw->font) {
        fprintf(stderr, "trac0r view: cannot load the font %s: %s\n", o->font_path, TTF_GetError());
        return CLI_USAGE;
    }
    vw->win = SDL_CreateWindow("trac0r view", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED,
                               (int)o->c.width, (int)o->c.height, SDL_WINDOW_RESIZABLE);
    if (!vw->win) {
        fprintf(stderr, "trac0r view: cannot create the window: %s\n", SDL_GetError());
        return CLI_FAILURE;
    }
    vw->ren = SDL_CreateRenderer(vw->win, -1, 0);
    if (!vw->ren) {
        fprintf(stderr, "trac0r view: cannot create a renderer: %s\n", SDL_GetError());
        return CLI_FAILURE;
    }
    vw->w = o->c.width;
    vw->h = o->c.height;
    int ow = 0, oh = 0;
    if (SDL_GetRendererOutputSize(vw->ren, &ow, &oh) == 0 && ow > 0 && oh > 0) {
        vw->w = (uint32_t)ow;
        vw->h = (uint32_t)oh;
        fit_film_limits(vw->ren, &vw->w, &vw->h);
    }
    return CLI_OK;
}

/* The camera, the state and the render thread. CLI_OK or CLI_FAILURE (said). */
static int start_rendering(view_window *vw, cli_backend *be) {
    const view_options *o = vw->o;
    tr_error err;
    const tr_camera *scene_cam = tr_scene_camera(vw->scene);
    const tr_aabb bounds = tr_scene_bounds(vw->scene);
    vw->fly0 = tr_fly_from_camera(scene_cam, tr_fly_default_speed(&bounds));
    vw->fly = vw->fly0;
    /* The scene's own camera until the user moves: so that the first view's film is
     * exactly what `trac0r render` computes. */
    vw->cam = *scene_cam;
    if (tr_camera_resize(&vw->cam, vw->w, vw->h, &err) != TR_OK) {
        fprintf(stderr, "trac0r view: %s\n", err.msg);
        return CLI_FAILURE;
    }
    vw->st.stride = o->stride;
    vw->st.exposure = o->exposure;
    vw->st.recon = o->recon;
    vw->st.bvh_depth = 3;
    tr_render_config cfg = cli_render_config(&o->c);
    /* Moving frames: independent numbers unless --sampler names a sampler. */
    const int motion_sampler = o->c.sampler >= 0 ? o->c.sampler : TR_SAMPLER_REALTIME;
    tr_realtime_desc rtd = {0};
    cli_realtime_firefly(&o->c, &rtd.clamp_indirect, &rtd.regularize);
    rtd.restir = o->c.restir;
    rtd.restir_unbiased = o->c.restir_unbiased;
    if (view_renderer_start(&vw->r, vw->scene, o->animate, be->dev, &cfg, motion_sampler,
                            &o->recon_params, &vw->cam, vw->st.stride, vw->st.exposure, o->curve,
                            o->max_spp, &rtd, &err) != TR_OK) {
        fprintf(stderr, "trac0r view: %s\n", err.msg);
        return CLI_FAILURE;
    }
    view_renderer_set_budget(&vw->r, 1000.0 / o->target_fps);
    view_renderer_set_recon(&vw->r, vw->st.recon);
    if (o->dump_file) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_sigusr1; /* stays installed (no SA_RESETHAND) */
        sigemptyset(&sa.sa_mask);
        sa.sa_flags = SA_RESTART;
        sigaction(SIGUSR1, &sa, NULL);
    }
    vw->fps_t0 = vw->last = tr_time_now();
    vw->state_dirty = 1;
    vw->last_change_t = -1e9;
    vw->running = 1;
    return CLI_OK;
}

/* C: the camera as scene JSON, on stdout and into the next free file. */
static void save_camera(view_window *vw) {
    char json[1024], path[4200];
    tr_fly_json(&vw->fly, json, sizeof json);
    fputs(json, stdout);
    fflush(stdout);
    next_file_path(vw->o->shot_dir, "trac0r-camera", "json", path, sizeof path);
    tr_error cerr;
    if (tr_outfile_write(path, json, strlen(json), &cerr) != TR_OK) {
        fprintf(stderr, "trac0r view: %s\n", cerr.msg);
    } else {
        printf("trac0r view: saved %s\n", path);
        fflush(stdout);
        vw->st.cameras += 1;
    }
}

/* One key pressed; sets *view_changed when the camera or the stride changed. */
static void on_key(view_window *vw, SDL_Keycode key, int *view_changed) {
    view_state *st = &vw->st;
    switch (key) {
    case SDLK_ESCAPE:
        vw->running = 0;
        break;
    case SDLK_b:
        st->overlay = !st->overlay;
        break;
    case SDLK_h:
        st->help = !st->help;
        break;
    case SDLK_v:
        st->bvh = !st->bvh;
        break;
    case SDLK_LEFTBRACKET:
        st->bvh_depth = st->bvh_depth ? st->bvh_depth - 1 : 0;
        break;
    case SDLK_RIGHTBRACKET:
        st->bvh_depth =
            st->bvh_depth < view_bvh_depth(vw->scene) ? st->bvh_depth + 1 : st->bvh_depth;
        break;
    case SDLK_n:
        st->timings = !st->timings;
        break;
    case SDLK_1:
    case SDLK_2:
    case SDLK_3:
        st->stride = 1 << (key - SDLK_1);
        *view_changed = 1;
        break;
    case SDLK_PLUS:
    case SDLK_EQUALS:
    case SDLK_KP_PLUS:
    case SDLK_MINUS:
    case SDLK_KP_MINUS: {
        const int up = key == SDLK_PLUS || key == SDLK_EQUALS || key == SDLK_KP_PLUS;
        st->exposure = up ? fminf(st->exposure + 0.5f, 20.0f) : fmaxf(st->exposure - 0.5f, -20.0f);
        view_renderer_set_exposure(&vw->r, st->exposure);
        break;
    }
    case SDLK_m:
        st->recon = (st->recon + 1) % TR_RECON_COUNT;
        view_renderer_set_recon(&vw->r, st->recon);
        break;
    case SDLK_r:
        /* Back to the scene's camera and speed. */
        vw->fly = vw->fly0;
        *view_changed = 1;
        break;
    case SDLK_c:
        save_camera(vw);
        break;
    case SDLK_f: /* a lens focuses on the surface under the mouse (r.mu: --animate moves it) */
        pthread_mutex_lock(&vw->r.mu);
        *view_changed |= vw->fly.lens_radius > 0.0f &&
                         tr_scene_focus_distance(vw->scene, &vw->cam, (float)vw->mouse_x + 0.5f,
                                                 (float)vw->mouse_y + 0.5f, &vw->fly.focus_dist);
        pthread_mutex_unlock(&vw->r.mu);
        break;
    case SDLK_F12: {
        char path[4200];
        next_file_path(vw->o->shot_dir, "trac0r-view", "png", path, sizeof path);
        view_renderer_screenshot(&vw->r, path);
        break;
    }
    default:
        break;
    }
}

/* One event; sets *view_changed when the view changed. */
static void on_event(view_window *vw, const SDL_Event *ev, int *view_changed) {
    switch (ev->type) {
    case SDL_QUIT:
        vw->running = 0;
        break;
    case SDL_WINDOWEVENT:
        if (ev->window.event == SDL_WINDOWEVENT_SIZE_CHANGED) {
            int ow = 0, oh = 0;
            SDL_GetRendererOutputSize(vw->ren, &ow, &oh);
            if (ow > 0 && oh > 0) {
                vw->w = (uint32_t)ow;
                vw->h = (uint32_t)oh;
                fit_film_limits(vw->ren, &vw->w, &vw->h);
                *view_changed = 1;
            }
        }
        vw->state_dirty = 1;
        break;
    case SDL_MOUSEBUTTONDOWN:
        if (ev->button.button == SDL_BUTTON_RIGHT) {
            vw->st.mouselook = !vw->st.mouselook;
            SDL_SetRelativeMouseMode(vw->st.mouselook ? SDL_TRUE : SDL_FALSE);
            vw->state_dirty = 1;
        }
        break;
    case SDL_MOUSEMOTION:
        vw->mouse_x = ev->motion.x;
        vw->mouse_y = ev->motion.y;
        if (vw->st.mouselook && (ev->motion.xrel || ev->motion.yrel)) {
            /* 0.0025 radians per pixel of mouse motion. */
            tr_fly_look(&vw->fly, 0.0025f * (float)ev->motion.xrel,
                        0.0025f * (float)ev->motion.yrel);
            *view_changed = 1;
        }
        break;
    case SDL_MOUSEWHEEL:
        vw->fly.speed *= powf(1.25f, (float)ev->wheel.y);
        vw->fly.speed = fminf(fmaxf(vw->fly.speed, 1e-4f), 1e4f);
        vw->state_dirty = 1;
        break;
    case SDL_KEYDOWN:
        if (!ev->key.repeat) {
            vw->state_dirty = 1;
            on_key(vw, ev->key.keysym.sym, view_changed);
        }
        break;
    default:
        break;
    }
}

/* Held keys move and roll the camera at a rate independent of the frame rate; a changed
 * view (or the end of a movement) goes to the render thread. */
static void steer(view_window *vw, double t_in, double dt, int view_changed) {
    const Uint8 *k = SDL_GetKeyboardState(NULL);
    view_changed |= tr_fly_step(&vw->fly, (float)(k[SDL_SCANCODE_W] - k[SDL_SCANCODE_S]),
                                (float)(k[SDL_SCANCODE_D] - k[SDL_SCANCODE_A]),
                                (float)(k[SDL_SCANCODE_SPACE] - k[SDL_SCANCODE_LCTRL]),
                                (float)(k[SDL_SCANCODE_E] - k[SDL_SCANCODE_Q]), (float)dt);
    /* Moving: a view change in the last 150 ms. The renderer then holds the frame budget;
     * the first tick without changes asks for the full-resolution view. */
    if (view_changed) {
        vw->last_change_t = t_in;
    }
    const int moving = t_in - vw->last_change_t < 0.15;
    if (view_changed || moving != vw->was_moving) {
        tr_camera next;
        if (!view_changed || tr_fly_make(&vw->fly, vw->w, vw->h, &next, NULL) == TR_OK) {
            if (view_changed) {
                vw->cam = next;
            }
            view_renderer_set_view(&vw->r, &vw->cam, vw->st.stride, moving);
        }
        vw->was_moving = moving;
        vw->state_dirty = 1;
    }
}

/* The newest frame, if any, into the texture (under the render thread's lock). */
static void take_frame(view_window *vw) {
    view_renderer *r = &vw->r;
    const double t0 = tr_time_now();
    if (!vw->tex || vw->tex_w != r->pw || vw->tex_h != r->ph) {
        if (vw->tex) {
            SDL_DestroyTexture(vw->tex);
        }
        vw->tex = SDL_CreateTexture(vw->ren, SDL_PIXELFORMAT_ARGB8888, SDL_TEXTUREACCESS_STREAMING,
                                    (int)r->pw, (int)r->ph);
        vw->tex_w = r->pw;
        vw->tex_h = r->ph;
    }
    if (vw->tex) {
        SDL_UpdateTexture(vw->tex, NULL, r->pixels, (int)(r->pw * sizeof(uint32_t)));
    }
    vw->shown_seq = r->seq;
    vw->shown_gen = r->shown_gen;
    vw->spp = r->spp;
    vw->times.render = r->render_ms;
    vw->times.rebuild = r->rebuild_ms;
    vw->st.updates = r->updates;
    vw->st.rebuild_ms = r->rebuild_ms;
    vw->times.tonemap = r->tonemap_ms;
    vw->times.temporal = r->temporal_ms;
    vw->times.spatial = r->spatial_ms;
    vw->times.upload = (tr_time_now() - t0) * 1e3;
    vw->sf.scale = r->scale;
    vw->sf.frame_spp = r->frame_spp;
    vw->state_dirty = 1;
}

/* What the render thread published since the last tick: a failure (returned, said), a
 * screenshot's result, a new frame. */
static int collect(view_window *vw) {
    view_renderer *r = &vw->r;
    pthread_mutex_lock(&r->mu);
    const int failed = r->failed;
    if (failed) {
        fprintf(stderr, "trac0r view: %s\n", r->error);
    }
    if (r->shot_done) {
        r->shot_done = 0;
        if (r->shot_ok) {
            printf("trac0r view: saved %s\n", r->shot_msg);
            fflush(stdout);
            vw->st.shots += 1;
        } else {
            fprintf(stderr, "trac0r view: screenshot failed: %s\n", r->shot_msg);
        }
        vw->state_dirty = 1;
    }
    if (r->pixels && r->seq != vw->shown_seq) {
        take_frame(vw);
    }
    vw->frames_done = r->frames_done;
    vw->cancelled = r->cancelled;
    pthread_mutex_unlock(&r->mu);
    return failed;
}

/* The frame rate, the timings line (N) and the window's title. */
static void report(view_window *vw, double now) {
    if (now - vw->fps_t0 >= 0.5) {
        vw->fps = (double)(vw->frames_done - vw->fps_frames0) / (now - vw->fps_t0);
        vw->fps_frames0 = vw->frames_done;
        vw->fps_t0 = now;
    }
    const stage_times *t = &vw->times;
    if (vw->st.timings && vw->shown_seq != vw->last_printed_seq) {
        printf("frame %llu: input %.3f ms, scene rebuild %.3f ms, render %.2f ms, "
               "reconstruction (temporal %.2f, spatial %.2f) %.2f ms, "
               "film->texture %.2f ms (tonemap %.2f, upload %.2f), %u spp\n",
               (unsigned long long)vw->shown_seq, t->input, t->rebuild, t->render, t->temporal,
               t->spatial, t->temporal + t->spatial, t->tonemap + t->upload, t->tonemap, t->upload,
               vw->spp);
        fflush(stdout);
        vw->last_printed_seq = vw->shown_seq;
    }
    if (now - vw->title_t >= 0.25) {
        char title[160];
        snprintf(title, sizeof title, "trac0r view - %u spp - %.1f FPS", vw->spp, vw->fps);
        SDL_SetWindowTitle(vw->win, title);
        vw->title_t = now;
    }
}

/* The debug text (B) in the top left. */
static void draw_overlay(view_window *vw, const char *accel, uint32_t bvh_depth) {
    const view_options *o = vw->o;
    const view_state *st = &vw->st;
    const stage_times *t = &vw->times;
    const tr_camera *cam = &vw->cam;
    /* shown_gen != r.generation: a read of our own write. */
    const int scene_changing = vw->shown_gen != vw->r.generation || o->animate;
    const float mx = (float)vw->mouse_x + 0.5f, my = (float)vw->mouse_y + 0.5f;
    const tr_vec3 mc = view_screen_to_camera(cam, mx, my), mw = view_screen_to_world(cam, mx, my);
    char text[4096];
    snprintf(text, sizeof text,
             "FPS %.2f   %u spp   %ux%u   stride %d   exposure %+.1f\n"
             "%s: 1/%.2f resolution, %u spp per frame, budget %.1f ms\n"
             "input %.2f ms  scene rebuild %.2f ms  render %.1f ms\n"
             "reconstruction %s: temporal %.2f ms  spatial %.2f ms\n"
             "film->texture %.2f ms (tonemap %.2f + upload %.2f)\n"
             "scene %s: %s\n"
             "accel %s\n"
             "pos  % .3f % .3f % .3f\n"
             "dir  % .3f % .3f % .3f\n"
             "up   % .3f % .3f % .3f\n"
             "fov  h %.1f  v %.1f deg   speed %.3g/s\n"
             "mouse screen %d %d\n"
             "mouse camera % .3f % .3f % .3f\n"
             "mouse world  % .3f % .3f % .3f\n"
             "%s",
             vw->fps, vw->spp, vw->w, vw->h, st->stride, st->exposure,
             vw->was_moving ? "moving" : "at rest", (double)vw->sf.scale, vw->sf.frame_spp,
             1000.0 / o->target_fps, t->input, t->rebuild, t->render, tr_recon_name(st->recon),
             t->temporal, t->spatial, t->tonemap + t->upload, t->tonemap, t->upload, o->c.scene,
             scene_changing ? "changing" : "static", accel, cam->pos.x, cam->pos.y, cam->pos.z,
             cam->dir.x, cam->dir.y, cam->dir.z, cam->up.x, cam->up.y, cam->up.z,
             cam->horizontal_fov, cam->vertical_fov, vw->fly.speed, vw->mouse_x, vw->mouse_y, mc.x,
             mc.y, mc.z, mw.x, mw.y, mw.z, st->bvh ? "BVH boxes on (V), [ ] depth" : "");
    if (st->bvh) {
        char line[64];
        snprintf(line, sizeof line, " %u of %u", st->bvh_depth, bvh_depth);
        strncat(text, line, sizeof text - strlen(text) - 1);
    }
    if (vw->h < 540) {
        /* A small window shows the timings alone (the first five lines). */
        char *end = text;
        for (int i = 0; i < 5 && end; ++i) {
            end = strchr(end + (i > 0), '\n');
        }
        if (end) {
            *end = '\0';
        }
    }
    const SDL_Rect r = view_draw_text(vw->ren, vw->font, 0, 0, text);
    if (memcmp(&r, &vw->st.overlay_rect, sizeof r) != 0) {
        vw->st.overlay_rect = r;
        vw->state_dirty = 1;
    }
}

/* The frame, the wireframes, the overlay and the help; a window dump if asked. */
static void draw(view_window *vw) {
    SDL_Renderer *ren = vw->ren;
    SDL_SetRenderDrawColor(ren, 0, 0, 0, 255);
    SDL_RenderClear(ren);
    if (vw->tex) {
        SDL_RenderCopy(ren, vw->tex, NULL, NULL);
    }
    /* The render thread moves the scene under r.mu when animating. */
    pthread_mutex_lock(&vw->r.mu);
    if (vw->st.overlay) {
        const SDL_Color yellow = {255, 255, 0, 255};
        tr_aabb boxes[256];
        size_t nb = 0;
        for (uint32_t i = 0; i < tr_scene_shape_count(vw->scene) && nb < 256; ++i) {
            boxes[nb++] = tr_scene_shape_box(vw->scene, i);
        }
        view_draw_boxes(ren, &vw->cam, boxes, nb, yellow);
    }
    if (vw->st.bvh) {
        view_draw_bvh(ren, &vw->cam, vw->scene, vw->st.bvh_depth); /* nothing without a BVH */
    }
    char accel[160];
    tr_scene_accel_describe(vw->scene, 1, accel, sizeof accel);
    const uint32_t bvh_depth = view_bvh_depth(vw->scene);
    pthread_mutex_unlock(&vw->r.mu);
    if (vw->st.overlay) {
        draw_overlay(vw, accel, bvh_depth);
    }
    if (vw->st.help) {
        /* Bottom right, clear of the debug text in the top left. */
        const SDL_Rect r = view_draw_text(ren, vw->font, -1, -1, help_text);
        if (memcmp(&r, &vw->st.help_rect, sizeof r) != 0) {
            vw->st.help_rect = r;
            vw->state_dirty = 1;
        }
    }
    if (dump_requested && vw->o->dump_file) {
        tr_error err;
        dump_requested = 0;
        if (dump_window(ren, vw->o->dump_file, &err) != 0) {
            fprintf(stderr, "trac0r view: %s\n", err.msg);
        }
        vw->st.dumps += 1;
        vw->state_dirty = 1;
    }
    SDL_RenderPresent(ren);
}

/* --state-file: written when something changed. */
static void save_state(view_window *vw) {
    if (!vw->state_dirty || !vw->o->state_file) {
        return;
    }
    tr_error err;
    shown_frame *sf = &vw->sf;
    sf->frames = vw->frames_done;
    sf->cancelled = vw->cancelled;
    sf->spp = vw->spp;
    sf->gen = vw->shown_gen;
    sf->view_gen = vw->r.generation;
    sf->moving = vw->was_moving;
    /* Said once, not at every frame, when the file cannot be written. */
    if (write_state(vw->o->state_file, &vw->st, &vw->fly, sf, vw->w, vw->h, vw->fps, &err) != 0 &&
        !vw->state_failed) {
        fprintf(stderr, "trac0r view: --state-file: %s\n", err.msg);
        vw->state_failed = 1;
    }
    vw->state_dirty = 0;
}

/* One tick: events, steering, the render thread's news, and a redraw when there is news
 * (and 4 times a second for the overlay's numbers: the render threads need the cores more
 * than an unchanged window does). Returns CLI_FAILURE when rendering failed, else CLI_OK. */
static int tick(view_window *vw) {
    SDL_Event ev;
    int have = SDL_WaitEventTimeout(&ev, 10);
    const int any_event = have;
    const double t_in = tr_time_now();
    const double dt = fmin(t_in - vw->last, 0.1);
    vw->last = t_in;
    int view_changed = 0;
    while (have) {
        on_event(vw, &ev, &view_changed);
        have = SDL_PollEvent(&ev);
    }
    steer(vw, t_in, dt, view_changed);
    vw->times.input = (tr_time_now() - t_in) * 1e3;
    if (collect(vw)) {
        return CLI_FAILURE;
    }
    const double now = tr_time_now();
    report(vw, now);
    if (vw->state_dirty || any_event || dump_requested || now - vw->drawn_t >= 0.25) {
        vw->drawn_t = now;
        draw(vw);
        save_state(vw);
    }
    return CLI_OK;
}

int view_run_window(const cli_args *a, const view_options *o, tr_scene *scene, cli_backend *be) {
    int status = open_video(a);
    if (status != CLI_OK) {
        return status;
    }
    view_window *vw = calloc(1, sizeof *vw);
    if (!vw) {
        fprintf(stderr, "trac0r view: out of memory\n");
        SDL_Quit();
        return CLI_FAILURE;
    }
    vw->o = o;
    vw->scene = scene;
    vw->r.started = 0;
    status = open_window(vw);
    status = status == CLI_OK ? start_rendering(vw, be) : status;
    while (status == CLI_OK && vw->running) {
        status = tick(vw);
    }
    view_renderer_stop(&vw->r);
    if (vw->tex) {
        SDL_DestroyTexture(vw->tex);
    }
    if (vw->ren) {
        SDL_DestroyRenderer(vw->ren);
    }
    if (vw->win) {
        SDL_DestroyWindow(vw->win);
    }
    if (vw->font) {
        TTF_CloseFont(vw->font);
    }
    if (vw->ttf) {
        TTF_Quit();
    }
    SDL_Quit();
    free(vw);
    return status;
}
