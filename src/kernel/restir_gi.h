/* restir_gi.h - ReSTIR GI: reservoir resampling of the indirect light at the camera ray's
 * first surface, as pure per-pixel functions (the driver is src/realtime/restir.c).
 *
 * After Y. Ouyang, S. Liu, M. Kettunen, M. Pharr and J. Pantaleoni, "ReSTIR GI: Path
 * Resampling for Real-Time Path Tracing", Computer Graphics Forum 40(8), HPG 2021. Each
 * pixel's first surface x_v (the "visible point") samples one direction from its BSDF,
 * finds the next surface x_s (the "sample point") and estimates the radiance L_o leaving
 * x_s towards x_v by a path traced on from x_s (pt's own estimator, without the emission
 * of x_s that ReSTIR DI samples already: the result is the indirect light only). The
 * sample (x_s, its normal n_s, L_o) is kept in a reservoir with contribution weight
 * W = 1 / p(w) (one candidate, its solid-angle density at x_v). Reservoirs are then
 * merged as in ReSTIR DI (restir.h): with the previous frame's at the reprojected pixel
 * and with neighbours' on similar surfaces, each sample resampled by the target
 *     p_hat_q(x_s) = luminance(f_q(w_o, w_i) L_o |cos(w_i, n_q)|),  w_i towards x_s,
 * at the merging pixel q. A sample made at x_r and reused at x_q is reconnected to x_s,
 * so its density changes measure: the paper's equation 11,
 *     J = (|cos phi_q| / |cos phi_r|) (|x_r - x_s|^2 / |x_q - x_s|^2),
 * phi being the angle at x_s between n_s and the direction to the visible point, is the
 * Jacobian d w_q / d w_r of the shift from x_r's directions to x_q's (the ratio of the
 * solid angles a small patch at x_s subtends from x_q and from x_r), and the reused
 * weight is W J (generalized RIS: Lin et al. 2022, the shift's Jacobian). A neighbour's sample is
 * reused only if x_s is visible from x_q (one shadow ray; the paper's spatial reuse tests it too)
 * and on the side of x_s whose radiance L_o is (the same sign of cos phi); the previous
 * frame's is not tested (its visible point is near, as in the paper's temporal reuse).
 * L_o is not re-evaluated for the new direction (the paper's approximation: exact for a
 * diffuse x_s, close for a rough one); a specular x_s is not reused.
 *
 * MIS weights as in restir.h: biased, M_i / sum M_j; unbiased, Talbot's balance
 * heuristic with confidences in the common area measure at x_s,
 *     m_i = M_i p_hat_i^A / sum_j M_j p_hat_j^A,  p_hat_j^A = p_hat_j |cos phi_j| / d_j^2,
 * each reservoir's target evaluated at its own surface (without visibility: the weights
 * then sum to one only where x_s is visible from every merged surface).
 *
 * Valid C99 and OpenCL C (kernel style), though only the CPU runs it so far. */
#ifndef TR_KERNEL_RESTIR_GI_H
#define TR_KERNEL_RESTIR_GI_H

#include "bsdf.h"
#include "compat.h"
#include "integrator_pt.h"
#include "material.h"
#include "material_eval.h"
#include "restir.h"
#include "rng.h"
#include "sampler.h"
#include "scene_view.h"
#include "types.h"
#include "vec.h"

/* One indirect-light sample and its weights. */
typedef struct tr_gi_reservoir {
    tr_vec3 xs;        /* the sample point */
    tr_vec3 ns;        /* its geometric normal */
    tr_vec3 lo;        /* the radiance leaving it towards the visible point that found it */
    float W;           /* unbiased contribution weight, in solid angle at the holder's surface */
    float M;           /* confidence */
    uint32_t valid;    /* 1: holds a sample */
    uint32_t reusable; /* 1: x_s is not specular, so another visible point may reconnect */
} tr_gi_reservoir;

