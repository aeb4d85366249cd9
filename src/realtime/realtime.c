/* realtime.c - the real-time frame loop (realtime.h): sampling, reconstruction and the
 * frame budget, each stage its own function below. */
#include "trac0r/realtime.h"
#include "trac0r/recon_device.h"
#include "realtime/fresh.h"
#include "realtime/gradient.h"
#include "post/filter.h"
#include "post/recon_upscale.h"
#include "realtime/restir_stage.h"
#include "trac0r/upscale.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* One reconstruction method's history: on the host (rec) or on the device (rdev). */
typedef struct rt_history {
    tr_recon rec;
    tr_recon_device *rdev;
    uint32_t width, height; /* the size it was made for (0: not made) */
    int used;               /* rec or rdev holds a history */
    uint64_t frame;         /* the rendered frame it last took */
    tr_upscale up;          /* upscaled frames: the output's history (full resolution) */
    uint64_t up_frame;      /* the upscaled frame it last took (0: none) */
} rt_history;

struct tr_realtime {
    tr_device *dev;
    tr_scene *scene;
    /* tr_realtime_frame's cancel, for its reconstruction (NULL outside a frame). */
    int (*cancel)(void *user);
    void *cancel_user;
    tr_render_config cfg;
    tr_recon_params params;
    int rt_sampler;  /* TR_SAMPLER_* of real-time frames */
    int rt_roulette; /* their roulette start */
    float rt_clamp;  /* their indirect clamp (0: none) */
    int rt_regularize;
    int rt_psr; /* their passes' primary surface replacement */
    int restir; /* TR_REALTIME_RESTIR_* */
    tr_restir_params restir_params;
    tr_restir_stage *restir_stage;
    double restir_ms;
    uint32_t spp;
    int accumulate, animated, keep_passes;
    int on_device; /* the reconstruction runs where the film lies (an OpenCL device) */

    /* Sampling. */
    tr_film film;       /* the film of samples, on the host */
    int film_stale;     /* the device's film was not read into film */
    int have_view;      /* film holds a view that later frames may add to */
    tr_camera view_cam; /* the view asked for (full resolution) */
    tr_camera rcam;     /* the camera the film is rendered with (reduced while moving) */
    tr_camera alb_cam;  /* the camera of the output's albedo (alb, below) */
    int view_stride, view_moving, view_method;
    uint32_t acc_spp;       /* samples per pixel in the film */
    uint32_t frame_spp;     /* ... of which the last frame traced */
    uint32_t calls;         /* tr_realtime_render calls: real-time frames' numbers */
    uint32_t moving_frames; /* moving frames: their sample numbers */
    uint64_t rendered;      /* frames rendered to the end */
    double render_ms;
    float budget_scale;  /* the resolution divisor the budget asks for while moving */
    uint32_t budget_spp; /* samples per moving frame under a budget */
    tr_vec3 *motion;     /* animated: each primitive's motion since the last frame */
    uint32_t motion_ids; /* its entries (triangles + 1) */
    int moved;           /* motion holds some this frame */

    /* Reconstruction. */
    tr_gbuffer gb;     /* the frame's means and passes on the host */
    int gb_frame_set;  /* gb holds the last rendered frame (emission resolved) */
    double resolve_ms; /* the frame's emission resolve */
    uint32_t resolved;
    rt_history hist[TR_RECON_COUNT];
    tr_film disp; /* the reconstruction as a film of one sample per pixel */

    /* Temporal upscaling (upscale.h). */
    int budget_upscale; /* the desc's */
    float up_div;       /* this frame's divisor per axis (1: every pixel traced) */
    int view_upscaled;  /* the film is a traced fraction of the view, to upscale */
    float *pos;         /* its samples' positions in output pixels, 2 per film pixel */
    size_t pos_len;
    float *low; /* the reconstruction of the traced frame, 3 per film pixel */
    size_t low_len;
    uint32_t up_resolved; /* output pixels whose emission the upscaling resolved */
    float *emis[2];       /* the emission at the output's resolution, this frame and the last */
    size_t emis_len;
    int emis_cur;
    uint64_t emis_frame; /* the frame emis[emis_cur] is of (0: none) */
    float *alb;          /* the albedo at the output's resolution (tr_upscale_albedo) */
    size_t alb_len;
    uint64_t alb_frame; /* the frame alb is of (0: none) */

    /* Temporal gradients (gradient.h; tr_recon_params.gradients). */
    tr_grad grad;
    /* The pixels without history and their extra samples (fresh.h;
     * tr_recon_params.fresh_spp). */
    tr_fresh fresh;
};

static int same_camera(const tr_camera *a, const tr_camera *b) {
    /* Bitwise on purpose: any change of any bit is a new view (tr_camera has no padding:
     * 23 four-byte members). */
    return memcmp(a, b, sizeof *a) == 0; /* NOLINT(bugprone-suspicious-memory-comparison) */
}

void tr_realtime_budget_adapt(double frame_ms, double budget_ms, float *scale, uint32_t *spp) {
    if (!(budget_ms > 0.0) || !(frame_ms >= 0.0)) {
        return;
    }
    const double ratio = frame_ms / budget_ms;
    if (ratio > 1.0 && *spp > 1) {
        *spp /= 2;
        return;
    }
    /* A dead band around 80 % of the budget: no hunting between two sizes. */
    if (ratio > 0.9 || ratio < 0.6) {
        const double target = ratio / 0.8;
        double s = (double)*scale * pow(target > 1e-6 ? target : 1e-6, 0.25);
        s = s < 1.0 ? 1.0 : s > TR_REALTIME_MAX_SCALE ? TR_REALTIME_MAX_SCALE : s;
        *scale = (float)s;
    }
    if (*scale <= 1.0f && ratio < 0.4 && *spp < TR_REALTIME_MAX_SPP) {
        *spp *= 2;
    }
}

