/* restir.h - ReSTIR DI: reservoir resampling of the direct light at the camera ray's first
 * surface, as pure per-pixel functions (the driver is src/realtime/restir.c).
 *
 * Resampled importance sampling (J. Talbot, D. Cline and P. Egbert, "Importance
 * Resampling for Global Illumination", EGSR 2005) draws M candidate light samples from
 * cheap source distributions (the light tree or the power CDF with a point uniform on the
 * emitter's area, the environment map, the sun: pt's next-event samplers, but for the
 * spherical triangles) and keeps one in proportion to a
 * target function p_hat (the unshadowed contribution's luminance), with an unbiased
 * contribution weight W, so that f L G V W estimates the direct light. Spatiotemporal
 * reservoir resampling (B. Bitterli, C. Wyman, M. Pharr, P. Shirley, A. Lefohn and W.
 * Jarosz, "Spatiotemporal Reservoir Resampling for Real-Time Ray Tracing with Dynamic
 * Direct Lighting", ACM TOG 39(4), SIGGRAPH 2020) then merges each pixel's reservoir with
 * the previous frame's at the reprojected pixel and with neighbours' on similar surfaces,
 * each reservoir's sample resampled by p_hat at the merging pixel; the merge is that of
 * generalized RIS (D. Lin, M. Kettunen, B. Bitterli, J. Pantaleoni, C. Yuksel and C.
 * Wyman, "Generalized Resampled Importance Sampling", ACM TOG 41(4), SIGGRAPH 2022):
 * w_i = m_i(y_i) p_hat_q(y_i) W_i, W = sum w / p_hat_q(y). The MIS weights m_i decide the
 * bias:
 *   biased    m_i = M_i / sum M_j (Bitterli et al.'s 1/M): cheap, but a sample a
 *             neighbour could not have produced is counted as if it could; the stage can
 *             also reuse the chosen samples' visibility (an occluded sample's W set to 0),
 *             which darkens everything near a shadow (off by default);
 *   unbiased  m_i(y) = M_i p_hat_i(y) / sum_j M_j p_hat_j(y), the balance heuristic over
 *             the reused domains with confidence weights (Talbot's MIS, Bitterli et al.
 *             section 4.3): sums to one for every y, no visibility reuse.
 *
 * Samples live in one of three domains, each in its own measure: a point on an emissive
 * triangle (area measure: p_hat includes the geometry term cos_x cos_y / d^2, and the
 * candidate's solid-angle density is turned into an area density), a direction of the
 * environment or of the sun (solid angle). A sample keeps its point or direction when it
 * moves to another pixel, so the shift between pixels has Jacobian 1.
 *
 * Valid C99 and OpenCL C (kernel style), though only the CPU runs it so far. */
#ifndef TR_KERNEL_RESTIR_H
#define TR_KERNEL_RESTIR_H

#include "bsdf.h"
#include "camera.h"
#include "compat.h"
#include "envmap.h"
#include "light.h"
#include "material_eval.h"
#include "rng.h"
#include "sampler.h"
#include "scene_view.h"
#include "sun.h"
#include "types.h"
#include "vec.h"

/* tr_reservoir.light: a triangle index, or one of these. */
#define TR_RESTIR_NONE 0xffffffffu
#define TR_RESTIR_ENV 0xfffffffeu
#define TR_RESTIR_SUN 0xfffffffdu
/* At most this many reservoirs in one merge (the pixel and its neighbours). */
#define TR_RESTIR_MAX_MERGE 8

/* The surface a pixel's camera ray meets first (cut-outs passed), as pt's first segment
 * finds it: valid when it is a non-specular, non-emitting surface, where pt (with
 * TR_FRAME_NO_PRIMARY_DIRECT) leaves its direct light to the stage. */
typedef struct tr_restir_surface {
    /* What the spatial reuse's test of a neighbour reads (tr_restir_similar) comes first,
     * so that a neighbour it turns down costs one cache line, not the three the whole
     * surface spans: the point, the shading normal (m.ns again), the material. */
    tr_vec3 p; /* the hit point */
    tr_vec3 n; /* m.ns */
    uint32_t material;
    uint32_t valid;
    float dist; /* from the camera */
    tr_vec3 wo; /* towards the camera */
    tr_bsdf_params m;
} tr_restir_surface;

