/* view_render.h - the viewer's render thread.
 *
 * One thread owns the float film and renders frame after frame (sample k in frame k)
 * of the current view, publishing each finished frame as tonemapped 32-bit pixels.
 * The UI thread changes the view with view_renderer_set_view, which restarts
 * accumulation, so input never waits for a slow frame. Everything shared is guarded by
 * `mu`.
 *
 * Staying live in motion: a view change cancels the frame in flight only when that frame
 * refines a view already on screen (its second sample or later). The first frame of a
 * view is always finished and shown, so a camera that changes every 10 ms still gets a
 * new picture every frame instead of a frozen one. While the UI says the view is moving,
 * frames are rendered at a reduced resolution (the window stretches them) chosen to hold
 * the frame budget, and with more than one sample per pixel when even full resolution
 * leaves time over; at rest the film accumulates at full resolution as before.
 *
 * The frames themselves come from the library's real-time loop (tr_realtime, realtime.h):
 * it picks the resolution, samples and reconstruction on whatever device renders; this
 * thread decides which frames may be cancelled, tonemaps and publishes them. A device
 * that finishes its frames (OpenCL) cannot cancel one, so a view change waits for it and
 * then discards it. */
#ifndef TRAC0R_VIEW_RENDER_H
#define TRAC0R_VIEW_RENDER_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>

#include "trac0r/device.h"
#include "trac0r/post.h"
#include "trac0r/realtime.h"
#include "trac0r/trac0r.h"

/* animate: nonzero moves the scene's last shape before every frame and animates the
 * lights as TR_LIGHT_ANIMATION_(animate - 1) (tr_scene_animate_light). */
typedef struct view_renderer {
    tr_scene *scene; /* changed only by this thread, under mu, when animating */
    int animate;     /* move the scene's last shape before every frame (tr_scene_animate_sway) */
    tr_device *dev;  /* renders there (the scene uploaded) */
    tr_render_config cfg;
    uint32_t max_spp; /* stop accumulating here (0: never stop) */
    pthread_t thread;
    int started;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    atomic_int cancel;

    /* Requests, guarded by mu. */
    tr_camera cam;
    int stride;
    float exposure;
    int curve;           /* tr_tonemap_curve_kind of the display (fixed at the start) */
    int moving;          /* the UI's camera is changing: render to the frame budget */
    int recon;           /* tr_recon_method of the frames shown */
    double budget_ms;    /* the frame budget while moving (1000 / --target-fps) */
    uint64_t generation; /* bumped by every view change */
    int quit;
    char shot_path[4096]; /* F12: write the film here (empty: no request) */

    /* Results, guarded by mu. */
    uint32_t *pixels; /* ARGB8888, pw x ph, the last finished frame */
    uint32_t pw, ph;
    uint64_t seq;         /* bumped by every published frame */
    uint64_t shown_gen;   /* the generation of the published frame */
    uint32_t spp;         /* samples in the published frame */
    double render_ms;     /* tr_render_frame of the last frame */
    double rebuild_ms;    /* the scene update before the last frame (animate) */
    uint64_t updates;     /* scene updates since start */
    double tonemap_ms;    /* film -> pixels of the last frame */
    uint64_t frames_done; /* frames finished since start (for FPS) */
    uint64_t cancelled;   /* frames cancelled since start */
    float scale;          /* resolution divisor of the published frame (1: full) */
    double temporal_ms;   /* reconstruction of the published frame: temporal stage */
    double spatial_ms;    /* ... and its spatial filter */
    uint32_t frame_spp;   /* samples per pixel the published frame traced */
    int failed;           /* rendering failed: error holds why; the thread stopped */
    char error[600];
    int shot_done; /* a screenshot request finished: shot_msg says how */
    int shot_ok;
    char shot_msg[4700];

    /* Private to the thread. */
    tr_realtime *rt;      /* the frame loop: sampling, reconstruction, budget (realtime.h) */
    const tr_film *shown; /* the last frame shown (tr_realtime's, valid until its next frame) */
    uint32_t *back;       /* the next frame's pixels */
    size_t back_px;       /* back's capacity in pixels */
    size_t pixels_px;     /* ... and pixels' */
    atomic_int refining;  /* the frame in flight refines a view on screen: cancellable */
} view_renderer;

/* Starts the thread rendering `cam` (whose size sets the film's) with cfg's settings, on
 * the CPU (cl NULL) or on the OpenCL context cl, which holds `scene` already; moving or
 * animated frames take `motion_sampler` (TR_SAMPLER_*) instead of cfg's, and the
 * reconstruction `params`. With
 * `animate` the thread moves the scene's last shape before every frame (and uploads the
 * scene again to a device); readers of the scene on other threads hold mu. `rt` (may be
 * NULL) gives the real-time loop's frame-stage settings (its firefly control and later
 * stages); its other fields are ignored. */
int view_renderer_start(view_renderer *r, tr_scene *scene, int animate, tr_device *dev,
                        const tr_render_config *cfg, int motion_sampler,
                        const tr_recon_params *params, const tr_camera *cam, int stride,
                        float exposure, int curve, uint32_t max_spp, const tr_realtime_desc *rt,
                        tr_error *err);
/* Asks for another view (camera, size, stride or moving): restarts accumulation if it
 * differs. `moving` says that the camera is changing: frames then hold the budget. */
void view_renderer_set_view(view_renderer *r, const tr_camera *cam, int stride, int moving);
/* The frame budget while moving, in milliseconds. */
void view_renderer_set_budget(view_renderer *r, double budget_ms);
/* Shows later frames through reconstruction `method` (tr_recon_method): a new view, as
 * the film then keeps the passes the guided filters need. */
void view_renderer_set_recon(view_renderer *r, int method);
/* Tonemaps later frames with this exposure (accumulation continues). */
void view_renderer_set_exposure(view_renderer *r, float exposure);
/* Asks the thread to write its film (mean radiance, tonemapped) to path; the result
 * appears in shot_done/shot_ok/shot_msg. */
void view_renderer_screenshot(view_renderer *r, const char *path);
/* Stops the thread and frees everything. Safe on a renderer that never started. */
void view_renderer_stop(view_renderer *r);

/* Tonemaps a film into ARGB8888 pixels (black where no sample landed). */
void view_tonemap(const tr_film *film, float exposure, int curve, uint32_t *pixels);

#endif