float tr_realtime_level(float scale) {
    static const float levels[] = {1.0f, 1.25f, 1.5f, 2.0f,  2.5f,  3.0f, 4.0f,
                                   5.0f, 6.0f,  8.0f, 10.0f, 12.0f, 16.0f};
    for (size_t k = 0; k < sizeof levels / sizeof levels[0]; ++k) {
        if (levels[k] >= 0.95f * scale) {
            return levels[k];
        }
    }
    return TR_REALTIME_MAX_SCALE;
}

tr_realtime *tr_realtime_create(tr_device *dev, tr_scene *scene, const tr_realtime_desc *desc,
                                tr_error *err) {
    if (!dev || !scene) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_realtime_create: %s is NULL",
                     dev ? "the scene" : "the device");
        return NULL;
    }
    const tr_realtime_desc zero = {0};
    const tr_realtime_desc *d = desc ? desc : &zero;
    const tr_render_config cfg = d->config ? *d->config : tr_render_config_default();
    if (tr_render_config_check(&cfg, err) != TR_OK) {
        return NULL;
    }
    if (d->sampler < 0 || d->sampler > TR_REALTIME_SAMPLER(TR_SAMPLER_ZSOBOL)) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_realtime_desc.sampler: unknown %d",
                     d->sampler);
        return NULL;
    }
    if (d->psr < -1 || d->psr > 1) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_realtime_desc: psr %d out of range",
                     d->psr);
        return NULL;
    }
    if (!(d->clamp_indirect <= 3.0e38f) || d->regularize < -1 || d->regularize > 1) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                     "tr_realtime_desc: clamp_indirect %g or regularize %d out of range",
                     (double)d->clamp_indirect, d->regularize);
        return NULL;
    }
    if (d->restir != TR_REALTIME_RESTIR_OFF && d->restir != TR_REALTIME_RESTIR_DI &&
        d->restir != TR_REALTIME_RESTIR_DI_GI) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_realtime_desc.restir: unknown %d",
                     d->restir);
        return NULL;
    }
    /* ReSTIR runs where the film lies (restir_stage.h). */
    if (d->restir != TR_REALTIME_RESTIR_OFF && cfg.integrator != TR_INTEGRATOR_PT) {
        tr_error_set(err, TR_STATUS_UNSUPPORTED, "ReSTIR DI needs the pt integrator");
        return NULL;
    }
    if (d->spp > TR_REALTIME_MAX_SPP * 64u) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                     "tr_realtime_desc.spp: expected at most %u, got %u", TR_REALTIME_MAX_SPP * 64u,
                     d->spp);
        return NULL;
    }
    tr_realtime *rt = calloc(1, sizeof *rt);
    if (!rt) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for tr_realtime");
        return NULL;
    }
    rt->dev = dev;
    rt->scene = scene;
    rt->cfg = cfg;
    rt->cfg.passes = 0;
    rt->cfg.cancel = NULL;
    rt->cfg.cancel_user = NULL;
    rt->params = d->recon ? *d->recon : tr_recon_params_default();
    rt->rt_sampler = d->sampler ? d->sampler - 1 : TR_SAMPLER_REALTIME;
    rt->rt_roulette = cfg.roulette_start ? cfg.roulette_start : TR_ROULETTE_START_REALTIME;
    rt->rt_clamp = d->clamp_indirect > 0.0f    ? d->clamp_indirect
                   : d->clamp_indirect == 0.0f ? TR_REALTIME_CLAMP_INDIRECT
                                               : 0.0f;
    rt->rt_regularize = d->regularize >= 0 ? 1 : 0;
    rt->rt_psr = d->psr >= 0 ? 1 : 0;
    rt->spp = d->spp ? d->spp : 1u;
    rt->accumulate = d->accumulate != 0;
    rt->animated = d->animated != 0;
    rt->keep_passes = d->keep_passes != 0;
    /* On a device with a film of its own (OpenCL) the reconstruction runs where the film
     * lies (recon_device.h). */
    rt->on_device = (tr_device_caps(dev) & TR_DEVICE_CAP_HOST) == 0u;
    rt->budget_scale = 1.0f;
    rt->budget_spp = 1;
    rt->restir = d->restir;
    rt->restir_params = tr_restir_params_default();
    rt->restir_params.unbiased = d->restir_unbiased != 0;
    rt->restir_params.gi = d->restir == TR_REALTIME_RESTIR_DI_GI;
    rt->restir_params.gi_unbiased = d->restir_unbiased != 0;
    if (rt->restir && !(rt->restir_stage = tr_restir_stage_create(err))) {
        free(rt);
        return NULL;
    }
    /* A driver may take many seconds to build ReSTIR's program (33 s on an H100 without
     * its cache): built here, the session's first frame does not carry it. */
    if (rt->restir && rt->on_device && tr_restir_stage_prepare_device(dev, err) != TR_OK) {
        tr_restir_stage_destroy(rt->restir_stage);
        free(rt);
        return NULL;
    }
    rt->budget_upscale = d->budget_upscale != 0;
    rt->up_div = 1.0f;
    return rt;
}

static void free_history(rt_history *h) {
    tr_upscale_free(&h->up);
    tr_recon_free(&h->rec);
    tr_recon_device_destroy(h->rdev);
    memset(h, 0, sizeof *h);
}

void tr_realtime_destroy(tr_realtime *rt) {
    if (!rt) {
        return;
    }
    for (int m = 0; m < TR_RECON_COUNT; ++m) {
        free_history(&rt->hist[m]);
    }
    tr_restir_stage_destroy(rt->restir_stage);
    tr_film_free(&rt->film);
    tr_film_free(&rt->disp);
    tr_gbuffer_free(&rt->gb);
    free(rt->motion);
    free(rt->pos);
    free(rt->low);
    free(rt->emis[0]);
    free(rt->emis[1]);
    free(rt->alb);
    tr_grad_free(&rt->grad);
    tr_fresh_free(&rt->fresh);
    free(rt);
}