/* One light sample and its weights. */
typedef struct tr_reservoir {
    tr_vec3 y;      /* the point on the emitter, or the direction towards the light */
    uint32_t light; /* the triangle, TR_RESTIR_ENV, TR_RESTIR_SUN, TR_RESTIR_NONE (empty) */
    float u, v;     /* the point's barycentrics (the material stage's) */
    float W;        /* unbiased contribution weight */
    float M;        /* confidence: the candidates' frames it stands for */
    float ph;       /* the target p_hat of y at the surface of the pixel that holds the
                       reservoir (0 where empty): a merge in the same frame takes it
                       instead of evaluating the BSDF again */
} tr_reservoir;

TR_FN tr_reservoir tr_reservoir_empty(void) {
    tr_reservoir r;
    r.y = v3s(0.0f);
    r.light = TR_RESTIR_NONE;
    r.u = 0.0f;
    r.v = 0.0f;
    r.W = 0.0f;
    r.M = 0.0f;
    r.ph = 0.0f;
    return r;
}

TR_FN float tr_restir_luminance(tr_vec3 c) {
    return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}

/* The camera ray of sample `sample` of pixel (x, y), exactly as pt traces it
 * (kernel.h: the same sampler, the same jitter), and the surface it meets first. */
TR_FN tr_restir_surface tr_restir_primary(const tr_scene_view *s, const tr_camera *cam,
                                          uint64_t seed, uint64_t pixel, uint32_t x, uint32_t y,
                                          uint32_t sample, uint32_t sampler) {
    tr_restir_surface out;
    out.valid = 0u;
    out.p = v3s(0.0f);
    out.n = v3s(0.0f);
    out.wo = v3s(0.0f);
    out.dist = 0.0f;
    out.material = 0u;
    tr_sampler smp = tr_sampler_make_pixel(seed, pixel, x, y, sample, sampler);
    float jx, jy;
    tr_sampler_2d(&smp, TR_DIM_CAMERA, &jx, &jy);
    tr_ray ray = tr_camera_ray(cam, (float)x, (float)y, jx, jy);
    if (cam->lens_radius > 0.0f) {
        float lu, lv;
        tr_sampler_2d(&smp, TR_DIM_LENS, &lu, &lv);
        ray = tr_camera_ray_lens(cam, (float)x, (float)y, jx, jy, lu, lv);
    }
    for (int holes = 0;; ++holes) {
        tr_hit hit;
        if (!tr_intersect_scene(s, &ray, &hit)) {
            return out;
        }
        tr_triangle tri_tmp;
        TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, hit.triangle, &tri_tmp);
        tr_vec3 p = v3_madd(ray.origin, ray.dir, hit.t);
        tr_bsdf_params m = tr_material_eval(s, hit.triangle, hit.u, hit.v, p, tri->normal, ray.dir);
        if (m.hole && holes < TR_MAX_HOLES) {
            ray.tmin = hit.t + 1e-5f * tr_fmaxf(1.0f, hit.t);
            continue;
        }
        out.m = m;
        out.p = p;
        out.n = m.ns;
        out.wo = v3_neg(ray.dir);
        out.dist = hit.t;
        out.material = tri->material;
        out.valid = !tr_bsdf_is_delta(&m) && m.type != TR_MATERIAL_EMITTER;
        return out;
    }
}

/* The unshadowed contribution f L cos_x (times cos_y / d^2 for a point on an emitter) of
 * reservoir r's sample at surface q: the integrand without visibility, in the sample's
 * measure. *wi and *len get the direction and distance to the light (len 0: distant). */
TR_FN tr_vec3 tr_restir_contribution(const tr_scene_view *s, const tr_restir_surface *q,
                                     const tr_reservoir *r, tr_vec3 *wi, float *len) {
    *wi = v3s(0.0f);
    *len = 0.0f;
    if (!q->valid || r->light == TR_RESTIR_NONE) {
        return v3s(0.0f);
    }
    tr_vec3 le;
    float g = 1.0f;
    if (r->light == TR_RESTIR_ENV || r->light == TR_RESTIR_SUN) {
        *wi = r->y;
        if (r->light == TR_RESTIR_ENV) {
            le = s->env_count > 0u ? tr_env_radiance(s, r->y) : v3s(0.0f);
        } else {
            le = s->sun_count > 0u ? tr_sun_radiance(s, r->y) : v3s(0.0f);
        }
    } else {
        tr_triangle tri_tmp;
        TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, r->light, &tri_tmp);
        tr_vec3 d = v3_sub(r->y, q->p);
        float d2 = v3_dot(d, d);
        if (!(d2 > 0.0f)) {
            return v3s(0.0f);
        }
        float dist = tr_sqrtf(d2);
        *wi = v3_scale(d, 1.0f / dist);
        *len = dist;
        float cos_y = tr_fabsf(v3_dot(tri->normal, *wi));
        le = tr_emitted_at(s, r->light, r->u, r->v, r->y, tri->normal, v3_neg(*wi));
        g = cos_y / d2;
    }
    if (tr_restir_luminance(le) <= 0.0f) {
        return v3s(0.0f);
    }
    tr_vec3 f = tr_bsdf_eval(&q->m, q->wo, *wi);
    float cos_x = tr_fabsf(v3_dot(*wi, q->m.ns));
    return v3_scale(v3_mul(f, le), cos_x * g);
}

