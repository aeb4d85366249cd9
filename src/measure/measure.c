/* measure.c - references that know their own error, real-time frames scored against
 * them, and integrators at equal time (measure.h). */
#include "trac0r/measure.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trac0r/camera.h"
#include "trac0r/film.h"

/* The samples a reference renders per device call: progress moves at least this often. */
#define REFERENCE_CHUNK 16u

/* Renders samples first .. first+count-1 of cfg in calls of REFERENCE_CHUNK; *done counts
 * them for progress(done, total). */
static int render_chunks(tr_device *dev, const tr_camera *cam, const tr_render_config *cfg,
                         uint32_t first, uint32_t count, uint64_t *done, uint64_t total,
                         tr_measure_progress_fn progress, void *user, tr_error *err) {
    for (uint32_t k = 0; k < count; k += REFERENCE_CHUNK) {
        const uint32_t n = count - k < REFERENCE_CHUNK ? count - k : REFERENCE_CHUNK;
        if (tr_device_render(dev, cam, cfg, first + k, n, NULL, NULL, err) != TR_OK) {
            return TR_ERR;
        }
        *done += n;
        if (progress && progress(user, *done, total) != 0) {
            tr_error_set(err, TR_STATUS_CANCELLED, "reference: cancelled");
            return TR_ERR;
        }
    }
    return TR_OK;
}

/* The second half of a reference is scrambled by a seed of its own, this far from the first
 * half's. */
#define REFERENCE_SECOND_SEED 0x9e3779b97f4a7c15ull

int tr_reference_render(tr_device *dev, const tr_camera *cam, const tr_render_config *cfg,
                        uint32_t spp, tr_film *film, float *ref, float *half, double *own_mse,
                        tr_measure_progress_fn progress, void *user, tr_error *err) {
    if (spp < 2 || !film || !ref || !half || !own_mse) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                     "reference: needs at least 2 samples and its buffers (spp %u)", spp);
        return TR_ERR;
    }
    /* Two independent estimates A (h1 samples) and B (h2 samples), so that the first
     * half's distance to the whole measures the whole's own error. Samples 0..h1-1 and
     * h1..spp-1 of one Sobol sequence are not independent: together they are better
     * stratified than either, and the distance overstated the whole's error (2.3 times on
     * a scene of many small lamps at 32 samples). B therefore takes samples 0..h2-1 again
     * under another seed, an independent scrambling of the same points. Then
     * ref = (h1 A + h2 B) / spp and E[(A - ref)^2] = (h2 / h1) var(ref), hence the factor
     * h1 / h2 below (1 for an even spp). */
    const uint32_t h1 = spp / 2, h2 = spp - h1;
    const size_t px = (size_t)film->width * film->height;
    tr_render_config second = *cfg;
    second.seed = cfg->seed + REFERENCE_SECOND_SEED;
    uint64_t done = 0;
    if (tr_device_clear(dev, err) != TR_OK ||
        render_chunks(dev, cam, cfg, 0, h1, &done, spp, progress, user, err) != TR_OK ||
        tr_device_read_film(dev, film, err) != TR_OK) {
        return TR_ERR;
    }
    tr_film_mean(film, half);
    if (render_chunks(dev, cam, &second, 0, h2, &done, spp, progress, user, err) != TR_OK ||
        tr_device_read_film(dev, film, err) != TR_OK) {
        return TR_ERR;
    }
    tr_film_mean(film, ref);
    *own_mse = tr_image_compare(half, ref, px).mse * (double)h1 / (double)h2;
    return TR_OK;
}

/* ---- The scorer ------------------------------------------------------------------ */

struct tr_scorer {
    uint32_t width, height;
    size_t px;
    int slots;
    tr_film film;                 /* the references' read-back */
    float *ref, *half, *ref_prev; /* 3 floats per pixel */
    float *prev;                  /* per slot: its previous output */
    unsigned char *have_prev;     /* per slot: prev holds the last frame's output */
    int have_ref;                 /* ref holds this frame's reference */
    int have_ref_prev;            /* ref_prev holds the previous frame's reference */
    double own;                   /* the reference's own MSE */
    size_t *idx, nidx;            /* the region's pixels */
    float *gathered;              /* 3 images of the region: output, reference, half */
    double region_own;            /* the reference's own MSE over the region */
    double half_scale;            /* tr_reference_render's factor h1 / h2 on the halves' MSE */
};