int tr_realtime_on_device(const tr_realtime *rt) {
    return rt ? rt->on_device : 0;
}

/* The passes of a frame reconstructed with `method`, upscaled or not: the raw frame keeps
 * none unless asked, or upscaled (the upscaling reprojects through the distance and
 * primitive passes, and takes the light apart from the albedo pass: without them a moving
 * view's raw frames ghosted, and an albedo of 1 stood for the pass). */
static uint32_t frame_passes(const tr_realtime *rt, int method, int upscaled) {
    if (!rt || (method == TR_RECON_OFF && !rt->keep_passes && !upscaled)) {
        return 0u;
    }
    /* The direct pass where SVGF filters direct and indirect light apart (not bdpt). */
    const uint32_t direct =
        rt->params.svgf_split && !tr_integrator_is_bidirectional(rt->cfg.integrator)
            ? TR_PASS_DIRECT
            : 0u;
    /* The emission pass where the reconstruction resolves emitters' edges (pt only: the
     * resolved edge follows pt's first segment). */
    const uint32_t emission =
        rt->params.emission_samples > 0 && rt->cfg.integrator == TR_INTEGRATOR_PT ? TR_PASS_EMISSION
                                                                                  : 0u;
    /* The specular pass where SVGF filters diffuse and specular light apart (pt only). */
    const uint32_t specular =
        rt->params.svgf_specular && rt->cfg.integrator == TR_INTEGRATOR_PT ? TR_PASS_SPECULAR : 0u;
    return TR_PASS_ALL | direct | emission | specular;
}

uint32_t tr_realtime_passes(const tr_realtime *rt, int method) {
    return frame_passes(rt, method, 0);
}

/* ---- Sampling -------------------------------------------------------------------- */

static int check_frame_desc(const tr_realtime *rt, const tr_realtime_frame_desc *fd,
                            tr_error *err) {
    if (!rt || !fd || !fd->camera) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_realtime: %s is NULL",
                            !rt   ? "the instance"
                            : !fd ? "the frame desc"
                                  : "the camera");
    }
    if (!tr_recon_name(fd->method)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_realtime: unknown method %d",
                            fd->method);
    }
    if (fd->camera->screen_width == 0 || fd->camera->screen_height == 0) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_realtime: the camera is empty");
    }
    if (fd->upscale < 0 || fd->upscale > 16) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tr_realtime: upscale %d must be in 0..16", fd->upscale);
    }
    return TR_OK;
}

/* Whether the frame fd asks for adds to the film's view instead of starting a new one. */
static int continues_view(const tr_realtime *rt, const tr_realtime_frame_desc *fd, int stride) {
    return rt->accumulate && !rt->animated && rt->have_view && !fd->restart &&
           same_camera(&rt->view_cam, fd->camera) && rt->view_stride == stride &&
           rt->view_moving == (fd->moving != 0) && rt->view_method == fd->method &&
           !rt->view_upscaled && rt->up_div <= 1.0f;
}

/* The divisor per axis of the frame fd asks for: sqrt(upscale), or under a budget with
 * desc.budget_upscale the budget's resolution level up to 2 (a quarter of the pixels);
 * 1 (every pixel) with a stride or a bidirectional integrator, whose samples' positions
 * the upscaling does not know. */
static float upscale_divisor(const tr_realtime *rt, const tr_realtime_frame_desc *fd, int stride) {
    if (stride > 1 || tr_integrator_is_bidirectional(rt->cfg.integrator)) {
        return 1.0f;
    }
    float s = fd->upscale > 1 ? sqrtf((float)fd->upscale) : 1.0f;
    if (rt->budget_upscale && fd->moving && fd->budget_ms > 0.0 && rt->budget_scale > 1.0f) {
        float b = tr_realtime_level(rt->budget_scale);
        b = b < 2.0f ? b : 2.0f;
        s = b > s ? b : s;
    }
    return s;
}

/* A new view: the film sized to the camera (reduced to a resolution level while moving
 * under a budget) with the method's passes, cleared here and on the device. */
static int start_view(tr_realtime *rt, const tr_realtime_frame_desc *fd, int stride,
                      tr_error *err) {
    rt->have_view = 0;
    rt->view_cam = *fd->camera;
    rt->rcam = *fd->camera;
    rt->view_stride = stride;
    rt->view_moving = fd->moving != 0;
    rt->view_method = fd->method;
    rt->view_upscaled = rt->up_div > 1.0f;
    if (rt->view_upscaled) {
        /* A traced fraction of the view: the same camera at fewer pixels. */
        const float s = rt->up_div;
        const uint32_t w = (uint32_t)((float)fd->camera->screen_width / s + 0.5f);
        const uint32_t h = (uint32_t)((float)fd->camera->screen_height / s + 0.5f);
        (void)tr_camera_resize(&rt->rcam, w ? w : 1, h ? h : 1, err);
    } else if (rt->view_moving && rt->budget_scale > 1.0f) {
        const float s = tr_realtime_level(rt->budget_scale);
        const uint32_t w = (uint32_t)((float)fd->camera->screen_width / s + 0.5f);
        const uint32_t h = (uint32_t)((float)fd->camera->screen_height / s + 0.5f);
        /* Cannot fail: the size only shrinks, and stays at least 1x1. */
        (void)tr_camera_resize(&rt->rcam, w ? w : 1, h ? h : 1, err);
    }
    const uint32_t w = rt->rcam.screen_width, h = rt->rcam.screen_height;
    const uint32_t passes = frame_passes(rt, fd->method, rt->view_upscaled);
    if (rt->film.sum && rt->film.width == w && rt->film.height == h && rt->film.passes == passes) {
        tr_film_clear(&rt->film);
    } else {
        tr_film_free(&rt->film);
        if (tr_film_init_passes(&rt->film, w, h, passes, err) != TR_OK) {
            return TR_ERR;
        }
    }
    if (tr_device_clear(rt->dev, err) != TR_OK) {
        return TR_ERR;
    }
    rt->acc_spp = 0;
    rt->film_stale = 0;
    rt->have_view = 1;
    return TR_OK;
}