/* The target function: the luminance of the unshadowed contribution. */
TR_FN float tr_restir_target(const tr_scene_view *s, const tr_restir_surface *q,
                             const tr_reservoir *r) {
    tr_vec3 wi;
    float len;
    return tr_restir_luminance(tr_restir_contribution(s, q, r, &wi, &len));
}

/* The surface as the targets see it: its BSDF without the multiple-scattering
 * compensation (the tables of ggx_ms.h, about a third of a principled evaluation's
 * instructions). RIS is unbiased with any target that is positive wherever the integrand
 * is (J. Talbot, D. Cline and P. Egbert, "Importance Resampling for Global Illumination",
 * EGSR 2005), and the compensation only scales lobes that are positive without it; every
 * merge of a frame uses this one, and the shading evaluates the exact BSDF. */
TR_FN void tr_restir_target_surface(tr_restir_surface *q) {
    q->m.ms = 0;
}

/* Whether nothing blocks the light of r's sample from q (pt's shadow ray). */
TR_FN int tr_restir_visible(const tr_scene_view *s, const tr_restir_surface *q,
                            const tr_reservoir *r) {
    if (!q->valid || r->light == TR_RESTIR_NONE) {
        return 0;
    }
    if (r->light == TR_RESTIR_ENV || r->light == TR_RESTIR_SUN) {
        tr_ray shadow = tr_ray_make(tr_surface_origin(&q->m, q->p, r->y), r->y, 0.0f, TR_INFINITY);
        return !tr_occluded_masked(s, &shadow);
    }
    tr_vec3 wi = v3_normalize(v3_sub(r->y, q->p));
    tr_vec3 o = tr_surface_origin(&q->m, q->p, wi);
    tr_vec3 od = v3_sub(r->y, o);
    float len = v3_length(od);
    if (!(len > 0.0f)) {
        return 0;
    }
    tr_ray shadow = tr_ray_make(o, v3_scale(od, 1.0f / len), 0.0f, len * (1.0f - 1e-4f));
    return !tr_occluded_masked(s, &shadow);
}

/* One candidate from the source distributions at surface q: us picks the source (the
 * emitters, the environment, the sun: each present one equally likely), (u1, u2) the
 * sample in it. Returns its density in its own measure (0: no sample) and fills *c
 * (W and M are left to the caller). */