void tr_scorer_destroy(tr_scorer *s) {
    if (!s) {
        return;
    }
    tr_film_free(&s->film);
    free(s->ref);
    free(s->half);
    free(s->ref_prev);
    free(s->prev);
    free(s->have_prev);
    free(s->idx);
    free(s->gathered);
    free(s);
}

tr_scorer *tr_scorer_create(uint32_t width, uint32_t height, int slots, tr_error *err) {
    if (slots < 1 || slots > 64 || tr_film_check_size(width, height, err) != TR_OK) {
        if (slots < 1 || slots > 64) {
            tr_error_set(err, TR_STATUS_INVALID_ARGUMENT, "scorer: %d slots (1..64)", slots);
        }
        return NULL;
    }
    tr_scorer *s = calloc(1, sizeof *s);
    if (!s) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "scorer: out of memory");
        return NULL;
    }
    s->width = width;
    s->height = height;
    s->px = (size_t)width * height;
    s->slots = slots;
    const size_t img = 3 * s->px * sizeof(float);
    s->ref = malloc(img);
    s->half = malloc(img);
    s->ref_prev = malloc(img);
    s->prev = malloc((size_t)slots * img);
    s->have_prev = calloc((size_t)slots, 1);
    s->idx = malloc(s->px * sizeof *s->idx);
    s->gathered = malloc(3 * img);
    if (!s->ref || !s->half || !s->ref_prev || !s->prev || !s->have_prev || !s->idx ||
        !s->gathered) {
        tr_scorer_destroy(s);
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "scorer: out of memory at %ux%u", width, height);
        return NULL;
    }
    if (tr_film_init(&s->film, width, height, err) != TR_OK) {
        tr_scorer_destroy(s);
        return NULL;
    }
    return s;
}

int tr_scorer_reference(tr_scorer *s, tr_device *dev, const tr_camera *cam,
                        const tr_render_config *cfg, uint32_t spp, tr_error *err) {
    /* The last reference becomes the previous one; ref and ref_prev trade places. */
    float *t = s->ref_prev;
    s->ref_prev = s->ref;
    s->ref = t;
    s->nidx = 0;
    const int had = s->have_ref;
    s->have_ref = 0;
    s->have_ref_prev = had;
    if (tr_reference_render(dev, cam, cfg, spp, &s->film, s->ref, s->half, &s->own, NULL, NULL,
                            err) != TR_OK) {
        s->have_ref_prev = 0;
        memset(s->have_prev, 0, (size_t)s->slots);
        return TR_ERR;
    }
    s->half_scale = (double)(spp / 2) / (double)(spp - spp / 2);
    s->have_ref = 1;
    return TR_OK;
}

const float *tr_scorer_reference_rgb(const tr_scorer *s, double *own_mse) {
    if (own_mse) {
        *own_mse = s->own;
    }
    return s->ref;
}

int tr_scorer_bias(tr_scorer *s, tr_device *dev, const tr_camera *cam, const tr_render_config *cfg,
                   uint32_t spp, double *bias_mse, double *own, tr_error *err) {
    /* The second reference goes where the region's gathered images live (3 images):
     * nothing there outlives a frame's scoring. */
    float *other = s->gathered, *half = s->gathered + 3 * s->px;
    double own2 = 0.0;
    s->nidx = 0;
    if (tr_reference_render(dev, cam, cfg, spp, &s->film, other, half, &own2, NULL, NULL, err) !=
        TR_OK) {
        return TR_ERR;
    }
    *bias_mse = tr_image_compare(s->ref, other, s->px).mse - s->own - own2;
    *own = s->own + own2;
    return TR_OK;
}

/* Pixels idx[0..n) of image a (3 floats each) into out. */
static void gather(const float *a, const size_t *idx, size_t n, float *out) {
    for (size_t j = 0; j < n; ++j) {
        memcpy(out + 3 * j, a + 3 * idx[j], 3 * sizeof *out);
    }
}