/* The first sample number of a frame of n samples per pixel: at rest the film's next
 * ones, as `trac0r render` numbers them; a real-time frame's by its frame number, so that
 * the noise changes from frame to frame. */
static uint32_t first_sample(tr_realtime *rt, uint32_t n) {
    if (!rt->accumulate) {
        return (rt->calls - 1u) * n;
    }
    if (rt->animated) {
        return rt->calls;
    }
    if (rt->view_moving) {
        return (rt->moving_frames++ & 0xffffu) * (uint32_t)TR_REALTIME_MAX_SPP + rt->acc_spp;
    }
    return rt->acc_spp;
}

/* Animated: how far each primitive moved since the last frame (tr_scene_take_motion),
 * for the reconstruction. Without memory the motion is dropped: the history of moving
 * shapes is then rejected, as for a static scene. */
static void take_motion(tr_realtime *rt) {
    rt->moved = 0;
    if (!rt->animated) {
        return;
    }
    const uint32_t n = tr_scene_triangle_count(rt->scene) + 1;
    if (rt->motion_ids != n) {
        free(rt->motion);
        rt->motion = calloc(n, sizeof *rt->motion);
        rt->motion_ids = rt->motion ? n : 0;
    }
    int moved = 0;
    tr_error err;
    if (rt->motion && tr_scene_take_motion(rt->scene, rt->motion, n, &moved, &err) == TR_OK) {
        rt->moved = moved;
    }
}

/* The frame's pixels without history traced again, with tr_recon_params.fresh_spp
 * samples in all (fresh.h): when the film holds the frame's own n samples alone, where it
 * lies, for real-time frames traced at every pixel by the frame's config (after the
 * temporal gradients, whose replay compares the frame's own samples). Not with ReSTIR
 * (its stage shades the frame's own samples). Otherwise the previous frame is forgotten,
 * so that the next frame the extra samples apply to starts from no history. */
static int fresh_samples(tr_realtime *rt, const tr_render_config *cfg, uint32_t n, int restir,
                         int stride, tr_error *err) {
    const int spp = rt->params.fresh_spp;
    const int on = spp > (int)n && !restir && stride <= 1 && !rt->view_upscaled &&
                   rt->acc_spp == n && (rt->view_moving || rt->animated || !rt->accumulate) &&
                   rt->film.depth && rt->film.normal && rt->film.prim &&
                   !tr_integrator_is_bidirectional(rt->cfg.integrator);
    if (!on) {
        tr_fresh_reset(&rt->fresh);
        return TR_OK;
    }
    tr_fresh *f = &rt->fresh;
    const uint32_t extra = (uint32_t)spp - n;
    /* Numbers apart from every frame's own, by frame (fresh.h). */
    const uint32_t sample = TR_FRESH_SAMPLE_BASE + ((rt->calls - 1u) & 0xfffffu) * extra;
    if (rt->on_device) {
        /* Where the film lies: mask, samples and memory in one call. */
        return tr_fresh_frame_device(f, rt->dev, &rt->rcam, cfg, sample, extra,
                                     rt->moved ? rt->motion : NULL, rt->moved ? rt->motion_ids : 0u,
                                     err);
    }
    if (tr_fresh_mask(f, &rt->film, &rt->rcam, rt->moved ? rt->motion : NULL,
                      rt->moved ? rt->motion_ids : 0u, rt->cfg.threads, err) != TR_OK) {
        return TR_ERR;
    }
    if (f->fresh > 0) {
        if (tr_fresh_trace(f, rt->scene, &rt->rcam, cfg, sample, extra, rt->cfg.threads, &rt->film,
                           err) != TR_OK) {
            return TR_ERR;
        }
    }
    return tr_fresh_remember(f, &rt->film, &rt->rcam, err);
}