TR_FN tr_gi_reservoir tr_gi_reservoir_empty(void) {
    tr_gi_reservoir r;
    r.xs = v3s(0.0f);
    r.ns = v3s(0.0f);
    r.lo = v3s(0.0f);
    r.W = 0.0f;
    r.M = 0.0f;
    r.valid = 0u;
    r.reusable = 0u;
    return r;
}

/* The unshadowed contribution f L_o |cos| of r's sample at surface q (w_i towards x_s),
 * and in *cos_s the cosine at x_s between n_s and the direction back to q, in *d2 the
 * squared distance. */
TR_FN tr_vec3 tr_gi_contribution(const tr_restir_surface *q, const tr_gi_reservoir *r, float *cos_s,
                                 float *d2) {
    *cos_s = 0.0f;
    *d2 = 0.0f;
    if (!q->valid || !r->valid) {
        return v3s(0.0f);
    }
    tr_vec3 d = v3_sub(r->xs, q->p);
    float dd = v3_dot(d, d);
    if (!(dd > 0.0f)) {
        return v3s(0.0f);
    }
    float dist = tr_sqrtf(dd);
    tr_vec3 wi = v3_scale(d, 1.0f / dist);
    *cos_s = -v3_dot(r->ns, wi);
    *d2 = dd;
    tr_vec3 f = tr_bsdf_eval(&q->m, q->wo, wi);
    float c = tr_fabsf(v3_dot(wi, q->m.ns));
    return v3_scale(v3_mul(f, r->lo), c);
}

/* The target p_hat_q: the luminance of the unshadowed contribution. */
TR_FN float tr_gi_target(const tr_restir_surface *q, const tr_gi_reservoir *r) {
    float cs, d2;
    return tr_restir_luminance(tr_gi_contribution(q, r, &cs, &d2));
}

/* The Jacobian d w_q / d w_r of reconnecting x_s, found from the visible point x_r, to the
 * visible point x_q (Ouyang et al., equation 11): (|cos phi_q| / |cos phi_r|)
 * (|x_r - x_s|^2 / |x_q - x_s|^2). 0 where x_q sees the other side of x_s or either
 * cosine or distance vanishes. */
TR_FN float tr_gi_jacobian(tr_vec3 xr, tr_vec3 xq, tr_vec3 xs, tr_vec3 ns) {
    tr_vec3 dr = v3_sub(xr, xs), dq = v3_sub(xq, xs);
    float d2r = v3_dot(dr, dr), d2q = v3_dot(dq, dq);
    if (!(d2r > 0.0f) || !(d2q > 0.0f)) {
        return 0.0f;
    }
    float cr = v3_dot(ns, dr) / tr_sqrtf(d2r);
    float cq = v3_dot(ns, dq) / tr_sqrtf(d2q);
    if (!(cr * cq > 0.0f)) {
        return 0.0f;
    }
    return (tr_fabsf(cq) / tr_fabsf(cr)) * (d2r / d2q);
}

/* Whether x_s of r is visible from surface q (one shadow ray). */
TR_FN int tr_gi_visible(const tr_scene_view *s, const tr_restir_surface *q,
                        const tr_gi_reservoir *r) {
    tr_vec3 wi = v3_normalize(v3_sub(r->xs, q->p));
    tr_vec3 o = tr_surface_origin(&q->m, q->p, wi);
    tr_vec3 od = v3_sub(r->xs, o);
    float len = v3_length(od);
    if (!(len > 0.0f)) {
        return 0;
    }
    tr_ray shadow = tr_ray_make(o, v3_scale(od, 1.0f / len), 0.0f, len * (1.0f - 1e-3f));
    return !tr_occluded_masked(s, &shadow);
}

