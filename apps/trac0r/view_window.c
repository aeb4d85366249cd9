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
#include "view_camera.h"
#include "view_overlay.h"
#include "view_render.h"
#include "view_vec.h"
#include "view_wire.h"
#include "trac0r/outfile.h"

static volatile sig_atomic_t dump_requested = 0;

static void on_sigusr1(int sig) {
    (void)sig;
    dump_requested = 1;
}

typedef struct view_state {
    int overlay, help, bvh, timings, mouselook;
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

static int write_state(const char *path, const view_state *s, const fly_camera *f,
                       const shown_frame *sf, uint32_t w, uint32_t h, double fps, tr_error *err) {
    tr_outfile *out = tr_outfile_open(path, err);
    if (!out) {
        return -1;
    }
    fprintf(
        tr_outfile_stream(out),
        "spp %u\ngeneration %llu\nview_generation %llu\nframes %llu\ncancelled %llu\nsize %u %u\n"
        "pos %.6f %.6f %.6f\ndir %.6f %.6f %.6f\nup %.6f %.6f %.6f\nspeed %.6f\n"
        "overlay %d\nhelp %d\nbvh %d\nbvh_depth %u\ntimings %d\nmouselook %d\nstride %d\n"
        "exposure %.2f\nfps %.3f\ndumps %llu\nshots %llu\nupdates %llu\nrebuild_ms %.3f\n"
        "moving %d\nscale %.3f\nframe_spp %u\ncameras %llu\nmirrored %d\nrecon %s\n",
        sf->spp, (unsigned long long)sf->gen, (unsigned long long)sf->view_gen,
        (unsigned long long)sf->frames, (unsigned long long)sf->cancelled, w, h, f->pos.x, f->pos.y,
        f->pos.z, f->dir.x, f->dir.y, f->dir.z, f->up.x, f->up.y, f->up.z, f->speed, s->overlay,
        s->help, s->bvh, s->bvh_depth, s->timings, s->mouselook, s->stride, s->exposure, fps,
        (unsigned long long)s->dumps, (unsigned long long)s->shots, (unsigned long long)s->updates,
        s->rebuild_ms, sf->moving, (double)sf->scale, sf->frame_spp, (unsigned long long)s->cameras,
        f->mirrored, tr_recon_name(s->recon));
    return tr_outfile_commit(out, err) == TR_OK ? 0 : -1;
}

/* Writes the renderer's current output (the window's pixels) as a binary PPM. */
static int dump_window(SDL_Renderer *ren, const char *path, tr_error *err) {
    int w = 0, h = 0;
    if (SDL_GetRendererOutputSize(ren, &w, &h) != 0 || w <= 0 || h <= 0) {
        tr_error_set(err, TR_STATUS_DEVICE, "%s: no window size: %s", path, SDL_GetError());
        return -1;
    }
    uint8_t *px = malloc((size_t)w * h * 3);
    if (!px) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "%s: out of memory", path);
        return -1;
    }
    if (SDL_RenderReadPixels(ren, NULL, SDL_PIXELFORMAT_RGB24, px, w * 3) != 0) {
        tr_error_set(err, TR_STATUS_DEVICE, "%s: cannot read the window: %s", path, SDL_GetError());
        free(px);
        return -1;
    }
    tr_outfile *out = tr_outfile_open(path, err);
    if (!out) {
        free(px);
        return -1;
    }
    fprintf(tr_outfile_stream(out), "P6\n%d %d\n255\n", w, h);
    fwrite(px, 3, (size_t)w * h, tr_outfile_stream(out)); /* checked by the commit */
    free(px);
    return tr_outfile_commit(out, err) == TR_OK ? 0 : -1;
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
                                "W/S        forward / back\n"
                                "A/D        left / right\n"
                                "Space/LCtrl up / down\n"
                                "Q/E        roll\n"
                                "right mouse toggle mouse-look\n"
                                "wheel      movement speed\n"
                                "R          reset the camera\n"
                                "C          camera as scene JSON\n"
                                "M          reconstruction method\n"
                                "+/-        exposure\n"
                                "1/2/3      preview stride 1/2/4\n"
                                "B          debug view\n"
                                "V  [ ]     BVH boxes, depth\n"
                                "N          timings on stdout\n"
                                "F12        screenshot PNG\n"
                                "H          this help\n"
                                "Esc        quit";

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