int tr_realtime_render(tr_realtime *rt, const tr_realtime_frame_desc *fd, tr_error *err) {
    if (check_frame_desc(rt, fd, err) != TR_OK) {
        return TR_ERR;
    }
    rt->calls += 1;
    rt->gb_frame_set = 0;
    const int stride = fd->stride ? fd->stride : rt->cfg.stride;
    rt->up_div = upscale_divisor(rt, fd, stride);
    if (!continues_view(rt, fd, stride) && start_view(rt, fd, stride, err) != TR_OK) {
        return TR_ERR;
    }
    tr_render_config cfg = rt->cfg;
    cfg.stride = stride;
    cfg.passes = rt->film.passes;
    cfg.cancel = fd->cancel;
    cfg.cancel_user = fd->cancel_user;
    /* The passes see through mirrors and glass at rest too, so that the guides of one view
     * stay the same whether it moves or accumulates (the radiance is the same either way). */
    cfg.psr = rt->rt_psr;
    /* A real-time frame is reconstructed from few samples: pt's roulette starts early
     * there, which adds noise the filter hides and saves a fifth of the frame, and its
     * numbers are independent, which the reconstruction cannot tell from Sobol points and
     * cost less (docs/realtime.md). At rest the film converges with the config's, so that
     * it equals `trac0r render`. */
    if (rt->view_moving || rt->animated || !rt->accumulate) {
        cfg.roulette_start = rt->rt_roulette;
        cfg.sampler = rt->rt_sampler;
        /* Fireflies a filter would spread over a region are clamped and regularized away
         * (biased; docs/realtime.md measures by how much). */
        cfg.clamp_indirect = rt->rt_clamp;
        cfg.regularize = rt->rt_regularize;
    }
    /* ReSTIR DI: pt leaves the direct light at the first surface to the stage below (not
     * for a preview stride, whose traced pixels fill blocks). */
    const int restir = rt->restir != TR_REALTIME_RESTIR_OFF && stride <= 1;
    cfg.no_primary_direct = !restir ? 0 : rt->restir_params.gi ? 2 : 1;
    const uint32_t n = rt->view_moving && fd->budget_ms > 0.0 ? rt->budget_spp : rt->spp;
    const uint32_t sample = first_sample(rt, n);
    const double t0 = tr_time_now();
    if (tr_device_render(rt->dev, &rt->rcam, &cfg, sample, n, NULL, NULL, err) != TR_OK) {
        rt->have_view = 0; /* the film may hold part of a sample: start over */
        return TR_ERR;
    }
    if (fd->cancel && fd->cancel(fd->cancel_user)) {
        rt->have_view = 0;
        return tr_error_set(err, TR_STATUS_CANCELLED, "frame cancelled");
    }
    /* Reconstructed on an OpenCL device, the film stays there: at 1920x1080 reading it
     * with its passes took 10-12 ms a frame on an H100 (docs/gpu.md). */
    rt->film_stale = 1;
    if (!rt->on_device) {
        if (tr_device_read_film(rt->dev, &rt->film, err) != TR_OK) {
            rt->have_view = 0;
            return TR_ERR;
        }
        rt->film_stale = 0;
    }
    take_motion(rt);
    rt->restir_ms = 0.0;
    if (restir) {
        const double t1 = tr_time_now();
        tr_restir_params rp = rt->restir_params; /* ReSTIR GI's paths as this frame's */
        rp.max_depth = cfg.max_depth ? cfg.max_depth : tr_default_max_depth(cfg.integrator);
        rp.rr_start = cfg.roulette_start ? cfg.roulette_start : TR_ROULETTE_START_PT;
        rp.clamp_indirect = cfg.clamp_indirect;
        rp.regularize = cfg.regularize;
        const int rc = rt->on_device
                           ? tr_restir_stage_run_device(rt->restir_stage, rt->dev, &rt->rcam, &rp,
                                                        cfg.seed, sample, (uint32_t)cfg.sampler, n,
                                                        rt->calls, rt->film.passes, err)
                           : tr_restir_stage_run(rt->restir_stage, rt->scene, &rt->rcam, &rp,
                                                 cfg.seed, sample, (uint32_t)cfg.sampler, n,
                                                 rt->calls, cfg.threads, &rt->film, err);
        if (rc != TR_OK) {
            rt->have_view = 0;
            return TR_ERR;
        }
        rt->restir_ms = (tr_time_now() - t1) * 1e3;
    }
    if (rt->view_upscaled) {
        /* Where each traced pixel's samples lie in the output (the kernel's jitter). */
        const size_t need = 2 * (size_t)rt->rcam.screen_width * rt->rcam.screen_height;
        if (rt->pos_len < need) {
            free(rt->pos);
            rt->pos_len = 0;
            if (!(rt->pos = malloc(need * sizeof *rt->pos))) {
                rt->have_view = 0;
                return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a frame");
            }
            rt->pos_len = need;
        }
        if (tr_upscale_positions(&cfg, rt->rcam.screen_width, rt->rcam.screen_height,
                                 rt->view_cam.screen_width, rt->view_cam.screen_height, sample, n,
                                 rt->pos, err) != TR_OK) {
            rt->have_view = 0;
            return TR_ERR;
        }
    }
    /* Temporal gradients where the film holds this frame's samples alone, traced at every
     * pixel by pt or naive (the replay runs where the film lies): not with ReSTIR, whose
     * first surfaces' light the replay would not resample, nor upscaled frames. */
    const int grad = rt->params.gradients && !restir && stride <= 1 && !rt->view_upscaled &&
                     rt->acc_spp == 0 && !tr_integrator_is_bidirectional(cfg.integrator);
    rt->acc_spp += n;
    rt->frame_spp = n;
    rt->rendered += 1;
    rt->grad.ms = 0.0;
    if (!grad) {
        tr_grad_reset(&rt->grad);
    } else if (rt->on_device) {
        if (tr_grad_frame_device(&rt->grad, rt->dev, &rt->rcam, &cfg, sample, n, rt->calls,
                                 rt->moved ? rt->motion : NULL, rt->moved ? rt->motion_ids : 0u,
                                 rt->params.alpha_min, err) != TR_OK) {
            rt->have_view = 0;
            return TR_ERR;
        }
    } else if (tr_grad_frame(&rt->grad, rt->scene, &rt->film, &rt->rcam, &cfg, sample, n, rt->calls,
                             rt->moved ? rt->motion : NULL, rt->moved ? rt->motion_ids : 0u,
                             rt->params.alpha_min, rt->cfg.threads, err) != TR_OK) {
        rt->have_view = 0;
        return TR_ERR;
    }
    /* After the gradients, whose replay compares the frame's own samples. */
    if (fresh_samples(rt, &cfg, n, restir, stride, err) != TR_OK) {
        rt->have_view = 0;
        return TR_ERR;
    }
    rt->render_ms = (tr_time_now() - t0) * 1e3;
    return TR_OK;
}

int tr_realtime_film(tr_realtime *rt, const tr_film **film, tr_error *err) {
    if (!rt || !film) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_realtime_film: NULL argument");
    }
    if (!rt->have_view || rt->acc_spp == 0) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION, "tr_realtime: no frame rendered");
    }
    if (rt->film_stale) {
        if (tr_device_read_film(rt->dev, &rt->film, err) != TR_OK) {
            return TR_ERR;
        }
        rt->film_stale = 0;
    }
    *film = &rt->film;
    return TR_OK;
}

/* ---- Reconstruction ---------------------------------------------------------------- */