size_t tr_scorer_region(tr_scorer *s, const uint32_t *ids, uint32_t lo, uint32_t hi) {
    s->nidx = 0;
    s->region_own = 0.0;
    for (size_t i = 0; ids && i < s->px; ++i) {
        if (ids[i] >= lo && ids[i] < hi) {
            s->idx[s->nidx++] = i;
        }
    }
    if (s->nidx > 0) {
        float *ref = s->gathered + 3 * s->px, *half = s->gathered + 6 * s->px;
        gather(s->ref, s->idx, s->nidx, ref);
        gather(s->half, s->idx, s->nidx, half);
        s->region_own = tr_image_compare(half, ref, s->nidx).mse * s->half_scale;
    }
    return s->nidx;
}

size_t tr_scorer_region_rect(tr_scorer *s, const uint32_t r[4]) {
    s->nidx = 0;
    s->region_own = 0.0;
    if (r[2] == 0 || r[3] == 0 || r[0] >= s->width || r[1] >= s->height || r[2] > s->width - r[0] ||
        r[3] > s->height - r[1]) {
        return 0;
    }
    for (uint32_t y = r[1]; y < r[1] + r[3]; ++y) {
        for (uint32_t x = r[0]; x < r[0] + r[2]; ++x) {
            s->idx[s->nidx++] = (size_t)y * s->width + x;
        }
    }
    float *ref = s->gathered + 3 * s->px, *half = s->gathered + 6 * s->px;
    gather(s->ref, s->idx, s->nidx, ref);
    gather(s->half, s->idx, s->nidx, half);
    s->region_own = tr_image_compare(half, ref, s->nidx).mse * s->half_scale;
    return s->nidx;
}

double tr_psnr_less_reference(double mse, double own) {
    const double m = mse - own;
    const double floor = own > 0.0 ? TR_REFERENCE_RESOLUTION * own : 1e-12;
    return tr_psnr(m > floor ? m : floor > 1e-12 ? floor : 1e-12);
}

tr_frame_scores tr_scorer_score(tr_scorer *s, int slot, const float *rgb) {
    tr_frame_scores sc;
    memset(&sc, 0, sizeof sc);
    if (slot < 0 || slot >= s->slots) {
        sc.psnr = sc.ssim = sc.region_psnr = NAN;
        return sc;
    }
    const size_t px = s->px;
    sc.psnr = tr_psnr_less_reference(tr_image_compare(rgb, s->ref, px).mse, s->own);
    sc.ssim = tr_ssim(rgb, s->ref, s->width, s->height);
    float *pm = s->prev + (size_t)slot * 3 * px;
    sc.flicker = s->have_prev[slot] && s->have_ref_prev
                     ? tr_image_flicker(rgb, pm, s->ref, s->ref_prev, px)
                     : 0.0;
    sc.region_psnr = NAN;
    if (s->nidx > 0) {
        gather(rgb, s->idx, s->nidx, s->gathered);
        sc.region_psnr = tr_psnr_less_reference(
            tr_image_compare(s->gathered, s->gathered + 3 * px, s->nidx).mse, s->region_own);
    }
    memcpy(pm, rgb, 3 * px * sizeof *rgb);
    s->have_prev[slot] = 1;
    return sc;
}

