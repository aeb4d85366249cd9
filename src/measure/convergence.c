/* convergence.c - integrators compared at equal render time (measure.h). */
#include "trac0r/measure.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trac0r/film.h"

#define CONVERGENCE_MAX_METHODS 8

/* The methods' turns: each its own film, samples so far, the sample count of its next
 * recorded point, render time, and whether it is finished. */
typedef struct turns {
    tr_film films[CONVERGENCE_MAX_METHODS];
    uint32_t spp[CONVERGENCE_MAX_METHODS], next[CONVERGENCE_MAX_METHODS];
    double elapsed[CONVERGENCE_MAX_METHODS];
    int done[CONVERGENCE_MAX_METHODS];
    float *cur; /* a film's mean, 3 floats per pixel */
    size_t px;
} turns;

/* The unfinished method with the least render time so far, or -1 when all are done. */
static int next_method(const turns *t, int methods) {
    int mi = -1;
    for (int k = 0; k < methods; ++k) {
        if (!t->done[k] && (mi < 0 || t->elapsed[k] < t->elapsed[mi])) {
            mi = k;
        }
    }
    return mi;
}

/* Render time used against every method's budget (a finished method counts its whole),
 * in ms. */
static uint64_t budget_used(const turns *t, int methods, double budget) {
    uint64_t used = 0;
    for (int k = 0; k < methods; ++k) {
        used += (uint64_t)((t->done[k] || t->elapsed[k] > budget ? budget : t->elapsed[k]) * 1e3);
    }
    return used;
}

/* Method mi's film as it stands, scored as r's next point; the method is done past the
 * stop PSNR or at its last point. */
static int record_point(const tr_convergence_desc *d, turns *t, int mi, int last,
                        tr_convergence_run *r, tr_error *err) {
    if (tr_device_read_film(d->devs[mi], &t->films[mi], err) != TR_OK) {
        return TR_ERR;
    }
    tr_film_mean(&t->films[mi], t->cur);
    tr_convergence_point *p = &r->pt[r->n++];
    p->spp = t->spp[mi];
    p->seconds = t->elapsed[mi];
    p->raw = tr_image_compare(t->cur, d->ref, t->px);
    p->psnr =
        d->ref_mse > 0.0 ? tr_psnr_less_reference(p->raw.mse, d->ref_mse) : tr_psnr(p->raw.mse);
    const uint32_t step = (uint32_t)ceil(t->next[mi] * 0.19);
    t->next[mi] += step > 0 ? step : 1;
    if (p->psnr > (d->stop_psnr > 0.0 ? d->stop_psnr : 41.0) || last) {
        t->done[mi] = 1;
        if (d->finished) {
            d->finished(d->user, r);
        }
    }
    return TR_OK;
}

/* One 1-spp frame of method mi. */
static int method_turn(const tr_convergence_desc *d, turns *t, int mi, tr_convergence_run *r,
                       tr_error *err) {
    tr_render_stats st;
    if (tr_device_render(d->devs[mi], tr_scene_camera(d->scene), &d->configs[mi], t->spp[mi], 1,
                         NULL, &st, err) != TR_OK) {
        return TR_ERR;
    }
    t->elapsed[mi] += st.seconds;
    ++t->spp[mi];
    const int last = t->elapsed[mi] >= d->budget || r->n == TR_CONVERGENCE_MAX_POINTS - 1 ||
                     (d->max_spp > 0 && t->spp[mi] >= d->max_spp);
    if (t->spp[mi] == t->next[mi] || last) {
        return record_point(d, t, mi, last, r, err);
    }
    return TR_OK;
}

int tr_convergence_measure(const tr_convergence_desc *d, tr_convergence_run *runs, tr_error *err) {
    if (!d || !d->scene || !d->devs || !d->configs || !d->ref || d->methods < 1 ||
        d->methods > CONVERGENCE_MAX_METHODS || !(d->budget > 0.0)) {
        tr_error_set(err, TR_STATUS_INVALID_ARGUMENT,
                     "convergence: needs a scene, 1..%d methods with devices and configs, a "
                     "reference and a positive budget",
                     CONVERGENCE_MAX_METHODS);
        return TR_ERR;
    }
    const tr_camera *cam = tr_scene_camera(d->scene);
    turns t;
    memset(&t, 0, sizeof t);
    t.px = (size_t)cam->screen_width * cam->screen_height;
    t.cur = malloc(3 * t.px * sizeof *t.cur);
    int rc = t.cur ? TR_OK : TR_ERR;
    if (!t.cur) {
        tr_error_set(err, TR_STATUS_OUT_OF_MEMORY, "convergence: out of memory");
    }
    int nfilms = 0;
    for (int mi = 0; mi < d->methods && rc == TR_OK; ++mi) {
        memset(&runs[mi], 0, sizeof runs[mi]);
        runs[mi].integrator = d->configs[mi].integrator;
        runs[mi].width = cam->screen_width;
        runs[mi].height = cam->screen_height;
        t.next[mi] = 1; /* every method records its first point at 1 spp */
        rc = tr_film_init(&t.films[mi], cam->screen_width, cam->screen_height, err);
        nfilms += rc == TR_OK;
        if (rc == TR_OK) { /* a device's film may hold samples of earlier work */
            rc = tr_device_clear(d->devs[mi], err);
        }
    }
    const uint64_t total = (uint64_t)(d->budget * 1e3) * (uint64_t)d->methods;
    while (rc == TR_OK) {
        if (d->progress && d->progress(d->user, budget_used(&t, d->methods, d->budget), total)) {
            tr_error_set(err, TR_STATUS_CANCELLED, "convergence: cancelled");
            rc = TR_ERR;
            break;
        }
        const int mi = next_method(&t, d->methods);
        if (mi < 0) {
            break;
        }
        rc = method_turn(d, &t, mi, &runs[mi], err);
    }
    for (int k = 0; k < nfilms; ++k) {
        tr_film_free(&t.films[k]);
    }
    free(t.cur);
    return rc;
}

double tr_convergence_reach(const tr_convergence_run *r, double db, int use_spp) {
    for (int i = 0; i < r->n; ++i) {
        if (r->pt[i].psnr >= db) {
            const double x1 = use_spp ? r->pt[i].spp : r->pt[i].seconds;
            if (i == 0) {
                return x1;
            }
            const double x0 = use_spp ? r->pt[i - 1].spp : r->pt[i - 1].seconds;
            const double p0 = r->pt[i - 1].psnr, p1 = r->pt[i].psnr;
            const double f = p1 > p0 ? (db - p0) / (p1 - p0) : 1.0;
            return exp(log(x0) + f * (log(x1) - log(x0)));
        }
    }
    return -1.0;
}