/* The display film sized to the frame (one sample per pixel). */
static int size_disp(tr_realtime *rt, uint32_t w, uint32_t h, tr_error *err) {
    if (rt->disp.sum && rt->disp.width == w && rt->disp.height == h) {
        return TR_OK;
    }
    tr_film_free(&rt->disp);
    if (tr_film_init(&rt->disp, w, h, err) != TR_OK) {
        return TR_ERR;
    }
    for (size_t i = 0; i < (size_t)w * h; ++i) {
        rt->disp.count[i] = 1;
    }
    return TR_OK;
}

/* Method m's history for this frame: (re)made for a new size, forgotten when the method
 * skipped a frame (its reprojection and motion are from one frame to the next). */
static int prepare_history(tr_realtime *rt, int m, uint32_t w, uint32_t h, tr_error *err) {
    rt_history *hist = &rt->hist[m];
    if (hist->width != w || hist->height != h) {
        /* The output's history of upscaled frames outlives a new traced size. */
        const tr_upscale keep = hist->up;
        const uint64_t keep_frame = hist->up_frame;
        memset(&hist->up, 0, sizeof hist->up);
        free_history(hist);
        hist->up = keep;
        hist->up_frame = keep_frame;
        if (rt->on_device) {
            if (!(hist->rdev = tr_recon_device_create(rt->dev, w, h, err))) {
                return TR_ERR;
            }
        } else if (tr_recon_init(&hist->rec, w, h, err) != TR_OK) {
            return TR_ERR;
        }
        hist->width = w;
        hist->height = h;
    } else if (hist->used && hist->frame + 1 != rt->rendered) {
        if (rt->on_device) {
            tr_recon_device_clear(hist->rdev);
        } else {
            tr_recon_clear(&hist->rec);
        }
    }
    hist->used = 1;
    hist->frame = rt->rendered;
    return TR_OK;
}

/* The frame's means and passes on the host, its emitters' edges resolved over the pixels'
 * area (post.h): once per frame, whatever methods follow. */
static int host_frame(tr_realtime *rt, tr_error *err) {
    if (rt->gb_frame_set) {
        return TR_OK;
    }
    const uint32_t w = rt->film.width, h = rt->film.height;
    if (rt->gb.width != w || rt->gb.height != h || !rt->gb.color) {
        tr_gbuffer_free(&rt->gb);
        if (tr_gbuffer_init(&rt->gb, w, h, err) != TR_OK) {
            return TR_ERR;
        }
    }
    if (tr_gbuffer_from_film(&rt->gb, &rt->film, err) != TR_OK) {
        return TR_ERR;
    }
    rt->resolve_ms = 0.0;
    rt->resolved = 0;
    if (rt->gb.has_emission) {
        const double t0 = tr_time_now();
        if (tr_resolve_emission(rt->scene, &rt->rcam, rt->params.emission_samples, rt->cfg.threads,
                                &rt->gb, &rt->resolved, err) != TR_OK) {
            return TR_ERR;
        }
        rt->resolve_ms = (tr_time_now() - t0) * 1e3;
    }
    if (rt->params.albedo_samples > 0 && rt->film.albedo) {
        /* Counted with the emission's resolve: both are part of the temporal stage. */
        const double t0 = tr_time_now();
        if (tr_resolve_albedo(rt->scene, &rt->rcam, rt->params.albedo_samples, rt->cfg.threads,
                              &rt->gb, NULL, err) != TR_OK) {
            return TR_ERR;
        }
        rt->resolve_ms += (tr_time_now() - t0) * 1e3;
    }
    rt->gb_frame_set = 1;
    return TR_OK;
}

/* The traced frame's reconstruction buffer (upscaled frames), w x h. */
static int size_low(tr_realtime *rt, uint32_t w, uint32_t h, tr_error *err) {
    const size_t need = 3 * (size_t)w * h;
    if (rt->low_len >= need) {
        return TR_OK;
    }
    free(rt->low);
    rt->low_len = 0;
    if (!(rt->low = malloc(need * sizeof *rt->low))) {
        return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a %ux%u frame", w, h);
    }
    rt->low_len = need;
    return TR_OK;
}

/* The albedo at the output's resolution into rt->alb, once per frame whatever methods
 * follow: from the traced frame's albedo `low` (rt->rcam's size) where it gives it, traced
 * elsewhere (tr_upscale_albedo). */
static int output_albedo(tr_realtime *rt, const float *low, tr_error *err) {
    const size_t n3 = 3 * (size_t)rt->view_cam.screen_width * rt->view_cam.screen_height;
    if (rt->alb_len != n3) {
        free(rt->alb);
        rt->alb_len = 0;
        rt->alb_frame = 0;
        if (!(rt->alb = malloc(n3 * sizeof *rt->alb))) {
            return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a frame");
        }
        rt->alb_len = n3;
    }
    if (rt->alb_frame != rt->rendered) {
        /* The previous frame's output albedo, overwritten pixel by pixel as it is read, where
         * it saw the same view: there it keeps details narrower than the traced pixels that
         * an earlier frame's samples found. From a moving camera or scene it would describe
         * other surfaces and ask for much of a textured frame to be traced (23-43 % of the
         * textured demo's pixels moving at 640x360, against 20 % without). */
        const int same = rt->alb_frame != 0 && rt->alb_frame + 1 == rt->rendered && !rt->moved &&
                         same_camera(&rt->alb_cam, &rt->view_cam);
        const float *prev = same ? rt->alb : NULL;
        if (tr_upscale_albedo(rt->scene, &rt->view_cam, rt->cfg.threads, rt->rcam.screen_width,
                              rt->rcam.screen_height, low, prev, rt->alb, NULL, err) != TR_OK) {
            return TR_ERR;
        }
        rt->alb_frame = rt->rendered;
        rt->alb_cam = rt->view_cam;
    }
    return TR_OK;
}

/* tr_recon_device_upscale's albedo callback: the output's albedo from the device frame's. */
static const float *device_albedo(void *user, const float *frame_albedo, tr_error *err) {
    tr_realtime *rt = user;
    return output_albedo(rt, frame_albedo, err) == TR_OK ? rt->alb : NULL;
}