static int cmp_double(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double tr_median(double *v, int n) {
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int tr_measure_builds(tr_scene *scene, const tr_accel_type *accels, const int *skip, int count,
                      int builds, double *ms, tr_error *err) {
    if (!scene || !accels || !ms || count < 1 || count > TR_MEASURE_MAX_ACCELS || builds < 1 ||
        builds > TR_MEASURE_MAX_BUILDS) {
        return tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                            "tr_measure_builds: %d structures and %d builds (1..%d and 1..%d)",
                            count, builds, TR_MEASURE_MAX_ACCELS, TR_MEASURE_MAX_BUILDS);
    }
    double t[TR_MEASURE_MAX_ACCELS][TR_MEASURE_MAX_BUILDS];
    int n[TR_MEASURE_MAX_ACCELS] = {0};
    for (int k = 0; k < count; ++k) {
        if (skip && skip[k]) {
            continue;
        }
        for (int r = -1; r < builds; ++r) {
            if (tr_scene_commit(scene, accels[k], err) != TR_OK) {
                return TR_ERR;
            }
            if (r >= 0) {
                t[k][n[k]++] = 1e3 * tr_scene_build_seconds(scene);
            }
        }
    }
    for (int k = 0; k < count; ++k) {
        ms[k] = n[k] > 0 ? tr_median(t[k], n[k]) : 0.0;
    }
    return TR_OK;
}

tr_scores_summary tr_scores_summarize(const tr_frame_scores *frames, uint32_t from,
                                      uint32_t until) {
    tr_scores_summary s;
    memset(&s, 0, sizeof s);
    s.psnr_min = INFINITY;
    double region = 0.0;
    for (uint32_t f = from; f < until; ++f) {
        const tr_frame_scores *x = &frames[f];
        s.mean.render_ms += x->render_ms;
        s.mean.temporal_ms += x->temporal_ms;
        s.mean.spatial_ms += x->spatial_ms;
        s.mean.psnr += x->psnr;
        s.mean.ssim += x->ssim;
        s.mean.flicker += x->flicker;
        s.psnr_min = fmin(s.psnr_min, x->psnr);
        if (x->region_psnr == x->region_psnr) {
            region += x->region_psnr;
            ++s.region_frames;
        }
    }
    const double n = until > from ? (double)(until - from) : 1.0;
    const double nf = from == 0 && until > 1 ? n - 1.0 : n; /* frame 0 has no flicker */
    s.mean.render_ms /= n;
    s.mean.temporal_ms /= n;
    s.mean.spatial_ms /= n;
    s.mean.psnr /= n;
    s.mean.ssim /= n;
    s.mean.flicker /= nf;
    s.mean.region_psnr = s.region_frames ? region / s.region_frames : NAN;
    s.total_ms = s.mean.render_ms + s.mean.temporal_ms + s.mean.spatial_ms;
    s.fps = 1000.0 / s.total_ms;
    return s;
}

int tr_recovery_frames(const tr_frame_scores *frames, uint32_t count, uint32_t before,
                       uint32_t after, int region, double tolerance, double *steady) {
    double sum = 0.0;
    int n = 0;
    for (uint32_t f = before > 8 ? before - 8 : 0; f < before && f < count; ++f) {
        const double v = region ? frames[f].region_psnr : frames[f].psnr;
        if (v == v) {
            sum += v;
            ++n;
        }
    }
    *steady = n > 0 ? sum / n : NAN;
    for (uint32_t f = after; n > 0 && f < count; ++f) {
        if ((region ? frames[f].region_psnr : frames[f].psnr) >= *steady - tolerance) {
            return (int)(f - after);
        }
    }
    return -1;
}

int tr_camera_path(const tr_camera *c0, float diag, uint32_t f, uint32_t frames, uint32_t cut,
                   tr_camera *out, tr_error *err) {
    const double t = frames ? (double)f / (double)frames : 0.0;
    const float sway = (float)sin(2.0 * 3.14159265358979 * t);
    tr_vec3 pos = c0->pos, dir = c0->dir;
    float side = 0.03f * diag * sway, fwd = 0.1f * diag * (float)t, yaw = 0.15f * sway, lift = 0;
    if (cut > 0 && f >= cut) {
        side += 0.2f * diag;
        lift = 0.08f * diag;
        yaw -= 0.3f;
    }
    for (int k = 0; k < 3; ++k) {
        const float *r = &c0->right.x, *u = &c0->up.x, *d = &c0->dir.x;
        (&pos.x)[k] += r[k] * side + d[k] * fwd + u[k] * lift;
        (&dir.x)[k] = d[k] + r[k] * yaw;
    }
    tr_camera c;
    if (tr_camera_make(&c, pos, dir, c0->world_up, c0->vertical_fov, c0->near_dist, c0->far_dist,
                       c0->screen_width, c0->screen_height, err) != TR_OK) {
        return TR_ERR;
    }
    /* tr_camera_make's right is up x dir; c0's may be mirrored (a right-handed scene). */
    const tr_vec3 r0 = c0->right, r1 = c.right;
    if (r0.x * r1.x + r0.y * r1.y + r0.z * r1.z < 0.0f) {
        c.right = tr_vec3_make(-r1.x, -r1.y, -r1.z);
    }
    c.lens_radius = c0->lens_radius; /* c0's thin lens, if any, moves with it */
    c.focus_dist = c0->focus_dist;
    *out = c;
    return TR_OK;
}