int view_run_window(const cli_args *a, const view_options *o, tr_scene *scene, cli_backend *be) {
    tr_error err;
    const char *font_path = o->font_path;
    /* With DISPLAY set and no driver asked for, use X11 only: SDL would otherwise fall
     * back to other drivers when the X server cannot be reached. */
    const char *driver = getenv("SDL_VIDEODRIVER"), *wayland = getenv("WAYLAND_DISPLAY");
    if ((!driver || !*driver) && (!wayland || !*wayland)) {
        SDL_SetHint(SDL_HINT_VIDEODRIVER, "x11");
    }
    if (SDL_Init(SDL_INIT_VIDEO) != 0) {
        const char *display = getenv("DISPLAY");
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
        const char *display = getenv("DISPLAY");
        cli_error(a,
                  "cannot open a window: no display reachable (DISPLAY='%s', WAYLAND_DISPLAY='%s'; "
                  "SDL fell back to its %s driver)",
                  display ? display : "", wayland ? wayland : "", got);
        SDL_Quit();
        return CLI_USAGE;
    }
    int status = CLI_FAILURE;
    SDL_Window *win = NULL;
    SDL_Renderer *ren = NULL;
    SDL_Texture *tex = NULL;
    TTF_Font *font = NULL;
    int ttf = 0;
    view_renderer r;
    r.started = 0;

    if (TTF_Init() != 0) {
        fprintf(stderr, "trac0r view: SDL2_ttf: %s\n", TTF_GetError());
        goto done;
    }
    ttf = 1;
    font = TTF_OpenFont(font_path, 14);
    if (!font) {
        fprintf(stderr, "trac0r view: cannot load the font %s: %s\n", font_path, TTF_GetError());
        status = CLI_USAGE;
        goto done;
    }
    win = SDL_CreateWindow("trac0r view", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED,
                           (int)o->c.width, (int)o->c.height, SDL_WINDOW_RESIZABLE);
    if (!win) {
        fprintf(stderr, "trac0r view: cannot create the window: %s\n", SDL_GetError());
        goto done;
    }
    ren = SDL_CreateRenderer(win, -1, 0);
    if (!ren) {
        fprintf(stderr, "trac0r view: cannot create a renderer: %s\n", SDL_GetError());
        goto done;
    }

    uint32_t w = o->c.width, h = o->c.height;
    {
        int ow = 0, oh = 0;
        if (SDL_GetRendererOutputSize(ren, &ow, &oh) == 0 && ow > 0 && oh > 0) {
            w = (uint32_t)ow;
            h = (uint32_t)oh;
            fit_film_limits(ren, &w, &h);
        }
    }
    const tr_camera *scene_cam = tr_scene_camera(scene);
    const tr_aabb bounds = tr_scene_bounds(scene);
    const fly_camera fly0 = fly_from_camera(scene_cam, view_default_speed(&bounds));
    fly_camera fly = fly0;
    /* The scene's own camera until the user moves: so that the first view's film is
     * exactly what `trac0r render` computes. */
    tr_camera cam = *scene_cam;
    if (tr_camera_resize(&cam, w, h, &err) != TR_OK) {
        fprintf(stderr, "trac0r view: %s\n", err.msg);
        goto done;
    }
    view_state st = {0};
    st.stride = o->stride;
    st.exposure = o->exposure;
    st.recon = o->recon;
    st.bvh_depth = 3;

    tr_render_config cfg = cli_render_config(&o->c);
    /* Moving frames: independent numbers unless --sampler names a sampler. */
    const int motion_sampler = o->c.sampler >= 0 ? o->c.sampler : TR_SAMPLER_REALTIME;
    if (view_renderer_start(&r, scene, o->animate, be->dev, &cfg, motion_sampler, &o->recon_params,
                            &cam, st.stride, st.exposure, o->curve, o->max_spp, &err) != TR_OK) {
        fprintf(stderr, "trac0r view: %s\n", err.msg);
        goto done;
    }
    view_renderer_set_budget(&r, 1000.0 / o->target_fps);
    view_renderer_set_recon(&r, st.recon);
    if (o->dump_file) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_sigusr1; /* stays installed (no SA_RESETHAND) */
        sigemptyset(&sa.sa_mask);
        sa.sa_flags = SA_RESTART;
        sigaction(SIGUSR1, &sa, NULL);
    }

    uint32_t tex_w = 0, tex_h = 0;
    uint64_t shown_seq = 0, shown_gen = 0, last_printed_seq = 0;
    uint32_t spp = 0;
    stage_times times = {0};
    double fps = 0.0, fps_t0 = tr_time_now(), last = fps_t0, title_t = 0.0, drawn_t = 0.0;
    uint64_t fps_frames0 = 0;
    int state_dirty = 1, state_failed = 0, mouse_x = 0, mouse_y = 0, was_moving = 0;
    double last_change_t = -1e9;
    shown_frame sf = {0};
    int running = 1;
    status = CLI_OK;
    char title[160], text[4096];

    while (running) {
        SDL_Event ev;
        int have = SDL_WaitEventTimeout(&ev, 10);
        const int any_event = have;
        const double t_in = tr_time_now();
        const double dt = fmin(t_in - last, 0.1);
        last = t_in;
        int view_changed = 0;
        while (have) {
            switch (ev.type) {
            case SDL_QUIT:
                running = 0;
                break;
            case SDL_WINDOWEVENT:
                if (ev.window.event == SDL_WINDOWEVENT_SIZE_CHANGED) {
                    int ow = 0, oh = 0;
                    SDL_GetRendererOutputSize(ren, &ow, &oh);
                    if (ow > 0 && oh > 0) {
                        w = (uint32_t)ow;
                        h = (uint32_t)oh;
                        fit_film_limits(ren, &w, &h);
                        view_changed = 1;
                    }
                }
                state_dirty = 1;
                break;
            case SDL_MOUSEBUTTONDOWN:
                if (ev.button.button == SDL_BUTTON_RIGHT) {
                    st.mouselook = !st.mouselook;
                    SDL_SetRelativeMouseMode(st.mouselook ? SDL_TRUE : SDL_FALSE);
                    state_dirty = 1;
                }
                break;
            case SDL_MOUSEMOTION:
                mouse_x = ev.motion.x;
                mouse_y = ev.motion.y;
                if (st.mouselook && (ev.motion.xrel || ev.motion.yrel)) {
                    const float k = 0.0025f; /* radians per pixel */
                    /* Pitch turns about up x dir whatever the handedness (up stays up);
                     * yaw turns towards the screen's right, which a mirrored camera has
                     * on the other side. */
                    tr_vec3 right = v3_normalize(v3_cross(fly.up, fly.dir));
                    const float yaw = fly.mirrored ? -k : k;
                    fly.dir = view_rotate(fly.dir, fly.up, (float)ev.motion.xrel * yaw);
                    fly.dir = view_rotate(fly.dir, right, (float)ev.motion.yrel * k);
                    fly.up = view_rotate(fly.up, right, (float)ev.motion.yrel * k);
                    fly_orthonormalize(&fly);
                    view_changed = 1;
                }
                break;
            case SDL_MOUSEWHEEL:
                fly.speed *= powf(1.25f, (float)ev.wheel.y);
                fly.speed = fminf(fmaxf(fly.speed, 1e-4f), 1e4f);
                state_dirty = 1;
                break;
            case SDL_KEYDOWN:
                if (ev.key.repeat) {
                    break;
                }
                state_dirty = 1;
                switch (ev.key.keysym.sym) {
                case SDLK_ESCAPE:
                    running = 0;
                    break;
                case SDLK_b:
                    st.overlay = !st.overlay;
                    break;
                case SDLK_h:
                    st.help = !st.help;
                    break;
                case SDLK_v:
                    st.bvh = !st.bvh;
                    break;
                case SDLK_LEFTBRACKET:
                    st.bvh_depth = st.bvh_depth ? st.bvh_depth - 1 : 0;
                    break;
                case SDLK_RIGHTBRACKET:
                    st.bvh_depth =
                        st.bvh_depth < view_bvh_depth(scene) ? st.bvh_depth + 1 : st.bvh_depth;
                    break;
                case SDLK_n:
                    st.timings = !st.timings;
                    break;
                case SDLK_1:
                case SDLK_2:
                case SDLK_3:
                    st.stride = 1 << (ev.key.keysym.sym - SDLK_1);
                    view_changed = 1;
                    break;
                case SDLK_PLUS:
                case SDLK_EQUALS:
                case SDLK_KP_PLUS:
                    st.exposure = fminf(st.exposure + 0.5f, 20.0f);
                    view_renderer_set_exposure(&r, st.exposure);
                    break;
                case SDLK_MINUS:
                case SDLK_KP_MINUS:
                    st.exposure = fmaxf(st.exposure - 0.5f, -20.0f);
                    view_renderer_set_exposure(&r, st.exposure);
                    break;
                case SDLK_m:
                    st.recon = (st.recon + 1) % TR_RECON_COUNT;
                    view_renderer_set_recon(&r, st.recon);
                    break;
                case SDLK_r:
                    /* Back to the scene's camera and speed. */
                    fly = fly0;
                    view_changed = 1;
                    break;
                case SDLK_c: {
                    char json[1024], path[4200];
                    view_camera_json(&fly, json, sizeof json);
                    fputs(json, stdout);
                    fflush(stdout);
                    next_file_path(o->shot_dir, "trac0r-camera", "json", path, sizeof path);
                    tr_error cerr;
                    tr_outfile *cf = tr_outfile_open(path, &cerr);
                    if (cf) {
                        fputs(json, tr_outfile_stream(cf)); /* checked by the commit */
                    }
                    if (!cf || tr_outfile_commit(cf, &cerr) != TR_OK) {
                        fprintf(stderr, "trac0r view: %s\n", cerr.msg);
                    } else {
                        printf("trac0r view: saved %s\n", path);
                        fflush(stdout);
                        st.cameras += 1;
                    }
                    break;
                }
                case SDLK_F12: {
                    char path[4200];
                    next_file_path(o->shot_dir, "trac0r-view", "png", path, sizeof path);
                    view_renderer_screenshot(&r, path);
                    break;
                }
                default:
                    break;
                }
                break;
            default:
                break;
            }
            have = SDL_PollEvent(&ev);
        }

        /* Held keys move and roll the camera at a rate independent of the frame rate. */
        const Uint8 *keys = SDL_GetKeyboardState(NULL);
        tr_vec3 right = fly_right(&fly);
        tr_vec3 move = v3(0.0f, 0.0f, 0.0f);
        move =
            v3_add(move, v3_scale(fly.dir, (float)(keys[SDL_SCANCODE_W] - keys[SDL_SCANCODE_S])));
        move = v3_add(move, v3_scale(right, (float)(keys[SDL_SCANCODE_D] - keys[SDL_SCANCODE_A])));
        move = v3_add(
            move, v3_scale(fly.up, (float)(keys[SDL_SCANCODE_SPACE] - keys[SDL_SCANCODE_LCTRL])));
        if (v3_dot(move, move) > 0.0f) {
            fly.pos = v3_add(fly.pos, v3_scale(v3_normalize(move), fly.speed * (float)dt));
            view_changed = 1;
        }
        const int roll = keys[SDL_SCANCODE_E] - keys[SDL_SCANCODE_Q];
        if (roll) {
            fly.up = view_rotate(fly.up, fly.dir, (float)roll * 1.0f * (float)dt);
            fly_orthonormalize(&fly);
            view_changed = 1;
        }
        /* Moving: a view change in the last 150 ms. The renderer then holds the frame
         * budget; the first tick without changes asks for the full-resolution view. */
        if (view_changed) {
            last_change_t = t_in;
        }
        const int moving = t_in - last_change_t < 0.15;
        if (view_changed || moving != was_moving) {
            tr_camera next;
            if (!view_changed || fly_make(&fly, w, h, &next) == TR_OK) {
                if (view_changed) {
                    cam = next;
                }
                view_renderer_set_view(&r, &cam, st.stride, moving);
            }
            was_moving = moving;
            state_dirty = 1;
        }
        times.input = (tr_time_now() - t_in) * 1e3;

        /* Take the newest frame, if any, into the texture. */
        pthread_mutex_lock(&r.mu);
        int failed = r.failed;
        if (failed) {
            fprintf(stderr, "trac0r view: %s\n", r.error);
        }
        if (r.shot_done) {
            r.shot_done = 0;
            if (r.shot_ok) {
                printf("trac0r view: saved %s\n", r.shot_msg);
                fflush(stdout);
                st.shots += 1;
            } else {
                fprintf(stderr, "trac0r view: screenshot failed: %s\n", r.shot_msg);
            }
            state_dirty = 1;
        }
        if (r.pixels && r.seq != shown_seq) {
            const double t0 = tr_time_now();
            if (!tex || tex_w != r.pw || tex_h != r.ph) {
                if (tex) {
                    SDL_DestroyTexture(tex);
                }
                tex = SDL_CreateTexture(ren, SDL_PIXELFORMAT_ARGB8888, SDL_TEXTUREACCESS_STREAMING,
                                        (int)r.pw, (int)r.ph);
                tex_w = r.pw;
                tex_h = r.ph;
            }
            if (tex) {
                SDL_UpdateTexture(tex, NULL, r.pixels, (int)(r.pw * sizeof(uint32_t)));
            }
            shown_seq = r.seq;
            shown_gen = r.shown_gen;
            spp = r.spp;
            times.render = r.render_ms;
            times.rebuild = r.rebuild_ms;
            st.updates = r.updates;
            st.rebuild_ms = r.rebuild_ms;
            times.tonemap = r.tonemap_ms;
            times.temporal = r.temporal_ms;
            times.spatial = r.spatial_ms;
            times.upload = (tr_time_now() - t0) * 1e3;
            sf.scale = r.scale;
            sf.frame_spp = r.frame_spp;
            state_dirty = 1;
        }
        const uint64_t frames_done = r.frames_done, cancelled = r.cancelled;
        pthread_mutex_unlock(&r.mu);
        if (failed) {
            status = CLI_FAILURE;
            break;
        }
        /* shown_gen != r.generation: a read of our own write. */
        const int scene_changing = shown_gen != r.generation || o->animate;

        const double now = tr_time_now();
        if (now - fps_t0 >= 0.5) {
            fps = (double)(frames_done - fps_frames0) / (now - fps_t0);
            fps_frames0 = frames_done;
            fps_t0 = now;
        }
        if (st.timings && shown_seq != last_printed_seq) {
            printf("frame %llu: input %.3f ms, scene rebuild %.3f ms, render %.2f ms, "
                   "reconstruction (temporal %.2f, spatial %.2f) %.2f ms, "
                   "film->texture %.2f ms (tonemap %.2f, upload %.2f), %u spp\n",
                   (unsigned long long)shown_seq, times.input, times.rebuild, times.render,
                   times.temporal, times.spatial, times.temporal + times.spatial,
                   times.tonemap + times.upload, times.tonemap, times.upload, spp);
            fflush(stdout);
            last_printed_seq = shown_seq;
        }
        if (now - title_t >= 0.25) {
            snprintf(title, sizeof title, "trac0r view - %u spp - %.1f FPS", spp, fps);
            SDL_SetWindowTitle(win, title);
            title_t = now;
        }

        /* Redraw on news only (and 4 times a second for the overlay's numbers): the
         * render threads need the cores more than an unchanged window does. */
        if (!(state_dirty || any_event || dump_requested || now - drawn_t >= 0.25)) {
            continue;
        }
        drawn_t = now;
        SDL_SetRenderDrawColor(ren, 0, 0, 0, 255);
        SDL_RenderClear(ren);
        if (tex) {
            SDL_RenderCopy(ren, tex, NULL, NULL);
        }
        /* The render thread moves the scene under r.mu when animating. */
        pthread_mutex_lock(&r.mu);
        if (st.overlay) {
            const SDL_Color yellow = {255, 255, 0, 255};
            tr_aabb boxes[256];
            size_t nb = 0;
            for (uint32_t i = 0; i < tr_scene_shape_count(scene) && nb < 256; ++i) {
                boxes[nb++] = tr_scene_shape_box(scene, i);
            }
            view_draw_boxes(ren, &cam, boxes, nb, yellow);
        }
        if (st.bvh) {
            view_draw_bvh(ren, &cam, scene, st.bvh_depth); /* nothing without a BVH */
        }
        char accel[160];
        cli_describe_accel(accel, sizeof accel, scene);
        const uint32_t bvh_depth = view_bvh_depth(scene);
        pthread_mutex_unlock(&r.mu);
        if (st.overlay) {
            tr_vec3 mc = view_screen_to_camera(&cam, (float)mouse_x + 0.5f, (float)mouse_y + 0.5f);
            tr_vec3 mw = view_screen_to_world(&cam, (float)mouse_x + 0.5f, (float)mouse_y + 0.5f);
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
                     fps, spp, w, h, st.stride, st.exposure, was_moving ? "moving" : "at rest",
                     (double)sf.scale, sf.frame_spp, 1000.0 / o->target_fps, times.input,
                     times.rebuild, times.render, tr_recon_name(st.recon), times.temporal,
                     times.spatial, times.tonemap + times.upload, times.tonemap, times.upload,
                     o->c.scene, scene_changing ? "changing" : "static", accel, cam.pos.x,
                     cam.pos.y, cam.pos.z, cam.dir.x, cam.dir.y, cam.dir.z, cam.up.x, cam.up.y,
                     cam.up.z, cam.horizontal_fov, cam.vertical_fov, fly.speed, mouse_x, mouse_y,
                     mc.x, mc.y, mc.z, mw.x, mw.y, mw.z,
                     st.bvh ? "BVH boxes on (V), [ ] depth" : "");
            char line[64];
            if (st.bvh) {
                snprintf(line, sizeof line, " %u of %u", st.bvh_depth, bvh_depth);
                strncat(text, line, sizeof text - strlen(text) - 1);
            }
            view_draw_text(ren, font, 0, 0, text);
        }
        if (st.help) {
            /* Bottom right, clear of the debug text in the top left. */
            const int hx = (int)w - 290, hy = (int)h - 16 * TTF_FontLineSkip(font) - 20;
            view_draw_text(ren, font, hx > 0 ? hx : 0, hy > 0 ? hy : 0, help_text);
        }
        if (dump_requested && o->dump_file) {
            dump_requested = 0;
            if (dump_window(ren, o->dump_file, &err) != 0) {
                fprintf(stderr, "trac0r view: %s\n", err.msg);
            }
            st.dumps += 1;
            state_dirty = 1;
        }
        SDL_RenderPresent(ren);
        if (state_dirty && o->state_file) {
            sf.frames = frames_done;
            sf.cancelled = cancelled;
            sf.spp = spp;
            sf.gen = shown_gen;
            sf.view_gen = r.generation;
            sf.moving = was_moving;
            /* Said once, not at every frame, when the file cannot be written. */
            if (write_state(o->state_file, &st, &fly, &sf, w, h, fps, &err) != 0 && !state_failed) {
                fprintf(stderr, "trac0r view: --state-file: %s\n", err.msg);
                state_failed = 1;
            }
            state_dirty = 0;
        }
    }

done:
    view_renderer_stop(&r);
    if (tex) {
        SDL_DestroyTexture(tex);
    }
    if (ren) {
        SDL_DestroyRenderer(ren);
    }
    if (win) {
        SDL_DestroyWindow(win);
    }
    if (font) {
        TTF_CloseFont(font);
    }
    if (ttf) {
        TTF_Quit();
    }
    SDL_Quit();
    return status;
}