/* The upscaling of an upscaled frame on the host: rt->low (the method's reconstruction of
 * the traced frame), the samples' positions and the frame's distance and id passes into
 * the display film at the view's full resolution, through the method's own output history.
 * (On an OpenCL device tr_recon_device_upscale does all of it where the film lies.) */
static int upscale_stage(tr_realtime *rt, rt_history *hist, int method, const tr_vec3 *motion,
                         uint32_t ids, tr_error *err) {
    const uint32_t w = rt->rcam.screen_width, h = rt->rcam.screen_height;
    const uint32_t W = rt->view_cam.screen_width, H = rt->view_cam.screen_height;
    if (hist->up.width != W || hist->up.height != H) {
        tr_upscale_free(&hist->up);
        if (tr_upscale_init(&hist->up, W, H, err) != TR_OK) {
            return TR_ERR;
        }
    } else if (hist->up_frame == 0 || hist->up_frame + 1 != rt->rendered) {
        tr_upscale_clear(&hist->up);
    }
    hist->up_frame = rt->rendered;
    /* On the host the emission the reconstruction added back is taken out again and
     * resolved at the output's resolution after the upscaling: a lamp's edge resolved at
     * the traced resolution would be spread over the output pixels each traced pixel
     * covers, and its rim holds most of the frame's error (docs/realtime.md). */
    const int emission = rt->gb.has_emission && rt->params.emission_samples > 0;
    if (emission) {
        const float *e = method != TR_RECON_OFF && rt->gb.has_resolved ? rt->gb.emission_resolved
                                                                       : rt->gb.emission;
        const size_t n3 = 3 * (size_t)w * h;
        for (size_t i = 0; i < n3; ++i) {
            rt->low[i] -= e[i];
        }
    }
    /* The light apart from the albedo (tr_recon_params.upscale_albedo): the reconstruction
     * divided by the albedo it multiplied by (SVGF's albedo history, else the frame's), and
     * the upscaled light multiplied by the output's own albedo after. */
    /* Every upscaled frame keeps its passes (frame_passes), the albedo among them. */
    const int apart = rt->params.upscale_albedo;
    if (apart) {
        const float *a = method == TR_RECON_SVGF && hist->rec.have_albedo
                             ? hist->rec.hist_albedo[hist->rec.cur]
                             : rt->gb.albedo;
        const size_t n3 = 3 * (size_t)w * h;
        for (size_t i = 0; i < n3; ++i) {
            rt->low[i] /= tr_post_upscale_factor(a[i]);
        }
    }
    const tr_upscale_input in = {w, h, rt->low, rt->pos, rt->gb.depth, rt->gb.prim};
    if (tr_upscale_frame(&hist->up, &in, &rt->view_cam, motion, ids, 0.0f, rt->cfg.threads,
                         rt->disp.sum, err) != TR_OK) {
        return TR_ERR;
    }
    if (apart) {
        const double t0 = tr_time_now();
        if (output_albedo(rt, rt->gb.albedo, err) != TR_OK) {
            return TR_ERR;
        }
        const size_t n3 = 3 * (size_t)W * H;
        for (size_t i = 0; i < n3; ++i) {
            /* No surface (albedo 0) reflects nothing, whatever light was spread there. */
            rt->disp.sum[i] =
                rt->alb[i] > 0.0f ? rt->disp.sum[i] * tr_post_upscale_factor(rt->alb[i]) : 0.0f;
        }
        hist->up.ms += (tr_time_now() - t0) * 1e3;
    }
    if (emission) {
        const double t0 = tr_time_now();
        const size_t n3 = 3 * (size_t)W * H;
        if (rt->emis_len != n3) {
            free(rt->emis[0]);
            free(rt->emis[1]);
            rt->emis[0] = calloc(n3, sizeof(float));
            rt->emis[1] = calloc(n3, sizeof(float));
            rt->emis_len = rt->emis[0] && rt->emis[1] ? n3 : 0;
            rt->emis_frame = 0;
            if (!rt->emis_len) {
                return tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "out of memory for a frame");
            }
        }
        /* Once per frame, whatever methods follow. */
        if (rt->emis_frame != rt->rendered) {
            const float *prev = rt->emis_frame + 1 == rt->rendered ? rt->emis[rt->emis_cur] : NULL;
            rt->emis_cur = 1 - rt->emis_cur;
            if (tr_upscale_emission(rt->scene, &rt->view_cam, rt->params.emission_samples,
                                    rt->cfg.threads, w, h, rt->gb.emission, prev,
                                    rt->emis[rt->emis_cur], &rt->up_resolved, err) != TR_OK) {
                return TR_ERR;
            }
            rt->emis_frame = rt->rendered;
        }
        const float *e = rt->emis[rt->emis_cur];
        for (size_t i = 0; i < n3; ++i) {
            rt->disp.sum[i] += e[i];
        }
        hist->up.ms += (tr_time_now() - t0) * 1e3;
    }
    return TR_OK;
}

static void fill_result(const tr_realtime *rt, const tr_film *film, const float *rgb, int method,
                        tr_realtime_result *out) {
    memset(out, 0, sizeof *out);
    out->film = film;
    out->rgb = rgb;
    out->width = film->width;
    out->height = film->height;
    out->scale = (float)rt->view_cam.screen_width / (float)film->width;
    out->spp = rt->acc_spp;
    out->frame_spp = rt->frame_spp;
    out->method = method;
    out->render_ms = rt->render_ms;
    out->restir_ms = rt->restir_ms;
    out->traced_width = rt->rcam.screen_width;
    out->traced_height = rt->rcam.screen_height;
}