TR_FN float tr_restir_candidate(const tr_scene_view *s, const tr_restir_surface *q, float us,
                                float u1, float u2, tr_reservoir *c) {
    *c = tr_reservoir_empty();
    const uint32_t nl = s->light_count > 0u ? 1u : 0u;
    const uint32_t ne = s->env_count > 0u ? 1u : 0u;
    const uint32_t ns = s->sun_count > 0u ? 1u : 0u;
    const uint32_t k = nl + ne + ns;
    if (k == 0u) {
        return 0.0f;
    }
    uint32_t pick = (uint32_t)(us * (float)k);
    pick = pick < k ? pick : k - 1u;
    const float share = 1.0f / (float)k;
    if (pick < nl && s->light_node_count == 0u) {
        /* From the power CDF, a point uniform on the emitter's area: its density is in the
         * area measure already. Cheaper than pt's sampling by solid angle (Arvo's
         * spherical triangles: a few hundred instructions with their sines and arc
         * tangent), whose better spread over a large nearby emitter the resampling by
         * the target makes up for. */
        float uu = u1, sel;
        const uint32_t t = s->lights[tr_light_pick_rescale(s, &uu, &sel)];
        tr_triangle lt_tmp;
        TR_CONST_GLOBAL tr_triangle *tri = tr_view_triangle(s, t, &lt_tmp);
        if (!(sel > 0.0f) || !(tri->area > 0.0f)) {
            return 0.0f;
        }
        c->y = tr_light_area_point(tri, uu, u2, &c->u, &c->v);
        c->light = t;
        return share * sel / tri->area;
    }
    if (pick < nl) {
        uint32_t t;
        tr_vec3 y;
        float u, v;
        float pl = tr_light_sample_n(s, q->p, q->m.ns, u1, u2, &t, &y, &u, &v);
        tr_vec3 d = v3_sub(y, q->p);
        float d2 = v3_dot(d, d);
        if (!(pl > 0.0f) || !(d2 > 0.0f)) {
            return 0.0f;
        }
        tr_triangle lt_tmp;
        float cos_y = tr_fabsf(v3_dot(tr_view_triangle(s, t, &lt_tmp)->normal, d)) / tr_sqrtf(d2);
        if (!(cos_y > 0.0f)) {
            return 0.0f;
        }
        c->y = y;
        c->light = t;
        c->u = u;
        c->v = v;
        return share * pl * cos_y / d2; /* solid angle to area */
    }
    tr_vec3 dir;
    float pdf;
    if (pick < nl + ne) {
        (void)tr_env_sample(s, u1, u2, &dir, &pdf);
        c->light = TR_RESTIR_ENV;
    } else {
        (void)tr_sun_sample(s, u1, u2, &dir, &pdf);
        c->light = TR_RESTIR_SUN;
    }
    c->y = dir;
    return pdf > 0.0f ? share * pdf : 0.0f;
}

/* Streams a sample of resampling weight w into reservoir r (whose weight sum is *wsum),
 * keeping it with probability w / (*wsum + w) by the uniform number u; returns 1 when it
 * kept it. */
TR_FN int tr_reservoir_update(tr_reservoir *r, float *wsum, const tr_reservoir *c, float w,
                              float u) {
    if (!(w > 0.0f)) {
        return 0;
    }
    *wsum += w;
    if (u * *wsum < w) {
        tr_vec3 y = c->y;
        r->y = y;
        r->light = c->light;
        r->u = c->u;
        r->v = c->v;
        return 1;
    }
    return 0;
}

/* RIS over `count` candidates at q (the random numbers from rng): the pixel's own
 * reservoir, M = 1, W = (sum w / count) / p_hat(y). */
TR_FN tr_reservoir tr_restir_initial(const tr_scene_view *s, const tr_restir_surface *q, int count,
                                     tr_rng *rng) {
    tr_reservoir r = tr_reservoir_empty();
    float wsum = 0.0f, ph_sel = 0.0f;
    for (int i = 0; i < count; ++i) {
        float us = tr_rng_float(rng), u1 = tr_rng_float(rng), u2 = tr_rng_float(rng);
        float ur = tr_rng_float(rng);
        tr_reservoir c;
        float pdf = tr_restir_candidate(s, q, us, u1, u2, &c);
        if (!(pdf > 0.0f)) {
            continue;
        }
        const float ph = tr_restir_target(s, q, &c);
        if (tr_reservoir_update(&r, &wsum, &c, ph / pdf, ur)) {
            ph_sel = ph;
        }
    }
    r.M = 1.0f;
    if (r.light != TR_RESTIR_NONE) {
        r.W = ph_sel > 0.0f ? wsum / ((float)count * ph_sel) : 0.0f;
        r.ph = ph_sel;
    }
    return r;
}

/* The MIS weights of a merge of n reservoirs of confidences M[j] for one sample y, where
 * ph[j] is reservoir j's own target at y (p_hat_j(y): its surface's): unbiased, Talbot's
 * balance heuristic with confidence weights, M_j ph_j / sum M_k ph_k; biased, M_j / sum
 * M_k. Each set sums to one (or is all zero where no reservoir's domain holds y). */
TR_FN void tr_restir_mis(const float *M, const float *ph, int n, int unbiased, float *m) {
    float total = 0.0f;
    for (int j = 0; j < n; ++j) {
        total += unbiased ? M[j] * ph[j] : M[j];
    }
    for (int j = 0; j < n; ++j) {
        m[j] = total > 0.0f ? (unbiased ? M[j] * ph[j] : M[j]) / total : 0.0f;
    }
}