/* The initial sample at surface q: a direction from q's BSDF (ulobe, u1, u2), the surface
 * x_s it meets (cut-outs passed) and the radiance leaving x_s towards q, estimated by pt
 * (tr_trace_pt_ff with smp, paths of at most max_depth - 1 more segments, roulette after
 * rr_start - 1, clamp and flags as the frame's) without the emission of x_s that light
 * sampling reaches (TR_FRAME_NO_FIRST_LIGHT). M = 1, W = 1 / p(w_i) where the sample
 * carries light, an empty reservoir of confidence 1 otherwise. *rays counts the queries. */
TR_FN tr_gi_reservoir tr_gi_initial(const tr_scene_view *s, const tr_restir_surface *q, float ulobe,
                                    float u1, float u2, const tr_sampler *smp, int max_depth,
                                    int rr_start, float clamp_indirect, uint32_t flags,
                                    uint32_t *rays) {
    tr_gi_reservoir r = tr_gi_reservoir_empty();
    r.M = 1.0f;
    if (!q->valid || max_depth < 2) {
        return r;
    }
    tr_scatter bs;
    if (!tr_bsdf_sample(&q->m, q->wo, ulobe, u1, u2, &bs) || bs.delta || !(bs.pdf > 0.0f)) {
        return r;
    }
    tr_ray ray = tr_ray_make(tr_surface_origin(&q->m, q->p, bs.wi), bs.wi, 0.0f, TR_INFINITY);
    /* The sample point, as pt's first segment will find it. */
    tr_ray probe = ray;
    tr_hit hit;
    tr_bsdf_params ms;
    tr_vec3 xs;
    tr_triangle hit_tmp;
    for (int holes = 0;; ++holes) {
        *rays += 1u;
        if (!tr_intersect_scene(s, &probe, &hit)) {
            return r; /* the environment and the sun: direct light, ReSTIR DI's */
        }
        xs = v3_madd(probe.origin, probe.dir, hit.t);
        ms = tr_material_eval(s, hit.triangle, hit.u, hit.v, xs,
                              tr_view_triangle(s, hit.triangle, &hit_tmp)->normal, probe.dir);
        if (!(ms.hole && holes < TR_MAX_HOLES)) {
            break;
        }
        probe.tmin = hit.t + 1e-5f * tr_fmaxf(1.0f, hit.t);
    }
    tr_vec3 lo =
        tr_trace_pt_ff(s, ray, max_depth - 1, rr_start > 2 ? rr_start - 1 : 1, clamp_indirect,
                       flags | TR_FRAME_NO_FIRST_LIGHT, smp, rays, (tr_sample *)0);
    if (!(tr_restir_luminance(lo) > 0.0f)) {
        return r;
    }
    r.xs = xs;
    r.ns = tr_view_triangle(s, hit.triangle, &hit_tmp)->normal;
    r.lo = lo;
    r.valid = 1u;
    r.reusable = !tr_bsdf_is_delta(&ms) && ms.type != TR_MATERIAL_EMITTER;
    r.W = tr_gi_target(q, &r) > 0.0f ? 1.0f / bs.pdf : 0.0f;
    return r;
}

/* Merges reservoirs r[0..n) (r[0] the pixel's own at surf[0], r[j] found at surf[j]) at
 * surf[0] by generalized RIS: w_i = m_i p_hat_0(x_s) W_i J_i, J_i the reconnection's
 * Jacobian from surf[i] to surf[0] (1 for the own sample). vis[i] nonzero: reservoir i's
 * sample must be visible from surf[0] (a shadow ray; an occluded one is not taken). A
 * The biased mode's weights are M_i / sum M_j, except for the own sample when its sample
 * point is specular (a path through the window's glass): no other pixel can draw that
 * path, so its weight is 1 (with M_0 / sum M_j the window room came out 17 % dark). The result's
 * confidence is the sum of all, at most m_cap. */