int tr_realtime_reconstruct(tr_realtime *rt, int method, tr_realtime_result *out, tr_error *err) {
    if (!rt || !out) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tr_realtime_reconstruct: NULL argument");
    }
    if (!tr_recon_name(method)) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_realtime: unknown method %d",
                            method);
    }
    if (!rt->have_view || rt->acc_spp == 0) {
        return tr_error_set(err, TR_STATUS_INVALID_OPERATION, "tr_realtime: no frame rendered");
    }
    const uint32_t w = rt->rcam.screen_width, h = rt->rcam.screen_height;
    const int up = rt->view_upscaled;
    const uint32_t dw = up ? rt->view_cam.screen_width : w;
    const uint32_t dh = up ? rt->view_cam.screen_height : h;
    if (size_disp(rt, dw, dh, err) != TR_OK || prepare_history(rt, method, w, h, err) != TR_OK ||
        (up && !rt->on_device && size_low(rt, w, h, err) != TR_OK)) {
        return TR_ERR;
    }
    rt_history *hist = &rt->hist[method];
    /* Upscaled on the host, the reconstruction of the traced frame goes to rt->low first
     * (a device reconstructs and upscales where its film lies: rt->low is never made). */
    float *const dst = up ? rt->low : rt->disp.sum;
    const tr_vec3 *motion = rt->moved ? rt->motion : NULL;
    const uint32_t ids = rt->moved ? rt->motion_ids : 0u;
    double temporal = 0.0, spatial = 0.0, up_ms = 0.0;
    if (rt->on_device && up) {
        /* Reconstructed and upscaled where the film lies; only the output comes back. */
        const int keep = hist->up_frame != 0 && hist->up_frame + 1 == rt->rendered;
        if (tr_recon_device_upscale(hist->rdev, &rt->rcam, &rt->view_cam, rt->pos,
                                    rt->params.upscale_albedo ? device_albedo : NULL, rt, motion,
                                    ids, method, &rt->params, keep, rt->disp.sum, &up_ms,
                                    err) != TR_OK) {
            return TR_ERR;
        }
        hist->up_frame = rt->rendered;
        tr_recon_device_times(hist->rdev, &temporal, &spatial);
        temporal += up_ms;
    } else if (rt->on_device) {
        if (tr_recon_device_frame(hist->rdev, &rt->rcam, motion, ids, method, &rt->params, dst,
                                  err) != TR_OK) {
            return TR_ERR;
        }
        tr_recon_device_times(hist->rdev, &temporal, &spatial);
    } else {
        /* The gradients' history caps, for this frame only. */
        hist->rec.len_cap = rt->grad.valid ? rt->grad.cap : NULL;
        hist->rec.cancel = rt->cancel;
        hist->rec.cancel_user = rt->cancel_user;
        if (host_frame(rt, err) != TR_OK ||
            tr_recon_frame_moving(&hist->rec, &rt->gb, &rt->rcam, motion, ids, method, &rt->params,
                                  rt->cfg.threads, dst, err) != TR_OK) {
            return TR_ERR;
        }
        /* The resolve counts as part of the temporal stage; "off" does not use it. */
        temporal = hist->rec.ms_temporal + (method != TR_RECON_OFF ? rt->resolve_ms : 0.0);
        spatial = hist->rec.ms_spatial;
    }
    if (up && !rt->on_device) {
        if (upscale_stage(rt, hist, method, motion, ids, err) != TR_OK) {
            return TR_ERR;
        }
        up_ms = hist->up.ms;
        temporal += up_ms;
    } else if (!up) {
        hist->up_frame = 0;
    }
    fill_result(rt, &rt->disp, rt->disp.sum, method, out);
    out->upscale_ms = up_ms;
    out->temporal_ms = temporal;
    out->spatial_ms = spatial;
    out->resolve_ms = rt->on_device ? 0.0 : rt->resolve_ms;
    out->resolved = rt->on_device ? 0u : rt->resolved;
    out->gradient_ms = rt->grad.ms;
    out->gradient_valid = rt->grad.valid;
    out->gradient_changed = rt->grad.changed;
    return TR_OK;
}

const tr_gbuffer *tr_realtime_gbuffer(const tr_realtime *rt) {
    return rt && !rt->on_device && rt->gb_frame_set ? &rt->gb : NULL;
}

/* ---- The frame --------------------------------------------------------------------- */

int tr_realtime_frame(tr_realtime *rt, const tr_realtime_frame_desc *fd, tr_realtime_result *out,
                      tr_error *err) {
    if (!out) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "tr_realtime_frame: NULL result");
    }
    if (tr_realtime_render(rt, fd, err) != TR_OK) {
        return TR_ERR;
    }
    const double t0 = tr_time_now();
    if (fd->method != TR_RECON_OFF || rt->view_upscaled) {
        /* Stopped between stages and between the spatial filter's iterations (on the
         * host), so that a viewer closed mid-frame does not wait for the frame's end. */
        if (fd->cancel && fd->cancel(fd->cancel_user)) {
            rt->have_view = 0;
            return tr_error_set(err, TR_STATUS_CANCELLED, "frame cancelled");
        }
        rt->cancel = fd->cancel;
        rt->cancel_user = fd->cancel_user;
        const int rc = tr_realtime_reconstruct(rt, fd->method, out, err);
        rt->cancel = NULL;
        rt->cancel_user = NULL;
        if (rc != TR_OK) {
            if (err && err->code == TR_STATUS_CANCELLED) {
                rt->have_view = 0;
            }
            return TR_ERR;
        }
    } else {
        const tr_film *film = NULL;
        if (tr_realtime_film(rt, &film, err) != TR_OK) {
            return TR_ERR;
        }
        fill_result(rt, film, NULL, TR_RECON_OFF, out);
    }
    /* The budget: the next moving frame's divisor and samples from this one's time. */
    if (rt->view_moving) {
        const double ms = rt->render_ms + (tr_time_now() - t0) * 1e3 + fd->extra_ms;
        tr_realtime_budget_adapt(ms, fd->budget_ms, &rt->budget_scale, &rt->budget_spp);
    }
    return TR_OK;
}