/* What a merge may take from the reservoirs instead of evaluating the target again
 * (tr_restir_merge's `known`): r[0].ph is r[0]'s target at surf[0]; each r[j].ph is its
 * target at surf[j]. Only within one frame: the previous frame's value was taken with
 * that frame's lights. */
#define TR_RESTIR_KNOWN_OWN 1
#define TR_RESTIR_KNOWN_ALL 2

/* Merges reservoirs r[0..n) (r[0] the pixel's own, at surface surf[0]; r[j] found at
 * surf[j]) at surf[0] by generalized RIS with tr_restir_mis's weights, the random numbers
 * from rng; the result's confidence is the sum, at most m_cap, its ph the chosen sample's
 * target at surf[0]. `known` (TR_RESTIR_KNOWN_*) says which targets the reservoirs
 * already hold. Where c is not NULL and the chosen sample's unshadowed contribution at
 * surf[0] was evaluated, it goes to *c and the function sets *c_known to 1 (else 0). */
TR_FN tr_reservoir tr_restir_merge(const tr_scene_view *s, const tr_restir_surface *surf,
                                   const tr_reservoir *r, int n, int unbiased, float m_cap,
                                   int known, tr_rng *rng, tr_vec3 *c, int *c_known) {
    tr_reservoir out = tr_reservoir_empty();
    float wsum = 0.0f, mtot = 0.0f;
    float M[TR_RESTIR_MAX_MERGE], ph[TR_RESTIR_MAX_MERGE], mw[TR_RESTIR_MAX_MERGE];
    n = n < TR_RESTIR_MAX_MERGE ? n : TR_RESTIR_MAX_MERGE;
    for (int j = 0; j < n; ++j) {
        M[j] = r[j].M;
        mtot += r[j].M;
    }
    float ph_sel = 0.0f;
    int sel_known = 0;
    tr_vec3 c_sel = v3s(0.0f);
    for (int i = 0; i < n; ++i) {
        const float u = tr_rng_float(rng);
        if (r[i].light == TR_RESTIR_NONE || !(r[i].W > 0.0f)) {
            continue;
        }
        tr_vec3 ci = v3s(0.0f);
        int ci_known = 0;
        float ph_q;
        if (i == 0 && (known & (TR_RESTIR_KNOWN_OWN | TR_RESTIR_KNOWN_ALL))) {
            ph_q = r[0].ph;
        } else {
            tr_vec3 wi;
            float len;
            ci = tr_restir_contribution(s, &surf[0], &r[i], &wi, &len);
            ci_known = 1;
            ph_q = tr_restir_luminance(ci);
        }
        if (!(ph_q > 0.0f)) {
            continue;
        }
        for (int j = 0; j < n; ++j) {
            ph[j] = !unbiased ? 0.0f
                    : j == 0  ? ph_q
                    : j == i && (known & TR_RESTIR_KNOWN_ALL)
                        ? r[i].ph
                        : tr_restir_target(s, &surf[j], &r[i]);
        }
        tr_restir_mis(M, ph, n, unbiased, mw);
        const float w = mw[i] * ph_q * r[i].W;
        if (tr_reservoir_update(&out, &wsum, &r[i], w, u)) {
            ph_sel = ph_q;
            sel_known = ci_known;
            c_sel = ci;
        }
    }
    out.M = mtot < m_cap ? mtot : m_cap;
    out.W = ph_sel > 0.0f && out.light != TR_RESTIR_NONE ? wsum / ph_sel : 0.0f;
    out.ph = out.W > 0.0f ? ph_sel : 0.0f;
    if (c) {
        *c = c_sel;
        *c_known = sel_known && out.W > 0.0f;
    }
    return out;
}

/* The direct light at q from reservoir r: f L G V W. Where c_known, c is r's unshadowed
 * contribution at q (tr_restir_contribution's value, which a merge found), not evaluated
 * again. */
TR_FN tr_vec3 tr_restir_shade(const tr_scene_view *s, const tr_restir_surface *q,
                              const tr_reservoir *r, tr_vec3 c, int c_known) {
    if (!q->valid || r->light == TR_RESTIR_NONE || !(r->W > 0.0f)) {
        return v3s(0.0f);
    }
    if (!c_known) {
        tr_vec3 wi;
        float len;
        c = tr_restir_contribution(s, q, r, &wi, &len);
    }
    if (tr_restir_luminance(c) <= 0.0f || !tr_restir_visible(s, q, r)) {
        return v3s(0.0f);
    }
    return v3_scale(c, r->W);
}

#endif