TR_FN tr_gi_reservoir tr_gi_merge(const tr_scene_view *s, const tr_restir_surface *surf,
                                  const tr_gi_reservoir *r, const int *vis, int n, int unbiased,
                                  float m_cap, tr_rng *rng) {
    tr_gi_reservoir out = tr_gi_reservoir_empty();
    float wsum = 0.0f, mtot = 0.0f, ph_sel = 0.0f;
    float M[TR_RESTIR_MAX_MERGE], ph[TR_RESTIR_MAX_MERGE], mw[TR_RESTIR_MAX_MERGE];
    float phq[TR_RESTIR_MAX_MERGE], jac[TR_RESTIR_MAX_MERGE];
    n = n < TR_RESTIR_MAX_MERGE ? n : TR_RESTIR_MAX_MERGE;
    /* Which samples surf[0] can take, their targets there and Jacobians; z sums the
     * confidences of the reservoirs but those whose sample lies outside surf[0]'s domain
     * (occluded from it, seen from its other side, specular). */
    float z = 0.0f;
    for (int i = 0; i < n; ++i) {
        M[i] = r[i].M;
        mtot += r[i].M;
        phq[i] = 0.0f;
        jac[i] = 0.0f;
        if (!r[i].valid || !(r[i].W > 0.0f)) {
            z += M[i]; /* it found no light: samples of zero weight, counted */
            continue;
        }
        if (i > 0 && !r[i].reusable) {
            continue;
        }
        const float j0 = i == 0 ? 1.0f : tr_gi_jacobian(surf[i].p, surf[0].p, r[i].xs, r[i].ns);
        if (!(j0 > 0.0f) || (vis[i] && !tr_gi_visible(s, &surf[0], &r[i]))) {
            continue;
        }
        z += M[i];
        phq[i] = tr_gi_target(&surf[0], &r[i]);
        jac[i] = j0;
    }
    for (int i = 0; i < n; ++i) {
        const float u = tr_rng_float(rng);
        if (!(phq[i] > 0.0f)) {
            continue;
        }
        float m;
        if (unbiased) {
            float cs0, d20;
            (void)tr_gi_contribution(&surf[0], &r[i], &cs0, &d20);
            for (int j = 0; j < n; ++j) {
                float cs = cs0, d2 = d20, pj = phq[i];
                if (j != 0) {
                    pj = tr_restir_luminance(tr_gi_contribution(&surf[j], &r[i], &cs, &d2));
                }
                /* A specular sample point is its own pixel's alone. */
                const int reach = j == i || r[i].reusable;
                ph[j] = reach && d2 > 0.0f && cs * cs0 > 0.0f ? pj * tr_fabsf(cs) / d2 : 0.0f;
            }
            tr_restir_mis(M, ph, n, 1, mw);
            m = mw[i];
        } else {
            /* A specular sample point's path only its own pixel can draw. */
            m = r[i].reusable ? M[i] / z : 1.0f;
        }
        const float w = m * phq[i] * r[i].W * jac[i];
        if (!(w > 0.0f)) {
            continue;
        }
        wsum += w;
        if (u * wsum < w) {
            out.xs = r[i].xs;
            out.ns = r[i].ns;
            out.lo = r[i].lo;
            out.valid = 1u;
            out.reusable = r[i].reusable;
            ph_sel = phq[i];
        }
    }
    out.M = mtot < m_cap ? mtot : m_cap;
    out.W = ph_sel > 0.0f && out.valid ? wsum / ph_sel : 0.0f;
    return out;
}

/* The indirect light at q from reservoir r: f L_o |cos| W (the sample was seen from q:
 * the own one by its ray, a neighbour's by its shadow ray). */
TR_FN tr_vec3 tr_gi_shade(const tr_restir_surface *q, const tr_gi_reservoir *r) {
    if (!q->valid || !r->valid || !(r->W > 0.0f)) {
        return v3s(0.0f);
    }
    float cs, d2;
    return v3_scale(tr_gi_contribution(q, r, &cs, &d2), r->W);
}

#endif
